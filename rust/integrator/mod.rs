//! Adaptive Dormand–Prince 5(4) integrator that reproduces SciPy's
//! `solve_ivp(method="RK45")` step for step.
//!
//! * `stepper.rs` – Butcher tableau, error norm, step-size control, [`Stepper`].
//! * `dense.rs`   – SciPy's quartic interpolant and the piecewise [`DenseOutput`].
//! * `events.rs`  – [`Event`] functions and SciPy's `brentq` root finder.
//! * this file    – public types and the [`rk45`] driver (SciPy's `solve_ivp` loop).
//!
//! Stiffness detection ([`StiffnessCheck`], Hairer's DOPRI5 test) only observes the accepted
//! steps: with `Off` or `Warn` the steps are exactly SciPy's; `Stop` ends the run early.
//!
//! Same problem + same options ⇒ same accept/reject decisions, step count and `nfev` as SciPy:
//! every formula is evaluated as SciPy writes it, with sums in plain stage order. NumPy sums
//! through OpenBLAS (FMA, CPU-dependent blocking) and the error estimate cancels ~7+ digits,
//! so step times can differ from SciPy's by up to ~1e-7 relative at tight tolerances (as
//! SciPy's own do between CPUs); values at fixed times (t_end, t_eval, events) agree to ~1e-14.

mod dense;
mod events;
mod stepper;

pub use dense::{eval_segment, DenseOutput};
pub use events::{Event, EventDirection, EventFn};
pub use stepper::{StepOutcome, Stepper};

use thiserror::Error;

/// Right-hand side `dy/dt = f(t, y)` of a first-order system.
pub trait OdeSystem {
    /// Number of state components.
    fn dim(&self) -> usize;
    /// Fill `dydt`; an `Err` stops the integration with that message
    /// (status [`Status::RhsError`]) and the time reached.
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String>;
    /// Called on each accepted state (e.g. to re-normalise quaternions); not on `y0`.
    /// Contract: `rhs(t, project(y)) == rhs(t, y)`, so FSAL stays valid. Default: no-op.
    fn project(&mut self, _y: &mut [f64]) {}
}

impl<S: OdeSystem + ?Sized> OdeSystem for &mut S {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
        (**self).rhs(t, y, dydt)
    }
    fn project(&mut self, y: &mut [f64]) {
        (**self).project(y)
    }
}

impl<S: OdeSystem + ?Sized> OdeSystem for Box<S> {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
        (**self).rhs(t, y, dydt)
    }
    fn project(&mut self, y: &mut [f64]) {
        (**self).project(y)
    }
}

/// Adapter turning a closure `f(t, y, dydt) -> Result<(), String>` into an [`OdeSystem`].
/// (A closure carries no dimension, hence an adapter instead of a blanket impl.)
pub struct FnSystem<F> {
    dim: usize,
    f: F,
}

impl<F> FnSystem<F>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), String>,
{
    pub fn new(dim: usize, f: F) -> Self {
        Self { dim, f }
    }
}

impl<F> OdeSystem for FnSystem<F>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), String>,
{
    fn dim(&self) -> usize {
        self.dim
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
        (self.f)(t, y, dydt)
    }
}

/// A tolerance: one value for all components or one per component.
#[derive(Debug, Clone, PartialEq)]
pub enum Tol {
    Scalar(f64),
    PerComponent(Vec<f64>),
}

impl From<f64> for Tol {
    fn from(v: f64) -> Self {
        Tol::Scalar(v)
    }
}

impl From<Vec<f64>> for Tol {
    fn from(v: Vec<f64>) -> Self {
        Tol::PerComponent(v)
    }
}

impl From<&[f64]> for Tol {
    fn from(v: &[f64]) -> Self {
        Tol::PerComponent(v.to_vec())
    }
}

/// Step-size controller.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Controller {
    /// SciPy's: `factor = SAFETY * err^(-1/5)`, clamped to `[MIN_FACTOR, MAX_FACTOR]`.
    #[default]
    Standard,
    /// Gustafsson/Hairer PI control on accepted steps:
    /// `factor = SAFETY * err^(-alpha) * err_prev^beta` (err_prev = previous accepted
    /// error norm, floored at 1e-4 as in Hairer's DOPRI5); after a rejection
    /// `factor = max(MIN_FACTOR, SAFETY * err^(-alpha))`. Not SciPy-compatible.
    PI { alpha: f64, beta: f64 },
}

impl Controller {
    /// Hairer's DOPRI5 defaults: `beta = 0.04`, `alpha = 1/5 - 0.75 * beta = 0.17`.
    pub fn hairer_pi() -> Self {
        Controller::PI {
            alpha: 0.17,
            beta: 0.04,
        }
    }
}

/// What to do when the problem looks stiff.
///
/// The test is Hairer's (DOPRI5, `NSTIFF`; Hairer & Wanner, *Solving ODEs II*, IV.2): after
/// each accepted step, `h·|λ| ≈ h ‖k7 − k6‖ / ‖y7 − y6‖`, where `y6`, `y7 = y_new` are the
/// two stage states at `t + h` and `k6`, `k7` their derivatives, estimates the step times the
/// dominant eigenvalue of the Jacobian. Above [`STIFF_H_LAMBDA`] (the edge of the
/// Dormand–Prince stability region, ≈ 3.3) on [`STIFF_STEPS`] accepted steps (a run of
/// [`NONSTIFF_RESET`] steps below it starts the count again) the step size is limited by
/// stability, not accuracy: an explicit method then needs ~|λ|·T/3 steps whatever the
/// tolerance, where an implicit one (SciPy's Radau, BDF) would not.
///
/// Cost: two vector differences per accepted step; no extra right-hand-side call.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StiffnessCheck {
    /// No test.
    Off,
    /// Test; report the first detection in [`Solution::stiffness`] and append a warning to the
    /// message. The steps are unchanged (still SciPy's, step for step).
    #[default]
    Warn,
    /// Test, and stop at the first detection with [`Status::Stiff`] (the step that completed the
    /// detection is kept).
    Stop,
}

/// `h·|λ|` above which a step counts as stability-limited (Hairer's 3.25).
pub const STIFF_H_LAMBDA: f64 = 3.25;
/// Number of stability-limited accepted steps that make a detection (Hairer's 15).
pub const STIFF_STEPS: usize = 15;
/// Consecutive steps below [`STIFF_H_LAMBDA`] that reset the count (Hairer's 6).
pub const NONSTIFF_RESET: usize = 6;

/// A stiffness detection: where it happened and the estimate `h·|λ|` on that step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffness {
    /// End of the accepted step that completed the detection.
    pub t: f64,
    /// `h·|λ|` estimated on that step.
    pub h_lambda: f64,
    /// The step size `|h|` of that step (so `|λ| ≈ h_lambda / h`).
    pub h: f64,
}

impl Stiffness {
    /// Estimated magnitude of the dominant eigenvalue, `h_lambda / h`.
    pub fn lambda(&self) -> f64 {
        self.h_lambda / self.h
    }

    fn warning(&self) -> String {
        format!(
            "warning: the problem looks stiff from t = {} (h·|λ| ≈ {:.2} > {STIFF_H_LAMBDA} on \
             {STIFF_STEPS} accepted steps, |λ| ≈ {:.3e}): the step size is limited by the \
             stability of the explicit method, not by the tolerance; an implicit solver (e.g. \
             SciPy's Radau or BDF) or softer stiff elements would need far fewer steps",
            fmt_time(self.t),
            self.h_lambda,
            self.lambda()
        )
    }
}

/// A time for a message: plain decimals in the usual range, scientific notation for very
/// small or very large magnitudes (Rust's `Display` would print 70 zeros for 1e-70).
pub fn fmt_time(t: f64) -> String {
    let a = t.abs();
    if t == 0.0 || (1e-4..1e15).contains(&a) || !t.is_finite() {
        format!("{t}")
    } else {
        format!("{t:e}")
    }
}

/// Integration options. Defaults equal SciPy's RK45 defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct Rk45Options {
    /// Relative tolerance (default 1e-3). Values below `100 * f64::EPSILON` are raised to it
    /// (as SciPy does) and `Solution::rtol_clamped` / `Stepper::rtol_clamped` is set.
    pub rtol: Tol,
    /// Absolute tolerance (default 1e-6).
    pub atol: Tol,
    /// First step size; `None` selects it as SciPy's `select_initial_step` (one extra rhs call).
    pub first_step: Option<f64>,
    /// Largest step size (default `f64::INFINITY`).
    pub max_step: f64,
    /// Maximum number of accepted steps (default 1_000_000). Rejected attempts are not
    /// counted; they are bounded anyway because each one shrinks the step by >= 10 %
    /// until it falls below the minimum step (status `StepTooSmall`).
    pub max_steps: usize,
    pub controller: Controller,
    /// Keep the interpolant of every step in `Solution::dense` (SciPy's `dense_output`).
    pub dense: bool,
    /// Output only at these times (from the interpolant), like SciPy's `t_eval`. Must lie within
    /// `t_span` and be strictly monotone in the direction of integration. Ignored by [`Stepper`].
    pub t_eval: Option<Vec<f64>>,
    /// Stiffness detection (default [`StiffnessCheck::Warn`]: report, steps unchanged).
    pub stiffness: StiffnessCheck,
}

impl Default for Rk45Options {
    fn default() -> Self {
        Self {
            rtol: Tol::Scalar(1e-3),
            atol: Tol::Scalar(1e-6),
            first_step: None,
            max_step: f64::INFINITY,
            max_steps: 1_000_000,
            controller: Controller::Standard,
            dense: false,
            t_eval: None,
            stiffness: StiffnessCheck::Warn,
        }
    }
}

/// Invalid input; `argument()` names the offending argument.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum InputError {
    #[error("y0: the system has no components (dim() == 0)")]
    EmptyState,
    #[error("y0: length {got} does not match the system dimension {expected}")]
    Y0Length { expected: usize, got: usize },
    #[error("y0: component {index} is not finite ({value})")]
    Y0NonFinite { index: usize, value: f64 },
    #[error("t_span: bounds must be finite, got ({t0}, {t_end})")]
    TSpanNonFinite { t0: f64, t_end: f64 },
    #[error("t_span: t0 and t_end must differ (both are {0})")]
    TSpanEmpty(f64),
    #[error("{name}: length {got} does not match the system dimension {expected}")]
    TolLength {
        name: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{name}: component {index} must be finite and non-negative, got {value}")]
    TolInvalid {
        name: &'static str,
        index: usize,
        value: f64,
    },
    #[error("max_step: must be positive, got {0}")]
    MaxStep(f64),
    #[error("t_eval: {points} output times of {dim} components need {bytes} bytes, which cannot be allocated")]
    OutputTooLarge {
        points: usize,
        dim: usize,
        bytes: u128,
    },
    #[error("max_steps: must be at least 1")]
    MaxSteps,
    #[error("first_step: must be positive and finite, got {0}")]
    FirstStepNotPositive(f64),
    #[error("first_step: {first_step} exceeds the length {span} of t_span")]
    FirstStepBeyondSpan { first_step: f64, span: f64 },
    #[error(
        "controller: PI needs finite alpha > 0 and beta >= 0, got alpha = {alpha}, beta = {beta}"
    )]
    Controller { alpha: f64, beta: f64 },
    #[error("t_eval: value {value} at index {index} is not within t_span ({t0}, {t_end})")]
    TEvalOutsideSpan {
        index: usize,
        value: f64,
        t0: f64,
        t_end: f64,
    },
    #[error("t_eval: values must be strictly {order} (direction of integration); index {index} breaks it")]
    TEvalNotSorted { index: usize, order: &'static str },
}

impl InputError {
    /// Name of the offending argument (for mapping to e.g. a Python `ValueError`).
    pub fn argument(&self) -> &'static str {
        match self {
            InputError::EmptyState
            | InputError::Y0Length { .. }
            | InputError::Y0NonFinite { .. } => "y0",
            InputError::TSpanNonFinite { .. } | InputError::TSpanEmpty(_) => "t_span",
            InputError::TolLength { name, .. } | InputError::TolInvalid { name, .. } => name,
            InputError::MaxStep(_) => "max_step",
            InputError::MaxSteps => "max_steps",
            InputError::FirstStepNotPositive(_) | InputError::FirstStepBeyondSpan { .. } => {
                "first_step"
            }
            InputError::Controller { .. } => "controller",
            InputError::TEvalOutsideSpan { .. }
            | InputError::TEvalNotSorted { .. }
            | InputError::OutputTooLarge { .. } => "t_eval",
        }
    }
}

/// Which quantity became NaN or infinite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NonFiniteKind {
    /// A value returned by `rhs`.
    Derivative,
    /// The integrated state (a stage or an accepted step).
    State,
}

/// How an integration ended. In every variant `t` is the time reached (last accepted
/// state, or the event time); `at` is the time of the offending evaluation.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// Reached `t_end`.
    Success,
    /// Event number `event` reached its terminal count at time `t`.
    TerminalEvent { event: usize, t: f64 },
    /// The required step fell below `min_step = 10 * ulp(t)` (SciPy's failure).
    StepTooSmall { t: f64, min_step: f64 },
    /// `max_steps` accepted steps were taken before reaching `t_end`.
    MaxSteps { t: f64, max_steps: usize },
    /// A derivative or the state became NaN/inf.
    NonFinite {
        t: f64,
        at: f64,
        what: NonFiniteKind,
    },
    /// The right-hand side returned `Err(message)`.
    RhsError { t: f64, at: f64, message: String },
    /// Event number `event` was NaN at `at` (a Python event that raised reports NaN); the
    /// step that reached `at` was discarded.
    EventNaN { t: f64, at: f64, event: usize },
    /// Stiffness was detected and [`StiffnessCheck::Stop`] asked to stop (see [`Stiffness`]).
    Stiff { t: f64, h_lambda: f64, h: f64 },
}

impl Status {
    /// SciPy's status code: 0 reached the end, 1 terminal event, -1 failure.
    pub fn code(&self) -> i32 {
        match self {
            Status::Success => 0,
            Status::TerminalEvent { .. } => 1,
            _ => -1,
        }
    }

    pub fn is_success(&self) -> bool {
        self.code() >= 0
    }

    /// Human-readable account of what happened, always including the time reached.
    pub fn describe(&self, t_reached: f64) -> String {
        let f = fmt_time;
        match self {
            Status::Success => {
                format!(
                    "reached the end of the integration interval at t = {}",
                    f(t_reached)
                )
            }
            Status::TerminalEvent { event, t } => {
                format!("terminal event {event} occurred at t = {}", f(*t))
            }
            Status::StepTooSmall { t, min_step } => {
                format!(
                    "step size fell below the minimum {min_step:.3e} at t = {}",
                    f(*t)
                )
            }
            Status::MaxSteps { t, max_steps } => {
                format!(
                    "maximum number of steps ({max_steps}) reached at t = {}",
                    f(*t)
                )
            }
            Status::NonFinite { t, at, what } => {
                let what = match what {
                    NonFiniteKind::Derivative => {
                        "the right-hand side returned a non-finite value (NaN or inf)"
                    }
                    NonFiniteKind::State => "the state became non-finite (NaN or inf)",
                };
                format!(
                    "{what} at t = {}; integration reached t = {}",
                    f(*at),
                    f(*t)
                )
            }
            Status::RhsError { t, at, message } => format!(
                "the right-hand side failed at t = {}: {message}; integration reached t = {}",
                f(*at),
                f(*t)
            ),
            Status::EventNaN { t, at, event } => format!(
                "event {event} returned NaN (not a number) at t = {}; integration reached t = {}",
                f(*at),
                f(*t)
            ),
            Status::Stiff { t, h_lambda, h } => format!(
                "the problem is stiff at t = {}: on {STIFF_STEPS} accepted steps the step size \
                 was limited by the stability of the explicit method (h·|λ| ≈ {h_lambda:.2} > \
                 {STIFF_H_LAMBDA}, |λ| ≈ {:.3e}), not by the tolerance; use an implicit solver \
                 (e.g. SciPy's Radau or BDF) or soften the stiff elements",
                f(*t),
                h_lambda / h
            ),
        }
    }
}

/// Result of [`rk45`].
#[derive(Debug, Clone)]
pub struct Solution {
    pub dim: usize,
    /// Output times: t0 and every accepted step, or the `t_eval` values reached.
    pub t: Vec<f64>,
    /// States, row-major `t.len() × dim` (row `i` is the state at `t[i]`).
    pub y: Vec<f64>,
    /// Event times, one list per event (in the order given).
    pub t_events: Vec<Vec<f64>>,
    /// States at the event times, per event row-major `t_events[i].len() × dim`.
    pub y_events: Vec<Vec<f64>>,
    /// Right-hand-side evaluations (SciPy's count: events do not call it).
    pub nfev: usize,
    /// Always 0 (explicit method).
    pub njev: usize,
    pub n_accepted: usize,
    pub n_rejected: usize,
    pub status: Status,
    /// What happened and the time reached.
    pub message: String,
    /// Last time reached (t_end, the terminal event time, or where it stopped).
    pub t_reached: f64,
    /// Some rtol was below `100 * EPS` and raised to it (SciPy warns instead).
    pub rtol_clamped: bool,
    /// Piecewise interpolant when `Rk45Options::dense` is on.
    pub dense: Option<DenseOutput>,
    /// First stiffness detection (`None` if none, or if the check was off).
    pub stiffness: Option<Stiffness>,
}

impl Solution {
    /// SciPy's `success`: reached the end or a terminal event.
    pub fn success(&self) -> bool {
        self.status.is_success()
    }

    /// State at output index `i`.
    pub fn state(&self, i: usize) -> &[f64] {
        &self.y[i * self.dim..(i + 1) * self.dim]
    }

    /// Dense output at `t` (SciPy's `sol(t)`); `None` unless `dense` was on and a step was taken.
    pub fn dense_eval(&self, t: f64) -> Option<Vec<f64>> {
        let d = self.dense.as_ref()?;
        (d.n_segments() > 0).then(|| d.eval(t))
    }

    /// As [`Solution::dense_eval`] into `out` (length `dim`); returns false if unavailable.
    pub fn dense_eval_into(&self, t: f64, out: &mut [f64]) -> bool {
        match &self.dense {
            Some(d) if d.n_segments() > 0 => {
                d.eval_into(t, out);
                true
            }
            _ => false,
        }
    }
}

fn validate_t_eval(t_eval: &[f64], t0: f64, t_end: f64) -> Result<(), InputError> {
    let (lo, hi) = if t0 < t_end { (t0, t_end) } else { (t_end, t0) };
    for (index, &value) in t_eval.iter().enumerate() {
        // Written so that NaN fails too.
        if !(value >= lo && value <= hi) {
            return Err(InputError::TEvalOutsideSpan {
                index,
                value,
                t0,
                t_end,
            });
        }
    }
    let forward = t_end > t0;
    for index in 1..t_eval.len() {
        let d = t_eval[index] - t_eval[index - 1];
        if (forward && d <= 0.0) || (!forward && d >= 0.0) {
            let order = if forward { "increasing" } else { "decreasing" };
            return Err(InputError::TEvalNotSorted { index, order });
        }
    }
    Ok(())
}

/// Integrate `sys` over `t_span = (t0, t_end)` (backwards if `t_end < t0`) from `y0`,
/// exactly as SciPy's `solve_ivp(..., method="RK45")`. Runtime failures are reported
/// in `Solution::status`; only invalid input gives `Err`.
pub fn rk45<S: OdeSystem>(
    sys: S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &Rk45Options,
    events: &mut [Event<'_>],
) -> Result<Solution, InputError> {
    let (t0, t_end) = t_span;
    let mut st = Stepper::new(sys, t0, y0, t_end, opts)?;
    if let Some(te) = &opts.t_eval {
        validate_t_eval(te, t0, t_end)?;
    }
    let dim = y0.len();
    let dir = st.direction();
    let t_eval = opts.t_eval.as_deref();
    let mut t_eval_i = 0usize;

    let mut t_out: Vec<f64> = Vec::new();
    let mut y_out: Vec<f64> = Vec::new();
    if let Some(te) = t_eval {
        // The caller sized the output: refuse it now, clearly, rather than abort mid-run.
        let too_large = || InputError::OutputTooLarge {
            points: te.len(),
            dim,
            bytes: te.len() as u128 * (dim as u128 + 1) * 8,
        };
        let len = te.len().checked_mul(dim).ok_or_else(too_large)?;
        y_out.try_reserve_exact(len).map_err(|_| too_large())?;
        t_out.try_reserve_exact(te.len()).map_err(|_| too_large())?;
    }
    if t_eval.is_none() {
        t_out.push(t0);
        y_out.extend_from_slice(y0);
    }
    let mut dense = opts.dense.then(|| DenseOutput::new(dim, t0));

    // Event state; all buffers are allocated once here.
    let n_ev = events.len();
    let mut g: Vec<f64> = events.iter_mut().map(|e| (e.func)(t0, y0)).collect();
    // An event that is not a number cannot be watched: the run stops there with the reason
    // (a Python event that raised reports NaN and keeps its exception for the caller).
    let nan_event = |g: &[f64], t_old: f64, at: f64| {
        g.iter()
            .position(|x| x.is_nan())
            .map(|event| Status::EventNaN {
                t: t_old,
                at,
                event,
            })
    };
    let mut failed_at_start = nan_event(&g, t0, t0);
    let mut g_new = vec![0.0; n_ev];
    let mut counts = vec![0usize; n_ev];
    let mut roots: Vec<(usize, f64)> = Vec::with_capacity(n_ev);
    let mut t_events: Vec<Vec<f64>> = vec![Vec::new(); n_ev];
    let mut y_events: Vec<Vec<f64>> = vec![Vec::new(); n_ev];

    let mut q = vec![0.0; 4 * dim]; // interpolant coefficients of the current step
    let mut ybuf = vec![0.0; dim]; // interpolant values (roots, t_eval, terminal state)
    let mut y_term = vec![0.0; dim];

    let status = loop {
        if let Some(s) = failed_at_start.take() {
            break s;
        }
        let outcome = match st.step() {
            Ok(o) => o,
            Err(s) => break s, // SciPy stores nothing from a failed step
        };
        let t_old = st.t_old();
        let mut t = st.t();
        let h = t - t_old;
        // The interpolant is needed for dense output, events and t_eval; it is cheap (28·dim flops).
        let need_q = dense.is_some() || n_ev > 0 || t_eval.is_some();
        if need_q {
            st.fill_dense_q(&mut q);
        }
        if let Some(d) = dense.as_mut() {
            d.push_segment(t_old, h, st.y_old(), &q);
        }

        let mut status = None;
        let mut terminal_state = false;
        if n_ev > 0 {
            let y = st.y();
            for (e, gn) in events.iter_mut().zip(g_new.iter_mut()) {
                *gn = (e.func)(t, y);
            }
            if let Some(s) = nan_event(&g_new, t_old, t) {
                // Nothing of this step is kept (its state, output or dense segment).
                if let Some(d) = dense.as_mut() {
                    d.pop_segment();
                }
                break s;
            }
            roots.clear();
            for i in 0..n_ev {
                if events::is_active(g[i], g_new[i], events[i].direction) {
                    counts[i] += 1;
                    roots.push((i, 0.0));
                }
            }
            if !roots.is_empty() {
                let y_old = st.y_old();
                for r in roots.iter_mut() {
                    let ev = &mut events[r.0];
                    r.1 = events::solve_event_equation(t_old, t, |tt| {
                        eval_segment(t_old, h, y_old, &q, tt, &mut ybuf);
                        (ev.func)(tt, &ybuf)
                    });
                }
                let term = roots
                    .iter()
                    .any(|&(i, _)| events[i].terminal > 0 && counts[i] >= events[i].terminal);
                if term {
                    // Keep the roots up to (and including) the first one that terminates.
                    roots.sort_by(|a, b| (dir * a.1).total_cmp(&(dir * b.1)));
                    let k = roots
                        .iter()
                        .position(|&(i, _)| {
                            events[i].terminal > 0 && counts[i] >= events[i].terminal
                        })
                        .expect("a terminating root exists");
                    roots.truncate(k + 1);
                }
                for &(i, te) in roots.iter() {
                    eval_segment(t_old, h, y_old, &q, te, &mut ybuf);
                    t_events[i].push(te);
                    y_events[i].extend_from_slice(&ybuf);
                }
                if term {
                    let &(i, te) = roots.last().expect("non-empty");
                    t = te;
                    eval_segment(t_old, h, y_old, &q, te, &mut y_term);
                    terminal_state = true;
                    status = Some(Status::TerminalEvent { event: i, t: te });
                }
            }
            std::mem::swap(&mut g, &mut g_new);
        }

        match t_eval {
            None => {
                // SciPy drops a zero-length last segment (terminal root exactly at t_old).
                let duplicate = dense.is_some() && t_out.len() > 1 && *t_out.last().unwrap() == t;
                if duplicate {
                    dense.as_mut().unwrap().pop_segment();
                } else {
                    t_out.push(t);
                    y_out.extend_from_slice(if terminal_state { &y_term } else { st.y() });
                    if let Some(d) = dense.as_mut() {
                        d.push_breakpoint(t);
                    }
                }
            }
            Some(te) => {
                // Every t_eval value up to and including t, from this step's interpolant.
                while t_eval_i < te.len() && dir * (te[t_eval_i] - t) <= 0.0 {
                    eval_segment(t_old, h, st.y_old(), &q, te[t_eval_i], &mut ybuf);
                    t_out.push(te[t_eval_i]);
                    y_out.extend_from_slice(&ybuf);
                    t_eval_i += 1;
                }
                if let Some(d) = dense.as_mut() {
                    d.push_breakpoint(t);
                }
            }
        }

        if let Some(s) = status {
            break s;
        }
        if outcome == StepOutcome::Finished {
            break Status::Success;
        }
    };

    let t_reached = match &status {
        Status::TerminalEvent { t, .. } | Status::EventNaN { t, .. } => *t,
        _ => st.t(),
    };
    let stiffness = st.stiffness();
    let mut message = status.describe(t_reached);
    if let (Some(s), false) = (stiffness, matches!(status, Status::Stiff { .. })) {
        message.push_str("; ");
        message.push_str(&s.warning());
    }
    Ok(Solution {
        dim,
        t: t_out,
        y: y_out,
        t_events,
        y_events,
        nfev: st.nfev(),
        njev: 0,
        n_accepted: st.n_accepted(),
        n_rejected: st.n_rejected(),
        message,
        status,
        t_reached,
        rtol_clamped: st.rtol_clamped(),
        dense,
        stiffness,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Jacobi elliptic functions (sn, cn, dn)(u | m), 0 < m < 1, by the AGM / descending
    /// Landen (Gauss) transformation in Bulirsch's stable form (as Numerical Recipes' `sncndn`);
    /// the textbook `dn = cos φ0 / cos(φ1 - φ0)` loses digits near odd multiples of K.
    fn ellipj(u: f64, m: f64) -> (f64, f64, f64) {
        const CA: f64 = 1e-8; // AGM converges quadratically: 1e-8 -> ~1e-16
        let (mut em, mut en) = ([0.0f64; 16], [0.0f64; 16]);
        let (mut a, mut emc, mut c, mut dn) = (1.0f64, 1.0 - m, 0.0f64, 1.0f64);
        let mut l = 0;
        for i in 0..16 {
            l = i;
            em[i] = a;
            emc = emc.sqrt();
            en[i] = emc;
            c = 0.5 * (a + emc);
            if (a - emc).abs() <= CA * a {
                break;
            }
            emc *= a;
            a = c;
        }
        let v = u * c;
        let (mut sn, mut cn) = (v.sin(), v.cos());
        if sn != 0.0 {
            let mut a = cn / sn;
            c *= a;
            for ii in (0..=l).rev() {
                let b = em[ii];
                a *= c;
                c *= dn;
                dn = (en[ii] + a) / (b + a);
                a = c / b;
            }
            let r = 1.0 / (c * c + 1.0).sqrt();
            sn = if sn >= 0.0 { r } else { -r };
            cn = c * sn;
        }
        (sn, cn, dn)
    }

    /// Complete elliptic integral K(m) = π / (2 AGM(1, √(1-m))).
    fn ellipk(m: f64) -> f64 {
        let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
        for _ in 0..10 {
            // Quadratic convergence: 10 iterations are far more than enough for 0 < m < 1 - 1e-10.
            (a, b) = ((a + b) / 2.0, (a * b).sqrt());
        }
        std::f64::consts::PI / (2.0 * a)
    }

    #[test]
    fn jacobi_elliptic_reference_implementation() {
        let m = 0.51;
        for k in 0..100 {
            let u = -7.0 + 0.17 * k as f64;
            let (sn, cn, dn) = ellipj(u, m);
            assert!((sn * sn + cn * cn - 1.0).abs() < 4e-15, "u={u}");
            assert!(
                (dn * dn + m * sn * sn - 1.0).abs() < 4e-15,
                "u={u}: {}",
                dn * dn + m * sn * sn - 1.0
            );
            // d sn/du = cn dn (central difference)
            let d = 1e-5;
            let dsn = (ellipj(u + d, m).0 - ellipj(u - d, m).0) / (2.0 * d);
            assert!((dsn - cn * dn).abs() < 1e-9, "u={u}");
        }
        // K(1/2) (A&S table 17.1) and sn(K) = 1, cn(K) = 0, dn(K) = √(1-m).
        assert!((ellipk(0.5) - 1.854_074_677_301_372).abs() < 1e-14);
        let (sn, cn, dn) = ellipj(ellipk(m), m);
        assert!(
            (sn - 1.0).abs() < 1e-14 && cn.abs() < 1e-7 && (dn - (1.0 - m).sqrt()).abs() < 1e-14
        );
        // Cephes (scipy.special.ellipj) values.
        let (sn, cn, dn) = ellipj(12.0, 0.51);
        assert!((sn + 0.7053978095225708).abs() < 1e-14);
        assert!((cn + 0.7088116324671591).abs() < 1e-14);
        assert!((dn - 0.8638466903702229).abs() < 1e-14);
        let (sn, cn, dn) = ellipj(0.3, 0.9);
        assert!((sn - 0.29173204781861856).abs() < 1e-15);
        assert!((cn - 0.9565000848277826).abs() < 1e-15);
        assert!((dn - 0.9609386926583817).abs() < 1e-15);
        // m -> 0: circular functions.
        let (sn, cn, dn) = ellipj(1.2, 1e-300);
        assert!(
            (sn - 1.2f64.sin()).abs() < 1e-15
                && (cn - 1.2f64.cos()).abs() < 1e-15
                && (dn - 1.0).abs() < 1e-15
        );
    }

    #[allow(clippy::type_complexity)]
    fn krogh() -> FnSystem<impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), String>> {
        FnSystem::new(3, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1] * y[2];
            dy[1] = -y[0] * y[2];
            dy[2] = -0.51 * y[0] * y[1];
            Ok(())
        })
    }

    fn tol(tol: f64) -> Rk45Options {
        Rk45Options {
            rtol: tol.into(),
            atol: tol.into(),
            ..Default::default()
        }
    }

    /// SciPy 1.17 `solve_ivp(krogh, (0, 12), [0, 1, 1], rtol=tol, atol=tol)`: tol, nfev, steps, y(12).
    const SCIPY_KROGH: [(f64, usize, usize, [f64; 3]); 4] = [
        (
            1e-6,
            290,
            40,
            [-0.7053837295840913, -0.7088187876243793, 0.8638491355867974],
        ),
        (
            1e-8,
            608,
            96,
            [-0.7053976933189424, -0.708811680790365, 0.8638467076303797],
        ),
        (
            1e-10,
            1430,
            238,
            [-0.705397808403615, -0.708811632881521, 0.86384669051326],
        ),
        (
            1e-12,
            3584,
            597,
            [-0.7053978095115906, -0.7088116324711137, 0.8638466903715681],
        ),
    ];

    #[test]
    fn krogh_rigid_body_against_exact_solution_and_scipy() {
        let (sn, cn, dn) = ellipj(12.0, 0.51);
        let exact = [sn, cn, dn];
        let mut prev_err = f64::INFINITY;
        for &(tl, nfev, steps, y_scipy) in SCIPY_KROGH.iter() {
            let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(tl), &mut []).unwrap();
            assert_eq!(sol.status, Status::Success);
            assert_eq!(sol.t_reached, 12.0);
            let y = sol.state(sol.t.len() - 1);
            let err = (0..3).map(|i| (y[i] - exact[i]).abs()).fold(0.0, f64::max);
            // SciPy's own error is 11-14 × tol on this problem.
            assert!(err < 20.0 * tl, "tol {tl}: error {err}");
            assert!(err < prev_err / 10.0, "error must fall with the tolerance");
            prev_err = err;
            assert_eq!(
                (sol.nfev, sol.n_accepted, sol.t.len()),
                (nfev, steps, steps + 1),
                "tol {tl}"
            );
            for i in 0..3 {
                assert!(
                    (y[i] - y_scipy[i]).abs() <= 1e-12 * y_scipy[i].abs(),
                    "tol {tl}: {y:?} vs {y_scipy:?}"
                );
            }
            assert_eq!(sol.nfev, 2 + 6 * (sol.n_accepted + sol.n_rejected));
        }
    }

    #[test]
    fn t_eval_and_dense_match_scipy() {
        // SciPy: solve_ivp(krogh, (0, 12), [0, 1, 1], rtol=1e-6, atol=1e-6, dense_output=True,
        //                  t_eval=[0, 2.5, 5, 7.5, 12]); sol(5.5), sol(3.0).
        let y_ref = [
            [0.0, 1.0, 1.0],
            [0.8955678783891637, -0.44491799383282227, 0.7687361247870935],
            [-0.9117258458368565, -0.4107931346396479, 0.7589876922522777],
            [0.049398104974078344, 0.9987765076297669, 0.9993758692252135],
            [-0.7053837295840915, -0.7088187876243793, 0.8638491355867973],
        ];
        let opts = Rk45Options {
            dense: true,
            t_eval: Some(vec![0.0, 2.5, 5.0, 7.5, 12.0]),
            ..tol(1e-6)
        };
        let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
        assert_eq!(sol.t, vec![0.0, 2.5, 5.0, 7.5, 12.0]);
        assert_eq!(sol.nfev, 290);
        let close = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= 1e-13 * y.abs().max(1.0))
        };
        for (i, r) in y_ref.iter().enumerate() {
            assert!(close(sol.state(i), r), "{i}: {:?} vs {r:?}", sol.state(i));
        }
        let d = sol.dense.as_ref().unwrap();
        assert_eq!(d.n_segments(), 40);
        assert!(close(
            &sol.dense_eval(5.5).unwrap(),
            &[-0.998100601916966, -0.06154927474960803, 0.7013779251735642]
        ));
        assert!(close(
            &sol.dense_eval(3.0).unwrap(),
            &[0.6414061767684152, -0.7671989487199022, 0.8889219765383558]
        ));
        // Without t_eval the output is t0 plus every accepted step.
        let plain = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(1e-6), &mut []).unwrap();
        assert_eq!(plain.t.len(), plain.n_accepted + 1);
        assert_eq!(plain.t[0], 0.0);
        assert_eq!(plain.state(0), &[0.0, 1.0, 1.0]);
        assert!(plain.t.windows(2).all(|w| w[1] > w[0]));
        assert!(plain.dense_eval(1.0).is_none());
    }

    #[test]
    fn krogh_events_match_scipy() {
        let mut evs = [Event::new(|_t, y: &[f64]| y[0])];
        let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(1e-6), &mut evs).unwrap();
        let scipy = [
            0.0,
            3.7252845246476824,
            7.450570655182676,
            11.175859348266739,
        ];
        assert_eq!(sol.t_events[0].len(), 4);
        for (a, b) in sol.t_events[0].iter().zip(scipy) {
            assert!((a - b).abs() <= 1e-13 * b.max(1.0), "{a} vs {b}");
        }
    }

    #[test]
    fn backward_integration() {
        // SciPy: solve_ivp(lambda t, y: -y, (1, 0), [1.0]) -> nfev 14, t, y below.
        let decay = || {
            FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
                dy[0] = -y[0];
                Ok(())
            })
        };
        let sol = rk45(
            decay(),
            (1.0, 0.0),
            &[1.0],
            &Rk45Options::default(),
            &mut [],
        )
        .unwrap();
        assert_eq!(sol.status, Status::Success);
        assert_eq!(sol.nfev, 14);
        assert_eq!(sol.t.len(), 3);
        assert_eq!(sol.t[2], 0.0);
        assert!((sol.t[1] - 0.8999800079952034).abs() < 1e-15);
        assert!(
            (sol.y[1] - 1.1051930131367926).abs() < 1e-15
                && (sol.y[2] - 2.7183269995016905).abs() < 1e-14
        );
        assert!((sol.y[2] - std::f64::consts::E).abs() < 1e-4);

        // Krogh backwards from the exact y(12) to t = 0 (SciPy: nfev 902, 151 points).
        let (sn, cn, dn) = ellipj(12.0, 0.51);
        let opts = Rk45Options {
            dense: true,
            t_eval: Some(vec![12.0, 6.0, 1.0, 0.0]),
            ..tol(1e-9)
        };
        let sol = rk45(krogh(), (12.0, 0.0), &[sn, cn, dn], &opts, &mut []).unwrap();
        assert_eq!(sol.nfev, 902);
        assert_eq!(sol.t, vec![12.0, 6.0, 1.0, 0.0]);
        for (i, &t) in sol.t.iter().enumerate() {
            let (s, c, d) = ellipj(t, 0.51);
            let y = sol.state(i);
            assert!(
                (y[0] - s).abs() < 1e-7 && (y[1] - c).abs() < 1e-7 && (y[2] - d).abs() < 1e-7,
                "t={t}"
            );
        }
        let y = sol.dense_eval(3.3).unwrap();
        assert!((y[0] - ellipj(3.3, 0.51).0).abs() < 1e-7);
    }

    #[test]
    fn nan_in_rhs_gives_non_finite_with_time() {
        let sys = FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
            dy[0] = if t > 0.5 { f64::NAN } else { -y[0] };
            Ok(())
        });
        let sol = rk45(sys, (0.0, 2.0), &[1.0], &Rk45Options::default(), &mut []).unwrap();
        match sol.status {
            Status::NonFinite { t, at, what } => {
                assert_eq!(what, NonFiniteKind::Derivative);
                assert!(t <= 0.5 && at > 0.5 && at > t, "t={t} at={at}");
                assert_eq!(sol.t_reached, t);
                assert_eq!(*sol.t.last().unwrap(), t);
            }
            ref s => panic!("unexpected {s:?}"),
        }
        assert_eq!(sol.status.code(), -1);
        assert!(!sol.success());
        assert!(
            sol.message.contains("non-finite") && sol.message.contains("t = "),
            "{}",
            sol.message
        );
    }

    #[test]
    fn overflowing_state_gives_non_finite_state() {
        let sys = FnSystem::new(1, |_t, _y: &[f64], dy: &mut [f64]| {
            dy[0] = f64::MAX;
            Ok(())
        });
        let sol = rk45(sys, (0.0, 1.0), &[1.0], &Rk45Options::default(), &mut []).unwrap();
        assert!(
            matches!(sol.status, Status::NonFinite { t, what: NonFiniteKind::State, .. } if t == 0.0),
            "{:?}",
            sol.status
        );
    }

    #[test]
    fn max_steps_is_honoured() {
        let opts = Rk45Options {
            max_steps: 5,
            ..tol(1e-10)
        };
        let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
        assert_eq!(sol.n_accepted, 5);
        assert_eq!(sol.t.len(), 6);
        match sol.status {
            Status::MaxSteps { t, max_steps: 5 } => assert_eq!(t, sol.t[5]),
            ref s => panic!("unexpected {s:?}"),
        }
        assert!(
            sol.message.contains("maximum number of steps (5)"),
            "{}",
            sol.message
        );
    }

    #[test]
    fn blow_up_gives_step_too_small_like_scipy() {
        // y' = y², y(0) = 1: y = 1/(1-t), singular at t = 1. SciPy fails at
        // t = 0.9999286400563746 after 66 steps and 632 evaluations.
        let sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[0] * y[0];
            Ok(())
        });
        let sol = rk45(sys, (0.0, 2.0), &[1.0], &Rk45Options::default(), &mut []).unwrap();
        match sol.status {
            Status::StepTooSmall { t, min_step } => {
                assert!((t - 0.9999286400563746).abs() < 1e-12, "{t}");
                assert!(min_step > 0.0 && min_step < 1e-14);
            }
            ref s => panic!("unexpected {s:?}"),
        }
        assert_eq!((sol.nfev, sol.t.len()), (632, 67));
        assert!(
            sol.message.starts_with("step size fell below the minimum"),
            "{}",
            sol.message
        );
        assert!(sol.message.contains("at t = 0.99992"), "{}", sol.message);
    }

    #[test]
    fn rhs_error_is_propagated() {
        let sys = FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
            if t > 1.0 {
                return Err(format!("boom at {t}"));
            }
            dy[0] = -y[0];
            Ok(())
        });
        let sol = rk45(sys, (0.0, 3.0), &[1.0], &Rk45Options::default(), &mut []).unwrap();
        match &sol.status {
            Status::RhsError { t, at, message } => {
                assert!(*t <= 1.0 && *at > 1.0);
                assert!(message.starts_with("boom at"));
            }
            s => panic!("unexpected {s:?}"),
        }
        assert!(
            sol.message.contains("boom") && sol.message.contains("reached t = "),
            "{}",
            sol.message
        );
        // Failure in the very first evaluation: nothing beyond t0.
        let sys = FnSystem::new(1, |_t, _y: &[f64], _dy: &mut [f64]| Err("no".to_string()));
        let sol = rk45(
            sys,
            (0.0, 3.0),
            &[1.0],
            &Rk45Options {
                dense: true,
                ..Default::default()
            },
            &mut [],
        )
        .unwrap();
        assert!(matches!(sol.status, Status::RhsError { t, at, .. } if t == 0.0 && at == 0.0));
        assert_eq!((sol.t.len(), sol.nfev, sol.n_accepted), (1, 1, 0));
        assert!(sol.dense_eval(1.0).is_none());
    }

    #[test]
    fn bad_inputs_give_typed_errors() {
        let y0 = [0.0, 1.0, 1.0];
        let run = |span: (f64, f64), y0: &[f64], opts: Rk45Options| {
            rk45(krogh(), span, y0, &opts, &mut []).unwrap_err()
        };
        let ok = (0.0, 1.0);
        let e = run(ok, &[0.0, f64::NAN, 1.0], Rk45Options::default());
        assert!(
            matches!(e, InputError::Y0NonFinite { index: 1, value } if value.is_nan()),
            "{e:?}"
        );
        assert_eq!(e.argument(), "y0");
        assert_eq!(
            run(ok, &[0.0, 1.0], Rk45Options::default()),
            InputError::Y0Length {
                expected: 3,
                got: 2
            }
        );
        assert_eq!(
            run((1.0, 1.0), &y0, Rk45Options::default()),
            InputError::TSpanEmpty(1.0)
        );
        assert_eq!(
            run((0.0, f64::INFINITY), &y0, Rk45Options::default()).argument(),
            "t_span"
        );
        let e = run(
            ok,
            &y0,
            Rk45Options {
                rtol: (-1e-3).into(),
                ..Default::default()
            },
        );
        assert_eq!(
            e,
            InputError::TolInvalid {
                name: "rtol",
                index: 0,
                value: -1e-3
            }
        );
        let e = run(
            ok,
            &y0,
            Rk45Options {
                atol: vec![1e-6, -1.0, 1e-6].into(),
                ..Default::default()
            },
        );
        assert_eq!(
            e,
            InputError::TolInvalid {
                name: "atol",
                index: 1,
                value: -1.0
            }
        );
        let e = run(
            ok,
            &y0,
            Rk45Options {
                atol: vec![1e-6; 2].into(),
                ..Default::default()
            },
        );
        assert_eq!(
            e,
            InputError::TolLength {
                name: "atol",
                expected: 3,
                got: 2
            }
        );
        assert_eq!(e.argument(), "atol");
        let e = run(
            ok,
            &y0,
            Rk45Options {
                rtol: vec![1e-6; 4].into(),
                ..Default::default()
            },
        );
        assert_eq!(e.argument(), "rtol");
        assert_eq!(
            run(
                ok,
                &y0,
                Rk45Options {
                    max_step: 0.0,
                    ..Default::default()
                }
            ),
            InputError::MaxStep(0.0)
        );
        assert_eq!(
            run(
                ok,
                &y0,
                Rk45Options {
                    max_step: -1.0,
                    ..Default::default()
                }
            )
            .argument(),
            "max_step"
        );
        assert_eq!(
            run(
                ok,
                &y0,
                Rk45Options {
                    max_steps: 0,
                    ..Default::default()
                }
            ),
            InputError::MaxSteps
        );
        let e = run(
            ok,
            &y0,
            Rk45Options {
                first_step: Some(0.0),
                ..Default::default()
            },
        );
        assert_eq!(e, InputError::FirstStepNotPositive(0.0));
        let e = run(
            ok,
            &y0,
            Rk45Options {
                first_step: Some(2.0),
                ..Default::default()
            },
        );
        assert_eq!(
            e,
            InputError::FirstStepBeyondSpan {
                first_step: 2.0,
                span: 1.0
            }
        );
        assert!(e.to_string().starts_with("first_step:"), "{e}");
        let e = run(
            ok,
            &y0,
            Rk45Options {
                controller: Controller::PI {
                    alpha: -1.0,
                    beta: 0.0,
                },
                ..Default::default()
            },
        );
        assert_eq!(e.argument(), "controller");
        let e = run(
            ok,
            &y0,
            Rk45Options {
                t_eval: Some(vec![0.5, 1.5]),
                ..Default::default()
            },
        );
        assert!(
            matches!(e, InputError::TEvalOutsideSpan { index: 1, .. }),
            "{e:?}"
        );
        let e = run(
            ok,
            &y0,
            Rk45Options {
                t_eval: Some(vec![0.5, 0.5]),
                ..Default::default()
            },
        );
        assert!(
            matches!(
                e,
                InputError::TEvalNotSorted {
                    index: 1,
                    order: "increasing"
                }
            ),
            "{e:?}"
        );
        let e = run(
            (1.0, 0.0),
            &y0,
            Rk45Options {
                t_eval: Some(vec![0.2, 0.5]),
                ..Default::default()
            },
        );
        assert!(
            matches!(
                e,
                InputError::TEvalNotSorted {
                    order: "decreasing",
                    ..
                }
            ),
            "{e:?}"
        );
        assert!(e.to_string().starts_with("t_eval:"));
    }

    #[test]
    fn tiny_rtol_is_clamped_with_a_flag() {
        let sol = rk45(
            krogh(),
            (0.0, 1.0),
            &[0.0, 1.0, 1.0],
            &Rk45Options {
                rtol: 0.0.into(),
                ..Default::default()
            },
            &mut [],
        )
        .unwrap();
        assert!(sol.rtol_clamped && sol.success());
        let sol = rk45(
            krogh(),
            (0.0, 1.0),
            &[0.0, 1.0, 1.0],
            &Rk45Options::default(),
            &mut [],
        )
        .unwrap();
        assert!(!sol.rtol_clamped);
    }

    #[test]
    fn per_component_tolerances_equal_scalar_ones() {
        let a = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(1e-7), &mut []).unwrap();
        let opts = Rk45Options {
            rtol: vec![1e-7; 3].into(),
            atol: vec![1e-7; 3].into(),
            ..Default::default()
        };
        let b = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
        assert_eq!((&a.t, &a.y), (&b.t, &b.y));
        // A looser atol on one component must change the steps.
        let opts = Rk45Options {
            atol: vec![1e-7, 1e-7, 1e-2].into(),
            ..tol(1e-7)
        };
        let c = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
        assert_ne!(c.t, b.t);
    }

    #[test]
    fn boxed_dyn_system_and_mut_ref_work() {
        let mut sys = krogh();
        let a = rk45(
            &mut sys,
            (0.0, 1.0),
            &[0.0, 1.0, 1.0],
            &Rk45Options::default(),
            &mut [],
        )
        .unwrap();
        let boxed: Box<dyn OdeSystem> = Box::new(krogh());
        let b = rk45(
            boxed,
            (0.0, 1.0),
            &[0.0, 1.0, 1.0],
            &Rk45Options::default(),
            &mut [],
        )
        .unwrap();
        assert_eq!(a.y, b.y);
    }

    // ----------------------------------------------------------------------------------------
    // Stiffness detection
    // ----------------------------------------------------------------------------------------

    /// Prothero–Robinson: `y' = λ (y − cos t) − sin t`, exact `y = cos t` for `y(0) = 1`;
    /// stiff for large `|λ|` once the (absent) transient is gone.
    #[allow(clippy::type_complexity)]
    fn prothero_robinson(
        lambda: f64,
    ) -> FnSystem<impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), String>> {
        FnSystem::new(1, move |t, y: &[f64], dy: &mut [f64]| {
            dy[0] = lambda * (y[0] - t.cos()) - t.sin();
            Ok(())
        })
    }

    fn with_stiffness(opts: Rk45Options, stiffness: StiffnessCheck) -> Rk45Options {
        Rk45Options { stiffness, ..opts }
    }

    #[test]
    fn h_lambda_is_exact_on_a_linear_scalar_problem() {
        // y' = λ y: k7 − k6 = λ (y7 − y6) exactly, so the estimate is h·|λ| to round-off.
        let lambda = -37.0;
        let sys = FnSystem::new(1, move |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = lambda * y[0];
            Ok(())
        });
        let mut st = Stepper::new(sys, 0.0, &[1.0], 1.0, &tol(1e-6)).unwrap();
        assert!(st.h_lambda().is_nan());
        for _ in 0..5 {
            st.step().unwrap();
            let expected = st.step_size() * lambda.abs();
            assert!(
                (st.h_lambda() - expected).abs() <= 1e-9 * expected,
                "{} vs {expected}",
                st.h_lambda()
            );
        }
    }

    #[test]
    fn stiff_linear_problem_is_detected_early_and_steps_are_unchanged() {
        let lambda = -1e4;
        let opts = tol(1e-6);
        let run = |check| {
            rk45(
                prothero_robinson(lambda),
                (0.0, 10.0),
                &[1.0],
                &with_stiffness(opts.clone(), check),
                &mut [],
            )
            .unwrap()
        };
        let off = run(StiffnessCheck::Off);
        let warn = run(StiffnessCheck::Warn);
        // Observing changes nothing: same steps, same values (SciPy compatibility).
        assert_eq!((&off.t, &off.y, off.nfev), (&warn.t, &warn.y, warn.nfev));
        assert!(off.stiffness.is_none() && off.success());
        assert!(!off.message.contains("stiff"));
        // The explicit method needs ~|λ| T / 3.3 steps here: the cost stiffness causes.
        assert!(warn.n_accepted as f64 > 0.2 * lambda.abs() * 10.0 / 3.3);
        let s = warn.stiffness.expect("detected");
        assert!(warn.success() && warn.status == Status::Success);
        assert!(s.t < 0.05, "detected late, at t = {}", s.t);
        assert!(s.h_lambda > STIFF_H_LAMBDA);
        // |λ| estimated within a few per cent (the Jacobian is exactly λ).
        assert!(
            (s.lambda() / lambda.abs() - 1.0).abs() < 0.05,
            "{}",
            s.lambda()
        );
        assert!(
            warn.message.starts_with("reached the end")
                && warn
                    .message
                    .contains("warning: the problem looks stiff from t = "),
            "{}",
            warn.message
        );
        // Still accurate: stability-limited steps are tiny, the error is far below tolerance.
        let y_end = warn.y[warn.y.len() - 1];
        assert!((y_end - 10f64.cos()).abs() < 1e-6);

        // Stop: ends at the detection, with the status naming it.
        let stop = run(StiffnessCheck::Stop);
        match stop.status {
            Status::Stiff { t, h_lambda, h } => {
                assert_eq!(t, s.t);
                assert_eq!(h_lambda, s.h_lambda);
                assert!(h > 0.0 && (h_lambda / h - s.lambda()).abs() < 1e-9 * s.lambda());
            }
            ref other => panic!("unexpected {other:?}"),
        }
        assert_eq!(stop.status.code(), -1);
        assert!(!stop.success());
        assert_eq!(stop.t_reached, s.t);
        assert_eq!(*stop.t.last().unwrap(), s.t);
        // The steps up to the detection are the same as without the check.
        let n = stop.t.len();
        assert_eq!(&stop.t[..], &off.t[..n]);
        assert!(n < 200, "{n} steps before stopping");
        assert!(
            stop.message.starts_with("the problem is stiff at t = ")
                && stop.message.contains("implicit"),
            "{}",
            stop.message
        );
    }

    #[test]
    fn stiffness_and_max_steps_are_reported_together() {
        let opts = Rk45Options {
            max_steps: 500,
            ..tol(1e-6)
        };
        let sol = rk45(prothero_robinson(-1e5), (0.0, 10.0), &[1.0], &opts, &mut []).unwrap();
        assert!(matches!(
            sol.status,
            Status::MaxSteps { max_steps: 500, .. }
        ));
        assert_eq!(sol.n_accepted, 500);
        assert!(sol.stiffness.is_some());
        assert!(
            sol.message
                .starts_with("maximum number of steps (500) reached")
                && sol.message.contains("looks stiff"),
            "{}",
            sol.message
        );
    }

    #[test]
    fn stop_with_stepper_fails_on_the_call_after_the_detection() {
        let opts = with_stiffness(tol(1e-6), StiffnessCheck::Stop);
        let mut st = Stepper::new(prothero_robinson(-1e4), 0.0, &[1.0], 10.0, &opts).unwrap();
        let mut n = 0;
        let err = loop {
            match st.step() {
                Ok(StepOutcome::Accepted) => n += 1,
                Ok(StepOutcome::Finished) => panic!("should have stopped"),
                Err(e) => break e,
            }
            assert!(n < 10_000);
        };
        assert!(matches!(err, Status::Stiff { t, .. } if t == st.t()));
        assert_eq!(st.n_accepted(), n);
        assert_eq!(st.stiffness().unwrap().t, st.t());
        assert_eq!(st.step(), Err(err.clone()));
        assert_eq!(st.failure(), Some(&err));
    }

    #[test]
    fn non_stiff_problems_are_not_flagged() {
        for &(tl, ..) in SCIPY_KROGH.iter() {
            let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(tl), &mut []).unwrap();
            assert!(sol.stiffness.is_none(), "Krogh at {tl}");
        }
        // Loose tolerances give the largest h·|λ|.
        for tl in [1e-2, 1e-3, 1e-4] {
            let sol = rk45(krogh(), (0.0, 60.0), &[0.0, 1.0, 1.0], &tol(tl), &mut []).unwrap();
            assert!(sol.stiffness.is_none(), "Krogh at {tl}");
            let osc = FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
                dy[0] = 50.0 * y[1];
                dy[1] = -50.0 * y[0];
                Ok(())
            });
            let sol = rk45(osc, (0.0, 20.0), &[1.0, 0.0], &tol(tl), &mut []).unwrap();
            assert!(sol.stiffness.is_none(), "oscillator at {tl}");
        }
        // A stiff transient that the tolerance must resolve (h·|λ| small while it lasts) and
        // then dies: y' = -1e3 y from y = 1 over a span where it never decays to atol is not
        // stability-limited.
        let sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = -1e3 * y[0];
            Ok(())
        });
        let sol = rk45(sys, (0.0, 5e-3), &[1.0], &tol(1e-10), &mut []).unwrap();
        assert!(sol.stiffness.is_none());
    }

    #[test]
    fn stiff_joint_spring_scene_is_detected_through_simulate() {
        // A 1 kg, 0.3 m link on a revolute joint with a stiff spring and a strong damper:
        // eigenvalues ≈ −c/I and −k/c, i.e. a fast decaying mode the explicit method must keep
        // stable while the slow one sets the time scale.
        let text = r#"
name = "stiff spring"
[[body]]
name = "link"
joint = { type = "Revolute", axis = [0.0, 1.0, 0.0] }
mass = 1.0
com = [0.15, 0.0, 0.0]
inertia_diag = [1e-3, 7.5e-3, 7.5e-3]
q0 = [0.3]
[[effect]]
type = "gravity"
g = [0.0, 0.0, -9.81]
[[effect]]
type = "spring"
stiffness = 1e4
[[effect]]
type = "damper"
damping = 3e3
"#;
        let scene = crate::scene::Scene::from_toml(text, "stiff.toml").unwrap();
        let run = |check, max_steps| {
            let opts = Rk45Options {
                stiffness: check,
                max_steps,
                ..tol(1e-8)
            };
            crate::simulate::simulate(
                &scene.model,
                &scene.effects,
                crate::effects::Disabled::none(),
                &scene.q0,
                &scene.v0,
                (0.0, 2.0),
                &opts,
                &[],
                Vec::new(),
                crate::simulate::Record::default(),
                None,
            )
            .unwrap()
        };
        // I_O = 7.5e-3 + 1·0.15² = 0.03: fast eigenvalue ≈ −c / I_O = −1e5.
        let stop = run(StiffnessCheck::Stop, 1_000_000);
        match stop.status {
            Status::Stiff { t, h_lambda, h } => {
                assert!(t < 0.01, "{t}");
                let lambda = h_lambda / h;
                assert!((lambda / 1e5 - 1.0).abs() < 0.1, "|λ| ≈ {lambda}");
            }
            ref s => panic!("unexpected {s:?}"),
        }
        assert!(stop.n_accepted < 500 && !stop.success);
        // Warn with a step budget: stops at max_steps, and says why so many were needed.
        let warn = run(StiffnessCheck::Warn, 2000);
        assert!(matches!(warn.status, Status::MaxSteps { .. }));
        assert!(warn.message.contains("looks stiff"), "{}", warn.message);
        // Off: the same run without the remark.
        let off = run(StiffnessCheck::Off, 2000);
        assert_eq!(off.t, warn.t);
        assert!(!off.message.contains("stiff"), "{}", off.message);
    }

    #[test]
    fn stiffness_estimate_survives_huge_values_and_times_read_well() {
        // y' = λ y with |y| ~ 1e200: squared sums would overflow; the estimate must not.
        let lambda = -50.0;
        let sys = FnSystem::new(2, move |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = lambda * y[0];
            dy[1] = lambda * y[1];
            Ok(())
        });
        let opts = Rk45Options {
            first_step: Some(1e-3),
            ..tol(1e-6)
        };
        let mut st = Stepper::new(sys, 0.0, &[1e200, -3e199], 1.0, &opts).unwrap();
        st.step().unwrap();
        let expected = st.step_size() * lambda.abs();
        assert!(
            (st.h_lambda() - expected).abs() <= 1e-9 * expected,
            "{}",
            st.h_lambda()
        );
        assert_eq!(fmt_time(0.0), "0");
        assert_eq!(fmt_time(10.0), "10");
        assert_eq!(fmt_time(0.5), "0.5");
        assert_eq!(fmt_time(2.5e-73), "2.5e-73");
        assert_eq!(fmt_time(-3e20), "-3e20");
        let st = Status::MaxSteps {
            t: 1e-9,
            max_steps: 3,
        };
        assert_eq!(
            st.describe(1e-9),
            "maximum number of steps (3) reached at t = 1e-9"
        );
    }
}
