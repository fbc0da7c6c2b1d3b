//! Effects a scene declares. The engine composes exactly the declared ones: an undeclared
//! effect costs nothing, and a scene with none runs free motion.
//!
//! Two layers:
//! * [`Effect`] is the declaration a scene stores (TOML `[[effect]]` tables, `pmd.Spring(...)`
//!   and friends in Python): plain, comparable, serialisable data that names joints and
//!   bodies but does not know the model yet. Each variant holds a type from its own file
//!   that implements [`Declaration`] (its family, its name, how it builds its law);
//!   `each_effect!` is the one match that reaches them.
//! * [`ForceLaw`] is the one trait the engine calls. [`Effects::new`] resolves each declaration
//!   against the model (joint names to coordinate slots, tables to their columns) into a
//!   `Box<dyn ForceLaw>` with everything it needs preallocated, so evaluating it allocates
//!   nothing. `simulate/` and the recursions do not change for a new effect.
//!
//! Adding an effect type is a new file here (the declaration and its `Declaration`, the law,
//! `from_toml`, tests), one variant of [`Effect`] (appended), one line in `each_effect!`, a row in
//! `TOML_TYPES`, then persistence, the Python binding, stubs and docs: every step, with the
//! files and functions, is in `docs/adding-an-effect.md`.
//!
//! Uniform gravity is a law whose [`ForceLaw::base_acceleration`] the engine puts on the
//! base twist rate `[0; −g]`, so it costs no extra pass. Every other law adds generalized
//! joint forces to `τ` and/or wrenches `[moment about the link origin; force]` (world axes)
//! on the moving links, which the O(n) forward dynamics takes as `external`.
//!
//! Families (the names of the global disable switch, MuJoCo-style): `gravity`, `springs`,
//! `dampers`, `friction`, `torques` (constant, tabulated, PD and callback torques) and
//! `external`. All effect parameters are SI with angles in radians, whatever a scene's
//! `angles` key says (that key is about `q0`, `v0` and `rpy`).
//!
//! Energy: gravity and springs are conservative ([`ForceLaw::potential_energy`]); for every
//! effect `e` its power is `P_e = τ_e · v`, so along any motion
//! `d(T + V_gravity + V_springs)/dt = Σ_{e non-conservative} P_e`. A point spring with
//! damping `c` has a potential and a power `P_e = −dV_e/dt − c l̇²`: it adds `−c l̇²` there.
//!
//! Scene files: one `[[effect]]` table per effect, `type` selecting it; every type but
//! gravity takes an optional `name` (its output key; default the family's name, numbered
//! `springs_2`, ... from the second on). `joints` is a body name or index or a list of them
//! (omitted: every moving joint); per-joint numbers are one number or a list, one per joint.
//!
//! | type               | keys                                                        |
//! |--------------------|-------------------------------------------------------------|
//! | `gravity`          | `g = [x, y, z]`                                             |
//! | `spring`           | `joints`, `stiffness`, `rest` (number, or coordinates)      |
//! | `damper`           | `joints`, `damping`                                         |
//! | `friction`         | `joints`, `friction`, `v_eps` (default 1e-3)                |
//! | `torque`           | `joints`, `tau` (number, or one per speed)                  |
//! | `tabulated_torque` | `joints`, `time = [...]`, `values` (list, or rows per time) |
//! | `pd_torque`        | `joints`, `kp`, `kd`, `time`, `reference` (rows per time)   |
//! | `external`         | `body`, `point`, `frame` ("world"/"body"), `force`, `moment`; with `time`, `force`/`moment` are rows per time |
//! | `point_spring`     | `body_a`, `point_a`, `body_b`, `point_b` (a body name or index, or "world"/-1; each point in its body's frame), `stiffness`, `rest_length` (default 0), `damping` (default 0) |
//!
//! `[simulate] disable = ["gravity", "springs"]` switches families off.
pub mod damper;
pub mod derivatives;
pub mod external;
pub mod friction;
pub mod gravity;
pub mod point_spring;
pub mod spring;
pub mod table;
pub mod torque;

use crate::error::{check_finite, Error, Result};
use crate::joint::Joint;
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::recursive::{self, Data};
use crate::spatial::{Vec3, Vec6};

pub use damper::Damper;
pub use external::{External, ExternalLoad, Frame};
pub use friction::Friction;
pub use point_spring::PointSpring;
pub use spring::Spring;
pub use table::Table;
pub use torque::{Torque, TorqueFunction, TorqueLaw, TorqueSource};

// ------------------------------------------------------------------------------------------
// Declarations
// ------------------------------------------------------------------------------------------

/// A declared effect (see the module docs). Each variant's data lives in its own file.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Effect {
    /// Uniform gravity `g` (m/s², world frame): `f_ij = m_ij g` on every point mass.
    Gravity {
        g: Vec3,
    },
    Spring(Spring),
    Damper(Damper),
    Friction(Friction),
    Torque(Torque),
    External(External),
    PointSpring(PointSpring),
}

/// What each declared effect type implements, in its own file: the declaration's family,
/// its user-given name and how it resolves against a model into the [`ForceLaw`] the engine
/// evaluates. [`Effect`]'s methods reach these through [`each_effect!`].
pub trait Declaration {
    /// The family a global `disable` switch turns off.
    fn kind(&self) -> Kind;
    /// The name the user gave (the effect's output key), if any.
    fn label(&self) -> Option<&str>;
    /// Resolves the declaration against `model`, with everything the law needs allocated
    /// here, once. Errors name the field at fault (`joints`, `stiffness`, `values`, ...).
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>>;
}

/// The one match over [`Effect`]'s variants: `each_effect!(effect, gravity(g) => a, e => b)`
/// evaluates `a` for gravity (`g`: its `&Vec3`) and `b` for every other variant, with `e`
/// bound to the variant's [`Declaration`]. A new effect type adds its line here.
macro_rules! each_effect {
    ($effect:expr, gravity($g:pat) => $gravity:expr, $e:ident => $each:expr) => {
        match $effect {
            Effect::Gravity { g: $g } => $gravity,
            Effect::Spring($e) => $each,
            Effect::Damper($e) => $each,
            Effect::Friction($e) => $each,
            Effect::Torque($e) => $each,
            Effect::External($e) => $each,
            Effect::PointSpring($e) => $each,
        }
    };
}

impl Effect {
    /// A copy with one parameter replaced, checked as the effect's constructor checks it
    /// (per-run parameters of a batch): gravity `g`; a spring's `stiffness` and `rest`; a
    /// damper's `damping`; friction's `friction` and `v_eps`; a point spring's `stiffness`,
    /// `rest_length` and `damping`; a constant torque's `tau`, a tabulated torque's `values`
    /// (same times), a PD torque's `kp` and `kd`. A per-joint parameter takes one value
    /// (every joint) or one per joint.
    pub fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let per_joint = || match values {
            [x] => PerJoint::All(*x),
            xs => PerJoint::Each(xs.to_vec()),
        };
        let scalar = || match values {
            [x] => Ok(*x),
            xs => Err(Error::arg(
                key,
                "one number",
                format!("{} values", xs.len()),
            )),
        };
        Ok(match (self, key) {
            (Effect::Gravity { .. }, "g") => match values {
                [x, y, z] => Effect::gravity(Vec3::new(*x, *y, *z))?,
                xs => return Err(Error::arg("g", "3 values", format!("{} values", xs.len()))),
            },
            (Effect::Spring(e), "stiffness") => Effect::Spring(Spring::new(
                e.name.clone(),
                e.joints.clone(),
                per_joint(),
                Some(e.rest.clone()),
            )?),
            (Effect::Spring(e), "rest") => Effect::Spring(Spring::new(
                e.name.clone(),
                e.joints.clone(),
                e.stiffness.clone(),
                Some(per_joint()),
            )?),
            (Effect::Damper(e), "damping") => {
                Effect::Damper(Damper::new(e.name.clone(), e.joints.clone(), per_joint())?)
            }
            (Effect::Friction(e), "friction") => Effect::Friction(Friction::new(
                e.name.clone(),
                e.joints.clone(),
                per_joint(),
                Some(e.v_eps),
            )?),
            (Effect::Friction(e), "v_eps") => Effect::Friction(Friction::new(
                e.name.clone(),
                e.joints.clone(),
                e.friction.clone(),
                Some(scalar()?),
            )?),
            (Effect::PointSpring(e), "stiffness" | "rest_length" | "damping") => {
                let x = scalar()?;
                let pick = |k: &str, now: f64| if k == key { x } else { now };
                Effect::PointSpring(PointSpring::new(
                    e.name.clone(),
                    e.body_a.clone(),
                    e.point_a,
                    e.body_b.clone(),
                    e.point_b,
                    pick("stiffness", e.stiffness),
                    pick("rest_length", e.rest_length),
                    pick("damping", e.damping),
                )?)
            }
            (Effect::Torque(e), key) => {
                let law = match (&e.law, key) {
                    (TorqueLaw::Constant(_), "tau") => {
                        return Ok(Effect::Torque(Torque::constant(
                            e.name.clone(),
                            e.joints.clone(),
                            per_joint(),
                        )?))
                    }
                    // The same times, new values (row-major, one row per time).
                    (TorqueLaw::Tabulated(t), "values") => {
                        let (rows, cols) = (t.time().len(), t.cols());
                        if values.len() != rows * cols {
                            return Err(Error::arg(
                                "values",
                                format!("{rows} × {cols} values (the table's times × columns)"),
                                format!("{} values", values.len()),
                            ));
                        }
                        let m = Matrix {
                            values: values.to_vec(),
                            rows,
                            cols,
                            one_d: cols == 1,
                        };
                        TorqueLaw::Tabulated(Table::new(t.time().to_vec(), m, "time", "values")?)
                    }
                    (TorqueLaw::Pd { kp, kd, reference }, "kp" | "kd") => {
                        let (kp, kd) = match key {
                            "kp" => (per_joint(), kd.clone()),
                            _ => (kp.clone(), per_joint()),
                        };
                        return Ok(Effect::Torque(Torque::pd(
                            e.name.clone(),
                            e.joints.clone(),
                            kp,
                            kd,
                            reference.clone(),
                        )?));
                    }
                    _ => {
                        return Err(Error::arg(
                            "parameter",
                            "tau (constant torque), values (tabulated torque), kp or kd (PD torque)",
                            format!("'{key}' for this torque effect"),
                        ))
                    }
                };
                Effect::Torque(Torque {
                    name: e.name.clone(),
                    joints: e.joints.clone(),
                    law,
                })
            }
            (e, key) => {
                return Err(Error::arg(
                    "parameter",
                    "g (gravity), stiffness or rest (spring), damping (damper), friction or v_eps (friction), stiffness, rest_length or damping (point_spring), tau, values, kp or kd (torques)",
                    format!("'{key}' for a {} effect", e.kind().name()),
                ))
            }
        })
    }

    pub fn gravity(g: Vec3) -> Result<Effect> {
        check_finite("gravity", g.as_slice())?;
        Ok(Effect::Gravity { g })
    }

    /// The family this effect belongs to (what `disable` switches off).
    pub fn kind(&self) -> Kind {
        each_effect!(self, gravity(_g) => Kind::Gravity, e => e.kind())
    }

    /// The name the user gave, if any.
    pub fn label(&self) -> Option<&str> {
        each_effect!(self, gravity(_g) => None, e => e.label())
    }

    /// The user's name, or the family's.
    pub fn name(&self) -> &str {
        self.label().unwrap_or(self.kind().name())
    }

    /// Resolves the declaration against `model` into the law the engine evaluates. Errors
    /// name the field at fault (`joints`, `stiffness`, `values`, ...).
    pub fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        each_effect!(
            self,
            gravity(g) => Ok(Box::new(gravity::GravityLaw { g: *g })),
            e => e.build(model)
        )
    }

    /// Parses one `[[effect]]` table of a scene file. Errors name the key (without the
    /// `effect[k].` prefix, which the scene adds).
    pub fn from_toml(table: &toml::Table) -> Result<Effect> {
        let mut f = Fields::new(table);
        let one_of = || {
            let names: Vec<String> = TOML_TYPES.iter().map(|t| format!("\"{}\"", t.0)).collect();
            format!("one of {}", names.join(", "))
        };
        let ty = f
            .string("type")?
            .ok_or_else(|| Error::arg("type", one_of(), "nothing"))?;
        let Some((_, keys, parse)) = TOML_TYPES.iter().find(|t| t.0 == ty) else {
            return Err(Error::arg("type", one_of(), format!("\"{ty}\"")));
        };
        // A misspelt key first: it is usually why a required one is missing.
        f.check_keys(&ty, keys)?;
        parse(&ty, &mut f)
    }
}

/// A scene file's `[[effect]]` parser: `(type, f)` to the declared effect.
type ParseToml = fn(&str, &mut Fields<'_>) -> Result<Effect>;

/// Every `type` of a scene file's `[[effect]]` table, with its keys (besides `type`) and its
/// parser, in the order error messages list them. A new effect type adds a row.
const TOML_TYPES: &[(&str, &[&str], ParseToml)] = &[
    ("gravity", gravity::KEYS, |_, f| gravity::from_toml(f)),
    ("spring", spring::KEYS, |_, f| {
        Ok(Effect::Spring(Spring::from_toml(f)?))
    }),
    ("damper", damper::KEYS, |_, f| {
        Ok(Effect::Damper(Damper::from_toml(f)?))
    }),
    ("friction", friction::KEYS, |_, f| {
        Ok(Effect::Friction(Friction::from_toml(f)?))
    }),
    ("torque", torque::KEYS_CONSTANT, |ty, f| {
        Ok(Effect::Torque(Torque::from_toml(ty, f)?))
    }),
    ("tabulated_torque", torque::KEYS_TABULATED, |ty, f| {
        Ok(Effect::Torque(Torque::from_toml(ty, f)?))
    }),
    ("pd_torque", torque::KEYS_PD, |ty, f| {
        Ok(Effect::Torque(Torque::from_toml(ty, f)?))
    }),
    ("external", external::KEYS, |_, f| {
        Ok(Effect::External(External::from_toml(f)?))
    }),
    ("point_spring", point_spring::KEYS, |_, f| {
        Ok(Effect::PointSpring(PointSpring::from_toml(f)?))
    }),
];

/// Effect families: what a global disable switch turns off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    Gravity,
    Springs,
    Dampers,
    Friction,
    Torques,
    External,
}

impl Kind {
    pub const ALL: [Kind; 6] = [
        Kind::Gravity,
        Kind::Springs,
        Kind::Dampers,
        Kind::Friction,
        Kind::Torques,
        Kind::External,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kind::Gravity => "gravity",
            Kind::Springs => "springs",
            Kind::Dampers => "dampers",
            Kind::Friction => "friction",
            Kind::Torques => "torques",
            Kind::External => "external",
        }
    }

    /// The singular a user may write instead of `name` (the same word when there is none).
    fn singular(self) -> &'static str {
        match self {
            Kind::Springs => "spring",
            Kind::Dampers => "damper",
            Kind::Torques => "torque",
            other => other.name(),
        }
    }

    /// The family named `name` (singular forms accepted: `spring`, `damper`, `torque`).
    pub fn parse(name: &str) -> Option<Kind> {
        Kind::ALL
            .into_iter()
            .find(|k| k.name() == name || k.singular() == name)
    }

    fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// The set of disabled families (empty by default).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Disabled(u8);

impl Disabled {
    pub fn none() -> Self {
        Disabled(0)
    }
    pub fn with(self, kind: Kind) -> Self {
        Disabled(self.0 | kind.bit())
    }
    pub fn contains(self, kind: Kind) -> bool {
        self.0 & kind.bit() != 0
    }
    /// Parses family names; errors name `arg` and list the valid names.
    pub fn parse<S: AsRef<str>>(names: &[S], arg: &str) -> Result<Self> {
        let mut d = Disabled::none();
        for (k, n) in names.iter().enumerate() {
            let n = n.as_ref();
            let kind = Kind::parse(n).ok_or_else(|| {
                let names: Vec<String> = Kind::ALL
                    .iter()
                    .map(|k| format!("\"{}\"", k.name()))
                    .collect();
                Error::arg(
                    format!("{arg}[{k}]"),
                    format!("one of {}", names.join(", ")),
                    format!("\"{n}\""),
                )
            })?;
            d = d.with(kind);
        }
        Ok(d)
    }
    /// The disabled families' names, in `Kind::ALL` order.
    pub fn names(self) -> Vec<&'static str> {
        Kind::ALL
            .iter()
            .filter(|k| self.contains(**k))
            .map(|k| k.name())
            .collect()
    }
}

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
        let b = resolve_body(model, r, arg)?;
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

// ------------------------------------------------------------------------------------------
// The engine's side
// ------------------------------------------------------------------------------------------

/// The state an effect is evaluated at.
#[derive(Clone, Copy)]
pub struct Context<'a> {
    pub model: &'a Model,
    pub t: f64,
    pub q: &'a [f64],
    pub v: &'a [f64],
}

/// One effect, resolved against a model: the only interface the engine knows.
pub trait ForceLaw: Send {
    /// A uniform acceleration field put on the base twist rate (gravity). The engine then
    /// never calls `apply` for this law in the right-hand side. Default: none.
    fn base_acceleration(&self) -> Option<Vec3> {
        None
    }
    /// Whether `apply` may write link wrenches (so the engine zeroes that buffer only then).
    fn writes_wrenches(&self) -> bool {
        false
    }
    /// Adds this effect's generalized joint forces at `cx` to `tau` (length nv) and its link
    /// wrenches `[moment about the link origin; force]` (world axes) to `wrenches`; returns
    /// whether it wrote a wrench. Must not allocate. An `Err` stops the integration.
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String>;
    /// Adds the derivatives of this law's joint forces `τ_e` (the `tau` part of `apply`) to
    /// `dq` (`∂τ_e/∂q`, columns in the tangent space as the dynamics derivatives,
    /// docs/derivatives.md) and `dv` (`∂τ_e/∂v`), both nv × nv; returns whether it did.
    /// `false` (the default) leaves them untouched and the caller differentiates the law's
    /// generalized force numerically (central differences), saying so in its result: external
    /// loads and Python callbacks. Must not allocate.
    fn add_derivatives(
        &mut self,
        _cx: &Context<'_>,
        _dq: &mut nalgebra::DMatrix<f64>,
        _dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        Ok(false)
    }
    /// Potential energy of a conservative effect (`links` holds positions at `cx.q`);
    /// `None` for the others.
    fn potential_energy(&self, _cx: &Context<'_>, _links: &[LinkState]) -> Option<f64> {
        None
    }
}

struct Item {
    label: String,
    kind: Kind,
    law: Box<dyn ForceLaw>,
    /// Evaluated in the right-hand side (false for base-acceleration laws).
    in_rhs: bool,
}

/// Names an effect output may not take (they are keys of the energy dictionary).
pub const RESERVED_LABELS: [&str; 2] = ["kinetic", "total"];

/// The declared, enabled effects of a scene, resolved against its model.
pub struct Effects {
    /// Sum of the enabled uniform gravities (zero when none).
    pub gravity: Vec3,
    items: Vec<Item>,
    rhs_items: usize,
    rhs_wrenches: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            gravity: Vec3::zeros(),
            items: Vec::new(),
            rhs_items: 0,
            rhs_wrenches: false,
        }
    }
}

impl Effects {
    /// No effect at all: free motion.
    pub fn none() -> Self {
        Effects::default()
    }

    /// Resolves `specs` against `model`, leaving out the `disabled` families. Errors name
    /// `{list}[k].field` (`list` is `effects` for Python, `effect` in a scene file).
    pub fn new(model: &Model, specs: &[Effect], disabled: Disabled, list: &str) -> Result<Self> {
        let mut set = Effects::none();
        // Labels: the user's names first (unique, not reserved), then the family names,
        // numbered from the second of a family on (`springs`, `springs_2`, ...).
        let mut labels: Vec<Option<String>> = vec![None; specs.len()];
        for (k, s) in specs.iter().enumerate() {
            if let Some(l) = s.label() {
                let arg = format!("{list}[{k}].name");
                if l.is_empty() || RESERVED_LABELS.contains(&l) {
                    return Err(Error::arg(
                        arg,
                        "a non-empty name other than 'kinetic' and 'total'",
                        format!("'{l}'"),
                    ));
                }
                if labels.iter().flatten().any(|x| x == l) {
                    return Err(Error::arg(
                        arg,
                        "a name no other effect has",
                        format!("'{l}' again"),
                    ));
                }
                labels[k] = Some(l.to_string());
            }
        }
        for (k, s) in specs.iter().enumerate() {
            if labels[k].is_none() {
                let base = s.kind().name();
                let mut n = 1;
                let mut l = base.to_string();
                while labels.iter().flatten().any(|x| *x == l) {
                    n += 1;
                    l = format!("{base}_{n}");
                }
                labels[k] = Some(l);
            }
        }
        for (k, (s, label)) in specs.iter().zip(labels).enumerate() {
            // Resolve even disabled effects, so a scene is valid or not whatever is switched off.
            let law = s
                .build(model)
                .map_err(|e| e.in_arg(&format!("{list}[{k}]")))?;
            if disabled.contains(s.kind()) {
                continue;
            }
            let in_rhs = match law.base_acceleration() {
                Some(g) => {
                    set.gravity += g;
                    false
                }
                None => true,
            };
            if in_rhs {
                set.rhs_items += 1;
                set.rhs_wrenches |= law.writes_wrenches();
            }
            set.items.push(Item {
                label: label.unwrap_or_default(),
                kind: s.kind(),
                law,
                in_rhs,
            });
        }
        Ok(set)
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
    /// Output names of the enabled effects, in declaration order.
    pub fn labels(&self) -> Vec<String> {
        self.items.iter().map(|i| i.label.clone()).collect()
    }
    pub fn kinds(&self) -> Vec<Kind> {
        self.items.iter().map(|i| i.kind).collect()
    }

    /// The right-hand side's composition: overwrites `tau` with the sum of the joint forces
    /// of the enabled effects (gravity excepted: it rides on the base acceleration) and, when
    /// any effect writes wrenches, `wrenches` with theirs; returns whether it wrote wrenches.
    /// With no such effect it touches nothing (`tau` is expected zero then).
    #[inline]
    pub fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        if self.rhs_items == 0 {
            return Ok(false);
        }
        tau.fill(0.0);
        if self.rhs_wrenches {
            wrenches.fill(Vec6::zeros());
        }
        let mut wrote = false;
        for item in self.items.iter_mut().filter(|i| i.in_rhs) {
            wrote |= item.law.apply(cx, tau, wrenches)?;
        }
        Ok(wrote)
    }

    /// Sum of the potential energies (gravity, springs); `links` holds positions at `cx.q`.
    pub fn potential_energy(&self, cx: &Context<'_>, links: &[LinkState]) -> f64 {
        self.items
            .iter()
            .filter_map(|i| i.law.potential_energy(cx, links))
            .sum()
    }

    /// `(label, V)` of every conservative effect.
    pub fn potentials(&self, cx: &Context<'_>, links: &[LinkState]) -> Vec<(String, f64)> {
        self.items
            .iter()
            .filter_map(|i| {
                i.law
                    .potential_energy(cx, links)
                    .map(|v| (i.label.clone(), v))
            })
            .collect()
    }
}

/// Workspace for evaluating effects one by one (per-effect generalized forces and power):
/// wrenches become joint forces through the inverse dynamics at rest, `τ_e = −ID(q, 0, 0)`.
pub struct Probe {
    data: Data,
    zeros: Vec<f64>,
    tau: Vec<f64>,
    id_out: Vec<f64>,
    wrenches: Vec<Vec6>,
}

impl Probe {
    pub fn new(model: &Model) -> Self {
        Probe {
            data: Data::new(model),
            zeros: vec![0.0; model.nv],
            tau: vec![0.0; model.nv],
            id_out: vec![0.0; model.nv],
            wrenches: vec![Vec6::zeros(); model.links.len()],
        }
    }

    /// `ID(q, 0, 0)` into `id_out`: the joint forces that hold the model at rest at `cx.q`
    /// against gravity `g` and, `with_wrenches`, the link wrenches in `wrenches`.
    fn inverse_at_rest(&mut self, cx: &Context<'_>, g: &Vec3, with_wrenches: bool) {
        recursive::inverse_dynamics(
            cx.model,
            &mut self.data,
            cx.q,
            &self.zeros,
            &self.zeros,
            g,
            with_wrenches.then_some(&self.wrenches[..]),
            &mut self.id_out,
        );
    }

    /// Generalized force of each enabled effect at `cx`, row-major `len × nv` into `out`
    /// (gravity's included: `Nᵀ f^G`).
    pub fn forces(
        &mut self,
        effects: &mut Effects,
        cx: &Context<'_>,
        out: &mut [f64],
    ) -> std::result::Result<(), String> {
        let nv = cx.model.nv;
        for (k, item) in effects.items.iter_mut().enumerate() {
            let row = &mut out[k * nv..(k + 1) * nv];
            if let Some(g) = item.law.base_acceleration() {
                self.inverse_at_rest(cx, &g, false);
                for (r, x) in row.iter_mut().zip(&self.id_out) {
                    *r = -x;
                }
                continue;
            }
            self.tau.fill(0.0);
            self.wrenches.fill(Vec6::zeros());
            let wrote = item.law.apply(cx, &mut self.tau, &mut self.wrenches)?;
            row.copy_from_slice(&self.tau);
            if wrote {
                self.inverse_at_rest(cx, &Vec3::zeros(), true);
                for (r, x) in row.iter_mut().zip(&self.id_out) {
                    *r -= x;
                }
            }
        }
        Ok(())
    }
}

// ------------------------------------------------------------------------------------------
// Scene-file fields
// ------------------------------------------------------------------------------------------

/// The keys of one `[[effect]]` table, read with errors that name the key; `check_keys` refuses
/// unknown keys up front.
pub struct Fields<'a> {
    table: &'a toml::Table,
}

/// A key's value that must be given: `value`, or an error naming `key`, what was `expected`
/// and "nothing".
pub fn required<T>(value: Option<T>, key: &str, expected: &str) -> Result<T> {
    value.ok_or_else(|| Error::arg(key, expected, "nothing"))
}

fn toml_got(v: &toml::Value) -> String {
    let s = v.to_string();
    if s.len() > 60 {
        format!(
            "{}...",
            &s[..s.char_indices().nth(57).map(|(i, _)| i).unwrap_or(s.len())]
        )
    } else {
        s
    }
}

fn toml_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

impl<'a> Fields<'a> {
    pub fn new(table: &'a toml::Table) -> Self {
        Fields { table }
    }

    pub fn get(&mut self, key: &'static str) -> Option<&'a toml::Value> {
        self.table.get(key)
    }

    pub fn has(&self, key: &str) -> bool {
        self.table.contains_key(key)
    }

    /// Errors on a key that is not `type` or one of `keys`, listing those.
    pub fn check_keys(&self, ty: &str, keys: &[&str]) -> Result<()> {
        for key in self.table.keys() {
            if key != "type" && !keys.contains(&key.as_str()) {
                return Err(Error::arg(
                    key.as_str(),
                    format!("a key of a \"{ty}\" effect (type, {})", keys.join(", ")),
                    "an unknown key",
                ));
            }
        }
        Ok(())
    }

    /// `key`'s value as `convert` reads it, `None` when the key is absent; an error naming
    /// the key and what was `expected` when `convert` refuses the value.
    fn typed<T>(
        &mut self,
        key: &'static str,
        expected: &str,
        convert: impl Fn(&toml::Value) -> Option<T>,
    ) -> Result<Option<T>> {
        match self.get(key) {
            None => Ok(None),
            Some(v) => convert(v)
                .map(Some)
                .ok_or_else(|| Error::arg(key, expected, toml_got(v))),
        }
    }

    pub fn string(&mut self, key: &'static str) -> Result<Option<String>> {
        self.typed(key, "a string", |v| v.as_str().map(str::to_string))
    }

    pub fn number(&mut self, key: &'static str) -> Result<Option<f64>> {
        self.typed(key, "a number", toml_number)
    }

    pub fn list(&mut self, key: &'static str) -> Result<Option<Vec<f64>>> {
        self.typed(key, "a list of numbers", list_of_numbers)
    }

    pub fn vec3(&mut self, key: &'static str) -> Result<Option<Vec3>> {
        let x = self.typed(key, "a list of 3 numbers", |v| {
            list_of_numbers(v).filter(|x| x.len() == 3)
        })?;
        match x {
            None => Ok(None),
            Some(x) => {
                check_finite(key, &x)?;
                Ok(Some(Vec3::new(x[0], x[1], x[2])))
            }
        }
    }

    /// The `name` and `joints` keys of an effect on joints.
    pub fn name_and_joints(&mut self) -> Result<(Option<String>, Option<Vec<JointRef>>)> {
        Ok((self.string("name")?, self.joints("joints")?))
    }

    /// A number (for all joints) or a list of numbers (one per joint).
    pub fn per_joint(&mut self, key: &'static str) -> Result<Option<PerJoint>> {
        self.typed(key, "a number or a list of numbers", |v| {
            toml_number(v)
                .map(PerJoint::All)
                .or_else(|| list_of_numbers(v).map(PerJoint::Each))
        })
    }

    /// A body name or index, or a list of them.
    pub fn joints(&mut self, key: &'static str) -> Result<Option<Vec<JointRef>>> {
        let one = |v: &toml::Value| -> Option<JointRef> {
            match v {
                toml::Value::String(s) => Some(JointRef::Name(s.clone())),
                toml::Value::Integer(i) if *i >= 0 => Some(JointRef::Index(*i as usize)),
                _ => None,
            }
        };
        self.typed(
            key,
            "a body name or index (>= 0), or a list of them",
            |v| match v {
                toml::Value::Array(a) => a.iter().map(one).collect(),
                _ => one(v).map(|r| vec![r]),
            },
        )
    }

    /// A table of numbers: a list (one column) or a list of equal-length rows. Returns
    /// `(values row-major, rows, cols, given as one list)`.
    pub fn matrix(&mut self, key: &'static str) -> Result<Option<Matrix>> {
        match self.get(key) {
            None => Ok(None),
            Some(v) => {
                if let Some(x) = list_of_numbers(v) {
                    let n = x.len();
                    return Ok(Some(Matrix {
                        values: x,
                        rows: n,
                        cols: 1,
                        one_d: true,
                    }));
                }
                let bad = || {
                    Error::arg(
                        key,
                        "a list of numbers or a list of rows of numbers",
                        toml_got(v),
                    )
                };
                let toml::Value::Array(rows) = v else {
                    return Err(bad());
                };
                let mut values = Vec::new();
                let mut cols = None;
                for (i, r) in rows.iter().enumerate() {
                    let row = list_of_numbers(r).ok_or_else(bad)?;
                    match cols {
                        None => cols = Some(row.len()),
                        Some(c) if c != row.len() => {
                            return Err(Error::arg(
                                key,
                                format!("rows of equal length ({c})"),
                                format!("row {i} of length {}", row.len()),
                            ))
                        }
                        _ => {}
                    }
                    values.extend(row);
                }
                Ok(Some(Matrix {
                    values,
                    rows: rows.len(),
                    cols: cols.unwrap_or(0),
                    one_d: false,
                }))
            }
        }
    }
}

fn list_of_numbers(v: &toml::Value) -> Option<Vec<f64>> {
    match v {
        toml::Value::Array(a) => a.iter().map(toml_number).collect(),
        _ => None,
    }
}

/// A numeric table as given (row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct Matrix {
    pub values: Vec<f64>,
    pub rows: usize,
    pub cols: usize,
    /// Given as a flat list (shape `(rows,)`).
    pub one_d: bool,
}

impl Matrix {
    pub fn shape(&self) -> String {
        if self.one_d {
            format!("shape ({},)", self.rows)
        } else {
            format!("shape ({}, {})", self.rows, self.cols)
        }
    }
}

#[cfg(test)]
mod tests;
