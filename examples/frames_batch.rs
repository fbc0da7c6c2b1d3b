//! The batched frame and COM Jacobians of Panda's hand over ROWS configurations, ITERS
//! times: for instruction counts (callgrind) of `frames::batch`, steadier than wall times
//! on a shared machine, and for the thread threshold of `frames::rows`.
//!
//! ```text
//! cargo build --release --example frames_batch
//! valgrind --tool=callgrind target/release/examples/frames_batch jac 1000 20 URDF
//! target/release/examples/frames_batch split 0 0 URDF
//! ```
//!
//! `jac` (LOCAL frame Jacobian, benches/kinematics.py's case), `world`, `aligned` or `com`
//! (COM and its Jacobian); URDF is Panda's (example-robot-data). Subtract a run with
//! ITERS = 0 to remove the setup, then divide by ROWS × ITERS; the best time per row of the
//! calls is printed. `split`: the best time of blocks of 256..32,768 rows on one thread and
//! split over two (`frames::rows::split`), alternating, to place `ROWS_LINKS_PER_THREAD`.
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use pointmass_dyn::frames::{batch, evaluate, rows, ReferenceFrame};
use pointmass_dyn::io::urdf::{load_urdf, RootJoint};
use pointmass_dyn::kinematics::LinkState;
use pointmass_dyn::Model;

fn configurations(rows: usize, nq: usize) -> Vec<f64> {
    // Angles spread over ±2.5 rad by a fixed recurrence (no RNG dependency).
    let mut x = 0.123_f64;
    (0..rows * nq)
        .map(|_| {
            x = (x * 3.7 + 0.31).fract();
            5.0 * x - 2.5
        })
        .collect()
}

/// Best wall time of `f` over `reps` calls.
fn best(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The frame Jacobian (WORLD) of `n` rows on `threads` threads, as `evaluate` splits it.
fn jac_on(model: &Model, qs: &[f64], n: usize, threads: usize, out: &mut [f64]) {
    let f = model.frame_named("frame", "panda_hand").unwrap();
    let mut support: Vec<usize> = model.support(f.link).collect();
    support.reverse();
    let walk = batch::Walk::new(model, &support);
    let block = |first: usize,
                 count: usize,
                 o: &mut [f64],
                 _: &mut [f64],
                 poll: &dyn Fn() -> pointmass_dyn::Result<()>| {
        batch::frame_jacobian_rows(
            model,
            &walk,
            &f,
            ReferenceFrame::World,
            qs,
            first,
            count,
            o,
            poll,
        )
    };
    rows::split("split", n, threads, out, 6 * model.nv, &mut [], 0, block).unwrap();
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (what, rows, iters, path) = match &args[1..] {
        [w, r, i, p] => (w.as_str(), r.parse().unwrap(), i.parse().unwrap(), p),
        _ => panic!("usage: frames_batch jac|world|aligned|com|split ROWS ITERS URDF"),
    };
    let model = load_urdf(Path::new(path), RootJoint::Fixed).unwrap().model;
    let nv = model.nv;
    if what == "split" {
        let qs = configurations(32_768, model.nq);
        let mut out = vec![0.0; 32_768 * 6 * nv];
        for n in [256, 512, 1024, 2048, 4096, 8192, 16_384, 32_768] {
            let (mut one, mut two) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..5 {
                one = one.min(best(5, || jac_on(&model, &qs, n, 1, &mut out)));
                two = two.min(best(5, || jac_on(&model, &qs, n, 2, &mut out)));
            }
            println!(
                "{n:6} rows ({:7} rows x links): one thread {:8.1} us, two {:8.1} us, two/one {:.2}",
                n * model.links.len(),
                one * 1e6,
                two * 1e6,
                two / one
            );
        }
        return;
    }
    let qs = configurations(rows, model.nq);
    let f = model.frame_named("frame", "panda_hand").unwrap();
    let mut out = vec![0.0; rows * 6 * nv];
    let mut com = vec![0.0; rows * 3];
    // One row is computed in these links (the bindings lend a pooled workspace's).
    let mut links = vec![LinkState::default(); model.links.len()];
    let t = best(iters, || {
        match what {
            "com" => evaluate::com_batch(
                &model,
                &mut links,
                &qs,
                rows,
                true,
                &mut com,
                Some(&mut out[..rows * 3 * nv]),
            )
            .unwrap(),
            w => {
                let rf = match w {
                    "world" => ReferenceFrame::World,
                    "aligned" => ReferenceFrame::LocalWorldAligned,
                    _ => ReferenceFrame::Local,
                };
                evaluate::frame_jacobians(&model, &mut links, &f, rf, &qs, rows, true, &mut out)
                    .unwrap()
            }
        }
        black_box(&out);
    });
    println!(
        "{what}: best {:.1} ns per row (checksum {})",
        t / rows as f64 * 1e9,
        out.iter().sum::<f64>() + com.iter().sum::<f64>()
    );
}
