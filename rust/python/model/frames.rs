//! `Model`'s frames, frame Jacobians, centre of mass and centroidal methods
//! (`crate::frames`): arguments converted, the core called, results converted.
use crate::python::Obj;
use numpy::ndarray::IxDyn;
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyString;

use super::calls::calls;
use super::PyModel;
use crate::frames::rows::threads_for;
use crate::frames::{calls, evaluate, placement, FrameRef, ReferenceFrame};
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::python::convert::plain_f64_block;
use crate::python::errors::IntoPyResult;
use crate::python::signals::detach_interruptible;
use crate::support::error::Result;

/// A frame by name or index (`crate::frames::args::frame`); a Python string read in place
/// (no copy of the name per call).
pub fn frame_arg(model: &Model, obj: &Obj, arg: &str) -> PyResult<FrameRef> {
    match obj.cast::<PyString>() {
        Ok(name) => Ok(model.frame_named(arg, name.to_str()?)?),
        Err(_) => crate::frames::args::frame(model, obj, arg),
    }
}

pub use crate::model::args::configurations;

/// What [`PyModel::over_rows`] hands the core: the model, the pooled workspace's links, the
/// rows of `q`, their count and whether stacked.
type RowsOf<'a> = (&'a Model, &'a mut [LinkState], &'a [f64], usize, bool);

impl PyModel {
    /// `f` over `q` (nq,) or (N, nq) into new C-ordered arrays, one per entry of `shapes`
    /// (one row's, under a leading axis of rows when `q` is (N, nq)); `f` writes every
    /// entry (one row in the pooled workspace's links). `q` is read in place when it is a
    /// C-ordered float64 array whose block one thread computes in well under a millisecond
    /// (`frames::rows::threads_for` gives 1): the call then keeps the interpreter, so
    /// nothing can change `q` meanwhile and it need not be copied (the copy was ~2 % of a
    /// 1,000-row Jacobian). Otherwise it is copied, and run detached (Ctrl-C heard) unless
    /// it is one row.
    fn over_rows<'py, const N: usize>(
        &self,
        py: Python<'py>,
        q: &Obj,
        shapes: [&[usize]; N],
        f: impl FnOnce(RowsOf<'_>, [&mut [f64]; N]) -> Result<()> + Send,
    ) -> PyResult<[Bound<'py, PyArrayDyn<f64>>; N]> {
        self.with_workspace(|ws| {
            let (model, links): (&Model, &mut [LinkState]) =
                (&ws.version.model, &mut ws.data.links);
            let plain = plain_f64_block(q).filter(|(_, [rows, cols], _)| {
                *cols == model.nq && *rows > 0 && threads_for(model, *rows) == 1
            });
            let copied;
            let (qs, rows, stacked, inline) = match plain {
                Some((data, [rows, _], stacked)) => (data, rows, stacked, true),
                None => {
                    let (rows, data, stacked) = configurations(model, q, "q")?;
                    copied = data;
                    (copied.as_slice(), rows, stacked, rows == 1)
                }
            };
            let arrays = shapes.map(|tail| {
                // One row's shape under a leading axis of rows when stacked, on the stack
                // (a tail has at most 3 axes).
                let (mut shape, at) = ([rows; 4], usize::from(stacked));
                shape[at..at + tail.len()].copy_from_slice(tail);
                let shape = &shape[..at + tail.len()];
                // SAFETY: f64 has no invalid bit patterns, and `f` writes every entry before
                // Python sees the array (dropped unseen on an error).
                unsafe { PyArrayDyn::<f64>::new(py, IxDyn(shape), false) }
            });
            // SAFETY: new C-contiguous arrays no Python code has seen yet (as `as_slice_mut`).
            let outs = arrays
                .each_ref()
                .map(|a| unsafe { std::slice::from_raw_parts_mut(a.data(), a.len()) });
            let call = || f((model, links, qs, rows, stacked), outs);
            match inline {
                true => call().py(py)?,
                false => detach_interruptible(py, call)?,
            }
            // (Finiteness checked by the core, in its pass.)
            Ok(arrays)
        })
    }
}

#[pymethods]
impl PyModel {
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
        let f = frame_arg(&self.model(), frame, "frame")?;
        let shapes = [&[3, 3][..], &[3]];
        let [rot, org] = self.over_rows(py, q, shapes, |(m, _, qs, rows, stacked), [r, o]| {
            placement::frame_placement(m, &f, (qs, rows, stacked), r, o)
        })?;
        Ok((rot.into_any(), org.into_any()))
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
        let (f, nv) = (frame_arg(&self.model(), frame, "frame")?, self.model().nv);
        let [j] = self.over_rows(py, q, [&[6, nv]], |(m, links, qs, rows, stacked), [out]| {
            evaluate::frame_jacobians(m, links, &f, rf, qs, rows, stacked, out)
        })?;
        Ok(j.into_any())
    }

    #[pyo3(signature = (q, jacobian=false))]
    fn center_of_mass<'py>(&self, py: Python<'py>, q: &Obj, jacobian: bool) -> PyResult<Obj<'py>> {
        let nv = self.model().nv;
        if !jacobian {
            let [c] = self.over_rows(py, q, [&[3]], |(m, links, qs, rows, stacked), [c]| {
                evaluate::com_batch(m, links, qs, rows, stacked, c, None)
            })?;
            return Ok(c.into_any());
        }
        let shapes = [&[3][..], &[3, nv]];
        let [c, j] = self.over_rows(py, q, shapes, |(m, links, qs, rows, stacked), [c, j]| {
            evaluate::com_batch(m, links, qs, rows, stacked, c, Some(j))
        })?;
        Ok((c, j).into_pyobject(py)?.into_any())
    }
}

calls! {
    #[pyo3(signature = (frame, point, q, v=None))]
    fn point_path(frame: &Obj, point: &Obj, q: &Obj, v: Option<&Obj>)
        = calls::point_path => (pos, vel) detached;
    #[pyo3(signature = (frame, q, v, reference="local"))]
    fn frame_jacobian_dot(frame: &Obj, q: &Obj, v: &Obj, reference: &str)
        = calls::frame_jacobian_dot => (jd);
    #[pyo3(signature = (frame, q, v, a=None, reference="local"))]
    fn frame_motion(frame: &Obj, q: &Obj, v: &Obj, a: Option<&Obj>, reference: &str)
        = calls::frame_motion => (vel, acc);
    #[pyo3(signature = (q, v, a=None))]
    fn center_of_mass_motion(q: &Obj, v: &Obj, a: Option<&Obj>) = calls::com_motion => (c, vc, ac);
    #[pyo3(signature = (q, v=None, a=None))]
    fn centroidal(q: &Obj, v: Option<&Obj>, a: Option<&Obj>) = calls::centroidal => (named);
    #[pyo3(signature = (q, independent=None))]
    fn independent_map(q: &Obj, independent: Option<&Obj>) = calls::independent_map => (g, idx);
}
