//! Fixed-step methods: [`Rk4`] (classical Runge–Kutta) and [`Euler`] (semi-implicit, as
//! MuJoCo's `mjINT_EULER`), stepped by [`FixedStep`] at `dt` with no error control.
//!
//! Time grid: every step is exactly `h = dt·dir` and step `k` ends at `t0 + k·dt·dir`. The
//! last step ends at `t_end` exactly: a grid point within 1e-9·dt of `t_end` is taken as
//! `t_end` (the step keeps `h = dt`), else the step that would pass `t_end` is shortened
//! to `h = t_end − t`. Each step's interpolant is the cubic Hermite
//! through its end states and derivatives ([`Interpolant::Hermite`]); the derivative at the
//! end is the next step's first evaluation, so dense output costs nothing extra but at the
//! very last step.

use std::marker::PhantomData;

use super::common::{self, call_rhs, check_start, check_state, Lifecycle, Stepping};
use super::dense::Interpolant;
use super::method::{Counts, Integrator};
use super::{InputError, Method, OdeSystem, SolverOptions, Status, StepOutcome};

/// The update of one fixed-step scheme.
pub trait Scheme {
    const METHOD: Method;
    /// Stage buffers of `dim` it needs in [`Work::k`] (row 0 holds `f(t, y)` on entry).
    const STAGES: usize;
    /// `w.y_new` from `(t, w.y)` over the signed step `h`, `w.k[0..dim] = f(t, y)`.
    fn advance<S: OdeSystem>(w: &mut Work<S>, t: f64, h: f64) -> Result<(), Status>;
}

/// The state and buffers a scheme works on.
pub struct Work<S> {
    sys: S,
    dim: usize,
    /// `Some(nq)` for a system `y = [q; v]` (see [`OdeSystem::split`]).
    split: Option<usize>,
    y: Vec<f64>,
    y_new: Vec<f64>,
    y_stage: Vec<f64>,
    /// Stage derivatives, `STAGES` rows of `dim` (row 0: `f(t, y)` of the step).
    k: Vec<f64>,
    nfev: usize,
}

/// Classical fourth-order Runge–Kutta:
/// `k1 = f(t, y)`, `k2 = f(t + h/2, y + (0.5 h) k1)`, `k3 = f(t + h/2, y + (0.5 h) k2)`,
/// `k4 = f(t + h, y + h k3)`, `y_new = y + (h / 6) (((k1 + 2 k2) + 2 k3) + k4)`
/// (evaluated in exactly this order). Four evaluations per step.
pub struct Rk4;

/// Semi-implicit (symplectic) Euler, MuJoCo's `mjINT_EULER` without its implicit damping:
/// for a system `y = [q; v]` ([`OdeSystem::split`]) `v_new = v + h v̇(q, v)`, then
/// `q_new = q + h q̇(q, v_new)` (for quaternions `q̇ = ½ q ⊗ ω` followed by the projection
/// that normalises them, where MuJoCo uses the exponential map). For a system without the
/// split it is explicit Euler, `y_new = y + h f(t, y)`. One evaluation per step (two when the
/// system gives no [`OdeSystem::position_rate`]).
pub struct Euler;

impl Scheme for Rk4 {
    const METHOD: Method = Method::Rk4;
    const STAGES: usize = 4;
    fn advance<S: OdeSystem>(w: &mut Work<S>, t: f64, h: f64) -> Result<(), Status> {
        let n = w.dim;
        let half = 0.5 * h;
        let stages = [(half, 0.5), (half, 0.5), (h, 1.0)];
        for (s, &(a, c)) in stages.iter().enumerate() {
            let (prev, rest) = w.k.split_at_mut((s + 1) * n);
            let kp = &prev[s * n..];
            for ((ys, y), k) in w.y_stage.iter_mut().zip(&w.y).zip(kp) {
                *ys = y + a * k;
            }
            let at = t + c * h;
            check_state(&w.y_stage, t, at)?;
            call_rhs(&mut w.sys, &mut w.nfev, t, at, &w.y_stage, &mut rest[..n])?;
        }
        let sixth = h / 6.0;
        let k = &w.k;
        for i in 0..n {
            let sum = ((k[i] + 2.0 * k[n + i]) + 2.0 * k[2 * n + i]) + k[3 * n + i];
            w.y_new[i] = w.y[i] + sixth * sum;
        }
        Ok(())
    }
}

impl Scheme for Euler {
    const METHOD: Method = Method::Euler;
    const STAGES: usize = 2;
    fn advance<S: OdeSystem>(w: &mut Work<S>, t: f64, h: f64) -> Result<(), Status> {
        let n = w.dim;
        let Some(nq) = w.split.filter(|&nq| nq <= n) else {
            for i in 0..n {
                w.y_new[i] = w.y[i] + h * w.k[i];
            }
            return Ok(());
        };
        // v first ...
        for i in nq..n {
            w.y_new[i] = w.y[i] + h * w.k[i];
        }
        // ... then q with the new v: q̇(q, v_new) into k[1] (positions only).
        w.y_stage[..nq].copy_from_slice(&w.y[..nq]);
        w.y_stage[nq..].copy_from_slice(&w.y_new[nq..]);
        check_state(&w.y_stage, t, t)?;
        let (_, k1) = w.k.split_at_mut(n);
        let provided = w
            .sys
            .position_rate(&w.y_stage, &mut k1[..nq])
            .map_err(|message| Status::RhsError { t, at: t, message })?;
        if !provided {
            call_rhs(&mut w.sys, &mut w.nfev, t, t, &w.y_stage, &mut k1[..n])?;
        }
        for ((yn, y), qd) in w.y_new[..nq].iter_mut().zip(&w.y).zip(&k1[..nq]) {
            *yn = y + h * qd;
        }
        Ok(())
    }
}

/// A fixed-step method `M` at step `dt` (SciPy-like solver object, one step at a time).
pub struct FixedStep<S: OdeSystem, M: Scheme> {
    w: Work<S>,
    t: f64,
    t_old: f64,
    t0: f64,
    t_bound: f64,
    direction: f64,
    dt: f64,
    /// Steps taken (the grid index of `t`).
    n_accepted: usize,
    max_steps: usize,
    y_old: Vec<f64>,
    /// `f(t_old, y_old)` of the last step (the Hermite interpolant's start slope).
    f_old: Vec<f64>,
    /// `w.k[0..dim]` holds `f(t, y)` (computed lazily: the next step's, or the interpolant's).
    f_valid: bool,
    lifecycle: Lifecycle,
    _m: PhantomData<M>,
}

impl<S: OdeSystem, M: Scheme> FixedStep<S, M> {
    /// Validates the inputs (`opts.dt` required) and allocates every buffer.
    pub fn new(
        sys: S,
        t0: f64,
        y0: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
    ) -> Result<Self, InputError> {
        let dim = sys.dim();
        check_start(dim, y0, t0, t_bound)?;
        // Unused at a fixed step, but a NaN or negative one is still a mistake to report.
        super::common::tolerances(opts, dim)?;
        let dt = opts.dt.ok_or(InputError::DtMissing {
            method: M::METHOD.name(),
        })?;
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(InputError::DtInvalid(dt));
        }
        if opts.max_steps == 0 {
            return Err(InputError::MaxSteps);
        }
        let split = sys.split();
        Ok(Self {
            w: Work {
                sys,
                dim,
                split,
                y: y0.to_vec(),
                y_new: vec![0.0; dim],
                y_stage: vec![0.0; dim],
                k: vec![0.0; M::STAGES.max(2) * dim],
                nfev: 0,
            },
            t: t0,
            t_old: t0,
            t0,
            t_bound,
            direction: if t_bound > t0 { 1.0 } else { -1.0 },
            dt,
            n_accepted: 0,
            max_steps: opts.max_steps,
            y_old: y0.to_vec(),
            f_old: vec![0.0; dim],
            f_valid: false,
            lifecycle: Lifecycle::Running,
            _m: PhantomData,
        })
    }

    /// `w.k[0..dim] = f(t, y)` unless already there.
    fn ensure_f(&mut self) -> Result<(), Status> {
        if !self.f_valid {
            let (n, t) = (self.w.dim, self.t);
            let w = &mut self.w;
            call_rhs(&mut w.sys, &mut w.nfev, t, t, &w.y, &mut w.k[..n])?;
            self.f_valid = true;
        }
        Ok(())
    }

    /// The end of the next step and its signed size: `dt·dir` to the next grid point,
    /// except for the last step, which ends at `t_end` (of size `dt` still when the grid
    /// point is within 1e-9·dt of `t_end`, else `t_end − t`).
    fn next_step(&self) -> (f64, f64) {
        let dir = self.direction;
        let h = self.dt * dir;
        let t_grid = self.t0 + (self.n_accepted + 1) as f64 * h;
        let tol = 1e-9 * self.dt;
        if (t_grid - self.t_bound).abs() <= tol {
            (self.t_bound, h)
        } else if dir * (t_grid - self.t_bound) > 0.0 {
            (self.t_bound, self.t_bound - self.t)
        } else {
            (t_grid, h)
        }
    }

    fn step_impl(&mut self) -> Result<StepOutcome, Status> {
        let t = self.t;
        if self.n_accepted >= self.max_steps {
            return Err(Status::MaxSteps {
                t,
                max_steps: self.max_steps,
            });
        }
        self.ensure_f()?;
        let (t_new, h) = self.next_step();
        M::advance(&mut self.w, t, h)?;
        let w = &mut self.w;
        w.sys
            .project(&mut w.y_new)
            .map_err(|message| Status::RhsError {
                t,
                at: t_new,
                message,
            })?;
        check_state(&w.y_new, t, t_new)?;
        let n = w.dim;
        self.f_old.copy_from_slice(&w.k[..n]);
        std::mem::swap(&mut self.y_old, &mut w.y);
        std::mem::swap(&mut w.y, &mut w.y_new);
        self.f_valid = false;
        self.t_old = t;
        self.t = t_new;
        self.n_accepted += 1;
        if t_new == self.t_bound {
            Ok(StepOutcome::Finished)
        } else {
            Ok(StepOutcome::Accepted)
        }
    }

    pub fn nfev(&self) -> usize {
        self.w.nfev
    }

    /// The interval continued to `t_bound` (`integrator::resume`): the grid goes on from
    /// `t0`, and the next step evaluates `f(t, y)` afresh (the right-hand side may have
    /// changed at `t`).
    pub(crate) fn extend(&mut self, t_bound: f64) {
        self.t_bound = t_bound;
        self.f_valid = false;
        if self.lifecycle == Lifecycle::Finished {
            self.lifecycle = Lifecycle::Running;
        }
    }
}

/// Nothing to evaluate before the first step (`f(t0, y0)` is the first step's own).
impl<S: OdeSystem, M: Scheme> Stepping for FixedStep<S, M> {
    fn lifecycle(&mut self) -> &mut Lifecycle {
        &mut self.lifecycle
    }
    fn start(&mut self) -> Result<(), Status> {
        Ok(())
    }
    fn advance(&mut self) -> Result<StepOutcome, Status> {
        self.step_impl()
    }
}

impl<S: OdeSystem, M: Scheme> Integrator for FixedStep<S, M> {
    type System = S;
    fn step(&mut self) -> Result<StepOutcome, Status> {
        common::step(self)
    }
    fn dim(&self) -> usize {
        self.w.dim
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
        &self.w.y
    }
    fn y_old(&self) -> &[f64] {
        &self.y_old
    }
    fn counts(&self) -> Counts {
        Counts::explicit(self.w.nfev, self.n_accepted, 0)
    }
    fn h_next(&self) -> f64 {
        self.dt
    }
    fn interpolant(&self) -> Interpolant {
        Interpolant::Hermite
    }
    /// Cubic Hermite: `q0 = h f_old`, `q1 = 3Δ − 2 h f_old − h f`, `q2 = h f_old + h f − 2Δ`
    /// (`f = f(t, y)`, the next step's first evaluation, computed now if need be).
    fn dense_coefficients(&mut self, q: &mut [f64]) -> Result<(), Status> {
        let r = self.ensure_f();
        common::record(&mut self.lifecycle, r)?;
        let h = self.t - self.t_old;
        let (n, f) = (self.w.dim, &self.w.k);
        for i in 0..n {
            let delta = self.w.y[i] - self.y_old[i];
            let (a, b) = (h * self.f_old[i], h * f[i]);
            q[3 * i] = a;
            q[3 * i + 1] = 3.0 * delta - 2.0 * a - b;
            q[3 * i + 2] = a + b - 2.0 * delta;
        }
        Ok(())
    }
    fn system_mut(&mut self) -> &mut S {
        &mut self.w.sys
    }
    fn into_system(self) -> S {
        self.w.sys
    }
}
