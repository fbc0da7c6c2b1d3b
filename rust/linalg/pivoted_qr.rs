//! Householder QR with optional column pivoting, in place on a reused buffer: the
//! rank-revealing factorisation of a constraint Jacobian `Jᵀ` (columns: constraint rows).
//! By hand because the rank test must stop at a caller's tolerance (scaled to how far the
//! configuration is off its manifold) with no allocation per call; nalgebra's `col_piv_qr`
//! pivots on the largest entry, not the largest column norm, so its R does not reveal the rank,
//! and faer's would add a dependency for matrices of at most a few hundred columns.
//!
//! With pivoting, `A P = Q R`, `|R₀₀| ≥ |R₁₁| ≥ …`: the factorisation stops at the first
//! column whose remaining norm is at or below the tolerance, so the first `rank` pivoted
//! columns are a well-conditioned basis of the column space and the others depend on them.
use nalgebra::DMatrix;

use super::rank_qr::pivot_ratio;

/// A `rows × cols` factorisation kept in `a`: `R` on and above the diagonal, the reflectors'
/// vectors (implicit leading 1) below it, their factors in `tau`.
pub struct PivotedQr {
    pub a: DMatrix<f64>,
    tau: Vec<f64>,
    /// `perm[k]`: the input column now at position k.
    pub perm: Vec<usize>,
    norms: Vec<f64>,
    pub rank: usize,
}

impl PivotedQr {
    pub fn new(rows: usize, max_cols: usize) -> Self {
        PivotedQr {
            a: DMatrix::zeros(rows, max_cols),
            tau: vec![0.0; max_cols.min(rows)],
            perm: vec![0; max_cols],
            norms: vec![0.0; max_cols],
            rank: 0,
        }
    }

    /// Factors the first `cols` columns of `self.a` (filled by the caller). With `pivot`, the
    /// column of largest remaining norm goes first and the factorisation stops when it is
    /// `≤ max(rel_tol · (largest column norm), abs_tol)`; without, every nonzero column is
    /// taken in order. Returns the rank; a NaN stops it (the callers check their results).
    pub fn factor(&mut self, cols: usize, pivot: bool, rel_tol: f64, abs_tol: f64) -> usize {
        let rows = self.a.nrows();
        let data = self.a.as_mut_slice();
        for (k, p) in self.perm[..cols].iter_mut().enumerate() {
            *p = k;
        }
        let tail_norm = |data: &[f64], j: usize, k: usize| {
            data[j * rows + k..(j + 1) * rows]
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt()
        };
        let mut tol = abs_tol;
        let mut rank = 0;
        for k in 0..rows.min(cols) {
            let p = if pivot {
                // Exact remaining norms each step (no downdating, which loses accuracy exactly
                // at the near-dependent columns this is for).
                for j in k..cols {
                    self.norms[j] = tail_norm(data, j, k);
                }
                (k..cols)
                    .max_by(|&i, &j| self.norms[i].total_cmp(&self.norms[j]))
                    .unwrap_or(k)
            } else {
                k
            };
            let norm = if pivot {
                self.norms[p]
            } else {
                tail_norm(data, k, k)
            };
            if k == 0 {
                tol = tol.max(rel_tol * norm);
            }
            if norm.is_nan() || norm <= tol || norm == 0.0 {
                break;
            }
            if p != k {
                for i in 0..rows {
                    data.swap(k * rows + i, p * rows + i);
                }
                self.perm.swap(k, p);
            }
            let (head, rest) = data.split_at_mut((k + 1) * rows);
            let col = &mut head[k * rows..];
            let tau = householder(&mut col[k..], norm);
            self.tau[k] = tau;
            let u = &col[k + 1..];
            // Columns are contiguous; a column orthogonal to the reflector (a constraint row
            // on other coordinates: J is sparse) is left as it is.
            for target in rest.chunks_exact_mut(rows).take(cols - k - 1) {
                let dot: f64 = u.iter().zip(&target[k + 1..]).map(|(a, b)| a * b).sum();
                let s = tau * (target[k] + dot);
                if s == 0.0 {
                    continue;
                }
                target[k] -= s;
                for (t, ui) in target[k + 1..].iter_mut().zip(u) {
                    *t -= s * ui;
                }
            }
            rank += 1;
        }
        self.rank = rank;
        rank
    }

    /// [`super::rank_qr::RankQr::pivot_ratio`] of this factorisation.
    pub fn pivot_ratio(&self) -> f64 {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        pivot_ratio((0..self.rank).map(|k| data[k * rows + k]))
    }

    /// `R₁₁ᵀ w = b` (forward substitution) for the first `rank` pivoted columns: `b[k]` is the
    /// right-hand side of pivoted column k. In place in `w` (length ≥ rank).
    pub fn solve_rt(&self, w: &mut [f64]) {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        for i in 0..self.rank {
            let col = &data[i * rows..i * rows + i + 1];
            let s: f64 = col[..i].iter().zip(&w[..i]).map(|(a, b)| a * b).sum();
            w[i] = (w[i] - s) / col[i];
        }
    }

    /// `R₁₁ y = w` (back substitution), in place; column-oriented.
    pub fn solve_r(&self, w: &mut [f64]) {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        for i in (0..self.rank).rev() {
            let col = &data[i * rows..i * rows + i + 1];
            let wi = w[i] / col[i];
            w[i] = wi;
            if wi != 0.0 {
                for (x, r) in w[..i].iter_mut().zip(&col[..i]) {
                    *x -= wi * r;
                }
            }
        }
    }

    /// `x = Q [w; 0]` (x of length rows; w the first `rank` entries).
    pub fn apply_q(&self, w: &[f64], x: &mut [f64]) {
        x.fill(0.0);
        x[..self.rank].copy_from_slice(&w[..self.rank]);
        self.apply_q_full(x);
    }
}

impl PivotedQr {
    /// `x ← Q x` for a full-length `x` (all `rows` entries, not only the first `rank`).
    pub fn apply_q_full(&self, x: &mut [f64]) {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        // Q = H₀ H₁ ⋯ H_{r−1}: the last reflector first.
        for k in (0..self.rank).rev() {
            let u = &data[k * rows + k + 1..(k + 1) * rows];
            let dot: f64 = u.iter().zip(&x[k + 1..]).map(|(a, b)| a * b).sum();
            let s = self.tau[k] * (x[k] + dot);
            x[k] -= s;
            for (xi, ui) in x[k + 1..].iter_mut().zip(u) {
                *xi -= s * ui;
            }
        }
    }

    /// `R`'s diagonal entry `k` (`k < rank`).
    pub fn diagonal(&self, k: usize) -> f64 {
        self.a[(k, k)]
    }
}

/// Turns `col` (of 2-norm `norm > 0`) into its Householder reflector in place: `β` in
/// `col[0]`, the vector `v` (with `v₀ = 1` implied) below it; returns `τ` (`H = I − τ v vᵀ`).
/// Shared by the dense pivoted and the banded QR.
#[inline]
pub(crate) fn householder(col: &mut [f64], norm: f64) -> f64 {
    let x0 = col[0];
    // β of the sign opposite to x0: `x0 − β` does not cancel.
    let beta = if x0 >= 0.0 { -norm } else { norm };
    let tau = (beta - x0) / beta;
    let inv = 1.0 / (x0 - beta);
    col[0] = beta;
    for x in &mut col[1..] {
        *x *= inv;
    }
    tau
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reveals_the_rank_and_solves_the_transposed_system() {
        // Columns 0, 1 independent; column 2 = column 0 + 2·column 1; column 3 tiny but
        // independent (a near-singular position), kept at a tolerance below its size.
        let cols = [
            [1.0, 2.0, 0.0, 1.0],
            [0.0, 1.0, 1.0, -1.0],
            [1.0, 4.0, 2.0, -1.0],
            [1e-9, 0.0, 0.0, 0.0],
        ];
        let mut qr = PivotedQr::new(4, 4);
        for (j, c) in cols.iter().enumerate() {
            qr.a.column_mut(j).copy_from_slice(c);
        }
        assert_eq!(qr.factor(4, true, 1e-13, 0.0), 3);
        assert_eq!(qr.perm[2], 3);
        // The min-norm x with cᵀx = b for the independent columns: x = Q R⁻ᵀ b.
        let b_of = |j: usize| [1.0, -2.0, -3.0, 3e-9][j];
        let mut w: Vec<f64> = (0..3).map(|k| b_of(qr.perm[k])).collect();
        qr.solve_rt(&mut w);
        let mut x = [0.0; 4];
        qr.apply_q(&w, &mut x);
        for (j, c) in cols.iter().enumerate() {
            let got: f64 = c.iter().zip(&x).map(|(a, b)| a * b).sum();
            let want = if j == 2 {
                b_of(0) + 2.0 * b_of(1)
            } else {
                b_of(j)
            };
            assert!(
                (got - want).abs() < 1e-14 * (1.0 + want.abs()),
                "{j}: {got} {want}"
            );
        }
        // A tolerance above the tiny column drops it.
        for (j, c) in cols.iter().enumerate() {
            qr.a.column_mut(j).copy_from_slice(c);
        }
        assert_eq!(qr.factor(4, true, 1e-13, 1e-6), 2);
    }
}
