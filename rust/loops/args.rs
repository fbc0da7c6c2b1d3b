//! The closed-loop calls' arguments as a binding hands them over ([`Arg`]): assembly's
//! tolerance and iteration limit, a loop's ends, a coupling's arguments; and the residual at
//! a configuration in one call.
use super::LoopKinematics;
use crate::effects::args::joint_body;
use crate::model::args::body;
use crate::model::Model;
use crate::support::args::{int, opt, placement, Arg};
use crate::support::error::Error;
use crate::support::spatial::Placement;

/// Assembly's `tol` (positive, finite) and `max_iterations` (>= 1; `None`: 50).
pub fn assembly<A: Arg>(tol: f64, max_iterations: Option<&A>) -> Result<(f64, usize), A::Err> {
    if !(tol > 0.0 && tol.is_finite()) {
        return Err(Error::arg("tol", "a positive finite number", tol.to_string()).into());
    }
    let expected = "a whole number of iterations >= 1";
    let n = opt(max_iterations, |m| {
        int(m, "max_iterations", 1, i64::MAX, expected)
    })?;
    Ok((tol, n.map_or(50, |n| n as usize)))
}

/// The constraint residual (cut joints', then couplings') at a checked `q`.
pub fn residual_at(model: &Model, q: &[f64]) -> Vec<f64> {
    let mut kin = LoopKinematics::new(model);
    kin.positions(model, q);
    let mut r = vec![0.0; model.nconstraints()];
    super::residual(model, &kin, &mut r);
    r
}

/// `Model.add_loop`'s two ends: each one's body (`None`: the world) and the cut joint's
/// placement on it (`translation_a`, `rotation_a`, then the same of `b`).
pub fn loop_ends<A: Arg>(
    model: &Model,
    bodies: [Option<&A>; 2],
    translations: [Option<&A>; 2],
    rotations: [Option<&A>; 2],
) -> Result<[(Option<usize>, Placement); 2], A::Err> {
    let fa = placement(translations[0], rotations[0], "translation_a", "rotation_a")?;
    let fb = placement(translations[1], rotations[1], "translation_b", "rotation_b")?;
    let a = body(model, bodies[0], "body_a")?;
    Ok([(a, fa), (body(model, bodies[1], "body_b")?, fb)])
}

/// `Model.add_coupling`'s joint and reference (`crate::effects::args::joint_body`), `ratio`
/// (1 if not given) and `offset` (0 if not given).
pub fn coupling<A: Arg>(
    model: &Model,
    [joint, reference]: [&A; 2],
    ratio: Option<&A>,
    offset: Option<&A>,
) -> Result<(usize, usize, f64, f64), A::Err> {
    // `real` refuses bools and strings with the argument's name (a bare f64 took True as 1).
    let ratio = opt(ratio, |x| x.real("ratio"))?.unwrap_or(1.0);
    let offset = opt(offset, |x| x.real("offset"))?.unwrap_or(0.0);
    let j = joint_body(model, joint, "joint")?;
    Ok((j, joint_body(model, reference, "reference")?, ratio, offset))
}
