//! `Model.from_urdf` and, for the Python importers (`pointmass_dyn.io`: MuJoCo,
//! Pinocchio), `Model._from_parts`, the core's constructor from bodies in tree order
//! (`urdf::model_from_parts`). `Model.from_mujoco` and `Model.from_pinocchio` are those
//! importers, attached to the class in Python: nothing here calls back into Python.

use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict};

use super::PyModel;
use crate::python::convert::to_array1;
use crate::python::errors::IntoPyResult;
use crate::python::joint::PyJoint;
use crate::python::record::record;

#[pymethods]
impl PyModel {
    #[staticmethod]
    #[pyo3(signature = (path, *, root_joint=None, repair=None, package_dirs=None, mimic=true))]
    fn from_urdf(
        py: Python<'_>,
        path: std::path::PathBuf,
        root_joint: Option<&Obj>,
        repair: Option<&Obj>,
        package_dirs: Option<&Obj>,
        mimic: bool,
    ) -> PyResult<Self> {
        let package_dirs = crate::python::visuals::package_dirs(py, package_dirs)?;
        let root = crate::io::urdf::RootJoint::parse(root_joint)?;
        let repair = crate::io::urdf::Repair::parse(repair)?;
        let (model, warnings) =
            crate::io::urdf::load_model(&path, (root, repair.as_ref()), &package_dirs, mimic)
                .py(py)?;
        for (category, message) in &warnings {
            warn(py, category, message)?;
        }
        Ok(PyModel::from_model(model))
    }

    #[staticmethod]
    #[pyo3(signature = (parts, ranges=None))]
    fn _from_parts(
        py: Python<'_>,
        parts: Vec<Obj>,
        ranges: Option<Vec<Option<(f64, f64)>>>,
    ) -> PyResult<Self> {
        let joint = |j: &Obj| j.extract::<PyRef<'_, PyJoint>>().ok().map(|j| j.inner);
        let out = crate::io::urdf::parts_arg(&parts, ranges, joint)?;
        let built = crate::io::urdf::model_from_parts(&out).py(py)?;
        Ok(PyModel::from_model(built.model))
    }

    fn reference_poses<'py>(
        &self,
        py: Python<'py>,
        srdf: std::path::PathBuf,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (poses, warning) =
            crate::io::urdf::reference_poses_warned(&self.model(), &srdf).py(py)?;
        if let Some(message) = warning {
            warn(py, "UrdfWarning", &message)?;
        }
        let poses = poses.into_iter().map(|p| (p.name, to_array1(py, &p.q)));
        poses.collect::<Vec<_>>().into_py_dict(py)
    }
}

crate::python::getters!(PyModel |s, py| {
    repairs -> Vec<PyRepair> = s.records().repairs.iter().cloned().map(PyRepair).collect(),
});

/// `warnings.warn(message, pointmass_dyn.errors.<category>)`.
fn warn(py: Python<'_>, category: &str, message: &str) -> PyResult<()> {
    let category = py.import("pointmass_dyn.errors")?.getattr(category)?;
    py.import("warnings")?
        .call_method1("warn", (message, &category, 1))
        .map(drop)
}

record!(
    /// One link or welded joint changed by `from_urdf(..., repair=...)` (`model.repairs`).
    PyRepair("UrdfRepair", crate::io::urdf::RepairRecord) {
        link, joint, rules, mass, principal_moments, joint_type
    } eq
);
