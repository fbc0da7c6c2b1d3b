//! Where the forces on a link's pins come from, for its members' strength
//! (`pointmass_dyn.design._strength`, docs/design.md §4a): each pin of [`super::pins`] with
//! the joint whose bearing force acts there and its sign, so that the force on the link at
//! the pin is a signed block of the design regressor's rows (`regressor::Layout`).
use crate::model::Model;
use crate::support::spatial::{Mat3, Vec3};

/// Which rows of the regressor give the force on the link at a pin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PinSource {
    /// Tree joint of link `link` (`Layout::bearing`, world axes): `sign` +1 on the link's
    /// own joint (the parent's force on it), −1 on a child's joint (reaction).
    Tree { link: usize, sign: f64 },
    /// Cut joint `k` (`Layout::cut`, frame a's axes: rotate by body a's rotation times
    /// `frame_a`): `sign` +1 on body b, −1 on body a.
    Cut {
        k: usize,
        sign: f64,
        body_a: Option<usize>,
        frame_a: Mat3,
    },
}

/// A pin on the link: its point and axis in the body frame (axis zero for a ball joint),
/// and where its force comes from. Same order as [`super::pins`].
#[derive(Debug, Clone, Copy)]
pub struct PinLoad {
    pub point: Vec3,
    pub axis: Vec3,
    pub source: PinSource,
}

/// Every pin on body `b` with the source of its force.
pub fn pin_loads(model: &Model, b: usize) -> Vec<PinLoad> {
    let mut out = Vec::new();
    let body = &model.bodies[b];
    if let (Some(axis), Some(link)) = (body.joint.pin(), body.link) {
        out.push(PinLoad {
            point: Vec3::zeros(),
            axis,
            source: PinSource::Tree { link, sign: 1.0 },
        });
    }
    for child in model.bodies.iter().filter(|c| c.parent == Some(b)) {
        if let (Some(axis), Some(link)) = (child.joint.pin(), child.link) {
            out.push(PinLoad {
                point: child.placement.translation,
                axis: child.placement.rotation * axis,
                source: PinSource::Tree { link, sign: -1.0 },
            });
        }
    }
    for (k, lp) in model.loops.iter().enumerate() {
        let Some(axis) = lp.joint.pin() else {
            continue;
        };
        let source = |sign| PinSource::Cut {
            k,
            sign,
            body_a: lp.body_a,
            frame_a: lp.frame_a.rotation,
        };
        if lp.body_a == Some(b) {
            out.push(PinLoad {
                point: lp.frame_a.translation,
                axis: lp.frame_a.rotation * axis,
                source: source(-1.0),
            });
        }
        if lp.body_b == Some(b) {
            out.push(PinLoad {
                point: lp.frame_b.translation,
                // As `pins`: frame b's rotation carries the axis when the loop is closed.
                axis: lp.frame_b.rotation * axis,
                source: source(1.0),
            });
        }
    }
    out
}
