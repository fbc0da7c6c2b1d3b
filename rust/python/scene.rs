//! `Scene`: a model, its initial state, effects and the settings of its runs.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{to_array, to_array1};
use super::derivatives::{PyForwardDerivatives, PyInverseDerivatives};
use super::effects::PyEffect;
use super::errors::IntoPyResult;
use super::model::PyModel;
use super::simulate::callbacks;
use crate::io::scene::{Scene, Settings};
use crate::simulate::at_state;
use crate::simulate::RunConfig;

#[pyclass(name = "Scene", module = "pointmass_dyn._core", frozen)]
pub struct PyScene {
    pub inner: Scene,
}

#[pymethods]
impl PyScene {
    /// Settings by keyword beyond `disable`: `crate::simulate::config_args::SCENE_KEYS`.
    #[new]
    #[pyo3(signature = (model, q0=None, v0=None, effects=None, t_span=None, rtol=None, atol=None, name=None, description=None, disable=None, **settings))]
    #[pyo3(
        text_signature = "(model, q0=None, v0=None, effects=None, t_span=None, rtol=None, atol=None, name=None, description=None, disable=None, *, method=None, dt=None, max_step=None, max_steps=None, first_step=None)"
    )]
    fn new(
        model: PyRef<'_, PyModel>,
        q0: Option<&Obj>,
        v0: Option<&Obj>,
        effects: Option<&Obj>,
        t_span: Option<&Obj>,
        rtol: Option<&Obj>,
        atol: Option<&Obj>,
        name: Option<String>,
        description: Option<String>,
        disable: Option<&Obj>,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let named = [
            ("t_span", t_span),
            ("rtol", rtol),
            ("atol", atol),
            ("disable", disable),
        ];
        let settings =
            RunConfig::scene_call(settings.map(|d| d.as_any()), &named, Settings::default())?;
        let base = Scene::of_model(model.model());
        let inner = base.replaced(None, [effects, q0, v0], (name, description), settings)?;
        Ok(PyScene { inner })
    }

    /// A copy with what is given replaced and everything else kept: the model (of this
    /// scene's sizes), the effects (checked against the model as the constructor checks
    /// them), the start state (`q0`, `v0`: checked, `q0` normalised), the name and
    /// description, and any run setting (`SCENE_KEYS`: `t_span`, `rtol`, `atol`, `method`,
    /// `dt`, `max_step`, `max_steps`, `first_step`, `disable`).
    #[pyo3(signature = (model=None, effects=None, *, q0=None, v0=None, name=None, description=None, **settings))]
    #[pyo3(
        text_signature = "(self, model=None, effects=None, *, q0=None, v0=None, t_span=None, rtol=None, atol=None, name=None, description=None, disable=None, method=None, dt=None, max_step=None, max_steps=None, first_step=None)"
    )]
    fn replace(
        &self,
        model: Option<PyRef<'_, PyModel>>,
        effects: Option<&Obj>,
        q0: Option<&Obj>,
        v0: Option<&Obj>,
        name: Option<String>,
        description: Option<String>,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let base = self.inner.settings.clone();
        let settings = RunConfig::scene_call(settings.map(|d| d.as_any()), &[], base)?;
        let model = model.map(|m| m.model());
        let inner =
            (self.inner).replaced(model, [effects, q0, v0], (name, description), settings)?;
        Ok(PyScene { inner })
    }

    /// Parses a scene from TOML text; `file` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, file="<string>"))]
    fn from_toml(py: Python<'_>, text: &str, file: &str) -> PyResult<Self> {
        Scene::from_toml(text, file)
            .py(py)
            .map(|inner| PyScene { inner })
    }

    /// Reads a scene file (a regular file of at most 128 MiB; a FIFO or a device is refused
    /// before it is opened). Raises `SceneError` naming the file.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        Scene::from_file(&path)
            .py(py)
            .map(|inner| PyScene { inner })
    }

    /// The scene as scene-file text that `Scene.from_toml` reads back as an equal scene
    /// (README.md, "Scenes and the command line"). Raises `InvalidInputError` naming an effect no
    /// file can state (a torque function).
    fn to_toml(&self, py: Python<'_>) -> PyResult<String> {
        self.inner.to_toml().py(py)
    }

    /// Writes `to_toml()` to `path` (`load_scene(path)` reads it back).
    fn write(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        self.inner.write(&path).py(py)
    }

    /// `∂ẏ/∂y` of the equations of motion `y = [q; v]` (nq + nv square, `q`'s own
    /// coordinates), what implicit integrators use; `None` for a scene with closed loops.
    #[pyo3(signature = (y, t=0.0, disable=None))]
    fn state_jacobian<'py>(
        &self,
        py: Python<'py>,
        y: &Obj,
        t: f64,
        disable: Option<&Obj>,
    ) -> PyResult<Option<Obj<'py>>> {
        let jac = || Ok(at_state::state_jacobian(&self.inner, t, y, disable));
        let dim = self.inner.model.nq + self.inner.model.nv;
        let jac = callbacks(py, jac)??;
        jac.map(|j| to_array(py, j, &[dim, dim])).transpose()
    }
    fn __repr__(&self) -> String {
        self.inner.repr()
    }
}

/// The scene's derivatives, one method per direction:
/// `name(third argument: type) -> record = the core's function`.
macro_rules! derivatives {
    ($($(#[$doc:meta])* $name:ident($x:ident: $t:ty $(= $default:tt)?) -> $record:ident = $core:ident),*) => {
        #[pymethods]
        impl PyScene {$(
            $(#[$doc])*
            #[pyo3(signature = (q, v, $x $(= $default)?, t=0.0, disable=None))]
            fn $name(&self, py: Python<'_>, q: &Obj, v: &Obj, $x: $t, t: f64, disable: Option<&Obj>) -> PyResult<$record> {
                let d = || Ok(at_state::$core(&self.inner, t, (q, v, $x), disable));
                Ok($record(callbacks(py, d)??))
            }
        )*}
    };
}

derivatives! {
    /// `{"dq": ∂q̈/∂q, "dv": ∂q̈/∂v, "dtau": M⁻¹, "numerical": [...]}` of the scene's
    /// accelerations at `(t, q, v)` with the joint forces `tau` (default zero) on top of the
    /// enabled effects; `numerical` names the effects differentiated by central differences
    /// (docs/derivatives.md).
    forward_dynamics_derivatives(tau: Option<&Obj> = None) -> PyForwardDerivatives = forward_derivatives,
    /// `{"dq": ∂τ/∂q, "dv": ∂τ/∂v, "da": M, "numerical": [...]}` of the joint forces
    /// `τ = ID(q, v, a) − τ_effects(t, q, v)` that give accelerations `a`.
    inverse_dynamics_derivatives(a: &Obj) -> PyInverseDerivatives = inverse_derivatives
}

super::getters!(PyScene |s, py| {
    /// The scene's model (shared, not copied: adding a body to it copies it first, so the
    /// scene never changes).
    model -> PyModel = PyModel::from_shared(s.inner.model.clone()),
    q0 -> Obj<'py> = to_array1(py, &s.inner.q0).into_any(),
    v0 -> Obj<'py> = to_array1(py, &s.inner.v0).into_any(),
    effects -> Vec<PyEffect> = s.inner.effects.iter().map(|e| e.clone().into()).collect(),
    /// Integration method of the scene's `[simulate]` table (`None`: not set).
    method -> Option<&'static str> = s.inner.settings.method.map(|m| m.name()),
    /// Effect families the scene switches off (`None`: the scene says nothing).
    disable -> Option<Vec<&'static str>> = s.inner.settings.disable.map(|d| d.names()),
    name -> String = s.inner.name.clone(),
    description -> String = s.inner.description.clone(),
    t_span -> Option<(f64, f64)> = s.inner.settings.t_span,
    rtol -> Option<f64> = s.inner.settings.rtol,
    atol -> Option<f64> = s.inner.settings.atol,
    max_step -> Option<f64> = s.inner.settings.max_step,
    max_steps -> Option<usize> = s.inner.settings.max_steps,
    first_step -> Option<f64> = s.inner.settings.first_step,
    dt -> Option<f64> = s.inner.settings.dt,
});
