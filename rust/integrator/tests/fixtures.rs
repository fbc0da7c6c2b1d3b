//! Systems and options shared by the integrator's tests.
use crate::integrator::{FnSystem, SolverOptions};

/// An `FnSystem` built from a plain closure.
pub(crate) type TestSystem = FnSystem<fn(f64, &[f64], &mut [f64]) -> Result<(), String>>;

/// Krogh's rigid-body problem (Euler's equations; the exact solution is Jacobi's elliptic
/// functions sn, cn, dn with m = 0.51 from y0 = (0, 1, 1)).
pub(crate) fn krogh() -> TestSystem {
    FnSystem::new(3, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1] * y[2];
        dy[1] = -y[0] * y[2];
        dy[2] = -0.51 * y[0] * y[1];
        Ok(())
    })
}

/// SciPy 1.17 `solve_ivp(krogh, (0, 12), [0, 1, 1], rtol=tol, atol=tol)`: tol, nfev, steps, y(12).
pub(crate) const SCIPY_KROGH: [(f64, usize, usize, [f64; 3]); 4] = [
    (
        1e-6,
        290,
        40,
        [-0.7053837295840913, -0.7088187876243793, 0.8638491355867974],
    ),
    (
        1e-8,
        608,
        96,
        [-0.7053976933189424, -0.708811680790365, 0.8638467076303797],
    ),
    (
        1e-10,
        1430,
        238,
        [-0.705397808403615, -0.708811632881521, 0.86384669051326],
    ),
    (
        1e-12,
        3584,
        597,
        [-0.7053978095115906, -0.7088116324711137, 0.8638466903715681],
    ),
];

/// The harmonic oscillator `y0' = y1, y1' = −y0`: `(sin t, cos t)` from `(0, 1)`,
/// `(cos t, −sin t)` from `(1, 0)`.
pub(crate) fn oscillator() -> TestSystem {
    FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    })
}

/// Exponential decay `y' = −y`.
pub(crate) fn decay() -> TestSystem {
    FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = -y[0];
        Ok(())
    })
}

/// Default options with `rtol = atol = tol`.
pub(crate) fn tol(tol: f64) -> SolverOptions {
    SolverOptions {
        rtol: tol.into(),
        atol: tol.into(),
        ..Default::default()
    }
}

/// `error(h)` at the fixed steps h = 1/4, 1/8, 1/16, 1/32.
pub(crate) fn at_halved_steps(error: impl Fn(f64) -> f64) -> Vec<f64> {
    [0.25, 0.125, 0.0625, 0.03125].map(error).to_vec()
}

/// The convergence orders `log2(e[i] / e[i+1])` of errors at halved step sizes.
pub(crate) fn observed_orders(errs: &[f64]) -> Vec<f64> {
    errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}
