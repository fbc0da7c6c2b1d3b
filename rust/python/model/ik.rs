//! `Model._inverse_kinematics` (`crate::frames::ik`), called by
//! `pointmass_dyn.inverse_kinematics`, which normalises the targets.
use crate::python::Obj;
use pyo3::prelude::*;

use super::frames::frame_arg;
use super::PyModel;
use crate::frames::ik::{self, Options, Target, Task};
use crate::python::convert::{mat3, vec3};
use crate::python::errors::{invalid, IntoPyResult};
use crate::python::record::record;
use crate::python::signals::detach_interruptible;
use crate::support::spatial::Placement;

#[pymethods]
impl PyModel {
    /// Tasks are (frame, rotation (3, 3) or None for a position target, position (3,),
    /// weights (3 or 6 floats)).
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (tasks, q0, limits, tol, max_iterations, restarts, seed))]
    fn _inverse_kinematics<'py>(
        &self,
        py: Python<'py>,
        tasks: Vec<(Obj<'py>, Option<Obj<'py>>, Obj<'py>, Vec<f64>)>,
        q0: &Obj,
        limits: bool,
        tol: f64,
        max_iterations: usize,
        restarts: usize,
        seed: u64,
    ) -> PyResult<PyIkSolution> {
        let (model, q0) = self
            .state_only(py, q0)
            .map_err(|e| super::rename(py, e, "q", "q0"))?;
        let mut list = Vec::with_capacity(tasks.len());
        for (frame, rot, pos, weights) in &tasks {
            let f = frame_arg(&model, frame, "targets")?;
            let t = vec3(pos, "targets")?;
            crate::support::error::check_finite("targets", t.as_slice()).py(py)?;
            let target = match rot {
                Some(r) if !r.is_none() => {
                    let r =
                        crate::model::checked_rotation(&mat3(r, "targets")?, "targets").py(py)?;
                    Target::Pose(Placement::new(r, t))
                }
                _ => Target::Position(t),
            };
            let rows = if matches!(target, Target::Pose(_)) {
                6
            } else {
                3
            };
            if weights.len() != rows || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
                return Err(invalid(
                    py,
                    "weights",
                    format!("{rows} finite weights >= 0 for this target"),
                    format!("{weights:?}"),
                ));
            }
            list.push(Task {
                frame: f,
                target,
                weights: weights.clone(),
            });
        }
        if !(tol > 0.0 && tol.is_finite()) {
            return Err(invalid(py, "tol", "a finite number > 0", tol));
        }
        let opts = Options {
            tol,
            max_iterations,
            restarts,
            limits: limits.then(|| ik::joint_limits(&model)),
            seed,
        };
        let sol = detach_interruptible(py, || ik::solve(&model, &list, &q0, &opts))?;
        Ok(PyIkSolution(sol))
    }
}

record!(
    /// What `Model._inverse_kinematics` found (`crate::frames::ik::Solution`).
    PyIkSolution("IkSolution", ik::Solution) { q, residual, errors, iterations, restarts, converged, message }
);
