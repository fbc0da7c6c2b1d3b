//! What the generic driver needs of an integration method: the [`Integrator`] trait (one
//! accepted step at a time, the state and counts, the last step's interpolant) and the
//! [`Method`] names a caller chooses from.
use super::dense::Interpolant;
use super::{InputError, OdeSystem, Status, StepOutcome, Stiffness};

/// The evaluation counts of a run (SciPy's `nfev`, `njev`, `nlu`) and its steps.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Right-hand-side evaluations, as SciPy counts them (the evaluations of
    /// finite-difference Jacobians are not included).
    pub nfev: usize,
    /// Jacobian evaluations (analytic or by finite differences).
    pub njev: usize,
    /// LU decompositions.
    pub nlu: usize,
    pub n_accepted: usize,
    pub n_rejected: usize,
}

impl Counts {
    /// An explicit method's counts: no Jacobian, no LU.
    pub fn explicit(nfev: usize, n_accepted: usize, n_rejected: usize) -> Self {
        Counts {
            nfev,
            njev: 0,
            nlu: 0,
            n_accepted,
            n_rejected,
        }
    }
}

impl std::ops::Add for Counts {
    type Output = Counts;
    fn add(self, o: Counts) -> Counts {
        Counts {
            nfev: self.nfev + o.nfev,
            njev: self.njev + o.njev,
            nlu: self.nlu + o.nlu,
            n_accepted: self.n_accepted + o.n_accepted,
            n_rejected: self.n_rejected + o.n_rejected,
        }
    }
}

/// A one-step method the generic driver (`driver::run`) drives: SciPy's `OdeSolver` protocol.
///
/// `step` takes one accepted step (retrying internally as the method's step control decides)
/// and allocates nothing; after a failure every call returns the same `Err`. Before the first
/// step `t() == t_old()` and `y() == y_old()` hold the initial state.
pub trait Integrator {
    type System: OdeSystem;
    /// One accepted step; `Finished` when it reached `t_bound`.
    fn step(&mut self) -> Result<StepOutcome, Status>;
    fn dim(&self) -> usize;
    /// Current time (end of the last accepted step).
    fn t(&self) -> f64;
    /// Start of the last accepted step.
    fn t_old(&self) -> f64;
    /// End of the interval.
    fn t_bound(&self) -> f64;
    /// +1 forward, -1 backward.
    fn direction(&self) -> f64;
    /// State at `t()`.
    fn y(&self) -> &[f64];
    /// State at `t_old()`.
    fn y_old(&self) -> &[f64];
    fn counts(&self) -> Counts;
    /// First stiffness detection (methods that test for it).
    fn stiffness(&self) -> Option<Stiffness> {
        None
    }
    /// Some rtol was raised to the method's floor.
    fn rtol_clamped(&self) -> bool {
        false
    }
    /// Size of the next step the method would try (for a continuation by another method).
    fn h_next(&self) -> f64;
    /// The kind of the last step's interpolant (`kind.n_coef() · dim` coefficients).
    fn interpolant(&self) -> Interpolant;
    /// The last accepted step's interpolant coefficients into `q`
    /// (`interpolant().n_coef() · dim`, component `i`'s at `q[n_coef·i ..]`; see
    /// [`Interpolant`]). May evaluate the right-hand side (DOP853's three extra stages, counted
    /// in `nfev` as SciPy counts them), hence `&mut` and a failure `Status`. Called at most once
    /// per step, and only when the driver needs it (dense output, an event's sign change, a
    /// `t_eval` value in the step), as SciPy's `solve_ivp` does.
    fn dense_coefficients(&mut self, q: &mut [f64]) -> Result<(), Status>;
    fn system_mut(&mut self) -> &mut Self::System;
    fn into_system(self) -> Self::System
    where
        Self: Sized;
}

/// The integration method of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Method {
    /// Dormand–Prince 5(4), SciPy's `RK45` step for step (default).
    #[default]
    Rk45,
    /// Dormand–Prince 8(5,3), SciPy's `DOP853` step for step.
    Dop853,
    /// Verner's 9(8) pair (not SciPy's), for tight tolerances on smooth non-stiff problems.
    Vern9,
    /// Variable-order (1–11), variable-step Adams–Bashforth–Moulton PECE (Shampine–Gordon),
    /// two evaluations per step, for smooth non-stiff problems at tight tolerances.
    Adams,
    /// Radau IIA order 5 (implicit), SciPy's `Radau`.
    Radau,
    /// Classical Runge–Kutta 4 at a fixed step `dt`.
    Rk4,
    /// Semi-implicit (symplectic) Euler at a fixed step `dt` (explicit Euler for a system
    /// without a `[q; v]` split; see [`OdeSystem::split`]).
    Euler,
    /// RK45 (DOP853 when every rtol ≤ [`super::AUTO_DOP853_RTOL`]) until Hairer's stiffness test
    /// fires, then Radau from that state.
    Auto,
}

impl Method {
    /// Every accepted name (case-insensitive), for messages.
    pub const NAMES: &'static str =
        "'RK45', 'DOP853', 'Vern9', 'Adams', 'Radau', 'RK4', 'Euler' or 'auto'";

    /// SciPy's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Method::Rk45 => "RK45",
            Method::Dop853 => "DOP853",
            Method::Vern9 => "Vern9",
            Method::Adams => "Adams",
            Method::Radau => "Radau",
            Method::Rk4 => "RK4",
            Method::Euler => "Euler",
            Method::Auto => "auto",
        }
    }

    /// A method by name (case-insensitive); `None` for an unknown name.
    pub fn parse(name: &str) -> Option<Method> {
        [
            Method::Rk45,
            Method::Dop853,
            Method::Vern9,
            Method::Adams,
            Method::Radau,
            Method::Rk4,
            Method::Euler,
            Method::Auto,
        ]
        .into_iter()
        .find(|m| m.name().eq_ignore_ascii_case(name))
    }

    /// Fixed-step methods (they need `dt`, have no error control).
    pub fn is_fixed_step(self) -> bool {
        matches!(self, Method::Rk4 | Method::Euler)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = InputError;
    fn from_str(s: &str) -> Result<Self, InputError> {
        Method::parse(s).ok_or_else(|| InputError::UnknownMethod(s.to_string()))
    }
}
