//! `solve_ivp(..., jac=...)`: the Jacobian of a Python right-hand side for the implicit
//! method (Radau, and `auto` once it switches), as SciPy takes it: a callable
//! `jac(t, y) -> (n, n)` (an array-like or a SciPy sparse matrix), or a constant `(n, n)`
//! array-like.
use crate::python::Obj;
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::prelude::*;

use super::errors::{invalid, IntoPyResult};
use crate::integrator::{Method, OdeSystem};
use crate::support::error::check_finite_matrix;

/// The `jac` argument.
pub(super) enum JacArg<'a> {
    None,
    Callable(&'a Obj<'a>),
    /// Row-major `dim × dim`.
    Constant(Vec<f64>),
}

/// A dense `(dim, dim)` matrix from an array-like or anything with `toarray()` (SciPy sparse).
fn matrix(obj: &Obj, arg: &str, dim: usize) -> PyResult<Vec<f64>> {
    let dense;
    let obj = if obj.hasattr("toarray")? {
        dense = obj.call_method0("toarray")?;
        &dense
    } else {
        obj
    };
    crate::support::args::matrix(obj, arg, dim, dim)
}

/// Check `jac` for a system of `dim` components integrated with `method`: only the implicit
/// methods use a Jacobian, so one given to another method is refused rather than ignored.
/// With `"auto"` a callable is called once at the start `(t0, y0)`: Radau calls it at once,
/// but `auto` only if it switches, which would leave a wrong `jac` unnoticed until then.
pub(super) fn jac_arg<'a>(
    py: Python<'_>,
    jac: Option<&'a Obj<'a>>,
    dim: usize,
    method: Method,
    start: (f64, &[f64]),
) -> PyResult<JacArg<'a>> {
    let Some(jac) = jac.filter(|j| !j.is_none()) else {
        return Ok(JacArg::None);
    };
    if !matches!(method, Method::Radau | Method::Auto) {
        return Err(invalid(
            py,
            "jac",
            format!("None with method '{method}' (only 'Radau' and 'auto' use a Jacobian)"),
            "a Jacobian",
        ));
    }
    if jac.is_callable() {
        if method == Method::Auto {
            let (t0, y0) = start;
            let m = jac.call1((t0, PyArray1::from_slice(py, y0)))?;
            check_finite_matrix("jac(t0, y0)", &matrix(&m, "jac(t, y)", dim)?, dim).py(py)?;
        }
        return Ok(JacArg::Callable(jac));
    }
    let m = matrix(jac, "jac", dim)?;
    check_finite_matrix("jac", &m, dim).py(py)?;
    Ok(JacArg::Constant(m))
}

/// A system with the Jacobian from a Python callable `jac(t, y)`; an exception from `jac` is kept in `failure`
/// (the run stops with its message, and the caller re-raises it).
pub(super) struct WithJacobian<'a, S> {
    pub inner: S,
    pub jac: &'a Obj<'a>,
    pub failure: &'a Mutex<Option<PyErr>>,
}

impl<S: OdeSystem> OdeSystem for WithJacobian<'_, S> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
        self.inner.rhs(t, y, dydt)
    }
    fn project(&mut self, y: &mut [f64]) -> Result<bool, String> {
        self.inner.project(y)
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, String> {
        let f = self.jac;
        let dim = y.len();
        let py = f.py();
        let out = f
            .call1((t, PyArray1::from_slice(py, y)))
            .and_then(|out| matrix(&out, "jac(t, y)", dim));
        match out {
            Ok(m) => {
                jac.copy_from_slice(&m);
                Ok(true)
            }
            Err(e) => {
                let msg = e.to_string();
                if let Ok(mut slot) = self.failure.lock() {
                    slot.get_or_insert(e);
                }
                Err(msg)
            }
        }
    }
}
