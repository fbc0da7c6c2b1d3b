//! Uniform gravity: `f_ij = m_ij g` on every point mass. It rides on the base twist rate
//! `[0; −g]`, so the forward dynamics pays nothing for it; its potential energy is
//! `−Σ m_ij g·x_ij` (zero at the world origin).
use super::{Context, ForceLaw};
use crate::kinematics::LinkState;
use crate::spatial::{Vec3, Vec6};

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
    ) -> Result<bool, String> {
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
