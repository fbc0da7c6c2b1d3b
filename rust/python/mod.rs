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
        $crate::python::getters!($ty |s, py| { $($(#[$m])* $name -> $t = s.$($field).+.clone()),* });
    };
    ($ty:ident |$s:ident, $py:ident| { $($(#[$m:meta])* $name:ident -> $t:ty = $e:expr),* $(,)? }) => {
        #[pyo3::pymethods]
        #[allow(unused_variables, clippy::clone_on_copy)]
        impl $ty {
            $($(#[$m])* #[getter] fn $name<'py>(&self, $py: pyo3::Python<'py>) -> $t { let $s = self; $e })*
        }
    };
    ($ty:ident.$read:ident { $($(#[$m:meta])* $name:ident: $t:ty = |$x:ident, $py:ident| $get:expr),* $(,)? }) => {
        #[pyo3::pymethods]
        #[allow(unused_variables)]
        impl $ty {
            $($(#[$m])* #[getter] fn $name<'py>(&self, $py: pyo3::Python<'py>) -> $t { self.$read($py, |$x| $get) })*
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

/// Adds to module `m` each binding module's classes (first list) and functions (second).
macro_rules! register {
    ($m:ident; $($module:ident: [$($class:ident),*] [$($function:ident),*];)*) => {
        $(
            $($m.add_class::<$module::$class>()?;)*
            $($m.add_function(wrap_pyfunction!($module::$function, $m)?)?;)*
        )*
    };
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    crate::support::cpu::check_cpu_features().map_err(pyo3::exceptions::PyImportError::new_err)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The widest copy of the multiversioned loops that runs: "avx512", "avx2" or "baseline"
    // (rust/support/cpu.rs; POINTMASS_DYN_BASELINE=1 forces "baseline").
    m.add("cpu_dispatch", crate::support::cpu::dispatch())?;
    register! { m;
        body: [PyRigidBody, PyPointMasses] [];
        joint: [PyJoint] [];
        model: [PyModel] [];
        effects: [PyEffect, PyContactParameters, PyContactStates] [];
        rk45: [PyOdeSolution] [rk45];
        events: [PyStateEvent] [];
        scene: [PyScene] [];
        dense: [PyDenseSolution] [];
        run_config: [PyRunConfig] [];
        control: [PySimulator] [];
        trajectory: [PyRunResult, PyRunStatus] [];
        identification: [PyBase, PyIdentified] [identification_regressor,
            identification_parameters, identification_base, identification_fit, identification_model];
        simulate: [] [simulate_scene, simulate_batch, effect_forces, energies];
        along: [] [scene_along, scene_shaking];
        visuals: [] [resolve_mesh];
        design: [] [design_cells, design_regressor, design_pins, design_pin_loads, design_solve];
        pickle: [] [_dumps, _loads];
    }
    model::add_records(m)?;
    Ok(())
}
