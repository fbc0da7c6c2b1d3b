//! A [`Simulator`] that owns its model (for a binding's object, which cannot borrow).
//!
//! Why `unsafe` remains: a [`Simulator`] borrows its model (`&'a Model`, down through
//! `Dynamics<'a>` and every integrator), and a Python object cannot hold a borrow, so this
//! struct holds both the model and a simulator borrowing it (a self-reference). A safe
//! design would make `Dynamics` generic over how it holds the model (`&Model` or
//! `Arc<Model>`), a change through the integrators and the batch code that this one owner
//! does not justify; a crate such as `ouroboros` or `self_cell` would wrap the same
//! reasoning in a macro (and a dependency).
use std::sync::Arc;

use super::{ControlKind, Simulator};
use crate::integrator::Method;
use crate::io::scene::Scene;
use crate::model::Model;
use crate::simulate::RunConfig;
use crate::support::error::Result as CoreResult;

/// A [`Simulator`] together with the model it borrows.
pub struct OwnedSimulator {
    // Declared first: dropped before the model it borrows.
    sim: Simulator<'static>,
    model: Arc<Model>,
}

impl OwnedSimulator {
    /// `build` makes the simulator from the model `model` holds. `build` may be called with
    /// any lifetime (`for<'m>`), so it cannot keep the reference beyond the simulator.
    pub fn new<E>(
        model: Arc<Model>,
        build: impl for<'m> FnOnce(&'m Model) -> Result<Simulator<'m>, E>,
    ) -> Result<Self, E> {
        // SAFETY: the reference is valid for as long as `sim` can use it, because
        // (1) the `Model` lives on the heap inside the `Arc`, so its address does not change
        //     when an `OwnedSimulator` moves;
        // (2) `self.model` keeps that allocation alive, and `sim` is dropped before it
        //     (fields drop in declaration order), so no use outlives it;
        // (3) nothing mutates the model while it is shared: the `Arc` is private and only
        //     handed out as `&Model`, and `Model` has no interior mutability;
        // (4) the `'static` lifetime never reaches a caller: `build` and the closures of
        //     [`OwnedSimulator::with`] / [`OwnedSimulator::with_mut`] are generic over the
        //     lifetime, so they cannot store the simulator or its reference anywhere that
        //     outlives the call (not even by swapping the simulator out of the `&mut`: they
        //     have no other `Simulator<'m>` of that lifetime to put in its place, since
        //     `Simulator` never hands out its model).
        let m: &'static Model = unsafe { &*Arc::as_ptr(&model) };
        Ok(OwnedSimulator {
            sim: build(m)?,
            model,
        })
    }

    /// `f` applied to the simulator.
    pub fn with<R>(&self, f: impl for<'m> FnOnce(&Simulator<'m>) -> R) -> R {
        f(&self.sim)
    }

    /// `f` applied to the simulator, mutably.
    pub fn with_mut<R>(&mut self, f: impl for<'m> FnOnce(&mut Simulator<'m>) -> R) -> R {
        f(&mut self.sim)
    }

    pub fn model(&self) -> &Model {
        &self.model
    }
}

/// What a scene's stepping simulator is asked for, beyond the run configuration.
pub struct Stepping<'a> {
    pub t0: f64,
    /// Seconds between control updates.
    pub period: f64,
    pub kind: ControlKind,
    pub record: bool,
    /// Recorded times (`None`: every step).
    pub t_eval: Option<&'a [f64]>,
}

impl OwnedSimulator {
    /// The stepping simulator of `scene` with the run configuration `call` (the same checks
    /// and precedence over the scene's settings as `simulate`): from `t0` without an end, no
    /// cap on the steps of the whole run (a long run of short calls), and Radau where
    /// `simulate` would choose automatically (what it starts stiff scenes with; a simulator
    /// does not switch).
    pub fn of_scene(scene: &Scene, call: RunConfig, at: Stepping<'_>) -> CoreResult<Self> {
        let s = scene;
        let named = call.method.is_some() || s.settings.method.is_some();
        let call = RunConfig {
            t_span: Some((at.t0, at.t0)),
            ..call
        };
        let run = call.resolve(&s.settings, &s.effects, s.model.nq + s.model.nv)?;
        let (off, mut opts) = (run.disabled, run.opts);
        opts.max_steps = usize::MAX;
        if opts.method == Method::Auto && !named {
            opts.method = Method::Radau;
        }
        let (q0, v0, effects) = (&s.q0, &s.v0, &s.effects);
        let (t0, period, kind, record) = (at.t0, at.period, at.kind, at.record);
        let mut sim = OwnedSimulator::new(s.model.clone(), |m| {
            Simulator::new(m, effects, off, (q0, v0), t0, opts, period, kind, record)
        })?;
        if let Some(te) = at.t_eval {
            sim.with_mut(|s| s.set_t_eval(te))?;
        }
        Ok(sim)
    }
}
