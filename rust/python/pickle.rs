//! Pickling and copies: `_dumps(obj) -> (data, callables)` and `_loads(data, callables)`,
//! which `pointmass_dyn/_pickle.py` registers with `copyreg` for every class below (so
//! `pickle`, `copy.copy` and `copy.deepcopy` all go through them).
//!
//! `data` is a [`crate::io::persist`] frame (version byte, postcard, checksum) of one [`Payload`],
//! whose variant says which class it holds. Every value is serialised as it is, derived data
//! included (a model's links and point masses, a URDF model's joint metadata), so the copy is
//! bit-identical. Python callables inside (`TorqueFunction(f)`) are not in the bytes: they
//! travel as the tuple `callables`, in effect order, which pickle stores by reference like
//! any function (a lambda then fails with pickle's own error).
use crate::python::Obj;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};
use serde::{Deserialize, Serialize};

use super::body::{PyPointMasses, PyRigidBody};
use super::dense::PyDenseSolution;
use super::effects::{torque_callback, PyEffect};
use super::errors::py_error;
use super::events::PyStateEvent;
use super::joint::PyJoint;
use super::model::PyModel;
use super::scene::PyScene;
use crate::effects::{torque_functions, Disabled, Effect, Effects};
use crate::integrator::DenseOutput;
use crate::io::scene::Scene;
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::point_masses::EquimomentalSet;
use crate::model::Model;
use crate::simulate::StateEvent;

/// The pickled classes: `Variant(core type) = Class { its core value; the class holding one }`.
/// One generic path serves them all ([`_dumps`], [`_loads`]).
macro_rules! payloads {
    ($($(#[$m:meta])* $v:ident($t:ty) = $class:ident { $read:expr; $make:expr }),* $(,)?) => {
        /// One pickled object. Append new variants at the end (postcard numbers them in
        /// order); any other change of a serialised type needs `persist::FORMAT_VERSION` bumped.
        #[derive(Serialize, Deserialize)]
        enum Payload {
            $($(#[$m])* $v($t)),*
        }

        impl Payload {
            /// The payload of a pointmass_dyn object; `None` for any other object.
            fn of(obj: &Obj) -> Option<Payload> {
                $(if let Ok(x) = obj.cast::<$class>() {
                    return Some(Payload::$v(($read)(x.get())));
                })*
                None
            }

            /// The Python object this payload describes.
            fn object(self, py: Python<'_>) -> PyResult<Py<PyAny>> {
                Ok(match self {
                    $(Payload::$v(x) => Py::new(py, ($make)(x))?.into_any()),*
                })
            }
        }
    };
}

payloads! {
    RigidBody(RigidBody) = PyRigidBody { |x: &PyRigidBody| x.inner; |inner| PyRigidBody { inner } },
    PointMasses(EquimomentalSet) = PyPointMasses {
        |x: &PyPointMasses| x.inner; |inner| PyPointMasses { inner }
    },
    Joint(Joint) = PyJoint { |x: &PyJoint| x.inner; |inner| PyJoint { inner } },
    /// A model, its joint records (names, limits, repairs) included.
    Model(std::sync::Arc<Model>) = PyModel { |x: &PyModel| x.model(); PyModel::from_shared },
    Effect(Effect) = PyEffect { |x: &PyEffect| x.inner.clone(); |inner| PyEffect { inner } },
    StateEvent(StateEvent) = PyStateEvent {
        |x: &PyStateEvent| x.inner.clone(); |inner| PyStateEvent { inner }
    },
    Scene(Scene) = PyScene { |x: &PyScene| x.inner.clone(); |inner| PyScene { inner } },
    DenseSolution(DenseOutput) = PyDenseSolution {
        |x: &PyDenseSolution| x.inner.clone(); |inner| PyDenseSolution { inner }
    },
}

impl Payload {
    /// The effects it holds, whose torque functions' callables travel beside the bytes.
    fn effects(&mut self) -> &mut [Effect] {
        match self {
            Payload::Effect(e) => std::slice::from_mut(e),
            Payload::Scene(s) => &mut s.effects,
            _ => &mut [],
        }
    }
}

fn unpickling_error(py: Python<'_>, message: impl std::fmt::Display) -> PyErr {
    py_error(
        py,
        "UnpicklingError",
        format!("cannot unpickle a pointmass_dyn object: {message}"),
    )
}

/// `(data, callables)` of a pointmass_dyn object; `_loads(data, callables)` rebuilds it.
#[pyfunction]
pub fn _dumps<'py>(
    py: Python<'py>,
    obj: &Obj<'py>,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyTuple>)> {
    let Some(mut payload) = Payload::of(obj) else {
        return Err(PyTypeError::new_err(format!(
            "_dumps: expected a pointmass_dyn object, got {}",
            obj.get_type().name()?
        )));
    };
    let callables = torque_functions(payload.effects())
        .map(
            |f| match f.source().and_then(|s| s.downcast_ref::<Py<PyAny>>()) {
                Some(c) => Ok(c.clone_ref(py)),
                None => Err(PyValueError::new_err(
                    "a torque function not made from a Python callable cannot be pickled",
                )),
            },
        )
        .collect::<PyResult<Vec<_>>>()?;
    let data = crate::io::persist::encode(&payload).map_err(|e| {
        match py.import("pickle").and_then(|m| m.getattr("PicklingError")) {
            Ok(cls) => PyErr::from_value(cls.call1((e.to_string(),)).unwrap_or(cls)),
            Err(err) => err,
        }
    })?;
    Ok((PyBytes::new(py, &data), PyTuple::new(py, callables)?))
}

/// The object `_dumps` described. Raises `pointmass_dyn.errors.UnpicklingError` for data that
/// is not an intact frame of this format version.
#[pyfunction]
#[pyo3(signature = (data, callables=None))]
pub fn _loads(
    py: Python<'_>,
    data: &Bound<'_, PyBytes>,
    callables: Option<&Bound<'_, PyTuple>>,
) -> PyResult<Py<PyAny>> {
    let mut payload: Payload =
        crate::io::persist::decode(data.as_bytes()).map_err(|e| unpickling_error(py, e))?;
    let (n, m) = (
        torque_functions(payload.effects()).count(),
        callables.map_or(0, |c| c.len()),
    );
    if n != m {
        let got = format!("the data holds {n} torque functions but {m} callables came with it");
        return Err(unpickling_error(py, got));
    }
    let given = callables.iter().flat_map(|c| c.iter());
    for (f, c) in torque_functions(payload.effects()).zip(given) {
        *f = torque_callback(c.unbind());
    }
    if let Payload::Scene(s) = &payload {
        // What `Scene(...)` checks: the state fits the model, the effects resolve.
        let effects = Effects::new(&s.model, &s.effects, Disabled::none(), "effects");
        let checked = s
            .model
            .check_state(&s.q0, Some(&s.v0))
            .and(effects.map(|_| ()));
        checked.map_err(|e| unpickling_error(py, e))?;
    }
    payload.object(py)
}
