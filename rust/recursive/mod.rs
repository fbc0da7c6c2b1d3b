//! O(n) recursive dynamics over the DeNOC quantities: twists and twist rates outward,
//! wrenches inward (`τ_i = P_iᵀ w_i`), the articulated-body recursion for forward dynamics
//! (equivalent to Saha's UDUᵀ of the GIM, never forming it), and the composite-body GIM.
//! All vectors are about each link's origin, angular part first. The default forward and
//! inverse dynamics (`forward_dynamics`, `inverse_dynamics`) run in body frames
//! (`forward_local`, `inverse_local`, sharing one outward kinematic pass); the world-axes
//! versions (`forward_dynamics_world`, `inverse_dynamics_world`) stay as cross-checks.
//! Nothing here allocates: `Data` is the workspace, sized once per model.
pub mod forward;
pub mod forward_local;
pub mod inverse;
pub mod inverse_local;
pub mod mass_matrix;
pub mod mass_matrix_local;
#[cfg(test)]
mod tests;

use crate::kinematics::LinkState;
use crate::model::Model;
use crate::spatial::{ArticulatedInertia, BodyInertia, Mat3, Vec3, Vec6};

pub use forward::forward_dynamics_world;
pub use forward_local::{forward_dynamics_local, LocalLink};
pub use inverse::inverse_dynamics_world;
pub use inverse_local::inverse_dynamics_local;
pub use mass_matrix::mass_matrix_world;
pub use mass_matrix_local::mass_matrix_local;

/// Workspace for one model (like Pinocchio's `Data`): built by `Data::new(model)` and valid
/// for that model only (it caches per-link constants such as the joints' plane codes).
#[derive(Debug, Clone)]
pub struct Data {
    pub links: Vec<LinkState>,
    /// Twist rates `ṫ_i`.
    pub accel: Vec<Vec6>,
    /// Wrenches transmitted by each joint.
    pub wrench: Vec<Vec6>,
    pub art_inertia: Vec<ArticulatedInertia>,
    pub art_bias: Vec<Vec6>,
    /// `U = M̂ P` (columns).
    pub u: Vec<[Vec6; 3]>,
    /// `D⁻¹ = (Pᵀ M̂ P)⁻¹`, upper-left dof × dof block used.
    pub d_inv: Vec<Mat3>,
    /// `τ − Pᵀ b̂`.
    pub u_tau: Vec<Vec3>,
    pub composite: Vec<BodyInertia>,
    /// Workspace of the body-frame recursion (`forward_local`), per link; its `plane` codes
    /// are the model's, set here once.
    pub local: Vec<LocalLink>,
    /// Each link's own inertia in the form that starts its articulated inertia (model
    /// constant, set here once).
    pub local_body: Vec<forward_local::LocalInertia>,
    /// `(link, q index)` of the revolute joints about a coordinate axis, whose sines and
    /// cosines the outward pass takes four at a time (model constant).
    pub axis_angles: Vec<(usize, usize)>,
    /// `nv` zeros (the speeds of a position-only outward pass).
    pub zero_v: Vec<f64>,
}

impl Data {
    pub fn new(model: &Model) -> Self {
        let n = model.links.len();
        let (local, local_body) = forward_local::local_links_of(model);
        Data {
            links: vec![LinkState::default(); n],
            accel: vec![Vec6::zeros(); n],
            wrench: vec![Vec6::zeros(); n],
            art_inertia: vec![ArticulatedInertia::zero(); n],
            art_bias: vec![Vec6::zeros(); n],
            u: vec![[Vec6::zeros(); 3]; n],
            d_inv: vec![Mat3::zeros(); n],
            u_tau: vec![Vec3::zeros(); n],
            composite: vec![BodyInertia::zero(); n],
            axis_angles: local
                .iter()
                .zip(&model.links)
                .enumerate()
                .filter(|(_, (l, _))| l.kind != forward_local::OTHER_KIND)
                .map(|(i, (_, link))| (i, link.q_index))
                .collect(),
            zero_v: vec![0.0; model.nv],
            local,
            local_body,
        }
    }

    pub fn fits(&self, model: &Model) -> bool {
        self.links.len() == model.links.len()
    }
}

/// Accelerations `a` from `I a + C v − τ_g − Nᵀ f_ext = τ`: the body-frame articulated-body
/// recursion ([`forward_dynamics_local`]). `external`: one wrench per link,
/// `[moment about the link origin; force]` in world axes. Errors at a ZYZ Euler singularity
/// or a non-positive joint block.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn forward_dynamics(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    a: &mut [f64],
) -> crate::error::Result<()> {
    forward_dynamics_local(model, data, q, v, tau, g, external, a)
}

/// The generalized inertia matrix (nv × nv) at `q`, by composite bodies in link frames
/// ([`mass_matrix_local`]; [`mass_matrix_world`] is the world-frame cross-check).
#[inline]
pub fn mass_matrix(model: &Model, data: &mut Data, q: &[f64], gim: &mut nalgebra::DMatrix<f64>) {
    mass_matrix_local(model, data, q, gim)
}

/// `τ = I a + C v − τ_g − Nᵀ f_ext`: the body-frame Newton–Euler recursion
/// ([`inverse_dynamics_local`]), which rounds the geometry exactly as [`forward_dynamics`]
/// does. `external` as for [`forward_dynamics`]. Writes `tau` (length nv).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn inverse_dynamics(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    tau: &mut [f64],
) {
    inverse_dynamics_local(model, data, q, v, a, g, external, tau)
}

/// Base twist rate that puts uniform gravity into every body: `ṫ_0 = [0; −g]`.
#[inline]
pub(crate) fn base_accel(g: &Vec3) -> Vec6 {
    Vec6::new(0.0, 0.0, 0.0, -g.x, -g.y, -g.z)
}

/// Kinetic energy `½ Σ t_iᵀ M_i t_i` (needs velocities in `data`).
pub fn kinetic_energy(data: &Data) -> f64 {
    data.links
        .iter()
        .map(|s| 0.5 * s.twist.dot(&s.inertia.mul_twist(&s.twist)))
        .sum()
}

/// Gravitational potential `−Σ m_ij g·x_ij` (needs positions in `data`).
pub fn potential_energy(data: &Data, g: &Vec3) -> f64 {
    -data
        .links
        .iter()
        .map(|s| g.dot(&(s.origin * s.inertia.mass + s.inertia.first_moment)))
        .sum::<f64>()
}

/// Refuses a configuration at a joint's coordinate singularity (ZYZ at sin θ ≈ 0), for the
/// recursive and the explicit paths alike.
pub fn check_singularities(model: &Model, q: &[f64]) -> crate::error::Result<()> {
    for (i, l) in model.links.iter().enumerate() {
        if l.joint
            .singularity(&q[l.q_index..l.q_index + l.joint.nq()])
            .is_some()
        {
            return Err(crate::error::Error::Singular(singular_message(model, i, q)));
        }
    }
    Ok(())
}

/// A message naming the link whose joint makes the recursion singular.
pub(crate) fn singular_message(model: &Model, link: usize, q: &[f64]) -> String {
    let l = &model.links[link];
    let name = &model.bodies[l.body].name;
    if l.joint
        .singularity(&q[l.q_index..l.q_index + l.joint.nq()])
        .is_some()
    {
        let what = l.joint.describe_singularity(&q[l.q_index..], l.q_index);
        return format!("{} joint of body '{name}' {what}", l.joint.kind());
    }
    format!("joint of body '{name}' has a singular articulated inertia (a massless subtree, or a body too slender for the recursion: try method='denoc')")
}
