//! Ctrl-C (and progress reports) while the interpreter is released, polled by elapsed time
//! as `support::pacing` says.
use crate::python::Obj;
use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use pyo3::prelude::*;

use super::errors::IntoPyResult;
use crate::support::interrupt;
use crate::support::pacing::Pacer;
pub use crate::support::pacing::INTERVAL;

/// Polls Python's signal handlers (and an optional callback) when its [`Pacer`] says;
/// keeps the first exception raised.
#[derive(Default)]
pub struct Watch {
    pacer: Pacer,
    pub error: Option<PyErr>,
}

impl Watch {
    /// Polls every `interval` exactly (a progress interval the caller chose).
    pub fn every(interval: Duration) -> Self {
        let pacer = Pacer::every(interval);
        Watch { pacer, error: None }
    }

    /// `true` to keep going. `also` runs after the signal handlers, attached, when due.
    pub fn poll(&mut self, also: impl FnOnce(Python<'_>) -> PyResult<()>) -> bool {
        if self.error.is_some() || !self.pacer.due() {
            return self.error.is_none();
        }
        let asked = Instant::now();
        let mut waited = Duration::ZERO;
        let outcome = Python::attach(|py| {
            waited = asked.elapsed();
            py.check_signals().and_then(|_| also(py))
        });
        self.pacer.polled(waited);
        self.error = outcome.err();
        self.error.is_none()
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
