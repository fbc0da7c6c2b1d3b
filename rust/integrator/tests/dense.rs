use super::*;
use crate::integrator::stepper::B;
use crate::integrator::tests::fixtures::{at_halved_steps, observed_orders, oscillator};
use crate::integrator::{rk45, SolverOptions, Tol};

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
    let opts = SolverOptions {
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
    let opts = SolverOptions {
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
    let errs = at_halved_steps(midpoint_error);
    for order in observed_orders(&errs) {
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
