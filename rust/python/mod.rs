//! The Python bindings: one thin layer that converts arrays and errors and calls the core.
mod body;
mod convert;
mod dense;
mod derivatives;
mod effects;
mod errors;
mod events;
mod jac;
mod joint;
mod loops;
mod model;
mod options;
mod pickle;
mod reactions;
mod rk45;
mod scene;
mod signals;
mod simulate;
mod visuals;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<body::PyRigidBody>()?;
    m.add_class::<body::PyPointMasses>()?;
    m.add_class::<joint::PyJoint>()?;
    m.add_class::<model::PyModel>()?;
    m.add_class::<effects::PyEffect>()?;
    m.add_class::<events::PyStateEvent>()?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<dense::PyDenseSolution>()?;
    m.add_function(wrap_pyfunction!(simulate::simulate_scene, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate_batch, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::effect_forces, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::energies, m)?)?;
    m.add_function(wrap_pyfunction!(rk45::rk45, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_dumps, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_loads, m)?)?;
    Ok(())
}
