//! `Scene.forward_dynamics_derivatives`, `Scene.inverse_dynamics_derivatives` and
//! `Scene.state_jacobian`: the scene-level derivatives (docs/derivatives.md).
use crate::python::Obj;
use pyo3::prelude::*;

use super::errors::check_result;
use super::record::{record, Field};
use crate::simulate::derivatives::SceneDerivatives;
use nalgebra::DMatrix;

/// From this size on, [`c_ordered_triple`] allocates the three matrices as one block.
const ONE_BLOCK_NV: usize = 64;

/// From this size on, `Model`'s derivatives are filled by rows (C order, no transposing
/// copy); below it the column fill and a transposing copy cost fewer instructions (chain7's
/// inverse derivatives: 28.9k per Python call against 34.9k by rows, callgrind).
pub(crate) const ROWS_NV: usize = 32;

/// NumPy copies of three nv × nv matrices whose column-major data is already their C order
/// (stored by rows, or symmetric): plain copies. From [`ONE_BLOCK_NV`] on, they are views of
/// one (3, nv, nv) array: three separate blocks freed together at the top of glibc's heap
/// exceed its trim threshold, so every call gave the pages back and faulted them in again
/// (on a 300-link chain, more than the derivatives themselves); one block of that size stays
/// allocated for the next call (the dynamic mmap threshold).
/// `transpose`: the first two are stored by columns (below [`ROWS_NV`] only) and are
/// transposed into place.
pub(crate) fn c_ordered_triple<'py>(
    py: Python<'py>,
    m: [&DMatrix<f64>; 3],
    transpose: bool,
) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
    use numpy::{PyArray2, PyArray3, PyArrayMethods};
    let n = m[0].nrows();
    let len = n * n;
    if n < ONE_BLOCK_NV {
        // SAFETY: new C-contiguous arrays of exactly n × n elements, all written.
        let one = |x: &DMatrix<f64>, t: bool| unsafe {
            let arr = PyArray2::<f64>::new(py, [n, n], false);
            if t {
                let (src, dst) = (x.as_slice(), arr.data());
                for i in 0..n {
                    for j in 0..n {
                        *dst.add(i * n + j) = src[j * n + i];
                    }
                }
            } else {
                std::ptr::copy_nonoverlapping(x.as_ptr(), arr.data(), len);
            }
            arr.into_any()
        };
        return Ok((one(m[0], transpose), one(m[1], transpose), one(m[2], false)));
    }
    // SAFETY: a new C-contiguous array of exactly 3 n² elements, all written.
    let block = unsafe {
        let arr = PyArray3::<f64>::new(py, [3, n, n], false);
        for (k, x) in m.iter().enumerate() {
            std::ptr::copy_nonoverlapping(x.as_ptr(), arr.data().add(k * len), len);
        }
        arr
    };
    Ok((block.get_item(0)?, block.get_item(1)?, block.get_item(2)?))
}

/// `Model.inverse_dynamics_derivatives` at the workspace's loaded `(q, v, a)`: the three
/// arrays allocated as [`c_ordered_triple`] does, then filled by the derivatives themselves
/// (by rows: C order), nothing copied; their entries read for finiteness only when the
/// per-dof vectors do not already rule out an overflow. `detach`: run without the GIL.
pub(crate) fn inverse_into_arrays<'py>(
    py: Python<'py>,
    ws: &mut crate::dynamics::shared::Workspace,
    g: &crate::support::spatial::Vec3,
    name: &str,
    detach: bool,
) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
    use numpy::{PyArray2, PyArray3, PyArrayMethods};
    let n = ws.model().nv;
    let len = n * n;
    let run = |ws: &mut crate::dynamics::shared::Workspace, out: [&mut [f64]; 3]| {
        if detach {
            py.detach(|| ws.inverse_derivatives_into(g, out))
        } else {
            ws.inverse_derivatives_into(g, out)
        }
    };
    if n < ONE_BLOCK_NV {
        let arrays: [Bound<'py, PyArray2<f64>>; 3] =
            std::array::from_fn(|_| unsafe { PyArray2::<f64>::new(py, [n, n], false) });
        // SAFETY: new C-contiguous arrays no other code holds yet, every entry written by
        // the fill before they are handed to Python.
        let out = arrays
            .each_ref()
            .map(|a| unsafe { std::slice::from_raw_parts_mut(a.data(), len) });
        if !run(ws, out) {
            for a in &arrays {
                check_result(py, name, unsafe { a.as_slice()? })?;
            }
        }
        let [a, b, c] = arrays;
        return Ok((a.into_any(), b.into_any(), c.into_any()));
    }
    // SAFETY: as above, one block of 3 n² entries.
    let block = unsafe { PyArray3::<f64>::new(py, [3, n, n], false) };
    let all = unsafe { std::slice::from_raw_parts_mut(block.data(), 3 * len) };
    let (a, rest) = all.split_at_mut(len);
    let (b, c) = rest.split_at_mut(len);
    if !run(ws, [a, b, c]) {
        check_result(py, name, unsafe { block.as_slice()? })?;
    }
    Ok((block.get_item(0)?, block.get_item(1)?, block.get_item(2)?))
}

/// A scene's derivatives, the matrices in C order.
type Derivs = SceneDerivatives;

record!(
    /// `Scene.forward_dynamics_derivatives`: `dq` ∂q̈/∂q, `dv` ∂q̈/∂v, `dtau` M⁻¹, and
    /// `numerical`, the effects differentiated by central differences.
    PyForwardDerivatives("SceneForwardDerivatives", Derivs) {
        dq: |d: &Derivs, py| d.dq.field(py),
        dv: |d: &Derivs, py| d.dv.field(py),
        dtau: |d: &Derivs, py| d.third.field(py),
        numerical,
    }
);

record!(
    /// `Scene.inverse_dynamics_derivatives`: `dq` ∂τ/∂q, `dv` ∂τ/∂v, `da` M, and
    /// `numerical`, the effects differentiated by central differences.
    PyInverseDerivatives("SceneInverseDerivatives", Derivs) {
        dq: |d: &Derivs, py| d.dq.field(py),
        dv: |d: &Derivs, py| d.dv.field(py),
        da: |d: &Derivs, py| d.third.field(py),
        numerical,
    }
);
