//! A model from a list of bodies in tree order, each on one named joint, with the URDF
//! loader's rules for massless links (an exactly zero body when some body below has mass, an
//! error otherwise): what the MuJoCo and Pinocchio importers (python/pointmass_dyn/
//! importers.py) hand over, so a MuJoCo body with several joints becomes a chain of massless
//! bodies, and joint order and names are kept.
use super::{Urdf, UrdfJoint};
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Mat3, Placement, Vec3};

/// One body: its joint frame in the parent's body frame, its joint and its own inertial
/// (mass may be 0: a massless intermediate body).
#[derive(Debug, Clone)]
pub struct Part {
    pub name: String,
    pub parent: Option<usize>,
    pub placement: Placement,
    pub joint: Joint,
    pub joint_name: String,
    pub mass: f64,
    pub com: Vec3,
    pub inertia: Mat3,
    /// The joint's range `(lower, upper)` (MJCF `range` of a limited joint), if any.
    pub range: Option<(f64, f64)>,
}

/// The model of `parts` (each parent before its children); errors name the body.
pub fn model_from_parts(parts: &[Part]) -> Result<Urdf> {
    let placeholder = RigidBody {
        mass: 1.0,
        com: Vec3::zeros(),
        inertia: Mat3::identity(),
    };
    let named = |p: &Part, e: Error| {
        Error::arg(format!("body '{}'", p.name), "a valid body", e.to_string())
    };
    let mut model = Model::new();
    for p in parts {
        model
            .add_body(
                placeholder,
                p.joint,
                p.parent,
                p.placement,
                Some(p.name.clone()),
                None,
            )
            .map_err(|e| named(p, e))?;
    }
    for (k, p) in parts.iter().enumerate() {
        if p.mass > 0.0 {
            RigidBody::new(p.mass, p.com, p.inertia).map_err(|e| named(p, e))?;
        } else if p.mass < 0.0 || !p.mass.is_finite() {
            return Err(named(
                p,
                Error::arg("mass", "a finite number >= 0", p.mass.to_string()),
            ));
        }
        model.set_body_inertial(
            k,
            RigidBody {
                mass: p.mass,
                com: p.com,
                inertia: p.inertia,
            },
        );
    }
    let merged = model.link_bodies();
    let mut below = vec![0.0; merged.len()];
    for l in (0..merged.len()).rev() {
        if let Some(parent) = model.links[l].parent {
            below[parent] += below[l] + merged[l].mass;
        }
    }
    for (l, body) in merged.into_iter().enumerate() {
        let p = &parts[model.links[l].body];
        if body.mass <= 0.0 && (below[l] <= 0.0 || body.inertia.abs().max() > 0.0) {
            return Err(named(
                p,
                Error::arg(
                    "mass",
                    "mass > 0 on a moving body, or a massless body with bodies with mass below it",
                    format!("mass 0 on joint '{}' that moves nothing else", p.joint_name),
                ),
            ));
        }
        model.set_link_body(l, body).map_err(|e| named(p, e))?;
    }
    let joints = parts
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let link = model.bodies[k].link;
            let moving = p.joint != Joint::Fixed;
            let idx = |f: fn(&crate::model::Link) -> usize| {
                link.filter(|_| moving).map(|l| f(&model.links[l]))
            };
            UrdfJoint {
                name: p.joint_name.clone(),
                kind: p.joint.urdf_type(),
                parent: p
                    .parent
                    .map_or_else(|| "world".to_string(), |q| parts[q].name.clone()),
                child: p.name.clone(),
                body: k,
                link,
                q_index: idx(|l| l.q_index),
                v_index: idx(|l| l.v_index),
                axis: p.joint.axis().unwrap_or_else(Vec3::x),
                limit: p.range.map(|(lower, upper)| super::Limit {
                    lower,
                    upper,
                    effort: f64::INFINITY,
                    velocity: f64::INFINITY,
                }),
                damping: 0.0,
                friction: 0.0,
                mimic: None,
            }
        })
        .collect();
    model.records = crate::model::joint_records::JointRecords::new(joints, Vec::new());
    Ok(Urdf {
        name: String::new(),
        model,
        warnings: Vec::new(),
        base_dir: None,
    })
}

/// `parts` as a binding hands them over: `(name, parent, joint, translation, rotation,
/// joint_name, mass, com, inertia)` each (`joint` read by the binding's `joint`), `parent`
/// -1 or an earlier part's index; `ranges` one `(lower, upper)` or `None` per part.
pub fn parts_arg<A: crate::support::args::Arg>(
    parts: &[A],
    ranges: Option<Vec<Option<(f64, f64)>>>,
    joint: impl Fn(&A) -> Option<Joint>,
) -> std::result::Result<Vec<Part>, A::Err> {
    use crate::support::args::{int, mat3, text, vec3};
    let n = parts.len();
    let ranges = ranges.unwrap_or_else(|| vec![None; n]);
    if ranges.len() != n {
        let expected = format!("one (lower, upper) or None per part ({n})");
        return Err(Error::arg("ranges", expected, format!("{} entries", ranges.len())).into());
    }
    let fields = "(name, parent, joint, translation, rotation, joint_name, mass, com, inertia)";
    let mut out = Vec::with_capacity(n);
    for (k, (p, range)) in parts.iter().zip(ranges).enumerate() {
        let arg = format!("parts[{k}]");
        let bad = || Error::arg(&arg, fields, p.shown());
        let items = p.items().ok_or_else(bad)??;
        let [name, parent, j, t, r, joint_name, mass, com, inertia] = &items[..] else {
            return Err(bad().into());
        };
        let parent_arg = format!("{arg}.parent");
        let earlier = format!("-1 or an earlier part's index 0..{k}");
        let parent = match int(parent, &parent_arg, i64::MIN, i64::MAX, &earlier)? {
            -1 => None,
            i if i >= 0 && (i as usize) < k => Some(i as usize),
            i => return Err(Error::arg(parent_arg, earlier, i.to_string()).into()),
        };
        out.push(Part {
            name: text(name, &arg, fields)?,
            parent,
            placement: Placement::new(mat3(r, "rotation")?, vec3(t, "translation")?),
            joint: joint(j).ok_or_else(bad)?,
            joint_name: text(joint_name, &arg, fields)?,
            mass: mass.real(&arg)?,
            com: vec3(com, "com")?,
            inertia: mat3(inertia, "inertia")?,
            range,
        });
    }
    Ok(out)
}

impl super::RootJoint {
    /// `root_joint=` as a caller writes it: `None` (fixed), `"fixed"` or `"free"`.
    pub fn parse<A: crate::support::args::Arg>(x: Option<&A>) -> std::result::Result<Self, A::Err> {
        use super::RootJoint::{Fixed, Free};
        let choices = [("fixed", Fixed), ("free", Free)];
        let expected = "None, \"fixed\" or \"free\"";
        let root = crate::support::args::opt(x, |r| {
            crate::support::args::choice(r, "root_joint", &choices, expected)
        })?;
        Ok(root.unwrap_or(Fixed))
    }
}
