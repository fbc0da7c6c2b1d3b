//! A caller's list of events as a run takes it: the state events (evaluated in the core,
//! first) and the caller's own (`P`: a binding's callables, after them), with where each
//! stood in the caller's list, so the trajectory's events come back in the caller's order.
use super::StateEvent;
use crate::support::args::{given, Arg};
use crate::support::error::Error;

pub struct EventList<P> {
    pub state: Vec<StateEvent>,
    pub other: Vec<P>,
    /// Per caller's event: (is one of `other`, index in its list).
    order: Vec<(bool, usize)>,
}

impl<P> Default for EventList<P> {
    fn default() -> Self {
        EventList {
            state: Vec::new(),
            other: Vec::new(),
            order: Vec::new(),
        }
    }
}

/// One of the caller's events: a state event, or one of the binding's own (`P`).
pub enum CallerEvent<P> {
    State(StateEvent),
    Other(P),
}

impl<P> EventList<P> {
    /// The caller's `events`: none, one event of the binding's own (`single` says which), or
    /// a sequence of events, each read by `read(k, events[k])`, in the caller's order.
    pub fn from_arg<A: Arg>(
        events: Option<&A>,
        single: impl Fn(&A) -> bool,
        mut read: impl FnMut(usize, &A) -> Result<CallerEvent<P>, A::Err>,
    ) -> Result<Self, A::Err> {
        let mut out = EventList::default();
        let mut push = |k, e: &A| -> Result<(), A::Err> {
            match read(k, e)? {
                CallerEvent::State(s) => out.push_state(s),
                CallerEvent::Other(p) => out.push_other(p),
            }
            Ok(())
        };
        match given(events) {
            None => {}
            Some(e) if single(e) => push(0, e)?,
            Some(evs) => {
                // Not a sequence at all: the binding's type error, as a Python loop's would be.
                let expected = "an event callable, or a sequence of callables and StateEvents";
                let list = evs.items().filter(|_| evs.text().is_none());
                let list = list.ok_or_else(|| evs.wrong_type("events", expected))??;
                for (k, e) in list.iter().enumerate() {
                    push(k, e)?;
                }
            }
        }
        Ok(out)
    }

    pub fn push_state(&mut self, e: StateEvent) {
        self.order.push((false, self.state.len()));
        self.state.push(e);
    }

    pub fn push_other(&mut self, e: P) {
        self.order.push((true, self.other.len()));
        self.other.push(e);
    }

    /// The list, if a run of this kind takes it: a run without a scene (`rk45`) no state
    /// events, a batch (`threads`) no caller's callables, which cannot run on its threads.
    pub fn for_run(self, scene: bool, threads: bool) -> Result<Self, Error> {
        if !scene && !self.state.is_empty() {
            let expected = "event callables (a StateEvent needs a scene: pmd.simulate)";
            return Err(Error::arg("events", expected, "a StateEvent"));
        }
        if threads && !self.other.is_empty() {
            let expected =
                "StateEvent objects only (Python callables cannot run on the batch's threads)";
            return Err(Error::arg("events", expected, "a callable"));
        }
        Ok(self)
    }

    /// The trajectory's slot of each event, in the caller's order.
    pub fn slots(&self) -> Vec<usize> {
        let ns = self.state.len();
        self.order
            .iter()
            .map(|&(other, k)| if other { ns + k } else { k })
            .collect()
    }
}

/// What the caller's event function `events[k]` returned at `t`: a real number; NaN (which
/// would silently hide the event) and anything else refused, naming the event.
pub fn event_value<A: Arg>(k: usize, t: f64, value: &A) -> Result<f64, A::Err> {
    let name = format!("events[{k}]");
    let expected = "an event function returning a real number";
    let x = value
        .real(&name)
        .map_err(|_| Error::arg(&name, expected, format!("{} at t = {t}", value.shown())))?;
    match x.is_nan() {
        true => Err(Error::Numerical(format!(
            "{name}: the event function returned NaN at t = {t}"
        ))
        .into()),
        false => Ok(x),
    }
}
