//! When a long computation running without the Python interpreter looks back at it (for
//! Ctrl-C and progress reports). Re-attaching waits for whichever thread holds the
//! interpreter, up to its switch interval (5 ms) and more, so a computation re-attaches by
//! elapsed time, every [`INTERVAL`], never per evaluation; when re-attaching had to wait (a
//! busy neighbour thread), the interval doubles up to [`MAX_INTERVAL`], so such a neighbour
//! costs a few per cent, and Ctrl-C still answers within a quarter of a second.
use std::time::{Duration, Instant};

/// How often a detached computation looks at the interpreter.
pub const INTERVAL: Duration = Duration::from_millis(50);
/// The longest interval when the interpreter is busy elsewhere.
pub const MAX_INTERVAL: Duration = Duration::from_millis(250);
/// An attach that took longer than this waited for another thread.
const CONTENDED: Duration = Duration::from_millis(1);

/// The clock of a poll: due every [`INTERVAL`] (backing off while contended), or every
/// interval the caller chose exactly.
pub struct Pacer {
    last: Instant,
    interval: Duration,
    /// Back off when the interpreter is contended (not when the caller chose the interval).
    adaptive: bool,
    current: Duration,
}

impl Default for Pacer {
    fn default() -> Self {
        Pacer {
            adaptive: true,
            ..Pacer::every(INTERVAL)
        }
    }
}

impl Pacer {
    /// Due every `interval` exactly (a progress interval the caller chose).
    pub fn every(interval: Duration) -> Self {
        Pacer {
            last: Instant::now(),
            interval,
            adaptive: false,
            current: interval,
        }
    }

    pub fn due(&self) -> bool {
        self.last.elapsed() >= self.current
    }

    /// A poll ended now; attaching to the interpreter took `waited`.
    pub fn polled(&mut self, waited: Duration) {
        self.last = Instant::now();
        if self.adaptive {
            self.current = match waited > CONTENDED {
                true => (self.current * 2).min(MAX_INTERVAL),
                false => self.interval,
            };
        }
    }
}
