//! Rotor inertia (armature): a motor's rotor, seen through its gearbox, adds `armature ·
//! q̈` to its joint's force and `armature` to the joint's diagonal entry of the mass matrix
//! (MuJoCo's `armature`, Pinocchio's `model.armature`; docs/couplings.md §3). Every
//! algorithm adds it: the articulated-body recursion to the joint block `D` (a link with
//! armature takes the general 1-dof path, [`super::compiled`]), inverse dynamics `τ +=
//! armature · a`, the mass matrix and the explicit DeNOC products its diagonal, the kinetic
//! energy `½ armature v²`. A model without armature (`Model::armature` empty) skips all of it.
use nalgebra::DMatrix;

use crate::joint::MotionClass;
use crate::model::Model;
use crate::support::error::{Error, Result};

impl Model {
    /// Sets the armature of body `body`'s joint: one value per speed of the joint (or one
    /// for all of them), finite and `≥ 0`. Refused on a free flyer, whose body's own inertia
    /// is the joint block, and on a body welded to its parent.
    pub fn set_armature(&mut self, body: usize, values: &[f64]) -> Result<()> {
        let n = self.bodies.len();
        let l = self
            .bodies
            .get(body)
            .and_then(|b| b.link)
            .filter(|&l| self.links[l].body == body)
            .ok_or_else(|| {
                Error::arg(
                    "joint",
                    "a body on a moving joint (index or name)",
                    match self.bodies.get(body) {
                        Some(b) => format!("body '{}' on a fixed joint", b.name),
                        None => format!("{body} (the model has {n} bodies)"),
                    },
                )
            })?;
        let link = &self.links[l];
        let nv = link.joint.nv();
        if link.joint.motion() == MotionClass::Free {
            return Err(Error::arg(
                "joint",
                "a revolute, prismatic or spherical joint (a free flyer has no rotor)",
                format!("the free-flyer joint of body '{}'", self.bodies[body].name),
            ));
        }
        let values: Vec<f64> = match values {
            [x] => vec![*x; nv],
            xs if xs.len() == nv => xs.to_vec(),
            xs => {
                return Err(Error::arg(
                    "value",
                    format!("one number, or {nv} (one per speed of the joint)"),
                    format!("{} numbers", xs.len()),
                ))
            }
        };
        if let Some(k) = values.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(Error::arg(
                "value",
                "finite numbers >= 0",
                format!("{} at index {k}", values[k]),
            ));
        }
        if self.armature.is_empty() {
            if values.iter().all(|x| *x == 0.0) {
                return Ok(());
            }
            self.armature = vec![0.0; self.nv];
        }
        self.armature[link.v_index..link.v_index + nv].copy_from_slice(&values);
        if self.armature.iter().all(|x| *x == 0.0) {
            self.armature.clear();
        }
        self.drop_compiled();
        Ok(())
    }

    /// Checks a deserialised model's armature (empty or one finite `≥ 0` value per speed,
    /// none on a free flyer).
    pub(crate) fn check_armature(&self) -> Result<()> {
        if self.armature.is_empty() {
            return Ok(());
        }
        let ok = self.armature.len() == self.nv
            && self.armature.iter().all(|x| x.is_finite() && *x >= 0.0)
            && self.links.iter().all(|l| {
                l.joint.motion() != MotionClass::Free
                    || self.armature[l.v_index..l.v_index + 6]
                        .iter()
                        .all(|x| *x == 0.0)
            });
        if ok {
            Ok(())
        } else {
            Err(Error::model(
                "model",
                "armature: expected one finite value >= 0 per speed, none on a free flyer",
            ))
        }
    }

    /// The armature of link `l`'s speeds (zeros beyond its joint's), for the recursions.
    pub(crate) fn link_armature(&self, l: usize) -> [f64; 3] {
        let mut out = [0.0; 3];
        if self.armature.is_empty() {
            return out;
        }
        let link = &self.links[l];
        let nv = link.joint.nv().min(3);
        out[..nv].copy_from_slice(&self.armature[link.v_index..link.v_index + nv]);
        out
    }
}

/// `τ += armature · a` (inverse dynamics).
#[inline]
pub fn add_to_forces(model: &Model, a: &[f64], tau: &mut [f64]) {
    for ((t, x), arm) in tau.iter_mut().zip(a).zip(&model.armature) {
        *t += arm * x;
    }
}

/// `M += diag(armature)` (the mass matrix).
#[inline]
pub fn add_to_mass_matrix(model: &Model, gim: &mut DMatrix<f64>) {
    for (k, arm) in model.armature.iter().enumerate() {
        gim[(k, k)] += arm;
    }
}

/// `½ Σ armature v²`.
#[inline]
pub fn kinetic_energy(model: &Model, v: &[f64]) -> f64 {
    0.5 * model
        .armature
        .iter()
        .zip(v)
        .map(|(arm, x)| arm * x * x)
        .sum::<f64>()
}
