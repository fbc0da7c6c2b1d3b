//! Scenes: a model, the effects it calls for, its initial state and integrator settings,
//! read from TOML. Errors name the file and the key.
//!
//! Reading goes in the file's order: the TOML into the structs below, then the units, the
//! URDF (if any), each `[[body]]` ([`bodies`]), `[initial]`, the effects and `[simulate]`.
use std::path::Path;

use serde::Deserialize;

use crate::effects::{Disabled, Effect, Effects};
use crate::model::Model;
use crate::support::error::{Error, FileKind, Location, Result};

mod args;
mod bodies;
mod couplings;
mod loops;
mod write;

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
    /// Integration method (`[simulate] method = "DOP853"`).
    pub method: Option<crate::integrator::Method>,
    /// Fixed step of the methods RK4 and Euler (`[simulate] dt = 1e-3`).
    pub dt: Option<f64>,
}

impl Settings {
    /// Checks the values; errors name the setting (`rtol`, `t_span`, …). Times are finite
    /// and different; tolerances and steps finite and > 0.
    pub fn check(&self) -> Result<()> {
        if let Some((a, b)) = self.t_span {
            if !(a.is_finite() && b.is_finite()) || a == b {
                return Err(Error::arg(
                    "t_span",
                    "two different finite times",
                    format!("[{a}, {b}]"),
                ));
            }
        }
        for (name, x) in [
            ("rtol", self.rtol),
            ("atol", self.atol),
            ("max_step", self.max_step),
            ("first_step", self.first_step),
            ("dt", self.dt),
        ] {
            if let Some(x) = x {
                if x <= 0.0 || !x.is_finite() {
                    return Err(Error::arg(name, "a finite number > 0", x.to_string()));
                }
            }
        }
        Ok(())
    }
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
    /// How the URDF's root link is attached to the world: "fixed" (default) or "free" (a
    /// `FreeFlyer` root joint, as Pinocchio's `JointModelFreeFlyer` root).
    root_joint: Option<String>,
    /// Which of the URDF's `<dynamics>` attributes become effects: "damping" (a damper per
    /// joint) and/or "friction" (regularised Coulomb friction per joint).
    urdf_dynamics: Option<Vec<String>>,
    /// `true`: load the URDF with the default repairs of `Model.from_urdf(..., repair=True)`
    /// (docs/robots.md); the scene is then its author's statement that they are wanted.
    urdf_repair: Option<bool>,
    /// Initial state of the whole model (overrides per-body q0/v0): `q0` (nq values) and
    /// `v0` (nv values), angular entries in the file's units.
    initial: Option<InitialFile>,
    #[serde(default)]
    body: Vec<BodyFile>,
    #[serde(default)]
    effect: Vec<EffectFile>,
    /// Cut joints closing kinematic loops (`loops.rs`).
    #[serde(default, rename = "loop")]
    loops: Vec<loops::LoopFile>,
    /// Joint couplings (`couplings.rs`): `joint`, `reference`, `ratio`, `offset`, `name`.
    #[serde(default)]
    coupling: Vec<toml::Table>,
    /// Rotor inertia by joint or body name (`couplings.rs`).
    armature: Option<toml::Table>,
    simulate: Option<SimulateFile>,
    /// What the model keeps beside its dynamics (`write.rs` writes it): the source file's
    /// joints (names, limits), repairs, visuals and the model's name.
    records: Option<write::RecordsFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InitialFile {
    q0: Option<Vec<f64>>,
    v0: Option<Vec<f64>>,
    /// Bodies whose joint coordinates are held when the loops are closed at load time.
    #[serde(default)]
    fixed: Vec<String>,
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
    /// Rotor inertia of the body's joint: one number or one per speed.
    armature: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(tag = "type", deny_unknown_fields)]
enum JointFile {
    Revolute { axis: [f64; 3] },
    Prismatic { axis: [f64; 3] },
    SphericalZYZ,
    Spherical,
    Fixed,
    FreeFlyer,
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
    /// "RK45" (default), "DOP853", "Radau", "RK4", "Euler" or "auto".
    method: Option<String>,
    /// Fixed step of RK4 and Euler.
    dt: Option<f64>,
}

impl Scene {
    /// Reads and parses a scene file. Only a regular file of at most
    /// [`crate::support::files::MAX_FILE_BYTES`] is read (a FIFO or a device is refused before it is
    /// opened); errors name the path (shortened if too long to show).
    pub fn from_file(path: &Path) -> Result<Scene> {
        let text = crate::support::files::read_text(path, FileKind::Scene)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        Self::parse(&text, &crate::support::files::display_path(path), dir)
    }

    /// Parses a scene from TOML text; `file` names it in errors, and a `urdf` key is resolved
    /// relative to its directory.
    pub fn from_toml(text: &str, file: &str) -> Result<Scene> {
        let dir = Path::new(file).parent().unwrap_or(Path::new(""));
        Self::parse(text, file, dir)
    }

    /// Errors are [`Error::File`] of kind [`FileKind::Scene`], naming the key.
    fn parse(text: &str, file: &str, dir: &Path) -> Result<Scene> {
        let ctx = Ctx { file };
        let sf = read_toml(&ctx, text)?;
        let units = Units::of(&ctx, &sf)?;
        if sf.body.is_empty() && sf.urdf.is_none() {
            return Err(ctx.err("body", "a scene needs at least one [[body]] (or a urdf)"));
        }
        let (mut model, urdf_effects) = urdf_model(&ctx, dir, &sf)?;
        // The URDF's joints (empty without a urdf), read while the model changes.
        let records = model.records.clone();
        let urdf_joints = records.joints.as_slice();
        let mut q0 = model.neutral();
        let mut v0 = vec![0.0; model.nv];
        bodies::add_bodies(&ctx, &mut model, &sf.body, units, &mut q0, &mut v0)?;
        if let Some(r) = sf.records {
            set_records(&ctx, &mut model, r, sf.urdf.is_some())?;
        }
        loops::add_loops(&ctx, &mut model, &sf.loops, units)?;
        couplings::add_couplings(&ctx, &mut model, urdf_joints, &sf.coupling, units)?;
        for (k, b) in sf.body.iter().enumerate() {
            if let (Some(value), Some(index)) = (&b.armature, model.body_index(&b.name)) {
                let key = format!("body[{k}] ('{}').armature", b.name);
                couplings::set_armature(&ctx, &mut model, index, &key, value)?;
            }
        }
        if let Some(table) = &sf.armature {
            couplings::set_armatures(&ctx, &mut model, urdf_joints, table)?;
        }
        if let Some(init) = &sf.initial {
            initial_state(&ctx, &model, init, units, &mut q0, &mut v0)?;
        }
        model.normalize(&mut q0);
        let fixed = sf
            .initial
            .as_ref()
            .map(|i| i.fixed.as_slice())
            .unwrap_or(&[]);
        loops::close_initial_state(&ctx, &model, fixed, &mut q0, &mut v0)?;
        let effects = scene_effects(&ctx, &model, &sf.effect, urdf_effects, urdf_joints)?;
        let settings = match sf.simulate {
            Some(s) => settings(&ctx, s)?,
            None => Settings::default(),
        };
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

/// `[records]` (a written scene's, for a model without a `urdf` key): the joints' names and
/// limits, repairs, visuals and name, checked against the model's bodies and coordinates.
fn set_records(ctx: &Ctx, model: &mut Model, r: write::RecordsFile, urdf: bool) -> Result<()> {
    if urdf {
        return Err(ctx.err(
            "records",
            "only for a scene without a urdf key (a written scene)",
        ));
    }
    model.name = r.model;
    model.records = crate::model::joint_records::JointRecords::new(r.joints, r.repairs);
    model.visuals = r.visuals;
    model
        .check_structure()
        .and_then(|_| model.check_records())
        .map_err(|e| ctx.core("records", e))
}

/// Error builder bound to one scene file.
struct Ctx<'a> {
    file: &'a str,
}

impl Ctx<'_> {
    fn at(&self, key: impl Into<String>) -> Location {
        Location::new(self.file, key)
    }
    /// `file: key: message`.
    fn err(&self, key: impl Into<String>, message: impl Into<String>) -> Error {
        Error::file(FileKind::Scene, self.at(key), message)
    }
    /// A core error met at `key`: `file: key: <its whole text>`.
    fn core(&self, key: impl Into<String>, e: Error) -> Error {
        e.in_file(FileKind::Scene, self.at(key))
    }
    /// A core error whose argument is (the rest of) the key: `file: key.arg: expected ...`.
    fn at_arg(&self, key: impl Into<String>, e: Error) -> Error {
        e.at_arg_in_file(FileKind::Scene, self.at(key))
    }
}

fn read_toml(ctx: &Ctx, text: &str) -> Result<SceneFile> {
    toml::from_str(text).map_err(|e| {
        let (line, col) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
        let message = format!(
            "invalid scene TOML at line {line}, column {col}: {}",
            e.message()
        );
        let at = ctx.at("");
        let at = if line > 0 {
            at.at_line(line).at_column(col)
        } else {
            at
        };
        Error::file(FileKind::Scene, at, message)
    })
}

/// Radians per file unit of angles and of angular rates.
#[derive(Clone, Copy)]
struct Units {
    angle: f64,
    rate: f64,
}

impl Units {
    fn of(ctx: &Ctx, sf: &SceneFile) -> Result<Units> {
        let unit_of = |key: &str, value: Option<&str>, default: f64| match value {
            None => Ok(default),
            Some("radians") => Ok(1.0),
            Some("degrees") => Ok(std::f64::consts::PI / 180.0),
            Some(other) => Err(ctx.err(
                key,
                format!("expected \"radians\" or \"degrees\", got \"{other}\""),
            )),
        };
        let angle = unit_of("angles", sf.angles.as_deref(), 1.0)?;
        let rate = unit_of("rates", sf.rates.as_deref(), angle)?;
        Ok(Units { angle, rate })
    }
}

/// The model the `urdf` key starts (empty without one), the effects its `urdf_dynamics`
/// asks for, and its joints (their `<limit>`s: joint limits without bounds, torques limited
/// at `"effort"`).
#[allow(clippy::type_complexity)]
fn urdf_model(ctx: &Ctx, dir: &Path, sf: &SceneFile) -> Result<(Model, Vec<Effect>)> {
    let Some(rel) = &sf.urdf else {
        if sf.urdf_dynamics.is_some() {
            return Err(ctx.err("urdf_dynamics", "needs a urdf key"));
        }
        if sf.root_joint.is_some() {
            return Err(ctx.err("root_joint", "needs a urdf key"));
        }
        if sf.urdf_repair.is_some() {
            return Err(ctx.err("urdf_repair", "needs a urdf key"));
        }
        return Ok((Model::new(), Vec::new()));
    };
    let root = match sf.root_joint.as_deref() {
        None | Some("fixed") => crate::io::urdf::RootJoint::Fixed,
        Some("free") => crate::io::urdf::RootJoint::Free,
        Some(other) => {
            return Err(ctx.err(
                "root_joint",
                format!("expected \"fixed\" or \"free\", got \"{other}\""),
            ))
        }
    };
    // Its URDF warnings are not reported here.
    let repair = sf
        .urdf_repair
        .unwrap_or(false)
        .then(crate::io::urdf::Repair::default);
    let urdf = crate::io::urdf::load_urdf_with(&dir.join(rel), root, repair.as_ref(), &[])
        .map_err(|e| ctx.core("urdf", e))?;
    let effects = urdf_dynamics_effects(ctx, &urdf, sf.urdf_dynamics.as_deref())?;
    Ok((urdf.model, effects))
}

/// `[initial]`: the whole state (overriding the bodies' `q0`/`v0`), angular coordinates in
/// the file's units.
fn initial_state(
    ctx: &Ctx,
    model: &Model,
    init: &InitialFile,
    units: Units,
    q0: &mut [f64],
    v0: &mut [f64],
) -> Result<()> {
    for (given, target, n, arg) in [
        (&init.q0, &mut *q0, model.nq, "q0"),
        (&init.v0, &mut *v0, model.nv, "v0"),
    ] {
        let Some(given) = given else { continue };
        if given.len() != n {
            return Err(ctx.err(
                format!("initial.{arg}"),
                format!("expected {n} values, got {}", given.len()),
            ));
        }
        target.copy_from_slice(given);
        for l in &model.links {
            let j = &l.joint;
            if arg == "q0" {
                let q = &mut target[l.q_index..l.q_index + j.nq()];
                to_radians(q, |k| j.q_is_angle(k), units.angle);
            } else {
                let v = &mut target[l.v_index..l.v_index + j.nv()];
                to_radians(v, |k| j.v_is_angular(k), units.rate);
            }
        }
    }
    model
        .check_state(q0, Some(v0))
        .map_err(|e| ctx.err("initial", e.to_string()))
}

/// Scales the entries of `values` that are angles (or rates) by `unit`, in place.
fn to_radians(values: &mut [f64], is_angle: impl Fn(usize) -> bool, unit: f64) {
    for (k, x) in values.iter_mut().enumerate() {
        if is_angle(k) {
            *x *= unit;
        }
    }
}

/// The URDF's effects, then each `[[effect]]`, resolved against the model now so that a
/// scene that loads also runs. Errors name `effect[k].field` and say what was expected.
fn scene_effects(
    ctx: &Ctx,
    model: &Model,
    tables: &[EffectFile],
    mut effects: Vec<Effect>,
    urdf_joints: &[crate::io::urdf::UrdfJoint],
) -> Result<Vec<Effect>> {
    let from_urdf = effects.len();
    for (k, e) in tables.iter().enumerate() {
        effects.push(Effect::from_toml(e).map_err(|x| ctx.at_arg(format!("effect[{k}]"), x))?);
    }
    // Joint limits without bounds and torques limited at "effort" take the URDF's (bodies
    // added by [[body]] have none).
    let tabled = &mut effects[from_urdf..];
    crate::effects::fill_model_limits(model, urdf_joints, tabled, "effect")
        .map_err(|x| ctx.at_arg("", x))?;
    Effects::new(model, &effects, Disabled::none(), "effect").map_err(|x| ctx.at_arg("", x))?;
    Ok(effects)
}

/// `[simulate]`: the integrator settings, checked.
fn settings(ctx: &Ctx, s: SimulateFile) -> Result<Settings> {
    let t_span = match (s.t_span, s.t_end) {
        (Some(_), Some(_)) => {
            return Err(ctx.err("simulate.t_end", "give either t_span or t_end, not both"))
        }
        (Some([a, b]), None) => Some((a, b)),
        (None, Some(b)) => Some((0.0, b)),
        (None, None) => None,
    };
    let disable = match &s.disable {
        Some(names) => {
            Some(Disabled::parse(names, "simulate.disable").map_err(|x| ctx.at_arg("", x))?)
        }
        None => None,
    };
    let method = match &s.method {
        Some(name) => Some(crate::integrator::Method::parse(name).ok_or_else(|| {
            ctx.err(
                "simulate.method",
                format!(
                    "expected one of {}, got '{name}'",
                    crate::integrator::Method::NAMES
                ),
            )
        })?),
        None => None,
    };
    let settings = Settings {
        method,
        dt: s.dt,
        t_span,
        rtol: s.rtol,
        atol: s.atol,
        max_step: s.max_step,
        max_steps: s.max_steps,
        first_step: s.first_step,
        disable,
    };
    settings.check().map_err(|e| ctx.at_arg("simulate", e))?;
    Ok(settings)
}

/// Effects from the URDF's `<dynamics damping friction>` as the scene asks: a damper and/or
/// a friction effect over the joints whose value is non-zero (none if all are zero). Errors
/// are at the key `urdf_dynamics`.
fn urdf_dynamics_effects(
    ctx: &Ctx,
    urdf: &crate::io::urdf::Urdf,
    asked: Option<&[String]>,
) -> Result<Vec<Effect>> {
    let core = |e: Error| ctx.core("urdf_dynamics", e);
    use crate::effects::{damper::Damper, friction::Friction, JointRef, PerJoint};
    let mut out = Vec::new();
    for what in asked.unwrap_or(&[]) {
        let pick = |f: fn(&crate::io::urdf::UrdfJoint) -> f64| -> (Vec<JointRef>, Vec<f64>) {
            urdf.joints()
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
                        Damper::new(name, Some(joints), PerJoint::Each(values)).map_err(core)?,
                    ));
                }
            }
            "friction" => {
                let (joints, values) = pick(|j| j.friction);
                if !joints.is_empty() {
                    let name = Some("urdf_friction".to_string());
                    out.push(Effect::Friction(
                        Friction::new(name, Some(joints), PerJoint::Each(values), None)
                            .map_err(core)?,
                    ));
                }
            }
            other => {
                return Err(ctx.err(
                    "urdf_dynamics",
                    format!("expected \"damping\" and/or \"friction\", got \"{other}\""),
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
