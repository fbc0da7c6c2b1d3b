//! Effects a scene declares. The engine composes exactly the declared ones: an undeclared
//! effect costs nothing, and a scene with none runs free motion.
//!
//! Two layers:
//! * [`Effect`] is the declaration a scene stores (TOML `[[effect]]` tables, `pmd.Spring(...)`
//!   and friends in Python): plain, comparable, serialisable data that names joints and
//!   bodies but does not know the model yet. Each variant holds a type from its own file
//!   that implements [`Declaration`] (its family, name, parameters, scene-file keys, repr and
//!   how it builds its law); [`registry!`] is the one match that reaches them.
//! * [`ForceLaw`] is the one trait the engine calls. [`Effects::new`] resolves each declaration
//!   against the model (joint names to coordinate slots, tables to their columns) into a
//!   `Box<dyn ForceLaw>` with everything it needs preallocated, so evaluating it allocates
//!   nothing. `simulate/` and the recursions do not change for a new effect.
//!
//! Adding an effect type is one new file here (the declaration, its [`Declaration`], the law,
//! tests' fixtures stay in `tests.rs`) and one line in the [`registry!`] below; the compiler
//! flags a declaration that forgets a method or a variant without its registry line.
//! `docs/adding-an-effect.md` walks through it, with persistence and docs; Python constructs
//! it as `pmd.Effect("foo", **keys)` through `args::effect`, with no binding code.
//!
//! Uniform gravity is a law whose [`ForceLaw::base_acceleration`] the engine puts on the
//! base twist rate `[0; −g]`, so it costs no extra pass. Every other law adds generalized
//! joint forces to `τ` and/or wrenches `[moment about the link origin; force]` (world axes)
//! on the moving links, which the O(n) forward dynamics takes as `external`.
//!
//! Families (the names of the global disable switch, MuJoCo-style): `gravity`, `springs`,
//! `dampers`, `friction`, `torques` (constant, tabulated, PD and callback torques, each
//! optionally clamped at an actuator limit: `torque_limit.rs`), `external`, `contact` (ground
//! contact) and `limits` (joint ranges). All effect parameters are SI with angles in radians,
//! whatever a scene's `angles` key says (that key is about `q0`, `v0` and `rpy`).
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
//! | `torque`           | `joints`, `tau` (number, or one per speed), `limit`         |
//! | `tabulated_torque` | `joints`, `time = [...]`, `values` (list, or rows per time), `limit` |
//! | `pd_torque`        | `joints`, `kp`, `kd`, `time`, `reference` (rows per time), `limit` |
//! | `external`         | `body`, `point`, `frame` ("world"/"body"), `force`, `moment`; with `time`, `force`/`moment` are rows per time |
//! | `point_spring`     | `body_a`, `point_a`, `body_b`, `point_b` (a body name or index, or "world"/-1; each point in its body's frame), `stiffness`, `rest_length` (default 0), `damping` (default 0) |
//! | `ground_contact`   | `points = [[body, [x, y, z]] or [body, [x, y, z], radius], ...]`, `normal` (default [0, 0, 1]), `height` (0), `stiffness` (default: 1 mm static sink under the model's weight), `exponent` (1.5), `damping` (default: critical at that sink), `friction`, `v_eps` (1e-3) |
//! | `joint_limit`      | `joints` (default: every revolute/prismatic joint), `lower`, `upper` (default: the model's limits), `stiffness`, `damping` |
//!
//! A torque's `limit` is one number, one per speed, or `"effort"` (the URDF's `<limit effort>`);
//! a joint limit's missing bounds and a torque's `"effort"` are the model's, filled in when a
//! scene is built ([`fill_model_limits`]).
//!
//! `[simulate] disable = ["gravity", "springs"]` switches families off.
mod accessors;
pub mod args;
mod body_point;
pub mod damper;
pub mod derivatives;
pub mod external;
mod family;
pub mod friction;
pub mod gravity;
pub mod ground_contact;
pub mod joint_limit;
mod law;
pub mod point_spring;
mod scene_file;
pub mod scene_writer;
mod select;
pub mod spring;
pub mod table;
pub mod torque;
pub mod torque_limit;
// The toy effect docs/adding-an-effect.md shows whole (tests/test_guides.py).
#[cfg(test)]
pub mod toy_spring;

use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec3;

pub use accessors::{torque_functions, ContactParameters};
pub use damper::Damper;
pub use external::{External, ExternalLoad, Frame};
pub use family::{Disabled, Kind};
pub use friction::Friction;
pub use gravity::Gravity;
pub use ground_contact::{ContactPoint, GroundContact};
pub use joint_limit::{fill_model_limits, limits_by_link, JointLimit};
pub use law::{Context, Effects, ForceLaw, Probe, RESERVED_LABELS};
pub use point_spring::PointSpring;
pub use scene_file::{required, Fields, Matrix, TomlType};
pub use select::{
    check_values, joints_repr, one_number, resolve_body, resolve_joint_body, resolve_joints,
    JointRef, JointSlot, PerJoint, Sign,
};
pub use spring::Spring;
pub use table::Table;
pub use torque::{Torque, TorqueFunction, TorqueLaw, TorqueSource};
pub use torque_limit::TorqueLimit;

/// A declared effect (see the module docs). Each variant's data lives in its own file;
/// variants are appended (serialisation writes the variant's index).
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
    GroundContact(GroundContact),
    JointLimit(JointLimit),
    #[cfg(test)]
    ToySpring(toy_spring::ToySpring),
}

/// What each declared effect type implements, in its own file. Every method is required, so
/// a new effect cannot forget one; [`Effect`]'s methods reach them through [`registry!`].
pub trait Declaration {
    /// The family a global `disable` switch turns off.
    fn kind(&self) -> Kind;
    /// The name the user gave (the effect's output key), if any.
    fn label(&self) -> Option<&str>;
    /// Resolves the declaration against `model`, with everything the law needs allocated
    /// here, once. Errors name the field at fault (`joints`, `stiffness`, `values`, ...).
    /// The law's derivatives are its [`ForceLaw::add_derivatives`].
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>>;
    /// The parameters [`Declaration::with_parameter`] replaces (empty: none), in the order
    /// error messages list them.
    fn parameters(&self) -> &'static [&'static str];
    /// A copy with parameter `key` (one of [`Declaration::parameters`]) set to `values`,
    /// checked as the constructor checks it (per-run parameters of a batch). A per-joint
    /// parameter takes one value (every joint) or one per joint.
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect>;
    /// How Python shows the declaration (`Spring(joints=all)`), the factory's name first.
    fn repr(&self) -> String;
    /// The `[[effect]]` table that the scene file reads back as an equal declaration
    /// (`scene_writer.rs`); an effect no file can state (a Python-function torque) is an
    /// error naming it.
    fn to_toml(&self) -> Result<toml::Table>;
    /// The scene-file `type`s this declaration reads, with their keys and parsers.
    fn toml_types() -> &'static [TomlType]
    where
        Self: Sized;
}

/// The registry: one line per effect type, `pattern => its declaration; its type`. It
/// writes [`Effect::declaration`] (the one match over the variants: exhaustive, so a new
/// variant without its line does not compile) and the scene file's list of types. A line
/// may carry attributes (the test build's toy effect: `#[cfg(test)]`).
macro_rules! registry {
    ($($(#[$attr:meta])* $pattern:pat => $declaration:expr; $ty:ty),* $(,)?) => {
        impl Effect {
            /// This effect's declaration, whatever its type.
            pub fn declaration(&self) -> &dyn Declaration {
                match self {
                    $($(#[$attr])* $pattern => $declaration,)*
                }
            }
        }

        /// Every scene-file `type`, in the order error messages list them.
        // Pushed one by one: a line's `#[cfg]` applies to a statement, not to an item of
        // `vec![...]`.
        #[allow(clippy::vec_init_then_push)]
        fn all_toml_types() -> impl Iterator<Item = &'static TomlType> + Clone {
            let mut types: Vec<&'static [TomlType]> = Vec::new();
            $($(#[$attr])* types.push(<$ty as Declaration>::toml_types());)*
            types.into_iter().flatten()
        }
    };
}

registry! {
    Effect::Gravity { g } => Gravity::view(g); Gravity,
    Effect::Spring(e) => e; Spring,
    Effect::Damper(e) => e; Damper,
    Effect::Friction(e) => e; Friction,
    Effect::Torque(e) => e; Torque,
    Effect::External(e) => e; External,
    Effect::PointSpring(e) => e; PointSpring,
    Effect::GroundContact(e) => e; GroundContact,
    Effect::JointLimit(e) => e; JointLimit,
    #[cfg(test)]
    Effect::ToySpring(e) => e; toy_spring::ToySpring,
}

impl Effect {
    /// A copy with one parameter replaced, checked as the effect's constructor checks it
    /// (per-run parameters of a batch); each type's [`Declaration::parameters`] lists them.
    pub fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let d = self.declaration();
        let known = d.parameters();
        if !known.contains(&key) {
            let expected = match known {
                [] => format!(
                    "none (a {} effect has no parameter to replace)",
                    self.kind().name()
                ),
                ks => format!(
                    "{} (the parameters of this {} effect)",
                    ks.join(", "),
                    self.kind().name()
                ),
            };
            return Err(Error::arg(
                "parameter",
                expected,
                format!("'{key}' for a {} effect", self.kind().name()),
            ));
        }
        d.with_parameter(key, values)
    }

    pub fn gravity(g: Vec3) -> Result<Effect> {
        Gravity::new(g).map(Effect::from)
    }

    /// The family this effect belongs to (what `disable` switches off).
    pub fn kind(&self) -> Kind {
        self.declaration().kind()
    }

    /// The name the user gave, if any.
    pub fn label(&self) -> Option<&str> {
        self.declaration().label()
    }

    /// The user's name, or the family's.
    pub fn name(&self) -> &str {
        self.label().unwrap_or(self.kind().name())
    }

    /// How Python shows it.
    pub fn repr(&self) -> String {
        self.declaration().repr()
    }

    /// Resolves the declaration against `model` into the law the engine evaluates. Errors
    /// name the field at fault (`joints`, `stiffness`, `values`, ...).
    pub fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        self.declaration().build(model)
    }

    /// The `[[effect]]` table of this effect (`Declaration::to_toml`).
    pub fn to_toml(&self) -> Result<toml::Table> {
        self.declaration().to_toml()
    }

    /// Parses one `[[effect]]` table of a scene file. Errors name the key (without the
    /// `effect[k].` prefix, which the scene adds).
    pub fn from_toml(table: &toml::Table) -> Result<Effect> {
        scene_file::parse(table, all_toml_types())
    }
}

/// `, name='…'` for a named declaration's repr, nothing otherwise.
pub fn label_repr(label: Option<&str>) -> String {
    match label {
        Some(l) => format!(", name='{l}'"),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests;
