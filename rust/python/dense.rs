//! `DenseSolution`: the dense output of an `rk45` run, callable as SciPy's `OdeSolution`.
use crate::python::Obj;
use pyo3::prelude::*;

use super::convert::{to_array, to_array1};
use crate::integrator::DenseOutput;

/// The dense output of an `rk45` run: `sol(t)` for a scalar (shape (n,)) or an array of
/// times (shape (n, len(t))), as SciPy's `OdeSolution`.
#[pyclass(name = "DenseSolution", module = "pointmass_dyn._core", frozen)]
pub struct PyDenseSolution {
    pub(crate) inner: DenseOutput,
}

#[pymethods]
impl PyDenseSolution {
    fn __call__<'py>(&self, py: Python<'py>, t: &Obj) -> PyResult<Obj<'py>> {
        match self.inner.sample_arg(t)? {
            (y, None) => Ok(to_array1(py, &y).into_any()),
            (y, Some(m)) => to_array(py, y, &[self.inner.dim(), m]),
        }
    }
    #[getter]
    fn ts<'py>(&self, py: Python<'py>) -> Obj<'py> {
        to_array1(py, self.inner.breakpoints()).into_any()
    }
}
