//! Timings of the mass matrix's inverse and the forward derivatives' two products at one
//! size, the choice of rust/linalg/spd.rs measured (benches/README.md, session 10):
//!
//! ```text
//! cargo build --release --example spd_inverse
//! target/release/examples/spd_inverse 300 50
//! ```
//!
//! `spd_inverse` (faer's blocked factor and inverse from `SMALL` on) against the column-loop
//! Cholesky it replaced (kept here, AVX2 where the CPU has it, as it ran), and `−M⁻¹ D` by
//! nalgebra's `gemm` (matrixmultiply) against faer's `matmul` (sequential). Prints the best
//! of ITERS calls of each, in microseconds, and the largest entry of `|M M⁻¹ − I|`.
use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use nalgebra::DMatrix;
use pointmass_dyn::linalg::spd::{spd_inverse, SpdScratch};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (n, iters) = match args.as_slice() {
        [_, n, i] => (n.parse::<usize>()?, i.parse::<usize>()?),
        _ => return Err("usage: spd_inverse N ITERS".into()),
    };
    // A chain's mass matrix is dense and well conditioned enough; any SPD matrix serves.
    let b = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 13) % 17) as f64 / 17.0 - 0.5);
    let m = &b * b.transpose() + DMatrix::identity(n, n) * n as f64;
    let d = DMatrix::from_fn(n, n, |i, j| ((i * 3 + j * 5) % 11) as f64 - 5.0);
    let (mut a, mut out, mut prod) = (m.clone(), m.clone(), m.clone());
    let mut inv_diag = vec![0.0; n];
    let mut scratch = SpdScratch::new(n);
    let best = |f: &mut dyn FnMut()| {
        (0..iters.max(1))
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64() * 1e6
            })
            .fold(f64::INFINITY, f64::min)
    };
    let t_new = best(&mut || {
        a.copy_from(&m);
        spd_inverse(&mut a, &mut out, &mut inv_diag, &mut scratch).expect("SPD");
    });
    let err_new = (&m * &a - DMatrix::identity(n, n)).amax();
    let t_old = best(&mut || {
        a.copy_from(&m);
        old::spd_inverse(&mut a, &mut prod, &mut out, &mut inv_diag).expect("SPD");
    });
    let err_old = (&m * &a - DMatrix::identity(n, n)).amax();
    let t_nalgebra = best(&mut || prod.gemm(-1.0, &a, &d, 0.0));
    let t_faer = best(&mut || {
        let dst = MatMut::from_column_major_slice_mut(prod.as_mut_slice(), n, n);
        let lhs = MatRef::from_column_major_slice(a.as_slice(), n, n);
        let rhs = MatRef::from_column_major_slice(d.as_slice(), n, n);
        matmul(dst, Accum::Replace, lhs, rhs, -1.0, Par::Seq);
    });
    println!(
        "n {n}: spd_inverse faer {t_new:.1} us (|MM^-1 - I| {err_new:.1e}), column loops {t_old:.1} us ({err_old:.1e}); -M^-1 D nalgebra gemm {t_nalgebra:.1} us, faer matmul {t_faer:.1} us"
    );
    Ok(())
}

/// The column-loop Cholesky, `L⁻¹` and `L⁻ᵀ L⁻¹` that rust/linalg/spd.rs ran from `SMALL` on
/// before session 10, as it was (for n ≥ 24 only).
mod old {
    use nalgebra::DMatrix;

    pub fn spd_inverse(
        m: &mut DMatrix<f64>,
        t: &mut DMatrix<f64>,
        out: &mut DMatrix<f64>,
        inv_diag: &mut [f64],
    ) -> Result<(), usize> {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { avx2(m, t, out, inv_diag) };
        }
        body(m, t, out, inv_diag)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn avx2(
        m: &mut DMatrix<f64>,
        t: &mut DMatrix<f64>,
        out: &mut DMatrix<f64>,
        inv_diag: &mut [f64],
    ) -> Result<(), usize> {
        body(m, t, out, inv_diag)
    }

    #[inline(always)]
    fn body(
        m: &mut DMatrix<f64>,
        t: &mut DMatrix<f64>,
        out: &mut DMatrix<f64>,
        inv_diag: &mut [f64],
    ) -> Result<(), usize> {
        let n = m.nrows();
        let a = m.as_mut_slice();
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
        let a = m.as_mut_slice();
        for j in 0..n {
            for i in j + 1..n {
                a[i * n + j] = a[j * n + i];
            }
        }
        Ok(())
    }
}
