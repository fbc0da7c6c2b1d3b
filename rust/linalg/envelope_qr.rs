//! Householder QR of a sparse matrix held in a dense buffer, working only inside each
//! column's envelope (the row range that can hold its nonzeros), with threshold rank
//! detection: the large, banded constraint Jacobians `Jᵀ` of long mechanisms (a chain of
//! loops: each constraint row touches a few neighbouring coordinates). By hand, as
//! `pivoted_qr`: the rank test stops at a caller's tolerance, nothing is allocated per call,
//! and a band of width `w` costs `O(rows · w²)` (faer's dense QR is `O(rows · cols²)`; a
//! general sparse QR's symbolic analysis is more than this whole factorisation here).
//!
//! Columns are taken in the caller's order (order them by the last row they touch, and a
//! band stays a band): a column whose remaining norm, after the reflectors of the columns
//! kept before it, is at or below the tolerance depends on them (to that tolerance) and is
//! set aside, as sparse QR codes do (Eigen's SparseQR, SuiteSparseQR: "Heath's method"); the
//! others are factored in place. The tolerance is that of [`super::pivoted_qr`]: `rel_tol`
//! times the largest column norm, or `abs_tol`. Where column pivoting takes the largest
//! remaining column first, this keeps the caller's order: the rank is the same count of
//! columns whose part independent of the others exceeds the tolerance, the kept set may be a
//! different (equally valid) basis.
use nalgebra::DMatrix;

use super::rank_qr::pivot_ratio;

/// A `rows × cols` factorisation kept in `a`: each kept column holds its column of `R` from
/// row `start` to the diagonal and its reflector's vector (implicit leading 1) below it.
pub struct EnvelopeQr {
    pub a: DMatrix<f64>,
    tau: Vec<f64>,
    /// `perm[k]`: the input (and buffer) column of `R`'s column `k`: the kept columns in
    /// order, then those set aside.
    pub perm: Vec<usize>,
    /// Row range `[lo, hi)` outside which a buffer column is zero.
    lo: Vec<usize>,
    hi: Vec<usize>,
    /// `R`'s column `k`: rows `start[k]..=k`; its reflector: rows `k..end[k]`.
    start: Vec<usize>,
    end: Vec<usize>,
    /// Columns set aside at the last factorisation.
    dead: Vec<usize>,
    /// `reach[t]`: the least `lo` of the columns from `t` on, before the factorisation.
    reach: Vec<usize>,
    pub rank: usize,
}

impl EnvelopeQr {
    pub fn new(rows: usize, max_cols: usize) -> Self {
        EnvelopeQr {
            a: DMatrix::zeros(rows, max_cols),
            tau: vec![0.0; max_cols.min(rows)],
            perm: vec![0; max_cols],
            lo: vec![0; max_cols],
            hi: vec![0; max_cols],
            start: vec![0; max_cols.min(rows)],
            end: vec![0; max_cols.min(rows)],
            dead: Vec::with_capacity(max_cols),
            reach: vec![0; max_cols],
            rank: 0,
        }
    }

    /// Buffer column `j` is zero outside rows `lo..hi` (the caller's knowledge of its
    /// nonzeros, set for every column before [`EnvelopeQr::factor`]).
    pub fn set_envelope(&mut self, j: usize, lo: usize, hi: usize) {
        self.lo[j] = lo;
        self.hi[j] = hi.max(lo);
    }

    /// The envelopes of the first `cols` buffer columns from their nonzeros.
    pub fn scan_envelopes(&mut self, cols: usize) {
        let rows = self.a.nrows();
        for j in 0..cols {
            let col = &self.a.as_slice()[j * rows..(j + 1) * rows];
            let lo = col.iter().position(|&x| x != 0.0).unwrap_or(rows);
            let hi = col.iter().rposition(|&x| x != 0.0).map_or(lo, |i| i + 1);
            self.set_envelope(j, lo, hi);
        }
    }

    /// The largest column norm, and `reach`.
    fn prepare(&mut self, cols: usize) -> f64 {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        let mut largest: f64 = 0.0;
        for j in 0..cols {
            let col = &data[j * rows + self.lo[j]..j * rows + self.hi[j]];
            let norm: f64 = col.iter().map(|x| x * x).sum::<f64>().sqrt();
            largest = largest.max(norm);
        }
        let mut least = rows;
        for j in (0..cols).rev() {
            least = least.min(self.lo[j]);
            self.reach[j] = least;
        }
        largest
    }

    /// Factors the first `cols` columns of `self.a` (filled by the caller, zero outside the
    /// envelopes it set), in order: a column whose remaining norm is `≤ max(rel_tol · (largest
    /// column norm), abs_tol)` is set aside. Returns the rank; a NaN stops it (the callers
    /// check their results).
    pub fn factor(&mut self, cols: usize, rel_tol: f64, abs_tol: f64) -> usize {
        let rows = self.a.nrows();
        let tol = abs_tol.max(rel_tol * self.prepare(cols));
        self.dead.clear();
        let data = self.a.as_mut_slice();
        let mut r = 0;
        let mut stopped = cols;
        // The last column a reflector has changed: past it, every column keeps the
        // envelope it came with, bounded below by `reach`.
        let mut touched = 0;
        for j in 0..cols {
            let (lo, hi) = (self.lo[j].max(r), self.hi[j]);
            let norm = if lo < hi {
                let col = &data[j * rows + lo..j * rows + hi];
                col.iter().map(|x| x * x).sum::<f64>().sqrt()
            } else {
                0.0
            };
            if norm.is_nan() {
                stopped = j;
                break;
            }
            if norm <= tol || norm == 0.0 {
                self.dead.push(j);
                continue;
            }
            let (head, rest) = data.split_at_mut((j + 1) * rows);
            let col = &mut head[j * rows..];
            let tau = super::pivoted_qr::householder(&mut col[r..hi], norm);
            self.tau[r] = tau;
            self.start[r] = self.lo[j].min(r);
            self.end[r] = hi;
            self.perm[r] = j;
            let u = &col[r + 1..hi];
            // Only the later columns whose envelope meets the reflector's rows `r..hi`.
            for (k, target) in rest.chunks_exact_mut(rows).take(cols - j - 1).enumerate() {
                let t = j + 1 + k;
                if t > touched && self.reach[t] >= hi {
                    break;
                }
                if self.hi[t] <= r || self.lo[t] >= hi {
                    continue;
                }
                let (a, b) = (self.lo[t].max(r + 1), self.hi[t].min(hi));
                let dot: f64 = if a < b {
                    u[a - r - 1..b - r - 1]
                        .iter()
                        .zip(&target[a..b])
                        .map(|(x, y)| x * y)
                        .sum()
                } else {
                    0.0
                };
                let s = tau * (target[r] + dot);
                if s == 0.0 {
                    continue;
                }
                target[r] -= s;
                for (x, ui) in target[r + 1..hi].iter_mut().zip(u) {
                    *x -= s * ui;
                }
                self.lo[t] = self.lo[t].min(r);
                self.hi[t] = self.hi[t].max(hi);
                touched = touched.max(t);
            }
            r += 1;
        }
        self.rank = r;
        // The columns set aside, then any after a NaN, follow the kept ones.
        let mut k = r;
        for &j in &self.dead {
            self.perm[k] = j;
            k += 1;
        }
        for j in stopped..cols {
            self.perm[k] = j;
            k += 1;
        }
        r
    }

    /// [`super::rank_qr::RankQr::pivot_ratio`] of this factorisation.
    pub fn pivot_ratio(&self) -> f64 {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        pivot_ratio((0..self.rank).map(|k| data[self.perm[k] * rows + k]))
    }

    /// `R₁₁ᵀ w = b` (forward substitution): `b[k]` is the right-hand side of `R`'s column k
    /// (input column `perm[k]`). In place in `w` (length ≥ rank).
    pub fn solve_rt(&self, w: &mut [f64]) {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        for i in 0..self.rank {
            let c = self.perm[i] * rows;
            let s0 = self.start[i];
            let col = &data[c + s0..c + i + 1];
            let s: f64 = col[..i - s0]
                .iter()
                .zip(&w[s0..i])
                .map(|(a, b)| a * b)
                .sum();
            w[i] = (w[i] - s) / col[i - s0];
        }
    }

    /// `R₁₁ y = w` (back substitution), in place; column-oriented.
    pub fn solve_r(&self, w: &mut [f64]) {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        for i in (0..self.rank).rev() {
            let c = self.perm[i] * rows;
            let s0 = self.start[i];
            let col = &data[c + s0..c + i + 1];
            let wi = w[i] / col[i - s0];
            w[i] = wi;
            if wi != 0.0 {
                for (x, r) in w[s0..i].iter_mut().zip(&col[..i - s0]) {
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

impl EnvelopeQr {
    /// `x ← Q x` for a full-length `x` (all `rows` entries, not only the first `rank`).
    pub fn apply_q_full(&self, x: &mut [f64]) {
        let rows = self.a.nrows();
        let data = self.a.as_slice();
        for k in (0..self.rank).rev() {
            let c = self.perm[k] * rows;
            let end = self.end[k];
            let u = &data[c + k + 1..c + end];
            let dot: f64 = u.iter().zip(&x[k + 1..end]).map(|(a, b)| a * b).sum();
            let s = self.tau[k] * (x[k] + dot);
            // Most reflectors of a banded solve meet zeros: skipping them changes no bit.
            if s == 0.0 {
                continue;
            }
            x[k] -= s;
            for (xi, ui) in x[k + 1..end].iter_mut().zip(u) {
                *xi -= s * ui;
            }
        }
    }

    /// `R`'s diagonal entry `k` (`k < rank`).
    pub fn diagonal(&self, k: usize) -> f64 {
        self.a[(k, self.perm[k])]
    }
}

#[cfg(test)]
mod tests {
    use super::super::pivoted_qr::PivotedQr;
    use super::*;

    /// A banded `rows × cols` matrix (column j on rows j..j+3, as a chain of loops' `Jᵀ`),
    /// entries from a fixed pseudo-random sequence; columns listed in `deps` replaced by
    /// `c_{j−1} + 2 c_{j−2}` (plus `eps` in row j+1: near-dependent).
    fn banded(rows: usize, cols: usize, deps: &[usize], eps: f64) -> DMatrix<f64> {
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut a = DMatrix::zeros(rows, cols);
        for j in 0..cols {
            for i in j..(j + 3).min(rows) {
                a[(i, j)] = next();
            }
            if deps.contains(&j) {
                let c = a.column(j - 1) + a.column(j - 2) * 2.0;
                a.set_column(j, &c);
                a[(j + 1, j)] += eps;
            }
        }
        a
    }

    /// Rank and the minimum-norm `x` with `Aᵀ x = b` on the kept columns, by both QRs.
    fn both(a: &DMatrix<f64>, b: &[f64], abs_tol: f64) -> ((usize, Vec<f64>), (usize, Vec<f64>)) {
        let (rows, cols) = a.shape();
        let mut env = EnvelopeQr::new(rows, cols);
        env.a.copy_from(a);
        env.scan_envelopes(cols);
        let r_env = env.factor(cols, 1e-11, abs_tol);
        let mut w: Vec<f64> = (0..r_env).map(|k| b[env.perm[k]]).collect();
        env.solve_rt(&mut w);
        let mut x_env = vec![0.0; rows];
        env.apply_q(&w, &mut x_env);
        let mut piv = PivotedQr::new(rows, cols);
        piv.a.copy_from(a);
        let r_piv = piv.factor(cols, true, 1e-11, abs_tol);
        let mut w: Vec<f64> = (0..r_piv).map(|k| b[piv.perm[k]]).collect();
        piv.solve_rt(&mut w);
        let mut x_piv = vec![0.0; rows];
        piv.apply_q(&w, &mut x_piv);
        ((r_env, x_env), (r_piv, x_piv))
    }

    #[test]
    fn banded_qr_matches_the_pivoted_one_on_full_and_deficient_bands() {
        for (deps, eps, abs_tol, rank) in [
            (vec![], 0.0, 0.0, 40),
            (vec![7, 20, 33], 0.0, 0.0, 37),
            // Near-dependent by 1e-8: kept below it, set aside above.
            (vec![7, 20, 33], 1e-8, 1e-12, 40),
            (vec![7, 20, 33], 1e-8, 1e-6, 37),
        ] {
            let a = banded(42, 40, &deps, eps);
            // A consistent right-hand side: b = Aᵀ x* for some x*.
            let x_star: Vec<f64> = (0..42).map(|i| (i as f64 * 0.37).sin()).collect();
            let b: Vec<f64> = (0..40)
                .map(|j| (0..42).map(|i| a[(i, j)] * x_star[i]).sum())
                .collect();
            let ((r_env, x_env), (r_piv, x_piv)) = both(&a, &b, abs_tol);
            assert_eq!((r_env, r_piv), (rank, rank), "{deps:?} {eps} {abs_tol}");
            // Where the kept columns span the same space the minimum-norm solutions agree,
            // to the conditioning (1e-8 near-dependent columns: ~1e8).
            if eps == 0.0 || rank == 40 {
                let scale = x_piv.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let tol = if eps == 0.0 { 1e-10 } else { 1e-6 };
                for (e, p) in x_env.iter().zip(&x_piv) {
                    assert!((e - p).abs() < tol * scale, "{deps:?} {eps}: {e} {p}");
                }
            }
        }
    }

    #[test]
    fn banded_qr_sets_aside_dependent_columns_and_solves_with_the_rest() {
        let a = banded(12, 10, &[4], 0.0);
        let mut env = EnvelopeQr::new(12, 10);
        env.a.copy_from(&a);
        env.scan_envelopes(10);
        assert_eq!(env.factor(10, 1e-11, 0.0), 9);
        // Column 4 depends on 2 and 3: set aside, after the kept ones in order.
        assert_eq!(&env.perm[..10], &[0, 1, 2, 3, 5, 6, 7, 8, 9, 4]);
        // R₁₁ y = w and R₁₁ᵀ w = b round trip; Q [w; 0] has the norm of w.
        let b: Vec<f64> = (0..9).map(|k| 1.0 + k as f64).collect();
        let mut w = b.clone();
        env.solve_rt(&mut w);
        let mut x = vec![0.0; 12];
        env.apply_q(&w, &mut x);
        let norm = |v: &[f64]| v.iter().map(|t| t * t).sum::<f64>().sqrt();
        assert!((norm(&x) - norm(&w[..9])).abs() < 1e-12 * norm(&w));
        for k in 0..9 {
            let got: f64 = (0..12).map(|i| a[(i, env.perm[k])] * x[i]).sum();
            assert!(
                (got - b[k]).abs() < 1e-11 * (1.0 + b[k].abs()),
                "{k}: {got}"
            );
        }
        // Without a tolerance every nonzero column is kept (a zero one is not).
        env.a.copy_from(&banded(12, 10, &[], 0.0));
        env.a.column_mut(6).fill(0.0);
        env.scan_envelopes(10);
        assert_eq!(env.factor(10, 0.0, 0.0), 9);
    }
}
