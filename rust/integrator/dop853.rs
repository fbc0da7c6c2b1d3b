//! Dormand–Prince 8(5,3), a line-by-line port of SciPy's `DOP853` (scipy/integrate/_ivp/rk.py):
//! 12 stages, the solution propagated with the 8th-order weights, the error estimate of
//! Hairer's DOP853 (5th- and 3rd-order embedded estimates combined), SciPy's step control and
//! initial step (error estimator order 7), and the 7th-order dense output from three extra
//! stages, evaluated only when asked for (and then counted in `nfev`, as SciPy does).
//! Arithmetic in NumPy's order, so accept/reject decisions and counts match SciPy's.

use super::dense::Interpolant;
use super::dop853_tableau::{A, B, C, D, E3, E5, INTERPOLATOR_POWER, N_STAGES, N_STAGES_EXTENDED};
use super::method::{Counts, Integrator};
use super::stepper::{
    call_rhs, check_start, check_state, check_step_options, combine, next_toward,
    select_initial_step, tolerances, Start, State, MAX_FACTOR, MIN_FACTOR, SAFETY,
};
use super::{Controller, InputError, OdeSystem, SolverOptions, Status, StepOutcome};

/// SciPy's `DOP853.error_estimator_order`.
const ERROR_ESTIMATOR_ORDER: u32 = 7;
/// -1 / (error_estimator_order + 1).
const ERROR_EXPONENT: f64 = -1.0 / 8.0;

/// The first `S` entries of row `s` of the tableau.
#[inline(always)]
fn row<const S: usize>(s: usize) -> [f64; S] {
    std::array::from_fn(|j| A[s][j])
}

/// Adaptive DOP853 usable one step at a time (SciPy's `DOP853` solver object). All buffers
/// are allocated in [`Dop853::new`]; `step` allocates nothing.
pub struct Dop853<S: OdeSystem> {
    sys: S,
    dim: usize,
    t: f64,
    t_old: f64,
    t_bound: f64,
    direction: f64,
    y: Vec<f64>,
    y_old: Vec<f64>,
    /// f(t, y).
    f: Vec<f64>,
    /// Stage derivatives, 16 rows of `dim`: 12 stages, row 12 = f(t_new, y_new), rows 13..16
    /// the dense output's extra stages.
    k: Vec<f64>,
    y_stage: Vec<f64>,
    y_new: Vec<f64>,
    rtol: Vec<f64>,
    atol: Vec<f64>,
    rtol_clamped: bool,
    max_step: f64,
    first_step: Option<f64>,
    max_steps: usize,
    h_abs: f64,
    nfev: usize,
    n_accepted: usize,
    n_rejected: usize,
    state: State,
}

impl<S: OdeSystem> Dop853<S> {
    /// Validate the inputs and allocate all workspaces (no rhs call yet). Only SciPy's
    /// controller exists for DOP853.
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
        if opts.controller != Controller::Standard {
            return Err(InputError::ControllerUnsupported { method: "DOP853" });
        }
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
            k: vec![0.0; N_STAGES_EXTENDED * dim],
            y_stage: vec![0.0; dim],
            y_new: vec![0.0; dim],
            rtol,
            atol,
            rtol_clamped,
            max_step: opts.max_step,
            first_step: opts.first_step,
            max_steps: opts.max_steps,
            h_abs: 0.0,
            nfev: 0,
            n_accepted: 0,
            n_rejected: 0,
            state: State::Uninitialised,
        })
    }

    /// `f(t0, y0)` and the first step (SciPy's `select_initial_step`, order 7).
    fn initialize(&mut self) -> Result<(), Status> {
        let t0 = self.t;
        call_rhs(&mut self.sys, &mut self.nfev, t0, t0, &self.y, &mut self.f)?;
        let n = self.dim;
        self.h_abs = match self.first_step {
            Some(h) => h,
            None => select_initial_step(
                &mut self.sys,
                &mut self.nfev,
                Start {
                    t0,
                    y0: &self.y,
                    f0: &self.f,
                    t_bound: self.t_bound,
                    direction: self.direction,
                },
                (&self.atol, &self.rtol),
                self.max_step,
                ERROR_ESTIMATOR_ORDER,
                (&mut self.y_new, &mut self.y_stage, &mut self.k[n..2 * n]),
            )?,
        };
        Ok(())
    }

    /// Stage `s` (1..16) from `base` at `t_base`: `y_stage = base + (K[:s]ᵀ A[s, :s]) h`,
    /// then `K[s] = f(t_base + C[s] h, y_stage)`.
    fn stage(&mut self, s: usize, from_old: bool, t_reached: f64, h: f64) -> Result<(), Status> {
        let n = self.dim;
        let (ys, k) = (&mut self.y_stage[..], &self.k[..s * n]);
        let (base, t_base) = if from_old {
            (&self.y_old[..], self.t_old)
        } else {
            (&self.y[..], self.t)
        };
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
        let at = t_base + C[s] * h;
        check_state(&self.y_stage, t_reached, at)?;
        let ks = &mut self.k[s * n..(s + 1) * n];
        call_rhs(
            &mut self.sys,
            &mut self.nfev,
            t_reached,
            at,
            &self.y_stage,
            ks,
        )
    }

    /// SciPy `rk_step`: the 12 stages, `y_new` and `K[12] = f(t + h, y_new)`.
    fn rk_stages(&mut self, t: f64, h: f64) -> Result<(), Status> {
        let n = self.dim;
        self.k[..n].copy_from_slice(&self.f);
        for s in 1..N_STAGES {
            self.stage(s, false, t, h)?;
        }
        combine(&mut self.y_new, &self.y, &self.k[..N_STAGES * n], &B, h);
        check_state(&self.y_new, t, t + h)?;
        let last = &mut self.k[N_STAGES * n..(N_STAGES + 1) * n];
        call_rhs(&mut self.sys, &mut self.nfev, t, t + h, &self.y_new, last)
    }

    /// SciPy `DOP853._estimate_error_norm`: `|h| ‖e5‖² / sqrt((‖e5‖² + 0.01 ‖e3‖²) n)` with
    /// `e = (Kᵀ E) / scale`, `scale = atol + max(|y|, |y_new|) rtol`.
    fn error_norm(&self, h: f64) -> f64 {
        let n = self.dim;
        let k = &self.k;
        let (mut s5, mut s3) = (0.0f64, 0.0f64);
        for i in 0..n {
            let (mut e5, mut e3) = (k[i] * E5[0], k[i] * E3[0]);
            for s in 1..N_STAGES + 1 {
                e5 += k[s * n + i] * E5[s];
                e3 += k[s * n + i] * E3[s];
            }
            let (a, b) = (self.y[i].abs(), self.y_new[i].abs());
            let scale = self.atol[i] + if a >= b { a } else { b } * self.rtol[i];
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
            let h = t_new - t;
            h_abs = h.abs();
            self.rk_stages(t, h)?;
            let error_norm = self.error_norm(h);
            if error_norm < 1.0 {
                let mut factor = if error_norm == 0.0 {
                    MAX_FACTOR
                } else {
                    MAX_FACTOR.min(SAFETY * error_norm.powf(ERROR_EXPONENT))
                };
                if rejected {
                    factor = factor.min(1.0);
                }
                h_abs *= factor;
                break t_new;
            }
            h_abs *= MIN_FACTOR.max(SAFETY * error_norm.powf(ERROR_EXPONENT));
            rejected = true;
            self.n_rejected += 1;
        };
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
        let n = self.dim;
        if moved {
            call_rhs(
                &mut self.sys,
                &mut self.nfev,
                t,
                t_new,
                &self.y,
                &mut self.f,
            )?;
        } else {
            self.f
                .copy_from_slice(&self.k[N_STAGES * n..(N_STAGES + 1) * n]);
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

    /// SciPy `DOP853._dense_output_impl`: three more stages (13..16) from `y_old`, then
    /// `F = [Δ, h f_old − Δ, 2Δ − h (f + f_old), h D K]`, `Δ = y − y_old`, into
    /// `q[7 i + j] = F[j][i]`.
    fn dense_impl(&mut self, q: &mut [f64]) -> Result<(), Status> {
        let (n, h, t) = (self.dim, self.t - self.t_old, self.t);
        for s in N_STAGES + 1..N_STAGES_EXTENDED {
            self.stage(s, true, t, h)?;
        }
        let k = &self.k;
        for i in 0..n {
            let delta = self.y[i] - self.y_old[i];
            let f_old = k[i];
            let qi = &mut q[INTERPOLATOR_POWER * i..INTERPOLATOR_POWER * (i + 1)];
            qi[0] = delta;
            qi[1] = h * f_old - delta;
            qi[2] = 2.0 * delta - h * (self.f[i] + f_old);
            for (j, d) in D.iter().enumerate() {
                let mut acc = d[0] * k[i];
                for s in 1..N_STAGES_EXTENDED {
                    acc += d[s] * k[s * n + i];
                }
                qi[3 + j] = h * acc;
            }
        }
        Ok(())
    }

    pub fn nfev(&self) -> usize {
        self.nfev
    }
    pub fn n_accepted(&self) -> usize {
        self.n_accepted
    }
}

impl<S: OdeSystem> Integrator for Dop853<S> {
    type System = S;

    /// One accepted step (SciPy `_step_impl`); after a failure every call returns it again.
    fn step(&mut self) -> Result<StepOutcome, Status> {
        match &self.state {
            State::Uninitialised => {
                if let Err(s) = self.initialize() {
                    self.state = State::Failed(s.clone());
                    return Err(s);
                }
                self.state = State::Running;
            }
            State::Running => {}
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
    fn rtol_clamped(&self) -> bool {
        self.rtol_clamped
    }
    fn h_next(&self) -> f64 {
        self.h_abs
    }
    fn interpolant(&self) -> Interpolant {
        Interpolant::Dop853
    }
    fn dense_coefficients(&mut self, q: &mut [f64]) -> Result<(), Status> {
        let r = self.dense_impl(q);
        if let Err(s) = &r {
            self.state = State::Failed(s.clone());
        }
        r
    }
    fn system_mut(&mut self) -> &mut S {
        &mut self.sys
    }
    fn into_system(self) -> S {
        self.sys
    }
}
