//! The design maps against the dynamics computed directly (shaking from the point motion,
//! driving and bearing forces from Newton–Euler with the loops' own solve), and the conic
//! program against problems with known solutions.
use nalgebra::{DMatrix, DVector};

use super::*;
use crate::dynamics::reactions;
use crate::loops::{self, LoopSolver};
use crate::model::Model;
use crate::recursive::reference::Workspace;
use crate::support::spatial::{linear, Vec3, Vec6};

fn fourbar() -> (Model, Vec<f64>) {
    let scene = crate::io::scene::Scene::from_toml(
        include_str!("../../../python/pointmass_dyn/scenes/fourbar.toml"),
        "fourbar.toml",
    )
    .unwrap();
    ((*scene.model).clone(), scene.q0.clone())
}

/// A closed state of the four-bar with the crank at `theta`, turning at `speed` and
/// accelerating at `alpha`.
fn fourbar_state(model: &Model, q0: &[f64], theta: f64, speed: f64, alpha: f64) -> [Vec<f64>; 3] {
    let fixed = [true, false, false];
    let mut guess = q0.to_vec();
    guess[0] = theta;
    let q = loops::assemble(model, &guess, &fixed, 1e-13, 50).unwrap();
    let mut v = vec![speed, 0.0, 0.0];
    loops::project_velocity_like(model, &q, None, &mut v, &fixed).unwrap();
    let mut a = vec![alpha, 0.0, 0.0];
    loops::project_velocity_like(model, &q, Some(&v), &mut a, &fixed).unwrap();
    [q, v, a]
}

/// Shaking, driving forces, bearing and cut forces computed directly, in the regressor's
/// row order.
fn direct(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    about: &Vec3,
    act: &[usize],
) -> Vec<f64> {
    let mut ws = Workspace::new(model);
    let mut pm = reactions::PointMotion::default();
    reactions::point_motion(model, &mut ws, q, v, a, &mut pm);
    let (f, m) = reactions::shaking(&pm, about);
    let mut out: Vec<f64> = f.iter().chain(m.iter()).copied().collect();
    let mut tree = vec![0.0; model.nv];
    let mut ws2 = Workspace::new(model);
    crate::recursive::reference::inverse_dynamics_world(
        model, &mut ws2, q, v, a, g, None, &mut tree,
    );
    let (tau, cut) = if model.loops.is_empty() {
        (tree.clone(), vec![])
    } else {
        let mut solver = LoopSolver::new(model);
        loops::driving_forces(model, &mut solver, q, v, a, &tree, act).unwrap()
    };
    out.extend(act.iter().map(|&c| tau[c]));
    reactions::link_accelerations(model, &mut ws, q, v, a);
    let mut ext = vec![Vec6::zeros(); model.links.len()];
    reactions::add_cut_wrenches(model, &ws, &cut, &mut ext);
    let mut t = vec![0.0; model.nv];
    let w = reactions::joint_wrenches(model, &mut ws, q, v, a, g, Some(&ext), &mut t);
    for wi in &w {
        out.extend(linear(wi).iter());
    }
    for c in &cut {
        out.extend(&c[..3]);
    }
    out
}

fn check_against_direct(model: &Model, states: &[[Vec<f64>; 3]], act: &[usize]) {
    let g = Vec3::new(0.0, -9.81, 0.0);
    let about = Vec3::new(0.02, -0.01, 0.0);
    let (q, v, a): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        states.iter().flat_map(|s| s[0].clone()).collect(),
        states.iter().flat_map(|s| s[1].clone()).collect(),
        states.iter().flat_map(|s| s[2].clone()).collect(),
    );
    let reg = regressor(model, &q, &v, &a, &g, &about, act).unwrap();
    let phi = DVector::from_vec(model_parameters(model));
    let rows = reg.layout.rows();
    for (k, s) in states.iter().enumerate() {
        let want = direct(model, &s[0], &s[1], &s[2], &g, &about, act);
        let got = reg.data.rows(k * rows, rows) * &phi;
        let scale = want.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (r, (x, y)) in got.iter().zip(&want).enumerate() {
            assert!(
                (x - y).abs() <= 1e-10 * scale,
                "sample {k} row {r}: {x} vs {y}"
            );
        }
    }
}

#[test]
fn the_maps_reproduce_the_dynamics_of_a_tree() {
    let model = crate::benchmark_models::chain(4);
    let states: Vec<[Vec<f64>; 3]> = (0..3)
        .map(|k| {
            let f = |i: usize, s: f64| ((i * 7 + k * 3) as f64 * 0.37 + s).sin();
            [
                (0..model.nq).map(|i| f(i, 0.1)).collect(),
                (0..model.nv).map(|i| 2.0 * f(i, 1.3)).collect(),
                (0..model.nv).map(|i| 5.0 * f(i, 2.1)).collect(),
            ]
        })
        .collect();
    let act: Vec<usize> = (0..model.nv).collect();
    check_against_direct(&model, &states, &act);
}

#[test]
fn the_maps_reproduce_the_dynamics_of_a_fourbar_with_its_cut_joint() {
    let (model, q0) = fourbar();
    let states: Vec<[Vec<f64>; 3]> = [0.3, 1.9, 4.0]
        .iter()
        .map(|&th| fourbar_state(&model, &q0, th, 30.0, 7.0))
        .collect();
    check_against_direct(&model, &states, &[0]);
}

#[test]
fn bad_regressor_input_is_refused() {
    let (model, q0) = fourbar();
    let g = Vec3::zeros();
    assert!(regressor(&model, &q0, &[0.0; 3], &[0.0; 3], &g, &g, &[]).is_err());
    assert!(regressor(&model, &q0, &[0.0; 2], &[0.0; 3], &g, &g, &[0]).is_err());
    assert!(regressor(&model, &q0, &[0.0; 3], &[0.0; 3], &g, &g, &[5]).is_err());
}

/// min Σ w ‖y‖² with y = x₁ e₁ + x₂ e₂ − (1, 2): a least-squares problem with bounds.
fn toy(norm: Norm, limit: Option<f64>, upper: f64) -> Problem {
    let rows = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]);
    Problem {
        lower: vec![0.0, 0.0],
        upper: vec![upper, upper],
        map: vec![(0, 0, 1.0), (1, 1, 1.0)],
        ndelta: 2,
        groups: vec![],
        equal: vec![],
        quantities: vec![Quantity {
            peak: false,
            name: "y".into(),
            rows,
            constant: DVector::from_vec(vec![-1.0, -2.0]),
            dim: 2,
            samples: 1,
            weight: 1.0,
            reference: 5f64.sqrt(),
            limit,
            zero: false,
        }],
        norm,
        mass_weight: 0.0,
        mass_reference: 1.0,
        mass_limit: None,
        least_mass: false,
        flows: vec![],
    }
}

#[test]
fn the_program_finds_known_optima() {
    // Unconstrained: y = 0 at x = (1, 2).
    let s = solve(&toy(Norm::Rms, None, 10.0)).unwrap();
    assert!(
        (s.x[0] - 1.0).abs() < 1e-8 && (s.x[1] - 2.0).abs() < 1e-8,
        "{:?}",
        s.x
    );
    assert!(s.gap_abs <= 1e-8, "{}", s.gap_abs);
    // Bounded by 1.5: x = (1, 1.5), |y| = 0.5 (a norm is flat to first order across its
    // minimiser, so x₁ is found to about the square root of the gap only).
    let s = solve(&toy(Norm::Peak, None, 1.5)).unwrap();
    assert!(
        (s.x[0] - 1.0).abs() < 1e-4 && (s.x[1] - 1.5).abs() < 1e-8,
        "{:?}",
        s.x
    );
    assert!((s.values[0] - 0.5).abs() < 1e-8);
    // A limit no bounded design meets.
    let err = solve(&toy(Norm::Peak, Some(0.1), 1.5)).unwrap_err();
    assert!(err.to_string().contains("limits"), "{err}");
    // ...by how much: the least peak within the bounds is 0.5 (x = (1, 1.5)).
    let Ok(Outcome::Infeasible(r)) = solve_outcome(&toy(Norm::Peak, Some(0.1), 1.5)) else {
        panic!("expected an infeasible outcome");
    };
    assert!(r.items.len() == 1 && r.items[0].binding());
    assert!((r.items[0].needed - 0.5).abs() < 1e-7, "{r:?}");
    assert_eq!(r.items[0].alone, Some(r.items[0].needed));
    assert!(err.to_string().contains("needs 5.0000e-1"), "{err}");
    // Least mass among equal optima: y depends on x₁ + 2 x₂ only, so x = (0, ½).
    let mut p = toy(Norm::Rms, None, 10.0);
    p.quantities[0].constant = DVector::from_vec(vec![-1.0, 0.0]);
    p.map = vec![(0, 0, 1.0), (0, 1, 2.0)];
    p.least_mass = true;
    let s = solve(&p).unwrap();
    assert!(
        s.x[0].abs() < 1e-8 && (s.x[1] - 0.5).abs() < 1e-8,
        "{:?}",
        s.x
    );
}

/// Cutting planes over samples: y_b = x − p_b for 360 points on an arc of 0.9π of a unit
/// circle about (3, 4) (its ends the first and last samples); the least peak is the
/// smallest enclosing circle's radius, sin 0.45π, centred on the ends' chord — found from a
/// subset of the samples (the last end is not in the first one), every sample then within.
#[test]
fn peak_programs_by_active_samples_reach_the_full_optimum() {
    let n = 360;
    let arc = 0.9 * std::f64::consts::PI;
    let mut rows = DMatrix::zeros(2 * n, 2);
    let mut constant = DVector::zeros(2 * n);
    for b in 0..n {
        let a = arc * b as f64 / (n - 1) as f64;
        rows[(2 * b, 0)] = 1.0;
        rows[(2 * b + 1, 1)] = 1.0;
        constant[2 * b] = -(3.0 + a.cos());
        constant[2 * b + 1] = -(4.0 + a.sin());
    }
    let mut p = toy(Norm::Peak, None, 10.0);
    p.quantities[0].rows = rows;
    p.quantities[0].constant = constant;
    p.quantities[0].samples = n;
    p.quantities[0].reference = 1.0;
    let s = solve(&p).unwrap();
    assert!(
        (s.values[0] - (arc / 2.0).sin()).abs() < 1e-8,
        "{:?}",
        s.values
    );
    let center = [3.0 + (1.0 + arc.cos()) / 2.0, 4.0 + arc.sin() / 2.0];
    assert!(
        (s.x[0] - center[0]).abs() < 1e-4 && (s.x[1] - center[1]).abs() < 1e-4,
        "{:?}",
        s.x
    );
    assert!(s.rounds > 1, "{}", s.rounds);
}
