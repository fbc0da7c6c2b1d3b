//! Uniform gravity: `f_ij = m_ij g` on every point mass. It rides on the base twist rate
//! `[0; −g]`, so the forward dynamics pays nothing for it; its potential energy is
//! `−Σ m_ij g·x_ij` (zero at the world origin).
use super::scene_writer as w;
use super::{required, Context, Declaration, Effect, Fields, ForceLaw, Kind, TomlType};
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::{Vec3, Vec6};

/// Gravity's declaration. [`Effect::Gravity`] stores its field inline (`{ g }`, the
/// serialised shape since the first format), so the registry reaches it through
/// [`Gravity::view`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(transparent)]
pub struct Gravity {
    /// m/s², world frame.
    pub g: Vec3,
}

impl Gravity {
    pub fn new(g: Vec3) -> Result<Gravity> {
        check_finite("gravity", g.as_slice())?;
        Ok(Gravity { g })
    }

    /// `Effect::Gravity { g }`'s field as a declaration.
    pub fn view(g: &Vec3) -> &Gravity {
        // SAFETY: `Gravity` is `repr(transparent)` over `Vec3`: same layout and alignment.
        unsafe { &*(g as *const Vec3 as *const Gravity) }
    }

    fn from_toml(f: &mut Fields<'_>) -> Result<Gravity> {
        let g = required(f.vec3("g")?, "g", "a 3-vector (m/s², world frame)")?;
        Gravity::new(g)
    }
}

impl From<Gravity> for Effect {
    fn from(d: Gravity) -> Effect {
        Effect::Gravity { g: d.g }
    }
}

impl Declaration for Gravity {
    fn to_toml(&self) -> Result<toml::Table> {
        Ok(w::EffectTable::new("gravity", None)
            .set("g", w::vec3(&self.g))
            .done())
    }
    fn kind(&self) -> Kind {
        Kind::Gravity
    }
    fn label(&self) -> Option<&str> {
        None
    }
    fn build(&self, _model: &Model) -> Result<Box<dyn ForceLaw>> {
        Ok(Box::new(GravityLaw { g: self.g }))
    }
    fn parameters(&self) -> &'static [&'static str] {
        &["g"]
    }
    fn with_parameter(&self, _key: &str, values: &[f64]) -> Result<Effect> {
        match values {
            [x, y, z] => Effect::gravity(Vec3::new(*x, *y, *z)),
            xs => Err(Error::arg("g", "3 values", format!("{} values", xs.len()))),
        }
    }
    fn repr(&self) -> String {
        let g = self.g;
        format!("Gravity(g=[{}, {}, {}])", g.x, g.y, g.z)
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "gravity",
            keys: &["g"],
            parse: |_, f| Gravity::from_toml(f).map(Effect::from),
        }];
        TYPES
    }
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
