//! Verner 9(8): its order on a problem with a known solution (Kepler's elliptic orbit, the
//! error at halved fixed steps, of the steps and of the interpolant between them), its error
//! falling with the tolerance, and agreement with DOP853 at rtol 1e-13 on chain7, Panda and
//! the spatial pendulum (the scenes' dynamics); an ignored run prints work against error.
use super::fixtures::{observed_orders, tol};
use crate::integrator::{solve, FnSystem, Interpolant, Method, SolverOptions, Status};

pub(super) const ECC: f64 = 0.5;

/// The two-body problem `q'' = −q / |q|³` (state `(q, q')`), started at pericentre of the
/// orbit of eccentricity [`ECC`] (period 2π).
pub(super) fn kepler() -> FnSystem<fn(f64, &[f64], &mut [f64]) -> Result<(), String>> {
    FnSystem::new(4, |_t, y: &[f64], dy: &mut [f64]| {
        let r3 = (y[0] * y[0] + y[1] * y[1]).powf(1.5);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = -y[0] / r3;
        dy[3] = -y[1] / r3;
        Ok(())
    })
}

/// Kepler's orbit at `t` from Kepler's equation `E − e sin E = t` (Newton to convergence).
pub(super) fn kepler_exact(t: f64) -> [f64; 4] {
    let mut e_an = t;
    for _ in 0..50 {
        e_an -= (e_an - ECC * e_an.sin() - t) / (1.0 - ECC * e_an.cos());
    }
    let (s, c) = e_an.sin_cos();
    let b = (1.0 - ECC * ECC).sqrt();
    let d = 1.0 - ECC * c;
    [c - ECC, b * s, -s / d, b * c / d]
}

pub(super) fn kepler_y0() -> [f64; 4] {
    [1.0 - ECC, 0.0, 0.0, ((1.0 + ECC) / (1.0 - ECC)).sqrt()]
}

pub(super) fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Fixed steps `h`: every step accepted (tolerances far above the error) and capped at `h`.
fn fixed(h: f64, t_eval: Vec<f64>) -> SolverOptions {
    SolverOptions {
        method: Method::Vern9,
        first_step: Some(h),
        max_step: h,
        t_eval: Some(t_eval),
        ..tol(1e3)
    }
}

#[test]
fn vern9_is_of_order_nine_at_its_steps_and_between_them() {
    let t_end = 2.0;
    // Errors at t_end (a step end) and at t_end − h/2 (inside the last step: the interpolant).
    let (mut at_steps, mut between) = (vec![], vec![]);
    for n in [8, 16, 32] {
        let h = t_end / n as f64;
        let t_mid = t_end - 0.5 * h;
        let opts = fixed(h, vec![t_mid, t_end]);
        let sol = solve(kepler(), (0.0, t_end), &kepler_y0(), &opts, &mut []).unwrap();
        assert_eq!(sol.status, Status::Success);
        assert_eq!(sol.n_rejected, 0);
        assert!(
            sol.n_accepted == n || sol.n_accepted == n + 1,
            "fixed steps"
        );
        between.push(max_diff(sol.state(0), &kepler_exact(t_mid)));
        at_steps.push(max_diff(sol.state(1), &kepler_exact(t_end)));
    }
    // Halving h divides the error by 2⁹ = 512 (a method of order 8 would give 256).
    for (what, errs) in [("steps", &at_steps), ("interpolant", &between)] {
        let orders = observed_orders(errs);
        assert!(
            orders.iter().all(|p| (8.5..10.5).contains(p)),
            "{what}: errors {errs:?}, orders {orders:?}"
        );
    }
}

#[test]
fn vern9_error_falls_with_the_tolerance() {
    let t_end = 4.0 * std::f64::consts::PI;
    let exact = kepler_exact(t_end);
    let mut errs = vec![];
    for tl in [1e-7, 1e-9, 1e-11] {
        let opts = SolverOptions {
            method: Method::Vern9,
            ..tol(tl)
        };
        let sol = solve(kepler(), (0.0, t_end), &kepler_y0(), &opts, &mut []).unwrap();
        assert_eq!(sol.status, Status::Success);
        let err = max_diff(sol.state(sol.t.len() - 1), &exact);
        // Within a few hundred tolerances of the truth over two orbits.
        assert!(err < 300.0 * tl, "tol {tl}: error {err}");
        errs.push(err);
    }
    // A hundred times tighter, at least ten times more accurate.
    assert!(errs.windows(2).all(|w| w[1] < 0.1 * w[0]), "{errs:?}");
}

/// Work against error, Vern9 beside DOP853, on Kepler's orbit and chain7 (2 s):
/// `cargo test --lib vern9_work -- --ignored --nocapture` (figures, not a test).
#[test]
#[ignore]
fn vern9_work_precision() {
    let t_end = 4.0 * std::f64::consts::PI;
    let exact = kepler_exact(t_end);
    let reference = scene_run("chain7.toml", Method::Dop853, 1e-13, 2.0);
    for tl in [1e-4, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12] {
        for method in [Method::Dop853, Method::Vern9] {
            let opts = SolverOptions { method, ..tol(tl) };
            let sol = solve(kepler(), (0.0, t_end), &kepler_y0(), &opts, &mut []).unwrap();
            let err = max_diff(sol.state(sol.t.len() - 1), &exact);
            let (y, nfev) = scene_run_counted("chain7.toml", method, tl, 2.0);
            let err7 = max_diff(&y, &reference);
            println!(
                "{tl:.0e} {method}: Kepler nfev {} err {err:.1e}; chain7 nfev {nfev} err {err7:.1e}",
                sol.nfev
            );
        }
    }
}

#[test]
fn vern9_dense_output_is_its_interpolant() {
    let opts = SolverOptions {
        method: Method::Vern9,
        dense: true,
        ..tol(1e-10)
    };
    let sol = solve(kepler(), (0.0, 3.0), &kepler_y0(), &opts, &mut []).unwrap();
    let d = sol.dense.as_ref().unwrap();
    assert!((0..d.n_segments()).all(|s| d.kind(s) == Interpolant::Vern9));
    let mut y = [0.0; 4];
    for t in [0.1, 0.77, 1.3, 2.9] {
        d.eval_into(t, &mut y);
        let err = max_diff(&y, &kepler_exact(t));
        assert!(err < 1e-8, "t {t}: {err}");
    }
}

/// A scene run to `t_end`, the states at `t_eval`, with `method` at rtol = atol = `tl`.
pub(super) fn scene_run(path: &str, method: Method, tl: f64, t_end: f64) -> Vec<f64> {
    scene_run_counted(path, method, tl, t_end).0
}

/// [`scene_run`] and its evaluations.
pub(super) fn scene_run_counted(
    path: &str,
    method: Method,
    tl: f64,
    t_end: f64,
) -> (Vec<f64>, usize) {
    let file = format!(
        "{}/python/pointmass_dyn/scenes/{path}",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&file).unwrap();
    let scene = crate::io::scene::Scene::from_toml(&text, &file).unwrap();
    let t_eval: Vec<f64> = (1..=5).map(|k| t_end * k as f64 / 5.0).collect();
    let opts = SolverOptions {
        method,
        t_eval: Some(t_eval),
        max_steps: 10_000_000,
        ..tol(tl)
    };
    let tr = crate::simulate::simulate(
        &scene.model,
        &scene.effects,
        Default::default(),
        &scene.q0,
        &scene.v0,
        (0.0, t_end),
        &opts,
        &[],
        Vec::new(),
        Default::default(),
        None,
    )
    .unwrap();
    assert_eq!(tr.t.len(), 5, "{path}");
    (tr.q.iter().chain(&tr.v).copied().collect(), tr.nfev)
}

#[test]
fn vern9_agrees_with_dop853_on_the_scenes() {
    for (scene, t_end) in [
        ("chain7.toml", 1.0),
        ("panda.toml", 1.0),
        ("pendulum_spatial.toml", 3.0),
    ] {
        let reference = scene_run(scene, Method::Dop853, 1e-13, t_end);
        for (tl, bound) in [(1e-13, 1e-10), (1e-9, 1e-6)] {
            let ours = scene_run(scene, Method::Vern9, tl, t_end);
            let scale = reference.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            let err = max_diff(&ours, &reference) / scale;
            assert!(err < bound, "{scene} at rtol {tl}: {err:e}");
        }
    }
}

/// `cargo test --lib vern9_stiffness_detection -- --ignored --nocapture` (figures for
/// `auto`'s choice, docs/integrators.md): evaluations until the stiffness test stops DOP853
/// and Vern9 on `y' = −1e4 (y − cos t)` over 0–2, and to the end on Krogh (non-stiff).
#[test]
#[ignore]
fn vern9_stiffness_detection() {
    use crate::integrator::{Status, StiffnessCheck};
    let stiff = || {
        FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
            dy[0] = -1e4 * (y[0] - t.cos());
            Ok(())
        })
    };
    for tl in [1e-6, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12] {
        let mut row = format!("{tl:e}");
        for method in [Method::Dop853, Method::Vern9] {
            let opts = SolverOptions {
                method,
                stiffness: StiffnessCheck::Stop,
                ..super::fixtures::tol(tl)
            };
            let s = solve(stiff(), (0.0, 2.0), &[0.0], &opts, &mut []).unwrap();
            let k = solve(
                super::fixtures::krogh(),
                (0.0, 12.0),
                &[0.0, 1.0, 1.0],
                &opts,
                &mut [],
            )
            .unwrap();
            let at = match s.status {
                Status::Stiff { t, .. } => format!("stops at t={t:.4} after {}", s.nfev),
                _ => format!("never ({})", s.nfev),
            };
            row += &format!(" | {method:?}: stiff {at}; krogh {}", k.nfev);
        }
        println!("{row}");
    }
}
