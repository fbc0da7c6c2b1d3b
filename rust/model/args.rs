//! A model's arguments as a binding hands them over ([`Arg`]): a body by name or index (or
//! the world), the held coordinates of `assemble`, the actuated joints of a closed-loop
//! model, gravity and external wrenches. Parsed here, once, so the binding only converts;
//! every refusal names the argument, the expected form and what was given.
use super::visual::{Shape, Visual};
use super::Model;
use crate::support::args::vector;
use crate::support::args::{count, given, int, items, opt, placement, shape_str, text, vec3};
use crate::support::args::{Arg, Int};
use crate::support::error::{check_finite, Error};
use crate::support::spatial::{Placement, Vec3, Vec6};

type R<T, A> = Result<T, <A as Arg>::Err>;

/// A body given as an index (−1: the world), a name, or `"world"`/`None`: `None` for the
/// world.
pub fn body<A: Arg>(model: &Model, x: Option<&A>, arg: &str) -> R<Option<usize>, A> {
    let Some(x) = given(x) else {
        return Ok(None);
    };
    if let Some(name) = x.text() {
        return match name.as_str() {
            "world" => Ok(None),
            name => Ok(Some(model.body_named(arg, name)?)),
        };
    }
    let expected = "a body index, a body name, or -1 / 'world' for the ground";
    let n = model.nbodies();
    match int(x, arg, i64::MIN, i64::MAX, expected)? {
        -1 => Ok(None),
        k if k >= 0 && (k as usize) < n => Ok(Some(k as usize)),
        k => Err(Error::model(
            arg,
            format!("expected -1 (the world) or a body index 0..{n}, got {k}"),
        )
        .into()),
    }
}

/// A body of the model, not the world.
pub fn some_body<A: Arg>(model: &Model, x: &A, arg: &str) -> R<usize, A> {
    let world = || Error::arg(arg, "a body of the model (not the world)", "the world");
    body(model, Some(x), arg)?.ok_or_else(|| world().into())
}

/// The link of a named or indexed moving body, for `fixed` and `actuated` entries.
fn moving_link<A: Arg>(model: &Model, x: &A, arg: &str) -> R<usize, A> {
    let body = body(model, Some(x), arg)?;
    let link = body.and_then(|b| {
        let l = model.bodies[b].link?;
        (model.links[l].body == b).then_some(l)
    });
    let got = || match body {
        Some(b) => format!(
            "'{}', which has no joint coordinates (fixed joint)",
            model.bodies[b].name
        ),
        None => "the world".to_string(),
    };
    link.ok_or_else(|| Error::arg(arg, "the name of a body on a moving joint", got()).into())
}

/// `f` of each entry of `x`: one name or index, or a sequence of them.
fn each<A: Arg>(x: &A, arg: &str, expected: &str, mut f: impl FnMut(&A) -> R<(), A>) -> R<(), A> {
    if x.text().is_some() || matches!(x.int(), Int::Value(_)) {
        return f(x);
    }
    match x.items() {
        Some(items) => items?.iter().try_for_each(f),
        None => Err(Error::arg(arg, expected, x.shown()).into()),
    }
}

/// `fixed` as a mask over v: a q index marks its joint's speed (all speeds of a quaternion
/// joint, whose q and v differ), a body name all of that body's joint speeds.
pub fn fixed_mask<A: Arg>(model: &Model, x: Option<&A>) -> R<Vec<bool>, A> {
    let mut mask = vec![false; model.nv];
    let Some(x) = given(x) else {
        return Ok(mask);
    };
    let nq = model.nq;
    let expected = "a list of q indices (int) or body names (str)";
    each(x, "fixed", expected, |item| {
        let l = if item.text().is_some() {
            moving_link(model, item, "fixed")?
        } else {
            let want = format!("q indices 0..{nq} or body names");
            let k = int(item, "fixed", 0, nq as i64 - 1, &want)? as usize;
            let l = model
                .links
                .iter()
                .position(|l| (l.q_index..l.q_index + l.joint.nq()).contains(&k));
            let link = &model.links[l.unwrap_or(0)];
            if link.joint.nq() == link.joint.nv() {
                mask[link.v_index + k - link.q_index] = true;
                return Ok(());
            }
            l.unwrap_or(0)
        };
        let link = &model.links[l];
        mask[link.v_index..link.v_index + link.joint.nv()].fill(true);
        Ok(())
    })?;
    Ok(mask)
}

/// `actuated` as sorted v indices: ints are v indices, names all of that body's joint speeds.
pub fn actuated<A: Arg>(model: &Model, x: &A) -> R<Vec<usize>, A> {
    speeds_named(model, x, "actuated")
}

/// The actuated joints a call needs: `None` for a model without loops (every joint is
/// actuated, and naming some is an error), their v indices for a model with loops (where
/// they are required: the cut joints' forces are otherwise undetermined). With couplings
/// alone, `None` gives the tree's forces (each joint driven on its own).
pub fn loop_actuation<A: Arg>(model: &Model, x: Option<&A>) -> R<Option<Vec<usize>>, A> {
    match (model.has_constraints(), given(x)) {
        (_, None) if model.loops.is_empty() => Ok(None),
        (false, Some(x)) => {
            let expected = "None for a model without loops or couplings (every joint is actuated)";
            Err(Error::arg("actuated", expected, x.shown()).into())
        }
        (true, Some(x)) => actuated(model, x).map(Some),
        (_, None) => Err(Error::arg(
            "actuated",
            format!("the actuated joints (v indices or body names) for a model with {} loop(s): the cut joints' forces are otherwise undetermined", model.loops.len()),
            "None",
        )
        .into()),
    }
}

/// Gravity `g` (3,), finite; `None` means no gravity: a model computes only what it is
/// asked for.
pub fn gravity<A: Arg>(x: Option<&A>) -> R<Vec3, A> {
    let Some(x) = given(x) else {
        return Ok(Vec3::zeros());
    };
    let g = vec3(x, "gravity")?;
    check_finite("gravity", g.as_slice())?;
    Ok(g)
}

/// The point moments are taken about (3,), finite; `None`: the world origin.
pub fn about<A: Arg>(x: Option<&A>) -> R<Vec3, A> {
    let Some(x) = given(x) else {
        return Ok(Vec3::zeros());
    };
    let o = vec3(x, "about")?;
    check_finite("about", o.as_slice())?;
    Ok(o)
}

/// A trajectory's samples `t` (N,), `q` (N, nq), `v` (N, nv), finite (a bad one named by
/// its sample), as flat arrays.
pub fn samples<A: Arg>(model: &Model, t: &A, q: &A, v: &A) -> R<[Vec<f64>; 3], A> {
    let ((ts, t), (qs, q), (vs, v)) = (t.array("t")?, q.array("q")?, v.array("v")?);
    let (n, nq, nv) = (t.len(), model.nq, model.nv);
    if ts.len() != 1 || qs != [n, nq] || vs != [n, nv] {
        let got = [&ts, &qs, &vs].map(|s| shape_str(s)).join(", ");
        let expected = format!("shapes (N,), (N, {nq}), (N, {nv})");
        return Err(Error::arg("t, q, v", expected, got).into());
    }
    let row = |k: usize| {
        q[k * nq..(k + 1) * nq]
            .iter()
            .chain(&v[k * nv..(k + 1) * nv])
    };
    if let Some(k) = (0..n).find(|&k| !t[k].is_finite() || row(k).any(|x| !x.is_finite())) {
        let got = format!("a non-finite value at sample {k}");
        return Err(Error::arg("t, q, v", "finite values", got).into());
    }
    Ok([t, q, v])
}

/// External wrenches, one `[moment about the link origin; force]` per moving link (world
/// axes), finite; `None`: none.
pub fn external<A: Arg>(model: &Model, x: Option<&A>) -> R<Option<Vec<Vec6>>, A> {
    let Some(x) = given(x) else {
        return Ok(None);
    };
    let (shape, data) = x.array("external")?;
    let n = model.links.len();
    if shape != [n, 6] {
        let expected = format!("shape ({n}, 6): one wrench [moment about the link origin; force] per moving link, world axes");
        return Err(Error::arg("external", expected, shape_str(&shape)).into());
    }
    check_finite("external", &data)?;
    Ok(Some(
        data.chunks_exact(6).map(Vec6::from_column_slice).collect(),
    ))
}

/// A [`Visual`] from a mapping as a binding writes it (`body`, `kind`, the shape's sizes;
/// `rotation`, `translation` default to the identity, `rgba` to none, a mesh's `path` to its
/// `uri`, `scale` to ones). [`Visual::check`] then checks the values.
pub fn visual<A: Arg>(x: &A, arg: &str) -> R<Visual, A> {
    let at = |k: &str| format!("{arg}['{k}']");
    let Some(_) = x.get("body") else {
        return Err(Error::arg(arg, "a dict with 'body' and 'kind'", x.shown()).into());
    };
    let opt_key = |k: &str| x.get(k).flatten().filter(|v| !v.absent());
    let key = |k: &str| opt_key(k).ok_or_else(|| Error::arg(at(k), "a value", "nothing"));
    let num = |k: &str| key(k).map_err(A::Err::from).and_then(|v| v.real(&at(k)));
    let three = |k: &str| key(k).map_err(A::Err::from).and_then(|v| vec3(&v, &at(k)));
    let body = count(&key("body")?, &at("body"), "a body index")?;
    let kind_obj = key("kind")?;
    let shape = match kind_obj.text().as_deref() {
        Some("box") => Shape::Box {
            size: three("size")?,
        },
        Some("cylinder") => Shape::Cylinder {
            radius: num("radius")?,
            length: num("length")?,
        },
        Some("capsule") => Shape::Capsule {
            radius: num("radius")?,
            length: num("length")?,
        },
        Some("sphere") => Shape::Sphere {
            radius: num("radius")?,
        },
        Some("ellipsoid") => Shape::Ellipsoid {
            radii: three("radii")?,
        },
        Some("mesh") => {
            let uri = text(&key("uri")?, &at("uri"), "a string")?;
            let path = match x.get("path").flatten() {
                Some(p) if p.absent() => None,
                Some(p) => Some(text(&p, &at("path"), "a path (str) or None")?),
                None => Some(uri.clone()),
            };
            let scale = opt(opt_key("scale").as_ref(), |s| vec3(s, &at("scale")))?;
            let scale = scale.unwrap_or(Vec3::new(1.0, 1.0, 1.0));
            Shape::Mesh { uri, path, scale }
        }
        _ => {
            let expected = "'box', 'cylinder', 'capsule', 'sphere', 'ellipsoid' or 'mesh'";
            return Err(Error::arg(at("kind"), expected, kind_obj.shown()).into());
        }
    };
    let origin = placement(
        opt_key("translation").as_ref(),
        opt_key("rotation").as_ref(),
        &at("translation"),
        &at("rotation"),
    )?;
    let rgba = opt(opt_key("rgba").as_ref(), |c| {
        let c = vector(c, &at("rgba"), Some(4))?;
        Ok([c[0], c[1], c[2], c[3]])
    })?;
    let rotation = super::checked_rotation(&origin.rotation, &at("rotation"))?;
    Ok(Visual {
        body,
        origin: Placement::new(rotation, origin.translation),
        shape,
        rgba,
    })
}

/// Configurations `q` (nq,) or (N, nq): (rows, the values row by row, whether stacked).
pub fn configurations<A: Arg>(model: &Model, q: &A, arg: &str) -> R<(usize, Vec<f64>, bool), A> {
    let (shape, data) = q.array(arg)?;
    match shape.as_slice() {
        [n] if *n == model.nq => Ok((1, data, false)),
        [rows, n] if *n == model.nq => Ok((*rows, data, true)),
        _ => {
            let expected = format!("shape ({0},) or (N, {0})", model.nq);
            Err(Error::arg(arg, expected, shape_str(&shape)).into())
        }
    }
}

/// Speeds `v` for `rows` configurations: (rows, nv), or (nv,) for one; finite; `None`: none.
pub fn speeds<A: Arg>(model: &Model, v: Option<&A>, rows: usize) -> R<Option<Vec<f64>>, A> {
    let Some(v) = given(v) else { return Ok(None) };
    let (shape, data) = v.array("v")?;
    if shape != [rows, model.nv] && !(rows == 1 && shape == [model.nv]) {
        let expected = format!("shape ({rows}, {})", model.nv);
        return Err(Error::arg("v", expected, shape_str(&shape)).into());
    }
    check_finite("v", &data)?;
    Ok(Some(data))
}

/// One state or a stack of them: N (`None` for a single state) and the states row by row.
pub type Stack = (Option<usize>, Vec<f64>, Vec<f64>, Vec<f64>);

/// One state or a stack of them: `q` (nq,) or (N, nq), `v` and `a` (nv,) or (N, nv), the
/// same N; the shapes checked here, the values by [`check_rows`].
pub fn states<A: Arg>(model: &Model, q: &A, v: &A, a: &A) -> R<Stack, A> {
    let (sq, q) = q.array("q")?;
    let (sv, v) = v.array("v")?;
    let (sa, a) = a.array("a")?;
    let (nq, nv) = (model.nq, model.nv);
    let count = match sq.as_slice() {
        [n] if *n == nq => None,
        [rows, n] if *n == nq => Some(*rows),
        _ => {
            let expected = format!("shape ({nq},) or (N, {nq})");
            return Err(Error::arg("q", expected, shape_str(&sq)).into());
        }
    };
    let want: Vec<usize> = match count {
        None => vec![nv],
        Some(rows) => vec![rows, nv],
    };
    for (arg, shape) in [("v", &sv), ("a", &sa)] {
        if *shape != want {
            let expected = format!("{} (as q)", shape_str(&want));
            return Err(Error::arg(arg, expected, shape_str(shape)).into());
        }
    }
    Ok((count, q, v, a))
}

/// Each state of a stack checked (a loop model's check closes its loops: long for many
/// states, so Ctrl-C is honoured); errors name the row.
pub fn check_rows(
    model: &Model,
    count: Option<usize>,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> crate::support::error::Result<()> {
    let (nq, nv) = (model.nq, model.nv);
    for k in 0..count.unwrap_or(1) {
        crate::support::interrupt::check("checking the states")?;
        let row = |e: Error| match count {
            Some(_) => e.map_arg(|name| format!("{name}[{k}]")),
            None => e,
        };
        let (qk, vk) = (&q[k * nq..(k + 1) * nq], &v[k * nv..(k + 1) * nv]);
        model.check_state(qk, Some(vk)).map_err(row)?;
        check_finite("a", &a[k * nv..(k + 1) * nv]).map_err(row)?;
    }
    Ok(())
}

/// `[(body, [x, y, z]), ...]`: points in their bodies' frames as `(link, offset in the link
/// frame)`; `None`: every link's seven point masses, link by link. A body welded to the world
/// carries no moving point and is refused.
pub fn body_points<A: Arg>(model: &Model, list: Option<&A>) -> R<Vec<(usize, Vec3)>, A> {
    let Some(list) = given(list) else {
        let links = model.links.iter().enumerate();
        return Ok(links
            .flat_map(|(i, l)| l.points.positions.iter().map(move |p| (i, *p)))
            .collect());
    };
    let expected =
        "a list of (body, [x, y, z]) pairs: a body index or name and a point in its frame";
    let mut out = Vec::new();
    for (k, item) in items(list, "points", expected)?.iter().enumerate() {
        let arg = format!("points[{k}]");
        let pair = items(item, &arg, expected)?;
        let [body, xyz] = pair.as_slice() else {
            return Err(Error::arg(&arg, expected, item.shown()).into());
        };
        let b = some_body(model, body, &arg)?;
        let moving = "a body that moves (not welded to the world)";
        let named = || format!("'{}'", model.bodies[b].name);
        let link = model.bodies[b].link;
        let link = link.ok_or_else(|| Error::arg(&arg, moving, named()))?;
        let p = vec3(xyz, &arg)?;
        check_finite(&arg, p.as_slice())?;
        out.push((link, model.bodies[b].in_link.act_point(&p)));
    }
    Ok(out)
}

/// One state (`states`, a stack refused), checked.
pub fn one_state<A: Arg>(model: &Model, q: &A, v: &A, a: &A) -> R<[Vec<f64>; 3], A> {
    match states(model, q, v, a)? {
        (None, q, v, a) => {
            check_rows(model, None, &q, &v, &a)?;
            Ok([q, v, a])
        }
        _ => {
            let expected = format!("shape ({},): one state", model.nq);
            Err(Error::arg("q", expected, "a stack of states").into())
        }
    }
}

/// A checked state: `q` (nq,) and, when given, `v` (nv,) (empty when not), each named in
/// errors as the caller calls it (`q_guess`, `v_guess`).
pub fn state<A: Arg>(
    model: &Model,
    (q, q_arg): (&A, &str),
    v: Option<(&A, &str)>,
) -> R<(Vec<f64>, Vec<f64>), A> {
    let q = vector(q, q_arg, Some(model.nq))?;
    let (v, v_arg) = match v {
        Some((v, arg)) => (Some(vector(v, arg, Some(model.nv))?), arg),
        None => (None, "v"),
    };
    let named = |n: String| match n.as_str() {
        "q" => q_arg.to_string(),
        "v" => v_arg.to_string(),
        _ => n,
    };
    model
        .check_state(&q, v.as_deref())
        .map_err(|e| e.map_arg(named))?;
    Ok((q, v.unwrap_or_default()))
}

/// [`actuated`] under another argument name (`independent`): v indices or body names, as
/// sorted v indices.
pub fn speeds_named<A: Arg>(model: &Model, x: &A, arg: &str) -> R<Vec<usize>, A> {
    let nv = model.nv;
    let mut mask = vec![false; nv];
    let expected = "a list of v indices (int) or body names (str)";
    each(x, arg, expected, |item| {
        if item.text().is_some() {
            let l = &model.links[moving_link(model, item, arg)?];
            mask[l.v_index..l.v_index + l.joint.nv()].fill(true);
        } else {
            let want = format!("v indices 0..{nv} or body names");
            mask[int(item, arg, 0, nv as i64 - 1, &want)? as usize] = true;
        }
        Ok(())
    })?;
    Ok((0..nv).filter(|&k| mask[k]).collect())
}
