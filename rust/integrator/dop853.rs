//! Dormand–Prince 8(5,3), SciPy's `DOP853` (scipy/integrate/_ivp/rk.py) for the explicit
//! Runge–Kutta engine ([`ExplicitRk`]): 12 stages, the solution propagated with the 8th-order
//! weights, the error estimate of Hairer's DOP853 (5th- and 3rd-order embedded estimates
//! combined), error estimator order 7, and the 7th-order dense output from three extra
//! stages, evaluated only when asked for (and then counted in `nfev`, as SciPy does). The
//! tableau's digits are in `dop853_tableau.rs`.

use super::dense::Interpolant;
use super::dop853_tableau::{A, B, C, D, E3, E5, INTERPOLATOR_POWER, N_STAGES, N_STAGES_EXTENDED};
use super::explicit_rk::{error_scale, stage_sum, ExplicitRk, Tableau};
use super::method::Method;
use super::stepper::combine;

/// The first `S` entries of row `s` of the tableau.
#[inline(always)]
fn row<const S: usize>(s: usize) -> [f64; S] {
    std::array::from_fn(|j| A[s][j])
}

/// SciPy's `DOP853` tableau. Hairer's DOP853 stiffness threshold 6.1.
pub struct Dop853Tableau;

impl Tableau for Dop853Tableau {
    const METHOD: Method = Method::Dop853;
    const N_STAGES: usize = N_STAGES;
    const ROWS: usize = N_STAGES_EXTENDED;
    const C: &'static [f64] = &C;
    const ERROR_ESTIMATOR_ORDER: u32 = 7;
    const ERROR_EXPONENT: f64 = -1.0 / 8.0;
    const STIFF_H_LAMBDA: f64 = 6.1;
    const INTERPOLANT: Interpolant = Interpolant::Dop853;

    #[inline(always)]
    fn stage_state(s: usize, ys: &mut [f64], base: &[f64], k: &[f64], h: f64) {
        match s {
            1 => combine(ys, base, k, &row::<1>(1), h),
            2 => combine(ys, base, k, &row::<2>(2), h),
            3 => combine(ys, base, k, &row::<3>(3), h),
            4 => combine(ys, base, k, &row::<4>(4), h),
            5 => combine(ys, base, k, &row::<5>(5), h),
            6 => combine(ys, base, k, &row::<6>(6), h),
            7 => combine(ys, base, k, &row::<7>(7), h),
            8 => combine(ys, base, k, &row::<8>(8), h),
            9 => combine(ys, base, k, &row::<9>(9), h),
            10 => combine(ys, base, k, &row::<10>(10), h),
            11 => combine(ys, base, k, &row::<11>(11), h),
            13 => combine(ys, base, k, &row::<13>(13), h),
            14 => combine(ys, base, k, &row::<14>(14), h),
            _ => combine(ys, base, k, &row::<15>(15), h),
        }
    }

    #[inline(always)]
    fn propagate(out: &mut [f64], y: &[f64], k: &[f64], h: f64) {
        combine(out, y, k, &B, h);
    }

    /// SciPy `DOP853._estimate_error_norm`: `|h| ‖e5‖² / sqrt((‖e5‖² + 0.01 ‖e3‖²) n)` with
    /// `e = (Kᵀ E) / scale`, `scale = atol + max(|y|, |y_new|) rtol`.
    fn error_norm(
        k: &[f64],
        (y, y_new): (&[f64], &[f64]),
        (atol, rtol): (&[f64], &[f64]),
        h: f64,
        _scratch: &mut [f64],
    ) -> f64 {
        let n = y.len();
        let (mut s5, mut s3) = (0.0f64, 0.0f64);
        for i in 0..n {
            let (mut e5, mut e3) = (k[i] * E5[0], k[i] * E3[0]);
            for s in 1..N_STAGES + 1 {
                e5 += k[s * n + i] * E5[s];
                e3 += k[s * n + i] * E3[s];
            }
            let (a, b) = (y[i].abs(), y_new[i].abs());
            let scale = atol[i] + if a >= b { a } else { b } * rtol[i];
            let (e5, e3) = (e5 / scale, e3 / scale);
            s5 += e5 * e5;
            s3 += e3 * e3;
        }
        // np.linalg.norm(x)**2: the square root squared again, as SciPy rounds it.
        let (n5, n3) = (s5.sqrt(), s3.sqrt());
        let (e5n2, e3n2) = (n5 * n5, n3 * n3);
        if e5n2 == 0.0 && e3n2 == 0.0 {
            return 0.0;
        }
        let denom = e5n2 + 0.01 * e3n2;
        h.abs() * e5n2 / (denom * n as f64).sqrt()
    }

    const BLENDS_LOWER_ORDER: bool = true;

    fn error_vectors(k: &[f64], h: f64, e: &mut [f64], e_low: &mut [f64]) {
        let n = e.len();
        for i in 0..n {
            e[i] = stage_sum(k, n, i, &E5) * h;
            e_low[i] = stage_sum(k, n, i, &E3) * h;
        }
    }

    /// The norm above of `e = h Kᵀ E5`, `e_low = h Kᵀ E3`: `‖e‖² / sqrt((‖e‖² + 0.01
    /// ‖e_low‖²) n)` (the factors `h` cancel).
    fn norm_of_vectors(
        e: &[f64],
        e_low: &[f64],
        ys: (&[f64], &[f64]),
        tols: (&[f64], &[f64]),
    ) -> f64 {
        let (mut s5, mut s3) = (0.0f64, 0.0f64);
        for i in 0..e.len() {
            let scale = error_scale(i, ys, tols);
            s5 += (e[i] / scale).powi(2);
            s3 += (e_low[i] / scale).powi(2);
        }
        if s5 == 0.0 && s3 == 0.0 {
            return 0.0;
        }
        s5 / ((s5 + 0.01 * s3) * e.len() as f64).sqrt()
    }

    /// SciPy `DOP853._dense_output_impl` (the extra stages 13..16 already in `k`):
    /// `F = [Δ, h f_old − Δ, 2Δ − h (f + f_old), h D K]`, `Δ = y − y_old`, into
    /// `q[7 i + j] = F[j][i]`.
    fn dense(k: &[f64], (y_old, y, f): (&[f64], &[f64], &[f64]), h: f64, q: &mut [f64]) {
        let n = y.len();
        for i in 0..n {
            let delta = y[i] - y_old[i];
            let f_old = k[i];
            let qi = &mut q[INTERPOLATOR_POWER * i..INTERPOLATOR_POWER * (i + 1)];
            qi[0] = delta;
            qi[1] = h * f_old - delta;
            qi[2] = 2.0 * delta - h * (f[i] + f_old);
            for (j, d) in D.iter().enumerate() {
                let mut acc = d[0] * k[i];
                for s in 1..N_STAGES_EXTENDED {
                    acc += d[s] * k[s * n + i];
                }
                qi[3 + j] = h * acc;
            }
        }
    }
}

/// Adaptive DOP853 usable one step at a time (SciPy's `DOP853` solver object): the explicit
/// Runge–Kutta engine with the [`Dop853Tableau`].
pub type Dop853<S> = ExplicitRk<S, Dop853Tableau>;
