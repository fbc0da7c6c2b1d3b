//! Frames, frame and point Jacobians, centre of mass, centroidal momentum and inverse
//! kinematics (docs/kinematics.md). A *frame* is a placement fixed on a body: every body is
//! one (a URDF link welded by a fixed joint keeps its own body record, so its placement in
//! its parent's link is kept too), and [`Model::add_frame`] adds others (tool points, MJCF
//! sites). Every algorithm here reads the tree's world-frame kinematics
//! ([`crate::kinematics`]) and never changes the dynamics.
//!
//! Six-vectors are angular first, as everywhere in the crate (`[ω; v]`); the three
//! reference frames are Pinocchio's (`ReferenceFrame`).
use crate::model::frame::Frame;
use crate::model::{checked_rotation, Model};
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::Placement;

pub mod args;
pub mod batch;
mod box_qp;
pub mod calls;
pub mod centroidal;
pub mod com;
pub mod constrained;
pub mod evaluate;
pub mod ik;
pub mod jacobian;
pub mod jacobian_dot;
pub mod lanes;
pub mod motion;
mod null_step;
pub mod placement;
pub mod rows;
#[cfg(test)]
mod tests;

pub use motion::FrameKinematics;

/// A frame resolved to the moving link that carries it: its placement in the link frame, or
/// in the world when `link` is `None` (welded to the world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameRef {
    pub link: Option<usize>,
    pub placement: Placement,
}

/// In which frame a Jacobian, velocity or acceleration is expressed (Pinocchio's
/// `ReferenceFrame`; six-vectors angular part first):
/// * `World`: world axes, the linear part the velocity of the body point passing through
///   the world origin (Pinocchio's WORLD, a spatial velocity);
/// * `Local`: the frame's own axes, the linear part the velocity of the frame origin;
/// * `LocalWorldAligned`: world axes, the linear part the velocity of the frame origin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceFrame {
    World,
    Local,
    LocalWorldAligned,
}

impl ReferenceFrame {
    /// From its name: "world", "local", "local_world_aligned" (any case).
    pub fn parse(arg: &str, name: &str) -> Result<ReferenceFrame> {
        // Compared in place: a call per Jacobian allocates no lowercase copy.
        let is = |s: &str| name.eq_ignore_ascii_case(s);
        match () {
            _ if is("local") => Ok(ReferenceFrame::Local),
            _ if is("world") => Ok(ReferenceFrame::World),
            _ if is("local_world_aligned") || is("lwa") => Ok(ReferenceFrame::LocalWorldAligned),
            _ => Err(Error::arg(
                arg,
                "'world', 'local' or 'local_world_aligned'",
                format!("'{name}'"),
            )),
        }
    }
}

impl Model {
    /// Every frame's name: the bodies' (in body order), then the added frames'.
    pub fn frame_names(&self) -> Vec<String> {
        self.bodies
            .iter()
            .map(|b| b.name.clone())
            .chain(self.frames.iter().map(|f| f.name.clone()))
            .collect()
    }

    /// Adds a frame `placement` in body `body`'s frame; its name must be new among bodies
    /// and frames. Returns its index in [`Model::frames`].
    pub fn add_frame(&mut self, name: &str, body: usize, placement: Placement) -> Result<usize> {
        crate::support::error::check_name("frame", Some(name))?;
        if body >= self.bodies.len() {
            return Err(Error::model(
                "body",
                format!(
                    "no body with index {body}: the model has {} bodies",
                    self.bodies.len()
                ),
            ));
        }
        check_finite("translation", placement.translation.as_slice())?;
        let rotation = checked_rotation(&placement.rotation, "rotation")?;
        if self.body_index(name).is_some() || self.frames.iter().any(|f| f.name == name) {
            return Err(Error::model(
                "name",
                format!("a body or frame named '{name}' already exists"),
            ));
        }
        self.frames.push(Frame {
            name: name.to_string(),
            body,
            placement: Placement::new(rotation, placement.translation),
        });
        Ok(self.frames.len() - 1)
    }

    /// The frame named `name` (a body or an added frame) on its link, or an error on
    /// argument `arg` listing the frames (the first 30).
    pub fn frame_named(&self, arg: &str, name: &str) -> Result<FrameRef> {
        if let Some(b) = self.body_index(name) {
            return Ok(self.body_frame(b, &Placement::identity()));
        }
        if let Some(f) = self.frames.iter().find(|f| f.name == name) {
            return Ok(self.body_frame(f.body, &f.placement));
        }
        let names = self.frame_names();
        let mut shown: Vec<String> = names.iter().take(30).map(|n| format!("'{n}'")).collect();
        if names.len() > 30 {
            shown.push(format!(
                "… ({} frames; Model.frame_names lists them)",
                names.len()
            ));
        }
        Err(Error::model(
            arg,
            format!(
                "no frame named '{name}': expected one of {}",
                shown.join(", ")
            ),
        ))
    }

    /// A placement fixed on body `body` (in its frame), resolved to its link.
    pub fn body_frame(&self, body: usize, placement: &Placement) -> FrameRef {
        let b = &self.bodies[body];
        match b.link {
            Some(l) => FrameRef {
                link: Some(l),
                placement: b.in_link.compose(placement),
            },
            None => {
                let mut p = b.placement.compose(placement);
                let mut parent = b.parent;
                while let Some(k) = parent {
                    p = self.bodies[k].placement.compose(&p);
                    parent = self.bodies[k].parent;
                }
                FrameRef {
                    link: None,
                    placement: p,
                }
            }
        }
    }

    /// Checks the added frames point at bodies of this model (a deserialised model's may not).
    pub(crate) fn check_frames(&self) -> Result<()> {
        let mut seen = std::collections::HashSet::new();
        for f in &self.frames {
            if f.body >= self.bodies.len() || !seen.insert(f.name.as_str()) {
                return Err(Error::model(
                    format!("frame '{}'", f.name),
                    "its body is outside the model, or its name is repeated",
                ));
            }
        }
        Ok(())
    }

    /// The moving links from `link` up to the root (`link` first).
    pub fn support(&self, link: Option<usize>) -> impl Iterator<Item = usize> + '_ {
        std::iter::successors(link, move |&l| self.links[l].parent)
    }
}
