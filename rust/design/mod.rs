//! Design of bodies and counterweights along a prescribed motion (docs/design.md).
//!
//! The point-mass model's reason to exist: a body's mass, first and second moments are
//! linear in point masses, so the shaking force and moment, the driving forces and every
//! joint's bearing force along a given motion are linear in the masses of material cells
//! and counterweight candidates. [`cells`] turns an envelope into cells, [`regressor`] gives
//! the linear maps along a motion, [`problem`] states the trade-off as a conic program and
//! solves it with Clarabel (in place of a hand-written interior point).
mod active;
mod args;
pub mod cells;
pub mod connectivity;
pub mod pins;
pub mod problem;
mod program;
pub mod regressor;
pub mod results;
pub mod strength;

pub use args::MapsCall;
pub use cells::{cube_moments, fill, point_moments, Envelope};
pub use connectivity::Flow;
pub use pins::pins;
pub use problem::{
    solve, solve_outcome, Norm, Outcome, Problem, Quantity, Relaxation, Relaxed, Solution,
};
pub use regressor::{model_parameters, regressor, Layout, Regressor, NPARAM};

#[cfg(test)]
mod tests;
