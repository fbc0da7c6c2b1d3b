//! Joint torques (forces on prismatic joints), the `torques` family:
//! * constant: `τ = τ_0` on the selected joints' speeds;
//! * tabulated in time: linear interpolation between rows, the end rows held outside;
//! * a PD law tracking a tabulated reference on 1-dof joints:
//!   `τ = kp (q_ref(t) − q) + kd (q̇_ref(t) − v)`, with `q̇_ref` the slope of the table's
//!   segment (right-continuous at breakpoints, zero outside the table);
//! * a function `f(t, q, v) → τ` (length nv), e.g. a Python callable.
use super::scene_writer as w;
use std::any::Any;
use std::sync::Arc;

use super::table::Table;
use super::torque_limit::{Saturated, TorqueLimit};
use super::{joints_repr, label_repr, Effect, TomlType};
use super::{
    required, resolve_joints, Context, Declaration, Fields, ForceLaw, JointRef, JointSlot, Kind,
    Matrix, PerJoint, Sign,
};
use crate::joint::Joint;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec6;

/// A torque callback: `f(t, q, v, out)` writes all `nv` generalized forces into `out`.
pub type TorqueFn =
    dyn Fn(f64, &[f64], &[f64], &mut [f64]) -> std::result::Result<(), String> + Send + Sync;

/// What a torque callback was made from (e.g. a Python callable), kept beside the closure so
/// a serialised scene can carry it; the core never looks inside.
pub type TorqueSource = Arc<dyn Any + Send + Sync>;

/// A shared torque callback (equal only to itself), with the object it was made from, if any.
///
/// Serialisation writes no data for it: whoever serialises a scene carries the sources beside
/// the bytes (the Python bindings pickle them as objects, in effect order) and replaces each
/// deserialised function, a placeholder that fails when called, with one rebuilt from its
/// source. A function without a source (a Rust closure) cannot be serialised.
#[derive(Clone)]
pub struct TorqueFunction(pub Arc<TorqueFn>, pub Option<TorqueSource>);

impl TorqueFunction {
    /// A callback without a source (it cannot be serialised).
    pub fn new(f: Arc<TorqueFn>) -> Self {
        TorqueFunction(f, None)
    }

    /// A callback made from `source`, which serialisation carries beside the bytes.
    pub fn with_source(f: Arc<TorqueFn>, source: TorqueSource) -> Self {
        TorqueFunction(f, Some(source))
    }

    /// The object this callback was made from, if it was given.
    pub fn source(&self) -> Option<&TorqueSource> {
        self.1.as_ref()
    }

    /// What deserialisation returns until the caller restores the callback from its source.
    pub fn unrestored() -> Self {
        TorqueFunction::new(Arc::new(|_, _, _, _| {
            Err("this torque function was deserialised without its callable: restore it from the source serialised beside the data".to_string())
        }))
    }
}

impl std::fmt::Debug for TorqueFunction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "TorqueFunction({:p})", Arc::as_ptr(&self.0))
    }
}

impl serde::Serialize for TorqueFunction {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        if self.1.is_none() {
            return Err(serde::ser::Error::custom(
                "a torque function without a source (a Rust closure) cannot be serialised",
            ));
        }
        s.serialize_unit_struct("TorqueFunction")
    }
}

impl<'de> serde::Deserialize<'de> for TorqueFunction {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Unit;
        impl serde::de::Visitor<'_> for Unit {
            type Value = ();
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a torque function marker (unit)")
            }
            fn visit_unit<E: serde::de::Error>(self) -> std::result::Result<(), E> {
                Ok(())
            }
        }
        d.deserialize_unit_struct("TorqueFunction", Unit)?;
        Ok(TorqueFunction::unrestored())
    }
}

impl PartialEq for TorqueFunction {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum TorqueLaw {
    /// One number for every speed of the selected joints, or one per speed.
    Constant(PerJoint),
    /// One column per speed of the selected joints, in order.
    Tabulated(Table),
    /// 1-dof joints only; the reference has one column per selected joint.
    Pd {
        kp: PerJoint,
        kd: PerJoint,
        reference: Table,
    },
    /// All `nv` generalized forces from a function; acts on every joint (`joints` is None).
    Function(TorqueFunction),
}

/// Keys of `type = "torque"`, `"tabulated_torque"` and `"pd_torque"` tables.
const KEYS_CONSTANT: &[&str] = &["name", "joints", "tau", "limit"];
const KEYS_TABULATED: &[&str] = &["name", "joints", "time", "values", "limit"];
const KEYS_PD: &[&str] = &["name", "joints", "kp", "kd", "time", "reference", "limit"];

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Torque {
    pub name: Option<String>,
    /// `None`: every moving joint.
    pub joints: Option<Vec<JointRef>>,
    pub law: TorqueLaw,
    /// Actuator limits: the output clamped per speed (`torque_limit.rs`); `None`: unlimited.
    pub limit: Option<TorqueLimit>,
}

impl Torque {
    pub fn constant(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        tau: PerJoint,
    ) -> Result<Torque> {
        tau.check("tau", Sign::Any)?;
        Ok(Torque {
            name,
            joints,
            law: TorqueLaw::Constant(tau),
            limit: None,
        })
    }

    pub fn tabulated(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        table: Table,
    ) -> Result<Torque> {
        Ok(Torque {
            name,
            joints,
            law: TorqueLaw::Tabulated(table),
            limit: None,
        })
    }

    pub fn pd(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        kp: PerJoint,
        kd: PerJoint,
        reference: Table,
    ) -> Result<Torque> {
        kp.check("kp", Sign::NonNegative)?;
        kd.check("kd", Sign::NonNegative)?;
        Ok(Torque {
            name,
            joints,
            law: TorqueLaw::Pd { kp, kd, reference },
            limit: None,
        })
    }

    pub fn function(name: Option<String>, f: TorqueFunction) -> Torque {
        Torque {
            name,
            joints: None,
            law: TorqueLaw::Function(f),
            limit: None,
        }
    }

    /// The same torques clamped at `limit` per speed.
    pub fn with_limit(mut self, limit: Option<TorqueLimit>) -> Torque {
        self.limit = limit;
        self
    }

    /// The speeds this torque drives, in order (every speed for a function).
    fn speeds(&self, model: &Model) -> Result<Vec<usize>> {
        Ok(match &self.law {
            TorqueLaw::Function(_) => (0..model.nv).collect(),
            _ => resolve_joints(model, &self.joints, "joints")?
                .iter()
                .flat_map(JointSlot::speeds)
                .collect(),
        })
    }

    /// The limit on each of the model's `nv` speeds (inf where unlimited or not driven).
    pub fn limit_per_speed(&self, model: &Model) -> Result<Vec<f64>> {
        let mut out = vec![f64::INFINITY; model.nv];
        let Some(TorqueLimit::Given(limit)) = &self.limit else {
            return Ok(out);
        };
        let speeds = self.speeds(model)?;
        let values = limit.expand(speeds.len(), "limit", "speed of the selected joints")?;
        for (s, l) in speeds.into_iter().zip(values) {
            out[s] = l;
        }
        Ok(out)
    }

    /// A copy whose `Effort` limit is the model's: `effort(link)` of each driven joint (inf
    /// where the file gives none), one value per speed.
    pub fn with_model_effort(
        &self,
        model: &Model,
        effort: impl Fn(usize) -> f64,
    ) -> Result<Torque> {
        if self.limit != Some(TorqueLimit::Effort) {
            return Ok(self.clone());
        }
        let values = match &self.law {
            TorqueLaw::Function(_) => model
                .links
                .iter()
                .enumerate()
                .flat_map(|(i, l)| std::iter::repeat_n(effort(i), l.joint.nv()))
                .collect(),
            _ => resolve_joints(model, &self.joints, "joints")?
                .iter()
                .flat_map(|s| std::iter::repeat_n(effort(s.link), s.joint.nv()))
                .collect(),
        };
        let mut out = self.clone();
        out.limit = Some(TorqueLimit::Given(PerJoint::Each(values)));
        Ok(out)
    }

    pub(super) fn from_toml(ty: &str, f: &mut Fields<'_>) -> Result<Torque> {
        let limit = match f.get("limit") {
            None => None,
            Some(toml::Value::String(s)) if s == "effort" => Some(TorqueLimit::Effort),
            Some(_) => match f.per_joint("limit")? {
                Some(l) => Some(TorqueLimit::given(l)?),
                None => None,
            },
        };
        Ok(Self::from_toml_unlimited(ty, f)?.with_limit(limit))
    }

    fn from_toml_unlimited(ty: &str, f: &mut Fields<'_>) -> Result<Torque> {
        let (name, joints) = f.name_and_joints()?;
        let times = "a list of increasing times";
        match ty {
            "torque" => {
                let tau = f.per_joint("tau")?;
                let tau = required(tau, "tau", "a number or one per joint speed")?;
                Torque::constant(name, joints, tau)
            }
            "tabulated_torque" => {
                let time = f.list("time")?;
                let values = f.matrix("values")?;
                let time = required(time, "time", times)?;
                let values = required(
                    values,
                    "values",
                    "one row per time, one column per joint speed",
                )?;
                Torque::tabulated(name, joints, Table::new(time, values, "time", "values")?)
            }
            _ => {
                let kp = f.per_joint("kp")?;
                let kd = f.per_joint("kd")?;
                let time = f.list("time")?;
                let reference = f.matrix("reference")?;
                let kp = required(kp, "kp", "a number >= 0 or one per joint")?;
                let kd = required(kd, "kd", "a number >= 0 or one per joint")?;
                let time = required(time, "time", times)?;
                let reference = required(
                    reference,
                    "reference",
                    "one row per time, one column per joint",
                )?;
                let table = Table::new(time, reference, "time", "reference")?;
                Torque::pd(name, joints, kp, kd, table)
            }
        }
    }
}

impl Declaration for Torque {
    fn to_toml(&self) -> Result<toml::Table> {
        let name = self.label();
        let t = match &self.law {
            TorqueLaw::Constant(tau) => w::EffectTable::new("torque", name)
                .joints(&self.joints)
                .set("tau", w::per_joint(tau)),
            TorqueLaw::Tabulated(table) => w::table(
                w::EffectTable::new("tabulated_torque", name).joints(&self.joints),
                table,
                "values",
            ),
            TorqueLaw::Pd { kp, kd, reference } => w::table(
                w::EffectTable::new("pd_torque", name)
                    .joints(&self.joints)
                    .set("kp", w::per_joint(kp))
                    .set("kd", w::per_joint(kd)),
                reference,
                "reference",
            ),
            TorqueLaw::Function(_) => {
                return Err(Error::arg(
                    "effect",
                    "effects a scene file can state (a torque function is Python code: give a table or a PD torque, or save the scene with pickle)",
                    format!("the torque function '{}'", self.label().unwrap_or("torques")),
                ))
            }
        };
        let limit = match &self.limit {
            None => None,
            Some(TorqueLimit::Given(l)) => Some(w::per_joint(l)),
            Some(TorqueLimit::Effort) => Some(toml::Value::String("effort".into())),
        };
        Ok(t.maybe("limit", limit).done())
    }
    fn parameters(&self) -> &'static [&'static str] {
        match self.law {
            TorqueLaw::Constant(_) => &["tau"],
            TorqueLaw::Tabulated(_) => &["values"],
            TorqueLaw::Pd { .. } => &["kp", "kd"],
            TorqueLaw::Function(_) => &[],
        }
    }
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let (name, joints) = (self.name.clone(), self.joints.clone());
        let e = match (&self.law, key) {
            (TorqueLaw::Tabulated(t), _) => {
                Torque::tabulated(name, joints, t.with_values(values)?)?
            }
            (TorqueLaw::Pd { kp, kd, reference }, _) => {
                let (kp, kd) = match key {
                    "kp" => (PerJoint::from_values(values), kd.clone()),
                    _ => (kp.clone(), PerJoint::from_values(values)),
                };
                Torque::pd(name, joints, kp, kd, reference.clone())?
            }
            // Constant (`tau`; a function has no parameter, `Effect::with_parameter` says so).
            _ => Torque::constant(name, joints, PerJoint::from_values(values))?,
        };
        Ok(Effect::Torque(e.with_limit(self.limit.clone())))
    }
    fn repr(&self) -> String {
        let label = match &self.limit {
            None => label_repr(self.label()),
            Some(TorqueLimit::Effort) => format!(", limit='effort'{}", label_repr(self.label())),
            Some(TorqueLimit::Given(_)) => format!(", limited{}", label_repr(self.label())),
        };
        let joints = joints_repr(&self.joints);
        match &self.law {
            TorqueLaw::Constant(_) => format!("JointTorque(joints={joints}{label})"),
            TorqueLaw::Tabulated(t) => {
                format!("TabulatedTorque(joints={joints}, {} rows{label})", t.len())
            }
            TorqueLaw::Pd { reference, .. } => {
                format!("PDTorque(joints={joints}, {} rows{label})", reference.len())
            }
            TorqueLaw::Function(_) => format!("TorqueFunction({})", label.trim_start_matches(", ")),
        }
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[
            TomlType {
                name: "torque",
                keys: KEYS_CONSTANT,
                parse: |ty, f| Torque::from_toml(ty, f).map(Effect::Torque),
            },
            TomlType {
                name: "tabulated_torque",
                keys: KEYS_TABULATED,
                parse: |ty, f| Torque::from_toml(ty, f).map(Effect::Torque),
            },
            TomlType {
                name: "pd_torque",
                keys: KEYS_PD,
                parse: |ty, f| Torque::from_toml(ty, f).map(Effect::Torque),
            },
        ];
        TYPES
    }
    fn kind(&self) -> Kind {
        Kind::Torques
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let law = self.build_unlimited(model)?;
        match &self.limit {
            None => Ok(law),
            Some(TorqueLimit::Given(_)) => {
                let per_speed = self.limit_per_speed(model)?;
                Ok(Box::new(Saturated::new(law, &per_speed)))
            }
            Some(TorqueLimit::Effort) => Err(Error::arg(
                "limit",
                "numbers, or 'effort' with a model that has joint efforts (from_urdf)",
                "'effort' without the model's efforts",
            )),
        }
    }
}

impl Torque {
    fn build_unlimited(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        if let TorqueLaw::Function(f) = &self.law {
            if self.joints.is_some() {
                return Err(Error::arg(
                    "joints",
                    "None for a torque function (it returns all nv generalized forces)",
                    "a selection",
                ));
            }
            return Ok(Box::new(FunctionLaw {
                f: f.clone(),
                out: vec![0.0; model.nv],
            }));
        }
        let slots = resolve_joints(model, &self.joints, "joints")?;
        let dofs: Vec<usize> = slots.iter().flat_map(JointSlot::speeds).collect();
        let names = || {
            slots
                .iter()
                .map(|s| format!("'{}'", s.name))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match &self.law {
            TorqueLaw::Constant(tau) => {
                let tau = tau.expand(dofs.len(), "tau", "speed of the selected joints")?;
                Ok(Box::new(ConstantLaw {
                    dofs: dofs.into_iter().zip(tau).collect(),
                }))
            }
            TorqueLaw::Tabulated(table) => {
                if table.cols() != dofs.len() {
                    return Err(Error::arg(
                        "values",
                        format!(
                            "shape ({}, {}): one column per speed of the selected joints ({})",
                            table.len(),
                            dofs.len(),
                            names()
                        ),
                        table.shape(),
                    ));
                }
                Ok(Box::new(TableLaw {
                    row: vec![0.0; dofs.len()],
                    dofs,
                    table: table.clone(),
                    hint: 0,
                }))
            }
            TorqueLaw::Pd { kp, kd, reference } => {
                one_dof_only(&slots)?;
                let n = slots.len();
                if reference.cols() != n {
                    return Err(Error::arg(
                        "reference",
                        format!(
                            "shape ({}, {n}): one column per selected joint ({})",
                            reference.len(),
                            names()
                        ),
                        reference.shape(),
                    ));
                }
                let kp = kp.expand(n, "kp", "joint")?;
                let kd = kd.expand(n, "kd", "joint")?;
                Ok(Box::new(PdLaw {
                    joints: slots
                        .iter()
                        .zip(kp.into_iter().zip(kd))
                        .map(|(s, (kp, kd))| (s.q_index, s.v_index, kp, kd))
                        .collect(),
                    table: reference.clone(),
                    hint: 0,
                    r: vec![0.0; n],
                    rd: vec![0.0; n],
                    held: false,
                }))
            }
            TorqueLaw::Function(_) => unreachable!("handled above"),
        }
    }
}

fn one_dof_only(slots: &[JointSlot]) -> Result<()> {
    match slots
        .iter()
        .find(|s| !matches!(s.joint, Joint::Revolute { .. } | Joint::Prismatic { .. }))
    {
        None => Ok(()),
        Some(s) => Err(Error::arg(
            "joints",
            "revolute or prismatic joints for a PD torque",
            format!("body '{}' on a {} joint", s.name, s.joint.kind()),
        )),
    }
}

/// A `Matrix` from a flat column (Python and tests build tables this way).
pub fn column(values: Vec<f64>) -> Matrix {
    let n = values.len();
    Matrix {
        values,
        rows: n,
        cols: 1,
        one_d: true,
    }
}

struct ConstantLaw {
    dofs: Vec<(usize, f64)>,
}

impl ForceLaw for ConstantLaw {
    #[inline]
    fn apply(
        &mut self,
        _cx: &Context<'_>,
        tau: &mut [f64],
        _w: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        for &(i, x) in &self.dofs {
            tau[i] += x;
        }
        Ok(false)
    }

    /// Independent of the state.
    fn add_derivatives(
        &mut self,
        _cx: &Context<'_>,
        _dq: &mut nalgebra::DMatrix<f64>,
        _dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        Ok(true)
    }
}

struct TableLaw {
    dofs: Vec<usize>,
    table: Table,
    hint: usize,
    row: Vec<f64>,
}

impl ForceLaw for TableLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _w: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        self.table.eval(cx.t, &mut self.hint, &mut self.row);
        for (&i, x) in self.dofs.iter().zip(&self.row) {
            tau[i] += x;
        }
        Ok(false)
    }

    /// A function of time only.
    fn add_derivatives(
        &mut self,
        _cx: &Context<'_>,
        _dq: &mut nalgebra::DMatrix<f64>,
        _dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        Ok(true)
    }
}

struct PdLaw {
    /// (q index, v index, kp, kd)
    joints: Vec<(usize, usize, f64, f64)>,
    table: Table,
    hint: usize,
    r: Vec<f64>,
    rd: Vec<f64>,
    /// A stepping simulator's target, held instead of the table (`ForceLaw::hold_reference`).
    held: bool,
}

impl ForceLaw for PdLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _w: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        if !self.held {
            self.table
                .eval_with_slope(cx.t, &mut self.hint, &mut self.r, &mut self.rd);
        }
        for (k, &(iq, iv, kp, kd)) in self.joints.iter().enumerate() {
            tau[iv] += kp * (self.r[k] - cx.q[iq]) + kd * (self.rd[k] - cx.v[iv]);
        }
        Ok(false)
    }

    fn reference_joints(&self) -> usize {
        self.joints.len()
    }

    /// The target into `r` (the table is not read while held), a zero rate into `rd`.
    fn hold_reference(&mut self, target: Option<&[f64]>) {
        self.held = target.is_some();
        if let Some(t) = target.filter(|t| t.len() == self.r.len()) {
            self.r.copy_from_slice(t);
            self.rd.fill(0.0);
        }
    }

    /// `−kp` and `−kd` on each joint's diagonal (one-speed joints: the tangent is the
    /// coordinate).
    fn add_derivatives(
        &mut self,
        _cx: &Context<'_>,
        dq: &mut nalgebra::DMatrix<f64>,
        dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        for &(_, iv, kp, kd) in &self.joints {
            dq[(iv, iv)] -= kp;
            dv[(iv, iv)] -= kd;
        }
        Ok(true)
    }
}

struct FunctionLaw {
    f: TorqueFunction,
    out: Vec<f64>,
}

impl ForceLaw for FunctionLaw {
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _w: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        self.out.fill(0.0);
        (self.f.0)(cx.t, cx.q, cx.v, &mut self.out)?;
        // A non-finite torque fails the run like any effect's (`success=False` with the time),
        // whichever binding's callback gave it.
        crate::support::error::check_finite("torque function f(t, q, v)", &self.out)
            .map_err(|e| e.to_string())?;
        for (t, x) in tau.iter_mut().zip(&self.out) {
            *t += x;
        }
        Ok(false)
    }
}
