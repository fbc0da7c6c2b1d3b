//! The simulate loop, entirely in Rust: state `y = [q; v]`, `q̇` from `v`, `v̇` from the
//! recursive forward dynamics with the scene's declared effects, integrated by the method of
//! the run's options (see `integrator::Method`; a run that names none: RK45, or `auto` for a
//! scene with contact or joint limits, [`default_method`]).
//!
//! The right-hand side asks the effects for joint forces and link wrenches only when the
//! scene declares such effects; gravity rides on the base acceleration. A scene with no
//! effects runs the bare forward dynamics.
mod along;
pub mod at_state;
pub mod batch;
pub mod config_args;
pub mod derivatives;
mod dynamics;
mod evaluate;
mod event_list;
mod settings;

pub use along::{along, Along, Asked, SceneAlong};
pub use dynamics::{Dynamics, Progress};
pub use event_list::{event_value, CallerEvent, EventList};
pub use settings::{default_method, disabled, Resolved, RunConfig};

use crate::effects::{Disabled, Effect};
use crate::integrator::{self, Event, SolverOptions, Status};
use crate::io::scene::Scene;
use crate::model::Model;
use crate::support::error::{Error, Result};

/// An event on the state: `q[index] − value` or `v[index] − value` crossing zero.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StateEvent {
    pub on_velocity: bool,
    pub index: usize,
    pub value: f64,
    /// −1, 0 or +1 (crossing direction that counts).
    pub direction: i32,
    /// Stop at the n-th occurrence (0: never).
    pub terminal: usize,
}

/// What to record at every output time besides `t`, `q`, `v`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Record {
    /// Kinetic plus the enabled effects' potential energy (gravity, springs).
    pub energy: bool,
    /// Power `τ_e · v` of each enabled effect.
    pub power: bool,
}

#[derive(Debug, Clone)]
pub struct Trajectory {
    pub nq: usize,
    pub nv: usize,
    pub t: Vec<f64>,
    /// Row-major N × nq.
    pub q: Vec<f64>,
    /// Row-major N × nv.
    pub v: Vec<f64>,
    pub energy: Option<Vec<f64>>,
    /// With loops: the largest constraint residual of each output state (after projection).
    pub constraint_residual: Option<Vec<f64>>,
    /// With loops: the largest residual an accepted step had before it was projected.
    pub constraint_drift: Option<f64>,
    /// With loops: the first accepted state at a singular position within rounding,
    /// `(t, pivot ratio relative to the run's best so far)` ([`dynamics::SINGULAR_PASSAGE`]).
    pub singular_passage: Option<(f64, f64)>,
    /// With loops and one degree of freedom: how many singular positions the motion passed
    /// between accepted states, and the time just past the first (`dynamics::Crossings`).
    pub singular_crossings: Option<(usize, Option<f64>)>,
    /// Output names of the enabled effects (the columns of `power`).
    pub effect_labels: Vec<String>,
    /// Row-major N × effect_labels.len().
    pub power: Option<Vec<f64>>,
    pub t_events: Vec<Vec<f64>>,
    /// Per event, row-major states `[q; v]` at the event times.
    pub y_events: Vec<Vec<f64>>,
    pub nfev: usize,
    pub njev: usize,
    pub nlu: usize,
    pub n_accepted: usize,
    pub n_rejected: usize,
    /// The method asked for, and for `auto` the one it switched to and when.
    pub method: integrator::Method,
    pub switched_to: Option<integrator::Method>,
    pub t_switch: Option<f64>,
    pub status: Status,
    pub message: String,
    pub t_reached: f64,
    pub success: bool,
}

impl Trajectory {
    /// A run of a batch that never started, stopped by `error`: the batch's stop
    /// ([`Error::Interrupted`], its message then says by what), else the refusal of its
    /// input, named by its exception class as the caller will see it.
    pub fn refused(error: &Error) -> Trajectory {
        match error {
            Error::Interrupted(m) => Trajectory::not_started(m.clone()),
            e => {
                let text = crate::support::error::compact_numbers(&e.to_string());
                let class = e.kind_name().unwrap_or("Error");
                Trajectory::not_started(format!("{class}: {text}"))
            }
        }
    }

    /// A run that never started (a batch run whose input was refused): no samples, no
    /// evaluations, `message` saying why.
    pub fn not_started(message: String) -> Trajectory {
        Trajectory {
            nq: 0,
            nv: 0,
            t: Vec::new(),
            q: Vec::new(),
            v: Vec::new(),
            energy: None,
            constraint_residual: None,
            constraint_drift: None,
            singular_passage: None,
            singular_crossings: None,
            effect_labels: Vec::new(),
            power: None,
            t_events: Vec::new(),
            y_events: Vec::new(),
            nfev: 0,
            njev: 0,
            nlu: 0,
            n_accepted: 0,
            n_rejected: 0,
            method: integrator::Method::Rk45,
            switched_to: None,
            t_switch: None,
            status: Status::NotStarted {
                reason: message.clone(),
            },
            message,
            t_reached: f64::NAN,
            success: false,
        }
    }

    /// The run as the caller gets it: its events in the caller's order (`slots`, the core's
    /// `EventList::slots`), its interruption named by `stopped` (what stopped it, if the
    /// caller knows).
    pub fn finished(mut self, stopped: Option<&str>, slots: &[usize]) -> Self {
        if let Some(reason) = stopped {
            self.name_interruption(reason);
        }
        self.order_events(slots);
        self
    }

    /// The events in the caller's order: `slots[k]` is the trajectory's slot of the
    /// caller's event `k` (state events and callables are run in two lists).
    pub fn order_events(&mut self, slots: &[usize]) {
        self.t_events = slots.iter().map(|&s| self.t_events[s].clone()).collect();
        self.y_events = slots.iter().map(|&s| self.y_events[s].clone()).collect();
    }

    /// Each event's `q` states (m × nq), or its `v` states (m × nv) with `velocities`.
    pub fn event_matrices(&self, velocities: bool) -> Vec<nalgebra::DMatrix<f64>> {
        let (nq, nv) = (self.nq, self.nv);
        let cols = if velocities { nq..nq + nv } else { 0..nq };
        integrator::event_matrices(&self.y_events, nq + nv, cols)
    }

    /// The power of each enabled effect over the output times, by its label.
    pub fn power_columns(&self) -> Option<Vec<(String, Vec<f64>)>> {
        let (p, m) = (self.power.as_ref()?, self.effect_labels.len());
        let col = |k: usize| (0..self.t.len()).map(|i| p[i * m + k]).collect();
        Some(
            (self.effect_labels.iter().cloned().enumerate())
                .map(|(k, l)| (l, col(k)))
                .collect(),
        )
    }

    /// A run its caller interrupted ([`Status::Interrupted`]) says by what: `reason`, which
    /// only the caller knows (the exception its progress callback raised, Ctrl-C).
    pub fn name_interruption(&mut self, reason: &str) {
        let Status::Interrupted { t, at, .. } = self.status else {
            return;
        };
        let before = self.status.describe(self.t_reached);
        let rest = self.message.strip_prefix(before.as_str()).unwrap_or("");
        let rest = rest.to_string();
        self.status = Status::Interrupted {
            t,
            at,
            reason: Some(reason.to_string()),
        };
        self.message = self.status.describe(self.t_reached) + &rest;
    }
}

/// Runs `scene` as `config` asks: the caller's settings over the scene's, over the
/// defaults ([`RunConfig::resolve`]), then [`simulate`] from the scene's initial state.
pub fn run_scene(
    scene: &Scene,
    config: RunConfig,
    state_events: &[StateEvent],
    extra_events: Vec<Event<'_>>,
    progress: Option<Progress<'_>>,
) -> Result<Trajectory> {
    let dim = scene.model.nq + scene.model.nv;
    let run = config.resolve(&scene.settings, &scene.effects, dim)?;
    simulate(
        &scene.model,
        &scene.effects,
        run.disabled,
        &scene.q0,
        &scene.v0,
        run.t_span,
        &run.opts,
        state_events,
        extra_events,
        run.record,
        progress,
    )
}

/// Integrates `model` with `effects` (minus the `disabled` families) from `(q0, v0)` over
/// `t_span`. `extra_events` are caller-built events on `y = [q; v]` (e.g. Python callables),
/// evaluated after the state events. Invalid input is an `Err`; a run that fails midway
/// returns `Ok` with `success = false` and a message naming the reason and the time reached.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    model: &Model,
    effects: &[Effect],
    disabled: Disabled,
    q0: &[f64],
    v0: &[f64],
    t_span: (f64, f64),
    opts: &SolverOptions,
    state_events: &[StateEvent],
    extra_events: Vec<Event<'_>>,
    record: Record,
    progress: Option<Progress<'_>>,
) -> Result<Trajectory> {
    model.check_state(q0, Some(v0))?;
    check_state_events(model, state_events)?;
    let mut sys = Dynamics::try_new(model, effects, disabled)?;
    let mut y0 = initial_state(model, q0, v0);
    if let Some(solver) = sys.loops.as_mut() {
        close_initial_state(model, solver, &mut y0)?;
    }
    let mut events: Vec<Event<'_>> = state_events
        .iter()
        .map(|e| state_event(e, model.nq))
        .collect();
    events.extend(extra_events);
    let n_user = events.len();
    let guarded = push_euler_guards(model, opts, &y0, &mut events);
    sys.progress = progress;
    let mut sol =
        integrator::solve(&mut sys, t_span, &y0, opts, &mut events).map_err(input_error)?;
    drop(events);
    report_euler_singularity(model, &guarded, n_user, &mut sol);
    let stalled = matches!(
        sol.status,
        Status::StepTooSmall { .. } | Status::MaxSteps { .. }
    );
    if let Some(c) = sys.crossings.as_ref() {
        note_crossings(c.count, c.first, &mut sol.message);
    }
    if sys.loops.is_some() && stalled {
        sol.message.push_str(
            "; if the mechanism is near a singular position there, rtol/atol may ask for more \
             than the loops' projection can resolve (docs/mechanisms.md §2): loosen them \
             (DOP853 passes the IFToMM N-four-bar down to rtol 1e-12)",
        );
    }
    if let (Status::NonFinite { at, .. }, Some((t_fail, message))) =
        (&sol.status, sys.off_manifold_failure.as_ref())
    {
        if t_fail == at {
            sol.message.push_str(&format!(
                "; the right-hand side failed there at a stage too far off the loops' \
                 manifolds to project (the step that led there was too long for rtol/atol: \
                 tighten them): {message}"
            ));
        }
    }
    if let (Status::RhsError { t, at, .. }, Some(_)) = (&sol.status, sys.interrupted_at) {
        sol.status = Status::Interrupted {
            t: *t,
            at: *at,
            reason: None,
        };
        sol.message = sol.status.describe(sol.t_reached);
    }
    sol.t_events.truncate(n_user);
    sol.y_events.truncate(n_user);
    let (mut q, mut v) = split_states(model, &sol);
    let (constraint_residual, constraint_drift) = match sys.loops.as_mut() {
        Some(solver) => {
            let residual = close_outputs(model, solver, sol.t.len(), &mut q, &mut v);
            (Some(residual), Some(solver.max_drift))
        }
        None => (None, None),
    };
    let energy = record
        .energy
        .then(|| energies(&mut sys, sol.t.len(), &q, &v));
    let labels = sys.effects.labels();
    let power = match record.power {
        true => Some(powers(&mut sys, labels.len(), &sol.t, &q, &v)?),
        false => None,
    };
    Ok(Trajectory {
        nq: model.nq,
        nv: model.nv,
        success: sol.status.is_success(),
        t: sol.t,
        q,
        v,
        energy,
        constraint_residual,
        constraint_drift,
        singular_passage: sys.singular_passage,
        singular_crossings: sys.crossings.as_ref().map(|c| (c.count, c.first)),
        effect_labels: labels,
        power,
        t_events: sol.t_events,
        y_events: sol.y_events,
        nfev: sol.nfev,
        njev: sol.njev,
        nlu: sol.nlu,
        method: sol.method,
        switched_to: sol.switched_to,
        t_switch: sol.t_switch,
        n_accepted: sol.n_accepted,
        n_rejected: sol.n_rejected,
        message: sol.message,
        t_reached: sol.t_reached,
        status: sol.status,
    })
}

/// Each state event's index within `q` (or `v`).
fn check_state_events(model: &Model, state_events: &[StateEvent]) -> Result<()> {
    for (k, e) in state_events.iter().enumerate() {
        let n = if e.on_velocity { model.nv } else { model.nq };
        if e.index >= n {
            return Err(Error::arg(
                format!("events[{k}].index"),
                format!(
                    "an index into {} (0..{n})",
                    if e.on_velocity { "v" } else { "q" }
                ),
                e.index.to_string(),
            ));
        }
    }
    Ok(())
}

/// `y0 = [q0; v0]` with unit quaternions.
pub(crate) fn initial_state(model: &Model, q0: &[f64], v0: &[f64]) -> Vec<f64> {
    let mut y0 = Vec::with_capacity(model.nq + model.nv);
    y0.extend_from_slice(q0);
    y0.extend_from_slice(v0);
    model.normalize(&mut y0[..model.nq]);
    y0
}

/// A model with loops starts on the constraint manifolds: `q0` must close every loop to
/// 1e-8 and `v0` keep them closed (else an error pointing at `assemble`); what remains is
/// projected away.
pub(crate) fn close_initial_state(
    model: &Model,
    solver: &mut crate::loops::LoopSolver,
    y0: &mut [f64],
) -> Result<()> {
    let (q0, v0) = y0.split_at(model.nq);
    let mut kin = crate::loops::LoopKinematics::new(model);
    kin.positions(model, q0);
    let mut r = vec![0.0; model.nconstraints()];
    crate::loops::residual(model, &kin, &mut r);
    let name = |row: usize| model.constraint_name(row);
    if let Some((row, x)) = r.iter().enumerate().find(|(_, x)| x.abs() > 1e-8) {
        return Err(Error::Closure(format!(
            "q0: {} is open by {x:.3e} (constraint row {row}): close it first with model.assemble(q0, fixed=[...])",
            name(row)
        )));
    }
    let mut j = nalgebra::DMatrix::zeros(model.nconstraints(), model.nv);
    crate::loops::jacobian(model, &kin, &mut j);
    let jv = &j * nalgebra::DVector::from_column_slice(v0);
    let scale = 1.0 + v0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if jv.amax() > 1e-8 * scale {
        let row = jv.iamax();
        return Err(Error::arg(
            "v0",
            "speeds that keep the loops closed (J v0 = 0; see model.assemble_velocity)",
            format!("J v0 = {:.3e} in row {row} ({})", jv[row], name(row)),
        ));
    }
    crate::loops::project_state(model, solver, y0).map_err(Error::Closure)?;
    crate::loops::check_mobility(model, solver, &y0[..model.nq])?;
    solver.max_drift = 0.0;
    Ok(())
}

/// A run that passed singular positions says, in its message, that its error past them is
/// not rtol's (docs/mechanisms.md §5): the family of `tests/test_singular_crossings.py`
/// ends up to 160 times 100 rtol from its exact reduction after crossings (and on another
/// branch when a pass crawls: that is `singular_passage`, with a warning).
fn note_crossings(count: usize, first: Option<f64>, message: &mut String) {
    if let Some(t) = first {
        message.push_str(&format!(
            "; the motion passed {count} singular position(s) of its loops (the first just \
             before t = {}): past one its error is not bounded by rtol's (docs/mechanisms.md §5)",
            integrator::fmt_time(t)
        ));
    }
}

/// Projects each output state of a model with loops (dense output between steps is not
/// projected by the integrator) and returns each one's largest residual afterwards.
fn close_outputs(
    model: &Model,
    solver: &mut crate::loops::LoopSolver,
    n: usize,
    q: &mut [f64],
    v: &mut [f64],
) -> Vec<f64> {
    let (nq, nv) = (model.nq, model.nv);
    let drift = solver.max_drift;
    let mut y = vec![0.0; nq + nv];
    let mut r = vec![0.0; model.nconstraints()];
    let mut kin = crate::loops::LoopKinematics::new(model);
    let out = (0..n)
        .map(|i| {
            y[..nq].copy_from_slice(&q[row(i, nq)]);
            y[nq..].copy_from_slice(&v[row(i, nv)]);
            // A failed projection leaves the sample as the integrator gave it.
            if crate::loops::project_state(model, solver, &mut y).is_ok() {
                q[row(i, nq)].copy_from_slice(&y[..nq]);
                v[row(i, nv)].copy_from_slice(&y[nq..]);
            }
            kin.positions(model, &q[row(i, nq)]);
            crate::loops::residual(model, &kin, &mut r);
            r.iter().fold(0.0f64, |m, x| m.max(x.abs()))
        })
        .collect();
    solver.max_drift = drift;
    out
}

/// A state event as an integrator event on `y = [q; v]`.
fn state_event(e: &StateEvent, nq: usize) -> Event<'static> {
    let offset = if e.on_velocity { nq } else { 0 } + e.index;
    let value = e.value;
    Event::new(move |_t, y: &[f64]| y[offset] - value)
        .direction(integrator::EventDirection::from_sign(e.direction as f64))
        .terminal(e.terminal)
}

/// Euler-angle joints: a terminal event where sin θ changes sign, located on the dense
/// output, stops the run at the singularity even when a loose tolerance would step over
/// it, and long before the integrator crawls towards it with ever smaller steps. A second
/// stops it where the joint comes within [`chart_band`] of it: there the rounding of the
/// Euler-angle accelerations (relative `ε / sin²θ`) exceeds the tolerance, and a run that
/// passed would report success with the rotation off by far more than `rtol`. Returns the
/// guarded links with the band, in the order of their events (after `events`' others).
fn push_euler_guards(
    model: &Model,
    opts: &SolverOptions,
    y0: &[f64],
    events: &mut Vec<Event<'_>>,
) -> Vec<(usize, Option<f64>)> {
    let mut guarded = Vec::new();
    for (i, l) in model.links.iter().enumerate() {
        if !matches!(l.joint, crate::joint::Joint::SphericalZYZ) {
            continue;
        }
        let theta = l.q_index + 1;
        events.push(Event::new(move |_t, y: &[f64]| y[theta].sin()).terminal(1));
        guarded.push((i, None));
        // A run that starts nearer is let go until it gets twice as near.
        let band = chart_band(opts, theta).min(0.5 * y0[theta].sin().abs());
        events.push(
            Event::new(move |_t, y: &[f64]| y[theta].sin().abs() - band)
                .direction(integrator::EventDirection::Falling)
                .terminal(1),
        );
        guarded.push((i, Some(band)));
    }
    guarded
}

/// `|sin θ|` below which a ZYZ joint's accelerations carry rounding errors (relative
/// `ε / sin²θ`, the conditioning of the Euler-angle rates) above a ninth of the tolerance:
/// `3 √(ε / rtol)` (1.4e-3 at rtol 1e-9, 1.4e-6 at the default 1e-3), never below the
/// joint's own refusal. Measured on a rod passing the singularity (tests/test_hardening.py):
/// nearer than this the rotation ends 40 to 10⁶ times rtol off.
fn chart_band(opts: &SolverOptions, theta: usize) -> f64 {
    let rtol = match &opts.rtol {
        integrator::Tol::Scalar(r) => *r,
        integrator::Tol::PerComponent(r) => r.get(theta).copied().unwrap_or(1e-3),
    };
    let band = 3.0 * (f64::EPSILON / rtol.max(f64::EPSILON)).sqrt();
    band.max(crate::joint::ZYZ_SINGULAR_SIN)
}

/// A run stopped by an Euler guard (event `n_user` on) failed: the status and message say
/// which joint reached its singularity, or came too near it for the tolerance.
fn report_euler_singularity(
    model: &Model,
    guarded: &[(usize, Option<f64>)],
    n_user: usize,
    sol: &mut integrator::Solution,
) {
    if let Status::TerminalEvent { event, t } = sol.status {
        if event >= n_user {
            let (link, band) = guarded[event - n_user];
            let name = &model.bodies[model.links[link].body].name;
            let message = match band {
                None => format!(
                    "SphericalZYZ joint of body '{name}' reached its Euler singularity (sin theta = 0) at t = {t}: the Euler-angle rates diverge there; model the joint as Spherical (a quaternion) to move through it"
                ),
                Some(band) => format!(
                    "SphericalZYZ joint of body '{name}' came within |sin theta| = {band:.1e} of its Euler singularity (sin theta = 0) at t = {t}: nearer, rounding in the Euler-angle rates (growing like 1/sin^2 theta) exceeds the tolerance and the rotation would be off by far more than rtol; model the joint as Spherical (a quaternion) to move through it, or loosen rtol"
                ),
            };
            sol.message = format!("{message}; integration stopped at t = {t}");
            sol.status = Status::RhsError { t, at: t, message };
        }
    }
}

/// The integrator's refusal, an output too large said to be `simulate`'s.
pub(crate) fn input_error(e: integrator::InputError) -> Error {
    Error::from(e).map_arg(|_| "simulate".into())
}

/// The output states as row-major `q` (N × nq, unit quaternions) and `v` (N × nv).
fn split_states(model: &Model, sol: &integrator::Solution) -> (Vec<f64>, Vec<f64>) {
    let (nq, nv, n) = (model.nq, model.nv, sol.t.len());
    let mut q = Vec::with_capacity(n * nq);
    let mut v = Vec::with_capacity(n * nv);
    for i in 0..n {
        let y = sol.state(i);
        q.extend_from_slice(&y[..nq]);
        v.extend_from_slice(&y[nq..]);
    }
    // Dense output between steps is not re-projected; keep reported quaternions unit.
    for row in q.chunks_exact_mut(nq.max(1)).take(n) {
        model.normalize(row);
    }
    (q, v)
}

/// Row `i` of a row-major matrix of `m` columns.
fn row(i: usize, m: usize) -> std::ops::Range<usize> {
    i * m..(i + 1) * m
}

/// The energy at each of the `n` output rows of `q` and `v`.
fn energies(sys: &mut Dynamics<'_>, n: usize, q: &[f64], v: &[f64]) -> Vec<f64> {
    let (nq, nv) = (sys.model.nq, sys.model.nv);
    (0..n)
        .map(|i| sys.energy(&q[row(i, nq)], &v[row(i, nv)]))
        .collect()
}

/// The power of each of the `m` enabled effects at each output time: row-major N × m.
fn powers(sys: &mut Dynamics<'_>, m: usize, t: &[f64], q: &[f64], v: &[f64]) -> Result<Vec<f64>> {
    let (nq, nv, n) = (sys.model.nq, sys.model.nv, t.len());
    let mut out = vec![0.0; n * m];
    let mut scratch = vec![0.0; m * nv];
    for i in 0..n {
        sys.effect_power(
            t[i],
            &q[row(i, nq)],
            &v[row(i, nv)],
            &mut scratch,
            &mut out[row(i, m)],
        )
        .map_err(|e| Error::InvalidSetting(format!("power at t = {}: {e}", t[i])))?;
    }
    Ok(out)
}
