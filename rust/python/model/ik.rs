//! `Model._inverse_kinematics` (`crate::frames::ik`), called by
//! `pointmass_dyn.inverse_kinematics`, which normalises the targets.
use crate::python::Obj;
use pyo3::prelude::*;

use super::PyModel;
use crate::frames::args::{ik_options, ik_tasks};
use crate::frames::ik;
use crate::python::record::record;
use crate::python::signals::detach_interruptible;

#[pymethods]
impl PyModel {
    /// Tasks are (frame, rotation (3, 3) or None for a position target, position (3,),
    /// weights (3 or 6 floats)).
    #[pyo3(signature = (tasks, q0, limits, tol, max_iterations, restarts, seed))]
    fn _inverse_kinematics(
        &self,
        py: Python<'_>,
        tasks: &Obj,
        q0: &Obj,
        limits: bool,
        tol: f64,
        max_iterations: usize,
        restarts: usize,
        seed: u64,
    ) -> PyResult<PyIkSolution> {
        let (model, q0, _) = self.state_as((q0, "q0"), None)?;
        let tasks = ik_tasks(&model, tasks)?;
        let opts = ik_options(&model, limits, tol, [max_iterations, restarts], seed)?;
        let sol = detach_interruptible(py, || ik::solve(&model, &tasks, &q0, &opts))?;
        Ok(PyIkSolution(sol))
    }
}

record!(
    /// What `Model._inverse_kinematics` found (`crate::frames::ik::Solution`).
    PyIkSolution("IkSolution", ik::Solution) { q, residual, errors, iterations, restarts, converged, message }
);
