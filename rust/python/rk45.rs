//! `rk45` (`solve_ivp`): our integrators (RK45 by default) on a Python right-hand side, and
//! its Jacobian `jac` for the implicit methods (Radau, and `auto` once it switches) as SciPy
//! takes it: a callable `jac(t, y) -> (n, n)` (an array-like or a SciPy sparse matrix), or a
//! constant `(n, n)` array-like.
use crate::python::Obj;
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict};
use pyo3::IntoPyObjectExt;

use super::convert::{to_array, vector};
use super::dense::PyDenseSolution;
use super::effects::repr_of;
use super::errors::invalid;
use super::errors::IntoPyResult;
use super::events::{event_list, keep, python_events};
use super::record::Field;
use super::run_config::{call_config, PyRunConfig};
use crate::integrator::{self, OdeSystem};
use crate::io::scene::Settings;
use crate::simulate::config_args::ode_jacobian;
use crate::support::args::{given, matrix};

// Docstring: `_core.pyi`; `pointmass_dyn.rk45` (and `solve_ivp`) wrap it.
#[pyfunction]
#[pyo3(signature = (fun, t_span, y0, rtol=None, atol=None, *, config=None, events=None, jac=None, **settings))]
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
        let expected = "a callable fun(t, y) -> array";
        return Err(invalid(py, "fun", expected, repr_of(fun)));
    }
    let y0 = vector(y0, "y0", None)?;
    let dim = y0.len();
    // No scene: the caller's settings, else the defaults.
    let run = call_config(config, Some(t_span), rtol, atol, settings)?
        .resolve(&Settings::default(), &[], dim)
        .py(py)?;
    let (t_span, opts) = (run.t_span, run.opts);
    let jac = given(jac);
    let constant = match jac {
        None => None,
        Some(j) => {
            let first = || dense(j.call1((t_span.0, PyArray1::from_slice(py, &y0)))?);
            ode_jacobian(&dense(j.clone())?, j.is_callable(), dim, opts.method, first)?
        }
    };
    let events = event_list(py, events)?.for_run(false, false)?;
    // The first exception from `fun`, `jac` or an event (Ctrl-C included) stops the run;
    // `pointmass_dyn.rk45` re-raises it with the solution computed so far attached.
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    let mut evs = python_events(&events, None, &failure);
    let jac = jac.filter(|j| j.is_callable());
    let sys = PySystem {
        fun,
        jac,
        dim,
        failure: &failure,
    };
    // The method is the core's choice; a constant `jac` is the core's to keep.
    let sol = integrator::solve_with_jacobian(sys, t_span, &y0, &opts, &mut evs, constant)
        .map_err(crate::support::error::Error::from);
    let mut run = sol.py(py)?;
    drop(evs);
    let error = failure.into_inner().ok().flatten();
    let dense = run.dense.take().map(|inner| PyDenseSolution { inner });
    Ok(PyOdeSolution(Ode {
        run,
        sol: dense.map(|d| Py::new(py, d)).transpose()?,
        error: error.map(|e| e.into_value(py).into_any()),
    }))
}

/// `x`, or `x.toarray()` for anything that has one (a SciPy sparse matrix).
fn dense<'py>(x: Obj<'py>) -> PyResult<Obj<'py>> {
    match x.hasattr("toarray")? {
        true => x.call_method0("toarray"),
        false => Ok(x),
    }
}

/// `fun(t, y) -> array` as the system's right-hand side, and a callable `jac(t, y)` as its
/// Jacobian; the first exception of either is kept in `failure` (the run stops with its
/// message).
struct PySystem<'a> {
    fun: &'a Obj<'a>,
    jac: Option<&'a Obj<'a>>,
    dim: usize,
    failure: &'a Mutex<Option<PyErr>>,
}

impl OdeSystem for PySystem<'_> {
    fn dim(&self) -> usize {
        self.dim
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
        let out = self.fun.call1((t, PyArray1::from_slice(self.fun.py(), y)));
        let out = out.and_then(|out| vector(&out, "fun(t, y)", Some(self.dim)));
        out.map(|v| dydt.copy_from_slice(&v))
            .map_err(|e| keep(self.failure, e))
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, String> {
        let Some(f) = self.jac else { return Ok(false) };
        let out = f
            .call1((t, PyArray1::from_slice(f.py(), y)))
            .and_then(dense);
        let out = out.and_then(|m| matrix(&m, "jac(t, y)", self.dim, self.dim));
        let filled = out.map(|m| {
            jac.copy_from_slice(&m);
            true
        });
        filled.map_err(|e| keep(self.failure, e))
    }
}

/// An `rk45` run (without events, the event lists are `None`).
pub struct Ode {
    run: integrator::Solution,
    sol: Option<Py<PyDenseSolution>>,
    error: Option<Py<PyAny>>,
}

// `rk45`'s result (docstring: `_core.pyi`; `pointmass_dyn.OdeResult` is built from it).
super::trajectory::run_record!(
    PyOdeSolution("OdeSolution", Ode) {
        t: |r: &Ode, py| r.run.t.field(py),
        y: |r: &Ode, py| to_array(py, r.run.y_by_component(), &[r.run.dim, r.run.t.len()]),
        t_events: |r: &Ode, py| (!r.run.t_events.is_empty()).then(|| r.run.t_events.field(py)).transpose()?.into_bound_py_any(py),
        y_events: |r: &Ode, py| (!r.run.t_events.is_empty()).then(|| r.run.event_matrices().field(py)).transpose()?.into_bound_py_any(py),
        stiff: |r: &Ode, py| {
            let entries = |s: &integrator::Stiffness| [("t", s.t), ("h_lambda", s.h_lambda), ("h", s.h), ("lambda", s.lambda())];
            r.run.stiffness.as_ref().map(|s| entries(s).into_py_dict(py)).transpose()?.into_bound_py_any(py)
        },
        sol: |r: &Ode, py| r.sol.as_ref().into_bound_py_any(py),
    }
);
