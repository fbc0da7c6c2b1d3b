//! Argument conversion for the closed-loop methods of `Model` (`add_loop`, `assemble`, ...):
//! bodies by index or name, held coordinates and actuated joints as v masks/indices.
use pyo3::prelude::*;
use pyo3::types::{PyList, PyString, PyTuple};

use super::convert::int_arg;
use super::errors::{invalid, py_error};
use crate::model::Model;

/// A body given as an index (−1: the world), a name, or "world"/None.
pub fn body_ref(
    model: &Model,
    obj: Option<&Bound<'_, PyAny>>,
    arg: &str,
) -> PyResult<Option<usize>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let py = obj.py();
    let n = model.nbodies();
    if let Ok(name) = obj.cast::<PyString>() {
        let name = name.to_cow()?;
        let name = name.as_ref();
        if name == "world" {
            return Ok(None);
        }
        return model.body_index(name).map(Some).ok_or_else(|| {
            py_error(
                py,
                "ModelStructureError",
                format!("{arg}: no body named '{name}' (the model has {n} bodies; 'world' is the ground)"),
            )
        });
    }
    let k = int_arg(
        obj,
        arg,
        i64::MIN,
        i64::MAX,
        "a body index, a body name, or -1 / 'world' for the ground",
    )?;
    match k {
        -1 => Ok(None),
        k if k >= 0 && (k as usize) < n => Ok(Some(k as usize)),
        k => Err(py_error(
            py,
            "ModelStructureError",
            format!("{arg}: expected -1 (the world) or a body index 0..{n}, got {k}"),
        )),
    }
}

/// The link of a named/indexed moving body, for `fixed` and `actuated` entries.
fn moving_link(model: &Model, obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<usize> {
    let body = body_ref(model, Some(obj), arg)?;
    let py = obj.py();
    let link = body.and_then(|b| {
        let l = model.bodies[b].link?;
        (model.links[l].body == b).then_some(l)
    });
    link.ok_or_else(|| {
        invalid(
            py,
            arg,
            "the name of a body on a moving joint",
            match body {
                Some(b) => format!(
                    "'{}', which has no joint coordinates (fixed joint)",
                    model.bodies[b].name
                ),
                None => "the world".to_string(),
            },
        )
    })
}

fn items<'py>(
    obj: &Bound<'py, PyAny>,
    arg: &str,
    expected: &str,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    if obj.is_instance_of::<PyString>() || obj.extract::<i64>().is_ok() {
        return Ok(vec![obj.clone()]);
    }
    if obj.is_instance_of::<PyList>()
        || obj.is_instance_of::<PyTuple>()
        || obj.hasattr("__array__")?
    {
        return obj.try_iter()?.collect();
    }
    Err(invalid(
        obj.py(),
        arg,
        expected,
        format!("an object of type {}", obj.get_type().name()?),
    ))
}

const FIXED: &str = "a list of q indices (int) or body names (str)";

/// `fixed` as a mask over v: a q index marks its joint's speed (all speeds of a quaternion
/// joint, whose q and v differ), a body name all of that body's joint speeds.
pub fn fixed_mask(model: &Model, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<bool>> {
    let mut mask = vec![false; model.nv];
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(mask);
    };
    for item in items(obj, "fixed", FIXED)? {
        let link = if item.is_instance_of::<PyString>() {
            moving_link(model, &item, "fixed")?
        } else {
            let nq = model.nq;
            let k = int_arg(
                &item,
                "fixed",
                0,
                nq as i64 - 1,
                &format!("q indices 0..{nq} or body names"),
            )? as usize;
            let l = model
                .links
                .iter()
                .position(|l| (l.q_index..l.q_index + l.joint.nq()).contains(&k))
                .unwrap_or(0);
            let link = &model.links[l];
            if link.joint.nq() == link.joint.nv() {
                mask[link.v_index + k - link.q_index] = true;
                continue;
            }
            l
        };
        let link = &model.links[link];
        mask[link.v_index..link.v_index + link.joint.nv()].fill(true);
    }
    Ok(mask)
}

/// The actuated joints a call needs: `None` for a model without loops (every joint is
/// actuated, and naming some is an error), their v indices for a model with loops (where
/// they are required: the cut joints' forces are otherwise undetermined).
pub fn loop_actuation(
    py: Python<'_>,
    model: &Model,
    actuated: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<Vec<usize>>> {
    let actuated = actuated.filter(|x| !x.is_none());
    // With couplings alone `None` gives the tree's forces (each joint driven on its own);
    // with loops the cut joints' forces are otherwise undetermined.
    match (model.has_constraints(), actuated) {
        (_, None) if model.loops.is_empty() => Ok(None),
        (false, Some(x)) => Err(invalid(
            x.py(),
            "actuated",
            "None for a model without loops or couplings (every joint is actuated)",
            x.repr()?.to_string(),
        )),
        (true, Some(x)) => actuated_indices(model, x).map(Some),
        (_, None) => Err(invalid(
            py,
            "actuated",
            format!("the actuated joints (v indices or body names) for a model with {} loop(s): the cut joints' forces are otherwise undetermined", model.loops.len()),
            "None",
        )),
    }
}

/// `actuated` as sorted v indices: ints are v indices, names all of that body's joint speeds.
pub fn actuated_indices(model: &Model, obj: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    let nv = model.nv;
    let mut mask = vec![false; nv];
    for item in items(
        obj,
        "actuated",
        "a list of v indices (int) or body names (str)",
    )? {
        if item.is_instance_of::<PyString>() {
            let l = &model.links[moving_link(model, &item, "actuated")?];
            mask[l.v_index..l.v_index + l.joint.nv()].fill(true);
        } else {
            let k = int_arg(
                &item,
                "actuated",
                0,
                nv as i64 - 1,
                &format!("v indices 0..{nv} or body names"),
            )?;
            mask[k as usize] = true;
        }
    }
    Ok((0..nv).filter(|&k| mask[k]).collect())
}
