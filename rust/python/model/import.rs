//! `Model.from_urdf` and, for the Python importers (`pointmass_dyn.io`: MuJoCo,
//! Pinocchio), `Model._from_parts`, the core's constructor from bodies in tree order
//! (`urdf::model_from_parts`). `Model.from_mujoco` and `Model.from_pinocchio` are those
//! importers, attached to the class in Python: nothing here calls back into Python.

use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::PyModel;
use crate::python::convert::{mat3, vec3};
use crate::python::errors::{invalid, IntoPyResult};
use crate::python::joint::PyJoint;
use crate::python::record::record;
use crate::support::spatial::Placement;

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
        use crate::io::urdf::RootJoint::{Fixed, Free};
        let choices = [("fixed", Fixed), ("free", Free)];
        let root = crate::support::args::opt(root_joint, |r| {
            crate::support::args::choice(r, "root_joint", &choices, "None, \"fixed\" or \"free\"")
        })?;
        let root = root.unwrap_or(Fixed);
        let repair = crate::io::urdf::Repair::parse(repair)?;
        let mut urdf =
            crate::io::urdf::load_urdf_with(&path, root, repair.as_ref(), &package_dirs).py(py)?;
        if !mimic {
            urdf.independent_mimics(&crate::support::files::display_path(&path));
        }
        for w in &urdf.warnings {
            warn(py, "UrdfWarning", w)?;
        }
        if !urdf.repairs().is_empty() {
            let lines: Vec<String> = urdf.repairs().iter().map(|r| r.describe()).collect();
            let message = format!(
                "{}: repaired {} link(s)/joint(s) (model.repairs lists them):\n  {}",
                crate::support::files::display_path(&path),
                urdf.repairs().len(),
                lines.join("\n  ")
            );
            warn(py, "UrdfRepairWarning", &message)?;
        }
        Ok(PyModel::from_model(urdf.model))
    }

    #[staticmethod]
    #[pyo3(signature = (parts, ranges=None))]
    fn _from_parts(
        py: Python<'_>,
        parts: Vec<Obj>,
        ranges: Option<Vec<Option<(f64, f64)>>>,
    ) -> PyResult<Self> {
        let ranges = ranges.unwrap_or_else(|| vec![None; parts.len()]);
        if ranges.len() != parts.len() {
            return Err(invalid(
                py,
                "ranges",
                format!("one (lower, upper) or None per part ({})", parts.len()),
                format!("{} entries", ranges.len()),
            ));
        }
        let mut out = Vec::with_capacity(parts.len());
        for (k, p) in parts.iter().enumerate() {
            #[allow(clippy::type_complexity)]
            let (name, parent, joint, t, r, joint_name, mass, com, inertia): (
                String,
                i64,
                PyRef<'_, PyJoint>,
                Obj,
                Obj,
                String,
                f64,
                Obj,
                Obj,
            ) = p.extract().map_err(|_| {
                invalid(
                    py,
                    &format!("parts[{k}]"),
                    "(name, parent, joint, translation, rotation, joint_name, mass, com, inertia)",
                    p.repr().map_or_else(|_| "?".to_string(), |x| x.to_string()),
                )
            })?;
            let parent = match parent {
                -1 => None,
                q if q >= 0 && (q as usize) < k => Some(q as usize),
                q => {
                    return Err(invalid(
                        py,
                        &format!("parts[{k}].parent"),
                        format!("-1 or an earlier part's index 0..{k}"),
                        q,
                    ))
                }
            };
            out.push(crate::io::urdf::Part {
                name,
                parent,
                placement: Placement::new(mat3(&r, "rotation")?, vec3(&t, "translation")?),
                joint: joint.inner,
                joint_name,
                mass,
                com: vec3(&com, "com")?,
                inertia: mat3(&inertia, "inertia")?,
                range: ranges[k],
            });
        }
        let built = crate::io::urdf::model_from_parts(&out).py(py)?;
        Ok(PyModel::from_model(built.model))
    }

    fn reference_poses<'py>(
        &self,
        py: Python<'py>,
        srdf: std::path::PathBuf,
    ) -> PyResult<Bound<'py, PyDict>> {
        let model = self.model();
        let (poses, skipped) = crate::io::urdf::load_reference_poses(&model, &srdf).py(py)?;
        if !skipped.is_empty() {
            let message = format!(
                "{}: joints the model does not move, skipped: {}",
                crate::support::files::display_path(&srdf),
                skipped.join(", ")
            );
            warn(py, "UrdfWarning", &message)?;
        }
        let out = PyDict::new(py);
        for p in poses {
            out.set_item(p.name, crate::python::convert::to_array1(py, &p.q))?;
        }
        Ok(out)
    }

    #[getter]
    fn repairs(&self) -> Vec<PyRepair> {
        self.records()
            .repairs
            .iter()
            .cloned()
            .map(PyRepair)
            .collect()
    }
}

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
