//! `RunConfig`: the core's `simulate::RunConfig` (one run's settings, `None` where nothing
//! is said) built from keyword arguments and read back through typed getters. The runs
//! (`simulate_scene`, `simulate_batch`, `rk45`) take one, plus the same keywords, which beat
//! it; which setting a run uses is the core's `RunConfig::resolve`.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict, PyFloat, PyTuple};

use super::convert::to_array1;
use crate::integrator::{Controller, Method, StiffnessCheck, Tol};
use crate::simulate::RunConfig;

#[pyclass(name = "RunConfig", module = "pointmass_dyn._core", frozen, eq)]
#[derive(Clone, PartialEq)]
pub struct PyRunConfig {
    pub inner: RunConfig,
}

#[pymethods]
impl PyRunConfig {
    /// Every setting `None` unless given: a run then takes the scene's (`[simulate]`), else
    /// the default. `rtol`/`atol`: a number or one per state component; `max_step=inf`
    /// counts as not given. The keywords: `crate::simulate::config_args::KEYS`.
    #[new]
    #[pyo3(signature = (t_span=None, **settings))]
    #[pyo3(
        text_signature = "(t_span=None, *, rtol=None, atol=None, t_eval=None, first_step=None, max_step=None, max_steps=None, method=None, dt=None, controller=None, stiffness=None, disable=None, energy=None, power=None, dense_output=None)"
    )]
    fn new(t_span: Option<Obj>, settings: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let named = [("t_span", t_span.as_ref())];
        let inner = RunConfig::from_call(settings.map(|d| d.as_any()), &named)?;
        Ok(PyRunConfig { inner })
    }
    /// The settings given, by keyword (what `RunConfig(**d)` rebuilds).
    fn as_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        super::record::items(slf, &slf.get().inner.given())?.into_py_dict(slf.py())
    }

    /// A copy with the given settings replaced (`None` unsets one); the others kept.
    #[pyo3(signature = (**changes))]
    fn replace(&self, changes: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let inner = self.inner.replaced(changes.map(|c| c.as_any()))?;
        Ok(PyRunConfig { inner })
    }

    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        super::record::repr(slf, "RunConfig", &slf.get().inner.given())
    }

    fn __getnewargs_ex__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        Ok((PyTuple::empty(slf.py()), Self::as_dict(slf)?))
    }
}

impl PyRunConfig {
    fn read<R>(&self, _py: Python<'_>, f: impl FnOnce(&RunConfig) -> R) -> R {
        f(&self.inner)
    }
}

super::getters!(PyRunConfig.read {
    t_span: Option<(f64, f64)> = |c, py| c.t_span,
    /// A number, or an array of one per state component.
    rtol: Option<Obj<'py>> = |c, py| c.rtol.as_ref().map(|t| tol_py(py, t)),
    atol: Option<Obj<'py>> = |c, py| c.atol.as_ref().map(|t| tol_py(py, t)),
    t_eval: Option<Obj<'py>> = |c, py| c.t_eval.as_ref().map(|t| to_array1(py, t).into_any()),
    first_step: Option<f64> = |c, py| c.first_step,
    max_step: Option<f64> = |c, py| c.max_step,
    max_steps: Option<usize> = |c, py| c.max_steps,
    /// SciPy's spelling: "RK45", "DOP853", "Radau", "RK4", "Euler" or "auto".
    method: Option<&'static str> = |c, py| c.method.map(Method::name),
    dt: Option<f64> = |c, py| c.dt,
    /// "standard" (SciPy's) or "pi" (Hairer's).
    controller: Option<&'static str> = |c, py| c.controller.map(Controller::name),
    /// "warn", "stop" or "off".
    stiffness: Option<&'static str> = |c, py| c.stiffness.map(StiffnessCheck::name),
    /// The effect families switched off, as a tuple of names (`()`: none).
    disable: PyResult<Option<Bound<'py, PyTuple>>> =
        |c, py| c.disable.map(|d| PyTuple::new(py, d.names())).transpose(),
    energy: Option<bool> = |c, py| c.energy,
    power: Option<bool> = |c, py| c.power,
    dense_output: Option<bool> = |c, py| c.dense,
});

/// The settings of a run call: its keywords (`t_span`, `rtol`, `atol` and `settings`, as
/// `RunConfig`'s constructor takes them) over `config`'s.
pub(super) fn call_config(
    config: Option<PyRef<'_, PyRunConfig>>,
    t_span: Option<&Obj>,
    rtol: Option<&Obj>,
    atol: Option<&Obj>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<RunConfig> {
    let named = [("t_span", t_span), ("rtol", rtol), ("atol", atol)];
    let call = RunConfig::from_call(settings.map(|d| d.as_any()), &named)?;
    Ok(call.over(config.map(|c| c.inner.clone()).unwrap_or_default()))
}

fn tol_py<'py>(py: Python<'py>, tol: &Tol) -> Obj<'py> {
    match tol {
        Tol::Scalar(x) => PyFloat::new(py, *x).into_any(),
        Tol::PerComponent(v) => to_array1(py, v).into_any(),
    }
}
