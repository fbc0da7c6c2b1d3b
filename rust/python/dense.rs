//! `DenseSolution`: the dense output of an `rk45` run, callable as SciPy's `OdeSolution`.
use pyo3::prelude::*;

use super::convert::{array, to_array, to_array1};
use super::errors::{invalid, py_error};
use crate::integrator::DenseOutput;

/// The dense output of an `rk45` run: `sol(t)` for a scalar (shape (n,)) or an array of
/// times (shape (n, len(t))), as SciPy's `OdeSolution`.
#[pyclass(name = "DenseSolution", module = "pointmass_dyn._core", frozen)]
pub struct PyDenseSolution {
    pub(crate) inner: DenseOutput,
}

#[pymethods]
impl PyDenseSolution {
    fn __call__<'py>(&self, py: Python<'py>, t: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyAny>> {
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
        if let Some(bad) = ts.iter().find(|x| !x.is_finite()) {
            return Err(invalid(py, "t", "finite times", bad));
        }
        // Outside the integrated interval the interpolant extrapolates, and overflows far away.
        let check = |x: f64, y: &[f64]| -> PyResult<()> {
            if y.iter().all(|v| v.is_finite()) {
                return Ok(());
            }
            let b = self.inner.breakpoints();
            let (first, last) = (
                b.first().copied().unwrap_or(f64::NAN),
                b.last().copied().unwrap_or(f64::NAN),
            );
            let (lo, hi) = (first.min(last), first.max(last));
            Err(py_error(
                py,
                "NumericalError",
                format!("sol(t): the dense output at t = {x:e} is not finite: it extrapolates the solution on [{lo}, {hi}] far outside it"),
            ))
        };
        if shape.is_empty() {
            let y = self.inner.eval(ts[0]);
            check(ts[0], &y)?;
            return Ok(to_array1(py, &y).into_any());
        }
        if shape.len() != 1 {
            return Err(invalid(
                py,
                "t",
                "a scalar or a 1-D array",
                format!("shape {shape:?}"),
            ));
        }
        let mut out = vec![0.0; dim * ts.len()];
        let mut buf = vec![0.0; dim];
        for (j, x) in ts.iter().enumerate() {
            self.inner.eval_into(*x, &mut buf);
            check(*x, &buf)?;
            for i in 0..dim {
                out[i * ts.len() + j] = buf[i];
            }
        }
        to_array(py, out, &[dim, ts.len()])
    }
    #[getter]
    fn ts<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, self.inner.breakpoints()).into_any()
    }
}
