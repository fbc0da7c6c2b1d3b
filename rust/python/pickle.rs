//! Pickling and copies: `_dumps(obj) -> (data, callables)` and `_loads(data, callables)`,
//! which `pointmass_dyn/_pickle.py` registers with `copyreg` for every class below (so
//! `pickle`, `copy.copy` and `copy.deepcopy` all go through them). `data` is the core's
//! [`Payload`] (`rust/io/pickled.rs`); `callables` the Python functions of its torque
//! functions, which pickle stores by reference like any function (a lambda then fails with
//! pickle's own error).
use crate::python::Obj;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

use super::body::{PyPointMasses, PyRigidBody};
use super::dense::PyDenseSolution;
use super::effects::{torque_callback, PyEffect};
use super::errors::py_error;
use super::events::PyStateEvent;
use super::joint::PyJoint;
use super::model::PyModel;
use super::scene::PyScene;
use crate::io::pickled::Payload;

pyo3::import_exception!(pickle, PicklingError);

/// The pickled classes: `Variant = Class { its core value; the class holding one }`.
macro_rules! payloads {
    ($($v:ident = $class:ident { $read:expr; $make:expr }),* $(,)?) => {
        /// The payload of a pointmass_dyn object; `None` for any other object.
        fn payload_of(obj: &Obj) -> Option<Payload> {
            $(if let Ok(x) = obj.cast::<$class>() {
                return Some(Payload::$v(($read)(x.get())));
            })*
            None
        }

        /// The Python object a payload describes.
        fn object(py: Python<'_>, payload: Payload) -> PyResult<Py<PyAny>> {
            Ok(match payload {
                $(Payload::$v(x) => Py::new(py, ($make)(x))?.into_any()),*
            })
        }
    };
}

payloads! {
    RigidBody = PyRigidBody { |x: &PyRigidBody| x.inner; |inner| PyRigidBody { inner } },
    PointMasses = PyPointMasses { |x: &PyPointMasses| x.inner; |inner| PyPointMasses { inner } },
    Joint = PyJoint { |x: &PyJoint| x.inner; |inner| PyJoint { inner } },
    Model = PyModel { |x: &PyModel| x.model(); PyModel::from_shared },
    Effect = PyEffect { |x: &PyEffect| x.inner.clone(); |inner| PyEffect { inner } },
    StateEvent = PyStateEvent { |x: &PyStateEvent| x.inner.clone(); |inner| PyStateEvent { inner } },
    Scene = PyScene { |x: &PyScene| x.inner.clone(); |inner| PyScene { inner } },
    DenseSolution = PyDenseSolution {
        |x: &PyDenseSolution| x.inner.clone(); |inner| PyDenseSolution { inner }
    },
}

/// `(data, callables)` of a pointmass_dyn object; `_loads(data, callables)` rebuilds it.
#[pyfunction]
pub fn _dumps<'py>(
    py: Python<'py>,
    obj: &Obj<'py>,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyTuple>)> {
    let Some(mut payload) = payload_of(obj) else {
        let got = obj.get_type().name()?;
        let message = format!("_dumps: expected a pointmass_dyn object, got {got}");
        return Err(PyTypeError::new_err(message));
    };
    let source = |f: &mut crate::effects::TorqueFunction| {
        let c = f.source().and_then(|s| s.downcast_ref::<Py<PyAny>>());
        let message = "a torque function not made from a Python callable cannot be pickled";
        c.map(|c| c.clone_ref(py))
            .ok_or_else(|| PyValueError::new_err(message))
    };
    let callables: Vec<_> = payload
        .torque_functions()
        .map(source)
        .collect::<PyResult<_>>()?;
    let data = crate::io::persist::encode(&payload);
    let data = data.map_err(|e| PicklingError::new_err(e.to_string()))?;
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
    let sources = callables.map_or(vec![], |c| c.iter().map(|c| c.unbind()).collect());
    let payload = Payload::decode(data.as_bytes(), sources, torque_callback).map_err(|e| {
        let message = format!("cannot unpickle a pointmass_dyn object: {e}");
        py_error(py, "UnpicklingError", message)
    })?;
    object(py, payload)
}
