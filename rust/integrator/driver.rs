//! The [`rk45`] driver: SciPy's `solve_ivp` loop around the [`Stepper`]. Each accepted step
//! goes through the events ([`EventTracker`]) and into the output ([`Output`]); both
//! allocate their buffers once, before the first step.
use super::dense::{eval_segment, DenseOutput};
use super::events::{self, Event};
use super::stepper::{StepOutcome, Stepper};
use super::{InputError, OdeSystem, Rk45Options, Solution, Status};

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
    let mut out = Output::new(opts, t0, y0)?;
    let mut tracker = EventTracker::new(events, t0, y0);
    let status = run(&mut st, events, &mut tracker, &mut out);
    Ok(solution(st, status, out, tracker))
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

/// The step loop: steps until the end, a terminal event or a failure, which it returns.
fn run<S: OdeSystem>(
    st: &mut Stepper<S>,
    events: &mut [Event<'_>],
    tracker: &mut EventTracker,
    out: &mut Output<'_>,
) -> Status {
    let dim = st.dim();
    // An event that is not a number at t0 cannot be watched: the run ends before a step.
    if let Some(s) = nan_event(&tracker.g, st.t(), st.t()) {
        return s;
    }
    let mut q = vec![0.0; 4 * dim]; // interpolant coefficients of the current step
    let mut y_term = vec![0.0; dim];
    // The interpolant is needed for dense output, events and t_eval; it is cheap (28·dim flops).
    let need_q = out.dense.is_some() || !events.is_empty() || out.t_eval.is_some();
    loop {
        let outcome = match st.step() {
            Ok(o) => o,
            Err(s) => return s, // SciPy stores nothing from a failed step
        };
        if need_q {
            st.fill_dense_q(&mut q);
        }
        let seg = Segment {
            t_old: st.t_old(),
            h: st.t() - st.t_old(),
            y_old: st.y_old(),
            q: &q,
        };
        if let Some(d) = out.dense.as_mut() {
            d.push_segment(seg.t_old, seg.h, seg.y_old, seg.q);
        }
        let terminal = match tracker.step(events, &seg, st.t(), st.y(), st.direction()) {
            Ok(terminal) => terminal,
            Err(s) => {
                // Nothing of this step is kept (its state, output or dense segment).
                if let Some(d) = out.dense.as_mut() {
                    d.pop_segment();
                }
                return s;
            }
        };
        match terminal {
            Some((event, te)) => {
                seg.eval(te, &mut y_term);
                out.record(&seg, te, &y_term, st.direction());
                return Status::TerminalEvent { event, t: te };
            }
            None => out.record(&seg, st.t(), st.y(), st.direction()),
        }
        if outcome == StepOutcome::Finished {
            return Status::Success;
        }
    }
}

/// The run's `Solution`: the outputs, events, counts and the message.
fn solution<S: OdeSystem>(
    st: Stepper<S>,
    status: Status,
    out: Output<'_>,
    tracker: EventTracker,
) -> Solution {
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
    Solution {
        dim: st.dim(),
        t: out.t,
        y: out.y,
        t_events: tracker.t_events,
        y_events: tracker.y_events,
        nfev: st.nfev(),
        njev: 0,
        n_accepted: st.n_accepted(),
        n_rejected: st.n_rejected(),
        message,
        status,
        t_reached,
        rtol_clamped: st.rtol_clamped(),
        dense: out.dense,
        stiffness,
    }
}

/// The accepted step from `t_old` over `h`: its start and interpolant coefficients.
struct Segment<'s> {
    t_old: f64,
    h: f64,
    y_old: &'s [f64],
    q: &'s [f64],
}

impl Segment<'_> {
    /// The interpolant at `t` into `out`.
    #[inline]
    fn eval(&self, t: f64, out: &mut [f64]) {
        eval_segment(self.t_old, self.h, self.y_old, self.q, t, out);
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

    /// After the step `seg` to `(t, y)`: records the roots of the events in it, up to the
    /// first that terminates the run, and returns that one `(event, time)`. An event that
    /// is NaN at `t` is the run's end (`Err`); the step's roots are not looked for then.
    fn step(
        &mut self,
        events: &mut [Event<'_>],
        seg: &Segment<'_>,
        t: f64,
        y: &[f64],
        dir: f64,
    ) -> Result<Option<(usize, f64)>, Status> {
        if events.is_empty() {
            return Ok(None);
        }
        for (e, gn) in events.iter_mut().zip(self.g_new.iter_mut()) {
            *gn = (e.func)(t, y);
        }
        if let Some(s) = nan_event(&self.g_new, seg.t_old, t) {
            return Err(s);
        }
        self.find_roots(events, seg, t);
        let terminal = self.keep_roots_to_terminal(events, dir);
        for &(i, te) in self.roots.iter() {
            seg.eval(te, &mut self.ybuf);
            self.t_events[i].push(te);
            self.y_events[i].extend_from_slice(&self.ybuf);
        }
        std::mem::swap(&mut self.g, &mut self.g_new);
        Ok(terminal.then(|| *self.roots.last().expect("non-empty")))
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
    fn new(opts: &'o Rk45Options, t0: f64, y0: &[f64]) -> Result<Self, InputError> {
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
                out.t.push(t0);
                out.y.extend_from_slice(y0);
            }
        }
        Ok(out)
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
