//! URDF import: a robot as a [`Model`] whose joint order, body names and coordinates equal
//! Pinocchio's `buildModelFromUrdf(path)` (fixed base) or, with [`RootJoint::Free`],
//! `buildModelFromUrdf(path, JointModelFreeFlyer())` (floating base).
//!
//! * Tree and order. The root link (the one link that is no joint's child) is welded to the
//!   world with a `Fixed` joint, or moves on a `FreeFlyer` joint named `root_joint` (first in
//!   q and v: position, quaternion; linear and angular velocity in the root link's frame). The links are then added depth first, and the children of a
//!   link in the byte order of their joints' names: urdfdom, Pinocchio's parser, keeps joints
//!   in a `std::map` by name, so that is Pinocchio's order (checked against `model.names` and
//!   the order of its BODY frames). Bodies are named after the links, every link (fixed ones
//!   included) is a body, and the moving joints are the links' joints in q/v order.
//! * Joints. `revolute` and `continuous` → [`Joint::Revolute`] (q is the angle: Pinocchio's
//!   continuous joint stores (cos q, sin q) instead), `prismatic` → [`Joint::Prismatic`],
//!   `fixed` → [`Joint::Fixed`] (welded into the parent's link). `<origin xyz rpy>` places the
//!   joint frame in the parent link's frame, `R = Rz(y) Ry(p) Rx(r)`; `<axis xyz>` (default
//!   x) is normalised. `floating` and `planar` joints are refused with an error naming the
//!   joint. `<limit>`, `<dynamics damping friction>` and `<mimic>` are kept in [`UrdfJoint`];
//!   each `<mimic>` becomes a coupling `q = multiplier · q_joint + offset` (named after the
//!   mimicking joint; `crate::loops::coupling`), as Pinocchio's `mimic=True` models them.
//! * Inertia. `<inertial>`: `com = origin.xyz`, `I_link = R I Rᵀ` with `R` from
//!   `origin.rpy`; each link's inertial is validated like any [`RigidBody`] (a negative or
//!   non-physical tensor is an error naming the link).
//! * Massless links. URDF allows links without `<inertial>` (or with mass 0). Such a link on a
//!   fixed joint adds nothing. A moving link whose merged body (with its fixed descendants)
//!   has no mass gets an exactly zero body when some link below it has mass (the intermediate
//!   bodies of a multi-axis joint: Pinocchio does the same), and is an error otherwise:
//!   Pinocchio loads such a model, but its mass matrix has a zero row and `aba` returns NaN.
//!   Mass 0 with a non-zero rotational inertia is accepted on a fixed joint (it is added to
//!   the parent link's inertia, as Pinocchio does) and refused on a moving link that has no
//!   mass of its own, which seven point masses cannot represent.
//! * Ignored. Geometry (`<visual>`, `<collision>`, `<material>`) silently; any other element
//!   the dynamics does not use (`<gazebo>`, `<transmission>`, `<calibration>`,
//!   `<safety_controller>`, …) with one summary warning.
//!
//! The loader reads the XML into plain data ([`parse`]), connects the links ([`tree`]) and
//! builds the model through `Model`'s own methods ([`build`]).
use std::path::{Path, PathBuf};

use crate::joint::{rot_x, rot_y, rot_z};
use crate::model::Model;
use crate::support::error::{FileKind, Result};
use crate::support::spatial::{Mat3, Vec3};

mod build;
mod parse;
mod parts;
mod repair;
mod srdf;
mod tree;
mod visuals;

pub use crate::model::joint_records::{Limit, Mimic, RepairRecord, UrdfJoint};
pub use parts::{model_from_parts, parts_arg, Part};
pub use repair::Repair;
pub use srdf::{load_reference_poses, reference_poses, reference_poses_warned, ReferencePose};

use parse::Ctx;
use tree::Tree;

/// How the URDF's root link is attached to the world.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RootJoint {
    /// Welded (a fixed-base robot).
    #[default]
    Fixed,
    /// A free flyer named `root_joint` (a floating-base robot).
    Free,
}

/// The name Pinocchio gives the root joint it adds.
pub const ROOT_JOINT_NAME: &str = "root_joint";

/// A loaded URDF: the model, every joint (fixed ones included) and the warnings.
#[derive(Debug, Clone)]
pub struct Urdf {
    /// `<robot name>`.
    pub name: String,
    /// The model; its [`Model::records`] hold every joint (fixed ones included) and the
    /// repairs.
    pub model: Model,
    /// Things loaded differently from what the file says (ignored elements, missing limits).
    pub warnings: Vec<String>,
    /// Directory the file's relative resources (mesh files) are resolved against.
    pub base_dir: Option<PathBuf>,
}

impl Urdf {
    /// Every joint (fixed ones included), in the model's order.
    pub fn joints(&self) -> &[UrdfJoint] {
        &self.model.records.joints
    }
    /// What a `repair` changed, one record per link or welded joint (empty without repair).
    pub fn repairs(&self) -> &[RepairRecord] {
        &self.model.records.repairs
    }
    /// The moving joints, in q/v order.
    pub fn moving_joints(&self) -> impl Iterator<Item = &UrdfJoint> {
        self.joints().iter().filter(|j| j.is_moving())
    }
    pub fn joint(&self, name: &str) -> Option<&UrdfJoint> {
        self.joints().iter().find(|j| j.name == name)
    }

    /// Drops the couplings the `<mimic>` elements made: the mimic joints move independently
    /// (Pinocchio's `buildModelFromUrdf` without `mimic=True`), which one warning says.
    pub fn independent_mimics(&mut self, file: &str) {
        let names: Vec<String> = self
            .model
            .couplings
            .iter()
            .map(|c| format!("'{}'", c.name))
            .collect();
        if names.is_empty() {
            return;
        }
        self.model.couplings.clear();
        self.warnings.push(format!(
            "{file}: mimic=False: {} mimic joint(s) loaded as independent joints: {}",
            names.len(),
            names.join(", ")
        ));
    }
}

/// Reads and loads a URDF file; errors name `path` as given.
/// Only a regular file of at most [`crate::support::files::MAX_FILE_BYTES`] is read (a FIFO or a
/// device is refused before it is opened); a path too long to show is shortened in messages.
pub fn load_urdf(path: &Path, root: RootJoint) -> Result<Urdf> {
    load_urdf_with(path, root, None, &[])
}

/// [`load_urdf`] with the given repairs (`None`: none; invalid inertials are errors) and
/// the directories `package://` mesh URIs are looked for in besides the file's ancestors.
pub fn load_urdf_with(
    path: &Path,
    root: RootJoint,
    repair: Option<&Repair>,
    package_dirs: &[PathBuf],
) -> Result<Urdf> {
    let text = crate::support::files::read_text(path, FileKind::Urdf)?;
    model_from_urdf_with(
        &text,
        &crate::support::files::display_path(path),
        path.parent(),
        root,
        repair,
        package_dirs,
    )
}

/// A URDF file as `Model.from_urdf` loads it ([`load_urdf_with`]; `mimic` false: the mimic
/// joints independent): the model, and its warnings as `(category, message)`, the file's
/// (`UrdfWarning`) then what `repair` changed (`UrdfRepairWarning`).
pub fn load_model(
    path: &Path,
    (root, repair): (RootJoint, Option<&Repair>),
    package_dirs: &[PathBuf],
    mimic: bool,
) -> Result<(Model, Vec<(&'static str, String)>)> {
    let mut urdf = load_urdf_with(path, root, repair, package_dirs)?;
    let file = crate::support::files::display_path(path);
    if !mimic {
        urdf.independent_mimics(&file);
    }
    let mut warnings: Vec<_> = urdf
        .warnings
        .drain(..)
        .map(|w| ("UrdfWarning", w))
        .collect();
    warnings.extend(
        urdf.repairs_warning(&file)
            .map(|m| ("UrdfRepairWarning", m)),
    );
    Ok((urdf.model, warnings))
}

/// URDF roll-pitch-yaw: `Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy_matrix(rpy: &Vec3) -> Mat3 {
    rot_z(rpy.z) * rot_y(rpy.y) * rot_x(rpy.x)
}

/// Parses URDF text. `file` names it in errors and warnings; `base_dir` is the directory its
/// relative resources would resolve against (kept in [`Urdf::base_dir`]). Errors are
/// [`crate::support::error::Error::File`] of kind [`FileKind::Urdf`], naming the element and, where
/// known, the line.
pub fn model_from_urdf(
    text: &str,
    file: &str,
    base_dir: Option<&Path>,
    root: RootJoint,
) -> Result<Urdf> {
    model_from_urdf_with(text, file, base_dir, root, None, &[])
}

/// [`model_from_urdf`] with the given repairs and `package_dirs` (see [`load_urdf_with`]).
pub fn model_from_urdf_with(
    text: &str,
    file: &str,
    base_dir: Option<&Path>,
    root: RootJoint,
    repair: Option<&Repair>,
    package_dirs: &[PathBuf],
) -> Result<Urdf> {
    let ctx = Ctx::new(file, text);
    let mut robot = parse::parse_robot(&ctx, text)?;
    let mut repairs = repair::inertials(&mut robot, repair);
    let tree = Tree::new(&ctx, &robot.links, &robot.joints)?;
    if repair.is_some_and(|r| r.weld_massless) {
        repairs.extend(repair::weld_massless(&mut robot, &tree));
    }
    let mut built = build::build_model(&ctx, &robot, &tree, root)?;
    let joints = build::joint_records(&robot, &tree, &built);
    let mimics = build::add_mimics(&ctx, &mut built.model, &joints)?;
    let meshes = visuals::attach(&robot, &mut built.model, file, base_dir, package_dirs);
    let warnings = std::mem::take(&mut robot.notes)
        .into_iter()
        .chain(built.warning)
        .chain(meshes)
        .chain(build::joint_warnings(file, &joints, &robot.ignored))
        .chain(mimics)
        .collect();
    built.model.records = crate::model::joint_records::JointRecords::new(joints, repairs);
    Ok(Urdf {
        name: robot.name,
        model: built.model,
        warnings,
        base_dir: base_dir.map(Path::to_path_buf),
    })
}

#[cfg(test)]
mod tests;
