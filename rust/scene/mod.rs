//! Scenes: a model, the effects it calls for, its initial state and integrator settings,
//! read from TOML. Errors name the file and the key.
use std::collections::HashMap;

use serde::Deserialize;

use crate::body::RigidBody;
use crate::effects::{Disabled, Effect, Effects};
use crate::error::Error;
use crate::joint::{rot_x, rot_y, rot_z, Joint};
use crate::model::Model;
use crate::spatial::{Mat3, Placement, Vec3};

#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub file: String,
    pub key: String,
    pub message: String,
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: {}: {}", self.file, self.key, self.message)
        }
    }
}
impl std::error::Error for SceneError {}

/// Integrator settings a scene may carry; the caller's arguments override them.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
    pub t_span: Option<(f64, f64)>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub max_step: Option<f64>,
    pub max_steps: Option<usize>,
    pub first_step: Option<f64>,
    /// Effect families to leave out (`[simulate] disable = [...]`).
    pub disable: Option<Disabled>,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Scene {
    pub name: String,
    pub description: String,
    /// Shared with the Python `Model` objects made from it (`scene.model`): never copied.
    pub model: std::sync::Arc<Model>,
    pub q0: Vec<f64>,
    pub v0: Vec<f64>,
    pub effects: Vec<Effect>,
    pub settings: Settings,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    description: Option<String>,
    /// "radians" (default) or "degrees": units of angular q0 and of `rpy`.
    angles: Option<String>,
    /// "radians" or "degrees" (per second): units of angular v0; default: as `angles`.
    rates: Option<String>,
    /// A URDF file, relative to the scene file's directory: its robot starts the model (at
    /// q = 0, v = 0); `[[body]]` entries follow and may name its links as parents.
    urdf: Option<String>,
    /// Which of the URDF's `<dynamics>` attributes become effects: "damping" (a damper per
    /// joint) and/or "friction" (regularised Coulomb friction per joint).
    urdf_dynamics: Option<Vec<String>>,
    /// Initial state of the whole model (overrides per-body q0/v0): `q0` (nq values) and
    /// `v0` (nv values), angular entries in the file's units.
    initial: Option<InitialFile>,
    #[serde(default)]
    body: Vec<BodyFile>,
    #[serde(default)]
    effect: Vec<EffectFile>,
    simulate: Option<SimulateFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InitialFile {
    q0: Option<Vec<f64>>,
    v0: Option<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BodyFile {
    name: String,
    parent: Option<String>,
    joint: JointFile,
    translation: Option<[f64; 3]>,
    rotation: Option<[[f64; 3]; 3]>,
    /// Roll, pitch, yaw of the joint frame (URDF convention: Rz(y) Ry(p) Rx(r)).
    rpy: Option<[f64; 3]>,
    mass: f64,
    com: Option<[f64; 3]>,
    inertia: Option<[[f64; 3]; 3]>,
    inertia_diag: Option<[f64; 3]>,
    point_mass_center: Option<[f64; 3]>,
    q0: Option<Vec<f64>>,
    v0: Option<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(tag = "type", deny_unknown_fields)]
enum JointFile {
    Revolute { axis: [f64; 3] },
    Prismatic { axis: [f64; 3] },
    SphericalZYZ,
    Spherical,
    Fixed,
}

/// One `[[effect]]` table, read by `Effect::from_toml` (so a new effect type needs no
/// change here); its `type` key selects the effect.
type EffectFile = toml::Table;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulateFile {
    t_span: Option<[f64; 2]>,
    t_end: Option<f64>,
    rtol: Option<f64>,
    atol: Option<f64>,
    max_step: Option<f64>,
    max_steps: Option<usize>,
    first_step: Option<f64>,
    /// Effect families switched off without editing the scene ("gravity", "springs", ...).
    disable: Option<Vec<String>>,
}

impl Scene {
    /// Reads and parses a scene file. Only a regular file of at most
    /// [`crate::files::MAX_FILE_BYTES`] is read (a FIFO or a device is refused before it is
    /// opened); errors name the path (shortened if too long to show).
    pub fn from_file(path: &std::path::Path) -> Result<Scene, SceneError> {
        let file = crate::files::display_path(path);
        let text = crate::files::read_text(path, "scene").map_err(|message| SceneError {
            file: file.clone(),
            key: String::new(),
            message,
        })?;
        let dir = path.parent().unwrap_or(std::path::Path::new(""));
        Self::parse(&text, &file, dir)
    }

    /// Parses a scene from TOML text; `file` names it in errors, and a `urdf` key is resolved
    /// relative to its directory.
    pub fn from_toml(text: &str, file: &str) -> Result<Scene, SceneError> {
        let dir = std::path::Path::new(file)
            .parent()
            .unwrap_or(std::path::Path::new(""));
        Self::parse(text, file, dir)
    }

    fn parse(text: &str, file: &str, dir: &std::path::Path) -> Result<Scene, SceneError> {
        let err = |key: String, message: String| SceneError {
            file: file.to_string(),
            key,
            message,
        };
        let sf: SceneFile = toml::from_str(text).map_err(|e| {
            let (line, col) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
            SceneError {
                file: file.to_string(),
                key: String::new(),
                message: format!(
                    "invalid scene TOML at line {line}, column {col}: {}",
                    e.message()
                ),
            }
        })?;
        let unit_of = |key: &str, value: Option<&str>, default: f64| match value {
            None => Ok(default),
            Some("radians") => Ok(1.0),
            Some("degrees") => Ok(std::f64::consts::PI / 180.0),
            Some(other) => Err(err(
                key.into(),
                format!("expected \"radians\" or \"degrees\", got \"{other}\""),
            )),
        };
        let unit = unit_of("angles", sf.angles.as_deref(), 1.0)?;
        let rate_unit = unit_of("rates", sf.rates.as_deref(), unit)?;
        if sf.body.is_empty() && sf.urdf.is_none() {
            return Err(err(
                "body".into(),
                "a scene needs at least one [[body]] (or a urdf)".into(),
            ));
        }
        let mut model = Model::new();
        let mut index: HashMap<String, usize> = HashMap::new();
        let mut urdf_effects = Vec::new();
        if let Some(rel) = &sf.urdf {
            let urdf = scene_urdf(dir, rel).map_err(|m| err("urdf".into(), m))?;
            urdf_effects = urdf_dynamics_effects(&urdf, sf.urdf_dynamics.as_deref())
                .map_err(|m| err("urdf_dynamics".into(), m))?;
            model = urdf.model;
            for (k, b) in model.bodies.iter().enumerate() {
                index.insert(b.name.clone(), k);
            }
        } else if sf.urdf_dynamics.is_some() {
            return Err(err("urdf_dynamics".into(), "needs a urdf key".into()));
        }
        let mut q0 = model.neutral();
        let mut v0 = vec![0.0; model.nv];
        for (k, b) in sf.body.iter().enumerate() {
            let key = |field: &str| format!("body[{k}] ('{}').{field}", b.name);
            let core = |field: &str, e: Error| err(key(field), e.to_string());
            let parent = match b.parent.as_deref() {
                None | Some("world") => None,
                Some(p) => Some(*index.get(p).ok_or_else(|| {
                    err(
                        key("parent"),
                        format!("no body named '{p}' before this one (bodies must follow their parents; 'world' is the ground)"),
                    )
                })?),
            };
            let joint = match &b.joint {
                JointFile::Revolute { axis } => Joint::revolute(Vec3::from(*axis)),
                JointFile::Prismatic { axis } => Joint::prismatic(Vec3::from(*axis)),
                JointFile::SphericalZYZ => Ok(Joint::SphericalZYZ),
                JointFile::Spherical => Ok(Joint::Spherical),
                JointFile::Fixed => Ok(Joint::Fixed),
            }
            .map_err(|e| core("joint.axis", e))?;
            let rotation = match (b.rotation, b.rpy) {
                (Some(_), Some(_)) => {
                    return Err(err(
                        key("rotation"),
                        "give either rotation or rpy, not both".into(),
                    ))
                }
                (Some(r), None) => Mat3::from_row_slice(&r.concat()),
                (None, Some([r, p, y])) => rot_z(y * unit) * rot_y(p * unit) * rot_x(r * unit),
                (None, None) => Mat3::identity(),
            };
            let inertia = match (b.inertia, b.inertia_diag) {
                (Some(_), Some(_)) => {
                    return Err(err(
                        key("inertia"),
                        "give either inertia or inertia_diag, not both".into(),
                    ))
                }
                (Some(i), None) => Mat3::from_row_slice(&i.concat()),
                (None, Some(d)) => Mat3::from_diagonal(&Vec3::from(d)),
                (None, None) => {
                    return Err(err(
                        key("inertia"),
                        "missing: give inertia (3x3, about the COM) or inertia_diag".into(),
                    ))
                }
            };
            let com = Vec3::from(b.com.unwrap_or([0.0; 3]));
            let body = RigidBody::new(b.mass, com, inertia).map_err(|e| {
                let field = match &e {
                    Error::InvalidInertia { arg, .. } | Error::InvalidArgument { arg, .. } => {
                        arg.clone()
                    }
                    _ => "inertia".into(),
                };
                core(&field, e)
            })?;
            let placement = Placement::new(rotation, Vec3::from(b.translation.unwrap_or([0.0; 3])));
            let center = b.point_mass_center.map(Vec3::from);
            let idx = model
                .add_body(body, joint, parent, placement, Some(b.name.clone()), center)
                .map_err(|e| {
                    let field = match &e {
                        Error::InvalidArgument { arg, .. } | Error::InvalidModel { arg, .. } => {
                            arg.clone()
                        }
                        _ => String::new(),
                    };
                    core(&field, e)
                })?;
            index.insert(b.name.clone(), idx);
            // Initial state of this joint, in file units.
            let angular = matches!(
                joint,
                Joint::Revolute { .. } | Joint::SphericalZYZ | Joint::Spherical
            );
            let mut q = vec![0.0; joint.nq()];
            joint.neutral(&mut q);
            if let Some(given) = &b.q0 {
                if given.len() != joint.nq() {
                    return Err(err(
                        key("q0"),
                        format!(
                            "expected {} values for a {} joint, got {}",
                            joint.nq(),
                            joint.kind(),
                            given.len()
                        ),
                    ));
                }
                let scale = if matches!(joint, Joint::Revolute { .. } | Joint::SphericalZYZ) {
                    unit
                } else {
                    1.0
                };
                q = given.iter().map(|x| x * scale).collect();
                joint
                    .check_configuration(&q, "q0")
                    .map_err(|e| core("q0", e))?;
            }
            let mut v = vec![0.0; joint.nv()];
            if let Some(given) = &b.v0 {
                if given.len() != joint.nv() {
                    return Err(err(
                        key("v0"),
                        format!(
                            "expected {} values for a {} joint, got {}",
                            joint.nv(),
                            joint.kind(),
                            given.len()
                        ),
                    ));
                }
                let scale = if angular { rate_unit } else { 1.0 };
                v = given.iter().map(|x| x * scale).collect();
                crate::error::check_finite("v0", &v).map_err(|e| core("v0", e))?;
            }
            q0.extend(q);
            v0.extend(v);
        }
        if let Some(init) = &sf.initial {
            // Scale the angular coordinates (revolute and ZYZ angles, all rotational speeds).
            for (given, target, n, arg) in [
                (&init.q0, &mut q0, model.nq, "q0"),
                (&init.v0, &mut v0, model.nv, "v0"),
            ] {
                let Some(given) = given else { continue };
                if given.len() != n {
                    return Err(err(
                        format!("initial.{arg}"),
                        format!("expected {n} values, got {}", given.len()),
                    ));
                }
                target.copy_from_slice(given);
                for l in &model.links {
                    let angular_q = matches!(l.joint, Joint::Revolute { .. } | Joint::SphericalZYZ);
                    let (start, len, scale) = if arg == "q0" {
                        (l.q_index, l.joint.nq(), if angular_q { unit } else { 1.0 })
                    } else {
                        (
                            l.v_index,
                            l.joint.nv(),
                            if l.joint.moves_angular() {
                                rate_unit
                            } else {
                                1.0
                            },
                        )
                    };
                    target[start..start + len]
                        .iter_mut()
                        .for_each(|x| *x *= scale);
                }
            }
            model
                .check_state(&q0, Some(&v0))
                .map_err(|e| err("initial".into(), e.to_string()))?;
        }
        model.normalize(&mut q0);
        // Effect errors: the key is `effect[k].field`, the message what was expected.
        let effect_err = |x: Error, prefix: &str| match x {
            Error::InvalidArgument { arg, expected, got } => err(
                if arg.is_empty() {
                    prefix.trim_end_matches('.').to_string()
                } else {
                    format!("{prefix}{arg}")
                },
                format!("expected {expected}, got {got}"),
            ),
            other => err(prefix.trim_end_matches('.').to_string(), other.to_string()),
        };
        let mut effects = urdf_effects;
        for (k, e) in sf.effect.iter().enumerate() {
            effects
                .push(Effect::from_toml(e).map_err(|x| effect_err(x, &format!("effect[{k}].")))?);
        }
        // Resolve joint and body names, table widths and effect names against the model now,
        // so a scene that loads also runs.
        Effects::new(&model, &effects, Disabled::none(), "effect")
            .map_err(|x| effect_err(x, ""))?;
        let mut settings = Settings::default();
        if let Some(s) = sf.simulate {
            settings.t_span = match (s.t_span, s.t_end) {
                (Some(_), Some(_)) => {
                    return Err(err(
                        "simulate.t_end".into(),
                        "give either t_span or t_end, not both".into(),
                    ))
                }
                (Some([a, b]), None) => Some((a, b)),
                (None, Some(b)) => Some((0.0, b)),
                (None, None) => None,
            };
            if let Some((a, b)) = settings.t_span {
                if !(a.is_finite() && b.is_finite()) || a == b {
                    return Err(err(
                        "simulate.t_span".into(),
                        format!("expected two different finite times, got [{a}, {b}]"),
                    ));
                }
            }
            for (name, x) in [
                ("rtol", s.rtol),
                ("atol", s.atol),
                ("max_step", s.max_step),
                ("first_step", s.first_step),
            ] {
                if let Some(x) = x {
                    if !(x > 0.0) || !x.is_finite() {
                        return Err(err(
                            format!("simulate.{name}"),
                            format!("expected a finite number > 0, got {x}"),
                        ));
                    }
                }
            }
            settings.rtol = s.rtol;
            settings.atol = s.atol;
            settings.max_step = s.max_step;
            settings.max_steps = s.max_steps;
            settings.first_step = s.first_step;
            if let Some(names) = &s.disable {
                settings.disable = Some(
                    Disabled::parse(names, "simulate.disable").map_err(|x| effect_err(x, ""))?,
                );
            }
        }
        Ok(Scene {
            name: sf.name.unwrap_or_else(|| file.to_string()),
            description: sf.description.unwrap_or_default(),
            model: std::sync::Arc::new(model),
            q0,
            v0,
            effects,
            settings,
        })
    }
}

/// The model of a scene's `urdf` file, resolved relative to the scene file's directory
/// `dir` (its URDF warnings are not reported here).
fn scene_urdf(dir: &std::path::Path, rel: &str) -> Result<crate::urdf::Urdf, String> {
    crate::urdf::load_urdf(&dir.join(rel)).map_err(|e| e.to_string())
}

/// Effects from the URDF's `<dynamics damping friction>` as the scene asks: a damper and/or
/// a friction effect over the joints whose value is non-zero (none if all are zero).
fn urdf_dynamics_effects(
    urdf: &crate::urdf::Urdf,
    asked: Option<&[String]>,
) -> Result<Vec<Effect>, String> {
    use crate::effects::{damper::Damper, friction::Friction, JointRef, PerJoint};
    let mut out = Vec::new();
    for what in asked.unwrap_or(&[]) {
        let pick = |f: fn(&crate::urdf::UrdfJoint) -> f64| -> (Vec<JointRef>, Vec<f64>) {
            urdf.joints
                .iter()
                .filter(|j| j.q_index.is_some() && f(j) != 0.0)
                .map(|j| (JointRef::Index(j.body), f(j)))
                .unzip()
        };
        match what.as_str() {
            "damping" => {
                let (joints, values) = pick(|j| j.damping);
                if !joints.is_empty() {
                    let name = Some("urdf_damping".to_string());
                    out.push(Effect::Damper(
                        Damper::new(name, Some(joints), PerJoint::Each(values))
                            .map_err(|e| e.to_string())?,
                    ));
                }
            }
            "friction" => {
                let (joints, values) = pick(|j| j.friction);
                if !joints.is_empty() {
                    let name = Some("urdf_friction".to_string());
                    out.push(Effect::Friction(
                        Friction::new(name, Some(joints), PerJoint::Each(values), None)
                            .map_err(|e| e.to_string())?,
                    ));
                }
            }
            other => {
                return Err(format!(
                    "expected \"damping\" and/or \"friction\", got \"{other}\""
                ))
            }
        }
    }
    Ok(out)
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
    (line, col)
}

#[cfg(test)]
mod tests;
