//! Arguments and results of the design functions (crate::design): cells of an envelope, the
//! maps along a motion, a body's pins, and the conic program. Conversion only.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::IntoPyObjectExt;

use super::convert::{mat3_to_array, to_array, to_array1};
use super::model::PyModel;
use super::record::record;
use super::signals::detach_interruptible;
use crate::design::results::{pin_records, Maps, PinRecord};
use crate::design::{self, Envelope, Problem, Relaxation, Relaxed};
use crate::model::args::some_body;
use crate::support::spatial::Vec3;

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
    let flat = cells.iter().flat_map(|c| c.iter().copied()).collect();
    to_array(py, flat, &[cells.len(), 3])
}

record!(
    /// The maps along a motion: `data` (N · rows, 10 · nlinks), `rows`, `nactuated`,
    /// `nlinks`, `nloops` and `parameters` (the links' current ten numbers).
    PyMaps("DesignMaps", Maps) { data, rows, nactuated, nlinks, nloops, parameters }
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
    let call = design::MapsCall::from_args(&model, [q, v, a], gravity, about)?;
    Ok(PyMaps(detach_interruptible(py, || {
        call.maps(&model, &actuated)
    })?))
}

/// The joints a body carries, in its own frame: `(point, axis)` pairs (axis zero for a
/// spherical joint) — its own joint, its children's, and the cut joints on it.
#[pyfunction]
pub fn design_pins<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    body: &Obj,
) -> PyResult<Vec<(Obj<'py>, Obj<'py>)>> {
    let model = model.model();
    let pins = design::pins(&model, some_body(&model, body, "body")?);
    let array = |x: Vec3| to_array1(py, x.as_slice()).into_any();
    Ok(pins
        .into_iter()
        .map(|(p, a)| (array(p), array(a)))
        .collect())
}

record!(
    /// A pin of `design_pins` with where its force comes from (design/_strength.py): `point`,
    /// `axis`, `kind` ("joint" or "cut"), `index` (link or cut joint), `sign`, `frame_body`
    /// (the body whose axes the rows are in after `frame_rotation`; -1: the world) and
    /// `frame_rotation` (3, 3).
    PyPinLoad("PinLoad", PinRecord) {
        point, axis, kind, index, sign,
        frame_body: |p: &PinRecord, py| p.frame_body.into_bound_py_any(py),
        frame_rotation: |p: &PinRecord, py| mat3_to_array(py, &p.frame_rotation),
    }
);

/// The pins of `design_pins` (same order), each a `PinLoad`.
#[pyfunction]
pub fn design_pin_loads(model: PyRef<'_, PyModel>, body: &Obj) -> PyResult<Vec<PyPinLoad>> {
    let model = model.model();
    let b = some_body(&model, body, "body")?;
    Ok(pin_records(&model, b).into_iter().map(PyPinLoad).collect())
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

record!(
    /// An infeasible design program: `status` "Infeasible", the `message` naming the binding
    /// requirements, and per requirement its `relaxation` `(name, zero, asked, needed,
    /// before, binding, alone)`.
    PyDesignInfeasible("DesignInfeasible", Relaxation) {
        status: |_: &Relaxation, py| "Infeasible".into_bound_py_any(py),
        message: |r: &Relaxation, py| r.error().to_string().into_bound_py_any(py),
        relaxation: |r: &Relaxation, py| {
            let row = |r: &Relaxed| (r.name.clone(), r.zero, r.asked, r.needed, r.before, r.binding(), r.alone);
            r.items.iter().map(row).collect::<Vec<_>>().into_bound_py_any(py)
        },
    }
);

/// Solves the design program (see `pointmass_dyn`'s design module): a `DesignSolution`, or
/// a `DesignInfeasible`.
#[pyfunction]
pub fn design_solve<'py>(py: Python<'py>, spec: &Obj<'py>) -> PyResult<Obj<'py>> {
    let problem = Problem::from_arg(spec)?;
    match detach_interruptible(py, || design::solve_outcome(&problem))? {
        design::Outcome::Solved(sol) => PyDesignSolution(sol).into_bound_py_any(py),
        design::Outcome::Infeasible(relaxation) => {
            PyDesignInfeasible(relaxation).into_bound_py_any(py)
        }
    }
}
