//! The integration arguments and result entries common to `rk45` and `simulate_scene`
//! (`run_config.rs` gathers the arguments into a `RunConfig`).
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::integrator::{self, Status};

/// An optional argument that was given (`None` counts as not given).
pub(super) fn given<'a, 'py>(obj: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
    obj.filter(|o| !o.is_none())
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
    d.set_item("message", crate::support::error::compact_numbers(message))?;
    d.set_item("success", status.is_success())?;
    d.set_item("t_reached", t_reached)
}
