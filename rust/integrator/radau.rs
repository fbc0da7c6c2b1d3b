//! Radau IIA of order 5, the implicit method for stiff problems: a port of SciPy's
//! `solve_ivp(method="Radau")` (scipy/integrate/_ivp/radau.py; Hairer & Wanner, *Solving
//! ODEs II*, IV.8), decision for decision.
//!
//! * Three-stage collocation at `c = ((4 − √6)/10, (4 + √6)/10, 1)`. The stage increments
//!   `Z` solve `Z = h (A ⊗ I) F(y + Z)`; with `A⁻¹ = T Λ T⁻¹` (one real eigenvalue `μ`, one
//!   complex pair `α ± iβ`) simplified Newton needs one real and one complex `n × n` LU:
//!   `μ/h I − J` and `(α + iβ)/h I − J`, with `J` a Jacobian at some earlier point.
//! * Newton: at most [`NEWTON_MAXITER`] iterations, stopped early when the contraction rate
//!   predicts it cannot reach `newton_tol = max(10 EPS/rtol, min(0.03, √rtol))`; converged
//!   when `rate/(1 − rate) ‖ΔW‖ < newton_tol`. A failure first re-evaluates `J` (if it is not
//!   current), then halves the step.
//! * Error: the embedded third-order estimate `(μ/h I − J)⁻¹ (f + Zᵀ e / h)`, once more
//!   filtered through the LU with `f(y + err)` after a rejection (Hairer's stiff-robust
//!   estimate, as SciPy applies it).
//! * Step size: Gustafsson's predictive controller with safety `0.9 (2 N + 1)/(2 N + iters)`;
//!   `J` is re-evaluated after a step that needed more than 2 slowly converging iterations; the
//!   LUs are kept while the step size changes by less than a factor 1.2.
//! * Dense output: the collocation cubic `y_old + Q (x, x², x³)`, `x = (t − t_old)/h`,
//!   `Q = Zᵀ P`; it also predicts the next step's `Z`.
//!
//! The Jacobian is the system's [`OdeSystem::jacobian`] when it provides one (returns `true`),
//! a given constant matrix, or SciPy's finite differences ([`super::num_jac`]).
//! `nfev` counts right-hand-side calls as SciPy does (not those of finite-difference Jacobians:
//! [`Radau::jac_evaluations`]); `njev` Jacobians, `nlu` LU factorisations.
//!
//! Deviations from SciPy, all on paths where SciPy would carry NaN/inf along: a non-finite
//! stage state or a singular Newton matrix counts as a Newton failure without calling the
//! right-hand side on it; a NaN error norm rejects the step (SciPy would accept it); a
//! non-finite derivative at an accepted state or in a Jacobian ends the run with
//! [`Status::NonFinite`]. Per-component `rtol` (which SciPy's Radau does not accept) sets
//! `newton_tol` from its smallest entry.
// Index loops over parallel arrays read as SciPy's formulas; T and TI are SciPy's digits verbatim.
#![allow(clippy::needless_range_loop, clippy::excessive_precision)]

use std::ops::Deref;

use nalgebra::Complex;

use super::common::{
    self, check_start, check_state, check_step_options, rms_norm as rms, step_state_accessors,
    tolerances, Lifecycle, StepState, Stepping,
};
use super::dense::Interpolant;
use super::method::{Counts, Integrator};
use super::num_jac::NumJac;
use super::radau_tableau::{mu_complex, mu_real, C, E, P, T, TI};
use super::{
    Controller, InputError, NonFiniteKind, OdeSystem, SolverOptions, Status, StepOutcome, Tol,
};
use crate::linalg::lu::Lu;

/// Maximum number of simplified Newton iterations per attempt.
pub const NEWTON_MAXITER: usize = 6;
const MIN_FACTOR: f64 = 0.2;
const MAX_FACTOR: f64 = 10.0;

/// Where the Jacobian `∂f/∂y` comes from.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum JacobianSource {
    /// The system's [`OdeSystem::jacobian`] if it fills one at `(t0, y0)`, else finite
    /// differences (SciPy `jac=None`).
    #[default]
    Auto,
    /// Finite differences even if the system has an analytic Jacobian.
    FiniteDifference,
    /// A constant matrix, row-major `dim × dim` (SciPy `jac=array`): never re-evaluated.
    Constant(Vec<f64>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum JacMode {
    Analytic,
    FiniteDifference,
    Constant,
}

/// Radau IIA (order 5) usable one step at a time (SciPy's `Radau` solver object).
///
/// Buffers are allocated in [`Radau::new`]; [`Radau::step`] allocates nothing. The first
/// `step` (or [`Radau::initialize`]) evaluates `f(t0, y0)`, one more rhs for the initial step
/// (without `first_step`) and the first Jacobian.
pub struct Radau<S: OdeSystem> {
    sys: S,
    st: StepState,
    newton_tol: f64,
    /// SciPy's `h_abs_old` / `error_norm_old` (the controller's memory).
    h_abs_old: Option<f64>,
    error_norm_old: Option<f64>,
    /// The Jacobian, row-major `dim × dim`.
    jac: Vec<f64>,
    jac_source: JacobianSource,
    jac_mode: JacMode,
    num_jac: NumJac,
    /// `jac` was evaluated at the current state (a Newton failure then halves the step).
    current_jac: bool,
    lu_real: Lu<f64>,
    lu_complex: Lu<Complex<f64>>,
    mu_real: f64,
    mu_complex: Complex<f64>,
    /// Stage increments (3 rows of `dim`) and their Newton workspaces.
    z: Vec<f64>,
    z0: Vec<f64>,
    w: Vec<f64>,
    dw: Vec<f64>,
    stage_f: Vec<f64>,
    y_stage: Vec<f64>,
    scale: Vec<f64>,
    rhs_real: Vec<f64>,
    rhs_complex: Vec<Complex<f64>>,
    ze: Vec<f64>,
    err: Vec<f64>,
    /// Dense coefficients of the last accepted step, `q[3 i + j]`.
    q: Vec<f64>,
    njev: usize,
    nlu: usize,
    n_newton_failures: usize,
    /// Why the step size fell: the last attempt of a failed step was a Newton failure.
    last_attempt_newton_failure: bool,
    /// That failure's cause: a stage derivative that was not finite (its time), or a
    /// singular Newton matrix; neither: the corrections did not contract.
    newton_nonfinite_at: Option<f64>,
    newton_singular: bool,
}

/// SciPy `predict_factor` (Gustafsson's predictive controller, Hairer & Wanner IV.8).
fn predict_factor(
    h_abs: f64,
    h_abs_old: Option<f64>,
    error_norm: f64,
    error_norm_old: Option<f64>,
) -> f64 {
    let multiplier = match (h_abs_old, error_norm_old) {
        (Some(h_old), Some(e_old)) if error_norm != 0.0 => {
            h_abs / h_old * (e_old / error_norm).powf(0.25)
        }
        _ => 1.0,
    };
    // Python's min(1, nan) is 1, like f64::min.
    1f64.min(multiplier) * error_norm.powf(-0.25)
}

impl<S: OdeSystem> Radau<S> {
    /// Validate the inputs and allocate all workspaces (no rhs call yet), with the system's
    /// Jacobian or finite differences ([`JacobianSource::Auto`]). Of `opts`, `rtol`, `atol`,
    /// `first_step`, `max_step` and `max_steps` apply (`dense`, `t_eval` are the driver's).
    pub fn new(
        sys: S,
        t0: f64,
        y0: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
    ) -> Result<Self, InputError> {
        Self::with_jacobian(sys, t0, y0, t_bound, opts, JacobianSource::Auto)
    }

    /// As [`Radau::new`] with the Jacobian from `jacobian`.
    pub fn with_jacobian(
        sys: S,
        t0: f64,
        y0: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
        jacobian: JacobianSource,
    ) -> Result<Self, InputError> {
        let dim = sys.dim();
        check_start(dim, y0, t0, t_bound)?;
        check_step_options(opts, (t_bound - t0).abs())?;
        if opts.controller != Controller::Standard {
            return Err(InputError::ControllerUnsupported { method: "Radau" });
        }
        let tols = tolerances(opts, dim)?;
        check_atol_positive(&tols.1, "Radau")?;
        if let JacobianSource::Constant(m) = &jacobian {
            if m.len() != dim * dim {
                return Err(InputError::JacobianShape {
                    expected: dim,
                    got: m.len(),
                });
            }
            if let Some((index, &value)) = m.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(InputError::JacobianNonFinite { index, value });
            }
        }
        let newton_tol = newton_tolerance(&opts.rtol);
        let v = || vec![0.0; dim];
        let v3 = || vec![0.0; 3 * dim];
        Ok(Self {
            sys,
            st: StepState::new(t0, y0, t_bound, opts, tols),
            newton_tol,
            h_abs_old: None,
            error_norm_old: None,
            jac: vec![0.0; dim * dim],
            jac_source: jacobian,
            jac_mode: JacMode::FiniteDifference,
            num_jac: NumJac::new(dim),
            current_jac: true,
            lu_real: Lu::new(dim),
            lu_complex: Lu::new(dim),
            mu_real: mu_real(),
            mu_complex: mu_complex(),
            z: v3(),
            z0: v3(),
            w: v3(),
            dw: v3(),
            stage_f: v3(),
            y_stage: v(),
            scale: v(),
            rhs_real: v(),
            rhs_complex: vec![Complex::new(0.0, 0.0); dim],
            ze: v(),
            err: v(),
            q: v3(),
            njev: 0,
            nlu: 0,
            n_newton_failures: 0,
            last_attempt_newton_failure: false,
            newton_nonfinite_at: None,
            newton_singular: false,
        })
    }

    /// Evaluate `f(t0, y0)`, choose the first step and evaluate the first Jacobian. Called by
    /// the first [`Radau::step`].
    pub fn initialize(&mut self) -> Result<(), Status> {
        common::initialize(self)
    }

    /// Take one accepted step (retrying with smaller steps as needed), SciPy `_step_impl`.
    /// `Err` carries a failure status; after it, every call returns the same error.
    pub fn step(&mut self) -> Result<StepOutcome, Status> {
        common::step(self)
    }

    /// `f(t0, y0)`, the first step (SciPy's `select_initial_step` with the error estimator's
    /// order 3) and the first Jacobian.
    fn start(&mut self) -> Result<(), Status> {
        let t0 = self.st.t;
        self.st.rhs_here(&mut self.sys)?;
        self.st.h_abs = match self.st.first_step {
            Some(h) => h,
            None => {
                let scratch = (
                    &mut self.scale[..],
                    &mut self.y_stage[..],
                    &mut self.err[..],
                );
                self.st.initial_step(&mut self.sys, 3, scratch)?
            }
        };
        match std::mem::take(&mut self.jac_source) {
            JacobianSource::Constant(m) => {
                self.jac.copy_from_slice(&m);
                self.jac_mode = JacMode::Constant;
            }
            JacobianSource::FiniteDifference => {
                self.jac_mode = JacMode::FiniteDifference;
                self.update_jacobian()?;
            }
            JacobianSource::Auto => {
                // The system decides once, at (t0, y0), whether it has an analytic Jacobian.
                self.jac_mode = JacMode::Analytic;
                let has = self
                    .sys
                    .jacobian(t0, &self.st.y, &mut self.jac)
                    .map_err(|m| jacobian_error(t0, m))?;
                if has {
                    self.njev += 1;
                    self.sys.chain_projection(&self.st.y, &mut self.jac);
                    self.check_jacobian()?;
                } else {
                    self.jac_mode = JacMode::FiniteDifference;
                    self.update_jacobian()?;
                }
            }
        }
        self.current_jac = true;
        Ok(())
    }

    /// A fresh Jacobian at the current state `(t, y)`, `f = f(t, y)`.
    fn update_jacobian(&mut self) -> Result<(), Status> {
        let t = self.st.t;
        self.njev += 1;
        match self.jac_mode {
            JacMode::Analytic => {
                let filled = self
                    .sys
                    .jacobian(t, &self.st.y, &mut self.jac)
                    .map_err(|m| jacobian_error(t, m))?;
                if filled {
                    self.sys.chain_projection(&self.st.y, &mut self.jac);
                    return self.check_jacobian();
                }
                // Not provided here (though it was at t0): differences this time.
                self.num_jac.compute(
                    &mut self.sys,
                    t,
                    &self.st.y,
                    &self.st.f,
                    &self.st.atol,
                    &mut self.jac,
                )
            }
            JacMode::FiniteDifference => self.num_jac.compute(
                &mut self.sys,
                t,
                &self.st.y,
                &self.st.f,
                &self.st.atol,
                &mut self.jac,
            ),
            JacMode::Constant => Ok(()),
        }
    }

    fn check_jacobian(&self) -> Result<(), Status> {
        if self.jac.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(Status::NonFinite {
                t: self.st.t,
                at: self.st.t,
                what: NonFiniteKind::Jacobian,
            })
        }
    }

    /// Factorise `μ/h I − J` and `(α + iβ)/h I − J` (SciPy counts both in `nlu`).
    /// False if either is singular (or not finite).
    fn factor_newton_matrices(&mut self, h: f64) -> bool {
        let n = self.st.dim;
        let mr = self.mu_real / h;
        let mc = Complex::new(self.mu_complex.re / h, self.mu_complex.im / h);
        {
            let a = self.lu_real.matrix_mut();
            for i in 0..n {
                for j in 0..n {
                    let d = if i == j { mr } else { 0.0 };
                    a[i * n + j] = d - self.jac[i * n + j];
                }
            }
        }
        {
            let a = self.lu_complex.matrix_mut();
            for i in 0..n {
                for j in 0..n {
                    let d = if i == j { mc } else { Complex::new(0.0, 0.0) };
                    a[i * n + j] = d - Complex::new(self.jac[i * n + j], 0.0);
                }
            }
        }
        self.nlu += 2;
        let ok_real = self.lu_real.factor();
        let ok_complex = self.lu_complex.factor();
        ok_real && ok_complex
    }

    /// SciPy `solve_collocation_system` from the guess `z0`, into `z`. Returns (converged,
    /// iterations, last contraction rate or NaN).
    fn solve_collocation_system(&mut self, t: f64, h: f64) -> Result<(bool, usize, f64), Status> {
        let n = self.st.dim;
        let m_real = self.mu_real / h;
        let m_complex = Complex::new(self.mu_complex.re / h, self.mu_complex.im / h);
        let ch = [h * C[0], h * C[1], h * C[2]];
        // W = TI Z0, Z = Z0.
        for i in 0..n {
            let (a, b, c) = (self.z0[i], self.z0[n + i], self.z0[2 * n + i]);
            for r in 0..3 {
                self.w[r * n + i] = TI[r][0] * a + TI[r][1] * b + TI[r][2] * c;
            }
        }
        self.z.copy_from_slice(&self.z0);
        let mut dw_norm_old: Option<f64> = None;
        let mut rate: Option<f64> = None;
        let mut converged = false;
        let mut n_iter = 0;
        let tol = self.newton_tol;
        'newton: for k in 0..NEWTON_MAXITER {
            n_iter = k + 1;
            let mut finite = true;
            for s in 0..3 {
                for i in 0..n {
                    self.y_stage[i] = self.st.y[i] + self.z[s * n + i];
                }
                if !self.y_stage.iter().all(|v| v.is_finite()) {
                    // Diverged: nothing to evaluate (SciPy would call f on NaN/inf).
                    break 'newton;
                }
                let at = t + ch[s];
                self.st.nfev += 1;
                let fs = &mut self.stage_f[s * n..(s + 1) * n];
                self.sys
                    .rhs(at, &self.y_stage, fs)
                    .map_err(|message| Status::RhsError {
                        t: self.st.t,
                        at,
                        message,
                    })?;
                if !fs.iter().all(|v| v.is_finite()) {
                    finite = false;
                    self.newton_nonfinite_at = Some(at);
                }
            }
            if !finite {
                break;
            }
            let f = &self.stage_f;
            for i in 0..n {
                let (f0, f1, f2) = (f[i], f[n + i], f[2 * n + i]);
                self.rhs_real[i] =
                    (f0 * TI[0][0] + f1 * TI[0][1] + f2 * TI[0][2]) - m_real * self.w[i];
                // F·TI_COMPLEX with TI_COMPLEX = TI[1] + i TI[2].
                let fc = Complex::new(
                    f0 * TI[1][0] + f1 * TI[1][1] + f2 * TI[1][2],
                    f0 * TI[2][0] + f1 * TI[2][1] + f2 * TI[2][2],
                );
                self.rhs_complex[i] =
                    fc - m_complex * Complex::new(self.w[n + i], self.w[2 * n + i]);
            }
            self.lu_real.solve(&mut self.rhs_real);
            self.lu_complex.solve(&mut self.rhs_complex);
            for i in 0..n {
                self.dw[i] = self.rhs_real[i];
                self.dw[n + i] = self.rhs_complex[i].re;
                self.dw[2 * n + i] = self.rhs_complex[i].im;
            }
            let scale = &self.scale;
            let dw_norm = rms((0..3 * n).map(|k| self.dw[k] / scale[k % n]), 3 * n);
            if let Some(old) = dw_norm_old {
                rate = Some(dw_norm / old);
            }
            if let Some(r) = rate {
                if r >= 1.0 || r.powf((NEWTON_MAXITER - k) as f64) / (1.0 - r) * dw_norm > tol {
                    break;
                }
            }
            for k in 0..3 * n {
                self.w[k] += self.dw[k];
            }
            for i in 0..n {
                let (a, b, c) = (self.w[i], self.w[n + i], self.w[2 * n + i]);
                for r in 0..3 {
                    self.z[r * n + i] = T[r][0] * a + T[r][1] * b + T[r][2] * c;
                }
            }
            if dw_norm == 0.0 || rate.is_some_and(|r| r / (1.0 - r) * dw_norm < tol) {
                converged = true;
                break;
            }
            dw_norm_old = Some(dw_norm);
        }
        Ok((converged, n_iter, rate.unwrap_or(f64::NAN)))
    }

    /// `Z0`: the previous step's collocation polynomial at `t + h c` minus `y` (zero before
    /// the first step).
    fn predict_z0(&mut self, t: f64, h: f64) {
        let n = self.st.dim;
        if self.st.n_accepted == 0 {
            self.z0.fill(0.0);
            return;
        }
        let h_old = self.st.t - self.st.t_old;
        for s in 0..3 {
            let x = ((t + h * C[s]) - self.st.t_old) / h_old;
            let (p1, p2) = (x, x * x);
            let p3 = p2 * x;
            for i in 0..n {
                let q = &self.q[3 * i..3 * i + 3];
                let sol = (q[0] * p1 + q[1] * p2 + q[2] * p3) + self.st.y_old[i];
                self.z0[s * n + i] = sol - self.st.y[i];
            }
        }
    }

    /// SciPy `_step_impl`: attempts until one converges and passes the error test, then the
    /// controller's next step and the Jacobian/LU reuse decisions.
    fn advance_impl(&mut self) -> Result<StepOutcome, Status> {
        let (mut h_abs, min_step, clipped) = self.st.step_bounds()?;
        let t = self.st.t;
        // A clipped step forgets the controller's memory (SciPy's h_abs_old = None).
        let memory = if clipped {
            (None, None)
        } else {
            (self.h_abs_old, self.error_norm_old)
        };
        let mut current_jac = self.current_jac;
        let mut rejected = false;
        let (t_new, error_norm, n_iter, rate) = loop {
            if h_abs < min_step {
                return Err(self.too_small(t, min_step));
            }
            let (t_new, h) = self.st.attempt(h_abs);
            h_abs = h.abs();
            self.predict_z0(t, h);
            self.newton_nonfinite_at = None;
            self.newton_singular = false;
            let (converged, n_iter, rate) = self.newton(t, h, &mut current_jac)?;
            self.last_attempt_newton_failure = !converged;
            if !converged {
                h_abs *= 0.5;
                self.invalidate_lu();
                self.n_newton_failures += 1;
                continue;
            }
            let mut error_norm = self.error_norm(h);
            if rejected && error_norm > 1.0 {
                error_norm = self.filtered_error_norm(t)?;
            }
            // Written so that a NaN norm rejects.
            #[allow(clippy::neg_cmp_op_on_partial_ord)]
            if !(error_norm <= 1.0) {
                let factor = predict_factor(h_abs, memory.0, error_norm, memory.1);
                h_abs *= MIN_FACTOR.max(safety(n_iter) * factor);
                self.invalidate_lu();
                rejected = true;
                self.st.n_rejected += 1;
                continue;
            }
            break (t_new, error_norm, n_iter, rate);
        };
        let recompute_jac = self.jac_mode != JacMode::Constant && n_iter > 2 && rate > 1e-3;
        let mut factor = predict_factor(h_abs, memory.0, error_norm, memory.1);
        factor = MAX_FACTOR.min(safety(n_iter) * factor);
        if !recompute_jac && factor < 1.2 {
            factor = 1.0;
        } else {
            self.invalidate_lu();
        }
        self.accept(t_new)?;
        if recompute_jac {
            self.update_jacobian()?;
            current_jac = true;
        } else if self.jac_mode != JacMode::Constant {
            current_jac = false;
        }
        self.h_abs_old = Some(self.st.h_abs);
        self.error_norm_old = Some(error_norm);
        self.st.h_abs = h_abs * factor;
        self.current_jac = current_jac;
        self.fill_q();
        self.st.n_accepted += 1;
        Ok(self.st.outcome())
    }

    /// The failure when the step size fell below `min_step`: named after Newton when its
    /// failures drove the step down (a non-finite stage derivative as such).
    fn too_small(&self, t: f64, min_step: f64) -> Status {
        if !self.last_attempt_newton_failure {
            return Status::StepTooSmall { t, min_step };
        }
        match self.newton_nonfinite_at {
            Some(at) => Status::NonFinite {
                t,
                at,
                what: NonFiniteKind::Derivative,
            },
            None => Status::NewtonFailed {
                t,
                min_step,
                singular: self.newton_singular,
            },
        }
    }

    /// Simplified Newton for `Z` at step `h`: factorise if need be, iterate, and on failure
    /// with an old Jacobian re-evaluate it once and retry. Returns (converged, iterations,
    /// rate).
    fn newton(
        &mut self,
        t: f64,
        h: f64,
        current_jac: &mut bool,
    ) -> Result<(bool, usize, f64), Status> {
        let n = self.st.dim;
        for i in 0..n {
            self.scale[i] = self.st.atol[i] + self.st.y[i].abs() * self.st.rtol[i];
        }
        loop {
            let factored = if !(self.lu_real.is_valid() && self.lu_complex.is_valid()) {
                self.factor_newton_matrices(h)
            } else {
                true
            };
            self.newton_singular = !factored;
            let r = if factored {
                self.solve_collocation_system(t, h)?
            } else {
                (false, 0, f64::NAN)
            };
            if r.0 || *current_jac || self.jac_mode == JacMode::Constant {
                return Ok(r);
            }
            self.update_jacobian()?;
            *current_jac = true;
            self.invalidate_lu();
        }
    }

    /// `y_new = y + Z[2]` and the embedded error estimate `LU_real⁻¹ (f + Zᵀ E / h)` (into
    /// `err`, `Zᵀ E / h` kept in `ze`); its RMS norm scaled by `atol + max(|y|, |y_new|) rtol`.
    fn error_norm(&mut self, h: f64) -> f64 {
        let n = self.st.dim;
        for i in 0..n {
            self.st.y_new[i] = self.st.y[i] + self.z[2 * n + i];
        }
        for i in 0..n {
            let z = (self.z[i] * E[0] + self.z[n + i] * E[1]) + self.z[2 * n + i] * E[2];
            self.ze[i] = z / h;
            self.err[i] = self.st.f[i] + self.ze[i];
        }
        self.lu_real.solve(&mut self.err);
        self.sys.filter_error(&self.st.y, &mut self.err);
        for i in 0..n {
            let (a, b) = (self.st.y[i].abs(), self.st.y_new[i].abs());
            self.scale[i] = self.st.atol[i] + a.max(b) * self.st.rtol[i];
        }
        rms((0..n).map(|i| self.err[i] / self.scale[i]), n)
    }

    fn invalidate_lu(&mut self) {
        self.lu_real.invalidate();
        self.lu_complex.invalidate();
    }

    /// The accepted `y_new` (projected) becomes the state with its derivative `f`; if that
    /// derivative fails the step is undone.
    fn accept(&mut self, t_new: f64) -> Result<(), Status> {
        let t = self.st.t;
        self.sys
            .project(&mut self.st.y_new)
            .map_err(|message| Status::RhsError {
                t,
                at: t_new,
                message,
            })?;
        check_state(&self.st.y_new, t, t_new)?;
        // The new state (the interpolant keeps the unprojected collocation polynomial).
        let st = &mut self.st;
        let t_old_before = st.t_old;
        std::mem::swap(&mut st.y_old, &mut st.y);
        std::mem::swap(&mut st.y, &mut st.y_new);
        st.t_old = t;
        st.t = t_new;
        if let Err(mut s) = st.rhs_here(&mut self.sys) {
            // Not accepted after all: the time reached is the step's start.
            std::mem::swap(&mut st.y, &mut st.y_new);
            std::mem::swap(&mut st.y_old, &mut st.y);
            st.t = t;
            st.t_old = t_old_before;
            if let Status::RhsError { t: tr, .. } | Status::NonFinite { t: tr, .. } = &mut s {
                *tr = t;
            }
            return Err(s);
        }
        Ok(())
    }

    /// The step's interpolant `Q = Zᵀ P`.
    fn fill_q(&mut self) {
        let n = self.st.dim;
        for i in 0..n {
            let (a, b, c) = (self.z[i], self.z[n + i], self.z[2 * n + i]);
            for j in 0..3 {
                self.q[3 * i + j] = a * P[0][j] + b * P[1][j] + c * P[2][j];
            }
        }
    }

    /// After a rejection: the error estimate once more through the LU with `f(t, y + err)`
    /// (into `err`); its norm, infinite if that derivative is not finite.
    fn filtered_error_norm(&mut self, t: f64) -> Result<f64, Status> {
        let n = self.st.dim;
        for i in 0..n {
            self.y_stage[i] = self.st.y[i] + self.err[i];
        }
        if !self.y_stage.iter().all(|v| v.is_finite()) {
            return Ok(f64::INFINITY);
        }
        self.st.nfev += 1;
        self.sys
            .rhs(t, &self.y_stage, &mut self.err)
            .map_err(|message| Status::RhsError { t, at: t, message })?;
        if !self.err.iter().all(|v| v.is_finite()) {
            return Ok(f64::INFINITY);
        }
        for i in 0..n {
            self.err[i] += self.ze[i];
        }
        self.lu_real.solve(&mut self.err);
        self.sys.filter_error(&self.st.y, &mut self.err);
        Ok(rms((0..n).map(|i| self.err[i] / self.scale[i]), n))
    }

    /// Interpolant coefficients `Q = Zᵀ P` of the last accepted step (`3 · dim`, `q[3 i + j]`)
    /// for [`Interpolant::Radau`]`.eval(t_old(), t() - t_old(), y_old(), q, t, out)`.
    /// Returns false (leaving `q` untouched) before the first step.
    pub fn fill_dense_q(&self, q: &mut [f64]) -> bool {
        if self.st.n_accepted == 0 {
            return false;
        }
        q.copy_from_slice(&self.q);
        true
    }

    /// The last step's interpolant at `t` into `out` (false before the first step).
    pub fn dense_eval(&self, t: f64, out: &mut [f64]) -> bool {
        if self.st.n_accepted == 0 {
            return false;
        }
        Interpolant::Radau.eval(
            self.st.t_old,
            self.st.t - self.st.t_old,
            &self.st.y_old,
            &self.q,
            t,
            out,
        );
        true
    }

    /// Jacobian evaluations (analytic or finite-difference).
    pub fn njev(&self) -> usize {
        self.njev
    }
    /// LU factorisations (real and complex each count one).
    pub fn nlu(&self) -> usize {
        self.nlu
    }
    /// Right-hand-side calls spent on finite-difference Jacobians (not in `nfev`).
    pub fn jac_evaluations(&self) -> usize {
        self.num_jac.evaluations()
    }
    /// Whether the Jacobian is the system's analytic one.
    pub fn analytic_jacobian(&self) -> bool {
        self.jac_mode == JacMode::Analytic
    }
    /// Attempts whose Newton iteration did not converge (the step was halved).
    pub fn n_newton_failures(&self) -> usize {
        self.n_newton_failures
    }
    /// The failed step's last attempt was a Newton failure (for the failure message).
    pub fn failed_in_newton(&self) -> bool {
        self.last_attempt_newton_failure
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
    /// The step state and the system together, for a run continued across calls
    /// (`integrator::resume`).
    pub(crate) fn parts(&mut self) -> (&mut StepState, &mut S) {
        (&mut self.st, &mut self.sys)
    }
}

/// `solve(..)` with `method = Radau` and the Jacobian from `jacobian` (e.g. a constant matrix,
/// SciPy's `jac=array`): the same driver, events and outputs.
pub fn radau_solve<S: OdeSystem>(
    sys: S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &SolverOptions,
    events: &mut [super::Event<'_>],
    jacobian: JacobianSource,
) -> Result<super::Solution, InputError> {
    let (t0, t_end) = t_span;
    let st = Radau::with_jacobian(sys, t0, y0, t_end, opts, jacobian)?;
    super::driver::drive(st, opts, events, super::Method::Radau)
}

impl<S: OdeSystem> Integrator for Radau<S> {
    type System = S;
    fn step(&mut self) -> Result<StepOutcome, Status> {
        common::step(self)
    }
    step_state_accessors!();
    /// `nfev` as SciPy counts it: without the finite-difference Jacobians' evaluations
    /// ([`Radau::jac_evaluations`]).
    fn counts(&self) -> Counts {
        Counts {
            nfev: self.st.nfev,
            njev: self.njev,
            nlu: self.nlu,
            n_accepted: self.st.n_accepted,
            n_rejected: self.st.n_rejected,
        }
    }
    fn interpolant(&self) -> Interpolant {
        Interpolant::Radau
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

impl<S: OdeSystem> Stepping for Radau<S> {
    fn lifecycle(&mut self) -> &mut Lifecycle {
        &mut self.st.lifecycle
    }
    fn start(&mut self) -> Result<(), Status> {
        Radau::start(self)
    }
    fn advance(&mut self) -> Result<StepOutcome, Status> {
        self.advance_impl()
    }
}

impl<S: OdeSystem> Deref for Radau<S> {
    type Target = StepState;
    fn deref(&self) -> &StepState {
        &self.st
    }
}

/// SciPy's `newton_tol = max(10 EPS / rtol, min(0.03, √rtol))` from the rtol given (before it
/// is raised to 100 EPS; the smallest entry of a per-component one).
fn newton_tolerance(rtol: &Tol) -> f64 {
    let given = match rtol {
        Tol::Scalar(x) => *x,
        Tol::PerComponent(v) => v.iter().copied().fold(f64::INFINITY, f64::min),
    };
    // rtol = 0 would make the tolerance infinite (SciPy's 10 EPS / 0).
    let r = if given > 0.0 {
        given
    } else {
        100.0 * f64::EPSILON
    };
    (10.0 * f64::EPSILON / r).max(0.03f64.min(r.powf(0.5)))
}

/// Every `atol` entry positive (Radau, or `auto` that may continue with it): a zero one
/// makes the Newton scale `atol + rtol·|y|` vanish where `y` does (RADAU5's check).
pub(crate) fn check_atol_positive(atol: &[f64], method: &'static str) -> Result<(), InputError> {
    match atol.iter().enumerate().find(|(_, a)| !(**a > 0.0)) {
        Some((index, &value)) => Err(InputError::AtolZeroImplicit {
            method,
            index,
            value,
        }),
        None => Ok(()),
    }
}

/// The step-size safety factor after `n_iter` Newton iterations, `0.9 (2 N + 1)/(2 N + iters)`.
fn safety(n_iter: usize) -> f64 {
    0.9 * (2 * NEWTON_MAXITER + 1) as f64 / (2 * NEWTON_MAXITER + n_iter) as f64
}

fn jacobian_error(t: f64, message: String) -> Status {
    Status::RhsError {
        t,
        at: t,
        message: format!("jacobian: {message}"),
    }
}

#[cfg(test)]
#[path = "tests/radau.rs"]
mod tests;
