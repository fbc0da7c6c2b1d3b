//! Dense output: per accepted step an interpolant of one of several kinds ([`Interpolant`]),
//! evaluated exactly as SciPy evaluates it, and the piecewise [`DenseOutput`] over a run
//! (its segments may be of different kinds, e.g. RK45 then Radau after a method switch).
//!
//! RK45's is SciPy's quartic `y(t) = y_old + h · Q p(x)`, with `x = (t - t_old) / h`,
//! `p = (x, x², x³, x⁴)` and `Q = Kᵀ P` (Shampine 1986, optimal c6).
use crate::support::args::{shape_str, Arg};
use crate::support::error::Error;

/// How a step's coefficients `q` (`n_coef()` per component; component `i` at
/// `q[n_coef·i ..]`) give the state at `t`, with `x = (t - t_old) / h`, `h = t - t_old` signed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Interpolant {
    /// SciPy `RkDenseOutput` of RK45: `y_old + h · (q0 x + q1 x² + q2 x³ + q3 x⁴)`.
    Rk45,
    /// SciPy `Dop853DenseOutput`, `F = (q0 … q6)`: `y = 0; for i, f in enumerate(reversed(F)):
    /// y += f; y *= x if i is even else (1 − x)`, then `y + y_old`.
    Dop853,
    /// SciPy `RadauDenseOutput`: `y_old + (q0 x + q1 x² + q2 x³)` (no factor h).
    Radau,
    /// Cubic Hermite through `(y_old, f_old)` and `(y, f)` of a fixed step, in the Radau form
    /// `y_old + (q0 x + q1 x² + q2 x³)` with `q0 = h f_old`, `q1 = 3Δ − 2h f_old − h f`,
    /// `q2 = h f_old + h f − 2Δ`, `Δ = y − y_old`.
    Hermite,
    /// Verner 9(8)'s interpolant: `y_old + (q0 x + q1 x² + … + q8 x⁹)` (the factor h is in `q`).
    Vern9,
    /// The Adams polynomial of Shampine–Gordon's `INTRP` in powers of `s = x − 1`:
    /// `y_old + q0 + (q1 s + q2 s² + … + q13 s¹³)` (`q0 = y − y_old`, the factor h in `q`).
    Adams,
}

impl Interpolant {
    /// Coefficients per component.
    pub const fn n_coef(self) -> usize {
        match self {
            Interpolant::Rk45 => 4,
            Interpolant::Dop853 => 7,
            Interpolant::Radau | Interpolant::Hermite => 3,
            Interpolant::Vern9 => 9,
            Interpolant::Adams => 14,
        }
    }

    /// The interpolant at `t` into `out` (length `dim`, `y_old` and `q` of that dimension).
    #[inline]
    pub fn eval(self, t_old: f64, h: f64, y_old: &[f64], q: &[f64], t: f64, out: &mut [f64]) {
        match self {
            Interpolant::Rk45 => eval_segment(t_old, h, y_old, q, t, out),
            Interpolant::Dop853 => {
                let x = (t - t_old) / h;
                let xm = 1.0 - x;
                for (i, o) in out.iter_mut().enumerate() {
                    let f = &q[7 * i..7 * i + 7];
                    let mut y = 0.0;
                    for (k, fk) in f.iter().rev().enumerate() {
                        y += fk;
                        y *= if k % 2 == 0 { x } else { xm };
                    }
                    *o = y + y_old[i];
                }
            }
            Interpolant::Vern9 => {
                let x = (t - t_old) / h;
                for (i, o) in out.iter_mut().enumerate() {
                    let qi = &q[9 * i..9 * i + 9];
                    let mut y = qi[8];
                    for c in qi[..8].iter().rev() {
                        y = y * x + c;
                    }
                    *o = y * x + y_old[i];
                }
            }
            Interpolant::Adams => {
                let s = (t - t_old) / h - 1.0;
                for (i, o) in out.iter_mut().enumerate() {
                    let qi = &q[14 * i..14 * i + 14];
                    let mut y = qi[13];
                    for c in qi[1..13].iter().rev() {
                        y = y * s + c;
                    }
                    *o = (y * s + qi[0]) + y_old[i];
                }
            }
            Interpolant::Radau | Interpolant::Hermite => {
                let x = (t - t_old) / h;
                let (p1, p2) = (x, x * x);
                let p3 = p2 * x;
                for (i, o) in out.iter_mut().enumerate() {
                    let qi = &q[3 * i..3 * i + 3];
                    *o = (qi[0] * p1 + qi[1] * p2 + qi[2] * p3) + y_old[i];
                }
            }
        }
    }
}

/// SciPy's `RK45.P` (7 stages × 4 powers).
pub(crate) const P: [[f64; 4]; 7] = [
    [
        1.0,
        -8048581381.0 / 2820520608.0,
        8663915743.0 / 2820520608.0,
        -12715105075.0 / 11282082432.0,
    ],
    [0.0, 0.0, 0.0, 0.0],
    [
        0.0,
        131558114200.0 / 32700410799.0,
        -68118460800.0 / 10900136933.0,
        87487479700.0 / 32700410799.0,
    ],
    [
        0.0,
        -1754552775.0 / 470086768.0,
        14199869525.0 / 1410260304.0,
        -10690763975.0 / 1880347072.0,
    ],
    [
        0.0,
        127303824393.0 / 49829197408.0,
        -318862633887.0 / 49829197408.0,
        701980252875.0 / 199316789632.0,
    ],
    [
        0.0,
        -282668133.0 / 205662961.0,
        2019193451.0 / 616988883.0,
        -1453857185.0 / 822651844.0,
    ],
    [
        0.0,
        40617522.0 / 29380423.0,
        -110615467.0 / 29380423.0,
        69997945.0 / 29380423.0,
    ],
];

/// `Q = Kᵀ P` from the stage derivatives `k` (7 rows of `dim`), written as `q[4 i + j]`.
pub(crate) fn fill_q(k: &[f64], dim: usize, q: &mut [f64]) {
    for i in 0..dim {
        for j in 0..4 {
            let mut acc = k[i] * P[0][j];
            for (s, row) in P.iter().enumerate().skip(1) {
                acc += k[s * dim + i] * row[j];
            }
            q[4 * i + j] = acc;
        }
    }
}

/// Evaluate one step's interpolant at `t` into `out` (SciPy `RkDenseOutput._call_impl`).
/// `h = t_new - t_old` is signed; `q` comes from [`Stepper::fill_dense_q`](super::Stepper::fill_dense_q).
pub fn eval_segment(t_old: f64, h: f64, y_old: &[f64], q: &[f64], t: f64, out: &mut [f64]) {
    let x = (t - t_old) / h;
    // NumPy's cumprod order: x, x·x, (x·x)·x, ((x·x)·x)·x.
    let p1 = x;
    let p2 = p1 * x;
    let p3 = p2 * x;
    let p4 = p3 * x;
    for (i, o) in out.iter_mut().enumerate() {
        let qi = &q[4 * i..4 * i + 4];
        let dot = qi[0] * p1 + qi[1] * p2 + qi[2] * p3 + qi[3] * p4;
        *o = h * dot + y_old[i];
    }
}

/// Piecewise interpolant over the whole run (SciPy's `OdeSolution`).
///
/// Breakpoints are t0 and the output time of each step (the event time for a terminal step);
/// segment `i` spans `breakpoints[i]..breakpoints[i+1]`. A time exactly on a breakpoint uses the
/// earlier segment, and times outside the range extrapolate the first/last segment, as in SciPy.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "DenseData")]
pub struct DenseOutput {
    dim: usize,
    ts: Vec<f64>,
    t_old: Vec<f64>,
    h: Vec<f64>,
    y_old: Vec<f64>,
    /// Every segment's coefficients, one after the other.
    q: Vec<f64>,
    /// Each segment's interpolant.
    kind: Vec<Interpolant>,
    /// Where each segment's coefficients start in `q` (derived from `kind`).
    #[serde(skip)]
    offset: Vec<usize>,
}

/// A deserialised dense output, its lengths checked before use.
#[derive(serde::Deserialize)]
struct DenseData {
    dim: usize,
    ts: Vec<f64>,
    t_old: Vec<f64>,
    h: Vec<f64>,
    y_old: Vec<f64>,
    q: Vec<f64>,
    kind: Vec<Interpolant>,
}

impl TryFrom<DenseData> for DenseOutput {
    type Error = String;
    fn try_from(d: DenseData) -> Result<Self, String> {
        let n = d.t_old.len();
        let mut offset = Vec::with_capacity(d.kind.len());
        let mut total = Some(0usize);
        for k in &d.kind {
            offset.push(total.unwrap_or(0));
            total = total.and_then(|t| t.checked_add(k.n_coef().checked_mul(d.dim)?));
        }
        let consistent = d.ts.len() == n + 1
            && d.h.len() == n
            && d.kind.len() == n
            && Some(d.y_old.len()) == n.checked_mul(d.dim)
            && Some(d.q.len()) == total;
        if !consistent {
            return Err(format!(
                "inconsistent dense output: {n} segments of dimension {}, {} breakpoints, {} steps, {} kinds, {} states, {} coefficients",
                d.dim,
                d.ts.len(),
                d.h.len(),
                d.kind.len(),
                d.y_old.len(),
                d.q.len()
            ));
        }
        Ok(DenseOutput {
            dim: d.dim,
            ts: d.ts,
            t_old: d.t_old,
            h: d.h,
            y_old: d.y_old,
            q: d.q,
            kind: d.kind,
            offset,
        })
    }
}

impl DenseOutput {
    pub(crate) fn new(dim: usize, t0: f64) -> Self {
        Self {
            dim,
            ts: vec![t0],
            t_old: Vec::new(),
            h: Vec::new(),
            y_old: Vec::new(),
            q: Vec::new(),
            kind: Vec::new(),
            offset: Vec::new(),
        }
    }

    /// Append an RK45 step's interpolant; its breakpoint follows via `push_breakpoint`.
    #[cfg(test)]
    pub(crate) fn push_segment(&mut self, t_old: f64, h: f64, y_old: &[f64], q: &[f64]) {
        self.push(Interpolant::Rk45, t_old, h, y_old, q);
    }

    /// Append a step's interpolant of kind `kind` (`q`: `kind.n_coef() · dim` values).
    pub(crate) fn push(&mut self, kind: Interpolant, t_old: f64, h: f64, y_old: &[f64], q: &[f64]) {
        debug_assert_eq!(q.len(), kind.n_coef() * self.dim);
        self.t_old.push(t_old);
        self.h.push(h);
        self.y_old.extend_from_slice(y_old);
        self.offset.push(self.q.len());
        self.kind.push(kind);
        self.q.extend_from_slice(q);
    }

    pub(crate) fn push_breakpoint(&mut self, t: f64) {
        self.ts.push(t);
    }

    pub(crate) fn pop_segment(&mut self) {
        let n = self.t_old.len() - 1;
        self.t_old.truncate(n);
        self.h.truncate(n);
        self.y_old.truncate(n * self.dim);
        self.q.truncate(self.offset[n]);
        self.kind.truncate(n);
        self.offset.truncate(n);
    }

    /// The interpolant kind of segment `i`.
    pub fn kind(&self, i: usize) -> Interpolant {
        self.kind[i]
    }

    pub fn dim(&self) -> usize {
        self.dim
    }

    pub fn n_segments(&self) -> usize {
        self.t_old.len()
    }

    /// t0, then the end of every segment.
    pub fn breakpoints(&self) -> &[f64] {
        &self.ts
    }

    /// Index of the segment used for `t` (SciPy `OdeSolution._call_single`, `alt_segment=False`).
    pub fn segment_index(&self, t: f64) -> usize {
        let n = self.n_segments();
        assert!(n > 0, "DenseOutput has no segments");
        let ts = &self.ts;
        let ascending = ts[ts.len() - 1] >= ts[0];
        if ascending {
            // searchsorted(ts, t, side="left")
            let ind = ts.partition_point(|&v| v < t);
            ind.saturating_sub(1).min(n - 1)
        } else {
            // searchsorted(ts[::-1], t, side="right") = number of breakpoints <= t
            let ind = ts.iter().filter(|&&v| v <= t).count();
            n - 1 - ind.saturating_sub(1).min(n - 1)
        }
    }

    /// Interpolated state at `t` into `out` (length `dim`). Panics if there are no segments.
    pub fn eval_into(&self, t: f64, out: &mut [f64]) {
        let s = self.segment_index(t);
        let d = self.dim;
        let kind = self.kind[s];
        let q0 = self.offset[s];
        kind.eval(
            self.t_old[s],
            self.h[s],
            &self.y_old[s * d..(s + 1) * d],
            &self.q[q0..q0 + kind.n_coef() * d],
            t,
            out,
        );
    }

    /// Interpolated state at `t`. Panics if there are no segments.
    pub fn eval(&self, t: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.dim];
        self.eval_into(t, &mut out);
        out
    }

    /// The states at `ts`, `dim × ts.len()` row-major (one column per time, as SciPy's
    /// `OdeSolution`). Refuses a non-finite time, and a state that is not finite: outside
    /// the integrated interval the interpolant extrapolates, and overflows far away. Panics
    /// if there are no segments.
    pub fn sample(&self, ts: &[f64]) -> crate::support::error::Result<Vec<f64>> {
        if self.n_segments() == 0 {
            let t0 = self.ts.first().copied().unwrap_or(f64::NAN);
            return Err(Error::Simulation(format!("sol(t): the run ended at t = {t0} before its first step, so there is nothing to interpolate")));
        }
        if let Some(bad) = ts.iter().find(|x| !x.is_finite()) {
            return Err(Error::arg("t", "finite times", bad.to_string()));
        }
        let (n, mut buf) = (ts.len(), vec![0.0; self.dim]);
        let mut out = vec![0.0; self.dim * n];
        for (j, &t) in ts.iter().enumerate() {
            self.eval_into(t, &mut buf);
            if buf.iter().any(|v| !v.is_finite()) {
                let (a, b) = (self.ts[0], self.ts[self.ts.len() - 1]);
                let (lo, hi) = (a.min(b), a.max(b));
                return Err(Error::Numerical(format!("sol(t): the dense output at t = {t:e} is not finite: it extrapolates the solution on [{lo}, {hi}] far outside it")));
            }
            for (i, y) in buf.iter().enumerate() {
                out[i * n + j] = *y;
            }
        }
        Ok(out)
    }

    /// `sol(t)` as its caller writes `t`: one time (shape `()`) or a 1-D array of `m`; the
    /// states ([`DenseOutput::sample`]) and `Some(m)` for an array.
    pub fn sample_arg<A: Arg>(&self, t: &A) -> Result<(Vec<f64>, Option<usize>), A::Err> {
        let (shape, ts) = t.array("t")?;
        if shape.len() > 1 {
            return Err(Error::arg("t", "a scalar or a 1-D array", shape_str(&shape)).into());
        }
        Ok((self.sample(&ts)?, shape.first().copied()))
    }
}

#[cfg(test)]
#[path = "tests/dense.rs"]
mod tests;
