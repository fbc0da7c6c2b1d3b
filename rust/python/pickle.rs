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
use pyo3::exceptions::PyTypeError;
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
use crate::effects::{Disabled, Effect, Effects, TorqueFunction, TorqueLaw};
use crate::integrator::DenseOutput;
use crate::io::scene::Scene;
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::point_masses::EquimomentalSet;
use crate::model::Model;
use crate::simulate::StateEvent;

/// One pickled object. Append new variants at the end (postcard numbers them in order); any
/// other change of a serialised type needs `persist::FORMAT_VERSION` bumped.
#[derive(Serialize, Deserialize)]
enum Payload {
    RigidBody(RigidBody),
    PointMasses(EquimomentalSet),
    Joint(Joint),
    /// A model, its joint records (names, limits, repairs) included.
    Model(std::sync::Arc<Model>),
    Effect(Effect),
    StateEvent(StateEvent),
    Scene(Scene),
    DenseSolution(DenseOutput),
}

fn unpickling_error(py: Python<'_>, message: impl std::fmt::Display) -> PyErr {
    py_error(
        py,
        "UnpicklingError",
        format!("cannot unpickle a pointmass_dyn object: {message}"),
    )
}

/// The torque functions among `effects`, in order.
fn functions_mut(effects: &mut [Effect]) -> impl Iterator<Item = &mut TorqueFunction> {
    effects.iter_mut().filter_map(|e| match e {
        Effect::Torque(t) => match &mut t.law {
            TorqueLaw::Function(f) => Some(f),
            _ => None,
        },
        _ => None,
    })
}

/// The Python callables of the torque functions among `effects`, in order.
fn callables(py: Python<'_>, effects: &[Effect]) -> PyResult<Vec<Py<PyAny>>> {
    let mut out = Vec::new();
    for e in effects {
        if let Effect::Torque(t) = e {
            if let TorqueLaw::Function(f) = &t.law {
                let obj = f
                    .source()
                    .and_then(|s| s.downcast_ref::<Py<PyAny>>())
                    .ok_or_else(|| {
                        pyo3::exceptions::PyValueError::new_err(
                            "a torque function not made from a Python callable cannot be pickled",
                        )
                    })?;
                out.push(obj.clone_ref(py));
            }
        }
    }
    Ok(out)
}

/// Rebuilds the torque functions of `effects` from `callables` (one each, in order).
fn restore(py: Python<'_>, effects: &mut [Effect], callables: &Bound<'_, PyTuple>) -> PyResult<()> {
    let n = functions_mut(effects).count();
    if n != callables.len() {
        return Err(unpickling_error(
            py,
            format!(
                "the data holds {n} torque functions but {} callables came with it",
                callables.len()
            ),
        ));
    }
    for (f, c) in functions_mut(effects).zip(callables.iter()) {
        *f = torque_callback(c.unbind());
    }
    Ok(())
}

/// `(data, callables)` of a pointmass_dyn object; `_loads(data, callables)` rebuilds it.
#[pyfunction]
pub fn _dumps<'py>(
    py: Python<'py>,
    obj: &Obj<'py>,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyTuple>)> {
    let mut extras: Vec<Py<PyAny>> = Vec::new();
    let payload = if let Ok(x) = obj.cast::<PyRigidBody>() {
        Payload::RigidBody(x.get().inner)
    } else if let Ok(x) = obj.cast::<PyPointMasses>() {
        Payload::PointMasses(x.get().inner)
    } else if let Ok(x) = obj.cast::<PyJoint>() {
        Payload::Joint(x.get().inner)
    } else if let Ok(x) = obj.cast::<PyModel>() {
        Payload::Model(x.get().model())
    } else if let Ok(x) = obj.cast::<PyEffect>() {
        let e = x.get().inner.clone();
        extras = callables(py, std::slice::from_ref(&e))?;
        Payload::Effect(e)
    } else if let Ok(x) = obj.cast::<PyStateEvent>() {
        Payload::StateEvent(x.get().inner.clone())
    } else if let Ok(x) = obj.cast::<PyScene>() {
        let s = x.get().inner.clone();
        extras = callables(py, &s.effects)?;
        Payload::Scene(s)
    } else if let Ok(x) = obj.cast::<PyDenseSolution>() {
        Payload::DenseSolution(x.get().inner.clone())
    } else {
        return Err(PyTypeError::new_err(format!(
            "_dumps: expected a pointmass_dyn object, got {}",
            obj.get_type().name()?
        )));
    };
    let data = crate::io::persist::encode(&payload).map_err(|e| {
        let pickle = py.import("pickle");
        match pickle.and_then(|m| m.getattr("PicklingError")) {
            Ok(cls) => PyErr::from_value(cls.call1((e.to_string(),)).unwrap_or(cls)),
            Err(err) => err,
        }
    })?;
    Ok((PyBytes::new(py, &data), PyTuple::new(py, extras)?))
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
    let payload: Payload =
        crate::io::persist::decode(data.as_bytes()).map_err(|e| unpickling_error(py, e))?;
    let empty = PyTuple::empty(py);
    let callables = callables.unwrap_or(&empty);
    let check = |r: crate::Result<()>| r.map_err(|e| unpickling_error(py, e));
    Ok(match payload {
        Payload::RigidBody(inner) => Py::new(py, PyRigidBody { inner })?.into_any(),
        Payload::PointMasses(inner) => Py::new(py, PyPointMasses { inner })?.into_any(),
        Payload::Joint(inner) => Py::new(py, PyJoint { inner })?.into_any(),
        Payload::Model(model) => Py::new(py, PyModel::from_shared(model))?.into_any(),
        Payload::Effect(mut inner) => {
            restore(py, std::slice::from_mut(&mut inner), callables)?;
            Py::new(py, PyEffect { inner })?.into_any()
        }
        Payload::StateEvent(inner) => Py::new(py, PyStateEvent { inner })?.into_any(),
        Payload::Scene(mut inner) => {
            restore(py, &mut inner.effects, callables)?;
            // What `Scene(...)` checks: the state fits the model, the effects resolve.
            check(inner.model.check_state(&inner.q0, Some(&inner.v0)))?;
            check(
                Effects::new(&inner.model, &inner.effects, Disabled::none(), "effects").map(|_| ()),
            )?;
            Py::new(py, PyScene { inner })?.into_any()
        }
        Payload::DenseSolution(inner) => Py::new(py, PyDenseSolution { inner })?.into_any(),
    })
}
