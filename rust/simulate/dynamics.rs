//! The equations of motion `y = [q; v]`, `ẏ = [q̇(v); v̇]` with `v̇` from the recursive
//! forward dynamics and the scene's effects, as an [`OdeSystem`].
use crate::effects::{Context, Disabled, Effect, Effects, Probe};
use crate::integrator::OdeSystem;
use crate::kinematics;
use crate::loops::{self, LoopSolver};
use crate::model::Model;
use crate::recursive::{self, Data};
use crate::support::error::Result;
use crate::support::spatial::Vec6;

/// The equations of motion as a first-order system.
pub struct Dynamics<'a> {
    pub model: &'a Model,
    pub data: Data,
    pub effects: Effects,
    tau: Vec<f64>,
    wrenches: Vec<Vec6>,
    /// Called with the current time every `PROGRESS_EVERY` evaluations; returning false
    /// stops the run (Ctrl-C from Python, a cancelled progress bar). The hook decides by
    /// elapsed time whether to do anything (the Python one re-attaches every 50 ms).
    pub(super) progress: Option<Progress<'a>>,
    calls: usize,
    /// The time of the evaluation at which the progress hook asked to stop.
    pub(super) interrupted_at: Option<f64>,
    /// With loops: the last failure of an evaluation at a stage too far off the manifolds to
    /// project (`t`, message), handed to the integrator as a non-finite trial to reject.
    pub(super) off_manifold_failure: Option<(f64, String)>,
    probe: Option<Probe>,
    /// The closed-loop solver (models with loops only).
    pub loops: Option<Box<LoopSolver>>,
    /// The derivatives' buffers (built on the first `jacobian` call).
    deriv: Option<Box<super::derivatives::DerivativeWork>>,
    /// With loops: the stage state projected onto the constraint manifolds (docs/mechanisms.md §3).
    stage: Vec<f64>,
    /// With loops: `P′(y)` and a product buffer for [`OdeSystem::chain_projection`] (built on
    /// its first call).
    chain: Option<Box<(Vec<f64>, Vec<f64>)>>,
    /// With loops: a second state-sized buffer (`P(y)` in `projection_derivative`).
    stage_base: Vec<f64>,
    /// With loops: the last step's start `y` and its projection `P(y)`, the reference of
    /// [`OdeSystem::filter_error`] (built on its first call; one projection per step).
    filter_from: Option<Box<(Vec<f64>, Vec<f64>)>>,
    /// The last right-hand side's time: the accepted state's, when the integrator projects it.
    t_last: f64,
    /// With loops: the largest pivot ratio of an accepted state so far, and the first
    /// passage by a singular position, `(t, ratio / largest)`, once below [`SINGULAR_PASSAGE`].
    pivot_max: f64,
    rank_max: usize,
    pub singular_passage: Option<(f64, f64)>,
    /// With loops and one degree of freedom: the kept rows' oriented kernel, to see the
    /// motion pass singular positions (built on the first projection).
    pub crossings: Option<Box<Crossings>>,
    /// Joint torques held by a stepping simulator (`control::Simulator`), added after the
    /// effects' (length nv; empty: none).
    pub control: Vec<f64>,
}

/// The singular positions a one-degree-of-freedom mechanism passed: the orientation of the
/// kernel of its kept constraint rows (their generalized cross product,
/// [`LoopSolver::oriented_kernel`]) at consecutive accepted states. It is continuous along
/// a motion and reverses only where the rows pass through a dependence, so a reversal
/// says the motion went through (or jumped over) a singular position between the two
/// states, however long the step; a dead point of one coordinate partition does not
/// reverse it. Compared only while the kept rows are the same.
///
/// Where an even number of rows become dependent at once (the N-four-bar's 40 bars all flat
/// together) the orientation keeps its sign; the rows' volume (`Π |R_kk|`, a product of
/// their singular values) still falls like `|t − t*|^k` towards the position and rises past
/// it. A local minimum of the volume over accepted states below [`VOLUME_DIP`] of the run's
/// largest, with the same rows and no reversal there, counts as a passage too.
pub struct Crossings {
    kernel: Vec<f64>,
    prev: Vec<f64>,
    rows: Vec<usize>,
    prev_rows: Vec<usize>,
    order: Vec<usize>,
    have_prev: bool,
    /// Log-volume of the previous state's rows, the run's largest, and whether it fell into
    /// the previous state; `reversed`: a reversal was counted at the previous state.
    volume: f64,
    volume_max: f64,
    falling: bool,
    reversed: bool,
    /// How many, and the time of the accepted state just past the first.
    pub count: usize,
    pub first: Option<f64>,
}

impl Crossings {
    fn new(nv: usize, m: usize) -> Self {
        Crossings {
            kernel: vec![0.0; nv],
            prev: vec![0.0; nv],
            rows: Vec::with_capacity(m),
            prev_rows: Vec::with_capacity(m),
            order: Vec::with_capacity(m),
            have_prev: false,
            volume: f64::NEG_INFINITY,
            volume_max: f64::NEG_INFINITY,
            falling: false,
            reversed: false,
            count: 0,
            first: None,
        }
    }

    /// The accepted state at `t` whose projection `solver` has just factored. Returns
    /// whether the motion's tangent turned by more than [`TANGENT_TURN`] since the last one.
    fn update(&mut self, solver: &LoopSolver, t: f64) -> bool {
        if !solver.oriented_kernel(&mut self.kernel, &mut self.rows, &mut self.order) {
            self.have_prev = false;
            return false;
        }
        let mut turned = false;
        let volume = solver.log_volume();
        let mut reversed = false;
        if self.have_prev {
            let dot: f64 = self.kernel.iter().zip(&self.prev).map(|(a, b)| a * b).sum();
            turned = dot.abs() < TANGENT_TURN.cos();
            reversed = dot < 0.0 && self.rows == self.prev_rows;
        }
        if self.have_prev && self.rows == self.prev_rows {
            let dipped = self.falling
                && volume > self.volume
                && self.volume - self.volume_max < VOLUME_DIP.ln();
            if reversed || (dipped && !self.reversed) {
                self.count += 1;
                self.first.get_or_insert(t);
            }
            self.falling = volume < self.volume;
        } else {
            self.falling = false;
        }
        self.reversed = reversed;
        self.volume = volume;
        self.volume_max = self.volume_max.max(volume);
        std::mem::swap(&mut self.kernel, &mut self.prev);
        std::mem::swap(&mut self.rows, &mut self.prev_rows);
        self.have_prev = true;
        turned
    }
}

/// An accepted state whose loop rows are this close to dependent, relative to the best
/// conditioned state of the run so far, is at a singular position within rounding: there
/// the branch the motion continues on is decided by rounding (docs/mechanisms.md §5). The
/// N-four-bar's passes that stay on the parallel motion come no closer than 1e-4 (N = 4,
/// RK45 and DOP853 at rtol 1e-8 … 1e-12, Radau at 1e-6, 1e-7; A02, DOP853 at 1e-6 … 1e-12:
/// 6.5e-3); Radau's crawl at 1e-8 that left it, 1e-10. A parallelogram four-bar's runs that
/// crawled off their branch (DOP853, RK45 at rtol 1e-11 … 1e-13) came within 0.95e-7 …
/// 1.6e-7, those that stayed no closer than 1.5e-4 (issue 38; docs/mechanisms.md §5).
pub const SINGULAR_PASSAGE: f64 = 1e-5;

/// A local minimum of the kept rows' volume this far below the run's largest is a passage
/// by a singular position where several rows became dependent at once ([`Crossings`]).
pub const VOLUME_DIP: f64 = 1e-6;

/// A one-degree-of-freedom motion whose tangent (the kernel of the loop rows) turns by more
/// than this between two accepted states has changed branch at a crossing in one step (the
/// two branches' tangents differ there), or taken a step its tolerance cannot vouch for.
/// Runs of `tests/test_singular_crossings.py` turn by at most 6.3° per step, the
/// ones that leave their branch included (they crawl off it: the pivot ratio reports them).
pub const TANGENT_TURN: f64 = std::f64::consts::FRAC_PI_3;

/// The effects' view of the state `(t, q, v)`.
#[inline]
fn context<'c>(model: &'c Model, t: f64, q: &'c [f64], v: &'c [f64]) -> Context<'c> {
    Context { model, t, q, v }
}

/// A progress hook: current time in, "keep going?" out.
pub type Progress<'a> = Box<dyn FnMut(f64) -> bool + Send + 'a>;

/// Often enough for a 50 ms poll on any model; rare enough that the hook's clock read is
/// lost in the evaluations' cost (≥ 64 × 0.1 µs).
const PROGRESS_EVERY: usize = 64;

impl<'a> Dynamics<'a> {
    /// The system with `effects` resolved against `model`, the `disabled` families left out.
    pub fn try_new(model: &'a Model, effects: &[Effect], disabled: Disabled) -> Result<Self> {
        Ok(Self::with_effects(
            model,
            Effects::new(model, effects, disabled, "effects")?,
        ))
    }

    pub fn with_effects(model: &'a Model, effects: Effects) -> Self {
        Dynamics {
            model,
            data: Data::new(model),
            effects,
            tau: vec![0.0; model.nv],
            wrenches: vec![Vec6::zeros(); model.links.len()],
            progress: None,
            calls: 0,
            interrupted_at: None,
            off_manifold_failure: None,
            probe: None,
            loops: model
                .has_constraints()
                .then(|| Box::new(LoopSolver::new(model))),
            deriv: None,
            chain: None,
            stage: if !model.has_constraints() {
                Vec::new()
            } else {
                vec![0.0; model.nq + model.nv]
            },
            stage_base: if !model.has_constraints() {
                Vec::new()
            } else {
                vec![0.0; model.nq + model.nv]
            },
            filter_from: None,
            t_last: f64::NAN,
            pivot_max: 0.0,
            rank_max: 0,
            singular_passage: None,
            crossings: None,
            control: Vec::new(),
        }
    }

    /// The links' positions and velocities at `(q, v)` (for the energies).
    fn move_links(&mut self, q: &[f64], v: &[f64]) {
        kinematics::positions(self.model, q, &mut self.data.links);
        kinematics::velocities(self.model, q, v, &mut self.data.links);
    }

    /// Kinetic energy plus the potential energy of the enabled conservative effects
    /// (gravity, springs).
    pub fn energy(&mut self, q: &[f64], v: &[f64]) -> f64 {
        self.move_links(q, v);
        let cx = context(self.model, 0.0, q, v);
        recursive::kinetic_energy(&self.data)
            + recursive::armature::kinetic_energy(self.model, v)
            + self.effects.potential_energy(&cx, &self.data.links)
    }

    /// Kinetic energy and `(label, V)` of each conservative effect.
    pub fn energies(&mut self, q: &[f64], v: &[f64]) -> (f64, Vec<(String, f64)>) {
        self.move_links(q, v);
        let cx = context(self.model, 0.0, q, v);
        (
            recursive::kinetic_energy(&self.data)
                + recursive::armature::kinetic_energy(self.model, v),
            self.effects.potentials(&cx, &self.data.links),
        )
    }

    /// Generalized force of each enabled effect at `(t, q, v)`: row-major
    /// `effects.len() × nv` into `out`.
    pub fn effect_forces(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        out: &mut [f64],
    ) -> std::result::Result<(), String> {
        let probe = self.probe.get_or_insert_with(|| Probe::new(self.model));
        let cx = context(self.model, t, q, v);
        probe.forces(&mut self.effects, &cx, out)
    }

    /// Power `τ_e · v` of each enabled effect at `(t, q, v)` into `out` (length
    /// `effects.len()`); `scratch` has length `effects.len() × nv`.
    pub fn effect_power(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        scratch: &mut [f64],
        out: &mut [f64],
    ) -> std::result::Result<(), String> {
        self.effect_forces(t, q, v, scratch)?;
        let nv = self.model.nv;
        for (k, p) in out.iter_mut().enumerate() {
            *p = scratch[k * nv..(k + 1) * nv]
                .iter()
                .zip(v)
                .map(|(a, b)| a * b)
                .sum();
        }
        Ok(())
    }

    /// Accelerations `v̇` at `(t, q, v)` (one right-hand-side evaluation, without `q̇`).
    pub fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &mut [f64],
    ) -> std::result::Result<(), String> {
        self.accelerations_inline(t, q, v, a)
    }

    /// [`Dynamics::accelerations`], inlined into the right-hand side (one call frame less
    /// per evaluation).
    #[inline(always)]
    fn accelerations_inline(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &mut [f64],
    ) -> std::result::Result<(), String> {
        let cx = context(self.model, t, q, v);
        let ext = if self.effects.apply(&cx, &mut self.tau, &mut self.wrenches)? {
            Some(self.wrenches.as_slice())
        } else {
            None
        };
        if !self.control.is_empty() {
            // Without joint forces from the effects `tau` was not overwritten: clear it.
            if !self.effects.applies_in_rhs() {
                self.tau.fill(0.0);
            }
            self.tau
                .iter_mut()
                .zip(&self.control)
                .for_each(|(t, u)| *t += u);
        }
        recursive::forward_dynamics(
            self.model,
            &mut self.data,
            q,
            v,
            &self.tau,
            &self.effects.gravity,
            ext,
            a,
        )
        .map_err(|e| e.to_string())?;
        match self.loops.as_mut() {
            Some(solver) => {
                loops::constrained_forward_dynamics(self.model, &mut self.data, solver, q, v, a)
                    .map_err(|e| e.to_string())
            }
            None => Ok(()),
        }
    }
}

impl Dynamics<'_> {
    /// `P′(y)` row-major into `pd` (`dim × dim`): column `k` is `(P(y + ε e_k) − P(y))/ε`
    /// with `ε = √EPS · max(1, |y_k|)`. False (and `pd` meaningless) if a projection fails.
    fn projection_derivative(&mut self, y: &[f64], pd: &mut [f64]) -> bool {
        let (model, n) = (self.model, y.len());
        let Some(solver) = self.loops.as_mut() else {
            return false;
        };
        let mut buf = std::mem::take(&mut self.stage);
        let mut base = std::mem::take(&mut self.stage_base);
        let project = |x: &mut [f64], solver: &mut LoopSolver| project_aside(model, solver, x);
        base.copy_from_slice(y);
        let mut ok = project(&mut base, solver);
        for k in 0..n {
            if !ok {
                break;
            }
            let eps = f64::EPSILON.sqrt() * y[k].abs().max(1.0);
            buf.copy_from_slice(y);
            buf[k] += eps;
            ok = project(&mut buf, solver);
            for i in 0..n {
                pd[i * n + k] = (buf[i] - base[i]) / eps;
            }
        }
        self.stage = buf;
        self.stage_base = base;
        ok
    }
}

/// With loops the right-hand side is evaluated at the stage's projection onto the position
/// and velocity manifolds, `f(P(y))` (the index-3 information every stage keeps): the
/// index-1 equations extended off the manifold keep `Φ(q)` at the stage's error `δ`, whose
/// level set near a singular position bends sharply (accelerations ~ `δ/σ³` at a distance
/// `σ` from it, docs/mechanisms.md §3), while on the manifold the motion goes straight
/// through. A stage too far off for the projection (a rejected trial step) is evaluated
/// where it is (the second value false); the error estimate rejects it.
fn project_stage<'y>(
    model: &Model,
    solver: &mut LoopSolver,
    y: &'y [f64],
    stage: &'y mut [f64],
) -> (&'y [f64], bool) {
    stage.copy_from_slice(y);
    // The integrator's drift figure counts accepted steps only.
    let drift = solver.max_drift;
    let projected = loops::project_state(model, solver, stage).is_ok();
    solver.max_drift = drift;
    if projected && stage.iter().all(|x| x.is_finite()) {
        (stage, true)
    } else {
        (y, false)
    }
}

/// `x` projected onto the manifolds for a side computation (an error estimate, `P′`):
/// quaternions normalised, the integrator's drift figure untouched (it counts accepted
/// steps only). False if the projection fails or leaves a non-finite entry.
fn project_aside(model: &Model, solver: &mut LoopSolver, x: &mut [f64]) -> bool {
    model.normalize(&mut x[..model.nq]);
    let drift = solver.max_drift;
    let ok = loops::project_state(model, solver, x).is_ok() && x.iter().all(|v| v.is_finite());
    solver.max_drift = drift;
    ok
}

/// The right-hand side's error when the progress hook asks to stop (Ctrl-C, a raising
/// `progress`, a stopped batch); `simulate` reads `interrupted_at`, not this text, and
/// reports `Status::Interrupted`.
const INTERRUPTED: &str = "interrupted";

impl OdeSystem for Dynamics<'_> {
    fn dim(&self) -> usize {
        self.model.nq + self.model.nv
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> std::result::Result<(), String> {
        let nq = self.model.nq;
        self.t_last = t;
        if let Some(hook) = self.progress.as_mut() {
            self.calls += 1;
            if self.calls % PROGRESS_EVERY == 0 && !hook(t) {
                self.interrupted_at = Some(t);
                return Err(INTERRUPTED.into());
            }
        }
        let (qdot, vdot) = dydt.split_at_mut(nq);
        let Some(solver) = self.loops.as_mut() else {
            // A tree: the state as it is (no stage buffer to take and give back).
            let (q, v) = y.split_at(nq);
            self.model.velocity_to_qdot(q, v, qdot);
            return self.accelerations_inline(t, q, v, vdot);
        };
        let mut stage = std::mem::take(&mut self.stage);
        let (y, on_manifold) = project_stage(self.model, solver, y, &mut stage);
        let (q, v) = y.split_at(nq);
        self.model.velocity_to_qdot(q, v, qdot);
        let r = self.accelerations(t, q, v, vdot);
        self.stage = stage;
        match r {
            // A stage the projection could not reach may fail where a shorter step's would
            // not (an overconstrained linkage off its manifold loses its mobility: Bricard at
            // rtol 1e-2 read as locked): a non-finite derivative, so the integrator rejects
            // the trial and shrinks the step; `simulate` names this failure if it persists.
            Err(message) if !on_manifold && self.interrupted_at.is_none() => {
                self.off_manifold_failure = Some((t, message));
                vdot.fill(f64::NAN);
                Ok(())
            }
            r => r,
        }
    }

    /// `y = [q; v]`: the semi-implicit Euler updates `v`, then `q` with the new `v`.
    fn split(&self) -> Option<usize> {
        Some(self.model.nq)
    }

    /// `q̇(q, v)` alone (no dynamics), for the semi-implicit Euler.
    fn position_rate(&mut self, y: &[f64], qdot: &mut [f64]) -> std::result::Result<bool, String> {
        let (q, v) = y.split_at(self.model.nq);
        self.model.velocity_to_qdot(q, v, qdot);
        Ok(true)
    }

    /// The analytic state Jacobian (`super::derivatives`; with closed loops, of the
    /// constrained dynamics).
    fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        jac: &mut [f64],
    ) -> std::result::Result<bool, String> {
        let mut w = match self.deriv.take() {
            Some(w) => w,
            None => Box::new(super::derivatives::DerivativeWork::new(self)),
        };
        let r = self.state_jacobian(t, y, jac, &mut w);
        self.deriv = Some(w);
        r
    }

    /// With loops: the error estimate's part along the manifolds, `P(y + err) − P(y)` (the
    /// accepted state is projected, so the estimate's components across the manifolds are
    /// not errors the step keeps; docs/mechanisms.md §2, §6). `P(y)`, not `y`: near a
    /// singular position the accepted `y` is on the manifolds only to the rounding amplified
    /// there (`~ ε/σ`), an offset that does not shrink with the step. Left as it is when the
    /// projection fails (an estimate too large to matter: the step is rejected either way).
    fn filter_error(&mut self, y: &[f64], err: &mut [f64]) -> bool {
        let Some(solver) = self.loops.as_mut() else {
            return false;
        };
        let model = self.model;
        let project = |x: &mut [f64], solver: &mut LoopSolver| project_aside(model, solver, x);
        let from = self
            .filter_from
            .get_or_insert_with(|| Box::new((vec![f64::NAN; y.len()], vec![0.0; y.len()])));
        if from.0 != y {
            from.0.copy_from_slice(y);
            from.1.copy_from_slice(y);
            if !project(&mut from.1, solver) {
                from.1.copy_from_slice(y);
            }
        }
        let mut buf = std::mem::take(&mut self.stage);
        for ((b, a), e) in buf.iter_mut().zip(y).zip(err.iter()) {
            *b = a + e;
        }
        let ok = project(&mut buf, solver);
        if ok {
            for ((e, b), p) in err.iter_mut().zip(&buf).zip(&from.1) {
                *e = b - p;
            }
        }
        self.stage = buf;
        ok
    }

    fn filters_error(&self) -> bool {
        self.loops.is_some()
    }

    /// With loops: `jac · P′(y)`, the Jacobian of `f(P(y))` that `rhs` evaluates, `P′`'s
    /// columns as differences `(P(y + ε e_k) − P(y))/ε` (exact in the speeds, where `P` is
    /// linear). Without it Radau's simplified Newton sees `∂f/∂y` across the manifolds, where
    /// `f ∘ P` is constant: slow contraction and a Jacobian re-evaluated nearly every step.
    fn chain_projection(&mut self, y: &[f64], jac: &mut [f64]) -> bool {
        if self.loops.is_none() {
            return false;
        }
        let n = y.len();
        let mut chain = self
            .chain
            .take()
            .unwrap_or_else(|| Box::new((vec![0.0; n * n], vec![0.0; n * n])));
        let ok = self.projection_derivative(y, &mut chain.0);
        if ok {
            let (pd, prod) = &mut *chain;
            for i in 0..n {
                let row = &jac[i * n..(i + 1) * n];
                let out = &mut prod[i * n..(i + 1) * n];
                out.fill(0.0);
                for (k, &a) in row.iter().enumerate() {
                    if a != 0.0 {
                        let pk = &pd[k * n..(k + 1) * n];
                        out.iter_mut().zip(pk).for_each(|(o, p)| *o += a * p);
                    }
                }
            }
            jac.copy_from_slice(prod);
        }
        self.chain = Some(chain);
        ok
    }

    /// Unit quaternions (the right-hand side normalises them too, so FSAL stays valid);
    /// with loops, the state back onto the position and velocity manifolds.
    #[inline]
    fn project(&mut self, y: &mut [f64]) -> std::result::Result<bool, String> {
        self.model.normalize(&mut y[..self.model.nq]);
        match self.loops.is_some() {
            true => self.project_loops(y),
            false => Ok(false),
        }
    }
}

impl Dynamics<'_> {
    /// [`OdeSystem::project`] with loops: onto the manifolds, and the passage tests.
    fn project_loops(&mut self, y: &mut [f64]) -> std::result::Result<bool, String> {
        let Some(solver) = self.loops.as_mut() else {
            return Ok(false);
        };
        let changed = loops::project_state(self.model, solver, y)?;
        // At the position itself the rank test sets a row aside: a rank below the run's
        // highest is a passage too.
        let (rank, ratio) = (solver.rank(), solver.pivot_ratio());
        self.rank_max = self.rank_max.max(rank);
        self.pivot_max = self.pivot_max.max(ratio);
        let relative = if rank < self.rank_max {
            0.0
        } else {
            ratio / self.pivot_max
        };
        let (nv, m) = (self.model.nv, self.model.nconstraints());
        let turned = self
            .crossings
            .get_or_insert_with(|| Box::new(Crossings::new(nv, m)))
            .update(solver, self.t_last);
        if (turned || relative < SINGULAR_PASSAGE) && self.singular_passage.is_none() {
            self.singular_passage = Some((self.t_last, relative));
        }
        Ok(changed)
    }
}

#[cfg(test)]
#[path = "tests/dynamics.rs"]
mod tests;
