//! The Jacobian's stiffness test ([`super::SpectralCheck`]) against known spectra.
use super::{SpectralCheck, EVERY, FIRST, ITERATIONS, RUN};
use crate::integrator::tests::fixtures::tol;
use crate::integrator::{rk45, FnSystem, OdeSystem, SolverOptions, StiffnessCheck};

/// `y' = A y` with `A = Q diag(d) Qᵀ`, `Q` a rotation that mixes every axis: the dominant
/// eigenvalue is `d[0]` whatever the start direction.
fn linear(d: [f64; 3]) -> impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), String> {
    let (c, s) = (0.6f64, 0.8f64);
    // Q = R_x(θ) R_z(θ) with cos θ = 0.6.
    let q = [[c, -s, 0.0], [c * s, c * c, -s], [s * s, s * c, c]];
    let mut a = [[0.0; 3]; 3];
    for (i, row) in a.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| q[i][k] * d[k] * q[j][k]).sum();
        }
    }
    move |_t, y: &[f64], dy: &mut [f64]| {
        for i in 0..3 {
            dy[i] = (0..3).map(|j| a[i][j] * y[j]).sum();
        }
        Ok(())
    }
}

#[test]
fn power_iteration_finds_the_dominant_eigenvalue() {
    for d in [
        [-1000.0, -3.0, -1.0],
        [-2.0e5, 40.0, -7.0],
        [-5.0, -4.0, 0.5],
    ] {
        let mut f = linear(d);
        let y = [0.3, -1.2, 2.0];
        let mut fy = [0.0; 3];
        f(0.0, &y, &mut fy).unwrap();
        let mut sys = FnSystem::new(3, f);
        let mut check = SpectralCheck::new(3);
        check.v.copy_from_slice(&[1.0, 0.5, -0.25]);
        let mut nfev = 0;
        let rho = check
            .spectral_radius(&mut sys, &mut nfev, 0.0, &y, &fy)
            .unwrap()
            .unwrap();
        assert_eq!(nfev, ITERATIONS);
        // After three steps the others' share has shrunk by (|d1|/|d0|)³: exact for the
        // separated spectra, within 10 % for −5 against −4.
        let bound = if d[0] == -5.0 { 0.1 } else { 1e-6 };
        assert!((rho / d[0].abs() - 1.0).abs() < bound, "{d:?}: rho = {rho}");
    }
}

#[test]
fn a_detection_takes_run_checks_in_a_row() {
    let f = linear([-1000.0, -3.0, -1.0]);
    let mut sys = FnSystem::new(3, f);
    let mut check = SpectralCheck::new(3);
    let y = [1.0, 1.0, 1.0];
    let mut fy = [0.0; 3];
    sys.rhs(0.0, &y, &mut fy).unwrap();
    let stage = [0.9, 1.1, 1.0];
    let mut nfev = 0;
    let mut at = |check: &mut SpectralCheck, h: f64| {
        let r = check.check(&mut sys, &mut nfev, 0.0, &y, &fy, &stage, h, 2.0);
        r.unwrap()
    };
    // h·ρ = 3 above the limit twice, then 1 below: the run starts again.
    assert!(at(&mut check, 3e-3).is_none());
    assert!(at(&mut check, 3e-3).is_none());
    assert!(at(&mut check, 1e-3).is_none());
    for k in 1..=RUN {
        let fired = at(&mut check, 3e-3);
        assert_eq!(fired.is_some(), k == RUN, "check {k}");
        if let Some(h_rho) = fired {
            assert!((h_rho - 3.0).abs() < 1e-6, "{h_rho}");
        }
    }
    assert!(SpectralCheck::due(FIRST) && SpectralCheck::due(FIRST + EVERY));
    assert!(!SpectralCheck::due(FIRST - 1) && !SpectralCheck::due(FIRST + 1));
}

/// A non-stiff problem run long (a harmonic oscillator, `h·ρ ≈ 0.2`) with
/// `stiffness="stop"`: never stopped, the same steps as with the test off, and exactly
/// `ITERATIONS` more evaluations per check.
#[test]
fn non_stiff_runs_keep_their_steps_and_pay_three_evaluations_a_check() {
    let run = |check| {
        let opts = SolverOptions {
            stiffness: check,
            ..tol(1e-6)
        };
        let sys = FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1];
            dy[1] = -y[0];
            Ok(())
        });
        rk45(sys, (0.0, 100.0), &[1.0, 0.0], &opts, &mut []).unwrap()
    };
    let (off, stop) = (run(StiffnessCheck::Off), run(StiffnessCheck::Stop));
    assert!(stop.success() && stop.stiffness.is_none());
    assert_eq!((&off.t, &off.y), (&stop.t, &stop.y));
    let steps = off.t.len() - 1;
    assert!(steps > FIRST + 2 * EVERY, "{steps} steps: too few to check");
    let checks = (steps - FIRST) / EVERY + 1;
    assert_eq!(stop.nfev, off.nfev + ITERATIONS * checks);
}

/// An evaluation that fails inside a check (a Python `fun` raising, Ctrl-C) ends the run
/// after the accepted step, with that failure: never swallowed.
#[test]
fn a_failing_evaluation_in_a_check_ends_the_run() {
    // A third call in a row at one time is the check's: a step's last two stages are both
    // at its end (C = 1, the FSAL one), where the check comes next.
    let (mut last_t, mut same) = (f64::NAN, 0);
    let sys = FnSystem::new(2, move |t, y: &[f64], dy: &mut [f64]| {
        same = if t == last_t { same + 1 } else { 0 };
        last_t = t;
        if same == 2 {
            return Err("raised".into());
        }
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    });
    let opts = SolverOptions {
        stiffness: StiffnessCheck::Stop,
        ..tol(1e-6)
    };
    let sol = rk45(sys, (0.0, 100.0), &[1.0, 0.0], &opts, &mut []).unwrap();
    assert!(!sol.success(), "{}", sol.message);
    assert!(sol.message.contains("raised"), "{}", sol.message);
    assert_eq!(
        sol.t.len() - 1,
        FIRST,
        "ends after the step that ran the check"
    );
}
