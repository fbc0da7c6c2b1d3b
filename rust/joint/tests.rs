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
