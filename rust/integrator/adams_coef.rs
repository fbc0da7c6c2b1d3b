//! The coefficients of the variable-step Adams formulas in modified divided differences
//! (Shampine & Gordon, *Computer Solution of Ordinary Differential Equations*, 1975, ch. 5;
//! their code `STEP`, block 1, and `INTRP`): `ψ`, `α`, `β`, `σ` of the step-size history and
//! the integration coefficients `g`, recomputed only where the step size changed (`ns`, the
//! steps taken at the current size, bounds what is constant). Arrays are indexed from 1 as in
//! the book (entry 0 unused) so the recurrences read as written there.

/// Highest order.
pub(crate) const KMAX: usize = 12;

/// `γ*` of the error estimates at constant step (Shampine & Gordon's `gstr`).
pub(crate) const GSTR: [f64; KMAX + 2] = [
    0.0, 0.500, 0.0833, 0.0417, 0.0264, 0.0188, 0.0143, 0.0114, 0.00936, 0.00789, 0.00679, 0.00592,
    0.00524, 0.00468,
];

/// `2^i` (the step is doubled when the error at the new order is below `2^-(k+1)`).
pub(crate) const TWO: [f64; KMAX + 2] = [
    1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0, 2048.0, 4096.0, 8192.0,
];

/// Where the PECE pair of order `k` (Adams–Bashforth `k`-step predictor, Adams–Moulton
/// corrector of order `k + 1`, local extrapolation) stops being stable on the negative real
/// axis at constant step: `h λ ≥ −STABILITY[k]`. Computed from the constant-step companion
/// matrix (spectral radius 1; docs/integrators.md). Entry 12 is bounded by a small instability
/// bubble near the origin.
pub(crate) const STABILITY: [f64; KMAX + 1] = [
    0.0, 2.0, 2.4, 1.93, 1.41, 1.04, 0.77, 0.58, 0.44, 0.34, 0.26, 0.21, 0.062,
];

/// The step-size history and the coefficients of the next step.
#[derive(Debug, Clone)]
pub(crate) struct Coefficients {
    /// `ψ_i = x_{n+1} − x_{n+1−i}` (after the step's update).
    pub psi: [f64; KMAX + 1],
    pub alpha: [f64; KMAX + 1],
    pub beta: [f64; KMAX + 1],
    pub sig: [f64; KMAX + 2],
    pub g: [f64; KMAX + 2],
    v: [f64; KMAX + 2],
    w: [f64; KMAX + 2],
    /// Steps taken at the current size (including the current one), at most `kold + 1`.
    pub ns: usize,
}

impl Coefficients {
    pub fn new() -> Self {
        let mut c = Coefficients {
            psi: [0.0; KMAX + 1],
            alpha: [0.0; KMAX + 1],
            beta: [0.0; KMAX + 1],
            sig: [0.0; KMAX + 2],
            g: [0.0; KMAX + 2],
            v: [0.0; KMAX + 2],
            w: [0.0; KMAX + 2],
            ns: 0,
        };
        c.g[1] = 1.0;
        c.g[2] = 0.5;
        c.sig[1] = 1.0;
        c
    }

    /// `STEP`'s block 1: the coefficients of a step of size `h` at order `k` after steps of
    /// size `hold` at order `kold`. Only the entries a step-size change alters are recomputed.
    pub fn update(&mut self, k: usize, kold: usize, h: f64, hold: f64) {
        // `h == hold` exactly: the same step size (a clipped step changes it).
        if h != hold {
            self.ns = 0;
        }
        if self.ns <= kold {
            self.ns += 1;
        }
        let ns = self.ns;
        if k < ns {
            return;
        }
        self.beta[ns] = 1.0;
        self.alpha[ns] = 1.0 / ns as f64;
        let mut temp1 = h * ns as f64;
        self.sig[ns + 1] = 1.0;
        for i in ns + 1..=k {
            let temp2 = self.psi[i - 1];
            self.psi[i - 1] = temp1;
            self.beta[i] = self.beta[i - 1] * self.psi[i - 1] / temp2;
            temp1 = temp2 + h;
            self.alpha[i] = h / temp1;
            self.sig[i + 1] = i as f64 * self.alpha[i] * self.sig[i];
        }
        self.psi[k] = temp1;
        self.g_coefficients(k, kold, ns);
    }

    /// The `g` of block 1 through the work vectors `v` (kept between steps) and `w`.
    fn g_coefficients(&mut self, k: usize, kold: usize, ns: usize) {
        if ns <= 1 {
            for iq in 1..=k {
                self.v[iq] = 1.0 / (iq * (iq + 1)) as f64;
                self.w[iq] = self.v[iq];
            }
        } else {
            if k > kold {
                // The order was raised: the diagonal part of v.
                self.v[k] = 1.0 / (k * (k + 1)) as f64;
                for j in 1..=ns.saturating_sub(2) {
                    let i = k - j;
                    self.v[i] -= self.alpha[j + 1] * self.v[i + 1];
                }
            }
            let a = self.alpha[ns];
            for iq in 1..=k + 1 - ns {
                self.v[iq] -= a * self.v[iq + 1];
                self.w[iq] = self.v[iq];
            }
            self.g[ns + 1] = self.w[1];
        }
        for i in ns + 2..=k + 1 {
            let a = self.alpha[i - 1];
            for iq in 1..=k + 2 - i {
                self.w[iq] -= a * self.w[iq + 1];
            }
            self.g[i] = self.w[1];
        }
    }

    /// After a rejected step of size `h` at order `k`: `ψ` as before it (block 3).
    pub fn restore_psi(&mut self, k: usize, h: f64) {
        for i in 2..=k {
            self.psi[i - 1] = self.psi[i] - h;
        }
    }
}

/// `INTRP`'s coefficients as polynomials in `s = (t − x) / h` over the last step (`x` its end,
/// `h` its size): the solution there is `y(x) + s h Σ_{i=1}^{kold+1} G_i(s) φ_i`, and
/// `gs[i][d]` is the coefficient of `s^d` in `G_i` (degree `i − 1`).
pub(crate) fn interpolation_polynomials(
    kold: usize,
    psi: &[f64; KMAX + 1],
    h: f64,
    gs: &mut [[f64; KMAX + 2]; KMAX + 2],
) {
    let ki = kold + 1;
    // w[i] as a polynomial in s, w[i][d]; starts at the constants 1/i.
    let mut w = [[0.0f64; KMAX + 2]; KMAX + 3];
    for (i, wi) in w.iter_mut().enumerate().take(ki + 1).skip(1) {
        *wi = [0.0; KMAX + 2];
        wi[0] = 1.0 / i as f64;
    }
    for g in gs.iter_mut() {
        *g = [0.0; KMAX + 2];
    }
    gs[1][0] = 1.0;
    let mut term = 0.0;
    for j in 2..=ki {
        let p = psi[j - 1];
        // gamma = (s h + term) / p, eta = s h / p.
        let (g1, g0, e1) = (h / p, term / p, h / p);
        for i in 1..=ki + 1 - j {
            let (a, b) = (w[i], w[i + 1]);
            let mut out = [0.0; KMAX + 2];
            for d in 0..j {
                out[d] += g0 * a[d];
                out[d + 1] += g1 * a[d] - e1 * b[d];
            }
            w[i] = out;
        }
        gs[j] = w[1];
        term = p;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At a constant step the `g_i` are the Adams–Bashforth coefficients `γ_{i−1}`
    /// (Hairer, Nørsett & Wanner I, III.1: `γ_j = 1 − Σ_{i<j} γ_i / (j + 1 − i)`; 1, 1/2,
    /// 5/12, 3/8, 251/720, …) and `σ_i = 1`.
    #[test]
    fn constant_step_coefficients_are_adams_bashforth() {
        let mut gamma = [0.0f64; KMAX + 1];
        for j in 0..=KMAX {
            gamma[j] = 1.0 - (0..j).map(|i| gamma[i] / (j + 1 - i) as f64).sum::<f64>();
        }
        assert!((gamma[4] - 251.0 / 720.0).abs() < 1e-15);
        let h = 0.37;
        let mut c = Coefficients::new();
        let (mut k, mut kold) = (1, 0);
        // Raise the order by one each step at the same h (as the start-up does, but without
        // doubling), then hold it until the history is all at h.
        for step in 0..40 {
            c.update(k, kold, h, if step == 0 { 0.0 } else { h });
            kold = k;
            if k < KMAX {
                k += 1;
            }
        }
        for i in 1..=KMAX + 1 {
            assert!(
                (c.g[i] - gamma[i - 1]).abs() < 1e-13,
                "g[{i}] = {} against {}",
                c.g[i],
                gamma[i - 1]
            );
        }
        for i in 1..=KMAX + 1 {
            assert!((c.sig[i] - 1.0).abs() < 1e-13, "sig[{i}] = {}", c.sig[i]);
        }
    }
}
