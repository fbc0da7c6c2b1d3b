//! NumPy ⇄ Rust conversions. Anything array-like (lists, integer arrays) is accepted and
//! converted to float64; a wrong shape names the argument, the expected and the given shape.
use nalgebra::DMatrix;
use numpy::{AllowTypeChange, PyArray1, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::errors::invalid;
use crate::spatial::{Mat3, Vec3};

pub fn shape_str(shape: &[usize]) -> String {
    match shape.len() {
        1 => format!("shape ({},)", shape[0]),
        _ => format!(
            "shape ({})",
            shape
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Any array-like of numbers: its shape and its entries in C order.
pub fn array(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let py = obj.py();
    let arr: PyArrayLikeDyn<'_, f64, AllowTypeChange> = obj.extract().map_err(|_| {
        let ty = obj
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into());
        invalid(
            py,
            arg,
            "an array of real numbers",
            format!("an object of type {ty}"),
        )
    })?;
    let shape = arr.shape().to_vec();
    // Raw memory only in C order; Fortran-ordered or strided arrays are read logically.
    let data = match arr.as_slice() {
        Ok(s) if arr.is_c_contiguous() => s.to_vec(),
        _ => arr.as_array().iter().copied().collect(),
    };
    Ok((shape, data))
}

/// A 1-D array of length `len` (`None`: any length).
pub fn vector(obj: &Bound<'_, PyAny>, arg: &str, len: Option<usize>) -> PyResult<Vec<f64>> {
    let (shape, data) = array(obj, arg)?;
    if shape.len() != 1 || len.is_some_and(|n| n != shape[0]) {
        let want = match len {
            Some(n) => format!("shape ({n},)"),
            None => "a 1-D array".into(),
        };
        return Err(invalid(obj.py(), arg, want, shape_str(&shape)));
    }
    Ok(data)
}

/// Fast path for the per-call dynamics functions: a contiguous float64 1-D array is copied
/// straight into `out`; anything else goes through `vector`.
pub fn vector_into(obj: &Bound<'_, PyAny>, arg: &str, out: &mut [f64]) -> PyResult<()> {
    if let Ok(a) = obj.cast::<PyArray1<f64>>() {
        // SAFETY: the data is copied at once while attached to the interpreter, so no Python
        // code can write to the array meanwhile; this skips rust-numpy's borrow tracking,
        // which costs more than the copy for small arrays.
        if let Ok(s) = unsafe { a.as_slice() }.map_err(|_| ()).and_then(|s| {
            if a.is_c_contiguous() {
                Ok(s)
            } else {
                Err(())
            }
        }) {
            if s.len() == out.len() {
                out.copy_from_slice(s);
                return Ok(());
            }
        }
    }
    let v = vector(obj, arg, Some(out.len()))?;
    out.copy_from_slice(&v);
    Ok(())
}

pub fn vec3(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Vec3> {
    let mut v = [0.0; 3];
    vector_into(obj, arg, &mut v)?;
    Ok(Vec3::from(v))
}

pub fn mat3(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Mat3> {
    let (shape, data) = array(obj, arg)?;
    if shape != [3, 3] {
        return Err(invalid(obj.py(), arg, "shape (3, 3)", shape_str(&shape)));
    }
    Ok(Mat3::from_row_slice(&data))
}

/// An (n, 3) array of points (also accepts (a, b, 3), flattened over the leading axes).
pub fn points(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Vec<Vec3>> {
    let (shape, data) = array(obj, arg)?;
    if shape.len() < 2 || shape[shape.len() - 1] != 3 {
        return Err(invalid(obj.py(), arg, "shape (n, 3)", shape_str(&shape)));
    }
    Ok(data.chunks_exact(3).map(Vec3::from_column_slice).collect())
}

pub fn to_array1<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A row-major array of the given shape from C-ordered data.
pub fn to_array<'py>(
    py: Python<'py>,
    data: Vec<f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let flat = PyArray1::from_vec(py, data);
    Ok(flat.reshape(shape.to_vec())?.into_any())
}

pub fn mat3_to_array<'py>(py: Python<'py>, m: &Mat3) -> PyResult<Bound<'py, PyAny>> {
    to_array(py, m.transpose().as_slice().to_vec(), &[3, 3])
}

pub fn dmatrix_to_array<'py>(py: Python<'py>, m: &DMatrix<f64>) -> PyResult<Bound<'py, PyAny>> {
    // nalgebra is column-major; NumPy wants C order.
    to_array(
        py,
        m.transpose().as_slice().to_vec(),
        &[m.nrows(), m.ncols()],
    )
}
