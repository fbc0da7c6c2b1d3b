//! `simulate_scene`, `effect_forces` and `energies`: runs and evaluations of a scene.
use crate::python::Obj;
use std::sync::Mutex;

use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict};

use super::convert::to_array1;
use super::effects::take_callback_error;
use super::errors::{interrupt_reason, IntoPyResult};
use super::events::{event_list, python_events};
use super::run_config::{call_config, PyRunConfig};
use super::scene::PyScene;
use super::signals::{Watch, INTERVAL};
use super::trajectory::PyRunResult;
use crate::io::scene::Scene;
use crate::simulate::batch::{name_stop, run_scenes};
use crate::simulate::{at_state, run_scene, Progress};
use crate::support::args::given;
use crate::support::error::Error;

/// Runs a scene as its `config` says, the keywords given here (`RunConfig`'s) beating
/// it: the `RunResult` that `pointmass_dyn.simulate` wraps.
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
    let nq = s.model.nq;
    let config = call_config(config, t_span, rtol, atol, settings)?;
    let interval = crate::simulate::config_args::progress_interval(progress_interval).py(py)?;
    let mut watch = interval.map_or_else(Watch::default, Watch::every);
    let events = event_list(py, events)?;
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    take_callback_error();
    let result = py.detach(|| {
        let extra = python_events(&events, Some(nq), &failure);
        // Ctrl-C and progress by elapsed time (support::pacing), not per evaluation, so a
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
            Ok(PyRunResult::new(py, traj, &events.slots(), raised))
        }
        (Err(_), Some(raised)) => Err(raised),
        (Err(e), None) => Err(super::errors::to_py(py, e)),
    }
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
    let forces = callbacks(py, || {
        Ok(at_state::effect_forces(&scene.inner, t, (q, v), disable))
    })??;
    let forces = forces
        .into_iter()
        .map(|(l, f): (String, Vec<f64>)| (l, to_array1(py, &f)));
    forces.into_py_dict(py)
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
    at_state::energies(&scene.inner, (q, v), disable)?.into_py_dict(py)
}

/// Runs many scenes (or one scene from many initial states) on a pool of threads, the GIL
/// released once: a `RunResult` per run as `simulate_scene` returns them, in the runs'
/// order. A run that could not start (bad input) is `NotStarted`, its exception in `error`. Every run is
/// exactly the `simulate` call it stands for.
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
    let states = |x: Option<&Obj>, arg| given(x).map(|x| super::convert::array(x, arg));
    let (q0, v0) = (states(q0, "q0").transpose()?, states(v0, "v0").transpose()?);
    let events = event_list(py, events)?.for_run(true, true)?;
    let threads = crate::support::args::threads(threads)?;
    // Ctrl-C and the caller's progress from this thread, by elapsed time (signals::Watch).
    let mut watch = Watch::default();
    take_callback_error();
    let results = py.detach(|| {
        let state = &events.state;
        run_scenes(
            &scenes,
            &config,
            q0,
            v0,
            state,
            threads,
            INTERVAL,
            |done, n| {
                watch.poll(|py| match &progress {
                    Some(cb) => cb.bind(py).call1((done, n)).map(|_| ()),
                    None => Ok(()),
                })
            },
        )
    });
    let results = results.py(py)?;
    let panicked = |_| Error::Simulation("a batch thread panicked".into());
    let mut results = results.map_err(panicked).py(py)?;
    // Ctrl-C or a raising `progress` stopped the batch: the caller gets it back with every
    // run's result so far (finished, stopped midway, not started).
    let mut stopped = watch.error.take().or(take_callback_error());
    // A last report at the end, so a caller's progress bar always reaches B.
    let count = results.len();
    if let (None, Some(cb)) = (&stopped, &progress) {
        stopped = cb.bind(py).call1((count, count)).err();
    }
    if let Some(e) = &stopped {
        name_stop(&mut results, &interrupt_reason(py, e));
    }
    let slots = events.slots();
    let out = results.into_iter().map(|result| match result {
        Ok(traj) => PyRunResult::new(py, traj, &slots, None),
        Err(e) => PyRunResult::not_started(py, e),
    });
    Ok((out.collect(), stopped.map(|e| e.into_value(py).into_any())))
}
