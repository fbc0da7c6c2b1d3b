//! Verner's "most efficient" 9(8) pair for the explicit Runge–Kutta engine
//! ([`ExplicitRk`]): 16 stages per step (the first is the previous step's `f(t + h, y_new)`),
//! the 9th-order solution, the 8th-order embedded estimate (error estimator order 8, RMS
//! norm as RK45's) and a 9th-order interpolant from 9 further stages, evaluated only for
//! steps the output needs (counted in `nfev`). Not a SciPy method; meant for tight
//! tolerances (rtol ≲ 1e-7) on smooth non-stiff problems, where its order should let it take
//! fewer evaluations than DOP853 for the same error (docs/integrators.md). The coefficients
//! are in `vern9_tableau.rs`.

use super::dense::Interpolant;
use super::explicit_rk::{error_scale, ExplicitRk, Tableau};
use super::method::Method;
use super::vern9_tableau::{A, B, C, E, N_STAGES, R, ROWS};

/// `out = base + h Σ_j w_j K[j]` over the non-zero weights `w` (accumulated in `out` first:
/// one pass per weight, each vectorised over the components).
#[inline(always)]
fn combine_sparse(out: &mut [f64], base: &[f64], k: &[f64], w: &[(usize, f64)], h: f64) {
    let n = out.len();
    out.fill(0.0);
    for &(j, a) in w {
        let kj = &k[j * n..(j + 1) * n];
        for (o, x) in out.iter_mut().zip(kj) {
            *o += a * x;
        }
    }
    for (o, b) in out.iter_mut().zip(&base[..n]) {
        *o = b + *o * h;
    }
}

/// `Σ_j E_j K[j]` of component `i`.
#[inline(always)]
fn error_of(k: &[f64], n: usize, i: usize) -> f64 {
    E.iter().map(|&(j, e)| e * k[j * n + i]).sum()
}

/// Verner's 9(8) tableau. Its stability interval on the negative axis ends at `h λ ≈ −4.48`
/// (computed from the tableau), hence the stiffness threshold 4.4.
pub struct Vern9Tableau;

impl Tableau for Vern9Tableau {
    const METHOD: Method = Method::Vern9;
    const N_STAGES: usize = N_STAGES;
    const ROWS: usize = ROWS;
    const C: &'static [f64] = &C;
    const ERROR_ESTIMATOR_ORDER: u32 = 8;
    const ERROR_EXPONENT: f64 = -1.0 / 9.0;
    const STIFF_H_LAMBDA: f64 = 4.4;
    const INTERPOLANT: Interpolant = Interpolant::Vern9;

    #[inline(always)]
    fn stage_state(s: usize, out: &mut [f64], base: &[f64], k: &[f64], h: f64) {
        combine_sparse(out, base, k, A[s], h);
    }

    #[inline(always)]
    fn propagate(out: &mut [f64], y: &[f64], k: &[f64], h: f64) {
        combine_sparse(out, y, k, &B, h);
    }

    /// RMS of `h (Kᵀ E) / scale`, `scale = atol + max(|y|, |y_new|) rtol`.
    fn error_norm(
        k: &[f64],
        ys: (&[f64], &[f64]),
        tols: (&[f64], &[f64]),
        h: f64,
        scratch: &mut [f64],
    ) -> f64 {
        let n = scratch.len();
        scratch.fill(0.0);
        for &(j, e) in &E {
            for (o, x) in scratch.iter_mut().zip(&k[j * n..(j + 1) * n]) {
                *o += e * x;
            }
        }
        let mut sq = 0.0;
        for (i, e) in scratch.iter().enumerate() {
            let r = e * h / error_scale(i, ys, tols);
            sq += r * r;
        }
        (sq / n as f64).sqrt()
    }

    const BLENDS_LOWER_ORDER: bool = false;

    fn error_vectors(k: &[f64], h: f64, e: &mut [f64], _e_low: &mut [f64]) {
        let n = e.len();
        for (i, x) in e.iter_mut().enumerate() {
            *x = error_of(k, n, i) * h;
        }
    }

    fn norm_of_vectors(
        e: &[f64],
        _e_low: &[f64],
        ys: (&[f64], &[f64]),
        tols: (&[f64], &[f64]),
    ) -> f64 {
        let sq: f64 = (0..e.len())
            .map(|i| (e[i] / error_scale(i, ys, tols)).powi(2))
            .sum();
        (sq / e.len() as f64).sqrt()
    }

    /// `q[9 i + p − 1] = h Σ_s R_s[p − 1] K[s][i]` (p = 1..9): the interpolant
    /// `y_old + Σ_p q_p θ^p` ([`Interpolant::Vern9`]).
    fn dense(k: &[f64], (y_old, _, _): (&[f64], &[f64], &[f64]), h: f64, q: &mut [f64]) {
        let n = y_old.len();
        q[..9 * n].fill(0.0);
        for (s, r) in &R {
            let ks = &k[s * n..(s + 1) * n];
            for (i, x) in ks.iter().enumerate() {
                let qi = &mut q[9 * i..9 * i + 9];
                for (c, rp) in qi.iter_mut().zip(r) {
                    *c += rp * x;
                }
            }
        }
        for c in &mut q[..9 * n] {
            *c *= h;
        }
    }
}

/// Adaptive Verner 9(8) usable one step at a time: the explicit Runge–Kutta engine with the
/// [`Vern9Tableau`].
pub type Vern9<S> = ExplicitRk<S, Vern9Tableau>;
