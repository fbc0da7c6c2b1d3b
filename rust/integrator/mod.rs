//! Integration methods behind one driver, SciPy's `solve_ivp` loop: adaptive Dormand–Prince
//! 5(4) (`RK45`) and 8(5,3) (`DOP853`) that reproduce SciPy step for step, fixed-step `RK4`
//! and semi-implicit `Euler`, and `auto` (RK45 or, at tight tolerances, DOP853, then Radau
//! once stiff). See docs/integrators.md.
//!
//! * `method.rs`     – the [`Integrator`] trait every method implements, [`Method`] names.
//! * `common.rs`     – what every method shares: [`StepState`], the solver life cycle, checks.
//! * `explicit_rk.rs` – the one explicit Runge–Kutta engine [`ExplicitRk`] over a [`Tableau`].
//! * `stepper.rs`    – the RK45 tableau ([`Rk45`]; [`Stepper`] = the engine with it).
//! * `dop853.rs`     – DOP853 ([`Dop853`]), its tableau in `dop853_tableau.rs`.
//! * `adams.rs`      – variable-order Adams PECE ([`Adams`], Shampine–Gordon's `STEP`), its
//!   coefficient recurrences in `adams_coef.rs`.
//! * `radau.rs`      – Radau IIA ([`Radau`]), its coefficients in `radau_tableau.rs`,
//!   finite-difference Jacobians in `num_jac.rs`.
//! * `fixed_step.rs` – the fixed-step methods ([`FixedStep`] with [`Rk4`] or [`Euler`]).
//! * `dense.rs`      – the interpolants ([`Interpolant`]) and the piecewise [`DenseOutput`].
//! * `events.rs`     – [`Event`] functions and SciPy's `brentq` root finder.
//! * `driver.rs`     – the generic driver ([`solve`], [`rk45`]): outputs, events, `auto`.
//! * this file       – the public types.
//!
//! Stiffness detection ([`StiffnessCheck`], Hairer's DOPRI5 test) only observes the accepted
//! steps: with `Off` or `Warn` the steps are exactly SciPy's; `Stop` ends the run early.
//!
//! Same problem + same options ⇒ same accept/reject decisions, step count and `nfev` as SciPy:
//! every formula is evaluated as SciPy writes it, with sums in plain stage order. NumPy sums
//! through OpenBLAS (FMA, CPU-dependent blocking) and the error estimate cancels ~7+ digits,
//! so step times can differ from SciPy's by up to ~1e-7 relative at tight tolerances (as
//! SciPy's own do between CPUs); values at fixed times (t_end, t_eval, events) agree to ~1e-14.

mod adams;
mod adams_coef;
mod common;
mod dense;
mod dop853;
mod dop853_tableau;
mod driver;
mod events;
mod explicit_rk;
mod fixed_step;
mod method;
mod num_jac;
mod radau;
mod radau_tableau;
mod resume;
mod spectral;
mod stepper;
mod vern9;
mod vern9_tableau;

pub use adams::Adams;
pub use common::{StepOutcome, StepState};
pub use dense::{eval_segment, DenseOutput, Interpolant};
pub use dop853::{Dop853, Dop853Tableau};
#[cfg(test)]
pub(crate) use driver::auto as driver_auto;
pub use driver::{rk45, solve, solve_with_jacobian, AUTO_ADAMS_RTOL, AUTO_DOP853_RTOL};
pub use events::{Event, EventDirection, EventFn};
pub use explicit_rk::{ExplicitRk, Tableau};
pub use fixed_step::{Euler, FixedStep, Rk4, Scheme, Work};
pub use method::{Counts, Integrator, Method};
pub use radau::{radau_solve, JacobianSource, Radau, NEWTON_MAXITER};
pub use resume::Resume;
pub use stepper::{Rk45, Stepper};
pub use vern9::{Vern9, Vern9Tableau};

use thiserror::Error;

/// Right-hand side `dy/dt = f(t, y)` of a first-order system.
pub trait OdeSystem {
    /// Number of state components.
    fn dim(&self) -> usize;
    /// Fill `dydt`; an `Err` stops the integration with that message
    /// (status [`Status::RhsError`]) and the time reached.
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String>;
    /// Called on each accepted state (re-normalising quaternions, closing kinematic loops);
    /// not on `y0`. Returns whether `y` moved so far that `f(t, y)` must be evaluated again
    /// (FSAL is kept only for `false`: quaternion normalisation, which the right-hand side
    /// ignores); `Err` stops the run with that message. Default: no-op.
    fn project(&mut self, _y: &mut [f64]) -> Result<bool, String> {
        Ok(false)
    }
    /// Analytic Jacobian `∂f/∂y` at `(t, y)`, row-major `dim × dim` into `jac`; returns
    /// `Ok(true)` when it filled it. Default: not provided (`Ok(false)`; implicit methods
    /// then use finite differences).
    fn jacobian(&mut self, _t: f64, _y: &[f64], _jac: &mut [f64]) -> Result<bool, String> {
        Ok(false)
    }
    /// `Some(nq)` when the state is `y = [q; v]` with `q̇` a function of `(q, v)` only and
    /// `v̇` the rest (a mechanical system): the semi-implicit Euler then updates `v` first
    /// and `q` with the new `v`. Default `None` (Euler is then explicit Euler).
    fn split(&self) -> Option<usize> {
        None
    }
    /// With [`OdeSystem::split`]: `q̇` at `y = [q; v]` into `qdot` (length `nq`), without
    /// the accelerations; returns `Ok(true)` when provided. Default `Ok(false)`: Euler then
    /// takes `q̇` from a full `rhs` call (counted in `nfev`).
    fn position_rate(&mut self, _y: &[f64], _qdot: &mut [f64]) -> Result<bool, String> {
        Ok(false)
    }
    /// Radau's error estimate `err` of a step from the accepted state `y`, reduced to the
    /// part the step keeps: a system whose [`OdeSystem::project`] moves each accepted state
    /// onto a manifold removes the estimate's components across it (the projection discards
    /// them). Returns whether `err` was changed. Default: no-op (plain ODEs: SciPy's estimate).
    fn filter_error(&mut self, _y: &[f64], _err: &mut [f64]) -> bool {
        false
    }
    /// Whether [`OdeSystem::filter_error`] may change an estimate (the explicit methods then
    /// form the estimate as displacements and filter them). Default `false`.
    fn filters_error(&self) -> bool {
        false
    }
    /// The Jacobian of the system as integrated when [`OdeSystem::rhs`] evaluates `f` at a
    /// projection `P(y)` of the state: `jac ← jac · P′(y)` for the `jac` = `∂f/∂y` that
    /// [`OdeSystem::jacobian`] filled (Radau's Newton matrices; finite differences see
    /// `f ∘ P` already). Returns whether `jac` was changed. Default: no-op.
    fn chain_projection(&mut self, _y: &[f64], _jac: &mut [f64]) -> bool {
        false
    }
}

/// A system behind a reference or a box is the system: every hook forwarded.
macro_rules! forward_ode_system {
    ($($ptr:ty),*) => {$(
        impl<S: OdeSystem + ?Sized> OdeSystem for $ptr {
            fn dim(&self) -> usize {
                (**self).dim()
            }
            fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
                (**self).rhs(t, y, dydt)
            }
            fn project(&mut self, y: &mut [f64]) -> Result<bool, String> {
                (**self).project(y)
            }
            fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, String> {
                (**self).jacobian(t, y, jac)
            }
            fn split(&self) -> Option<usize> {
                (**self).split()
            }
            fn position_rate(&mut self, y: &[f64], qdot: &mut [f64]) -> Result<bool, String> {
                (**self).position_rate(y, qdot)
            }
            fn filter_error(&mut self, y: &[f64], err: &mut [f64]) -> bool {
                (**self).filter_error(y, err)
            }
            fn filters_error(&self) -> bool {
                (**self).filters_error()
            }
            fn chain_projection(&mut self, y: &[f64], jac: &mut [f64]) -> bool {
                (**self).chain_projection(y, jac)
            }
        }
    )*};
}
forward_ode_system!(&mut S, Box<S>);

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
/// Dormand–Prince 5(4) stability region, ≈ 3.3; DOP853's 6.1) on [`STIFF_STEPS`] accepted steps (a run of
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

/// `h·|λ|` above which an RK45 step counts as stability-limited (Hairer's 3.25 in DOPRI5;
/// DOP853's is 6.1, [`Tableau::STIFF_H_LAMBDA`]).
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
            "warning: the problem looks stiff from t = {} (h·|λ| ≈ {:.2} on {STIFF_STEPS} \
             accepted steps, |λ| ≈ {:.3e}): the step size is limited by the stability of the \
             explicit method, not by the tolerance; an implicit solver (e.g. SciPy's Radau or \
             BDF) or softer stiff elements would need far fewer steps",
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

/// Integration options of every method. Defaults equal SciPy's
/// RK45 defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverOptions {
    /// The method [`solve`] uses (default RK45; [`rk45`] ignores it).
    pub method: Method,
    /// Fixed step of `RK4` and `Euler` (required by them, refused by the others). The last
    /// step is shortened to land on `t_end` exactly.
    pub dt: Option<f64>,
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
    /// until it falls below the minimum step (status `StepTooSmall`, or `NonFinite` when the
    /// last attempt was not finite).
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

impl Default for SolverOptions {
    fn default() -> Self {
        Self {
            method: Method::Rk45,
            dt: None,
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
    #[error(
        "atol: component {index} must be > 0 for method '{method}' (Radau's Newton iteration \
         measures its corrections by atol + rtol·|y|, which is 0 wherever a component is 0; \
         Hairer's RADAU5 refuses it alike), got {value}"
    )]
    AtolZeroImplicit {
        method: &'static str,
        index: usize,
        value: f64,
    },
    #[error(
        "atol: component {index} must be > 0 for method 'Adams' (its error weights \
         atol + rtol·|y| must stay positive when a component passes through 0), got {value}"
    )]
    AtolZeroAdams { index: usize, value: f64 },
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
    #[error(
        "method: expected one of 'RK45', 'DOP853', 'Vern9', 'Adams', 'Radau', 'RK4', 'Euler' or 'auto', got '{0}'"
    )]
    UnknownMethod(String),
    #[error("dt: method '{method}' takes a fixed step size dt > 0, got none")]
    DtMissing { method: &'static str },
    #[error("controller: method '{method}' has SciPy's controller only ('standard')")]
    ControllerUnsupported { method: &'static str },
    #[error("dt: must be positive and finite, got {0}")]
    DtInvalid(f64),
    #[error("dt: only the fixed-step methods 'RK4' and 'Euler' take dt; method '{method}' chooses its own steps (got dt = {dt}; use first_step/max_step instead)")]
    DtNotUsed { method: &'static str, dt: f64 },
    #[error(
        "jac: a constant Jacobian must have dim × dim = {expected} × {expected} entries, got {got}"
    )]
    JacobianShape { expected: usize, got: usize },
    #[error("jac: entry {index} (row-major) is not finite ({value})")]
    JacobianNonFinite { index: usize, value: f64 },
}

/// A setting refused (`InvalidSetting`), or an output too large to allocate.
impl From<InputError> for crate::support::error::Error {
    fn from(e: InputError) -> Self {
        match e {
            InputError::OutputTooLarge { bytes, .. } => Self::OutOfMemory {
                what: "the solution".into(),
                bytes,
                detail: e.to_string(),
            },
            e => Self::InvalidSetting(e.to_string()),
        }
    }
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
            InputError::AtolZeroImplicit { .. } | InputError::AtolZeroAdams { .. } => "atol",
            InputError::MaxStep(_) => "max_step",
            InputError::MaxSteps => "max_steps",
            InputError::FirstStepNotPositive(_) | InputError::FirstStepBeyondSpan { .. } => {
                "first_step"
            }
            InputError::Controller { .. } | InputError::ControllerUnsupported { .. } => {
                "controller"
            }
            InputError::TEvalOutsideSpan { .. }
            | InputError::TEvalNotSorted { .. }
            | InputError::OutputTooLarge { .. } => "t_eval",
            InputError::UnknownMethod(_) => "method",
            InputError::DtMissing { .. }
            | InputError::DtInvalid(_)
            | InputError::DtNotUsed { .. } => "dt",
            InputError::JacobianShape { .. } | InputError::JacobianNonFinite { .. } => "jac",
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
    /// An entry of the Jacobian `∂f/∂y` (the system's or a `jac` given).
    Jacobian,
}

impl NonFiniteKind {
    pub const ALL: [NonFiniteKind; 3] = [Self::Derivative, Self::State, Self::Jacobian];
    /// `"derivative"`, `"state"` or `"jacobian"`.
    /// The kind a caller names ("derivative", "state" or "jacobian").
    pub fn from_arg<A: crate::support::args::Arg>(x: &A) -> Result<Self, A::Err> {
        let choices = NonFiniteKind::ALL.map(|k| (k.name(), k));
        crate::support::args::choice(x, "what", &choices, "derivative, state or jacobian")
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Derivative => "derivative",
            Self::State => "state",
            Self::Jacobian => "jacobian",
        }
    }
}

/// The variants of [`Status`], listed once: `status_variants!(m)` calls the macro `m` with
/// them (and with the `extra` variants given, apart), so the core declares [`Status`] from this list
/// and a binding its typed mirror (rust/python/trajectory.rs) without repeating it.
macro_rules! status_variants {
    ($m:ident $(, $($extra:tt)*)?) => {
        $m! {[
            /// Reached `t_end`.
            Success,
            /// Event number `event` reached its terminal count at time `t`.
            TerminalEvent { event: usize, t: f64 },
            /// The required step fell below `min_step = 10 * ulp(t)` (SciPy's failure).
            StepTooSmall { t: f64, min_step: f64 },
            /// Radau's simplified Newton iteration failed at every step size down to `min_step`
            /// (`singular`: the last Newton matrix could not be factorised).
            NewtonFailed { t: f64, min_step: f64, singular: bool },
            /// `max_steps` accepted steps were taken before reaching `t_end`.
            MaxSteps { t: f64, max_steps: usize },
            /// A derivative or the state became NaN/inf.
            NonFinite { t: f64, at: f64, what: NonFiniteKind },
            /// The right-hand side returned `Err(message)`.
            RhsError { t: f64, at: f64, message: String },
            /// Event number `event` was NaN at `at` (a Python event that raised reports NaN); the
            /// step that reached `at` was discarded.
            EventNaN { t: f64, at: f64, event: usize },
            /// Stiffness was detected and [`StiffnessCheck::Stop`] asked to stop (see [`Stiffness`]).
            Stiff { t: f64, h_lambda: f64, h: f64 },
            /// The caller stopped the run from the evaluation at `at` (Ctrl-C, its progress callback,
            /// a stopped batch); `reason` says which when the caller has named it.
            Interrupted { t: f64, at: f64, reason: Option<String> },
            /// A run of a batch that never started: its input was refused, or the batch
            /// stopped first (`reason` says which).
            NotStarted { reason: String },
        ] [$($($extra)*)?]}
    };
}
#[allow(unused_imports)] // used by the binding only (the `python` feature)
pub(crate) use status_variants;

macro_rules! declare_status {
    ([$($(#[$doc:meta])* $v:ident $({ $($f:ident: $t:ty),* })?,)*] []) => {
        /// How an integration ended. In every variant `t` is the time reached (last accepted
        /// state, or the event time); `at` is the time of the offending evaluation.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Status {
            $($(#[$doc])* $v $({ $($f: $t),* })?,)*
        }
    };
}
status_variants!(declare_status);

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
            Status::NewtonFailed {
                t,
                min_step,
                singular,
            } => format!(
                "Radau's Newton iteration did not converge ({}) at any step size down to the \
                 minimum {min_step:.3e} at t = {}; the implicit stage equations have no nearby \
                 solution there (a singularity or a discontinuity of the right-hand side, or a \
                 Jacobian far from the true one)",
                if *singular {
                    "its matrix was singular"
                } else {
                    "the corrections did not contract"
                },
                f(*t)
            ),
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
                    NonFiniteKind::Jacobian => {
                        "the Jacobian returned a non-finite value (NaN or inf)"
                    }
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
            Status::Interrupted { t, at, reason } => format!(
                "interrupted at t = {} {}; integration reached t = {}",
                f(*at),
                match reason {
                    Some(r) => format!("by {r}"),
                    None => "(Ctrl-C, or the progress callback raised or the batch was stopped)"
                        .to_string(),
                },
                f(*t)
            ),
            Status::NotStarted { reason } => reason.clone(),
            Status::Stiff { t, h_lambda, h } => format!(
                "the problem is stiff at t = {}: on {STIFF_STEPS} accepted steps the step size \
                 was limited by the stability of the explicit method (h·|λ| ≈ {h_lambda:.2}, \
                 |λ| ≈ {:.3e}), not by the tolerance; use an implicit solver \
                 (e.g. SciPy's Radau or BDF) or soften the stiff elements",
                f(*t),
                h_lambda / h
            ),
        }
    }
}

/// Each event's states (`ys[k]`: rows of `width` entries), the columns `cols` of them, as
/// one matrix per event.
pub fn event_matrices(
    ys: &[Vec<f64>],
    width: usize,
    cols: std::ops::Range<usize>,
) -> Vec<nalgebra::DMatrix<f64>> {
    let matrix = |y: &Vec<f64>| {
        let rows = y.chunks_exact(width.max(1));
        let entries = rows.clone().flat_map(|r| r[cols.clone()].iter().copied());
        nalgebra::DMatrix::from_row_iterator(rows.len(), cols.len(), entries)
    };
    ys.iter().map(matrix).collect()
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
    /// Jacobian evaluations (0 for the explicit methods).
    pub njev: usize,
    /// LU decompositions (0 for the explicit methods).
    pub nlu: usize,
    pub n_accepted: usize,
    pub n_rejected: usize,
    pub status: Status,
    /// What happened and the time reached.
    pub message: String,
    /// Last time reached (t_end, the terminal event time, or where it stopped).
    pub t_reached: f64,
    /// Some rtol was below `100 * EPS` and raised to it (SciPy warns instead).
    pub rtol_clamped: bool,
    /// Piecewise interpolant when `SolverOptions::dense` is on.
    pub dense: Option<DenseOutput>,
    /// First stiffness detection (`None` if none, or if the check was off).
    pub stiffness: Option<Stiffness>,
    /// The method asked for.
    pub method: Method,
    /// `auto`: the method it switched to (Radau), if it did, and when.
    pub switched_to: Option<Method>,
    pub t_switch: Option<f64>,
}

impl Solution {
    /// SciPy's `success`: reached the end or a terminal event.
    pub fn success(&self) -> bool {
        self.status.is_success()
    }

    /// The states by component, SciPy's layout: row-major `dim × t.len()`.
    /// Each event's states as an m × dim matrix.
    pub fn event_matrices(&self) -> Vec<nalgebra::DMatrix<f64>> {
        event_matrices(&self.y_events, self.dim, 0..self.dim)
    }

    pub fn y_by_component(&self) -> Vec<f64> {
        let (dim, n) = (self.dim, self.t.len());
        (0..dim * n)
            .map(|k| self.y[(k % n) * dim + k / n])
            .collect()
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

#[cfg(test)]
mod tests;
