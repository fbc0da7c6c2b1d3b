//! The effects built from a binding's arguments ([`Arg`]): the forms a caller writes
//! (`pmd.Effect("spring", joints=..., stiffness=...)` in Python, [`effect`]) read here, once,
//! so the binding only converts. A scene file's `[[effect]]` tables are read by `scene_file.rs`.
use super::ground_contact::ContactStates;
use super::{
    ContactPoint, Damper, Disabled, Effect, External, Frame, Friction, GroundContact, JointLimit,
    JointRef, Matrix, PerJoint, PointSpring, Spring, Table, Torque, TorqueLimit,
};
use crate::model::Model;
use crate::support::args::{flag, given, int, items, opt, shape_str, text, vec3, vector, Arg, Int};
use crate::support::error::Error;
use crate::support::spatial::Vec3;

type R<T, A> = Result<T, <A as Arg>::Err>;

/// A body name or index.
pub fn joint_ref<A: Arg>(x: &A, arg: &str) -> R<JointRef, A> {
    if let Some(s) = x.text() {
        return Ok(JointRef::Name(s));
    }
    match x.int() {
        Int::Value(i) if i >= 0 && !x.is_bool() => Ok(JointRef::Index(i as usize)),
        _ => Err(Error::arg(arg, "a body name (str) or body index (int >= 0)", x.shown()).into()),
    }
}

/// A body name or index, or the world (`"world"`, −1 or `None`): `None` for the world.
pub fn body_or_world<A: Arg>(x: &A, arg: &str) -> R<Option<JointRef>, A> {
    const EXPECTED: &str =
        "a body name (str) or index (int >= 0), or 'world' / -1 / None for the ground";
    if x.absent() {
        return Ok(None);
    }
    if let Some(s) = x.text() {
        return Ok((s != "world").then_some(JointRef::Name(s)));
    }
    if x.is_bool() || !matches!(x.int(), Int::Value(_)) {
        return Err(Error::arg(arg, EXPECTED, x.shown()).into());
    }
    match int(x, arg, -1, i64::MAX, EXPECTED)? {
        -1 => Ok(None),
        i => Ok(Some(JointRef::Index(i as usize))),
    }
}

/// `None` (every moving joint), one body name or index, or a sequence of them.
pub fn joints<A: Arg>(x: Option<&A>) -> R<Option<Vec<JointRef>>, A> {
    let Some(x) = given(x) else {
        return Ok(None);
    };
    if x.text().is_some() || matches!(x.int(), Int::Value(_)) {
        return Ok(Some(vec![joint_ref(x, "joints")?]));
    }
    let expected = "None, a body name or index, or a sequence of them";
    let list = items(x, "joints", expected)?;
    list.iter()
        .enumerate()
        .map(|(k, j)| joint_ref(j, &format!("joints[{k}]")))
        .collect::<R<_, A>>()
        .map(Some)
}

/// A number (all joints) or a 1-D array (one per joint).
pub fn per_joint<A: Arg>(x: &A, arg: &str) -> R<PerJoint, A> {
    let (shape, values) = x.array(arg)?;
    match shape.len() {
        0 => Ok(PerJoint::All(values[0])),
        1 => Ok(PerJoint::Each(values)),
        _ => Err(Error::arg(arg, "a number or a 1-D array", shape_str(&shape)).into()),
    }
}

/// A 1-D or 2-D array, one row per time.
pub fn matrix<A: Arg>(x: &A, arg: &str) -> R<Matrix, A> {
    let (shape, values) = x.array(arg)?;
    let (rows, cols, one_d) = match shape.as_slice() {
        [n] => (*n, 1, true),
        [n, c] => (*n, *c, false),
        _ => {
            let expected = "a 1-D or 2-D array (one row per time)";
            return Err(Error::arg(arg, expected, shape_str(&shape)).into());
        }
    };
    Ok(Matrix {
        values,
        rows,
        cols,
        one_d,
    })
}

/// Contact points: a sequence of `(body, [x, y, z])` or `(body, [x, y, z], radius)`.
pub fn contact_points<A: Arg>(x: &A) -> R<Vec<ContactPoint>, A> {
    const EXPECTED: &str =
        "a sequence of (body, [x, y, z]) or (body, [x, y, z], radius): a body name or index, a point in its frame";
    let mut out = Vec::new();
    for (k, item) in items(x, "points", EXPECTED)?.iter().enumerate() {
        let arg = format!("points[{k}]");
        let parts = items(item, &arg, EXPECTED)?;
        let (body, point, radius) = match parts.as_slice() {
            [b, p] => (b, p, 0.0),
            [b, p, r] => (b, p, r.real(&format!("{arg} radius"))?),
            _ => return Err(Error::arg(&arg, EXPECTED, item.shown()).into()),
        };
        out.push(ContactPoint {
            body: joint_ref(body, &arg)?,
            point: vec3(point, &arg)?,
            radius,
        });
    }
    Ok(out)
}

/// A torque limit: None, `"effort"` or one number / one per speed.
pub fn torque_limit<A: Arg>(x: Option<&A>) -> R<Option<TorqueLimit>, A> {
    Ok(match given(x) {
        None => None,
        Some(x) if x.text().is_some_and(|s| s == "effort") => Some(TorqueLimit::Effort),
        Some(x) => Some(TorqueLimit::given(per_joint(x, "limit")?)?),
    })
}

/// `None`, one family name, or a sequence of them.
pub fn disable<A: Arg>(x: Option<&A>) -> R<Option<Disabled>, A> {
    let Some(x) = given(x) else {
        return Ok(None);
    };
    let bad = || {
        Error::arg(
            "disable",
            "None, an effect family name or a sequence of them",
            x.shown(),
        )
    };
    let names: Vec<String> = match x.text() {
        Some(s) => vec![s],
        None => x
            .items()
            .ok_or_else(bad)??
            .iter()
            .map(|n| n.text().ok_or_else(bad))
            .collect::<Result<_, _>>()?,
    };
    Ok(Some(Disabled::parse(&names, "disable")?))
}

/// Uniform gravity `g` (default `[0, 0, −9.81]`).
pub fn gravity<A: Arg>(g: Option<&A>) -> R<Effect, A> {
    let g = opt(g, |g| vec3(g, "g"))?.unwrap_or(Vec3::new(0.0, 0.0, -9.81));
    Ok(Effect::gravity(g)?)
}

/// The effect of scene-file type `ty` (`"spring"`, `"torque"`, ...: the registry's types) from
/// keyword arguments `kw`, a mapping of that type's keys (`keys`: those given): the one
/// constructor behind `pmd.Effect(type, **keys)` and every Python factory. Arrays are read
/// here with errors in the caller's terms (NumPy shapes) naming the argument; a type without
/// its line below (a new effect) is read by its scene-file parser, its arguments written as
/// a file would state them, so it needs no code here.
pub fn effect<A: Arg>(ty: &str, keys: &[String], kw: &A) -> R<Effect, A> {
    let found = super::scene_file::find_type(Some(ty), super::all_toml_types())?;
    super::scene_file::check_keys(found, keys)?;
    let k = Keywords(kw);
    let name = k.parse("name", |x, key| text(x, key, "a string"))?;
    let limit = || torque_limit(k.opt("limit").as_ref());
    let real = |x: &A, key: &str| x.real(key);
    let e = match ty {
        "gravity" => return gravity(k.opt("g").as_ref()),
        "spring" => {
            let (joints, stiffness) = (k.joints()?, k.req("stiffness", per_joint)?);
            Effect::Spring(Spring::new(
                name,
                joints,
                stiffness,
                k.parse("rest", per_joint)?,
            )?)
        }
        "damper" => {
            let (joints, damping) = (k.joints()?, k.req("damping", per_joint)?);
            Effect::Damper(Damper::new(name, joints, damping)?)
        }
        "friction" => {
            let v_eps = k.parse("v_eps", real)?;
            let (joints, f) = (k.joints()?, k.req("friction", per_joint)?);
            Effect::Friction(Friction::new(name, joints, f, v_eps)?)
        }
        "torque" => {
            let (joints, tau) = (k.joints()?, k.req("tau", per_joint)?);
            Effect::Torque(Torque::constant(name, joints, tau)?.with_limit(limit()?))
        }
        "tabulated_torque" => {
            let (joints, table) = (k.joints()?, k.table("values")?);
            Effect::Torque(Torque::tabulated(name, joints, table)?.with_limit(limit()?))
        }
        "pd_torque" => {
            let joints = k.joints()?;
            let (kp, kd) = (k.req("kp", per_joint)?, k.req("kd", per_joint)?);
            let table = k.table("reference")?;
            Effect::Torque(Torque::pd(name, joints, kp, kd, table)?.with_limit(limit()?))
        }
        "external" => external(&k, name)?,
        "point_spring" => {
            let (body_a, point_a) = (k.req("body_a", body_or_world)?, k.req("point_a", vec3)?);
            let (body_b, point_b) = (k.req("body_b", body_or_world)?, k.req("point_b", vec3)?);
            let stiffness = k.req("stiffness", real)?;
            let rest = k.parse("rest_length", real)?.unwrap_or(0.0);
            let c = k.parse("damping", real)?.unwrap_or(0.0);
            let (a, b) = ((body_a, point_a), (body_b, point_b));
            Effect::PointSpring(PointSpring::new(
                name, a.0, a.1, b.0, b.1, stiffness, rest, c,
            )?)
        }
        "ground_contact" => Effect::GroundContact(GroundContact::new(
            name,
            k.req("points", |x, _| contact_points(x))?,
            k.req("normal", vec3)?,
            k.req("height", real)?,
            k.parse("stiffness", real)?,
            k.req("exponent", real)?,
            k.parse("damping", real)?,
            k.req("friction", real)?,
            k.req("v_eps", real)?,
        )?),
        "joint_limit" => {
            let joints = k.joints()?;
            let (lower, upper) = (k.parse("lower", per_joint)?, k.parse("upper", per_joint)?);
            let (s, c) = (k.req("stiffness", per_joint)?, k.req("damping", per_joint)?);
            Effect::JointLimit(JointLimit::new(name, joints, lower, upper, s, c)?)
        }
        _ => Effect::from_toml(&k.scene_table(found.name, keys)?)?,
    };
    Ok(e)
}

/// A force and a moment on a body at a body-fixed point, each constant, or tabulated at
/// `time` (rows per time).
fn external<A: Arg>(k: &Keywords<'_, A>, name: Option<String>) -> R<Effect, A> {
    let body = k.req("body", joint_ref)?;
    let point = k.parse("point", vec3)?.unwrap_or_else(Vec3::zeros);
    let frame = k.parse("frame", |x, key| text(x, key, "\"world\" or \"body\""))?;
    let frame = Frame::parse(frame.as_deref().unwrap_or("world"), "frame")?;
    let (force, moment) = (k.opt("force"), k.opt("moment"));
    if force.is_none() && moment.is_none() {
        return Err(Error::arg("force", "a force (or a moment)", "None").into());
    }
    let inner = match k.parse("time", |x, key| vector(x, key, None))? {
        Some(t) => {
            let f = opt(force.as_ref(), |f| matrix(f, "force"))?;
            let m = opt(moment.as_ref(), |m| matrix(m, "moment"))?;
            External::tabulated(name, body, point, t, f, m, frame)?
        }
        None => {
            let f = opt(force.as_ref(), |f| vec3(f, "force"))?.unwrap_or_else(Vec3::zeros);
            let m = opt(moment.as_ref(), |m| vec3(m, "moment"))?.unwrap_or_else(Vec3::zeros);
            External::constant(name, body, point, f, m, frame)?
        }
    };
    Ok(Effect::External(inner))
}

/// The keyword arguments of one effect: a mapping (Python's `**kwargs`) of its scene-file keys.
struct Keywords<'a, A>(&'a A);

impl<A: Arg> Keywords<'_, A> {
    /// The value under `key`, if one was given (`None` is not one).
    fn opt(&self, key: &str) -> Option<A> {
        self.0.get(key).flatten().filter(|x| !x.absent())
    }
    /// `parse` of the value under `key`, if one was given.
    fn parse<T>(&self, key: &str, parse: impl Fn(&A, &str) -> R<T, A>) -> R<Option<T>, A> {
        self.opt(key).map(|x| parse(&x, key)).transpose()
    }
    /// `parse` of the value under `key`, which must be there (a `None` goes to `parse`).
    fn req<T>(&self, key: &str, parse: impl Fn(&A, &str) -> R<T, A>) -> R<T, A> {
        match self.0.get(key).flatten() {
            Some(x) => parse(&x, key),
            None => Err(Error::arg(key, "a value", "nothing").into()),
        }
    }
    /// `None` (every moving joint), one body name or index, or a sequence of them.
    fn joints(&self) -> R<Option<Vec<JointRef>>, A> {
        joints(self.opt("joints").as_ref())
    }
    /// `time` and the rows of `values` at those times.
    fn table(&self, values: &str) -> R<Table, A> {
        let t = self.req("time", |x, key| vector(x, key, None))?;
        let m = self.req(values, matrix)?;
        Ok(Table::new(t, m, "time", values)?)
    }
    /// The `[[effect]]` table of type `ty` stating the arguments `keys` (`None`s left out).
    fn scene_table(&self, ty: &str, keys: &[String]) -> R<toml::Table, A> {
        let mut t = toml::Table::new();
        t.insert("type".into(), ty.into());
        for key in keys {
            if let Some(x) = self.opt(key) {
                t.insert(key.clone(), toml_value(&x, key)?);
            }
        }
        Ok(t)
    }
}

/// A value as a scene file states it: a bool, a string, an integer, a number, or a list
/// of those (an array's rows).
fn toml_value<A: Arg>(x: &A, arg: &str) -> R<toml::Value, A> {
    Ok(if x.is_bool() {
        toml::Value::Boolean(flag(x, arg)?)
    } else if let Some(s) = x.text() {
        toml::Value::String(s)
    } else if let Int::Value(i) = x.int() {
        toml::Value::Integer(i)
    } else if let Some(items) = x.items() {
        let items = items?;
        let values = (items.iter().enumerate()).map(|(k, x)| toml_value(x, &format!("{arg}[{k}]")));
        toml::Value::Array(values.collect::<R<_, A>>()?)
    } else {
        toml::Value::Float(x.real(arg)?)
    })
}

/// A joint given as a body index, a URDF joint name or a body name: its body's index
/// ([`resolve_joint_body`](super::resolve_joint_body)).
pub fn joint_body<A: Arg>(model: &Model, x: &A, arg: &str) -> R<usize, A> {
    let r = match x.text() {
        Some(name) => JointRef::Name(name),
        None => {
            let expected = "a body index, a joint name or a body name";
            JointRef::Index(int(x, arg, 0, i64::MAX, expected)? as usize)
        }
    };
    Ok(super::resolve_joint_body(model, &r, arg)?)
}

/// One number or a 1-D array of them (a joint's armature: one per speed); a bool is refused
/// as a number.
pub fn numbers<A: Arg>(x: &A, arg: &str, expected: &str) -> R<Vec<f64>, A> {
    if x.is_bool() {
        return Err(Error::arg(arg, expected, format!("the bool {}", x.shown())).into());
    }
    let (shape, values) = x.array(arg)?;
    if shape.len() > 1 {
        return Err(Error::arg(arg, expected, shape_str(&shape)).into());
    }
    Ok(values)
}

/// A ground contact's points along states `q` (N, nq) and `v` (N, nv)
/// ([`Effect::contact_states`]).
pub fn contact_states<A: Arg>(effect: &Effect, model: &Model, q: &A, v: &A) -> R<ContactStates, A> {
    let (qs, qv) = q.array("q")?;
    let (vs, vv) = v.array("v")?;
    let (nq, nv) = (model.nq, model.nv);
    if qs.len() != 2 || qs[1] != nq || vs.len() != 2 || vs[1] != nv || vs[0] != qs[0] {
        let expected = format!("arrays (N, {nq}) and (N, {nv})");
        let got = format!("{} and {}", shape_str(&qs), shape_str(&vs));
        return Err(Error::arg("q, v", expected, got).into());
    }
    Ok(effect.contact_states(model, &qv, &vv)?)
}

#[cfg(test)]
#[path = "tests/args.rs"]
mod tests;

/// [`Effect::with_parameter`] of a binding's value (one number or an array of them).
pub fn with_parameter<A: Arg>(effect: &Effect, key: &str, value: &A) -> R<Effect, A> {
    let (_, values) = value.array(key)?;
    Ok(effect.with_parameter(key, &values)?)
}

/// A binding's value that may be one of its effect objects.
pub trait EffectArg: Arg {
    /// The effect it holds, if it is an effect object.
    fn effect(&self) -> Option<Effect>;
}

/// A list of effects (a lone effect is a common slip: the error says what a list is, not
/// "not iterable"), each item named by its index when it is no effect.
pub fn effect_list<A: EffectArg>(effects: &A) -> R<Vec<Effect>, A> {
    let expected = "a list of effects such as [pmd.Gravity()]";
    let items = items(effects, "effects", expected)?;
    let one = |(k, e): (usize, &A)| {
        let expected = "an effect such as pmd.Gravity(...)";
        let bad = || Error::arg(format!("effects[{k}]"), expected, e.shown()).into();
        e.effect().ok_or_else(bad)
    };
    items.iter().enumerate().map(one).collect()
}
