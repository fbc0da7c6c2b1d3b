//! The frame calls' arguments as a binding hands them over ([`Arg`]): a frame by name or
//! index, the optional speeds and accelerations, the inverse-kinematics tasks and options.
//! Parsed here, once (not in `model::args`, which `frames` must not import back).
use super::ik::{self, Options, Target, Task};
use super::{FrameRef, ReferenceFrame};
use crate::model::{checked_rotation, Model};
use crate::support::args::{given, int, items, mat3, vec3, vector, Arg};
use crate::support::error::{check_finite, Error};
use crate::support::spatial::Placement;

type R<T, A> = Result<T, <A as Arg>::Err>;

/// A frame: its name (a body or an added frame) or its index in `Model.frame_names` (the
/// bodies', then the added frames'; a body's index is its frame's).
pub fn frame<A: Arg>(model: &Model, x: &A, arg: &str) -> R<FrameRef, A> {
    if let Some(name) = x.text() {
        return Ok(model.frame_named(arg, &name)?);
    }
    let (nb, nf) = (model.nbodies(), model.frames.len());
    let expected = "a frame name or index (Model.frame_names)";
    let k = int(x, arg, 0, (nb + nf) as i64 - 1, expected)? as usize;
    Ok(match k.checked_sub(nb) {
        Some(i) => model.body_frame(model.frames[i].body, &model.frames[i].placement),
        None => model.body_frame(k, &Placement::identity()),
    })
}

/// A frame ([`frame`], named `frame` in errors) and the reference frame a quantity of it is
/// expressed in.
pub fn frame_in<A: Arg>(model: &Model, x: &A, reference: &str) -> R<(FrameRef, ReferenceFrame), A> {
    let f = frame(model, x, "frame")?;
    Ok((f, ReferenceFrame::parse("reference", reference)?))
}

/// An optional vector of nv values (`v`, `a`), checked; `None`: not given.
pub fn speeds<A: Arg>(model: &Model, x: Option<&A>, arg: &str) -> R<Option<Vec<f64>>, A> {
    let Some(x) = given(x) else { return Ok(None) };
    let v = vector(x, arg, Some(model.nv))?;
    model.check_vector(arg, &v)?;
    Ok(Some(v))
}

/// The tasks of inverse kinematics: `(frame, rotation (3, 3) or None for a position target,
/// position (3,), weights (3 or 6 numbers >= 0))` each.
pub fn ik_tasks<A: Arg>(model: &Model, tasks: &A) -> R<Vec<Task>, A> {
    let expected = "(frame, rotation or None, position, weights) per target";
    let mut out = Vec::new();
    for task in items(tasks, "targets", expected)? {
        let parts = items(&task, "targets", expected)?;
        let [f, rot, pos, weights] = &parts[..] else {
            return Err(Error::arg("targets", expected, task.shown()).into());
        };
        let frame = frame(model, f, "targets")?;
        let t = vec3(pos, "targets")?;
        check_finite("targets", t.as_slice())?;
        let target = match given(Some(rot)) {
            Some(r) => {
                let r = checked_rotation(&mat3(r, "targets")?, "targets")?;
                Target::Pose(Placement::new(r, t))
            }
            None => Target::Position(t),
        };
        let rows = if matches!(target, Target::Pose(_)) {
            6
        } else {
            3
        };
        let weights = vector(weights, "weights", None)?;
        if weights.len() != rows || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            let expected = format!("{rows} finite weights >= 0 for this target");
            return Err(Error::arg("weights", expected, format!("{weights:?}")).into());
        }
        out.push(Task {
            frame,
            target,
            weights,
        });
    }
    Ok(out)
}

/// The options of inverse kinematics; `limits`: the model's joint limits kept.
pub fn ik_options(
    model: &Model,
    limits: bool,
    tol: f64,
    [max_iterations, restarts]: [usize; 2],
    seed: u64,
) -> crate::support::error::Result<Options> {
    if !(tol > 0.0 && tol.is_finite()) {
        return Err(Error::arg("tol", "a finite number > 0", tol.to_string()));
    }
    let limits = limits.then(|| ik::joint_limits(model));
    Ok(Options {
        tol,
        max_iterations,
        restarts,
        limits,
        seed,
    })
}
