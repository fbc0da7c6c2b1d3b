//! Rotation matrices the joints are made of: about coordinate axes, about any unit axis
//! (Rodrigues), and of a unit quaternion.
use crate::support::spatial::{Mat3, Vec3};
use crate::support::trig::sin_cos;

pub fn rot_x(a: f64) -> Mat3 {
    let (s, c) = sin_cos(a);
    Mat3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}
pub fn rot_y(a: f64) -> Mat3 {
    let (s, c) = sin_cos(a);
    Mat3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}
pub fn rot_z(a: f64) -> Mat3 {
    let (s, c) = sin_cos(a);
    Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Rotation by `angle` about the unit vector `e` (Rodrigues: `c 1 + s ẽ + (1 − c) e eᵀ`).
#[inline]
pub fn axis_angle(e: &Vec3, angle: f64) -> Mat3 {
    let (s, c) = sin_cos(angle);
    let t = 1.0 - c;
    let (x, y, z) = (e.x, e.y, e.z);
    Mat3::new(
        c + t * x * x,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        c + t * y * y,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        c + t * z * z,
    )
}

/// Below this a quaternion's direction is mostly rounding of whatever produced it.
pub const MIN_QUATERNION_NORM: f64 = 1e-8;

/// The norm of a quaternion `(x, y, z, w)`; scaled by its largest part first when the sum of
/// squares overflows or underflows (a quaternion of norm 1e155 is still a rotation), which
/// only the rare unnormal case pays for.
#[inline]
pub fn quat_norm(q: &[f64]) -> f64 {
    let n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    if n2.is_normal() {
        return n2.sqrt();
    }
    let m = q[..4].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 || !m.is_finite() {
        return n2.sqrt();
    }
    m * q[..4].iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt()
}

/// Rotation matrix of a quaternion `(x, y, z, w)`, normalised first.
pub fn quat_to_matrix(q: &[f64]) -> Mat3 {
    let n = quat_norm(q);
    let (x, y, z, w) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    Mat3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - z * w),
        2.0 * (x * z + y * w),
        2.0 * (x * y + z * w),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - x * w),
        2.0 * (x * z - y * w),
        2.0 * (y * z + x * w),
        1.0 - 2.0 * (x * x + y * y),
    )
}
