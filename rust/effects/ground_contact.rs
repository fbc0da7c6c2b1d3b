//! Compliant ground contact, family `contact`: points fixed in bodies against a plane
//! `n · x = h` (unit normal `n` pointing out of the ground). With the penetration
//! `δ = h − n · p` and its rate `δ̇ = −n · ṗ`, each point with `δ > 0` feels
//!
//! * the Hunt–Crossley normal force `F_n = max(0, k δᵉ + c δᵉ δ̇)` along `n`: elastic
//!   `k δᵉ` (Hertz: `e = 3/2` for a sphere), damping proportional to the penetration so the
//!   force starts at zero on touch-down, and never pulling (the `max`);
//! * regularised Coulomb friction `F_t = −μ F_n tanh(|v_t| / v_eps) v_t / |v_t|` on the
//!   tangential velocity `v_t = ṗ − (n · ṗ) n`: viscous with slope `μ F_n / v_eps` below
//!   `v_eps` (smooth, no stick-slip switching), `μ F_n` when sliding.
//!
//! Generalized forces `τ = Σ Jᵀ f` through each point's Jacobian along its body's path
//! (`body_point::PointSet`: the points' paths walked once per evaluation, a point's columns
//! built only while it touches): no link wrench, O(depth) per point.
//! The elastic part has the potential `V = k δ^(e+1) / (e + 1)` (in `energies`); the power
//! is `−dV/dt − c δᵉ δ̇² + F_t · v_t ≤ −dV/dt` (with the `max` active too): contact never
//! adds energy. The derivatives are analytic (`add_derivatives`), which Radau needs: a
//! stiff contact makes a scene stiff.
use super::body_point::{add_force, velocity, PointSet};
use super::scene_writer as w;
use super::{label_repr, one_number, Effect, TomlType};
use super::{required, Context, Declaration, Fields, ForceLaw, JointRef, Kind};
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::array::Array;
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::{angular, Mat3, Vec3, Vec6};

/// Keys of a `type = "ground_contact"` table.
const KEYS: &[&str] = &[
    "name",
    "points",
    "normal",
    "height",
    "stiffness",
    "exponent",
    "damping",
    "friction",
    "v_eps",
];

/// Default Hunt–Crossley exponent (Hertz contact of a sphere).
pub const DEFAULT_EXPONENT: f64 = 1.5;
/// Default friction regularisation speed (m/s).
pub const DEFAULT_V_EPS: f64 = 1e-3;
/// The static sink the default stiffness gives (m): the model at rest, its weight shared
/// equally by the points, sinks 1 mm at each ([`GroundContact::resolved`]).
pub const DEFAULT_SINK: f64 = 1e-3;
/// The gravity the defaults weigh the model with (m/s², the library's `Gravity()`), whatever
/// gravity the scene declares: the defaults depend on the model and the points only.
pub const DEFAULT_GRAVITY: f64 = 9.81;

/// A point fixed in a body, in the body's frame; with a radius it is the centre of a
/// sphere, which touches the plane when the centre is `radius` above it (exact for a sphere
/// on a plane, whatever its orientation).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactPoint {
    pub body: JointRef,
    pub point: Vec3,
    /// m, ≥ 0.
    pub radius: f64,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GroundContact {
    pub name: Option<String>,
    pub points: Vec<ContactPoint>,
    /// Unit normal of the plane, out of the ground (world frame).
    pub normal: Vec3,
    /// The plane's offset along `normal`: it holds the points `x` with `n · x = height`.
    pub height: f64,
    /// `k` > 0, N/mᵉ; `None`: the default from the model's weight, filled in when a scene
    /// is built ([`GroundContact::resolved`]).
    #[serde(with = "nan_is_none")]
    pub stiffness: Option<f64>,
    /// `e` ≥ 1.
    pub exponent: f64,
    /// `c` ≥ 0, N·s/m^(e+1); `None`: the default (critical damping at the static sink).
    #[serde(with = "nan_is_none")]
    pub damping: Option<f64>,
    /// `μ` ≥ 0.
    pub friction: f64,
    /// > 0, m/s.
    pub v_eps: f64,
}

/// A parameter that may wait for its default, serialised as a plain number with NaN for
/// `None` (no given value is NaN): the pickle format (`crate::io::persist`) keeps its layout.
mod nan_is_none {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(x.unwrap_or(f64::NAN))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        let x = f64::deserialize(d)?;
        Ok((!x.is_nan()).then_some(x))
    }
}

/// The largest contact offset, radius and plane height (m): a thousand kilometres, beyond
/// any mechanism; at 1e300 the penetration overflows at run time.
pub const MAX_LENGTH: f64 = 1e6;

impl GroundContact {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: Option<String>,
        points: Vec<ContactPoint>,
        normal: Vec3,
        height: f64,
        stiffness: Option<f64>,
        exponent: f64,
        damping: Option<f64>,
        friction: f64,
        v_eps: f64,
    ) -> Result<GroundContact> {
        if points.is_empty() {
            return Err(Error::arg(
                "points",
                "at least one (body, [x, y, z]) point",
                "an empty list",
            ));
        }
        for (k, p) in points.iter().enumerate() {
            check_finite(&format!("points[{k}]"), p.point.as_slice())?;
            if let Some(x) = p.point.iter().find(|x| x.abs() > MAX_LENGTH) {
                return Err(Error::arg(
                    format!("points[{k}]"),
                    format!("an offset within ±{MAX_LENGTH:e} m of its body's origin"),
                    crate::support::error::num(*x),
                ));
            }
            if !(p.radius.is_finite() && (0.0..=MAX_LENGTH).contains(&p.radius)) {
                return Err(Error::arg(
                    format!("points[{k}]"),
                    format!("a radius that is a number in [0, {MAX_LENGTH:e}] m"),
                    crate::support::error::num(p.radius),
                ));
            }
        }
        check_finite("normal", normal.as_slice())?;
        let n = normal.norm();
        if !(n > 1e-12) {
            return Err(Error::arg(
                "normal",
                "a non-zero 3-vector",
                format!("[{}, {}, {}]", normal.x, normal.y, normal.z),
            ));
        }
        check_finite("height", &[height])?;
        if height.abs() > MAX_LENGTH {
            return Err(Error::arg(
                "height",
                format!("a plane within ±{MAX_LENGTH:e} m of the origin"),
                crate::support::error::num(height),
            ));
        }
        let positive = |arg: &str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(Error::arg(
                    arg,
                    "a finite number > 0",
                    crate::support::error::num(x),
                ))
            }
        };
        let non_negative = |arg: &str, x: f64| {
            if x.is_finite() && x >= 0.0 {
                Ok(())
            } else {
                Err(Error::arg(
                    arg,
                    "a finite number >= 0",
                    crate::support::error::num(x),
                ))
            }
        };
        if let Some(k) = stiffness {
            positive("stiffness", k)?;
        }
        if let Some(c) = damping {
            non_negative("damping", c)?;
        }
        non_negative("friction", friction)?;
        if !(exponent.is_finite() && exponent >= 1.0) {
            return Err(Error::arg(
                "exponent",
                "a finite number >= 1 (1: linear, 1.5: Hertz)",
                exponent.to_string(),
            ));
        }
        // The law divides by v_eps: a subnormal one would make 0 · inf = NaN.
        if !(v_eps > 0.0 && v_eps.is_finite() && (1.0 / v_eps).is_finite()) {
            return Err(Error::arg(
                "v_eps",
                "a finite number > 0 whose reciprocal is finite",
                format!("{v_eps:e}"),
            ));
        }
        Ok(GroundContact {
            name,
            points,
            normal: normal / n,
            height,
            stiffness,
            exponent,
            damping,
            friction,
            v_eps,
        })
    }

    pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<GroundContact> {
        let name = f.string("name")?;
        let points = match f.get("points") {
            None => None,
            Some(v) => Some(points_from_toml(v)?),
        };
        let normal = f.vec3("normal")?;
        let height = f.number("height")?;
        let stiffness = f.number("stiffness")?;
        let exponent = f.number("exponent")?;
        let damping = f.number("damping")?;
        let friction = f.number("friction")?;
        let v_eps = f.number("v_eps")?;
        let points = required(points, "points", POINTS_EXPECTED)?;
        let friction = required(friction, "friction", "a number >= 0 (Coulomb μ)")?;
        GroundContact::new(
            name,
            points,
            normal.unwrap_or(Vec3::z()),
            height.unwrap_or(0.0),
            stiffness,
            exponent.unwrap_or(DEFAULT_EXPONENT),
            damping,
            friction,
            v_eps.unwrap_or(DEFAULT_V_EPS),
        )
    }
}

const POINTS_EXPECTED: &str =
    "a list of [body, [x, y, z]] or [body, [x, y, z], radius] (a body name or index, a point in its frame, a sphere's radius)";

fn points_from_toml(v: &toml::Value) -> Result<Vec<ContactPoint>> {
    let bad = |k: usize, got: &toml::Value| {
        Error::arg(format!("points[{k}]"), POINTS_EXPECTED, got.to_string())
    };
    let toml::Value::Array(items) = v else {
        return Err(Error::arg("points", POINTS_EXPECTED, v.to_string()));
    };
    let mut out = Vec::with_capacity(items.len());
    for (k, item) in items.iter().enumerate() {
        let toml::Value::Array(pair) = item else {
            return Err(bad(k, item));
        };
        let (body, point, radius) = match pair.as_slice() {
            [b, p] => (b, p, 0.0),
            [b, p, toml::Value::Float(r)] => (b, p, *r),
            [b, p, toml::Value::Integer(r)] => (b, p, *r as f64),
            _ => return Err(bad(k, item)),
        };
        let body = match body {
            toml::Value::String(s) => JointRef::Name(s.clone()),
            toml::Value::Integer(i) if *i >= 0 => JointRef::Index(*i as usize),
            _ => return Err(bad(k, item)),
        };
        let xyz: Option<Vec<f64>> = match point {
            toml::Value::Array(a) if a.len() == 3 => a
                .iter()
                .map(|x| match x {
                    toml::Value::Float(x) => Some(*x),
                    toml::Value::Integer(i) => Some(*i as f64),
                    _ => None,
                })
                .collect(),
            _ => None,
        };
        let Some(xyz) = xyz else {
            return Err(bad(k, item));
        };
        out.push(ContactPoint {
            body,
            point: Vec3::new(xyz[0], xyz[1], xyz[2]),
            radius,
        });
    }
    Ok(out)
}

impl Declaration for GroundContact {
    fn to_toml(&self) -> Result<toml::Table> {
        let points = self
            .points
            .iter()
            .map(|p| {
                toml::Value::Array(vec![
                    w::joint_ref(&p.body),
                    w::vec3(&p.point),
                    w::number(p.radius),
                ])
            })
            .collect();
        Ok(w::EffectTable::new("ground_contact", self.label())
            .set("points", toml::Value::Array(points))
            .set("normal", w::vec3(&self.normal))
            .set("height", w::number(self.height))
            .maybe("stiffness", self.stiffness.map(w::number))
            .set("exponent", w::number(self.exponent))
            .maybe("damping", self.damping.map(w::number))
            .set("friction", w::number(self.friction))
            .set("v_eps", w::number(self.v_eps))
            .done())
    }
    fn kind(&self) -> Kind {
        Kind::Contact
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        Ok(Box::new(self.law(model)?))
    }
    fn parameters(&self) -> &'static [&'static str] {
        &[
            "height",
            "stiffness",
            "exponent",
            "damping",
            "friction",
            "v_eps",
        ]
    }
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let x = one_number(key, values)?;
        let pick = |k: &str, now: f64| if k == key { x } else { now };
        let pick_or_default = |k: &str, now: Option<f64>| if k == key { Some(x) } else { now };
        let e = GroundContact::new(
            self.name.clone(),
            self.points.clone(),
            self.normal,
            pick("height", self.height),
            pick_or_default("stiffness", self.stiffness),
            pick("exponent", self.exponent),
            pick_or_default("damping", self.damping),
            pick("friction", self.friction),
            pick("v_eps", self.v_eps),
        )?;
        Ok(Effect::GroundContact(e))
    }
    fn repr(&self) -> String {
        let n = &self.normal;
        format!(
            "GroundContact({} points, normal=[{}, {}, {}], height={}, stiffness={}, exponent={}, damping={}, friction={}, v_eps={}{})",
            self.points.len(),
            n.x,
            n.y,
            n.z,
            self.height,
            or_none(self.stiffness),
            self.exponent,
            or_none(self.damping),
            self.friction,
            self.v_eps,
            label_repr(self.label()),
        )
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "ground_contact",
            keys: KEYS,
            parse: |_, f| GroundContact::from_toml(f).map(Effect::GroundContact),
        }];
        TYPES
    }
}

/// A parameter for `repr`: its value, or `None` (the default, not yet computed).
fn or_none(x: Option<f64>) -> String {
    x.map_or_else(|| "None".into(), |x| x.to_string())
}

impl GroundContact {
    /// `(stiffness, damping)`: the given ones, else the defaults from the weight `W = M g`
    /// of the model (its total mass `M`, [`DEFAULT_GRAVITY`]) shared equally by the `N`
    /// points, `w = W / N` each (docs/contact.md §1):
    ///
    /// * `k = w / δ₀ᵉ`: at rest each point sinks `δ₀` = [`DEFAULT_SINK`] (1 mm);
    /// * `c = 2 sqrt(k_lin M / N) / δ_sᵉ`: critical damping of the contact mode linearised at
    ///   the static sink `δ_s = (w / k)^(1/e)` (with the given or default `k`), where the
    ///   law's stiffness is `k_lin = e k δ_sᵉ⁻¹ = e w / δ_s` and its damping `c δ_sᵉ`.
    ///
    /// A massless model has no default: the error names `stiffness` (or `damping`).
    pub fn resolved(&self, model: &Model) -> Result<(f64, f64)> {
        if let (Some(k), Some(c)) = (self.stiffness, self.damping) {
            return Ok((k, c));
        }
        let n = self.points.len() as f64;
        let mass = model.total_mass();
        let w = mass * DEFAULT_GRAVITY / n;
        if !(w.is_finite() && w > 0.0) {
            let arg = if self.stiffness.is_none() {
                "stiffness"
            } else {
                "damping"
            };
            return Err(Error::arg(
                arg,
                "a number: its default comes from the model's weight, and this model's total mass is not a positive number",
                format!("None (total mass {})", crate::support::error::num(mass + 0.0)), // not "-0"
            ));
        }
        let e = self.exponent;
        let k = self.stiffness.unwrap_or_else(|| w / DEFAULT_SINK.powf(e));
        let c = self.damping.unwrap_or_else(|| {
            let sink_e = w / k; // δ_sᵉ
            let k_lin = e * w / sink_e.powf(1.0 / e);
            2.0 * (k_lin * mass / n).sqrt() / sink_e
        });
        // An extreme exponent or mass can overflow: the defaults checked as given ones are.
        let defaulted = [
            ("stiffness", k, self.stiffness.is_none()),
            ("damping", c, self.damping.is_none()),
        ];
        for (arg, x, _) in defaulted.into_iter().filter(|d| d.2) {
            if !(x.is_finite() && x > 0.0) {
                return Err(Error::arg(
                    arg,
                    "a number: its default from the model's weight is not a finite number > 0",
                    format!("None (default {})", crate::support::error::num(x)),
                ));
            }
        }
        Ok((k, c))
    }

    /// This contact with its default stiffness and damping computed for `model` (what a
    /// scene keeps and reports); itself when both are given.
    pub fn with_model_defaults(&self, model: &Model) -> Result<GroundContact> {
        let (k, c) = self.resolved(model)?;
        Ok(GroundContact {
            stiffness: Some(k),
            damping: Some(c),
            ..self.clone()
        })
    }

    /// The law, resolved against `model` (also used to report the contact forces along a
    /// trajectory, [`GroundContactLaw::evaluate`]).
    pub fn law(&self, model: &Model) -> Result<GroundContactLaw> {
        let points = self.points.iter().map(|p| (&p.body, &p.point));
        let set = PointSet::resolve(model, points, |k| format!("points[{k}]"))?;
        let (k, c) = self.resolved(model)?;
        Ok(GroundContactLaw {
            set,
            radii: self.points.iter().map(|p| p.radius).collect(),
            normal: self.normal,
            height: self.height,
            k,
            e: self.exponent,
            c,
            mu: self.friction,
            v_eps: self.v_eps,
        })
    }
}

/// A ground contact evaluated along states: per state and point (row-major, state first),
/// the point's world position (3 each), its penetration (negative above the plane), the
/// normal force and the whole force on it (3 each, world frame: normal plus friction).
#[derive(Debug, Clone, Default)]
pub struct ContactStates {
    /// How many states, and points per state.
    pub states: usize,
    pub points: usize,
    /// (states, points, 3), (states, points), (states, points), (states, points, 3).
    pub position: Array,
    pub penetration: Array,
    pub normal_force: Array,
    pub force: Array,
}

impl GroundContact {
    /// The contact at each of the states `q` (rows of `nq`) and `v` (rows of `nv`, as many).
    /// The force is a function of the state, so these are exact wherever the states are.
    pub fn states(&self, model: &Model, q: &[f64], v: &[f64]) -> Result<ContactStates> {
        let (nq, nv) = (model.nq, model.nv);
        let n = q.len().checked_div(nq).unwrap_or(0);
        if q.len() != n * nq || v.len() != n * nv {
            return Err(Error::arg(
                "q, v",
                format!("as many states of {nq} coordinates and {nv} speeds"),
                format!("{} coordinates and {} speeds", q.len(), v.len()),
            ));
        }
        for (arg, x, width) in [("q", q, nq), ("v", v, nv)] {
            if let Some(i) = x.iter().position(|x| !x.is_finite()) {
                let at = format!("{} in state {} (entry {})", x[i], i / width, i % width);
                return Err(Error::arg(arg, "finite states", at));
            }
        }
        // A finite state can still be none (a zero quaternion): as every model call checks it.
        for k in 0..n {
            let (qk, vk) = (&q[k * nq..(k + 1) * nq], &v[k * nv..(k + 1) * nv]);
            model
                .check_state(qk, Some(vk))
                .map_err(|e| e.map_arg(|a| format!("{a} (state {k})")))?;
        }
        let mut law = self.law(model)?;
        let np = law.npoints();
        let mut out = ContactStates {
            states: n,
            points: np,
            position: Array::zeros(&[n, np, 3]),
            penetration: Array::zeros(&[n, np]),
            normal_force: Array::zeros(&[n, np]),
            force: Array::zeros(&[n, np, 3]),
        };
        for i in 0..n {
            let (qi, vi) = (&q[i * nq..(i + 1) * nq], &v[i * nv..(i + 1) * nv]);
            law.evaluate(model, qi, vi, |k, p, pf| {
                let at = i * np + k;
                out.position.data[3 * at..3 * at + 3].copy_from_slice(p.as_slice());
                out.penetration.data[at] = pf.penetration;
                out.normal_force.data[at] = pf.normal;
                out.force.data[3 * at..3 * at + 3].copy_from_slice(pf.force.as_slice());
            });
        }
        Ok(out)
    }
}

/// One point's contact force and its Jacobians with respect to the point's position and
/// velocity (world frame).
#[derive(Debug, Clone, Copy)]
pub struct PointForce {
    /// Penetration `δ` (negative: above the plane).
    pub penetration: f64,
    /// Normal force `F_n` ≥ 0.
    pub normal: f64,
    /// The whole force `F_n n + F_t` on the point.
    pub force: Vec3,
    /// `∂f/∂p`, `∂f/∂ṗ`.
    pub dp: Mat3,
    pub dv: Mat3,
}

pub struct GroundContactLaw {
    set: PointSet,
    /// Per point, the sphere's radius (0: a point).
    radii: Vec<f64>,
    normal: Vec3,
    height: f64,
    k: f64,
    e: f64,
    c: f64,
    mu: f64,
    v_eps: f64,
}

/// `g(x) = tanh(x)/x` and `g'(x)/x`, with series near 0 where the closed forms cancel
/// (below 1e-2 the next terms are < 1e-12 relative).
#[inline]
fn tanh_ratio(x: f64) -> (f64, f64) {
    if x < 1e-2 {
        let x2 = x * x;
        (
            1.0 - x2 / 3.0 + 2.0 * x2 * x2 / 15.0,
            -2.0 / 3.0 + 8.0 * x2 / 15.0 - 34.0 * x2 * x2 / 105.0,
        )
    } else {
        let t = x.tanh();
        let sech2 = 1.0 - t * t;
        (t / x, (x * sech2 - t) / (x * x * x))
    }
}

impl GroundContactLaw {
    /// `(δᵉ, δᵉ⁻¹)`, without `powf` for the usual exponents (Hertz's 1.5 and the linear 1).
    #[inline]
    fn powers(&self, delta: f64) -> (f64, f64) {
        if self.e == 1.5 {
            let r = delta.sqrt();
            (delta * r, r)
        } else if self.e == 1.0 {
            (delta, 1.0)
        } else {
            let d1 = delta.powf(self.e - 1.0);
            (d1 * delta, d1)
        }
    }

    /// The force on a point (a sphere's centre of radius `r`) at world position `p` moving
    /// at `pd`, with its Jacobians.
    #[inline]
    pub fn point_force(&self, p: &Vec3, pd: &Vec3, r: f64) -> PointForce {
        let n = self.normal;
        let delta = self.height + r - n.dot(p);
        let zero = PointForce {
            penetration: delta,
            normal: 0.0,
            force: Vec3::zeros(),
            dp: Mat3::zeros(),
            dv: Mat3::zeros(),
        };
        if delta <= 0.0 {
            return zero;
        }
        let delta_dot = -n.dot(pd);
        let (de, de1) = self.powers(delta);
        let fn_ = de * (self.k + self.c * delta_dot);
        if fn_ <= 0.0 {
            // The damping would pull: the contact lets go (`max(0, ·)`).
            return zero;
        }
        // ∂F_n/∂p = ∂F_n/∂δ (−nᵀ), ∂F_n/∂ṗ = c δᵉ (−nᵀ).
        let dfn_ddelta = self.e * de1 * (self.k + self.c * delta_dot);
        let dfn_dp = -n * dfn_ddelta;
        let dfn_dv = -n * (self.c * de);
        let vt = pd + n * delta_dot; // ṗ − (n·ṗ) n
        let s = vt.norm();
        let x = s / self.v_eps;
        let (g, dg_over_x) = tanh_ratio(x);
        // F_t = −μ F_n φ v_t with φ = g(x)/v_eps; ∂(φ v_t)/∂v_t = φ 1 + (φ'/s) v_t v_tᵀ, and
        // φ'/s = g'(x)/(x v_eps³).
        let phi = g / self.v_eps;
        let dphi_over_s = dg_over_x / (self.v_eps * self.v_eps * self.v_eps);
        let dir = n - vt * (self.mu * phi); // f = F_n · dir
        let projector = Mat3::identity() - n * n.transpose();
        let dvt = (Mat3::identity() * phi + vt * vt.transpose() * dphi_over_s) * projector;
        PointForce {
            penetration: delta,
            normal: fn_,
            force: dir * fn_,
            dp: dir * dfn_dp.transpose(),
            dv: dir * dfn_dv.transpose() - dvt * (self.mu * fn_),
        }
    }

    /// Per point: the world position, the penetration and the force (world frame), at the
    /// state `(q, v)`.
    pub fn evaluate(
        &mut self,
        model: &Model,
        q: &[f64],
        v: &[f64],
        mut each: impl FnMut(usize, &Vec3, &PointForce),
    ) {
        self.set.place(model, q);
        for k in 0..self.set.len() {
            let p = self.set.position(k);
            let pd = velocity(self.set.jacobian(model, k, &p), v);
            let pf = self.point_force(&p, &pd, self.radii[k]);
            each(k, &p, &pf);
        }
    }

    pub fn npoints(&self) -> usize {
        self.set.len()
    }
}

impl ForceLaw for GroundContactLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        self.set.place(cx.model, cx.q);
        for k in 0..self.set.len() {
            let p = self.set.position(k);
            let delta = self.height + self.radii[k] - self.normal.dot(&p);
            if delta <= 0.0 {
                continue; // in the air: neither its Jacobian nor its velocity is needed
            }
            let pd = velocity(self.set.jacobian(cx.model, k, &p), cx.v);
            let f = self.point_force(&p, &pd, self.radii[k]).force;
            add_force(self.set.columns(k), &f, tau);
        }
        Ok(false)
    }

    /// `τ = Jᵀ f(p, ṗ)` differentiated, per point: the Jacobian's own turn `(∂j_m/∂δ_c)·f`
    /// (a column turns as `ω_c × j_m` under a column that carries it, as `ω_m × j_c` under
    /// one downstream), and `j_kᵀ (∂f/∂p j_c + ∂f/∂ṗ h_c)` with `h_c = Σ_m v_m ∂j_m/∂δ_c`
    /// the change of `ṗ`; `∂τ/∂v = Jᵀ ∂f/∂ṗ J`.
    fn add_derivatives(
        &mut self,
        cx: &Context<'_>,
        dq: &mut nalgebra::DMatrix<f64>,
        dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        self.set.place(cx.model, cx.q);
        for k in 0..self.set.len() {
            let p = self.set.position(k);
            if self.height + self.radii[k] - self.normal.dot(&p) <= 0.0 {
                continue;
            }
            let pd = velocity(self.set.jacobian(cx.model, k, &p), cx.v);
            let pf = self.point_force(&p, &pd, self.radii[k]);
            if pf.normal == 0.0 {
                continue;
            }
            let cols = self.set.columns(k);
            for (ci, c) in cols.iter().enumerate() {
                let wc = angular(&c.s);
                let mut hc = Vec3::zeros();
                for (mi, m) in cols.iter().enumerate() {
                    let djm = if m.moved_by(c, ci < mi) {
                        wc.cross(&m.j)
                    } else {
                        angular(&m.s).cross(&c.j)
                    };
                    hc += djm * cx.v[m.v];
                    dq[(m.v, c.v)] += djm.dot(&pf.force);
                }
                let a = pf.dp * c.j + pf.dv * hc;
                let b = pf.dv * c.j;
                for m in cols {
                    dq[(m.v, c.v)] += m.j.dot(&a);
                    dv[(m.v, c.v)] += m.j.dot(&b);
                }
            }
        }
        Ok(true)
    }

    /// `Σ k δ^(e+1) / (e + 1)` over the penetrating points: the elastic part's potential.
    fn potential_energy(&self, _cx: &Context<'_>, links: &[LinkState]) -> Option<f64> {
        let mut v = 0.0;
        for (k, r) in self.radii.iter().enumerate() {
            let delta = self.height + r - self.normal.dot(&self.set.position_from(links, k));
            if delta > 0.0 {
                v += self.k * delta.powf(self.e + 1.0) / (self.e + 1.0);
            }
        }
        Some(v)
    }
}

#[cfg(test)]
#[path = "tests/ground_contact.rs"]
mod tests;
