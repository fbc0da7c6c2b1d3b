//! One pickled object of the bindings (`_dumps`/`_loads` in `rust/python/pickle.rs`): a
//! [`persist`] frame (version byte, postcard, checksum) of one [`Payload`], whose variant says
//! which class it holds. Every value is serialised as it is, derived data included (a model's
//! links and point masses, a URDF model's joint metadata), so the copy is bit-identical.
//! Torque functions' sources (Python callables) are not in the bytes: they travel beside
//! them, in effect order.
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::persist;
use super::scene::Scene;
use crate::effects::{torque_functions, Disabled, Effect, Effects, TorqueFunction};
use crate::integrator::DenseOutput;
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::point_masses::EquimomentalSet;
use crate::model::Model;
use crate::simulate::StateEvent;

/// One pickled object. Append new variants at the end (postcard numbers them in order); any
/// other change of a serialised type needs `persist::FORMAT_VERSION` bumped.
#[derive(Serialize, Deserialize)]
pub enum Payload {
    RigidBody(RigidBody),
    PointMasses(EquimomentalSet),
    Joint(Joint),
    /// A model, its joint records (names, limits, repairs) included.
    Model(Arc<Model>),
    Effect(Effect),
    StateEvent(StateEvent),
    Scene(Scene),
    DenseSolution(DenseOutput),
}

impl Payload {
    /// The torque functions of the effects it holds, in order: their sources travel beside
    /// the bytes.
    pub fn torque_functions(&mut self) -> impl Iterator<Item = &mut TorqueFunction> {
        torque_functions(match self {
            Payload::Effect(e) => std::slice::from_mut(e),
            Payload::Scene(s) => &mut s.effects,
            _ => &mut [],
        })
    }

    /// The payload framed in `data`, its torque functions rebuilt by `restore` from the
    /// `sources` that came with it (one each, in order) and a scene checked as `Scene(...)`
    /// checks it. `Err` says what is wrong: a damaged frame, another format version, a count
    /// that does not match.
    pub fn decode<S>(
        data: &[u8],
        sources: Vec<S>,
        restore: impl Fn(S) -> TorqueFunction,
    ) -> Result<Payload, String> {
        let mut payload: Payload = persist::decode(data).map_err(|e| e.to_string())?;
        let (n, m) = (payload.torque_functions().count(), sources.len());
        if n != m {
            return Err(format!(
                "the data holds {n} torque functions but {m} callables came with it"
            ));
        }
        for (f, s) in payload.torque_functions().zip(sources) {
            *f = restore(s);
        }
        if let Payload::Scene(s) = &payload {
            let effects = Effects::new(&s.model, &s.effects, Disabled::none(), "effects");
            let checked = s.model.check_state(&s.q0, Some(&s.v0));
            checked
                .and(effects.map(|_| ()))
                .map_err(|e| e.to_string())?;
        }
        Ok(payload)
    }
}
