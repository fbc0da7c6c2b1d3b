//! Compliant joint ranges, family `limits`: on a revolute or prismatic joint with range
//! `[lower, upper]`, a one-sided spring–damper pushes back only outside it:
//!
//! * below: `δ = lower − q > 0`, `τ = max(0, k δ − c q̇)`;
//! * above: `δ = q − upper > 0`, `τ = −max(0, k δ + c q̇)`;
//!
//! zero inside the range. The `max` keeps the damper from pulling the joint back into the
//! wall as it leaves. Potential `½ k δ²` (in `energies`); the power is `−dV/dt − c q̇²`
//! (or 0 ≤ −dV/dt where the `max` is active): a limit never adds energy. Infinite bounds are
//! allowed (a one-sided range, or none). Without `lower`/`upper` the model's own limits are
//! used ([`JointLimit::with_model_limits`]: URDF `<limit>`, MJCF `range`).
use super::scene_writer as w;
use super::{joints_repr, label_repr, Effect, TomlType};
use super::{
    required, resolve_joints, Context, Declaration, Fields, ForceLaw, JointRef, JointSlot, Kind,
    PerJoint, Sign,
};
use crate::joint::Joint;
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec6;

/// Keys of a `type = "joint_limit"` table.
const KEYS: &[&str] = &["name", "joints", "lower", "upper", "stiffness", "damping"];

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointLimit {
    pub name: Option<String>,
    /// `None`: every revolute and prismatic joint.
    pub joints: Option<Vec<JointRef>>,
    /// Bounds (rad or m; ±inf allowed), one number or one per selected joint; `None`: the
    /// model's own (filled in by [`JointLimit::with_model_limits`]).
    pub lower: Option<PerJoint>,
    pub upper: Option<PerJoint>,
    /// `k` ≥ 0 (N·m/rad or N/m) and `c` ≥ 0 (N·m·s/rad or N·s/m).
    pub stiffness: PerJoint,
    pub damping: PerJoint,
}

/// The largest finite bound (rad or m): a billion radians is 160 million turns, a billion
/// metres beyond any mechanism; larger finite bounds overflow `k δ` at run time. ±inf is
/// the way to say "no bound".
pub const MAX_BOUND: f64 = 1e9;

/// A bound may be ±inf (no bound on that side) or a number within ±[`MAX_BOUND`], not NaN.
fn check_bound(arg: &str, b: &Option<PerJoint>) -> Result<()> {
    let fine = |x: &f64| x.is_infinite() || x.abs() <= MAX_BOUND;
    let bad = |x: f64, at: String| {
        Error::arg(
            arg,
            format!("numbers within ±{MAX_BOUND:e} (rad or m), or ±inf for no bound"),
            format!("{}{at}", crate::support::error::num(x)),
        )
    };
    match b {
        None => Ok(()),
        Some(PerJoint::All(x)) if !fine(x) => Err(bad(*x, String::new())),
        Some(PerJoint::Each(v)) if v.is_empty() => {
            Err(Error::arg(arg, "a number or a non-empty list", "[]"))
        }
        Some(PerJoint::Each(v)) => match v.iter().position(|x| !fine(x)) {
            Some(k) => Err(bad(v[k], format!(" at index {k}"))),
            None => Ok(()),
        },
        _ => Ok(()),
    }
}

impl JointLimit {
    pub fn new(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        lower: Option<PerJoint>,
        upper: Option<PerJoint>,
        stiffness: PerJoint,
        damping: PerJoint,
    ) -> Result<JointLimit> {
        check_bound("lower", &lower)?;
        check_bound("upper", &upper)?;
        stiffness.check("stiffness", Sign::NonNegative)?;
        damping.check("damping", Sign::NonNegative)?;
        // lower > upper where both are known as numbers now; per-joint lists are compared
        // again in `build`, once their lengths are checked.
        if let (Some(lo), Some(up)) = (&lower, &upper) {
            let n = match (lo, up) {
                (PerJoint::Each(a), _) => a.len(),
                (_, PerJoint::Each(b)) => b.len(),
                _ => 1,
            };
            if let (Ok(a), Ok(b)) = (
                lo.expand(n, "lower", "joint"),
                up.expand(n, "upper", "joint"),
            ) {
                check_order(&a, &b, |k| format!("entry {k}"))?;
            }
        }
        Ok(JointLimit {
            name,
            joints,
            lower,
            upper,
            stiffness,
            damping,
        })
    }

    pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<JointLimit> {
        let (name, joints) = f.name_and_joints()?;
        let lower = f.per_joint("lower")?;
        let upper = f.per_joint("upper")?;
        let stiffness = f.per_joint("stiffness")?;
        let damping = f.per_joint("damping")?;
        let stiffness = required(stiffness, "stiffness", "a number >= 0 or one per joint")?;
        let damping = required(damping, "damping", "a number >= 0 or one per joint")?;
        JointLimit::new(name, joints, lower, upper, stiffness, damping)
    }

    /// The selected joints: the given ones (each must be revolute or prismatic), or every
    /// revolute and prismatic joint.
    fn slots(&self, model: &Model) -> Result<Vec<JointSlot>> {
        let slots = resolve_joints(model, &self.joints, "joints")?;
        if self.joints.is_none() {
            let slots: Vec<JointSlot> = slots.into_iter().filter(|s| one_dof(s.joint)).collect();
            if slots.is_empty() {
                return Err(Error::arg(
                    "joints",
                    "a model with revolute or prismatic joints (the only joints a JointLimit acts on)",
                    "a model that has no 1-dof joints",
                ));
            }
            return Ok(slots);
        }
        if let Some(s) = slots.iter().find(|s| !one_dof(s.joint)) {
            return Err(Error::arg(
                "joints",
                "revolute or prismatic joints (a range on one coordinate)",
                format!("body '{}' on a {} joint", s.name, s.joint.kind()),
            ));
        }
        Ok(slots)
    }

    /// A copy whose missing bounds are the model's: `limit(link)` gives `(lower, upper)` of
    /// a link's joint (±inf where the file gives none).
    pub fn with_model_limits(
        &self,
        model: &Model,
        limit: impl Fn(usize) -> (f64, f64),
    ) -> Result<JointLimit> {
        if self.lower.is_some() && self.upper.is_some() {
            return Ok(self.clone());
        }
        let slots = self.slots(model)?;
        let mut out = self.clone();
        if out.lower.is_none() {
            out.lower = Some(PerJoint::Each(
                slots.iter().map(|s| limit(s.link).0).collect(),
            ));
        }
        if out.upper.is_none() {
            out.upper = Some(PerJoint::Each(
                slots.iter().map(|s| limit(s.link).1).collect(),
            ));
        }
        let unbounded = |b: &Option<PerJoint>| match b {
            Some(PerJoint::Each(v)) => v.iter().all(|x| x.is_infinite()),
            _ => false,
        };
        if self.lower.is_none()
            && self.upper.is_none()
            && unbounded(&out.lower)
            && unbounded(&out.upper)
        {
            return Err(Error::arg(
                "lower",
                "numbers, or a model whose selected joints have limits (URDF <limit>, MJCF range)",
                "no bounds, and a model without limits on these joints",
            ));
        }
        Ok(out)
    }
}

fn one_dof(j: Joint) -> bool {
    matches!(j, Joint::Revolute { .. } | Joint::Prismatic { .. })
}

fn check_order(lower: &[f64], upper: &[f64], at: impl Fn(usize) -> String) -> Result<()> {
    match lower.iter().zip(upper).position(|(a, b)| a > b) {
        None => Ok(()),
        Some(k) => Err(Error::arg(
            "lower",
            "bounds with lower <= upper",
            format!(
                "lower {} > upper {} ({})",
                crate::support::error::num(lower[k]),
                crate::support::error::num(upper[k]),
                at(k)
            ),
        )),
    }
}

impl Declaration for JointLimit {
    fn to_toml(&self) -> Result<toml::Table> {
        Ok(w::EffectTable::new("joint_limit", self.label())
            .joints(&self.joints)
            .maybe("lower", self.lower.as_ref().map(w::per_joint))
            .maybe("upper", self.upper.as_ref().map(w::per_joint))
            .set("stiffness", w::per_joint(&self.stiffness))
            .set("damping", w::per_joint(&self.damping))
            .done())
    }
    fn kind(&self) -> Kind {
        Kind::Limits
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn parameters(&self) -> &'static [&'static str] {
        &["lower", "upper", "stiffness", "damping"]
    }
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let given = || Some(PerJoint::from_values(values));
        let mut e = self.clone();
        match key {
            "lower" => e.lower = given(),
            "upper" => e.upper = given(),
            "stiffness" => e.stiffness = PerJoint::from_values(values),
            _ => e.damping = PerJoint::from_values(values),
        }
        let e = JointLimit::new(e.name, e.joints, e.lower, e.upper, e.stiffness, e.damping)?;
        Ok(Effect::JointLimit(e))
    }
    fn repr(&self) -> String {
        let bounds = if self.lower.is_none() || self.upper.is_none() {
            "the model's"
        } else {
            "given"
        };
        format!(
            "JointLimit(joints={}, bounds={bounds}{})",
            joints_repr(&self.joints),
            label_repr(self.label())
        )
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "joint_limit",
            keys: KEYS,
            parse: |_, f| JointLimit::from_toml(f).map(Effect::JointLimit),
        }];
        TYPES
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let slots = self.slots(model)?;
        let missing = "numbers, or a model that has limits (from_urdf's <limit>, from_mujoco's range): give lower and upper";
        let lower = self
            .lower
            .as_ref()
            .ok_or_else(|| Error::arg("lower", missing, "nothing"))?;
        let upper = self
            .upper
            .as_ref()
            .ok_or_else(|| Error::arg("upper", missing, "nothing"))?;
        let n = slots.len();
        let lower = lower.expand(n, "lower", "joint")?;
        let upper = upper.expand(n, "upper", "joint")?;
        check_order(&lower, &upper, |k| format!("body '{}'", slots[k].name))?;
        let k = self.stiffness.expand(n, "stiffness", "joint")?;
        let c = self.damping.expand(n, "damping", "joint")?;
        let ranges = slots
            .iter()
            .enumerate()
            .filter(|(i, _)| lower[*i].is_finite() || upper[*i].is_finite())
            .map(|(i, s)| Range {
                q: s.q_index,
                v: s.v_index,
                lower: lower[i],
                upper: upper[i],
                k: k[i],
                c: c[i],
            })
            .collect();
        Ok(Box::new(JointLimitLaw { ranges }))
    }
}

struct Range {
    q: usize,
    v: usize,
    lower: f64,
    upper: f64,
    k: f64,
    c: f64,
}

impl Range {
    /// `(τ, active)`: the force at `(q, q̇)`, and whether the spring–damper is engaged
    /// (outside the range and not let go by the `max`).
    #[inline]
    fn force(&self, q: f64, v: f64) -> (f64, bool) {
        if q < self.lower {
            let t = self.k * (self.lower - q) - self.c * v;
            if t > 0.0 {
                return (t, true);
            }
        } else if q > self.upper {
            let t = self.k * (q - self.upper) + self.c * v;
            if t > 0.0 {
                return (-t, true);
            }
        }
        (0.0, false)
    }
}

pub struct JointLimitLaw {
    ranges: Vec<Range>,
}

impl ForceLaw for JointLimitLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        for r in &self.ranges {
            tau[r.v] += r.force(cx.q[r.q], cx.v[r.v]).0;
        }
        Ok(false)
    }

    /// `−k` and `−c` on the diagonal where a range is engaged, 0 elsewhere.
    fn add_derivatives(
        &mut self,
        cx: &Context<'_>,
        dq: &mut nalgebra::DMatrix<f64>,
        dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        for r in &self.ranges {
            if r.force(cx.q[r.q], cx.v[r.v]).1 {
                dq[(r.v, r.v)] -= r.k;
                dv[(r.v, r.v)] -= r.c;
            }
        }
        Ok(true)
    }

    fn potential_energy(&self, cx: &Context<'_>, _links: &[LinkState]) -> Option<f64> {
        let mut e = 0.0;
        for r in &self.ranges {
            let q = cx.q[r.q];
            let d = if q < r.lower {
                r.lower - q
            } else if q > r.upper {
                q - r.upper
            } else {
                0.0
            };
            e += 0.5 * r.k * d * d;
        }
        Some(e)
    }
}

/// `(lower, upper, effort)` of each link's joint from a URDF's joints (±inf bounds where
/// there is no `<limit>`, and always for continuous joints; inf effort where none): what
/// [`JointLimit::with_model_limits`] and a torque's `"effort"` limit take.
pub fn limits_by_link(
    model: &Model,
    joints: &[crate::model::joint_records::UrdfJoint],
) -> Vec<[f64; 3]> {
    let inf = f64::INFINITY;
    let mut out = vec![[-inf, inf, inf]; model.links.len()];
    for j in joints {
        if let (Some(link), Some(lim)) = (j.link, j.limit) {
            if link < out.len() && model.links[link].body == j.body {
                out[link] = [lim.lower, lim.upper, lim.effort];
            }
        }
    }
    out
}

/// Fills what the declarations in `effects` take from the model: the missing bounds of
/// joint limits and the `"effort"` limits of torques, from the model's URDF joints
/// (`urdf_joints`, empty for a model built otherwise: no bounds, no effort), and a ground
/// contact's default stiffness and damping, from the model's weight
/// ([`super::GroundContact::resolved`]), so that the scene reports the values it runs with.
/// Errors name `{list}[k].field`.
pub fn fill_model_limits(
    model: &Model,
    urdf_joints: &[crate::model::joint_records::UrdfJoint],
    effects: &mut [Effect],
    list: &str,
) -> Result<()> {
    let needed = effects.iter().any(|e| match e {
        Effect::JointLimit(l) => l.lower.is_none() || l.upper.is_none(),
        Effect::Torque(t) => t.limit == Some(super::TorqueLimit::Effort),
        Effect::GroundContact(c) => c.stiffness.is_none() || c.damping.is_none(),
        _ => false,
    });
    if !needed {
        return Ok(());
    }
    let limits = limits_by_link(model, urdf_joints);
    for (k, e) in effects.iter_mut().enumerate() {
        let filled = match e {
            Effect::JointLimit(l) => l
                .with_model_limits(model, |link| (limits[link][0], limits[link][1]))
                .map(Effect::JointLimit),
            Effect::Torque(t) => t
                .with_model_effort(model, |link| limits[link][2])
                .map(Effect::Torque),
            Effect::GroundContact(c) => c.with_model_defaults(model).map(Effect::GroundContact),
            _ => continue,
        };
        *e = filled.map_err(|x| x.in_arg(&format!("{list}[{k}]")))?;
    }
    Ok(())
}

#[cfg(test)]
#[path = "tests/joint_limit.rs"]
mod tests;
