//! One explicit Runge–Kutta engine for every embedded tableau, SciPy's `RungeKutta`
//! (`_step_impl`, `rk_step`; scipy/integrate/_ivp/rk.py): a [`Tableau`] gives the stages, the
//! propagated solution, the error norm and the interpolant; [`ExplicitRk`] does the rest —
//! step-size control (SciPy's, or the PI controller), FSAL, projection, Hairer's stiffness
//! test and the dense output's extra stages. `Stepper` (RK45) and `Dop853` are this engine
//! with their tableaux. Arithmetic is kept in NumPy's order so accept/reject decisions, and
//! hence step counts, match SciPy's. A trial with a non-finite stage is rejected as SciPy's
//! NaN/inf error norm rejects it, without evaluating its remaining stages (so `nfev` is then
//! lower than SciPy's); a non-finite value at an accepted state, or in a trial at the minimum
//! step, ends the run ([`Status::NonFinite`]).

use std::ops::{Deref, DerefMut};

use super::common::{
    self, call_rhs, check_start, check_state, check_step_options, step_state_accessors, tolerances,
    Lifecycle, StepState, Stepping,
};
use super::dense::Interpolant;
use super::method::{Counts, Integrator, Method};
use super::spectral::SpectralCheck;
use super::{
    Controller, InputError, OdeSystem, SolverOptions, Status, StepOutcome, Stiffness,
    StiffnessCheck, NONSTIFF_RESET, STIFF_STEPS,
};

pub(crate) const SAFETY: f64 = 0.9;
pub(crate) const MIN_FACTOR: f64 = 0.2;
pub(crate) const MAX_FACTOR: f64 = 10.0;
/// Floor of the previous error in the PI controller (Hairer's `facold` start value).
const PI_ERR_FLOOR: f64 = 1e-4;

/// An embedded explicit Runge–Kutta pair as the engine needs it (SciPy's class attributes
/// `C`, `A`, `B`, `E`, `P`, `order`, `error_estimator_order`, `n_stages`).
///
/// `k` holds [`Tableau::ROWS`] rows of `dim`: the stages `0..N_STAGES`, then
/// `f(t_new, y_new)` (FSAL), then the dense output's extra stages, if any. Its last stage
/// ends at `t + h` (`C[N_STAGES - 1] = 1`), which the stiffness test uses.
pub trait Tableau {
    /// The method's name in results and messages.
    const METHOD: Method;
    const N_STAGES: usize;
    /// Rows of `k` (at least `N_STAGES + 1`).
    const ROWS: usize;
    /// The nodes of every row of `k` but the FSAL one.
    const C: &'static [f64];
    /// SciPy's `error_estimator_order` (the initial step's order).
    const ERROR_ESTIMATOR_ORDER: u32;
    /// `-1 / (error_estimator_order + 1)`, evaluated as SciPy does.
    const ERROR_EXPONENT: f64;
    /// Hairer's `h·|λ|` threshold of the stiffness test (the edge of the stability region
    /// along the negative axis: 3.25 in DOPRI5, 6.1 in DOP853).
    const STIFF_H_LAMBDA: f64;
    const INTERPOLANT: Interpolant;
    /// Stage `s` (`1 ≤ s < ROWS`, not the FSAL row): `out = base + (K[:s]ᵀ A[s, :s]) h`.
    fn stage_state(s: usize, out: &mut [f64], base: &[f64], k: &[f64], h: f64);
    /// `out = y + (K[:N_STAGES]ᵀ B) h`.
    fn propagate(out: &mut [f64], y: &[f64], k: &[f64], h: f64);
    /// The step's error norm (`< 1` accepts), SciPy's `_estimate_error_norm`;
    /// `scratch` is a workspace of `dim`.
    fn error_norm(
        k: &[f64],
        ys: (&[f64], &[f64]),
        tols: (&[f64], &[f64]),
        h: f64,
        scratch: &mut [f64],
    ) -> f64;
    /// The interpolant's coefficients (`INTERPOLANT.n_coef()` per component) from every row
    /// of `k`, the step's ends and `h = t - t_old`.
    fn dense(k: &[f64], ends: (&[f64], &[f64], &[f64]), h: f64, q: &mut [f64]);
    /// The error estimate as displacements of the state, `h Kᵀ E` into `e` (and the
    /// lower-order one, where the method blends two, into `e_low`): what
    /// [`OdeSystem::filter_error`] reduces for systems kept on a manifold.
    fn error_vectors(k: &[f64], h: f64, e: &mut [f64], e_low: &mut [f64]);
    /// Whether the norm blends a lower-order estimate (`e_low` is used).
    const BLENDS_LOWER_ORDER: bool;
    /// [`Tableau::error_norm`] of the (filtered) displacements of [`Tableau::error_vectors`].
    fn norm_of_vectors(
        e: &[f64],
        e_low: &[f64],
        ys: (&[f64], &[f64]),
        tols: (&[f64], &[f64]),
    ) -> f64;
}

/// With loops, the share of the plain (unfiltered) error estimate a step must still pass:
/// a step whose estimate across the manifolds exceeds ~3000 tolerances has stages so far
/// off them that their projections (onto the branch nearest each stage, near a singular
/// position) are outside the estimate's range; A02 took such a step over a crossing at rtol
/// 1e-12 (plain 2.3e4, filtered 0.09, an energy jump of 3e-9). Rounding alone stays below
/// it: from its scene state A02 passes every rtol from 1e-6 to 1e-12 for values 1e-4 to 1e-3;
/// 3e-3 crawls again (docs/mechanisms.md §2 for how far that holds near other states).
pub(super) const OFF_MANIFOLD_TRUST: f64 = 3e-4;

/// With loops, a step's second rejection that leaves it below this share of the reference step
/// (`h_ref`: the last step accepted at the first try, or 0.9ⁿ times an earlier longer one
/// n such steps before) means the controller may be trapped at a singular position: near
/// one the accelerations carry the projection's rounding amplified `~ 1/σ³`, every stage
/// within ~2e-4 s of the crossing fails the test at rtol 1e-12, and the shrinking steps
/// approach the crossing geometrically instead of passing it (docs/mechanisms.md §2). A step
/// about as long as before may put the crossing between its stages and pass the same test;
/// once the state is itself within ~2e-4 s of it no step does, hence 0.35 (early in the
/// shrinking), not a smaller share that waits for the approach.
const TRAPPED: f64 = 0.35;
/// The reference step's decay per step accepted at the first try.
const REF_DECAY: f64 = 0.9;
/// The trapped controller's attempts, in shares of the reference step: several, as where
/// the stages fall relative to the crossing decides. Bounded: one round, then none until a
/// step is accepted at the first try again.
const JUMP_FACTORS: [f64; 5] = [1.0, 0.77, 1.3, 0.6, 0.45];

/// `Σ_s k_s w_s` of component `i` (`k`: rows of `n`), in stage order.
#[inline(always)]
pub(super) fn stage_sum(k: &[f64], n: usize, i: usize, w: &[f64]) -> f64 {
    let mut e = k[i] * w[0];
    for (s, ws) in w.iter().enumerate().skip(1) {
        e += k[s * n + i] * ws;
    }
    e
}

/// `scale = atol + max(|y|, |y_new|) rtol` of component `i`.
#[inline(always)]
pub(super) fn error_scale(
    i: usize,
    (y, y_new): (&[f64], &[f64]),
    (atol, rtol): (&[f64], &[f64]),
) -> f64 {
    atol[i] + y[i].abs().max(y_new[i].abs()) * rtol[i]
}

/// Adaptive explicit Runge–Kutta with tableau `T`, usable one step at a time (SciPy's solver
/// object). All buffers are allocated in [`ExplicitRk::new`]; [`ExplicitRk::step`] allocates
/// nothing. The first `step` (or an explicit [`ExplicitRk::initialize`]) evaluates
/// `f(t0, y0)` and, without `first_step`, one more rhs call to choose the initial step.
/// Dereferences to its [`StepState`] (`t()`, `y()`, `nfev()`, ...).
pub struct ExplicitRk<S: OdeSystem, T: Tableau> {
    sys: S,
    st: StepState,
    /// Stage derivatives, `T::ROWS` rows of `dim`.
    k: Vec<f64>,
    y_stage: Vec<f64>,
    /// Workspace of the error norm.
    scaled_error: Vec<f64>,
    /// With a system kept on a manifold ([`OdeSystem::filters_error`]): the error
    /// estimate's displacements (and the lower-order ones), filtered before the norm.
    error_vectors: Option<(Vec<f64>, Vec<f64>)>,
    controller: Controller,
    /// Previous accepted error norm (PI controller only).
    err_prev: f64,
    stiffness_check: StiffnessCheck,
    /// Hairer's IASTI / NONSTI counters.
    stiff_count: usize,
    nonstiff_count: usize,
    /// `h·|λ|` of the last accepted step (NaN before the first, or with the check off).
    h_lambda: f64,
    /// With loops: the step size the controller had before it was trapped at a singular
    /// position (see [`ExplicitRk::jump`]); 0 before the first step.
    h_ref: f64,
    /// With loops: a step accepted at the first try since the last round of jumps.
    jump_armed: bool,
    /// `StiffnessCheck::Stop` without manifolds: the Jacobian's test ([`SpectralCheck`]).
    spectral: Option<SpectralCheck>,
    /// First detection.
    stiffness: Option<Stiffness>,
    /// `StiffnessCheck::Stop`: the failure the next `step` returns.
    stop: Option<Status>,
    _tableau: std::marker::PhantomData<T>,
}

impl<S: OdeSystem, T: Tableau> Deref for ExplicitRk<S, T> {
    type Target = StepState;
    fn deref(&self) -> &StepState {
        &self.st
    }
}

impl<S: OdeSystem, T: Tableau> DerefMut for ExplicitRk<S, T> {
    fn deref_mut(&mut self) -> &mut StepState {
        &mut self.st
    }
}

impl<S: OdeSystem, T: Tableau> ExplicitRk<S, T> {
    /// Validate the inputs and allocate all workspaces (no rhs call yet).
    /// `opts.dense` and `opts.t_eval` are driver options and ignored here.
    pub fn new(
        sys: S,
        t0: f64,
        y0: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
    ) -> Result<Self, InputError> {
        let dim = sys.dim();
        check_start(dim, y0, t0, t_bound)?;
        let tols = tolerances(opts, dim)?;
        check_step_options(opts, (t_bound - t0).abs())?;
        let filters = sys.filters_error();
        Ok(Self {
            sys,
            st: StepState::new(t0, y0, t_bound, opts, tols),
            k: vec![0.0; T::ROWS * dim],
            y_stage: vec![0.0; dim],
            scaled_error: vec![0.0; dim],
            error_vectors: filters.then(|| (vec![0.0; dim], vec![0.0; dim])),
            controller: opts.controller,
            err_prev: PI_ERR_FLOOR,
            stiffness_check: opts.stiffness,
            stiff_count: 0,
            nonstiff_count: 0,
            h_lambda: f64::NAN,
            h_ref: 0.0,
            jump_armed: false,
            spectral: (opts.stiffness == StiffnessCheck::Stop && !filters)
                .then(|| SpectralCheck::new(dim)),
            stiffness: None,
            stop: None,
            _tableau: std::marker::PhantomData,
        })
    }

    /// Evaluate `f(t0, y0)` and choose the first step. Called by the first
    /// [`ExplicitRk::step`]; call it yourself to keep those rhs calls out of a timing.
    pub fn initialize(&mut self) -> Result<(), Status> {
        common::initialize(self)
    }

    /// Take one accepted step (retrying with smaller steps as needed), SciPy `_step_impl`.
    /// `Err` carries a failure status (StepTooSmall, MaxSteps, NonFinite, RhsError, and Stiff
    /// with [`StiffnessCheck::Stop`]: the step that completes a detection is accepted and
    /// returned, the next call fails); after it, every call returns the same error.
    #[inline]
    pub fn step(&mut self) -> Result<StepOutcome, Status> {
        common::step(self)
    }

    /// Stage `s` from `y` at `t` (or from `y_old` at `t_old` for the dense output's extra
    /// stages): `y_stage`, then `K[s] = f(t_base + C[s] h, y_stage)`.
    #[inline(always)]
    fn stage(&mut self, s: usize, from_old: bool, t_reached: f64, h: f64) -> Result<(), Status> {
        let n = self.st.dim;
        let (base, t_base) = if from_old {
            (&self.st.y_old[..], self.st.t_old)
        } else {
            (&self.st.y[..], self.st.t)
        };
        T::stage_state(s, &mut self.y_stage, base, &self.k[..s * n], h);
        let at = t_base + T::C[s] * h;
        check_state(&self.y_stage, t_reached, at)?;
        let ks = &mut self.k[s * n..(s + 1) * n];
        call_rhs(
            &mut self.sys,
            &mut self.st.nfev,
            t_reached,
            at,
            &self.y_stage,
            ks,
        )
    }

    /// SciPy `rk_step`: the stages, `y_new` and `K[N_STAGES] = f(t + h, y_new)`.
    fn rk_stages(&mut self, t: f64, h: f64) -> Result<(), Status> {
        let n = self.st.dim;
        self.k[..n].copy_from_slice(&self.st.f);
        for s in 1..T::N_STAGES {
            self.stage(s, false, t, h)?;
        }
        T::propagate(
            &mut self.st.y_new,
            &self.st.y,
            &self.k[..T::N_STAGES * n],
            h,
        );
        check_state(&self.st.y_new, t, t + h)?;
        let last = &mut self.k[T::N_STAGES * n..(T::N_STAGES + 1) * n];
        call_rhs(
            &mut self.sys,
            &mut self.st.nfev,
            t,
            t + h,
            &self.st.y_new,
            last,
        )
    }

    /// The step's error norm. With loops the estimate's displacements are first reduced to
    /// what the projected step keeps, `P(y + e) − P(y)` (as Radau's; docs/mechanisms.md §2):
    /// near a singular position the stages' accelerations carry the rounding of the
    /// projection amplified `~ 1/σ³` across the manifolds, which the accepted state's
    /// projection removes and a plain estimate chases with ever shorter steps (A02 at rtol
    /// 1e-12 crawled at 1e-9 s steps). The plain estimate still rejects a step once it is
    /// [`OFF_MANIFOLD_TRUST`]⁻¹ times the tolerance.
    fn error_norm(&mut self, h: f64) -> f64 {
        let st = &self.st;
        let ys = (&st.y[..], &st.y_new[..]);
        let tols = (&st.atol[..], &st.rtol[..]);
        match self.error_vectors.as_mut() {
            None => T::error_norm(&self.k, ys, tols, h, &mut self.scaled_error),
            Some((e, e_low)) => {
                T::error_vectors(&self.k, h, e, e_low);
                let raw = T::norm_of_vectors(e, e_low, ys, tols);
                self.sys.filter_error(&st.y, e);
                if T::BLENDS_LOWER_ORDER {
                    self.sys.filter_error(&st.y, e_low);
                }
                T::norm_of_vectors(e, e_low, ys, tols).max(OFF_MANIFOLD_TRUST * raw)
            }
        }
    }

    /// Trapped at a singular position (loops only; see [`TRAPPED`]): a few attempts of
    /// about the step the controller had before, each under the unchanged acceptance test
    /// (a non-finite stage, as far off a manifold as a long step may land, fails the
    /// attempt, not the run). The first that passes: `(t_new, next h_abs)`.
    fn jump(&mut self, t: f64) -> Result<Option<(f64, f64)>, Status> {
        let mut last = 0.0;
        for f in JUMP_FACTORS {
            let (t_new, h) = self.st.attempt((self.h_ref * f).min(self.st.max_step));
            if h == last {
                continue; // clipped to t_bound or max_step like the one before
            }
            last = h;
            match self.rk_stages(t, h) {
                Err(Status::NonFinite { .. }) => {}
                Err(e) => return Err(e),
                Ok(()) => {
                    let error_norm = self.error_norm(h);
                    if error_norm < 1.0 {
                        let factor = self.accept_factor(error_norm).min(1.0);
                        return Ok(Some((t_new, h.abs() * factor)));
                    }
                }
            }
            self.st.n_rejected += 1;
        }
        Ok(None)
    }

    fn accept_factor(&mut self, error_norm: f64) -> f64 {
        match self.controller {
            Controller::Standard => {
                if error_norm == 0.0 {
                    MAX_FACTOR
                } else {
                    MAX_FACTOR.min(SAFETY * error_norm.powf(T::ERROR_EXPONENT))
                }
            }
            Controller::PI { alpha, beta } => {
                let f = if error_norm == 0.0 {
                    MAX_FACTOR
                } else {
                    (SAFETY * error_norm.powf(-alpha) * self.err_prev.powf(beta))
                        .clamp(MIN_FACTOR, MAX_FACTOR)
                };
                self.err_prev = error_norm.max(PI_ERR_FLOOR);
                f
            }
        }
    }

    fn reject_factor(&self, error_norm: f64) -> f64 {
        let exponent = match self.controller {
            Controller::Standard => T::ERROR_EXPONENT,
            Controller::PI { alpha, .. } => -alpha,
        };
        // f64::max ignores NaN like Python's max(MIN_FACTOR, nan) here: a NaN norm shrinks by 5.
        MIN_FACTOR.max(SAFETY * error_norm.powf(exponent))
    }

    /// Hairer's stiffness test on the step just accepted (before projection): `h·|λ|` from the
    /// two stage states at `t + h` (`y_stage` holds the last stage, `y_new` the FSAL one) and
    /// their derivatives (`K[N_STAGES - 1]`, `K[N_STAGES]`).
    fn stiffness_test(&mut self, h: f64, t_new: f64) {
        let (n, s) = (self.st.dim, T::N_STAGES);
        let (k6, k7) = (&self.k[(s - 1) * n..s * n], &self.k[s * n..(s + 1) * n]);
        let (y6, y7) = (&self.y_stage, &self.st.y_new);
        // Scaled sums, so that huge (but finite) states or derivatives cannot overflow.
        let (mut sk, mut sy) = (0.0f64, 0.0f64);
        for i in 0..n {
            sk = sk.max((k7[i] - k6[i]).abs());
            sy = sy.max((y7[i] - y6[i]).abs());
        }
        if !(sy > 0.0 && sy.is_finite() && sk.is_finite()) {
            // Identical stage states (or an overflowing difference): no information; Hairer
            // keeps the previous estimate.
            return;
        }
        let (mut num, mut den) = (0.0, 0.0);
        if sk > 0.0 {
            for i in 0..n {
                let dk = (k7[i] - k6[i]) / sk;
                let dy = (y7[i] - y6[i]) / sy;
                num += dk * dk;
                den += dy * dy;
            }
        } else {
            den = 1.0;
        }
        let h_lambda = h.abs() * (sk / sy) * (num / den).sqrt();
        if h_lambda.is_finite() {
            self.h_lambda = h_lambda;
            self.count_stiff(h_lambda, h.abs(), t_new);
        }
    }

    /// Hairer's counters: `STIFF_STEPS` steps above the threshold make a detection, a run of
    /// `NONSTIFF_RESET` below it starts the count again.
    fn count_stiff(&mut self, h_lambda: f64, h: f64, t: f64) {
        if h_lambda <= T::STIFF_H_LAMBDA {
            self.nonstiff_count += 1;
            if self.nonstiff_count == NONSTIFF_RESET {
                self.stiff_count = 0;
            }
            return;
        }
        self.nonstiff_count = 0;
        self.stiff_count += 1;
        if self.stiff_count == STIFF_STEPS && self.stiffness.is_none() {
            self.stiffness = Some(Stiffness { t, h_lambda, h });
            if self.stiffness_check == StiffnessCheck::Stop {
                self.stop = Some(Status::Stiff { t, h_lambda, h });
            }
        }
    }

    /// The Jacobian's stiffness test ([`SpectralCheck`]) on the state just accepted after a
    /// step of size `h`, when due and nothing was detected yet.
    fn spectral_test(&mut self, h: f64) {
        let Some(check) = self.spectral.as_mut() else {
            return;
        };
        if self.stiffness.is_some() || !SpectralCheck::due(self.st.n_accepted) {
            return;
        }
        let st = &mut self.st;
        let (t, y, f) = (st.t, &st.y, &st.f);
        let limit = super::spectral::FRACTION * T::STIFF_H_LAMBDA;
        let sys = &mut self.sys;
        // Like a detection, a failed evaluation ends the run after this accepted step.
        match check.check(sys, &mut st.nfev, t, y, f, &self.y_stage, h, limit) {
            Ok(None) => {}
            Ok(Some(h_lambda)) => {
                self.stiffness = Some(Stiffness { t, h_lambda, h });
                self.stop.get_or_insert(Status::Stiff { t, h_lambda, h });
            }
            Err(failure) => {
                self.stop.get_or_insert(failure);
            }
        }
    }

    /// The accepted `y_new` becomes the state (projected first), `f` its derivative.
    fn accept(&mut self, t_new: f64, h_abs: f64) -> Result<StepOutcome, Status> {
        let t = self.st.t;
        let moved = self
            .sys
            .project(&mut self.st.y_new)
            .map_err(|message| Status::RhsError {
                t,
                at: t_new,
                message,
            })?;
        check_state(&self.st.y_new, t, t_new)?;
        let st = &mut self.st;
        std::mem::swap(&mut st.y_old, &mut st.y);
        std::mem::swap(&mut st.y, &mut st.y_new);
        if moved {
            // The projected state's own derivative starts the next step (FSAL's is the
            // unprojected one); the interpolant keeps the step's stages.
            call_rhs(&mut self.sys, &mut st.nfev, t, t_new, &st.y, &mut st.f)?;
        } else {
            let n = st.dim;
            let fsal = T::N_STAGES * n;
            st.f.copy_from_slice(&self.k[fsal..fsal + n]);
        }
        st.t_old = t;
        st.t = t_new;
        st.h_abs = h_abs;
        st.n_accepted += 1;
        Ok(st.outcome())
    }

    /// The stage derivatives of the last step (`T::ROWS` rows of `dim`).
    pub(crate) fn stages(&self) -> &[f64] {
        &self.k
    }
    /// Hairer's `h·|λ|` estimate on the last accepted step (NaN before it or with the check off).
    pub fn h_lambda(&self) -> f64 {
        self.h_lambda
    }
    /// First stiffness detection, if any (see [`StiffnessCheck`]).
    pub fn stiffness(&self) -> Option<Stiffness> {
        self.stiffness
    }
    pub fn system(&self) -> &S {
        &self.sys
    }
    pub fn system_mut(&mut self) -> &mut S {
        &mut self.sys
    }
    pub fn into_system(self) -> S {
        self.sys
    }
    /// The step state and the system together, for a run continued across calls
    /// (`integrator::resume`).
    pub(crate) fn parts(&mut self) -> (&mut StepState, &mut S) {
        (&mut self.st, &mut self.sys)
    }
}

impl<S: OdeSystem, T: Tableau> Stepping for ExplicitRk<S, T> {
    fn lifecycle(&mut self) -> &mut Lifecycle {
        &mut self.st.lifecycle
    }

    fn start(&mut self) -> Result<(), Status> {
        self.st.rhs_here(&mut self.sys)?;
        self.st.h_abs = match self.st.first_step {
            Some(h) => h,
            None => {
                let n = self.st.dim;
                let scratch = (
                    &mut self.scaled_error[..],
                    &mut self.y_stage[..],
                    &mut self.k[n..2 * n],
                );
                self.st
                    .initial_step(&mut self.sys, T::ERROR_ESTIMATOR_ORDER, scratch)?
            }
        };
        Ok(())
    }

    fn advance(&mut self) -> Result<StepOutcome, Status> {
        let (mut h_abs, min_step, _) = self.st.step_bounds()?;
        let t = self.st.t;
        let mut rejections = 0usize;
        // The last attempt's non-finite stage: the failure if the step falls below `min_step`.
        let mut non_finite = None;
        let t_new = loop {
            if h_abs < min_step {
                return Err(non_finite.unwrap_or(Status::StepTooSmall { t, min_step }));
            }
            let (t_new, h) = self.st.attempt(h_abs);
            h_abs = h.abs();
            // A non-finite stage (state or derivative) rejects the attempt as SciPy's NaN/inf
            // error norm does (shrunk by MIN_FACTOR); its remaining stages are not evaluated.
            let error_norm = match self.rk_stages(t, h) {
                Ok(()) => {
                    non_finite = None;
                    self.error_norm(h)
                }
                Err(s @ Status::NonFinite { .. }) => {
                    non_finite = Some(s);
                    f64::INFINITY
                }
                Err(e) => return Err(e),
            };
            if error_norm < 1.0 {
                let mut factor = self.accept_factor(error_norm);
                if rejections > 0 {
                    factor = factor.min(1.0);
                }
                h_abs *= factor;
                break t_new;
            }
            h_abs *= self.reject_factor(error_norm);
            rejections += 1;
            self.st.n_rejected += 1;
            // From the second rejection on: a first one that shrinks much is common on a
            // regular mechanism (Andrews' transient) where the round only costs evaluations.
            if self.jump_armed && rejections >= 2 && h_abs < self.h_ref * TRAPPED {
                self.jump_armed = false;
                if let Some((t_new, next)) = self.jump(t)? {
                    h_abs = next;
                    break t_new;
                }
            }
        };
        if self.error_vectors.is_some() && rejections == 0 {
            self.h_ref = (t_new - t).abs().max(self.h_ref * REF_DECAY);
            self.jump_armed = true;
        }
        if self.stiffness_check != StiffnessCheck::Off {
            self.stiffness_test(t_new - t, t_new);
        }
        let outcome = self.accept(t_new, h_abs)?;
        self.spectral_test((t_new - t).abs());
        Ok(outcome)
    }

    fn take_pending(&mut self) -> Option<Status> {
        self.stop.take()
    }
}

impl<S: OdeSystem, T: Tableau> Integrator for ExplicitRk<S, T> {
    type System = S;
    #[inline]
    fn step(&mut self) -> Result<StepOutcome, Status> {
        common::step(self)
    }
    step_state_accessors!();
    fn counts(&self) -> Counts {
        Counts::explicit(self.st.nfev, self.st.n_accepted, self.st.n_rejected)
    }
    fn stiffness(&self) -> Option<Stiffness> {
        self.stiffness
    }
    fn interpolant(&self) -> Interpolant {
        T::INTERPOLANT
    }
    /// The extra stages from `y_old` (counted in `nfev`, as SciPy does), then the tableau's
    /// coefficients.
    fn dense_coefficients(&mut self, q: &mut [f64]) -> Result<(), Status> {
        let (t, h) = (self.st.t, self.st.t - self.st.t_old);
        for s in T::N_STAGES + 1..T::ROWS {
            let r = self.stage(s, true, t, h);
            common::record(&mut self.st.lifecycle, r)?;
        }
        let st = &self.st;
        T::dense(&self.k, (&st.y_old, &st.y, &st.f), h, q);
        Ok(())
    }
    fn system_mut(&mut self) -> &mut S {
        &mut self.sys
    }
    fn into_system(self) -> S {
        self.sys
    }
}
