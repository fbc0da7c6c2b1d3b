//! URDF import: a fixed-base robot as a [`Model`] whose joint order, body names and
//! coordinates equal Pinocchio's `buildModelFromUrdf(path)` (no root joint).
//!
//! * Tree and order. The root link (the one link that is no joint's child) is welded to the
//!   world with a `Fixed` joint. The links are then added depth first, and the children of a
//!   link in the byte order of their joints' names: urdfdom, Pinocchio's parser, keeps joints
//!   in a `std::map` by name, so that is Pinocchio's order (checked against `model.names` and
//!   the order of its BODY frames). Bodies are named after the links, every link (fixed ones
//!   included) is a body, and the moving joints are the links' joints in q/v order.
//! * Joints. `revolute` and `continuous` → [`Joint::Revolute`] (q is the angle: Pinocchio's
//!   continuous joint stores (cos q, sin q) instead), `prismatic` → [`Joint::Prismatic`],
//!   `fixed` → [`Joint::Fixed`] (welded into the parent's link). `<origin xyz rpy>` places the
//!   joint frame in the parent link's frame, `R = Rz(y) Ry(p) Rx(r)`; `<axis xyz>` (default
//!   x) is normalised. `floating` and `planar` joints are refused with an error naming the
//!   joint. `<limit>`, `<dynamics damping friction>` and `<mimic>` are kept in [`UrdfJoint`]
//!   (mimic constraints are not applied: such joints are independent, with a warning).
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
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use roxmltree::{Document, Node, ParsingOptions};

use crate::body::RigidBody;
use crate::error::Error;
use crate::joint::{rot_x, rot_y, rot_z, Joint};
use crate::model::Model;
use crate::point_masses::EquimomentalSet;
use crate::spatial::{BodyInertia, Mat3, Placement, Vec3};

/// `<limit>` of a joint. A continuous joint has `lower = −∞`, `upper = +∞`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Limit {
    pub lower: f64,
    pub upper: f64,
    pub effort: f64,
    pub velocity: f64,
}

/// `<mimic joint multiplier offset>`: recorded, not enforced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Mimic {
    pub joint: String,
    pub multiplier: f64,
    pub offset: f64,
}

/// One URDF joint, in the model's order (depth first; the moving ones in q/v order).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UrdfJoint {
    pub name: String,
    /// "revolute", "continuous", "prismatic" or "fixed".
    pub kind: &'static str,
    /// Parent and child link names.
    pub parent: String,
    pub child: String,
    /// Index of the child link's body in `model.bodies`.
    pub body: usize,
    /// The model link the child belongs to (`None`: welded to the world).
    pub link: Option<usize>,
    /// Position of this joint's coordinate in q and v (`None` for fixed joints).
    pub q_index: Option<usize>,
    pub v_index: Option<usize>,
    /// Unit axis in the joint frame (as given, or x, for fixed joints).
    pub axis: Vec3,
    pub limit: Option<Limit>,
    /// `<dynamics damping>` (N·m·s/rad or N·s/m) and `friction` (N·m or N); 0 when absent.
    pub damping: f64,
    pub friction: f64,
    pub mimic: Option<Mimic>,
}

/// A deserialised [`UrdfJoint`], its `kind` owned until matched to one of the four names.
#[derive(serde::Deserialize)]
struct UrdfJointData {
    name: String,
    kind: String,
    parent: String,
    child: String,
    body: usize,
    link: Option<usize>,
    q_index: Option<usize>,
    v_index: Option<usize>,
    axis: Vec3,
    limit: Option<Limit>,
    damping: f64,
    friction: f64,
    mimic: Option<Mimic>,
}

// By hand: a derived impl would require `'de: 'static` for the `&'static str`.
impl<'de> serde::Deserialize<'de> for UrdfJoint {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        <UrdfJointData as serde::Deserialize>::deserialize(d)?
            .try_into()
            .map_err(serde::de::Error::custom)
    }
}

impl TryFrom<UrdfJointData> for UrdfJoint {
    type Error = String;
    fn try_from(j: UrdfJointData) -> Result<UrdfJoint, String> {
        let kind = ["revolute", "continuous", "prismatic", "fixed"]
            .into_iter()
            .find(|k| *k == j.kind)
            .ok_or_else(|| format!("joint '{}': unknown kind '{}'", j.name, j.kind))?;
        Ok(UrdfJoint {
            name: j.name,
            kind,
            parent: j.parent,
            child: j.child,
            body: j.body,
            link: j.link,
            q_index: j.q_index,
            v_index: j.v_index,
            axis: j.axis,
            limit: j.limit,
            damping: j.damping,
            friction: j.friction,
            mimic: j.mimic,
        })
    }
}

impl UrdfJoint {
    pub fn is_moving(&self) -> bool {
        self.kind != "fixed"
    }
}

/// A loaded URDF: the model, every joint (fixed ones included) and the warnings.
#[derive(Debug, Clone)]
pub struct Urdf {
    /// `<robot name>`.
    pub name: String,
    pub model: Model,
    pub joints: Vec<UrdfJoint>,
    /// Things loaded differently from what the file says (mimic joints, ignored elements).
    pub warnings: Vec<String>,
    /// Directory the file's relative resources would be resolved against (the geometry is
    /// not loaded, so nothing is resolved yet).
    pub base_dir: Option<PathBuf>,
}

impl Urdf {
    /// The moving joints, in q/v order.
    pub fn moving_joints(&self) -> impl Iterator<Item = &UrdfJoint> {
        self.joints.iter().filter(|j| j.is_moving())
    }
    pub fn joint(&self, name: &str) -> Option<&UrdfJoint> {
        self.joints.iter().find(|j| j.name == name)
    }
}

/// An error that names the file and the element (`joint 'x'`, `link 'y'`, …).
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfError {
    pub file: String,
    pub element: String,
    pub message: String,
}

impl std::fmt::Display for UrdfError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.element.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: {}: {}", self.file, self.element, self.message)
        }
    }
}
impl std::error::Error for UrdfError {}

/// Reads and loads a URDF file; errors name `path` as given.
/// Only a regular file of at most [`crate::files::MAX_FILE_BYTES`] is read (a FIFO or a
/// device is refused before it is opened); a path too long to show is shortened in messages.
pub fn load_urdf(path: &Path) -> Result<Urdf, UrdfError> {
    let file = crate::files::display_path(path);
    let text = crate::files::read_text(path, "URDF").map_err(|message| UrdfError {
        file: file.clone(),
        element: String::new(),
        message,
    })?;
    model_from_urdf(&text, &file, path.parent())
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Revolute => "revolute",
            Kind::Continuous => "continuous",
            Kind::Prismatic => "prismatic",
            Kind::Fixed => "fixed",
        }
    }
}

/// A link's own inertial, in the link frame. Mass may be 0 (no `<inertial>`).
#[derive(Debug, Clone, Copy)]
struct Inertial {
    mass: f64,
    com: Vec3,
    inertia: Mat3,
}

impl Inertial {
    fn none() -> Self {
        Inertial {
            mass: 0.0,
            com: Vec3::zeros(),
            inertia: Mat3::zeros(),
        }
    }
    fn body(&self) -> RigidBody {
        RigidBody {
            mass: self.mass,
            com: self.com,
            inertia: self.inertia,
        }
    }
}

struct LinkData {
    name: String,
    line: u32,
    inertial: Inertial,
    /// Why the inertial is no rigid body's: an error unless the link is welded to the world.
    invalid: Option<UrdfError>,
}

struct JointData {
    name: String,
    line: u32,
    kind: Kind,
    parent: String,
    child: String,
    origin: Placement,
    axis: Vec3,
    limit: Option<Limit>,
    damping: f64,
    friction: f64,
    mimic: Option<Mimic>,
}

/// Error builder bound to one file.
struct Ctx<'a> {
    file: &'a str,
    /// Byte offset of the start of each line, so a node's line is a binary search (roxmltree's
    /// `text_pos_at` scans from the start of the text: quadratic over a large file).
    line_starts: Vec<usize>,
}

impl Ctx<'_> {
    fn err(&self, element: impl Into<String>, message: impl Into<String>) -> UrdfError {
        UrdfError {
            file: self.file.to_string(),
            element: element.into(),
            message: message.into(),
        }
    }
    fn line(&self, node: Node) -> u32 {
        let pos = node.range().start;
        self.line_starts.partition_point(|&s| s <= pos) as u32
    }
    /// An error about `node`, with its line.
    fn at(&self, element: &str, node: Node, message: impl std::fmt::Display) -> UrdfError {
        self.err(element, format!("{message} (line {})", self.line(node)))
    }

    /// A finite number attribute, if present.
    fn number(&self, element: &str, node: Node, attr: &str) -> Result<Option<f64>, UrdfError> {
        match node.attribute(attr) {
            None => Ok(None),
            Some(s) => match s.trim().parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(self.at(
                    element,
                    node,
                    format!(
                        "<{} {attr}>: expected a finite number, got '{s}'",
                        node.tag_name().name()
                    ),
                )),
            },
        }
    }

    fn required(&self, element: &str, node: Node, attr: &str) -> Result<f64, UrdfError> {
        self.number(element, node, attr)?.ok_or_else(|| {
            self.at(
                element,
                node,
                format!(
                    "<{}> is missing the '{attr}' attribute",
                    node.tag_name().name()
                ),
            )
        })
    }

    /// A three-number attribute (`xyz`, `rpy`), if present.
    fn triple(&self, element: &str, node: Node, attr: &str) -> Result<Option<Vec3>, UrdfError> {
        let Some(s) = node.attribute(attr) else {
            return Ok(None);
        };
        let parts: Vec<Option<f64>> = s
            .split_whitespace()
            .map(|p| p.parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect();
        if parts.len() != 3 || parts.iter().any(|p| p.is_none()) {
            return Err(self.at(
                element,
                node,
                format!(
                    "<{} {attr}>: expected three finite numbers, got '{s}'",
                    node.tag_name().name()
                ),
            ));
        }
        Ok(Some(Vec3::new(
            parts[0].unwrap(),
            parts[1].unwrap(),
            parts[2].unwrap(),
        )))
    }

    /// `<origin xyz rpy>` (absent: identity).
    fn origin(&self, element: &str, node: Option<Node>) -> Result<Placement, UrdfError> {
        let Some(node) = node else {
            return Ok(Placement::identity());
        };
        let xyz = self
            .triple(element, node, "xyz")?
            .unwrap_or_else(Vec3::zeros);
        let rpy = self
            .triple(element, node, "rpy")?
            .unwrap_or_else(Vec3::zeros);
        Ok(Placement::new(rpy_matrix(&rpy), xyz))
    }
}

/// URDF roll-pitch-yaw: `Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy_matrix(rpy: &Vec3) -> Mat3 {
    rot_z(rpy.z) * rot_y(rpy.y) * rot_x(rpy.x)
}

fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

fn count(ignored: &mut BTreeMap<String, usize>, key: String) {
    *ignored.entry(key).or_insert(0) += 1;
}

fn parse_link(
    ctx: &Ctx,
    node: Node,
    ignored: &mut BTreeMap<String, usize>,
) -> Result<LinkData, UrdfError> {
    let name = node
        .attribute("name")
        .ok_or_else(|| ctx.at("link", node, "<link> has no 'name' attribute"))?
        .to_string();
    let element = format!("link '{name}'");
    let mut inertial = Inertial::none();
    let mut invalid = None;
    let mut seen_inertial = false;
    for c in node.children().filter(|c| c.is_element()) {
        match c.tag_name().name() {
            "inertial" if !seen_inertial => {
                seen_inertial = true;
                (inertial, invalid) = parse_inertial(ctx, &element, c, ignored)?;
            }
            "visual" | "collision" => {}
            other => count(ignored, format!("<link><{other}>")),
        }
    }
    Ok(LinkData {
        name,
        line: ctx.line(node),
        inertial,
        invalid,
    })
}

fn parse_inertial(
    ctx: &Ctx,
    element: &str,
    node: Node,
    ignored: &mut BTreeMap<String, usize>,
) -> Result<(Inertial, Option<UrdfError>), UrdfError> {
    for c in node.children().filter(|c| c.is_element()) {
        let tag = c.tag_name().name();
        if !matches!(tag, "origin" | "mass" | "inertia") {
            count(ignored, format!("<inertial><{tag}>"));
        }
    }
    let origin = ctx.origin(element, child(node, "origin"))?;
    let mass_node = child(node, "mass")
        .ok_or_else(|| ctx.at(element, node, "<inertial> has no <mass value=...>"))?;
    let mass = ctx.required(element, mass_node, "value")?;
    let inertia_node = child(node, "inertia").ok_or_else(|| {
        ctx.at(
            element,
            node,
            "<inertial> has no <inertia ixx ixy ixz iyy iyz izz>",
        )
    })?;
    let mut v = [0.0; 6];
    for (k, attr) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
        .iter()
        .enumerate()
    {
        v[k] = ctx.required(element, inertia_node, attr)?;
    }
    let i = Mat3::new(v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5]);
    let r = origin.rotation;
    let rotated = r * i * r.transpose();
    let inertia = (rotated + rotated.transpose()) * 0.5;
    let com = origin.translation;
    // Validate the link's own body, with our RigidBody's rules and messages. Mass 0 is a
    // massless link (checked later against the tree); its tensor must still be physical.
    // Tolerances scale with the link's inertia about its origin, m (|c|² + (1 mm)²): files
    // written from CAD carry rounding noise (iCub's head: a point mass with
    // ixz = 2.4e-35) that is no error at the scale the link enters the dynamics. A tensor
    // accepted only at that scale is replaced by the nearest physical one (a change of that
    // rounding size), since the point-mass solver must not see a non-physical tensor.
    let (check_mass, scale) = if mass == 0.0 {
        (1.0, 0.0)
    } else {
        (mass, mass * (com.norm_squared() + 1e-6))
    };
    let mut inertia = inertia;
    let mut invalid = None;
    if RigidBody::new(check_mass, com, inertia).is_err() {
        match RigidBody::new_with_scale(check_mass, com, inertia, scale) {
            Ok(_) => inertia = nearest_physical(&inertia),
            Err(e) => {
                let line = ctx.line(node);
                invalid = Some(match e {
                    Error::InvalidInertia { arg, reason } if arg == "mass" => ctx.err(
                        element,
                        format!("<inertial><mass value>: {reason} (line {line})"),
                    ),
                    e => ctx.err(element, format!("<inertial>: {e} (line {line})")),
                });
            }
        }
    }
    Ok((Inertial { mass, com, inertia }, invalid))
}

/// The physical inertia nearest `i` in principal second moments: `σ_k = ½(λ_i + λ_j − λ_k)`
/// clamped at 0, `λ'_k = σ_i + σ_j`, same principal axes.
fn nearest_physical(i: &Mat3) -> Mat3 {
    let eig = i.symmetric_eigen();
    let l = eig.eigenvalues;
    let s = Vec3::new(
        (0.5 * (l[1] + l[2] - l[0])).max(0.0),
        (0.5 * (l[0] + l[2] - l[1])).max(0.0),
        (0.5 * (l[0] + l[1] - l[2])).max(0.0),
    );
    let d = Vec3::new(s.y + s.z, s.x + s.z, s.x + s.y);
    let v = eig.eigenvectors;
    let out = v * Mat3::from_diagonal(&d) * v.transpose();
    (out + out.transpose()) * 0.5
}

fn parse_joint(
    ctx: &Ctx,
    node: Node,
    ignored: &mut BTreeMap<String, usize>,
) -> Result<JointData, UrdfError> {
    let name = node
        .attribute("name")
        .ok_or_else(|| ctx.at("joint", node, "<joint> has no 'name' attribute"))?
        .to_string();
    let element = format!("joint '{name}'");
    let el = element.as_str();
    let kind = match node.attribute("type") {
        Some("revolute") => Kind::Revolute,
        Some("continuous") => Kind::Continuous,
        Some("prismatic") => Kind::Prismatic,
        Some("fixed") => Kind::Fixed,
        Some(t @ ("floating" | "planar")) => {
            return Err(ctx.at(
                el,
                node,
                format!("{t} joints are not supported yet; got joint '{name}' of type {t}"),
            ))
        }
        Some(t) => {
            return Err(ctx.at(
                el,
                node,
                format!(
                    "unknown joint type '{t}' (expected revolute, continuous, prismatic or fixed)"
                ),
            ))
        }
        None => return Err(ctx.at(el, node, "<joint> has no 'type' attribute")),
    };
    let link_of = |tag: &str| -> Result<String, UrdfError> {
        let c = child(node, tag)
            .ok_or_else(|| ctx.at(el, node, format!("<joint> has no <{tag} link=...>")))?;
        c.attribute("link")
            .map(str::to_string)
            .ok_or_else(|| ctx.at(el, c, format!("<{tag}> has no 'link' attribute")))
    };
    let parent = link_of("parent")?;
    let child_link = link_of("child")?;
    let origin = ctx.origin(el, child(node, "origin"))?;
    let mut axis = Vec3::x();
    if let Some(a) = child(node, "axis") {
        if let Some(given) = ctx.triple(el, a, "xyz")? {
            if kind != Kind::Fixed {
                let n = given.norm();
                if n == 0.0 {
                    return Err(ctx.at(
                        el,
                        a,
                        "<axis xyz>: expected a non-zero vector, got '0 0 0'",
                    ));
                }
                axis = given / n;
            } else if given.norm() > 0.0 {
                axis = given.normalize();
            }
        }
    }
    let mut limit = None;
    if let (Some(l), true) = (child(node, "limit"), kind != Kind::Fixed) {
        let effort = ctx.required(el, l, "effort")?;
        let velocity = ctx.required(el, l, "velocity")?;
        let (lower, upper) = if kind == Kind::Continuous {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (
                ctx.number(el, l, "lower")?.unwrap_or(0.0),
                ctx.number(el, l, "upper")?.unwrap_or(0.0),
            )
        };
        limit = Some(Limit {
            lower,
            upper,
            effort,
            velocity,
        });
    }
    let (mut damping, mut friction) = (0.0, 0.0);
    if let Some(d) = child(node, "dynamics") {
        for (attr, out) in [("damping", &mut damping), ("friction", &mut friction)] {
            if let Some(x) = ctx.number(el, d, attr)? {
                if x < 0.0 {
                    return Err(ctx.at(
                        el,
                        d,
                        format!("<dynamics {attr}>: expected a number >= 0, got {x}"),
                    ));
                }
                *out = x;
            }
        }
    }
    let mimic = match child(node, "mimic") {
        None => None,
        Some(m) => Some(Mimic {
            joint: m
                .attribute("joint")
                .ok_or_else(|| ctx.at(el, m, "<mimic> has no 'joint' attribute"))?
                .to_string(),
            multiplier: ctx.number(el, m, "multiplier")?.unwrap_or(1.0),
            offset: ctx.number(el, m, "offset")?.unwrap_or(0.0),
        }),
    };
    for c in node.children().filter(|c| c.is_element()) {
        let tag = c.tag_name().name();
        if !matches!(
            tag,
            "parent" | "child" | "origin" | "axis" | "limit" | "dynamics" | "mimic"
        ) {
            count(ignored, format!("<joint><{tag}>"));
        }
    }
    Ok(JointData {
        name,
        line: ctx.line(node),
        kind,
        parent,
        child: child_link,
        origin,
        axis,
        limit,
        damping,
        friction,
        mimic,
    })
}

/// Bodies summed in one frame; unlike [`RigidBody::merged`] any of them (or all) may have
/// zero mass.
fn sum_bodies(parts: &[RigidBody]) -> RigidBody {
    let mass: f64 = parts.iter().map(|b| b.mass).sum();
    let com = if mass > 0.0 {
        parts.iter().fold(Vec3::zeros(), |a, b| a + b.com * b.mass) / mass
    } else {
        Vec3::zeros()
    };
    let mut inertia = Mat3::zeros();
    for b in parts {
        inertia += if b.mass > 0.0 {
            b.inertia_about(&com)
        } else {
            b.inertia
        };
    }
    RigidBody {
        mass,
        com,
        inertia: (inertia + inertia.transpose()) * 0.5,
    }
}

/// Parses URDF text. `file` names it in errors and warnings; `base_dir` is the directory its
/// relative resources would resolve against (kept in [`Urdf::base_dir`]).
pub fn model_from_urdf(text: &str, file: &str, base_dir: Option<&Path>) -> Result<Urdf, UrdfError> {
    let options = ParsingOptions {
        allow_dtd: true,
        ..ParsingOptions::default()
    };
    let doc = Document::parse_with_options(text, options).map_err(|e| {
        let pos = e.pos();
        let (line, col) = match e {
            roxmltree::Error::UnexpectedEndOfStream | roxmltree::Error::UnclosedRootNode => {
                (text.lines().count().max(1) as u32, 1)
            }
            _ => (pos.row, pos.col),
        };
        UrdfError {
            file: file.to_string(),
            element: String::new(),
            message: format!("malformed XML at line {line}, column {col}: {e}"),
        }
    })?;
    let line_starts: Vec<usize> = std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect();
    let ctx = Ctx { file, line_starts };
    let robot = doc.root_element();
    if robot.tag_name().name() != "robot" {
        return Err(ctx.at(
            "",
            robot,
            format!(
                "expected a <robot> root element, got <{}>",
                robot.tag_name().name()
            ),
        ));
    }
    let robot_name = robot.attribute("name").unwrap_or("").to_string();

    let mut ignored: BTreeMap<String, usize> = BTreeMap::new();
    let mut links: Vec<LinkData> = Vec::new();
    let mut joints: Vec<JointData> = Vec::new();
    for c in robot.children().filter(|c| c.is_element()) {
        match c.tag_name().name() {
            "link" => links.push(parse_link(&ctx, c, &mut ignored)?),
            "joint" => joints.push(parse_joint(&ctx, c, &mut ignored)?),
            "material" => {}
            other => count(&mut ignored, format!("<{other}>")),
        }
    }
    if links.is_empty() {
        return Err(ctx.at("robot", robot, "no <link> elements"));
    }

    // ---- The tree ----
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (k, l) in links.iter().enumerate() {
        if let Some(&first) = link_index.get(l.name.as_str()) {
            return Err(ctx.err(
                format!("link '{}'", l.name),
                format!("defined twice (lines {} and {})", links[first].line, l.line),
            ));
        }
        link_index.insert(&l.name, k);
    }
    let mut joint_names: HashMap<&str, usize> = HashMap::new();
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
    for (k, j) in joints.iter().enumerate() {
        let element = format!("joint '{}'", j.name);
        if let Some(&first) = joint_names.get(j.name.as_str()) {
            return Err(ctx.err(
                element,
                format!(
                    "defined twice (lines {} and {})",
                    joints[first].line, j.line
                ),
            ));
        }
        joint_names.insert(&j.name, k);
        let p = *link_index.get(j.parent.as_str()).ok_or_else(|| {
            ctx.err(
                &element,
                format!(
                    "parent link '{}' is not defined (line {})",
                    j.parent, j.line
                ),
            )
        })?;
        let c = *link_index.get(j.child.as_str()).ok_or_else(|| {
            ctx.err(
                &element,
                format!("child link '{}' is not defined (line {})", j.child, j.line),
            )
        })?;
        if p == c {
            return Err(ctx.err(
                element,
                format!(
                    "link '{}' is both parent and child: the joints form a cycle (line {})",
                    j.child, j.line
                ),
            ));
        }
        if let Some(other) = parent_joint[c] {
            return Err(ctx.err(
                element,
                format!(
                    "link '{}' already has a parent through joint '{}': a link may have only one parent (line {})",
                    j.child, joints[other].name, j.line
                ),
            ));
        }
        parent_joint[c] = Some(k);
        children[p].push(k);
    }
    let roots: Vec<usize> = (0..links.len())
        .filter(|&l| parent_joint[l].is_none())
        .collect();
    let cycle_from = |start: usize| -> String {
        // Each link has at most one parent: walking up from a link off the tree ends in a cycle.
        let mut seen = vec![false; links.len()];
        let mut l = start;
        while !seen[l] {
            seen[l] = true;
            l = link_index[joints[parent_joint[l].unwrap()].parent.as_str()];
        }
        let mut names = Vec::new();
        let first = l;
        loop {
            let j = parent_joint[l].unwrap();
            names.push(format!("'{}'", joints[j].name));
            l = link_index[joints[j].parent.as_str()];
            if l == first {
                break;
            }
        }
        names.reverse();
        names.join(", ")
    };
    let root = match roots.as_slice() {
        [] => {
            return Err(ctx.err(
                "robot",
                format!(
                    "no root link: every link is the child of a joint, so the joints form a cycle (joints {})",
                    cycle_from(0)
                ),
            ))
        }
        [r] => *r,
        many => {
            let names: Vec<String> = many.iter().map(|&l| format!("'{}'", links[l].name)).collect();
            return Err(ctx.err(
                "robot",
                format!(
                    "several root links ({}): a URDF must be one tree; connect them with joints",
                    names.join(", ")
                ),
            ));
        }
    };
    for c in children.iter_mut() {
        c.sort_by(|&a, &b| joints[a].name.as_bytes().cmp(joints[b].name.as_bytes()));
    }
    // Depth first, children in joint-name order (Pinocchio's order).
    let mut order: Vec<usize> = Vec::with_capacity(joints.len());
    let mut stack: Vec<usize> = children[root].iter().rev().copied().collect();
    while let Some(j) = stack.pop() {
        order.push(j);
        let c = link_index[joints[j].child.as_str()];
        stack.extend(children[c].iter().rev().copied());
    }
    if order.len() != joints.len() {
        let mut reached = vec![false; links.len()];
        reached[root] = true;
        for &j in &order {
            reached[link_index[joints[j].child.as_str()]] = true;
        }
        let off = (0..links.len()).find(|&l| !reached[l]).unwrap();
        return Err(ctx.err(
            "robot",
            format!(
                "the joints {} form a cycle, detached from the root link '{}'",
                cycle_from(off),
                links[root].name
            ),
        ));
    }

    // ---- The model ----
    // add_body merges welded bodies as it goes and needs mass > 0; it gets a placeholder for
    // massless links, and every link's body is set from the URDF inertials afterwards.
    let placeholder = RigidBody {
        mass: 1.0,
        com: Vec3::zeros(),
        inertia: Mat3::identity(),
    };
    let safe = |l: &LinkData| {
        if l.inertial.mass > 0.0 && l.invalid.is_none() {
            l.inertial.body()
        } else {
            placeholder
        }
    };
    let model_err = |element: &str, e: Error| ctx.err(element, e.to_string());
    let mut model = Model::new();
    let mut body_of_link = vec![usize::MAX; links.len()];
    let r = &links[root];
    body_of_link[root] = model
        .add_body(
            safe(r),
            Joint::Fixed,
            None,
            Placement::identity(),
            Some(r.name.clone()),
            None,
        )
        .map_err(|e| model_err(&format!("link '{}'", r.name), e))?;
    for &j in &order {
        let jd = &joints[j];
        let element = format!("joint '{}'", jd.name);
        let joint = match jd.kind {
            Kind::Revolute | Kind::Continuous => Joint::revolute(jd.axis),
            Kind::Prismatic => Joint::prismatic(jd.axis),
            Kind::Fixed => Ok(Joint::Fixed),
        }
        .map_err(|e| model_err(&element, e))?;
        let c = link_index[jd.child.as_str()];
        let p = link_index[jd.parent.as_str()];
        body_of_link[c] = model
            .add_body(
                safe(&links[c]),
                joint,
                Some(body_of_link[p]),
                jd.origin,
                Some(jd.child.clone()),
                None,
            )
            .map_err(|e| model_err(&element, e))?;
    }
    // A link welded to the world does not enter the dynamics (Pinocchio ignores it too): an
    // invalid inertial there is only a warning. Robots often carry a dummy root inertia
    // (ANYmal's base: izz only, no rigid body has it).
    let mut warnings = Vec::new();
    let mut ignored_invalid = Vec::new();
    let dfs_links: Vec<usize> = std::iter::once(root)
        .chain(order.iter().map(|&j| link_index[joints[j].child.as_str()]))
        .collect();
    for &l in &dfs_links {
        let data = &links[l];
        let body = body_of_link[l];
        if let Some(e) = &data.invalid {
            if model.bodies[body].link.is_some() {
                return Err(e.clone());
            }
            ignored_invalid.push(format!("link '{}': {}", data.name, e.message));
        }
        model.bodies[body].body = data.inertial.body();
    }
    if !ignored_invalid.is_empty() {
        warnings.push(format!(
            "{file}: invalid inertia ignored on links welded to the world (outside the dynamics): {}",
            ignored_invalid.join("; ")
        ));
    }
    // Each moving link's body: its own inertial and those of the links welded to it.
    let nlinks = model.links.len();
    let mut parts: Vec<Vec<RigidBody>> = vec![Vec::new(); nlinks];
    for b in &model.bodies {
        if let Some(l) = b.link {
            parts[l].push(
                b.body
                    .transformed(&b.in_link.rotation, &b.in_link.translation),
            );
        }
    }
    let merged: Vec<RigidBody> = parts.iter().map(|p| sum_bodies(p)).collect();
    // Mass strictly below each link (its descendant links).
    let mut below = vec![0.0; nlinks];
    for l in (0..nlinks).rev() {
        if let Some(p) = model.links[l].parent {
            below[p] += below[l] + merged[l].mass;
        }
    }
    let joint_of_body: HashMap<usize, usize> = order
        .iter()
        .map(|&j| (body_of_link[link_index[joints[j].child.as_str()]], j))
        .collect();
    for l in 0..nlinks {
        let body = merged[l];
        let link = &mut model.links[l];
        let jd = &joints[joint_of_body[&link.body]];
        if body.mass > 0.0 {
            link.rigid = body;
            link.points = EquimomentalSet::solve(&body, &body.com);
            link.inertia = BodyInertia::from_points(&link.points.masses, &link.points.positions);
        } else if body.inertia.abs().max() > 0.0 {
            return Err(ctx.err(
                format!("link '{}'", jd.child),
                format!(
                    "zero mass with a non-zero rotational inertia on the {} joint '{}' (line {}): seven point masses cannot represent a body without mass; give it a mass > 0",
                    jd.kind.name(), jd.name, jd.line
                ),
            ));
        } else if below[l] > 0.0 {
            link.rigid = body;
            link.points = EquimomentalSet {
                masses: [0.0; 7],
                positions: [Vec3::zeros(); 7],
                half_sides: Vec3::zeros(),
                center: Vec3::zeros(),
            };
            link.inertia = BodyInertia::zero();
        } else {
            return Err(ctx.err(
                format!("joint '{}'", jd.name),
                format!(
                    "child link '{}' has no mass and no link with mass below it, so this {} joint moves nothing and its acceleration is undetermined (line {}); give the link an <inertial> with mass > 0 or make the joint fixed",
                    jd.child, jd.kind.name(), jd.line
                ),
            ));
        }
    }

    // ---- Joint records and warnings ----
    let mut out_joints = Vec::with_capacity(order.len());
    for &j in &order {
        let jd = &joints[j];
        let body = body_of_link[link_index[jd.child.as_str()]];
        let link = model.bodies[body].link;
        let (q_index, v_index) = match (jd.kind, link) {
            (Kind::Fixed, _) | (_, None) => (None, None),
            (_, Some(l)) => (Some(model.links[l].q_index), Some(model.links[l].v_index)),
        };
        out_joints.push(UrdfJoint {
            name: jd.name.clone(),
            kind: jd.kind.name(),
            parent: jd.parent.clone(),
            child: jd.child.clone(),
            body,
            link,
            q_index,
            v_index,
            axis: jd.axis,
            limit: jd.limit,
            damping: jd.damping,
            friction: jd.friction,
            mimic: jd.mimic.clone(),
        });
    }
    let mimics: Vec<String> = out_joints
        .iter()
        .filter_map(|j| {
            j.mimic
                .as_ref()
                .map(|m| format!("'{}' (mimics '{}')", j.name, m.joint))
        })
        .collect();
    if !mimics.is_empty() {
        warnings.push(format!(
            "{file}: mimic constraints are not supported: {} joint(s) are loaded as independent joints: {}",
            mimics.len(),
            mimics.join(", ")
        ));
    }
    let unlimited: Vec<String> = out_joints
        .iter()
        .filter(|j| matches!(j.kind, "revolute" | "prismatic") && j.limit.is_none())
        .map(|j| format!("'{}'", j.name))
        .collect();
    if !unlimited.is_empty() {
        warnings.push(format!(
            "{file}: revolute/prismatic joint(s) without the <limit> the URDF format requires, loaded without limits: {}",
            unlimited.join(", ")
        ));
    }
    if !ignored.is_empty() {
        let kinds: Vec<String> = ignored
            .iter()
            .map(|(k, n)| {
                if *n > 1 {
                    format!("{k} ×{n}")
                } else {
                    k.clone()
                }
            })
            .collect();
        warnings.push(format!(
            "{file}: elements ignored (not used for dynamics): {}",
            kinds.join(", ")
        ));
    }
    Ok(Urdf {
        name: robot_name,
        model,
        joints: out_joints,
        warnings,
        base_dir: base_dir.map(Path::to_path_buf),
    })
}

#[cfg(test)]
mod tests;
