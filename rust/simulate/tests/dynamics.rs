//! The loop hooks Radau uses (`filter_error`, `chain_projection`) against finite differences
//! of the right-hand side as integrated and the closure residual.
use super::Dynamics;
use crate::effects::{Disabled, Effect};
use crate::integrator::OdeSystem;
use crate::joint::Joint;
use crate::loops::{self, LoopKinematics};
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::spatial::{Mat3, Placement, Vec3};

fn at(x: f64) -> Placement {
    Placement::new(Mat3::identity(), Vec3::new(x, 0.0, 0.0))
}

fn rod(length: f64, mass: f64) -> RigidBody {
    let i = mass * length * length / 12.0;
    RigidBody::new(
        mass,
        Vec3::new(length / 2.0, 0.0, 0.0),
        Mat3::from_diagonal(&Vec3::new(1e-6, i, i)),
    )
    .unwrap()
}

/// A planar four-bar (ground 0.6, crank 0.3, coupler 0.8, rocker 0.5), away from its
/// change points, and a closed state of it moving.
fn four_bar() -> (Model, Vec<f64>) {
    let z = || Joint::revolute(Vec3::z()).unwrap();
    let mut m = Model::new();
    m.add_body(rod(0.3, 0.5), z(), None, at(0.0), None, None)
        .unwrap();
    m.add_body(rod(0.8, 1.5), z(), Some(0), at(0.3), None, None)
        .unwrap();
    m.add_body(rod(0.5, 0.7), z(), None, at(0.6), None, None)
        .unwrap();
    m.add_loop(Some(1), Some(2), z(), at(0.8), at(0.5), None)
        .unwrap();
    let q = loops::assemble(&m, &[1.2, -0.9, 1.9], &[true, false, false], 1e-14, 50).unwrap();
    let mut y = q;
    y.extend([2.0, -1.0, 0.5]);
    let mut solver = loops::LoopSolver::new(&m);
    loops::project_state(&m, &mut solver, &mut y).unwrap();
    (m, y)
}

fn gravity() -> Vec<Effect> {
    vec![Effect::gravity(Vec3::new(0.0, -9.81, 0.0)).unwrap()]
}

fn residual(m: &Model, q: &[f64]) -> f64 {
    let mut kin = LoopKinematics::new(m);
    kin.positions(m, q);
    let mut out = vec![0.0; m.nconstraints()];
    loops::residual(m, &kin, &mut out);
    out.iter().fold(0.0, |a, x| a.max(x.abs()))
}

#[test]
fn chained_jacobian_is_that_of_the_projected_right_hand_side() {
    let (m, y) = four_bar();
    let mut sys = Dynamics::try_new(&m, &gravity(), Disabled::none()).unwrap();
    let n = y.len();
    let mut jac = vec![0.0; n * n];
    assert!(sys.jacobian(0.0, &y, &mut jac).unwrap());
    let plain = jac.clone();
    assert!(sys.chain_projection(&y, &mut jac));
    // Central differences of `rhs`, which evaluates f at the stage's projection.
    let h = 1e-6;
    let (mut yp, mut fp, mut fm) = (y.clone(), vec![0.0; n], vec![0.0; n]);
    let (mut err_chained, mut err_plain, mut size) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..n {
        yp[k] = y[k] + h;
        sys.rhs(0.0, &yp, &mut fp).unwrap();
        yp[k] = y[k] - h;
        sys.rhs(0.0, &yp, &mut fm).unwrap();
        yp[k] = y[k];
        for i in 0..n {
            let d = (fp[i] - fm[i]) / (2.0 * h);
            err_chained = err_chained.max((jac[i * n + k] - d).abs());
            err_plain = err_plain.max((plain[i * n + k] - d).abs());
            size = size.max(d.abs());
        }
    }
    assert!(err_chained < 1e-6 * size, "{err_chained} of {size}");
    // `∂f/∂y` alone differs across the manifolds (the test has teeth).
    assert!(err_plain > 1e-2 * size, "{err_plain} of {size}");
}

#[test]
fn filtered_error_lands_on_the_manifolds_and_keeps_tangent_errors() {
    let (m, y) = four_bar();
    let mut sys = Dynamics::try_new(&m, &gravity(), Disabled::none()).unwrap();
    let n = y.len();
    let nq = m.nq;
    let raw: Vec<f64> = (0..n).map(|i| 1e-6 * (1.0 + i as f64).sin()).collect();
    let mut err = raw.clone();
    assert!(sys.filter_error(&y, &mut err));
    let moved = |e: &[f64]| -> Vec<f64> { y.iter().zip(e).map(|(a, b)| a + b).collect() };
    // Across the position manifold: the raw estimate opens the loop by ~1e-6, the filtered
    // one leaves it closed to round-off.
    assert!(residual(&m, &moved(&raw)[..nq]) > 1e-8);
    assert!(residual(&m, &moved(&err)[..nq]) < 1e-13);
    // A filtered estimate is tangent: filtering it again changes it by O(|err|²) only.
    let mut again = err.clone();
    assert!(sys.filter_error(&y, &mut again));
    let change = again
        .iter()
        .zip(&err)
        .fold(0.0f64, |a, (x, e)| a.max((x - e).abs()));
    assert!(change < 1e-10, "{change}");
    assert!(err.iter().any(|e| e.abs() > 1e-8));
}

#[test]
fn loop_free_systems_keep_the_plain_estimate_and_jacobian() {
    let m = crate::benchmark_models::chain(3);
    let mut sys = Dynamics::try_new(&m, &gravity(), Disabled::none()).unwrap();
    let n = m.nq + m.nv;
    let y = vec![0.1; n];
    let mut err = vec![1e-6; n];
    assert!(!sys.filter_error(&y, &mut err));
    assert!(err.iter().all(|&e| e == 1e-6));
    let mut jac = vec![0.5; n * n];
    assert!(!sys.chain_projection(&y, &mut jac));
    assert!(jac.iter().all(|&e| e == 0.5));
}

/// A parallelogram four-bar (all four bars 1 m): crank, coupler on its tip, rocker pinned
/// 1 m along; the cut joint closes the coupler's end on the rocker's tip. With every bar
/// turned by `phi` (the coupler level) it is closed for any `phi`; at `phi = 0` all bars are
/// collinear, the change point.
fn parallelogram_state(phi: f64) -> (Model, Vec<f64>) {
    let z = || Joint::revolute(Vec3::z()).unwrap();
    let mut m = Model::new();
    m.add_body(rod(1.0, 1.0), z(), None, at(0.0), None, None)
        .unwrap();
    m.add_body(rod(1.0, 1.0), z(), Some(0), at(1.0), None, None)
        .unwrap();
    m.add_body(rod(1.0, 1.0), z(), None, at(1.0), None, None)
        .unwrap();
    m.add_loop(Some(1), Some(2), z(), at(1.0), at(1.0), None)
        .unwrap();
    let y = vec![phi, -phi, phi, 1.0, -1.0, 1.0];
    (m, y)
}

#[test]
fn a_step_ended_at_a_singular_position_is_reported_with_its_time() {
    let (m, y_regular) = parallelogram_state(std::f64::consts::FRAC_PI_2);
    let mut sys = Dynamics::try_new(&m, &gravity(), Disabled::none()).unwrap();
    let mut dydt = vec![0.0; 6];
    let mut accepted = |sys: &mut Dynamics, t: f64, y: &[f64]| {
        let mut y = y.to_vec();
        sys.rhs(t, &y, &mut dydt).unwrap();
        sys.project(&mut y).unwrap();
        assert!(residual(&m, &y[..3]) < 1e-12);
    };
    accepted(&mut sys, 0.5, &y_regular);
    accepted(&mut sys, 0.7, &parallelogram_state(0.3).1);
    assert_eq!(sys.singular_passage, None);
    // 1e-9 rad from the change point (the rows' pivot ratio ~1e-9 of the upright state's),
    // then exactly at it (a row set aside): the first is the one reported.
    accepted(&mut sys, 1.25, &parallelogram_state(1e-9).1);
    let (t, ratio) = sys.singular_passage.expect("the passage at 1e-9 rad");
    assert_eq!(t, 1.25);
    assert!(ratio < 1e-7, "{ratio}");
    accepted(&mut sys, 1.5, &parallelogram_state(0.0).1);
    assert_eq!(sys.singular_passage.map(|p| p.0), Some(1.25));
    // A run that only starts there reports nothing: its best state so far is that one.
    let mut fresh = Dynamics::try_new(&m, &gravity(), Disabled::none()).unwrap();
    accepted(&mut fresh, 0.0, &parallelogram_state(0.0).1);
    accepted(&mut fresh, 0.1, &parallelogram_state(1e-3).1);
    assert_eq!(fresh.singular_passage, None);
}
