//! `rk45` (`solve_ivp`): our integrators (RK45 by default) on a Python right-hand side.
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::convert::{to_array, to_array1, vector};
use super::dense::PyDenseSolution;
use super::effects::repr_of;
use super::errors::IntoPyResult;
use super::errors::{invalid, py_error};
use super::events::{event_spec, python_event, PyEventSpec};
use super::jac::{jac_arg, JacArg, WithJacobian};
use super::options::{set_method, set_outcome};
use super::run_config::{call_config, PyRunConfig};
use crate::integrator::{self, Event, FnSystem, OdeSystem};
use crate::io::scene::Settings;

/// Our integrators on a Python right-hand side `fun(t, y) -> array`: `method` "RK45"
/// (default) and "DOP853" step for step SciPy's `solve_ivp`, "RK4"/"Euler" at the fixed `dt`.
#[pyfunction]
#[pyo3(signature = (fun, t_span, y0, rtol=None, atol=None, *, config=None, events=None, jac=None, **settings))]
#[allow(clippy::too_many_arguments)]
pub fn rk45<'py>(
    py: Python<'py>,
    fun: &Bound<'_, PyAny>,
    t_span: &Bound<'_, PyAny>,
    y0: &Bound<'_, PyAny>,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    config: Option<PyRef<'_, PyRunConfig>>,
    events: Option<&Bound<'_, PyAny>>,
    jac: Option<&Bound<'_, PyAny>>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
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
    solution_dict(py, sol, raised, !specs.is_empty())
}

/// `None`, one event callable, or a sequence of them.
fn event_specs(py: Python<'_>, events: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<PyEventSpec>> {
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
    fun: &'a Bound<'_, PyAny>,
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

/// The dict `pointmass_dyn.rk45` wraps (SciPy's `OdeResult` entries): `y` as (dim, N),
/// the event lists `None` when no events were given.
fn solution_dict<'py>(
    py: Python<'py>,
    sol: integrator::Solution,
    raised: Option<PyErr>,
    with_events: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let (dim, n) = (sol.dim, sol.t.len());
    let mut y_t = vec![0.0; dim * n];
    for i in 0..n {
        for j in 0..dim {
            y_t[j * n + i] = sol.y[i * dim + j];
        }
    }
    let d = PyDict::new(py);
    d.set_item("error", raised.map(|e| e.into_value(py)))?;
    d.set_item("t", to_array1(py, &sol.t))?;
    d.set_item("y", to_array(py, y_t, &[dim, n])?)?;
    let te = PyList::empty(py);
    let ye = PyList::empty(py);
    for (times, ys) in sol.t_events.iter().zip(&sol.y_events) {
        te.append(to_array1(py, times))?;
        ye.append(to_array(py, ys.clone(), &[times.len(), dim])?)?;
    }
    let none = || py.None().into_bound(py);
    d.set_item("t_events", if with_events { te.into_any() } else { none() })?;
    d.set_item("y_events", if with_events { ye.into_any() } else { none() })?;
    d.set_item("nfev", sol.nfev)?;
    set_method(
        &d,
        sol.method,
        (sol.njev, sol.nlu),
        sol.switched_to,
        sol.t_switch,
    )?;
    set_outcome(
        &d,
        &sol.status,
        sol.n_accepted,
        sol.n_rejected,
        &sol.message,
        sol.t_reached,
    )?;
    d.set_item("stiff", stiffness_dict(py, sol.stiffness)?)?;
    d.set_item("sol", sol.dense.map(|inner| PyDenseSolution { inner }))?;
    Ok(d)
}

pub(super) fn invalid_setting(py: Python<'_>, e: integrator::InputError) -> PyErr {
    let class = match e {
        integrator::InputError::OutputTooLarge { .. } => "OutOfMemoryError",
        _ => "InvalidInputError",
    };
    py_error(py, class, e.to_string())
}

/// `None`, or `{"t", "h_lambda", "h", "lambda"}` of the first detection.
pub(super) fn stiffness_dict<'py>(
    py: Python<'py>,
    s: Option<integrator::Stiffness>,
) -> PyResult<Bound<'py, PyAny>> {
    match s {
        None => Ok(py.None().into_bound(py)),
        Some(s) => {
            let d = PyDict::new(py);
            d.set_item("t", s.t)?;
            d.set_item("h_lambda", s.h_lambda)?;
            d.set_item("h", s.h)?;
            d.set_item("lambda", s.lambda())?;
            Ok(d.into_any())
        }
    }
}
