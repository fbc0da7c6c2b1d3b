//! Events: `StateEvent` (evaluated in Rust) and Python event callables (SciPy's convention).
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use super::convert::{count_arg, int_arg, opt_real, real};
use super::effects::repr_of;
use super::errors::{invalid, py_error};
use crate::integrator::{Event, EventDirection};
use crate::simulate::StateEvent;

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

pub(super) fn terminal_count(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    if let Ok(b) = obj.cast::<pyo3::types::PyBool>() {
        return Ok(b.is_true() as usize);
    }
    match obj.extract::<i64>() {
        Ok(n) if n >= 0 => Ok(n as usize),
        _ => Err(invalid(
            py,
            "terminal",
            "a bool or a count >= 0",
            repr_of(obj),
        )),
    }
}

#[pymethods]
impl PyStateEvent {
    #[new]
    #[pyo3(signature = (variable, index, value=None, direction=None, terminal=None))]
    fn new(
        py: Python<'_>,
        variable: &str,
        index: &Bound<'_, PyAny>,
        value: Option<&Bound<'_, PyAny>>,
        direction: Option<&Bound<'_, PyAny>>,
        terminal: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let index = count_arg(index, "index", "a coordinate index >= 0")?;
        let value = opt_real(value, "value")?.unwrap_or(0.0);
        let direction = match direction.filter(|d| !d.is_none()) {
            None => 0,
            Some(d) => int_arg(d, "direction", i64::MIN, i64::MAX, "-1, 0 or 1")?.signum() as i32,
        };
        let on_velocity = match variable {
            "q" => false,
            "v" => true,
            other => return Err(invalid(py, "variable", "'q' or 'v'", format!("'{other}'"))),
        };
        if !value.is_finite() {
            return Err(invalid(py, "value", "a finite number", value));
        }
        let terminal = match terminal {
            Some(t) if !t.is_none() => terminal_count(py, t)?,
            _ => 0,
        };
        Ok(PyStateEvent {
            inner: StateEvent {
                on_velocity,
                index,
                value,
                direction: direction.signum(),
                terminal,
            },
        })
    }
    #[getter]
    fn terminal(&self) -> usize {
        self.inner.terminal
    }
    #[getter]
    fn direction(&self) -> i32 {
        self.inner.direction
    }
    fn __repr__(&self) -> String {
        let e = &self.inner;
        format!(
            "StateEvent('{}', {}, value={}, direction={}, terminal={})",
            if e.on_velocity { "v" } else { "q" },
            e.index,
            e.value,
            e.direction,
            e.terminal
        )
    }
}

/// A Python event callable: `(args...) -> float`, with optional `terminal` and `direction`
/// attributes (SciPy's convention).
pub(super) struct PyEventSpec {
    /// Position in the caller's `events` (named in errors).
    index: usize,
    func: Py<PyAny>,
    terminal: usize,
    direction: f64,
}

pub(super) fn event_spec(py: Python<'_>, k: usize, e: &Bound<'_, PyAny>) -> PyResult<PyEventSpec> {
    if !e.is_callable() {
        return Err(invalid(
            py,
            &format!("events[{k}]"),
            "a callable or a pmd.StateEvent",
            repr_of(e),
        ));
    }
    let terminal = match e.getattr("terminal") {
        Ok(t) if !t.is_none() => terminal_count(py, &t)?,
        _ => 0,
    };
    let direction = match e.getattr("direction") {
        Ok(d) if !d.is_none() => real(&d, &format!("events[{k}].direction"))?,
        _ => 0.0,
    };
    Ok(PyEventSpec {
        index: k,
        func: e.clone().unbind(),
        terminal,
        direction,
    })
}

/// Builds an event that calls Python (re-attaching to the interpreter when called from a
/// detached thread); the first exception is kept in `failure` and re-raised afterwards.
pub(super) fn python_event<'a>(
    spec: &'a PyEventSpec,
    split: Option<usize>,
    failure: &'a Mutex<Option<PyErr>>,
) -> Event<'a> {
    let f = move |t: f64, y: &[f64]| -> f64 {
        Python::attach(|py| {
            let args = match split {
                Some(nq) => PyTuple::new(
                    py,
                    [
                        t.into_pyobject(py).map(|x| x.into_any()),
                        Ok(PyArray1::from_slice(py, &y[..nq]).into_any()),
                        Ok(PyArray1::from_slice(py, &y[nq..]).into_any()),
                    ]
                    .into_iter()
                    .collect::<Result<Vec<_>, _>>()
                    .unwrap_or_default(),
                ),
                None => PyTuple::new(
                    py,
                    [
                        t.into_pyobject(py).map(|x| x.into_any()),
                        Ok(PyArray1::from_slice(py, y).into_any()),
                    ]
                    .into_iter()
                    .collect::<Result<Vec<_>, _>>()
                    .unwrap_or_default(),
                ),
            };
            // A non-number or NaN would silently hide the event: an error naming it.
            let name = format!("events[{}]", spec.index);
            let out = args
                .and_then(|a| spec.func.bind(py).call1(a))
                .and_then(|r| {
                    real(&r, &name).map_err(|_| {
                        invalid(
                            py,
                            &name,
                            "an event function returning a real number",
                            format!("{} at t = {t}", repr_of(&r)),
                        )
                    })
                })
                .and_then(|x| {
                    if x.is_nan() {
                        Err(py_error(
                            py,
                            "NumericalError",
                            format!("{name}: the event function returned NaN at t = {t}"),
                        ))
                    } else {
                        Ok(x)
                    }
                });
            match out {
                Ok(x) => x,
                Err(e) => {
                    if let Ok(mut slot) = failure.lock() {
                        slot.get_or_insert(e);
                    }
                    f64::NAN
                }
            }
        })
    };
    Event::new(f)
        .direction(EventDirection::from_sign(spec.direction))
        .terminal(spec.terminal)
}
