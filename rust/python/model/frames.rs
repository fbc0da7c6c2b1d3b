//! `Model`'s frames, frame Jacobians, centre of mass and centroidal methods
//! (`crate::frames`): arguments converted, the core called, results converted.
use crate::python::Obj;
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use super::{load_state, PyModel};
use crate::frames::args::speeds;
use crate::frames::{constrained, evaluate, jacobian, placement, FrameRef, ReferenceFrame};
use crate::model::Model;
use crate::python::convert::{plain_f64_rows, to_array, to_array1, vec3};
use crate::python::errors::{check_result, IntoPyResult};
use crate::python::signals::detach_interruptible;

/// A frame by name or index (`crate::frames::args::frame`); a Python string read in place
/// (no copy of the name per call).
pub fn frame_arg(model: &Model, obj: &Obj, arg: &str) -> PyResult<FrameRef> {
    match obj.cast::<PyString>() {
        Ok(name) => Ok(model.frame_named(arg, name.to_str()?)?),
        Err(_) => crate::frames::args::frame(model, obj, arg),
    }
}

pub use crate::model::args::configurations;

/// `q` (nq,) or (N, nq) for a call over rows, as (rows, stacked, whether to run it here).
/// Read in place when it is a C-ordered float64 (N, nq) array whose block one thread
/// computes in well under a millisecond (`frames::rows::threads_for` gives 1): then the
/// call keeps the interpreter, so nothing can change `q` meanwhile and it need not be
/// copied (the copy was ~2 % of a 1,000-row Jacobian). Otherwise copied into `buf`, and
/// run detached (Ctrl-C heard) unless it is one row.
fn rows_of<'a>(
    model: &Model,
    q: &'a Obj,
    buf: &'a mut Vec<f64>,
) -> PyResult<(&'a [f64], usize, bool, bool)> {
    if let Some((data, [rows, cols])) = plain_f64_rows(q) {
        if cols == model.nq && rows > 0 && crate::frames::rows::threads_for(model, rows) == 1 {
            return Ok((data, rows, true, true));
        }
    }
    let (rows, data, stacked) = configurations(model, q, "q")?;
    *buf = data;
    Ok((buf.as_slice(), rows, stacked, rows == 1))
}

/// `f` here (`inline`) or with the interpreter released, Ctrl-C heard.
fn run(
    py: Python<'_>,
    inline: bool,
    f: impl FnOnce() -> crate::support::error::Result<()> + Send,
) -> PyResult<()> {
    match inline {
        true => f().py(py),
        false => detach_interruptible(py, f),
    }
}

/// Whether `q` is a one-dimensional NumPy array: the one-configuration calls' path (its
/// values then read as any `q`); anything else goes through [`configurations`]. Cheaper
/// than a typed cast, which compares the dtype through NumPy's API.
fn one_dimensional(q: &Obj) -> bool {
    q.cast::<numpy::PyUntypedArray>()
        .is_ok_and(|a| numpy::PyUntypedArrayMethods::ndim(a) == 1)
}

pub fn lead(stacked: bool, rows: usize, tail: &[usize]) -> Vec<usize> {
    let mut s = if stacked { vec![rows] } else { vec![] };
    s.extend_from_slice(tail);
    s
}

/// An uninitialised C-ordered float64 array of `shape` (the caller writes every entry).
fn new_array<'py>(py: Python<'py>, shape: &[usize]) -> Bound<'py, numpy::PyArrayDyn<f64>> {
    // SAFETY: f64 has no invalid bit patterns; the callers fill the array before Python
    // sees it.
    unsafe { numpy::PyArrayDyn::<f64>::new(py, numpy::ndarray::IxDyn(shape), false) }
}

/// The entries of an optional array from [`new_array`], to be written.
///
/// # Safety
/// A new array no Python code has seen yet (C-contiguous); every entry is written before
/// it is returned (dropped unseen on an error).
#[allow(clippy::mut_from_ref)] // NumPy's memory, not `arr`'s: as `as_slice_mut` itself
unsafe fn entries<'a>(
    arr: &'a Option<Bound<'_, numpy::PyArrayDyn<f64>>>,
) -> PyResult<Option<&'a mut [f64]>> {
    Ok(match arr {
        Some(a) => Some(unsafe { a.as_slice_mut() }?),
        None => None,
    })
}

#[pymethods]
impl PyModel {
    #[getter]
    fn frame_names(&self) -> Vec<String> {
        self.model().frame_names()
    }

    #[pyo3(signature = (name, body, translation=None, rotation=None))]
    fn add_frame(
        &self,
        py: Python<'_>,
        name: String,
        body: &Obj,
        translation: Option<&Obj>,
        rotation: Option<&Obj>,
    ) -> PyResult<usize> {
        let b = crate::model::args::some_body(&self.model(), body, "body")?;
        let at = crate::support::args::placement(translation, rotation, "translation", "rotation")?;
        self.shared.update(|m| m.add_frame(&name, b, at)).py(py)
    }

    fn frame_placement<'py>(
        &self,
        py: Python<'py>,
        frame: &Obj,
        q: &Obj,
    ) -> PyResult<(Obj<'py>, Obj<'py>)> {
        let model = self.model();
        let f = frame_arg(&model, frame, "frame")?;
        let (rows, qs, stacked) = configurations(&model, q, "q")?;
        let (rot, org) = detach_interruptible(py, || {
            placement::frame_placement(&model, &f, &qs, rows, stacked)
        })?;
        check_result(py, "frame_placement", &org)?;
        Ok((
            to_array(py, rot, &lead(stacked, rows, &[3, 3]))?,
            to_array(py, org, &lead(stacked, rows, &[3]))?,
        ))
    }

    #[pyo3(signature = (frame, point, q, v=None))]
    fn point_path<'py>(
        &self,
        py: Python<'py>,
        frame: &Obj,
        point: &Obj,
        q: &Obj,
        v: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Option<Obj<'py>>)> {
        let model = self.model();
        let f = frame_arg(&model, frame, "frame")?;
        let p = vec3(point, "point")?;
        let (rows, qs, _) = configurations(&model, q, "q")?;
        let vs = crate::model::args::speeds(&model, v, rows)?;
        let (pos, vel) = detach_interruptible(py, || {
            placement::point_path_of(&model, &f, &p, &qs, vs.as_deref(), rows)
        })?;
        check_result(py, "point_path", &pos)?;
        let vel = vel.map(|vel| to_array(py, vel, &[rows, 3])).transpose()?;
        Ok((to_array(py, pos, &[rows, 3])?, vel))
    }

    #[pyo3(signature = (frame, q, reference="local"))]
    fn frame_jacobian<'py>(
        &self,
        py: Python<'py>,
        frame: &Obj,
        q: &Obj,
        reference: &str,
    ) -> PyResult<Obj<'py>> {
        let rf = ReferenceFrame::parse("reference", reference)?;
        if one_dimensional(q) {
            // One configuration: the pooled workspace's buffers, no thread hand-off.
            return self.with_workspace(|ws| {
                load_state(ws, py, q, None)?;
                let model = &ws.version.model;
                let f = frame_arg(model, frame, "frame")?;
                // The support's poses and joint columns only (no inertias).
                crate::kinematics::plan::frame_poses_for(model, &ws.q, &mut ws.data.links, f.link);
                let nv = model.nv;
                // Uninitialised: `frame_jacobian_links` writes every entry.
                let arr = new_array(py, &[6, nv]);
                // SAFETY: a new array no Python code has seen yet, C-contiguous, 6 × nv.
                let out = unsafe { arr.as_slice_mut() }?;
                jacobian::frame_jacobian_links(model, &ws.data.links, &f, rf, out);
                check_result(py, "frame_jacobian", out)?;
                Ok(arr.into_any())
            });
        }
        let model = self.model();
        let f = frame_arg(&model, frame, "frame")?;
        let mut buf = Vec::new();
        let (qs, rows, stacked, inline) = rows_of(&model, q, &mut buf)?;
        let arr = new_array(py, &lead(stacked, rows, &[6, model.nv]));
        // SAFETY: a new array no Python code has seen yet, C-contiguous; every entry is
        // written before it is returned (dropped unseen on an error).
        let out = unsafe { arr.as_slice_mut() }?;
        run(py, inline, || {
            evaluate::frame_jacobians(&model, &f, rf, qs, rows, stacked, out)
        })?;
        // (Finiteness checked by the core, in its pass.)
        Ok(arr.into_any())
    }

    #[pyo3(signature = (frame, q, v, reference="local"))]
    fn frame_jacobian_dot<'py>(
        &self,
        py: Python<'py>,
        frame: &Obj,
        q: &Obj,
        v: &Obj,
        reference: &str,
    ) -> PyResult<Obj<'py>> {
        let (model, q, v) = self.state(q, v)?;
        let f = frame_arg(&model, frame, "frame")?;
        let rf = ReferenceFrame::parse("reference", reference)?;
        let out = evaluate::frame_jacobian_dot(&model, &f, rf, &q, &v);
        check_result(py, "frame_jacobian_dot", &out)?;
        to_array(py, out, &[6, model.nv])
    }

    #[pyo3(signature = (frame, q, v, a=None, reference="local"))]
    fn frame_motion<'py>(
        &self,
        py: Python<'py>,
        frame: &Obj,
        q: &Obj,
        v: &Obj,
        a: Option<&Obj>,
        reference: &str,
    ) -> PyResult<(Obj<'py>, Obj<'py>)> {
        let (model, q, v) = self.state(q, v)?;
        let a = speeds(&model, a, "a")?;
        let f = frame_arg(&model, frame, "frame")?;
        let rf = ReferenceFrame::parse("reference", reference)?;
        let (vel, acc) = evaluate::frame_motion(&model, &f, rf, &q, &v, a.as_deref());
        check_result(py, "frame_motion", acc.as_slice())?;
        Ok((
            to_array1(py, vel.as_slice()).into_any(),
            to_array1(py, acc.as_slice()).into_any(),
        ))
    }

    #[pyo3(signature = (q, jacobian=false))]
    fn center_of_mass<'py>(&self, py: Python<'py>, q: &Obj, jacobian: bool) -> PyResult<Obj<'py>> {
        if one_dimensional(q) {
            // One configuration: the pooled workspace's buffers, no thread hand-off.
            return self.with_workspace(|ws| {
                load_state(ws, py, q, None)?;
                let model = &ws.version.model;
                // Uninitialised: `com_one` writes every entry of the Jacobian.
                let arr = jacobian.then(|| new_array(py, &[3, model.nv]));
                // SAFETY: `arr` is new and `com_one` writes every entry of the Jacobian.
                let j = unsafe { entries(&arr) }?;
                let c = evaluate::com_one(model, &ws.q, &mut ws.data.links, j)?;
                check_result(py, "center_of_mass", c.as_slice())?;
                let c = to_array1(py, c.as_slice()).into_any();
                match arr {
                    Some(j) => Ok((c, j).into_pyobject(py)?.into_any()),
                    None => Ok(c),
                }
            });
        }
        let model = self.model();
        let mut buf = Vec::new();
        let (qs, rows, stacked, inline) = rows_of(&model, q, &mut buf)?;
        let com = new_array(py, &lead(stacked, rows, &[3]));
        let jac = jacobian.then(|| new_array(py, &lead(stacked, rows, &[3, model.nv])));
        // SAFETY: new arrays no Python code has seen yet, C-contiguous; every entry is
        // written before they are returned (dropped unseen on an error).
        let c = unsafe { com.as_slice_mut() }?;
        let j = unsafe { entries(&jac) }?;
        run(py, inline, || {
            evaluate::com_batch(&model, qs, rows, stacked, c, j)
        })?;
        // (Finiteness checked by the core, in its pass.)
        match jac {
            Some(j) => Ok((com, j).into_pyobject(py)?.into_any()),
            None => Ok(com.into_any()),
        }
    }

    #[pyo3(signature = (q, v, a=None))]
    fn center_of_mass_motion<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        a: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
        let (model, q, v) = self.state(q, v)?;
        let a = speeds(&model, a, "a")?;
        let motion = evaluate::com_motion(&model, &q, &v, a.as_deref())?;
        check_result(py, "center_of_mass_motion", motion[2].as_slice())?;
        let [c, vc, ac] = motion.map(|x| to_array1(py, x.as_slice()).into_any());
        Ok((c, vc, ac))
    }

    #[pyo3(signature = (q, v=None, a=None))]
    fn centroidal<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: Option<&Obj>,
        a: Option<&Obj>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (model, q) = self.state_only(q)?;
        let v = speeds(&model, v, "v")?;
        let a = speeds(&model, a, "a")?;
        let (ag, rest) = evaluate::centroidal(&model, &q, v.as_deref(), a.as_deref())?;
        check_result(py, "centroidal", &ag)?;
        let d = PyDict::new(py);
        d.set_item("A", to_array(py, ag, &[6, model.nv])?)?;
        if let Some((h, hdot)) = rest {
            check_result(py, "centroidal", hdot.as_slice())?;
            d.set_item("momentum", to_array1(py, h.as_slice()))?;
            d.set_item("rate", to_array1(py, hdot.as_slice()))?;
        }
        Ok(d)
    }

    #[pyo3(signature = (q, independent=None))]
    fn independent_map<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        independent: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Vec<usize>)> {
        let (model, q) = self.state_only(q)?;
        let idx = independent.filter(|x| !x.is_none());
        let idx = idx.map(|x| crate::model::args::speeds_named(&model, x, "independent"));
        let (g, idx) = constrained::independent_map_for(&model, &q, idx.transpose()?)?;
        Ok((crate::python::convert::dmatrix_to_array(py, &g)?, idx))
    }
}
