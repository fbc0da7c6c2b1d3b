//! `Scene`: a model, its initial state, effects and the settings of its runs.
use pyo3::prelude::*;

use super::convert::{to_array1, vector};
use super::effects::{repr_of, PyEffect};
use super::errors::{invalid, IntoPyResult};
use super::model::PyModel;
use crate::effects::{Disabled, Effects};
use crate::io::scene::{Scene, Settings};
use crate::simulate::RunConfig;

#[pyclass(name = "Scene", module = "pointmass_dyn._core", frozen)]
pub struct PyScene {
    pub inner: Scene,
}

#[pymethods]
impl PyScene {
    #[new]
    #[pyo3(signature = (model, q0=None, v0=None, effects=None, t_span=None, rtol=None, atol=None, name=None, description=None, disable=None, *, method=None, dt=None, max_step=None, max_steps=None, first_step=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        model: PyRef<'_, PyModel>,
        q0: Option<&Bound<'_, PyAny>>,
        v0: Option<&Bound<'_, PyAny>>,
        effects: Option<&Bound<'_, PyAny>>,
        t_span: Option<&Bound<'_, PyAny>>,
        rtol: Option<&Bound<'_, PyAny>>,
        atol: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
        description: Option<String>,
        disable: Option<&Bound<'_, PyAny>>,
        method: Option<&Bound<'_, PyAny>>,
        dt: Option<&Bound<'_, PyAny>>,
        max_step: Option<&Bound<'_, PyAny>>,
        max_steps: Option<&Bound<'_, PyAny>>,
        first_step: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let given = [
            t_span, rtol, atol, disable, method, dt, max_step, max_steps, first_step,
        ];
        let settings = settings_over(given, Settings::default())?;
        let m = model.model();
        let mut q = match q0 {
            Some(q) if !q.is_none() => vector(q, "q0", Some(m.nq))?,
            _ => m.neutral(),
        };
        let v = match v0 {
            Some(v) if !v.is_none() => vector(v, "v0", Some(m.nv))?,
            _ => vec![0.0; m.nv],
        };
        m.check_state(&q, Some(&v))
            .map_err(|e| super::errors::to_py(py, e.map_arg(|a| format!("{a}0"))))?;
        m.normalize(&mut q);
        let mut list = Vec::new();
        if let Some(effs) = effects {
            if !effs.is_none() {
                // A lone effect is a common slip: say what a list is, not "not iterable".
                let items = effs.try_iter().map_err(|_| {
                    invalid(
                        py,
                        "effects",
                        "a list of effects such as [pmd.Gravity()]",
                        repr_of(effs),
                    )
                })?;
                for (k, e) in items.enumerate() {
                    let e = e?;
                    let eff = e.cast::<PyEffect>().map_err(|_| {
                        invalid(
                            py,
                            &format!("effects[{k}]"),
                            "an effect such as pmd.Gravity(...)",
                            repr_of(&e),
                        )
                    })?;
                    list.push(eff.get().inner.clone());
                }
            }
        }
        // Joint limits without bounds and torques limited at "effort" take the model's
        // (URDF <limit>, MJCF range).
        crate::effects::fill_model_limits(&m, &m.records.joints, &mut list, "effects").py(py)?;
        // Joint and body names, table widths and effect names must fit the model.
        Effects::new(&m, &list, Disabled::none(), "effects").py(py)?;
        Ok(PyScene {
            inner: Scene {
                name: name.unwrap_or_else(|| "scene".into()),
                description: description.unwrap_or_default(),
                model: m,
                q0: q,
                v0: v,
                effects: list,
                settings,
            },
        })
    }

    /// A copy with what is given replaced and everything else kept: the model (of this
    /// scene's sizes), the effects (checked against the model as the constructor checks
    /// them), the start state (`q0`, `v0`: checked, `q0` normalised), the name and
    /// description, and any run setting (`t_span`, `rtol`, `atol`, `method`, `dt`,
    /// `max_step`, `max_steps`, `first_step`, `disable`).
    #[pyo3(signature = (model=None, effects=None, *, q0=None, v0=None, t_span=None, rtol=None, atol=None, name=None, description=None, disable=None, method=None, dt=None, max_step=None, max_steps=None, first_step=None))]
    #[allow(clippy::too_many_arguments)]
    fn replace(
        &self,
        py: Python<'_>,
        model: Option<PyRef<'_, PyModel>>,
        effects: Option<Vec<PyRef<'_, PyEffect>>>,
        q0: Option<&Bound<'_, PyAny>>,
        v0: Option<&Bound<'_, PyAny>>,
        t_span: Option<&Bound<'_, PyAny>>,
        rtol: Option<&Bound<'_, PyAny>>,
        atol: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
        description: Option<String>,
        disable: Option<&Bound<'_, PyAny>>,
        method: Option<&Bound<'_, PyAny>>,
        dt: Option<&Bound<'_, PyAny>>,
        max_step: Option<&Bound<'_, PyAny>>,
        max_steps: Option<&Bound<'_, PyAny>>,
        first_step: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let mut inner = self.inner.clone();
        let given = [
            t_span, rtol, atol, disable, method, dt, max_step, max_steps, first_step,
        ];
        inner.settings = settings_over(given, inner.settings)?;
        if let Some(m) = model {
            let m = m.model();
            if (m.nq, m.nv) != (inner.model.nq, inner.model.nv) {
                return Err(invalid(
                    py,
                    "model",
                    format!(
                        "a model with nq = {}, nv = {} (this scene's)",
                        inner.model.nq, inner.model.nv
                    ),
                    format!("nq = {}, nv = {}", m.nq, m.nv),
                ));
            }
            inner.model = m;
        }
        if let Some(list) = effects {
            inner.effects = list.iter().map(|e| e.inner.clone()).collect();
            let (m, list) = (&inner.model, &mut inner.effects);
            // New effects take their missing limits from the model's URDF joints.
            crate::effects::fill_model_limits(m, &m.records.joints, list, "effects").py(py)?;
        }
        Effects::new(&inner.model, &inner.effects, Disabled::none(), "effects").py(py)?;
        let m = &inner.model;
        if let Some(q) = q0.filter(|q| !q.is_none()) {
            inner.q0 = vector(q, "q0", Some(m.nq))?;
        }
        if let Some(v) = v0.filter(|v| !v.is_none()) {
            inner.v0 = vector(v, "v0", Some(m.nv))?;
        }
        m.check_state(&inner.q0, Some(&inner.v0))
            .map_err(|e| super::errors::to_py(py, e.map_arg(|a| format!("{a}0"))))?;
        m.normalize(&mut inner.q0);
        inner.name = name.unwrap_or(inner.name);
        inner.description = description.unwrap_or(inner.description);
        Ok(PyScene { inner })
    }

    /// Parses a scene from TOML text; `file` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, file="<string>"))]
    fn from_toml(py: Python<'_>, text: &str, file: &str) -> PyResult<Self> {
        Scene::from_toml(text, file)
            .map(|inner| PyScene { inner })
            .py(py)
    }

    /// Reads a scene file (a regular file of at most 128 MiB; a FIFO or a device is refused
    /// before it is opened). Raises `SceneError` naming the file.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        Scene::from_file(&path)
            .map(|inner| PyScene { inner })
            .py(py)
    }

    /// The scene as scene-file text that `Scene.from_toml` reads back as an equal scene
    /// (docs/scenes.md, "Saving a scene"). Raises `InvalidInputError` naming an effect no
    /// file can state (a torque function).
    fn to_toml(&self, py: Python<'_>) -> PyResult<String> {
        self.inner.to_toml().py(py)
    }

    /// Writes `to_toml()` to `path` (`load_scene(path)` reads it back).
    fn write(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        self.inner.write(&path).py(py)
    }

    /// The scene's model (shared, not copied: adding a body to it copies it first, so the
    /// scene never changes).
    #[getter]
    fn model(&self) -> PyModel {
        PyModel::from_shared(self.inner.model.clone())
    }
    #[getter]
    fn q0<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, &self.inner.q0).into_any()
    }
    #[getter]
    fn v0<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, &self.inner.v0).into_any()
    }
    #[getter]
    fn effects(&self) -> Vec<PyEffect> {
        self.inner
            .effects
            .iter()
            .map(|e| e.clone().into())
            .collect()
    }
    /// Integration method of the scene's `[simulate]` table (`None`: not set).
    #[getter]
    fn method(&self) -> Option<&'static str> {
        self.inner.settings.method.map(|m| m.name())
    }
    /// Effect families the scene switches off (`None`: the scene says nothing).
    #[getter]
    fn disable(&self) -> Option<Vec<&'static str>> {
        self.inner.settings.disable.map(|d| d.names())
    }
    /// `{"dq": ∂q̈/∂q, "dv": ∂q̈/∂v, "dtau": M⁻¹, "numerical": [...]}` of the scene's
    /// accelerations at `(t, q, v)` with the joint forces `tau` (default zero) on top of the
    /// enabled effects; `numerical` names the effects differentiated by central differences
    /// (docs/derivatives.md).
    #[pyo3(signature = (q, v, tau=None, t=0.0, disable=None))]
    fn forward_dynamics_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        tau: Option<&Bound<'_, PyAny>>,
        t: f64,
        disable: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        super::derivatives::forward(py, &self.inner, q, v, tau, t, disable)
    }
    /// `{"dq": ∂τ/∂q, "dv": ∂τ/∂v, "da": M, "numerical": [...]}` of the joint forces
    /// `τ = ID(q, v, a) − τ_effects(t, q, v)` that give accelerations `a`.
    #[pyo3(signature = (q, v, a, t=0.0, disable=None))]
    fn inverse_dynamics_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        t: f64,
        disable: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        super::derivatives::inverse(py, &self.inner, q, v, a, t, disable)
    }
    /// `∂ẏ/∂y` of the equations of motion `y = [q; v]` (nq + nv square, `q`'s own
    /// coordinates), what implicit integrators use; `None` for a scene with closed loops.
    #[pyo3(signature = (y, t=0.0, disable=None))]
    fn state_jacobian<'py>(
        &self,
        py: Python<'py>,
        y: &Bound<'_, PyAny>,
        t: f64,
        disable: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        super::derivatives::state_jacobian(py, &self.inner, y, t, disable)
    }
    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "Scene(name='{}', nbodies={}, nq={}, nv={}, effects=[{}])",
            s.name,
            s.model.nbodies(),
            s.model.nq,
            s.model.nv,
            s.effects
                .iter()
                .map(|e| e.name())
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

/// `base` with the settings a `Scene` call was given (`None`: not given) laid over it,
/// parsed as `RunConfig`'s keywords are (`RunConfig::onto_scene`).
fn settings_over(given: [Option<&Bound<'_, PyAny>>; 9], base: Settings) -> PyResult<Settings> {
    const KEYS: [&str; 9] = [
        "t_span",
        "rtol",
        "atol",
        "disable",
        "method",
        "dt",
        "max_step",
        "max_steps",
        "first_step",
    ];
    let pairs = KEYS
        .iter()
        .zip(given)
        .filter_map(|(k, v)| v.map(|v| (*k, v)));
    Ok(RunConfig::from_args(pairs)?.onto_scene(base)?)
}

super::getters!(PyScene {
    name: String = inner.name,
    description: String = inner.description,
    t_span: Option<(f64, f64)> = inner.settings.t_span,
    rtol: Option<f64> = inner.settings.rtol,
    atol: Option<f64> = inner.settings.atol,
    max_step: Option<f64> = inner.settings.max_step,
    max_steps: Option<usize> = inner.settings.max_steps,
    first_step: Option<f64> = inner.settings.first_step,
    dt: Option<f64> = inner.settings.dt,
});
