//! A frame on a body, as the model keeps it (moved here from `frames/` so the model does not
//! depend on the algorithms; those are `crate::frames`).
use crate::support::spatial::Placement;

/// A user frame: `placement` in body `body`'s frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Frame {
    pub name: String,
    pub body: usize,
    pub placement: Placement,
}
