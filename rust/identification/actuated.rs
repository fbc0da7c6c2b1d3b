//! The regressor of the actuated joint forces, `τ_a = Y_a π`, for a mechanism with loops or
//! couplings driven at some of its joints (docs/identification.md §7).
//!
//! The actuated forces solve `S_aᵀ τ_a + Jᵀ λ = τ_tree` in the minimum-norm sense, as
//! `inverse_dynamics(..., actuated)` does ([`crate::loops::driving_forces`]); that solution is
//! `(τ_a, λ) = [S_a | Jᵀ]⁺ τ_tree`, linear in the tree's forces, so with `P(q)` the first
//! `na` rows of the pseudo-inverse, `Y_a = P(q) Y_tree`. `P` depends on the positions only:
//! the accelerations need not satisfy the loops exactly (measured ones never do).
use nalgebra::DMatrix;

use super::regressor::{check_states, tree_regressor, Extras};
use crate::loops::{self, LoopKinematics};
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec3;

/// Relative singular-value threshold of `[S_a | Jᵀ]` (J's redundant rows are exact zeros or
/// rounding; a mechanism's real stiffness is far above this).
const RANK_TOL: f64 = 1e-10;

/// Checks `actuated` (v indices, distinct, at least one) against `model`, which must have
/// loops or couplings (a tree's joints are each driven: `inverse_dynamics` refuses
/// `actuated` there too).
pub fn check_actuated(model: &Model, actuated: &[usize]) -> Result<()> {
    let nv = model.nv;
    if !model.has_constraints() {
        return Err(Error::arg(
            "actuated",
            "None for a model without loops or couplings (every joint is actuated)",
            format!("{actuated:?}"),
        ));
    }
    if actuated.is_empty() {
        return Err(Error::arg(
            "actuated",
            "at least one driven joint (v index or body name)",
            "none",
        ));
    }
    for (k, &c) in actuated.iter().enumerate() {
        if c >= nv || actuated[..k].contains(&c) {
            return Err(Error::arg(
                "actuated",
                format!("distinct v indices below {nv}"),
                format!("{actuated:?}"),
            ));
        }
    }
    Ok(())
}

/// `Y_a` along `samples` stacked states: (N · na) × columns, sample-major rows (sample k's
/// actuated forces in rows `k na .. (k+1) na`, in the order of `actuated`). The same columns
/// as [`super::torque_regressor`] (the tree's links, then the joint-space terms, whose forces
/// at passive joints reach the actuators through the loops). Errors if the actuated joints
/// cannot drive the mechanism at some sample.
pub fn actuated_regressor(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    extras: &Extras,
    actuated: &[usize],
) -> Result<DMatrix<f64>> {
    check_actuated(model, actuated)?;
    let samples = check_states(model, q, v, a)?;
    let tree = tree_regressor(model, q, v, a, g, extras)?;
    let (nq, nv, na, m) = (model.nq, model.nv, actuated.len(), model.nconstraints());
    let cols = tree.ncols();
    let mut out = crate::support::alloc::try_zeros(samples * na, cols, "actuated regressor")?;
    let mut kin = LoopKinematics::new(model);
    let mut jac = DMatrix::zeros(m, nv);
    let mut sys = DMatrix::zeros(nv, na + m);
    for k in 0..samples {
        if k % 1024 == 0 {
            crate::support::interrupt::check("actuated regressor")?;
        }
        kin.positions(model, &q[k * nq..(k + 1) * nq]);
        loops::jacobian(model, &kin, &mut jac);
        sys.fill(0.0);
        for (i, &c) in actuated.iter().enumerate() {
            sys[(c, i)] = 1.0;
        }
        sys.view_mut((0, na), (nv, m)).tr_copy_from(&jac);
        let p = driving_map(&sys, na, actuated, k)?;
        let rows = tree.view((k * nv, 0), (nv, cols));
        out.view_mut((k * na, 0), (na, cols)).copy_from(&(p * rows));
    }
    Ok(out)
}

/// The first `na` rows of `[S_a | Jᵀ]⁺` (na × nv); refuses a `sys` of rank below nv (the
/// actuated joints and the loops cannot balance every tree force: an under-actuated choice).
fn driving_map(
    sys: &DMatrix<f64>,
    na: usize,
    actuated: &[usize],
    k: usize,
) -> Result<DMatrix<f64>> {
    let nv = sys.nrows();
    let svd = sys.clone().svd(true, true);
    let top = svd.singular_values.amax();
    let tol = RANK_TOL * top.max(1.0);
    let rank = svd.singular_values.iter().filter(|&&s| s > tol).count();
    if rank < nv {
        return Err(Error::Singular(format!(
            "the actuated coordinates {actuated:?} cannot drive the mechanism at sample {k}: with the loops they balance only {rank} of the {nv} joint-force directions (an under-actuated choice, or a singular position: actuate a joint that moves the mechanism)"
        )));
    }
    let pinv = svd
        .pseudo_inverse(tol)
        .map_err(|e| Error::Singular(format!("actuated regressor: {e}")))?;
    Ok(pinv.rows(0, na).into_owned())
}

/// The regressor of the joint forces: [`actuated_regressor`] when `actuated` is given, the
/// tree's ([`super::torque_regressor`]) otherwise.
pub fn joint_force_regressor(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    extras: &Extras,
    actuated: &[usize],
) -> Result<DMatrix<f64>> {
    if actuated.is_empty() {
        super::torque_regressor(model, q, v, a, g, extras)
    } else {
        actuated_regressor(model, q, v, a, g, extras, actuated)
    }
}

/// Closes `q` (one state) onto the loops and couplings, then projects `v` and `a` onto the
/// velocity and acceleration constraints: a state the mechanism can be in near the given one.
/// `None` when Newton cannot close it from there.
pub fn closed_state(model: &Model, q: &[f64], v: &mut [f64], a: &mut [f64]) -> Option<Vec<f64>> {
    if !model.has_constraints() {
        return Some(q.to_vec());
    }
    let free = vec![false; model.nv];
    let q = loops::assemble(model, q, &free, 1e-10, 50).ok()?;
    loops::project_velocity_like(model, &q, None, v, &free).ok()?;
    loops::project_velocity_like(model, &q, Some(v), a, &free).ok()?;
    Some(q)
}
