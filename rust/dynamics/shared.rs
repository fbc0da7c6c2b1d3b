//! A model many threads call at once: versions replaced (never mutated) when a body or a loop
//! is added, and a small pool of per-call workspaces, so calls in flight, scenes and copies
//! share one model without locks and a call allocates nothing once its workspace exists.
//! The Python `Model` is one of these.
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use crate::dynamics::denoc;
use crate::loops::{self, LoopSolver};
use crate::model::Model;
use crate::recursive::{self, Data, DerivativeData};
use crate::support::error::Result;
use crate::support::spatial::{Vec3, Vec6};

/// Workspaces kept for reuse per model (more threads than this allocate their own).
const POOL: usize = 4;

/// One version of a model: replaced, never mutated, by `add_body`, so calls in flight, scenes
/// and copies share it without locks.
#[derive(Clone)]
pub struct Version {
    pub model: Arc<Model>,
    id: u64,
}

static NEXT_VERSION: AtomicU64 = AtomicU64::new(1);

fn next_version() -> u64 {
    NEXT_VERSION.fetch_add(1, Ordering::Relaxed)
}

/// Forward (τ → a) or inverse (a → τ) dynamics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    Forward,
    Inverse,
}

/// The buffers of one call: taken from the model's pool, so any number of threads can use
/// one model at once, and put back for the next call.
pub struct Workspace {
    pub version: Version,
    pub data: Data,
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    /// The argument that is not a state (τ or a).
    pub x: Vec<f64>,
    pub out: Vec<f64>,
    /// The closed-loop solver's buffers (models with loops only).
    pub loops: Option<Box<LoopSolver>>,
    /// The derivatives' buffers (built on the first derivative call).
    pub deriv: Option<Box<DerivativeData>>,
}

impl Workspace {
    fn new(version: Version) -> Self {
        let m = &version.model;
        let (nq, nv) = (m.nq, m.nv);
        Workspace {
            data: Data::new(m),
            q: vec![0.0; nq],
            v: vec![0.0; nv],
            x: vec![0.0; nv],
            out: vec![0.0; nv],
            loops: m.has_constraints().then(|| Box::new(LoopSolver::new(m))),
            deriv: None,
            version,
        }
    }

    pub fn model(&self) -> &Model {
        &self.version.model
    }

    /// Checks the loaded `q` (and `v`, when `with_v`) against the model.
    pub fn check_state(&self, with_v: bool) -> Result<()> {
        self.version
            .model
            .check_state(&self.q, with_v.then_some(self.v.as_slice()))
    }

    /// Recursive forward or inverse dynamics at the loaded `(q, v, x)` into `out`; with loops,
    /// the forward accelerations corrected by the cut joints' forces.
    pub fn dynamics(&mut self, direction: Direction, g: &Vec3, ext: Option<&[Vec6]>) -> Result<()> {
        let model: &Model = &self.version.model;
        let (data, q, v, x, out) = (&mut self.data, &self.q, &self.v, &self.x, &mut self.out);
        match direction {
            Direction::Forward => recursive::forward_dynamics(model, data, q, v, x, g, ext, out)?,
            Direction::Inverse => recursive::inverse_dynamics(model, data, q, v, x, g, ext, out),
        }
        self.close_loops(direction)
    }

    /// [`Workspace::dynamics`] by the explicit DeNOC products (no external wrenches); the
    /// result is returned (the products allocate anyway).
    pub fn denoc_dynamics(&mut self, direction: Direction, g: &Vec3) -> Result<Vec<f64>> {
        let (model, q, v, x) = (&*self.version.model, &self.q, &self.v, &self.x);
        let out = match direction {
            Direction::Forward => denoc::forward_dynamics(model, q, v, x, g)?,
            Direction::Inverse => denoc::inverse_dynamics(model, q, v, x, g)?,
        };
        self.out.copy_from_slice(out.as_slice());
        self.close_loops(direction)?;
        Ok(self.out.clone())
    }

    fn close_loops(&mut self, direction: Direction) -> Result<()> {
        match (direction, self.loops.as_mut()) {
            (Direction::Forward, Some(solver)) => loops::constrained_forward_dynamics(
                &self.version.model,
                &mut self.data,
                solver,
                &self.q,
                &self.v,
                &mut self.out,
            ),
            _ => Ok(()),
        }
    }

    /// The forces of the `actuated` coordinates driving a model with loops at the loaded
    /// `(q, v, a = x)`, given the tree's inverse dynamics `tau_tree`.
    pub fn driving_forces(&mut self, tau_tree: &[f64], actuated: &[usize]) -> Result<Vec<f64>> {
        let model: &Model = &self.version.model;
        let solver = self
            .loops
            .get_or_insert_with(|| Box::new(LoopSolver::new(model)));
        let (tau, _) =
            loops::driving_forces(model, solver, &self.q, &self.v, &self.x, tau_tree, actuated)?;
        Ok(tau)
    }

    /// The cut joints' wrenches under the loaded `tau = x` (forward dynamics first).
    pub fn constraint_forces(&mut self, g: &Vec3, ext: Option<&[Vec6]>) -> Result<Vec<[f64; 6]>> {
        let model: &Model = &self.version.model;
        let (data, q, v, x, out) = (&mut self.data, &self.q, &self.v, &self.x, &mut self.out);
        recursive::forward_dynamics(model, data, q, v, x, g, ext, out)?;
        let solver = self
            .loops
            .get_or_insert_with(|| Box::new(LoopSolver::new(model)));
        loops::constraint_forces(model, data, solver, q, v, out)
    }

    /// Every constraint multiplier (cut joints' rows, then couplings') under the loaded
    /// `tau = x` (forward dynamics first).
    pub fn constraint_multipliers(&mut self, g: &Vec3) -> Result<Vec<f64>> {
        let model: &Model = &self.version.model;
        let (data, q, v, x, out) = (&mut self.data, &self.q, &self.v, &self.x, &mut self.out);
        recursive::forward_dynamics(model, data, q, v, x, g, None, out)?;
        let solver = self
            .loops
            .get_or_insert_with(|| Box::new(LoopSolver::new(model)));
        loops::constraint_forces(model, data, solver, q, v, out)?;
        Ok(solver.lambda.as_slice().to_vec())
    }

    /// Forward or inverse dynamics derivatives at the loaded `(q, v, x)` into the
    /// derivatives' buffers (returned), stored by rows when `row_major`
    /// ([`DerivativeData::row_major`]).
    pub fn derivatives(
        &mut self,
        direction: Direction,
        g: &Vec3,
        row_major: bool,
    ) -> Result<&DerivativeData> {
        let model: &Model = &self.version.model;
        let dd = self
            .deriv
            .get_or_insert_with(|| Box::new(DerivativeData::new(model)));
        dd.row_major = row_major;
        let (data, q, v, x) = (&mut self.data, &self.q, &self.v, &self.x);
        match direction {
            Direction::Forward => {
                recursive::forward_dynamics_derivatives(model, data, dd, q, v, x, g)?
            }
            Direction::Inverse => {
                recursive::inverse_dynamics_derivatives(model, data, dd, q, v, x, g)
            }
        }
        Ok(dd)
    }
}

impl Workspace {
    /// Inverse dynamics derivatives at the loaded `(q, v, a = x)` by rows into `out`
    /// ([`recursive::inverse_dynamics_derivatives_into`]); whether every entry is surely
    /// finite without reading them ([`recursive::rows_surely_finite`]).
    pub fn inverse_derivatives_into(&mut self, g: &Vec3, out: [&mut [f64]; 3]) -> bool {
        let model: &Model = &self.version.model;
        let dd = self
            .deriv
            .get_or_insert_with(|| Box::new(DerivativeData::new(model)));
        let (data, q, v, x) = (&mut self.data, &self.q, &self.v, &self.x);
        recursive::inverse_dynamics_derivatives_into(model, data, dd, q, v, x, g, out);
        recursive::rows_surely_finite(dd)
    }
}

/// A model shared by every thread that calls it: its current [`Version`] and a pool of
/// workspaces of that version.
pub struct SharedModel {
    current: Mutex<Version>,
    /// `current.id`, readable without the lock on every call.
    current_id: AtomicU64,
    // Boxed: a checked-out workspace moves in and out of the pool as one pointer.
    #[allow(clippy::vec_box)]
    pool: Mutex<Vec<Box<Workspace>>>,
}

impl SharedModel {
    /// A model sharing `model` (a scene's, another model's): nothing is copied until one of
    /// them adds a body.
    pub fn new(model: Arc<Model>) -> Self {
        let id = next_version();
        SharedModel {
            current: Mutex::new(Version { model, id }),
            current_id: AtomicU64::new(id),
            pool: Mutex::new(Vec::new()),
        }
    }

    /// The current version (a clone of its handles).
    pub fn version(&self) -> Version {
        self.lock_version().clone()
    }

    /// The model as it is now (shared, immutable).
    pub fn model(&self) -> Arc<Model> {
        self.lock_version().model.clone()
    }

    fn lock_version(&self) -> MutexGuard<'_, Version> {
        // A thread that panicked while holding the lock left a whole `Version` behind: the
        // value is still consistent, so a poisoned lock is taken as it is.
        self.current.lock().unwrap_or_else(|p| p.into_inner())
    }

    #[allow(clippy::vec_box)]
    fn pool(&self) -> MutexGuard<'_, Vec<Box<Workspace>>> {
        self.pool.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Changes the model (copy-on-write: a model shared with a scene, a copy or a call in
    /// flight is copied once; a model built body by body is extended in place, amortised
    /// Changes what no computation depends on (visuals, name): the version and the pooled
    /// workspaces stay valid.
    pub fn update_presentation(&self, f: impl FnOnce(&mut Model)) {
        f(Arc::make_mut(&mut self.lock_version().model));
    }

    /// O(1) per body) and starts a new version; `f` sees the model as it is now.
    pub fn update<T>(&self, f: impl FnOnce(&mut Model) -> Result<T>) -> Result<T> {
        let mut version = self.lock_version();
        let out = f(Arc::make_mut(&mut version.model))?;
        version.id = next_version();
        self.current_id.store(version.id, Ordering::Release);
        drop(version);
        self.pool().clear();
        Ok(out)
    }

    /// Runs `f` with a workspace of the current model: one from the pool when there is one
    /// of this version, otherwise a new one (put back afterwards for the next call).
    pub fn with_workspace<R>(&self, f: impl FnOnce(&mut Workspace) -> R) -> R {
        let id = self.current_id.load(Ordering::Acquire);
        let reused = self.pool().pop().filter(|ws| ws.version.id == id);
        let mut ws = match reused {
            Some(ws) => ws,
            None => Box::new(Workspace::new(self.version())),
        };
        let result = f(&mut ws);
        if ws.version.id == self.current_id.load(Ordering::Acquire) {
            let mut pool = self.pool();
            if pool.len() < POOL {
                pool.push(ws);
            }
        }
        result
    }
}
