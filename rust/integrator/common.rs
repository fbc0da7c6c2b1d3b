//! What every one-step method shares (SciPy's `OdeSolver` and `_ivp/common.py`): the step
//! state ([`StepState`]: time, state, interval, counts, tolerances and step limits), the one
//! life cycle of a solver object ([`Stepping`]: initialise on the first step, then step
//! until finished or failed, a failure repeated by every later call), the input checks, the
//! checked right-hand-side call, and SciPy's `select_initial_step`.

use super::{Controller, InputError, NonFiniteKind, OdeSystem, SolverOptions, Status, Tol};

/// Result of an accepted step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepOutcome {
    /// Step accepted, `t_bound` not reached yet.
    Accepted,
    /// Step accepted and `t_bound` reached (further calls do nothing and return this again).
    Finished,
}

/// Where a solver object is in its run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Lifecycle {
    Uninitialised,
    Running,
    Finished,
    Failed(Status),
}

/// The state every adaptive method carries and the accessors over it: the solvers
/// dereference to it (`stepper.t()`, `radau.nfev()`), and [`super::Integrator`]'s accessors read it.
/// Fields are the solvers' to update; the accessors are read-only.
#[derive(Debug, Clone)]
pub struct StepState {
    pub(crate) dim: usize,
    pub(crate) t: f64,
    pub(crate) t_old: f64,
    pub(crate) t_bound: f64,
    pub(crate) direction: f64,
    pub(crate) y: Vec<f64>,
    pub(crate) y_old: Vec<f64>,
    /// `f(t, y)` (valid once initialised).
    pub(crate) f: Vec<f64>,
    /// The attempted step's end state (workspace).
    pub(crate) y_new: Vec<f64>,
    pub(crate) rtol: Vec<f64>,
    pub(crate) atol: Vec<f64>,
    pub(crate) rtol_clamped: bool,
    pub(crate) max_step: f64,
    pub(crate) first_step: Option<f64>,
    pub(crate) max_steps: usize,
    /// Size of the next step to try.
    pub(crate) h_abs: f64,
    pub(crate) nfev: usize,
    pub(crate) n_accepted: usize,
    pub(crate) n_rejected: usize,
    pub(crate) lifecycle: Lifecycle,
}

impl StepState {
    /// The state at `t0` of a run to `t_bound` with tolerances already checked.
    pub(crate) fn new(
        t0: f64,
        y0: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
        (rtol, atol, rtol_clamped): (Vec<f64>, Vec<f64>, bool),
    ) -> Self {
        let dim = y0.len();
        Self {
            dim,
            t: t0,
            t_old: t0,
            t_bound,
            direction: if t_bound > t0 { 1.0 } else { -1.0 },
            y: y0.to_vec(),
            y_old: y0.to_vec(),
            f: vec![0.0; dim],
            y_new: vec![0.0; dim],
            rtol,
            atol,
            rtol_clamped,
            max_step: opts.max_step,
            first_step: opts.first_step,
            max_steps: opts.max_steps,
            h_abs: 0.0,
            nfev: 0,
            n_accepted: 0,
            n_rejected: 0,
            lifecycle: Lifecycle::Uninitialised,
        }
    }

    /// SciPy's checks at the start of `_step_impl`: `MaxSteps`, then the step to try clipped
    /// to `[min_step, max_step]`. Returns `(h_abs, min_step, clipped)`.
    #[inline]
    pub(crate) fn step_bounds(&self) -> Result<(f64, f64, bool), Status> {
        let t = self.t;
        if self.n_accepted >= self.max_steps {
            return Err(Status::MaxSteps {
                t,
                max_steps: self.max_steps,
            });
        }
        let min_step = 10.0 * (next_toward(t, self.direction) - t).abs();
        Ok(if self.h_abs > self.max_step {
            (self.max_step, min_step, true)
        } else if self.h_abs < min_step {
            (min_step, min_step, true)
        } else {
            (self.h_abs, min_step, false)
        })
    }

    /// The end of an attempt of size `h_abs` from `t`, clipped to `t_bound`, and the step
    /// actually taken (SciPy recomputes it even when not clipped).
    #[inline]
    pub(crate) fn attempt(&self, h_abs: f64) -> (f64, f64) {
        let (t, dir) = (self.t, self.direction);
        let mut t_new = t + h_abs * dir;
        if dir * (t_new - self.t_bound) > 0.0 {
            t_new = self.t_bound;
        }
        (t_new, t_new - t)
    }

    /// Whether `t` reached `t_bound`.
    #[inline]
    pub(crate) fn outcome(&self) -> StepOutcome {
        if self.direction * (self.t - self.t_bound) >= 0.0 {
            StepOutcome::Finished
        } else {
            StepOutcome::Accepted
        }
    }

    /// `f(t, y)` at the current state into `f`.
    pub(crate) fn rhs_here<S: OdeSystem>(&mut self, sys: &mut S) -> Result<(), Status> {
        let t = self.t;
        call_rhs(sys, &mut self.nfev, t, t, &self.y, &mut self.f)
    }

    /// SciPy `select_initial_step` from `(t, y, f)` for an error estimator of order `order`,
    /// with three workspaces of `dim` (scale, y1, f1).
    pub(crate) fn initial_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        order: u32,
        scratch: (&mut [f64], &mut [f64], &mut [f64]),
    ) -> Result<f64, Status> {
        let start = Start {
            t0: self.t,
            y0: &self.y,
            f0: &self.f,
            t_bound: self.t_bound,
            direction: self.direction,
        };
        let tols = (&self.atol[..], &self.rtol[..]);
        select_initial_step(
            sys,
            &mut self.nfev,
            start,
            tols,
            self.max_step,
            order,
            scratch,
        )
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t
    }
    /// Start of the last accepted step (t0 before any step).
    pub fn t_old(&self) -> f64 {
        self.t_old
    }
    pub fn t_bound(&self) -> f64 {
        self.t_bound
    }
    /// +1 forward, -1 backward.
    pub fn direction(&self) -> f64 {
        self.direction
    }
    /// Current state.
    pub fn y(&self) -> &[f64] {
        &self.y
    }
    /// State at `t_old()`.
    pub fn y_old(&self) -> &[f64] {
        &self.y_old
    }
    /// `f(t, y)` (valid once initialised).
    pub fn f(&self) -> &[f64] {
        &self.f
    }
    pub fn dim(&self) -> usize {
        self.dim
    }
    /// Size of the next step to try.
    pub fn h_next(&self) -> f64 {
        self.h_abs
    }
    /// |t - t_old|, the last accepted step size.
    pub fn step_size(&self) -> f64 {
        (self.t - self.t_old).abs()
    }
    /// Right-hand-side calls, counted as SciPy does.
    pub fn nfev(&self) -> usize {
        self.nfev
    }
    pub fn n_accepted(&self) -> usize {
        self.n_accepted
    }
    /// Attempts rejected by the error test.
    pub fn n_rejected(&self) -> usize {
        self.n_rejected
    }
    /// Some rtol was below `100 EPS` and raised to it.
    pub fn rtol_clamped(&self) -> bool {
        self.rtol_clamped
    }
    pub fn is_finished(&self) -> bool {
        self.lifecycle == Lifecycle::Finished
    }
    /// The failure status, if the solver failed.
    pub fn failure(&self) -> Option<&Status> {
        match &self.lifecycle {
            Lifecycle::Failed(s) => Some(s),
            _ => None,
        }
    }
}

/// The life cycle of a solver object, written once: a method gives its first evaluations
/// ([`Stepping::start`]) and one accepted step ([`Stepping::advance`]); [`initialize`] and
/// [`step`] run them in order and make every failure final.
pub(crate) trait Stepping {
    fn lifecycle(&mut self) -> &mut Lifecycle;
    /// `f(t0, y0)`, the first step size, whatever else the method needs before stepping.
    fn start(&mut self) -> Result<(), Status>;
    /// One accepted step (SciPy `_step_impl`).
    fn advance(&mut self) -> Result<StepOutcome, Status>;
    /// A failure decided on the previous step, returned by the next (stiffness `Stop`).
    fn take_pending(&mut self) -> Option<Status> {
        None
    }
}

/// Runs [`Stepping::start`] once; a failure is final.
pub(crate) fn initialize<X: Stepping>(x: &mut X) -> Result<(), Status> {
    match x.lifecycle() {
        Lifecycle::Uninitialised => {}
        Lifecycle::Failed(s) => return Err(s.clone()),
        _ => return Ok(()),
    }
    let r = x.start();
    *x.lifecycle() = match &r {
        Ok(()) => Lifecycle::Running,
        Err(s) => Lifecycle::Failed(s.clone()),
    };
    r
}

/// One accepted step, initialising first if need be; after `Finished` every call returns it
/// again, after a failure the same failure.
#[inline]
pub(crate) fn step<X: Stepping>(x: &mut X) -> Result<StepOutcome, Status> {
    match x.lifecycle() {
        Lifecycle::Uninitialised => initialize(x)?,
        Lifecycle::Running => {
            if let Some(s) = x.take_pending() {
                *x.lifecycle() = Lifecycle::Failed(s.clone());
                return Err(s);
            }
        }
        Lifecycle::Finished => return Ok(StepOutcome::Finished),
        Lifecycle::Failed(s) => return Err(s.clone()),
    }
    let r = x.advance();
    match &r {
        Ok(StepOutcome::Finished) => *x.lifecycle() = Lifecycle::Finished,
        Ok(StepOutcome::Accepted) => {}
        Err(s) => *x.lifecycle() = Lifecycle::Failed(s.clone()),
    }
    r
}

/// A failure outside `step` (e.g. in dense output) is final too.
pub(crate) fn record<T>(lifecycle: &mut Lifecycle, r: Result<T, Status>) -> Result<T, Status> {
    if let Err(s) = &r {
        *lifecycle = Lifecycle::Failed(s.clone());
    }
    r
}

/// The accessors of [`super::Integrator`] every adaptive method shares, from its [`StepState`]
/// (a field `st`).
macro_rules! step_state_accessors {
    () => {
        fn dim(&self) -> usize {
            self.st.dim
        }
        fn t(&self) -> f64 {
            self.st.t
        }
        fn t_old(&self) -> f64 {
            self.st.t_old
        }
        fn t_bound(&self) -> f64 {
            self.st.t_bound
        }
        fn direction(&self) -> f64 {
            self.st.direction
        }
        fn y(&self) -> &[f64] {
            &self.st.y
        }
        fn y_old(&self) -> &[f64] {
            &self.st.y_old
        }
        fn rtol_clamped(&self) -> bool {
            self.st.rtol_clamped
        }
        fn h_next(&self) -> f64 {
            self.st.h_abs
        }
    };
}
pub(crate) use step_state_accessors;

pub(crate) fn expand_tol(
    tol: &Tol,
    name: &'static str,
    dim: usize,
) -> Result<Vec<f64>, InputError> {
    let v = match tol {
        Tol::Scalar(x) => vec![*x; dim],
        Tol::PerComponent(v) if v.len() == dim => v.clone(),
        Tol::PerComponent(v) => {
            return Err(InputError::TolLength {
                name,
                expected: dim,
                got: v.len(),
            })
        }
    };
    if let Some((index, &value)) = v
        .iter()
        .enumerate()
        .find(|(_, x)| !(x.is_finite() && **x >= 0.0))
    {
        return Err(InputError::TolInvalid { name, index, value });
    }
    Ok(v)
}

/// RMS norm, as `np.linalg.norm(x) / x.size ** 0.5`.
pub(crate) fn rms_norm(it: impl Iterator<Item = f64>, n: usize) -> f64 {
    let sq: f64 = it.map(|v| v * v).sum();
    sq.sqrt() / (n as f64).sqrt()
}

/// `np.nextafter(x, dir * inf)` for finite `x`.
pub(crate) fn next_toward(x: f64, dir: f64) -> f64 {
    if x == 0.0 {
        let tiny = f64::from_bits(1);
        return if dir > 0.0 { tiny } else { -tiny };
    }
    let bits = x.to_bits();
    // Moving away from zero increases the magnitude bits.
    if (x > 0.0) == (dir > 0.0) {
        f64::from_bits(bits + 1)
    } else {
        f64::from_bits(bits - 1)
    }
}

/// One rhs evaluation with the NonFinite / RhsError checks.
pub(crate) fn call_rhs<S: OdeSystem>(
    sys: &mut S,
    nfev: &mut usize,
    t_reached: f64,
    t: f64,
    y: &[f64],
    out: &mut [f64],
) -> Result<(), Status> {
    *nfev += 1;
    sys.rhs(t, y, out).map_err(|message| Status::RhsError {
        t: t_reached,
        at: t,
        message,
    })?;
    if all_finite(out) {
        Ok(())
    } else {
        Err(Status::NonFinite {
            t: t_reached,
            at: t,
            what: NonFiniteKind::Derivative,
        })
    }
}

/// Whether every entry is finite. This runs twice per evaluation on values that almost
/// always are: `v − v` is +0 (no bit set) for a finite `v` and NaN for ±inf or NaN, and the
/// bits' OR, unlike a sum of floats, may be taken in any order, so it vectorises.
#[inline]
#[allow(clippy::eq_op)] // `v - v` is the test, not a slip
pub(crate) fn all_finite(y: &[f64]) -> bool {
    y.iter().fold(0u64, |b, v| b | (v - v).to_bits()) == 0
}

pub(crate) fn check_state(y: &[f64], t_reached: f64, at: f64) -> Result<(), Status> {
    if all_finite(y) {
        Ok(())
    } else {
        Err(Status::NonFinite {
            t: t_reached,
            at,
            what: NonFiniteKind::State,
        })
    }
}

/// The start of a run: `f0 = f(t0, y0)`.
pub(crate) struct Start<'a> {
    pub t0: f64,
    pub y0: &'a [f64],
    pub f0: &'a [f64],
    pub t_bound: f64,
    pub direction: f64,
}

/// SciPy `select_initial_step` (Hairer, Nørsett & Wanner, Sec. II.4) for an error estimator
/// of order `order`; `scratch` = three buffers of `dim` (scale, y1, f1). One rhs call.
pub(crate) fn select_initial_step<S: OdeSystem>(
    sys: &mut S,
    nfev: &mut usize,
    st: Start<'_>,
    (atol, rtol): (&[f64], &[f64]),
    max_step: f64,
    order: u32,
    scratch: (&mut [f64], &mut [f64], &mut [f64]),
) -> Result<f64, Status> {
    let (scale, y1, f1) = scratch;
    let (t0, dir, y0, f0) = (st.t0, st.direction, st.y0, st.f0);
    let n = y0.len();
    let interval_length = (st.t_bound - t0).abs();
    for i in 0..n {
        scale[i] = atol[i] + y0[i].abs() * rtol[i];
    }
    let d0 = rms_norm((0..n).map(|i| y0[i] / scale[i]), n);
    let d1 = rms_norm((0..n).map(|i| f0[i] / scale[i]), n);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(interval_length);
    let hd = h0 * dir;
    for i in 0..n {
        y1[i] = y0[i] + hd * f0[i];
    }
    // A non-finite `f1` is no failure (SciPy's neither): it makes `d2` inf (`h1 = 0`, the
    // first step the minimum one) or NaN (ignored by Python's `max(d1, d2)`).
    let at = t0 + h0 * dir;
    *nfev += 1;
    sys.rhs(at, y1, f1)
        .map_err(|message| Status::RhsError { t: t0, at, message })?;
    let d2 = rms_norm((0..n).map(|i| (f1[i] - f0[i]) / scale[i]), n) / h0;
    let h1 = if d1 <= 1e-15 && d2 <= 1e-15 {
        (1e-6f64).max(h0 * 1e-3)
    } else {
        (0.01 / if d2 > d1 { d2 } else { d1 }).powf(1.0 / (order + 1) as f64)
    };
    Ok((100.0 * h0).min(h1).min(interval_length).min(max_step))
}

/// The initial state and the interval: `dim` finite components, two different finite times.
pub(crate) fn check_start(dim: usize, y0: &[f64], t0: f64, t_bound: f64) -> Result<(), InputError> {
    if dim == 0 {
        return Err(InputError::EmptyState);
    }
    if y0.len() != dim {
        return Err(InputError::Y0Length {
            expected: dim,
            got: y0.len(),
        });
    }
    if let Some((index, &value)) = y0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(InputError::Y0NonFinite { index, value });
    }
    if !(t0.is_finite() && t_bound.is_finite()) {
        return Err(InputError::TSpanNonFinite { t0, t_end: t_bound });
    }
    if t0 == t_bound {
        return Err(InputError::TSpanEmpty(t0));
    }
    Ok(())
}

/// `rtol` and `atol` per component, and whether some rtol was raised to `100 EPS`.
pub(crate) fn tolerances(
    opts: &SolverOptions,
    dim: usize,
) -> Result<(Vec<f64>, Vec<f64>, bool), InputError> {
    let mut rtol = expand_tol(&opts.rtol, "rtol", dim)?;
    let atol = expand_tol(&opts.atol, "atol", dim)?;
    // SciPy: rtol = max(rtol, 100 EPS) with a warning; we set a flag instead.
    let rtol_min = 100.0 * f64::EPSILON;
    let rtol_clamped = rtol.iter().any(|&r| r < rtol_min);
    if rtol_clamped {
        rtol.iter_mut().for_each(|r| *r = r.max(rtol_min));
    }
    Ok((rtol, atol, rtol_clamped))
}

/// `max_step`, `max_steps`, `first_step` (within the interval's length `span`) and the
/// controller's parameters.
pub(crate) fn check_step_options(opts: &SolverOptions, span: f64) -> Result<(), InputError> {
    if opts.max_step.is_nan() || opts.max_step <= 0.0 {
        return Err(InputError::MaxStep(opts.max_step));
    }
    if opts.max_steps == 0 {
        return Err(InputError::MaxSteps);
    }
    if let Some(h) = opts.first_step {
        if !(h > 0.0 && h.is_finite()) {
            return Err(InputError::FirstStepNotPositive(h));
        }
        if h > span {
            return Err(InputError::FirstStepBeyondSpan {
                first_step: h,
                span,
            });
        }
    }
    if let Controller::PI { alpha, beta } = opts.controller {
        if !(alpha.is_finite() && beta.is_finite() && alpha > 0.0 && beta >= 0.0) {
            return Err(InputError::Controller { alpha, beta });
        }
    }
    Ok(())
}
