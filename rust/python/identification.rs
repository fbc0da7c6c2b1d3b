//! Arguments and results of the identification functions (crate::identification).
//! Conversion only.
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{array, dmatrix_to_array, points, to_array1};
use super::errors::{check_result, invalid};
use super::model::{gravity_arg, PyModel};
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

/// The joint torque regressor along N states: (N · nv, p), sample-major rows; with
/// `actuated` (v indices) the driven joints' forces, (N · na, p).
#[pyfunction]
#[pyo3(signature = (model, q, v, a, gravity=None, viscous=false, coulomb=false, armature=false, offset=false, actuated=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub fn identification_regressor<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    a: &Bound<'_, PyAny>,
    gravity: Option<&Bound<'_, PyAny>>,
    viscous: bool,
    coulomb: bool,
    armature: bool,
    offset: bool,
    actuated: Vec<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let model = model.model();
    let g = gravity_arg(py, gravity)?;
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
) -> PyResult<(Vec<String>, Bound<'py, PyAny>)> {
    let model = model.model();
    let ex = extras(viscous, coulomb, armature, offset);
    let names = ident::parameter_names(&model, &ex);
    let mut values = ident::model_parameters(&model);
    values.resize(names.len(), 0.0);
    Ok((names, to_array1(py, &values).into_any()))
}

/// Base parameters of a regressor `y` (rows, p): `(rank, independent, dependent,
/// coefficients (rank, p − rank), pivots)`.
#[pyfunction]
#[pyo3(signature = (y, rank_tol=1e-8))]
pub fn identification_base<'py>(
    py: Python<'py>,
    y: &Bound<'_, PyAny>,
    rank_tol: f64,
) -> PyResult<Bound<'py, PyDict>> {
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
    let base = detach_interruptible(py, || {
        Ok(ident::base_parameters(
            &ident::identify::reduced(&m).r,
            rank_tol,
        ))
    })?;
    base_dict(py, &base)
}

fn base_dict<'py>(py: Python<'py>, base: &ident::Base) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("rank", base.rank)?;
    d.set_item("independent", base.independent.clone())?;
    d.set_item("dependent", base.dependent.clone())?;
    d.set_item("coefficients", dmatrix_to_array(py, &base.coefficients)?)?;
    d.set_item("pivots", to_array1(py, &base.pivots))?;
    Ok(d)
}

/// The identification (crate::identification::identify); `cells`: a list of
/// `(link index, centres (K, 3), side)` for method "cells".
#[pyfunction]
#[pyo3(signature = (model, q, v, a, tau, gravity, method, free, prior, prior_weight, weights, cells, viscous, coulomb, armature, offset, rank_tol=1e-8, actuated=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub fn identification_fit<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    a: &Bound<'_, PyAny>,
    tau: &Bound<'_, PyAny>,
    gravity: Option<&Bound<'_, PyAny>>,
    method: &str,
    free: Vec<bool>,
    prior: Vec<f64>,
    prior_weight: f64,
    weights: Vec<f64>,
    cells: Vec<(usize, Bound<'_, PyAny>, f64)>,
    viscous: bool,
    coulomb: bool,
    armature: bool,
    offset: bool,
    rank_tol: f64,
    actuated: Vec<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = model.model();
    let g = gravity_arg(py, gravity)?;
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
    let d = PyDict::new(py);
    d.set_item("names", out.names.clone())?;
    d.set_item("free", out.free.clone())?;
    d.set_item("base", base_dict(py, &out.base)?)?;
    d.set_item("base_names", out.base_names.clone())?;
    d.set_item("beta", to_array1(py, &out.fit.beta))?;
    d.set_item("std", to_array1(py, &out.fit.std))?;
    d.set_item("pi", to_array1(py, &out.fit.pi))?;
    d.set_item("rss", out.fit.rss)?;
    d.set_item("condition", out.fit.condition)?;
    d.set_item("structural_rank", out.structural_rank)?;
    d.set_item("residuals", to_array1(py, &out.residuals))?;
    let masses: Vec<Bound<'py, PyAny>> = out
        .masses
        .iter()
        .map(|m| to_array1(py, m).into_any())
        .collect();
    d.set_item("masses", masses)?;
    Ok(d)
}

/// A copy of `model` with links `links` given the parameters `pi` (10 per link, all links)
/// and the armature of the 1-dof joints when given.
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
