//! Frames against finite differences of the placements.
use super::*;
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::support::spatial::{Mat3, Vec3};

fn chain() -> Model {
    let mut m = Model::new();
    let rod = RigidBody::new(1.0, Vec3::new(0.5, 0.1, 0.0), Mat3::identity() * 0.1).unwrap();
    let z = Joint::revolute(Vec3::z()).unwrap();
    let y = Joint::revolute(Vec3::y()).unwrap();
    let a = m
        .add_body(rod, z, None, Placement::identity(), None, None)
        .unwrap();
    let p1 = Placement::new(crate::joint::rot_x(0.3), Vec3::new(1.0, 0.0, 0.2));
    let b = m.add_body(rod, y, Some(a), p1, None, None).unwrap();
    m.add_frame(
        "tip",
        b,
        Placement::new(crate::joint::rot_z(0.4), Vec3::new(1.0, 0.2, 0.0)),
    )
    .unwrap();
    m
}

#[test]
fn jacobian_matches_finite_differences() {
    let m = chain();
    let f = m.frame_named("frame", "tip").unwrap();
    let q = [0.3, -0.7];
    let mut kin = FrameKinematics::new(&m);
    kin.positions(&m, &q);
    let mut j = vec![0.0; 12];
    jacobian::frame_jacobian(&m, &kin, &f, ReferenceFrame::LocalWorldAligned, &mut j);
    let h = 1e-6;
    for c in 0..2 {
        let (mut qp, mut qm) = (q, q);
        qp[c] += h;
        qm[c] -= h;
        kin.positions(&m, &qp);
        let xp = kin.frame_pose(&f).translation;
        kin.positions(&m, &qm);
        let xm = kin.frame_pose(&f).translation;
        let d = (xp - xm) / (2.0 * h);
        for i in 0..3 {
            assert!((d[i] - j[(3 + i) * 2 + c]).abs() < 1e-8, "{c} {i}");
        }
    }
}

#[test]
fn unknown_frame_lists_frames() {
    let m = chain();
    let e = m.frame_named("frame", "nope").unwrap_err().to_string();
    assert!(e.contains("'tip'") && e.contains("'body0'"), "{e}");
}

#[test]
fn log3_is_accurate_small_and_near_half_turn() {
    for angle in [1e-12, 1e-8, 0.3, 3.0, std::f64::consts::PI - 1e-9] {
        let axis = Vec3::new(0.3, -0.5, 0.8).normalize();
        let r = crate::joint::rotation::axis_angle(&axis, angle);
        let phi = ik::log3(&r);
        assert!(
            (phi - axis * angle).norm() <= 1e-15 + 1e-9 * angle,
            "{angle}: {phi:?}"
        );
    }
}
