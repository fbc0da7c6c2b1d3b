//! A controller in the loop: a stepping simulator ([`Simulator`]) that advances a scene one
//! control period at a time with a control held constant over it (zero-order hold: joint
//! torques, or targets for the scene's PD torques), keeping an adaptive method's state across
//! calls ([`crate::integrator::Resume`]), and the sensors a controller reads ([`sensors`]).
//! docs/control.md.
mod args;
mod owned;
pub mod sensors;
mod stepping;

pub use owned::{OwnedSimulator, Stepping};
pub use sensors::Imu;
pub use stepping::{ControlKind, Simulator};
