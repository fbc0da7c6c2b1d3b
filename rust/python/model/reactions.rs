//! `Model`'s reactions (`crate::dynamics::reactions`): the point masses in motion, the balancing
//! regressors, shaking forces and bearing forces.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::PyModel;
use crate::dynamics::reactions;
use crate::model::args::loop_actuation;
use crate::python::convert::to_array;
use crate::python::errors::{check_result, invalid, to_py, IntoPyResult};
use crate::python::record::record;
use crate::python::signals::{detach_watched, stopped_with_partial};
use crate::recursive;
use crate::support::spatial::Vec3;

#[pymethods]
impl PyModel {
    fn point_motion(&self, py: Python<'_>, q: &Obj, v: &Obj, a: &Obj) -> PyResult<PyPointMotion> {
        let model = self.model();
        let (qs, vs, accs) = one_state(&model, q, v, a)?;
        let mut ws = recursive::reference::Workspace::new(&model);
        let mut pm = reactions::PointMotion::default();
        reactions::point_motion(&model, &mut ws, &qs, &vs, &accs, &mut pm);
        for (k, x) in [
            ("positions", &pm.positions),
            ("velocities", &pm.velocities),
            ("accelerations", &pm.accelerations),
        ] {
            check_result(py, &format!("point_motion['{k}']"), &flat(x))?;
        }
        Ok(PyPointMotion(pm))
    }

    #[pyo3(signature = (q, v, a, points=None, gravity=None))]
    fn point_regressor<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        a: &Obj,
        points: Option<&Obj>,
        gravity: Option<&Obj>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let model = self.model();
        let g = crate::model::args::gravity(gravity)?;
        let (count, qs, vs, accs) = crate::python::reactions::states(&model, q, v, a)?;
        let pts = crate::model::args::body_points(&model, points)?;
        let rows = count.unwrap_or(1);
        let (np, nv) = (pts.len(), model.nv);
        let states = reactions::States {
            rows,
            q: &qs,
            v: &vs,
            a: &accs,
        };
        let (done, raised) =
            detach_watched(py, || reactions::point_regressor(&model, &states, &pts, &g));
        let reactions::Rows {
            value,
            rows: reached,
            stopped,
        } = match done {
            Ok(done) => done,
            Err(e) => return Err(raised.unwrap_or_else(|| to_py(py, e))),
        };
        let (pos, acc, gen) = (value.positions, value.accelerations, value.generalized);
        for (k, x) in [
            ("positions", &pos),
            ("accelerations", &acc),
            ("generalized", &gen),
        ] {
            check_result(py, &format!("point_regressor['{k}']"), x)?;
        }
        let lead: Vec<usize> = count.map(|_| reached).into_iter().collect();
        let shape = |tail: &[usize]| [lead.as_slice(), tail].concat();
        let d = PyDict::new(py);
        d.set_item("positions", to_array(py, pos, &shape(&[np, 3]))?)?;
        d.set_item("accelerations", to_array(py, acc, &shape(&[np, 3]))?)?;
        d.set_item("generalized", to_array(py, gen, &shape(&[np, nv]))?)?;
        match stopped {
            None => Ok(d),
            Some(why) => Err(partial_rows(
                py,
                &d,
                "point_regressor",
                reached,
                rows,
                raised,
                why,
            )),
        }
    }

    #[pyo3(signature = (q, v, a, about=None))]
    fn shaking<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        a: &Obj,
        about: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Obj<'py>)> {
        let model = self.model();
        let (count, qs, vs, accs) = crate::python::reactions::states(&model, q, v, a)?;
        let about = crate::model::args::about(about)?;
        let states = reactions::States {
            rows: count.unwrap_or(1),
            q: &qs,
            v: &vs,
            a: &accs,
        };
        let (done, raised) =
            detach_watched(py, || reactions::shaking_of_states(&model, &states, &about));
        let (force, moment) = done.value;
        check_result(py, "shaking", &force)?;
        check_result(py, "shaking", &moment)?;
        let shape: Vec<usize> = match count {
            Some(_) => vec![done.rows, 3],
            None => vec![3],
        };
        let (force, moment) = (to_array(py, force, &shape)?, to_array(py, moment, &shape)?);
        match done.stopped {
            None => Ok((force, moment)),
            Some(why) => {
                let d = PyDict::new(py);
                d.set_item("force", force)?;
                d.set_item("moment", moment)?;
                let n = count.unwrap_or(1);
                Err(partial_rows(py, &d, "shaking", done.rows, n, raised, why))
            }
        }
    }

    #[pyo3(signature = (q, v, a, gravity=None, external=None, actuated=None, frame="joint"))]
    #[allow(clippy::too_many_arguments)]
    fn bearing_forces(
        &self,
        py: Python<'_>,
        q: &Obj,
        v: &Obj,
        a: &Obj,
        gravity: Option<&Obj>,
        external: Option<&Obj>,
        actuated: Option<&Obj>,
        frame: &str,
    ) -> PyResult<PyBearingForces> {
        let world = crate::python::reactions::world_frame(py, frame)?;
        let model = self.model();
        let g = crate::model::args::gravity(gravity)?;
        let (qs, vs, accs) = one_state(&model, q, v, a)?;
        let ext = crate::model::args::external(&model, external)?;
        let actuated = loop_actuation(&model, actuated)?;
        let (ext, actuated) = (ext.as_deref(), actuated.as_deref());
        let out = reactions::bearing_forces(&model, &qs, &vs, &accs, &g, ext, actuated, world);
        let out = out.py(py)?;
        check_result(py, "bearing_forces", &out.joints)?;
        Ok(PyBearingForces(out))
    }
}

/// `(q, v, a)` of one state (`crate::python::reactions::states`), a stack refused.
fn one_state(
    model: &crate::model::Model,
    q: &Obj,
    v: &Obj,
    a: &Obj,
) -> PyResult<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    match crate::python::reactions::states(model, q, v, a)? {
        (None, qs, vs, accs) => Ok((qs, vs, accs)),
        _ => {
            let expected = format!("shape ({},): one state", model.nq);
            Err(invalid(q.py(), "q", expected, "a stack of states"))
        }
    }
}

fn flat(x: &[Vec3]) -> Vec<f64> {
    x.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
}

/// Points of the links, seven per link, as (n, 7, 3).
fn sevens<'py>(py: Python<'py>, x: &[Vec3]) -> PyResult<Obj<'py>> {
    to_array(py, flat(x), &[x.len() / 7, 7, 3])
}

record!(
    /// The links' point masses in motion (`Model.point_motion`).
    PyPointMotion("PointMotion", reactions::PointMotion) {
        masses: |r: &reactions::PointMotion, py| to_array(py, r.masses.clone(), &[r.masses.len() / 7, 7]),
        positions: |r: &reactions::PointMotion, py| sevens(py, &r.positions),
        velocities: |r: &reactions::PointMotion, py| sevens(py, &r.velocities),
        accelerations: |r: &reactions::PointMotion, py| sevens(py, &r.accelerations),
    }
);

record!(
    /// What every joint transmits at one state (`Model.bearing_forces`).
    PyBearingForces("BearingForces", reactions::BearingForces) {
        joints: |r: &reactions::BearingForces, py| to_array(py, r.joints.clone(), &[r.joints.len() / 6, 6]),
        loops: |r: &reactions::BearingForces, py| {
            let flat: Vec<f64> = r.loops.iter().flatten().copied().collect();
            to_array(py, flat, &[r.loops.len(), 6])
        },
        tau,
    }
);

/// The exception of a computation over `total` states stopped after `reached`: `partial`
/// (completed with `states` and `message`) attached as `.result`.
fn partial_rows(
    py: Python<'_>,
    partial: &Bound<'_, PyDict>,
    what: &str,
    reached: usize,
    total: usize,
    raised: Option<PyErr>,
    why: crate::support::error::Error,
) -> PyErr {
    let message = format!("{what} stopped after {reached} of {total} states: interrupted");
    let _ = partial.set_item("states", reached);
    let _ = partial.set_item("message", &message);
    let note = format!("{message}; the states done are in this exception's .result");
    stopped_with_partial(py, raised, why, partial.as_any(), &note)
}
