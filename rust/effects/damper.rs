//! Viscous joint dampers: `τ = −c v` on every speed of each selected joint (isotropic on the
//! 3 speeds of a spherical joint). Power `−c |v|²`.
use super::scene_writer as w;
use super::{joints_repr, label_repr, Effect, TomlType};
use super::{
    required, resolve_joints, Context, Declaration, Fields, ForceLaw, JointRef, Kind, PerJoint,
    Sign,
};
use crate::model::Model;
use crate::support::error::Result;
use crate::support::spatial::Vec6;

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Damper {
    pub name: Option<String>,
    /// `None`: every moving joint.
    pub joints: Option<Vec<JointRef>>,
    /// N·m·s/rad or N·s/m, one number or one per selected joint.
    pub damping: PerJoint,
}

impl Damper {
    pub fn new(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        damping: PerJoint,
    ) -> Result<Damper> {
        damping.check("damping", Sign::NonNegative)?;
        Ok(Damper {
            name,
            joints,
            damping,
        })
    }

    pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<Damper> {
        let (name, joints) = f.name_and_joints()?;
        let damping = f.per_joint("damping")?;
        let damping = required(damping, "damping", "a number >= 0 or one per joint")?;
        Damper::new(name, joints, damping)
    }
}

impl Declaration for Damper {
    fn to_toml(&self) -> Result<toml::Table> {
        Ok(w::EffectTable::new("damper", self.label())
            .joints(&self.joints)
            .set("damping", w::per_joint(&self.damping))
            .done())
    }
    fn parameters(&self) -> &'static [&'static str] {
        &["damping"]
    }
    fn with_parameter(&self, _key: &str, values: &[f64]) -> Result<Effect> {
        let c = PerJoint::from_values(values);
        let e = Damper::new(self.name.clone(), self.joints.clone(), c)?;
        Ok(Effect::Damper(e))
    }
    fn repr(&self) -> String {
        let label = label_repr(self.label());
        format!("Damper(joints={}{label})", joints_repr(&self.joints))
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "damper",
            keys: &["name", "joints", "damping"],
            parse: |_, f| Damper::from_toml(f).map(Effect::Damper),
        }];
        TYPES
    }
    fn kind(&self) -> Kind {
        Kind::Dampers
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let slots = resolve_joints(model, &self.joints, "joints")?;
        let c = self.damping.expand(slots.len(), "damping", "joint")?;
        let dofs = slots
            .iter()
            .zip(c)
            .flat_map(|(s, c)| s.speeds().map(move |i| (i, c)))
            .collect();
        Ok(Box::new(DamperLaw { dofs }))
    }
}

pub struct DamperLaw {
    dofs: Vec<(usize, f64)>,
}

impl ForceLaw for DamperLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        for &(i, c) in &self.dofs {
            tau[i] -= c * cx.v[i];
        }
        Ok(false)
    }

    /// `∂τ/∂v = −c` on each damped speed.
    fn add_derivatives(
        &mut self,
        _cx: &Context<'_>,
        _dq: &mut nalgebra::DMatrix<f64>,
        dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        for &(i, c) in &self.dofs {
            dv[(i, i)] -= c;
        }
        Ok(true)
    }
}
