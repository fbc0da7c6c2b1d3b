//! `Model.visuals`, `Model.name`, `Model.set_visuals` and the `package_dirs` argument of
//! `from_urdf`: the visual geometry (crate::model::visual) as plain Python data, a list of dicts.
use crate::python::Obj;
use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::convert::{short_repr, toml_to_py};
use super::errors::invalid;
use super::model::PyModel;
use crate::model::visual::Visual;

/// `package_dirs`: None, one path or a sequence of paths.
pub(super) fn package_dirs(py: Python<'_>, obj: Option<&Obj>) -> PyResult<Vec<PathBuf>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    if let Ok(one) = obj.extract::<PathBuf>() {
        return Ok(vec![one]);
    }
    obj.extract::<Vec<PathBuf>>().map_err(|_| {
        invalid(
            py,
            "package_dirs",
            "a path or a list of paths",
            short_repr(obj),
        )
    })
}

/// A visual as the dict `Model.visuals` lists (`Visual::fields`).
fn to_dict<'py>(py: Python<'py>, v: &Visual, body_name: &str) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (key, value) in v.fields(body_name) {
        d.set_item(key, value.map(|x| toml_to_py(py, &x)).transpose()?)?;
    }
    Ok(d)
}

#[pymethods]
impl PyModel {
    /// The visual geometry (URDF `<visual>`, MJCF geoms; docs/visualisation.md): one dict per
    /// shape with `body` (index), `body_name`, `kind` ("box", "cylinder", "sphere",
    /// "capsule", "ellipsoid", "mesh"), `rotation` (3×3) and `translation` of its frame in
    /// the body frame, its sizes (`size` full sides; `radius`, `length` along z; `radii`;
    /// a mesh's `uri` as written, `path` where found or None, `scale`) and `rgba` or None.
    #[getter]
    fn visuals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let m = self.model();
        let items = m
            .visuals
            .iter()
            .map(|v| to_dict(py, v, &m.bodies[v.body].name))
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// Replaces the visual geometry with `visuals` (dicts as `Model.visuals` gives them; a
    /// mesh's `path` defaults to its `uri`) and, if given, the name. The dynamics is unchanged.
    #[pyo3(signature = (visuals, *, name=None))]
    fn set_visuals(&self, visuals: Vec<Obj>, name: Option<String>) -> PyResult<()> {
        let out = crate::model::visual::parse_visuals(&visuals, self.model().nbodies())?;
        self.update_model(|m| {
            m.visuals = out;
            if let Some(n) = name {
                m.name = n;
            }
        });
        Ok(())
    }
}

/// Where a mesh `uri` of a model file in `base_dir` is (`package://`, `file://`, absolute or
/// relative), as `from_urdf` finds its meshes (`crate::model::visual::resolve_mesh`); `None` when no
/// candidate is a file. `urdf_contact_points` reads collision meshes with it.
#[pyfunction]
#[pyo3(signature = (uri, base_dir=None, package_dirs=None))]
pub fn resolve_mesh(
    py: Python<'_>,
    uri: &str,
    base_dir: Option<PathBuf>,
    package_dirs: Option<&Obj>,
) -> PyResult<Option<PathBuf>> {
    let dirs = self::package_dirs(py, package_dirs)?;
    Ok(crate::model::visual::resolve_mesh(
        uri,
        base_dir.as_deref(),
        &dirs,
    ))
}

crate::python::getters!(PyModel |m| {
    /// The model's name (URDF `<robot name>`, MJCF `<mujoco model>`; "" if none).
    name: m.model().name.clone();
});
