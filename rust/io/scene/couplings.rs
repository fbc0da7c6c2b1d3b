//! A scene's joint couplings (`[[coupling]]`: `q_joint = ratio · q_reference + offset`,
//! docs/couplings.md) and its joints' rotor inertia (`armature` of a `[[body]]`, or the
//! `[armature]` table by joint or body name). Joints are named as in `Model.add_coupling`:
//! a URDF joint name or a body name. Errors name the key (`coupling[k].ratio`,
//! `armature.elbow`, `body[k] ('name').armature`).
use super::{Ctx, Units};
use crate::io::urdf::UrdfJoint;
use crate::model::Model;
use crate::support::error::Result;

/// The keys of a `[[coupling]]` table.
const COUPLING_KEYS: &str = "joint, reference, ratio, offset, name";

/// The body of the joint named `name` (a URDF joint name first, then a body name).
fn joint_body(
    ctx: &Ctx,
    model: &Model,
    urdf_joints: &[UrdfJoint],
    key: &str,
    name: &str,
) -> Result<usize> {
    if let Some(j) = urdf_joints.iter().find(|j| j.name == name) {
        return Ok(j.body);
    }
    model.body_index(name).ok_or_else(|| {
        let names: Vec<String> = model
            .links
            .iter()
            .take(12)
            .map(|l| format!("'{}'", model.bodies[l.body].name))
            .collect();
        let more = if model.links.len() > 12 { ", …" } else { "" };
        ctx.err(
            key,
            format!(
                "expected a joint name or the name of its body ({}{more}), got '{name}'",
                names.join(", ")
            ),
        )
    })
}

/// Radians (or metres) per file unit of body `b`'s joint coordinate: the angle unit for a
/// revolute joint, 1 otherwise.
fn unit_of(model: &Model, b: usize, units: Units) -> f64 {
    let link = model.bodies[b].link.map(|l| &model.links[l]);
    match link {
        Some(l) if l.body == b && l.joint.q_is_angle(0) => units.angle,
        _ => 1.0,
    }
}

fn number(ctx: &Ctx, key: &str, value: &toml::Value) -> Result<f64> {
    match value {
        toml::Value::Float(x) => Ok(*x),
        toml::Value::Integer(i) => Ok(*i as f64),
        other => Err(ctx.err(key, format!("expected a number, got {other}"))),
    }
}

fn string<'a>(ctx: &Ctx, key: &str, value: &'a toml::Value) -> Result<&'a str> {
    value
        .as_str()
        .ok_or_else(|| ctx.err(key, format!("expected a joint or body name, got {value}")))
}

/// Adds each `[[coupling]]` to `model`. With `angles = "degrees"`, a revolute joint's
/// `offset` is in degrees and `ratio` relates the joints' file units.
pub(super) fn add_couplings(
    ctx: &Ctx,
    model: &mut Model,
    urdf_joints: &[UrdfJoint],
    tables: &[toml::Table],
    units: Units,
) -> Result<()> {
    for (k, t) in tables.iter().enumerate() {
        let key = |field: &str| format!("coupling[{k}].{field}");
        if let Some(bad) = t
            .keys()
            .find(|f| !COUPLING_KEYS.split(", ").any(|x| x == f.as_str()))
        {
            return Err(ctx.err(
                key(bad),
                format!("unknown key (a coupling has {COUPLING_KEYS})"),
            ));
        }
        let body = |field: &str| -> Result<usize> {
            let v = t
                .get(field)
                .ok_or_else(|| ctx.err(key(field), "missing (a joint or body name)"))?;
            let name = string(ctx, &key(field), v)?;
            joint_body(ctx, model, urdf_joints, &key(field), name)
        };
        let j = body("joint")?;
        let r = body("reference")?;
        let get = |field: &str, default: f64| match t.get(field) {
            Some(v) => number(ctx, &key(field), v),
            None => Ok(default),
        };
        let (uj, ur) = (unit_of(model, j, units), unit_of(model, r, units));
        let ratio = get("ratio", 1.0)? * uj / ur;
        let offset = get("offset", 0.0)? * uj;
        let name = match t.get("name") {
            Some(v) => Some(
                v.as_str()
                    .ok_or_else(|| ctx.err(key("name"), format!("expected a string, got {v}")))?
                    .to_string(),
            ),
            None => None,
        };
        model
            .add_coupling(j, r, ratio, offset, name)
            .map_err(|e| ctx.at_arg(format!("coupling[{k}]"), e))?;
    }
    Ok(())
}

/// An armature value: one number, or an array of them (one per speed of the joint).
pub(super) fn armature_values(ctx: &Ctx, key: &str, value: &toml::Value) -> Result<Vec<f64>> {
    let bad = || {
        ctx.err(
            key,
            format!("expected a number >= 0, or one per speed of the joint, got {value}"),
        )
    };
    match value {
        toml::Value::Array(xs) => xs
            .iter()
            .map(|x| match x {
                toml::Value::Float(f) => Ok(*f),
                toml::Value::Integer(i) => Ok(*i as f64),
                _ => Err(bad()),
            })
            .collect(),
        _ => number(ctx, key, value).map(|x| vec![x]).map_err(|_| bad()),
    }
}

/// Sets body `b`'s armature from `value` (at `key`).
pub(super) fn set_armature(
    ctx: &Ctx,
    model: &mut Model,
    b: usize,
    key: &str,
    value: &toml::Value,
) -> Result<()> {
    let values = armature_values(ctx, key, value)?;
    model.set_armature(b, &values).map_err(|e| match e {
        // The core names its arguments `joint` and `value`: here both are the key.
        crate::support::error::Error::InvalidArgument { expected, got, .. } => {
            ctx.err(key, format!("expected {expected}, got {got}"))
        }
        other => ctx.core(key, other),
    })
}

/// The `[armature]` table: joint (or body) name → value.
pub(super) fn set_armatures(
    ctx: &Ctx,
    model: &mut Model,
    urdf_joints: &[UrdfJoint],
    table: &toml::Table,
) -> Result<()> {
    for (name, value) in table {
        let key = format!("armature.{name}");
        let b = joint_body(ctx, model, urdf_joints, &key, name)?;
        set_armature(ctx, model, b, &key, value)?;
    }
    Ok(())
}
