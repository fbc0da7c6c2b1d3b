//! Joints: configuration, the rotation/translation they produce, and their joint-motion
//! propagation matrix `P` (design.md §2) with its time derivative.
//!
//! Coordinates follow Pinocchio so models compare one to one: a revolute/prismatic `q` is
//! the angle/displacement along the axis given in the joint frame; `Spherical` stores a unit
//! quaternion `(x, y, z, w)` and its 3 speeds are the body's angular velocity relative to its
//! parent, in the body frame; `SphericalZYZ` is the paper's Euler-angle joint with Euler
//! rates as speeds (singular where sin θ = 0).
use crate::error::{Error, Result};
use crate::spatial::{stack, Mat3, Vec3, Vec6};
use crate::trig::sin_cos;

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Joint {
    Revolute { axis: Vec3 },
    Prismatic { axis: Vec3 },
    SphericalZYZ,
    Spherical,
    Fixed,
}

/// Columns of `P` (world coordinates), `dof` of them in use.
pub type Subspace = [Vec6; 3];

fn unit_axis(axis: Vec3) -> Result<Vec3> {
    let largest = axis.amax();
    if !axis.iter().all(|x| x.is_finite()) || largest == 0.0 {
        return Err(Error::arg(
            "axis",
            "a finite, non-zero 3-vector",
            format!("[{}, {}, {}]", axis.x, axis.y, axis.z),
        ));
    }
    let n = axis.norm();
    if n.is_finite() && n > 1e-100 {
        return Ok(axis / n);
    }
    // The squares overflow (|x| > 1e154) or underflow: divide by the largest entry first.
    let scaled = axis / largest;
    Ok(scaled / scaled.norm())
}

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

/// Rotation matrix of a quaternion `(x, y, z, w)`, normalised first.
pub fn quat_to_matrix(q: &[f64]) -> Mat3 {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
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

/// `L(φ, θ)` of paper eq 38b: relative angular velocity (joint frame) = `L q̇` for ZYZ angles.
pub fn zyz_rate_matrix(phi: f64, theta: f64) -> Mat3 {
    let (sp, cp) = sin_cos(phi);
    let (st, ct) = sin_cos(theta);
    Mat3::new(0.0, -sp, cp * st, 0.0, cp, sp * st, 1.0, 0.0, ct)
}

/// `|sin θ|` below which a `SphericalZYZ` joint is refused as singular: the Euler rates for a
/// finite angular velocity grow like 1/sin θ and the joint's columns of the GIM lose rank, so
/// accelerations there would be rounding noise.
pub const ZYZ_SINGULAR_SIN: f64 = 1e-6;

impl Joint {
    /// `Some(sin θ)` when this joint is at (or too near) its coordinate singularity.
    #[inline]
    pub fn singularity(&self, q: &[f64]) -> Option<f64> {
        match self {
            Joint::SphericalZYZ => {
                let s = q[1].sin();
                (s.abs() < ZYZ_SINGULAR_SIN).then_some(s)
            }
            _ => None,
        }
    }

    pub fn revolute(axis: Vec3) -> Result<Joint> {
        Ok(Joint::Revolute {
            axis: unit_axis(axis)?,
        })
    }
    pub fn prismatic(axis: Vec3) -> Result<Joint> {
        Ok(Joint::Prismatic {
            axis: unit_axis(axis)?,
        })
    }

    pub fn nq(&self) -> usize {
        match self {
            Joint::Revolute { .. } | Joint::Prismatic { .. } => 1,
            Joint::SphericalZYZ => 3,
            Joint::Spherical => 4,
            Joint::Fixed => 0,
        }
    }
    pub fn nv(&self) -> usize {
        match self {
            Joint::Revolute { .. } | Joint::Prismatic { .. } => 1,
            Joint::SphericalZYZ | Joint::Spherical => 3,
            Joint::Fixed => 0,
        }
    }
    /// Whether coordinate `k` of this joint's `q` is an angle (scaled by a file's angle
    /// unit): revolute and ZYZ angles are; quaternion parts and displacements are not.
    #[inline]
    pub fn q_is_angle(&self, k: usize) -> bool {
        k < self.nq() && matches!(self, Joint::Revolute { .. } | Joint::SphericalZYZ)
    }
    /// Whether speed `k` of this joint is an angular rate (every speed of every joint
    /// but `Prismatic`).
    #[inline]
    pub fn v_is_angular(&self, k: usize) -> bool {
        k < self.nv() && self.moves_angular()
    }
    /// Whether the joint's motion subspace is purely angular (`P = [A; 0]`) rather than
    /// purely linear (`[0; A]`): true for every joint but `Prismatic`.
    #[inline]
    pub fn moves_angular(&self) -> bool {
        !matches!(self, Joint::Prismatic { .. })
    }

    pub fn kind(&self) -> &'static str {
        match self {
            Joint::Revolute { .. } => "Revolute",
            Joint::Prismatic { .. } => "Prismatic",
            Joint::SphericalZYZ => "SphericalZYZ",
            Joint::Spherical => "Spherical",
            Joint::Fixed => "Fixed",
        }
    }

    pub fn neutral(&self, q: &mut [f64]) {
        q.fill(0.0);
        if let Joint::Spherical = self {
            q[3] = 1.0;
        }
    }

    /// Rotation and translation of the body frame in the joint frame at configuration `q`.
    #[inline]
    pub fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        match self {
            Joint::Revolute { axis } => (axis_angle(axis, q[0]), Vec3::zeros()),
            Joint::Prismatic { axis } => (Mat3::identity(), axis * q[0]),
            Joint::SphericalZYZ => (rot_z(q[0]) * rot_y(q[1]) * rot_z(q[2]), Vec3::zeros()),
            Joint::Spherical => (quat_to_matrix(q), Vec3::zeros()),
            Joint::Fixed => (Mat3::identity(), Vec3::zeros()),
        }
    }

    /// Columns of `P` in world coordinates. `r_joint` is the joint frame's orientation (the
    /// parent's orientation times the fixed placement), `r_body` the body's.
    #[inline]
    pub fn subspace(&self, q: &[f64], r_joint: &Mat3, r_body: &Mat3) -> Subspace {
        let z = Vec3::zeros();
        let mut s = [Vec6::zeros(); 3];
        match self {
            Joint::Revolute { axis } => s[0] = stack(&(r_joint * axis), &z),
            Joint::Prismatic { axis } => s[0] = stack(&z, &(r_joint * axis)),
            Joint::SphericalZYZ => {
                let w = r_joint * zyz_rate_matrix(q[0], q[1]);
                for k in 0..3 {
                    s[k] = stack(&w.column(k).into_owned(), &z);
                }
            }
            Joint::Spherical => {
                for k in 0..3 {
                    s[k] = stack(&r_body.column(k).into_owned(), &z);
                }
            }
            Joint::Fixed => {}
        }
        s
    }

    /// Time derivative of the columns of `P`, given the parent's angular velocity `w_parent`,
    /// the body's `w_body` and the joint speeds `v`. Axes fixed in the joint frame turn with
    /// the parent; the quaternion joint's columns turn with the body; the ZYZ columns also
    /// change with φ and θ.
    #[inline]
    pub fn subspace_rate(
        &self,
        q: &[f64],
        v: &[f64],
        s: &Subspace,
        r_joint: &Mat3,
        w_parent: &Vec3,
        w_body: &Vec3,
    ) -> Subspace {
        let mut d = [Vec6::zeros(); 3];
        let z = Vec3::zeros();
        let turn = |col: &Vec6, w: &Vec3, angular_part: bool| -> Vec6 {
            if angular_part {
                stack(&w.cross(&col.fixed_rows::<3>(0).into_owned()), &z)
            } else {
                stack(&z, &w.cross(&col.fixed_rows::<3>(3).into_owned()))
            }
        };
        match self {
            Joint::Revolute { .. } => d[0] = turn(&s[0], w_parent, true),
            Joint::Prismatic { .. } => d[0] = turn(&s[0], w_parent, false),
            Joint::SphericalZYZ => {
                let (sp, cp) = sin_cos(q[0]);
                let (st, ct) = sin_cos(q[1]);
                let (dphi, dtheta) = (v[0], v[1]);
                let dl1 = Vec3::new(-cp * dphi, -sp * dphi, 0.0);
                let dl2 = Vec3::new(
                    -sp * st * dphi + cp * ct * dtheta,
                    cp * st * dphi + sp * ct * dtheta,
                    -st * dtheta,
                );
                d[0] = turn(&s[0], w_parent, true);
                d[1] = turn(&s[1], w_parent, true) + stack(&(r_joint * dl1), &z);
                d[2] = turn(&s[2], w_parent, true) + stack(&(r_joint * dl2), &z);
            }
            Joint::Spherical => {
                for k in 0..3 {
                    d[k] = turn(&s[k], w_body, true);
                }
            }
            Joint::Fixed => {}
        }
        d
    }

    /// `q̇` from the speeds `v` (they differ only for the quaternion joint:
    /// `q̇ = ½ q ⊗ (v, 0)`, with the quaternion normalised so `q̇` does not depend on |q|).
    pub fn velocity_to_qdot(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) {
        match self {
            Joint::Spherical => {
                let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
                let (x, y, z, w) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
                let (a, b, c) = (v[0], v[1], v[2]);
                qdot[0] = 0.5 * (w * a + y * c - z * b);
                qdot[1] = 0.5 * (w * b + z * a - x * c);
                qdot[2] = 0.5 * (w * c + x * b - y * a);
                qdot[3] = -0.5 * (x * a + y * b + z * c);
            }
            _ => qdot.copy_from_slice(v),
        }
    }

    /// Checks a configuration: finite, and a quaternion of usable norm.
    pub fn check_configuration(&self, q: &[f64], arg: &str) -> Result<()> {
        crate::error::check_finite(arg, q)?;
        if let Joint::Spherical = self {
            let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
            if !(n > 1e-8) {
                return Err(Error::arg(
                    arg,
                    "a quaternion (x, y, z, w) of non-zero norm for a Spherical joint",
                    format!("[{}, {}, {}, {}] (norm {n:.3e})", q[0], q[1], q[2], q[3]),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
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
}
