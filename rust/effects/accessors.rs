//! What a binding reads off an effect of a given family, and the family-specific copies it
//! asks for: one call each, the family checked here (an effect of another family answers
//! `None`, or an error naming the argument).
use super::ground_contact::ContactStates;
use super::{Effect, Torque, TorqueFunction, TorqueLaw, TorqueLimit};
use crate::model::Model;
use crate::support::error::{check_result, Error, Result};
use crate::support::spatial::Vec3;

/// A ground contact's law parameters (SI); `stiffness`/`damping` are `None` until a scene
/// fills in their defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactParameters {
    pub height: f64,
    pub stiffness: Option<f64>,
    pub exponent: f64,
    pub damping: Option<f64>,
    pub friction: f64,
    pub v_eps: f64,
}

impl Effect {
    /// A ground contact's law parameters; `None` for other effects.
    pub fn contact_parameters(&self) -> Option<ContactParameters> {
        let Effect::GroundContact(c) = self else {
            return None;
        };
        Some(ContactParameters {
            height: c.height,
            stiffness: c.stiffness,
            exponent: c.exponent,
            damping: c.damping,
            friction: c.friction,
            v_eps: c.v_eps,
        })
    }

    /// A ground contact's points along the states `q` (N rows of `nq`), `v` (N of `nv`).
    /// Finite states whose law overflows (a damping of 1e307) are a `Numerical` error
    /// naming the quantity (`contact_state['force']`).
    pub fn contact_states(&self, model: &Model, q: &[f64], v: &[f64]) -> Result<ContactStates> {
        let Effect::GroundContact(c) = self else {
            return Err(self.not_a("self", "a GroundContact effect"));
        };
        let s = c.states(model, q, v)?;
        for (what, x) in [
            ("position", &s.position),
            ("penetration", &s.penetration),
            ("normal_force", &s.normal_force),
            ("force", &s.force),
        ] {
            check_result(&format!("contact_state['{what}']"), &x.data)?;
        }
        Ok(s)
    }

    /// A torque effect clamped per speed at `limit` (`None` removes it).
    pub fn with_torque_limit(&self, limit: Option<TorqueLimit>) -> Result<Effect> {
        let Effect::Torque(t) = self else {
            let expected =
                "a torque effect (JointTorque, TabulatedTorque, PDTorque, TorqueFunction)";
            return Err(self.not_a("limit", expected));
        };
        Ok(Effect::Torque(t.clone().with_limit(limit)))
    }

    /// A torque effect's limit on each of `model`'s speeds (inf where unlimited or not
    /// driven; all inf for another effect).
    pub fn torque_limit_per_speed(&self, model: &Model) -> Result<Vec<f64>> {
        match self {
            Effect::Torque(t) => t.limit_per_speed(model),
            _ => Ok(vec![f64::INFINITY; model.nv]),
        }
    }

    /// A torque effect's limit, if it has one.
    pub fn torque_limit(&self) -> Option<&TorqueLimit> {
        match self {
            Effect::Torque(Torque { limit, .. }) => limit.as_ref(),
            _ => None,
        }
    }

    /// A gravity effect's acceleration `g`; `None` for other effects.
    pub fn gravity_vector(&self) -> Option<Vec3> {
        match self {
            Effect::Gravity { g } => Some(*g),
            _ => None,
        }
    }

    /// A ground contact's plane `n · x = height` as `(n, height)`; `None` for other effects.
    pub fn plane(&self) -> Option<(Vec3, f64)> {
        match self {
            Effect::GroundContact(c) => Some((c.normal, c.height)),
            _ => None,
        }
    }

    /// The refusal of this effect where `expected` was needed, for argument `arg`.
    fn not_a(&self, arg: &str, expected: &str) -> Error {
        Error::arg(arg, expected, format!("a {} effect", self.kind().name()))
    }
}

/// The torque functions among `effects`, in order: what serialisation carries beside the
/// bytes (their sources) and restores after reading them.
pub fn torque_functions(effects: &mut [Effect]) -> impl Iterator<Item = &mut TorqueFunction> {
    effects.iter_mut().filter_map(|e| match e {
        Effect::Torque(Torque {
            law: TorqueLaw::Function(f),
            ..
        }) => Some(f),
        _ => None,
    })
}
