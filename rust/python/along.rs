//! `scene_along`: a scene's accelerations and effect forces at the N states of a trajectory
//! (`crate::simulate::SceneAlong`), for the analyses along a result; `scene_shaking`: the
//! shaking force and moment there, from the same pass.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict};

use super::convert::to_array;
use super::scene::PyScene;
use super::signals::detach_interruptible;
use super::simulate::callbacks;
use crate::simulate::{Along, Asked, SceneAlong};

/// The request read, then run with the interpreter released (Ctrl-C heard); an exception
/// a Python torque function raised wins.
fn run(
    py: Python<'_>,
    scene: &PyScene,
    x: (&Obj, &Obj, &Obj),
    disable: Option<&Obj>,
    (asked, threads): (Asked, Option<usize>),
) -> PyResult<Along> {
    let call = SceneAlong::new(&scene.inner, x, disable, asked, threads)?;
    let run = || Ok(detach_interruptible(py, || call.run(&scene.inner)));
    callbacks(py, run)?
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
    let asked = Asked::new(accelerations, forces, None);
    let out = run(py, &scene, (t, q, v), disable, (asked, threads))?;
    let rows = [out.samples, scene.inner.model.nv];
    let forces = out.labels.into_iter().zip(out.forces);
    let forces: PyResult<Vec<_>> = forces
        .map(|(l, f)| Ok((l, to_array(py, f, &rows)?)))
        .collect();
    let a = accelerations.then(|| to_array(py, out.accelerations, &rows));
    Ok((a.transpose()?, forces?.into_py_dict(py)?))
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
    let asked = Asked::new(false, false, Some(crate::model::args::about(about)?));
    let out = run(py, &scene, (t, q, v), None, (asked, threads))?;
    let [force, moment] = out
        .shaking_parts()
        .map(|p| to_array(py, p, &[out.samples, 3]));
    Ok((force?, moment?))
}
