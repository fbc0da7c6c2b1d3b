//! Arguments of the shaking-force and bearing-force methods of `Model`
//! (crate::dynamics::reactions), parsed in the core (`crate::model::args`).
use crate::python::Obj;
use pyo3::prelude::*;

use super::signals::detach_interruptible;
use crate::model::args::{self, Stack};
use crate::model::Model;

/// One state or a stack of them (`crate::model::args::states`), every row checked with the
/// interpreter released and Ctrl-C honoured.
pub fn states(model: &Model, q: &Obj, v: &Obj, a: &Obj) -> PyResult<Stack> {
    let py = q.py();
    let (count, q, v, a) = args::states(model, q, v, a)?;
    detach_interruptible(py, || args::check_rows(model, count, &q, &v, &a))?;
    Ok((count, q, v, a))
}
