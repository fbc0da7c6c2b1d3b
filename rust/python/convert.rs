//! NumPy ⇄ Rust conversions. Real numeric input only: Python floats and ints, NumPy arrays
//! and scalars of integer or floating dtype, and sequences of those (converted to float64).
//! Refused with `InvalidInputError` naming the argument and what was given: complex numbers,
//! strings and bytes, bools and bool arrays (a mask passed as numbers is a bug, not a value),
//! object arrays (ragged lists, `Decimal`, huge ints), masked arrays (the mask would be
//! silently dropped). A wrong shape names the argument, the expected and the given shape.
//! Index and count arguments are Python ints (or NumPy integers) converted by [`int_arg`].
use crate::python::Obj;
use nalgebra::{Dim, Matrix, RawStorage};
use numpy::{
    AllowTypeChange, PyArray1, PyArrayDescrMethods, PyArrayLikeDyn, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyOverflowError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyByteArray, PyBytes, PyFloat, PyInt, PyList, PyString, PyTuple};

use super::errors::py_error;
use crate::support::args::{shortened, Arg, Int, NotReal};
use crate::support::spatial::Vec3;

// The core's parsers under the names the bindings call them by.
pub use crate::support::args::{count as count_arg, mat3, points, scalar, vector};

fn type_name(obj: &Obj) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// `repr(obj)`, cut to 60 characters.
pub fn short_repr(obj: &Obj) -> String {
    shortened(obj.repr().map(|r| r.to_string()).unwrap_or_default())
}

fn is_exact_ndarray(obj: &Obj) -> bool {
    let py = obj.py();
    let t = <PyUntypedArray as pyo3::PyTypeInfo>::type_object_raw(py);
    // SAFETY: `obj` is a live object; reading its type pointer takes no reference.
    unsafe { pyo3::ffi::Py_TYPE(obj.as_ptr()) == t }
}

fn is_masked(obj: &Obj) -> bool {
    // Asked of ndarray subclasses only. No masked array can exist before numpy.ma is
    // imported, and importing it here would cost the first call ~10 ms (numpy.ma builds its
    // docstrings on import): look it up among the loaded modules.
    let modules = obj
        .py()
        .import("sys")
        .and_then(|sys| sys.getattr("modules"));
    let masked = modules.and_then(|m| m.get_item("numpy.ma")?.getattr("MaskedArray"));
    masked.is_ok_and(|t| obj.is_instance(&t).unwrap_or(false))
}

/// Refuses an array whose dtype is not integer or floating.
fn check_dtype(arr: &Bound<'_, PyUntypedArray>, arg: &str) -> PyResult<()> {
    let dtype = arr.dtype();
    let refused = NotReal::dtype(dtype.kind(), || dtype.to_string());
    refused.map_or(Ok(()), |r| Err(r.at(arg).into()))
}

/// A conversion's failure as `fallback()`, except Ctrl-C (a `KeyboardInterrupt` that NumPy
/// raised while converting), which stays itself.
fn unless_interrupt(py: Python<'_>, e: PyErr, fallback: impl FnOnce() -> PyErr) -> PyErr {
    if e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py) {
        e
    } else {
        fallback()
    }
}

/// `obj` as a NumPy array of real (integer or floating) dtype, or `InvalidInputError`.
pub fn real_array<'py>(obj: &Obj<'py>, arg: &str) -> PyResult<Obj<'py>> {
    let py = obj.py();
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        if !is_exact_ndarray(obj) && is_masked(obj) {
            return Err(NotReal::Masked.at(arg).into());
        }
        check_dtype(a, arg)?;
        return Ok(obj.clone());
    }
    if obj.is_instance_of::<PyString>()
        || obj.is_instance_of::<PyBytes>()
        || obj.is_instance_of::<PyByteArray>()
    {
        return Err(NotReal::Text(type_name(obj), short_repr(obj))
            .at(arg)
            .into());
    }
    let not_an_array = || NotReal::Object(type_name(obj)).at(arg).into();
    let a = py
        .import("numpy")
        .and_then(|np| np.call_method1("asarray", (obj,)))
        .map_err(|e| unless_interrupt(py, e, not_an_array))?;
    // `asarray` gives a base-class array: no mask left to check.
    check_dtype(a.cast::<PyUntypedArray>().map_err(|_| not_an_array())?, arg)?;
    Ok(a)
}

/// A real number: a Python float or int, a NumPy integer or floating scalar, or a 0-d array
/// of those. NaN and inf pass (callers decide); an int beyond the double range does not.
pub fn real(obj: &Obj, arg: &str) -> PyResult<f64> {
    if let Ok(f) = obj.cast_exact::<PyFloat>() {
        return Ok(f.value());
    }
    if obj.is_instance_of::<PyInt>() && !obj.is_instance_of::<PyBool>() {
        return obj.extract::<f64>().map_err(|_| {
            let bits = obj
                .call_method0("bit_length")
                .and_then(|b| b.extract::<u64>());
            NotReal::HugeInt(bits.unwrap_or(0)).at(arg).into()
        });
    }
    Ok(scalar(array(obj, arg)?, arg)?)
}

/// A Python object as the core's [`Arg`]: the core parses, this only converts.
impl Arg for Obj<'_> {
    type Err = PyErr;
    fn absent(&self) -> bool {
        self.is_none()
    }
    fn is_bool(&self) -> bool {
        self.is_instance_of::<PyBool>()
    }
    fn text(&self) -> Option<String> {
        if let Ok(s) = self.cast::<PyString>() {
            return s.to_str().ok().map(str::to_owned);
        }
        // A path (`pathlib.Path`, any `os.PathLike` of text) reads as its text. An int never
        // is one, and is asked first: frame and joint indices come by here.
        let fspath = pyo3::intern!(self.py(), "__fspath__");
        if self.is_instance_of::<PyInt>() || !self.hasattr(fspath).unwrap_or(false) {
            return None;
        }
        let path: std::path::PathBuf = self.extract().ok()?;
        path.into_os_string().into_string().ok()
    }
    fn int(&self) -> Int {
        match self.extract::<i64>() {
            Ok(n) => Int::Value(n),
            Err(e) if e.is_instance_of::<PyOverflowError>(self.py()) => Int::TooBig,
            Err(_) => Int::No,
        }
    }
    fn shown(&self) -> String {
        short_repr(self)
    }
    fn items(&self) -> Option<PyResult<Vec<Self>>> {
        self.try_iter().ok().map(|it| it.collect())
    }
    fn real(&self, arg: &str) -> PyResult<f64> {
        real(self, arg)
    }
    fn array(&self, arg: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
        array(self, arg)
    }
    fn copy_plain(&self, out: &mut [f64]) -> bool {
        let plain = plain_f64_nd::<1>(self).filter(|(s, _)| s.len() == out.len());
        plain.map(|(s, _)| out.copy_from_slice(s)).is_some()
    }
    fn get(&self, key: &str) -> Option<Option<Self>> {
        let d = self.cast::<pyo3::types::PyDict>().ok()?;
        Some(d.get_item(key).ok().flatten())
    }
    fn keys(&self) -> Option<Vec<Self>> {
        let d = self.cast::<pyo3::types::PyDict>().ok()?;
        Some(d.keys().iter().collect())
    }
    fn attr(&self, name: &str) -> Option<Self> {
        self.getattr(name).ok()
    }
    fn wrong_type(&self, arg: &str, expected: &str) -> PyErr {
        let got = short_repr(self);
        py_error(
            self.py(),
            "ArgumentTypeError",
            format!("{arg}: expected {expected}, got {got}"),
        )
    }
}

/// A TOML value (the core's tree of plain data: an effect's `[[effect]]` table, a visual's
/// fields) as Python data: dicts, lists, str, int, float, bool.
pub fn toml_to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Obj<'py>> {
    use pyo3::IntoPyObjectExt;
    Ok(match v {
        toml::Value::String(s) => s.into_bound_py_any(py)?,
        toml::Value::Integer(i) => i.into_bound_py_any(py)?,
        toml::Value::Float(x) => x.into_bound_py_any(py)?,
        toml::Value::Boolean(b) => b.into_bound_py_any(py)?,
        toml::Value::Datetime(d) => d.to_string().into_bound_py_any(py)?,
        toml::Value::Array(a) => {
            let items = a.iter().map(|x| toml_to_py(py, x));
            pyo3::types::PyList::new(py, items.collect::<PyResult<Vec<_>>>()?)?.into_any()
        }
        toml::Value::Table(t) => {
            let d = pyo3::types::PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, toml_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A Python float, or an int within int64 (NumPy's dtype for it) as NumPy converts int64
/// to float64; `None` for anything else (a bool, a NumPy scalar: NumPy reads those).
fn plain_number(obj: &Obj) -> Option<f64> {
    if let Ok(f) = obj.cast_exact::<PyFloat>() {
        return Some(f.value());
    }
    let n = obj.cast_exact::<PyInt>().ok()?.extract::<i64>().ok()?;
    Some(n as f64)
}

/// Any array-like of real numbers: its shape and its entries in C order.
pub fn array(obj: &Obj, arg: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    // The common forms read directly, as `np.asarray` would give them (a number: a 0-d
    // float64 or int64; a float64 vector: itself): NumPy's import and `asarray` cost a
    // short run more than its evaluations (`rtol=1e-4`, `t_eval=np.linspace(...)`).
    if let Some(x) = plain_number(obj) {
        return Ok((Vec::new(), vec![x]));
    }
    if let Some((s, shape)) = plain_f64_nd::<1>(obj) {
        return Ok((shape.to_vec(), s.to_vec()));
    }
    // A tuple or list of such numbers (`t_span=(0, 1)`): float64 in NumPy too.
    let items: Option<Vec<f64>> = match (obj.cast_exact::<PyTuple>(), obj.cast_exact::<PyList>()) {
        (Ok(t), _) => t.iter().map(|x| plain_number(&x)).collect(),
        (_, Ok(l)) => l.iter().map(|x| plain_number(&x)).collect(),
        _ => None,
    };
    if let Some(v) = items {
        return Ok((vec![v.len()], v));
    }
    let py = obj.py();
    let obj = &real_array(obj, arg)?;
    let arr = obj
        .extract::<PyArrayLikeDyn<'_, f64, AllowTypeChange>>()
        .map_err(|e| unless_interrupt(py, e, || NotReal::Object(type_name(obj)).at(arg).into()))?;
    let shape = arr.shape().to_vec();
    // Raw memory only in C order; Fortran-ordered or strided arrays are read logically.
    let data = match arr.as_slice() {
        Ok(s) if arr.is_c_contiguous() => s.to_vec(),
        _ => arr.as_array().iter().copied().collect(),
    };
    Ok((shape, data))
}

/// A 2-D array as [`plain_f64_nd`] reads it: its data (C order) and its shape `(rows, cols)`.
pub fn plain_f64_rows<'a>(obj: &'a Obj) -> Option<(&'a [f64], [usize; 2])> {
    plain_f64_nd::<2>(obj)
}

/// An `ND`-dimensional, C-contiguous, aligned, native-order float64 `numpy.ndarray` (exactly
/// that type) as a slice and its shape, read from the array's own fields: rust-numpy's checked
/// cast (dtype objects compared through NumPy's API) costs more than copying a short vector.
/// `None` for anything else.
fn plain_f64_nd<'a, const ND: usize>(obj: &'a Obj) -> Option<(&'a [f64], [usize; ND])> {
    use numpy::npyffi::{self, NPY_TYPES};
    if !is_exact_ndarray(obj) {
        return None;
    }
    const FLAGS: std::os::raw::c_int = npyffi::NPY_ARRAY_C_CONTIGUOUS | npyffi::NPY_ARRAY_ALIGNED;
    // SAFETY: `obj` is exactly a NumPy array (checked above), so it has the array object's
    // layout; its descriptor and, for nd = ND, its ND dimensions are valid while `obj` lives.
    // The data is read by the caller attached to the interpreter (no Python code runs
    // meanwhile), as the checked path does.
    unsafe {
        let arr = &(*(obj.as_ptr() as *const npyffi::PyArrayObject)).fields;
        if arr.nd != ND as std::os::raw::c_int || arr.flags & FLAGS != FLAGS {
            return None;
        }
        let d = &(*arr.descr).fields;
        if d.type_num != NPY_TYPES::NPY_DOUBLE as std::os::raw::c_int
            || d.byteorder == b'>' as std::os::raw::c_char
        {
            return None;
        }
        let mut shape = [0usize; ND];
        for (k, n) in shape.iter_mut().enumerate() {
            *n = usize::try_from(*arr.dimensions.add(k)).ok()?;
        }
        let len = shape.iter().try_fold(1usize, |a, &n| a.checked_mul(n))?;
        Some((
            std::slice::from_raw_parts(arr.data as *const f64, len),
            shape,
        ))
    }
}

/// Fast path for the per-call dynamics functions: a contiguous float64 1-D array is copied
/// straight into `out`; anything else goes through `vector`.
pub fn vector_into(obj: &Obj, arg: &str, out: &mut [f64]) -> PyResult<()> {
    if obj.copy_plain(out) {
        return Ok(());
    }
    let v = vector(obj, arg, Some(out.len()))?;
    out.copy_from_slice(&v);
    Ok(())
}

pub fn vec3(obj: &Obj, arg: &str) -> PyResult<Vec3> {
    let mut v = [0.0; 3];
    vector_into(obj, arg, &mut v)?;
    Ok(Vec3::from(v))
}

pub fn to_array1<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A row-major array of the given shape from C-ordered data.
pub fn to_array<'py>(py: Python<'py>, data: Vec<f64>, shape: &[usize]) -> PyResult<Obj<'py>> {
    let flat = PyArray1::from_vec(py, data);
    Ok(flat.reshape(shape.to_vec())?.into_any())
}

/// A core array of any rank as a NumPy array of its shape.
impl super::record::Field for crate::support::array::Array {
    fn field<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        to_array(py, self.data.clone(), &self.shape)
    }
}

pub use matrix_to_array as dmatrix_to_array;
pub use matrix_to_array as mat3_to_array;

/// Any nalgebra matrix (a `Mat3`, a `DMatrix`) as a 2-D array.
pub fn matrix_to_array<'py, R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
    py: Python<'py>,
    m: &Matrix<f64, R, C, S>,
) -> PyResult<Obj<'py>> {
    // nalgebra is column-major; NumPy wants C order.
    let (rows, cols) = m.shape();
    let c_order = (0..rows).flat_map(|i| (0..cols).map(move |j| m[(i, j)]));
    to_array(py, c_order.collect(), &[rows, cols])
}

/// [`plain_f64_rows`] or a one-dimensional such array (one row, not stacked): `(data,
/// [rows, cols], stacked)`.
pub fn plain_f64_block<'a>(obj: &'a Obj) -> Option<(&'a [f64], [usize; 2], bool)> {
    match plain_f64_nd::<1>(obj) {
        Some((s, _)) => Some((s, [1, s.len()], false)),
        None => plain_f64_rows(obj).map(|(s, shape)| (s, shape, true)),
    }
}
