//! `RunConfig`: the core's `simulate::RunConfig` (one run's settings, `None` where nothing
//! is said) built from keyword arguments and read back through typed getters. The runs
//! (`simulate_scene`, `simulate_batch`, `rk45`) take one, plus the same keywords, which beat
//! it; which setting a run uses is the core's `RunConfig::resolve`.
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat, PyTuple};
use pyo3::PyTypeInfo;

use super::convert::{array, opt_count, opt_real, shape_str, vector};
use super::errors::invalid;
use super::options::{controller_arg, given, stiffness_arg, t_span_arg};
use super::scene::disable_arg;
use crate::integrator::{Controller, Method, StiffnessCheck, Tol};
use crate::simulate::RunConfig;

#[pyclass(name = "RunConfig", module = "pointmass_dyn._core", frozen, eq)]
#[derive(Clone, PartialEq)]
pub struct PyRunConfig {
    pub inner: RunConfig,
}

/// The keywords, in the constructor's order (`t_span` may also come first by position).
const KEYS: [&str; 15] = [
    "t_span",
    "rtol",
    "atol",
    "t_eval",
    "first_step",
    "max_step",
    "max_steps",
    "method",
    "dt",
    "controller",
    "stiffness",
    "disable",
    "energy",
    "power",
    "dense_output",
];

#[pymethods]
impl PyRunConfig {
    /// Every setting `None` unless given: a run then takes the scene's (`[simulate]`), else
    /// the default. `rtol`/`atol`: a number or one per state component; `max_step=inf`
    /// counts as not given.
    #[new]
    #[pyo3(signature = (t_span=None, *, rtol=None, atol=None, t_eval=None, first_step=None, max_step=None, max_steps=None, method=None, dt=None, controller=None, stiffness=None, disable=None, energy=None, power=None, dense_output=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        t_span: Option<&Bound<'_, PyAny>>,
        rtol: Option<&Bound<'_, PyAny>>,
        atol: Option<&Bound<'_, PyAny>>,
        t_eval: Option<&Bound<'_, PyAny>>,
        first_step: Option<&Bound<'_, PyAny>>,
        max_step: Option<&Bound<'_, PyAny>>,
        max_steps: Option<&Bound<'_, PyAny>>,
        method: Option<&str>,
        dt: Option<&Bound<'_, PyAny>>,
        controller: Option<&str>,
        stiffness: Option<&str>,
        disable: Option<&Bound<'_, PyAny>>,
        energy: Option<bool>,
        power: Option<bool>,
        dense_output: Option<bool>,
    ) -> PyResult<Self> {
        let inner = RunConfig {
            t_span: given(t_span).map(|t| t_span_arg(py, t)).transpose()?,
            rtol: given(rtol).map(|r| tol_arg(r, "rtol")).transpose()?,
            atol: given(atol).map(|a| tol_arg(a, "atol")).transpose()?,
            t_eval: given(t_eval)
                .map(|t| vector(t, "t_eval", None))
                .transpose()?,
            first_step: opt_real(first_step, "first_step")?,
            max_step: opt_real(max_step, "max_step")?.filter(|x| *x != f64::INFINITY),
            max_steps: opt_count(max_steps, "max_steps", "a step count >= 0 (or None)")?,
            method: method.map(|m| method_arg(py, m)).transpose()?,
            dt: opt_real(dt, "dt")?,
            controller: controller.map(|c| controller_arg(py, c)).transpose()?,
            stiffness: stiffness.map(|s| stiffness_arg(py, s)).transpose()?,
            disable: disable_arg(py, disable)?,
            energy,
            power,
            dense: dense_output,
        };
        Ok(PyRunConfig { inner })
    }

    #[getter]
    fn t_span(&self) -> Option<(f64, f64)> {
        self.inner.t_span
    }
    /// A number, or an array of one per state component.
    #[getter]
    fn rtol<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        self.inner.rtol.as_ref().map(|t| tol_py(py, t))
    }
    #[getter]
    fn atol<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        self.inner.atol.as_ref().map(|t| tol_py(py, t))
    }
    #[getter]
    fn t_eval<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner
            .t_eval
            .as_ref()
            .map(|t| PyArray1::from_slice(py, t))
    }
    #[getter]
    fn first_step(&self) -> Option<f64> {
        self.inner.first_step
    }
    #[getter]
    fn max_step(&self) -> Option<f64> {
        self.inner.max_step
    }
    #[getter]
    fn max_steps(&self) -> Option<usize> {
        self.inner.max_steps
    }
    /// SciPy's spelling: "RK45", "DOP853", "Radau", "RK4", "Euler" or "auto".
    #[getter]
    fn method(&self) -> Option<&'static str> {
        self.inner.method.map(Method::name)
    }
    #[getter]
    fn dt(&self) -> Option<f64> {
        self.inner.dt
    }
    /// "standard" (SciPy's) or "pi" (Hairer's).
    #[getter]
    fn controller(&self) -> Option<&'static str> {
        self.inner.controller.map(|c| match c {
            Controller::Standard => "standard",
            Controller::PI { .. } => "pi",
        })
    }
    /// "warn", "stop" or "off".
    #[getter]
    fn stiffness(&self) -> Option<&'static str> {
        self.inner.stiffness.map(|s| match s {
            StiffnessCheck::Warn => "warn",
            StiffnessCheck::Stop => "stop",
            StiffnessCheck::Off => "off",
        })
    }
    /// The effect families switched off, as a tuple of names (`()`: none).
    #[getter]
    fn disable<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyTuple>>> {
        self.inner
            .disable
            .map(|d| PyTuple::new(py, d.names()))
            .transpose()
    }
    #[getter]
    fn energy(&self) -> Option<bool> {
        self.inner.energy
    }
    #[getter]
    fn power(&self) -> Option<bool> {
        self.inner.power
    }
    #[getter]
    fn dense_output(&self) -> Option<bool> {
        self.inner.dense
    }

    /// The settings given, by keyword (what `RunConfig(**d)` rebuilds).
    fn as_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(slf.py());
        for key in KEYS {
            let value = slf.getattr(key)?;
            if !value.is_none() {
                d.set_item(key, value)?;
            }
        }
        Ok(d)
    }

    /// A copy with the given settings replaced (`None` unsets one); the others kept.
    #[pyo3(signature = (**changes))]
    fn replace<'py>(
        slf: &Bound<'py, Self>,
        changes: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, Self>> {
        let d = Self::as_dict(slf)?;
        if let Some(changes) = changes {
            check_keys(changes)?;
            d.update(changes.as_mapping())?;
        }
        Self::type_object(slf.py())
            .call((), Some(&d))?
            .cast_into::<Self>()
            .map_err(Into::into)
    }

    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let parts = Self::as_dict(slf)?
            .iter()
            .map(|(k, v)| Ok(format!("{k}={}", v.repr()?)))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(format!("RunConfig({})", parts.join(", ")))
    }

    fn __getnewargs_ex__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        Ok((PyTuple::empty(slf.py()), Self::as_dict(slf)?))
    }
}

/// Unknown keywords, named with the ones there are.
fn check_keys(d: &Bound<'_, PyDict>) -> PyResult<()> {
    for key in d.keys() {
        let name: String = key.extract()?;
        if !KEYS.contains(&name.as_str()) {
            return Err(invalid(
                d.py(),
                &name,
                format!("a setting of RunConfig: {}", KEYS.join(", ")),
                "an unknown keyword",
            ));
        }
    }
    Ok(())
}

/// The settings of a run call: its keywords (`t_span`, `rtol`, `atol` and `settings`, as
/// `RunConfig`'s constructor takes them) over `config`'s.
pub(super) fn call_config(
    py: Python<'_>,
    config: Option<PyRef<'_, PyRunConfig>>,
    t_span: Option<&Bound<'_, PyAny>>,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<RunConfig> {
    let below = config.map(|c| c.inner.clone()).unwrap_or_default();
    let bare = settings.is_none_or(|s| s.is_empty());
    if bare && given(t_span).is_none() && given(rtol).is_none() && given(atol).is_none() {
        return Ok(below);
    }
    let d = match settings {
        Some(s) => {
            check_keys(s)?;
            s.copy()?
        }
        None => PyDict::new(py),
    };
    for (key, value) in [("t_span", t_span), ("rtol", rtol), ("atol", atol)] {
        if let Some(v) = value {
            d.set_item(key, v)?;
        }
    }
    let call = PyRunConfig::type_object(py).call((), Some(&d))?;
    Ok(call.cast::<PyRunConfig>()?.get().inner.clone().over(below))
}

/// The `RunConfig` of the keywords given (`None`: not given), parsed by its constructor.
pub(super) fn config_of(
    py: Python<'_>,
    given: &[(&str, Option<&Bound<'_, PyAny>>)],
) -> PyResult<RunConfig> {
    let d = PyDict::new(py);
    for (key, value) in given {
        if let Some(v) = value {
            d.set_item(key, v)?;
        }
    }
    let config = PyRunConfig::type_object(py).call((), Some(&d))?;
    Ok(config.cast::<PyRunConfig>()?.get().inner.clone())
}

pub(super) fn method_arg(py: Python<'_>, name: &str) -> PyResult<Method> {
    Method::parse(name).ok_or_else(|| {
        invalid(
            py,
            "method",
            format!("one of {}", Method::NAMES),
            format!("'{name}'"),
        )
    })
}

/// A tolerance: a number, or one per state component (its length is checked by the run).
fn tol_arg(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Tol> {
    let (shape, values) = array(obj, arg)?;
    match shape.len() {
        0 => Ok(Tol::Scalar(values[0])),
        1 => Ok(Tol::PerComponent(values)),
        _ => Err(invalid(
            obj.py(),
            arg,
            "a number or one per state component (n,)",
            shape_str(&shape),
        )),
    }
}

fn tol_py<'py>(py: Python<'py>, tol: &Tol) -> Bound<'py, PyAny> {
    match tol {
        Tol::Scalar(x) => PyFloat::new(py, *x).into_any(),
        Tol::PerComponent(v) => PyArray1::from_slice(py, v).into_any(),
    }
}
