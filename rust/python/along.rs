//! `scene_along`: a scene's accelerations and effect forces at the N states of a trajectory
//! (`crate::simulate::along`), for the analyses along a result.
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{array, shape_str, to_array};
use super::effects::take_callback_error;
use super::errors::invalid;
use super::scene::PyScene;
use super::signals::detach_interruptible;

/// `(a, forces)` at the states `(t[k], q[k], v[k])`: `a` (N, nv) (None unless
/// `accelerations`); `forces` a dict from each enabled effect's name to its generalized force
/// (N, nv) (empty unless `forces`). On `threads` threads (None: one per core), the same
/// bits whatever their number.
#[pyfunction]
#[pyo3(signature = (scene, t, q, v, disable=None, accelerations=true, forces=false, threads=None))]
#[allow(clippy::too_many_arguments)] // the arguments of the Python function
pub fn scene_along<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    t: &Bound<'_, PyAny>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    disable: Option<&Bound<'_, PyAny>>,
    accelerations: bool,
    forces: bool,
    threads: Option<usize>,
) -> PyResult<(Option<Bound<'py, PyAny>>, Bound<'py, PyDict>)> {
    let s = &scene.inner;
    let (nq, nv) = (s.model.nq, s.model.nv);
    let (ts, t) = array(t, "t")?;
    let (qs, q) = array(q, "q")?;
    let (vs, v) = array(v, "v")?;
    let n = t.len();
    if ts.len() != 1 || qs != [n, nq] || vs != [n, nv] {
        return Err(invalid(
            py,
            "t, q, v",
            format!("shapes (N,), (N, {nq}), (N, {nv})"),
            format!("{}, {}, {}", shape_str(&ts), shape_str(&qs), shape_str(&vs)),
        ));
    }
    if let Some(k) = (0..n).find(|&k| {
        !t[k].is_finite()
            || q[k * nq..(k + 1) * nq]
                .iter()
                .chain(&v[k * nv..(k + 1) * nv])
                .any(|x| !x.is_finite())
    }) {
        return Err(invalid(
            py,
            "t, q, v",
            "finite values",
            format!("a non-finite value at sample {k}"),
        ));
    }
    let disabled = crate::simulate::disabled(crate::effects::args::disable(disable)?, &s.settings);
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let (model, effects) = (&*s.model, &s.effects[..]);
    take_callback_error();
    let out = detach_interruptible(py, || {
        let states = (&t[..], &q[..], &v[..]);
        crate::simulate::along(
            model,
            effects,
            disabled,
            states,
            accelerations,
            forces,
            threads,
        )
    });
    if let Some(e) = take_callback_error() {
        return Err(e);
    }
    let out = out?;
    let d = PyDict::new(py);
    for (label, f) in out.labels.into_iter().zip(out.forces) {
        d.set_item(label, to_array(py, f, &[n, nv])?)?;
    }
    let a = match accelerations {
        true => Some(to_array(py, out.accelerations, &[n, nv])?),
        false => None,
    };
    Ok((a, d))
}
