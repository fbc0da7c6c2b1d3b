//! `Joint`: the joint types a body hangs on (revolute, prismatic, spherical, fixed, free).
use crate::python::Obj;
use pyo3::prelude::*;

use super::convert::{to_array1, vec3};
use super::errors::IntoPyResult;
use crate::joint::Joint;

#[pyclass(name = "Joint", module = "pointmass_dyn._core", frozen, from_py_object)]
#[derive(Clone)]
pub struct PyJoint {
    pub inner: Joint,
}

impl From<Joint> for PyJoint {
    fn from(inner: Joint) -> Self {
        PyJoint { inner }
    }
}

#[pymethods]
impl PyJoint {
    #[staticmethod]
    fn revolute(py: Python<'_>, axis: &Obj) -> PyResult<Self> {
        Ok(Joint::revolute(vec3(axis, "axis")?).py(py)?.into())
    }
    #[staticmethod]
    fn prismatic(py: Python<'_>, axis: &Obj) -> PyResult<Self> {
        Ok(Joint::prismatic(vec3(axis, "axis")?).py(py)?.into())
    }
    #[staticmethod]
    fn spherical_zyz() -> Self {
        Joint::SphericalZYZ.into()
    }
    #[staticmethod]
    fn spherical() -> Self {
        Joint::Spherical.into()
    }
    #[staticmethod]
    fn fixed() -> Self {
        Joint::Fixed.into()
    }
    #[staticmethod]
    fn free_flyer() -> Self {
        Joint::FreeFlyer.into()
    }
    #[getter]
    fn axis<'py>(&self, py: Python<'py>) -> Option<Obj<'py>> {
        let axis = self.inner.axis()?;
        Some(to_array1(py, axis.as_slice()).into_any())
    }
    fn __repr__(&self) -> String {
        self.inner.repr()
    }
}

crate::python::getters!(PyJoint |j| {
    kind: j.inner.kind().to_string();
    nq: j.inner.nq();
    nv: j.inner.nv();
});
