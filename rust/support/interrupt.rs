//! Cooperative interruption of long computations. A caller (the Python bindings, to honour
//! Ctrl-C) installs a poller for the duration of a call with [`with_poller`]; long loops in
//! the core call [`check`] between blocks of work. Without a poller, `check` costs one
//! thread-local read and never interrupts.
use std::cell::RefCell;

use crate::support::error::{Error, Result};

/// "Keep going?": called often, so it should itself decide how often to do real work. It
/// owns its state (share what the caller must read afterwards through an `Rc`).
pub type Poller = Box<dyn FnMut() -> bool>;

thread_local! {
    static POLLER: RefCell<Option<Poller>> = const { RefCell::new(None) };
}

/// Runs `f` with `poller` installed on this thread (the previous one is restored after, on
/// unwinding too).
pub fn with_poller<R>(poller: Poller, f: impl FnOnce() -> R) -> R {
    let previous = POLLER.with(|p| p.borrow_mut().replace(poller));
    struct Restore(Option<Poller>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            POLLER.with(|p| *p.borrow_mut() = previous);
        }
    }
    let _restore = Restore(previous);
    f()
}

/// `Err(Interrupted)` if the installed poller says stop; `what` names the computation.
pub fn check(what: &str) -> Result<()> {
    let keep_going = POLLER.with(|p| match p.try_borrow_mut() {
        Ok(mut slot) => slot.as_mut().is_none_or(|poll| poll()),
        // A poller that re-enters `check` (it should not): let it run.
        Err(_) => true,
    });
    if keep_going {
        Ok(())
    } else {
        Err(Error::Interrupted(what.to_string()))
    }
}

/// Why a run stopped from its progress hook (`Status::Interrupted`'s reason): Ctrl-C, or the
/// exception `name` (its message `text`) the progress callback raised.
pub fn progress_reason(ctrl_c: bool, name: Option<String>, text: Option<String>) -> String {
    let name = name.unwrap_or_else(|| "an exception".into());
    match text {
        _ if ctrl_c => "Ctrl-C (or a KeyboardInterrupt raised by progress)".into(),
        Some(text) if !text.is_empty() => format!("{name}: {text}, raised by progress"),
        _ => format!("{name}, raised by progress"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poller_stops_and_is_removed_afterwards() {
        assert!(check("outside").is_ok());
        let mut calls = 0;
        let r = with_poller(
            Box::new(move || {
                calls += 1;
                calls < 3
            }),
            || (0..5).map(|_| check("loop")).collect::<Vec<_>>(),
        );
        assert!(r[0].is_ok() && r[1].is_ok());
        assert_eq!(r[2], Err(Error::Interrupted("loop".into())));
        assert!(check("after").is_ok());
    }
}
