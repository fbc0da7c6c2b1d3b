//! Free-flyer joint: six degrees of freedom, Pinocchio's `JointModelFreeFlyer` convention.
//! `q = (x, y, z, qx, qy, qz, qw)`: the body origin in the joint frame, then the body's
//! orientation as a unit quaternion; `v = (v, ω)`: the origin's linear velocity relative to
//! the joint frame and the angular velocity, both in **body** axes. So the motion columns
//! are constant in the body frame, `S = 1₆` (in our `[angular; linear]` twist order the
//! linear speeds come first), and in world axes they are the body's axes:
//! `P = [[0, R]; [R, 0]]` by columns. `ṗ = R v`, `q̇_quat = ½ q ⊗ (ω, 0)`. No coordinate
//! singularity. The body-frame recursions give it its own inward and outward steps
//! ([`MotionClass::Free`]): with `S = 1` the joint block is the whole articulated inertia.
use super::spherical::{check_quaternion, quaternion_rate};
use super::{quaternion, JacobianRows, JointType, LocalMotion, MotionClass, Subspace};
use crate::joint::rotation::quat_to_matrix;
use crate::support::error::Result;
use crate::support::spatial::{skew, stack, Mat3, Vec3, Vec6};
use nalgebra::DMatrixViewMut;

pub struct FreeFlyer;

impl JointType for FreeFlyer {
    const NAME: &'static str = "FreeFlyer";
    const NQ: usize = 7;
    const MOTION: MotionClass = MotionClass::Free;
    const URDF_TYPE: &'static str = "floating";
    const QUATERNION_AT: Option<usize> = Some(3);

    fn neutral(&self, q: &mut [f64]) {
        q.fill(0.0);
        q[6] = 1.0;
    }
    /// Positions and quaternion parts are not angles.
    fn q_is_angle(&self, _k: usize) -> bool {
        false
    }
    #[inline]
    fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        (quat_to_matrix(&q[3..7]), Vec3::new(q[0], q[1], q[2]))
    }
    /// Linear speeds first: `[0; R e_k]`, then angular `[R e_k; 0]` (k = 0, 1, 2).
    #[inline]
    fn subspace(&self, _q: &[f64], _r_joint: &Mat3, r_body: &Mat3) -> Subspace {
        let mut s = [Vec6::zeros(); 6];
        let z = Vec3::zeros();
        for k in 0..3 {
            let axis = r_body.column(k).into_owned();
            s[k] = stack(&z, &axis);
            s[3 + k] = stack(&axis, &z);
        }
        s
    }
    /// All six columns are body axes: they turn with the body.
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
        let mut d = [Vec6::zeros(); 6];
        for (dk, sk) in d.iter_mut().zip(s) {
            let (a, l) = (
                sk.fixed_rows::<3>(0).into_owned(),
                sk.fixed_rows::<3>(3).into_owned(),
            );
            *dk = stack(&w_body.cross(&a), &w_body.cross(&l));
        }
        d
    }
    /// Unused: the free-flyer steps of the recursions know `S = 1`.
    fn local_columns(&self) -> [Vec3; 3] {
        [Vec3::x(), Vec3::y(), Vec3::z()]
    }
    #[inline]
    fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion {
        LocalMotion {
            rotation: Some(quat_to_matrix(&q[3..7])),
            displacement: Some(Vec3::new(q[0], q[1], q[2])),
            v: Vec3::new(v[0], v[1], v[2]),
            w: Vec3::new(v[3], v[4], v[5]),
            ..LocalMotion::default()
        }
    }
    /// `ṗ = R v` (body-axes velocity to joint-frame rates), quaternion as the ball joint.
    fn velocity_to_qdot(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) {
        let p_dot = quat_to_matrix(&q[3..7]) * Vec3::new(v[0], v[1], v[2]);
        qdot[..3].copy_from_slice(p_dot.as_slice());
        quaternion_rate(&q[3..7], &v[3..6], &mut qdot[3..7]);
    }
    /// Finite, and a quaternion of usable norm.
    fn check_configuration(&self, q: &[f64], arg: &str) -> Result<()> {
        check_quaternion(q, 3, arg, Self::NAME)
    }
    /// The origin moved by `R δ_lin`, the body turned by `R exp(δ_ang)`.
    fn integrate(&self, q: &[f64], delta: &[f64], out: &mut [f64]) {
        let r = quat_to_matrix(&q[3..7]);
        let p = r * Vec3::new(delta[0], delta[1], delta[2]);
        for k in 0..3 {
            out[k] = q[k] + p[k];
        }
        quaternion::step(&q[3..7], &delta[3..6], &mut out[3..7]);
    }
    /// `Rᵀ` on the origin, the quaternion's map on the orientation.
    fn tangent_map(&self, q: &[f64], t: &mut DMatrixViewMut<'_, f64>) {
        let rot = quat_to_matrix(&q[3..7]);
        for r in 0..3 {
            for c in 0..3 {
                t[(r, c)] = rot[(c, r)];
            }
        }
        quaternion::tangent_into(&q[3..7], t, 3, 3);
    }
    /// `ṗ = R v`: `∂/∂v = R`, `∂/∂quat = −R ṽ ∂δ/∂quat`; the quaternion as the ball joint.
    fn qdot_jacobian(&self, q: &[f64], v: &[f64], jac: &mut JacobianRows<'_>) {
        let qq = &q[3..7];
        let rot = quat_to_matrix(qq);
        let vl = Vec3::new(v[0], v[1], v[2]);
        let rv: Mat3 = -rot * skew(&vl);
        let t = quaternion::tangent(qq);
        for r in 0..3 {
            for c in 0..3 {
                jac.set_v(r, c, rot[(r, c)]);
            }
            for c in 0..4 {
                jac.set_q(r, 3 + c, (0..3).map(|k| rv[(r, k)] * t[k][c]).sum::<f64>());
            }
        }
        quaternion::rate_blocks(qq, &v[3..6], jac, 3, 3);
    }
}
