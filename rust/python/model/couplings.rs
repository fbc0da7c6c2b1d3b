//! `Model`'s joint couplings (`add_coupling`; their forces are a one-state quantity, in
//! `dynamics.rs`) and rotor inertia
//! (`set_armature`, `armature`): argument conversion around `crate::loops::coupling` and
//! `crate::recursive::armature`.
use crate::python::Obj;
use pyo3::prelude::*;

use super::PyModel;
use crate::effects::args::{joint_body, numbers};
use crate::loops;
use crate::python::convert::to_array1;
use crate::python::errors::IntoPyResult;

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

    fn set_armature(&self, py: Python<'_>, joint: &Obj, value: &Obj) -> PyResult<()> {
        let j = joint_body(&self.model(), joint, "joint")?;
        let expected = "a number >= 0, or one per speed of the joint";
        let values = numbers(value, "value", expected)?;
        self.shared.update(|m| m.set_armature(j, &values)).py(py)
    }
}

crate::python::getters!(PyModel |s, py| {
    ncouplings -> usize = s.model().ncouplings(),
    couplings -> Vec<(String, String, String, f64, f64)> = s.model().coupling_list(),
    armature -> Obj<'py> = to_array1(py, &s.model().armature_per_speed()).into_any(),
});
