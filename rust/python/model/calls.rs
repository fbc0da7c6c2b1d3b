//! `calls!`: `Model` methods declared from a table, each by its name, its parameters and
//! the core call that reads them (`crate::frames::calls`, `crate::dynamics::kinematics_calls`).
//! The core reads the arguments with the interpreter held and returns the computation; the
//! method runs it detached (Ctrl-C heard) and converts the result: `=> (a, b)` each part
//! through [`Field`] (a tuple of several), `=> PyRecord` as that record.
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::kinematics::poses::{Keyed, Shaped};
use crate::python::convert::to_array;
use crate::python::record::Field;
use crate::python::Obj;

macro_rules! calls {
    (@out $py:ident, $x:ident, ($($o:ident),+)) => {{
        let ($($o),+) = $x;
        ($($crate::python::record::Field::field(&$o, $py)?),+).into_bound_py_any($py)
    }};
    (@out $py:ident, $x:ident, $record:ident) => { $record($x).into_bound_py_any($py) };
    ($($(#[$m:meta])* fn $name:ident($($a:ident: $t:ty),*) = $call:path => $out:tt;)*) => {
        #[pyo3::pymethods]
        impl PyModel {
            $($(#[$m])*
            #[allow(unused_parens)]
            fn $name<'py>(&self, py: Python<'py>, $($a: $t),*) -> PyResult<Obj<'py>> {
                use pyo3::IntoPyObjectExt;
                let model = self.model();
                let run = $call(&model, $($a),*)?;
                let x = $crate::python::signals::detach_interruptible(py, run)?;
                $crate::python::model::calls::calls!(@out py, x, $out)
            })*
        }
    };
}
pub(crate) use calls;

/// An array with its shape.
impl Field for Shaped {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        to_array(py, self.values.clone(), &self.shape)
    }
}

/// An array, or None.
impl Field for Option<Shaped> {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        match self {
            Some(x) => x.field(py),
            None => Ok(py.None().into_bound(py)),
        }
    }
}

/// Arrays by name: a dict of them.
impl Field for Vec<Keyed> {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let d = PyDict::new(py);
        for (key, x) in self {
            d.set_item(key, x.field(py)?)?;
        }
        Ok(d.into_any())
    }
}
