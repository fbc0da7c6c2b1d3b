//! `Model`'s frame calls as a binding asks for them: each reads the method's arguments
//! ([`Arg`], in the order the method lists them, so the first bad one is the one named) with
//! the caller's interpreter held, and returns the computation, which the binding runs
//! (detached from the interpreter, Ctrl-C heard, where it can be long) and converts. The batched `frame_jacobian`,
//! `center_of_mass` and `frame_placement` are not here: they compute in a pooled workspace.
use nalgebra::DMatrix;

use super::args::{frame, frame_in, ik_options, ik_tasks, speeds};
use super::{constrained, evaluate, ik, placement};
use crate::kinematics::poses::{Keyed, Shaped};
use crate::model::args::{configurations, speeds_named, state};
use crate::model::Model;
use crate::support::args::{given, vec3, Arg};
use crate::support::error::Result;

/// Arguments read, or the binding's error.
type Read<T, A> = std::result::Result<T, <A as Arg>::Err>;
/// A frame's velocity and acceleration, (6,) each.
type Motion = (Vec<f64>, Vec<f64>);
/// The centre of mass's position, velocity and acceleration, (3,) each.
type ComMotion = (Vec<f64>, Vec<f64>, Vec<f64>);
/// `G` (nv, k) and the independent speeds' v indices.
type IndependentMap = (DMatrix<f64>, Vec<usize>);

/// `point_path`: the world positions (N, 3) of `point` (in `frame`) at q (N, nq) and, with
/// `v` (N, nv), its velocities (N, 3).
pub fn point_path<'m, A: Arg>(
    model: &'m Model,
    frame_arg: &A,
    point: &A,
    q: &A,
    v: Option<&A>,
) -> Read<impl FnOnce() -> Result<(Shaped, Option<Shaped>)> + Send + 'm, A> {
    let f = frame(model, frame_arg, "frame")?;
    let p = vec3(point, "point")?;
    let (rows, qs, _) = configurations(model, q, "q")?;
    let vs = crate::model::args::speeds(model, v, rows)?;
    Ok(move || {
        let (pos, vel) = placement::point_path_of(model, &f, &p, &qs, vs.as_deref(), rows)?;
        let vel = vel.map(|vel| Shaped::new(vel, &[rows, 3]));
        Ok((Shaped::new(pos, &[rows, 3]), vel))
    })
}

/// `frame_jacobian_dot`: `J̇` (6, nv) of `frame` in `reference` at `(q, v)`.
pub fn frame_jacobian_dot<'m, A: Arg>(
    model: &'m Model,
    frame_arg: &A,
    q: &A,
    v: &A,
    reference: &str,
) -> Read<impl FnOnce() -> Result<Shaped> + Send + 'm, A> {
    let (q, v) = state(model, (q, "q"), Some((v, "v")))?;
    let (f, rf) = frame_in(model, frame_arg, reference)?;
    Ok(move || {
        let jd = evaluate::frame_jacobian_dot(model, &f, rf, &q, &v)?;
        Ok(Shaped::new(jd, &[6, model.nv]))
    })
}

/// `frame_motion`: the frame's velocity `J v` and acceleration `J a + J̇ v` (a = None: zero)
/// in `reference`, (6,) each.
pub fn frame_motion<'m, A: Arg>(
    model: &'m Model,
    frame_arg: &A,
    q: &A,
    v: &A,
    a: Option<&A>,
    reference: &str,
) -> Read<impl FnOnce() -> Result<Motion> + Send + 'm, A> {
    let (q, v) = state(model, (q, "q"), Some((v, "v")))?;
    let a = speeds(model, a, "a")?;
    let (f, rf) = frame_in(model, frame_arg, reference)?;
    Ok(move || {
        let (vel, acc) = evaluate::frame_motion(model, &f, rf, &q, &v, a.as_deref())?;
        Ok((vel.as_slice().to_vec(), acc.as_slice().to_vec()))
    })
}

/// `center_of_mass_motion`: the COM's position, velocity and acceleration (a = None: zero).
pub fn com_motion<'m, A: Arg>(
    model: &'m Model,
    q: &A,
    v: &A,
    a: Option<&A>,
) -> Read<impl FnOnce() -> Result<ComMotion> + Send + 'm, A> {
    let (q, v) = state(model, (q, "q"), Some((v, "v")))?;
    let a = speeds(model, a, "a")?;
    Ok(move || {
        let [c, vc, ac] = evaluate::com_motion(model, &q, &v, a.as_deref())?;
        let [c, vc, ac] = [c, vc, ac].map(|x| x.as_slice().to_vec());
        Ok((c, vc, ac))
    })
}

/// `centroidal`: `A` (A_g, 6 × nv) and, with `v`, `momentum` (A_g v) and `rate` (A_g a +
/// Ȧ_g v), by name: the keys a caller gets depend on whether `v` was given.
pub fn centroidal<'m, A: Arg>(
    model: &'m Model,
    q: &A,
    v: Option<&A>,
    a: Option<&A>,
) -> Read<impl FnOnce() -> Result<Vec<Keyed>> + Send + 'm, A> {
    let (q, _) = state(model, (q, "q"), None)?;
    let v = speeds(model, v, "v")?;
    let a = speeds(model, a, "a")?;
    Ok(move || {
        let (ag, rest) = evaluate::centroidal(model, &q, v.as_deref(), a.as_deref())?;
        let mut out = vec![("A", Shaped::new(ag, &[6, model.nv]))];
        if let Some((h, hdot)) = rest {
            out.push(("momentum", Shaped::new(h.as_slice().to_vec(), &[6])));
            out.push(("rate", Shaped::new(hdot.as_slice().to_vec(), &[6])));
        }
        Ok(out)
    })
}

/// `independent_map`: `G` (nv, k) with v = G v_I for the speeds `independent` (v indices or
/// body names; None: chosen from the constraint Jacobian), and their v indices.
pub fn independent_map<'m, A: Arg>(
    model: &'m Model,
    q: &A,
    independent: Option<&A>,
) -> Read<impl FnOnce() -> Result<IndependentMap> + Send + 'm, A> {
    let (q, _) = state(model, (q, "q"), None)?;
    let idx = given(independent).map(|x| speeds_named(model, x, "independent"));
    let idx = idx.transpose()?;
    Ok(move || constrained::independent_map_for(model, &q, idx))
}

/// `_inverse_kinematics`: tasks are (frame, rotation (3, 3) or None for a position target,
/// position (3,), weights (3 or 6 floats)).
#[allow(clippy::too_many_arguments)]
pub fn inverse_kinematics<'m, A: Arg>(
    model: &'m Model,
    tasks: &A,
    q0: &A,
    limits: bool,
    tol: f64,
    max_iterations: usize,
    restarts: usize,
    seed: u64,
) -> Read<impl FnOnce() -> Result<ik::Solution> + Send + 'm, A> {
    let (q0, _) = state(model, (q0, "q0"), None)?;
    let tasks = ik_tasks(model, tasks)?;
    let opts = ik_options(model, limits, tol, [max_iterations, restarts], seed)?;
    Ok(move || ik::solve(model, &tasks, &q0, &opts))
}
