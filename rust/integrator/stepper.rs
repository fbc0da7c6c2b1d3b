//! The Dormand–Prince 5(4) tableau of SciPy's `RK45` (scipy/integrate/_ivp/rk.py) for the
//! explicit Runge–Kutta engine ([`ExplicitRk`]): [`Stepper`] is that engine with it. Also the
//! stage and error kernels every tableau uses, in NumPy's order of summation.

use super::dense::{self, Interpolant};
use super::explicit_rk::{error_scale, stage_sum, ExplicitRk, Tableau};
use super::method::Method;
use super::OdeSystem;
#[cfg(test)]
use super::{common::next_toward, Controller, SolverOptions, StepOutcome};

pub(crate) const N_STAGES: usize = 6;
pub(crate) const C: [f64; N_STAGES] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0];
pub(crate) const A: [[f64; 5]; N_STAGES] = [
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
    ],
];
/// 5th-order weights (the solution is propagated with these: local extrapolation).
pub(crate) const B: [f64; N_STAGES] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
];
/// Error weights B - B̂ over the 7 FSAL stages.
pub(crate) const E: [f64; N_STAGES + 1] = [
    -71.0 / 57600.0,
    0.0,
    71.0 / 16695.0,
    -71.0 / 1920.0,
    17253.0 / 339200.0,
    -22.0 / 525.0,
    1.0 / 40.0,
];

/// The first `S` entries of a tableau row.
#[inline(always)]
pub(crate) fn first<const S: usize>(row: &[f64; 5]) -> [f64; S] {
    std::array::from_fn(|j| row[j])
}

crate::support::cpu::multiversion! {
    /// `out[i] = y[i] + (k_0[i] c_0 + k_1[i] c_1 + …) h` with `k_j = k[j n..(j + 1) n]`: per
    /// entry, the products summed left to right with every coefficient (zeros too), which is
    /// how `np.dot(K[:s].T, c)` rounds, so steps stay SciPy's. Runs its AVX2 copy where the
    /// CPU has it (`crate::support::cpu`; same arithmetic, packed lanes).
    pub(crate) fn combine / combine_avx2 / combine_baseline [const S: usize] (
        out: &mut [f64],
        y: &[f64],
        k: &[f64],
        coef: &[f64; S],
        h: f64,
    ) => combine_body
}

#[inline(always)]
fn combine_body<const S: usize>(out: &mut [f64], y: &[f64], k: &[f64], coef: &[f64; S], h: f64) {
    let n = out.len();
    let y = &y[..n];
    let ks: [&[f64]; S] = std::array::from_fn(|j| &k[j * n..(j + 1) * n]);
    for i in 0..n {
        let mut acc = ks[0][i] * coef[0];
        for j in 1..S {
            acc += ks[j][i] * coef[j];
        }
        out[i] = y[i] + acc * h;
    }
}

crate::support::cpu::multiversion! {
    /// `r[i] = (K[i]ᵀ E) h / (atol[i] + max(|y[i]|, |y_new[i]|) rtol[i])`, element-wise (its
    /// AVX2 copy where the CPU has it); the caller sums the squares in order.
    fn scaled_errors / scaled_errors_avx2 / scaled_errors_baseline [] (
        r: &mut [f64],
        k: &[f64],
        ys: (&[f64], &[f64]),
        tols: (&[f64], &[f64]),
        h: f64,
    ) => scaled_errors_body
}

#[inline(always)]
fn scaled_errors_body(
    r: &mut [f64],
    k: &[f64],
    (y, y_new): (&[f64], &[f64]),
    (atol, rtol): (&[f64], &[f64]),
    h: f64,
) {
    let n = r.len();
    let ks: [&[f64]; N_STAGES + 1] = std::array::from_fn(|s| &k[s * n..(s + 1) * n]);
    let (y, y_new, atol, rtol) = (&y[..n], &y_new[..n], &atol[..n], &rtol[..n]);
    for i in 0..n {
        let mut e = ks[0][i] * E[0];
        for s in 1..N_STAGES + 1 {
            e += ks[s][i] * E[s];
        }
        // Both finite here (checked): the plain comparison is `max` without NaN handling.
        let (a, b) = (y[i].abs(), y_new[i].abs());
        let scale = atol[i] + if a >= b { a } else { b } * rtol[i];
        r[i] = e * h / scale;
    }
}

/// SciPy's `RK45`: Dormand–Prince 5(4), the 4th-order error estimate, the quartic interpolant
/// (Shampine's). Hairer's DOPRI5 stiffness threshold 3.25.
pub struct Rk45;

impl Tableau for Rk45 {
    const METHOD: Method = Method::Rk45;
    const N_STAGES: usize = N_STAGES;
    const ROWS: usize = N_STAGES + 1;
    const C: &'static [f64] = &C;
    const ERROR_ESTIMATOR_ORDER: u32 = 4;
    const ERROR_EXPONENT: f64 = -1.0 / 5.0;
    const STIFF_H_LAMBDA: f64 = super::STIFF_H_LAMBDA;
    const INTERPOLANT: Interpolant = Interpolant::Rk45;

    #[inline(always)]
    fn stage_state(s: usize, out: &mut [f64], base: &[f64], k: &[f64], h: f64) {
        // y_s = y + (K[:s]ᵀ a[:s]) h, summed stage by stage like np.dot.
        match s {
            1 => combine(out, base, k, &first::<1>(&A[1]), h),
            2 => combine(out, base, k, &first::<2>(&A[2]), h),
            3 => combine(out, base, k, &first::<3>(&A[3]), h),
            4 => combine(out, base, k, &first::<4>(&A[4]), h),
            _ => combine(out, base, k, &first::<5>(&A[5]), h),
        }
    }

    #[inline(always)]
    fn propagate(out: &mut [f64], y: &[f64], k: &[f64], h: f64) {
        combine(out, y, k, &B, h);
    }

    /// RMS of `(Kᵀ E) h / scale`, `scale = atol + max(|y|, |y_new|) rtol`.
    #[inline(always)]
    fn error_norm(
        k: &[f64],
        ys: (&[f64], &[f64]),
        tols: (&[f64], &[f64]),
        h: f64,
        scaled: &mut [f64],
    ) -> f64 {
        scaled_errors(scaled, k, ys, tols, h);
        // The sum in index order, as NumPy's norm takes it for these short vectors.
        let mut sq = 0.0;
        for r in scaled.iter() {
            sq += r * r;
        }
        sq.sqrt() / (scaled.len() as f64).sqrt()
    }

    const BLENDS_LOWER_ORDER: bool = false;

    fn error_vectors(k: &[f64], h: f64, e: &mut [f64], _e_low: &mut [f64]) {
        let n = e.len();
        for (i, x) in e.iter_mut().enumerate() {
            *x = stage_sum(k, n, i, &E) * h;
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
        sq.sqrt() / (e.len() as f64).sqrt()
    }

    /// `Q = Kᵀ P` (`q[4 i + j]`).
    fn dense(k: &[f64], (y_old, _, _): (&[f64], &[f64], &[f64]), _h: f64, q: &mut [f64]) {
        dense::fill_q(k, y_old.len(), q);
    }
}

/// Adaptive RK45 usable one step at a time (SciPy's `RK45` solver object): the explicit
/// Runge–Kutta engine with the [`Rk45`] tableau.
pub type Stepper<S> = ExplicitRk<S, Rk45>;

impl<S: OdeSystem> ExplicitRk<S, Rk45> {
    /// Interpolant coefficients `Q = Kᵀ P` (`4 · dim`, `q[4 i + j]`) of the last accepted step,
    /// for [`dense::eval_segment`]`(t_old(), t() - t_old(), y_old(), q, t, out)`.
    /// Returns false (leaving `q` untouched) before the first step.
    pub fn fill_dense_q(&self, q: &mut [f64]) -> bool {
        if self.n_accepted() == 0 {
            return false;
        }
        dense::fill_q(self.stages(), self.dim(), q);
        true
    }
}

#[cfg(test)]
#[path = "tests/stepper.rs"]
mod tests;
