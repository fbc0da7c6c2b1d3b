//! The model from the parsed robot, through `Model`'s own methods: every link a body on its
//! joint (fixed ones welded into their parent's link), then the links' inertials, then each
//! moving link's merged body; and the joint records and warnings the caller sees.
use std::collections::{BTreeMap, HashMap};

use super::parse::{Ctx, Kind, LinkData, RobotData};
use super::tree::Tree;
use super::{RootJoint, UrdfJoint, ROOT_JOINT_NAME};
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::error::{Error, FileKind, Location, Result};
use crate::support::spatial::{Mat3, Placement, Vec3};

/// The model; for each link, its body's index; the warning about invalid inertials ignored
/// (if any).
pub(super) struct Built {
    pub model: Model,
    pub body_of_link: Vec<usize>,
    pub warning: Option<String>,
}

pub(super) fn build_model(
    ctx: &Ctx,
    robot: &RobotData,
    tree: &Tree,
    root: RootJoint,
) -> Result<Built> {
    let (mut model, body_of_link) = add_bodies(ctx, robot, tree, root)?;
    let warning = set_inertials(ctx, &mut model, robot, tree, &body_of_link)?;
    set_link_bodies(ctx, &mut model, robot, tree, &body_of_link)?;
    Ok(Built {
        model,
        body_of_link,
        warning,
    })
}

/// A core error met on `element`, named after the file and element.
fn in_element(ctx: &Ctx, element: String, e: Error) -> Error {
    e.in_file(FileKind::Urdf, Location::new(ctx.file, element))
}

/// The tree, root first then depth first. `add_body` merges welded bodies as it goes and
/// needs mass > 0; it gets a placeholder for massless links, and every link's body is set
/// from the URDF inertials afterwards.
fn add_bodies(
    ctx: &Ctx,
    robot: &RobotData,
    tree: &Tree,
    root: RootJoint,
) -> Result<(Model, Vec<usize>)> {
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
    let links = &robot.links;
    let mut model = Model::new();
    let mut body_of_link = vec![usize::MAX; links.len()];
    let r = &links[tree.root];
    body_of_link[tree.root] = model
        .add_body(
            safe(r),
            match root {
                RootJoint::Fixed => Joint::Fixed,
                RootJoint::Free => Joint::FreeFlyer,
            },
            None,
            Placement::identity(),
            Some(r.name.clone()),
            None,
        )
        .map_err(|e| in_element(ctx, format!("link '{}'", r.name), e))?;
    for &j in &tree.order {
        let jd = &robot.joints[j];
        let element = || format!("joint '{}'", jd.name);
        let joint = match jd.kind {
            Kind::Revolute | Kind::Continuous => Joint::revolute(jd.axis),
            Kind::Prismatic => Joint::prismatic(jd.axis),
            Kind::Fixed => Ok(Joint::Fixed),
        }
        .map_err(|e| in_element(ctx, element(), e))?;
        let (p, c) = (tree.parent_link[j], tree.child_link[j]);
        body_of_link[c] = model
            .add_body(
                safe(&links[c]),
                joint,
                Some(body_of_link[p]),
                jd.origin,
                Some(jd.child.clone()),
                None,
            )
            .map_err(|e| in_element(ctx, element(), e))?;
    }
    Ok((model, body_of_link))
}

/// Sets every body's own inertial. A link welded to the world does not enter the dynamics
/// (Pinocchio ignores it too): an invalid inertial there is only a warning (robots often
/// carry a dummy root inertia: ANYmal's base, izz only, which no rigid body has); on a
/// moving link it is an error.
fn set_inertials(
    ctx: &Ctx,
    model: &mut Model,
    robot: &RobotData,
    tree: &Tree,
    body_of_link: &[usize],
) -> Result<Option<String>> {
    let mut ignored_invalid = Vec::new();
    let dfs_links =
        std::iter::once(tree.root).chain(tree.order.iter().map(|&j| tree.child_link[j]));
    for l in dfs_links {
        let data = &robot.links[l];
        let body = body_of_link[l];
        if let Some((line, message)) = &data.invalid {
            let element = format!("link '{}'", data.name);
            if model.bodies[body].link.is_some() {
                return Err(ctx.located(element, Some(*line), message.clone()));
            }
            ignored_invalid.push(format!("{element}: {message}"));
        }
        model.set_body_inertial(body, data.inertial.body());
    }
    Ok((!ignored_invalid.is_empty()).then(|| {
        format!(
            "{}: invalid inertia ignored on links welded to the world (outside the dynamics): {}",
            ctx.file,
            ignored_invalid.join("; ")
        )
    }))
}

/// Each moving link's body: its own inertial and those of the links welded to it. A link
/// without mass gets an exactly zero body when some link below it has mass (the intermediate
/// links of a multi-axis joint, as Pinocchio does) and is an error otherwise (its joint's
/// acceleration is undetermined), as is mass 0 with a rotational inertia.
fn set_link_bodies(
    ctx: &Ctx,
    model: &mut Model,
    robot: &RobotData,
    tree: &Tree,
    body_of_link: &[usize],
) -> Result<()> {
    let merged = model.link_bodies();
    // Mass strictly below each link (its descendant links).
    let mut below = vec![0.0; merged.len()];
    for l in (0..merged.len()).rev() {
        if let Some(p) = model.links[l].parent {
            below[p] += below[l] + merged[l].mass;
        }
    }
    let joint_of_body: HashMap<usize, usize> = tree
        .order
        .iter()
        .map(|&j| (body_of_link[tree.child_link[j]], j))
        .collect();
    for (l, body) in merged.into_iter().enumerate() {
        // The root link moves only on a free-flyer root joint, which is no element of the file.
        let (child, kind, name, line) = match joint_of_body.get(&model.links[l].body) {
            Some(&j) => {
                let jd = &robot.joints[j];
                (
                    jd.child.as_str(),
                    jd.kind.name(),
                    jd.name.as_str(),
                    Some(jd.line),
                )
            }
            None => (
                robot.links[tree.root].name.as_str(),
                "floating",
                ROOT_JOINT_NAME,
                None,
            ),
        };
        let at = line.map(|n| format!(" (line {n})")).unwrap_or_default();
        let massless = body.mass <= 0.0; // masses are finite: parsed so
        if massless && body.inertia.abs().max() > 0.0 {
            return Err(ctx.located(
                format!("link '{child}'"),
                line,
                format!(
                    "zero mass with a non-zero rotational inertia on the {kind} joint '{name}'{at}: seven point masses cannot represent a body without mass; give it a mass > 0"
                ),
            ));
        }
        if massless && below[l] <= 0.0 {
            return Err(ctx.located(
                format!("joint '{name}'"),
                line,
                format!(
                    "child link '{child}' has no mass and no link with mass below it, so this {kind} joint moves nothing and its acceleration is undetermined{at}; give the link an <inertial> with mass > 0 or make the joint fixed (Model.from_urdf(..., repair=True) makes it fixed)"
                ),
            ));
        }
        model
            .set_link_body(l, body)
            .map_err(|e| in_element(ctx, format!("link '{child}'"), e))?;
    }
    Ok(())
}

/// One record per joint, in the model's (depth-first) order.
pub(super) fn joint_records(robot: &RobotData, tree: &Tree, built: &Built) -> Vec<UrdfJoint> {
    let model = &built.model;
    let root_body = built.body_of_link[tree.root];
    let root = model.bodies[root_body].link.map(|l| UrdfJoint {
        name: ROOT_JOINT_NAME.to_string(),
        kind: "floating",
        parent: "world".to_string(),
        child: robot.links[tree.root].name.clone(),
        body: root_body,
        link: Some(l),
        q_index: Some(model.links[l].q_index),
        v_index: Some(model.links[l].v_index),
        axis: Vec3::x(),
        limit: None,
        damping: 0.0,
        friction: 0.0,
        mimic: None,
    });
    root.into_iter()
        .chain(tree.order.iter().map(|&j| {
            let jd = &robot.joints[j];
            let body = built.body_of_link[tree.child_link[j]];
            let link = model.bodies[body].link;
            let (q_index, v_index) = match (jd.kind, link) {
                (Kind::Fixed, _) | (_, None) => (None, None),
                (_, Some(l)) => (Some(model.links[l].q_index), Some(model.links[l].v_index)),
            };
            UrdfJoint {
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
            }
        }))
        .collect()
}

/// `<mimic joint multiplier offset>` as couplings `q = multiplier · q_joint + offset` (the
/// loop solver holds them, `crate::loops::coupling`). A mimic in a cycle or of itself is an
/// error naming the joint; one of an unknown joint (a broken file, which loaded before mimic
/// joints were coupled) or on or of a fixed joint (a reduced model welds them) has nothing to
/// couple and is skipped, with the warning returned.
pub(super) fn add_mimics(
    ctx: &Ctx,
    model: &mut Model,
    joints: &[UrdfJoint],
) -> Result<Option<String>> {
    let (mut unknown, mut fixed) = (Vec::new(), Vec::new());
    for j in joints {
        let Some(m) = &j.mimic else { continue };
        let what = format!("'{}' (mimics '{}')", j.name, m.joint);
        let Some(reference) = joints.iter().find(|r| r.name == m.joint) else {
            unknown.push(what);
            continue;
        };
        if j.q_index.is_none() || reference.q_index.is_none() {
            fixed.push(what);
            continue;
        }
        model
            .add_coupling(
                j.body,
                reference.body,
                m.multiplier,
                m.offset,
                Some(j.name.clone()),
            )
            .map_err(|e| in_element(ctx, format!("joint '{}' <mimic>", j.name), e))?;
    }
    let mut parts = Vec::new();
    if !unknown.is_empty() {
        parts.push(format!("of unknown joints: {}", unknown.join(", ")));
    }
    if !fixed.is_empty() {
        parts.push(format!("on or of fixed joints: {}", fixed.join(", ")));
    }
    Ok((!parts.is_empty()).then(|| {
        format!(
            "{}: <mimic> elements with nothing to couple, loaded as independent joints: {}",
            ctx.file,
            parts.join("; ")
        )
    }))
}

/// What the file says that is not loaded as said: moving joints without `<limit>`, elements
/// the dynamics does not use.
pub(super) fn joint_warnings(
    file: &str,
    joints: &[UrdfJoint],
    ignored: &BTreeMap<String, usize>,
) -> Vec<String> {
    let mut warnings = Vec::new();
    let unlimited: Vec<String> = joints
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
    warnings
}
