//! `simulate_scene`, `effect_forces` and `energies`: runs and evaluations of a scene.
use crate::python::Obj;
use std::sync::Mutex;

use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict};

use super::convert::to_array1;
use super::effects::take_callback_error;
use super::errors::{interrupt_reason, to_py, IntoPyResult};
use super::events::{event_list, python_events};
use super::run_config::{call_config, PyRunConfig};
use super::scene::PyScene;
use super::signals::{Watch, INTERVAL};
use super::trajectory::PyRunResult;
use crate::io::scene::Scene;
use crate::simulate::batch::{batch_results, run_scenes, BatchArgs};
use crate::simulate::{at_state, run_scene, Progress};

// Docstrings of the run calls: `_core.pyi`; the public ones: `pointmass_dyn.simulate`,
// `simulate_batch`, `effect_forces`, `energies`, which wrap them.
#[pyfunction]
#[pyo3(signature = (scene, t_span=None, rtol=None, atol=None, *, config=None, events=None, progress=None, progress_interval=None, **settings))]
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
    let config = call_config(config, t_span, rtol, atol, settings)?;
    let interval = crate::simulate::config_args::progress_interval(progress_interval).py(py)?;
    let mut watch = interval.map_or_else(Watch::default, Watch::every);
    let events = event_list(py, events)?;
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    take_callback_error();
    let result = py.detach(|| {
        let extra = python_events(&events, Some(s.model.nq), &failure);
        // Ctrl-C and progress by elapsed time (support::pacing), not per evaluation, so a
        // busy Python thread beside the run costs one hand-over of the interpreter per poll.
        let hook: Progress<'_> = Box::new(|t: f64| watch.poll(|py| report(py, &progress, (t,))));
        run_scene(s, config, &events.state, extra, Some(hook))
    });
    // A Python callback that raised (or Ctrl-C) ends the run; its exception is re-raised by
    // `pointmass_dyn.simulate` with the trajectory computed so far attached.
    let raised = take_callback_error()
        .or(failure.into_inner().ok().flatten())
        .or(watch.error.take());
    let traj = match result {
        Err(e) => return Err(raised.unwrap_or_else(|| to_py(py, e))),
        Ok(traj) => traj,
    };
    let stopped = raised.as_ref().map(|e| interrupt_reason(py, e));
    let traj = traj.finished(stopped.as_deref(), &events.slots());
    Ok(PyRunResult::new(py, traj, raised))
}

/// Calls the caller's `progress(*args)`, if given.
fn report<'py>(
    py: Python<'py>,
    progress: &Option<Py<PyAny>>,
    args: impl pyo3::call::PyCallArgs<'py>,
) -> PyResult<()> {
    progress
        .as_ref()
        .map_or(Ok(()), |cb| cb.bind(py).call1(args).map(|_| ()))
}

/// `f`'s result, or the exception a Python callback (a torque function) raised inside it,
/// which wins.
pub(super) fn callbacks<T>(
    py: Python<'_>,
    f: impl FnOnce() -> crate::support::error::Result<T>,
) -> PyResult<T> {
    take_callback_error();
    let r = f();
    take_callback_error().map_or_else(|| r.py(py), Err)
}

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
    let forces = || Ok(at_state::effect_forces(&scene.inner, t, (q, v), disable));
    let forces = callbacks(py, forces)??.into_iter();
    forces.map(|(l, f)| (l, to_array1(py, &f))).into_py_dict(py)
}

#[pyfunction]
#[pyo3(signature = (scene, q, v, disable=None))]
pub fn energies<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    q: &Obj,
    v: &Obj,
    disable: Option<&Obj>,
) -> PyResult<Bound<'py, PyDict>> {
    at_state::energies(&scene.inner, (q, v), disable)?.into_py_dict(py)
}

#[pyfunction]
#[pyo3(signature = (scenes, q0=None, v0=None, t_span=None, rtol=None, atol=None, *, config=None, events=None, threads=None, progress=None, **settings))]
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
    let scenes: Vec<Scene> = scenes.iter().map(|s| s.inner.clone()).collect();
    let config = call_config(config, t_span, rtol, atol, settings)?;
    let batch = BatchArgs::new(q0, v0, threads)?;
    let events = event_list(py, events)?.for_run(true, true)?;
    // Ctrl-C and the caller's progress from this thread, by elapsed time (signals::Watch).
    let mut watch = Watch::default();
    let poll = |done, n| watch.poll(|py| report(py, &progress, (done, n)));
    take_callback_error();
    let run = || run_scenes(&scenes, &config, batch, &events.state, INTERVAL, poll);
    let results = py.detach(run).py(py)?;
    // Ctrl-C or a raising `progress` stopped the batch: the caller gets it back with every
    // run's result so far (finished, stopped midway, not started).
    let mut stopped = watch.error.take().or(take_callback_error());
    // A last report at the end, so a caller's progress bar always reaches B.
    if stopped.is_none() {
        stopped = report(py, &progress, (results.len(), results.len())).err();
    }
    // Only state events (`for_run`): the caller's order already. A run never started comes
    // with its error: its input refused, or the batch stopped before it.
    let reason = stopped.as_ref().map(|e| interrupt_reason(py, e));
    let out = batch_results(results, reason.as_deref()).into_iter();
    let out = out.map(|(traj, e)| PyRunResult::new(py, traj, e.map(|e| to_py(py, e))));
    Ok((out.collect(), stopped.map(|e| e.into_value(py).into_any())))
}
