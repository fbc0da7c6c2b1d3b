//! Which joints or bodies an effect acts on, and its per-joint numbers: references by name or
//! index, resolved against a model into coordinate slots.
use crate::joint::Joint;
use crate::model::Model;
use crate::support::error::{Error, Result};

/// A joint (or body) chosen by its body's name or its body index (as `add_body` returns).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum JointRef {
    Name(String),
    Index(usize),
}

impl std::fmt::Display for JointRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            JointRef::Name(n) => write!(f, "'{n}'"),
            JointRef::Index(i) => write!(f, "{i}"),
        }
    }
}

/// A joint selection as a repr shows it: `all` or `[0, 'arm']`.
pub fn joints_repr(joints: &Option<Vec<JointRef>>) -> String {
    match joints {
        None => "all".to_string(),
        Some(v) => format!(
            "[{}]",
            v.iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// A parameter given once for all selected joints or once per selected joint.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum PerJoint {
    All(f64),
    Each(Vec<f64>),
}

/// What a parameter must be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sign {
    Any,
    NonNegative,
    Positive,
}

impl Sign {
    fn ok(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Sign::Any => true,
                Sign::NonNegative => x >= 0.0,
                Sign::Positive => x > 0.0,
            }
    }
    fn expected(self) -> &'static str {
        match self {
            Sign::Any => "finite numbers",
            Sign::NonNegative => "finite numbers >= 0",
            Sign::Positive => "finite numbers > 0",
        }
    }
}

/// The one number a scalar parameter `key` takes, from values given at run time.
pub fn one_number(key: &str, values: &[f64]) -> Result<f64> {
    match values {
        [x] => Ok(*x),
        xs => Err(Error::arg(
            key,
            "one number",
            format!("{} values", xs.len()),
        )),
    }
}

/// Checks every entry of `values` against `sign`; names `arg` and the first bad index.
pub fn check_values(arg: &str, values: &[f64], sign: Sign) -> Result<()> {
    match values.iter().position(|x| !sign.ok(*x)) {
        None => Ok(()),
        Some(k) => Err(Error::arg(
            arg,
            sign.expected(),
            format!("{} at index {k}", values[k]),
        )),
    }
}

impl PerJoint {
    /// Values given at run time (a batch's parameter): one for every joint, or one per joint.
    pub fn from_values(values: &[f64]) -> PerJoint {
        match values {
            [x] => PerJoint::All(*x),
            xs => PerJoint::Each(xs.to_vec()),
        }
    }

    pub fn check(&self, arg: &str, sign: Sign) -> Result<()> {
        match self {
            PerJoint::All(x) => {
                if sign.ok(*x) {
                    Ok(())
                } else {
                    Err(Error::arg(arg, sign.expected(), x.to_string()))
                }
            }
            PerJoint::Each(v) => {
                if v.is_empty() {
                    return Err(Error::arg(arg, "a number or a non-empty list", "[]"));
                }
                check_values(arg, v, sign)
            }
        }
    }

    /// The `n` values, one per item; `what` says what the items are (for the error).
    pub fn expand(&self, n: usize, arg: &str, what: &str) -> Result<Vec<f64>> {
        match self {
            PerJoint::All(x) => Ok(vec![*x; n]),
            PerJoint::Each(v) if v.len() == n => Ok(v.clone()),
            PerJoint::Each(v) => Err(Error::arg(
                arg,
                format!("a number or {n} values, one per {what}"),
                format!("{} values", v.len()),
            )),
        }
    }
}

/// A joint an effect acts on, resolved against the model.
#[derive(Debug, Clone)]
pub struct JointSlot {
    pub body: usize,
    pub link: usize,
    pub name: String,
    pub joint: Joint,
    pub q_index: usize,
    pub v_index: usize,
}

impl JointSlot {
    /// The joint's speeds: their indices in `v` (and in `τ`).
    pub fn speeds(&self) -> std::ops::Range<usize> {
        self.v_index..self.v_index + self.joint.nv()
    }
}

/// Resolves a body name or index to the body's index; errors name `arg`.
pub fn resolve_body(model: &Model, r: &JointRef, arg: &str) -> Result<usize> {
    match r {
        JointRef::Name(n) => model.body_index(n).ok_or_else(|| {
            let names: Vec<String> = model
                .bodies
                .iter()
                .map(|b| format!("'{}'", b.name))
                .collect();
            Error::arg(
                arg,
                format!("the name of a body of the model ({})", names.join(", ")),
                format!("'{n}'"),
            )
        }),
        JointRef::Index(i) if *i < model.nbodies() => Ok(*i),
        JointRef::Index(i) => Err(Error::arg(
            arg,
            format!("a body index 0..{}", model.nbodies()),
            i.to_string(),
        )),
    }
}

/// Resolves a joint given by its name in the model's source file (a URDF joint), the name of
/// its body or its body's index to the body's index. Errors name `arg` and list the joints
/// that can be chosen (the moving ones), each with its body's name where that differs.
pub fn resolve_joint_body(model: &Model, r: &JointRef, arg: &str) -> Result<usize> {
    let JointRef::Name(n) = r else {
        return resolve_body(model, r, arg);
    };
    if let Some(j) = model.records.joints.iter().find(|j| &j.name == n) {
        return Ok(j.body);
    }
    if let Some(b) = model.body_index(n) {
        return Ok(b);
    }
    const SHOWN: usize = 30;
    let mut names: Vec<String> = model
        .joint_names()
        .into_iter()
        .zip(&model.links)
        .take(SHOWN)
        .map(|(joint, l)| match &model.bodies[l.body].name {
            body if *body == joint => format!("'{joint}'"),
            body => format!("'{joint}' (body '{body}')"),
        })
        .collect();
    if model.links.len() > SHOWN {
        names.push(format!("… {} more", model.links.len() - SHOWN));
    }
    let expected = match names.is_empty() {
        true => "a moving joint, but the model has none".to_string(),
        false => format!(
            "a moving joint's name or its body's name ({})",
            names.join(", ")
        ),
    };
    Err(Error::arg(arg, expected, format!("'{n}'")))
}

/// Resolves a selection (`None`: every moving joint, in q/v order) to coordinate slots.
pub fn resolve_joints(
    model: &Model,
    selection: &Option<Vec<JointRef>>,
    arg: &str,
) -> Result<Vec<JointSlot>> {
    let slot = |link: usize| {
        let l = &model.links[link];
        JointSlot {
            body: l.body,
            link,
            name: model.bodies[l.body].name.clone(),
            joint: l.joint,
            q_index: l.q_index,
            v_index: l.v_index,
        }
    };
    let Some(refs) = selection else {
        return Ok((0..model.links.len()).map(slot).collect());
    };
    if refs.is_empty() {
        return Err(Error::arg(arg, "at least one joint", "an empty list"));
    }
    let mut out: Vec<JointSlot> = Vec::with_capacity(refs.len());
    for (k, r) in refs.iter().enumerate() {
        let b = resolve_joint_body(model, r, arg)?;
        let rec = &model.bodies[b];
        let link = match (rec.joint, rec.link) {
            (Joint::Fixed, _) | (_, None) => {
                return Err(Error::arg(
                    arg,
                    "bodies on moving joints",
                    format!(
                    "body '{}' (entry {k}), which is on a Fixed joint: it has no joint coordinate",
                    rec.name
                ),
                ))
            }
            (_, Some(l)) => l,
        };
        if out.iter().any(|s| s.link == link) {
            return Err(Error::arg(
                arg,
                "each joint once",
                format!("body '{}' twice", rec.name),
            ));
        }
        out.push(slot(link));
    }
    Ok(out)
}
