//! Many runs at once: each run is exactly a [`simulate`] call (same arithmetic, so the same
//! bits whatever the thread count), run by a small pool of scoped threads that take the
//! next run from a shared counter. One failing run does not stop the others: each has its
//! own result.
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

use super::{simulate, Record, StateEvent, Trajectory};
use crate::effects::{Disabled, Effect};
use crate::error::{Error, Result};
use crate::integrator::SolverOptions;
use crate::model::Model;

/// One run of a batch: its model and effects (a scene's, or a variant of it), its initial
/// state, span and integrator options.
pub struct Run<'a> {
    pub model: &'a Model,
    pub effects: &'a [Effect],
    pub disabled: Disabled,
    pub q0: &'a [f64],
    pub v0: &'a [f64],
    pub t_span: (f64, f64),
    pub opts: &'a SolverOptions,
}

/// What the batch's caller sees while it runs: how many runs have finished, and a flag that
/// stops it (runs under way end at their next progress check, runs not started are not).
#[derive(Default)]
pub struct Control {
    pub done: AtomicUsize,
    pub stop: AtomicBool,
}

/// Runs every run on `threads` threads (at least one, at most one per run); the results
/// come back in the runs' order. A stopped batch gives `Err(Interrupted)` for the runs it
/// did not start.
pub fn run_batch(
    runs: &[Run<'_>],
    state_events: &[StateEvent],
    record: Record,
    threads: usize,
    control: &Control,
) -> Vec<Result<Trajectory>> {
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<Result<Trajectory>>>> =
        runs.iter().map(|_| Mutex::new(None)).collect();
    let work = || loop {
        let k = next.fetch_add(1, Ordering::Relaxed);
        let Some(run) = runs.get(k) else {
            break;
        };
        let result = if control.stop.load(Ordering::Relaxed) {
            Err(Error::Interrupted(
                "the batch was stopped before this run started".into(),
            ))
        } else {
            let keep_going: super::Progress<'_> =
                Box::new(|_t| !control.stop.load(Ordering::Relaxed));
            simulate(
                run.model,
                run.effects,
                run.disabled,
                run.q0,
                run.v0,
                run.t_span,
                run.opts,
                state_events,
                Vec::new(),
                record,
                Some(keep_going),
            )
        };
        if let Ok(mut slot) = slots[k].lock() {
            *slot = Some(result);
        }
        control.done.fetch_add(1, Ordering::Relaxed);
    };
    let threads = threads.clamp(1, runs.len().max(1));
    if threads == 1 {
        work();
    } else {
        std::thread::scope(|s| {
            for _ in 0..threads {
                s.spawn(work);
            }
        });
    }
    slots
        .into_iter()
        .map(|slot| {
            slot.into_inner()
                .ok()
                .flatten()
                .unwrap_or_else(|| Err(Error::Interrupted("the run did not finish".into())))
        })
        .collect()
}
