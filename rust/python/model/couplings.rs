//! `Model`'s joint couplings (`add_coupling`, their forces) and rotor inertia
//! (`set_armature`, `armature`): argument conversion around `crate::loops::coupling` and
//! `crate::recursive::armature`.
use crate::python::Obj;
use pyo3::prelude::*;

use super::{load_state, load_x, PyModel};
use crate::effects::args::{joint_body, numbers};
use crate::loops;
use crate::python::convert::to_array1;
use crate::python::errors::{check_result, IntoPyResult};

#[pymethods]
impl PyModel {
    #[pyo3(signature = (joint, reference, ratio=None, offset=None, name=None))]
    fn add_coupling(
        &self,
        py: Python<'_>,
        joint: &Obj,
        reference: &Obj,
        ratio: Option<&Obj>,
        offset: Option<&Obj>,
        name: Option<String>,
    ) -> PyResult<usize> {
        let (j, r, ratio, offset) =
            loops::args::coupling(&self.model(), [joint, reference], ratio, offset)?;
        self.shared
            .update(|m| m.add_coupling(j, r, ratio, offset, name))
            .py(py)
    }

    #[getter]
    fn ncouplings(&self) -> usize {
        self.model().ncouplings()
    }

    #[getter]
    fn couplings(&self) -> Vec<(String, String, String, f64, f64)> {
        self.model().coupling_list()
    }

    #[pyo3(signature = (q, v, tau, gravity=None))]
    fn coupling_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        tau: &Obj,
        gravity: Option<&Obj>,
    ) -> PyResult<Obj<'py>> {
        let g = crate::model::args::gravity(gravity)?;
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
            load_x(ws, py, tau, "tau")?;
            let lambda = ws.constraint_multipliers(&g).py(py)?;
            let f = loops::coupling::forces(ws.model(), &lambda);
            check_result(py, "coupling_forces", &f)?;
            Ok(to_array1(py, &f).into_any())
        })
    }

    fn set_armature(&self, py: Python<'_>, joint: &Obj, value: &Obj) -> PyResult<()> {
        let j = joint_body(&self.model(), joint, "joint")?;
        let expected = "a number >= 0, or one per speed of the joint";
        let values = numbers(value, "value", expected)?;
        self.shared.update(|m| m.set_armature(j, &values)).py(py)
    }

    #[getter]
    fn armature<'py>(&self, py: Python<'py>) -> Obj<'py> {
        to_array1(py, &self.model().armature_per_speed()).into_any()
    }
}
