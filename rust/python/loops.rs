//! The closed-loop arguments of `Model` (bodies, held coordinates, actuated joints), parsed
//! in the core (`crate::model::args`) under the names the bindings call them by.
pub use crate::model::args::{body as body_ref, fixed_mask};
