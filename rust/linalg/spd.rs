//! The inverse of a symmetric positive definite matrix in the caller's buffers. Not nalgebra's
//! `Cholesky::new(m).inverse()`: that takes the matrix by value and allocates the factor and
//! the inverse on every call; the derivatives reuse their workspace and allocate nothing.
use nalgebra::DMatrix;

crate::support::cpu::multiversion! {
    /// The inverse of a symmetric positive definite matrix, in place: `M = L Lᵀ`, `X = L⁻¹`,
    /// then `M⁻¹ = Xᵀ X`, the factorizations' inner loops along (contiguous) columns. `t`,
    /// `out`: scratch matrices of the same size; `inv_diag`: scratch of length n (the
    /// reciprocal pivots, so the substitution multiplies instead of dividing). `Err(k)` at a
    /// non-positive pivot `k`. Runs its AVX2 copy where the CPU has it (`crate::support::cpu`: the same
    /// IEEE operations in wider lanes, so the same bits).
    pub fn spd_inverse / spd_inverse_avx2 / spd_inverse_baseline [] (
        m: &mut DMatrix<f64>,
        t: &mut DMatrix<f64>,
        out: &mut DMatrix<f64>,
        inv_diag: &mut [f64],
    ) -> std::result::Result<(), usize> => spd_inverse_body
}

#[inline(always)]
fn spd_inverse_body(
    m: &mut DMatrix<f64>,
    t: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
    inv_diag: &mut [f64],
) -> std::result::Result<(), usize> {
    let n = m.nrows();
    if n < SMALL {
        factor_invert_small(m.as_mut_slice(), n, inv_diag)?;
        xtx_small(m.as_slice(), n, out.as_mut_slice());
        std::mem::swap(m, out);
        return Ok(());
    }
    let a = m.as_mut_slice();
    // Cholesky, left-looking: column j −= L_jk · column k (rows j..n), k < j.
    for j in 0..n {
        let (done, rest) = a.split_at_mut(j * n);
        let cj = &mut rest[..n];
        for k in 0..j {
            let ck = &done[k * n..(k + 1) * n];
            let l = ck[j];
            for (x, y) in cj[j..].iter_mut().zip(&ck[j..]) {
                *x -= l * y;
            }
        }
        let d = cj[j];
        if !(d > 0.0 && d.is_finite()) {
            return Err(j);
        }
        let d = d.sqrt();
        cj[j] = d;
        let inv = 1.0 / d;
        inv_diag[j] = inv;
        for x in &mut cj[j + 1..] {
            *x *= inv;
        }
    }
    // X = L⁻¹ by columns, left to right: column j is L x = e_j by column-oriented forward
    // substitution, reading only L's columns > j (not yet overwritten).
    for j in 0..n {
        let (head, tail) = a.split_at_mut((j + 1) * n);
        let cj = &mut head[j * n..];
        let xj = inv_diag[j];
        cj[j] = xj;
        for x in &mut cj[j + 1..] {
            *x *= -xj;
        }
        for k in j + 1..n {
            let ck = &tail[(k - j - 1) * n..(k - j) * n];
            let xk = cj[k] * inv_diag[k];
            cj[k] = xk;
            for (x, y) in cj[k + 1..].iter_mut().zip(&ck[k + 1..]) {
                *x -= xk * y;
            }
        }
    }
    // M⁻¹ = Xᵀ X by one matrix product (matrixmultiply's kernels): Xᵀ into `t`, the product
    // into `out`, swapped into place.
    for j in 0..n {
        for i in 0..j {
            a[j * n + i] = 0.0;
        }
    }
    {
        let (src, dst) = (m.as_slice(), t.as_mut_slice());
        for j in 0..n {
            for i in 0..n {
                dst[j * n + i] = src[i * n + j];
            }
        }
    }
    out.gemm(1.0, t, m, 0.0);
    std::mem::swap(m, out);
    // Exactly symmetric (the product rounds (i, j) and (j, i) alike, but say so).
    let a = m.as_mut_slice();
    for j in 0..n {
        for i in j + 1..n {
            a[i * n + j] = a[j * n + i];
        }
    }
    Ok(())
}

/// Below this size the factor, `X = L⁻¹` and `Xᵀ X` are scalar sums entry by entry: the
/// column loops' vector set-up (lengths 1…n) and matrixmultiply's packing buffers (allocated
/// per product) cost more than the n³/6 products of each (chain7's forward derivatives:
/// 5.8k instructions per call → see benches/README.md, callgrind).
pub const SMALL: usize = 24;

/// `out = Xᵀ X` for `X` lower triangular in the columns of `x` (its upper triangle is not
/// read): `(i, j) = Σ_{k ≥ max(i, j)} X_ki X_kj`, each entry computed once and mirrored, so
/// the result is exactly symmetric.
#[inline(always)]
fn xtx_small(x: &[f64], n: usize, out: &mut [f64]) {
    for j in 0..n {
        let cj = &x[j * n..(j + 1) * n];
        for i in j..n {
            let ci = &x[i * n..(i + 1) * n];
            let mut s = 0.0;
            for k in i..n {
                s += ci[k] * cj[k];
            }
            out[j * n + i] = s;
            out[i * n + j] = s;
        }
    }
}

/// `M = L Lᵀ` then `X = L⁻¹` in place (lower triangles, column-major), entry by entry as dot
/// products: the same operations in the same order as the column loops above (`L_ij = (M_ij −
/// Σ_{k<j} L_ik L_jk) / L_jj`, `X_ij = (−L_ij / L_jj − Σ_{j<k<i} L_ik X_kj) / L_ii`), so the
/// same bits.
#[inline(always)]
fn factor_invert_small(a: &mut [f64], n: usize, inv_diag: &mut [f64]) -> Result<(), usize> {
    let a = &mut a[..n * n];
    let inv_diag = &mut inv_diag[..n];
    for j in 0..n {
        for i in j..n {
            let mut s = a[j * n + i];
            for k in 0..j {
                s -= a[k * n + j] * a[k * n + i];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return Err(j);
                }
                let d = s.sqrt();
                a[j * n + j] = d;
                inv_diag[j] = 1.0 / d;
            } else {
                a[j * n + i] = s * inv_diag[j];
            }
        }
    }
    for j in 0..n {
        let xj = inv_diag[j];
        a[j * n + j] = xj;
        for i in j + 1..n {
            let mut s = a[j * n + i] * -xj;
            for k in j + 1..i {
                s -= a[j * n + k] * a[k * n + i];
            }
            a[j * n + i] = s * inv_diag[i];
        }
    }
    Ok(())
}
