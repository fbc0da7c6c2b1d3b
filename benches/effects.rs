//! Cost of one right-hand-side evaluation (`q̇`, `v̇` of the simulate loop) with each effect
//! declared alone, on chain7 and chain100 (docs/benchmarks.md), against the bare forward dynamics.
//! A scene pays only for what it declares: `free` (no effect) ≈ `base`, `gravity` ≈ `free`
//! (gravity rides on the base acceleration), and `all, disable=...` costs what the remaining
//! effects cost. `cargo bench --bench effects`.
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use pointmass_dyn::benchmark_models::chain;
use pointmass_dyn::effects::{
    Damper, Disabled, Effect, External, Frame, Friction, JointRef, Matrix, PerJoint, Spring, Table,
    Torque,
};
use pointmass_dyn::integrator::OdeSystem;
use pointmass_dyn::model::Model;
use pointmass_dyn::recursive::{self, Data};
use pointmass_dyn::simulate::Dynamics;
use pointmass_dyn::support::spatial::Vec3;

fn table(cols: usize) -> Table {
    let time: Vec<f64> = (0..50).map(|k| 0.1 * k as f64).collect();
    let values: Vec<f64> = (0..50 * cols).map(|k| (k as f64 * 0.37).sin()).collect();
    Table::new(
        time,
        Matrix {
            values,
            rows: 50,
            cols,
            one_d: false,
        },
        "time",
        "values",
    )
    .expect("valid table")
}

/// Each configuration: a name, the declared effects and the disabled families.
fn configurations(model: &Model) -> Vec<(&'static str, Vec<Effect>, Disabled)> {
    let n = model.links.len();
    let g = Effect::Gravity {
        g: Vec3::new(0.0, 0.0, -9.81),
    };
    let spring = Effect::Spring(
        Spring::new(None, None, PerJoint::All(5.0), Some(PerJoint::All(0.1))).expect("spring"),
    );
    let damper = Effect::Damper(Damper::new(None, None, PerJoint::All(0.1)).expect("damper"));
    let friction = Effect::Friction(
        Friction::new(None, None, PerJoint::All(0.2), Some(1e-2)).expect("friction"),
    );
    let constant =
        Effect::Torque(Torque::constant(None, None, PerJoint::All(0.3)).expect("torque"));
    let tabulated = Effect::Torque(Torque::tabulated(None, None, table(n)).expect("table"));
    let pd = Effect::Torque(
        Torque::pd(
            None,
            None,
            PerJoint::All(10.0),
            PerJoint::All(1.0),
            table(n),
        )
        .expect("pd"),
    );
    let tip = Effect::External(
        External::constant(
            None,
            JointRef::Index(model.nbodies() - 1),
            Vec3::new(0.3, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 2.0),
            Vec3::zeros(),
            Frame::World,
        )
        .expect("external"),
    );
    let all = vec![
        g.clone(),
        spring.clone(),
        damper.clone(),
        friction.clone(),
        constant.clone(),
        tabulated.clone(),
        pd.clone(),
        tip.clone(),
    ];
    let off = Disabled::none();
    vec![
        ("free", vec![], off),
        ("gravity", vec![g.clone()], off),
        ("springs", vec![spring.clone()], off),
        ("dampers", vec![damper], off),
        ("friction", vec![friction], off),
        ("torque_constant", vec![constant], off),
        ("torque_table", vec![tabulated], off),
        ("torque_pd", vec![pd], off),
        ("external_tip", vec![tip], off),
        ("gravity+springs", vec![g.clone(), spring.clone()], off),
        (
            "gravity+springs, disable both",
            vec![g, spring],
            off.with(pointmass_dyn::effects::Kind::Gravity)
                .with(pointmass_dyn::effects::Kind::Springs),
        ),
        ("all", all.clone(), off),
        (
            "all, disable all",
            all,
            Disabled::parse(
                &[
                    "gravity", "springs", "dampers", "friction", "torques", "external",
                ],
                "disable",
            )
            .expect("names"),
        ),
    ]
}

fn bench(c: &mut Criterion) {
    for n in [7usize, 100] {
        let model = chain(n);
        let q: Vec<f64> = (0..model.nq)
            .map(|k| 0.3 + 0.1 * (k as f64).sin())
            .collect();
        let v: Vec<f64> = (0..model.nv).map(|k| (k as f64 * 0.7).sin()).collect();
        let y: Vec<f64> = q.iter().chain(v.iter()).copied().collect();
        let mut group = c.benchmark_group(format!("rhs_chain{n}"));
        // The bare O(n) forward dynamics, no effect, zero torque: the floor.
        let mut data = Data::new(&model);
        let tau = vec![0.0; model.nv];
        let mut a = vec![0.0; model.nv];
        group.bench_function(
            BenchmarkId::from_parameter("base (forward_dynamics)"),
            |b| {
                b.iter(|| {
                    recursive::forward_dynamics(
                        &model,
                        &mut data,
                        black_box(&q),
                        black_box(&v),
                        &tau,
                        &Vec3::zeros(),
                        None,
                        &mut a,
                    )
                })
            },
        );
        for (name, effects, disabled) in configurations(&model) {
            let mut sys = Dynamics::try_new(&model, &effects, disabled).expect("effects fit");
            let mut dydt = vec![0.0; y.len()];
            group.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| sys.rhs(black_box(0.73), black_box(&y), &mut dydt))
            });
        }
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = bench
}
criterion_main!(benches);
