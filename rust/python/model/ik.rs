//! `Model._inverse_kinematics` (`crate::frames::ik`), called by
//! `pointmass_dyn.inverse_kinematics`, which normalises the targets.
use crate::python::Obj;
use pyo3::prelude::*;

use super::calls::calls;
use super::PyModel;
use crate::frames::{calls, ik};
use crate::python::record::record;

calls! {
    /// Tasks are (frame, rotation (3, 3) or None for a position target, position (3,),
    /// weights (3 or 6 floats)).
    #[pyo3(signature = (tasks, q0, limits, tol, max_iterations, restarts, seed))]
    fn _inverse_kinematics(
        tasks: &Obj, q0: &Obj, limits: bool, tol: f64, max_iterations: usize, restarts: usize,
        seed: u64
    ) = calls::inverse_kinematics => PyIkSolution detached;
}

record!(
    /// What `Model._inverse_kinematics` found (`crate::frames::ik::Solution`).
    PyIkSolution("IkSolution", ik::Solution) { q, residual, errors, iterations, restarts, converged, message }
);
