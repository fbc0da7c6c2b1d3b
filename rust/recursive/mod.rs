//! O(n) recursive dynamics over the DeNOC quantities (docs/method.md §4): twists and twist
//! rates outward, wrenches inward (`τ_i = P_iᵀ w_i`), the articulated-body recursion for
//! forward dynamics (equivalent to Saha's UDUᵀ of the GIM, never forming it), and the
//! composite-body GIM. All vectors are about each link's origin, angular part first.
//!
//! Layout (docs/architecture.md):
//! * [`reference`]: the world-axes recursions, short and close to the equations; the tests
//!   hold everything else to them.
//! * [`aba`], [`rnea`], [`crba`]: the default forward dynamics, inverse dynamics and mass
//!   matrix, in body frames; [`outward`] is the kinematic pass they share.
//! * [`rnea_derivatives`], [`aba_derivatives`]: analytic derivatives of the inverse and
//!   forward dynamics (world frame, tangent space; docs/derivatives.md).
//! * [`compiled`]: the model's constants for them (built once per model, [`Model::compiled`]);
//!   [`workspace`]: their per-call values ([`Data`]).
//! * [`algebra`] and [`shift`]: the 3×3 block algebra and the carrying of inertias and
//!   wrenches across a joint, written out so each joint case costs only its non-zeros.
//!
//! Nothing here allocates: `Data` is the workspace, sized once per model.
pub mod aba;
pub mod aba_derivatives;
mod aba_derivatives_small;
pub(crate) mod algebra;
pub mod armature;
pub mod compiled;
pub mod crba;
mod deriv_rows;
#[cfg(test)]
#[path = "tests/derivatives.rs"]
mod derivative_tests;
mod outward;
pub mod reference;
pub mod rnea;
pub mod rnea_derivatives;
pub(crate) mod shift;
pub mod tangent;
#[cfg(test)]
mod tests;
pub mod workspace;

use crate::model::Model;
use crate::support::spatial::{Vec3, Vec6};

pub use aba::forward_dynamics_local;
pub use aba_derivatives::forward_dynamics_derivatives;
pub use compiled::Compiled;
pub use crba::mass_matrix_local;
pub use deriv_rows::rows_surely_finite;
pub use rnea::inverse_dynamics_local;
pub use rnea_derivatives::{inverse_dynamics_derivatives, inverse_dynamics_derivatives_into};
pub use workspace::{Data, DerivativeData};

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
) -> crate::support::error::Result<()> {
    forward_dynamics_local(model, data, q, v, tau, g, external, a)
}

/// The generalized inertia matrix (nv × nv) at `q`, by composite bodies in link frames
/// ([`mass_matrix_local`]; [`reference::mass_matrix_world`] is the world-frame cross-check).
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
pub fn check_singularities(model: &Model, q: &[f64]) -> crate::support::error::Result<()> {
    for (i, l) in model.links.iter().enumerate() {
        if l.joint
            .singularity(&q[l.q_index..l.q_index + l.joint.nq()])
            .is_some()
        {
            return Err(crate::support::error::Error::Singular(singular_message(
                model, i, q,
            )));
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
