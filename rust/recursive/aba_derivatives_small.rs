//! The forward derivatives' linear algebra for small models at a size fixed at compile time
//! (n ≤ [`MAX_FIXED`]): `M⁻¹` from the Cholesky factor, then `−M⁻¹ ∂τ/∂q` and `−M⁻¹ ∂τ/∂v`,
//! in one pass over stack arrays. With `n` a constant every loop has a known trip count (no
//! bounds checks, no variable-length loop set-up, which cost more than the ~850 products of
//! chain7), and `M⁻¹`'s columns, padded to a multiple of four rows, are whole vector
//! registers in the products. The same operations in the same order as
//! [`crate::linalg::spd_inverse`]'s small path and the column products, so the same bits.

/// The largest size served here; above it, the run-time-sized loops.
pub(crate) const MAX_FIXED: usize = 12;

crate::support::cpu::multiversion! {
    /// `M⁻¹` into `minv`, `−M⁻¹ D_q` into `out_q`, `−M⁻¹ D_v` into `out_v` (every matrix
    /// n × n, column-major, `M` symmetric positive definite: only its lower triangle is
    /// read). `None` when n is not in 1..=[`MAX_FIXED`] (nothing written); `Some(Err(k))` at
    /// a non-positive pivot `k`. AVX2 where the CPU has it.
    pub(crate) fn inverse_and_products / inverse_and_products_avx2 / inverse_and_products_baseline [] (
        n: usize,
        mass: &[f64],
        d: [&[f64]; 2],
        minv: &mut [f64],
        out: [&mut [f64]; 2],
    ) -> Option<Result<(), usize>> => body
}

#[inline(always)]
fn body(
    n: usize,
    mass: &[f64],
    d: [&[f64]; 2],
    minv: &mut [f64],
    out: [&mut [f64]; 2],
) -> Option<Result<(), usize>> {
    // `P`: `N` rounded up to a multiple of four (one AVX2 register per four rows).
    macro_rules! sizes {
        ($($n:literal => $p:literal),*) => {
            match n {
                $($n => Some(fixed::<$n, $p>(mass, d, minv, out)),)*
                _ => None,
            }
        };
    }
    sizes!(1 => 4, 2 => 4, 3 => 4, 4 => 4, 5 => 8, 6 => 8, 7 => 8, 8 => 8, 9 => 12, 10 => 12,
        11 => 12, 12 => 12)
}

/// See [`inverse_and_products`]; `N` the size, `P ≥ N` the padded column length.
#[inline(always)]
fn fixed<const N: usize, const P: usize>(
    mass: &[f64],
    d: [&[f64]; 2],
    minv: &mut [f64],
    out: [&mut [f64]; 2],
) -> Result<(), usize> {
    // Columns: `a[j][i]` is entry (i, j).
    let mut a = [[0.0; N]; N];
    for (j, c) in a.iter_mut().enumerate() {
        c.copy_from_slice(&mass[j * N..(j + 1) * N]);
    }
    let mut inv_diag = [0.0; N];
    // `M = L Lᵀ`: `L_ij = (M_ij − Σ_{k<j} L_ik L_jk) / L_jj`.
    for j in 0..N {
        for i in j..N {
            let mut s = a[j][i];
            for k in 0..j {
                s -= a[k][j] * a[k][i];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return Err(j);
                }
                let r = s.sqrt();
                a[j][j] = r;
                inv_diag[j] = 1.0 / r;
            } else {
                a[j][i] = s * inv_diag[j];
            }
        }
    }
    // `X = L⁻¹` in place: `X_ij = (−L_ij / L_jj − Σ_{j<k<i} L_ik X_kj) / L_ii`.
    for j in 0..N {
        let xj = inv_diag[j];
        a[j][j] = xj;
        for i in j + 1..N {
            let mut s = a[j][i] * -xj;
            for k in j + 1..i {
                s -= a[j][k] * a[k][i];
            }
            a[j][i] = s * inv_diag[i];
        }
    }
    // `M⁻¹ = Xᵀ X`: `(i, j) = Σ_{k ≥ max(i, j)} X_ki X_kj`, computed once and mirrored (exactly
    // symmetric), into columns padded with zeros to `P` rows.
    let mut m = [[0.0; P]; N];
    for j in 0..N {
        for i in j..N {
            let mut s = 0.0;
            for k in i..N {
                s += a[i][k] * a[j][k];
            }
            m[j][i] = s;
            m[i][j] = s;
        }
    }
    for (j, c) in m.iter().enumerate() {
        minv[j * N..(j + 1) * N].copy_from_slice(&c[..N]);
    }
    // Column `j` of `−M⁻¹ D` is `−Σ_k D_kj M⁻¹[:, k]`, `k` in order (as the run-time-sized
    // product), over whole padded columns.
    for (d, out) in d.into_iter().zip(out) {
        let (d, out) = (&d[..N * N], &mut out[..N * N]);
        for j in 0..N {
            let mut acc = [0.0; P];
            for k in 0..N {
                let x = d[j * N + k];
                for r in 0..P {
                    acc[r] -= x * m[k][r];
                }
            }
            out[j * N..(j + 1) * N].copy_from_slice(&acc[..N]);
        }
    }
    Ok(())
}
