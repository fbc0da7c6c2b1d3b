//! A run continued across calls (a stepping simulator, `control::Simulator`): the interval
//! moved on to the next control boundary, and the right-hand side changed at a boundary.
//!
//! What a method keeps across a boundary: its step-size proposal (the controller's state), the
//! Radau Jacobian and LU and its collocation polynomial (Newton's starting guess); what it
//! redoes: `f(t, y)` at the boundary, once, when the right-hand side changed there (RK45 and
//! DOP853 carry it as their first stage, FSAL; Radau's error estimate reads it). A fixed-step
//! method carries nothing (its grid goes on from `t0`).
use super::common::{Lifecycle, StepState};
use super::explicit_rk::{ExplicitRk, Tableau};
use super::fixed_step::{FixedStep, Scheme};
use super::method::Integrator;
use super::radau::Radau;
use super::{OdeSystem, Status};

/// An [`Integrator`] that can go on past its `t_bound`.
pub trait Resume: Integrator {
    /// The interval now ends at `t_bound` (beyond `t()`); a finished method steps again.
    fn extend(&mut self, t_bound: f64);
    /// The right-hand side changed at `t()` (a new control held from there): what the method
    /// carries of the old one is evaluated afresh (one evaluation for the adaptive methods,
    /// none before the first step).
    fn discontinuity(&mut self) -> Result<(), Status>;
    /// The size of the next step to try (a clipped step's successor keeps the proposal of
    /// the unclipped one); ignored at a fixed step.
    fn set_h_next(&mut self, h: f64);
}

fn extend_state(st: &mut StepState, t_bound: f64) {
    st.t_bound = t_bound;
    if st.lifecycle == Lifecycle::Finished {
        st.lifecycle = Lifecycle::Running;
    }
}

fn refresh_f<S: OdeSystem>(st: &mut StepState, sys: &mut S) -> Result<(), Status> {
    match st.lifecycle {
        Lifecycle::Running | Lifecycle::Finished => st.rhs_here(sys),
        Lifecycle::Uninitialised | Lifecycle::Failed(_) => Ok(()),
    }
}

impl<S: OdeSystem, T: Tableau> Resume for ExplicitRk<S, T> {
    fn extend(&mut self, t_bound: f64) {
        extend_state(self.parts().0, t_bound);
    }
    fn discontinuity(&mut self) -> Result<(), Status> {
        let (st, sys) = self.parts();
        refresh_f(st, sys)
    }
    fn set_h_next(&mut self, h: f64) {
        self.parts().0.h_abs = h;
    }
}

impl<S: OdeSystem> Resume for Radau<S> {
    fn extend(&mut self, t_bound: f64) {
        extend_state(self.parts().0, t_bound);
    }
    fn discontinuity(&mut self) -> Result<(), Status> {
        let (st, sys) = self.parts();
        refresh_f(st, sys)
    }
    fn set_h_next(&mut self, h: f64) {
        self.parts().0.h_abs = h;
    }
}

impl<S: OdeSystem, M: Scheme> Resume for FixedStep<S, M> {
    fn extend(&mut self, t_bound: f64) {
        FixedStep::extend(self, t_bound);
    }
    fn discontinuity(&mut self) -> Result<(), Status> {
        Ok(())
    }
    fn set_h_next(&mut self, _h: f64) {}
}
