//! Active samples for peak programs (cutting planes): a peak is the largest block norm over
//! the motion, so a program holding only some blocks' cones is a relaxation of the full one.
//! Solve with a subset, add the blocks its optimum violates, re-solve until none is
//! violated: that optimum then meets every block, so it is the full program's optimum (and
//! an infeasible subset proves the full program infeasible). Most samples are never active
//! (a peak sits at a few instants), so each program is a fraction of the full one.
use nalgebra::DVector;

use super::problem::{Norm, Problem};
use super::program::{bound, scale, solve_program, Active, Layout, Raw, Stage};
use crate::support::error::Result;

/// Samples in the first program of each quantity (all their vectors).
const FIRST_SAMPLES: usize = 24;
/// After this many rounds, every block (never reached in practice: each round adds the
/// violated local maxima, of which a smooth motion has few).
const MAX_ROUNDS: usize = 40;

/// Blocks (vectors) per sample and the number of blocks of quantity `q`.
fn blocks(q: &super::problem::Quantity) -> (usize, usize) {
    let n = q.rows.nrows() / q.dim.max(1);
    ((n / q.samples.max(1)).max(1), n)
}

/// The first active set: every vector at evenly spread samples (every block with RMS).
pub(crate) fn initial(problem: &Problem) -> Active {
    problem
        .quantities
        .iter()
        .map(|q| {
            let (per, n) = blocks(q);
            let stride = match q.norm(problem.norm) {
                Norm::Peak => (n / per / FIRST_SAMPLES).max(1),
                Norm::Rms => 1,
            };
            (0..n).filter(|b| (b / per) % stride == 0).collect()
        })
        .collect()
}

/// Solves `stage` by cutting planes from `active` (which grows); the iterations and solver
/// time of all rounds are summed in the result. `None`: certified infeasible.
pub(crate) fn solve_cut(
    problem: &Problem,
    stage: Stage,
    active: &mut Active,
) -> Result<Option<(Raw, u32)>> {
    let lay = Layout::new(problem, stage);
    let (mut iterations, mut time, mut scouted) = (0, 0.0, 0);
    let any_peak = problem.norm == Norm::Peak || problem.quantities.iter().any(|q| q.peak);
    if any_peak && !problem.flows.is_empty() {
        // Scout: the stage's program without the connectivity flows is a relaxation (its
        // infeasibility is the full one's) a fraction of the size; its cutting planes find
        // most of the full program's active samples, so the full program is solved about
        // once per stage instead of once per round.
        let lean = Problem {
            flows: vec![],
            ..problem.clone()
        };
        let Some((raw, rounds)) = solve_cut(&lean, stage, active)? else {
            return Ok(None);
        };
        (iterations, time, scouted) = (raw.iterations, raw.solve_time, rounds);
    }
    for round in 1..=MAX_ROUNDS as u32 {
        let Some(mut raw) = solve_program(problem, &lay, stage, active)? else {
            return Ok(None);
        };
        iterations += raw.iterations;
        time += raw.solve_time;
        if !any_peak || add_violated(problem, &lay, stage, &raw, active) == 0 {
            raw.iterations = iterations;
            raw.solve_time = time;
            return Ok(Some((raw, round + scouted)));
        }
    }
    *active = problem
        .quantities
        .iter()
        .map(|q| (0..blocks(q).1).collect())
        .collect();
    let out = solve_program(problem, &lay, stage, active)?;
    Ok(out.map(|mut raw| {
        raw.iterations += iterations;
        raw.solve_time += time;
        (raw, MAX_ROUNDS as u32 + 1 + scouted)
    }))
}

/// Adds each quantity's blocks outside `active` whose norm at `raw` exceeds the bound and
/// is a local maximum along the motion (per vector: a sample's neighbours are the samples
/// before and after); returns how many were added.
fn add_violated(
    problem: &Problem,
    lay: &Layout,
    stage: Stage,
    raw: &Raw,
    active: &mut Active,
) -> usize {
    let delta = DVector::from_column_slice(&raw.z[lay.nx..lay.nx + lay.nd]);
    let mut added = 0;
    for (k, q) in problem.quantities.iter().enumerate() {
        let Some(b) = bound(problem, lay, stage, k) else {
            continue;
        };
        if q.norm(problem.norm) == Norm::Rms {
            continue; // one cone for the whole motion: always in the program
        }
        // Quantities are relative to their value before: 1e-9 of it, or of the bound.
        let limit = b.value(&raw.z);
        let limit = limit + 1e-9 * (1.0 + limit.abs());
        let y = (&q.rows * &delta + &q.constant) * scale(q);
        let (per, n) = blocks(q);
        let norms: Vec<f64> = (0..n).map(|b| y.rows(b * q.dim, q.dim).norm()).collect();
        let mut inside = vec![false; n];
        active[k].iter().for_each(|&b| inside[b] = true);
        let over = |b: usize| !inside[b] && norms[b] > limit;
        // A connected link's program costs a full solve per round and its cones little:
        // every violated block enters (the least-mass stage's peaks otherwise move one
        // sample per round: 40 rounds on a front's end, issue 39).
        let all = !problem.flows.is_empty();
        let mut new: Vec<usize> = (0..n)
            .filter(|&b| over(b))
            .filter(|&b| {
                all || {
                    let before = if b >= per { norms[b - per] } else { f64::MIN };
                    let after = if b + per < n {
                        norms[b + per]
                    } else {
                        f64::MIN
                    };
                    norms[b] >= before && norms[b] >= after
                }
            })
            .collect();
        if new.is_empty() {
            // Only where an active neighbour is larger (to the solver's tolerance): the worst.
            let worst = (0..n)
                .filter(|&b| over(b))
                .max_by(|&a, &b| norms[a].total_cmp(&norms[b]));
            new.extend(worst);
        }
        // With each its neighbours along the motion: the optimum moves when the new cones
        // enter, and the peak with it, usually by a sample (a round saved, at the price of a
        // few cones, which cost little beside a connected link's flows).
        let near: Vec<usize> = new
            .iter()
            .flat_map(|&b| [b.checked_sub(per), Some(b + per).filter(|&a| a < n)])
            .flatten()
            .filter(|&a| !inside[a])
            .collect();
        new.extend(near);
        new.sort_unstable();
        new.dedup();
        added += new.len();
        active[k].extend(new);
        active[k].sort_unstable();
    }
    added
}
