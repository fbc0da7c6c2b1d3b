//! `Model`'s reactions (`crate::dynamics::reactions`): the point masses in motion, the balancing
//! regressors, shaking forces and bearing forces.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::PyModel;
use crate::dynamics::{reaction_args, reactions, stacked};
use crate::python::convert::to_array;
use crate::python::errors::to_py;
use crate::python::record::record;
use crate::python::signals::{detach_watched, stopped_with_partial};
use crate::support::spatial::Vec3;

#[pymethods]
impl PyModel {
    fn point_motion(&self, q: &Obj, v: &Obj, a: &Obj) -> PyResult<PyPointMotion> {
        let pm = reaction_args::point_motion(&self.model(), [q, v, a])?;
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
        let call = stacked::Call::point_regressor(&model, [q, v, a], points, gravity)?;
        stacked(py, || call.regressor(&model))
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
        let call = stacked::Call::shaking(&model, [q, v, a], about)?;
        let d = stacked(py, || call.shaking_forces(&model))?.into_any();
        Ok((d.get_item("force")?, d.get_item("moment")?))
    }

    #[pyo3(signature = (q, v, a, gravity=None, external=None, actuated=None, frame="joint"))]
    fn bearing_forces(
        &self,
        q: &Obj,
        v: &Obj,
        a: &Obj,
        gravity: Option<&Obj>,
        external: Option<&Obj>,
        actuated: Option<&Obj>,
        frame: &str,
    ) -> PyResult<PyBearingForces> {
        let given = (gravity, external, actuated);
        let out = reaction_args::bearing_forces(&self.model(), [q, v, a], given, frame)?;
        Ok(PyBearingForces(out))
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

/// The core's arrays as a dict; a computation stopped short raises, the dict (completed
/// with `states` and `message`) attached as the exception's `.result`.
fn stacked<'py>(
    py: Python<'py>,
    f: impl FnOnce() -> crate::support::error::Result<stacked::Stacked> + Send,
) -> PyResult<Bound<'py, PyDict>> {
    let (done, raised) = detach_watched(py, f);
    let done = match done {
        Ok(done) => done,
        Err(e) => return Err(raised.unwrap_or_else(|| to_py(py, e))),
    };
    let d = PyDict::new(py);
    for (key, x, shape) in done.arrays {
        d.set_item(key, to_array(py, x, &shape)?)?;
    }
    let Some(stop) = done.stopped else {
        return Ok(d);
    };
    d.set_item("states", stop.states)?;
    d.set_item("message", &stop.message)?;
    let note = format!(
        "{}; the states done are in this exception's .result",
        stop.message
    );
    Err(stopped_with_partial(
        py,
        raised,
        stop.why,
        d.as_any(),
        &note,
    ))
}
