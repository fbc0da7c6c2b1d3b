//! A [`Simulator`] that owns its model (for a binding's object, which cannot borrow).
use std::sync::Arc;

use super::Simulator;
use crate::model::Model;

/// A [`Simulator`] together with the model it borrows.
pub struct OwnedSimulator {
    // Declared first: dropped before the model it borrows.
    sim: Simulator<'static>,
    model: Arc<Model>,
}

impl OwnedSimulator {
    /// `build` makes the simulator from the model `model` holds.
    pub fn new<E>(
        model: Arc<Model>,
        build: impl FnOnce(&'static Model) -> Result<Simulator<'static>, E>,
    ) -> Result<Self, E> {
        // SAFETY: the model lives on the heap behind the `Arc` this struct keeps, unchanged
        // (a `Model` is never mutated behind an `Arc`), for as long as `sim` exists; `sim` is
        // dropped first (field order) and the reference is never handed out (`Simulator`
        // gives no access to its model).
        let m: &'static Model = unsafe { &*Arc::as_ptr(&model) };
        Ok(OwnedSimulator {
            sim: build(m)?,
            model,
        })
    }

    pub fn sim(&mut self) -> &mut Simulator<'static> {
        &mut self.sim
    }
    pub fn get(&self) -> &Simulator<'static> {
        &self.sim
    }
    pub fn model(&self) -> &Model {
        &self.model
    }
}
