//! Joint springs. On a revolute or prismatic joint: `τ = −k (q − q_rest)`, potential
//! `½ k (q − q_rest)²`. On a quaternion `Spherical` joint: an isotropic rotational spring on
//! the rotation vector `θ = log(q_rest⁻¹ q)` (|θ| ≤ π) of the joint rotation relative to its
//! rest orientation: `τ = −k θ` (body-frame speeds, which is exactly `−∂V/∂` of the potential
//! `½ k |θ|²` since `θ` is an eigenvector of the SO(3) Jacobians). Euler-angle
//! (`SphericalZYZ`) joints are refused: use the quaternion joint.
use super::scene_writer as w;
use super::{joints_repr, label_repr, Effect, TomlType};
use super::{
    required, resolve_joints, Context, Declaration, Fields, ForceLaw, JointRef, Kind, PerJoint,
    Sign,
};
use crate::joint::Joint;
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec6;

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Spring {
    pub name: Option<String>,
    /// `None`: every moving joint.
    pub joints: Option<Vec<JointRef>>,
    /// N·m/rad or N/m, one number or one per selected joint.
    pub stiffness: PerJoint,
    /// Rest configuration: one number for every 1-dof joint (quaternion joints then rest at
    /// the identity), or the selected joints' coordinates in order (1 per revolute or
    /// prismatic joint, 4 per quaternion joint: x, y, z, w).
    pub rest: PerJoint,
}

impl Spring {
    pub fn new(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        stiffness: PerJoint,
        rest: Option<PerJoint>,
    ) -> Result<Spring> {
        stiffness.check("stiffness", Sign::NonNegative)?;
        let rest = rest.unwrap_or(PerJoint::All(0.0));
        rest.check("rest", Sign::Any)?;
        Ok(Spring {
            name,
            joints,
            stiffness,
            rest,
        })
    }

    pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<Spring> {
        let (name, joints) = f.name_and_joints()?;
        let stiffness = f.per_joint("stiffness")?;
        let rest = f.per_joint("rest")?;
        let stiffness = required(stiffness, "stiffness", "a number >= 0 or one per joint")?;
        Spring::new(name, joints, stiffness, rest)
    }
}

impl Declaration for Spring {
    fn to_toml(&self) -> Result<toml::Table> {
        Ok(w::EffectTable::new("spring", self.label())
            .joints(&self.joints)
            .set("stiffness", w::per_joint(&self.stiffness))
            .set("rest", w::per_joint(&self.rest))
            .done())
    }
    fn parameters(&self) -> &'static [&'static str] {
        &["stiffness", "rest"]
    }
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let x = PerJoint::from_values(values);
        let (k, rest) = match key {
            "stiffness" => (x, self.rest.clone()),
            _ => (self.stiffness.clone(), x),
        };
        let e = Spring::new(self.name.clone(), self.joints.clone(), k, Some(rest))?;
        Ok(Effect::Spring(e))
    }
    fn repr(&self) -> String {
        let label = label_repr(self.label());
        format!("Spring(joints={}{label})", joints_repr(&self.joints))
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "spring",
            keys: &["name", "joints", "stiffness", "rest"],
            parse: |_, f| Spring::from_toml(f).map(Effect::Spring),
        }];
        TYPES
    }
    fn kind(&self) -> Kind {
        Kind::Springs
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let slots = resolve_joints(model, &self.joints, "joints")?;
        let k = self.stiffness.expand(slots.len(), "stiffness", "joint")?;
        let ncoords: usize = slots.iter().map(|s| s.joint.nq()).sum();
        let mut law = SpringLaw {
            linear: Vec::new(),
            ball: Vec::new(),
        };
        let mut at = 0; // position in a flat `rest` list
        if let PerJoint::Each(r) = &self.rest {
            if r.len() != ncoords {
                return Err(Error::arg(
                    "rest",
                    format!("a number for the 1-dof joints, or {ncoords} values: the selected joints' coordinates (1 per revolute/prismatic joint, 4 per quaternion joint)"),
                    format!("{} values", r.len()),
                ));
            }
        }
        for (s, k) in slots.iter().zip(k) {
            match s.joint {
                Joint::Revolute { .. } | Joint::Prismatic { .. } => {
                    let rest = match &self.rest {
                        PerJoint::All(x) => *x,
                        PerJoint::Each(r) => r[at],
                    };
                    law.linear.push(Linear {
                        q: s.q_index,
                        v: s.v_index,
                        k,
                        rest,
                    });
                }
                Joint::Spherical => {
                    let mut r = [0.0, 0.0, 0.0, 1.0];
                    if let PerJoint::Each(given) = &self.rest {
                        r.copy_from_slice(&given[at..at + 4]);
                    }
                    let n = crate::joint::rotation::quat_norm(&r);
                    let min = crate::joint::rotation::MIN_QUATERNION_NORM;
                    if !(n >= min && n.is_finite()) {
                        return Err(Error::arg(
                            "rest",
                            format!("a finite quaternion (x, y, z, w) of norm at least {min:e} for a Spherical joint"),
                            format!("{r:?} for body '{}'", s.name),
                        ));
                    }
                    law.ball.push(Ball {
                        q: s.q_index,
                        v: s.v_index,
                        k,
                        rest_conj: [-r[0] / n, -r[1] / n, -r[2] / n, r[3] / n],
                    });
                }
                _ => {
                    return Err(Error::arg(
                        "joints",
                        "revolute, prismatic or quaternion Spherical joints (a spring on Euler angles is not a rotational spring: use the Spherical joint; a free flyer is held by a point spring or external forces)",
                        format!("body '{}' on a {} joint", s.name, s.joint.kind()),
                    ))
                }
            }
            at += s.joint.nq();
        }
        Ok(Box::new(law))
    }
}

struct Linear {
    q: usize,
    v: usize,
    k: f64,
    rest: f64,
}

struct Ball {
    q: usize,
    v: usize,
    k: f64,
    /// Conjugate of the (unit) rest quaternion.
    rest_conj: [f64; 4],
}

pub struct SpringLaw {
    linear: Vec<Linear>,
    ball: Vec<Ball>,
}

/// Rotation vector (|θ| ≤ π) of `r ⊗ q/|q|`, quaternions `(x, y, z, w)`.
#[inline]
pub fn relative_rotation_vector(r: &[f64; 4], q: &[f64]) -> [f64; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (bx, by, bz, bw) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    let (ax, ay, az, aw) = (r[0], r[1], r[2], r[3]);
    let mut w = aw * bw - (ax * bx + ay * by + az * bz);
    let mut x = aw * bx + bw * ax + (ay * bz - az * by);
    let mut y = aw * by + bw * ay + (az * bx - ax * bz);
    let mut z = aw * bz + bw * az + (ax * by - ay * bx);
    if w < 0.0 {
        (w, x, y, z) = (-w, -x, -y, -z);
    }
    let s = (x * x + y * y + z * z).sqrt();
    let factor = if s > 0.0 {
        2.0 * s.atan2(w) / s
    } else {
        2.0 / w
    };
    [factor * x, factor * y, factor * z]
}

impl ForceLaw for SpringLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        for s in &self.linear {
            tau[s.v] -= s.k * (cx.q[s.q] - s.rest);
        }
        for s in &self.ball {
            let th = relative_rotation_vector(&s.rest_conj, &cx.q[s.q..s.q + 4]);
            for (k, x) in th.iter().enumerate() {
                tau[s.v + k] -= s.k * x;
            }
        }
        Ok(false)
    }

    /// `−k` for a linear spring; for a ball spring `τ = −k θ`, `θ = log(r ⊗ q)`, and a right
    /// perturbation `q ⊗ exp(δ)` moves `θ` by `J_r⁻¹(θ) δ` (the inverse right Jacobian of
    /// SO(3)): `∂τ/∂δ = −k J_r⁻¹(θ)`. At `|θ| = π` the shortest rotation flips: the
    /// one-sided value is returned there.
    fn add_derivatives(
        &mut self,
        cx: &Context<'_>,
        dq: &mut nalgebra::DMatrix<f64>,
        _dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        for s in &self.linear {
            dq[(s.v, s.v)] -= s.k;
        }
        for s in &self.ball {
            let th = relative_rotation_vector(&s.rest_conj, &cx.q[s.q..s.q + 4]);
            let j =
                inverse_right_jacobian(&crate::support::spatial::Vec3::new(th[0], th[1], th[2]));
            for r in 0..3 {
                for c in 0..3 {
                    dq[(s.v + r, s.v + c)] -= s.k * j[(r, c)];
                }
            }
        }
        Ok(true)
    }

    fn potential_energy(&self, cx: &Context<'_>, _links: &[LinkState]) -> Option<f64> {
        let mut e = 0.0;
        for s in &self.linear {
            let d = cx.q[s.q] - s.rest;
            e += 0.5 * s.k * d * d;
        }
        for s in &self.ball {
            let th = relative_rotation_vector(&s.rest_conj, &cx.q[s.q..s.q + 4]);
            e += 0.5 * s.k * (th[0] * th[0] + th[1] * th[1] + th[2] * th[2]);
        }
        Some(e)
    }
}

/// `J_r⁻¹(θ) = 1 + ½ θ̃ + (1/|θ|² − (1 + cos|θ|)/(2|θ| sin|θ|)) θ̃²`: how `log(exp(θ̃) exp(δ̃))`
/// moves with `δ` at 0 (series below |θ| = 1e-4, where the coefficient tends to 1/12).
pub fn inverse_right_jacobian(th: &crate::support::spatial::Vec3) -> crate::support::spatial::Mat3 {
    let t = th.norm();
    let c = if t < 1e-4 {
        1.0 / 12.0 + t * t / 720.0
    } else {
        1.0 / (t * t) - (1.0 + t.cos()) / (2.0 * t * t.sin())
    };
    let s = crate::support::spatial::skew(th);
    crate::support::spatial::Mat3::identity() + s * 0.5 + s * s * c
}
