//! The inverse of a symmetric positive definite matrix in the caller's buffers. Not nalgebra's
//! `Cholesky::new(m).inverse()`: that takes the matrix by value and allocates the factor and
//! the inverse on every call; the derivatives reuse their workspace and allocate nothing.
//! Hand-written below [`SMALL`] (a library's blocking costs more than the products there);
//! from [`SMALL`] on, faer's blocked factor and inverse in a workspace sized once
//! ([`SpdScratch`]): 2.9× faster than the column loops it replaced at n = 300, 1.8× at 100
//! (`examples/spd_inverse.rs`, benches/README.md session 10).
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt;
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use nalgebra::DMatrix;

/// The inverse of a symmetric positive definite matrix, in place (only its lower triangle is
/// read). `out`: a scratch matrix of the same size. Below [`SMALL`], scalar sums entry by
/// entry (`inv_diag`: scratch of length n); from [`SMALL`] on, faer's blocked Cholesky
/// factor, triangular inverse and `L⁻ᵀ L⁻¹` product (their flops in faer's matrix kernels,
/// sequential: one thread, as the comparisons with Pinocchio assume; `scratch`: faer's
/// workspace). `Err(k)` at a non-positive (or non-finite) pivot `k`.
pub fn spd_inverse(
    m: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
    inv_diag: &mut [f64],
    scratch: &mut SpdScratch,
) -> std::result::Result<(), usize> {
    if m.nrows() < SMALL {
        spd_inverse_small(m, out, inv_diag)
    } else {
        spd_inverse_faer(m, out, scratch)
    }
}

/// faer's workspace for [`spd_inverse`] at one size (none below [`SMALL`]), allocated once:
/// the factor and the inverse then allocate nothing.
pub struct SpdScratch {
    n: usize,
    buf: MemBuffer,
}

impl SpdScratch {
    pub fn new(n: usize) -> Self {
        let req = if n < SMALL {
            StackReq::EMPTY
        } else {
            StackReq::any_of(&[
                llt::factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()),
                llt::inverse::inverse_scratch::<f64>(n, Par::Seq),
            ])
        };
        SpdScratch {
            n,
            buf: MemBuffer::new(req),
        }
    }
}

impl Clone for SpdScratch {
    fn clone(&self) -> Self {
        SpdScratch::new(self.n)
    }
}

impl std::fmt::Debug for SpdScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpdScratch").field("n", &self.n).finish()
    }
}

/// `M⁻¹` by faer (n ≥ [`SMALL`]): `M = L Lᵀ` in place, `M⁻¹ = L⁻ᵀ L⁻¹` (its lower triangle)
/// into `out`, mirrored (exactly symmetric) and swapped into `m`.
fn spd_inverse_faer(
    m: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
    scratch: &mut SpdScratch,
) -> std::result::Result<(), usize> {
    let n = m.nrows();
    if scratch.n != n {
        *scratch = SpdScratch::new(n);
    }
    let stack = MemStack::new(&mut scratch.buf);
    let a = MatMut::from_column_major_slice_mut(m.as_mut_slice(), n, n);
    llt::factor::cholesky_in_place(a, Default::default(), Par::Seq, stack, Default::default())
        .map_err(|llt::factor::LltError::NonPositivePivot { index }| index)?;
    // faer refuses pivots that are not > 0 (NaN too); an infinite one passes and leaves an
    // infinite diagonal entry of `L` at its index, refused here as the old factor did.
    let a = m.as_slice();
    if let Some(k) = (0..n).find(|&k| !a[k * n + k].is_finite()) {
        return Err(k);
    }
    let l = MatRef::from_column_major_slice(a, n, n);
    let o = MatMut::from_column_major_slice_mut(out.as_mut_slice(), n, n);
    llt::inverse::inverse(o, l, Par::Seq, stack);
    let o = out.as_mut_slice();
    for j in 0..n {
        for i in j + 1..n {
            o[i * n + j] = o[j * n + i];
        }
    }
    std::mem::swap(m, out);
    Ok(())
}

/// `out = α A B` (every matrix n × n): from [`SMALL`] on by faer's `matmul` (sequential, its
/// packing buffers kept per thread), which measured ~12 % faster than nalgebra's `gemm`
/// (matrixmultiply) at n = 100 and 300 (`examples/spd_inverse.rs`); below, nalgebra's as
/// before.
pub fn product(out: &mut DMatrix<f64>, alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>) {
    let n = out.nrows();
    if n < SMALL {
        out.gemm(alpha, a, b, 0.0);
        return;
    }
    let dst = MatMut::from_column_major_slice_mut(out.as_mut_slice(), n, n);
    let lhs = MatRef::from_column_major_slice(a.as_slice(), n, n);
    let rhs = MatRef::from_column_major_slice(b.as_slice(), n, n);
    matmul(dst, Accum::Replace, lhs, rhs, alpha, Par::Seq);
}

crate::support::cpu::multiversion! {
    /// [`spd_inverse`] below [`SMALL`]: `M = L Lᵀ`, `X = L⁻¹` in place, then `M⁻¹ = Xᵀ X`
    /// into `out` and swapped into place. Runs its AVX2 copy where the CPU has it
    /// (`crate::support::cpu`: the same IEEE operations in wider lanes, so the same bits).
    fn spd_inverse_small / spd_inverse_small_avx2 / spd_inverse_small_baseline [] (
        m: &mut DMatrix<f64>,
        out: &mut DMatrix<f64>,
        inv_diag: &mut [f64],
    ) -> std::result::Result<(), usize> => spd_inverse_small_body
}

#[inline(always)]
fn spd_inverse_small_body(
    m: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
    inv_diag: &mut [f64],
) -> std::result::Result<(), usize> {
    let n = m.nrows();
    factor_invert_small(m.as_mut_slice(), n, inv_diag)?;
    xtx_small(m.as_slice(), n, out.as_mut_slice());
    std::mem::swap(m, out);
    Ok(())
}

/// Below this size the factor, `X = L⁻¹` and `Xᵀ X` are scalar sums entry by entry: column
/// loops' vector set-up (lengths 1…n) and matrix kernels' packing cost more than the n³/6
/// products of each (chain7's forward derivatives: 5.8k instructions per call → see
/// benches/README.md, callgrind).
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
/// products (`L_ij = (M_ij − Σ_{k<j} L_ik L_jk) / L_jj`, `X_ij = (−L_ij / L_jj −
/// Σ_{j<k<i} L_ik X_kj) / L_ii`), in the order of
/// [`crate::recursive::aba_derivatives_small`], so the same bits.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense SPD matrix with a spread of eigenvalues (`B Bᵀ + c I`), not a mass matrix.
    fn spd(n: usize, c: f64) -> DMatrix<f64> {
        let b = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 13) % 17) as f64 / 17.0 - 0.5);
        &b * b.transpose() + DMatrix::identity(n, n) * c
    }

    /// faer's path (n ≥ SMALL) against nalgebra's own Cholesky inverse and `M M⁻¹ = I`, within
    /// a tolerance scaled by the condition number (backward-stable inverses: the error is
    /// ~ n ε κ, not bitwise); exactly symmetric; the scratch reused across calls.
    #[test]
    fn large_inverse_matches_nalgebra_and_identity() {
        for (n, c) in [(SMALL, 1.0), (40, 0.5), (40, 1e-3), (300, 2.0)] {
            let m = spd(n, c);
            let eig = m.clone().symmetric_eigen().eigenvalues;
            let kappa = eig.max() / eig.min();
            let tol = 64.0 * n as f64 * f64::EPSILON * kappa;
            let reference = m.clone().cholesky().expect("SPD").inverse();
            let (mut a, mut out) = (m.clone(), DMatrix::zeros(n, n));
            let (mut inv_diag, mut scratch) = (vec![0.0; n], SpdScratch::new(n));
            for _ in 0..2 {
                a.copy_from(&m);
                spd_inverse(&mut a, &mut out, &mut inv_diag, &mut scratch).expect("SPD");
                let rel = (&a - &reference).amax() / reference.amax();
                assert!(rel < tol, "n {n}: {rel:e} vs nalgebra (tol {tol:e})");
                let res = (&m * &a - DMatrix::identity(n, n)).amax();
                assert!(res < tol, "n {n}: |M M⁻¹ − I| {res:e} (tol {tol:e})");
                assert_eq!(a, a.transpose(), "n {n}: not exactly symmetric");
            }
        }
    }

    /// A non-positive pivot is reported at its index on both paths, and a non-finite one too.
    #[test]
    fn indefinite_reports_the_pivot() {
        for n in [SMALL - 1, SMALL, 40] {
            for (k, bad) in [
                (0, -1.0),
                (n / 2, 0.0),
                (n - 1, f64::NAN),
                (n / 3, f64::INFINITY),
            ] {
                let mut m = DMatrix::<f64>::identity(n, n);
                m[(k, k)] = bad;
                let mut out = DMatrix::zeros(n, n);
                let (mut inv_diag, mut scratch) = (vec![0.0; n], SpdScratch::new(n));
                let r = spd_inverse(&mut m, &mut out, &mut inv_diag, &mut scratch);
                assert_eq!(r, Err(k), "n {n}, pivot {k} = {bad}");
            }
        }
    }
}
