//! pointmass_dyn: multibody dynamics with equimomental point masses and DeNOC matrices.
//!
//! The core knows nothing of Python; `python` (behind the `python` feature) converts arrays
//! and errors and nothing else.
// `!(x > 0.0)` is how the checks reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// The recursions walk several per-link arrays in step; an index reads clearer than zips.
#![allow(clippy::needless_range_loop)]
pub mod alloc;
pub mod benchmark_models;
pub mod body;
pub mod control;
pub mod cpu;
pub mod denoc;
pub mod design;
pub mod effects;
pub mod error;
pub mod files;
pub mod frames;
pub mod identification;
pub mod integrator;
pub mod interrupt;
pub mod joint;
pub mod joint_records;
pub mod kinematics;
pub mod linalg;
pub mod loops;
pub mod model;
pub mod persist;
pub mod point_masses;
pub mod poses;
pub mod reactions;
pub mod recursive;
pub mod scene;
pub mod shared;
pub mod simulate;
pub mod spatial;
pub mod trig;
pub mod urdf;
pub mod visual;

#[cfg(feature = "python")]
mod python;

pub use body::RigidBody;
pub use error::{Error, Result};
pub use joint::Joint;
pub use model::Model;
pub use point_masses::EquimomentalSet;
