//! Arguments and results of the design functions (crate::design): cells of an envelope, the
//! maps along a motion, a body's pins, and the conic program. Conversion only.
use nalgebra::{DMatrix, DVector};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::convert::{array, mat3_to_array, to_array, to_array1};
use super::errors::{check_result, invalid};
use super::model::PyModel;
use super::signals::detach_interruptible;
use crate::design::{self, Envelope, Norm, Problem, Quantity};
use crate::support::spatial::{Mat3, Vec3};

fn points3(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Vec<Vec3>> {
    let (shape, data) = array(obj, arg)?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(invalid(
            obj.py(),
            arg,
            "an (N, 3) array",
            format!("shape {shape:?}"),
        ));
    }
    Ok(data
        .chunks(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect())
}

/// Cell centres (K, 3) of side `cell` in a `box` (2, 3), a `polygon` (P, 2) extruded over
/// `z` (2,), or a mesh of `triangles` (T, 3, 3).
#[pyfunction]
#[pyo3(signature = (cell, r#box=None, polygon=None, z=None, triangles=None))]
pub fn design_cells<'py>(
    py: Python<'py>,
    cell: f64,
    r#box: Option<&Bound<'_, PyAny>>,
    polygon: Option<&Bound<'_, PyAny>>,
    z: Option<(f64, f64)>,
    triangles: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let env = match (r#box, polygon, triangles) {
        (Some(b), None, None) => {
            let c = points3(b, "box")?;
            if c.len() != 2 {
                return Err(invalid(
                    py,
                    "box",
                    "(lower, upper) corners",
                    format!("{} points", c.len()),
                ));
            }
            Envelope::Box {
                lower: c[0],
                upper: c[1],
            }
        }
        (None, Some(p), None) => {
            let (shape, data) = array(p, "polygon")?;
            if shape.len() != 2 || shape[1] != 2 {
                return Err(invalid(
                    py,
                    "polygon",
                    "a (P, 2) array of vertices",
                    format!("shape {shape:?}"),
                ));
            }
            let z = z.ok_or_else(|| invalid(py, "z", "(z_low, z_high) for a polygon", "None"))?;
            Envelope::Prism {
                polygon: data.chunks(2).map(|c| [c[0], c[1]]).collect(),
                z,
            }
        }
        (None, None, Some(t)) => {
            let (shape, data) = array(t, "triangles")?;
            if shape.len() != 3 || shape[1] != 3 || shape[2] != 3 {
                return Err(invalid(
                    py,
                    "triangles",
                    "a (T, 3, 3) array",
                    format!("shape {shape:?}"),
                ));
            }
            let v = |k: usize| Vec3::new(data[3 * k], data[3 * k + 1], data[3 * k + 2]);
            Envelope::Mesh {
                triangles: (0..shape[0])
                    .map(|t| [v(3 * t), v(3 * t + 1), v(3 * t + 2)])
                    .collect(),
            }
        }
        _ => {
            return Err(invalid(
                py,
                "envelope",
                "exactly one of box, polygon or triangles",
                "none or several",
            ))
        }
    };
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
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    a: &Bound<'_, PyAny>,
    gravity: Option<&Bound<'_, PyAny>>,
    about: &Bound<'_, PyAny>,
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

/// The joints a body carries, in its own frame: `(point, axis)` pairs (axis zero for a
/// spherical joint) — its own joint, its children's, and the cut joints on it.
#[pyfunction]
pub fn design_pins<'py>(
    py: Python<'py>,
    model: PyRef<'_, PyModel>,
    body: &Bound<'_, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let model = model.model();
    let b = super::loops::body_ref(&model, Some(body), "body")?.ok_or_else(|| {
        invalid(
            py,
            "body",
            "a body of the model (not the world)",
            "the world",
        )
    })?;
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
    body: &Bound<'_, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    use crate::design::strength::{pin_loads, PinSource};
    let model = model.model();
    let b = super::loops::body_ref(&model, Some(body), "body")?.ok_or_else(|| {
        invalid(
            py,
            "body",
            "a body of the model (not the world)",
            "the world",
        )
    })?;
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

/// The design program as `pointmass_dyn.design` states it: a dict read key by key into
/// typed fields (`design_solve`'s argument; built by our Python, not by users).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct ProblemSpec {
    ndelta: usize,
    #[pyo3(from_py_with = reals)]
    lower: Vec<f64>,
    #[pyo3(from_py_with = reals)]
    upper: Vec<f64>,
    map_rows: Vec<usize>,
    map_cols: Vec<usize>,
    #[pyo3(from_py_with = reals)]
    map_vals: Vec<f64>,
    groups: Vec<(Vec<usize>, f64, f64)>,
    equal: Vec<(usize, usize)>,
    quantities: Vec<QuantitySpec>,
    norm: String,
    mass_weight: f64,
    mass_reference: f64,
    mass_limit: Option<f64>,
    least_mass: bool,
    /// Connected links' flows (crate::design::connectivity).
    #[pyo3(default)]
    flows: Vec<FlowSpec>,
}

#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct QuantitySpec {
    name: String,
    #[pyo3(from_py_with = shaped)]
    rows: (Vec<usize>, Vec<f64>),
    #[pyo3(from_py_with = reals)]
    constant: Vec<f64>,
    dim: usize,
    samples: usize,
    weight: f64,
    reference: f64,
    limit: Option<f64>,
    zero: bool,
    /// A member's stress: its limit at every sample whatever the norm.
    #[pyo3(default)]
    peak: bool,
}

#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct FlowSpec {
    nodes: Vec<usize>,
    edges: Vec<(usize, usize)>,
    bosses: Vec<Vec<usize>>,
    web: f64,
    hang: f64,
}

fn reals(obj: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    Ok(array(obj, "problem")?.1)
}

fn shaped(obj: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    array(obj, "quantities")
}

impl ProblemSpec {
    /// The core's problem, the sizes checked against each other.
    fn problem(self, py: Python<'_>) -> PyResult<Problem> {
        let n = self.map_rows.len();
        if self.map_cols.len() != n || self.map_vals.len() != n {
            let got = "different lengths";
            return Err(invalid(
                py,
                "map",
                "rows, columns and values of one length",
                got,
            ));
        }
        let norm = match self.norm.as_str() {
            "rms" => Norm::Rms,
            "peak" => Norm::Peak,
            other => {
                return Err(invalid(
                    py,
                    "norm",
                    "\"rms\" or \"peak\"",
                    format!("'{other}'"),
                ))
            }
        };
        let ndelta = self.ndelta;
        let quantities = self.quantities.into_iter().map(|q| {
            let (shape, rows) = q.rows;
            if shape.len() != 2 || shape[1] != ndelta {
                let want = format!("rows of shape (R, {ndelta})");
                return Err(invalid(py, &q.name, want, format!("{shape:?}")));
            }
            Ok(Quantity {
                rows: DMatrix::from_row_slice(shape[0], ndelta, &rows),
                constant: DVector::from_vec(q.constant),
                dim: q.dim,
                samples: q.samples,
                weight: q.weight,
                reference: q.reference,
                limit: q.limit,
                zero: q.zero,
                peak: q.peak,
                name: q.name,
            })
        });
        let map = self
            .map_rows
            .into_iter()
            .zip(self.map_cols)
            .zip(self.map_vals);
        Ok(Problem {
            lower: self.lower,
            upper: self.upper,
            map: map.map(|((r, c), v)| (r, c, v)).collect(),
            ndelta,
            groups: self.groups,
            equal: self.equal,
            quantities: quantities.collect::<PyResult<_>>()?,
            norm,
            mass_weight: self.mass_weight,
            mass_reference: self.mass_reference,
            mass_limit: self.mass_limit,
            least_mass: self.least_mass,
            flows: self
                .flows
                .into_iter()
                .map(|f| design::Flow {
                    nodes: f.nodes,
                    edges: f.edges,
                    bosses: f.bosses,
                    web: f.web,
                    hang: f.hang,
                })
                .collect(),
        })
    }
}

/// Solves the design program (see `pointmass_dyn`'s design module).
#[pyfunction]
pub fn design_solve<'py>(py: Python<'py>, spec: ProblemSpec) -> PyResult<Bound<'py, PyDict>> {
    let problem = spec.problem(py)?;
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
