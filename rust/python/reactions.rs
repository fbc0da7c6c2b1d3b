//! Arguments of the shaking-force and bearing-force methods of `Model` (crate::dynamics::reactions).
use pyo3::prelude::*;

use super::convert::{array, shape_str};
use super::errors::{invalid, IntoPyResult};
use super::signals::detach_interruptible;
use crate::model::Model;

/// One state or a stack of them: `q` (nq,) or (N, nq), `v` and `a` (nv,) or (N, nv), the same
/// N. Returns N (`None` for a single state) and the states row by row; every row checked.
#[allow(clippy::type_complexity)]
pub fn states(
    model: &Model,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    a: &Bound<'_, PyAny>,
) -> PyResult<(Option<usize>, Vec<f64>, Vec<f64>, Vec<f64>)> {
    let py = q.py();
    let (sq, q) = array(q, "q")?;
    let (sv, vv) = array(v, "v")?;
    let (sa, av) = array(a, "a")?;
    let count = match sq.as_slice() {
        [n] if *n == model.nq => None,
        [rows, n] if *n == model.nq => Some(*rows),
        _ => {
            return Err(invalid(
                py,
                "q",
                format!("shape ({0},) or (N, {0})", model.nq),
                shape_str(&sq),
            ))
        }
    };
    for (arg, shape) in [("v", &sv), ("a", &sa)] {
        let want: Vec<usize> = match count {
            None => vec![model.nv],
            Some(rows) => vec![rows, model.nv],
        };
        if *shape != want {
            return Err(invalid(
                py,
                arg,
                format!("{} (as q)", shape_str(&want)),
                shape_str(shape),
            ));
        }
    }
    // Row by row (a loop model's check closes its loops): long for many states, so with the
    // interpreter released and Ctrl-C honoured.
    detach_interruptible(py, || check_rows(model, count, &q, &vv, &av))?;
    Ok((count, q, vv, av))
}

fn check_rows(
    model: &Model,
    count: Option<usize>,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> crate::support::error::Result<()> {
    for k in 0..count.unwrap_or(1) {
        crate::support::interrupt::check("checking the states")?;
        let qk = &q[k * model.nq..(k + 1) * model.nq];
        let vk = &v[k * model.nv..(k + 1) * model.nv];
        let row = |e: crate::support::error::Error| match count {
            Some(_) => e.map_arg(|name| format!("{name}[{k}]")),
            None => e,
        };
        model.check_state(qk, Some(vk)).map_err(row)?;
        crate::support::error::check_finite("a", &a[k * model.nv..(k + 1) * model.nv])
            .map_err(row)?;
    }
    Ok(())
}

/// `frame`: "joint" (each link's own axes) or "world".
pub fn world_frame(py: Python<'_>, frame: &str) -> PyResult<bool> {
    match frame {
        "joint" => Ok(false),
        "world" => Ok(true),
        other => Err(invalid(
            py,
            "frame",
            "\"joint\" or \"world\"",
            format!("'{other}'"),
        )),
    }
}

/// `[(body, [x, y, z]), ...]`: points in their bodies' frames as `(link, offset in the link
/// frame)`. A body welded to the world carries no moving point and is refused.
pub fn body_points(
    model: &Model,
    list: &Bound<'_, PyAny>,
) -> PyResult<Vec<(usize, crate::support::spatial::Vec3)>> {
    let py = list.py();
    let expected =
        "a list of (body, [x, y, z]) pairs: a body index or name and a point in its frame";
    let mut out = Vec::new();
    for (k, item) in list.try_iter()?.enumerate() {
        let item = item?;
        let arg = format!("points[{k}]");
        let (body, xyz): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item.extract().map_err(|_| {
            invalid(
                py,
                &arg,
                expected,
                item.repr().map_or("?".into(), |r| r.to_string()),
            )
        })?;
        let b = super::loops::body_ref(model, Some(&body), &arg)?
            .ok_or_else(|| invalid(py, &arg, "a body of the model (not the world)", "the world"))?;
        let link = model.bodies[b].link.ok_or_else(|| {
            invalid(
                py,
                &arg,
                "a body that moves (not welded to the world)",
                format!("'{}'", model.bodies[b].name),
            )
        })?;
        let p = super::convert::vec3(&xyz, &arg)?;
        crate::support::error::check_finite(&arg, p.as_slice()).py(py)?;
        out.push((link, model.bodies[b].in_link.act_point(&p)));
    }
    Ok(out)
}
