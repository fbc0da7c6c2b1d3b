//! Tests of Radau IIA against SciPy 1.17's `solve_ivp(method="Radau")` (counts pinned from it),
//! published reference values (Hairer's test set) and exact solutions.
use super::*;
use crate::integrator::{FnSystem, SolverOptions};

type Counts = (usize, usize, usize, usize);

/// Van der Pol in Hairer's scaled form `y1' = y2`, `y2' = ((1 − y1²) y2 − y1)/ε`, ε = 1/μ².
struct VdP {
    eps: f64,
    analytic: bool,
}

impl OdeSystem for VdP {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
        dy[0] = y[1];
        dy[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.eps;
        Ok(())
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], j: &mut [f64]) -> Result<bool, String> {
        if !self.analytic {
            return Ok(false);
        }
        j.copy_from_slice(&[
            0.0,
            1.0,
            (-2.0 * y[0] * y[1] - 1.0) / self.eps,
            (1.0 - y[0] * y[0]) / self.eps,
        ]);
        Ok(true)
    }
}

/// Robertson's chemical kinetics.
struct Robertson {
    analytic: bool,
}

impl OdeSystem for Robertson {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
        dy[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
        dy[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1];
        dy[2] = 3e7 * y[1] * y[1];
        Ok(())
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], j: &mut [f64]) -> Result<bool, String> {
        if !self.analytic {
            return Ok(false);
        }
        j.copy_from_slice(&[
            -0.04,
            1e4 * y[2],
            1e4 * y[1],
            0.04,
            -1e4 * y[2] - 6e7 * y[1],
            -1e4 * y[1],
            0.0,
            6e7 * y[1],
            0.0,
        ]);
        Ok(true)
    }
}

fn opts(rtol: f64, atol: f64) -> SolverOptions {
    SolverOptions {
        rtol: rtol.into(),
        atol: atol.into(),
        ..Default::default()
    }
}

/// Steps to the end; ((steps, nfev, njev, nlu), y_end).
fn run<S: OdeSystem>(mut r: Radau<S>) -> (Counts, Vec<f64>) {
    loop {
        match r.step() {
            Ok(StepOutcome::Finished) => break,
            Ok(StepOutcome::Accepted) => {}
            Err(s) => panic!("{}", s.describe(r.t())),
        }
    }
    (
        (r.n_accepted(), r.nfev(), r.njev(), r.nlu()),
        r.y().to_vec(),
    )
}

fn vdp(eps: f64, analytic: bool, tol: f64) -> Radau<VdP> {
    Radau::with_jacobian(
        VdP { eps, analytic },
        0.0,
        &[2.0, 0.0],
        2.0,
        &opts(tol, tol),
        JacobianSource::Auto,
    )
    .unwrap()
}

fn robertson(analytic: bool, tol: f64) -> Radau<Robertson> {
    Radau::with_jacobian(
        Robertson { analytic },
        0.0,
        &[1.0, 0.0, 0.0],
        1e11,
        &opts(tol, tol * 1e-3),
        JacobianSource::Auto,
    )
    .unwrap()
}

fn close(a: &[f64], b: &[f64], rel: f64) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (x - y).abs() <= rel * y.abs().max(1e-300))
}

/// SciPy 1.17 `solve_ivp(vdp, (0, 2), [2, 0], method="Radau", rtol=tol, atol=tol,
/// jac=None | analytic)`, ε = 1e-6 (μ = 1e3): (analytic, tol, (steps, nfev, njev, nlu), y(2)).
const SCIPY_VDP_1E6: [(bool, f64, Counts, [f64; 2]); 4] = [
    (
        false,
        1e-3,
        (186, 1844, 62, 272),
        [1.7061747339238742, -0.8927384287259668],
    ),
    (
        true,
        1e-3,
        (186, 1841, 62, 272),
        [1.706176322477885, -0.8927316200037034],
    ),
    (
        false,
        1e-6,
        (879, 7392, 205, 608),
        [1.7061677250385054, -0.8928097047327269],
    ),
    (
        true,
        1e-6,
        (874, 7336, 207, 602),
        [1.7061677264562052, -0.8928097067951752],
    ),
];

/// As above for Robertson on (0, 1e11), rtol = tol, atol = 1e-3 tol.
const SCIPY_ROBERTSON: [(bool, f64, Counts, [f64; 3]); 3] = [
    (
        true,
        1e-3,
        (78, 857, 44, 214),
        [
            1.8514835168293258e-08,
            7.405934391244861e-14,
            0.9999999814850921,
        ],
    ),
    (
        false,
        1e-6,
        (316, 2484, 77, 356),
        [
            2.0832824747326362e-08,
            8.333130037800223e-14,
            0.9999999791670915,
        ],
    ),
    (
        true,
        1e-6,
        (316, 2484, 77, 356),
        [
            2.0832822472295478e-08,
            8.333129160453338e-14,
            0.999999979167095,
        ],
    ),
];

#[test]
fn van_der_pol_mu_1e3_is_scipys_step_for_step() {
    for (analytic, tol, counts, y_end) in SCIPY_VDP_1E6 {
        let (c, y) = run(vdp(1e-6, analytic, tol));
        assert_eq!(c, counts, "analytic {analytic}, tol {tol}");
        // Same steps; the Newton solves round differently (LAPACK vs ours).
        assert!(close(&y, &y_end, 1e-5), "{y:?} vs {y_end:?}");
    }
}

#[test]
fn robertson_is_scipys_step_for_step() {
    for (analytic, tol, counts, y_end) in SCIPY_ROBERTSON {
        let (c, y) = run(robertson(analytic, tol));
        assert_eq!(c, counts, "analytic {analytic}, tol {tol}");
        assert!(close(&y, &y_end, 1e-4), "{y:?} vs {y_end:?}");
    }
}

/// μ = 1e6 (ε = 1e-12): the Newton matrices have entries ~1e12, rounding differences of 1e-15
/// in the first steps grow and the step sequences part after ~17 steps; the work stays SciPy's
/// within a few per cent and the accuracy the same.
#[test]
fn van_der_pol_mu_1e6_costs_what_scipy_does() {
    // SciPy: (analytic, tol, steps, nfev, y(2)).
    let scipy = [
        (
            false,
            1e-3,
            322,
            3258,
            [1.7055391862787772, -0.8933889408853906],
        ),
        (
            true,
            1e-3,
            338,
            3409,
            [1.7055408170916004, -0.8933825016200553],
        ),
        (
            false,
            1e-6,
            1610,
            13979,
            [1.7055462061432116, -0.8934763721221453],
        ),
        (
            true,
            1e-6,
            1606,
            13834,
            [1.7055462075727337, -0.8934763706247363],
        ),
    ];
    for (analytic, tol, steps, nfev, y_end) in scipy {
        let (c, y) = run(vdp(1e-12, analytic, tol));
        let ratio = c.1 as f64 / nfev as f64;
        assert!((0.9..1.1).contains(&ratio), "nfev {} vs SciPy {nfev}", c.1);
        let sr = c.0 as f64 / steps as f64;
        assert!((0.9..1.1).contains(&sr), "steps {} vs SciPy {steps}", c.0);
        // Both within the tolerance's reach of each other.
        assert!(close(&y, &y_end, 50.0 * tol), "{y:?} vs {y_end:?}");
    }
}

/// Hairer's test set (VDPOL, ε = 1e-6): y(2) = (1.706167732170483, −0.8928097010247975).
#[test]
fn van_der_pol_matches_the_published_reference() {
    let reference = [1.706_167_732_170_483, -0.892_809_701_024_797_5];
    for tol in [1e-6, 1e-9] {
        let (_, y) = run(vdp(1e-6, true, tol));
        let err = (y[0] - reference[0]).abs().max((y[1] - reference[1]).abs());
        assert!(err < 100.0 * tol, "tol {tol}: error {err}");
    }
}

/// `y' = A y`, `A` with eigenvalues −1 and −1e4 (stiff, linear): exact `exp(At) y0`.
struct Linear;
const LAMBDA: [f64; 2] = [-1.0, -1e4];
impl OdeSystem for Linear {
    fn dim(&self) -> usize {
        2
    }
    // A = V diag(λ) V⁻¹ with V = [[1, 1], [1, −1]] / √2 (symmetric).
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
        let (a, b) = (0.5 * (LAMBDA[0] + LAMBDA[1]), 0.5 * (LAMBDA[0] - LAMBDA[1]));
        dy[0] = a * y[0] + b * y[1];
        dy[1] = b * y[0] + a * y[1];
        Ok(())
    }
}
fn linear_exact(t: f64, y0: [f64; 2]) -> [f64; 2] {
    let u = 0.5 * (y0[0] + y0[1]) * (LAMBDA[0] * t).exp();
    let v = 0.5 * (y0[0] - y0[1]) * (LAMBDA[1] * t).exp();
    [u + v, u - v]
}
fn linear_matrix() -> Vec<f64> {
    let (a, b) = (0.5 * (LAMBDA[0] + LAMBDA[1]), 0.5 * (LAMBDA[0] - LAMBDA[1]));
    vec![a, b, b, a]
}

#[test]
fn stiff_linear_system_is_accurate_in_few_steps_and_between_them() {
    let y0 = [1.0, 0.0];
    let tol = 1e-8;
    let mut r = Radau::with_jacobian(
        Linear,
        0.0,
        &y0,
        3.0,
        &opts(tol, tol),
        JacobianSource::Constant(linear_matrix()),
    )
    .unwrap();
    let mut out = [0.0; 2];
    let mut worst_dense: f64 = 0.0;
    loop {
        let o = r.step().unwrap();
        // The collocation cubic between the steps (order 3 on the step, error well below
        // the step's size times the tolerance's order).
        for k in 1..4 {
            let t = r.t_old() + (r.t() - r.t_old()) * k as f64 / 4.0;
            assert!(r.dense_eval(t, &mut out));
            let e = linear_exact(t, y0);
            worst_dense = worst_dense.max((out[0] - e[0]).abs().max((out[1] - e[1]).abs()));
        }
        if o == StepOutcome::Finished {
            break;
        }
    }
    let e = linear_exact(3.0, y0);
    let err = (r.y()[0] - e[0]).abs().max((r.y()[1] - e[1]).abs());
    assert!(err < 1e-7, "end error {err}");
    assert!(worst_dense < 1e-5, "dense error {worst_dense}");
    // An explicit method needs ~|λ| T / 3.3 = 9000 steps; the implicit one a handful.
    assert!(r.n_accepted() < 200, "{} steps", r.n_accepted());
    // A constant Jacobian is never re-evaluated.
    assert_eq!(r.njev(), 0);
    assert!(!r.analytic_jacobian());
}

/// Finite differences agree with the analytic Jacobian: same steps on Robertson (tol 1e-6,
/// pinned above), and their evaluations are counted apart from nfev.
#[test]
fn finite_difference_jacobian_evaluations_are_counted_apart() {
    let mut r = robertson(false, 1e-6);
    while r.step().unwrap() != StepOutcome::Finished {}
    assert!(!r.analytic_jacobian());
    // One evaluation per column and Jacobian, plus SciPy's retries of columns lost in
    // round-off (at most one more per column).
    assert!(r.jac_evaluations() >= 3 * r.njev() && r.jac_evaluations() <= 6 * r.njev());
    let mut a = robertson(true, 1e-6);
    while a.step().unwrap() != StepOutcome::Finished {}
    assert!(a.analytic_jacobian());
    assert_eq!(a.jac_evaluations(), 0);
}

/// A wrong (zero) constant Jacobian: simplified Newton is a fixed-point iteration that only
/// contracts for |h λ| small, so attempts fail and the step is halved until it does; the result
/// is still right.
#[test]
fn newton_failures_halve_the_step() {
    let y0 = [1.0, 0.0];
    let mut r = Radau::with_jacobian(
        Linear,
        0.0,
        &y0,
        0.01,
        &opts(1e-6, 1e-6),
        JacobianSource::Constant(vec![0.0; 4]),
    )
    .unwrap();
    while r.step().unwrap() != StepOutcome::Finished {}
    assert!(r.n_newton_failures() > 0);
    let e = linear_exact(0.01, y0);
    assert!((r.y()[0] - e[0]).abs() < 1e-5 && (r.y()[1] - e[1]).abs() < 1e-5);
}

/// `y' = y²`, `y(0) = 1` blows up at t = 1: the step size falls below the minimum there and
/// the failure names the time reached.
#[test]
fn blow_up_fails_with_step_too_small_and_the_time_reached() {
    let sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[0] * y[0];
        Ok(())
    });
    let mut r = Radau::with_jacobian(
        sys,
        0.0,
        &[1.0],
        2.0,
        &opts(1e-6, 1e-6),
        JacobianSource::Auto,
    )
    .unwrap();
    let status = loop {
        match r.step() {
            Ok(StepOutcome::Accepted) => {}
            Ok(StepOutcome::Finished) => panic!("passed the singularity"),
            Err(s) => break s,
        }
    };
    let t = match status {
        Status::StepTooSmall { t, .. } => t,
        ref other => panic!("{other:?}"),
    };
    assert!((t - 1.0).abs() < 1e-3, "stopped at {t}");
    assert!(status.describe(r.t()).contains(&format!("{t}")));
    // Every later call reports the same failure.
    assert_eq!(r.step(), Err(status));
}

#[test]
fn jacobian_errors_and_bad_constant_jacobians() {
    struct Failing;
    impl OdeSystem for Failing {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
            dy[0] = -y[0];
            Ok(())
        }
        fn jacobian(&mut self, _t: f64, _y: &[f64], _j: &mut [f64]) -> Result<bool, String> {
            Err("no Jacobian today".into())
        }
    }
    let mut r = Radau::with_jacobian(
        Failing,
        0.0,
        &[1.0],
        1.0,
        &opts(1e-3, 1e-6),
        JacobianSource::Auto,
    )
    .unwrap();
    match r.step() {
        Err(Status::RhsError { message, .. }) => {
            assert!(message.contains("jacobian: no Jacobian today"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    let e = Radau::with_jacobian(
        Linear,
        0.0,
        &[1.0, 0.0],
        1.0,
        &opts(1e-3, 1e-6),
        JacobianSource::Constant(vec![0.0; 3]),
    )
    .err()
    .unwrap();
    assert_eq!(e.argument(), "jac");
    assert!(e.to_string().contains("got 3"));
    let e = Radau::with_jacobian(
        Linear,
        0.0,
        &[1.0, 0.0],
        1.0,
        &opts(1e-3, 1e-6),
        JacobianSource::Constant(vec![0.0, f64::NAN, 0.0, 0.0]),
    )
    .err()
    .unwrap();
    assert_eq!(e.argument(), "jac");
}

/// Backwards in time on the linear system (from its exact state at t = 1 back to t = 0.5).
#[test]
fn integrates_backwards() {
    let y1 = linear_exact(1.0, [1.0, 0.0]);
    let (_, y) = run(Radau::with_jacobian(
        Linear,
        1.0,
        &y1,
        0.5,
        &opts(1e-10, 1e-12),
        JacobianSource::Constant(linear_matrix()),
    )
    .unwrap());
    // Backwards, the stiff mode grows: only the smooth one is present (it was damped).
    let e = linear_exact(0.5, [1.0, 0.0]);
    assert!(
        (y[0] - e[0]).abs() < 1e-8 && (y[1] - e[1]).abs() < 1e-8,
        "{y:?} vs {e:?}"
    );
}

fn radau_opts(tol: f64) -> SolverOptions {
    SolverOptions {
        method: crate::integrator::Method::Radau,
        ..opts(tol, tol)
    }
}

/// Through the generic driver: an event located on Radau's interpolant, `t_eval` values and the
/// dense output, against the exact solution of the stiff linear system.
#[test]
fn driver_events_t_eval_and_dense_output() {
    use crate::integrator::{solve, Event, EventDirection};
    let y0 = [1.0, 0.0];
    let tol = 1e-9;
    // y[0] = u + v with u = e^(−t)/2 and v = e^(−1e4 t)/2 (~e^(−6931) at the root): 1/4 at ln 2.
    let mut events = [Event::new(|_t, y: &[f64]| y[0] - 0.25)
        .direction(EventDirection::Falling)
        .terminal(1)];
    let t_eval: Vec<f64> = (1..=10).map(|k| 0.05 * k as f64).collect();
    let sol = solve(
        Linear,
        (0.0, 2.0),
        &y0,
        &SolverOptions {
            dense: true,
            t_eval: Some(t_eval.clone()),
            ..radau_opts(tol)
        },
        &mut events,
    )
    .unwrap();
    assert_eq!(
        sol.status,
        Status::TerminalEvent {
            event: 0,
            t: sol.t_events[0][0]
        }
    );
    let te = sol.t_events[0][0];
    assert!((te - std::f64::consts::LN_2).abs() < 1e-7, "event at {te}");
    assert_eq!(sol.t, t_eval[..sol.t.len()].to_vec());
    assert_eq!(sol.t.len(), 10); // 0.05 .. 0.5 < ln 2
    for (i, &t) in sol.t.iter().enumerate() {
        let e = linear_exact(t, y0);
        let y = sol.state(i);
        assert!(
            (y[0] - e[0]).abs() < 1e-7 && (y[1] - e[1]).abs() < 1e-7,
            "t = {t}"
        );
    }
    for k in 0..50 {
        let t = 0.01 + 0.0135 * k as f64;
        let y = sol.dense_eval(t).unwrap();
        let e = linear_exact(t, y0);
        assert!((y[0] - e[0]).abs() < 1e-7, "dense at {t}: {y:?} vs {e:?}");
    }
    assert_eq!(sol.method, crate::integrator::Method::Radau);
    assert!(sol.njev >= 1 && sol.nlu >= 2);
}

/// `auto` on Van der Pol μ = 1e3: RK45 until its stiffness test fires, then Radau; the end
/// state agrees with Radau's alone within the tolerance, for far fewer evaluations than RK45.
#[test]
fn auto_switches_to_radau_on_van_der_pol() {
    use crate::integrator::{solve, Method};
    let tol = 1e-6;
    let run_with = |method| {
        solve(
            VdP {
                eps: 1e-6,
                analytic: true,
            },
            (0.0, 2.0),
            &[2.0, 0.0],
            &SolverOptions {
                method,
                ..opts(tol, tol)
            },
            &mut [],
        )
        .unwrap()
    };
    let auto = run_with(Method::Auto);
    let radau = run_with(Method::Radau);
    assert!(auto.success() && radau.success());
    assert_eq!(auto.switched_to, Some(Method::Radau));
    let t_switch = auto.t_switch.unwrap();
    assert!(t_switch > 0.0 && t_switch < 2.0);
    let (a, r) = (auto.state(auto.t.len() - 1), radau.state(radau.t.len() - 1));
    assert!(
        (a[0] - r[0]).abs() < 1e-4 && (a[1] - r[1]).abs() < 1e-4,
        "{a:?} vs {r:?}"
    );
    // Radau alone: SciPy's counts (pinned above).
    assert_eq!(
        (radau.n_accepted, radau.nfev, radau.njev, radau.nlu),
        (874, 7336, 207, 602)
    );
}

#[test]
fn radau_refuses_a_pi_controller() {
    let e = Radau::new(
        Linear,
        0.0,
        &[1.0, 0.0],
        1.0,
        &SolverOptions {
            controller: crate::integrator::Controller::hairer_pi(),
            ..opts(1e-3, 1e-6)
        },
    )
    .err()
    .unwrap();
    assert_eq!(e.argument(), "controller");
}

/// chain7's links with stiff, heavily damped joints 1-6 (joint 0 free): the bends creep back
/// with time constant c/k = 0.5 s while the fast modes decay at ~1e4 /s, so an explicit
/// method is held to steps of ~1e-4 s by stability.
fn stiff_chain_scene() -> crate::io::scene::Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/python/pointmass_dyn/scenes/chain7.toml"
    );
    let mut text = std::fs::read_to_string(path).unwrap();
    text = text.replace("[simulate]", "[simulate_unused]");
    text = text[..text.find("[simulate_unused]").unwrap()].to_string();
    text.push_str(
        r#"
[[effect]]
type = "spring"
joints = ["link1", "link2", "link3", "link4", "link5", "link6"]
stiffness = 600.0
rest = 0.0

[[effect]]
type = "damper"
joints = ["link1", "link2", "link3", "link4", "link5", "link6"]
damping = 300.0
"#,
    );
    crate::io::scene::Scene::from_toml(&text, "stiff chain").unwrap()
}

/// On the stiff chain Radau reaches RK45's error (against DOP853 at 1e-13) for ≥ 10× fewer
/// right-hand-side evaluations, its finite-difference Jacobians counted at their most
/// (2 · dim per Jacobian: a column each, plus SciPy's one retry per column).
#[test]
fn stiff_chain_radau_needs_ten_times_fewer_evaluations_than_rk45() {
    use crate::integrator::{solve, Method};
    use crate::simulate::Dynamics;
    let scene = stiff_chain_scene();
    let model = &scene.model;
    let mut y0 = scene.q0.clone();
    y0.extend_from_slice(&scene.v0);
    let dim = y0.len();
    let go = |method, tol: f64| {
        let mut sys = Dynamics::try_new(model, &scene.effects, Default::default()).unwrap();
        let o = SolverOptions {
            method,
            ..opts(tol, tol)
        };
        let sol = solve(&mut sys, (0.0, 1.0), &y0, &o, &mut []).unwrap();
        assert!(sol.success(), "{}", sol.message);
        let y = sol.state(sol.t.len() - 1).to_vec();
        (y, sol.nfev + 2 * dim * sol.njev)
    };
    let (reference, _) = go(Method::Dop853, 1e-13);
    let error = |y: &[f64]| {
        y.iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let radau: Vec<(f64, usize)> = [1e-4, 1e-6, 1e-8, 1e-10]
        .iter()
        .map(|&tol| {
            let (y, cost) = go(Method::Radau, tol);
            (error(&y), cost)
        })
        .collect();
    for tol in [1e-4, 1e-6, 1e-8] {
        let (y, rk45_cost) = go(Method::Rk45, tol);
        let rk45_error = error(&y);
        // The cheapest Radau run at least as accurate.
        let cost = radau
            .iter()
            .filter(|(e, _)| *e <= rk45_error)
            .map(|&(_, c)| c)
            .min()
            .unwrap();
        assert!(
            10 * cost <= rk45_cost,
            "tol {tol}: RK45 {rk45_cost} evaluations (error {rk45_error:.1e}), Radau {cost}"
        );
    }
}

/// A system whose analytic Jacobian is available at t0 only: the later Jacobians fall back to
/// finite differences, and the run matches the all-analytic one to the tolerance.
#[test]
fn analytic_jacobian_missing_later_falls_back_to_differences() {
    struct Sometimes(VdP);
    impl OdeSystem for Sometimes {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
            self.0.rhs(t, y, dy)
        }
        fn jacobian(&mut self, t: f64, y: &[f64], j: &mut [f64]) -> Result<bool, String> {
            if t == 0.0 {
                self.0.jacobian(t, y, j)
            } else {
                Ok(false)
            }
        }
    }
    let sys = Sometimes(VdP {
        eps: 1e-6,
        analytic: true,
    });
    let r = Radau::new(sys, 0.0, &[2.0, 0.0], 2.0, &opts(1e-6, 1e-6)).unwrap();
    let (c, y) = run(r);
    assert!(c.2 > 1);
    let (_, y_ref) = run(vdp(1e-6, true, 1e-6));
    assert!((y[0] - y_ref[0]).abs() < 1e-5 && (y[1] - y_ref[1]).abs() < 1e-5);
}
