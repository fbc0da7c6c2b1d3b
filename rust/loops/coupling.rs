//! Joint couplings (mimic joints, gears, belts): `q_joint = ratio · q_reference + offset`
//! between two 1-dof joints, one holonomic constraint row each, solved by the loop solver
//! beside the cut joints (docs/couplings.md). Their rows come after every loop's:
//!
//! * position `φ = q_j − ratio · q_r − offset`;
//! * velocity `J = e_jᵀ − ratio · e_rᵀ` (a revolute or prismatic joint's speed is its `q̇`);
//! * `γ = J̇ q̇ = 0` (the row is constant).
//!
//! The multiplier is the generalized force the coupling applies to the joint (the reference
//! feels `−ratio` times it): `I q̈ + C q̇ = τ + Jᵀλ`.
use nalgebra::DMatrix;

use crate::model::constraints::Coupling;
use crate::model::Model;
use crate::support::error::{Error, Result};

/// A body's joint slot if it is a moving 1-dof joint: `(q index, v index)`.
fn slot(model: &Model, body: usize) -> Option<(usize, usize)> {
    let l = &model.links[model.bodies.get(body)?.link?];
    (l.body == body && l.joint.nv() == 1 && l.joint.nq() == 1).then_some((l.q_index, l.v_index))
}

impl Model {
    /// Number of couplings.
    pub fn ncouplings(&self) -> usize {
        self.couplings.len()
    }

    /// Whether the model has constraints (cut joints or couplings): then the dynamics goes
    /// through the loop solver.
    #[inline]
    pub fn has_constraints(&self) -> bool {
        !self.loops.is_empty() || !self.couplings.is_empty()
    }

    /// Couples body `joint`'s joint to body `reference`'s: `q_joint = ratio · q_reference +
    /// offset`. Both must be revolute or prismatic joints; refuses a joint coupled to itself,
    /// a joint already coupled, a cycle of couplings and non-finite numbers. Returns the
    /// coupling's index.
    pub fn add_coupling(
        &mut self,
        joint: usize,
        reference: usize,
        ratio: f64,
        offset: f64,
        name: Option<String>,
    ) -> Result<usize> {
        crate::support::error::check_name("coupling", name.as_deref())?;
        let n = self.bodies.len();
        for (arg, b) in [("joint", joint), ("reference", reference)] {
            if b >= n {
                return Err(Error::arg(
                    arg,
                    format!("a body index 0..{n} or a joint/body name"),
                    b.to_string(),
                ));
            }
            if slot(self, b).is_none() {
                return Err(Error::arg(
                    arg,
                    "a revolute or prismatic (1-dof) joint",
                    format!(
                        "the {} joint of body '{}'",
                        self.bodies[b].joint.kind(),
                        self.bodies[b].name
                    ),
                ));
            }
        }
        for (arg, x) in [("ratio", ratio), ("offset", offset)] {
            if !x.is_finite() {
                return Err(Error::arg(arg, "a finite number", x.to_string()));
            }
        }
        let body = |b: usize| format!("'{}'", self.bodies[b].name);
        if joint == reference {
            return Err(Error::arg(
                "reference",
                "a joint other than `joint` (a joint cannot be coupled to itself)",
                format!("the joint of body {} for both", body(joint)),
            ));
        }
        if let Some(c) = self.couplings.iter().find(|c| c.joint == joint) {
            return Err(Error::arg(
                "joint",
                "a joint not yet coupled (each joint follows at most one reference)",
                format!(
                    "body {}, which already follows {} (coupling '{}')",
                    body(joint),
                    body(c.reference),
                    c.name
                ),
            ));
        }
        // Each joint follows at most one reference, so the couplings form chains: walking
        // from `reference` along them must not come back to `joint`.
        let mut chain = vec![joint, reference];
        let mut at = reference;
        while let Some(c) = self.couplings.iter().find(|c| c.joint == at) {
            at = c.reference;
            chain.push(at);
            if at == joint {
                let names: Vec<String> = chain.iter().map(|&b| body(b)).collect();
                return Err(Error::arg(
                    "reference",
                    "a joint whose own chain of couplings does not lead back to `joint`",
                    format!("a cycle of couplings {}", names.join(" → ")),
                ));
            }
        }
        let index = self.couplings.len();
        let name = name.unwrap_or_else(|| format!("coupling{index}"));
        if self.couplings.iter().any(|c| c.name == name) {
            return Err(Error::model(
                "name",
                format!("a coupling named '{name}' already exists"),
            ));
        }
        self.couplings.push(Coupling {
            name,
            joint,
            reference,
            ratio,
            offset,
        });
        Ok(index)
    }

    /// Checks the couplings of a deserialised model (1-dof joints, finite numbers).
    pub(crate) fn check_couplings(&self) -> Result<()> {
        for c in &self.couplings {
            let ok = slot(self, c.joint).is_some()
                && slot(self, c.reference).is_some()
                && c.joint != c.reference
                && c.ratio.is_finite()
                && c.offset.is_finite();
            if !ok {
                return Err(Error::model(
                    "model",
                    format!(
                        "coupling '{}' names a body out of range, a joint that is not 1-dof, or non-finite numbers",
                        c.name
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The coupling owning constraint row `row`, if it is a coupling's (rows after the loops').
    pub fn coupling_of_row(&self, row: usize) -> Option<usize> {
        let first = self.nconstraints() - self.couplings.len();
        (row >= first).then(|| row - first)
    }

    /// What owns constraint row `row`, for messages: `loop 'name'` or `coupling 'name'`.
    pub fn constraint_name(&self, row: usize) -> String {
        match self.coupling_of_row(row) {
            Some(k) => format!("coupling '{}'", self.couplings[k].name),
            None => format!(
                "loop '{}'",
                self.loops[super::constraints::loop_of_row(self, row)].name
            ),
        }
    }
}

/// The couplings' `(q index, v index)` of joint and reference, resolved once per call.
fn slots(model: &Model, c: &Coupling) -> ((usize, usize), (usize, usize)) {
    // `add_coupling` and deserialisation admit only 1-dof joints.
    let s = |b| slot(model, b).unwrap_or((0, 0));
    (s(c.joint), s(c.reference))
}

/// Writes the couplings' residuals `q_j − ratio q_r − offset` into `out` (one per coupling).
pub(super) fn residual(model: &Model, q: &[f64], out: &mut [f64]) {
    for (c, o) in model.couplings.iter().zip(out) {
        let ((qj, _), (qr, _)) = slots(model, c);
        *o = q[qj] - c.ratio * q[qr] - c.offset;
    }
}

/// Writes the couplings' Jacobian rows from `first` on (the rest of the row is left zero).
pub(super) fn jacobian(model: &Model, first: usize, jac: &mut DMatrix<f64>) {
    for (k, c) in model.couplings.iter().enumerate() {
        let ((_, vj), (_, vr)) = slots(model, c);
        jac[(first + k, vj)] += 1.0;
        jac[(first + k, vr)] -= c.ratio;
    }
}

/// Each coupling's generalized force on its joint (its multiplier).
pub fn forces(model: &Model, lambda: &[f64]) -> Vec<f64> {
    let first = model.nconstraints() - model.couplings.len();
    lambda[first..first + model.couplings.len()].to_vec()
}
