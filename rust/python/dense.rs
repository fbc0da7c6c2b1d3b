//! `DenseSolution`: the dense output of an `rk45` run, callable as SciPy's `OdeSolution`.
use crate::python::Obj;
use pyo3::prelude::*;

use super::convert::{array, to_array, to_array1};
use super::errors::{invalid, py_error, IntoPyResult};
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
        let dim = self.inner.dim();
        if self.inner.n_segments() == 0 {
            return Err(py_error(
                py,
                "SimulationError",
                format!(
                    "sol(t): the run ended at t = {} before its first step, so there is nothing to interpolate",
                    self.inner.breakpoints().first().copied().unwrap_or(f64::NAN)
                ),
            ));
        }
        let (shape, ts) = array(t, "t")?;
        if shape.len() > 1 {
            let got = format!("shape {shape:?}");
            return Err(invalid(py, "t", "a scalar or a 1-D array", got));
        }
        let y = self.inner.sample(&ts).py(py)?;
        match shape.len() {
            0 => Ok(to_array1(py, &y).into_any()),
            _ => to_array(py, y, &[dim, ts.len()]),
        }
    }
    #[getter]
    fn ts<'py>(&self, py: Python<'py>) -> Obj<'py> {
        to_array1(py, self.inner.breakpoints()).into_any()
    }
}
