//! pointmass_dyn: multibody dynamics with equimomental point masses and DeNOC matrices.
//!
//! The core knows nothing of Python; `python` (behind the `python` feature) converts arrays
//! and errors and nothing else.
// `!(x > 0.0)` is how the checks reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// The recursions walk several per-link arrays in step; an index reads clearer than zips.
#![allow(clippy::needless_range_loop)]
// The layers, bottom up (docs/architecture.md): a group of modules uses only the groups
// before it and its own. The exceptions are counted by tests/test_code_limits.py (at most
// two cycles): the model keeps the recursions' constants (`recursive::Compiled`), which
// read the model, and the recursions read the world kinematics, which read the model.

// Infrastructure and the 3-/6-vector algebra everything speaks; the factorisations (a leaf).
pub mod linalg;
pub mod support;

// The model: joints, bodies and their point masses, the tree and what it carries.
pub mod joint;
pub mod model;

// The algorithms on a model.
pub mod dynamics;
pub mod frames;
pub mod kinematics;
pub mod loops;
pub mod recursive;

// Simulation: effects (forces), integrators, file formats (a scene file holds effects and
// solver settings), runs, stepped control.
pub mod control;
pub mod effects;
pub mod integrator;
pub mod io;
pub mod simulate;

// Applications.
pub mod design;
pub mod identification;

// The models every benchmark uses (docs/benchmarks.md), for benches, examples and tests:
// no part of the shipped library (feature `benchmark-models`, which those targets require).
#[cfg(any(test, feature = "benchmark-models"))]
pub mod benchmark_models;

#[cfg(feature = "python")]
mod python;

pub use joint::Joint;
pub use model::body::RigidBody;
pub use model::point_masses::EquimomentalSet;
pub use model::Model;
pub use support::error::{Error, Result};
