//! [`Simulator`]: a scene advanced period by period with a held control.
//!
//! At a control boundary the method is not restarted: the step that would pass the boundary
//! is clipped to end on it, the next step starts from the proposal the controller made
//! before that clipping (not from a smaller clipped one), and when the control changed, the
//! derivative at the boundary is evaluated again with the new control (one right-hand side
//! evaluation per change for RK45, DOP853 and Radau: their first stage; nothing for RK4 and
//! Euler). Radau keeps its Jacobian and LU (a held torque or target does not change
//! `∂f/∂y`). A restart would instead cost SciPy's initial-step selection (one more
//! evaluation) and a first step ~100 times shorter, every period.
use super::sensors::{self, Imu, SensorWork};
use crate::effects::{Disabled, Effect};
use crate::integrator::{
    Counts, Dop853, Euler, FixedStep, Integrator, Interpolant, Method, Radau, Resume, Rk4,
    SolverOptions, Status, StepOutcome, Stepper, Vern9,
};
use crate::model::Model;
use crate::simulate::{self, Dynamics, Trajectory};
use crate::support::error::{Error, Result};

/// What a control holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControlKind {
    /// Joint torques, one per speed (`nv`), added to the effects' forces.
    Torque,
    /// The references of the scene's PD torques, one per joint they drive, held at zero
    /// reference rate (their tables are not read while a target is held).
    PdTarget,
}

impl ControlKind {
    /// `control=`: "torque" or "pd".
    pub fn from_arg<A: crate::support::args::Arg>(x: &A) -> std::result::Result<Self, A::Err> {
        let choices = [("torque", Self::Torque), ("pd", Self::PdTarget)];
        let expected = "'torque' (joint torques) or 'pd' (targets of the scene's PD torques)";
        crate::support::args::choice(x, "control", &choices, expected)
    }
}

// One engine per Simulator, held for its whole life: Radau's larger size costs nothing, a box
// would cost an indirection per step.
#[allow(clippy::large_enum_variant)]
enum Engine<'a> {
    Rk45(Stepper<Dynamics<'a>>),
    Dop853(Dop853<Dynamics<'a>>),
    Vern9(Vern9<Dynamics<'a>>),
    Radau(Radau<Dynamics<'a>>),
    Rk4(FixedStep<Dynamics<'a>, Rk4>),
    Euler(FixedStep<Dynamics<'a>, Euler>),
}

/// `$body` with `$x` bound to the engine's integrator, whatever the method.
macro_rules! each {
    ($e:expr, $x:ident => $body:expr) => {
        match $e {
            Engine::Rk45($x) => $body,
            Engine::Dop853($x) => $body,
            Engine::Vern9($x) => $body,
            Engine::Radau($x) => $body,
            Engine::Rk4($x) => $body,
            Engine::Euler($x) => $body,
        }
    };
}

impl<'a> Engine<'a> {
    fn new(
        sys: Dynamics<'a>,
        t: f64,
        y: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
    ) -> Result<Self> {
        let e = simulate::input_error;
        Ok(match opts.method {
            Method::Rk45 => Engine::Rk45(Stepper::new(sys, t, y, t_bound, opts).map_err(e)?),
            Method::Dop853 => Engine::Dop853(Dop853::new(sys, t, y, t_bound, opts).map_err(e)?),
            Method::Vern9 => Engine::Vern9(Vern9::new(sys, t, y, t_bound, opts).map_err(e)?),
            Method::Radau => Engine::Radau(Radau::new(sys, t, y, t_bound, opts).map_err(e)?),
            Method::Rk4 => Engine::Rk4(FixedStep::new(sys, t, y, t_bound, opts).map_err(e)?),
            Method::Euler => Engine::Euler(FixedStep::new(sys, t, y, t_bound, opts).map_err(e)?),
            Method::Adams => {
                return Err(Error::arg(
                    "method",
                    "'RK45', 'DOP853', 'Vern9', 'Radau', 'RK4' or 'Euler' for a Simulator (a \
                     multistep method cannot restart cheaply at each control step)",
                    "'Adams'",
                ))
            }
            Method::Auto => {
                return Err(Error::arg(
                    "method",
                    "'RK45', 'DOP853', 'Vern9', 'Radau', 'RK4' or 'Euler' for a Simulator (it \
                     does not switch methods)",
                    "'auto'",
                ))
            }
        })
    }
    fn t(&self) -> f64 {
        each!(self, x => Integrator::t(x))
    }
    fn y(&self) -> &[f64] {
        each!(self, x => Integrator::y(x))
    }
    fn counts(&self) -> Counts {
        each!(self, x => Integrator::counts(x))
    }
    fn h_next(&self) -> f64 {
        each!(self, x => Integrator::h_next(x))
    }
    fn step(&mut self) -> std::result::Result<StepOutcome, Status> {
        each!(self, x => Integrator::step(x))
    }
    fn extend(&mut self, t_bound: f64) {
        each!(self, x => x.extend(t_bound))
    }
    fn discontinuity(&mut self) -> std::result::Result<(), Status> {
        each!(self, x => x.discontinuity())
    }
    fn set_h_next(&mut self, h: f64) {
        each!(self, x => x.set_h_next(h))
    }
    fn t_old(&self) -> f64 {
        each!(self, x => Integrator::t_old(x))
    }
    fn y_old(&self) -> &[f64] {
        each!(self, x => Integrator::y_old(x))
    }
    fn interpolant(&self) -> Interpolant {
        each!(self, x => Integrator::interpolant(x))
    }
    fn dense_coefficients(&mut self, q: &mut [f64]) -> std::result::Result<(), Status> {
        each!(self, x => Integrator::dense_coefficients(x, q))
    }
    fn sys(&mut self) -> &mut Dynamics<'a> {
        each!(self, x => Integrator::system_mut(x))
    }
    fn into_sys(self) -> Dynamics<'a> {
        each!(self, x => Integrator::into_system(x))
    }
}

/// A scene stepped one control period at a time (docs/control.md).
pub struct Simulator<'a> {
    model: &'a Model,
    engine: Option<Engine<'a>>,
    opts: SolverOptions,
    period: f64,
    kind: ControlKind,
    /// Joints the enabled PD torques drive.
    pd_joints: usize,
    /// The control held (None: none set yet; with PD targets, the tables then).
    control: Option<Vec<f64>>,
    /// The control changed since the last step (a discontinuity at the next one's start).
    changed: bool,
    /// `advance` calls so far (messages name the step).
    steps: usize,
    record: bool,
    t_out: Vec<f64>,
    y_out: Vec<f64>,
    /// Counts of the engines a state change replaced.
    counts: Counts,
    /// The failure that ended the run, if any.
    failure: Option<Status>,
    sensors: SensorWork,
    /// With output times (`set_t_eval`): the rows are the states there, from each step's
    /// interpolant, instead of every accepted step's.
    t_eval: Option<Box<Sampled>>,
}

/// Output times and the buffers that evaluate a step's interpolant at them.
struct Sampled {
    times: Vec<f64>,
    /// The next time to output.
    next: usize,
    coef: Vec<f64>,
    row: Vec<f64>,
}

impl<'a> Simulator<'a> {
    /// A simulator of `model` with `effects` (minus `disabled`) from `(q0, v0)` at `t0`,
    /// advancing `period` by default with `opts.method` (not `auto`). `record`: keep every
    /// accepted step for [`Simulator::trajectory`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        model: &'a Model,
        effects: &[Effect],
        disabled: Disabled,
        (q0, v0): (&[f64], &[f64]),
        t0: f64,
        opts: SolverOptions,
        period: f64,
        kind: ControlKind,
        record: bool,
    ) -> Result<Self> {
        if !(period > 0.0 && period.is_finite()) {
            return Err(Error::arg(
                "control_period",
                "a positive, finite number of seconds",
                format!("{period}"),
            ));
        }
        if !t0.is_finite() {
            return Err(Error::arg("t0", "a finite time", format!("{t0}")));
        }
        model.check_state(q0, Some(v0))?;
        let mut sys = Dynamics::try_new(model, effects, disabled)?;
        let pd_joints = sys.effects.pd_joints();
        if kind == ControlKind::PdTarget && pd_joints == 0 {
            return Err(Error::arg(
                "control",
                "'torque', or 'pd' for a scene with enabled PD torques (PDTorque)",
                "'pd' for a scene without one",
            ));
        }
        if kind == ControlKind::Torque {
            sys.control = vec![0.0; model.nv];
        }
        let mut y0 = simulate::initial_state(model, q0, v0);
        if let Some(solver) = sys.loops.as_mut() {
            simulate::close_initial_state(model, solver, &mut y0)?;
        }
        let engine = Engine::new(sys, t0, &y0, t0 + period, &opts)?;
        let mut s = Simulator {
            model,
            engine: Some(engine),
            opts,
            period,
            kind,
            pd_joints,
            control: None,
            changed: false,
            steps: 0,
            record,
            t_out: Vec::new(),
            y_out: Vec::new(),
            counts: Counts::default(),
            failure: None,
            sensors: SensorWork::new(model),
            t_eval: None,
        };
        s.push_row();
        Ok(s)
    }

    fn engine(&self) -> &Engine<'a> {
        self.engine
            .as_ref()
            .expect("the engine is only taken inside set_state")
    }
    fn engine_mut(&mut self) -> &mut Engine<'a> {
        self.engine
            .as_mut()
            .expect("the engine is only taken inside set_state")
    }

    fn push_row(&mut self) {
        if self.record && self.t_eval.is_none() {
            let (t, y) = (self.engine().t(), self.engine().y().to_vec());
            self.t_out.push(t);
            self.y_out.extend_from_slice(&y);
        }
    }

    pub fn t(&self) -> f64 {
        self.engine().t()
    }
    /// The state `[q; v]`.
    pub fn y(&self) -> &[f64] {
        self.engine().y()
    }
    pub fn nq(&self) -> usize {
        self.model.nq
    }
    pub fn nv(&self) -> usize {
        self.model.nv
    }
    pub fn period(&self) -> f64 {
        self.period
    }
    pub fn method(&self) -> Method {
        self.opts.method
    }
    pub fn kind(&self) -> ControlKind {
        self.kind
    }
    /// The control held (None before the first).
    pub fn control(&self) -> Option<&[f64]> {
        self.control.as_deref()
    }
    /// The length a control has: `nv` torques, or one target per PD-driven joint.
    pub fn control_len(&self) -> usize {
        match self.kind {
            ControlKind::Torque => self.model.nv,
            ControlKind::PdTarget => self.pd_joints,
        }
    }
    /// `advance` calls so far.
    pub fn steps(&self) -> usize {
        self.steps
    }
    pub fn failure(&self) -> Option<&Status> {
        self.failure.as_ref()
    }

    /// Holds `u` from now on (checked: its length, finite values; errors name the step).
    pub fn set_control(&mut self, u: &[f64]) -> Result<()> {
        let (n, k, t) = (self.control_len(), self.steps, self.t());
        let what = match self.kind {
            ControlKind::Torque => "joint torques, one per speed",
            ControlKind::PdTarget => "PD targets, one per joint the PD torques drive",
        };
        if u.len() != n {
            return Err(Error::arg(
                "control",
                format!("{n} {what} (step {k}, t = {t})"),
                format!("{} values", u.len()),
            ));
        }
        if let Some((i, x)) = u.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(Error::arg(
                "control",
                format!("finite {what} (step {k}, t = {t})"),
                format!("{x} at index {i}"),
            ));
        }
        if self.control.as_deref() == Some(u) {
            return Ok(());
        }
        let kind = self.kind;
        let sys = self.engine_mut().sys();
        match kind {
            ControlKind::Torque => sys.control.copy_from_slice(u),
            ControlKind::PdTarget => sys.effects.hold_pd_targets(Some(u)),
        }
        self.control = Some(u.to_vec());
        self.changed = true;
        Ok(())
    }

    /// Advances to `target` (after `t`) with the control held. A failure of the run (a
    /// non-finite state, a step too small, a failing callback) is returned as its status and
    /// kept: every later call returns it again.
    pub fn advance(&mut self, target: f64) -> Result<std::result::Result<(), Status>> {
        let t = self.t();
        if !(target > t && target.is_finite()) {
            return Err(Error::arg(
                "duration",
                format!("a positive, finite time to advance (step {})", self.steps),
                format!("{} (to t = {target} from t = {t})", target - t),
            ));
        }
        if let Some(s) = &self.failure {
            return Ok(Err(s.clone()));
        }
        self.steps += 1;
        let r = self.advance_to(target);
        if let Err(s) = &r {
            self.failure = Some(s.clone());
        }
        Ok(r)
    }

    fn advance_to(&mut self, target: f64) -> std::result::Result<(), Status> {
        let changed = std::mem::take(&mut self.changed);
        let e = self.engine_mut();
        e.extend(target);
        if changed {
            e.discontinuity()?;
        }
        loop {
            let e = self.engine_mut();
            let (h_before, t_before, rejected) = (e.h_next(), e.t(), e.counts().n_rejected);
            let outcome = e.step()?;
            let clipped = (e.t() - t_before).abs() < h_before;
            if outcome == StepOutcome::Finished
                && clipped
                && e.counts().n_rejected == rejected
                && e.h_next() < h_before
            {
                e.set_h_next(h_before);
            }
            self.push_row();
            self.sample()?;
            if outcome == StepOutcome::Finished {
                return Ok(());
            }
        }
    }

    /// Records the state only at `times` (increasing, finite, from the current time on)
    /// instead of at every accepted step, each from the interpolant of the step that reaches
    /// it (as `simulate`'s `t_eval`); a time equal to the current one is recorded now.
    /// Replaces the rows recorded so far.
    pub fn set_t_eval(&mut self, times: &[f64]) -> Result<()> {
        let t = self.t();
        if let Some((i, x)) = times.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(Error::arg(
                "t_eval",
                "finite times",
                format!("{x} at index {i}"),
            ));
        }
        if let Some(i) = (1..times.len()).find(|&i| times[i] <= times[i - 1]) {
            let what = format!("{} then {} at index {i}", times[i - 1], times[i]);
            return Err(Error::arg("t_eval", "strictly increasing times", what));
        }
        if let Some(&first) = times.first().filter(|&&x| x < t) {
            let got = format!("{first} before t = {t}");
            return Err(Error::arg("t_eval", "times from the current time on", got));
        }
        let dim = self.model.nq + self.model.nv;
        self.t_out.clear();
        self.y_out.clear();
        self.t_eval = Some(Box::new(Sampled {
            times: times.to_vec(),
            next: 0,
            coef: Vec::new(),
            row: vec![0.0; dim],
        }));
        // `times` from `t` on: only a first time equal to `t` is due now.
        if times.first() == Some(&t) {
            let y = self.y().to_vec();
            let s = self.t_eval.as_mut().expect("set above");
            s.next = 1;
            self.t_out.push(t);
            self.y_out.extend_from_slice(&y);
        }
        Ok(())
    }

    /// The output times the last step reached, from its interpolant (its end state exactly).
    fn sample(&mut self) -> std::result::Result<(), Status> {
        let (Some(s), Some(e)) = (self.t_eval.as_mut(), self.engine.as_mut()) else {
            return Ok(());
        };
        let t = e.t();
        if s.next >= s.times.len() || s.times[s.next] > t {
            return Ok(());
        }
        let kind = e.interpolant();
        s.coef.resize(kind.n_coef() * s.row.len(), 0.0);
        e.dense_coefficients(&mut s.coef)?;
        let (t_old, h) = (e.t_old(), t - e.t_old());
        while s.next < s.times.len() && s.times[s.next] <= t {
            let te = s.times[s.next];
            match te == t {
                true => s.row.copy_from_slice(e.y()),
                false => kind.eval(t_old, h, e.y_old(), &s.coef, te, &mut s.row),
            }
            self.t_out.push(te);
            self.y_out.extend_from_slice(&s.row);
            s.next += 1;
        }
        Ok(())
    }

    /// Replaces the state (a reset or a perturbation) at the current time: unit quaternions;
    /// with loops, `q` must close them to 1e-8 and `v` keep them closed, what remains is
    /// projected away (else an error, the state unchanged). The method starts afresh from
    /// it (its first step chosen again); the trajectory gets a second row at this time.
    pub fn set_state(&mut self, q: &[f64], v: &[f64]) -> Result<()> {
        self.model.check_state(q, Some(v))?;
        let mut y = simulate::initial_state(self.model, q, v);
        let (t, y_before) = (self.t(), self.y().to_vec());
        let engine = self.engine.take().expect("engine present");
        self.counts = self.counts + engine.counts();
        let mut sys = engine.into_sys();
        let closed = match sys.loops.as_mut() {
            Some(solver) => simulate::close_initial_state(self.model, solver, &mut y),
            None => Ok(()),
        };
        let y = match closed {
            Ok(()) => y,
            Err(e) => {
                // Refused: the run goes on from the state it had.
                self.engine = Some(Engine::new(sys, t, &y_before, t + self.period, &self.opts)?);
                return Err(e);
            }
        };
        self.engine = Some(Engine::new(sys, t, &y, t + self.period, &self.opts)?);
        self.failure = None;
        self.changed = false;
        self.push_row();
        Ok(())
    }

    /// Counts of the whole run (engines replaced by state changes included).
    pub fn counts(&self) -> Counts {
        self.counts + self.engine().counts()
    }

    /// Every accepted step so far (with `record`), as `simulate` returns it.
    pub fn trajectory(&self) -> Trajectory {
        let (nq, nv) = (self.model.nq, self.model.nv);
        let n = self.t_out.len();
        let (mut q, mut v) = (Vec::with_capacity(n * nq), Vec::with_capacity(n * nv));
        for row in self.y_out.chunks_exact(nq + nv) {
            q.extend_from_slice(&row[..nq]);
            v.extend_from_slice(&row[nq..]);
        }
        let c = self.counts();
        let t_reached = self.t();
        let status = self.failure.clone().unwrap_or(Status::Success);
        Trajectory {
            nq,
            nv,
            t: self.t_out.clone(),
            q,
            v,
            energy: None,
            constraint_residual: None,
            constraint_drift: None,
            singular_passage: None,
            singular_crossings: None,
            effect_labels: Vec::new(),
            power: None,
            t_events: Vec::new(),
            y_events: Vec::new(),
            nfev: c.nfev,
            njev: c.njev,
            nlu: c.nlu,
            n_accepted: c.n_accepted,
            n_rejected: c.n_rejected,
            method: self.opts.method,
            switched_to: None,
            t_switch: None,
            message: status.describe(t_reached),
            success: status.is_success(),
            status,
            t_reached,
        }
    }

    /// Joint torques the actuators apply now: the held torque control plus the scene's
    /// torques-family effects (PD torques included), `nv` values into `out`.
    pub fn joint_torques(&mut self, out: &mut [f64]) -> Result<()> {
        let t = self.t();
        let y = self.y().to_vec();
        let e = self.engine.as_mut().expect("engine present");
        sensors::joint_torques(self.model, e.sys(), &mut self.sensors, t, &y, out)
    }

    /// IMU readings now: per sensor the specific force (accelerometer, gravity included) and
    /// the angular velocity, both in the sensor's axes, 6 values each into `out`.
    pub fn imu(&mut self, imus: &[Imu], out: &mut [f64]) -> Result<()> {
        let t = self.t();
        let y = self.y().to_vec();
        let e = self.engine.as_mut().expect("engine present");
        sensors::imu(self.model, e.sys(), &mut self.sensors, imus, t, &y, out)
    }
}
