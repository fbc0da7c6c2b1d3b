//! The integration arguments and result entries common to `rk45` and `simulate_scene`.
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{array, opt_count, opt_real, shape_str, vector};
use super::errors::invalid;
use crate::integrator::{self, Controller, SolverOptions, Status, Tol};
use crate::simulate::Requested;

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

/// An optional argument that was given (`None` counts as not given).
pub(super) fn given<'a, 'py>(obj: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
    obj.filter(|o| !o.is_none())
}

/// `first_step`, `max_step` (inf: no limit, as if not given) and `max_steps` as numbers
/// and a count: a request with only these.
pub(super) fn step_args(
    first_step: Option<&Bound<'_, PyAny>>,
    max_step: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
) -> PyResult<Requested> {
    Ok(Requested {
        first_step: opt_real(first_step, "first_step")?,
        max_step: opt_real(max_step, "max_step")?.filter(|x| *x != f64::INFINITY),
        max_steps: opt_count(max_steps, "max_steps", "a step count >= 0 (or None)")?,
        ..Requested::default()
    })
}

/// `method` (a name, case-insensitive; `None`: not given) and the fixed step `dt` into
/// `requested`.
pub(super) fn method_args(
    py: Python<'_>,
    requested: &mut Requested,
    method: Option<&str>,
    dt: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    if let Some(name) = method {
        requested.method = Some(integrator::Method::parse(name).ok_or_else(|| {
            invalid(
                py,
                "method",
                format!("one of {}", integrator::Method::NAMES),
                format!("'{name}'"),
            )
        })?);
    }
    requested.dt = opt_real(dt, "dt")?;
    Ok(())
}

/// The run's method, evaluation counts and switch (`auto`) as result entries.
pub(super) fn set_method(
    d: &Bound<'_, PyDict>,
    method: integrator::Method,
    counts: (usize, usize),
    switched_to: Option<integrator::Method>,
    t_switch: Option<f64>,
) -> PyResult<()> {
    d.set_item("method", method.name())?;
    d.set_item("njev", counts.0)?;
    d.set_item("nlu", counts.1)?;
    d.set_item("switched_to", switched_to.map(|m| m.name()))?;
    d.set_item("t_switch", t_switch)
}

/// The caller's other integration arguments (common to `rk45` and `simulate`): the
/// tolerances into `requested` (a scene's may stand in for them), the rest into the options
/// no scene sets. The step limits come from `step_args`; `Requested` resolves them all.
#[allow(clippy::too_many_arguments)]
pub(super) fn options(
    py: Python<'_>,
    dim: usize,
    requested: &mut Requested,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    t_eval: Option<&Bound<'_, PyAny>>,
    dense: bool,
    controller: &str,
    stiffness: &str,
) -> PyResult<SolverOptions> {
    let controller = controller_arg(py, controller)?;
    requested.rtol = given(rtol).map(|r| tol_arg(r, "rtol", dim)).transpose()?;
    requested.atol = given(atol).map(|a| tol_arg(a, "atol", dim)).transpose()?;
    let t_eval = given(t_eval)
        .map(|t| vector(t, "t_eval", None))
        .transpose()?;
    Ok(SolverOptions {
        dense,
        controller,
        t_eval,
        stiffness: stiffness_arg(py, stiffness)?,
        ..Default::default()
    })
}

/// `"warn"` (default: detect, report, steps unchanged), `"stop"` or `"off"`.
fn stiffness_arg(py: Python<'_>, name: &str) -> PyResult<integrator::StiffnessCheck> {
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

/// How the run ended: the result entries after the evaluation counts.
pub(super) fn set_outcome(
    d: &Bound<'_, PyDict>,
    status: &Status,
    n_accepted: usize,
    n_rejected: usize,
    message: &str,
    t_reached: f64,
) -> PyResult<()> {
    d.set_item("n_accepted", n_accepted)?;
    d.set_item("n_rejected", n_rejected)?;
    d.set_item("status", status.code())?;
    // Numbers in exponent form where `{}` wrote hundreds of digits (as our errors').
    d.set_item("message", crate::error::compact_numbers(message))?;
    d.set_item("success", status.is_success())?;
    d.set_item("t_reached", t_reached)
}
