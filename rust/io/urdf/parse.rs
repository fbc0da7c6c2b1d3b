//! Reading the XML: the `<robot>`'s links and joints as plain data, with errors that name the
//! file, the element (`joint 'x'`, `link 'y'`) and the line.
use std::collections::BTreeMap;

use roxmltree::{Document, Node, ParsingOptions};

use super::{rpy_matrix, Limit, Mimic};
use crate::model::body::RigidBody;
use crate::support::error::{Error, FileKind, Location, Result};
use crate::support::spatial::{Mat3, Placement, Vec3};

mod visual;
pub(super) use visual::VisualData;

#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Kind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
}

impl Kind {
    pub(super) fn name(self) -> &'static str {
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
pub(super) struct Inertial {
    pub mass: f64,
    pub com: Vec3,
    pub inertia: Mat3,
}

impl Inertial {
    fn none() -> Self {
        Inertial {
            mass: 0.0,
            com: Vec3::zeros(),
            inertia: Mat3::zeros(),
        }
    }
    pub(super) fn body(&self) -> RigidBody {
        RigidBody {
            mass: self.mass,
            com: self.com,
            inertia: self.inertia,
        }
    }
}

pub(super) struct LinkData {
    pub name: String,
    pub line: u32,
    pub inertial: Inertial,
    /// The `<inertial>`'s line (the link's without one), and whether the link has one.
    pub inertial_line: u32,
    pub has_inertial: bool,
    /// Why the inertial is no rigid body's (its line, and the message, which says the line):
    /// an error unless the link is welded to the world. Not the reader's: `repair::inertials`
    /// sets it.
    pub invalid: Option<(u32, String)>,
    /// `<visual>` elements in file order (those that could be read).
    pub visuals: Vec<VisualData>,
    /// Why the others were dropped (moved to [`RobotData::notes`]).
    pub visual_notes: Vec<String>,
}

pub(super) struct JointData {
    pub name: String,
    pub line: u32,
    pub kind: Kind,
    pub parent: String,
    pub child: String,
    pub origin: Placement,
    pub axis: Vec3,
    pub limit: Option<Limit>,
    pub damping: f64,
    pub friction: f64,
    pub mimic: Option<Mimic>,
}

/// The `<robot>` as read: its name, links and joints in file order, and the elements the
/// dynamics does not use (`<gazebo>`, `<joint><calibration>`, ...) with how often each came.
pub(super) struct RobotData {
    pub name: String,
    pub links: Vec<LinkData>,
    pub joints: Vec<JointData>,
    pub ignored: BTreeMap<String, usize>,
    /// Leniencies the reader allowed itself (undeclared namespace prefixes), visuals dropped.
    pub notes: Vec<String>,
    /// Robot-level `<material name><color rgba>`, by name.
    pub materials: BTreeMap<String, [f64; 4]>,
}

/// Error builder bound to one file.
pub(super) struct Ctx<'a> {
    pub file: &'a str,
    /// Byte offset of the start of each line, so a node's line is a binary search (roxmltree's
    /// `text_pos_at` scans from the start of the text: quadratic over a large file).
    line_starts: Vec<usize>,
}

impl<'a> Ctx<'a> {
    pub(super) fn new(file: &'a str, text: &str) -> Self {
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Ctx { file, line_starts }
    }
    /// An error about `element` (empty: the file); `line` is where, when the message says it.
    pub(super) fn located(
        &self,
        element: impl Into<String>,
        line: Option<u32>,
        message: impl Into<String>,
    ) -> Error {
        let mut at = Location::new(self.file, element);
        at.line = line.map(|l| l as usize);
        Error::file(FileKind::Urdf, at, message)
    }
    pub(super) fn err(&self, element: impl Into<String>, message: impl Into<String>) -> Error {
        self.located(element, None, message)
    }
    /// An error about `element` at `line`: `message (line N)`.
    pub(super) fn on_line(
        &self,
        element: impl Into<String>,
        line: u32,
        message: impl std::fmt::Display,
    ) -> Error {
        self.located(element, Some(line), format!("{message} (line {line})"))
    }
    fn line(&self, node: Node) -> u32 {
        let pos = node.range().start;
        self.line_starts.partition_point(|&s| s <= pos) as u32
    }
    /// An error about `node`, with its line.
    fn at(&self, element: &str, node: Node, message: impl std::fmt::Display) -> Error {
        self.on_line(element, self.line(node), message)
    }

    /// A finite number attribute, if present.
    fn number(&self, element: &str, node: Node, attr: &str) -> Result<Option<f64>> {
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

    fn required(&self, element: &str, node: Node, attr: &str) -> Result<f64> {
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
    fn triple(&self, element: &str, node: Node, attr: &str) -> Result<Option<Vec3>> {
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
    fn origin(&self, element: &str, node: Option<Node>) -> Result<Placement> {
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

/// Parses the text's `<robot>`: every `<link>` and `<joint>` (each checked on its own; how
/// they connect is [`super::tree`]'s business).
pub(super) fn parse_robot(ctx: &Ctx, text: &str) -> Result<RobotData> {
    // Real files use namespace prefixes they never declare (`drake:`, `gazebo:`), which
    // urdfdom (TinyXML) reads; declare each one on the root element (same line: the line
    // numbers stay) and say so.
    let mut undeclared: Vec<String> = Vec::new();
    let mut declared = text.to_string();
    loop {
        let outcome = Document::parse_with_options(&declared, opts()).map(|_| ());
        match outcome {
            Ok(()) => break,
            Err(roxmltree::Error::UnknownNamespace(prefix, _))
                if undeclared.len() < 64 && !undeclared.contains(&prefix) =>
            {
                let Some(at) = root_name_end(text) else {
                    return Err(ctx.err("", "no root element"));
                };
                undeclared.push(prefix);
                let decls: String = undeclared
                    .iter()
                    .map(|p| format!(" xmlns:{p}=\"urn:pointmass-dyn:undeclared:{p}\""))
                    .collect();
                declared = format!("{}{decls}{}", &text[..at], &text[at..]);
            }
            Err(e) => return Err(malformed(ctx, text, e)),
        }
    }
    let doc =
        Document::parse_with_options(&declared, opts()).map_err(|e| malformed(ctx, text, e))?;
    let mut notes = Vec::new();
    if !undeclared.is_empty() {
        let names: Vec<String> = undeclared.iter().map(|p| format!("'{p}:'")).collect();
        notes.push(format!(
            "{}: undeclared XML namespace prefix(es) {} accepted (their elements and attributes are not URDF and are ignored)",
            ctx.file,
            names.join(", ")
        ));
    }
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
    let mut ignored: BTreeMap<String, usize> = BTreeMap::new();
    let mut links: Vec<LinkData> = Vec::new();
    let mut joints: Vec<JointData> = Vec::new();
    let mut materials = BTreeMap::new();
    for c in robot.children().filter(|c| c.is_element()) {
        if let Some(q) = foreign(c) {
            count(&mut ignored, format!("<{q}>"));
            continue;
        }
        match c.tag_name().name() {
            "link" => links.push(parse_link(ctx, c, &mut ignored)?),
            "joint" => joints.push(parse_joint(ctx, c, &mut ignored)?),
            "material" => match visual::material(ctx, "robot", c) {
                Ok((Some(name), Some(rgba))) => {
                    materials.insert(name, rgba);
                }
                Ok(_) => {}
                Err(warning) => notes.push(warning),
            },
            other => count(&mut ignored, format!("<{other}>")),
        }
    }
    for link in &mut links {
        notes.append(&mut link.visual_notes);
    }
    if links.is_empty() {
        return Err(ctx.at("robot", robot, "no <link> elements"));
    }
    Ok(RobotData {
        name: robot.attribute("name").unwrap_or("").to_string(),
        links,
        joints,
        ignored,
        notes,
        materials,
    })
}

fn opts<'a>() -> ParsingOptions<'a> {
    ParsingOptions {
        allow_dtd: true,
        ..ParsingOptions::default()
    }
}

/// Byte offset just after the root element's name (where declarations can be added).
fn root_name_end(text: &str) -> Option<usize> {
    let b = text.as_bytes();
    let mut i = 0;
    while i + 1 < b.len() {
        if b[i] == b'<' && (b[i + 1].is_ascii_alphabetic() || b[i + 1] == b'_') {
            let mut k = i + 1;
            while k < b.len() && !(b[k].is_ascii_whitespace() || b[k] == b'>' || b[k] == b'/') {
                k += 1;
            }
            return Some(k);
        }
        if text[i..].starts_with("<!--") {
            i += text[i..].find("-->").map_or(b.len(), |e| e + 3);
        } else {
            i += 1;
        }
    }
    None
}

/// `prefix:name` of an element in a namespace (no URDF element is in one), else `None`.
fn foreign(node: Node) -> Option<String> {
    let ns = node.tag_name().namespace()?;
    let prefix = node.lookup_prefix(ns).unwrap_or("?");
    Some(format!("{prefix}:{}", node.tag_name().name()))
}

/// Text that is no XML document: the line and column (at the end of the text when it
/// stops early).
fn malformed(ctx: &Ctx, text: &str, e: roxmltree::Error) -> Error {
    let pos = e.pos();
    let (line, col) = match e {
        roxmltree::Error::UnexpectedEndOfStream | roxmltree::Error::UnclosedRootNode => {
            (text.lines().count().max(1) as u32, 1)
        }
        _ => (pos.row, pos.col),
    };
    let message = format!("malformed XML at line {line}, column {col}: {e}");
    let mut err = ctx.located("", Some(line), message);
    if let Error::File { at, .. } = &mut err {
        at.column = Some(col as usize);
    }
    err
}

fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag && foreign(*c).is_none())
}

fn count(ignored: &mut BTreeMap<String, usize>, key: String) {
    *ignored.entry(key).or_insert(0) += 1;
}

/// Counts the children of `node` whose tag is not in `known` as ignored `<parent><tag>`.
fn count_unknown(node: Node, parent: &str, known: &[&str], ignored: &mut BTreeMap<String, usize>) {
    for c in node.children().filter(|c| c.is_element()) {
        if let Some(q) = foreign(c) {
            count(ignored, format!("<{parent}><{q}>"));
            continue;
        }
        let tag = c.tag_name().name();
        if !known.contains(&tag) {
            count(ignored, format!("<{parent}><{tag}>"));
        }
    }
}

/// The `name` of a `<link>` or `<joint>` (`tag`), and the element as errors name it
/// (`link 'base'`).
fn named(ctx: &Ctx, node: Node, tag: &str) -> Result<(String, String)> {
    let name = node
        .attribute("name")
        .ok_or_else(|| ctx.at(tag, node, format!("<{tag}> has no 'name' attribute")))?;
    Ok((name.to_string(), format!("{tag} '{name}'")))
}

fn parse_link(ctx: &Ctx, node: Node, ignored: &mut BTreeMap<String, usize>) -> Result<LinkData> {
    let (name, element) = named(ctx, node, "link")?;
    let mut inertial = Inertial::none();
    let mut line = ctx.line(node);
    let mut seen_inertial = false;
    let (mut visuals, mut visual_notes) = (Vec::new(), Vec::new());
    for c in node.children().filter(|c| c.is_element()) {
        if let Some(q) = foreign(c) {
            count(ignored, format!("<link><{q}>"));
            continue;
        }
        match c.tag_name().name() {
            "inertial" if !seen_inertial => {
                seen_inertial = true;
                count_unknown(c, "inertial", &["origin", "mass", "inertia"], ignored);
                inertial = parse_inertial(ctx, &element, c)?;
                line = ctx.line(c);
            }
            "visual" => match visual::visual(ctx, &element, c) {
                Ok(v) => visuals.push(v),
                Err(warning) => visual_notes.push(format!("{warning}: this visual is not drawn")),
            },
            "collision" => {}
            other => count(ignored, format!("<link><{other}>")),
        }
    }
    Ok(LinkData {
        name,
        line: ctx.line(node),
        inertial,
        inertial_line: line,
        has_inertial: seen_inertial,
        invalid: None,
        visuals,
        visual_notes,
    })
}

/// `<inertial>`: the link's own body in the link frame, and why it is no rigid body's (if it
/// is not; that is an error only on a moving link, decided once the tree is known).
fn parse_inertial(ctx: &Ctx, element: &str, node: Node) -> Result<Inertial> {
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
    Ok(Inertial {
        mass,
        com: origin.translation,
        inertia: (rotated + rotated.transpose()) * 0.5,
    })
}

fn parse_joint(ctx: &Ctx, node: Node, ignored: &mut BTreeMap<String, usize>) -> Result<JointData> {
    let (name, element) = named(ctx, node, "joint")?;
    let el = element.as_str();
    let kind = joint_kind(ctx, el, node, &name)?;
    let link_of = |tag: &str| -> Result<String> {
        let c = child(node, tag)
            .ok_or_else(|| ctx.at(el, node, format!("<joint> has no <{tag} link=...>")))?;
        c.attribute("link")
            .map(str::to_string)
            .ok_or_else(|| ctx.at(el, c, format!("<{tag}> has no 'link' attribute")))
    };
    let parent = link_of("parent")?;
    let child_link = link_of("child")?;
    let origin = ctx.origin(el, child(node, "origin"))?;
    let axis = joint_axis(ctx, el, node, kind)?;
    let limit = match (child(node, "limit"), kind) {
        (Some(l), k) if k != Kind::Fixed => Some(joint_limit(ctx, el, l, kind)?),
        _ => None,
    };
    let (damping, friction) = joint_dynamics(ctx, el, node)?;
    // One coupling per joint: a second <mimic> would be dropped without a word.
    let mut mimics = node
        .children()
        .filter(|c| c.is_element() && c.tag_name().name() == "mimic" && foreign(*c).is_none());
    if let (Some(_), Some(second)) = (mimics.next(), mimics.next()) {
        return Err(ctx.at(
            el,
            second,
            "a second <mimic>: a joint mimics at most one joint (q = multiplier · q_joint + offset); keep one",
        ));
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
    let known = [
        "parent", "child", "origin", "axis", "limit", "dynamics", "mimic",
    ];
    count_unknown(node, "joint", &known, ignored);
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

/// `<joint type>`: the four kinds we load; `floating` and `planar` are refused by name.
fn joint_kind(ctx: &Ctx, el: &str, node: Node, name: &str) -> Result<Kind> {
    match node.attribute("type") {
        Some("revolute") => Ok(Kind::Revolute),
        Some("continuous") => Ok(Kind::Continuous),
        Some("prismatic") => Ok(Kind::Prismatic),
        Some("fixed") => Ok(Kind::Fixed),
        Some(t @ ("floating" | "planar")) => Err(ctx.at(
            el,
            node,
            format!("{t} joints are not supported yet; got joint '{name}' of type {t}"),
        )),
        Some(t) => Err(ctx.at(
            el,
            node,
            format!("unknown joint type '{t}' (expected revolute, continuous, prismatic or fixed)"),
        )),
        None => Err(ctx.at(el, node, "<joint> has no 'type' attribute")),
    }
}

/// `<axis xyz>` normalised (default x); a zero axis is an error unless the joint is fixed.
fn joint_axis(ctx: &Ctx, el: &str, node: Node, kind: Kind) -> Result<Vec3> {
    let Some(a) = child(node, "axis") else {
        return Ok(Vec3::x());
    };
    let Some(given) = ctx.triple(el, a, "xyz")? else {
        return Ok(Vec3::x());
    };
    let n = given.norm();
    if kind != Kind::Fixed && n == 0.0 {
        return Err(ctx.at(el, a, "<axis xyz>: expected a non-zero vector, got '0 0 0'"));
    }
    Ok(if kind != Kind::Fixed {
        given / n
    } else if n > 0.0 {
        given.normalize()
    } else {
        Vec3::x()
    })
}

/// `<limit>` of a moving joint; a continuous joint's bounds are ±∞ whatever it says.
fn joint_limit(ctx: &Ctx, el: &str, l: Node, kind: Kind) -> Result<Limit> {
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
    Ok(Limit {
        lower,
        upper,
        effort,
        velocity,
    })
}

/// `<dynamics damping friction>`: both >= 0, 0 when absent.
fn joint_dynamics(ctx: &Ctx, el: &str, node: Node) -> Result<(f64, f64)> {
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
    Ok((damping, friction))
}
