//! `Model`'s closed loops: cut joints, their residuals and Jacobian, assembly, and the cut
//! joints' forces.
use crate::python::Obj;
use pyo3::prelude::*;

use super::{load_state, load_x, rename, PyModel};
use crate::loops;
use crate::python::convert::{dmatrix_to_array, to_array, to_array1};
use crate::python::errors::{check_result, invalid, IntoPyResult};
use crate::python::joint::PyJoint;
use crate::python::loops::body_ref;
use crate::python::record::record;
use crate::support::args::placement;

#[pymethods]
impl PyModel {
    #[pyo3(signature = (body_a, body_b, joint, translation_a=None, translation_b=None, rotation_a=None, rotation_b=None, name=None))]
    #[allow(clippy::too_many_arguments)]
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
        let fa = placement(translation_a, rotation_a, "translation_a", "rotation_a")?;
        let fb = placement(translation_b, rotation_b, "translation_b", "rotation_b")?;
        let model = self.model();
        let a = body_ref(&model, body_a, "body_a")?;
        let b = body_ref(&model, body_b, "body_b")?;
        // The handle let go first, so that the update extends the model in place.
        drop(model);
        self.shared
            .update(|m| m.add_loop(a, b, joint.inner, fa, fb, name))
            .py(py)
    }

    #[getter]
    fn nloops(&self) -> usize {
        self.model().nloops()
    }

    #[getter]
    fn nconstraints(&self) -> usize {
        self.model().nconstraints()
    }

    #[getter]
    fn loop_names(&self) -> Vec<String> {
        self.model().loops.iter().map(|l| l.name.clone()).collect()
    }

    fn constraint_residual<'py>(&self, py: Python<'py>, q: &Obj) -> PyResult<Obj<'py>> {
        let (model, q) = self.state_only(py, q)?;
        let mut kin = loops::LoopKinematics::new(&model);
        kin.positions(&model, &q);
        let mut r = vec![0.0; model.nconstraints()];
        loops::residual(&model, &kin, &mut r);
        check_result(py, "constraint_residual", &r)?;
        Ok(to_array1(py, &r).into_any())
    }

    fn constraint_jacobian<'py>(&self, py: Python<'py>, q: &Obj) -> PyResult<Obj<'py>> {
        let (model, q) = self.state_only(py, q)?;
        let mut kin = loops::LoopKinematics::new(&model);
        kin.positions(&model, &q);
        let mut j = nalgebra::DMatrix::zeros(model.nconstraints(), model.nv);
        loops::jacobian(&model, &kin, &mut j);
        check_result(py, "constraint_jacobian", j.as_slice())?;
        dmatrix_to_array(py, &j)
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
        let (model, q) = self
            .state_only(py, q_guess)
            .map_err(|e| rename(py, e, "q", "q_guess"))?;
        if !(tol > 0.0 && tol.is_finite()) {
            return Err(invalid(py, "tol", "a positive finite number", tol));
        }
        let max_iterations = match max_iterations.filter(|m| !m.is_none()) {
            Some(m) => crate::python::convert::int_arg(
                m,
                "max_iterations",
                1,
                i64::MAX,
                "a whole number of iterations >= 1",
            )? as usize,
            None => 50,
        };
        let mask = crate::python::loops::fixed_mask(&model, fixed)?;
        let q = py
            .detach(|| loops::assemble(&model, &q, &mask, tol, max_iterations))
            .py(py)?;
        Ok(to_array1(py, &q).into_any())
    }

    #[pyo3(signature = (q, v_guess, fixed=None))]
    fn assemble_velocity<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v_guess: &Obj,
        fixed: Option<&Obj>,
    ) -> PyResult<Obj<'py>> {
        let (model, q, mut v) = self
            .state(py, q, v_guess)
            .map_err(|e| rename(py, e, "v", "v_guess"))?;
        let mask = crate::python::loops::fixed_mask(&model, fixed)?;
        loops::project_velocity_like(&model, &q, None, &mut v, &mask).py(py)?;
        check_result(py, "assemble_velocity", &v)?;
        Ok(to_array1(py, &v).into_any())
    }

    #[pyo3(signature = (q, v, a_guess, fixed=None))]
    fn assemble_acceleration<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        a_guess: &Obj,
        fixed: Option<&Obj>,
    ) -> PyResult<Obj<'py>> {
        let (model, q, v) = self.state(py, q, v)?;
        let mut a = crate::python::convert::vector(a_guess, "a_guess", Some(model.nv))?;
        crate::support::error::check_finite("a_guess", &a).py(py)?;
        let mask = crate::python::loops::fixed_mask(&model, fixed)?;
        loops::project_velocity_like(&model, &q, Some(&v), &mut a, &mask).py(py)?;
        check_result(py, "assemble_acceleration", &a)?;
        Ok(to_array1(py, &a).into_any())
    }

    #[pyo3(signature = (q, v, tau, gravity=None, external=None))]
    fn constraint_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        tau: &Obj,
        gravity: Option<&Obj>,
        external: Option<&Obj>,
    ) -> PyResult<Obj<'py>> {
        let g = crate::model::args::gravity(gravity)?;
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
            load_x(ws, py, tau, "tau")?;
            let ext = crate::model::args::external(ws.model(), external)?;
            let w = ws.constraint_forces(&g, ext.as_deref()).py(py)?;
            let flat: Vec<f64> = w.iter().flatten().copied().collect();
            check_result(py, "constraint_forces", &flat)?;
            to_array(py, flat, &[w.len(), 6])
        })
    }
}

record!(
    /// How the loop solver factors a model (`Model.loop_solver_info`).
    PyLoopLayout("LoopSolverInfo", loops::Layout) { banded, order, profile, model_profile }
);
