//! Small dense factorizations done in place on reused buffers, so the constrained right-hand
//! side allocates nothing: Cholesky of the (positive definite) mass matrix (the rank of the
//! constraints is found by `linalg::pivoted_qr` on the Jacobian itself). Off the simulation
//! path, the minimum-norm solutions (constraint forces, driving forces) use a complete
//! orthogonal decomposition ([`min_norm_solve`]).
use nalgebra::{DMatrix, DMatrixViewMut};

/// `m = L Lᵀ` in place (lower triangle; the upper is left as it was). `Err(k)` if the k-th
/// pivot is not positive. Right-looking on contiguous columns, skipping zero entries: a
/// tree's mass matrix is zero between bodies on different branches, and the factor keeps
/// that sparsity (no fill outside the ancestor pairs).
///
/// `ends[k]` (unless `ends` is empty): one past the last nonzero row of column `k` of `L`,
/// so that the triangular solves stop there (a tree's factor is zero below each column's
/// descendants); each is set as its column is finished.
pub fn cholesky(m: &mut DMatrix<f64>, ends: &mut [usize]) -> Result<(), usize> {
    let n = m.nrows();
    let data = m.as_mut_slice();
    for j in 0..n {
        let (left, right) = data.split_at_mut((j + 1) * n);
        let col = &mut left[j * n..];
        let d = col[j];
        if d <= 0.0 || !d.is_finite() {
            return Err(j);
        }
        let d = d.sqrt();
        col[j] = d;
        let inv = 1.0 / d;
        // Past the column's last nonzero there is nothing to scale or update with.
        let last = col[j + 1..]
            .iter()
            .rposition(|&x| x != 0.0)
            .map_or(j + 1, |i| j + i + 2);
        for x in &mut col[j + 1..last] {
            *x *= inv;
        }
        if let Some(e) = ends.get_mut(j) {
            // Column j is final: later steps update the columns after it.
            *e = col[j + 1..last]
                .iter()
                .rposition(|&x| x != 0.0)
                .map_or(j + 1, |i| j + i + 2);
        }
        // Trailing update of the lower triangle: column k -= l_kj · l[k.., j].
        for k in j + 1..last {
            let lkj = col[k];
            if lkj == 0.0 {
                continue;
            }
            let target = &mut right[(k - j - 1) * n + k..(k - j) * n];
            for (t, l) in target.iter_mut().zip(&col[k..]) {
                *t -= lkj * l;
            }
        }
    }
    Ok(())
}

/// Solves `L x = b` in place (`L` lower triangular, from [`cholesky`], with its `ends`); column-oriented, skipping zero entries of `x` (a constraint row touches
/// a few coordinates) and starting at `from` and ending at `to` (`x` is zero outside
/// `from..to` on entry; past both `to` and the columns' fill it stays zero). Returns one
/// past the last entry of `x` that can be nonzero.
pub fn forward_substitute(
    l: &DMatrix<f64>,
    ends: &[usize],
    x: &mut [f64],
    from: usize,
    to: usize,
) -> usize {
    let n = x.len();
    let data = l.as_slice();
    let mut end = from;
    for k in from..n {
        if k >= end.max(to) {
            break;
        }
        if x[k] == 0.0 {
            continue;
        }
        let col = &data[k * n..k * n + ends[k]];
        let xk = x[k] / col[k];
        x[k] = xk;
        for (xi, lik) in x[k + 1..ends[k]].iter_mut().zip(&col[k + 1..]) {
            *xi -= xk * lik;
        }
        end = end.max(ends[k]);
    }
    end
}

/// Solves `Lᵀ x = b` in place.
pub fn back_substitute(l: &DMatrix<f64>, ends: &[usize], x: &mut [f64]) {
    let n = x.len();
    let data = l.as_slice();
    for i in (0..n).rev() {
        let col = &data[i * n..i * n + ends[i]];
        let s: f64 = col[i + 1..]
            .iter()
            .zip(&x[i + 1..ends[i]])
            .map(|(a, b)| a * b)
            .sum();
        x[i] = (x[i] - s) / col[i];
    }
}

/// Relative column norm below which [`min_norm_solve`] takes a column as dependent (the
/// callers' matrices are unsquared: `Jᵀ`, `[S_a | Jᵀ]`).
pub const RANK_TOL: f64 = 1e-12;

/// The Householder reflector `H = I − τ u uᵀ`, `u = (1, t / s)`, with `H (x0, t) = (β, 0)` for
/// a vector `(x0, t)` whose tail `t` has norm `tail_norm`: returns `(β, τ, 1/s)`; the caller
/// scales the tail by `1/s` to store `u`. The identity (`τ = 0`) for a zero vector.
fn reflector(x0: f64, tail_norm: f64) -> (f64, f64, f64) {
    let norm = x0.hypot(tail_norm);
    if norm == 0.0 {
        return (0.0, 0.0, 0.0);
    }
    // β of the sign opposite to x0: `x0 − β` does not cancel.
    let beta = if x0 >= 0.0 { -norm } else { norm };
    (beta, (beta - x0) / beta, 1.0 / (x0 - beta))
}

/// The minimum-norm least-squares solution `x = A⁺ b` of a small dense system, `A` (r × c)
/// overwritten, `b` (length r) overwritten by `Qᵀ b`, `x` of length c; `pivots` and `work`
/// are scratch of length ≥ c. Returns the numerical rank: columns whose remaining norm falls
/// to `rel_tol` of the largest column's are taken as dependent.
///
/// A complete orthogonal decomposition, as LAPACK's `xGELSY`: Householder QR with column
/// pivoting (the column of largest remaining norm first, so the diagonal of R decreases and
/// reveals the rank), `A P = Q [R₁₁ R₁₂; 0 ≈0]`, then reflectors from the right that fold
/// `R₁₂` into `R₁₁`, `[R₁₁ R₁₂] = [T 0] Z`; `x = P Zᵀ [T⁻¹ (Qᵀb)₁; 0]`. Orthogonal steps
/// only: backward stable, errors of round-off times the condition number. (nalgebra's SVD
/// loses up to 1e-9 on well-conditioned 3 × 3 systems: its 2 × 2 kernel cancels when an
/// off-diagonal entry is small; its `col_piv_qr` pivots on the largest entry, not the
/// largest column, so its R does not reveal the rank.)
pub fn min_norm_solve(
    mut a: DMatrixViewMut<'_, f64>,
    b: &mut [f64],
    x: &mut [f64],
    pivots: &mut [usize],
    work: &mut [f64],
    rel_tol: f64,
) -> usize {
    let (rows, cols) = a.shape();
    let norms = &mut work[..cols];
    let mut tol = 0.0;
    let mut rank = 0;
    for k in 0..rows.min(cols) {
        // Exact column norms each step (no downdating): the matrices are a few columns wide.
        for (j, nj) in norms.iter_mut().enumerate().skip(k) {
            *nj = a.view((k, j), (rows - k, 1)).norm();
        }
        let p = (k..cols)
            .max_by(|&i, &j| norms[i].total_cmp(&norms[j]))
            .unwrap_or(k);
        if k == 0 {
            tol = rel_tol * norms[p];
        }
        // A NaN stops here too (the callers check their residual).
        if norms[p].is_nan() || norms[p] <= tol {
            break;
        }
        a.swap_columns(k, p);
        pivots[k] = p;
        let tail_norm = a.view((k + 1, k), (rows - k - 1, 1)).norm();
        let (beta, tau, inv) = reflector(a[(k, k)], tail_norm);
        a[(k, k)] = beta;
        // u = (1, tail · inv) kept below the diagonal while it is applied, then cleared.
        for i in k + 1..rows {
            a[(i, k)] *= inv;
        }
        for j in k + 1..cols {
            let s = tau * (a[(k, j)] + (k + 1..rows).map(|i| a[(i, k)] * a[(i, j)]).sum::<f64>());
            a[(k, j)] -= s;
            for i in k + 1..rows {
                a[(i, j)] -= s * a[(i, k)];
            }
        }
        let s = tau * (b[k] + (k + 1..rows).map(|i| a[(i, k)] * b[i]).sum::<f64>());
        b[k] -= s;
        for i in k + 1..rows {
            b[i] -= s * a[(i, k)];
            a[(i, k)] = 0.0;
        }
        rank += 1;
    }
    let r = rank;
    // `[R₁₁ R₁₂] H_{r−1} ⋯ H₀ = [T 0]`, so Z = H₀ ⋯ H_{r−1}: H_k acts on coordinates k and
    // r.., zeroes row k of R₁₂ and leaves the rows below k alone (they are zero in column k
    // and in R₁₂ by then). H_k's vector is kept in row k of R₁₂, its τ in `work[k]`.
    let taus = &mut work[..r];
    if r < cols {
        for k in (0..r).rev() {
            let tail_norm = a.view((k, r), (1, cols - r)).norm();
            let (beta, tau, inv) = reflector(a[(k, k)], tail_norm);
            taus[k] = tau;
            a[(k, k)] = beta;
            for j in r..cols {
                a[(k, j)] *= inv;
            }
            for i in 0..k {
                let s = tau * (a[(i, k)] + (r..cols).map(|j| a[(i, j)] * a[(k, j)]).sum::<f64>());
                a[(i, k)] -= s;
                for j in r..cols {
                    a[(i, j)] -= s * a[(k, j)];
                }
            }
        }
    }
    // T u = (Qᵀb)₁; the free components (Z x)₂ are zero for the minimum norm.
    x[..cols].fill(0.0);
    for i in (0..r).rev() {
        let s = b[i] - (i + 1..r).map(|j| a[(i, j)] * x[j]).sum::<f64>();
        x[i] = s / a[(i, i)];
    }
    // Zᵀ = H_{r−1} ⋯ H₀: H₀ applied first.
    if r < cols {
        for k in 0..r {
            let s = taus[k] * (x[k] + (r..cols).map(|j| a[(k, j)] * x[j]).sum::<f64>());
            x[k] -= s;
            for j in r..cols {
                x[j] -= s * a[(k, j)];
            }
        }
    }
    // x = P y, P the column swaps in the order made: undo them last to first.
    for k in (0..r).rev() {
        x.swap(k, pivots[k]);
    }
    r
}
