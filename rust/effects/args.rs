//! The effects built from a binding's arguments ([`Arg`]): the forms a caller writes
//! (`pmd.Spring(joints, stiffness, ...)` in Python) read here, once, so the binding only
//! converts. A scene file's `[[effect]]` tables are read by `scene_file.rs`.
use super::ground_contact::ContactStates;
use super::{
    ContactPoint, Damper, Disabled, Effect, External, Frame, Friction, GroundContact, JointLimit,
    JointRef, Matrix, PerJoint, PointSpring, Spring, Table, Torque, TorqueFunction, TorqueLimit,
};
use crate::model::Model;
use crate::support::args::{given, int, items, opt, shape_str, vec3, vector, Arg, Int};
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

pub fn table<A: Arg>(time: &A, values: &A, values_arg: &str) -> R<Table, A> {
    let t = vector(time, "time", None)?;
    let m = matrix(values, values_arg)?;
    Ok(Table::new(t, m, "time", values_arg)?)
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

pub fn spring<A: Arg>(
    joints_: Option<&A>,
    k: &A,
    rest: Option<&A>,
    name: Option<String>,
) -> R<Effect, A> {
    let joints = joints(joints_)?;
    let k = per_joint(k, "stiffness")?;
    let rest = opt(rest, |r| per_joint(r, "rest"))?;
    Ok(Effect::Spring(Spring::new(name, joints, k, rest)?))
}

pub fn damper<A: Arg>(joints_: Option<&A>, c: &A, name: Option<String>) -> R<Effect, A> {
    let joints = joints(joints_)?;
    let c = per_joint(c, "damping")?;
    Ok(Effect::Damper(Damper::new(name, joints, c)?))
}

pub fn friction<A: Arg>(
    joints_: Option<&A>,
    f: &A,
    v_eps: Option<&A>,
    name: Option<String>,
) -> R<Effect, A> {
    let v_eps = opt(v_eps, |x| x.real("v_eps"))?;
    let joints = joints(joints_)?;
    let f = per_joint(f, "friction")?;
    Ok(Effect::Friction(Friction::new(name, joints, f, v_eps)?))
}

pub fn joint_torque<A: Arg>(joints_: Option<&A>, tau: &A, name: Option<String>) -> R<Effect, A> {
    let joints = joints(joints_)?;
    let tau = per_joint(tau, "tau")?;
    Ok(Effect::Torque(Torque::constant(name, joints, tau)?))
}

pub fn tabulated_torque<A: Arg>(
    joints_: Option<&A>,
    time: &A,
    values: &A,
    name: Option<String>,
) -> R<Effect, A> {
    let joints = joints(joints_)?;
    let table = table(time, values, "values")?;
    Ok(Effect::Torque(Torque::tabulated(name, joints, table)?))
}

/// PD torques tracking a tabulated reference: `gains` = (kp, kd), `reference` = (time, values).
pub fn pd_torque<A: Arg>(
    joints_: Option<&A>,
    gains: (&A, &A),
    reference: (&A, &A),
    name: Option<String>,
) -> R<Effect, A> {
    let joints = joints(joints_)?;
    let kp = per_joint(gains.0, "kp")?;
    let kd = per_joint(gains.1, "kd")?;
    let table = table(reference.0, reference.1, "reference")?;
    Ok(Effect::Torque(Torque::pd(name, joints, kp, kd, table)?))
}

pub fn torque_function(f: TorqueFunction, name: Option<String>) -> Effect {
    Effect::Torque(Torque::function(name, f))
}

/// A force and a moment on a body at a body-fixed point: `load` = (force, moment), each
/// constant, or tabulated at `time` (rows per time).
pub fn external_force<A: Arg>(
    body: &A,
    load: (Option<&A>, Option<&A>),
    point: Option<&A>,
    time: Option<&A>,
    frame: &str,
    name: Option<String>,
) -> R<Effect, A> {
    let body = joint_ref(body, "body")?;
    let point = opt(point, |p| vec3(p, "point"))?.unwrap_or_else(Vec3::zeros);
    let frame = Frame::parse(frame, "frame")?;
    let (force, moment) = (given(load.0), given(load.1));
    if force.is_none() && moment.is_none() {
        return Err(Error::arg("force", "a force (or a moment)", "None").into());
    }
    let inner = match given(time) {
        Some(t) => {
            let t = vector(t, "time", None)?;
            let f = opt(force, |f| matrix(f, "force"))?;
            let m = opt(moment, |m| matrix(m, "moment"))?;
            External::tabulated(name, body, point, t, f, m, frame)?
        }
        None => {
            let f = opt(force, |f| vec3(f, "force"))?.unwrap_or_else(Vec3::zeros);
            let m = opt(moment, |m| vec3(m, "moment"))?.unwrap_or_else(Vec3::zeros);
            External::constant(name, body, point, f, m, frame)?
        }
    };
    Ok(Effect::External(inner))
}

/// A spring–damper between `a` = (body, point) and `b` = (body, point); `law` = (stiffness,
/// rest length (default 0), damping (default 0)).
pub fn point_spring<A: Arg>(
    a: (&A, &A),
    b: (&A, &A),
    law: (&A, Option<&A>, Option<&A>),
    name: Option<String>,
) -> R<Effect, A> {
    let body_a = body_or_world(a.0, "body_a")?;
    let point_a = vec3(a.1, "point_a")?;
    let body_b = body_or_world(b.0, "body_b")?;
    let point_b = vec3(b.1, "point_b")?;
    let k = law.0.real("stiffness")?;
    let rest = opt(law.1, |x| x.real("rest_length"))?.unwrap_or(0.0);
    let c = opt(law.2, |x| x.real("damping"))?.unwrap_or(0.0);
    let inner = PointSpring::new(name, body_a, point_a, body_b, point_b, k, rest, c)?;
    Ok(Effect::PointSpring(inner))
}

/// Ground contact: `plane` = (normal, height); `law` = (stiffness, exponent, damping,
/// friction, v_eps), stiffness and damping optional (the model's defaults).
pub fn ground_contact<A: Arg>(
    points: &A,
    plane: (&A, &A),
    law: (Option<&A>, &A, Option<&A>, &A, &A),
    name: Option<String>,
) -> R<Effect, A> {
    let inner = GroundContact::new(
        name,
        contact_points(points)?,
        vec3(plane.0, "normal")?,
        plane.1.real("height")?,
        opt(law.0, |x| x.real("stiffness"))?,
        law.1.real("exponent")?,
        opt(law.2, |x| x.real("damping"))?,
        law.3.real("friction")?,
        law.4.real("v_eps")?,
    )?;
    Ok(Effect::GroundContact(inner))
}

/// Compliant joint ranges: `bounds` = (lower, upper), each optional (the model's).
pub fn joint_limit<A: Arg>(
    joints_: Option<&A>,
    bounds: (Option<&A>, Option<&A>),
    stiffness: &A,
    damping: &A,
    name: Option<String>,
) -> R<Effect, A> {
    let joints = joints(joints_)?;
    let lower = opt(bounds.0, |x| per_joint(x, "lower"))?;
    let upper = opt(bounds.1, |x| per_joint(x, "upper"))?;
    let k = per_joint(stiffness, "stiffness")?;
    let c = per_joint(damping, "damping")?;
    Ok(Effect::JointLimit(JointLimit::new(
        name, joints, lower, upper, k, c,
    )?))
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

/// A ground contact along states `q` (N, nq) and `v` (N, nv): N and the contact at each.
pub fn contact_states<A: Arg>(
    contact: &GroundContact,
    model: &Model,
    q: &A,
    v: &A,
) -> R<(usize, ContactStates), A> {
    let (qs, qv) = q.array("q")?;
    let (vs, vv) = v.array("v")?;
    let (nq, nv) = (model.nq, model.nv);
    if qs.len() != 2 || qs[1] != nq || vs.len() != 2 || vs[1] != nv || vs[0] != qs[0] {
        let expected = format!("arrays (N, {nq}) and (N, {nv})");
        let got = format!("{} and {}", shape_str(&qs), shape_str(&vs));
        return Err(Error::arg("q, v", expected, got).into());
    }
    Ok((qs[0], contact.states(model, &qv, &vv)?))
}
