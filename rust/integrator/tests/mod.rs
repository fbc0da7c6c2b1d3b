//! Tests of the integrator. `rk45.rs` and `stiffness.rs` test the driver; `dense.rs`,
//! `events.rs` and `stepper.rs` are the test modules of the files of the same name (included
//! there, so they see those files' private items); `fixtures.rs` holds what they share.
mod adams;
pub(super) mod fixtures;
mod methods;
mod rk45;
mod stiffness;
mod vern9;
