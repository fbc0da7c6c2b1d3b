//! The simulate loop, entirely in Rust: state `y = [q; v]`, `q̇` from `v`, `v̇` from the
//! recursive forward dynamics with the scene's declared effects, integrated by our RK45.
//!
//! The right-hand side asks the effects for joint forces and link wrenches only when the
//! scene declares such effects; gravity rides on the base acceleration. A scene with no
//! effects runs the bare forward dynamics.
use crate::effects::{Context, Disabled, Effect, Effects, Probe};
use crate::error::{Error, Result};
use crate::integrator::{self, Event, OdeSystem, Rk45Options, Status};
use crate::kinematics;
use crate::model::Model;
use crate::recursive::{self, Data};
use crate::spatial::Vec6;

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
    progress: Option<Progress<'a>>,
    calls: usize,
    probe: Option<Probe>,
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
            probe: None,
        }
    }

    /// Kinetic energy plus the potential energy of the enabled conservative effects
    /// (gravity, springs).
    pub fn energy(&mut self, q: &[f64], v: &[f64]) -> f64 {
        kinematics::positions(self.model, q, &mut self.data.links);
        kinematics::velocities(self.model, q, v, &mut self.data.links);
        let cx = Context {
            model: self.model,
            t: 0.0,
            q,
            v,
        };
        recursive::kinetic_energy(&self.data) + self.effects.potential_energy(&cx, &self.data.links)
    }

    /// Kinetic energy and `(label, V)` of each conservative effect.
    pub fn energies(&mut self, q: &[f64], v: &[f64]) -> (f64, Vec<(String, f64)>) {
        kinematics::positions(self.model, q, &mut self.data.links);
        kinematics::velocities(self.model, q, v, &mut self.data.links);
        let cx = Context {
            model: self.model,
            t: 0.0,
            q,
            v,
        };
        (
            recursive::kinetic_energy(&self.data),
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
        let cx = Context {
            model: self.model,
            t,
            q,
            v,
        };
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
        let cx = Context {
            model: self.model,
            t,
            q,
            v,
        };
        let ext = if self.effects.apply(&cx, &mut self.tau, &mut self.wrenches)? {
            Some(self.wrenches.as_slice())
        } else {
            None
        };
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
        .map_err(|e| e.to_string())
    }
}

impl OdeSystem for Dynamics<'_> {
    fn dim(&self) -> usize {
        self.model.nq + self.model.nv
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> std::result::Result<(), String> {
        let nq = self.model.nq;
        if let Some(hook) = self.progress.as_mut() {
            self.calls += 1;
            if self.calls % PROGRESS_EVERY == 0 && !hook(t) {
                return Err("interrupted".into());
            }
        }
        let (q, v) = y.split_at(nq);
        let (qdot, vdot) = dydt.split_at_mut(nq);
        self.model.velocity_to_qdot(q, v, qdot);
        self.accelerations(t, q, v, vdot)
    }

    /// Unit quaternions; the right-hand side normalises them too, so FSAL stays valid.
    fn project(&mut self, y: &mut [f64]) {
        self.model.normalize(&mut y[..self.model.nq]);
    }
}

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
    /// Output names of the enabled effects (the columns of `power`).
    pub effect_labels: Vec<String>,
    /// Row-major N × effect_labels.len().
    pub power: Option<Vec<f64>>,
    pub t_events: Vec<Vec<f64>>,
    /// Per event, row-major states `[q; v]` at the event times.
    pub y_events: Vec<Vec<f64>>,
    pub nfev: usize,
    pub n_accepted: usize,
    pub n_rejected: usize,
    pub status: Status,
    pub message: String,
    pub t_reached: f64,
    pub success: bool,
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
    opts: &Rk45Options,
    state_events: &[StateEvent],
    extra_events: Vec<Event<'_>>,
    record: Record,
    progress: Option<Progress<'_>>,
) -> Result<Trajectory> {
    model.check_state(q0, Some(v0))?;
    let (nq, nv) = (model.nq, model.nv);
    for (k, e) in state_events.iter().enumerate() {
        let n = if e.on_velocity { nv } else { nq };
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
    let mut sys = Dynamics::try_new(model, effects, disabled)?;
    let mut y0 = Vec::with_capacity(nq + nv);
    y0.extend_from_slice(q0);
    y0.extend_from_slice(v0);
    model.normalize(&mut y0[..nq]);

    let mut events: Vec<Event<'_>> = state_events
        .iter()
        .map(|e| {
            let offset = if e.on_velocity { nq } else { 0 } + e.index;
            let value = e.value;
            Event::new(move |_t, y: &[f64]| y[offset] - value)
                .direction(integrator::EventDirection::from_sign(e.direction as f64))
                .terminal(e.terminal)
        })
        .collect();
    events.extend(extra_events);
    // Euler-angle joints: a terminal event where sin θ changes sign, located on the dense
    // output, stops the run at the singularity even when a loose tolerance would step over
    // it, and long before the integrator crawls towards it with ever smaller steps.
    let n_user = events.len();
    let guarded: Vec<usize> = (0..model.links.len())
        .filter(|&i| matches!(model.links[i].joint, crate::joint::Joint::SphericalZYZ))
        .collect();
    for &i in &guarded {
        let theta = model.links[i].q_index + 1;
        events.push(Event::new(move |_t, y: &[f64]| y[theta].sin()).terminal(1));
    }

    sys.progress = progress;
    let mut sol =
        integrator::rk45(&mut sys, t_span, &y0, opts, &mut events).map_err(|e| match e {
            integrator::InputError::OutputTooLarge { bytes, .. } => Error::OutOfMemory {
                what: "simulate".into(),
                bytes,
                detail: e.to_string(),
            },
            e => Error::InvalidSetting(e.to_string()),
        })?;
    drop(events);
    if let Status::TerminalEvent { event, t } = sol.status {
        if event >= n_user {
            let link = guarded[event - n_user];
            let name = &model.bodies[model.links[link].body].name;
            let message = format!(
                "SphericalZYZ joint of body '{name}' reached its Euler singularity (sin theta = 0) at t = {t}: the Euler-angle rates diverge there; model the joint as Spherical (a quaternion) to move through it"
            );
            sol.message = format!("{message}; integration stopped at t = {t}");
            sol.status = Status::RhsError { t, at: t, message };
        }
    }
    sol.t_events.truncate(n_user);
    sol.y_events.truncate(n_user);
    let n = sol.t.len();
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
    let row = |i: usize, m: usize| i * m..(i + 1) * m;
    let energy = record.energy.then(|| {
        (0..n)
            .map(|i| sys.energy(&q[row(i, nq)], &v[row(i, nv)]))
            .collect()
    });
    let labels = sys.effects.labels();
    let power = if record.power {
        let m = labels.len();
        let mut out = vec![0.0; n * m];
        let mut scratch = vec![0.0; m * nv];
        for i in 0..n {
            sys.effect_power(
                sol.t[i],
                &q[row(i, nq)],
                &v[row(i, nv)],
                &mut scratch,
                &mut out[i * m..(i + 1) * m],
            )
            .map_err(|e| Error::InvalidSetting(format!("power at t = {}: {e}", sol.t[i])))?;
        }
        Some(out)
    } else {
        None
    };
    Ok(Trajectory {
        nq,
        nv,
        success: sol.status.is_success(),
        t: sol.t,
        q,
        v,
        energy,
        effect_labels: labels,
        power,
        t_events: sol.t_events,
        y_events: sol.y_events,
        nfev: sol.nfev,
        n_accepted: sol.n_accepted,
        n_rejected: sol.n_rejected,
        message: sol.message,
        t_reached: sol.t_reached,
        status: sol.status,
    })
}
