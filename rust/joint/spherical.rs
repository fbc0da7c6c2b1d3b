//! Spherical (ball) joint with a unit quaternion `q = (x, y, z, w)` (Pinocchio's order) and
//! the body's angular velocity relative to its parent, in body axes, as its three speeds:
//! `P = [R_body; 0]` (world axes), the identity columns in the body frame. No coordinate
//! singularity; `q̇ = ½ q ⊗ (v, 0)`.
use super::{
    quaternion, turn_columns, JacobianRows, JointType, LocalMotion, MotionClass, Subspace,
};
use crate::joint::rotation::{quat_norm, quat_to_matrix, MIN_QUATERNION_NORM};
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::{stack, Mat3, Vec3, Vec6};
use nalgebra::DMatrixViewMut;

pub struct Spherical;

impl JointType for Spherical {
    const NAME: &'static str = "Spherical";
    const NQ: usize = 4;
    const MOTION: MotionClass = MotionClass::Angular3;
    const URDF_TYPE: &'static str = "spherical";
    const QUATERNION_AT: Option<usize> = Some(0);

    /// A ball: a pin without an axis.
    fn pin(&self) -> Option<Vec3> {
        Some(Vec3::zeros())
    }
    fn neutral(&self, q: &mut [f64]) {
        q.fill(0.0);
        q[3] = 1.0;
    }
    /// Quaternion parts are not angles.
    fn q_is_angle(&self, _k: usize) -> bool {
        false
    }
    #[inline]
    fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        (quat_to_matrix(q), Vec3::zeros())
    }
    #[inline]
    fn subspace(&self, _q: &[f64], _r_joint: &Mat3, r_body: &Mat3) -> Subspace {
        let mut s = [Vec6::zeros(); 6];
        for (k, col) in s.iter_mut().take(3).enumerate() {
            *col = stack(&r_body.column(k).into_owned(), &Vec3::zeros());
        }
        s
    }
    /// The columns are the body's axes: they turn with the body.
    #[inline]
    fn subspace_rate(
        &self,
        _q: &[f64],
        _v: &[f64],
        s: &Subspace,
        _r: &Mat3,
        _wp: &Vec3,
        w_body: &Vec3,
    ) -> Subspace {
        turn_columns::<3>(s, w_body, true)
    }
    fn local_columns(&self) -> [Vec3; 3] {
        [Vec3::x(), Vec3::y(), Vec3::z()]
    }
    #[inline]
    fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion {
        LocalMotion {
            rotation: Some(quat_to_matrix(q)),
            w: Vec3::new(v[0], v[1], v[2]),
            ..LocalMotion::default()
        }
    }
    /// `q̇ = ½ q ⊗ (v, 0)`.
    fn velocity_to_qdot(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) {
        quaternion_rate(q, v, qdot);
    }
    /// Finite, and a quaternion of usable norm.
    fn check_configuration(&self, q: &[f64], arg: &str) -> Result<()> {
        check_quaternion(q, 0, arg, Self::NAME)
    }
    /// The body turned by `R exp(δ)`.
    fn integrate(&self, q: &[f64], delta: &[f64], out: &mut [f64]) {
        quaternion::step(q, delta, out);
    }
    fn tangent_map(&self, q: &[f64], t: &mut DMatrixViewMut<'_, f64>) {
        quaternion::tangent_into(q, t, 0, 0);
    }
    fn qdot_jacobian(&self, q: &[f64], v: &[f64], jac: &mut JacobianRows<'_>) {
        quaternion::rate_blocks(q, v, jac, 0, 0);
    }
}

/// `q̇ = ½ q ⊗ (w, 0)` for a quaternion `(x, y, z, w)` and a body-axes angular velocity, with
/// the quaternion normalised so `q̇` does not depend on |q|.
pub(super) fn quaternion_rate(q: &[f64], v: &[f64], qdot: &mut [f64]) {
    let n = quat_norm(q);
    let (x, y, z, w) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    let (a, b, c) = (v[0], v[1], v[2]);
    qdot[0] = 0.5 * (w * a + y * c - z * b);
    qdot[1] = 0.5 * (w * b + z * a - x * c);
    qdot[2] = 0.5 * (w * c + x * b - y * a);
    qdot[3] = -0.5 * (x * a + y * b + z * c);
}

/// Checks a joint's coordinates `q`, finite, with a quaternion of usable norm at
/// `q[at..at + 4]`.
pub(super) fn check_quaternion(q: &[f64], at: usize, arg: &str, joint: &str) -> Result<()> {
    check_finite(arg, q)?;
    let h = &q[at..at + 4];
    let n = quat_norm(h);
    if !(n >= MIN_QUATERNION_NORM) {
        return Err(Error::arg(
            arg,
            format!(
                "a quaternion (x, y, z, w) of norm at least {MIN_QUATERNION_NORM:e} for a {joint} joint (it is normalised; smaller ones have lost their direction to rounding)"
            ),
            format!("[{:?}, {:?}, {:?}, {:?}] (norm {n:.3e})", h[0], h[1], h[2], h[3]),
        ));
    }
    Ok(())
}
