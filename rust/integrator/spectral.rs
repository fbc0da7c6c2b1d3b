//! A second stiffness test for the explicit phase of `auto` (and `stiffness="stop"`): the
//! spectral radius `ρ` of the right-hand side's Jacobian by a few steps of power iteration,
//! each a finite difference along the iterate, every [`EVERY`] accepted steps from step
//! [`FIRST`] on; [`RUN`] checks in a row with `h·ρ` above [`FRACTION`] of the method's limit
//! for Hairer's estimate make a detection.
//!
//! Hairer's test reads `h·|λ|` off the difference of two stage states, which a saturating
//! right-hand side hides: regularised friction in its stick phase pushes the stages into
//! its flat part. On `solo12_standing` at rtol 1e-3 RK45 took 47 852 steps of ~40 µs to
//! reach 2 s with Hairer's estimate near 0.3 on most of them, while the Jacobian's `h·ρ` was
//! 3.7 (its eigenvalues ~ −1e5): every step sat at the method's stability limit and Radau
//! needs 62 steps. At rtol 1e-4 the steps settle inside the limit, `h·ρ` 1.8–2.9, and still
//! take 128 444 steps where Radau takes 81: the stiff modes are resolved though the solution
//! no longer needs them, hence a limit below the stability edge. On the non-stiff bundled
//! scenes `h·ρ` stayed below 1.6 at every rtol from 1e-3 to 1e-8
//! (benches/stiffness_spectral.py).
//!
//! Cost: [`ITERATIONS`] evaluations a check, about 2.5 % of RK45's past step 100. So the
//! test runs only where a detection stops the run (`StiffnessCheck::Stop`, what `auto`
//! runs): RK45 asked by name keeps SciPy's evaluations. Systems kept on manifolds (closed
//! loops) skip it: a random-ish direction leaves the manifolds, where the constraint
//! stabilisation's own fast modes would read as stiffness.
use super::{OdeSystem, Status};

/// Accepted steps before the first check: short runs never pay for it.
pub(super) const FIRST: usize = 100;
/// Accepted steps between checks.
pub(super) const EVERY: usize = 20;
/// Checks in a row above the limit that make a detection.
pub(super) const RUN: usize = 3;
/// The part of the method's limit on Hairer's estimate (`Tableau::STIFF_H_LAMBDA`: 3.25 for
/// RK45) above which a check counts: 2.44 for RK45, against 1.6 at most on non-stiff scenes.
pub(super) const FRACTION: f64 = 0.75;
/// Power-iteration steps (right-hand-side evaluations) a check.
pub(super) const ITERATIONS: usize = 3;

/// The check's workspace (three state-sized vectors, allocated once) and its counter.
#[derive(Debug, Clone)]
pub(super) struct SpectralCheck {
    v: Vec<f64>,
    y: Vec<f64>,
    w: Vec<f64>,
    run: usize,
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|a| a * a).sum::<f64>().sqrt()
}

impl SpectralCheck {
    pub(super) fn new(dim: usize) -> Self {
        Self {
            v: vec![0.0; dim],
            y: vec![0.0; dim],
            w: vec![0.0; dim],
            run: 0,
        }
    }

    /// Whether a check is due once `accepted` steps are done.
    pub(super) fn due(accepted: usize) -> bool {
        accepted >= FIRST && (accepted - FIRST) % EVERY == 0
    }

    /// One check at the accepted state `y` (derivative `fy`) after a step of size `h`,
    /// iterating from the direction `y − y_stage` (the last stage state: the step's own
    /// difference, as Hairer's test). Returns `h·ρ` when this check completes a detection
    /// (`RUN` in a row above `limit`). Evaluations are counted in `nfev`; one that is not
    /// finite skips the check, one that fails ends the run as a stage's would (a Python
    /// `fun` raising, Ctrl-C: never swallowed).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn check<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        nfev: &mut usize,
        t: f64,
        y: &[f64],
        fy: &[f64],
        y_stage: &[f64],
        h: f64,
        limit: f64,
    ) -> Result<Option<f64>, Status> {
        for ((v, a), b) in self.v.iter_mut().zip(y).zip(y_stage) {
            *v = a - b;
        }
        let Some(rho) = self.spectral_radius(sys, nfev, t, y, fy)? else {
            return Ok(None);
        };
        let h_rho = h * rho;
        if h_rho > limit {
            self.run += 1;
        } else {
            self.run = 0;
        }
        Ok((self.run == RUN).then_some(h_rho))
    }

    /// `ρ ≈ |J v|` after [`ITERATIONS`] steps `v ← J v / |J v|` from `self.v`, with `J v`
    /// the forward difference along `v` (step `√ε·max(1, |y|)`); None when no estimate, an
    /// error when an evaluation fails.
    pub(super) fn spectral_radius<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        nfev: &mut usize,
        t: f64,
        y: &[f64],
        fy: &[f64],
    ) -> Result<Option<f64>, Status> {
        let eps = f64::EPSILON.sqrt() * norm(y).max(1.0);
        let mut rho = None;
        for _ in 0..ITERATIONS {
            let nv = norm(&self.v);
            if !(nv > 0.0 && nv.is_finite()) {
                return Ok(rho);
            }
            let c = eps / nv;
            for ((p, a), v) in self.y.iter_mut().zip(y).zip(&self.v) {
                *p = a + c * v;
            }
            *nfev += 1;
            sys.rhs(t, &self.y, &mut self.w)
                .map_err(|message| Status::RhsError { t, at: t, message })?;
            for (w, f) in self.w.iter_mut().zip(fy) {
                *w = (*w - f) / eps;
            }
            let r = norm(&self.w);
            if !r.is_finite() {
                return Ok(None);
            }
            rho = Some(r);
            std::mem::swap(&mut self.v, &mut self.w);
        }
        Ok(rho)
    }
}

#[cfg(test)]
#[path = "tests/spectral.rs"]
mod tests;
