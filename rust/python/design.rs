//! Arguments and results of the design functions (crate::design): cells of an envelope, the
//! maps along a motion, a body's pins, and the conic program. Conversion only.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use pyo3::IntoPyObjectExt;

use super::convert::{mat3_to_array, to_array, to_array1};
use super::errors::{check_result, invalid};
use super::model::PyModel;
use super::record::{record, Field};
use super::signals::detach_interruptible;
use crate::design::strength::{pin_loads, PinLoad, PinSource};
use crate::design::{self, Envelope, Problem};
use crate::support::spatial::Mat3;

/// Cell centres (K, 3) of side `cell` in a `box` (2, 3), a `polygon` (P, 2) extruded over
/// `z` (2,), or a mesh of `triangles` (T, 3, 3).
#[pyfunction]
#[pyo3(signature = (cell, r#box=None, polygon=None, z=None, triangles=None))]
pub fn design_cells<'py>(
    py: Python<'py>,
    cell: f64,
    r#box: Option<&Obj>,
    polygon: Option<&Obj>,
    z: Option<&Obj>,
    triangles: Option<&Obj>,
) -> PyResult<Obj<'py>> {
    let env = Envelope::from_args(r#box, polygon, z, triangles)?;
    let cells = detach_interruptible(py, || design::fill(&env, cell))?;
    let n = cells.len();
    to_array(
        py,
        cells.iter().flat_map(|c| c.iter().copied()).collect(),
        &[n, 3],
    )
}

/// `design_regressor`'s result: the maps along a motion and the links' parameters now.
pub struct Maps {
    reg: design::Regressor,
    parameters: Vec<f64>,
}

record!(
    /// The maps along a motion: `data` (N · rows, 10 · nlinks), `rows`, `nactuated`,
    /// `nlinks`, `nloops` and `parameters` (the links' current ten numbers).
    PyMaps("DesignMaps", Maps) {
        data: |m: &Maps, py| m.reg.data.field(py),
        rows: |m: &Maps, py| m.reg.layout.rows().field(py),
        nactuated: |m: &Maps, py| m.reg.layout.nactuated.field(py),
        nlinks: |m: &Maps, py| m.reg.layout.nlinks.field(py),
        nloops: |m: &Maps, py| m.reg.layout.nloops.field(py),
        parameters: |m: &Maps, py| m.parameters.field(py),
    }
);

/// The maps along a motion (`DesignMaps`).
#[pyfunction]
#[pyo3(signature = (model, q, v, a, gravity, about, actuated))]
pub fn design_regressor(
    py: Python<'_>,
    model: PyRef<'_, PyModel>,
    q: &Obj,
    v: &Obj,
    a: &Obj,
    gravity: Option<&Obj>,
    about: &Obj,
    actuated: Vec<usize>,
) -> PyResult<PyMaps> {
    let model = model.model();
    let g = crate::model::args::gravity(gravity)?;
    let about = super::convert::vec3(about, "about")?;
    let (_, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
    let reg = detach_interruptible(py, || {
        design::regressor(&model, &qs, &vs, &accs, &g, &about, &actuated)
    })?;
    check_result(py, "design regressor", reg.data.as_slice())?;
    let parameters = design::model_parameters(&model);
    Ok(PyMaps(Maps { reg, parameters }))
}

/// `body` (a name or an index) as a body of `model`, the world refused.
fn design_body(py: Python<'_>, model: &crate::model::Model, body: &Obj) -> PyResult<usize> {
    let b = super::loops::body_ref(model, Some(body), "body")?;
    let expected = "a body of the model (not the world)";
    b.ok_or_else(|| invalid(py, "body", expected, "the world"))
}

/// The joints a body carries, in its own frame: `(point, axis)` pairs (axis zero for a
/// spherical joint) — its own joint, its children's, and the cut joints on it.
#[pyfunction]
pub fn design_pins<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    body: &Obj,
) -> PyResult<Bound<'py, PyList>> {
    let model = model.model();
    let b = design_body(py, &model, body)?;
    let pins = design::pins(&model, b);
    let out = PyList::empty(py);
    for (p, axis) in pins {
        out.append((to_array1(py, p.as_slice()), to_array1(py, axis.as_slice())))?;
    }
    Ok(out)
}

record!(
    /// A pin of `design_pins` with where its force comes from (design/_strength.py): `point`,
    /// `axis`, `kind` ("joint" or "cut"), `index` (link or cut joint), `sign`, `frame_body`
    /// (the body whose axes the rows are in after `frame_rotation`; -1: the world) and
    /// `frame_rotation` (3, 3).
    PyPinLoad("PinLoad", PinLoad) {
        point: |p: &PinLoad, py| p.point.as_slice().to_vec().field(py),
        axis: |p: &PinLoad, py| p.axis.as_slice().to_vec().field(py),
        kind: |p: &PinLoad, py| source(p).0.into_bound_py_any(py),
        index: |p: &PinLoad, py| source(p).1.into_bound_py_any(py),
        sign: |p: &PinLoad, py| source(p).2.into_bound_py_any(py),
        frame_body: |p: &PinLoad, py| source(p).3.into_bound_py_any(py),
        frame_rotation: |p: &PinLoad, py| mat3_to_array(py, &source(p).4),
    }
);

/// A pin's `(kind, index, sign, frame_body, frame_rotation)`.
fn source(p: &PinLoad) -> (&'static str, usize, f64, i64, Mat3) {
    match p.source {
        PinSource::Tree { link, sign } => ("joint", link, sign, -1, Mat3::identity()),
        PinSource::Cut {
            k,
            sign,
            body_a,
            frame_a,
        } => ("cut", k, sign, body_a.map_or(-1, |a| a as i64), frame_a),
    }
}

/// The pins of `design_pins` (same order), each a `PinLoad`.
#[pyfunction]
pub fn design_pin_loads(
    py: Python<'_>,
    model: PyRef<'_, PyModel>,
    body: &Obj,
) -> PyResult<Vec<PyPinLoad>> {
    let model = model.model();
    let b = design_body(py, &model, body)?;
    Ok(pin_loads(&model, b).into_iter().map(PyPinLoad).collect())
}

record!(
    /// A solved design program: the masses `x`, the parameters' change `delta`, each
    /// quantity's `values`, the last stage's `status`, `objective` and gaps, each stage's
    /// certificate (`stages`), `notes`, and the solver's `iterations`, `rounds`, `solve_time`.
    PyDesignSolution("DesignSolution", design::Solution) {
        x, delta, values, status, objective, gap_abs, gap_rel,
        stages: |s: &design::Solution, py| s.stages.clone().into_bound_py_any(py),
        notes,
        iterations: |s: &design::Solution, py| s.iterations.into_bound_py_any(py),
        rounds: |s: &design::Solution, py| s.rounds.into_bound_py_any(py),
        solve_time,
    }
);

/// Solves the design program (see `pointmass_dyn`'s design module): a `DesignSolution`, or
/// for an infeasible one a dict of `status` "Infeasible", `message` and `relaxation`.
#[pyfunction]
pub fn design_solve<'py>(py: Python<'py>, spec: &Obj<'py>) -> PyResult<Obj<'py>> {
    let problem = Problem::from_arg(spec)?;
    let relaxation = match detach_interruptible(py, || design::solve_outcome(&problem))? {
        design::Outcome::Solved(sol) => return PyDesignSolution(sol).into_bound_py_any(py),
        design::Outcome::Infeasible(relaxation) => relaxation,
    };
    let d = PyDict::new(py);
    d.set_item("status", "Infeasible")?;
    d.set_item("message", relaxation.error().to_string())?;
    let item = |r: &design::problem::Relaxed| {
        let (name, binding) = (r.name.clone(), r.binding());
        (name, r.zero, r.asked, r.needed, r.before, binding, r.alone)
    };
    d.set_item(
        "relaxation",
        relaxation.items.iter().map(item).collect::<Vec<_>>(),
    )?;
    Ok(d.into_any())
}
