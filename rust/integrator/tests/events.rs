use super::*;
use crate::integrator::tests::fixtures::{oscillator, tol};
use crate::integrator::{rk45, SolverOptions, Status};
use std::f64::consts::PI;

#[test]
fn brentq_finds_known_roots() {
    let r = brentq(
        |x| x * x - 2.0,
        0.0,
        2.0,
        4.0 * f64::EPSILON,
        4.0 * f64::EPSILON,
        100,
    );
    assert!((r - 2f64.sqrt()).abs() <= 8.0 * f64::EPSILON, "{r}");
    let r = brentq(
        |x: f64| x.cos(),
        3.0,
        1.0,
        4.0 * f64::EPSILON,
        4.0 * f64::EPSILON,
        100,
    );
    assert!((r - PI / 2.0).abs() <= 8.0 * f64::EPSILON, "{r}");
    // Exact zero at an endpoint is returned as is.
    assert_eq!(brentq(|x| x - 1.0, 1.0, 3.0, 1e-12, 1e-12, 100), 1.0);
    // Same sign at both ends: the endpoint closer to zero.
    assert_eq!(brentq(|x| x + 1e-20, 0.0, 1.0, 1e-12, 1e-12, 100), 0.0);
}

#[test]
fn activity_follows_scipy_find_active_events() {
    use EventDirection::*;
    assert!(
        is_active(-1.0, 1.0, Rising) && !is_active(-1.0, 1.0, Falling) && is_active(-1.0, 1.0, Any)
    );
    assert!(!is_active(1.0, -1.0, Rising) && is_active(1.0, -1.0, Falling));
    assert!(
        is_active(0.0, 1.0, Rising) && is_active(0.0, 1.0, Any) && !is_active(0.0, 1.0, Falling)
    );
    assert!(!is_active(1.0, 2.0, Any) && !is_active(f64::NAN, 1.0, Any));
}

/// Tight tolerances: events located to ~1e-10.
fn tight() -> SolverOptions {
    tol(1e-12)
}

#[test]
fn oscillator_zero_crossings_located_to_1e_10() {
    let mut evs = [Event::new(|_t, y: &[f64]| y[0])];
    let sol = rk45(oscillator(), (0.0, 10.0), &[1.0, 0.0], &tight(), &mut evs).unwrap();
    assert_eq!(sol.status, Status::Success);
    let expect = [0.5 * PI, 1.5 * PI, 2.5 * PI];
    assert_eq!(sol.t_events[0].len(), 3, "{:?}", sol.t_events);
    for (k, (&te, &ex)) in sol.t_events[0].iter().zip(&expect).enumerate() {
        assert!((te - ex).abs() < 1e-10, "root {te} vs {ex}");
        let ye = &sol.y_events[0][2 * k..2 * k + 2];
        assert!(
            ye[0].abs() < 1e-10 && (ye[1] + ex.sin()).abs() < 1e-10,
            "{ye:?}"
        );
    }
    // Events do not change the integration itself.
    let plain = rk45(oscillator(), (0.0, 10.0), &[1.0, 0.0], &tight(), &mut []).unwrap();
    assert_eq!((plain.t, plain.nfev), (sol.t, sol.nfev));
}

#[test]
fn direction_filtering() {
    let mut evs = [
        Event::new(|_t, y: &[f64]| y[0]).direction(EventDirection::Rising),
        Event::new(|_t, y: &[f64]| y[0]).direction(EventDirection::Falling),
    ];
    let sol = rk45(oscillator(), (0.0, 12.0), &[1.0, 0.0], &tight(), &mut evs).unwrap();
    let (up, down) = (&sol.t_events[0], &sol.t_events[1]);
    assert_eq!(up.len(), 2, "{up:?}");
    assert_eq!(down.len(), 2, "{down:?}");
    assert!((up[0] - 1.5 * PI).abs() < 1e-10 && (up[1] - 3.5 * PI).abs() < 1e-10);
    assert!((down[0] - 0.5 * PI).abs() < 1e-10 && (down[1] - 2.5 * PI).abs() < 1e-10);
}

#[test]
fn terminal_event_stops_at_the_event_time() {
    // Second rising crossing of y1 = cos t: 3.5 π; the non-terminal event before it is kept.
    let mut evs = [
        Event::new(|_t, y: &[f64]| y[0])
            .direction(EventDirection::Rising)
            .terminal(2),
        Event::new(|_t, y: &[f64]| y[1]),
    ];
    let sol = rk45(oscillator(), (0.0, 20.0), &[1.0, 0.0], &tight(), &mut evs).unwrap();
    let te = 3.5 * PI;
    assert!(matches!(sol.status, Status::TerminalEvent { event: 0, t } if (t - te).abs() < 1e-10));
    assert_eq!(sol.status.code(), 1);
    assert!(sol.success());
    assert_eq!(sol.t_events[0].len(), 2);
    // y2 = -sin t: g(t0) = 0 counts as a crossing (as in SciPy), then π, 2π, 3π before
    // the stop, not 4π after it.
    assert_eq!(sol.t_events[1].len(), 4, "{:?}", sol.t_events[1]);
    assert_eq!(sol.t_events[1][0], 0.0);
    let t_last = *sol.t.last().unwrap();
    assert_eq!(t_last, sol.t_events[0][1]);
    assert_eq!(sol.t_reached, t_last);
    let y_last = sol.state(sol.t.len() - 1);
    assert!(
        y_last[0].abs() < 1e-10 && (y_last[1] - 1.0).abs() < 1e-10,
        "{y_last:?}"
    );
    assert!(sol.message.contains("terminal event 0"), "{}", sol.message);
}

#[test]
fn terminal_event_with_t_eval_truncates_output() {
    let opts = SolverOptions {
        t_eval: Some((0..=20).map(|k| k as f64 * 0.5).collect()),
        ..tight()
    };
    let mut evs = [Event::new(|_t, y: &[f64]| y[0]).terminal(1)];
    let sol = rk45(oscillator(), (0.0, 10.0), &[1.0, 0.0], &opts, &mut evs).unwrap();
    // π/2 ≈ 1.5708: t_eval values 0, 0.5, 1.0, 1.5 only.
    assert_eq!(sol.t, vec![0.0, 0.5, 1.0, 1.5]);
    for (i, &t) in sol.t.iter().enumerate() {
        assert!((sol.state(i)[0] - t.cos()).abs() < 1e-10);
    }
}
