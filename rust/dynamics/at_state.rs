//! A model's one-state quantities as a binding asks for them (`Model.mass_matrix`,
//! `bias_forces`, the energies, the loops' residual, Jacobian and forces, the speeds and
//! accelerations they allow, the couplings' forces): the call's arguments read ([`Arg`]) into a pooled [`Workspace`] and checked, the
//! quantity computed there, checked finite and handed back as C-ordered values with their
//! shape, so that the binding declares its methods and converts.
use nalgebra::DMatrix;

use super::calls::{worth_detaching, Method};
use super::shared::Workspace;
use crate::model::args::{external, fixed_mask, gravity};
use crate::support::args::{vector, Arg};
use crate::support::error::{check_finite, check_result, Error, Result};
use crate::support::spatial::{Vec3, Vec6};

/// A quantity at one state, named as the method that asks for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    MassMatrix(Method),
    BiasForces,
    KineticEnergy,
    PotentialEnergy,
    ConstraintResidual,
    ConstraintJacobian,
    ConstraintForces,
    CouplingForces,
    AssembledVelocity,
    AssembledAcceleration,
}

/// A call's arguments by name; `None`: not one of the call's parameters, or not given.
pub struct Given<'a, A> {
    pub q: Option<&'a A>,
    pub v: Option<&'a A>,
    pub tau: Option<&'a A>,
    pub gravity: Option<&'a A>,
    pub external: Option<&'a A>,
    pub v_guess: Option<&'a A>,
    pub a_guess: Option<&'a A>,
    pub fixed: Option<&'a A>,
}

impl<'a, A> Given<'a, A> {
    /// `q` alone.
    pub fn q(q: &'a A) -> Self {
        Given {
            q: Some(q),
            ..Given::none()
        }
    }

    /// No argument given (the rest of a call's arguments, in struct-update syntax).
    pub fn none() -> Self {
        Given {
            q: None,
            v: None,
            tau: None,
            gravity: None,
            external: None,
            v_guess: None,
            a_guess: None,
            fixed: None,
        }
    }
}

/// A quantity's values in C order and their shape (`[]`: one number).
pub type Values = (Vec<f64>, Vec<usize>);

/// A call read: the quantity, gravity, the external wrenches and the held speeds of an
/// assembly (the state and the guesses are in the workspace).
pub struct Loaded {
    what: Quantity,
    g: Vec3,
    ext: Option<Vec<Vec6>>,
    fixed: Vec<bool>,
}

impl Quantity {
    /// The method's name, for messages.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::MassMatrix(_) => "mass_matrix",
            Quantity::BiasForces => "bias_forces",
            Quantity::KineticEnergy => "kinetic_energy",
            Quantity::PotentialEnergy => "potential_energy",
            Quantity::ConstraintResidual => "constraint_residual",
            Quantity::ConstraintJacobian => "constraint_jacobian",
            Quantity::ConstraintForces => "constraint_forces",
            Quantity::CouplingForces => "coupling_forces",
            Quantity::AssembledVelocity => "assemble_velocity",
            Quantity::AssembledAcceleration => "assemble_acceleration",
        }
    }
}

impl Loaded {
    /// Whether the computation is long enough to run detached from the binding's interpreter
    /// (with Ctrl-C honoured): the mass matrix of a long chain, or by the DeNOC products.
    pub fn long(&self, ws: &Workspace) -> bool {
        match self.what {
            Quantity::MassMatrix(Method::Denoc) => true,
            Quantity::MassMatrix(Method::Recursive) => worth_detaching(ws.model()),
            _ => false,
        }
    }
}

impl Workspace {
    /// Reads `what`'s arguments: gravity, then `q` and `v` (or `v_guess`) into the workspace,
    /// checked, then `tau` (or `a_guess`), the external wrenches and `fixed`.
    pub fn load<A: Arg>(
        &mut self,
        what: Quantity,
        given: Given<'_, A>,
    ) -> std::result::Result<Loaded, A::Err> {
        let g = gravity(given.gravity)?;
        let (nq, nv) = (self.model().nq, self.model().nv);
        // Each buffer replaced by one of its own length (the values are read into a new
        // vector anyway).
        if let Some(q) = given.q {
            self.q = vector(q, "q", Some(nq))?;
        }
        let v = (given.v.map(|v| (v, "v"))).or(given.v_guess.map(|v| (v, "v_guess")));
        if let Some((v, arg)) = v {
            self.v = vector(v, arg, Some(nv))?;
        }
        let v_arg = v.map_or("v", |(_, arg)| arg);
        let named = |e: Error| e.map_arg(|n| if n == "v" { v_arg.into() } else { n });
        self.check_state(v.is_some()).map_err(named)?;
        let x = (given.tau.map(|x| (x, "tau"))).or(given.a_guess.map(|x| (x, "a_guess")));
        if let Some((x, arg)) = x {
            self.x = vector(x, arg, Some(nv))?;
            check_finite(arg, &self.x)?;
        }
        let ext = external(self.model(), given.external)?;
        let fixed = match what {
            Quantity::AssembledVelocity | Quantity::AssembledAcceleration => {
                fixed_mask(self.model(), given.fixed)?
            }
            _ => vec![],
        };
        Ok(Loaded {
            what,
            g,
            ext,
            fixed,
        })
    }

    /// The quantity a [`Workspace::load`] read, at the loaded state, checked finite.
    pub fn compute(&mut self, call: &Loaded) -> Result<Values> {
        let (name, g) = (call.what.name(), &call.g);
        let c_order = |m: DMatrix<f64>| -> Result<Values> {
            check_result(name, m.as_slice())?;
            Ok((
                m.transpose().as_slice().to_vec(),
                vec![m.nrows(), m.ncols()],
            ))
        };
        let values = match call.what {
            Quantity::MassMatrix(Method::Recursive) => return c_order(self.mass_matrix()?),
            Quantity::MassMatrix(Method::Denoc) => {
                return c_order(super::denoc::mass_matrix(self.model(), &self.q)?)
            }
            Quantity::ConstraintJacobian => {
                let q = &self.q;
                return c_order(crate::frames::constrained::constraint_jacobian(
                    self.model(),
                    q,
                ));
            }
            Quantity::BiasForces => self.bias_forces(g).to_vec(),
            Quantity::KineticEnergy => vec![self.kinetic_energy()],
            Quantity::PotentialEnergy => vec![self.potential_energy(g)],
            Quantity::ConstraintResidual => crate::loops::args::residual_at(self.model(), &self.q),
            Quantity::ConstraintForces => {
                let w = self.constraint_forces(g, call.ext.as_deref())?;
                let flat: Vec<f64> = w.iter().flatten().copied().collect();
                check_result(name, &flat)?;
                return Ok((flat, vec![w.len(), 6]));
            }
            Quantity::CouplingForces => {
                let lambda = self.constraint_multipliers(g)?;
                crate::loops::coupling::forces(self.model(), &lambda)
            }
            // The guess projected onto the loops' speeds (accelerations at the loaded `v`).
            Quantity::AssembledVelocity | Quantity::AssembledAcceleration => {
                let at_v = call.what == Quantity::AssembledAcceleration;
                let mut x = if at_v { self.x.clone() } else { self.v.clone() };
                let v = at_v.then_some(self.v.as_slice());
                let (model, q) = (self.model(), &self.q);
                crate::loops::project_velocity_like(model, q, v, &mut x, &call.fixed)?;
                x
            }
        };
        check_result(name, &values)?;
        let shape = match call.what {
            Quantity::KineticEnergy | Quantity::PotentialEnergy => vec![],
            _ => vec![values.len()],
        };
        Ok((values, shape))
    }
}
