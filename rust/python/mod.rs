//! The Python bindings: one thin layer that converts arrays and errors and calls the core.
// Each binding takes the arguments of the Python function it declares, however many.
#![allow(clippy::too_many_arguments)]

/// `#[getter]`s, each with its docs: `getters!(PyX { name: Type = inner.field, ... });`
/// returns a field as it is; `getters!(PyX |s, py| { name -> Type = expr, ... });` the value
/// of `expr`, in which `s` is the object and `py` the interpreter;
/// `getters!(PyX.read { name: Type = |inner, py| value, ... });` the value from what the
/// class holds, which `PyX::read(f)` lends to `f`; `getters!(PyX |x| { name: expr; ... });`
/// `expr` converted as a record's fields are ([`Field`](record::Field)).
macro_rules! getters {
    ($ty:ident { $($(#[$m:meta])* $name:ident: $t:ty = $($field:ident).+),* $(,)? }) => {
        #[pyo3::pymethods]
        #[allow(clippy::clone_on_copy)]
        impl $ty {
            $($(#[$m])* #[getter] fn $name(&self) -> $t { self.$($field).+.clone() })*
        }
    };
    ($ty:ident |$s:ident, $py:ident| { $($(#[$m:meta])* $name:ident -> $t:ty = $e:expr),* $(,)? }) => {
        #[pyo3::pymethods]
        #[allow(unused_variables)]
        impl $ty {
            $($(#[$m])* #[getter] fn $name<'py>(&self, $py: pyo3::Python<'py>) -> $t { let $s = self; $e })*
        }
    };
    ($ty:ident.$read:ident { $($(#[$m:meta])* $name:ident: $t:ty = |$x:ident, $py:ident| $get:expr),* $(,)? }) => {
        #[pyo3::pymethods]
        #[allow(unused_variables)]
        impl $ty {
            $($(#[$m])* #[getter] fn $name<'py>(&self, $py: pyo3::Python<'py>) -> $t { self.$read(|$x| $get) })*
        }
    };
    ($ty:ident |$x:ident| { $($(#[$m:meta])* $name:ident: $e:expr;)* }) => {
        #[pyo3::pymethods]
        impl $ty {
            $($(#[$m])* #[getter] fn $name<'py>(&self, py: pyo3::Python<'py>) -> pyo3::PyResult<crate::python::Obj<'py>> {
                let $x = self;
                crate::python::record::Field::field(&$e, py)
            })*
        }
    };
}
pub(crate) use getters;

/// Any Python object, as the bindings take their arguments (converted in the core's terms).
pub type Obj<'py> = pyo3::Bound<'py, pyo3::PyAny>;

mod along;
mod body;
mod control;
mod convert;
mod dense;
mod derivatives;
mod design;
mod effects;
mod errors;
mod events;
mod identification;
mod joint;
mod model;
mod pickle;
mod record;
mod rk45;
mod run_config;
mod scene;
mod signals;
mod simulate;
mod trajectory;
mod visuals;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    crate::support::cpu::check_cpu_features().map_err(pyo3::exceptions::PyImportError::new_err)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The widest copy of the multiversioned loops that runs: "avx512", "avx2" or "baseline"
    // (rust/support/cpu.rs; POINTMASS_DYN_BASELINE=1 forces "baseline").
    m.add("cpu_dispatch", crate::support::cpu::dispatch())?;
    m.add_class::<body::PyRigidBody>()?;
    m.add_class::<body::PyPointMasses>()?;
    m.add_class::<joint::PyJoint>()?;
    m.add_class::<model::PyModel>()?;
    m.add_class::<effects::PyEffect>()?;
    m.add_class::<effects::PyContactParameters>()?;
    m.add_class::<effects::PyContactStates>()?;
    m.add_class::<rk45::PyOdeSolution>()?;
    m.add_class::<events::PyStateEvent>()?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<dense::PyDenseSolution>()?;
    m.add_class::<run_config::PyRunConfig>()?;
    m.add_class::<control::PySimulator>()?;
    m.add_class::<trajectory::PyRunResult>()?;
    m.add_class::<trajectory::PyRunStatus>()?;
    model::add_records(m)?;
    m.add_class::<identification::PyBase>()?;
    m.add_class::<identification::PyIdentified>()?;
    m.add_function(wrap_pyfunction!(simulate::simulate_scene, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate_batch, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::effect_forces, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::energies, m)?)?;
    m.add_function(wrap_pyfunction!(along::scene_along, m)?)?;
    m.add_function(wrap_pyfunction!(along::scene_shaking, m)?)?;
    m.add_function(wrap_pyfunction!(rk45::rk45, m)?)?;
    m.add_function(wrap_pyfunction!(visuals::resolve_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_cells, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_regressor, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_pins, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_pin_loads, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_solve, m)?)?;
    m.add_function(wrap_pyfunction!(
        identification::identification_regressor,
        m
    )?)?;
    m.add_function(wrap_pyfunction!(
        identification::identification_parameters,
        m
    )?)?;
    m.add_function(wrap_pyfunction!(identification::identification_base, m)?)?;
    m.add_function(wrap_pyfunction!(identification::identification_fit, m)?)?;
    m.add_function(wrap_pyfunction!(identification::identification_model, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_dumps, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_loads, m)?)?;
    Ok(())
}
