//! Closed loops: forward dynamics per call of the four-bar and of Andrews' squeezing
//! mechanism (tree recursion + the cut joints' correction, docs/loops.md §3) beside the
//! tree alone, and a whole `simulate` of Andrews' mechanism to t = 0.03 s.
//! `cargo bench --bench loops`.
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use pointmass_dyn::effects::Disabled;
use pointmass_dyn::integrator::SolverOptions;
use pointmass_dyn::io::scene::Scene;
use pointmass_dyn::joint::Joint;
use pointmass_dyn::loops::{self, LoopSolver};
use pointmass_dyn::model::body::RigidBody;
use pointmass_dyn::model::Model;
use pointmass_dyn::recursive::{self, Data};
use pointmass_dyn::simulate::{simulate, Record};
use pointmass_dyn::support::spatial::{Mat3, Placement, Vec3};

const G: Vec3 = Vec3::new(0.0, -9.81, 0.0);

/// The four-bar of tests/test_loops.py: ground 0.4, crank 0.1, coupler 0.35, rocker 0.3.
fn four_bar() -> (Model, Vec<f64>, Vec<f64>) {
    let bar = |l: f64| {
        let i = l * l / 12.0 + 1e-4;
        RigidBody::new(
            1.0,
            Vec3::new(l / 2.0, 0.0, 0.0),
            Mat3::from_diagonal(&Vec3::new(1e-4, i, i)),
        )
        .expect("valid bar")
    };
    let z = Joint::revolute(Vec3::z()).expect("unit axis");
    let at = |x: f64| Placement::new(Mat3::identity(), Vec3::new(x, 0.0, 0.0));
    let mut m = Model::new();
    m.add_body(bar(0.1), z, None, at(0.0), Some("crank".into()), None)
        .expect("crank");
    m.add_body(bar(0.35), z, Some(0), at(0.1), Some("coupler".into()), None)
        .expect("coupler");
    m.add_body(bar(0.3), z, None, at(0.4), Some("rocker".into()), None)
        .expect("rocker");
    m.add_loop(Some(1), Some(2), z, at(0.35), at(0.3), None)
        .expect("loop");
    let held = [true, false, false];
    let q = loops::assemble(&m, &[0.5, 0.5, 1.5], &held, 1e-12, 50).expect("closes");
    let mut v = vec![2.0, 0.0, 0.0];
    loops::project_velocity_like(&m, &q, None, &mut v, &held).expect("velocity");
    (m, q, v)
}

fn andrews() -> Option<Scene> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/python/pointmass_dyn/scenes/andrews.toml"
    );
    Scene::from_file(std::path::Path::new(path)).ok()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("loops_forward_dynamics");
    let mut cases = vec![("four_bar".to_string(), four_bar())];
    if let Some(s) = andrews() {
        cases.push((
            "andrews".to_string(),
            ((*s.model).clone(), s.q0.clone(), s.v0.clone()),
        ));
    }
    for (name, (model, q, v)) in &cases {
        let tau = vec![0.1; model.nv];
        let mut data = Data::new(model);
        let mut solver = LoopSolver::new(model);
        let mut a = vec![0.0; model.nv];
        group.bench_function(format!("{name}/tree_only"), |b| {
            b.iter(|| {
                recursive::forward_dynamics(
                    model,
                    &mut data,
                    black_box(q),
                    v,
                    &tau,
                    &G,
                    None,
                    &mut a,
                )
            })
        });
        group.bench_function(format!("{name}/with_loops"), |b| {
            b.iter(|| {
                recursive::forward_dynamics(
                    model,
                    &mut data,
                    black_box(q),
                    v,
                    &tau,
                    &G,
                    None,
                    &mut a,
                )
                .and_then(|_| {
                    loops::constrained_forward_dynamics(model, &mut data, &mut solver, q, v, &mut a)
                })
            })
        });
    }
    group.finish();
    if let Some(s) = andrews() {
        let mut group = c.benchmark_group("loops_simulate");
        group.sample_size(10);
        let opts = SolverOptions {
            rtol: 1e-10.into(),
            atol: 1e-10.into(),
            ..SolverOptions::default()
        };
        group.bench_function("andrews_to_0.03", |b| {
            b.iter(|| {
                simulate(
                    &s.model,
                    &s.effects,
                    Disabled::none(),
                    &s.q0,
                    &s.v0,
                    (0.0, 0.03),
                    &opts,
                    &[],
                    Vec::new(),
                    Record::default(),
                    None,
                )
                .expect("runs")
            })
        });
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(300)).measurement_time(std::time::Duration::from_secs(1));
    targets = bench
}
criterion_main!(benches);
