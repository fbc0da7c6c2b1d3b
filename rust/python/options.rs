//! The integration options common to `rk45` and `simulate_scene`.
use pyo3::prelude::*;

use super::convert::{array, opt_count, opt_real, shape_str, vector};
use super::errors::invalid;
use crate::integrator::{self, Controller, Rk45Options, Tol};

pub(super) fn t_span_arg(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<(f64, f64)> {
    let v = vector(obj, "t_span", Some(2))?;
    if !(v[0].is_finite() && v[1].is_finite()) || v[0] == v[1] {
        return Err(invalid(
            py,
            "t_span",
            "two different finite times (t0, t_end)",
            format!("({}, {})", v[0], v[1]),
        ));
    }
    Ok((v[0], v[1]))
}

pub(super) fn tol_arg(obj: &Bound<'_, PyAny>, arg: &str, dim: usize) -> PyResult<Tol> {
    let (shape, values) = array(obj, arg)?;
    if shape.is_empty() {
        return Ok(Tol::Scalar(values[0]));
    }
    if shape != [dim] {
        return Err(invalid(
            obj.py(),
            arg,
            format!("a number or shape ({dim},)"),
            shape_str(&shape),
        ));
    }
    Ok(Tol::PerComponent(values))
}

pub(super) fn controller_arg(py: Python<'_>, name: &str) -> PyResult<Controller> {
    match name {
        "standard" | "scipy" => Ok(Controller::Standard),
        "pi" => Ok(Controller::hairer_pi()),
        other => Err(invalid(
            py,
            "controller",
            "'standard' (SciPy's) or 'pi' (Hairer's PI)",
            format!("'{other}'"),
        )),
    }
}

/// `first_step`, `max_step` (inf: no limit) and `max_steps` as numbers and a count.
#[allow(clippy::type_complexity)]
pub(super) fn step_args(
    first_step: Option<&Bound<'_, PyAny>>,
    max_step: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Option<f64>, Option<f64>, Option<usize>)> {
    Ok((
        opt_real(first_step, "first_step")?,
        opt_real(max_step, "max_step")?.filter(|x| *x != f64::INFINITY),
        opt_count(max_steps, "max_steps", "a step count >= 0 (or None)")?,
    ))
}

/// Options common to `rk45` and `simulate`.
#[allow(clippy::too_many_arguments)]
pub(super) fn options(
    py: Python<'_>,
    dim: usize,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    t_eval: Option<&Bound<'_, PyAny>>,
    first_step: Option<f64>,
    max_step: Option<f64>,
    max_steps: Option<usize>,
    dense: bool,
    controller: &str,
) -> PyResult<Rk45Options> {
    let mut o = Rk45Options {
        dense,
        controller: controller_arg(py, controller)?,
        ..Default::default()
    };
    if let Some(r) = rtol.filter(|r| !r.is_none()) {
        o.rtol = tol_arg(r, "rtol", dim)?;
    }
    if let Some(a) = atol.filter(|a| !a.is_none()) {
        o.atol = tol_arg(a, "atol", dim)?;
    }
    if let Some(t) = t_eval.filter(|t| !t.is_none()) {
        o.t_eval = Some(vector(t, "t_eval", None)?);
    }
    o.first_step = first_step;
    if let Some(m) = max_step {
        o.max_step = m;
    }
    if let Some(n) = max_steps {
        o.max_steps = n;
    }
    Ok(o)
}

/// `"warn"` (default: detect, report, steps unchanged), `"stop"` or `"off"`.
pub(super) fn stiffness_arg(py: Python<'_>, name: &str) -> PyResult<integrator::StiffnessCheck> {
    match name {
        "warn" => Ok(integrator::StiffnessCheck::Warn),
        "stop" => Ok(integrator::StiffnessCheck::Stop),
        "off" => Ok(integrator::StiffnessCheck::Off),
        other => Err(invalid(
            py,
            "stiffness",
            "'warn' (detect and report), 'stop' (stop at the detection) or 'off'",
            format!("'{other}'"),
        )),
    }
}
