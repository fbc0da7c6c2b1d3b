//! Finite-difference Jacobian for the implicit methods: a port of SciPy's `num_jac`
//! (scipy/integrate/_ivp/common.py, dense case).
//!
//! Forward differences, column `j` with step `h_j = (y_j + factor_j s_j) − y_j`,
//! `s_j = sign(f_j) max(atol_j, |y_j|)` (stepping the way the flow goes). `factor` starts at
//! `√EPS` and adapts from call to call so that each column's largest difference stays well
//! above its round-off (`EPS |f|`): a column whose difference is lost in round-off is retried
//! once with a 10× larger step (one more evaluation each). One evaluation per column, plus the
//! retries: SciPy does not count these in `nfev`, nor do we (see [`NumJac::evaluations`]).
// Index loops over parallel arrays, as SciPy's vector expressions read.
#![allow(clippy::needless_range_loop)]

use super::{NonFiniteKind, OdeSystem, Status};

const EPS: f64 = f64::EPSILON;

/// SciPy's thresholds (`NUM_JAC_DIFF_REJECT` = EPS^0.875 etc.).
fn diff_reject() -> f64 {
    EPS.powf(0.875)
}
fn diff_small() -> f64 {
    EPS.powf(0.75)
}
fn diff_big() -> f64 {
    EPS.powf(0.25)
}
const MIN_FACTOR: f64 = 1e3 * EPS;
const FACTOR_INCREASE: f64 = 10.0;
const FACTOR_DECREASE: f64 = 0.1;

/// Workspace and the adapted step factors of successive finite-difference Jacobians.
pub(crate) struct NumJac {
    n: usize,
    /// `None` before the first call (SciPy's `factor=None`).
    factor: Option<Vec<f64>>,
    h: Vec<f64>,
    y_scale: Vec<f64>,
    /// Column `j` of `f(y + h_j e_j) − f(y)` at `diff[j n..(j + 1) n]`.
    diff: Vec<f64>,
    max_diff: Vec<f64>,
    scale: Vec<f64>,
    y_pert: Vec<f64>,
    f_pert: Vec<f64>,
    /// Right-hand-side evaluations made here, all calls together.
    evaluations: usize,
}

impl NumJac {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            factor: None,
            h: vec![0.0; n],
            y_scale: vec![0.0; n],
            diff: vec![0.0; n * n],
            max_diff: vec![0.0; n],
            scale: vec![0.0; n],
            y_pert: vec![0.0; n],
            f_pert: vec![0.0; n],
            evaluations: 0,
        }
    }

    /// Right-hand-side evaluations spent on Jacobians so far.
    pub(crate) fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// `f(t, y + h_j e_j)` into `f_pert`; returns its largest `|Δf|` row, that difference and
    /// the round-off scale `max(|f_i|, |f_pert_i|)` of that row.
    fn column<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &[f64],
        f: &[f64],
        j: usize,
        h: f64,
    ) -> Result<(f64, f64), Status> {
        self.y_pert.copy_from_slice(y);
        self.y_pert[j] = y[j] + h;
        self.evaluations += 1;
        sys.rhs(t, &self.y_pert, &mut self.f_pert)
            .map_err(|message| Status::RhsError { t, at: t, message })?;
        if !self.f_pert.iter().all(|v| v.is_finite()) {
            return Err(Status::NonFinite {
                t,
                at: t,
                what: NonFiniteKind::Derivative,
            });
        }
        // np.argmax: the first largest.
        let mut mi = 0;
        let mut best = -1.0;
        for i in 0..self.n {
            let d = (self.f_pert[i] - f[i]).abs();
            if d > best {
                best = d;
                mi = i;
            }
        }
        Ok((best, f[mi].abs().max(self.f_pert[mi].abs())))
    }

    /// The Jacobian `∂f/∂y` at `(t, y)`, `f = f(t, y)`, into `jac` (row-major `n × n`);
    /// `threshold` is `atol` per component.
    pub(crate) fn compute<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &[f64],
        f: &[f64],
        threshold: &[f64],
        jac: &mut [f64],
    ) -> Result<(), Status> {
        let n = self.n;
        let mut factor = self.factor.take().unwrap_or_else(|| vec![EPS.powf(0.5); n]);
        for j in 0..n {
            let f_sign = if f[j] >= 0.0 { 1.0 } else { -1.0 };
            let mut s = threshold[j].max(y[j].abs());
            if s == 0.0 {
                // y_j = 0 with atol_j = 0: SciPy would multiply `factor` by 10 forever.
                s = 1.0;
            }
            self.y_scale[j] = f_sign * s;
            let mut h = (y[j] + factor[j] * self.y_scale[j]) - y[j];
            // A step lost below y's spacing: grow it (SciPy's loop; rare).
            while h == 0.0 {
                factor[j] *= 10.0;
                h = (y[j] + factor[j] * self.y_scale[j]) - y[j];
            }
            self.h[j] = h;
        }
        for j in 0..n {
            let (md, sc) = self.column(sys, t, y, f, j, self.h[j])?;
            for i in 0..n {
                self.diff[j * n + i] = self.f_pert[i] - f[i];
            }
            self.max_diff[j] = md;
            self.scale[j] = sc;
        }
        let reject = diff_reject();
        for j in 0..n {
            if self.max_diff[j] < reject * self.scale[j] {
                let new_factor = FACTOR_INCREASE * factor[j];
                let h_new = (y[j] + new_factor * self.y_scale[j]) - y[j];
                let (md, sc) = self.column(sys, t, y, f, j, h_new)?;
                // Keep the retry if its difference stands out better from its round-off.
                if self.max_diff[j] * sc < md * self.scale[j] {
                    factor[j] = new_factor;
                    self.h[j] = h_new;
                    for i in 0..n {
                        self.diff[j * n + i] = self.f_pert[i] - f[i];
                    }
                    self.scale[j] = sc;
                    self.max_diff[j] = md;
                }
            }
        }
        for j in 0..n {
            let h = self.h[j];
            for i in 0..n {
                jac[i * n + j] = self.diff[j * n + i] / h;
            }
        }
        let (small, big) = (diff_small(), diff_big());
        for j in 0..n {
            if self.max_diff[j] < small * self.scale[j] {
                factor[j] *= FACTOR_INCREASE;
            }
            if self.max_diff[j] > big * self.scale[j] {
                factor[j] *= FACTOR_DECREASE;
            }
            factor[j] = factor[j].max(MIN_FACTOR);
        }
        self.factor = Some(factor);
        Ok(())
    }
}
