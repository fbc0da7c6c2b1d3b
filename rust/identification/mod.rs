//! Inertial parameter identification from measured motion and joint forces
//! (docs/identification.md): the joint torque regressor in Pinocchio's ten-parameter form
//! ([`regressor`]), the base parameters ([`base_parameters`]), least squares ([`solve`]) and
//! the physically consistent estimate as non-negative masses on cells inside each link's
//! envelope ([`cells`]).
pub mod actuated;
pub mod args;
pub mod base_parameters;
pub mod cells;
pub mod identify;
pub mod model;
pub mod regressor;
pub mod solve;

pub use actuated::{actuated_regressor, joint_force_regressor};
pub use base_parameters::{base_parameters, reduce, Base, Reduced};
pub use cells::{cell_parameters, LinkCells};
pub use identify::{identify, Identified, Method, Options};
pub use model::{body_from_parameters, identified_model};
pub use regressor::{
    body_parameters, model_parameters, parameter_names, torque_regressor, Extras, NPARAM,
};
pub use solve::{ols, Fit};
