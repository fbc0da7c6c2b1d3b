//! `Model`'s closed loops: cut joints and assembly (their residual, Jacobian and forces
//! are one-state quantities, in `dynamics.rs`).
use crate::python::Obj;
use pyo3::prelude::*;

use super::PyModel;
use crate::loops;
use crate::model::args::fixed_mask;
use crate::python::convert::to_array1;
use crate::python::errors::IntoPyResult;
use crate::python::joint::PyJoint;
use crate::python::record::record;

#[pymethods]
impl PyModel {
    #[pyo3(signature = (body_a, body_b, joint, translation_a=None, translation_b=None, rotation_a=None, rotation_b=None, name=None))]
    fn add_loop(
        &self,
        py: Python<'_>,
        body_a: Option<&Obj>,
        body_b: Option<&Obj>,
        joint: PyRef<'_, PyJoint>,
        translation_a: Option<&Obj>,
        translation_b: Option<&Obj>,
        rotation_a: Option<&Obj>,
        rotation_b: Option<&Obj>,
        name: Option<String>,
    ) -> PyResult<usize> {
        let [(a, fa), (b, fb)] = loops::args::loop_ends(
            &self.model(),
            [body_a, body_b],
            [translation_a, translation_b],
            [rotation_a, rotation_b],
        )?;
        self.shared
            .update(|m| m.add_loop(a, b, joint.inner, fa, fb, name))
            .py(py)
    }

    fn loop_solver_info(&self) -> PyLoopLayout {
        PyLoopLayout(loops::solver_layout(&self.model()))
    }

    #[pyo3(signature = (q_guess, fixed=None, tol=1e-12, max_iterations=None))]
    fn assemble<'py>(
        &self,
        py: Python<'py>,
        q_guess: &Obj,
        fixed: Option<&Obj>,
        tol: f64,
        max_iterations: Option<&Obj>,
    ) -> PyResult<Obj<'py>> {
        let (model, q, _) = self.state_as((q_guess, "q_guess"), None)?;
        let (tol, max_iterations) = loops::args::assembly(tol, max_iterations)?;
        let mask = fixed_mask(&model, fixed)?;
        let q = py.detach(|| loops::assemble(&model, &q, &mask, tol, max_iterations))?;
        Ok(to_array1(py, &q).into_any())
    }
}

crate::python::getters!(PyModel |s, py| {
    nloops -> usize = s.model().nloops(),
    nconstraints -> usize = s.model().nconstraints(),
    loop_names -> Vec<String> = s.model().loops.iter().map(|l| l.name.clone()).collect(),
});

record!(
    /// How the loop solver factors a model (`Model.loop_solver_info`).
    PyLoopLayout("LoopSolverInfo", loops::Layout) { banded, order, profile, model_profile }
);
