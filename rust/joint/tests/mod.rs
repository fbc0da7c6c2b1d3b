//! Each joint type against its definition (finite differences, invariants).
use super::*;

#[test]
fn zyz_rates_give_angular_velocity() {
    // ω̃ = Ṙ Rᵀ, by finite differences along a path.
    let q = [0.3, 0.7, -1.1];
    let qd = [0.5, -0.2, 0.9];
    let h = 1e-6;
    let r = |t: f64| {
        Joint::SphericalZYZ
            .transform(&[q[0] + t * qd[0], q[1] + t * qd[1], q[2] + t * qd[2]])
            .0
    };
    let rdot = (r(h) - r(-h)) / (2.0 * h);
    let w = rdot * r(0.0).transpose();
    let expect = zyz_rate_matrix(q[0], q[1]) * Vec3::from(qd);
    assert!((Vec3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]) - expect).norm() < 1e-8);
}

#[test]
fn quaternion_rate_is_body_angular_velocity() {
    let n = (0.2f64 * 0.2 + 0.4 * 0.4 + 0.1 * 0.1 + 0.88 * 0.88).sqrt();
    let q = [0.2 / n, -0.4 / n, 0.1 / n, 0.88 / n];
    let v = [0.3, -1.2, 0.7];
    let mut qd = [0.0; 4];
    Joint::Spherical.velocity_to_qdot(&q, &v, &mut qd);
    let h = 1e-6;
    let qp: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + h * b).collect();
    let qm: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a - h * b).collect();
    let rdot = (quat_to_matrix(&qp) - quat_to_matrix(&qm)) / (2.0 * h);
    // Body-frame angular velocity: ω̃_b = Rᵀ Ṙ.
    let wb = quat_to_matrix(&q).transpose() * rdot;
    assert!((Vec3::new(wb[(2, 1)], wb[(0, 2)], wb[(1, 0)]) - Vec3::from(v)).norm() < 1e-8);
}

#[test]
fn bad_axis_and_quaternion_are_errors() {
    assert!(Joint::revolute(Vec3::zeros()).is_err());
    assert!(Joint::prismatic(Vec3::new(f64::NAN, 0.0, 1.0)).is_err());
    assert!(Joint::Spherical
        .check_configuration(&[0.0; 4], "q")
        .is_err());
}

#[test]
fn free_flyer_rates_are_body_velocities() {
    // Pinocchio's convention: ṗ = R v (v in body axes), ω̃_b = Rᵀ Ṙ, along a path.
    let n = (0.3f64 * 0.3 + 0.1 * 0.1 + 0.5 * 0.5 + 0.8 * 0.8).sqrt();
    let q = [0.4, -1.0, 2.5, 0.3 / n, -0.1 / n, 0.5 / n, 0.8 / n];
    let v = [0.7, -0.2, 1.1, 0.3, -1.2, 0.6];
    let mut qd = [0.0; 7];
    Joint::FreeFlyer.velocity_to_qdot(&q, &v, &mut qd);
    let h = 1e-6;
    let at = |t: f64| -> Vec<f64> { q.iter().zip(&qd).map(|(a, b)| a + t * b).collect() };
    let (rp, pp) = Joint::FreeFlyer.transform(&at(h));
    let (rm, pm) = Joint::FreeFlyer.transform(&at(-h));
    let (r, _) = Joint::FreeFlyer.transform(&q);
    let lin = r.transpose() * (pp - pm) / (2.0 * h);
    let wb = r.transpose() * (rp - rm) / (2.0 * h);
    assert!((lin - Vec3::new(v[0], v[1], v[2])).norm() < 1e-8);
    assert!(
        (Vec3::new(wb[(2, 1)], wb[(0, 2)], wb[(1, 0)]) - Vec3::new(v[3], v[4], v[5])).norm() < 1e-8
    );
    // Its world columns give the same twist (at the body origin): Σ P_k v_k = [R ω; R v].
    let s = Joint::FreeFlyer.subspace(&q, &Mat3::identity(), &r);
    let twist: Vec6 = (0..6).map(|k| s[k] * v[k]).sum();
    let expect = stack(
        &(r * Vec3::new(v[3], v[4], v[5])),
        &(r * Vec3::new(v[0], v[1], v[2])),
    );
    assert!((twist - expect).norm() < 1e-14);
    assert_eq!((Joint::FreeFlyer.nq(), Joint::FreeFlyer.nv()), (7, 6));
    assert!(Joint::FreeFlyer
        .check_configuration(&[0.0; 7], "q")
        .is_err());
    assert!((0..6)
        .map(|k| Joint::FreeFlyer.v_is_angular(k))
        .eq([false, false, false, true, true, true]));
}

/// `Model::normalize` and `Model::velocity_to_qdot` skip their per-joint walk when nq = nv:
/// that holds only if the quaternion joints are exactly those with nq ≠ nv (nq > nv).
#[test]
fn only_quaternion_joints_have_more_coordinates_than_speeds() {
    let joints = [
        Joint::Revolute { axis: Vec3::z() },
        Joint::Prismatic { axis: Vec3::x() },
        Joint::SphericalZYZ,
        Joint::Spherical,
        Joint::Fixed,
        Joint::FreeFlyer,
        Joint::ToyCardan,
    ];
    for j in joints {
        // A new joint type fails to compile here until it is listed above.
        match j {
            Joint::Revolute { .. } | Joint::Prismatic { .. } | Joint::SphericalZYZ => {}
            Joint::Spherical | Joint::Fixed | Joint::FreeFlyer | Joint::ToyCardan => {}
        }
        assert!(j.nq() >= j.nv(), "{j:?}");
        assert_eq!(j.quaternion_at().is_some(), j.nq() != j.nv(), "{j:?}");
    }
}
