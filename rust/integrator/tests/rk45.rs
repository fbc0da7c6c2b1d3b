//! The `rk45` driver: SciPy agreement, outputs, failures and input errors.
use super::fixtures::{krogh, tol, SCIPY_KROGH};
use crate::integrator::*;

/// Jacobi elliptic functions (sn, cn, dn)(u | m), 0 < m < 1, by the AGM / descending
/// Landen (Gauss) transformation in Bulirsch's stable form (as Numerical Recipes' `sncndn`);
/// the textbook `dn = cos φ0 / cos(φ1 - φ0)` loses digits near odd multiples of K.
fn ellipj(u: f64, m: f64) -> (f64, f64, f64) {
    const CA: f64 = 1e-8; // AGM converges quadratically: 1e-8 -> ~1e-16
    let (mut em, mut en) = ([0.0f64; 16], [0.0f64; 16]);
    let (mut a, mut emc, mut c, mut dn) = (1.0f64, 1.0 - m, 0.0f64, 1.0f64);
    let mut l = 0;
    for i in 0..16 {
        l = i;
        em[i] = a;
        emc = emc.sqrt();
        en[i] = emc;
        c = 0.5 * (a + emc);
        if (a - emc).abs() <= CA * a {
            break;
        }
        emc *= a;
        a = c;
    }
    let v = u * c;
    let (mut sn, mut cn) = (v.sin(), v.cos());
    if sn != 0.0 {
        let mut a = cn / sn;
        c *= a;
        for ii in (0..=l).rev() {
            let b = em[ii];
            a *= c;
            c *= dn;
            dn = (en[ii] + a) / (b + a);
            a = c / b;
        }
        let r = 1.0 / (c * c + 1.0).sqrt();
        sn = if sn >= 0.0 { r } else { -r };
        cn = c * sn;
    }
    (sn, cn, dn)
}

/// Complete elliptic integral K(m) = π / (2 AGM(1, √(1-m))).
fn ellipk(m: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    for _ in 0..10 {
        // Quadratic convergence: 10 iterations are far more than enough for 0 < m < 1 - 1e-10.
        (a, b) = ((a + b) / 2.0, (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

#[test]
fn jacobi_elliptic_reference_implementation() {
    let m = 0.51;
    for k in 0..100 {
        let u = -7.0 + 0.17 * k as f64;
        let (sn, cn, dn) = ellipj(u, m);
        assert!((sn * sn + cn * cn - 1.0).abs() < 4e-15, "u={u}");
        assert!(
            (dn * dn + m * sn * sn - 1.0).abs() < 4e-15,
            "u={u}: {}",
            dn * dn + m * sn * sn - 1.0
        );
        // d sn/du = cn dn (central difference)
        let d = 1e-5;
        let dsn = (ellipj(u + d, m).0 - ellipj(u - d, m).0) / (2.0 * d);
        assert!((dsn - cn * dn).abs() < 1e-9, "u={u}");
    }
    // K(1/2) (A&S table 17.1) and sn(K) = 1, cn(K) = 0, dn(K) = √(1-m).
    assert!((ellipk(0.5) - 1.854_074_677_301_372).abs() < 1e-14);
    let (sn, cn, dn) = ellipj(ellipk(m), m);
    assert!((sn - 1.0).abs() < 1e-14 && cn.abs() < 1e-7 && (dn - (1.0 - m).sqrt()).abs() < 1e-14);
    // Cephes (scipy.special.ellipj) values.
    let (sn, cn, dn) = ellipj(12.0, 0.51);
    assert!((sn + 0.7053978095225708).abs() < 1e-14);
    assert!((cn + 0.7088116324671591).abs() < 1e-14);
    assert!((dn - 0.8638466903702229).abs() < 1e-14);
    let (sn, cn, dn) = ellipj(0.3, 0.9);
    assert!((sn - 0.29173204781861856).abs() < 1e-15);
    assert!((cn - 0.9565000848277826).abs() < 1e-15);
    assert!((dn - 0.9609386926583817).abs() < 1e-15);
    // m -> 0: circular functions.
    let (sn, cn, dn) = ellipj(1.2, 1e-300);
    assert!(
        (sn - 1.2f64.sin()).abs() < 1e-15
            && (cn - 1.2f64.cos()).abs() < 1e-15
            && (dn - 1.0).abs() < 1e-15
    );
}

#[test]
fn krogh_rigid_body_against_exact_solution_and_scipy() {
    let (sn, cn, dn) = ellipj(12.0, 0.51);
    let exact = [sn, cn, dn];
    let mut prev_err = f64::INFINITY;
    for &(tl, nfev, steps, y_scipy) in SCIPY_KROGH.iter() {
        let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(tl), &mut []).unwrap();
        assert_eq!(sol.status, Status::Success);
        assert_eq!(sol.t_reached, 12.0);
        let y = sol.state(sol.t.len() - 1);
        let err = (0..3).map(|i| (y[i] - exact[i]).abs()).fold(0.0, f64::max);
        // SciPy's own error is 11-14 × tol on this problem.
        assert!(err < 20.0 * tl, "tol {tl}: error {err}");
        assert!(err < prev_err / 10.0, "error must fall with the tolerance");
        prev_err = err;
        assert_eq!(
            (sol.nfev, sol.n_accepted, sol.t.len()),
            (nfev, steps, steps + 1),
            "tol {tl}"
        );
        for i in 0..3 {
            assert!(
                (y[i] - y_scipy[i]).abs() <= 1e-12 * y_scipy[i].abs(),
                "tol {tl}: {y:?} vs {y_scipy:?}"
            );
        }
        assert_eq!(sol.nfev, 2 + 6 * (sol.n_accepted + sol.n_rejected));
    }
}

#[test]
fn t_eval_and_dense_match_scipy() {
    // SciPy: solve_ivp(krogh, (0, 12), [0, 1, 1], rtol=1e-6, atol=1e-6, dense_output=True,
    //                  t_eval=[0, 2.5, 5, 7.5, 12]); sol(5.5), sol(3.0).
    let y_ref = [
        [0.0, 1.0, 1.0],
        [0.8955678783891637, -0.44491799383282227, 0.7687361247870935],
        [-0.9117258458368565, -0.4107931346396479, 0.7589876922522777],
        [0.049398104974078344, 0.9987765076297669, 0.9993758692252135],
        [-0.7053837295840915, -0.7088187876243793, 0.8638491355867973],
    ];
    let opts = SolverOptions {
        dense: true,
        t_eval: Some(vec![0.0, 2.5, 5.0, 7.5, 12.0]),
        ..tol(1e-6)
    };
    let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
    assert_eq!(sol.t, vec![0.0, 2.5, 5.0, 7.5, 12.0]);
    assert_eq!(sol.nfev, 290);
    let close = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-13 * y.abs().max(1.0))
    };
    for (i, r) in y_ref.iter().enumerate() {
        assert!(close(sol.state(i), r), "{i}: {:?} vs {r:?}", sol.state(i));
    }
    let d = sol.dense.as_ref().unwrap();
    assert_eq!(d.n_segments(), 40);
    assert!(close(
        &sol.dense_eval(5.5).unwrap(),
        &[-0.998100601916966, -0.06154927474960803, 0.7013779251735642]
    ));
    assert!(close(
        &sol.dense_eval(3.0).unwrap(),
        &[0.6414061767684152, -0.7671989487199022, 0.8889219765383558]
    ));
    // Without t_eval the output is t0 plus every accepted step.
    let plain = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(1e-6), &mut []).unwrap();
    assert_eq!(plain.t.len(), plain.n_accepted + 1);
    assert_eq!(plain.t[0], 0.0);
    assert_eq!(plain.state(0), &[0.0, 1.0, 1.0]);
    assert!(plain.t.windows(2).all(|w| w[1] > w[0]));
    assert!(plain.dense_eval(1.0).is_none());
}

#[test]
fn krogh_events_match_scipy() {
    let mut evs = [Event::new(|_t, y: &[f64]| y[0])];
    let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(1e-6), &mut evs).unwrap();
    let scipy = [
        0.0,
        3.7252845246476824,
        7.450570655182676,
        11.175859348266739,
    ];
    assert_eq!(sol.t_events[0].len(), 4);
    for (a, b) in sol.t_events[0].iter().zip(scipy) {
        assert!((a - b).abs() <= 1e-13 * b.max(1.0), "{a} vs {b}");
    }
}

#[test]
fn backward_integration() {
    // SciPy: solve_ivp(lambda t, y: -y, (1, 0), [1.0]) -> nfev 14, t, y below.
    let decay = || {
        FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = -y[0];
            Ok(())
        })
    };
    let sol = rk45(
        decay(),
        (1.0, 0.0),
        &[1.0],
        &SolverOptions::default(),
        &mut [],
    )
    .unwrap();
    assert_eq!(sol.status, Status::Success);
    assert_eq!(sol.nfev, 14);
    assert_eq!(sol.t.len(), 3);
    assert_eq!(sol.t[2], 0.0);
    assert!((sol.t[1] - 0.8999800079952034).abs() < 1e-15);
    assert!(
        (sol.y[1] - 1.1051930131367926).abs() < 1e-15
            && (sol.y[2] - 2.7183269995016905).abs() < 1e-14
    );
    assert!((sol.y[2] - std::f64::consts::E).abs() < 1e-4);

    // Krogh backwards from the exact y(12) to t = 0 (SciPy: nfev 902, 151 points).
    let (sn, cn, dn) = ellipj(12.0, 0.51);
    let opts = SolverOptions {
        dense: true,
        t_eval: Some(vec![12.0, 6.0, 1.0, 0.0]),
        ..tol(1e-9)
    };
    let sol = rk45(krogh(), (12.0, 0.0), &[sn, cn, dn], &opts, &mut []).unwrap();
    assert_eq!(sol.nfev, 902);
    assert_eq!(sol.t, vec![12.0, 6.0, 1.0, 0.0]);
    for (i, &t) in sol.t.iter().enumerate() {
        let (s, c, d) = ellipj(t, 0.51);
        let y = sol.state(i);
        assert!(
            (y[0] - s).abs() < 1e-7 && (y[1] - c).abs() < 1e-7 && (y[2] - d).abs() < 1e-7,
            "t={t}"
        );
    }
    let y = sol.dense_eval(3.3).unwrap();
    assert!((y[0] - ellipj(3.3, 0.51).0).abs() < 1e-7);
}

#[test]
fn nan_in_rhs_gives_non_finite_with_time() {
    let sys = FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
        dy[0] = if t > 0.5 { f64::NAN } else { -y[0] };
        Ok(())
    });
    let sol = rk45(sys, (0.0, 2.0), &[1.0], &SolverOptions::default(), &mut []).unwrap();
    match sol.status {
        Status::NonFinite { t, at, what } => {
            assert_eq!(what, NonFiniteKind::Derivative);
            assert!(t <= 0.5 && at > 0.5 && at > t, "t={t} at={at}");
            assert_eq!(sol.t_reached, t);
            assert_eq!(*sol.t.last().unwrap(), t);
        }
        ref s => panic!("unexpected {s:?}"),
    }
    assert_eq!(sol.status.code(), -1);
    assert!(!sol.success());
    assert!(
        sol.message.contains("non-finite") && sol.message.contains("t = "),
        "{}",
        sol.message
    );
}

#[test]
fn overflowing_state_gives_non_finite_state() {
    let sys = FnSystem::new(1, |_t, _y: &[f64], dy: &mut [f64]| {
        dy[0] = f64::MAX;
        Ok(())
    });
    let sol = rk45(sys, (0.0, 1.0), &[1.0], &SolverOptions::default(), &mut []).unwrap();
    assert!(
        matches!(sol.status, Status::NonFinite { t, what: NonFiniteKind::State, .. } if t == 0.0),
        "{:?}",
        sol.status
    );
}

#[test]
fn max_steps_is_honoured() {
    let opts = SolverOptions {
        max_steps: 5,
        ..tol(1e-10)
    };
    let sol = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
    assert_eq!(sol.n_accepted, 5);
    assert_eq!(sol.t.len(), 6);
    match sol.status {
        Status::MaxSteps { t, max_steps: 5 } => assert_eq!(t, sol.t[5]),
        ref s => panic!("unexpected {s:?}"),
    }
    assert!(
        sol.message.contains("maximum number of steps (5)"),
        "{}",
        sol.message
    );
}

#[test]
fn blow_up_gives_step_too_small_like_scipy() {
    // y' = y², y(0) = 1: y = 1/(1-t), singular at t = 1. SciPy fails at
    // t = 0.9999286400563746 after 66 steps and 632 evaluations.
    let sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[0] * y[0];
        Ok(())
    });
    let sol = rk45(sys, (0.0, 2.0), &[1.0], &SolverOptions::default(), &mut []).unwrap();
    match sol.status {
        Status::StepTooSmall { t, min_step } => {
            assert!((t - 0.9999286400563746).abs() < 1e-12, "{t}");
            assert!(min_step > 0.0 && min_step < 1e-14);
        }
        ref s => panic!("unexpected {s:?}"),
    }
    assert_eq!((sol.nfev, sol.t.len()), (632, 67));
    assert!(
        sol.message.starts_with("step size fell below the minimum"),
        "{}",
        sol.message
    );
    assert!(sol.message.contains("at t = 0.99992"), "{}", sol.message);
}

#[test]
fn rhs_error_is_propagated() {
    let sys = FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
        if t > 1.0 {
            return Err(format!("boom at {t}"));
        }
        dy[0] = -y[0];
        Ok(())
    });
    let sol = rk45(sys, (0.0, 3.0), &[1.0], &SolverOptions::default(), &mut []).unwrap();
    match &sol.status {
        Status::RhsError { t, at, message } => {
            assert!(*t <= 1.0 && *at > 1.0);
            assert!(message.starts_with("boom at"));
        }
        s => panic!("unexpected {s:?}"),
    }
    assert!(
        sol.message.contains("boom") && sol.message.contains("reached t = "),
        "{}",
        sol.message
    );
    // Failure in the very first evaluation: nothing beyond t0.
    let sys = FnSystem::new(1, |_t, _y: &[f64], _dy: &mut [f64]| Err("no".to_string()));
    let sol = rk45(
        sys,
        (0.0, 3.0),
        &[1.0],
        &SolverOptions {
            dense: true,
            ..Default::default()
        },
        &mut [],
    )
    .unwrap();
    assert!(matches!(sol.status, Status::RhsError { t, at, .. } if t == 0.0 && at == 0.0));
    assert_eq!((sol.t.len(), sol.nfev, sol.n_accepted), (1, 1, 0));
    assert!(sol.dense_eval(1.0).is_none());
}

#[test]
fn bad_inputs_give_typed_errors() {
    let y0 = [0.0, 1.0, 1.0];
    let run = |span: (f64, f64), y0: &[f64], opts: SolverOptions| {
        rk45(krogh(), span, y0, &opts, &mut []).unwrap_err()
    };
    let ok = (0.0, 1.0);
    // The error of a run on `ok` with one option set.
    let bad = |set: fn(&mut SolverOptions)| {
        let mut opts = SolverOptions::default();
        set(&mut opts);
        run(ok, &y0, opts)
    };
    let e = run(ok, &[0.0, f64::NAN, 1.0], SolverOptions::default());
    assert!(
        matches!(e, InputError::Y0NonFinite { index: 1, value } if value.is_nan()),
        "{e:?}"
    );
    assert_eq!(e.argument(), "y0");
    assert_eq!(
        run(ok, &[0.0, 1.0], SolverOptions::default()),
        InputError::Y0Length {
            expected: 3,
            got: 2
        }
    );
    assert_eq!(
        run((1.0, 1.0), &y0, SolverOptions::default()),
        InputError::TSpanEmpty(1.0)
    );
    assert_eq!(
        run((0.0, f64::INFINITY), &y0, SolverOptions::default()).argument(),
        "t_span"
    );
    let e = bad(|o| o.rtol = (-1e-3).into());
    assert_eq!(
        e,
        InputError::TolInvalid {
            name: "rtol",
            index: 0,
            value: -1e-3
        }
    );
    let e = bad(|o| o.atol = vec![1e-6, -1.0, 1e-6].into());
    assert_eq!(
        e,
        InputError::TolInvalid {
            name: "atol",
            index: 1,
            value: -1.0
        }
    );
    let e = bad(|o| o.atol = vec![1e-6; 2].into());
    assert_eq!(
        e,
        InputError::TolLength {
            name: "atol",
            expected: 3,
            got: 2
        }
    );
    assert_eq!(e.argument(), "atol");
    let e = bad(|o| o.rtol = vec![1e-6; 4].into());
    assert_eq!(e.argument(), "rtol");
    assert_eq!(bad(|o| o.max_step = 0.0), InputError::MaxStep(0.0));
    assert_eq!(bad(|o| o.max_step = -1.0).argument(), "max_step");
    assert_eq!(bad(|o| o.max_steps = 0), InputError::MaxSteps);
    let e = bad(|o| o.first_step = Some(0.0));
    assert_eq!(e, InputError::FirstStepNotPositive(0.0));
    let e = bad(|o| o.first_step = Some(2.0));
    assert_eq!(
        e,
        InputError::FirstStepBeyondSpan {
            first_step: 2.0,
            span: 1.0
        }
    );
    assert!(e.to_string().starts_with("first_step:"), "{e}");
    let e = bad(|o| {
        o.controller = Controller::PI {
            alpha: -1.0,
            beta: 0.0,
        }
    });
    assert_eq!(e.argument(), "controller");
    let e = bad(|o| o.t_eval = Some(vec![0.5, 1.5]));
    assert!(
        matches!(e, InputError::TEvalOutsideSpan { index: 1, .. }),
        "{e:?}"
    );
    let e = bad(|o| o.t_eval = Some(vec![0.5, 0.5]));
    assert!(
        matches!(
            e,
            InputError::TEvalNotSorted {
                index: 1,
                order: "increasing"
            }
        ),
        "{e:?}"
    );
    let e = run(
        (1.0, 0.0),
        &y0,
        SolverOptions {
            t_eval: Some(vec![0.2, 0.5]),
            ..Default::default()
        },
    );
    assert!(
        matches!(
            e,
            InputError::TEvalNotSorted {
                order: "decreasing",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().starts_with("t_eval:"));
}

#[test]
fn tiny_rtol_is_clamped_with_a_flag() {
    let sol = rk45(
        krogh(),
        (0.0, 1.0),
        &[0.0, 1.0, 1.0],
        &SolverOptions {
            rtol: 0.0.into(),
            ..Default::default()
        },
        &mut [],
    )
    .unwrap();
    assert!(sol.rtol_clamped && sol.success());
    let sol = rk45(
        krogh(),
        (0.0, 1.0),
        &[0.0, 1.0, 1.0],
        &SolverOptions::default(),
        &mut [],
    )
    .unwrap();
    assert!(!sol.rtol_clamped);
}

#[test]
fn per_component_tolerances_equal_scalar_ones() {
    let a = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &tol(1e-7), &mut []).unwrap();
    let opts = SolverOptions {
        rtol: vec![1e-7; 3].into(),
        atol: vec![1e-7; 3].into(),
        ..Default::default()
    };
    let b = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
    assert_eq!((&a.t, &a.y), (&b.t, &b.y));
    // A looser atol on one component must change the steps.
    let opts = SolverOptions {
        atol: vec![1e-7, 1e-7, 1e-2].into(),
        ..tol(1e-7)
    };
    let c = rk45(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
    assert_ne!(c.t, b.t);
}

#[test]
fn boxed_dyn_system_and_mut_ref_work() {
    let mut sys = krogh();
    let a = rk45(
        &mut sys,
        (0.0, 1.0),
        &[0.0, 1.0, 1.0],
        &SolverOptions::default(),
        &mut [],
    )
    .unwrap();
    let boxed: Box<dyn OdeSystem> = Box::new(krogh());
    let b = rk45(
        boxed,
        (0.0, 1.0),
        &[0.0, 1.0, 1.0],
        &SolverOptions::default(),
        &mut [],
    )
    .unwrap();
    assert_eq!(a.y, b.y);
}
