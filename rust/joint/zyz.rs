//! The paper's spherical joint: ZYZ Euler angles `q = (φ, θ, ψ)`, body = `Rz(φ) Ry(θ) Rz(ψ)`
//! in the joint frame, Euler rates as speeds (paper eq 38b). Singular where sin θ = 0: the
//! joint is refused there (use the quaternion `Spherical` joint through θ = 0 or π).
use super::{turn_columns, JointType, LocalMotion, MotionClass, Subspace};
use crate::joint::rotation::{rot_y, rot_z};
use crate::support::spatial::{stack, Mat3, Vec3, Vec6};
use crate::support::trig::sin_cos;

/// `|sin θ|` below which a `SphericalZYZ` joint is refused as singular: the Euler rates for a
/// finite angular velocity grow like 1/sin θ and the joint's columns of the GIM lose rank, so
/// accelerations there would be rounding noise.
pub const ZYZ_SINGULAR_SIN: f64 = 1e-6;

/// `L(φ, θ)` of paper eq 38b: relative angular velocity (joint frame) = `L q̇` for ZYZ angles.
pub fn zyz_rate_matrix(phi: f64, theta: f64) -> Mat3 {
    let (sp, cp) = sin_cos(phi);
    let (st, ct) = sin_cos(theta);
    Mat3::new(0.0, -sp, cp * st, 0.0, cp, sp * st, 1.0, 0.0, ct)
}

pub struct SphericalZyz;

impl JointType for SphericalZyz {
    const NAME: &'static str = "SphericalZYZ";
    const NQ: usize = 3;
    const MOTION: MotionClass = MotionClass::Angular3;
    /// Three revolutes in a chain: each column is fixed in the frame of the angles before it.
    const CHAINED_COLUMNS: bool = true;
    const URDF_TYPE: &'static str = "spherical_zyz";

    /// A ball: a pin without an axis.
    fn pin(&self) -> Option<Vec3> {
        Some(Vec3::zeros())
    }
    fn q_is_angle(&self, _k: usize) -> bool {
        true
    }
    #[inline]
    fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        (rot_z(q[0]) * rot_y(q[1]) * rot_z(q[2]), Vec3::zeros())
    }
    /// The columns of `L(φ, θ)` in world axes.
    #[inline]
    fn subspace(&self, q: &[f64], r_joint: &Mat3, _r_body: &Mat3) -> Subspace {
        let w = r_joint * zyz_rate_matrix(q[0], q[1]);
        let mut s = [Vec6::zeros(); 6];
        for (k, col) in s.iter_mut().take(3).enumerate() {
            *col = stack(&w.column(k).into_owned(), &Vec3::zeros());
        }
        s
    }
    /// The columns turn with the parent and also change with φ and θ.
    #[inline]
    fn subspace_rate(
        &self,
        q: &[f64],
        v: &[f64],
        s: &Subspace,
        r_joint: &Mat3,
        w_parent: &Vec3,
        _w_body: &Vec3,
    ) -> Subspace {
        let mut d = turn_columns::<3>(s, w_parent, true);
        let (sp, cp) = sin_cos(q[0]);
        let (st, ct) = sin_cos(q[1]);
        let (dphi, dtheta) = (v[0], v[1]);
        let dl1 = Vec3::new(-cp * dphi, -sp * dphi, 0.0);
        let dl2 = Vec3::new(
            -sp * st * dphi + cp * ct * dtheta,
            cp * st * dphi + sp * ct * dtheta,
            -st * dtheta,
        );
        d[1] += stack(&(r_joint * dl1), &Vec3::zeros());
        d[2] += stack(&(r_joint * dl2), &Vec3::zeros());
        d
    }
    /// Not constant: [`local_motion`](JointType::local_motion) gives them.
    fn local_columns(&self) -> [Vec3; 3] {
        [Vec3::zeros(); 3]
    }
    /// Rotation, body-frame columns `S = [R_qᵀ e_z, Rz(−ψ) e_y, e_z]` (independent of φ),
    /// `w = S q̇` and `Ṡ q̇`, with one sine and cosine per angle.
    #[inline]
    fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion {
        let (sp, cp) = sin_cos(q[0]);
        let (st, ct) = sin_cos(q[1]);
        let (ss, cs) = sin_cos(q[2]);
        // Rz(φ) Ry(θ) Rz(ψ).
        let rotation = Mat3::new(
            cp * ct * cs - sp * ss,
            -cp * ct * ss - sp * cs,
            cp * st,
            sp * ct * cs + cp * ss,
            -sp * ct * ss + cp * cs,
            sp * st,
            -st * cs,
            st * ss,
            ct,
        );
        let s = [
            Vec3::new(-st * cs, st * ss, ct),
            Vec3::new(ss, cs, 0.0),
            Vec3::z(),
        ];
        let (dphi, dtheta, dpsi) = (v[0], v[1], v[2]);
        // Ṡ q̇: the body-frame columns turn with θ and ψ.
        let d0 = Vec3::new(
            -ct * cs * dtheta + st * ss * dpsi,
            ct * ss * dtheta + st * cs * dpsi,
            -st * dtheta,
        );
        let d1 = Vec3::new(cs * dpsi, -ss * dpsi, 0.0);
        LocalMotion {
            rotation: Some(rotation),
            columns: Some(s),
            w: s[0] * dphi + s[1] * dtheta + s[2] * dpsi,
            sdot_qd: d0 * dphi + d1 * dtheta,
            ..LocalMotion::default()
        }
    }
    #[inline]
    fn singularity(&self, q: &[f64]) -> Option<f64> {
        let s = q[1].sin();
        (s.abs() < ZYZ_SINGULAR_SIN).then_some(s)
    }
    fn describe_singularity(&self, q: &[f64], q_index: usize) -> String {
        format!(
            "is at an Euler singularity: sin(theta) = {:.3e} (theta = q[{}] = {}); use the quaternion Spherical joint for motions through theta = 0 or pi",
            q[1].sin(),
            q_index + 1,
            q[1]
        )
    }
}
