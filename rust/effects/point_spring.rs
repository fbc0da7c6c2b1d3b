//! Point-to-point spring–dampers, family `springs`: a linear spring (and optional viscous
//! damper) between point `a` fixed in body a and point `b` fixed in body b, either of which
//! may be the world (the point then has world coordinates). With `d = p_b − p_a`, length
//! `l = |d|` and `u = d / l`, the force on b is `f_b = −(k (l − l₀) + c l̇) u` (pulling the
//! points together when stretched) and `f_a = −f_b`; `l̇ = u · (ṗ_b − ṗ_a)`.
//!
//! Generalized forces `τ = J_bᵀ f_b + J_aᵀ f_a` through the points' Jacobians, column by
//! column along each body's path from the root (`j = v_O + ω × (p − O)` per speed), so a
//! spring costs O(depth of its two bodies) and writes no link wrench. Potential
//! `V = ½ k (l − l₀)²`; power `−k (l − l₀) l̇ − c l̇²`, so with damping the effect is not
//! conservative: along a motion `P + dV/dt = −c l̇²`.
//!
//! The direction `u` is undefined where the points coincide (`l = 0`): the run stops there
//! with an error, unless `l₀ = 0` and `c = 0`, where the force is `−k d` (smooth through 0).
use super::body_point::End;
use super::scene_writer as w;
use super::{label_repr, one_number, Effect, TomlType};
use super::{Context, Declaration, Fields, ForceLaw, JointRef, Kind};
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::{angular, Mat3, Vec3, Vec6};

/// Keys of a `type = "point_spring"` table.
const KEYS: &[&str] = &[
    "name",
    "body_a",
    "point_a",
    "body_b",
    "point_b",
    "stiffness",
    "rest_length",
    "damping",
];

/// What a body argument of a point spring may be (for the errors).
const BODY_EXPECTED: &str = "a body name or index (>= 0), or \"world\" / -1 for the ground";

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointSpring {
    pub name: Option<String>,
    /// `None`: the world.
    pub body_a: Option<JointRef>,
    /// In body a's frame (world coordinates for the world).
    pub point_a: Vec3,
    pub body_b: Option<JointRef>,
    pub point_b: Vec3,
    /// N/m, ≥ 0.
    pub stiffness: f64,
    /// m, ≥ 0.
    pub rest_length: f64,
    /// N·s/m, ≥ 0.
    pub damping: f64,
}

impl PointSpring {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: Option<String>,
        body_a: Option<JointRef>,
        point_a: Vec3,
        body_b: Option<JointRef>,
        point_b: Vec3,
        stiffness: f64,
        rest_length: f64,
        damping: f64,
    ) -> Result<PointSpring> {
        check_finite("point_a", point_a.as_slice())?;
        check_finite("point_b", point_b.as_slice())?;
        for (arg, x) in [
            ("stiffness", stiffness),
            ("rest_length", rest_length),
            ("damping", damping),
        ] {
            if !(x.is_finite() && x >= 0.0) {
                return Err(Error::arg(arg, "a finite number >= 0", x.to_string()));
            }
        }
        if body_a == body_b {
            return Err(Error::arg(
                "body_b",
                "a body other than body_a (a spring within one rigid body does nothing)",
                match &body_a {
                    Some(r) => format!("{r} for both"),
                    None => "the world for both".to_string(),
                },
            ));
        }
        Ok(PointSpring {
            name,
            body_a,
            point_a,
            body_b,
            point_b,
            stiffness,
            rest_length,
            damping,
        })
    }

    pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<PointSpring> {
        let name = f.string("name")?;
        let body_a = body_or_world(f, "body_a")?;
        let point_a = f.vec3("point_a")?;
        let body_b = body_or_world(f, "body_b")?;
        let point_b = f.vec3("point_b")?;
        let stiffness = f.number("stiffness")?;
        let rest_length = f.number("rest_length")?;
        let damping = f.number("damping")?;
        let body_a = super::required(body_a, "body_a", BODY_EXPECTED)?;
        let point_a = super::required(point_a, "point_a", "a 3-vector in body_a's frame")?;
        let body_b = super::required(body_b, "body_b", BODY_EXPECTED)?;
        let point_b = super::required(point_b, "point_b", "a 3-vector in body_b's frame")?;
        let stiffness = super::required(stiffness, "stiffness", "a number >= 0 (N/m)")?;
        PointSpring::new(
            name,
            body_a,
            point_a,
            body_b,
            point_b,
            stiffness,
            rest_length.unwrap_or(0.0),
            damping.unwrap_or(0.0),
        )
    }
}

/// A body name or index, or the world (`"world"` or −1): `Some(None)` for the world.
fn body_or_world(f: &mut Fields<'_>, key: &'static str) -> Result<Option<Option<JointRef>>> {
    f.typed(key, BODY_EXPECTED, |v| match v {
        toml::Value::String(s) if s == "world" => Some(None),
        toml::Value::String(s) => Some(Some(JointRef::Name(s.clone()))),
        toml::Value::Integer(-1) => Some(None),
        toml::Value::Integer(i) if *i >= 0 => Some(Some(JointRef::Index(*i as usize))),
        _ => None,
    })
}

impl Declaration for PointSpring {
    fn to_toml(&self) -> Result<toml::Table> {
        let body = |b: &Option<JointRef>| match b {
            Some(r) => w::joint_ref(r),
            None => toml::Value::String("world".into()),
        };
        Ok(w::EffectTable::new("point_spring", self.label())
            .set("body_a", body(&self.body_a))
            .set("point_a", w::vec3(&self.point_a))
            .set("body_b", body(&self.body_b))
            .set("point_b", w::vec3(&self.point_b))
            .set("stiffness", w::number(self.stiffness))
            .set("rest_length", w::number(self.rest_length))
            .set("damping", w::number(self.damping))
            .done())
    }
    fn parameters(&self) -> &'static [&'static str] {
        &["stiffness", "rest_length", "damping"]
    }
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let x = one_number(key, values)?;
        let pick = |k: &str, now: f64| if k == key { x } else { now };
        let e = PointSpring::new(
            self.name.clone(),
            self.body_a.clone(),
            self.point_a,
            self.body_b.clone(),
            self.point_b,
            pick("stiffness", self.stiffness),
            pick("rest_length", self.rest_length),
            pick("damping", self.damping),
        )?;
        Ok(Effect::PointSpring(e))
    }
    fn repr(&self) -> String {
        let body = |b: &Option<JointRef>| match b {
            Some(r) => r.to_string(),
            None => "'world'".to_string(),
        };
        let p = |x: &Vec3| format!("[{}, {}, {}]", x.x, x.y, x.z);
        format!(
            "PointSpring(body_a={}, point_a={}, body_b={}, point_b={}, stiffness={}, rest_length={}, damping={}{})",
            body(&self.body_a),
            p(&self.point_a),
            body(&self.body_b),
            p(&self.point_b),
            self.stiffness,
            self.rest_length,
            self.damping,
            label_repr(self.label()),
        )
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "point_spring",
            keys: KEYS,
            parse: |_, f| PointSpring::from_toml(f).map(Effect::PointSpring),
        }];
        TYPES
    }
    fn kind(&self) -> Kind {
        Kind::Springs
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let a = End::resolve(model, &self.body_a, &self.point_a, "body_a")?;
        let b = End::resolve(model, &self.body_b, &self.point_b, "body_b")?;
        if a.link == b.link {
            return Err(Error::arg(
                "body_b",
                "a body that moves relative to body_a (a spring within one rigid body does nothing)",
                format!("{} and {}, welded together", a.what, b.what),
            ));
        }
        let coincide = format!(
            "the point spring{} between {} and {} has its two points coincide (length 0), where the direction of its force is undefined",
            self.name.as_ref().map(|n| format!(" '{n}'")).unwrap_or_default(),
            a.what,
            b.what
        );
        Ok(Box::new(PointSpringLaw {
            a,
            b,
            k: self.stiffness,
            rest: self.rest_length,
            c: self.damping,
            coincide,
            g: vec![Vec3::zeros(); model.nv],
            h: vec![Vec3::zeros(); model.nv],
        }))
    }
}

pub struct PointSpringLaw {
    a: End,
    b: End,
    k: f64,
    rest: f64,
    c: f64,
    /// The error when the points coincide (built once: the run stops on it).
    coincide: String,
    /// Per speed, `∂d/∂δ` and `∂ḋ/∂δ` of the points' separation `d` (derivatives only).
    g: Vec<Vec3>,
    h: Vec<Vec3>,
}

impl PointSpringLaw {
    /// The force on b, `f(d, ḋ)`, and its Jacobians `∂f/∂d`, `∂f/∂ḋ` (after `place`).
    fn force_jacobians(
        &self,
        d: &Vec3,
        dd: &Vec3,
    ) -> std::result::Result<(Vec3, Mat3, Mat3), String> {
        if self.rest == 0.0 && self.c == 0.0 {
            return Ok((-self.k * d, Mat3::identity() * -self.k, Mat3::zeros()));
        }
        let l = d.norm();
        if l == 0.0 {
            return Err(self.coincide.clone());
        }
        let u = d / l;
        let perp = (Mat3::identity() - u * u.transpose()) / l;
        let l_dot = u.dot(dd);
        let m = self.k * (l - self.rest) + self.c * l_dot;
        // f = −m u: ∂m/∂d = k u + c (1 − u uᵀ) ḋ / l, ∂u/∂d = (1 − u uᵀ)/l, ∂m/∂ḋ = c u.
        let dm = u * self.k + perp * dd * self.c;
        let fd = -(u * dm.transpose()) - perp * m;
        let fdd = -(u * u.transpose()) * self.c;
        Ok((-m * u, fd, fdd))
    }
}

impl ForceLaw for PointSpringLaw {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        let d = self.b.place(cx.model, cx.q) - self.a.place(cx.model, cx.q);
        let f_b = if self.rest == 0.0 && self.c == 0.0 {
            // −k d needs no direction: defined (and smooth) where the points meet.
            -self.k * d
        } else {
            let l = d.norm();
            if l == 0.0 {
                return Err(self.coincide.clone());
            }
            let u = d / l;
            let mut magnitude = self.k * (l - self.rest);
            if self.c > 0.0 {
                let l_dot = u.dot(&(self.b.velocity(cx.v) - self.a.velocity(cx.v)));
                magnitude += self.c * l_dot;
            }
            -magnitude * u
        };
        self.b.add_force(&f_b, tau);
        self.a.add_force(&-f_b, tau);
        Ok(false)
    }

    /// `τ = σ_b J_bᵀ f − …` differentiated: a column `j_k` of an end's point Jacobian turns
    /// as `ω_c × j_k` under a column `c` that carries it, and as `ω_k × j_c` (its point moves)
    /// under one downstream; `d` moves by `g_c = Σ σ j_c`, `ḋ` by
    /// `h_c = Σ σ Σ_m v_m ∂j_m/∂δ_c` along `δ_c` and by `g_c` along `v_c`.
    fn add_derivatives(
        &mut self,
        cx: &Context<'_>,
        dq: &mut nalgebra::DMatrix<f64>,
        dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        let d = self.b.place(cx.model, cx.q) - self.a.place(cx.model, cx.q);
        let ddot = self.b.velocity(cx.v) - self.a.velocity(cx.v);
        let (f, fd, fdd) = self.force_jacobians(&d, &ddot)?;
        let z = Vec3::zeros();
        for end in [&self.a, &self.b] {
            for col in &end.columns {
                self.g[col.v] = z;
                self.h[col.v] = z;
            }
        }
        for (sign, end) in [(-1.0, &self.a), (1.0, &self.b)] {
            let cols = &end.columns;
            for (ci, c) in cols.iter().enumerate() {
                let wc = angular(&c.s);
                self.g[c.v] += c.j * sign;
                let mut hc = Vec3::zeros();
                for (mi, m) in cols.iter().enumerate() {
                    let djm = if m.moved_by(c, ci < mi) {
                        wc.cross(&m.j)
                    } else {
                        angular(&m.s).cross(&c.j)
                    };
                    hc += djm * cx.v[m.v];
                    // (∂j_m/∂δ_c)·f, the Jacobian's own turn.
                    dq[(m.v, c.v)] += sign * djm.dot(&f);
                }
                self.h[c.v] += hc * sign;
            }
        }
        for (sign, end) in [(-1.0, &self.a), (1.0, &self.b)] {
            for k in &end.columns {
                let jf = fd.transpose() * k.j * sign;
                let jfd = fdd.transpose() * k.j * sign;
                for other in [&self.a, &self.b] {
                    for c in &other.columns {
                        // Each (k, c) once: the second end's columns shared with the first
                        // (a common ancestor) are skipped there.
                        if !std::ptr::eq(other, &self.a)
                            && self.a.columns.iter().any(|x| x.v == c.v)
                        {
                            continue;
                        }
                        dq[(k.v, c.v)] += jf.dot(&self.g[c.v]) + jfd.dot(&self.h[c.v]);
                        dv[(k.v, c.v)] += jfd.dot(&self.g[c.v]);
                    }
                }
            }
        }
        Ok(true)
    }

    fn potential_energy(&self, _cx: &Context<'_>, links: &[LinkState]) -> Option<f64> {
        let d = self.b.position(links) - self.a.position(links);
        let stretch2 = if self.rest > 0.0 {
            let s = d.norm() - self.rest;
            s * s
        } else {
            d.norm_squared()
        };
        Some(0.5 * self.k * stretch2)
    }
}
