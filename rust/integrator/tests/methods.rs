//! The methods beyond RK45 through the generic driver: DOP853 against SciPy's numbers, RK4 and
//! the semi-implicit Euler against their closed forms on linear problems, `auto`'s switch with
//! a test double, and the argument errors.
use super::fixtures::{krogh, oscillator, tol};
use crate::integrator::{
    solve, Event, FixedStep, InputError, Integrator, Interpolant, Method, OdeSystem, SolverOptions,
    Status, Stepper,
};

fn with(method: Method, opts: SolverOptions) -> SolverOptions {
    SolverOptions { method, ..opts }
}

/// SciPy 1.17 `solve_ivp(krogh, (0, 12), [0, 1, 1], method="DOP853", rtol=tol, atol=tol)`:
/// tol, nfev, steps, y(12).
const SCIPY_DOP853_KROGH: [(f64, usize, usize, [f64; 3]); 4] = [
    (
        1e-6,
        266,
        17,
        [-0.7053969317342933, -0.708811326858724, 0.8638465705436734],
    ),
    (
        1e-8,
        398,
        29,
        [-0.7053977946295514, -0.7088116305013459, 0.8638466899835163],
    ),
    (
        1e-10,
        590,
        49,
        [-0.7053978093768732, -0.7088116324944013, 0.863846690381683],
    ),
    (
        1e-12,
        1046,
        87,
        [-0.7053978095216843, -0.7088116324674658, 0.8638466903703376],
    ),
];

#[test]
fn dop853_krogh_equals_scipy_step_for_step() {
    for &(tl, nfev, steps, y_scipy) in SCIPY_DOP853_KROGH.iter() {
        let opts = with(Method::Dop853, tol(tl));
        let sol = solve(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
        assert_eq!(sol.status, Status::Success);
        assert_eq!((sol.nfev, sol.n_accepted), (nfev, steps), "tol {tl}");
        assert_eq!((sol.njev, sol.nlu, sol.method), (0, 0, Method::Dop853));
        let y = sol.state(sol.t.len() - 1);
        for i in 0..3 {
            assert!(
                (y[i] - y_scipy[i]).abs() <= 1e-13 * y_scipy[i].abs(),
                "tol {tl}: {y:?} vs {y_scipy:?}"
            );
        }
        // 12 evaluations per attempt after f(t0) and the initial-step probe.
        assert_eq!(sol.nfev, 2 + 12 * (sol.n_accepted + sol.n_rejected));
    }
}

#[test]
fn dop853_dense_output_and_t_eval_equal_scipy_and_count_like_it() {
    // SciPy: solve_ivp(krogh, (0, 12), [0, 1, 1], method="DOP853", rtol=1e-6, atol=1e-6,
    // dense_output=True, t_eval=[0, 2.5, 5, 7.5, 12]): nfev 317; sol(5.5), sol(3.0). Without
    // dense_output: nfev 281 (the 3 extra stages only on the 5 steps holding a t_eval value).
    let y_ref = [
        [0.0, 1.0, 1.0],
        [0.8955711307023523, -0.44491823448786383, 0.768736383501361],
        [-0.9117283957299589, -0.4107915649675024, 0.7589878769173686],
        [0.049408174218031675, 0.9987773847829047, 0.999376653709316],
        [-0.7053969317342933, -0.708811326858724, 0.8638465705436734],
    ];
    let t_eval = vec![0.0, 2.5, 5.0, 7.5, 12.0];
    let opts = SolverOptions {
        dense: true,
        t_eval: Some(t_eval.clone()),
        ..with(Method::Dop853, tol(1e-6))
    };
    let sol = solve(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
    assert_eq!(sol.nfev, 317);
    for (k, row) in y_ref.iter().enumerate() {
        for (y, r) in sol.state(k).iter().zip(row) {
            // The step times differ from SciPy's by ~2e-8 relative here (round-off in the error
            // estimate, which NumPy sums in BLAS's order), which moves the interpolant at a
            // fixed time by ~1e-13 at this tolerance.
            assert!((y - r).abs() <= 1e-12, "{k}: {y} vs {r}");
        }
    }
    let d = sol.dense.as_ref().unwrap();
    assert!((0..d.n_segments()).all(|s| d.kind(s) == Interpolant::Dop853));
    for (t, r) in [
        (
            5.5,
            [
                -0.9981038043980366,
                -0.06154693219904292,
                0.7013785550220288,
            ],
        ),
        (
            3.0,
            [0.6414090808816896, -0.7672044188519531, 0.8889244968956005],
        ),
    ] {
        let y = sol.dense_eval(t).unwrap();
        for i in 0..3 {
            assert!((y[i] - r[i]).abs() <= 1e-12, "{t}: {y:?}");
        }
    }
    let opts = SolverOptions {
        t_eval: Some(t_eval),
        ..with(Method::Dop853, tol(1e-6))
    };
    let sol = solve(krogh(), (0.0, 12.0), &[0.0, 1.0, 1.0], &opts, &mut []).unwrap();
    assert_eq!(sol.nfev, 281);
}

#[test]
fn dop853_terminal_event_on_the_oscillator() {
    // sin t from (0, 1): the falling zero of y0 is at π.
    let mut ev = [Event::new(|_t, y: &[f64]| y[0])
        .direction(crate::integrator::EventDirection::Falling)
        .terminal(1)];
    let opts = with(Method::Dop853, tol(1e-10));
    let sol = solve(oscillator(), (0.0, 10.0), &[0.0, 1.0], &opts, &mut ev).unwrap();
    let Status::TerminalEvent { event: 0, t } = sol.status else {
        panic!("{:?}", sol.status)
    };
    assert!((t - std::f64::consts::PI).abs() < 1e-9, "{t}");
    assert_eq!(sol.t_events[0].len(), 1);
    assert!((sol.y_events[0][1] + 1.0).abs() < 1e-9);
}

/// RK4's amplification on `y' = λ y`: `R(z) = 1 + z + z²/2 + z³/6 + z⁴/24`.
#[test]
fn rk4_is_its_stability_polynomial_on_the_oscillator() {
    // On y0' = y1, y1' = −y0 (λ = ±i), each step multiplies (y0 + i y1) by R(−i h).
    let h = 0.1f64;
    let (re, im) = (1.0 - h * h / 2.0 + h.powi(4) / 24.0, -(h - h.powi(3) / 6.0));
    let opts = SolverOptions {
        dt: Some(h),
        ..with(Method::Rk4, SolverOptions::default())
    };
    let sol = solve(oscillator(), (0.0, 1.0), &[0.0, 1.0], &opts, &mut []).unwrap();
    assert_eq!(sol.status, Status::Success);
    assert_eq!((sol.n_accepted, sol.nfev, sol.t.len()), (10, 40, 11));
    let (mut a, mut b) = (0.0f64, 1.0f64);
    for k in 1..=10 {
        (a, b) = (re * a - im * b, re * b + im * a);
        let y = sol.state(k);
        assert!((y[0] - a).abs() < 1e-14 && (y[1] - b).abs() < 1e-14, "{k}");
    }
    assert_eq!(sol.t[10], 1.0);
}

/// `y = [q; v]` with `q̇ = v`, `v̇ = −q`, split at 1: the symplectic Euler map.
struct SplitOscillator {
    position_rate: bool,
}

impl OdeSystem for SplitOscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    }
    fn split(&self) -> Option<usize> {
        Some(1)
    }
    fn position_rate(&mut self, y: &[f64], qdot: &mut [f64]) -> Result<bool, String> {
        qdot[0] = y[1];
        Ok(self.position_rate)
    }
}

#[test]
fn euler_is_semi_implicit_with_a_split_and_explicit_without() {
    let h = 0.01;
    let opts = SolverOptions {
        dt: Some(h),
        ..with(Method::Euler, SolverOptions::default())
    };
    for position_rate in [true, false] {
        let sys = SplitOscillator { position_rate };
        let sol = solve(sys, (0.0, 1.0), &[1.0, 0.0], &opts, &mut []).unwrap();
        let (mut q, mut v) = (1.0f64, 0.0f64);
        for k in 1..sol.t.len() {
            v += h * -q;
            q += h * v;
            assert_eq!(sol.state(k), &[q, v], "step {k}");
        }
        assert_eq!(sol.n_accepted, 100);
        // One evaluation per step, two when q̇ needs a full rhs call.
        assert_eq!(sol.nfev, if position_rate { 100 } else { 200 });
        // The symplectic map keeps q² + v² − h q v (a modified energy) exactly.
        let y = sol.state(sol.t.len() - 1);
        let inv = |q: f64, v: f64| q * q + v * v - h * q * v;
        assert!((inv(y[0], y[1]) - inv(1.0, 0.0)).abs() < 1e-13);
    }
    // Without a split: explicit Euler.
    let sol = solve(oscillator(), (0.0, 0.05), &[0.0, 1.0], &opts, &mut []).unwrap();
    let (mut a, mut b) = (0.0f64, 1.0f64);
    let n = sol.t.len();
    for k in 1..n {
        // The last step lands on t_end: h = t_end − t.
        let _ = n;
        (a, b) = (a + h * b, b + h * -a);
        assert_eq!(sol.state(k), &[a, b]);
    }
}

#[test]
fn fixed_steps_land_on_t_end_and_dense_output_is_hermite() {
    // 0.25 / 0.1: two full steps and a shortened last one of 0.05; backwards too.
    for (span, times) in [
        ((0.0, 0.25), vec![0.0, 0.1, 0.2, 0.25]),
        ((1.0, 0.75), vec![1.0, 0.9, 0.8, 0.75]),
    ] {
        let opts = SolverOptions {
            dt: Some(0.1),
            dense: true,
            ..with(Method::Rk4, SolverOptions::default())
        };
        let sol = solve(oscillator(), span, &[0.0, 1.0], &opts, &mut []).unwrap();
        for (a, b) in sol.t.iter().zip(&times) {
            assert!((a - b).abs() < 1e-15, "{:?}", sol.t);
        }
        assert_eq!(*sol.t.last().unwrap(), span.1);
        // The cubic Hermite interpolant reproduces the end states and is third order inside.
        let d = sol.dense.as_ref().unwrap();
        assert_eq!(d.kind(0), Interpolant::Hermite);
        for k in 0..sol.t.len() {
            let y = sol.dense_eval(sol.t[k]).unwrap();
            assert!((y[0] - sol.state(k)[0]).abs() < 1e-15);
        }
        let tm = 0.5 * (sol.t[0] + sol.t[1]);
        let y = sol.dense_eval(tm).unwrap();
        let exact = (tm - span.0).sin();
        assert!((y[0] - exact).abs() < 1e-5, "{y:?} vs {exact}");
    }
    // A step a hair short of t_end ends there instead of leaving a sliver.
    let opts = SolverOptions {
        dt: Some(0.1),
        ..with(Method::Euler, SolverOptions::default())
    };
    let sol = solve(
        oscillator(),
        (0.0, 0.3 + 1e-12),
        &[0.0, 1.0],
        &opts,
        &mut [],
    )
    .unwrap();
    assert_eq!(sol.n_accepted, 3);
}

#[test]
fn bad_method_arguments_are_named() {
    let run = |opts: SolverOptions| solve(oscillator(), (0.0, 1.0), &[0.0, 1.0], &opts, &mut []);
    let e = run(with(Method::Rk4, SolverOptions::default())).unwrap_err();
    assert_eq!(e, InputError::DtMissing { method: "RK4" });
    assert_eq!(e.argument(), "dt");
    assert!(e
        .to_string()
        .starts_with("dt: method 'RK4' takes a fixed step"));
    let e = run(SolverOptions {
        dt: Some(-1.0),
        ..with(Method::Euler, SolverOptions::default())
    })
    .unwrap_err();
    assert_eq!(e, InputError::DtInvalid(-1.0));
    let e = run(SolverOptions {
        dt: Some(0.1),
        ..with(Method::Dop853, SolverOptions::default())
    })
    .unwrap_err();
    assert_eq!(e.argument(), "dt");
    assert_eq!("dop853".parse::<Method>(), Ok(Method::Dop853));
    let e = "RK5".parse::<Method>().unwrap_err();
    assert_eq!(e.argument(), "method");
    assert!(e.to_string().contains("got 'RK5'"), "{e}");
}

/// `y' = −1000 (y − cos t)`: stiff once the transient has died (|λ| = 1000).
fn stiff() -> super::fixtures::TestSystem {
    crate::integrator::FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
        dy[0] = -1000.0 * (y[0] - t.cos());
        Ok(())
    })
}

/// A stand-in for Radau in `auto`: RK4 at a fixed step from the switch on.
fn rk4_double<S: OdeSystem>(
    sys: S,
    t: f64,
    y: &[f64],
    t_end: f64,
    opts: &SolverOptions,
) -> Result<FixedStep<S, crate::integrator::Rk4>, InputError> {
    let opts = SolverOptions {
        dt: Some(1e-3),
        ..opts.clone()
    };
    FixedStep::new(sys, t, y, t_end, &opts)
}

#[test]
fn auto_switches_at_the_stiffness_detection_and_continues_from_there() {
    let opts = SolverOptions {
        dense: true,
        ..with(Method::Auto, tol(1e-6))
    };
    let y0 = [0.0];
    let sol = crate::integrator::driver_auto(stiff(), (0.0, 2.0), &y0, &opts, &mut [], rk4_double)
        .unwrap();
    assert_eq!(sol.status, Status::Success);
    assert_eq!(sol.method, Method::Auto);
    assert_eq!(sol.switched_to, Some(Method::Radau));
    let ts = sol.t_switch.unwrap();
    // RK45 alone, stopping at the detection, stops exactly there.
    let first = SolverOptions {
        stiffness: crate::integrator::StiffnessCheck::Stop,
        ..tol(1e-6)
    };
    let alone = crate::integrator::rk45(stiff(), (0.0, 2.0), &y0, &first, &mut []).unwrap();
    let Status::Stiff { t, .. } = alone.status else {
        panic!("{:?}", alone.status)
    };
    assert_eq!(t, ts);
    assert!(
        sol.message.contains("switched from RK45 to Radau"),
        "{}",
        sol.message
    );
    // Same steps as RK45 up to the switch, then 1e-3 steps to t = 2.
    let n1 = alone.n_accepted;
    assert_eq!(&sol.t[..=n1], &alone.t[..]);
    let n2 = ((2.0 - ts) / 1e-3 - 1e-9).ceil() as usize;
    assert_eq!(sol.n_accepted, n1 + n2);
    // (+1: the last step's interpolant needs f(t_end), which no next step provides.)
    assert_eq!(sol.nfev, alone.nfev + 4 * n2 + 1);
    // The dense output carries both kinds; the solution follows the slow manifold
    // y ≈ cos t + 1e-3 sin t.
    let d = sol.dense.as_ref().unwrap();
    assert_eq!(d.kind(0), Interpolant::Rk45);
    assert_eq!(d.kind(d.n_segments() - 1), Interpolant::Hermite);
    let y = sol.state(sol.t.len() - 1)[0];
    let slow = 2f64.cos() + 1e-3 * 2f64.sin();
    assert!((y - slow).abs() < 1e-5, "{y} vs {slow}");
}

#[test]
fn every_method_is_an_integrator_with_counts() {
    let st = Stepper::new(krogh(), 0.0, &[0.0, 1.0, 1.0], 1.0, &tol(1e-6)).unwrap();
    assert_eq!(
        (st.t(), st.t_old(), st.y_old()),
        (0.0, 0.0, &[0.0, 1.0, 1.0][..])
    );
    assert_eq!(Integrator::counts(&st).nfev, 0);
}

/// At tight tolerances `auto` starts on Adams (cheaper there): on `y' = −1e4 (y − cos t)` at
/// rtol = atol = 1e-9 (where DOP853's stiffness test would fire only at t ≈ 1.26, Adams's
/// at t ≈ 0.23; docs/integrators.md) it switches where Adams alone, stopping at its
/// detection, stops, and says so.
#[test]
fn auto_starts_on_adams_at_tight_tolerances() {
    let stiffer = || {
        crate::integrator::FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
            dy[0] = -1e4 * (y[0] - t.cos());
            Ok(())
        })
    };
    let tight = 0.1 * crate::integrator::AUTO_ADAMS_RTOL;
    let opts = with(Method::Auto, tol(tight));
    let y0 = [0.0];
    let sol =
        crate::integrator::driver_auto(stiffer(), (0.0, 2.0), &y0, &opts, &mut [], rk4_double)
            .unwrap();
    assert_eq!(sol.switched_to, Some(Method::Radau));
    let first = SolverOptions {
        stiffness: crate::integrator::StiffnessCheck::Stop,
        ..with(Method::Adams, tol(tight))
    };
    let alone = solve(stiffer(), (0.0, 2.0), &y0, &first, &mut []).unwrap();
    let Status::Stiff { t, .. } = alone.status else {
        panic!("{:?}", alone.status)
    };
    assert!(t < 0.5, "{t}");
    assert_eq!(sol.t_switch, Some(t));
    assert!(
        sol.message.contains("switched from Adams to Radau"),
        "{}",
        sol.message
    );
    assert_eq!(&sol.t[..=alone.n_accepted], &alone.t[..]);
}
