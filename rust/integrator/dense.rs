//! SciPy RK45's dense output: per step the quartic `y(t) = y_old + h · Q p(x)`, with
//! `x = (t - t_old) / h`, `p = (x, x², x³, x⁴)` and `Q = Kᵀ P` (Shampine 1986, optimal c6).

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
    q: Vec<f64>,
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
}

impl TryFrom<DenseData> for DenseOutput {
    type Error = String;
    fn try_from(d: DenseData) -> Result<Self, String> {
        let n = d.t_old.len();
        let consistent = d.ts.len() == n + 1
            && d.h.len() == n
            && Some(d.y_old.len()) == n.checked_mul(d.dim)
            && Some(d.q.len()) == n.checked_mul(d.dim).and_then(|x| x.checked_mul(4));
        if !consistent {
            return Err(format!(
                "inconsistent dense output: {n} segments of dimension {}, {} breakpoints, {} steps, {} states, {} coefficients",
                d.dim,
                d.ts.len(),
                d.h.len(),
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
        }
    }

    /// Append a step's interpolant; its breakpoint follows via `push_breakpoint`.
    pub(crate) fn push_segment(&mut self, t_old: f64, h: f64, y_old: &[f64], q: &[f64]) {
        self.t_old.push(t_old);
        self.h.push(h);
        self.y_old.extend_from_slice(y_old);
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
        self.q.truncate(4 * n * self.dim);
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
        eval_segment(
            self.t_old[s],
            self.h[s],
            &self.y_old[s * d..(s + 1) * d],
            &self.q[4 * s * d..4 * (s + 1) * d],
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::stepper::B;
    use crate::integrator::{rk45, FnSystem, Rk45Options, Tol};

    #[allow(clippy::type_complexity)]
    fn oscillator() -> FnSystem<impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), String>> {
        // y1 = sin t, y2 = cos t
        FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1];
            dy[1] = -y[0];
            Ok(())
        })
    }

    #[test]
    fn interpolant_reproduces_the_step_weights() {
        // p(1) = (1,1,1,1): the rows of P must sum to the 5th-order weights B (b7 = 0),
        // and p'(0) = (1,0,0,0): y'(t_old) = k1.
        for s in 0..7 {
            let sum: f64 = P[s].iter().sum();
            let b = if s < 6 { B[s] } else { 0.0 };
            assert!((sum - b).abs() < 1e-15, "row {s}: {sum} vs {b}");
            assert_eq!(P[s][0], if s == 0 { 1.0 } else { 0.0 });
        }
    }

    #[test]
    fn dense_matches_step_end_points() {
        let opts = Rk45Options {
            rtol: 1e-8.into(),
            atol: 1e-8.into(),
            dense: true,
            ..Default::default()
        };
        let sol = rk45(oscillator(), (0.0, 10.0), &[0.0, 1.0], &opts, &mut []).unwrap();
        let d = sol.dense.as_ref().unwrap();
        assert_eq!(d.n_segments() + 1, sol.t.len());
        assert_eq!(d.breakpoints(), &sol.t[..]);
        for (i, &t) in sol.t.iter().enumerate() {
            let yd = sol.dense_eval(t).unwrap();
            for (a, b) in yd.iter().zip(sol.state(i)) {
                // x = 1 gives y_old + h·Σ(P rows)·K = y_new up to round-off (x = 0 is exact).
                assert!(
                    (a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0),
                    "t={t}: {a} vs {b}"
                );
            }
        }
        // Start of each segment is exact: the segment after a breakpoint, evaluated at its start.
        for s in 0..d.n_segments() {
            let mut out = [0.0; 2];
            let dd = 2;
            eval_segment(
                d.t_old[s],
                d.h[s],
                &d.y_old[s * dd..s * dd + 2],
                &d.q[8 * s..8 * s + 8],
                sol.t[s],
                &mut out,
            );
            assert_eq!(&out[..], sol.state(s));
        }
    }

    /// Max error at step midpoints of the interpolant with fixed steps `h`.
    fn midpoint_error(h: f64) -> f64 {
        let opts = Rk45Options {
            rtol: 1e-3.into(),
            atol: Tol::Scalar(1e-3),
            max_step: h,
            first_step: Some(h),
            dense: true,
            ..Default::default()
        };
        let sol = rk45(oscillator(), (0.0, 4.0), &[0.0, 1.0], &opts, &mut []).unwrap();
        assert_eq!(
            sol.n_accepted,
            (4.0 / h) as usize,
            "steps must be the fixed size"
        );
        assert_eq!(sol.n_rejected, 0);
        let mut err: f64 = 0.0;
        for w in sol.t.windows(2) {
            let tm = 0.5 * (w[0] + w[1]);
            let y = sol.dense_eval(tm).unwrap();
            err = err
                .max((y[0] - tm.sin()).abs())
                .max((y[1] - tm.cos()).abs());
        }
        err
    }

    #[test]
    fn dense_is_fourth_order_at_midpoints() {
        let errs: Vec<f64> = [0.25, 0.125, 0.0625, 0.03125]
            .iter()
            .map(|&h| midpoint_error(h))
            .collect();
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            // Local interpolation error O(h^5) (4th-order interpolant) on top of the
            // O(h^5) global error; must be clearly above 4.
            assert!(
                order > 4.3 && order < 5.7,
                "observed order {order}, errors {errs:?}"
            );
        }
        assert!(errs[3] < 1e-8, "{errs:?}");
    }

    #[test]
    fn segment_selection_follows_scipy() {
        let mut d = DenseOutput::new(1, 0.0);
        for (a, b) in [(0.0, 1.0), (1.0, 2.0), (2.0, 3.0)] {
            d.push_segment(a, b - a, &[0.0], &[0.0; 4]);
            d.push_breakpoint(b);
        }
        assert_eq!(d.segment_index(-1.0), 0);
        assert_eq!(d.segment_index(0.0), 0);
        assert_eq!(d.segment_index(1.0), 0); // on a breakpoint: the earlier segment
        assert_eq!(d.segment_index(1.5), 1);
        assert_eq!(d.segment_index(3.0), 2);
        assert_eq!(d.segment_index(9.0), 2);
        let mut b = DenseOutput::new(1, 3.0);
        for (a, e) in [(3.0, 2.0), (2.0, 1.0), (1.0, 0.0)] {
            b.push_segment(a, e - a, &[0.0], &[0.0; 4]);
            b.push_breakpoint(e);
        }
        assert_eq!(b.segment_index(3.5), 0);
        assert_eq!(b.segment_index(2.0), 0); // earlier segment in integration order
        assert_eq!(b.segment_index(1.5), 1);
        assert_eq!(b.segment_index(1.0), 1);
        assert_eq!(b.segment_index(-1.0), 2);
    }
}
