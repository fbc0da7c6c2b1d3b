//! Spherical (ball) joint with a unit quaternion `q = (x, y, z, w)` (Pinocchio's order) and
//! the body's angular velocity relative to its parent, in body axes, as its three speeds:
//! `P = [R_body; 0]` (world axes), the identity columns in the body frame. No coordinate
//! singularity; `q̇ = ½ q ⊗ (v, 0)`.
use super::{turn_columns, JointType, LocalMotion, MotionClass, Subspace};
use crate::error::{check_finite, Error, Result};
use crate::joint::rotation::quat_to_matrix;
use crate::spatial::{stack, Mat3, Vec3, Vec6};

pub struct Spherical;

impl JointType for Spherical {
    const NAME: &'static str = "Spherical";
    const NQ: usize = 4;
    const MOTION: MotionClass = MotionClass::Angular3;

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
        let mut s = [Vec6::zeros(); 3];
        for (k, col) in s.iter_mut().enumerate() {
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
    /// `q̇ = ½ q ⊗ (v, 0)`, with the quaternion normalised so `q̇` does not depend on |q|.
    fn velocity_to_qdot(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) {
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let (x, y, z, w) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
        let (a, b, c) = (v[0], v[1], v[2]);
        qdot[0] = 0.5 * (w * a + y * c - z * b);
        qdot[1] = 0.5 * (w * b + z * a - x * c);
        qdot[2] = 0.5 * (w * c + x * b - y * a);
        qdot[3] = -0.5 * (x * a + y * b + z * c);
    }
    /// Finite, and a quaternion of usable norm.
    fn check_configuration(&self, q: &[f64], arg: &str) -> Result<()> {
        check_finite(arg, q)?;
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        if !(n > 1e-8) {
            return Err(Error::arg(
                arg,
                "a quaternion (x, y, z, w) of non-zero norm for a Spherical joint",
                format!("[{}, {}, {}, {}] (norm {n:.3e})", q[0], q[1], q[2], q[3]),
            ));
        }
        Ok(())
    }
}
