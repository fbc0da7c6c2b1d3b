//! Many configurations in one call: the rows checked once for the whole block, then split
//! over scoped threads when the block is large. Each row is computed by the same code from
//! its own inputs alone, so the results do not depend on the split.
use std::sync::atomic::{AtomicBool, Ordering};

use crate::model::Model;
use crate::support::error::{all_finite, Result};

/// Rows (times links) per thread: one thread does blocks below twice this. Measured on a
/// 2-core machine (`examples/frames_batch.rs split`: Panda's hand, one thread against
/// `split` over two, best of 30 each, load ~14): two threads lost at 4,096 rows (36,864
/// rows × links, 1.14× one thread's time; the hand-off ~27 µs, a row ~72 ns) and won at
/// 8,192 (73,728; 0.86×). Below the threshold a C-ordered block is also read in place.
const ROWS_LINKS_PER_THREAD: usize = 32_768;

/// Checks the rows of `qs` (errors name `q[k]` when `stacked`, as
/// [`super::placement::check_rows`]). Without quaternions a configuration is valid when it
/// is finite: one pass over the block, and the row-by-row check only to name a bad row.
pub fn check_block(model: &Model, qs: &[f64], rows: usize, stacked: bool, arg: &str) -> Result<()> {
    let plain = model.links.iter().all(|l| l.joint.nq() == l.joint.nv());
    if plain && qs.len() == rows * model.nq && all_finite(qs) {
        return Ok(());
    }
    super::placement::check_rows(model, qs, rows, stacked, arg)
}

/// How many threads a block of `rows` configurations of `model` is worth (at most the
/// machine's cores).
pub fn threads_for(model: &Model, rows: usize) -> usize {
    let work = rows.saturating_mul(model.links.len().max(1));
    let want = work / ROWS_LINKS_PER_THREAD;
    if want < 2 {
        return 1;
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    want.min(cores).min(rows)
}

/// Calls `f(first, count, a, b)` on consecutive blocks of rows, `a` and `b` the blocks'
/// parts of the outputs (`per_a`, `per_b` values per row; `per_b` may be 0), on `threads`
/// threads (this one included). `f` polls for interrupts only on this thread; the others
/// stop at their next block of 256 rows once it has failed.
#[allow(clippy::too_many_arguments)]
pub fn split<F>(
    what: &'static str,
    rows: usize,
    threads: usize,
    a: &mut [f64],
    per_a: usize,
    b: &mut [f64],
    per_b: usize,
    f: F,
) -> Result<()>
where
    F: Fn(usize, usize, &mut [f64], &mut [f64], &dyn Fn() -> Result<()>) -> Result<()> + Sync,
{
    let poll_here = || crate::support::interrupt::check(what);
    if threads <= 1 || rows < 2 {
        return f(0, rows, a, b, &poll_here);
    }
    let stop = AtomicBool::new(false);
    let chunk = rows.div_ceil(threads);
    std::thread::scope(|s| {
        let mut handles = Vec::with_capacity(threads);
        let (mut a, mut b) = (a, b);
        let mut first = chunk.min(rows);
        let (mine_a, rest_a) = std::mem::take(&mut a).split_at_mut(first * per_a);
        let (mine_b, rest_b) = std::mem::take(&mut b).split_at_mut(first * per_b);
        (a, b) = (rest_a, rest_b);
        while first < rows {
            let count = chunk.min(rows - first);
            let (ca, ra) = std::mem::take(&mut a).split_at_mut(count * per_a);
            let (cb, rb) = std::mem::take(&mut b).split_at_mut(count * per_b);
            (a, b) = (ra, rb);
            let (f, stop) = (&f, &stop);
            let start = first;
            handles.push(s.spawn(move || {
                let poll = || match stop.load(Ordering::Relaxed) {
                    true => Err(crate::support::error::Error::Interrupted(what.into())),
                    false => Ok(()),
                };
                f(start, count, ca, cb, &poll)
            }));
            first += count;
        }
        let here = f(0, chunk.min(rows), mine_a, mine_b, &poll_here);
        if here.is_err() {
            stop.store(true, Ordering::Relaxed);
        }
        let mut out = here;
        for h in handles {
            let r = h.join().unwrap_or_else(|_| {
                Err(crate::support::error::Error::model(
                    what,
                    "a worker thread panicked",
                ))
            });
            if out.is_ok() {
                out = r;
            }
        }
        out
    })
}
