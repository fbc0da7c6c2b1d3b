//! Base (identifiable) parameters by rank-revealing QR: `Y P = Q [R₁₁ R₁₂]` on the
//! regressor with unit-norm columns (so the rank test does not depend on units), the first
//! `rank` pivoted columns independent and every other parameter entering only through
//! `β = π_ind + C π_dep`, `C = D_ind R₁₁⁻¹ R₁₂ D_dep⁻¹` (D the column scales; a column at rounding level of the
//! largest, `≤ 1e-11` of it, counts as zero). Then
//! `Y = Y_ind [I C]` (in the pivoted order) for every sample the regressor holds.
//!
//! A tall regressor is first reduced to its `R` (chunk by chunk, nalgebra's Householder QR,
//! the right-hand side as one more column): the column norms, the pivoting and the rank of
//! `R` are those of `Y`.
use nalgebra::{DMatrix, DVector};

use crate::linalg::pivoted_qr::PivotedQr;

/// `R` (p × p, upper), `z = Qᵀ b` (first p entries) and the residual sum of squares beyond
/// the columns' range, of a weighted regressor `W Y` and right-hand side `W b`.
#[derive(Debug, Clone)]
pub struct Reduced {
    pub r: DMatrix<f64>,
    pub z: DVector<f64>,
    pub rss: f64,
    pub rows: usize,
}

/// Reduces the columns `cols` of `Y` (rows × ·) and `b` (rows; zeros when `None`) with each
/// row scaled by `weights[row % weights.len()]` (e.g. one weight per joint: rows are
/// sample-major).
pub fn reduce(y: &DMatrix<f64>, cols: &[usize], b: Option<&[f64]>, weights: &[f64]) -> Reduced {
    let (rows, p) = (y.nrows(), cols.len());
    let chunk = (8 * p).max(256);
    let mut acc = DMatrix::<f64>::zeros(0, p + 1);
    let mut start = 0;
    while start < rows {
        let n = chunk.min(rows - start);
        let top = acc.nrows();
        let mut buf = DMatrix::<f64>::zeros(top + n, p + 1);
        buf.view_mut((0, 0), (top, p + 1)).copy_from(&acc);
        for (c, &yc) in cols.iter().enumerate() {
            let src = y.column(yc);
            for k in 0..n {
                buf[(top + k, c)] = weight(weights, start + k) * src[start + k];
            }
        }
        if let Some(b) = b {
            for k in 0..n {
                buf[(top + k, p)] = weight(weights, start + k) * b[start + k];
            }
        }
        acc = buf.qr().r();
        start += n;
    }
    let mut r = DMatrix::zeros(p, p);
    let mut z = DVector::zeros(p);
    let k = acc.nrows().min(p);
    r.view_mut((0, 0), (k, p))
        .copy_from(&acc.view((0, 0), (k, p)));
    for i in 0..k {
        z[i] = acc[(i, p)];
    }
    let rss = if acc.nrows() > p {
        acc[(p, p)].powi(2)
    } else {
        0.0
    };
    Reduced { r, z, rss, rows }
}

fn weight(weights: &[f64], row: usize) -> f64 {
    if weights.is_empty() {
        1.0
    } else {
        weights[row % weights.len()]
    }
}

/// The base parameters of a regressor.
#[derive(Debug, Clone)]
pub struct Base {
    pub rank: usize,
    /// Independent parameters (original column indices), in pivot order.
    pub independent: Vec<usize>,
    /// The others.
    pub dependent: Vec<usize>,
    /// `C` (rank × dependent): `β = π_ind + C π_dep`.
    pub coefficients: DMatrix<f64>,
    /// The scaled `R`'s diagonal (pivot order), `|R₀₀| = 1` at most: how far each independent
    /// column is from the span of the previous ones.
    pub pivots: Vec<f64>,
}

impl Base {
    /// `β = K π` as a matrix (rank × p).
    pub fn map(&self, p: usize) -> DMatrix<f64> {
        let mut k = DMatrix::zeros(self.rank, p);
        for (i, &c) in self.independent.iter().enumerate() {
            k[(i, c)] = 1.0;
            for (d, &e) in self.dependent.iter().enumerate() {
                k[(i, e)] = self.coefficients[(i, d)];
            }
        }
        k
    }

    /// `β` of a parameter vector `π`.
    pub fn of(&self, pi: &[f64]) -> Vec<f64> {
        (0..self.rank)
            .map(|i| {
                pi[self.independent[i]]
                    + self
                        .dependent
                        .iter()
                        .enumerate()
                        .map(|(d, &e)| self.coefficients[(i, d)] * pi[e])
                        .sum::<f64>()
            })
            .collect()
    }

    /// Each base parameter as the combination it is, e.g.
    /// `"link2.Izz + 0.0961*link3.m + 0.31*link3.mz"`; coefficients below `1e-10` (relative
    /// to the largest of the row, at least 1) are left out of the name.
    pub fn names(&self, names: &[String]) -> Vec<String> {
        (0..self.rank)
            .map(|i| {
                let row = self.coefficients.row(i);
                let cut = 1e-10 * row.amax().max(1.0);
                let mut s = names[self.independent[i]].clone();
                for (d, &e) in self.dependent.iter().enumerate() {
                    let c = row[d];
                    if c.abs() <= cut {
                        continue;
                    }
                    let sign = if c < 0.0 { '-' } else { '+' };
                    if (c.abs() - 1.0).abs() < 1e-12 {
                        s += &format!(" {sign} {}", names[e]);
                    } else {
                        s += &format!(" {sign} {:.6}*{}", c.abs(), names[e]);
                    }
                }
                s
            })
            .collect()
    }
}

/// Base parameters from a reduced regressor's `R` (p × p): column pivoting on unit-norm
/// columns, stopping at a remaining norm `≤ rel_tol` (1e-8 is a fair default: the
/// dependencies of a tree are exact, so their columns fall to rounding).
pub fn base_parameters(r: &DMatrix<f64>, rel_tol: f64) -> Base {
    let p = r.ncols();
    let norms: Vec<f64> = (0..p).map(|c| r.column(c).norm()).collect();
    let top = norms.iter().fold(0.0f64, |a, &n| a.max(n));
    // A column at rounding level of the largest (a parameter the motion cannot reach, its
    // entries cancellation noise) is zero, not scaled up into a spurious independent one.
    let scale: Vec<f64> = norms
        .iter()
        .map(|&n| {
            if n > 1e-11 * top && n.is_finite() {
                1.0 / n
            } else {
                0.0
            }
        })
        .collect();
    let mut qr = PivotedQr::new(p.max(1), p);
    for c in 0..p {
        for i in 0..p {
            qr.a[(i, c)] = r[(i, c)] * scale[c];
        }
    }
    let rank = qr.factor(p, true, rel_tol, rel_tol);
    let independent: Vec<usize> = qr.perm[..rank].to_vec();
    let dependent: Vec<usize> = qr.perm[rank..p].to_vec();
    // R₁₁⁻¹ R₁₂, column by column, back in units.
    let mut coefficients = DMatrix::zeros(rank, p - rank);
    let mut w = vec![0.0; rank];
    for (d, &e) in dependent.iter().enumerate() {
        for (i, x) in w.iter_mut().enumerate() {
            *x = qr.a[(i, rank + d)];
        }
        qr.solve_r(&mut w);
        if scale[e] > 0.0 {
            for i in 0..rank {
                coefficients[(i, d)] = w[i] * scale[independent[i]] / scale[e];
            }
        }
    }
    let pivots = (0..rank).map(|k| qr.diagonal(k).abs()).collect();
    Base {
        rank,
        independent,
        dependent,
        coefficients,
        pivots,
    }
}
