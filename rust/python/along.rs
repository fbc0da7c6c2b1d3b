//! `scene_along`: a scene's accelerations and effect forces at the N states of a trajectory
//! (`crate::simulate::along`), for the analyses along a result; `scene_shaking`: the shaking
//! force and moment there, from the same pass.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::to_array;
use super::effects::take_callback_error;
use super::scene::PyScene;
use super::signals::detach_interruptible;
use crate::simulate::{Along, Asked};

/// `(t, q, v)` as flat arrays, checked (`crate::model::args::samples`).
type States = [Vec<f64>; 3];

/// `crate::simulate::along` of the scene, the interpreter released (Ctrl-C heard).
fn run(
    py: Python<'_>,
    scene: &PyScene,
    [t, q, v]: &States,
    disable: Option<&Obj>,
    asked: Asked,
    threads: Option<usize>,
) -> PyResult<Along> {
    let s = &scene.inner;
    let disabled = crate::simulate::disabled(crate::effects::args::disable(disable)?, &s.settings);
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let (model, effects) = (&*s.model, &s.effects[..]);
    take_callback_error();
    let out = detach_interruptible(py, || {
        let states = (&t[..], &q[..], &v[..]);
        crate::simulate::along(model, effects, disabled, states, asked, threads)
    });
    if let Some(e) = take_callback_error() {
        return Err(e);
    }
    out
}

#[pyfunction]
#[pyo3(signature = (scene, t, q, v, disable=None, accelerations=true, forces=false, threads=None))]
pub fn scene_along<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    t: &Obj,
    q: &Obj,
    v: &Obj,
    disable: Option<&Obj>,
    accelerations: bool,
    forces: bool,
    threads: Option<usize>,
) -> PyResult<(Option<Obj<'py>>, Bound<'py, PyDict>)> {
    let nv = scene.inner.model.nv;
    let x = crate::model::args::samples(&scene.inner.model, t, q, v)?;
    let n = x[0].len();
    let asked = Asked {
        accelerations,
        forces,
        shaking: None,
    };
    let out = run(py, &scene, &x, disable, asked, threads)?;
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

#[pyfunction]
#[pyo3(signature = (scene, t, q, v, about=None, threads=None))]
pub fn scene_shaking<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    t: &Obj,
    q: &Obj,
    v: &Obj,
    about: Option<&Obj>,
    threads: Option<usize>,
) -> PyResult<(Obj<'py>, Obj<'py>)> {
    let x = crate::model::args::samples(&scene.inner.model, t, q, v)?;
    let n = x[0].len();
    let about = crate::model::args::about(about)?;
    let asked = Asked {
        accelerations: false,
        forces: false,
        shaking: Some(about),
    };
    let out = run(py, &scene, &x, None, asked, threads)?;
    let (mut force, mut moment) = (Vec::with_capacity(3 * n), Vec::with_capacity(3 * n));
    for row in out.shaking.chunks_exact(6) {
        force.extend_from_slice(&row[..3]);
        moment.extend_from_slice(&row[3..]);
    }
    Ok((
        to_array(py, force, &[n, 3])?,
        to_array(py, moment, &[n, 3])?,
    ))
}
