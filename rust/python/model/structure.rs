//! `Model`'s tree: building it body by body, its sizes and names, bodies and joints.

use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict};

use super::PyModel;
use crate::model::args::some_body;
use crate::model::Model;
use crate::python::body::PyRigidBody;
use crate::python::convert::to_array1;
use crate::python::errors::IntoPyResult;
use crate::python::joint::PyJoint;
use crate::support::args;

#[pymethods]
impl PyModel {
    #[new]
    fn new() -> Self {
        PyModel::from_model(Model::new())
    }

    /// Adds `body` (a RigidBody) on `joint` (a Joint) below `parent`; returns its index.
    ///
    /// parent: the parent body's name or index; -1, "world" or None for the world.
    /// translation, rotation: the joint frame in the parent's body frame (3-vector, 3×3
    /// rotation to 1e-9; within 4ε of a quarter or half turn it is taken as exactly that).
    /// name: unique body name (default "body<index>"). point_mass_center: where the seven
    /// point masses' box is centred, body frame (default: the COM).
    #[pyo3(signature = (body, joint, parent=None, translation=None, rotation=None, name=None, point_mass_center=None))]
    fn add_body(
        &self,
        py: Python<'_>,
        body: PyRef<'_, PyRigidBody>,
        joint: PyRef<'_, PyJoint>,
        parent: Option<&Obj>,
        translation: Option<&Obj>,
        rotation: Option<&Obj>,
        name: Option<String>,
        point_mass_center: Option<&Obj>,
    ) -> PyResult<usize> {
        let frame = args::placement(translation, rotation, "translation", "rotation")?;
        let center = args::opt(point_mass_center, |c| args::vec3(c, "point_mass_center"))?;
        let parent = crate::model::args::body(&self.model(), parent, "parent")?;
        self.shared
            .update(|model| model.add_body(body.inner, joint.inner, parent, frame, name, center))
            .py(py)
    }

    fn body_info(&self, index: &Obj) -> PyResult<(String, String, i64, i64)> {
        let index = crate::python::convert::count_arg(index, "index", "a body index >= 0")?;
        Ok(self.model().body_info(index)?)
    }

    fn joint_slices(&self) -> Vec<(usize, usize, usize, usize)> {
        self.model().joint_slices()
    }

    fn neutral<'py>(&self, py: Python<'py>) -> Obj<'py> {
        to_array1(py, &self.model().neutral()).into_any()
    }

    fn body(&self, body: &Obj) -> PyResult<PyRigidBody> {
        let model = self.model();
        let b = some_body(&model, body, "body")?;
        Ok(PyRigidBody {
            inner: model.bodies[b].body,
        })
    }

    fn with_body(
        &self,
        py: Python<'_>,
        body: &Obj,
        rigid_body: PyRef<'_, PyRigidBody>,
    ) -> PyResult<Self> {
        let ver = self.version();
        let b = some_body(&ver.model, body, "body")?;
        let mut model = (*ver.model).clone();
        model.replace_body(b, rigid_body.inner).py(py)?;
        Ok(PyModel::from_model(model))
    }

    fn __repr__(&self) -> String {
        self.model().summary()
    }

    fn joint_limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.model().joint_limits().into_py_dict(py)
    }

    fn joint_dynamics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.model().joint_dynamics().into_py_dict(py)
    }
}

crate::python::getters!(PyModel |m| {
    nq: m.model().nq;
    nv: m.model().nv;
    nbodies: m.model().nbodies();
    nlinks: m.model().links.len();
    body_names: m.model().bodies.iter().map(|b| b.name.clone()).collect::<Vec<_>>();
    link_names: m.model().link_names();
    joint_names: m.model().joint_names();
    frame_names: m.model().frame_names();
    total_mass: m.model().total_mass();
});
