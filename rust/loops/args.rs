//! The closed-loop calls' arguments as a binding hands them over ([`Arg`]): assembly's
//! tolerance and iteration limit; and the residual at a configuration in one call.
use super::LoopKinematics;
use crate::model::Model;
use crate::support::args::{int, opt, Arg};
use crate::support::error::Error;

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
