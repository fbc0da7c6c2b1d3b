//! Effects a scene declares. The engine composes exactly the declared ones: an undeclared
//! effect costs nothing, and a scene with none runs free motion.
//!
//! Uniform gravity enters the recursion as the base twist rate `[0; −g]`, so it costs no
//! extra pass; effects that add joint forces or body wrenches will implement `apply`.
use crate::error::{check_finite, Result};
use crate::spatial::{Vec3, Vec6};

#[derive(Debug, Clone, PartialEq)]
pub enum Effect {
    /// Uniform gravity `g` (m/s², world frame): `f_ij = m_ij g` on every point mass.
    Gravity { g: Vec3 },
}

impl Effect {
    pub fn gravity(g: Vec3) -> Result<Effect> {
        check_finite("gravity", g.as_slice())?;
        Ok(Effect::Gravity { g })
    }

    pub fn name(&self) -> &'static str {
        match self {
            Effect::Gravity { .. } => "gravity",
        }
    }
}

/// The declared effects, composed once for the right-hand side.
#[derive(Debug, Clone, Default)]
pub struct EffectSet {
    /// Sum of the declared uniform gravities (zero when none is declared).
    pub gravity: Vec3,
    pub has_gravity: bool,
}

impl EffectSet {
    pub fn new(effects: &[Effect]) -> Self {
        let mut set = EffectSet::default();
        for e in effects {
            match e {
                Effect::Gravity { g } => {
                    set.gravity += g;
                    set.has_gravity = true;
                }
            }
        }
        set
    }

    /// Adds the joint forces of the declared effects at `(t, q, v)` to `tau` and link
    /// wrenches to `wrenches`; returns whether any wrench was written. Gravity is not here:
    /// it rides on the base acceleration.
    #[inline]
    pub fn apply(
        &self,
        _t: f64,
        _q: &[f64],
        _v: &[f64],
        _tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> bool {
        false
    }
}
