//! Dormand–Prince 5(4) tableau and the adaptive single-step machinery, a line-by-line port of
//! SciPy's `RungeKutta._step_impl`, `rk_step` and `select_initial_step`
//! (scipy/integrate/_ivp/rk.py, common.py). Arithmetic is kept in NumPy's order so the
//! accept/reject decisions, and hence the step counts, match SciPy.

use super::method::{Counts, Integrator};
use super::{
    dense, Controller, InputError, NonFiniteKind, OdeSystem, SolverOptions, Status, Stiffness,
    StiffnessCheck, Tol, NONSTIFF_RESET, STIFF_H_LAMBDA, STIFF_STEPS,
};

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

pub(crate) const SAFETY: f64 = 0.9;
pub(crate) const MIN_FACTOR: f64 = 0.2;
pub(crate) const MAX_FACTOR: f64 = 10.0;
/// SciPy's `RK45.error_estimator_order`.
const ERROR_ESTIMATOR_ORDER: u32 = 4;
/// -1 / (error_estimator_order + 1), evaluated as SciPy does.
const ERROR_EXPONENT: f64 = -1.0 / 5.0;
/// Floor of the previous error in the PI controller (Hairer's `facold` start value).
const PI_ERR_FLOOR: f64 = 1e-4;

/// Result of an accepted step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepOutcome {
    /// Step accepted, `t_bound` not reached yet.
    Accepted,
    /// Step accepted and `t_bound` reached (further calls do nothing and return this again).
    Finished,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum State {
    Uninitialised,
    Running,
    Finished,
    Failed(Status),
}

/// Adaptive RK45 usable one step at a time (SciPy's `RK45` solver object).
///
/// All buffers are allocated in [`Stepper::new`]; [`Stepper::step`] allocates nothing.
/// The first `step` (or an explicit [`Stepper::initialize`]) evaluates `f(t0, y0)` and, without
/// `first_step`, one more rhs call to choose the initial step.
pub struct Stepper<S: OdeSystem> {
    sys: S,
    dim: usize,
    t: f64,
    t_old: f64,
    t_bound: f64,
    direction: f64,
    y: Vec<f64>,
    y_old: Vec<f64>,
    /// f(t, y), FSAL: the last stage of the previous step.
    f: Vec<f64>,
    /// Stage derivatives, 7 rows of `dim` (row 6 = f(t_new, y_new)).
    k: Vec<f64>,
    y_stage: Vec<f64>,
    y_new: Vec<f64>,
    /// Per-entry scaled errors of the step (workspace of `error_norm`).
    scaled_error: Vec<f64>,
    rtol: Vec<f64>,
    atol: Vec<f64>,
    rtol_clamped: bool,
    max_step: f64,
    first_step: Option<f64>,
    max_steps: usize,
    controller: Controller,
    /// Previous accepted error norm (PI controller only).
    err_prev: f64,
    /// Size of the next step to try.
    h_abs: f64,
    nfev: usize,
    n_accepted: usize,
    n_rejected: usize,
    state: State,
    stiffness_check: StiffnessCheck,
    /// Hairer's IASTI / NONSTI counters.
    stiff_count: usize,
    nonstiff_count: usize,
    /// `h·|λ|` of the last accepted step (NaN before the first, or with the check off).
    h_lambda: f64,
    /// First detection.
    stiffness: Option<Stiffness>,
    /// `StiffnessCheck::Stop`: the failure the next `step` returns.
    stop: Option<Status>,
}

pub(crate) fn expand_tol(
    tol: &Tol,
    name: &'static str,
    dim: usize,
) -> Result<Vec<f64>, InputError> {
    let v = match tol {
        Tol::Scalar(x) => vec![*x; dim],
        Tol::PerComponent(v) if v.len() == dim => v.clone(),
        Tol::PerComponent(v) => {
            return Err(InputError::TolLength {
                name,
                expected: dim,
                got: v.len(),
            })
        }
    };
    if let Some((index, &value)) = v
        .iter()
        .enumerate()
        .find(|(_, x)| !(x.is_finite() && **x >= 0.0))
    {
        return Err(InputError::TolInvalid { name, index, value });
    }
    Ok(v)
}

/// RMS norm, as `np.linalg.norm(x) / x.size ** 0.5`.
pub(crate) fn rms_norm(it: impl Iterator<Item = f64>, n: usize) -> f64 {
    let sq: f64 = it.map(|v| v * v).sum();
    sq.sqrt() / (n as f64).sqrt()
}

/// `np.nextafter(x, dir * inf)` for finite `x`.
pub(crate) fn next_toward(x: f64, dir: f64) -> f64 {
    if x == 0.0 {
        let tiny = f64::from_bits(1);
        return if dir > 0.0 { tiny } else { -tiny };
    }
    let bits = x.to_bits();
    // Moving away from zero increases the magnitude bits.
    if (x > 0.0) == (dir > 0.0) {
        f64::from_bits(bits + 1)
    } else {
        f64::from_bits(bits - 1)
    }
}

/// One rhs evaluation with the NonFinite / RhsError checks.
pub(crate) fn call_rhs<S: OdeSystem>(
    sys: &mut S,
    nfev: &mut usize,
    t_reached: f64,
    t: f64,
    y: &[f64],
    out: &mut [f64],
) -> Result<(), Status> {
    *nfev += 1;
    sys.rhs(t, y, out).map_err(|message| Status::RhsError {
        t: t_reached,
        at: t,
        message,
    })?;
    if all_finite(out) {
        Ok(())
    } else {
        Err(Status::NonFinite {
            t: t_reached,
            at: t,
            what: NonFiniteKind::Derivative,
        })
    }
}

/// Whether every entry is finite. This runs twice per evaluation on values that almost
/// always are: `0 · v` is ±0 for a finite `v` and NaN for ±inf or NaN, NaN survives the sums,
/// and four independent sums vectorise.
#[inline]
pub(crate) fn all_finite(y: &[f64]) -> bool {
    let mut acc = [0.0f64; 4];
    let mut chunks = y.chunks_exact(4);
    for c in &mut chunks {
        for k in 0..4 {
            acc[k] += c[k] * 0.0;
        }
    }
    let rest: f64 = chunks.remainder().iter().map(|v| v * 0.0).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest == 0.0
}

pub(crate) fn check_state(y: &[f64], t_reached: f64, at: f64) -> Result<(), Status> {
    if all_finite(y) {
        Ok(())
    } else {
        Err(Status::NonFinite {
            t: t_reached,
            at,
            what: NonFiniteKind::State,
        })
    }
}

/// The first `S` entries of a tableau row.
#[inline(always)]
pub(crate) fn first<const S: usize>(row: &[f64; 5]) -> [f64; S] {
    std::array::from_fn(|j| row[j])
}

crate::cpu::multiversion! {
    /// `out[i] = y[i] + (k_0[i] c_0 + k_1[i] c_1 + …) h` with `k_j = k[j n..(j + 1) n]`: per
    /// entry, the products summed left to right with every coefficient (zeros too), which is
    /// how `np.dot(K[:s].T, c)` rounds, so steps stay SciPy's. Runs its AVX2 copy where the
    /// CPU has it (`crate::cpu`; same arithmetic, packed lanes).
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

crate::cpu::multiversion! {
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

/// The start of a run: `f0 = f(t0, y0)`.
pub(crate) struct Start<'a> {
    pub t0: f64,
    pub y0: &'a [f64],
    pub f0: &'a [f64],
    pub t_bound: f64,
    pub direction: f64,
}

/// SciPy `select_initial_step` (Hairer, Nørsett & Wanner, Sec. II.4) for an error estimator
/// of order `order`; `scratch` = three buffers of `dim` (scale, y1, f1). One rhs call.
pub(crate) fn select_initial_step<S: OdeSystem>(
    sys: &mut S,
    nfev: &mut usize,
    st: Start<'_>,
    (atol, rtol): (&[f64], &[f64]),
    max_step: f64,
    order: u32,
    scratch: (&mut [f64], &mut [f64], &mut [f64]),
) -> Result<f64, Status> {
    let (scale, y1, f1) = scratch;
    let (t0, dir, y0, f0) = (st.t0, st.direction, st.y0, st.f0);
    let n = y0.len();
    let interval_length = (st.t_bound - t0).abs();
    for i in 0..n {
        scale[i] = atol[i] + y0[i].abs() * rtol[i];
    }
    let d0 = rms_norm((0..n).map(|i| y0[i] / scale[i]), n);
    let d1 = rms_norm((0..n).map(|i| f0[i] / scale[i]), n);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(interval_length);
    let hd = h0 * dir;
    for i in 0..n {
        y1[i] = y0[i] + hd * f0[i];
    }
    call_rhs(sys, nfev, t0, t0 + h0 * dir, y1, f1)?;
    let d2 = rms_norm((0..n).map(|i| (f1[i] - f0[i]) / scale[i]), n) / h0;
    let h1 = if d1 <= 1e-15 && d2 <= 1e-15 {
        (1e-6f64).max(h0 * 1e-3)
    } else {
        (0.01 / if d1 >= d2 { d1 } else { d2 }).powf(1.0 / (order + 1) as f64)
    };
    Ok((100.0 * h0).min(h1).min(interval_length).min(max_step))
}

/// The initial state and the interval: `dim` finite components, two different finite times.
pub(crate) fn check_start(dim: usize, y0: &[f64], t0: f64, t_bound: f64) -> Result<(), InputError> {
    if dim == 0 {
        return Err(InputError::EmptyState);
    }
    if y0.len() != dim {
        return Err(InputError::Y0Length {
            expected: dim,
            got: y0.len(),
        });
    }
    if let Some((index, &value)) = y0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(InputError::Y0NonFinite { index, value });
    }
    if !(t0.is_finite() && t_bound.is_finite()) {
        return Err(InputError::TSpanNonFinite { t0, t_end: t_bound });
    }
    if t0 == t_bound {
        return Err(InputError::TSpanEmpty(t0));
    }
    Ok(())
}

/// `rtol` and `atol` per component, and whether some rtol was raised to `100 EPS`.
pub(crate) fn tolerances(
    opts: &SolverOptions,
    dim: usize,
) -> Result<(Vec<f64>, Vec<f64>, bool), InputError> {
    let mut rtol = expand_tol(&opts.rtol, "rtol", dim)?;
    let atol = expand_tol(&opts.atol, "atol", dim)?;
    // SciPy: rtol = max(rtol, 100 EPS) with a warning; we set a flag instead.
    let rtol_min = 100.0 * f64::EPSILON;
    let rtol_clamped = rtol.iter().any(|&r| r < rtol_min);
    if rtol_clamped {
        rtol.iter_mut().for_each(|r| *r = r.max(rtol_min));
    }
    Ok((rtol, atol, rtol_clamped))
}

/// `max_step`, `max_steps`, `first_step` (within the interval's length `span`) and the
/// controller's parameters.
pub(crate) fn check_step_options(opts: &SolverOptions, span: f64) -> Result<(), InputError> {
    if opts.max_step.is_nan() || opts.max_step <= 0.0 {
        return Err(InputError::MaxStep(opts.max_step));
    }
    if opts.max_steps == 0 {
        return Err(InputError::MaxSteps);
    }
    if let Some(h) = opts.first_step {
        if !(h > 0.0 && h.is_finite()) {
            return Err(InputError::FirstStepNotPositive(h));
        }
        if h > span {
            return Err(InputError::FirstStepBeyondSpan {
                first_step: h,
                span,
            });
        }
    }
    if let Controller::PI { alpha, beta } = opts.controller {
        if !(alpha.is_finite() && beta.is_finite() && alpha > 0.0 && beta >= 0.0) {
            return Err(InputError::Controller { alpha, beta });
        }
    }
    Ok(())
}

impl<S: OdeSystem> Stepper<S> {
    /// Validate the inputs and allocate all workspaces (no rhs call yet).
    /// `opts.dense` and `opts.t_eval` are driver options and ignored here.
    pub fn new(
        sys: S,
        t0: f64,
        y0: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
    ) -> Result<Self, InputError> {
        let dim = sys.dim();
        check_start(dim, y0, t0, t_bound)?;
        let (rtol, atol, rtol_clamped) = tolerances(opts, dim)?;
        check_step_options(opts, (t_bound - t0).abs())?;
        Ok(Self {
            sys,
            dim,
            t: t0,
            t_old: t0,
            t_bound,
            direction: if t_bound > t0 { 1.0 } else { -1.0 },
            y: y0.to_vec(),
            y_old: y0.to_vec(),
            f: vec![0.0; dim],
            k: vec![0.0; (N_STAGES + 1) * dim],
            y_stage: vec![0.0; dim],
            scaled_error: vec![0.0; dim],
            y_new: vec![0.0; dim],
            rtol,
            atol,
            rtol_clamped,
            max_step: opts.max_step,
            first_step: opts.first_step,
            max_steps: opts.max_steps,
            controller: opts.controller,
            err_prev: PI_ERR_FLOOR,
            h_abs: 0.0,
            nfev: 0,
            n_accepted: 0,
            n_rejected: 0,
            state: State::Uninitialised,
            stiffness_check: opts.stiffness,
            stiff_count: 0,
            nonstiff_count: 0,
            h_lambda: f64::NAN,
            stiffness: None,
            stop: None,
        })
    }

    /// Evaluate `f(t0, y0)` and choose the first step. Called by the first [`Stepper::step`];
    /// call it yourself to keep those rhs calls out of a timing.
    pub fn initialize(&mut self) -> Result<(), Status> {
        match &self.state {
            State::Uninitialised => {}
            State::Failed(s) => return Err(s.clone()),
            _ => return Ok(()),
        }
        let r = self.initialize_impl();
        match r {
            Ok(()) => self.state = State::Running,
            Err(ref s) => self.state = State::Failed(s.clone()),
        }
        r
    }

    fn initialize_impl(&mut self) -> Result<(), Status> {
        let t0 = self.t;
        call_rhs(&mut self.sys, &mut self.nfev, t0, t0, &self.y, &mut self.f)?;
        self.h_abs = match self.first_step {
            Some(h) => h,
            None => self.select_initial_step()?,
        };
        Ok(())
    }

    /// SciPy `select_initial_step` (Hairer, Nørsett & Wanner, Sec. II.4), order 4.
    fn select_initial_step(&mut self) -> Result<f64, Status> {
        let n = self.dim;
        select_initial_step(
            &mut self.sys,
            &mut self.nfev,
            Start {
                t0: self.t,
                y0: &self.y,
                f0: &self.f,
                t_bound: self.t_bound,
                direction: self.direction,
            },
            (&self.atol, &self.rtol),
            self.max_step,
            ERROR_ESTIMATOR_ORDER,
            (&mut self.y_new, &mut self.y_stage, &mut self.k[n..2 * n]),
        )
    }

    /// SciPy `rk_step`: the six stages, `y_new` and `k[6] = f(t + h, y_new)`.
    fn rk_stages(&mut self, t: f64, h: f64) -> Result<(), Status> {
        let n = self.dim;
        self.k[..n].copy_from_slice(&self.f);
        for s in 1..N_STAGES {
            // y_s = y + (K[:s]ᵀ a[:s]) h, summed stage by stage like np.dot.
            let (ys, y, k) = (&mut self.y_stage[..], &self.y[..], &self.k[..s * n]);
            match s {
                1 => combine(ys, y, k, &first::<1>(&A[1]), h),
                2 => combine(ys, y, k, &first::<2>(&A[2]), h),
                3 => combine(ys, y, k, &first::<3>(&A[3]), h),
                4 => combine(ys, y, k, &first::<4>(&A[4]), h),
                _ => combine(ys, y, k, &first::<5>(&A[5]), h),
            }
            check_state(&self.y_stage, t, t + C[s] * h)?;
            let ks = &mut self.k[s * n..(s + 1) * n];
            call_rhs(
                &mut self.sys,
                &mut self.nfev,
                t,
                t + C[s] * h,
                &self.y_stage,
                ks,
            )?;
        }
        // y_new = y + h (K[:6]ᵀ B)
        combine(&mut self.y_new, &self.y, &self.k[..N_STAGES * n], &B, h);
        check_state(&self.y_new, t, t + h)?;
        let last = &mut self.k[N_STAGES * n..];
        call_rhs(&mut self.sys, &mut self.nfev, t, t + h, &self.y_new, last)
    }

    /// RMS of `(Kᵀ E) h / scale`, `scale = atol + max(|y|, |y_new|) rtol`.
    fn error_norm(&mut self, h: f64) -> f64 {
        let n = self.dim;
        scaled_errors(
            &mut self.scaled_error,
            &self.k,
            (&self.y, &self.y_new),
            (&self.atol, &self.rtol),
            h,
        );
        // The sum in index order, as NumPy's norm takes it for these short vectors.
        let mut sq = 0.0;
        for r in &self.scaled_error[..n] {
            sq += r * r;
        }
        sq.sqrt() / (n as f64).sqrt()
    }

    fn accept_factor(&mut self, error_norm: f64) -> f64 {
        match self.controller {
            Controller::Standard => {
                if error_norm == 0.0 {
                    MAX_FACTOR
                } else {
                    MAX_FACTOR.min(SAFETY * error_norm.powf(ERROR_EXPONENT))
                }
            }
            Controller::PI { alpha, beta } => {
                let f = if error_norm == 0.0 {
                    MAX_FACTOR
                } else {
                    (SAFETY * error_norm.powf(-alpha) * self.err_prev.powf(beta))
                        .clamp(MIN_FACTOR, MAX_FACTOR)
                };
                self.err_prev = error_norm.max(PI_ERR_FLOOR);
                f
            }
        }
    }

    fn reject_factor(&self, error_norm: f64) -> f64 {
        let exponent = match self.controller {
            Controller::Standard => ERROR_EXPONENT,
            Controller::PI { alpha, .. } => -alpha,
        };
        // f64::max ignores NaN like Python's max(MIN_FACTOR, nan) here: a NaN norm shrinks by 5.
        MIN_FACTOR.max(SAFETY * error_norm.powf(exponent))
    }

    /// Hairer's stiffness test on the step just accepted (before projection): `h·|λ|` from the
    /// two stage states at `t + h` (`y_stage` holds stage 6, `y_new` stage 7) and their
    /// derivatives (`k[5]`, `k[6]`).
    fn stiffness_test(&mut self, h: f64, t_new: f64) {
        let n = self.dim;
        let (k6, k7) = (&self.k[5 * n..6 * n], &self.k[6 * n..7 * n]);
        let y6 = &self.y_stage;
        let y7 = &self.y_new;
        // Scaled sums, so that huge (but finite) states or derivatives cannot overflow.
        let (mut sk, mut sy) = (0.0f64, 0.0f64);
        for i in 0..n {
            sk = sk.max((k7[i] - k6[i]).abs());
            sy = sy.max((y7[i] - y6[i]).abs());
        }
        if !(sy > 0.0 && sy.is_finite() && sk.is_finite()) {
            // Identical stage states (or an overflowing difference): no information; Hairer
            // keeps the previous estimate.
            return;
        }
        let (mut num, mut den) = (0.0, 0.0);
        if sk > 0.0 {
            for i in 0..n {
                let dk = (k7[i] - k6[i]) / sk;
                let dy = (y7[i] - y6[i]) / sy;
                num += dk * dk;
                den += dy * dy;
            }
        } else {
            den = 1.0;
        }
        let h_lambda = h.abs() * (sk / sy) * (num / den).sqrt();
        if !h_lambda.is_finite() {
            return;
        }
        self.h_lambda = h_lambda;
        if h_lambda > STIFF_H_LAMBDA {
            self.nonstiff_count = 0;
            self.stiff_count += 1;
            if self.stiff_count == STIFF_STEPS && self.stiffness.is_none() {
                let s = Stiffness {
                    t: t_new,
                    h_lambda,
                    h: h.abs(),
                };
                self.stiffness = Some(s);
                if self.stiffness_check == StiffnessCheck::Stop {
                    self.stop = Some(Status::Stiff {
                        t: t_new,
                        h_lambda,
                        h: h.abs(),
                    });
                }
            }
        } else {
            self.nonstiff_count += 1;
            if self.nonstiff_count == NONSTIFF_RESET {
                self.stiff_count = 0;
            }
        }
    }

    /// Take one accepted step (retrying with smaller steps as needed), SciPy `_step_impl`.
    /// `Err` carries a failure status (StepTooSmall, MaxSteps, NonFinite, RhsError, and Stiff
    /// with [`StiffnessCheck::Stop`]: the step that completes a detection is accepted and
    /// returned, the next call fails); after it, every call returns the same error.
    pub fn step(&mut self) -> Result<StepOutcome, Status> {
        match &self.state {
            State::Uninitialised => self.initialize()?,
            State::Running => {
                if let Some(s) = self.stop.take() {
                    self.state = State::Failed(s.clone());
                    return Err(s);
                }
            }
            State::Finished => return Ok(StepOutcome::Finished),
            State::Failed(s) => return Err(s.clone()),
        }
        let r = self.step_impl();
        match &r {
            Ok(StepOutcome::Finished) => self.state = State::Finished,
            Ok(StepOutcome::Accepted) => {}
            Err(s) => self.state = State::Failed(s.clone()),
        }
        r
    }

    fn step_impl(&mut self) -> Result<StepOutcome, Status> {
        let t = self.t;
        if self.n_accepted >= self.max_steps {
            return Err(Status::MaxSteps {
                t,
                max_steps: self.max_steps,
            });
        }
        let dir = self.direction;
        let min_step = 10.0 * (next_toward(t, dir) - t).abs();
        let mut h_abs = if self.h_abs > self.max_step {
            self.max_step
        } else if self.h_abs < min_step {
            min_step
        } else {
            self.h_abs
        };
        let mut rejected = false;
        let t_new = loop {
            if h_abs < min_step {
                return Err(Status::StepTooSmall { t, min_step });
            }
            let mut t_new = t + h_abs * dir;
            if dir * (t_new - self.t_bound) > 0.0 {
                t_new = self.t_bound;
            }
            // The step actually taken (SciPy recomputes it even when not clipped).
            let h = t_new - t;
            h_abs = h.abs();
            self.rk_stages(t, h)?;
            let error_norm = self.error_norm(h);
            if error_norm < 1.0 {
                let mut factor = self.accept_factor(error_norm);
                if rejected {
                    factor = factor.min(1.0);
                }
                h_abs *= factor;
                break t_new;
            }
            h_abs *= self.reject_factor(error_norm);
            rejected = true;
            self.n_rejected += 1;
        };
        if self.stiffness_check != StiffnessCheck::Off {
            self.stiffness_test(t_new - t, t_new);
        }
        let moved = self
            .sys
            .project(&mut self.y_new)
            .map_err(|message| Status::RhsError {
                t,
                at: t_new,
                message,
            })?;
        check_state(&self.y_new, t, t_new)?;
        std::mem::swap(&mut self.y_old, &mut self.y);
        std::mem::swap(&mut self.y, &mut self.y_new);
        if moved {
            // The projected state's own derivative starts the next step (FSAL's is the
            // unprojected one); the interpolant keeps the step's stages.
            call_rhs(
                &mut self.sys,
                &mut self.nfev,
                t,
                t_new,
                &self.y,
                &mut self.f,
            )?;
        } else {
            self.f.copy_from_slice(&self.k[N_STAGES * self.dim..]);
        }
        self.t_old = t;
        self.t = t_new;
        self.h_abs = h_abs;
        self.n_accepted += 1;
        if dir * (self.t - self.t_bound) >= 0.0 {
            Ok(StepOutcome::Finished)
        } else {
            Ok(StepOutcome::Accepted)
        }
    }

    /// Interpolant coefficients `Q = Kᵀ P` (`4 · dim`, `q[4 i + j]`) of the last accepted step,
    /// for [`dense::eval_segment`]`(t_old(), t() - t_old(), y_old(), q, t, out)`.
    /// Returns false (leaving `q` untouched) before the first step.
    pub fn fill_dense_q(&self, q: &mut [f64]) -> bool {
        if self.n_accepted == 0 {
            return false;
        }
        dense::fill_q(&self.k, self.dim, q);
        true
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t
    }
    /// Start of the last accepted step (t0 before any step).
    pub fn t_old(&self) -> f64 {
        self.t_old
    }
    pub fn t_bound(&self) -> f64 {
        self.t_bound
    }
    /// +1 forward, -1 backward.
    pub fn direction(&self) -> f64 {
        self.direction
    }
    /// Current state.
    pub fn y(&self) -> &[f64] {
        &self.y
    }
    /// State at `t_old()`.
    pub fn y_old(&self) -> &[f64] {
        &self.y_old
    }
    /// `f(t, y)` (valid once initialised).
    pub fn f(&self) -> &[f64] {
        &self.f
    }
    pub fn dim(&self) -> usize {
        self.dim
    }
    /// Size of the next step to try.
    pub fn h_next(&self) -> f64 {
        self.h_abs
    }
    /// |t - t_old|, the last accepted step size.
    pub fn step_size(&self) -> f64 {
        (self.t - self.t_old).abs()
    }
    pub fn nfev(&self) -> usize {
        self.nfev
    }
    pub fn n_accepted(&self) -> usize {
        self.n_accepted
    }
    pub fn n_rejected(&self) -> usize {
        self.n_rejected
    }
    pub fn rtol_clamped(&self) -> bool {
        self.rtol_clamped
    }
    /// First stiffness detection, if any (see [`StiffnessCheck`]).
    pub fn stiffness(&self) -> Option<Stiffness> {
        self.stiffness
    }
    /// Hairer's `h·|λ|` estimate on the last accepted step (NaN before it or with the check off).
    pub fn h_lambda(&self) -> f64 {
        self.h_lambda
    }
    pub fn is_finished(&self) -> bool {
        self.state == State::Finished
    }
    /// The failure status, if the stepper failed.
    pub fn failure(&self) -> Option<&Status> {
        match &self.state {
            State::Failed(s) => Some(s),
            _ => None,
        }
    }
    pub fn system(&self) -> &S {
        &self.sys
    }
    pub fn system_mut(&mut self) -> &mut S {
        &mut self.sys
    }
    pub fn into_system(self) -> S {
        self.sys
    }
}

impl<S: OdeSystem> Integrator for Stepper<S> {
    type System = S;
    #[inline]
    fn step(&mut self) -> Result<StepOutcome, Status> {
        Stepper::step(self)
    }
    fn dim(&self) -> usize {
        self.dim
    }
    fn t(&self) -> f64 {
        self.t
    }
    fn t_old(&self) -> f64 {
        self.t_old
    }
    fn t_bound(&self) -> f64 {
        self.t_bound
    }
    fn direction(&self) -> f64 {
        self.direction
    }
    fn y(&self) -> &[f64] {
        &self.y
    }
    fn y_old(&self) -> &[f64] {
        &self.y_old
    }
    fn counts(&self) -> Counts {
        Counts {
            nfev: self.nfev,
            njev: 0,
            nlu: 0,
            n_accepted: self.n_accepted,
            n_rejected: self.n_rejected,
        }
    }
    fn stiffness(&self) -> Option<Stiffness> {
        self.stiffness
    }
    fn rtol_clamped(&self) -> bool {
        self.rtol_clamped
    }
    fn h_next(&self) -> f64 {
        self.h_abs
    }
    fn interpolant(&self) -> dense::Interpolant {
        dense::Interpolant::Rk45
    }
    fn dense_coefficients(&mut self, q: &mut [f64]) -> Result<(), Status> {
        self.fill_dense_q(q);
        Ok(())
    }
    fn system_mut(&mut self) -> &mut S {
        &mut self.sys
    }
    fn into_system(self) -> S {
        self.sys
    }
}

#[cfg(test)]
#[path = "tests/stepper.rs"]
mod tests;
