//! Read-only attributes derived from a table, each one expression of the object converted
//! as a record's fields are ([`Field`](super::record::Field)): the sizes, names and values a
//! class passes on (`getters!` in mod.rs returns fields as they are).

/// `derived_getters!(PyX, |x| { /// doc
/// name: expr; ... })`: a getter `name` per row returning `expr` (`x` the object).
macro_rules! derived_getters {
    ($ty:ty, |$x:ident| { $($(#[$m:meta])* $name:ident: $e:expr;)* }) => {
        #[pyo3::pymethods]
        impl $ty {
            $($(#[$m])*
            #[getter]
            fn $name<'py>(
                &self,
                py: pyo3::Python<'py>,
            ) -> pyo3::PyResult<pyo3::Bound<'py, pyo3::PyAny>> {
                let $x = self;
                $crate::python::record::Field::field(&$e, py)
            })*
        }
    };
}
pub(crate) use derived_getters;
