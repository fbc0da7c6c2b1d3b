//! Viscous joint dampers: `τ = −c v` on every speed of each selected joint (isotropic on the
//! 3 speeds of a spherical joint). Power `−c |v|²`.
use super::{resolve_joints, Context, Fields, ForceLaw, JointRef, PerJoint, Sign};
use crate::error::{Error, Result};
use crate::model::Model;
use crate::spatial::Vec6;

/// Keys of a `type = "damper"` table.
pub(super) const KEYS: &[&str] = &["name", "joints", "damping"];

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
        let name = f.string("name")?;
        let joints = f.joints("joints")?;
        let damping = f
            .per_joint("damping")?
            .ok_or_else(|| Error::arg("damping", "a number >= 0 or one per joint", "nothing"))?;
        Damper::new(name, joints, damping)
    }

    pub fn build(&self, model: &Model) -> Result<DamperLaw> {
        let slots = resolve_joints(model, &self.joints, "joints")?;
        let c = self.damping.expand(slots.len(), "damping", "joint")?;
        let mut dofs = Vec::new();
        for (s, c) in slots.iter().zip(c) {
            for k in 0..s.joint.nv() {
                dofs.push((s.v_index + k, c));
            }
        }
        Ok(DamperLaw { dofs })
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
}
