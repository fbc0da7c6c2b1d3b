//! The per-call dynamics of a model as a binding asks for them: which path (`method`), what
//! a direction's call and input are named, and the one-configuration quantities computed in
//! a pooled [`Workspace`] at its loaded state. Each is one call, so a binding only converts.
use nalgebra::DMatrix;

use super::shared::{Direction, Workspace};
use crate::model::Model;
use crate::recursive;
use crate::support::alloc::try_zeros;
use crate::support::error::{check_result, Error, Result};
use crate::support::spatial::Vec3;

/// Link count above which a binding runs the recursive calls detached from its interpreter
/// (below it, the release costs more than it frees).
pub const DETACH_LINKS: usize = 64;

/// Whether a call on `model` is long enough to run detached ([`DETACH_LINKS`]).
pub fn worth_detaching(model: &Model) -> bool {
    model.links.len() >= DETACH_LINKS
}

/// The path a dynamics call takes: the recursive algorithms or the explicit DeNOC products.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Recursive,
    Denoc,
}

impl Method {
    /// `"recursive"` or `"denoc"`.
    pub fn parse(method: &str) -> Result<Self> {
        match method {
            "recursive" => Ok(Method::Recursive),
            "denoc" => Ok(Method::Denoc),
            other => Err(Error::arg(
                "method",
                "'recursive' or 'denoc'",
                format!("'{other}'"),
            )),
        }
    }
}

impl Direction {
    /// The call's name, for messages.
    pub fn name(self) -> &'static str {
        match self {
            Direction::Forward => "forward_dynamics",
            Direction::Inverse => "inverse_dynamics",
        }
    }

    /// The argument that is not a state: τ for forward dynamics, a for inverse.
    pub fn input(self) -> &'static str {
        match self {
            Direction::Forward => "tau",
            Direction::Inverse => "a",
        }
    }

    /// The derivatives call's name.
    pub fn derivatives_name(self) -> &'static str {
        match self {
            Direction::Forward => "forward_dynamics_derivatives",
            Direction::Inverse => "inverse_dynamics_derivatives",
        }
    }
}

impl Workspace {
    /// Refuses a model with loops or couplings for the derivatives call `name`: they are not
    /// differentiated.
    pub fn check_tree(&self, name: &str) -> Result<()> {
        let m = self.model();
        if !m.has_constraints() {
            return Ok(());
        }
        let expected =
            format!("a tree for {name} (closed loops and couplings are not differentiated)");
        let (nl, nc) = (m.loops.len(), m.couplings.len());
        let got = format!("a model with {nl} loop(s) and {nc} coupling(s)");
        Err(Error::arg("model", expected, got))
    }

    /// The joint-space inertia matrix at the loaded `q` (recursive).
    pub fn mass_matrix(&mut self) -> Result<DMatrix<f64>> {
        let nv = self.model().nv;
        let mut gim = try_zeros(nv, nv, "mass_matrix")?;
        recursive::mass_matrix(&self.version.model, &mut self.data, &self.q, &mut gim);
        Ok(gim)
    }

    /// The bias forces `C(q, v) v + g(q)` at the loaded `(q, v)` into `out` (inverse dynamics
    /// at zero acceleration).
    pub fn bias_forces(&mut self, g: &Vec3) -> &[f64] {
        self.x.fill(0.0);
        let (model, data) = (&*self.version.model, &mut self.data);
        recursive::inverse_dynamics(
            model,
            data,
            &self.q,
            &self.v,
            &self.x,
            g,
            None,
            &mut self.out,
        );
        &self.out
    }

    /// The kinetic energy at the loaded `(q, v)`, the rotors' (armature) included.
    pub fn kinetic_energy(&mut self) -> f64 {
        let model: &Model = &self.version.model;
        crate::kinematics::positions(model, &self.q, &mut self.data.links);
        crate::kinematics::velocities(model, &self.q, &self.v, &mut self.data.links);
        recursive::kinetic_energy(&self.data) + recursive::armature::kinetic_energy(model, &self.v)
    }

    /// The potential energy in gravity `g` at the loaded `q`.
    pub fn potential_energy(&mut self, g: &Vec3) -> f64 {
        crate::kinematics::positions(&self.version.model, &self.q, &mut self.data.links);
        recursive::potential_energy(&self.data, g)
    }
}

impl crate::dynamics::denoc::Denoc {
    /// Refuses matrices that are not finite (from finite inputs), naming the first.
    pub fn check_finite(&self, what: &str) -> Result<()> {
        for (k, m) in [("D", &self.d), ("N", &self.n), ("points", &self.points)] {
            check_result(&format!("{what}['{k}']"), m.as_slice())?;
        }
        Ok(())
    }
}

impl crate::dynamics::denoc::DenocRates {
    /// As [`crate::dynamics::denoc::Denoc::check_finite`].
    pub fn check_finite(&self, what: &str) -> Result<()> {
        for (k, m) in [("D", &self.d), ("N", &self.n)] {
            check_result(&format!("{what}['{k}']"), m.as_slice())?;
        }
        Ok(())
    }
}

/// The point masses (`n × 7`) and their world positions (`n × 7 × 3`, C order) at a checked
/// `q`, the positions checked finite.
pub fn point_masses(model: &Model, q: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
    let (masses, points) = super::denoc::point_positions(model, q);
    let points = points.transpose().as_slice().to_vec();
    check_result("point_masses", &points)?;
    Ok((masses.as_slice().to_vec(), points))
}
