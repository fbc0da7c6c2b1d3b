use super::*;
use crate::integrator::tests::fixtures::{at_halved_steps, decay, observed_orders, oscillator};

#[test]
fn tableau_order_conditions() {
    // Row sums of A equal C; B and the embedded B̂ = B - E[..6] (E[6] = -b̂7) satisfy
    // the quadrature conditions Σ b c^(q-1) = 1/q up to their orders (5 and 4).
    for s in 0..N_STAGES {
        let row: f64 = A[s].iter().sum();
        assert!((row - C[s]).abs() < 1e-15, "row {s}");
    }
    let c7 = [C[0], C[1], C[2], C[3], C[4], C[5], 1.0];
    let b7 = [B[0], B[1], B[2], B[3], B[4], B[5], 0.0];
    for q in 1..=5 {
        let s: f64 = (0..7).map(|i| b7[i] * c7[i].powi(q - 1)).sum();
        assert!((s - 1.0 / q as f64).abs() < 1e-14, "B, q={q}: {s}");
        let bh: f64 = (0..7).map(|i| (b7[i] - E[i]) * c7[i].powi(q - 1)).sum();
        if q <= 4 {
            assert!((bh - 1.0 / q as f64).abs() < 1e-14, "B̂, q={q}: {bh}");
        }
    }
    // The error estimate is not identically zero at 5th order.
    let e5: f64 = (0..7).map(|i| E[i] * c7[i].powi(4)).sum();
    assert!(e5.abs() > 1e-6);
}

#[test]
fn next_toward_matches_nextafter() {
    assert_eq!(next_toward(1.0, 1.0) - 1.0, f64::EPSILON);
    assert_eq!(1.0 - next_toward(1.0, -1.0), f64::EPSILON / 2.0);
    assert_eq!(next_toward(-1.0, -1.0), -1.0 - f64::EPSILON);
    assert_eq!(next_toward(0.0, -1.0), -f64::from_bits(1));
}

#[test]
fn combinations_round_alike_on_every_cpu_path() {
    // The dispatching helpers (AVX2 copy where the CPU has it) against the plain bodies,
    // bit for bit, on awkward magnitudes and odd lengths.
    for n in [1usize, 3, 4, 14, 33] {
        let val = |i: usize| ((i as f64 * 0.61).sin() * 10f64.powi((i % 7) as i32 - 3)) + 0.1;
        let k: Vec<f64> = (0..(N_STAGES + 1) * n).map(val).collect();
        let y: Vec<f64> = (0..n).map(|i| val(i + 500)).collect();
        let y_new: Vec<f64> = (0..n).map(|i| val(i + 900)).collect();
        let (atol, rtol) = (vec![1e-9; n], vec![1e-6; n]);
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        combine(&mut a, &y, &k, &first::<3>(&A[3]), 0.37);
        combine_body(&mut b, &y, &k, &first::<3>(&A[3]), 0.37);
        assert_eq!(bits(&a), bits(&b));
        combine(&mut a, &y, &k, &B, -0.37);
        combine_body(&mut b, &y, &k, &B, -0.37);
        assert_eq!(bits(&a), bits(&b));
        scaled_errors(&mut a, &k, (&y, &y_new), (&atol, &rtol), 0.37);
        scaled_errors_body(&mut b, &k, (&y, &y_new), (&atol, &rtol), 0.37);
        assert_eq!(bits(&a), bits(&b));
        // And the stage sum is np.dot's: left to right over the stages.
        let i = n - 1;
        let mut acc = k[i] * B[0];
        for (j, bj) in B.iter().enumerate().skip(1) {
            acc += k[j * n + i] * bj;
        }
        combine(&mut a, &y, &k, &B, 0.37);
        assert_eq!(a[i].to_bits(), (y[i] + acc * 0.37).to_bits());
    }
}

#[test]
fn first_steps_match_scipy() {
    // Reference: scipy 1.17 `RK45(lambda t, y: -y, 0, [1.0], 10)`; h_abs after init,
    // then t after each of the first three steps, and nfev.
    let mut st = Stepper::new(decay(), 0.0, &[1.0], 10.0, &SolverOptions::default()).unwrap();
    st.initialize().unwrap();
    assert_eq!(st.h_next(), SCIPY_DECAY_H0);
    for &t in SCIPY_DECAY_T.iter() {
        assert_eq!(st.step().unwrap(), StepOutcome::Accepted);
        // The error estimate K·E cancels ~7 digits, so round-off differences between our sums
        // and OpenBLAS's (FMA, kernel-dependent order) show up at ~1e-11 in the next step size.
        assert!((st.t() - t).abs() <= 1e-10 * t, "{} vs {t}", st.t());
    }
    assert_eq!(st.nfev(), 2 + 6 * 3);
    assert!((st.y()[0] - SCIPY_DECAY_Y3).abs() < 1e-10);
}

const SCIPY_DECAY_H0: f64 = 0.10001999200479661;
const SCIPY_DECAY_T: [f64; 3] = [0.10001999200479661, 1.0318648679402695, 1.9076513619864723];
const SCIPY_DECAY_Y3: f64 = 0.14860780882670885;

#[test]
fn stepper_runs_to_the_bound_and_stays_finished() {
    let mut st = Stepper::new(decay(), 0.0, &[1.0], 1.0, &SolverOptions::default()).unwrap();
    let mut n = 0;
    while st.step().unwrap() == StepOutcome::Accepted {
        n += 1;
        assert!(n < 1000);
    }
    assert_eq!(st.t(), 1.0);
    assert!(st.is_finished());
    let nfev = st.nfev();
    assert_eq!(st.step().unwrap(), StepOutcome::Finished);
    assert_eq!(st.nfev(), nfev);
    // SciPy: solve_ivp(lambda t, y: -y, (0, 1), [1.0]) -> y(1) = 0.36809007647621717, nfev 14.
    assert!((st.y()[0] - 0.36809007647621717).abs() < 1e-15);
    assert_eq!((st.nfev(), st.n_accepted()), (14, 2));
    assert!((st.y()[0] - (-1f64).exp()).abs() < 1e-3);
}

/// Global error at t = 2 of y'' = -y with fixed steps h (max_step = first_step = h).
fn fixed_step_error(h: f64) -> f64 {
    let sys = oscillator();
    let opts = SolverOptions {
        atol: 1e-2.into(),
        rtol: 1e-2.into(),
        max_step: h,
        first_step: Some(h),
        ..Default::default()
    };
    let mut st = Stepper::new(sys, 0.0, &[0.0, 1.0], 2.0, &opts).unwrap();
    while st.step().unwrap() == StepOutcome::Accepted {
        assert_eq!(st.step_size(), h, "step sizes must be equal");
    }
    assert_eq!(st.n_rejected(), 0);
    let t = st.t();
    ((st.y()[0] - t.sin()).powi(2) + (st.y()[1] - t.cos()).powi(2)).sqrt()
}

#[test]
fn fifth_order_convergence_with_fixed_steps() {
    let errs = at_halved_steps(fixed_step_error);
    for order in observed_orders(&errs) {
        assert!(
            (order - 5.0).abs() < 0.3,
            "observed order {order}, errors {errs:?}"
        );
    }
}

#[test]
fn max_step_is_respected() {
    let opts = SolverOptions {
        max_step: 0.1,
        ..Default::default()
    };
    let mut st = Stepper::new(decay(), 0.0, &[1.0], 3.0, &opts).unwrap();
    while st.step().unwrap() == StepOutcome::Accepted {
        // h = t_new - t is recomputed by subtraction, hence an ulp of t of slack.
        assert!(
            st.step_size() <= 0.1 + f64::EPSILON * st.t(),
            "{}",
            st.step_size()
        );
    }
    assert!(st.n_accepted() >= 30);
}

#[test]
fn pi_controller_is_accurate_and_differs_from_standard() {
    let run = |controller| {
        let opts = SolverOptions {
            rtol: 1e-8.into(),
            atol: 1e-8.into(),
            controller,
            ..Default::default()
        };
        let mut st = Stepper::new(decay(), 0.0, &[1.0], 20.0, &opts).unwrap();
        while st.step().unwrap() == StepOutcome::Accepted {}
        (st.y()[0], st.n_accepted(), st.nfev())
    };
    let (y_std, n_std, _) = run(Controller::Standard);
    let (y_pi, n_pi, _) = run(Controller::hairer_pi());
    let exact = (-20f64).exp();
    assert!((y_pi - exact).abs() < 1e-8 && (y_std - exact).abs() < 1e-8);
    assert_ne!(n_std, n_pi, "PI control must change the step sequence");
}

#[test]
fn projection_is_applied_to_each_accepted_state() {
    // Rotation on the unit circle, re-normalised after each step. (The rhs scales with |y|,
    // so FSAL is off by a round-off factor; irrelevant to what is checked here.)
    struct Circle {
        calls: usize,
    }
    impl OdeSystem for Circle {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
            dy[0] = -y[1];
            dy[1] = y[0];
            Ok(())
        }
        fn project(&mut self, y: &mut [f64]) -> Result<bool, String> {
            self.calls += 1;
            let r = (y[0] * y[0] + y[1] * y[1]).sqrt();
            y[0] /= r;
            y[1] /= r;
            Ok(false)
        }
    }
    let mut st = Stepper::new(
        Circle { calls: 0 },
        0.0,
        &[1.0, 0.0],
        50.0,
        &SolverOptions::default(),
    )
    .unwrap();
    while st.step().unwrap() == StepOutcome::Accepted {
        let r = (st.y()[0].powi(2) + st.y()[1].powi(2)).sqrt();
        assert!((r - 1.0).abs() < 4.0 * f64::EPSILON, "{r}");
    }
    assert_eq!(st.system().calls, st.n_accepted());
}
