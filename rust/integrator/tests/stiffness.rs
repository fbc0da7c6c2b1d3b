//! Stiffness detection (Hairer's DOPRI5 test) through `rk45`, `Stepper` and `simulate`.
use super::fixtures::{krogh, tol, SCIPY_KROGH};
use crate::integrator::*;

/// Prothero–Robinson: `y' = λ (y − cos t) − sin t`, exact `y = cos t` for `y(0) = 1`;
/// stiff for large `|λ|` once the (absent) transient is gone.
#[allow(clippy::type_complexity)]
fn prothero_robinson(
    lambda: f64,
) -> FnSystem<impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), String>> {
    FnSystem::new(1, move |t, y: &[f64], dy: &mut [f64]| {
        dy[0] = lambda * (y[0] - t.cos()) - t.sin();
        Ok(())
    })
}

fn with_stiffness(opts: SolverOptions, stiffness: StiffnessCheck) -> SolverOptions {
    SolverOptions { stiffness, ..opts }
}

#[test]
fn h_lambda_is_exact_on_a_linear_scalar_problem() {
    // y' = λ y: k7 − k6 = λ (y7 − y6) exactly, so the estimate is h·|λ| to round-off.
    let lambda = -37.0;
    let sys = FnSystem::new(1, move |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = lambda * y[0];
        Ok(())
    });
    let mut st = Stepper::new(sys, 0.0, &[1.0], 1.0, &tol(1e-6)).unwrap();
    assert!(st.h_lambda().is_nan());
    for _ in 0..5 {
        st.step().unwrap();
        let expected = st.step_size() * lambda.abs();
        assert!(
            (st.h_lambda() - expected).abs() <= 1e-9 * expected,
            "{} vs {expected}",
            st.h_lambda()
        );
    }
}

#[test]
fn stiff_linear_problem_is_detected_early_and_steps_are_unchanged() {
    let lambda = -1e4;
    let opts = tol(1e-6);
    let run = |check| {
        rk45(
            prothero_robinson(lambda),
            (0.0, 10.0),
            &[1.0],
            &with_stiffness(opts.clone(), check),
            &mut [],
        )
        .unwrap()
    };
    let off = run(StiffnessCheck::Off);
    let warn = run(StiffnessCheck::Warn);
    // Observing changes nothing: same steps, same values (SciPy compatibility).
    assert_eq!((&off.t, &off.y, off.nfev), (&warn.t, &warn.y, warn.nfev));
    assert!(off.stiffness.is_none() && off.success());
    assert!(!off.message.contains("stiff"));
    // The explicit method needs ~|λ| T / 3.3 steps here: the cost stiffness causes.
    assert!(warn.n_accepted as f64 > 0.2 * lambda.abs() * 10.0 / 3.3);
    let s = warn.stiffness.expect("detected");
    assert!(warn.success() && warn.status == Status::Success);
    assert!(s.t < 0.05, "detected late, at t = {}", s.t);
    assert!(s.h_lambda > STIFF_H_LAMBDA);
    // |λ| estimated within a few per cent (the Jacobian is exactly λ).
    assert!(
        (s.lambda() / lambda.abs() - 1.0).abs() < 0.05,
        "{}",
        s.lambda()
    );
    assert!(
        warn.message.starts_with("reached the end")
            && warn
                .message
                .contains("warning: the problem looks stiff from t = "),
        "{}",
        warn.message
    );
    // Still accurate: stability-limited steps are tiny, the error is far below tolerance.
    let y_end = warn.y[warn.y.len() - 1];
    assert!((y_end - 10f64.cos()).abs() < 1e-6);

    // Stop: ends at the detection, with the status naming it.
    let stop = run(StiffnessCheck::Stop);
    match stop.status {
        Status::Stiff { t, h_lambda, h } => {
            assert_eq!(t, s.t);
            assert_eq!(h_lambda, s.h_lambda);
            assert!(h > 0.0 && (h_lambda / h - s.lambda()).abs() < 1e-9 * s.lambda());
        }
        ref other => panic!("unexpected {other:?}"),
    }
    assert_eq!(stop.status.code(), -1);
    assert!(!stop.success());
    assert_eq!(stop.t_reached, s.t);
    assert_eq!(*stop.t.last().unwrap(), s.t);
    // The steps up to the detection are the same as without the check.
    let n = stop.t.len();
    assert_eq!(&stop.t[..], &off.t[..n]);
    assert!(n < 200, "{n} steps before stopping");
    assert!(
        stop.message.starts_with("the problem is stiff at t = ")
            && stop.message.contains("implicit"),
        "{}",
        stop.message
    );
}

#[test]
fn stiffness_and_max_steps_are_reported_together() {
    let opts = SolverOptions {
        max_steps: 500,
        ..tol(1e-6)
    };
    let sol = rk45(prothero_robinson(-1e5), (0.0, 10.0), &[1.0], &opts, &mut []).unwrap();
    assert!(matches!(
        sol.status,
        Status::MaxSteps { max_steps: 500, .. }
    ));
    assert_eq!(sol.n_accepted, 500);
    assert!(sol.stiffness.is_some());
    assert!(
        sol.message
            .starts_with("maximum number of steps (500) reached")
            && sol.message.contains("looks stiff"),
        "{}",
        sol.message
    );
}

#[test]
fn stop_with_stepper_fails_on_the_call_after_the_detection() {
    let opts = with_stiffness(tol(1e-6), StiffnessCheck::Stop);
    let mut st = Stepper::new(prothero_robinson(-1e4), 0.0, &[1.0], 10.0, &opts).unwrap();
    let mut n = 0;
    let err = loop {
        match st.step() {
            Ok(StepOutcome::Accepted) => n += 1,
            Ok(StepOutcome::Finished) => panic!("should have stopped"),
            Err(e) => break e,
        }
        assert!(n < 10_000);
    };
    assert!(matches!(err, Status::Stiff { t, .. } if t == st.t()));
    assert_eq!(st.n_accepted(), n);
    assert_eq!(st.stiffness().unwrap().t, st.t());
    assert_eq!(st.step(), Err(err.clone()));
    assert_eq!(st.failure(), Some(&err));
}

#[test]
fn non_stiff_problems_are_not_flagged() {
    for &(tl, ..) in SCIPY_KROGH.iter() {
        let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(tl), &mut []).unwrap();
        assert!(sol.stiffness.is_none(), "Krogh at {tl}");
    }
    // Loose tolerances give the largest h·|λ|.
    for tl in [1e-2, 1e-3, 1e-4] {
        let sol = rk45(krogh(), (0.0, 60.0), &[0.0, 1.0, 1.0], &tol(tl), &mut []).unwrap();
        assert!(sol.stiffness.is_none(), "Krogh at {tl}");
        let osc = FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = 50.0 * y[1];
            dy[1] = -50.0 * y[0];
            Ok(())
        });
        let sol = rk45(osc, (0.0, 20.0), &[1.0, 0.0], &tol(tl), &mut []).unwrap();
        assert!(sol.stiffness.is_none(), "oscillator at {tl}");
    }
    // A stiff transient that the tolerance must resolve (h·|λ| small while it lasts) and
    // then dies: y' = -1e3 y from y = 1 over a span where it never decays to atol is not
    // stability-limited.
    let sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = -1e3 * y[0];
        Ok(())
    });
    let sol = rk45(sys, (0.0, 5e-3), &[1.0], &tol(1e-10), &mut []).unwrap();
    assert!(sol.stiffness.is_none());
}

#[test]
fn stiff_joint_spring_scene_is_detected_through_simulate() {
    // A 1 kg, 0.3 m link on a revolute joint with a stiff spring and a strong damper:
    // eigenvalues ≈ −c/I and −k/c, i.e. a fast decaying mode the explicit method must keep
    // stable while the slow one sets the time scale.
    let text = r#"
name = "stiff spring"
[[body]]
name = "link"
joint = { type = "Revolute", axis = [0.0, 1.0, 0.0] }
mass = 1.0
com = [0.15, 0.0, 0.0]
inertia_diag = [1e-3, 7.5e-3, 7.5e-3]
q0 = [0.3]
[[effect]]
type = "gravity"
g = [0.0, 0.0, -9.81]
[[effect]]
type = "spring"
stiffness = 1e4
[[effect]]
type = "damper"
damping = 3e3
"#;
    let scene = crate::io::scene::Scene::from_toml(text, "stiff.toml").unwrap();
    let run = |check, max_steps| {
        let opts = SolverOptions {
            stiffness: check,
            max_steps,
            ..tol(1e-8)
        };
        crate::simulate::simulate(
            &scene.model,
            &scene.effects,
            crate::effects::Disabled::none(),
            &scene.q0,
            &scene.v0,
            (0.0, 2.0),
            &opts,
            &[],
            Vec::new(),
            crate::simulate::Record::default(),
            None,
        )
        .unwrap()
    };
    // I_O = 7.5e-3 + 1·0.15² = 0.03: fast eigenvalue ≈ −c / I_O = −1e5.
    let stop = run(StiffnessCheck::Stop, 1_000_000);
    match stop.status {
        Status::Stiff { t, h_lambda, h } => {
            assert!(t < 0.01, "{t}");
            let lambda = h_lambda / h;
            assert!((lambda / 1e5 - 1.0).abs() < 0.1, "|λ| ≈ {lambda}");
        }
        ref s => panic!("unexpected {s:?}"),
    }
    assert!(stop.n_accepted < 500 && !stop.success);
    // Warn with a step budget: stops at max_steps, and says why so many were needed.
    let warn = run(StiffnessCheck::Warn, 2000);
    assert!(matches!(warn.status, Status::MaxSteps { .. }));
    assert!(warn.message.contains("looks stiff"), "{}", warn.message);
    // Off: the same run without the remark.
    let off = run(StiffnessCheck::Off, 2000);
    assert_eq!(off.t, warn.t);
    assert!(!off.message.contains("stiff"), "{}", off.message);
}

#[test]
fn stiffness_estimate_survives_huge_values_and_times_read_well() {
    // y' = λ y with |y| ~ 1e200: squared sums would overflow; the estimate must not.
    let lambda = -50.0;
    let sys = FnSystem::new(2, move |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = lambda * y[0];
        dy[1] = lambda * y[1];
        Ok(())
    });
    let opts = SolverOptions {
        first_step: Some(1e-3),
        ..tol(1e-6)
    };
    let mut st = Stepper::new(sys, 0.0, &[1e200, -3e199], 1.0, &opts).unwrap();
    st.step().unwrap();
    let expected = st.step_size() * lambda.abs();
    assert!(
        (st.h_lambda() - expected).abs() <= 1e-9 * expected,
        "{}",
        st.h_lambda()
    );
    assert_eq!(fmt_time(0.0), "0");
    assert_eq!(fmt_time(10.0), "10");
    assert_eq!(fmt_time(0.5), "0.5");
    assert_eq!(fmt_time(2.5e-73), "2.5e-73");
    assert_eq!(fmt_time(-3e20), "-3e20");
    let st = Status::MaxSteps {
        t: 1e-9,
        max_steps: 3,
    };
    assert_eq!(
        st.describe(1e-9),
        "maximum number of steps (3) reached at t = 1e-9"
    );
}
