//! Regularised Coulomb joint friction: `τ = −F tanh(v / v_eps)` on each speed of a 1-dof or
//! Euler-angle joint, and `τ = −F tanh(|ω| / v_eps) ω/|ω|` (isotropic, frame-independent) on
//! a quaternion spherical joint's angular velocity `ω`. `F` is the friction torque (N·m) or
//! force (N) reached when sliding well above `v_eps`; below it the law is viscous with slope
//! `F / v_eps`, which keeps the equations smooth (no stick-slip switching). Power ≤ 0.
use super::scene_writer as w;
use super::{joints_repr, label_repr, one_number, Effect, TomlType};
use super::{
    required, resolve_joints, Context, Declaration, Fields, ForceLaw, JointRef, Kind, PerJoint,
    Sign,
};
use crate::joint::Joint;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec6;

/// Default regularisation speed (rad/s or m/s).
pub const DEFAULT_V_EPS: f64 = 1e-3;

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Friction {
    pub name: Option<String>,
    /// `None`: every moving joint.
    pub joints: Option<Vec<JointRef>>,
    /// Friction level `F`, one number or one per selected joint.
    pub friction: PerJoint,
    /// Regularisation speed `v_eps > 0`.
    pub v_eps: f64,
}

impl Friction {
    pub fn new(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        friction: PerJoint,
        v_eps: Option<f64>,
    ) -> Result<Friction> {
        friction.check("friction", Sign::NonNegative)?;
        let v_eps = v_eps.unwrap_or(DEFAULT_V_EPS);
        // The law uses 1 / v_eps: a subnormal v_eps would make it inf and 0 · inf = NaN.
        if !(v_eps > 0.0 && v_eps.is_finite() && (1.0 / v_eps).is_finite()) {
            return Err(Error::arg(
                "v_eps",
                "a finite number > 0 whose reciprocal is finite (>= 5.6e-309)",
                format!("{v_eps:e}"),
            ));
        }
        Ok(Friction {
            name,
            joints,
            friction,
            v_eps,
        })
    }

    pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<Friction> {
        let (name, joints) = f.name_and_joints()?;
        let friction = f.per_joint("friction")?;
        let v_eps = f.number("v_eps")?;
        let friction = required(friction, "friction", "a number >= 0 or one per joint")?;
        Friction::new(name, joints, friction, v_eps)
    }
}

impl Declaration for Friction {
    fn to_toml(&self) -> Result<toml::Table> {
        Ok(w::EffectTable::new("friction", self.label())
            .joints(&self.joints)
            .set("friction", w::per_joint(&self.friction))
            .set("v_eps", w::number(self.v_eps))
            .done())
    }
    fn parameters(&self) -> &'static [&'static str] {
        &["friction", "v_eps"]
    }
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let (friction, v_eps) = match key {
            "friction" => (PerJoint::from_values(values), self.v_eps),
            _ => (self.friction.clone(), one_number(key, values)?),
        };
        let e = Friction::new(
            self.name.clone(),
            self.joints.clone(),
            friction,
            Some(v_eps),
        )?;
        Ok(Effect::Friction(e))
    }
    fn repr(&self) -> String {
        let label = label_repr(self.label());
        let joints = joints_repr(&self.joints);
        format!(
            "JointFriction(joints={joints}, v_eps={}{label})",
            self.v_eps
        )
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "friction",
            keys: &["name", "joints", "friction", "v_eps"],
            parse: |_, f| Friction::from_toml(f).map(Effect::Friction),
        }];
        TYPES
    }
    fn kind(&self) -> Kind {
        Kind::Friction
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let slots = resolve_joints(model, &self.joints, "joints")?;
        let f = self.friction.expand(slots.len(), "friction", "joint")?;
        let mut law = FrictionLaw {
            scalar: Vec::new(),
            ball: Vec::new(),
            inv_eps: 1.0 / self.v_eps,
        };
        for (s, f) in slots.iter().zip(f) {
            match s.joint {
                Joint::Spherical => law.ball.push((s.v_index, f)),
                // Isotropic in the body's linear and in its angular velocity.
                Joint::FreeFlyer => law.ball.extend([(s.v_index, f), (s.v_index + 3, f)]),
                _ => law.scalar.extend(s.speeds().map(|i| (i, f))),
            }
        }
        Ok(Box::new(law))
    }
}

pub struct FrictionLaw {
    scalar: Vec<(usize, f64)>,
    ball: Vec<(usize, f64)>,
    inv_eps: f64,
}

impl ForceLaw for FrictionLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        for &(i, f) in &self.scalar {
            tau[i] -= f * (cx.v[i] * self.inv_eps).tanh();
        }
        for &(i, f) in &self.ball {
            let w = &cx.v[i..i + 3];
            let s = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            if s > 0.0 {
                let c = f * (s * self.inv_eps).tanh() / s;
                for k in 0..3 {
                    tau[i + k] -= c * w[k];
                }
            }
        }
        Ok(false)
    }

    /// The smooth law's derivative, `∂τ/∂v = −F sech²(v/ε)/ε` (scalar); for a ball joint,
    /// `τ = −F φ(s) w` with `φ(s) = tanh(s/ε)/s`, `s = |w|`: `∂τ/∂w = −F (φ 1 + φ'(s)/s w wᵀ)`,
    /// by its series near `s = 0` (where it tends to `−F/ε 1`).
    fn add_derivatives(
        &mut self,
        cx: &Context<'_>,
        _dq: &mut nalgebra::DMatrix<f64>,
        dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        let ie = self.inv_eps;
        for &(i, f) in &self.scalar {
            let c = (cx.v[i] * ie).cosh();
            dv[(i, i)] -= f * ie / (c * c);
        }
        for &(i, f) in &self.ball {
            let w = &cx.v[i..i + 3];
            let s = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            let x = s * ie;
            let (phi, dphi_s) = if x < 1e-4 {
                // tanh(x)/x = 1 − x²/3 + …
                (ie * (1.0 - x * x / 3.0), -2.0 / 3.0 * ie * ie * ie)
            } else {
                let t = x.tanh();
                let sech2 = 1.0 - t * t;
                (t / s, (sech2 * ie * s - t) / (s * s * s))
            };
            for r in 0..3 {
                for c in 0..3 {
                    let d = if r == c { phi } else { 0.0 };
                    dv[(i + r, i + c)] -= f * (d + dphi_s * w[r] * w[c]);
                }
            }
        }
        Ok(true)
    }
}
