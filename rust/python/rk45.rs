//! `rk45` (`solve_ivp`): our integrators (RK45 by default) on a Python right-hand side.
use crate::python::Obj;
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict, PyList};

use super::convert::{to_array, to_array1, vector};
use super::dense::PyDenseSolution;
use super::effects::repr_of;
use super::errors::IntoPyResult;
use super::errors::{invalid, py_error};
use super::events::{event_spec, python_event, PyEventSpec};
use super::jac::{jac_arg, JacArg, WithJacobian};
use super::run_config::{call_config, PyRunConfig};
use crate::integrator::{self, Event, FnSystem, OdeSystem};
use crate::io::scene::Settings;

/// Our integrators on a Python right-hand side `fun(t, y) -> array`: `method` "RK45"
/// (default) and "DOP853" step for step SciPy's `solve_ivp`, "RK4"/"Euler" at the fixed `dt`.
#[pyfunction]
#[pyo3(signature = (fun, t_span, y0, rtol=None, atol=None, *, config=None, events=None, jac=None, **settings))]
#[allow(clippy::too_many_arguments)]
pub fn rk45(
    py: Python<'_>,
    fun: &Obj,
    t_span: &Obj,
    y0: &Obj,
    rtol: Option<&Obj>,
    atol: Option<&Obj>,
    config: Option<PyRef<'_, PyRunConfig>>,
    events: Option<&Obj>,
    jac: Option<&Obj>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyOdeSolution> {
    if !fun.is_callable() {
        return Err(invalid(
            py,
            "fun",
            "a callable fun(t, y) -> array",
            repr_of(fun),
        ));
    }
    let t_span_given = crate::simulate::config_args::t_span(t_span)?;
    let y0 = vector(y0, "y0", None)?;
    let dim = y0.len();
    // No scene: the caller's settings, else the defaults.
    let run = call_config(config, Some(t_span), rtol, atol, settings)?
        .resolve(&Settings::default(), &[], dim)
        .py(py)?;
    let (t_span, opts) = (t_span_given, run.opts);
    let jac = jac_arg(py, jac, dim, opts.method, (t_span.0, &y0))?;
    let specs = event_specs(py, events)?;
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    let mut evs: Vec<Event<'_>> = specs
        .iter()
        .map(|s| python_event(s, None, &failure))
        .collect();
    let rhs_failure: Mutex<Option<PyErr>> = Mutex::new(None);
    let sys = python_system(py, fun, dim, &rhs_failure);
    // The method is the core's choice (`solve_with_jacobian`); a callable `jac` is Python's.
    let sol = match jac {
        JacArg::Callable(f) => {
            let with = WithJacobian {
                inner: sys,
                jac: f,
                failure: &rhs_failure,
            };
            integrator::solve(with, t_span, &y0, &opts, &mut evs)
        }
        JacArg::Constant(m) => {
            integrator::solve_with_jacobian(sys, t_span, &y0, &opts, &mut evs, Some(m))
        }
        JacArg::None => integrator::solve_with_jacobian(sys, t_span, &y0, &opts, &mut evs, None),
    }
    .map_err(|e| invalid_setting(py, e))?;
    drop(evs);
    // An exception from `fun` or an event (Ctrl-C included) is re-raised by
    // `pointmass_dyn.rk45` with the solution computed so far attached.
    let raised = rhs_failure
        .into_inner()
        .ok()
        .flatten()
        .or(failure.into_inner().ok().flatten());
    solution(py, sol, raised, !specs.is_empty())
}

/// `None`, one event callable, or a sequence of them.
fn event_specs(py: Python<'_>, events: Option<&Obj>) -> PyResult<Vec<PyEventSpec>> {
    let mut specs = Vec::new();
    if let Some(evs) = events.filter(|e| !e.is_none()) {
        if evs.is_callable() {
            specs.push(event_spec(py, 0, evs)?);
        } else {
            for (k, e) in evs.try_iter()?.enumerate() {
                specs.push(event_spec(py, k, &e?)?);
            }
        }
    }
    Ok(specs)
}

/// `fun(t, y) -> array` as the system's right-hand side; its first exception is kept in
/// `failure` (the run stops with its message).
fn python_system<'a>(
    py: Python<'a>,
    fun: &'a Obj,
    dim: usize,
    failure: &'a Mutex<Option<PyErr>>,
) -> impl OdeSystem + 'a {
    FnSystem::new(
        dim,
        move |t: f64, y: &[f64], dydt: &mut [f64]| -> Result<(), String> {
            let mut call = || -> PyResult<()> {
                let out = fun.call1((t, PyArray1::from_slice(py, y)))?;
                let v = vector(&out, "fun(t, y)", Some(dim))?;
                dydt.copy_from_slice(&v);
                Ok(())
            };
            call().map_err(|e| {
                let msg = e.to_string();
                if let Ok(mut slot) = failure.lock() {
                    slot.get_or_insert(e);
                }
                msg
            })
        },
    )
}

/// `rk45`'s result: the entries of SciPy's `OdeResult` (`pointmass_dyn.OdeResult` is built
/// from them), `y` as (dim, N), the event lists `None` when no events were given; `error`
/// the exception a Python callable stopped the run with.
#[pyclass(name = "OdeSolution", module = "pointmass_dyn._core", frozen, get_all)]
pub struct PyOdeSolution {
    t: Py<PyAny>,
    y: Py<PyAny>,
    t_events: Option<Py<PyList>>,
    y_events: Option<Py<PyList>>,
    nfev: usize,
    njev: usize,
    nlu: usize,
    method: &'static str,
    switched_to: Option<&'static str>,
    t_switch: Option<f64>,
    n_accepted: usize,
    n_rejected: usize,
    /// SciPy's code: 0 end reached, 1 terminal event, -1 failure.
    status: i32,
    message: String,
    success: bool,
    t_reached: f64,
    /// `{"t", "h_lambda", "h", "lambda"}` of the first stiffness detection, if any.
    stiff: Option<Py<PyDict>>,
    sol: Option<Py<PyDenseSolution>>,
    error: Option<Py<PyAny>>,
}

super::indexable!(PyOdeSolution [
    "t", "y", "t_events", "y_events", "nfev", "njev", "nlu", "method", "switched_to", "t_switch",
    "n_accepted", "n_rejected", "status", "message", "success", "t_reached", "stiff", "sol", "error",
]);

fn solution(
    py: Python<'_>,
    sol: integrator::Solution,
    raised: Option<PyErr>,
    with_events: bool,
) -> PyResult<PyOdeSolution> {
    let (dim, n) = (sol.dim, sol.t.len());
    // (N, dim) rows to (dim, N), SciPy's layout.
    let y_t: Vec<f64> = (0..dim * n).map(|k| sol.y[(k % n) * dim + k / n]).collect();
    let (te, ye) = (PyList::empty(py), PyList::empty(py));
    for (times, ys) in sol.t_events.iter().zip(&sol.y_events) {
        te.append(to_array1(py, times))?;
        ye.append(to_array(py, ys.clone(), &[times.len(), dim])?)?;
    }
    let stiff = sol.stiffness.map(|s| {
        let entries = [
            ("t", s.t),
            ("h_lambda", s.h_lambda),
            ("h", s.h),
            ("lambda", s.lambda()),
        ];
        entries.into_py_dict(py).map(Bound::unbind)
    });
    let dense = sol
        .dense
        .map(|inner| Py::new(py, PyDenseSolution { inner }));
    Ok(PyOdeSolution {
        t: to_array1(py, &sol.t).into_any().unbind(),
        y: to_array(py, y_t, &[dim, n])?.unbind(),
        t_events: with_events.then(|| te.unbind()),
        y_events: with_events.then(|| ye.unbind()),
        nfev: sol.nfev,
        njev: sol.njev,
        nlu: sol.nlu,
        method: sol.method.name(),
        switched_to: sol.switched_to.map(|m| m.name()),
        t_switch: sol.t_switch,
        n_accepted: sol.n_accepted,
        n_rejected: sol.n_rejected,
        status: sol.status.code(),
        // Numbers in exponent form where `{}` wrote hundreds of digits (as our errors').
        message: crate::support::error::compact_numbers(&sol.message),
        success: sol.status.is_success(),
        t_reached: sol.t_reached,
        stiff: stiff.transpose()?,
        sol: dense.transpose()?,
        error: raised.map(|e| e.into_value(py).into_any()),
    })
}

pub(super) fn invalid_setting(py: Python<'_>, e: integrator::InputError) -> PyErr {
    let class = match e {
        integrator::InputError::OutputTooLarge { .. } => "OutOfMemoryError",
        _ => "InvalidInputError",
    };
    py_error(py, class, e.to_string())
}
