//! `Scene.forward_dynamics_derivatives`, `Scene.inverse_dynamics_derivatives` and
//! `Scene.state_jacobian`: the scene-level derivatives (docs/derivatives.md).
use crate::python::Obj;
use pyo3::prelude::*;

use super::errors::check_result;
use super::record::{record, Field};
use crate::simulate::derivatives::SceneDerivatives;
use nalgebra::{DMatrix, DMatrixViewMut};

/// From this size on, [`three_arrays`] allocates the three matrices as one block.
const ONE_BLOCK_NV: usize = 64;

/// From this size on, `Model`'s derivatives are filled by rows (C order, no transposing
/// copy); below it the column fill and a transposing copy cost fewer instructions (chain7's
/// inverse derivatives: 28.9k per Python call against 34.9k by rows, callgrind).
pub(crate) const ROWS_NV: usize = 32;

/// Three new C-ordered n × n arrays and their entries. Unsafe: the caller writes every entry
/// before Python sees them, and drops the entries before the arrays. From [`ONE_BLOCK_NV`]
/// on, they are views of one (3, n, n) array: three separate blocks freed together at the
/// top of glibc's heap exceed its trim threshold, so every call gave the pages back and
/// faulted them in again (on a 300-link chain, more than the derivatives themselves); one
/// block of that size stays allocated for the next call (the dynamic mmap threshold).
unsafe fn three_arrays<'py, 'a>(
    py: Python<'py>,
    n: usize,
) -> PyResult<([Obj<'py>; 3], [&'a mut [f64]; 3])> {
    use numpy::{PyArray2, PyArray3, PyArrayMethods};
    let len = n * n;
    if n < ONE_BLOCK_NV {
        // New C-contiguous arrays of n × n entries that no other code holds yet.
        let arrays = std::array::from_fn(|_| PyArray2::<f64>::new(py, [n, n], false));
        let out = arrays
            .each_ref()
            .map(|a| std::slice::from_raw_parts_mut(a.data(), len));
        return Ok((arrays.map(Bound::into_any), out));
    }
    // As above, one block of 3 n² entries.
    let block = PyArray3::<f64>::new(py, [3, n, n], false);
    let all = std::slice::from_raw_parts_mut(block.data(), 3 * len);
    let (a, rest) = all.split_at_mut(len);
    let (b, c) = rest.split_at_mut(len);
    let views = [block.get_item(0)?, block.get_item(1)?, block.get_item(2)?];
    Ok((views, [a, b, c]))
}

/// NumPy copies of three nv × nv matrices whose column-major data is already their C order
/// (stored by rows, or symmetric): plain copies into [`three_arrays`].
/// `transpose`: the first two are stored by columns (below [`ROWS_NV`] only) and are
/// transposed into place.
pub(crate) fn c_ordered_triple<'py>(
    py: Python<'py>,
    m: [&DMatrix<f64>; 3],
    transpose: bool,
) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
    let n = m[0].nrows();
    // SAFETY: every entry copied below; `out` gone when the arrays are returned.
    let ([a, b, c], out) = unsafe { three_arrays(py, n)? };
    for (k, (x, dst)) in m.into_iter().zip(out).enumerate() {
        match transpose && k < 2 {
            true => DMatrixViewMut::from_slice(dst, n, n).tr_copy_from(x),
            false => dst.copy_from_slice(x.as_slice()),
        }
    }
    Ok((a, b, c))
}

/// `Model.inverse_dynamics_derivatives` at the workspace's loaded `(q, v, a)`: the three
/// arrays of [`three_arrays`] filled by the derivatives themselves (by rows: C order),
/// nothing copied; their entries read for finiteness only when the per-dof vectors do not
/// already rule out an overflow. `detach`: run without the GIL.
pub(crate) fn inverse_into_arrays<'py>(
    py: Python<'py>,
    ws: &mut crate::dynamics::shared::Workspace,
    g: &crate::support::spatial::Vec3,
    name: &str,
    detach: bool,
) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
    // SAFETY: the fill writes every entry; `out` gone when the arrays are returned.
    let ([a, b, c], mut out) = unsafe { three_arrays(py, ws.model().nv)? };
    let fill = out.each_mut().map(|x| &mut **x);
    let finite = match detach {
        true => py.detach(|| ws.inverse_derivatives_into(g, fill)),
        false => ws.inverse_derivatives_into(g, fill),
    };
    if !finite {
        for x in &out {
            check_result(py, name, x)?;
        }
    }
    Ok((a, b, c))
}

/// The scene's derivatives, one record per direction: `Type("Name") key of the third
/// matrix` (M⁻¹ or M) beside `dq`, `dv` and `numerical`.
macro_rules! scene_derivatives {
    ($($(#[$doc:meta])* $ty:ident($name:literal) $third:ident),*) => {$(
        record!($(#[$doc])* $ty($name, SceneDerivatives) {
            dq, dv, $third: |d: &SceneDerivatives, py| d.third.field(py), numerical,
        });
    )*};
}

scene_derivatives! {
    /// `Scene.forward_dynamics_derivatives`: `dq` ∂q̈/∂q, `dv` ∂q̈/∂v, `dtau` M⁻¹, and
    /// `numerical`, the effects differentiated by central differences.
    PyForwardDerivatives("SceneForwardDerivatives") dtau,
    /// `Scene.inverse_dynamics_derivatives`: `dq` ∂τ/∂q, `dv` ∂τ/∂v, `da` M, and
    /// `numerical`, the effects differentiated by central differences.
    PyInverseDerivatives("SceneInverseDerivatives") da
}
