//! Rust-native costs of forward dynamics, inverse dynamics, the GIM and one RK45 step on the
//! benchmark models of docs/benchmarks.md. `cargo bench --bench dynamics`.
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::DMatrix;
use pointmass_dyn::benchmark_models::{chain, paper_pendulum, tree};
use pointmass_dyn::effects::{Disabled, Effect};
use pointmass_dyn::integrator::{SolverOptions, Stepper};
use pointmass_dyn::model::Model;
use pointmass_dyn::recursive::{self, Data};
use pointmass_dyn::simulate::Dynamics;
use pointmass_dyn::support::spatial::Vec3;

const G: Vec3 = Vec3::new(0.0, 0.0, -9.81);

fn models() -> Vec<(String, Model)> {
    let mut out = vec![("pendulum".to_string(), paper_pendulum())];
    for n in [7, 30, 100, 300, 1000] {
        out.push((format!("chain{n}"), chain(n)));
    }
    out.push(("tree4x8".to_string(), tree(4, 8)));
    out
}

fn state(model: &Model) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut q = model.neutral();
    for l in &model.links {
        if l.joint.nq() == 1 || l.joint.nq() == 3 {
            for k in 0..l.joint.nq() {
                q[l.q_index + k] = 0.3 + 0.9 * k as f64;
            }
        }
    }
    let v: Vec<f64> = (0..model.nv).map(|k| (k as f64 * 0.7).sin()).collect();
    let u: Vec<f64> = (0..model.nv).map(|k| (k as f64 * 0.3).cos()).collect();
    (q, v, u)
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("forward_dynamics");
    for (name, model) in models() {
        let (q, v, tau) = state(&model);
        let mut data = Data::new(&model);
        let mut a = vec![0.0; model.nv];
        group.bench_function(BenchmarkId::from_parameter(&name), |b| {
            b.iter(|| {
                recursive::forward_dynamics(
                    &model,
                    &mut data,
                    black_box(&q),
                    black_box(&v),
                    black_box(&tau),
                    &G,
                    None,
                    &mut a,
                )
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("inverse_dynamics");
    for (name, model) in models() {
        let (q, v, acc) = state(&model);
        let mut data = Data::new(&model);
        let mut tau = vec![0.0; model.nv];
        group.bench_function(BenchmarkId::from_parameter(&name), |b| {
            b.iter(|| {
                recursive::inverse_dynamics(
                    &model,
                    &mut data,
                    black_box(&q),
                    black_box(&v),
                    black_box(&acc),
                    &G,
                    None,
                    &mut tau,
                )
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("mass_matrix");
    for (name, model) in models() {
        if model.nv > 300 {
            continue;
        }
        let (q, _, _) = state(&model);
        let mut data = Data::new(&model);
        let mut gim = DMatrix::zeros(model.nv, model.nv);
        group.bench_function(BenchmarkId::from_parameter(&name), |b| {
            b.iter(|| recursive::mass_matrix(&model, &mut data, black_box(&q), &mut gim))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("rk45_step");
    for (name, model) in models() {
        if model.nv > 300 {
            continue;
        }
        let (q, v, _) = state(&model);
        let y0: Vec<f64> = q.iter().chain(v.iter()).copied().collect();
        let effects = [Effect::Gravity { g: G }];
        let opts = SolverOptions {
            rtol: 1e-8.into(),
            atol: 1e-10.into(),
            max_step: 1e-3,
            ..Default::default()
        };
        group.bench_function(BenchmarkId::from_parameter(&name), |b| {
            b.iter_batched_ref(
                || {
                    let mut st = Stepper::new(
                        Dynamics::try_new(&model, &effects, Disabled::none())
                            .expect("gravity fits any model"),
                        0.0,
                        &y0,
                        1e9,
                        &opts,
                    )
                    .expect("valid options");
                    st.initialize().expect("initial step");
                    st
                },
                |st| st.step(),
                criterion::BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

/// The analytic derivatives (docs/derivatives.md): inverse (RNEA) and forward (ABA).
fn bench_derivatives(c: &mut Criterion) {
    for (label, forward) in [
        ("inverse_dynamics_derivatives", false),
        ("forward_dynamics_derivatives", true),
    ] {
        let mut group = c.benchmark_group(label);
        for (name, model) in models() {
            if model.nv > 300 {
                continue; // O(nv²) memory and O(nv³) time: beyond the compared sizes
            }
            let (q, v, u) = state(&model);
            let mut data = Data::new(&model);
            let mut dd = recursive::DerivativeData::new(&model);
            group.bench_function(BenchmarkId::from_parameter(&name), |b| {
                b.iter(|| {
                    if forward {
                        recursive::forward_dynamics_derivatives(
                            &model,
                            &mut data,
                            &mut dd,
                            black_box(&q),
                            black_box(&v),
                            black_box(&u),
                            &G,
                        )
                        .expect("regular configuration");
                    } else {
                        recursive::inverse_dynamics_derivatives(
                            &model,
                            &mut data,
                            &mut dd,
                            black_box(&q),
                            black_box(&v),
                            black_box(&u),
                            &G,
                        );
                    }
                })
            });
        }
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = bench, bench_derivatives
}
criterion_main!(benches);
