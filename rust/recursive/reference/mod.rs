//! The reference recursions: forward dynamics, inverse dynamics and the mass matrix written
//! in world axes over the paper's DeNOC quantities (twists `t_i = [ω_i; v_i]` about moving
//! link origins, `P_i` columns from [`crate::kinematics`]), the way docs/method.md states
//! them. They are short and read like the equations — start here — and the tests hold the
//! fast body-frame recursions ([`super::aba`], [`super::rnea`], [`super::crba`]) to them.
//! They need their own workspace ([`Workspace`]), which only they use.
pub mod forward;
pub mod inverse;
pub mod mass_matrix;

use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::spatial::{ArticulatedInertia, BodyInertia, Mat6, Vec6};

pub use forward::forward_dynamics_world;
pub use inverse::inverse_dynamics_world;
pub use mass_matrix::mass_matrix_world;

/// Per-call values of the world-frame recursions, per link.
#[derive(Debug, Clone)]
pub struct Workspace {
    pub links: Vec<LinkState>,
    /// Twist rates `ṫ_i`.
    pub accel: Vec<Vec6>,
    /// Wrenches transmitted by each joint.
    pub wrench: Vec<Vec6>,
    pub art_inertia: Vec<ArticulatedInertia>,
    pub art_bias: Vec<Vec6>,
    /// `U = M̂ P` (columns).
    pub u: Vec<[Vec6; 6]>,
    /// `D⁻¹ = (Pᵀ M̂ P)⁻¹`, upper-left dof × dof block used (the rest zero).
    pub d_inv: Vec<Mat6>,
    /// `τ − Pᵀ b̂` (dof entries, the rest zero).
    pub u_tau: Vec<Vec6>,
    pub composite: Vec<BodyInertia>,
}

impl Workspace {
    pub fn new(model: &Model) -> Self {
        let n = model.links.len();
        Workspace {
            links: vec![LinkState::default(); n],
            accel: vec![Vec6::zeros(); n],
            wrench: vec![Vec6::zeros(); n],
            art_inertia: vec![ArticulatedInertia::zero(); n],
            art_bias: vec![Vec6::zeros(); n],
            u: vec![[Vec6::zeros(); 6]; n],
            d_inv: vec![Mat6::zeros(); n],
            u_tau: vec![Vec6::zeros(); n],
            composite: vec![BodyInertia::zero(); n],
        }
    }
}
