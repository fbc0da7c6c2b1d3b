//! Events: `StateEvent` (evaluated in Rust) and Python event callables (SciPy's convention).
use crate::python::Obj;
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::prelude::*;

use super::effects::repr_of;
use super::errors::invalid;
use crate::integrator::{Event, EventDirection};
use crate::simulate::config_args::EventFunction;
use crate::simulate::StateEvent;
use crate::simulate::{event_value, CallerEvent, EventList};

/// `q[index]` (or `v[index]`) crossing `value`; evaluated in Rust, no GIL needed.
#[pyclass(
    name = "StateEvent",
    module = "pointmass_dyn._core",
    frozen,
    from_py_object
)]
#[derive(Clone)]
pub struct PyStateEvent {
    pub inner: StateEvent,
}

#[pymethods]
impl PyStateEvent {
    #[new]
    #[pyo3(signature = (variable, index, value=None, direction=None, terminal=None))]
    fn new(
        variable: &str,
        index: &Obj,
        value: Option<&Obj>,
        direction: Option<&Obj>,
        terminal: Option<&Obj>,
    ) -> PyResult<Self> {
        let inner = StateEvent::from_args(variable, index, value, direction, terminal)?;
        Ok(PyStateEvent { inner })
    }
    fn __repr__(&self) -> String {
        self.inner.to_string()
    }
}

super::getters!(PyStateEvent {
    terminal: usize = inner.terminal,
    direction: i32 = inner.direction,
});

/// A Python event callable: `(args...) -> float`, and how it counts.
pub(super) struct PyEventSpec {
    func: Py<PyAny>,
    counts: EventFunction,
}

fn event_spec(py: Python<'_>, k: usize, e: &Obj) -> PyResult<PyEventSpec> {
    if !e.is_callable() {
        let expected = "a callable or a pmd.StateEvent";
        return Err(invalid(py, &format!("events[{k}]"), expected, repr_of(e)));
    }
    let (func, counts) = (e.clone().unbind(), EventFunction::from_args(k, e)?);
    Ok(PyEventSpec { func, counts })
}

/// A run's events in the caller's order (the core's `EventList`): `None`, one event
/// callable, or a sequence of callables and `StateEvent`s (evaluated in Rust).
pub(super) fn event_list(py: Python<'_>, events: Option<&Obj>) -> PyResult<EventList<PyEventSpec>> {
    let read = |k, e: &Obj| match e.cast::<PyStateEvent>() {
        Ok(se) => Ok(CallerEvent::State(se.get().inner.clone())),
        Err(_) => event_spec(py, k, e).map(CallerEvent::Other),
    };
    EventList::from_arg(events, |e| e.is_callable(), read)
}

/// The caller's event callables as a run's events, each calling Python (re-attaching to
/// the interpreter when called from a detached thread) with `(t, q, v)` (`split`: the
/// state's `nq`) or `(t, y)`; the first exception is kept in `failure` and re-raised after.
pub(super) fn python_events<'a>(
    events: &'a EventList<PyEventSpec>,
    split: Option<usize>,
    failure: &'a Mutex<Option<PyErr>>,
) -> Vec<Event<'a>> {
    let event = |spec: &'a PyEventSpec| {
        let f = move |t: f64, y_all: &[f64]| -> f64 {
            Python::attach(|py| {
                let y = |y: &[f64]| PyArray1::from_slice(py, y).into_any();
                let args = match split {
                    Some(nq) => (t, y(&y_all[..nq]), y(&y_all[nq..])).into_pyobject(py),
                    None => (t, y(y_all)).into_pyobject(py),
                };
                let out = args.and_then(|a| spec.func.bind(py).call1(a));
                let out = out.and_then(|r| event_value(spec.counts.index, t, &r));
                out.unwrap_or_else(|e| {
                    keep(failure, e);
                    f64::NAN
                })
            })
        };
        Event::new(f)
            .direction(EventDirection::from_sign(spec.counts.direction))
            .terminal(spec.counts.terminal)
    };
    events.other.iter().map(event).collect()
}

/// Keeps `e` in `failure` unless an earlier exception is there (the first one stops the
/// run); its message, for the run's.
pub(super) fn keep(failure: &Mutex<Option<PyErr>>, e: PyErr) -> String {
    let message = e.to_string();
    if let Ok(mut slot) = failure.lock() {
        slot.get_or_insert(e);
    }
    message
}
