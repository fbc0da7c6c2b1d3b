//! `simulate_scene`, `effect_forces` and `energies`: runs and evaluations of a scene.
use crate::python::Obj;
use std::sync::Mutex;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{real, to_array1, vector};
use super::effects::take_callback_error;
use super::errors::{check_result, interrupt_reason, invalid, py_error, IntoPyResult};
use super::events::{event_spec, python_event, PyEventSpec, PyStateEvent};
use super::run_config::{call_config, PyRunConfig};
use super::scene::PyScene;
use super::signals::{Watch, INTERVAL};
use super::trajectory::PyRunResult;
use crate::integrator::Event;
use crate::io::scene::Scene;
use crate::simulate::batch::StateRows;
use crate::simulate::{run_scene, Dynamics, EventList, Progress};
use crate::support::args::given;

/// Runs a scene as its `config` says, the keywords given here (`RunConfig`'s) beating
/// it: the `RunResult` that `pointmass_dyn.simulate` wraps.
#[pyfunction]
#[pyo3(signature = (scene, t_span=None, rtol=None, atol=None, *, config=None, events=None, progress=None, progress_interval=None, **settings))]
#[allow(clippy::too_many_arguments)]
pub fn simulate_scene(
    py: Python<'_>,
    scene: PyRef<'_, PyScene>,
    t_span: Option<&Obj>,
    rtol: Option<&Obj>,
    atol: Option<&Obj>,
    config: Option<PyRef<'_, PyRunConfig>>,
    events: Option<&Obj>,
    progress: Option<Py<PyAny>>,
    progress_interval: Option<f64>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyRunResult> {
    let s = &scene.inner;
    let nq = s.model.nq;
    let config = call_config(config, t_span, rtol, atol, settings)?;
    let mut watch = watch_arg(py, progress_interval)?;
    let events = scene_events(py, events)?;
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    take_callback_error();
    let result = py.detach(|| {
        let extra: Vec<Event<'_>> = events
            .other
            .iter()
            .map(|spec| python_event(spec, Some(nq), &failure))
            .collect();
        // Ctrl-C and progress by elapsed time (signals::INTERVAL), not per evaluation, so a
        // busy Python thread beside the run costs one hand-over of the interpreter per poll.
        let hook: Progress<'_> = Box::new(|t: f64| {
            watch.poll(|py| match &progress {
                Some(cb) => cb.bind(py).call1((t,)).map(|_| ()),
                None => Ok(()),
            })
        });
        run_scene(s, config, &events.state, extra, Some(hook))
    });
    // A Python callback that raised (or Ctrl-C) ends the run; its exception is re-raised by
    // `pointmass_dyn.simulate` with the trajectory computed so far attached.
    let raised = take_callback_error()
        .or(failure.into_inner().ok().flatten())
        .or(watch.error.take());
    match (result, raised) {
        (Ok(mut traj), raised) => {
            if let Some(e) = &raised {
                traj.name_interruption(&interrupt_reason(py, e));
            }
            PyRunResult::new(py, traj, &events.slots(), raised)
        }
        (Err(_), Some(raised)) => Err(raised),
        (Err(e), None) => Err(super::errors::to_py(py, e)),
    }
}

/// `progress_interval`: seconds between progress calls (`None`: the default).
fn watch_arg(py: Python<'_>, progress_interval: Option<f64>) -> PyResult<Watch> {
    match progress_interval {
        None => Ok(Watch::default()),
        Some(x) if (0.0..=3600.0).contains(&x) => {
            Ok(Watch::every(std::time::Duration::from_secs_f64(x)))
        }
        Some(x) => Err(invalid(
            py,
            "progress_interval",
            "seconds between progress calls, 0 to 3600",
            x,
        )),
    }
}

/// A run's events: `StateEvent`s (evaluated in Rust) and Python callables, in the
/// caller's order (the core's `EventList`).
type SceneEvents = EventList<PyEventSpec>;

fn scene_events(py: Python<'_>, events: Option<&Obj>) -> PyResult<SceneEvents> {
    let mut out = SceneEvents::default();
    if let Some(evs) = events.filter(|e| !e.is_none()) {
        for (k, e) in evs.try_iter()?.enumerate() {
            let e = e?;
            match e.cast::<PyStateEvent>() {
                Ok(se) => out.push_state(se.get().inner.clone()),
                Err(_) => out.push_other(event_spec(py, k, &e)?),
            }
        }
    }
    Ok(out)
}

/// The scene's equations of motion with the `disable`d families (the caller's, else the
/// scene's) left out.
pub(super) fn scene_system<'s>(
    py: Python<'_>,
    s: &'s Scene,
    disable: Option<&Obj>,
) -> PyResult<Dynamics<'s>> {
    let disabled = crate::simulate::disabled(crate::effects::args::disable(disable)?, &s.settings);
    Dynamics::try_new(&s.model, &s.effects, disabled).py(py)
}

/// A finite time `t`.
pub(super) fn time_arg(py: Python<'_>, t: f64) -> PyResult<f64> {
    match t.is_finite() {
        true => Ok(t),
        false => Err(invalid(py, "t", "a finite time", t)),
    }
}

/// `(q, v)` checked against the scene's model.
pub(super) fn scene_state(
    py: Python<'_>,
    s: &Scene,
    q: &Obj,
    v: &Obj,
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
    t: &Obj,
    q: &Obj,
    v: &Obj,
    disable: Option<&Obj>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = &scene.inner;
    let t = time_arg(py, real(t, "t")?)?;
    let (q, v) = scene_state(py, s, q, v)?;
    let mut sys = scene_system(py, s, disable)?;
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
    q: &Obj,
    v: &Obj,
    disable: Option<&Obj>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = &scene.inner;
    let (q, v) = scene_state(py, s, q, v)?;
    let mut sys = scene_system(py, s, disable)?;
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

/// Runs many scenes (or one scene from many initial states) on a pool of threads, the GIL
/// released once: a `RunResult` per run as `simulate_scene` returns them, in the runs'
/// order. A run that could not start (bad input) is `NotStarted`, its exception in `error`. Every run is
/// exactly the `simulate` call it stands for.
#[pyfunction]
#[pyo3(signature = (scenes, q0=None, v0=None, t_span=None, rtol=None, atol=None, *, config=None, events=None, threads=None, progress=None, **settings))]
#[allow(clippy::too_many_arguments)]
pub fn simulate_batch<'py>(
    py: Python<'py>,
    scenes: Vec<PyRef<'_, PyScene>>,
    q0: Option<&Obj>,
    v0: Option<&Obj>,
    t_span: Option<&Obj>,
    rtol: Option<&Obj>,
    atol: Option<&Obj>,
    config: Option<PyRef<'_, PyRunConfig>>,
    events: Option<&Obj>,
    threads: Option<&Obj>,
    progress: Option<Py<PyAny>>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<(Vec<PyRunResult>, Option<Py<PyAny>>)> {
    use crate::simulate::batch::{broadcast, run_batch_polled};
    if scenes.is_empty() {
        return Err(invalid(py, "scenes", "at least one Scene", "none"));
    }
    let scenes: Vec<Scene> = scenes.iter().map(|s| s.inner.clone()).collect();
    let config = call_config(config, t_span, rtol, atol, settings)?;
    let q0s = batch_states("q0", q0, scenes[0].model.nq)?;
    let v0s = batch_states("v0", v0, scenes[0].model.nv)?;
    let events = scene_events(py, events)?;
    if !events.other.is_empty() {
        return Err(invalid(
            py,
            "events",
            "StateEvent objects only (Python callables cannot run on the batch's threads)",
            "a callable",
        ));
    }
    let threads = crate::support::args::threads(threads)?;
    // Settings per scene (each resolves the caller's against its own file's).
    let resolved = scenes
        .iter()
        .map(|s| {
            let dim = s.model.nq + s.model.nv;
            config.clone().resolve(&s.settings, &s.effects, dim)
        })
        .collect::<crate::support::error::Result<Vec<_>>>()
        .py(py)?;
    let runs = broadcast(&scenes, &resolved, q0s.as_ref(), v0s.as_ref()).py(py)?;
    let count = runs.len();
    // The record is the caller's alone (no scene file sets one).
    let record = resolved[0].record;
    // Ctrl-C and the caller's progress from this thread, by elapsed time (signals::Watch).
    let mut watch = Watch::default();
    take_callback_error();
    let results = py.detach(|| {
        run_batch_polled(&runs, &events.state, record, threads, INTERVAL, |done| {
            watch.poll(|py| match &progress {
                Some(cb) => cb.bind(py).call1((done, count)).map(|_| ()),
                None => Ok(()),
            })
        })
    });
    // Ctrl-C or a raising `progress` stopped the batch: the caller gets it back with every
    // run's result so far (finished, stopped midway, not started).
    let mut stopped = watch.error.take().or(take_callback_error());
    // A last report at the end, so a caller's progress bar always reaches B.
    if let (None, Some(cb)) = (&stopped, &progress) {
        if let Err(e) = cb.bind(py).call1((count, count)) {
            stopped = Some(e);
        }
    }
    let results = results
        .map_err(|_| py_error(py, "SimulationError", "a batch thread panicked".to_string()))?;
    let reason = stopped.as_ref().map(|e| interrupt_reason(py, e));
    let slots = events.slots();
    let mut out = Vec::with_capacity(results.len());
    for result in results {
        out.push(match result {
            Ok(mut traj) => {
                if let Some(r) = &reason {
                    traj.name_interruption(r);
                }
                PyRunResult::new(py, traj, &slots, None)?
            }
            Err(e) => {
                let why = match (&e, &reason) {
                    (crate::support::error::Error::Interrupted(_), Some(r)) => Some(format!(
                        "the batch was stopped before this run started, by {r}"
                    )),
                    _ => None,
                };
                PyRunResult::not_started(py, super::errors::to_py(py, e), why)?
            }
        });
    }
    Ok((out, stopped.map(|e| e.into_value(py).into_any())))
}

/// Per-run initial states: one (1-D) for every run, or a row per run (2-D `(B, width)`).
fn batch_states(arg: &str, obj: Option<&Obj>, width: usize) -> PyResult<Option<StateRows>> {
    let Some(obj) = given(obj) else {
        return Ok(None);
    };
    let (shape, data) = super::convert::array(obj, arg)?;
    StateRows::new(arg, &shape, data, width)
        .py(obj.py())
        .map(Some)
}
