//! Uniform gravity: `f_ij = m_ij g` on every point mass. It rides on the base twist rate
//! `[0; −g]`, so the forward dynamics pays nothing for it; its potential energy is
//! `−Σ m_ij g·x_ij` (zero at the world origin).
use super::{required, Context, Effect, Fields, ForceLaw};
use crate::error::Result;
use crate::kinematics::LinkState;
use crate::spatial::{Vec3, Vec6};

/// Keys of a `type = "gravity"` table.
pub(super) const KEYS: &[&str] = &["g"];

/// Parses a `type = "gravity"` table. Gravity has no declaration type of its own: it is
/// `Effect::Gravity { g }`, and `Effect`'s methods treat it apart (`each_effect!`).
pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<Effect> {
    let g = required(f.vec3("g")?, "g", "a 3-vector (m/s², world frame)")?;
    Effect::gravity(g)
}

pub struct GravityLaw {
    pub g: Vec3,
}

impl ForceLaw for GravityLaw {
    fn base_acceleration(&self) -> Option<Vec3> {
        Some(self.g)
    }
    fn apply(
        &mut self,
        _cx: &Context<'_>,
        _tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        Ok(false)
    }
    fn potential_energy(&self, _cx: &Context<'_>, links: &[LinkState]) -> Option<f64> {
        Some(
            -links
                .iter()
                .map(|s| {
                    self.g
                        .dot(&(s.origin * s.inertia.mass + s.inertia.first_moment))
                })
                .sum::<f64>(),
        )
    }
}
