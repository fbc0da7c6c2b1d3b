//! Ctrl-C (and progress reports) while the interpreter is released. Re-attaching to the
//! interpreter waits for whichever Python thread holds it, up to its switch interval (5 ms)
//! and more, so a long computation re-attaches by elapsed time, every [`INTERVAL`], never per
//! evaluation; when re-attaching had to wait (a busy Python thread), the interval doubles up
//! to [`MAX_INTERVAL`], so such a neighbour costs a few per cent, and Ctrl-C still answers
//! within a quarter of a second.
use crate::python::Obj;
use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use pyo3::prelude::*;

use super::errors::IntoPyResult;
use crate::support::interrupt;

/// How often a detached computation looks at the interpreter.
pub const INTERVAL: Duration = Duration::from_millis(50);
/// The longest interval when the interpreter is busy elsewhere.
pub const MAX_INTERVAL: Duration = Duration::from_millis(250);
/// An attach that took longer than this waited for another thread.
const CONTENDED: Duration = Duration::from_millis(1);

/// Polls Python's signal handlers (and an optional callback) at most every [`INTERVAL`];
/// keeps the first exception raised.
pub struct Watch {
    last: Instant,
    interval: Duration,
    /// Back off when the interpreter is contended (not when the caller chose the interval).
    adaptive: bool,
    current: Duration,
    pub error: Option<PyErr>,
}

impl Default for Watch {
    fn default() -> Self {
        Watch {
            adaptive: true,
            ..Watch::every(INTERVAL)
        }
    }
}

impl Watch {
    /// Polls every `interval` exactly (a progress interval the caller chose).
    pub fn every(interval: Duration) -> Self {
        Watch {
            last: Instant::now(),
            interval,
            adaptive: false,
            current: interval,
            error: None,
        }
    }

    /// `true` to keep going. `also` runs after the signal handlers, attached, when due.
    pub fn poll(&mut self, also: impl FnOnce(Python<'_>) -> PyResult<()>) -> bool {
        if self.error.is_some() {
            return false;
        }
        if self.last.elapsed() < self.current {
            return true;
        }
        let asked = Instant::now();
        let mut waited = Duration::ZERO;
        let outcome = Python::attach(|py| {
            waited = asked.elapsed();
            py.check_signals().and_then(|_| also(py))
        });
        self.last = Instant::now();
        if self.adaptive {
            self.current = if waited > CONTENDED {
                (self.current * 2).min(MAX_INTERVAL)
            } else {
                self.interval
            };
        }
        match outcome {
            Ok(()) => true,
            Err(e) => {
                self.error = Some(e);
                false
            }
        }
    }
}

/// Runs `f` detached from the interpreter with Ctrl-C honoured: the core's long loops call
/// `interrupt::check`, which polls the signal handlers by elapsed time. A `KeyboardInterrupt`
/// (or whatever a signal handler raised) comes back as itself.
pub fn detach_interruptible<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> crate::support::error::Result<T> + Send,
) -> PyResult<T> {
    let (result, raised) = detach_watched(py, f);
    match raised {
        Some(e) => Err(e),
        None => result.py(py),
    }
}

/// As [`detach_interruptible`], but returns what `f` computed beside the exception a signal
/// handler raised (if one did): for computations that keep their partial results.
pub fn detach_watched<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> (T, Option<PyErr>) {
    py.detach(|| {
        let watch = Rc::new(RefCell::new(Watch::default()));
        let poller = watch.clone();
        let result =
            interrupt::with_poller(Box::new(move || poller.borrow_mut().poll(|_| Ok(()))), f);
        let raised = watch.borrow_mut().error.take();
        (result, raised)
    })
}

/// The exception that stopped a computation that keeps its partial results: the one a
/// signal handler raised (Ctrl-C's `KeyboardInterrupt`), else `stopped` as our error; with
/// `partial` attached as `.result` and a note saying so.
pub fn stopped_with_partial(
    py: Python<'_>,
    raised: Option<PyErr>,
    stopped: crate::support::error::Error,
    partial: &Obj,
    note: &str,
) -> PyErr {
    let err = raised.unwrap_or_else(|| super::errors::to_py(py, stopped));
    let value = err.value(py);
    // An exception type that takes no attributes keeps its own message.
    let _ = value.setattr("result", partial);
    let _ = value.call_method1("add_note", (format!("pointmass_dyn: {note}"),));
    err
}
