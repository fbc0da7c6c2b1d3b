//! A toy joint, compiled in the test build only: the complete file that
//! docs/adding-a-joint.md shows (tests/test_guides.py holds the guide's copy equal to this
//! file). A ball joint on Cardan angles `q = (α, β, γ)`: the body is `Rx(α) Ry(β) Rz(γ)` in
//! the joint frame, the angle rates are its speeds, and it is singular where cos β = 0.
use super::{turn_columns, JointType, LocalMotion, MotionClass, Subspace, ZYZ_SINGULAR_SIN};
use crate::joint::rotation::{rot_x, rot_y, rot_z};
use crate::support::spatial::{stack, Mat3, Vec3, Vec6};
use crate::support::trig::sin_cos;

pub struct ToyCardan;

/// The columns in the joint frame, `[e_x, Rx(α) e_y, Rx(α) Ry(β) e_z]`: each fixed in the
/// frame the angles before it leave.
fn joint_columns(q: &[f64]) -> Mat3 {
    let (sa, ca) = sin_cos(q[0]);
    let (sb, cb) = sin_cos(q[1]);
    Mat3::new(1.0, 0.0, sb, 0.0, ca, -sa * cb, 0.0, sa, ca * cb)
}

impl JointType for ToyCardan {
    const NAME: &'static str = "ToyCardan";
    const NQ: usize = 3;
    const MOTION: MotionClass = MotionClass::Angular3;
    const URDF_TYPE: &'static str = "toy_cardan";
    /// Three revolutes in a chain (x, then y, then z), as the ZYZ joint.
    const CHAINED_COLUMNS: bool = true;

    fn q_is_angle(&self, _k: usize) -> bool {
        true
    }
    /// A ball: a pin without an axis.
    fn pin(&self) -> Option<Vec3> {
        Some(Vec3::zeros())
    }
    fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        (rot_x(q[0]) * rot_y(q[1]) * rot_z(q[2]), Vec3::zeros())
    }
    fn subspace(&self, q: &[f64], r_joint: &Mat3, _r_body: &Mat3) -> Subspace {
        let w = r_joint * joint_columns(q);
        let mut s = [Vec6::zeros(); 6];
        for (k, col) in s.iter_mut().take(3).enumerate() {
            *col = stack(&w.column(k).into_owned(), &Vec3::zeros());
        }
        s
    }
    /// The columns turn with the parent and also change with α and β.
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
        let (sa, ca) = sin_cos(q[0]);
        let (sb, cb) = sin_cos(q[1]);
        let (da, db) = (v[0], v[1]);
        let d1 = Vec3::new(0.0, -sa * da, ca * da);
        let d2 = Vec3::new(
            cb * db,
            -ca * cb * da + sa * sb * db,
            -sa * cb * da - ca * sb * db,
        );
        d[1] += stack(&(r_joint * d1), &Vec3::zeros());
        d[2] += stack(&(r_joint * d2), &Vec3::zeros());
        d
    }
    /// Not constant: [`local_motion`](JointType::local_motion) gives them.
    fn local_columns(&self) -> [Vec3; 3] {
        [Vec3::zeros(); 3]
    }
    /// Body-frame columns `S = [Rz(−γ) Ry(−β) e_x, Rz(−γ) e_y, e_z]`, `w = S q̇`, `Ṡ q̇`.
    fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion {
        let (sb, cb) = sin_cos(q[1]);
        let (sc, cc) = sin_cos(q[2]);
        let s = [
            Vec3::new(cb * cc, -cb * sc, sb),
            Vec3::new(sc, cc, 0.0),
            Vec3::z(),
        ];
        let (da, db, dc) = (v[0], v[1], v[2]);
        let d0 = Vec3::new(
            -sb * cc * db - cb * sc * dc,
            sb * sc * db - cb * cc * dc,
            cb * db,
        );
        let d1 = Vec3::new(cc * dc, -sc * dc, 0.0);
        LocalMotion {
            rotation: Some(self.transform(q).0),
            columns: Some(s),
            w: s[0] * da + s[1] * db + s[2] * dc,
            sdot_qd: d0 * da + d1 * db,
            ..LocalMotion::default()
        }
    }
    /// The columns lose rank where cos β = 0 (refused at the ZYZ joint's threshold).
    fn singularity(&self, q: &[f64]) -> Option<f64> {
        let c = q[1].cos();
        (c.abs() < ZYZ_SINGULAR_SIN).then_some(c)
    }
    fn describe_singularity(&self, q: &[f64], q_index: usize) -> String {
        format!(
            "is at its Euler singularity: cos(beta) = {:.3e} (beta = q[{}] = {})",
            q[1].cos(),
            q_index + 1,
            q[1]
        )
    }
}

#[cfg(test)]
mod tests {
    use crate::joint::{axis_angle, Joint};
    use crate::model::body::RigidBody;
    use crate::model::Model;
    use crate::recursive::{forward_dynamics, Data};
    use crate::support::spatial::{Mat3, Placement, Vec3};
    use nalgebra::{Rotation3, UnitQuaternion};

    const Q: [f64; 3] = [0.4, -0.7, 1.3];
    const QD: [f64; 3] = [0.9, -0.5, 1.2];

    fn vee(m: &Mat3) -> Vec3 {
        Vec3::new(m[(2, 1)], m[(0, 2)], m[(1, 0)])
    }

    /// Its rotation, columns and their rates against Rodrigues' rotations and central
    /// differences along a path `q + t q̇` (the parent turning at `w_p`).
    #[test]
    fn the_toy_cardan_joint_is_its_rotation() {
        let j = Joint::ToyCardan;
        let at = |t: f64| [Q[0] + t * QD[0], Q[1] + t * QD[1], Q[2] + t * QD[2]];
        let rodrigues = |q: [f64; 3]| {
            axis_angle(&Vec3::x(), q[0])
                * axis_angle(&Vec3::y(), q[1])
                * axis_angle(&Vec3::z(), q[2])
        };
        assert!((j.transform(&Q).0 - rodrigues(Q)).norm() < 1e-15);
        let h = 1e-6;
        let r = j.transform(&Q).0;
        let rdot = (rodrigues(at(h)) - rodrigues(at(-h))) / (2.0 * h);
        let w_joint = vee(&(rdot * r.transpose())); // joint frame
        let w_body = vee(&(r.transpose() * rdot));
        let local = j.local_motion(&Q, &QD);
        assert!((local.w - w_body).norm() < 1e-8);
        let s_body = |q: [f64; 3]| j.local_motion(&q, &QD).columns.unwrap();
        let (sp, sm) = (s_body(at(h)), s_body(at(-h)));
        let sdot_qd: Vec3 = (0..3).map(|k| (sp[k] - sm[k]) / (2.0 * h) * QD[k]).sum();
        assert!((local.sdot_qd - sdot_qd).norm() < 1e-8);
        // World columns, in a joint frame that turns with the parent at w_p.
        let w_p = Vec3::new(0.3, -0.8, 0.5);
        let r0 = *Rotation3::from_scaled_axis(Vec3::new(0.2, 0.5, -0.4)).matrix();
        let r_joint = |t: f64| axis_angle(&w_p.normalize(), t * w_p.norm()) * r0;
        let s = j.subspace(&Q, &r0, &(r0 * r));
        let w: Vec3 = (0..3).map(|k| s[k].fixed_rows::<3>(0) * QD[k]).sum();
        assert!((w - r0 * w_joint).norm() < 1e-8);
        let world = |t: f64| j.subspace(&at(t), &r_joint(t), &Mat3::identity());
        let rate = j.subspace_rate(&Q, &QD, &s, &r0, &w_p, &Vec3::zeros());
        for k in 0..3 {
            let fd = (world(h)[k] - world(-h)[k]) / (2.0 * h);
            assert!((rate[k] - fd).norm() < 1e-8, "column {k}");
        }
        assert!(j
            .singularity(&[0.0, std::f64::consts::FRAC_PI_2, 0.0])
            .is_some());
        assert_eq!((j.nq(), j.nv(), j.repr().as_str()), (3, 3, "ToyCardan()"));
    }

    /// A body with a child on the toy joint moves as on the quaternion `Spherical` joint:
    /// `ω_b = S q̇` and `ω̇_b = S q̈ + Ṡ q̇` with the ball's accelerations, under gravity.
    #[test]
    fn the_toy_cardan_joint_moves_as_the_ball_joint() {
        let inertia = Mat3::new(0.05, 0.005, 0.0, 0.005, 0.04, -0.004, 0.0, -0.004, 0.03);
        let body = RigidBody::new(1.5, Vec3::new(0.1, -0.2, 0.4), inertia).unwrap();
        let on = |ball: Joint| {
            let mut m = Model::new();
            let place = Placement::new(Mat3::identity(), Vec3::new(0.0, 0.0, 1.0));
            m.add_body(body, ball, None, place, None, None).unwrap();
            let hinge = Joint::revolute(Vec3::new(1.0, 1.0, 0.0)).unwrap();
            let below = Placement::new(Mat3::identity(), Vec3::new(0.3, 0.0, 0.5));
            m.add_body(body, hinge, Some(0), below, None, None).unwrap();
            m
        };
        let g = Vec3::new(0.0, 0.0, -9.81);
        let tau = [0.2, -0.1, 0.3, 0.05];
        let cardan = on(Joint::ToyCardan);
        let (q, v) = ([Q[0], Q[1], Q[2], 0.6], [QD[0], QD[1], QD[2], -0.4]);
        let mut a = [0.0; 4];
        forward_dynamics(
            &cardan,
            &mut Data::new(&cardan),
            &q,
            &v,
            &tau,
            &g,
            None,
            &mut a,
        )
        .unwrap();

        let ball = on(Joint::Spherical);
        let r = Joint::ToyCardan.transform(&Q).0;
        let quat = UnitQuaternion::from_matrix(&r);
        let qb = [quat.i, quat.j, quat.k, quat.w, q[3]];
        let local = Joint::ToyCardan.local_motion(&Q, &QD);
        let s = local.columns.unwrap();
        let vb = [local.w.x, local.w.y, local.w.z, v[3]];
        // The same torques: τ_ball = S⁻ᵀ τ_cardan (equal power for every speed).
        let s_mat = Mat3::from_columns(&s);
        let t = s_mat.transpose().try_inverse().unwrap() * Vec3::new(tau[0], tau[1], tau[2]);
        let tau_b = [t.x, t.y, t.z, tau[3]];
        let mut ab = [0.0; 4];
        forward_dynamics(
            &ball,
            &mut Data::new(&ball),
            &qb,
            &vb,
            &tau_b,
            &g,
            None,
            &mut ab,
        )
        .unwrap();
        // Ṡ q̇ by central differences, not the joint's own term (which its dynamics use).
        let h = 1e-6;
        let s_at = |t: f64| {
            let qt = [Q[0] + t * QD[0], Q[1] + t * QD[1], Q[2] + t * QD[2]];
            Joint::ToyCardan.local_motion(&qt, &QD).columns.unwrap()
        };
        let (sp, sm) = (s_at(h), s_at(-h));
        let sdot_qd: Vec3 = (0..3).map(|k| (sp[k] - sm[k]) / (2.0 * h) * QD[k]).sum();
        let wdot = s_mat * Vec3::new(a[0], a[1], a[2]) + sdot_qd;
        assert!((wdot - Vec3::new(ab[0], ab[1], ab[2])).norm() < 1e-8 * wdot.norm());
        assert!((a[3] - ab[3]).abs() < 1e-10 * a[3].abs().max(1.0));
        // Refused at its singularity, with its message.
        let q_bad = [0.1, std::f64::consts::FRAC_PI_2, 0.2, 0.0];
        let err = forward_dynamics(
            &cardan,
            &mut Data::new(&cardan),
            &q_bad,
            &v,
            &tau,
            &g,
            None,
            &mut a,
        );
        assert!(err.unwrap_err().to_string().contains("cos(beta)"));
    }
}
