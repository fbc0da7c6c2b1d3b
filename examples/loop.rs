//! A plain loop of calls, for instruction counts (callgrind) and quick timings, steadier on a
//! shared machine than criterion's wall times:
//!
//! ```text
//! cargo build --release --example loop --features benchmark-models
//! valgrind --tool=callgrind target/release/examples/loop fd 7 100000   # ÷ 100000 per call
//! target/release/examples/loop scene python/pointmass_dyn/scenes/panda.toml 1000000
//! ```
//!
//! `fd`, `id`, `gim`, `idd`, `fdd` (inverse and forward dynamics derivatives) N ITERS: the benchmark chain of N links (q = 0.3, v_k = sin 0.7k,
//! τ_k = cos 0.3k); `iddr`, `fddr`: the same derivatives by rows (`DerivativeData::row_major`,
//! what the bindings use past 32 dofs), the inverse's straight into C-ordered buffers; `scene` PATH ITERS: forward dynamics of a scene file's model (its tree);
//! `sidd`, `sfdd` PATH ITERS: its inverse and forward dynamics derivatives (q as `scene`'s);
//! `loops` PATH ITERS: the same with its loops closed, at the scene's (closed) initial state;
//! `sim` N ITERS: ITERS runs of `simulate` (RK45, rtol 1e-6, t in (0, 1)) of the chain, gravity
//! on (the integrator's whole loop: stages, error norm, output); `loopsim` PATH ITERS: ITERS
//! runs of `simulate` of a scene with loops (its effects, q0, v0; DOP853, rtol 1e-10,
//! atol 1e-12, t in (0, 20): IFToMM A02's high-precision run), printing the time per
//! right-hand side; `along` PATH ITERS: ITERS passes of `simulate::along` (the shaking, one
//! thread) over the states of one run of the scene (DOP853, rtol 1e-8, t in (0, 1));
//! `adams`/`dop853` N ITERS: ITERS runs of the chain without effects
//! (rtol = atol = 1e-9, t in (0, 1)) with that method, the evaluations counted (instructions
//! per evaluation: the method's own cost beside the forward dynamics'). Subtract a
//! run with ITERS = 0 to remove the setup. If valgrind stops at an AVX instruction it does not
//! decode, `POINTMASS_DYN_BASELINE=1` counts the baseline build instead (`pointmass_dyn::support::cpu`).
use std::hint::black_box;

use nalgebra::DMatrix;
use pointmass_dyn::benchmark_models::chain;
use pointmass_dyn::io::scene::Scene;
use pointmass_dyn::model::Model;
use pointmass_dyn::recursive::{self, Data};
use pointmass_dyn::support::spatial::Vec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage =
        "usage: loop (fd|id|gim|idd|fdd|iddr|fddr|sim|adams|dop853) N ITERS | loop (scene|loops|loopsim|along|sfdd|sidd) PATH ITERS";
    let (what, arg, iters) = match args.as_slice() {
        [_, w, a, i] => (w.as_str(), a.as_str(), i.parse::<usize>()?),
        _ => return Err(usage.into()),
    };
    let scene = match what {
        "scene" | "loops" | "loopsim" | "along" | "sfdd" | "sidd" => {
            Some(Scene::from_toml(&std::fs::read_to_string(arg)?, arg)?)
        }
        _ => None,
    };
    let model: Model = match &scene {
        Some(s) => (*s.model).clone(),
        None => chain(arg.parse()?),
    };
    let nv = model.nv;
    let q: Vec<f64> = match (what, &scene) {
        ("loops" | "loopsim" | "along", Some(s)) => s.q0.clone(),
        ("scene" | "sfdd" | "sidd", _) => (0..model.nq).map(|k| 0.3 + 0.1 * k as f64).collect(),
        _ => vec![0.3; model.nq],
    };
    let v: Vec<f64> = match (what, &scene) {
        ("loops" | "loopsim" | "along", Some(s)) => s.v0.clone(),
        _ => (0..nv).map(|k| (k as f64 * 0.7).sin()).collect(),
    };
    let mut solver = pointmass_dyn::loops::LoopSolver::new(&model);
    let tau: Vec<f64> = (0..nv).map(|k| (k as f64 * 0.3).cos()).collect();
    let g = Vec3::new(0.0, 0.0, -9.81);
    let mut data = Data::new(&model);
    let mut out = vec![0.0; nv];
    let mut gim = DMatrix::zeros(nv, nv);
    let mut dd = recursive::DerivativeData::new(&model);
    dd.row_major = matches!(what, "iddr" | "fddr");
    let mut rows = vec![0.0; 3 * nv * nv];
    // `along`: the states of one run (DOP853, rtol 1e-8, t in (0, 1)), its shaking per pass.
    let states = match (what, &scene) {
        ("along", Some(s)) => {
            let opts = pointmass_dyn::integrator::SolverOptions {
                method: pointmass_dyn::integrator::Method::Dop853,
                rtol: 1e-8.into(),
                atol: 1e-10.into(),
                ..Default::default()
            };
            let tr = run(&model, &s.effects, &q, &v, 1.0, &opts)?;
            eprintln!("along: {} states a pass", tr.t.len());
            Some(tr)
        }
        _ => None,
    };
    let start = std::time::Instant::now();
    let mut nfev = 0;
    for _ in 0..iters {
        match what {
            "fd" | "scene" => {
                let q = black_box(&q);
                recursive::forward_dynamics(&model, &mut data, q, &v, &tau, &g, None, &mut out)?
            }
            "id" => {
                let q = black_box(&q);
                recursive::inverse_dynamics(&model, &mut data, q, &v, &tau, &g, None, &mut out)
            }
            "gim" => recursive::mass_matrix(&model, &mut data, black_box(&q), &mut gim),
            "idd" | "sidd" => {
                let q = black_box(&q);
                recursive::inverse_dynamics_derivatives(&model, &mut data, &mut dd, q, &v, &tau, &g)
            }
            "iddr" => {
                let (dq, rest) = rows.split_at_mut(nv * nv);
                let (dv, mm) = rest.split_at_mut(nv * nv);
                let q = black_box(&q);
                recursive::inverse_dynamics_derivatives_into(
                    &model,
                    &mut data,
                    &mut dd,
                    q,
                    &v,
                    &tau,
                    &g,
                    [dq, dv, mm],
                )
            }
            "fdd" | "sfdd" | "fddr" => {
                let q = black_box(&q);
                recursive::forward_dynamics_derivatives(
                    &model, &mut data, &mut dd, q, &v, &tau, &g,
                )?
            }
            "sim" => {
                let opts = pointmass_dyn::integrator::SolverOptions {
                    rtol: 1e-6.into(),
                    atol: 1e-8.into(),
                    ..Default::default()
                };
                let tr = run(&model, &[], black_box(&q), &v, 1.0, &opts)?;
                out[0] = tr.q[tr.q.len() - 1];
            }
            "adams" | "dop853" => {
                // The cost per right-hand side of each method at a tight tolerance: the
                // evaluations are the same forward dynamics, the rest is the method's own.
                let opts = pointmass_dyn::integrator::SolverOptions {
                    method: if what == "adams" {
                        pointmass_dyn::integrator::Method::Adams
                    } else {
                        pointmass_dyn::integrator::Method::Dop853
                    },
                    rtol: 1e-9.into(),
                    atol: 1e-9.into(),
                    ..Default::default()
                };
                let tr = run(&model, &[], black_box(&q), &v, 1.0, &opts)?;
                nfev += tr.nfev;
                out[0] = tr.q[tr.q.len() - 1];
            }
            "loopsim" => {
                let Some(s) = &scene else {
                    return Err(usage.into());
                };
                let opts = pointmass_dyn::integrator::SolverOptions {
                    method: pointmass_dyn::integrator::Method::Dop853,
                    rtol: 1e-10.into(),
                    atol: 1e-12.into(),
                    max_steps: 2_000_000,
                    ..Default::default()
                };
                let tr = run(&model, &s.effects, black_box(&q), &v, 20.0, &opts)?;
                nfev += tr.nfev;
                out[0] = tr.q[tr.q.len() - 1];
            }
            "along" => {
                let (Some(s), Some(tr)) = (&scene, &states) else {
                    return Err(usage.into());
                };
                let asked = pointmass_dyn::simulate::Asked {
                    shaking: Some(Vec3::zeros()),
                    ..Default::default()
                };
                let x = (&tr.t[..], black_box(&tr.q[..]), &tr.v[..]);
                let r = pointmass_dyn::simulate::along(
                    &model,
                    &s.effects,
                    Default::default(),
                    x,
                    asked,
                    1,
                )?;
                out[0] = r.shaking[0];
                nfev += tr.t.len();
            }
            "loops" => {
                let q = black_box(&q);
                recursive::forward_dynamics(&model, &mut data, q, &v, &tau, &g, None, &mut out)?;
                pointmass_dyn::loops::constrained_forward_dynamics(
                    &model,
                    &mut data,
                    &mut solver,
                    q,
                    &v,
                    &mut out,
                )?
            }
            _ => return Err(usage.into()),
        }
    }
    let per_call = start.elapsed().as_secs_f64() / iters.max(1) as f64;
    println!("{what} {arg}: {:.1} ns per call", per_call * 1e9);
    if nfev > 0 {
        let per_rhs = start.elapsed().as_secs_f64() / nfev as f64;
        println!(
            "{nfev} right-hand sides (along: samples): {:.3} µs each",
            per_rhs * 1e6
        );
        println!("last state's q[0] = {:.17e}", out[0]);
    }
    black_box((&out, &gim, &dd.dtau_dq, &rows));
    Ok(())
}

/// A run from `(q, v)` over `(0, t_end)` with `effects`, no events, default recording.
fn run(
    model: &pointmass_dyn::Model,
    effects: &[pointmass_dyn::effects::Effect],
    q: &[f64],
    v: &[f64],
    t_end: f64,
    opts: &pointmass_dyn::integrator::SolverOptions,
) -> pointmass_dyn::Result<pointmass_dyn::simulate::Trajectory> {
    pointmass_dyn::simulate::simulate(
        model,
        effects,
        Default::default(),
        q,
        v,
        (0.0, t_end),
        opts,
        &[],
        Vec::new(),
        Default::default(),
        None,
    )
}
