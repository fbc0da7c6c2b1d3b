//! Estimates from a reduced regressor ([`Reduced`]): ordinary least squares on the base
//! parameters, with their standard deviations and the condition number.
use nalgebra::{DMatrix, DVector};

use super::base_parameters::{Base, Reduced};
use crate::support::error::{Error, Result};

/// An estimate of the base parameters and the full parameter vector it implies.
#[derive(Debug, Clone)]
pub struct Fit {
    pub beta: Vec<f64>,
    /// Standard deviation of each base parameter: `σ̂ · sqrt(diag((Y_bᵀ Y_b)⁻¹))`,
    /// `σ̂² = rss / (rows − rank)` (of the weighted rows).
    pub std: Vec<f64>,
    /// Every parameter: the dependent ones at their prior value (zero without one), the
    /// independent ones so that `K π = β`.
    pub pi: Vec<f64>,
    pub rss: f64,
    /// The base regressor's condition number with unit-norm columns (units left out).
    pub condition: f64,
}

/// `R` restricted to `columns` (p × k).
fn columns(r: &DMatrix<f64>, cols: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(r.nrows(), cols.len(), |i, j| r[(i, cols[j])])
}

/// Condition number of `a` with its columns scaled to unit norm (`inf` when singular).
pub fn scaled_condition(a: &DMatrix<f64>) -> f64 {
    if a.ncols() == 0 {
        return 1.0;
    }
    let mut s = a.clone();
    for mut c in s.column_iter_mut() {
        let n = c.norm();
        if n > 0.0 {
            c /= n;
        }
    }
    let sv = s.singular_values();
    let (lo, hi) = (sv.min(), sv.max());
    if lo > 0.0 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

/// Ordinary (weighted) least squares on the base parameters.
pub fn ols(red: &Reduced, base: &Base, prior: Option<&[f64]>) -> Result<Fit> {
    let rank = base.rank;
    if rank == 0 {
        return Err(Error::arg(
            "data",
            "a motion that excites at least one parameter",
            "a regressor of rank 0 (no motion, or no rows)",
        ));
    }
    let rb = columns(&red.r, &base.independent);
    let qr = rb.clone().qr();
    let mut z = red.z.clone();
    qr.q_tr_mul(&mut z);
    let r = qr.r();
    let zb = z.rows(0, rank).into_owned();
    let beta = r
        .solve_upper_triangular(&zb)
        .ok_or_else(|| Error::Singular("identification: the base regressor is singular".into()))?;
    let rss = red.rss + z.rows(rank, z.len() - rank).norm_squared();
    let dof = red.rows.saturating_sub(rank).max(1) as f64;
    let sigma = (rss / dof).sqrt();
    let rinv = r
        .solve_upper_triangular(&DMatrix::identity(rank, rank))
        .ok_or_else(|| Error::Singular("identification: the base regressor is singular".into()))?;
    let std = (0..rank).map(|i| sigma * rinv.row(i).norm()).collect();
    let p = red.r.ncols();
    let mut pi = vec![0.0; p];
    if let Some(prior) = prior {
        for &d in &base.dependent {
            pi[d] = prior[d];
        }
    }
    let beta: Vec<f64> = beta.iter().copied().collect();
    // π_ind = β − C π_dep.
    for (i, &c) in base.independent.iter().enumerate() {
        let dep: f64 = base
            .dependent
            .iter()
            .enumerate()
            .map(|(d, &e)| base.coefficients[(i, d)] * pi[e])
            .sum();
        pi[c] = beta[i] - dep;
    }
    Ok(Fit {
        beta,
        std,
        pi,
        rss,
        condition: scaled_condition(&rb),
    })
}

/// `‖R π − z‖² + rss`: the weighted residual sum of squares of a parameter vector.
pub fn residual(red: &Reduced, pi: &[f64]) -> f64 {
    let x = DVector::from_column_slice(pi);
    (&red.r * x - &red.z).norm_squared() + red.rss
}
