//! The pins a body carries (its own joint, its children's, the cut joints on it): a link
//! must keep material around them, whatever the design.
use crate::joint::Joint;
use crate::model::Model;
use crate::support::spatial::{Placement, Vec3};

/// `(point, axis)` in the body's frame per revolute or spherical joint on body `b` (axis
/// zero for a ball joint); prismatic, fixed and free joints carry no pin.
pub fn pins(model: &Model, b: usize) -> Vec<(Vec3, Vec3)> {
    let pin = |joint: &Joint, frame: &Placement| {
        let axis = joint.pin()?;
        Some((frame.translation, frame.rotation * axis))
    };
    let mut out = Vec::new();
    out.extend(pin(&model.bodies[b].joint, &Placement::identity()));
    for child in model.bodies.iter().filter(|c| c.parent == Some(b)) {
        out.extend(pin(&child.joint, &child.placement));
    }
    for lp in &model.loops {
        if lp.body_a == Some(b) {
            out.extend(pin(&lp.joint, &lp.frame_a));
        }
        if lp.body_b == Some(b) {
            // The cut joint's axis is given in frame a; frame b's rotation carries it when
            // the loop is closed (the two frames coincide).
            out.extend(pin(&lp.joint, &lp.frame_b));
        }
    }
    out
}
