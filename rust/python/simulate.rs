//! `simulate_scene`, `effect_forces` and `energies`: runs and evaluations of a scene.
use std::sync::Mutex;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::convert::{real, to_array, to_array1, vector};
use super::effects::take_callback_error;
use super::errors::{check_result, invalid, py_error, IntoPyResult};
use super::events::{event_spec, python_event, PyStateEvent};
use super::options::{options, step_args, stiffness_arg, t_span_arg};
use super::scene::{disable_arg, PyScene};
use super::signals::Watch;
use crate::integrator::{Event, Tol};
use crate::scene::Scene;
use crate::simulate::{simulate, Dynamics, Record};

/// Runs a scene: returns a dict that `pointmass_dyn.simulate` wraps.
#[pyfunction]
#[pyo3(signature = (scene, t_span=None, rtol=None, atol=None, t_eval=None, events=None, first_step=None, max_step=None, max_steps=None, energy=false, controller="standard", progress=None, disable=None, power=false, stiffness="warn", progress_interval=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate_scene<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    t_span: Option<&Bound<'_, PyAny>>,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    t_eval: Option<&Bound<'_, PyAny>>,
    events: Option<&Bound<'_, PyAny>>,
    first_step: Option<&Bound<'_, PyAny>>,
    max_step: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
    energy: bool,
    controller: &str,
    progress: Option<Py<PyAny>>,
    disable: Option<&Bound<'_, PyAny>>,
    power: bool,
    stiffness: &str,
    progress_interval: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let (first_step, max_step, max_steps) = step_args(first_step, max_step, max_steps)?;
    let s = &scene.inner;
    let watch = match progress_interval {
        None => Watch::default(),
        Some(x) if (0.0..=3600.0).contains(&x) => {
            Watch::every(std::time::Duration::from_secs_f64(x))
        }
        Some(x) => {
            return Err(invalid(
                py,
                "progress_interval",
                "seconds between progress calls, 0 to 3600",
                x,
            ))
        }
    };
    let disabled = disable_arg(py, disable)?
        .or(s.settings.disable)
        .unwrap_or_default();
    let (nq, nv) = (s.model.nq, s.model.nv);
    let t_span = match t_span.filter(|t| !t.is_none()) {
        Some(t) => t_span_arg(py, t)?,
        None => s
            .settings
            .t_span
            .ok_or_else(|| invalid(py, "t_span", "(t0, t_end): the scene sets none", "None"))?,
    };
    let mut opts = options(
        py,
        nq + nv,
        rtol,
        atol,
        t_eval,
        first_step.or(s.settings.first_step),
        max_step.or(s.settings.max_step),
        max_steps.or(s.settings.max_steps),
        false,
        controller,
    )?;
    opts.stiffness = stiffness_arg(py, stiffness)?; // stiffness detection (integrator)
    if rtol.is_none_or(|r| r.is_none()) {
        if let Some(r) = s.settings.rtol {
            opts.rtol = Tol::Scalar(r);
        }
    }
    if atol.is_none_or(|a| a.is_none()) {
        if let Some(a) = s.settings.atol {
            opts.atol = Tol::Scalar(a);
        }
    }
    let mut state_events = Vec::new();
    let mut py_events = Vec::new();
    // Keep the caller's order: state events first in the result would surprise; record slots.
    let mut order = Vec::new();
    if let Some(evs) = events.filter(|e| !e.is_none()) {
        for (k, e) in evs.try_iter()?.enumerate() {
            let e = e?;
            if let Ok(se) = e.cast::<PyStateEvent>() {
                order.push((false, state_events.len()));
                state_events.push(se.get().inner.clone());
            } else {
                order.push((true, py_events.len()));
                py_events.push(event_spec(py, k, &e)?);
            }
        }
    }
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    let model = &s.model;
    let (q0, v0, effects) = (&s.q0, &s.v0, &s.effects);
    let mut watch = watch;
    take_callback_error();
    let result = py.detach(|| {
        let extra: Vec<Event<'_>> = py_events
            .iter()
            .map(|spec| python_event(spec, Some(nq), &failure))
            .collect();
        // Ctrl-C and progress by elapsed time (signals::INTERVAL), not per evaluation, so a
        // busy Python thread beside the run costs one hand-over of the interpreter per poll.
        let hook: crate::simulate::Progress<'_> = Box::new(|t: f64| {
            watch.poll(|py| match &progress {
                Some(cb) => cb.bind(py).call1((t,)).map(|_| ()),
                None => Ok(()),
            })
        });
        simulate(
            model,
            effects,
            disabled,
            q0,
            v0,
            t_span,
            &opts,
            &state_events,
            extra,
            Record { energy, power },
            Some(hook),
        )
    });
    // A Python callback that raised (or Ctrl-C) ends the run; its exception is re-raised by
    // `pointmass_dyn.simulate` with the trajectory computed so far attached.
    let raised = take_callback_error()
        .or(failure.into_inner().ok().flatten())
        .or(watch.error.take());
    let (traj, raised) = match (result, raised) {
        (Ok(traj), raised) => (traj, raised),
        (Err(_), Some(raised)) => return Err(raised),
        (Err(e), None) => return Err(super::errors::to_py(py, e)),
    };
    let n = traj.t.len();
    let d = PyDict::new(py);
    d.set_item("error", raised.map(|e| e.into_value(py)))?;
    d.set_item("t", to_array1(py, &traj.t))?;
    d.set_item("q", to_array(py, traj.q, &[n, nq])?)?;
    d.set_item("v", to_array(py, traj.v, &[n, nv])?)?;
    d.set_item("energy", traj.energy.map(|e| to_array1(py, &e).into_any()))?;
    match &traj.power {
        Some(p) => {
            let m = traj.effect_labels.len();
            let pd = PyDict::new(py);
            for (k, label) in traj.effect_labels.iter().enumerate() {
                let col: Vec<f64> = (0..n).map(|i| p[i * m + k]).collect();
                pd.set_item(label, to_array1(py, &col))?;
            }
            d.set_item("power", pd)?;
        }
        None => d.set_item("power", py.None())?,
    }
    // Events back in the caller's order: state events were evaluated first.
    let ns = state_events.len();
    let te = PyList::empty(py);
    let qe = PyList::empty(py);
    let ve = PyList::empty(py);
    for (is_py, k) in order {
        let slot = if is_py { ns + k } else { k };
        let times = &traj.t_events[slot];
        let ys = &traj.y_events[slot];
        te.append(to_array1(py, times))?;
        let m = times.len();
        let mut qs = Vec::with_capacity(m * nq);
        let mut vs = Vec::with_capacity(m * nv);
        for row in ys.chunks_exact(nq + nv) {
            qs.extend_from_slice(&row[..nq]);
            vs.extend_from_slice(&row[nq..]);
        }
        qe.append(to_array(py, qs, &[m, nq])?)?;
        ve.append(to_array(py, vs, &[m, nv])?)?;
    }
    d.set_item("t_events", te)?;
    d.set_item("q_events", qe)?;
    d.set_item("v_events", ve)?;
    d.set_item("nfev", traj.nfev)?;
    d.set_item("n_accepted", traj.n_accepted)?;
    d.set_item("n_rejected", traj.n_rejected)?;
    d.set_item("status", traj.status.code())?;
    d.set_item("message", traj.message)?;
    d.set_item("success", traj.success)?;
    d.set_item("t_reached", traj.t_reached)?;
    Ok(d)
}

/// `(q, v)` checked against the scene's model.
pub(super) fn scene_state(
    py: Python<'_>,
    s: &Scene,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
) -> PyResult<(Vec<f64>, Vec<f64>)> {
    let q = vector(q, "q", Some(s.model.nq))?;
    let v = vector(v, "v", Some(s.model.nv))?;
    s.model.check_state(&q, Some(&v)).py(py)?;
    Ok((q, v))
}

/// The generalized force of each enabled effect of `scene` at `(t, q, v)`: a dict from the
/// effect's name to an (nv,) array (gravity's included).
#[pyfunction]
#[pyo3(signature = (scene, t, q, v, disable=None))]
pub fn effect_forces<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    t: &Bound<'_, PyAny>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    disable: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = &scene.inner;
    let t = real(t, "t")?;
    if !t.is_finite() {
        return Err(invalid(py, "t", "a finite time", t));
    }
    let (q, v) = scene_state(py, s, q, v)?;
    let disabled = disable_arg(py, disable)?
        .or(s.settings.disable)
        .unwrap_or_default();
    let mut sys = Dynamics::try_new(&s.model, &s.effects, disabled).py(py)?;
    let nv = s.model.nv;
    let mut out = vec![0.0; sys.effects.len() * nv];
    take_callback_error();
    let r = sys.effect_forces(t, &q, &v, &mut out);
    if let Some(e) = take_callback_error() {
        return Err(e);
    }
    r.map_err(|m| py_error(py, "NumericalError", m))?;
    for (k, label) in sys.effects.labels().iter().enumerate() {
        check_result(
            py,
            &format!("effect_forces['{label}']"),
            &out[k * nv..(k + 1) * nv],
        )?;
    }
    let d = PyDict::new(py);
    for (k, label) in sys.effects.labels().iter().enumerate() {
        d.set_item(label, to_array1(py, &out[k * nv..(k + 1) * nv]))?;
    }
    Ok(d)
}

/// Kinetic energy, the potential energy of each enabled conservative effect (gravity,
/// springs) under its name, and their sum under `total`.
#[pyfunction]
#[pyo3(signature = (scene, q, v, disable=None))]
pub fn energies<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    disable: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = &scene.inner;
    let (q, v) = scene_state(py, s, q, v)?;
    let disabled = disable_arg(py, disable)?
        .or(s.settings.disable)
        .unwrap_or_default();
    let mut sys = Dynamics::try_new(&s.model, &s.effects, disabled).py(py)?;
    let (kinetic, potentials) = sys.energies(&q, &v);
    let d = PyDict::new(py);
    check_result(py, "energies['kinetic']", &[kinetic])?;
    d.set_item("kinetic", kinetic)?;
    let mut total = kinetic;
    for (label, e) in potentials {
        check_result(py, &format!("energies['{label}']"), &[e])?;
        total += e;
        d.set_item(label, e)?;
    }
    check_result(py, "energies['total']", &[total])?;
    d.set_item("total", total)?;
    Ok(d)
}
