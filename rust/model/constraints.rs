//! The constraints a model carries beside its tree: cut joints closing loops and joint
//! couplings, as data (moved here from `loops/` so the model does not depend on the
//! algorithms). What they do to the dynamics is `crate::loops`.
use crate::joint::Joint;
use crate::support::spatial::{Placement, Vec3};

/// A cut joint closing one loop: `joint` between `frame_a` on body `body_a` and `frame_b` on
/// body `body_b` (`None`: the world). The loop is closed when the two frames coincide up to
/// the joint's motion (rotation about / sliding along `frame_a`'s axis; any rotation for a
/// spherical joint; none for a fixed one).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LoopJoint {
    pub name: String,
    pub body_a: Option<usize>,
    pub body_b: Option<usize>,
    pub joint: Joint,
    /// Frame a in body a's frame (the world frame for `None`).
    pub frame_a: Placement,
    /// Frame b in body b's frame.
    pub frame_b: Placement,
}

/// Which relative motions a cut joint removes: `linear` position rows (3, or the 2 normal to
/// a prismatic axis) and orientation rows (3 for fixed and prismatic, the 2 that keep a
/// revolute axis aligned, none for a spherical joint).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CutKind {
    Spherical,
    Revolute,
    Prismatic,
    Fixed,
}

impl CutKind {
    pub fn of(joint: &Joint) -> Option<CutKind> {
        match joint {
            Joint::Spherical => Some(CutKind::Spherical),
            Joint::Revolute { .. } => Some(CutKind::Revolute),
            Joint::Prismatic { .. } => Some(CutKind::Prismatic),
            Joint::Fixed => Some(CutKind::Fixed),
            _ => None,
        }
    }

    /// Number of scalar constraints.
    pub const fn rows(self) -> usize {
        match self {
            CutKind::Spherical => 3,
            CutKind::Revolute | CutKind::Prismatic => 5,
            CutKind::Fixed => 6,
        }
    }
}

impl LoopJoint {
    pub fn kind(&self) -> CutKind {
        // `add_loop` and deserialisation admit only the four cut-joint types.
        CutKind::of(&self.joint).unwrap_or(CutKind::Fixed)
    }

    /// The joint axis in frame a (zero for spherical and fixed cut joints).
    pub fn axis(&self) -> Vec3 {
        self.joint.axis().unwrap_or_else(Vec3::zeros)
    }
}

/// One coupling between the joints of two bodies (each body's own joint, revolute or
/// prismatic).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Coupling {
    pub name: String,
    /// The driven joint's body.
    pub joint: usize,
    /// The driving joint's body.
    pub reference: usize,
    pub ratio: f64,
    pub offset: f64,
}
