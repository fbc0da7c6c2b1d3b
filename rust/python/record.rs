//! Typed results: a core record crossing the boundary as a frozen Python class that holds
//! it, each field a read-only attribute converted when read ([`Field`]), instead of a dict
//! built field by field. The class also answers `r["field"]` and `r.keys()` (the dicts it
//! replaced were read so), and has a `repr` naming its fields.
use crate::python::Obj;
use nalgebra::DMatrix;
use pyo3::prelude::*;
use pyo3::IntoPyObjectExt;

use super::convert::{dmatrix_to_array, to_array1};

/// A record's field as Python sees it: numbers, strings and index lists as themselves, real
/// vectors and matrices as NumPy arrays.
pub trait Field {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>>;
}

macro_rules! as_itself {
    ($($t:ty),*) => {
        $(impl Field for $t {
            fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
                self.clone().into_bound_py_any(py)
            }
        })*
    };
}
as_itself!(
    bool,
    usize,
    f64,
    Option<f64>,
    String,
    Option<String>,
    Vec<String>,
    Vec<usize>,
    Vec<bool>
);
as_itself!((f64, f64), Option<(String, String)>);

impl Field for ([f64; 3], [f64; 3]) {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let t = |x: &[f64; 3]| (x[0], x[1], x[2]);
        (t(&self.0), t(&self.1)).into_bound_py_any(py)
    }
}

impl Field for Vec<f64> {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        Ok(to_array1(py, self).into_any())
    }
}

impl Field for nalgebra::DVector<f64> {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        Ok(to_array1(py, self.as_slice()).into_any())
    }
}

impl Field for DMatrix<f64> {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        dmatrix_to_array(py, self)
    }
}

/// A list of fields (vectors, matrices), each converted.
impl<T: Field> Field for [T] {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let items = self.iter().map(|x| x.field(py));
        items.collect::<PyResult<Vec<_>>>()?.into_bound_py_any(py)
    }
}

/// `record!(PyX("Name", core::X) { a, b: |r, py| expr, ... } eq);`: a frozen class
/// `Name` holding a `core::X` as `.0`; field `a` read through [`Field`], `b` through the
/// conversion given (`r` the record, `py` the interpreter). A trailing `eq` compares two
/// records by their fields (the core type's `PartialEq`). Iterating one gives its field
/// names, as a dict's keys.
macro_rules! record {
    (@get $s:ident, $py:ident, $f:ident) => {{
        use $crate::python::record::Field as _;
        $s.0.$f.field($py)
    }};
    (@get $s:ident, $py:ident, $f:ident, $conv:expr) => { ($conv)(&$s.0, $py) };
    (@eq $ty:ident) => {
        #[pyo3::pymethods]
        impl $ty {
            fn __eq__(&self, other: &pyo3::Bound<'_, pyo3::PyAny>) -> bool {
                other.cast::<Self>().is_ok_and(|o| o.get().0 == self.0)
            }
        }
    };
    ($(#[$m:meta])* $ty:ident($name:literal, $inner:ty) {
        $($f:ident $(: $conv:expr)?),* $(,)?
    } $($eq:ident)?) => {
        $(#[$m])*
        #[pyo3::pyclass(name = $name, module = "pointmass_dyn._core", frozen)]
        pub struct $ty(pub $inner);

        #[pyo3::pymethods]
        impl $ty {
            $(#[getter]
            #[allow(non_snake_case)]
            fn $f<'py>(&self, py: pyo3::Python<'py>) -> pyo3::PyResult<pyo3::Bound<'py, pyo3::PyAny>> {
                $crate::python::record::record!(@get self, py, $f $(, $conv)?)
            })*
            fn __repr__(slf: &pyo3::Bound<'_, Self>) -> pyo3::PyResult<String> {
                $crate::python::record::repr(slf, $name, &Self::KEYS)
            }
            fn __getitem__<'py>(
                slf: &pyo3::Bound<'py, Self>,
                key: &str,
            ) -> pyo3::PyResult<pyo3::Bound<'py, pyo3::PyAny>> {
                $crate::python::record::item(slf, key, &Self::KEYS)
            }
            fn keys(&self) -> Vec<&'static str> {
                Self::KEYS.to_vec()
            }
            fn __iter__<'py>(
                slf: &pyo3::Bound<'py, Self>,
            ) -> pyo3::PyResult<pyo3::Bound<'py, pyo3::types::PyIterator>> {
                use pyo3::types::PyAnyMethods;
                pyo3::types::PyList::new(slf.py(), Self::KEYS)?.as_any().try_iter()
            }
            fn __contains__(&self, key: &str) -> bool {
                Self::KEYS.contains(&key)
            }
            fn __len__(&self) -> usize {
                Self::KEYS.len()
            }
            fn items<'py>(slf: &pyo3::Bound<'py, Self>) -> pyo3::PyResult<Vec<(&'static str, pyo3::Bound<'py, pyo3::PyAny>)>> {
                $crate::python::record::items(slf, &Self::KEYS)
            }
            /// Pickled as the dict of its fields (the form these results had before).
            fn __reduce__<'py>(slf: &pyo3::Bound<'py, Self>) -> pyo3::PyResult<(pyo3::Bound<'py, pyo3::PyAny>, (Vec<(&'static str, pyo3::Bound<'py, pyo3::PyAny>)>,))> {
                let dict = slf.py().get_type::<pyo3::types::PyDict>().into_any();
                Ok((dict, ($crate::python::record::items(slf, &Self::KEYS)?,)))
            }
        }
        impl $ty {
            const KEYS: [&'static str; [$(stringify!($f)),*].len()] = [$(stringify!($f)),*];
        }
        $($crate::python::record::record!(@$eq $ty);)?
    };
}
pub(crate) use record;

/// `obj[key]` for one of a record's `fields`, else `KeyError`.
pub fn item<'py>(obj: &Obj<'py>, key: &str, fields: &[&str]) -> PyResult<Obj<'py>> {
    match fields.contains(&key) {
        true => obj.getattr(key),
        false => Err(pyo3::exceptions::PyKeyError::new_err(key.to_string())),
    }
}

/// `(name, value)` of each of a record's `fields`, in order.
pub fn items<'py>(
    obj: &Obj<'py>,
    fields: &[&'static str],
) -> PyResult<Vec<(&'static str, Obj<'py>)>> {
    fields.iter().map(|f| Ok((*f, obj.getattr(*f)?))).collect()
}

/// `Name(a=..., b=...)` of a record's fields.
pub fn repr(obj: &Obj, name: &str, fields: &[impl AsRef<str>]) -> PyResult<String> {
    let parts: PyResult<Vec<String>> = fields
        .iter()
        .map(|f| {
            Ok(format!(
                "{}={}",
                f.as_ref(),
                obj.getattr(f.as_ref())?.repr()?
            ))
        })
        .collect();
    Ok(format!("{name}({})", parts?.join(", ")))
}
