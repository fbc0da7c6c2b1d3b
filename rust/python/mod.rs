//! The Python bindings: one thin layer that converts arrays and errors and calls the core.
mod body;
mod convert;
mod errors;
mod model;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<body::PyRigidBody>()?;
    m.add_class::<body::PyPointMasses>()?;
    m.add_class::<model::PyJoint>()?;
    m.add_class::<model::PyModel>()?;
    Ok(())
}
