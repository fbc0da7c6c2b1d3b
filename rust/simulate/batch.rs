//! Many runs at once: each run is exactly a [`simulate`] call (same arithmetic, so the same
//! bits whatever the thread count), run by a small pool of scoped threads that take the
//! next run from a shared counter. One failing run does not stop the others: each has its
//! own result.
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use super::settings::Resolved;
use super::{simulate, Record, StateEvent, Trajectory};
use crate::effects::{Disabled, Effect};
use crate::integrator::SolverOptions;
use crate::io::scene::Scene;
use crate::model::Model;
use crate::support::args::{opt, Arg};
use crate::support::error::{Error, Result};

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

/// Per-run initial states: one row for every run, or a row per run (`rows × width`).
pub struct StateRows {
    pub rows: usize,
    pub width: usize,
    pub data: Vec<f64>,
}

impl StateRows {
    /// An array of `shape` (`(width,)` or `(B, width)`) and its row-major `data`; errors
    /// name `arg`.
    pub fn new(arg: &str, shape: &[usize], data: Vec<f64>, width: usize) -> Result<StateRows> {
        let rows = match shape {
            [w] if *w == width => 1,
            [b, w] if *w == width && *b >= 1 => *b,
            _ => {
                let dims: Vec<String> = shape.iter().map(|s| s.to_string()).collect();
                let got = match shape {
                    [n] => format!("shape ({n},)"),
                    _ => format!("shape ({})", dims.join(", ")),
                };
                return Err(Error::arg(
                    arg,
                    format!("shape ({width},) or (B, {width})"),
                    got,
                ));
            }
        };
        Ok(StateRows { rows, width, data })
    }

    fn row(&self, k: usize) -> &[f64] {
        let k = if self.rows == 1 { 0 } else { k };
        &self.data[k * self.width..(k + 1) * self.width]
    }
}

/// The runs of a batch: one per scene, per row of `q0` or per row of `v0` (each of these
/// counts 1 or the batch's size; a count of 1 is every run's), each scene with its own
/// `resolved` settings. Initial states need scenes of one model size. Errors name the
/// argument at fault.
pub fn broadcast<'a>(
    scenes: &'a [Scene],
    resolved: &'a [Resolved],
    q0: Option<&'a StateRows>,
    v0: Option<&'a StateRows>,
) -> Result<Vec<Run<'a>>> {
    let Some(first) = scenes.first() else {
        return Err(Error::arg("scenes", "at least one Scene", "none"));
    };
    // A scene per run, or one for all: the settings resolved for each.
    debug_assert_eq!(resolved.len(), scenes.len());
    let size = |s: &Scene| (s.model.nq, s.model.nv);
    if (q0.is_some() || v0.is_some()) && scenes.iter().any(|s| size(s) != size(first)) {
        return Err(Error::arg(
            "q0, v0",
            "scenes of one model size when initial states are given",
            "scenes of different sizes",
        ));
    }
    let rows = |x: Option<&StateRows>| x.map_or(1, |b| b.rows);
    let count = rows(q0).max(rows(v0)).max(scenes.len());
    for (arg, n) in [("q0", rows(q0)), ("v0", rows(v0)), ("scenes", scenes.len())] {
        if n != 1 && n != count {
            return Err(Error::arg(
                arg,
                format!("1 or {count} runs (as the other batch arguments)"),
                format!("{n}"),
            ));
        }
    }
    let pick = |k: usize| if scenes.len() == 1 { 0 } else { k };
    Ok((0..count)
        .map(|k| {
            let (s, r) = (&scenes[pick(k)], &resolved[pick(k)]);
            Run {
                model: &s.model,
                effects: &s.effects,
                disabled: r.disabled,
                q0: q0.map_or(&s.q0[..], |b| b.row(k)),
                v0: v0.map_or(&s.v0[..], |b| b.row(k)),
                t_span: r.t_span,
                opts: &r.opts,
            }
        })
        .collect())
}

/// [`run_batch`] on a thread of its own while this thread calls `poll(done)` every `tick`
/// with the number of finished runs; `poll` returning `false` stops the batch (runs under
/// way end at their next progress check, runs not started do not start). The batch wakes
/// this thread when it ends, so the call returns then, not at the next tick. `Err` if a
/// batch thread panicked.
pub fn run_batch_polled(
    runs: &[Run<'_>],
    state_events: &[StateEvent],
    record: Record,
    threads: usize,
    tick: Duration,
    mut poll: impl FnMut(usize) -> bool,
) -> std::thread::Result<Vec<Result<Trajectory>>> {
    let control = Control::default();
    let caller = std::thread::current();
    let finished = AtomicBool::new(false);
    std::thread::scope(|sc| {
        let handle = sc.spawn(|| {
            let out = run_batch(runs, state_events, record, threads, &control);
            finished.store(true, Ordering::Release);
            caller.unpark();
            out
        });
        let mut stopped = false;
        while !finished.load(Ordering::Acquire) {
            std::thread::park_timeout(tick);
            if finished.load(Ordering::Acquire) || stopped {
                continue;
            }
            if !poll(control.done.load(Ordering::Relaxed)) {
                stopped = true;
                control.stop.store(true, Ordering::Relaxed);
            }
        }
        handle.join()
    })
}

/// Initial states as a caller gave them: an array's shape and its row-major data.
pub type GivenStates = Option<(Vec<usize>, Vec<f64>)>;

/// A batch's own arguments as its caller gave them, read: the initial states `q0`/`v0`
/// (1-D: every run's, 2-D: a row per run; checked against the scenes when the batch
/// starts) and the thread count (`None`: one per core).
pub struct BatchArgs {
    q0: GivenStates,
    v0: GivenStates,
    threads: usize,
}

impl BatchArgs {
    pub fn new<A: Arg>(
        q0: Option<&A>,
        v0: Option<&A>,
        threads: Option<&A>,
    ) -> std::result::Result<Self, A::Err> {
        let states = |x: Option<&A>, arg: &str| opt(x, |x| x.array(arg));
        let (q0, v0) = (states(q0, "q0")?, states(v0, "v0")?);
        let threads = crate::support::args::threads(threads)?;
        Ok(BatchArgs { q0, v0, threads })
    }
}

/// A batch as its caller asks: `config` (the call's settings) resolved against each scene's
/// own, the runs broadcast over `args`' initial states, then run as [`run_batch_polled`]
/// runs them (`poll(done, runs)`). `Err`: input refused before any run started, or a batch
/// thread panicked.
pub fn run_scenes(
    scenes: &[Scene],
    config: &super::RunConfig,
    args: BatchArgs,
    state_events: &[StateEvent],
    tick: Duration,
    mut poll: impl FnMut(usize, usize) -> bool,
) -> Result<Vec<Result<Trajectory>>> {
    let Some(first) = scenes.first() else {
        return Err(Error::arg("scenes", "at least one Scene", "none"));
    };
    let rows = |arg: &str, given: GivenStates, width: usize| {
        given
            .map(|(shape, data)| StateRows::new(arg, &shape, data, width))
            .transpose()
    };
    let q0 = rows("q0", args.q0, first.model.nq)?;
    let v0 = rows("v0", args.v0, first.model.nv)?;
    // Settings per scene (each resolves the caller's against its own file's).
    let resolved = scenes
        .iter()
        .map(|s| {
            let dim = s.model.nq + s.model.nv;
            config.clone().resolve(&s.settings, &s.effects, dim)
        })
        .collect::<Result<Vec<_>>>()?;
    let runs = broadcast(scenes, &resolved, q0.as_ref(), v0.as_ref())?;
    // The record is the caller's alone (no scene file sets one).
    let record = resolved[0].record;
    let count = runs.len();
    let poll = |done| poll(done, count);
    let threads = args.threads;
    run_batch_polled(&runs, state_events, record, threads, tick, poll)
        .map_err(|_| Error::Simulation("a batch thread panicked".into()))
}

/// The batch's runs as results, each with the error that kept it from starting (as
/// [`Trajectory::refused`]); when something stopped the batch (`stopped`: what, as
/// [`name_stop`] names it), each run it stopped says so.
pub fn batch_results(
    mut results: Vec<Result<Trajectory>>,
    stopped: Option<&str>,
) -> Vec<(Trajectory, Option<Error>)> {
    if let Some(reason) = stopped {
        name_stop(&mut results, reason);
    }
    let result = |r: Result<Trajectory>| match r {
        Ok(traj) => (traj, None),
        Err(e) => (Trajectory::refused(&e), Some(e)),
    };
    results.into_iter().map(result).collect()
}

/// Names what stopped a batch (`reason`: only its caller knows, e.g. Ctrl-C) in the runs it
/// cut short: those interrupted midway, and those it never started.
fn name_stop(results: &mut [Result<Trajectory>], reason: &str) {
    for result in results {
        match result {
            Ok(traj) => traj.name_interruption(reason),
            Err(Error::Interrupted(m)) => {
                *m = format!("the batch was stopped before this run started, by {reason}")
            }
            Err(_) => {}
        }
    }
}
