//! Arguments and results of the design functions (crate::design): cells of an envelope, the
//! maps along a motion, a body's pins, and the conic program. Conversion only.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::convert::{mat3_to_array, to_array, to_array1};
use super::errors::{check_result, invalid};
use super::model::PyModel;
use super::signals::detach_interruptible;
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

/// The maps along a motion: dict with `data` (N · rows, 10 · nlinks), `rows`, `nactuated`,
/// `nlinks`, `nloops` and `parameters` (the links' current ten numbers).
#[pyfunction]
#[pyo3(signature = (model, q, v, a, gravity, about, actuated))]
#[allow(clippy::too_many_arguments)]
pub fn design_regressor<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    q: &Obj,
    v: &Obj,
    a: &Obj,
    gravity: Option<&Obj>,
    about: &Obj,
    actuated: Vec<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = model.model();
    let g = crate::model::args::gravity(gravity)?;
    let about = super::convert::vec3(about, "about")?;
    let (_, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
    let reg = detach_interruptible(py, || {
        design::regressor(&model, &qs, &vs, &accs, &g, &about, &actuated)
    })?;
    check_result(py, "design regressor", reg.data.as_slice())?;
    let d = PyDict::new(py);
    let (r, c) = reg.data.shape();
    // Row-major for NumPy.
    let data: Vec<f64> = reg.data.transpose().as_slice().to_vec();
    d.set_item("data", to_array(py, data, &[r, c])?)?;
    d.set_item("rows", reg.layout.rows())?;
    d.set_item("nactuated", reg.layout.nactuated)?;
    d.set_item("nlinks", reg.layout.nlinks)?;
    d.set_item("nloops", reg.layout.nloops)?;
    d.set_item(
        "parameters",
        to_array1(py, &design::model_parameters(&model)),
    )?;
    Ok(d)
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

/// The pins of `design_pins` with where each one's force comes from (design/_strength.py):
/// dicts with `point`, `axis`, `kind` ("joint" or "cut"), `index` (link or cut joint),
/// `sign`, `frame_body` (the body whose axes the rows are in after `frame_rotation`; -1:
/// the world) and `frame_rotation` (3, 3).
#[pyfunction]
pub fn design_pin_loads<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    body: &Obj,
) -> PyResult<Bound<'py, PyList>> {
    use crate::design::strength::{pin_loads, PinSource};
    let model = model.model();
    let b = design_body(py, &model, body)?;
    let out = PyList::empty(py);
    for pin in pin_loads(&model, b) {
        let d = PyDict::new(py);
        d.set_item("point", to_array1(py, pin.point.as_slice()))?;
        d.set_item("axis", to_array1(py, pin.axis.as_slice()))?;
        let (kind, index, sign, frame_body, rot) = match pin.source {
            PinSource::Tree { link, sign } => ("joint", link, sign, -1, Mat3::identity()),
            PinSource::Cut {
                k,
                sign,
                body_a,
                frame_a,
            } => ("cut", k, sign, body_a.map_or(-1, |a| a as i64), frame_a),
        };
        d.set_item("kind", kind)?;
        d.set_item("index", index)?;
        d.set_item("sign", sign)?;
        d.set_item("frame_body", frame_body)?;
        d.set_item("frame_rotation", mat3_to_array(py, &rot)?)?;
        out.append(d)?;
    }
    Ok(out)
}

/// Solves the design program (see `pointmass_dyn`'s design module).
#[pyfunction]
pub fn design_solve<'py>(py: Python<'py>, spec: &Obj<'py>) -> PyResult<Bound<'py, PyDict>> {
    let problem = Problem::from_arg(spec)?;
    let outcome = detach_interruptible(py, || design::solve_outcome(&problem))?;
    let d = PyDict::new(py);
    let sol = match outcome {
        design::Outcome::Solved(sol) => sol,
        design::Outcome::Infeasible(relaxation) => {
            d.set_item("status", "Infeasible")?;
            d.set_item("message", relaxation.error().to_string())?;
            let items = relaxation
                .items
                .iter()
                .map(|r| {
                    (
                        r.name.clone(),
                        r.zero,
                        r.asked,
                        r.needed,
                        r.before,
                        r.binding(),
                        r.alone,
                    )
                })
                .collect::<Vec<_>>();
            d.set_item("relaxation", items)?;
            return Ok(d);
        }
    };
    d.set_item("x", to_array1(py, &sol.x))?;
    d.set_item("delta", to_array1(py, &sol.delta))?;
    d.set_item("values", to_array1(py, &sol.values))?;
    d.set_item("status", sol.status)?;
    d.set_item("objective", sol.objective)?;
    d.set_item("gap_abs", sol.gap_abs)?;
    d.set_item("gap_rel", sol.gap_rel)?;
    d.set_item("stages", sol.stages)?;
    d.set_item("notes", sol.notes)?;
    d.set_item("iterations", sol.iterations)?;
    d.set_item("rounds", sol.rounds)?;
    d.set_item("solve_time", sol.solve_time)?;
    Ok(d)
}
