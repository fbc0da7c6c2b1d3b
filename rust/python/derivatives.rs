//! `Scene.forward_dynamics_derivatives`, `Scene.inverse_dynamics_derivatives` and
//! `Scene.state_jacobian`: the scene-level derivatives (docs/derivatives.md).
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{to_array, vector};
use super::effects::take_callback_error;
use super::errors::{check_result, invalid, py_error, to_py, IntoPyResult};
use super::simulate::{scene_state, scene_system, time_arg};
use crate::io::scene::Scene;
use crate::simulate::derivatives::DerivativeWork;
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

fn c_order(m: &DMatrix<f64>) -> Vec<f64> {
    m.transpose().as_slice().to_vec()
}

fn refuse_loops(py: Python<'_>, s: &Scene, name: &str) -> PyResult<()> {
    if !s.model.has_constraints() {
        return Ok(());
    }
    Err(invalid(
        py,
        "scene",
        format!("a scene without closed loops or couplings for {name}"),
        format!(
            "a model with {} loop(s) and {} coupling(s)",
            s.model.loops.len(),
            s.model.couplings.len()
        ),
    ))
}

/// Runs `f` on the scene's system with a derivative workspace; a failure (an effect's error,
/// a singular configuration) raises `NumericalError` (`SingularityError` for the latter, as
/// `Model`'s derivatives), a callback's own exception as itself.
fn run<'py>(
    py: Python<'py>,
    s: &Scene,
    disable: Option<&Obj>,
    name: &str,
    keys: [&str; 3],
    f: impl FnOnce(
        &mut crate::simulate::Dynamics<'_>,
        &mut DerivativeWork,
    ) -> crate::support::error::Result<()>,
    pick: impl Fn(&DerivativeWork) -> [&DMatrix<f64>; 3],
) -> PyResult<Bound<'py, PyDict>> {
    let mut sys = scene_system(py, s, disable)?;
    let mut w = DerivativeWork::new(&sys);
    take_callback_error();
    let r = f(&mut sys, &mut w);
    if let Some(e) = take_callback_error() {
        return Err(e);
    }
    r.map_err(|e| to_py(py, e.in_arg(name)))?;
    let d = PyDict::new(py);
    let nv = s.model.nv;
    for (key, m) in keys.iter().zip(pick(&w)) {
        let data = c_order(m);
        check_result(py, &format!("{name}['{key}']"), &data)?;
        d.set_item(*key, to_array(py, data, &[nv, nv])?)?;
    }
    let labels = sys.effects.labels();
    let numerical: Vec<String> = labels
        .into_iter()
        .zip(&w.effects.numerical)
        .filter(|(_, n)| **n)
        .map(|(l, _)| l)
        .collect();
    d.set_item("numerical", numerical)?;
    Ok(d)
}

#[allow(clippy::too_many_arguments)]
pub(super) fn forward<'py>(
    py: Python<'py>,
    s: &Scene,
    q: &Obj,
    v: &Obj,
    tau: Option<&Obj>,
    t: f64,
    disable: Option<&Obj>,
) -> PyResult<Bound<'py, PyDict>> {
    let t = time_arg(py, t)?;
    let (q, v) = scene_state(py, s, q, v)?;
    let tau = match tau {
        Some(x) if !x.is_none() => {
            let x = vector(x, "tau", Some(s.model.nv))?;
            crate::support::error::check_finite("tau", &x).py(py)?;
            x
        }
        _ => vec![0.0; s.model.nv],
    };
    run(
        py,
        s,
        disable,
        "forward_dynamics_derivatives",
        ["dq", "dv", "dtau"],
        |sys, w| sys.derivatives(t, &q, &v, &tau, w),
        |w| [&w.dd.ddq_dq, &w.dd.ddq_dv, &w.dd.minv],
    )
}

pub(super) fn inverse<'py>(
    py: Python<'py>,
    s: &Scene,
    q: &Obj,
    v: &Obj,
    a: &Obj,
    t: f64,
    disable: Option<&Obj>,
) -> PyResult<Bound<'py, PyDict>> {
    let t = time_arg(py, t)?;
    let (q, v) = scene_state(py, s, q, v)?;
    // A mechanism's driving forces depend on which joints are actuated (driving_forces).
    refuse_loops(py, s, "inverse_dynamics_derivatives")?;
    let a = vector(a, "a", Some(s.model.nv))?;
    crate::support::error::check_finite("a", &a).py(py)?;
    run(
        py,
        s,
        disable,
        "inverse_dynamics_derivatives",
        ["dq", "dv", "da"],
        |sys, w| sys.inverse_derivatives(t, &q, &v, &a, w),
        |w| [&w.dd.dtau_dq, &w.dd.dtau_dv, &w.dd.mass],
    )
}

pub(super) fn state_jacobian<'py>(
    py: Python<'py>,
    s: &Scene,
    y: &Obj,
    t: f64,
    disable: Option<&Obj>,
) -> PyResult<Option<Obj<'py>>> {
    use crate::integrator::OdeSystem;
    let t = time_arg(py, t)?;
    let (nq, nv) = (s.model.nq, s.model.nv);
    let y = vector(y, "y", Some(nq + nv))?;
    s.model.check_state(&y[..nq], Some(&y[nq..])).py(py)?;
    let mut sys = scene_system(py, s, disable)?;
    let dim = nq + nv;
    let mut jac = vec![0.0; dim * dim];
    take_callback_error();
    let r = sys.jacobian(t, &y, &mut jac);
    if let Some(e) = take_callback_error() {
        return Err(e);
    }
    let filled = r.map_err(|m| py_error(py, "NumericalError", format!("state_jacobian: {m}")))?;
    if !filled {
        return Ok(None);
    }
    check_result(py, "state_jacobian", &jac)?;
    Ok(Some(to_array(py, jac, &[dim, dim])?))
}
