//! Core errors to the package's own exception hierarchy (`pointmass_dyn.errors`, defined in
//! Python so classes can subclass both our base and `ValueError`/`ArithmeticError`).
use pyo3::prelude::*;
use pyo3::types::PyType;

use crate::support::error::{compact_numbers, Error};

/// Builds an instance of `pointmass_dyn.errors.<class_name>` with `message`.
pub fn py_error(py: Python<'_>, class_name: &str, message: String) -> PyErr {
    let cls = py
        .import("pointmass_dyn.errors")
        .and_then(|m| m.getattr(class_name))
        .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
    match cls {
        Ok(cls) => PyErr::from_type(cls, (message,)),
        // The package is always importable next to its extension; fall back loudly.
        Err(_) => pyo3::exceptions::PyValueError::new_err(message),
    }
}

pub fn to_py(py: Python<'_>, err: Error) -> PyErr {
    match err.kind_name() {
        Some(class) => py_error(py, class, compact_numbers(&err.to_string())),
        // Only when no signal handler left its own exception to re-raise.
        None => pyo3::exceptions::PyKeyboardInterrupt::new_err(err.to_string()),
    }
}

/// For `?` on the core's results where no `py` is at hand (the core's parsers, [`crate::support::args`]).
impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        Python::attach(|py| to_py(py, e))
    }
}

pub trait IntoPyResult<T> {
    fn py(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> IntoPyResult<T> for Result<T, Error> {
    fn py(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}

/// Raises `NumericalError` if a result computed from finite inputs is not finite.
pub fn check_result(py: Python<'_>, what: &str, values: &[f64]) -> PyResult<()> {
    crate::support::error::check_result(what, values).py(py)
}

/// `InvalidInputError`: `arg: expected ..., got ...` ([`Error::InvalidArgument`]'s text).
pub fn invalid(
    py: Python<'_>,
    arg: &str,
    expected: impl std::fmt::Display,
    got: impl std::fmt::Display,
) -> PyErr {
    to_py(py, Error::arg(arg, expected.to_string(), got.to_string()))
}

/// What stopped a run from its progress hook, for the run's message (the core words it).
pub fn interrupt_reason(py: Python<'_>, e: &PyErr) -> String {
    let ctrl_c = e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py);
    let name = e.get_type(py).name().map(|n| n.to_string()).ok();
    let text = e.value(py).str().map(|s| s.to_string()).ok();
    crate::support::interrupt::progress_reason(ctrl_c, name, text)
}
