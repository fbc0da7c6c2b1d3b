//! Jacobians with respect to independent coordinates of a mechanism with loops or couplings:
//! the constraint Jacobian `J_c` (cut joints and couplings, `crate::loops`) ties the speeds,
//! `J_c v = 0`, so `v = G v_I` with `G = [1; −J_D⁺ J_I]` (rows permuted back) for a chosen
//! independent set `I` whose complement `D` the constraints determine; a frame Jacobian `J`
//! becomes `J G`.
use nalgebra::DMatrix;

use crate::loops::{self, LoopKinematics};
use crate::model::Model;
use crate::support::error::{Error, Result};

/// Relative size below which a singular value counts as zero.
const RANK_TOL: f64 = 1e-10;

/// The constraint Jacobian (nconstraints × nv) at `q` (checked by the caller).
pub fn constraint_jacobian(model: &Model, q: &[f64]) -> DMatrix<f64> {
    let mut kin = LoopKinematics::new(model);
    kin.positions(model, q);
    let mut jac = DMatrix::zeros(model.nconstraints(), model.nv);
    loops::jacobian(model, &kin, &mut jac);
    jac
}

fn rank(m: &DMatrix<f64>, scale: f64) -> usize {
    if m.ncols() == 0 || m.nrows() == 0 {
        return 0;
    }
    let sv = m.clone().svd(false, false).singular_values;
    sv.iter().filter(|s| **s > RANK_TOL * scale).count()
}

/// An independent set: the coordinates, from the first, whose columns the constraints do not
/// determine (scanning from the last coordinate, each column that raises the rank of those
/// kept so far is dependent).
pub fn default_independent(jc: &DMatrix<f64>) -> Vec<usize> {
    let nv = jc.ncols();
    let scale = 1.0 + jc.amax();
    let mut dependent: Vec<usize> = Vec::new();
    let mut r = 0;
    for c in (0..nv).rev() {
        let mut trial = dependent.clone();
        trial.push(c);
        let sub = jc.select_columns(trial.iter());
        let rk = rank(&sub, scale);
        if rk > r {
            r = rk;
            dependent = trial;
        }
    }
    (0..nv).filter(|c| !dependent.contains(c)).collect()
}

/// `G` (nv × |independent|) at `q` for the speeds `independent` (v indices, distinct).
/// Errors when they do not determine the others at `q` (too few, or a singular choice) or
/// are not independent (too many).
pub fn independent_map(model: &Model, q: &[f64], independent: &[usize]) -> Result<DMatrix<f64>> {
    let nv = model.nv;
    let jc = constraint_jacobian(model, q);
    let dependent: Vec<usize> = (0..nv).filter(|c| !independent.contains(c)).collect();
    let ni = independent.len();
    let mut g = DMatrix::zeros(nv, ni);
    for (k, &c) in independent.iter().enumerate() {
        g[(c, k)] = 1.0;
    }
    if jc.nrows() == 0 {
        return Ok(g);
    }
    let scale = 1.0 + jc.amax();
    if dependent.is_empty() {
        return tied(&jc, &g, ni, scale).map(|_| g);
    }
    let jd = jc.select_columns(dependent.iter());
    let ji = jc.select_columns(independent.iter());
    if rank(&jd, scale) < dependent.len() {
        return Err(Error::arg(
            "independent",
            "coordinates that determine all the others through the loops and couplings",
            format!(
                "{ni} coordinate(s) that leave some others free or singular at this configuration (the constraints fix {} of the other {}); name more or other coordinates",
                rank(&jd, scale),
                dependent.len()
            ),
        ));
    }
    let svd = jd.clone().svd(true, true);
    let x = svd
        .solve(&(-&ji), RANK_TOL * scale)
        .map_err(|e| Error::model("independent", e.to_string()))?;
    for (k, &c) in dependent.iter().enumerate() {
        for j in 0..ni {
            g[(c, j)] = x[(k, j)];
        }
    }
    tied(&jc, &g, ni, scale)?;
    Ok(g)
}

/// An error if some column of `G` breaks the constraints (the independent set is too large).
fn tied(jc: &DMatrix<f64>, g: &DMatrix<f64>, ni: usize, scale: f64) -> Result<()> {
    let closure = (jc * g).amax();
    if closure > 1e-9 * scale {
        return Err(Error::arg(
            "independent",
            "coordinates that can move independently",
            format!(
                "{ni} coordinate(s) the loops and couplings tie together (a velocity of them breaks a constraint by {closure:.3e}); name fewer"
            ),
        ));
    }
    Ok(())
}

/// `G` at a checked `q` for the speeds `independent` (v indices), or for the default set
/// ([`default_independent`]) when `None`; with the set used.
pub fn independent_map_for(
    model: &Model,
    q: &[f64],
    independent: Option<Vec<usize>>,
) -> Result<(DMatrix<f64>, Vec<usize>)> {
    let idx = independent.unwrap_or_else(|| default_independent(&constraint_jacobian(model, q)));
    Ok((independent_map(model, q, &idx)?, idx))
}
