//! `Effect`: the constructors of the effect families and the parsers of their arguments;
//! Python torque functions as Rust callbacks.
use crate::python::Obj;
use std::cell::RefCell;
use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{to_array1, toml_to_py, vector_into};
use super::errors::{invalid, IntoPyResult};
use super::model::PyModel;
use super::record::record;
use crate::effects::ground_contact::ContactStates;
use crate::effects::TorqueLimit;
use crate::effects::{args, ContactParameters, Effect, PerJoint, Torque, TorqueFunction};
use pyo3::IntoPyObjectExt;

#[pyclass(
    name = "Effect",
    module = "pointmass_dyn._core",
    frozen,
    from_py_object
)]
#[derive(Clone)]
pub struct PyEffect {
    pub inner: Effect,
}

impl From<Effect> for PyEffect {
    fn from(inner: Effect) -> Self {
        PyEffect { inner }
    }
}

record!(
    /// A ground contact's law parameters (SI): attributes, and `p["stiffness"]` as well.
    PyContactParameters("ContactParameters", ContactParameters) {
        height, stiffness, exponent, damping, friction, v_eps
    } eq
);

record!(
    /// A ground contact's points along N states: `position` (N, P, 3), `penetration` (N, P),
    /// `normal_force` (N, P), `force` (N, P, 3).
    PyContactStates("ContactStates", ContactStates) {
        position, penetration, normal_force, force
    }
);

thread_local! {
    /// The first exception a Python torque function raised during the current call (the
    /// integration runs on the calling thread, detached from the interpreter).
    static CALLBACK_ERROR: RefCell<Option<PyErr>> = const { RefCell::new(None) };
}

pub(super) fn take_callback_error() -> Option<PyErr> {
    CALLBACK_ERROR.with(|c| c.borrow_mut().take())
}

pub(super) use super::convert::short_repr as repr_of;

/// A Python `f(t, q, v) -> tau` as a torque callback: re-attaches to the interpreter at
/// every evaluation. An exception it raises (or a result of the wrong shape) is kept for the
/// caller to re-raise; a non-finite torque fails the run like any effect's (the core checks
/// it), so it is not an exception. `func` is also kept as the function's source, which
/// pickling carries (`pickle.rs`).
pub(crate) fn torque_callback(func: Py<PyAny>) -> TorqueFunction {
    let source = Python::attach(|py| func.clone_ref(py));
    let f = move |t: f64, q: &[f64], v: &[f64], out: &mut [f64]| -> Result<(), String> {
        Python::attach(|py| {
            let (q, v) = (PyArray1::from_slice(py, q), PyArray1::from_slice(py, v));
            let tau = func.bind(py).call1((t, q, v));
            let keep = |e: PyErr| {
                let msg = e.to_string();
                CALLBACK_ERROR.with(|c| c.replace_with(|first| first.take().or(Some(e))));
                msg
            };
            (tau.and_then(|r| vector_into(&r, "torque function f(t, q, v)", out))).map_err(keep)
        })
    };
    TorqueFunction::with_source(Arc::new(f), Arc::new(source))
}

#[pymethods]
impl PyEffect {
    /// The effect of scene-file type `type` with that type's keys as keyword arguments: the
    /// core reads them (`effects::args::effect`).
    #[new]
    #[pyo3(signature = (r#type, /, **keys))]
    fn new(py: Python<'_>, r#type: &str, keys: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let keys = keys.cloned().unwrap_or_else(|| PyDict::new(py));
        let names: Vec<String> = keys.keys().extract()?;
        Ok(args::effect(r#type, &names, keys.as_any())?.into())
    }
    /// Uniform gravity `g` (m/s², world frame).
    #[staticmethod]
    #[pyo3(signature = (g=None))]
    fn gravity(g: Option<Obj>) -> PyResult<Self> {
        Ok(args::gravity(g.as_ref())?.into())
    }
    /// Generalized forces from a Python callable `f(t, q, v) -> (nv,)`.
    #[staticmethod]
    #[pyo3(signature = (f, name=None))]
    fn torque_function(py: Python<'_>, f: Obj<'_>, name: Option<String>) -> PyResult<Self> {
        if !f.is_callable() {
            let expected = "a callable f(t, q, v) -> tau";
            return Err(invalid(py, "f", expected, repr_of(&f)));
        }
        Ok(Effect::Torque(Torque::function(name, torque_callback(f.unbind()))).into())
    }

    /// A ground contact's points along states `q` (N, nq), `v` (N, nv): a `ContactStates`
    /// (indexable as a dict) of `position` (N, P, 3), `penetration` (N, P), `normal_force`
    /// (N, P), `force` (N, P, 3).
    fn contact_state(
        &self,
        model: PyRef<'_, PyModel>,
        q: &Obj,
        v: &Obj,
    ) -> PyResult<PyContactStates> {
        args::contact_states(&self.inner, &model.model(), q, v).map(PyContactStates)
    }

    /// A torque effect clamped per speed at `limit`: one number or one per speed of its
    /// joints (all `nv` for a torque function), or `"effort"` (the model's URDF `effort`,
    /// filled in when a scene is built); None removes the limit.
    fn with_torque_limit(&self, py: Python<'_>, limit: Option<&Obj>) -> PyResult<Self> {
        let limit = args::torque_limit(limit)?;
        Ok(self.inner.with_torque_limit(limit).py(py)?.into())
    }

    /// A torque effect's limit on each of `model`'s speeds (inf where unlimited or not
    /// driven; all inf for another effect).
    fn torque_limit_per_speed<'py>(
        &self,
        py: Python<'py>,
        model: PyRef<'_, PyModel>,
    ) -> PyResult<Obj<'py>> {
        let out = self.inner.torque_limit_per_speed(&model.model()).py(py)?;
        Ok(to_array1(py, &out).into_any())
    }

    /// A copy with one parameter replaced (checked as the factory checks it): gravity `g`;
    /// a spring's `stiffness`, `rest`; a damper's `damping`; friction's `friction`, `v_eps`;
    /// a point spring's `stiffness`, `rest_length`, `damping`.
    fn with_parameter(&self, name: &str, value: &Obj) -> PyResult<Self> {
        Ok(args::with_parameter(&self.inner, name, value)?.into())
    }
    /// The effect's scene-file `[[effect]]` table as a dict (`type`, `name`, its keys;
    /// README.md, "Scenes and the command line"): every parameter it holds, SI units and
    /// radians. Raises `InvalidInputError` for a torque function (Python code no file can
    /// state).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let table = self.inner.to_toml().py(py)?;
        toml_to_py(py, &toml::Value::Table(table))
    }
    fn __repr__(&self) -> String {
        self.inner.repr()
    }
    fn __eq__(&self, other: PyRef<'_, PyEffect>) -> bool {
        self.inner == other.inner
    }
}

super::getters!(PyEffect |s, py| {
    /// The user's name, or the family's (`'gravity'`, `'springs'`, ...).
    name -> String = s.inner.name().to_string(),
    /// The family, as `disable` names it.
    kind -> &'static str = s.inner.kind().name(),
    /// A ground contact's law parameters (`stiffness`/`damping` None until a scene fills in
    /// their defaults: the scene's effects hold the values it runs with); `None` for other
    /// effects.
    contact_parameters -> Option<PyContactParameters> =
        s.inner.contact_parameters().map(PyContactParameters),
    /// A gravity effect's acceleration `g` (3,); `None` for other effects.
    g -> Option<Bound<'py, PyArray1<f64>>> =
        s.inner.gravity_vector().map(|g| to_array1(py, g.as_slice())),
    /// A ground contact's plane `n · x = height`: `(n, height)`, `n` (3,) the unit normal out
    /// of the ground; `None` for other effects.
    plane -> Option<(Bound<'py, PyArray1<f64>>, f64)> =
        s.inner.plane().map(|(n, h)| (to_array1(py, n.as_slice()), h)),
    /// A torque effect's limit: a number or an array (per speed), `"effort"` (until a scene
    /// fills it in), or None.
    torque_limit -> PyResult<Option<Obj<'py>>> = Ok(match s.inner.torque_limit() {
        None => None,
        Some(TorqueLimit::Effort) => Some("effort".into_bound_py_any(py)?),
        Some(TorqueLimit::Given(PerJoint::All(x))) => Some(x.into_bound_py_any(py)?),
        Some(TorqueLimit::Given(PerJoint::Each(v))) => Some(to_array1(py, v).into_any()),
    }),
});

impl crate::effects::args::EffectArg for Obj<'_> {
    fn effect(&self) -> Option<Effect> {
        self.cast::<PyEffect>().ok().map(|e| e.get().inner.clone())
    }
}
