//! `calls!`: `Model` methods declared from a table, each by its name, its parameters and
//! the core call that reads them (`crate::frames::calls`, `crate::dynamics::kinematics_calls`).
//! The core reads the arguments with the interpreter held and returns the computation; the
//! method runs it, detached (Ctrl-C heard) when the entry ends in `detached` (a computation
//! that can be long: many rows, the explicit n × n products), and converts the result:
//! `=> (a, b)` each part through [`Out`] (a tuple of several), `=> PyRecord` as that record.
//! `calls! { in_workspace ... }` declares short, often repeated calls that read `q` (and `v`)
//! into the pooled workspace and compute there (`fn name(q, v) = core::call => (out);`).
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::kinematics::poses::{Keyed, Shaped};
use crate::python::convert::to_array;
use crate::python::record::Field;
use crate::python::Obj;

macro_rules! calls {
    (@out $py:ident, $x:ident, ($($o:ident),+)) => {{
        let ($($o),+) = $x;
        ($($crate::python::model::calls::Out::out($o, $py)?),+).into_bound_py_any($py)
    }};
    (@out $py:ident, $x:ident, $record:ident) => { $record($x).into_bound_py_any($py) };
    (@run $py:ident, $run:ident) => { $crate::python::errors::IntoPyResult::py($run(), $py) };
    (@run $py:ident, $run:ident, detached) => {
        $crate::python::signals::detach_interruptible($py, $run)
    };
    (in_workspace
        $($(#[$m:meta])* fn $name:ident($q:ident $(, $v:ident)?) = $call:path => $out:tt;)*) => {
        #[pyo3::pymethods]
        impl PyModel {
            $($(#[$m])*
            #[allow(unused_parens)]
            fn $name<'py>(&self, py: Python<'py>, $q: &Obj $(, $v: &Obj)?) -> PyResult<Obj<'py>> {
                use pyo3::IntoPyObjectExt;
                self.with_workspace(|ws| {
                    // q, and v when the method takes it, into the workspace's buffers.
                    super::load_state(ws, py, $q, None $(.or(Some($v)))?)?;
                    let x = $crate::python::errors::IntoPyResult::py($call(ws), py)?;
                    $crate::python::model::calls::calls!(@out py, x, $out)
                })
            })*
        }
    };
    ($($(#[$m:meta])* fn $name:ident($($a:ident: $t:ty),*) = $call:path => $out:tt $($d:ident)?;)*)
    => {
        #[pyo3::pymethods]
        impl PyModel {
            $($(#[$m])*
            #[allow(unused_parens)]
            fn $name<'py>(&self, py: Python<'py>, $($a: $t),*) -> PyResult<Obj<'py>> {
                use pyo3::IntoPyObjectExt;
                let model = self.model();
                let run = $call(&model, $($a),*)?;
                let x = $crate::python::model::calls::calls!(@run py, run $(, $d)?)?;
                $crate::python::model::calls::calls!(@out py, x, $out)
            })*
        }
    };
}
pub(crate) use calls;

/// A call's result as Python sees it, consumed: its arrays handed over, not copied.
pub trait Out {
    fn out<'py>(self, py: Python<'py>) -> PyResult<Obj<'py>>;
}

/// What a record's fields are ([`Field`]: numbers, vectors, matrices, index lists) as there.
impl<T: Field> Out for T {
    fn out<'py>(self, py: Python<'py>) -> PyResult<Obj<'py>> {
        self.field(py)
    }
}

/// An array with its shape (a 1-D one made as it is: a reshape costs NumPy a new view).
impl Out for Shaped {
    fn out<'py>(self, py: Python<'py>) -> PyResult<Obj<'py>> {
        match self.shape.len() {
            1 => Ok(numpy::PyArray1::from_vec(py, self.values).into_any()),
            _ => to_array(py, self.values, &self.shape),
        }
    }
}

/// An array, or None.
impl Out for Option<Shaped> {
    fn out<'py>(self, py: Python<'py>) -> PyResult<Obj<'py>> {
        match self {
            Some(x) => x.out(py),
            None => Ok(py.None().into_bound(py)),
        }
    }
}

/// Arrays by name: a dict of them.
impl Out for Vec<Keyed> {
    fn out<'py>(self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let d = PyDict::new(py);
        for (key, x) in self {
            d.set_item(key, x.out(py)?)?;
        }
        Ok(d.into_any())
    }
}
