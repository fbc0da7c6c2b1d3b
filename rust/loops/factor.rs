//! Small dense factorizations done in place on reused buffers, so the constrained right-hand
//! side allocates nothing: Cholesky of the (positive definite) mass matrix, and Cholesky with
//! diagonal pivoting of the (semi-definite) constraint-space matrices, which finds the rank
//! of redundant constraints and solves for a basic solution.
use nalgebra::DMatrix;

/// `m = L Lᵀ` in place (lower triangle; the upper is left as it was). `Err(k)` if the k-th
/// pivot is not positive.
pub fn cholesky(m: &mut DMatrix<f64>) -> Result<(), usize> {
    let n = m.nrows();
    for j in 0..n {
        let mut d = m[(j, j)];
        for k in 0..j {
            d -= m[(j, k)] * m[(j, k)];
        }
        if d <= 0.0 || !d.is_finite() {
            return Err(j);
        }
        let d = d.sqrt();
        m[(j, j)] = d;
        for i in j + 1..n {
            let mut s = m[(i, j)];
            for k in 0..j {
                s -= m[(i, k)] * m[(j, k)];
            }
            m[(i, j)] = s / d;
        }
    }
    Ok(())
}

/// Solves `L x = b` in place (`L` lower triangular, from [`cholesky`]).
pub fn forward_substitute(l: &DMatrix<f64>, x: &mut [f64]) {
    for i in 0..x.len() {
        let mut s = x[i];
        for k in 0..i {
            s -= l[(i, k)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
}

/// Solves `Lᵀ x = b` in place.
pub fn back_substitute(l: &DMatrix<f64>, x: &mut [f64]) {
    for i in (0..x.len()).rev() {
        let mut s = x[i];
        for k in i + 1..x.len() {
            s -= l[(k, i)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
}

/// Relative size below which a pivot of a constraint-space matrix counts as zero: exactly
/// dependent rows leave pivots of ~1e-16 of the largest, a genuinely stiff but independent
/// set (a mechanism near, not at, a singular position) leaves far more.
pub const RANK_TOL: f64 = 1e-12;

/// Pivoted Cholesky of the symmetric positive semi-definite leading `n × n` block of `a`
/// (overwritten) and a basic solution of `a x = b` (`b`, `x` of length n): the unknowns of
/// dependent rows are zero. `perm` and `work` are scratch of length ≥ n. Returns the rank.
pub fn solve_semidefinite(
    a: &mut DMatrix<f64>,
    n: usize,
    b: &[f64],
    x: &mut [f64],
    perm: &mut [usize],
    work: &mut [f64],
) -> usize {
    let perm = &mut perm[..n];
    for (k, p) in perm.iter_mut().enumerate() {
        *p = k;
    }
    let largest = (0..n).map(|i| a[(i, i)]).fold(0.0, f64::max);
    let tol = RANK_TOL * largest;
    let mut rank = 0;
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[(i, i)].total_cmp(&a[(j, j)]))
            .unwrap_or(k);
        if !(a[(p, p)] > tol) {
            break;
        }
        if p != k {
            for c in 0..n {
                a.swap((k, c), (p, c));
            }
            for r in 0..n {
                a.swap((r, k), (r, p));
            }
            perm.swap(k, p);
        }
        let d = a[(k, k)].sqrt();
        a[(k, k)] = d;
        for i in k + 1..n {
            a[(i, k)] /= d;
        }
        for j in k + 1..n {
            for i in j..n {
                let s = a[(i, k)] * a[(j, k)];
                a[(i, j)] -= s;
                // Keep the matrix symmetric for the row/column swaps that follow.
                a[(j, i)] = a[(i, j)];
            }
        }
        rank += 1;
    }
    let y = &mut work[..rank];
    for (i, yi) in y.iter_mut().enumerate() {
        *yi = b[perm[i]];
    }
    let l = &*a;
    for i in 0..rank {
        let mut s = y[i];
        for k in 0..i {
            s -= l[(i, k)] * y[k];
        }
        y[i] = s / l[(i, i)];
    }
    for i in (0..rank).rev() {
        let mut s = y[i];
        for k in i + 1..rank {
            s -= l[(k, i)] * y[k];
        }
        y[i] = s / l[(i, i)];
    }
    x[..n].fill(0.0);
    for i in 0..rank {
        x[perm[i]] = y[i];
    }
    rank
}
