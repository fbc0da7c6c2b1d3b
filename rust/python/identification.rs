//! Arguments and results of the identification functions (crate::identification).
//! Conversion only.
use crate::python::Obj;
use pyo3::prelude::*;

use super::convert::{array, dmatrix_to_array, points, to_array1};
use super::errors::{check_result, invalid};
use super::model::PyModel;
use super::record::{record, Field};
use super::signals::detach_interruptible;
use crate::identification::{self as ident, Extras, LinkCells, Method, Options};

fn extras(viscous: bool, coulomb: bool, armature: bool, offset: bool) -> Extras {
    Extras {
        viscous,
        coulomb,
        armature,
        offset,
    }
}

#[pyfunction]
#[pyo3(signature = (model, q, v, a, gravity=None, viscous=false, coulomb=false, armature=false, offset=false, actuated=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub fn identification_regressor<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    q: &Obj,
    v: &Obj,
    a: &Obj,
    gravity: Option<&Obj>,
    viscous: bool,
    coulomb: bool,
    armature: bool,
    offset: bool,
    actuated: Vec<usize>,
) -> PyResult<Obj<'py>> {
    let model = model.model();
    let g = crate::model::args::gravity(gravity)?;
    let (_, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
    let ex = extras(viscous, coulomb, armature, offset);
    let y = detach_interruptible(py, || {
        ident::joint_force_regressor(&model, &qs, &vs, &accs, &g, &ex, &actuated)
    })?;
    check_result(py, "torque regressor", y.as_slice())?;
    dmatrix_to_array(py, &y)
}

/// Column names and the model's own values of every column (friction and offsets zero, the
/// model's armature).
#[pyfunction]
#[pyo3(signature = (model, viscous=false, coulomb=false, armature=false, offset=false))]
pub fn identification_parameters<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    viscous: bool,
    coulomb: bool,
    armature: bool,
    offset: bool,
) -> PyResult<(Vec<String>, Obj<'py>)> {
    let model = model.model();
    let ex = extras(viscous, coulomb, armature, offset);
    let names = ident::parameter_names(&model, &ex);
    let mut values = ident::model_parameters(&model);
    values.resize(names.len(), 0.0);
    Ok((names, to_array1(py, &values).into_any()))
}

#[pyfunction]
#[pyo3(signature = (y, rank_tol=1e-8))]
pub fn identification_base<'py>(py: Python<'py>, y: &Obj, rank_tol: f64) -> PyResult<PyBase> {
    let (shape, data) = array(y, "regressor")?;
    if shape.len() != 2 {
        return Err(invalid(
            py,
            "regressor",
            "a 2-d array",
            format!("{shape:?}"),
        ));
    }
    let m = nalgebra::DMatrix::from_row_slice(shape[0], shape[1], &data);
    let reduced = |m| ident::identify::reduced(m).r;
    let base = detach_interruptible(py, || Ok(ident::base_parameters(&reduced(&m), rank_tol)))?;
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
        names,
        free,
        base: |r: &ident::Identified, py| Bound::new(py, PyBase(r.base.clone())).map(Bound::into_any),
        base_names,
        beta: |r: &ident::Identified, py| r.fit.beta.field(py),
        std: |r: &ident::Identified, py| r.fit.std.field(py),
        pi: |r: &ident::Identified, py| r.fit.pi.field(py),
        rss: |r: &ident::Identified, py| r.fit.rss.field(py),
        condition: |r: &ident::Identified, py| r.fit.condition.field(py),
        structural_rank,
        residuals,
        masses,
    }
);

#[pyfunction]
#[pyo3(signature = (model, q, v, a, tau, gravity, method, free, prior, prior_weight, weights, cells, viscous, coulomb, armature, offset, rank_tol=1e-8, actuated=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub fn identification_fit<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    q: &Obj,
    v: &Obj,
    a: &Obj,
    tau: &Obj,
    gravity: Option<&Obj>,
    method: &str,
    free: Vec<bool>,
    prior: Vec<f64>,
    prior_weight: f64,
    weights: Vec<f64>,
    cells: Vec<(usize, Obj, f64)>,
    viscous: bool,
    coulomb: bool,
    armature: bool,
    offset: bool,
    rank_tol: f64,
    actuated: Vec<usize>,
) -> PyResult<PyIdentified> {
    let model = model.model();
    let g = crate::model::args::gravity(gravity)?;
    let (_, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
    let (_, taus) = array(tau, "tau")?;
    let method = match method {
        "ols" => Method::Ols,
        "cells" => {
            let mut links = Vec::new();
            for (link, centres, side) in &cells {
                links.push(LinkCells {
                    link: *link,
                    centres: points(centres, "cells")?,
                    side: *side,
                });
            }
            Method::Cells(links)
        }
        other => {
            return Err(invalid(
                py,
                "method",
                "'cells' or 'ols'",
                format!("{other:?}"),
            ))
        }
    };
    let opt = Options {
        extras: extras(viscous, coulomb, armature, offset),
        free,
        prior,
        prior_weight,
        weights,
        rank_tol,
        method,
        actuated,
    };
    let out = detach_interruptible(py, || {
        ident::identify(&model, &qs, &vs, &accs, &taus, &g, &opt)
    })?;
    Ok(PyIdentified(out))
}

#[pyfunction]
#[pyo3(signature = (model, pi, links, armature=None))]
pub fn identification_model(
    py: Python<'_>,
    model: PyRef<'_, PyModel>,
    pi: Vec<f64>,
    links: Vec<usize>,
    armature: Option<Vec<f64>>,
) -> PyResult<PyModel> {
    let model = model.model();
    let n = model.links.len();
    if pi.len() < ident::NPARAM * n || links.iter().any(|&l| l >= n) {
        return Err(invalid(
            py,
            "parameters",
            format!("{} values and link indices below {n}", ident::NPARAM * n),
            format!("{} values, links {links:?}", pi.len()),
        ));
    }
    let out = ident::identified_model(&model, &pi, &links, armature.as_deref())
        .map_err(|e| super::errors::to_py(py, e))?;
    Ok(PyModel::from_model(out))
}
