//! Arguments and results of the identification functions (crate::identification).
//! Conversion only.
use crate::python::Obj;
use pyo3::prelude::*;

use super::convert::{dmatrix_to_array, to_array1};
use super::model::PyModel;
use super::record::record;
use super::signals::detach_interruptible;
use crate::identification::{self as ident, args};

/// `extras`: whether to add the (viscous, coulomb, armature, offset) columns.
#[pyfunction]
#[pyo3(signature = (model, q, v, a, gravity=None, extras=(false, false, false, false), actuated=Vec::new()))]
pub fn identification_regressor<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    q: &Obj,
    v: &Obj,
    a: &Obj,
    gravity: Option<&Obj>,
    extras: (bool, bool, bool, bool),
    actuated: Vec<usize>,
) -> PyResult<Obj<'py>> {
    let (model, extras) = (model.model(), args::extras(extras));
    let call = args::regressor_call(&model, [q, v, a], gravity)?;
    let y = detach_interruptible(py, || call.regressor(&model, &extras, &actuated))?;
    dmatrix_to_array(py, &y)
}

/// Column names and the model's own values of every column (friction and offsets zero, the
/// model's armature).
#[pyfunction]
#[pyo3(signature = (model, extras=(false, false, false, false)))]
pub fn identification_parameters<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    extras: (bool, bool, bool, bool),
) -> PyResult<(Vec<String>, Obj<'py>)> {
    let (names, values) = ident::regressor::parameters(&model.model(), &args::extras(extras));
    Ok((names, to_array1(py, &values).into_any()))
}

#[pyfunction]
#[pyo3(signature = (y, rank_tol=1e-8))]
pub fn identification_base<'py>(py: Python<'py>, y: &Obj, rank_tol: f64) -> PyResult<PyBase> {
    let y = args::regressor(y)?;
    let reduced = |y| ident::identify::reduced(y).r;
    let base = detach_interruptible(py, || Ok(ident::base_parameters(&reduced(&y), rank_tol)))?;
    Ok(PyBase(base))
}

record!(
    /// The base parameters of a regressor (`crate::identification::Base`).
    PyBase("IdentificationBase", ident::Base) {
        rank, independent, dependent, coefficients, pivots
    }
);

record!(
    /// An identification's result (`crate::identification::Identified`).
    PyIdentified("Identified", ident::Identified) {
        names, free,
        base: |r: &ident::Identified, py| Bound::new(py, PyBase(r.base.clone())).map(Bound::into_any),
        base_names, beta, std, pi, rss, condition, structural_rank, residuals, masses,
    }
);

/// `options`: the fit's keywords (`crate::identification::args::fit_options`).
#[pyfunction]
#[pyo3(signature = (model, q, v, a, tau, **options))]
pub fn identification_fit(
    py: Python<'_>,
    model: PyRef<'_, PyModel>,
    q: &Obj,
    v: &Obj,
    a: &Obj,
    tau: &Obj,
    options: Option<&Bound<'_, pyo3::types::PyDict>>,
) -> PyResult<PyIdentified> {
    let model = model.model();
    let call = args::fit_call(&model, [q, v, a, tau], options.map(|o| o.as_any()))?;
    Ok(PyIdentified(detach_interruptible(py, || {
        call.identify(&model)
    })?))
}

#[pyfunction]
#[pyo3(signature = (model, pi, links, armature=None))]
pub fn identification_model(
    model: PyRef<'_, PyModel>,
    pi: Vec<f64>,
    links: Vec<usize>,
    armature: Option<Vec<f64>>,
) -> PyResult<PyModel> {
    let out = ident::identified_model(&model.model(), &pi, &links, armature.as_deref())?;
    Ok(PyModel::from_model(out))
}
