//! Variable-order, variable-step Adams–Bashforth–Moulton (PECE, orders 1–11) in modified
//! divided differences: Shampine & Gordon's `STEP` (*Computer Solution of Ordinary
//! Differential Equations*, 1975; the code behind `DE`/`ODE` and SLATEC's `DEABM`) written
//! anew. Each step predicts with the `k`-step Adams–Bashforth formula, evaluates, corrects with
//! the Adams–Moulton formula of order `k + 1` (local extrapolation) and evaluates again: two
//! right-hand-side evaluations per step whatever the order. The order and the step follow the
//! error estimates at orders `k − 2 … k + 1`; the interpolant of a step is the Adams polynomial
//! itself (`INTRP`), so dense output, `t_eval` and events cost no evaluation. For smooth
//! non-stiff problems at tight tolerances (docs/integrators.md). Error test: the RMS norm of
//! the local error over `atol + rtol·|y|` (`y` at the step's start), as SciPy's methods.
//!
//! Stiffness: each step evaluates `f` at the predicted and at the corrected state at the same
//! time, so `h ‖f(y) − f(p)‖ / ‖y − p‖` estimates `h |λ|` for free; above the stability limit of
//! the step's order ([`STABILITY`]) on [`STIFF_STEPS`] steps it is reported as the explicit
//! Runge–Kutta methods report it (and `auto` hands over to Radau).

use std::ops::{Deref, DerefMut};

use super::adams_coef::{interpolation_polynomials, Coefficients, GSTR, KMAX, STABILITY, TWO};
use super::common::{
    self, call_rhs, check_start, check_state, check_step_options, next_toward,
    step_state_accessors, tolerances, Lifecycle, StepState, Stepping,
};
use super::dense::Interpolant;
use super::method::{Counts, Integrator};
use super::{
    InputError, OdeSystem, SolverOptions, Status, StepOutcome, Stiffness, StiffnessCheck,
    NONSTIFF_RESET, STIFF_STEPS,
};

/// Rows of the difference table: `φ_1 … φ_{k+2}` (`k ≤ 12`), then the two rounding
/// corrections of the compensated sums (`STEP`'s `φ_15`, `φ_16`).
/// The highest order used. Order 12 (Shampine–Gordon's limit) has an instability bubble on
/// the negative axis at `h λ ∈ (−0.12, −0.062)` (`adams_coef.rs`, [`STABILITY`]): on Kepler's
/// orbit its error levelled off at 2e-9 from rtol 1e-11; capped at 11 it reaches 1.2e-10 at
/// 1e-12 and chain7 needs no more evaluations for the same error (docs/integrators.md).
const MAX_ORDER: usize = 11;
const ROWS: usize = KMAX + 4;
const RND_P: usize = KMAX + 2;
const RND_Y: usize = KMAX + 3;

/// The highest order at which a step counts towards a stiffness detection. On a stiff
/// problem the estimates at high orders are dominated by the unstable components and the
/// order falls (Shampine & Gordon's `DE` reads "order ≤ 4 for 50 steps" as stiffness); on a
/// smooth oscillatory one (Krogh's rigid body at rtol 1e-8…1e-10) orders 10–11 run at `h |λ|`
/// above their small real-axis limits without instability, which would read as stiff.
const STIFF_MAX_ORDER: usize = 4;

/// Calls `body(l, w)` for the components `l..l + w` in blocks of 4, then 2, then 1, the
/// order in which the difference-table passes below walk them.
#[inline(always)]
fn for_columns(n: usize, mut body: impl FnMut(usize, usize)) {
    let mut l = 0;
    while l < n {
        let w = match n - l {
            4.. => 4,
            2 | 3 => 2,
            _ => 1,
        };
        body(l, w);
        l += w;
    }
}

/// `STEP`'s prediction for components `l..l + W`: rows `i = k … 1` scaled by `β_i` (`SCALE`:
/// some row's step size changed), summed into `p` with weights `g_i`, then `φ_i += φ_{i+1}`;
/// `φ_{k+2} = φ_{k+1}`, `φ_{k+1} = 0`. Each component sees the operations of the
/// row-by-row passes in their order (the same bits), but a block's sums stay in registers
/// instead of one pass over `φ` per row (each with its alias checks and remainder loop).
#[inline(always)]
fn predict_columns<const W: usize, const SCALE: bool>(
    phi: &mut [f64],
    p: &mut [f64],
    (n, l, k): (usize, usize, usize),
    gb: &[(f64, f64)],
) {
    let (r1, r2) = (k * n + l, (k + 1) * n + l);
    phi.copy_within(r1..r1 + W, r2);
    phi[r1..r1 + W].fill(0.0);
    let (mut acc, mut next) = ([0.0f64; W], [0.0f64; W]);
    // Row i starts at (i − 1) n: chunk i − 1 of the table from component l on.
    let rows = phi[l..l + k * n].chunks_exact_mut(n).zip(&gb[..k]);
    for (row, &(gi, bi)) in rows.rev() {
        let x = &mut row[..W];
        for (j, xj) in x.iter_mut().enumerate() {
            let xs = if SCALE { *xj * bi } else { *xj };
            acc[j] += gi * xs;
            next[j] += xs;
            *xj = next[j];
        }
    }
    p[l..l + W].copy_from_slice(&acc);
}

/// `STEP`'s block 4 for components `l..l + W`: `e = f − φ_1`, `φ_{k+1} = e`,
/// `φ_{k+2} = e − φ_{k+2}`, `φ_i += e` for `i = 1 … k` (order by order as before).
#[inline(always)]
fn correct_columns<const W: usize>(phi: &mut [f64], f: &[f64], n: usize, l: usize, k: usize) {
    let mut e = [0.0f64; W];
    for j in 0..W {
        e[j] = f[l + j] - phi[l + j];
    }
    let (r1, r2) = (k * n + l, (k + 1) * n + l);
    phi[r1..r1 + W].copy_from_slice(&e);
    let x = &mut phi[r2..r2 + W];
    for j in 0..W {
        x[j] = e[j] - x[j];
    }
    for row in phi[l..l + k * n].chunks_exact_mut(n) {
        let x = &mut row[..W];
        for j in 0..W {
            x[j] += e[j];
        }
    }
}

/// Variable-order Adams PECE usable one step at a time. All buffers are allocated in
/// [`Adams::new`]; a step allocates nothing. Dereferences to its [`StepState`].
pub struct Adams<S: OdeSystem> {
    sys: S,
    st: StepState,
    /// The modified divided differences `φ_i`, row `i − 1` (1-based as in the book).
    phi: Vec<f64>,
    /// The prediction.
    p: Vec<f64>,
    /// `f` at the prediction.
    fp: Vec<f64>,
    /// `1 / (atol + rtol·|y|)` at the step's start (a product per component in each norm).
    wt: Vec<f64>,
    c: Coefficients,
    /// Order of the next step and of the last accepted one.
    k: usize,
    kold: usize,
    /// Signed size of the next step and of the last accepted one.
    h: f64,
    hold: f64,
    /// Start-up: the order rises and the step doubles until an error estimate objects.
    phase1: bool,
    /// Plain sums (the tolerance is far above rounding); else compensated ones.
    nornd: bool,
    stiffness_check: StiffnessCheck,
    stiff_count: usize,
    nonstiff_count: usize,
    stiffness: Option<Stiffness>,
    stop: Option<Status>,
}

impl<S: OdeSystem> Deref for Adams<S> {
    type Target = StepState;
    fn deref(&self) -> &StepState {
        &self.st
    }
}

impl<S: OdeSystem> DerefMut for Adams<S> {
    fn deref_mut(&mut self) -> &mut StepState {
        &mut self.st
    }
}

/// The step's error estimates (`STEP`'s `erk`, `erkm1`, `erkm2`, `err`) and the order it
/// would lower to.
struct Estimates {
    err: f64,
    erk: f64,
    erkm1: f64,
    knew: usize,
}

impl<S: OdeSystem> Adams<S> {
    /// Validate the inputs and allocate all workspaces (no rhs call yet).
    pub fn new(
        sys: S,
        t0: f64,
        y0: &[f64],
        t_bound: f64,
        opts: &SolverOptions,
    ) -> Result<Self, InputError> {
        let dim = sys.dim();
        check_start(dim, y0, t0, t_bound)?;
        let tols = tolerances(opts, dim)?;
        check_step_options(opts, (t_bound - t0).abs())?;
        if opts.controller != super::Controller::Standard {
            return Err(InputError::ControllerUnsupported { method: "Adams" });
        }
        if let Some((index, &value)) = tols.1.iter().enumerate().find(|(_, a)| !(**a > 0.0)) {
            return Err(InputError::AtolZeroAdams { index, value });
        }
        Ok(Self {
            sys,
            st: StepState::new(t0, y0, t_bound, opts, tols),
            phi: vec![0.0; ROWS * dim],
            p: vec![0.0; dim],
            fp: vec![0.0; dim],
            wt: vec![0.0; dim],
            c: Coefficients::new(),
            k: 1,
            kold: 0,
            h: 0.0,
            hold: 0.0,
            phase1: true,
            nornd: true,
            stiffness_check: opts.stiffness,
            stiff_count: 0,
            nonstiff_count: 0,
            stiffness: None,
            stop: None,
        })
    }

    /// Row `i` (1-based) of the difference table.
    #[inline(always)]
    fn row(&self, i: usize) -> usize {
        (i - 1) * self.st.dim
    }

    /// `wt = 1 / (atol + rtol·|y|)` (`atol > 0`) and `2u·RMS(y · wt)`, the rounding level of
    /// the error norm.
    fn weights(&mut self) -> f64 {
        let st = &self.st;
        let mut sq = 0.0;
        let n = st.dim;
        let (wt, y) = (&mut self.wt[..n], &st.y[..n]);
        for (((w, yl), a), r) in wt.iter_mut().zip(y).zip(&st.atol[..n]).zip(&st.rtol[..n]) {
            *w = 1.0 / (a + r * yl.abs());
        }
        for (yl, w) in y.iter().zip(&*wt) {
            sq += (yl * w).powi(2);
        }
        2.0 * f64::EPSILON * (sq / st.dim as f64).sqrt()
    }

    /// `RMS(v · wt)` of the vector `v(l)`.
    #[inline(always)]
    fn norm(&self, v: impl Fn(usize) -> f64) -> f64 {
        let mut sq = 0.0;
        for l in 0..self.st.dim {
            sq += (v(l) * self.wt[l]).powi(2);
        }
        (sq / self.st.dim as f64).sqrt()
    }

    /// Block 2 up to the evaluation: `φ` to `φ*`, the prediction `p` and the predicted
    /// differences, `f(x + h, p)` into `fp`.
    fn predict(&mut self, t_new: f64) -> Result<(), Status> {
        let (n, k, ns) = (self.st.dim, self.k, self.c.ns);
        // (g_i, β_i) for i = 1 … k; β_i (× 1.0, exact, where
        // the step size did not change: i ≤ ns) scales row i.
        let mut gb = [(0.0, 1.0); KMAX];
        for (i, x) in gb.iter_mut().enumerate().take(k) {
            *x = (
                self.c.g[i + 1],
                if i >= ns { self.c.beta[i + 1] } else { 1.0 },
            );
        }
        let (phi, p, gb) = (&mut self.phi[..ROWS * n], &mut self.p[..n], &gb[..]);
        if ns < k {
            for_columns(n, |l, w| match w {
                4 => predict_columns::<4, true>(phi, p, (n, l, k), gb),
                2 => predict_columns::<2, true>(phi, p, (n, l, k), gb),
                _ => predict_columns::<1, true>(phi, p, (n, l, k), gb),
            });
        } else {
            for_columns(n, |l, w| match w {
                4 => predict_columns::<4, false>(phi, p, (n, l, k), gb),
                2 => predict_columns::<2, false>(phi, p, (n, l, k), gb),
                _ => predict_columns::<1, false>(phi, p, (n, l, k), gb),
            });
        }
        let p = &mut self.p[..n];
        let h = self.h;
        if self.nornd {
            for (pl, yl) in p.iter_mut().zip(&self.st.y[..n]) {
                *pl = yl + h * *pl;
            }
        } else {
            let (c15, c16) = (self.row(RND_P + 1), self.row(RND_Y + 1));
            for l in 0..n {
                let tau = h * self.p[l] - self.phi[c15 + l];
                self.p[l] = self.st.y[l] + tau;
                self.phi[c16 + l] = (self.p[l] - self.st.y[l]) - tau;
            }
        }
        let t = self.st.t;
        check_state(&self.p, t, t_new)?;
        call_rhs(
            &mut self.sys,
            &mut self.st.nfev,
            t,
            t_new,
            &self.p,
            &mut self.fp,
        )
    }

    /// Block 2's estimates at orders `k`, `k − 1`, `k − 2` and whether to lower the order.
    fn estimate(&self) -> Estimates {
        let (k, absh, n) = (self.k, self.h.abs(), self.st.dim);
        // The three norms in one pass over the rows (each summed in the order it would be
        // alone); rows `k`, `k − 1` stand in for absent ones at the lowest orders.
        let (rk, rkm1) = (self.row(k.max(1)), self.row(k.saturating_sub(1).max(1)));
        let (fp, p1, wt) = (&self.fp[..n], &self.phi[..n], &self.wt[..n]);
        let (a, b) = (&self.phi[rk..rk + n], &self.phi[rkm1..rkm1 + n]);
        let (mut s0, mut s1, mut s2) = (0.0f64, 0.0f64, 0.0f64);
        for l in 0..n {
            let d = fp[l] - p1[l];
            s0 += (d * wt[l]).powi(2);
            s1 += ((a[l] + d) * wt[l]).powi(2);
            s2 += ((b[l] + d) * wt[l]).powi(2);
        }
        let rms = |sq: f64| (sq / n as f64).sqrt();
        let erk_raw = rms(s0);
        let mut erkm1 = 0.0;
        let mut erkm2 = 0.0;
        if k >= 2 {
            erkm1 = absh * self.c.sig[k] * GSTR[k - 1] * rms(s1);
        }
        if k >= 3 {
            erkm2 = absh * self.c.sig[k - 1] * GSTR[k - 2] * rms(s2);
        }
        let temp5 = absh * erk_raw;
        let err = temp5 * (self.c.g[k] - self.c.g[k + 1]);
        let erk = temp5 * self.c.sig[k + 1] * GSTR[k];
        let knew = match k {
            1 => k,
            2 if erkm1 <= 0.5 * erk => k - 1,
            3.. if erkm1.max(erkm2) <= erk => k - 1,
            _ => k,
        };
        Estimates {
            err,
            erk,
            erkm1,
            knew,
        }
    }

    /// Block 3: undo the rejected step's changes to `φ` and `ψ`, halve the step (on the
    /// third failure in a row drop to order 1, after it take the optimal step).
    fn reject(&mut self, e: &Estimates, ifail: usize) {
        let (n, k) = (self.st.dim, self.k);
        self.phase1 = false;
        for i in 1..=k {
            let (b, ri, rn) = (1.0 / self.c.beta[i], self.row(i), self.row(i + 1));
            for l in 0..n {
                self.phi[ri + l] = b * (self.phi[ri + l] - self.phi[rn + l]);
            }
        }
        self.c.restore_psi(k, self.h);
        let mut factor = 0.5;
        let mut knew = e.knew;
        if ifail >= 3 {
            knew = 1;
        }
        if ifail > 3 && 0.5 < 0.25 * e.erk && e.erk.is_finite() {
            factor = (0.5 / e.erk).sqrt();
        }
        self.h *= factor;
        self.k = knew;
    }

    /// Block 4: correct, evaluate at the corrected state (after the system's projection),
    /// update the differences.
    fn correct(&mut self, t_new: f64) -> Result<(), Status> {
        let (n, k) = (self.st.dim, self.k);
        let temp1 = self.h * self.c.g[k + 1];
        let p1 = self.row(1);
        // y_new = p + h g_{k+1} (f(p) − φ_1); the old state goes to y_old.
        let st = &mut self.st;
        std::mem::swap(&mut st.y_old, &mut st.y);
        if self.nornd {
            let (y, p, fp) = (&mut st.y[..n], &self.p[..n], &self.fp[..n]);
            for (((yl, pl), fl), ql) in y.iter_mut().zip(p).zip(fp).zip(&self.phi[..n]) {
                *yl = pl + temp1 * (fl - ql);
            }
        } else {
            let (c15, c16) = ((RND_P) * n, (RND_Y) * n);
            for l in 0..n {
                let rho = temp1 * (self.fp[l] - self.phi[p1 + l]) - self.phi[c16 + l];
                st.y[l] = self.p[l] + rho;
                self.phi[c15 + l] = (st.y[l] - self.p[l]) - rho;
            }
        }
        let t = st.t;
        self.sys
            .project(&mut st.y)
            .map_err(|message| Status::RhsError {
                t,
                at: t_new,
                message,
            })?;
        check_state(&st.y, t, t_new)?;
        call_rhs(&mut self.sys, &mut st.nfev, t, t_new, &st.y, &mut st.f)?;
        let (phi, f) = (&mut self.phi[..ROWS * n], &st.f[..n]);
        for_columns(n, |l, w| match w {
            4 => correct_columns::<4>(phi, f, n, l, k),
            2 => correct_columns::<2>(phi, f, n, l, k),
            _ => correct_columns::<1>(phi, f, n, l, k),
        });
        Ok(())
    }

    /// Block 4's choice of the next order and step size.
    fn next_order_and_step(&mut self, e: &Estimates) {
        let k = self.k;
        let absh = self.h.abs();
        let mut erk = e.erk;
        if e.knew == k - 1 || k == MAX_ORDER {
            self.phase1 = false;
        }
        let raise = |s: &mut Self, erk: &mut f64, erkp1: f64| {
            s.k = k + 1;
            *erk = erkp1;
        };
        if self.phase1 {
            raise(self, &mut erk, 0.0);
        } else if e.knew == k - 1 {
            self.k = k - 1;
            erk = e.erkm1;
        } else if k < self.c.ns {
            let rk2 = self.row(k + 2);
            let erkp1 = absh * GSTR[k + 1] * self.norm(|l| self.phi[rk2 + l]);
            if k == 1 {
                if erkp1 < 0.5 * erk {
                    raise(self, &mut erk, erkp1);
                }
            } else if e.erkm1 <= erk.min(erkp1) {
                self.k = k - 1;
                erk = e.erkm1;
            } else if erkp1 < erk && k != MAX_ORDER {
                raise(self, &mut erk, erkp1);
            }
        }
        let k = self.k;
        let p5eps = 0.5;
        let mut hnew = 2.0 * self.h;
        if !self.phase1 && p5eps < erk * TWO[k + 1] {
            hnew = self.h;
            if p5eps < erk {
                let r = (p5eps / erk).powf(1.0 / (k + 1) as f64);
                hnew = absh * r.clamp(0.5, 0.9) * self.st.direction;
            }
        }
        self.h = hnew;
    }

    /// `h |λ|` from the two evaluations at `t_new` (prediction, corrected state), counted as
    /// Hairer counts his test, against the stability limit of the order `k` just used, and
    /// only at the low orders a stability-limited Adams run falls to.
    fn stiffness_test(&mut self, k: usize, h: f64, t_new: f64) {
        if k > STIFF_MAX_ORDER {
            // Non-stiff whatever `h |λ|` is: no pass over the state (it was 7 % of Adams's
            // own work at rtol 1e-9, where the orders are 8–11).
            self.count_nonstiff();
            return;
        }
        let (n, st) = (self.st.dim, &self.st);
        let (f, fp, y, p) = (&st.f[..n], &self.fp[..n], &st.y[..n], &self.p[..n]);
        // One pass: the largest differences and the plain sums of squares; the sums scaled by
        // the largest only where the plain ones could overflow or underflow.
        let (mut sk, mut sy, mut nf, mut ny) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for l in 0..n {
            let (df, dy) = ((f[l] - fp[l]).abs(), (y[l] - p[l]).abs());
            sk = sk.max(df);
            sy = sy.max(dy);
            nf += df * df;
            ny += dy * dy;
        }
        if !(sy > 0.0 && sy.is_finite() && sk.is_finite()) {
            return;
        }
        let h_lambda = if nf < 1e300 && ny > 1e-300 {
            h * (nf / ny).sqrt()
        } else {
            let (mut num, mut den) = (0.0, 0.0);
            for l in 0..n {
                num += ((f[l] - fp[l]) / sk.max(f64::MIN_POSITIVE)).powi(2);
                den += ((y[l] - p[l]) / sy).powi(2);
            }
            h * (sk / sy) * (num / den).sqrt()
        };
        if !h_lambda.is_finite() {
            return;
        }
        if h_lambda <= STABILITY[k] {
            self.count_nonstiff();
            return;
        }
        self.nonstiff_count = 0;
        self.stiff_count += 1;
        if self.stiff_count == STIFF_STEPS && self.stiffness.is_none() {
            self.stiffness = Some(Stiffness {
                t: t_new,
                h_lambda,
                h,
            });
            if self.stiffness_check == StiffnessCheck::Stop {
                self.stop = Some(Status::Stiff {
                    t: t_new,
                    h_lambda,
                    h,
                });
            }
        }
    }

    /// A non-stiff step: [`NONSTIFF_RESET`] in a row clear the stiff count.
    fn count_nonstiff(&mut self) {
        self.nonstiff_count += 1;
        if self.nonstiff_count == NONSTIFF_RESET {
            self.stiff_count = 0;
        }
    }

    /// The step to try from `t`: `self.h` within `max_step` and the interval; the new time.
    fn clip(&mut self) -> f64 {
        let st = &self.st;
        let dir = st.direction;
        if self.h.abs() > st.max_step {
            self.h = st.max_step * dir;
        }
        let t_new = st.t + self.h;
        if dir * (t_new - st.t_bound) >= 0.0 {
            self.h = st.t_bound - st.t;
            return st.t_bound;
        }
        t_new
    }

    pub fn stiffness(&self) -> Option<Stiffness> {
        self.stiffness
    }
    /// The order of the next step.
    pub fn order(&self) -> usize {
        self.k
    }
    pub fn into_system(self) -> S {
        self.sys
    }
}

impl<S: OdeSystem> Stepping for Adams<S> {
    fn lifecycle(&mut self) -> &mut Lifecycle {
        &mut self.st.lifecycle
    }

    /// `f(t0, y0)`, `φ_1 = f`, `φ_2 = 0` and `STEP`'s first step: the interval (or
    /// `first_step`), cut to `¼ √(1 / ‖f‖)` when the first-order error would exceed it.
    fn start(&mut self) -> Result<(), Status> {
        self.st.rhs_here(&mut self.sys)?;
        let n = self.st.dim;
        let round = self.weights();
        self.phi[..n].copy_from_slice(&self.st.f);
        self.phi[n..2 * n].fill(0.0);
        let sum = self.norm(|l| self.st.f[l]);
        let st = &self.st;
        let mut absh = match st.first_step {
            Some(h) => h,
            None => {
                let mut a = (st.t_bound - st.t).abs().min(st.max_step);
                if 1.0 < 16.0 * sum * a * a {
                    a = 0.25 * (1.0 / sum).sqrt();
                }
                a
            }
        };
        let min_step = 10.0 * (next_toward(st.t, st.direction) - st.t).abs();
        absh = absh.max(min_step);
        self.h = absh * st.direction;
        self.nornd = 0.5 > 100.0 * round;
        Ok(())
    }

    fn advance(&mut self) -> Result<StepOutcome, Status> {
        let t = self.st.t;
        if self.st.n_accepted >= self.st.max_steps {
            return Err(Status::MaxSteps {
                t,
                max_steps: self.st.max_steps,
            });
        }
        let round = self.weights();
        if self.nornd && 0.5 <= 100.0 * round {
            // The tolerance came near rounding: compensated sums from here on.
            self.nornd = false;
            let (a, b) = (RND_P * self.st.dim, ROWS * self.st.dim);
            self.phi[a..b].fill(0.0);
        }
        let mut ifail = 0;
        // The last attempt's non-finite value: the failure if the step falls below `min_step`.
        let mut non_finite = None;
        let (t_new, e) = loop {
            let min_step = 10.0 * (next_toward(t, self.st.direction) - t).abs();
            if self.h.abs() < min_step {
                return Err(non_finite.unwrap_or(Status::StepTooSmall { t, min_step }));
            }
            let t_new = self.clip();
            self.c.update(self.k, self.kold, self.h, self.hold);
            // A non-finite prediction rejects the step as an infinite error would.
            let e = match self.predict(t_new) {
                Ok(()) => {
                    non_finite = None;
                    self.estimate()
                }
                Err(s @ Status::NonFinite { .. }) => {
                    non_finite = Some(s);
                    Estimates {
                        err: f64::INFINITY,
                        erk: f64::INFINITY,
                        erkm1: f64::INFINITY,
                        knew: self.k,
                    }
                }
                Err(s) => return Err(s),
            };
            if e.err <= 1.0 {
                break (t_new, e);
            }
            ifail += 1;
            self.st.n_rejected += 1;
            self.reject(&e, ifail);
        };
        let (k, h) = (self.k, self.h);
        self.kold = k;
        self.hold = h;
        self.correct(t_new)?;
        if self.stiffness_check != StiffnessCheck::Off {
            self.stiffness_test(k, h.abs(), t_new);
        }
        self.next_order_and_step(&e);
        let st = &mut self.st;
        st.t_old = t;
        st.t = t_new;
        st.h_abs = self.h.abs();
        st.n_accepted += 1;
        Ok(st.outcome())
    }

    fn take_pending(&mut self) -> Option<Status> {
        self.stop.take()
    }
}

impl<S: OdeSystem> Integrator for Adams<S> {
    type System = S;
    #[inline]
    fn step(&mut self) -> Result<StepOutcome, Status> {
        common::step(self)
    }
    step_state_accessors!();
    fn counts(&self) -> Counts {
        Counts::explicit(self.st.nfev, self.st.n_accepted, self.st.n_rejected)
    }
    fn stiffness(&self) -> Option<Stiffness> {
        self.stiffness
    }
    fn interpolant(&self) -> Interpolant {
        Interpolant::Adams
    }
    /// `INTRP`'s polynomial of the last step in powers of `s = x − 1`
    /// ([`Interpolant::Adams`]): no evaluation.
    fn dense_coefficients(&mut self, q: &mut [f64]) -> Result<(), Status> {
        const NC: usize = Interpolant::Adams.n_coef();
        let st = &self.st;
        let n = st.dim;
        let h = st.t - st.t_old;
        let mut gs = [[0.0; KMAX + 2]; KMAX + 2];
        interpolation_polynomials(self.kold, &self.c.psi, h, &mut gs);
        let ki = self.kold + 1;
        for l in 0..n {
            let ql = &mut q[NC * l..NC * (l + 1)];
            ql.fill(0.0);
            ql[0] = st.y[l] - st.y_old[l];
            for (i, gi) in gs.iter().enumerate().take(ki + 1).skip(1) {
                let phi = h * self.phi[(i - 1) * n + l];
                for d in 0..i {
                    ql[d + 1] += gi[d] * phi;
                }
            }
        }
        Ok(())
    }
    fn system_mut(&mut self) -> &mut S {
        &mut self.sys
    }
    fn into_system(self) -> S {
        self.sys
    }
}
