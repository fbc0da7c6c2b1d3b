//! The generic driver: SciPy's `solve_ivp` loop around any [`Integrator`]. Each accepted
//! step goes through the events ([`EventTracker`]) and into the output ([`Output`]); both
//! allocate their buffers once, before the first step. [`solve`] picks the method,
//! [`rk45`] is the RK45 entry of old.
use super::adams::Adams;
use super::dense::{DenseOutput, Interpolant};
use super::dop853::{Dop853, Dop853Tableau};
use super::events::{self, Event};
use super::explicit_rk::ExplicitRk;
use super::fixed_step::{Euler, FixedStep, Rk4};
use super::method::{Counts, Integrator, Method};
use super::radau::{JacobianSource, Radau};
use super::stepper::{Rk45, Stepper};
use super::vern9::Vern9;
use super::StepOutcome;
use super::{fmt_time, InputError, OdeSystem, Solution, SolverOptions, Status, StiffnessCheck};

/// Integrate `sys` over `t_span = (t0, t_end)` (backwards if `t_end < t0`) from `y0`,
/// exactly as SciPy's `solve_ivp(..., method="RK45")` (whatever `opts.method` says).
/// Runtime failures are reported in `Solution::status`; only invalid input gives `Err`.
pub fn rk45<S: OdeSystem>(
    sys: S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &SolverOptions,
    events: &mut [Event<'_>],
) -> Result<Solution, InputError> {
    let (t0, t_end) = t_span;
    let st = Stepper::new(sys, t0, y0, t_end, opts)?;
    drive(st, opts, events, Method::Rk45)
}

/// Integrate `sys` with the method `opts.method` (SciPy's `solve_ivp`): RK45 and DOP853 step
/// for step as SciPy's, RK4 and Euler at the fixed step `opts.dt`, `Auto` RK45 then Radau
/// once the problem is found stiff.
pub fn solve<S: OdeSystem>(
    sys: S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &SolverOptions,
    events: &mut [Event<'_>],
) -> Result<Solution, InputError> {
    let (t0, t_end) = t_span;
    if !opts.method.is_fixed_step() {
        if let Some(dt) = opts.dt {
            return Err(InputError::DtNotUsed {
                method: opts.method.name(),
                dt,
            });
        }
    }
    match opts.method {
        Method::Rk45 => rk45(sys, t_span, y0, opts, events),
        Method::Dop853 => drive(
            Dop853::new(sys, t0, y0, t_end, opts)?,
            opts,
            events,
            Method::Dop853,
        ),
        Method::Vern9 => drive(
            Vern9::new(sys, t0, y0, t_end, opts)?,
            opts,
            events,
            Method::Vern9,
        ),
        Method::Adams => drive(
            Adams::new(sys, t0, y0, t_end, opts)?,
            opts,
            events,
            Method::Adams,
        ),
        Method::Rk4 => drive(
            FixedStep::<_, Rk4>::new(sys, t0, y0, t_end, opts)?,
            opts,
            events,
            Method::Rk4,
        ),
        Method::Euler => drive(
            FixedStep::<_, Euler>::new(sys, t0, y0, t_end, opts)?,
            opts,
            events,
            Method::Euler,
        ),
        Method::Radau => drive(
            Radau::new(sys, t0, y0, t_end, opts)?,
            opts,
            events,
            Method::Radau,
        ),
        Method::Auto => auto(sys, t_span, y0, opts, events, stiff_target::<S>),
    }
}

/// [`solve`] with a Jacobian of the caller's (SciPy's `jac`): `None` takes the system's own
/// (or finite differences); a constant row-major `dim × dim` matrix is never re-evaluated
/// (Radau keeps it as [`JacobianSource::Constant`]; `auto` hands it to Radau at its switch).
pub fn solve_with_jacobian<S: OdeSystem>(
    sys: S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &SolverOptions,
    events: &mut [Event<'_>],
    constant: Option<Vec<f64>>,
) -> Result<Solution, InputError> {
    match constant {
        None => solve(sys, t_span, y0, opts, events),
        Some(m) if opts.method == Method::Radau => {
            super::radau_solve(sys, t_span, y0, opts, events, JacobianSource::Constant(m))
        }
        Some(m) => solve(ConstantJacobian { sys, m }, t_span, y0, opts, events),
    }
}

/// A system whose Jacobian is the constant `m`.
struct ConstantJacobian<S> {
    sys: S,
    m: Vec<f64>,
}

impl<S: OdeSystem> OdeSystem for ConstantJacobian<S> {
    fn dim(&self) -> usize {
        self.sys.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
        self.sys.rhs(t, y, dydt)
    }
    fn project(&mut self, y: &mut [f64]) -> Result<bool, String> {
        self.sys.project(y)
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut [f64]) -> Result<bool, String> {
        jac.copy_from_slice(&self.m);
        Ok(true)
    }
}

/// The implicit method `auto` continues with: Radau from `(t, y)` to `t_end`.
type StiffTarget<S, J> = fn(S, f64, &[f64], f64, &SolverOptions) -> Result<J, InputError>;

/// Radau from `(t, y)`, with SciPy's controller (a PI controller asked for is RK45's).
fn stiff_target<S: OdeSystem>(
    sys: S,
    t: f64,
    y: &[f64],
    t_end: f64,
    opts: &SolverOptions,
) -> Result<Radau<S>, InputError> {
    let opts = SolverOptions {
        controller: super::Controller::Standard,
        ..opts.clone()
    };
    Radau::new(sys, t, y, t_end, &opts)
}

/// `auto`: RK45 (at tight tolerances Adams, [`AUTO_ADAMS_RTOL`], or DOP853 for a system kept
/// on manifolds, [`AUTO_DOP853_RTOL`]) with its stiffness test stopping it; from the state
/// where it fired,
/// the rest of the interval with the method `target` builds (Radau), same events and output.
pub(crate) fn auto<S: OdeSystem, J: Integrator<System = S>>(
    sys: S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &SolverOptions,
    events: &mut [Event<'_>],
    target: StiffTarget<S, J>,
) -> Result<Solution, InputError> {
    // Refused up front, not at the switch: whether `auto` needs Radau is not known yet.
    let (_, atol, _) = super::common::tolerances(opts, sys.dim())?;
    super::radau::check_atol_positive(&atol, "auto")?;
    let (t0, t_end) = t_span;
    let first = SolverOptions {
        stiffness: StiffnessCheck::Stop,
        ..opts.clone()
    };
    match auto_first(opts, sys.filters_error()) {
        Method::Adams => {
            let st = Adams::new(sys, t0, y0, t_end, &first)?;
            auto_from(st, Method::Adams, t_span, opts, events, target)
        }
        Method::Dop853 => {
            let st = ExplicitRk::<S, Dop853Tableau>::new(sys, t0, y0, t_end, &first)?;
            auto_from(st, Method::Dop853, t_span, opts, events, target)
        }
        _ => {
            let st = ExplicitRk::<S, Rk45>::new(sys, t0, y0, t_end, &first)?;
            auto_from(st, Method::Rk45, t_span, opts, events, target)
        }
    }
}

/// Every `rtol` at or below which `auto` starts on DOP853 instead of RK45 for a system kept
/// on manifolds (loops; [`OdeSystem::filters_error`]): cheaper there on non-stiff problems,
/// and its stiffness test fires as early (measured, docs/integrators.md).
pub const AUTO_DOP853_RTOL: f64 = 1e-8;

/// Every `rtol` at or below which `auto` starts on Adams instead of RK45 (other systems):
/// 25–40 % fewer evaluations than DOP853 at equal error on chain7 and Krogh, and its
/// stiffness test stops it after 300–3600 evaluations where DOP853's fires late or never
/// (measured, docs/integrators.md). Systems kept on manifolds stay on DOP853, whose error
/// control knows their projection.
pub const AUTO_ADAMS_RTOL: f64 = 1e-8;

/// The explicit method `auto` starts on for these tolerances (`manifolds`: the system
/// filters its error estimates). A PI controller asked for rules Adams out (it has SciPy's
/// controller only; `auto` keeps the PI controller on its explicit part): DOP853 instead.
fn auto_first(opts: &SolverOptions, manifolds: bool) -> Method {
    let all_below = |limit: f64| match &opts.rtol {
        super::Tol::Scalar(r) => *r <= limit,
        super::Tol::PerComponent(v) => v.iter().all(|r| *r <= limit),
    };
    let standard = opts.controller == super::Controller::Standard;
    if all_below(AUTO_ADAMS_RTOL) && !manifolds && standard {
        Method::Adams
    } else if all_below(AUTO_DOP853_RTOL) {
        Method::Dop853
    } else {
        Method::Rk45
    }
}

/// `auto` from its first method `st` (`method`, run with `StiffnessCheck::Stop`).
fn auto_from<S: OdeSystem, I: Integrator<System = S>, J: Integrator<System = S>>(
    mut st: I,
    method: Method,
    (t0, t_end): (f64, f64),
    opts: &SolverOptions,
    events: &mut [Event<'_>],
    target: StiffTarget<S, J>,
) -> Result<Solution, InputError> {
    if let Some(te) = &opts.t_eval {
        validate_t_eval(te, t0, t_end)?;
    }
    let y0 = st.y().to_vec();
    let mut out = Output::new(opts, t0, &y0)?;
    let mut tracker = EventTracker::new(events, t0, &y0);
    let status = run(&mut st, events, &mut tracker, &mut out);
    let Status::Stiff { t: t_switch, .. } = status else {
        let info = RunInfo::of(&st, Method::Auto);
        return Ok(solution(info, status, out, tracker));
    };
    let mut info = RunInfo::of(&st, Method::Auto);
    let y = st.y().to_vec();
    let second = SolverOptions {
        first_step: None,
        ..opts.clone()
    };
    let mut st2 = target(st.into_system(), t_switch, &y, t_end, &second)?;
    let status = run(&mut st2, events, &mut tracker, &mut out);
    let info2 = RunInfo::of(&st2, Method::Radau);
    info.counts = info.counts + info2.counts;
    info.t = info2.t;
    info.rtol_clamped |= info2.rtol_clamped;
    info.switched = Some((method, Method::Radau, t_switch));
    Ok(solution(info, status, out, tracker))
}

/// Run `st` to the end with the driver's outputs and events.
pub(crate) fn drive<I: Integrator>(
    mut st: I,
    opts: &SolverOptions,
    events: &mut [Event<'_>],
    method: Method,
) -> Result<Solution, InputError> {
    let (t0, t_end) = (st.t(), st.t_bound());
    if let Some(te) = &opts.t_eval {
        validate_t_eval(te, t0, t_end)?;
    }
    let y0 = st.y().to_vec();
    let mut out = Output::new(opts, t0, &y0)?;
    let mut tracker = EventTracker::new(events, t0, &y0);
    let status = run(&mut st, events, &mut tracker, &mut out);
    Ok(solution(RunInfo::of(&st, method), status, out, tracker))
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

/// The most coefficients any interpolant has per component.
const MAX_COEF: usize = Interpolant::Adams.n_coef();

/// The step loop: steps until the end, a terminal event or a failure, which it returns.
/// The interpolant of a step is computed only when needed (dense output, an event's sign
/// change, a `t_eval` value within the step), as in SciPy (DOP853's costs 3 evaluations).
fn run<I: Integrator>(
    st: &mut I,
    events: &mut [Event<'_>],
    tracker: &mut EventTracker,
    out: &mut Output<'_>,
) -> Status {
    let dim = st.dim();
    // An event that is not a number at t0 cannot be watched: the run ends before a step.
    if let Some(s) = nan_event(&tracker.g, st.t(), st.t()) {
        return s;
    }
    let mut q = vec![0.0; MAX_COEF * dim]; // interpolant coefficients of the current step
    let mut y_term = vec![0.0; dim];
    loop {
        let outcome = match st.step() {
            Ok(o) => o,
            Err(s) => return s, // SciPy stores nothing from a failed step
        };
        let kind = st.interpolant();
        let q = &mut q[..kind.n_coef() * dim];
        let (t, dir) = (st.t(), st.direction());
        let mut have_q = false;
        if out.dense.is_some() {
            if let Err(s) = st.dense_coefficients(q) {
                return s;
            }
            have_q = true;
            if let Some(d) = out.dense.as_mut() {
                d.push(kind, st.t_old(), t - st.t_old(), st.y_old(), q);
            }
        }
        let active = match tracker.evaluate(events, st.t_old(), t, st.y()) {
            Ok(active) => active,
            Err(s) => {
                // Nothing of this step is kept (its state, output or dense segment).
                if let Some(d) = out.dense.as_mut() {
                    d.pop_segment();
                }
                return s;
            }
        };
        if !have_q && (active || out.wants_interpolant(t, dir)) {
            if let Err(s) = st.dense_coefficients(q) {
                return s;
            }
        }
        let seg = Segment {
            kind,
            t_old: st.t_old(),
            h: t - st.t_old(),
            y_old: st.y_old(),
            q,
        };
        let terminal = if active {
            tracker.roots(events, &seg, t, dir)
        } else {
            None
        };
        match terminal {
            Some((event, te)) => {
                seg.eval(te, &mut y_term);
                out.record(&seg, te, &y_term, dir);
                return Status::TerminalEvent { event, t: te };
            }
            None => out.record(&seg, t, st.y(), dir),
        }
        if outcome == StepOutcome::Finished {
            return Status::Success;
        }
    }
}

/// What a run's `Solution` takes from its integrator(s).
struct RunInfo {
    dim: usize,
    t: f64,
    counts: Counts,
    rtol_clamped: bool,
    stiffness: Option<super::Stiffness>,
    method: Method,
    /// `auto`: the method it switched from, to, and when.
    switched: Option<(Method, Method, f64)>,
}

impl RunInfo {
    fn of<I: Integrator>(st: &I, method: Method) -> Self {
        RunInfo {
            dim: st.dim(),
            t: st.t(),
            counts: st.counts(),
            rtol_clamped: st.rtol_clamped(),
            stiffness: st.stiffness(),
            method,
            switched: None,
        }
    }
}

/// The run's `Solution`: the outputs, events, counts and the message.
fn solution(info: RunInfo, status: Status, out: Output<'_>, tracker: EventTracker) -> Solution {
    let t_reached = match &status {
        Status::TerminalEvent { t, .. } | Status::EventNaN { t, .. } => *t,
        _ => info.t,
    };
    let stiffness = info.stiffness;
    let mut message = status.describe(t_reached);
    match info.switched {
        Some((from, to, t)) => {
            message.push_str(&format!(
                "; switched from {from} to {to} at t = {} (stiffness detected)",
                fmt_time(t)
            ));
        }
        None => {
            if let (Some(s), false) = (stiffness, matches!(status, Status::Stiff { .. })) {
                message.push_str("; ");
                message.push_str(&s.warning());
            }
        }
    }
    let c = info.counts;
    Solution {
        dim: info.dim,
        t: out.t,
        y: out.y,
        t_events: tracker.t_events,
        y_events: tracker.y_events,
        nfev: c.nfev,
        njev: c.njev,
        nlu: c.nlu,
        n_accepted: c.n_accepted,
        n_rejected: c.n_rejected,
        message,
        status,
        t_reached,
        rtol_clamped: info.rtol_clamped,
        dense: out.dense,
        stiffness,
        method: info.method,
        switched_to: info.switched.map(|s| s.1),
        t_switch: info.switched.map(|s| s.2),
    }
}

/// The accepted step from `t_old` over `h`: its start and interpolant.
struct Segment<'s> {
    kind: Interpolant,
    t_old: f64,
    h: f64,
    y_old: &'s [f64],
    q: &'s [f64],
}

impl Segment<'_> {
    /// The interpolant at `t` into `out`.
    #[inline]
    fn eval(&self, t: f64, out: &mut [f64]) {
        self.kind
            .eval(self.t_old, self.h, self.y_old, self.q, t, out);
    }
}

/// A run stops where an event is not a number, with the reason (a Python event that raised
/// reports NaN and keeps its exception for the caller).
fn nan_event(g: &[f64], t_old: f64, at: f64) -> Option<Status> {
    g.iter()
        .position(|x| x.is_nan())
        .map(|event| Status::EventNaN {
            t: t_old,
            at,
            event,
        })
}

/// The events' values at the last state, their occurrence counts and the roots found.
struct EventTracker {
    g: Vec<f64>,
    g_new: Vec<f64>,
    counts: Vec<usize>,
    roots: Vec<(usize, f64)>,
    t_events: Vec<Vec<f64>>,
    y_events: Vec<Vec<f64>>,
    /// The interpolant at a root.
    ybuf: Vec<f64>,
}

impl EventTracker {
    fn new(events: &mut [Event<'_>], t0: f64, y0: &[f64]) -> Self {
        let n = events.len();
        EventTracker {
            g: events.iter_mut().map(|e| (e.func)(t0, y0)).collect(),
            g_new: vec![0.0; n],
            counts: vec![0; n],
            roots: Vec::with_capacity(n),
            t_events: vec![Vec::new(); n],
            y_events: vec![Vec::new(); n],
            ybuf: vec![0.0; y0.len()],
        }
    }

    /// After the step from `t_old` to `(t, y)`: the events' new values, and whether some
    /// changed sign (then [`EventTracker::roots`] must follow). An event that is NaN at `t`
    /// is the run's end (`Err`).
    fn evaluate(
        &mut self,
        events: &mut [Event<'_>],
        t_old: f64,
        t: f64,
        y: &[f64],
    ) -> Result<bool, Status> {
        if events.is_empty() {
            return Ok(false);
        }
        for (e, gn) in events.iter_mut().zip(self.g_new.iter_mut()) {
            *gn = (e.func)(t, y);
        }
        if let Some(s) = nan_event(&self.g_new, t_old, t) {
            return Err(s);
        }
        let active = (0..events.len())
            .any(|i| events::is_active(self.g[i], self.g_new[i], events[i].direction));
        if !active {
            std::mem::swap(&mut self.g, &mut self.g_new);
        }
        Ok(active)
    }

    /// After [`EventTracker::evaluate`] found sign changes over the step `seg` ending at `t`:
    /// records the roots of the events in it, up to the first that terminates the run, and
    /// returns that one `(event, time)`.
    fn roots(
        &mut self,
        events: &mut [Event<'_>],
        seg: &Segment<'_>,
        t: f64,
        dir: f64,
    ) -> Option<(usize, f64)> {
        self.find_roots(events, seg, t);
        let terminal = self.keep_roots_to_terminal(events, dir);
        for &(i, te) in self.roots.iter() {
            seg.eval(te, &mut self.ybuf);
            self.t_events[i].push(te);
            self.y_events[i].extend_from_slice(&self.ybuf);
        }
        std::mem::swap(&mut self.g, &mut self.g_new);
        terminal.then(|| *self.roots.last().expect("non-empty"))
    }

    /// The events whose sign changed over the step (counted), each with its root.
    fn find_roots(&mut self, events: &mut [Event<'_>], seg: &Segment<'_>, t: f64) {
        self.roots.clear();
        for (i, e) in events.iter().enumerate() {
            if events::is_active(self.g[i], self.g_new[i], e.direction) {
                self.counts[i] += 1;
                self.roots.push((i, 0.0));
            }
        }
        let ybuf = &mut self.ybuf;
        for r in self.roots.iter_mut() {
            let ev = &mut events[r.0];
            r.1 = events::solve_event_equation(seg.t_old, t, |tt| {
                seg.eval(tt, ybuf);
                (ev.func)(tt, ybuf)
            });
        }
    }

    /// If a root terminates the run: the roots in time order up to (and including) the
    /// first that does, and true.
    fn keep_roots_to_terminal(&mut self, events: &[Event<'_>], dir: f64) -> bool {
        let counts = &self.counts;
        let terminates = |i: usize| events[i].terminal > 0 && counts[i] >= events[i].terminal;
        if !self.roots.iter().any(|&(i, _)| terminates(i)) {
            return false;
        }
        self.roots
            .sort_by(|a, b| (dir * a.1).total_cmp(&(dir * b.1)));
        let k = self
            .roots
            .iter()
            .position(|&(i, _)| terminates(i))
            .expect("a terminating root exists");
        self.roots.truncate(k + 1);
        true
    }
}

/// Samples an output of every step reserves before the first (bounded by [`RESERVE_BYTES`]).
const RESERVE_SAMPLES: usize = 64;
const RESERVE_BYTES: usize = 16 * 1024;

/// The output times and states (every step's, or the `t_eval` values') and the dense output.
struct Output<'o> {
    t_eval: Option<&'o [f64]>,
    /// The next `t_eval` value to output.
    next: usize,
    t: Vec<f64>,
    y: Vec<f64>,
    dense: Option<DenseOutput>,
    /// The interpolant at a `t_eval` value.
    ybuf: Vec<f64>,
}

impl<'o> Output<'o> {
    /// The output of a run from `(t0, y0)`: with `t_eval`, its whole size reserved now.
    fn new(opts: &'o SolverOptions, t0: f64, y0: &[f64]) -> Result<Self, InputError> {
        let dim = y0.len();
        let mut out = Output {
            t_eval: opts.t_eval.as_deref(),
            next: 0,
            t: Vec::new(),
            y: Vec::new(),
            dense: opts.dense.then(|| DenseOutput::new(dim, t0)),
            ybuf: vec![0.0; dim],
        };
        match out.t_eval {
            // The caller sized the output: refuse it now, clearly, rather than abort mid-run.
            Some(te) => {
                let too_large = || InputError::OutputTooLarge {
                    points: te.len(),
                    dim,
                    bytes: te.len() as u128 * (dim as u128 + 1) * 8,
                };
                let len = te.len().checked_mul(dim).ok_or_else(too_large)?;
                out.y.try_reserve_exact(len).map_err(|_| too_large())?;
                out.t.try_reserve_exact(te.len()).map_err(|_| too_large())?;
            }
            None => {
                // Room for the first steps at once rather than by doubling from one sample
                // (ten reallocations in a run of 24 steps); a few kB at most.
                let samples = (RESERVE_BYTES / (8 * (dim + 1))).clamp(1, RESERVE_SAMPLES);
                out.t.reserve_exact(samples);
                out.y.reserve_exact(samples * dim);
                out.t.push(t0);
                out.y.extend_from_slice(y0);
            }
        }
        Ok(out)
    }

    /// Whether recording a step ending at `t` evaluates the interpolant (a `t_eval` value
    /// up to `t`).
    #[inline]
    fn wants_interpolant(&self, t: f64, dir: f64) -> bool {
        match self.t_eval {
            None => false,
            Some(te) => self.next < te.len() && dir * (te[self.next] - t) <= 0.0,
        }
    }

    /// The step `seg`, ending at `(t, y)` (the step's end, or a terminal event's).
    #[inline]
    fn record(&mut self, seg: &Segment<'_>, t: f64, y: &[f64], dir: f64) {
        match self.t_eval {
            None => {
                // SciPy drops a zero-length last segment (terminal root exactly at t_old).
                let duplicate =
                    self.dense.is_some() && self.t.len() > 1 && *self.t.last().unwrap() == t;
                if duplicate {
                    self.dense.as_mut().unwrap().pop_segment();
                } else {
                    self.t.push(t);
                    self.y.extend_from_slice(y);
                    if let Some(d) = self.dense.as_mut() {
                        d.push_breakpoint(t);
                    }
                }
            }
            Some(te) => {
                // Every t_eval value up to and including t, from this step's interpolant.
                while self.next < te.len() && dir * (te[self.next] - t) <= 0.0 {
                    seg.eval(te[self.next], &mut self.ybuf);
                    self.t.push(te[self.next]);
                    self.y.extend_from_slice(&self.ybuf);
                    self.next += 1;
                }
                if let Some(d) = self.dense.as_mut() {
                    d.push_breakpoint(t);
                }
            }
        }
    }
}
