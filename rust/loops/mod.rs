//! Closed kinematic loops by cut joints (docs/loops.md). A mechanism with loops is modelled
//! as its spanning tree plus one *cut joint* per loop: a joint between a frame on body a and
//! a frame on body b that the tree does not contain. The cut joint's constraint wrench is
//! carried as Lagrange multipliers, `I q̈ + C q̇ = τ + Jᵀλ`, `J q̈ = −J̇ q̇`, as the DeNOC
//! school treats loops; the tree's dynamics is untouched.
//!
//! * [`constraints`]: the cut joints' residual, velocity Jacobian `J` and `J̇ q̇`, from the
//!   world-frame kinematics of the tree.
//! * [`solve`]: the constrained forward dynamics (redundant constraints included), the
//!   constraint wrenches, the driving forces of chosen actuated joints, and the projections
//!   onto the position, velocity and acceleration manifolds (`assemble`).
//! * [`derivatives`]: the constrained forward dynamics' derivatives (state Jacobian).
pub mod args;
mod constraints;
pub mod coupling;
mod derivatives;
mod ordering;
mod solve;
#[cfg(test)]
mod tests;

pub use constraints::{gamma, jacobian, residual, wrenches, Constraints, LoopKinematics};
pub use derivatives::{constrained_derivatives, LoopDerivativeWork};
pub use solve::{
    assemble, check_mobility, constrained_forward_dynamics, constraint_forces, driving_forces,
    project_state, project_velocity_like, LoopSolver,
};

pub use ordering::Layout;

use crate::joint::Joint;
use crate::model::constraints::{CutKind, LoopJoint};
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Placement;

impl Model {
    /// Number of cut joints.
    pub fn nloops(&self) -> usize {
        self.loops.len()
    }

    /// Number of scalar constraints of all cut joints and couplings (rows of the constraint
    /// Jacobian; the couplings' rows come last, one each).
    pub fn nconstraints(&self) -> usize {
        self.loops.iter().map(|l| l.kind().rows()).sum::<usize>() + self.couplings.len()
    }

    /// First constraint row of each loop, and the first row after the loops'.
    pub fn constraint_rows(&self) -> Vec<usize> {
        let mut rows = Vec::with_capacity(self.loops.len() + 1);
        let mut r = 0;
        for l in &self.loops {
            rows.push(r);
            r += l.kind().rows();
        }
        rows.push(r);
        rows
    }

    /// Adds a cut joint closing a loop; returns its index. `frame_a`/`frame_b` place the cut
    /// joint's frame on each body. Refuses unknown bodies, a loop from a body to itself (or
    /// to a body rigidly welded to it: both in one link, or both fixed to the world), joint
    /// types other than revolute, prismatic, spherical and fixed, and duplicate names.
    pub fn add_loop(
        &mut self,
        body_a: Option<usize>,
        body_b: Option<usize>,
        joint: Joint,
        frame_a: Placement,
        frame_b: Placement,
        name: Option<String>,
    ) -> Result<usize> {
        crate::support::error::check_name("loop", name.as_deref())?;
        let n = self.bodies.len();
        for (arg, b) in [("body_a", body_a), ("body_b", body_b)] {
            if let Some(k) = b {
                if k >= n {
                    return Err(Error::model(
                        arg,
                        format!("no body with index {k}: the model has {n} bodies (indices 0..{n}), or -1 / 'world' for the ground"),
                    ));
                }
            }
        }
        if CutKind::of(&joint).is_none() {
            return Err(Error::arg(
                "joint",
                "a Revolute, Prismatic, Spherical or Fixed cut joint",
                format!("a {} joint", joint.kind()),
            ));
        }
        let link = |b: Option<usize>| b.and_then(|k| self.bodies[k].link);
        if link(body_a) == link(body_b) {
            let what = |b: Option<usize>| match b {
                Some(k) => format!("body '{}'", self.bodies[k].name),
                None => "the world".to_string(),
            };
            let reason = if body_a == body_b {
                format!(
                    "a loop must join two different bodies; both are {}",
                    what(body_a)
                )
            } else {
                format!(
                    "{} and {} are welded together (fixed joints), so the loop would join a rigid body to itself",
                    what(body_a),
                    what(body_b)
                )
            };
            return Err(Error::model("body_b", reason));
        }
        let mut frames = [frame_a, frame_b];
        for (f, (rot, trans)) in frames.iter_mut().zip([
            ("rotation_a", "translation_a"),
            ("rotation_b", "translation_b"),
        ]) {
            crate::support::error::check_finite(trans, f.translation.as_slice())?;
            f.rotation = crate::model::checked_rotation(&f.rotation, rot)?;
        }
        let index = self.loops.len();
        let name = name.unwrap_or_else(|| format!("loop{index}"));
        if self.loops.iter().any(|l| l.name == name) {
            return Err(Error::model(
                "name",
                format!("a loop named '{name}' already exists"),
            ));
        }
        self.loops.push(LoopJoint {
            name,
            body_a,
            body_b,
            joint,
            frame_a: frames[0],
            frame_b: frames[1],
        });
        Ok(index)
    }

    /// Checks the cut joints of a deserialised model (bodies in range, admitted types).
    pub(crate) fn check_loops(&self) -> Result<()> {
        let n = self.bodies.len();
        for l in &self.loops {
            let bad_body = [l.body_a, l.body_b].iter().flatten().any(|&k| k >= n);
            if bad_body || CutKind::of(&l.joint).is_none() {
                return Err(Error::model(
                    "model",
                    format!("loop '{}' names a body out of range or a joint type that cannot cut a loop", l.name),
                ));
            }
        }
        Ok(())
    }
}

/// The loop solver's layout for `model` (docs/loops.md §3): the banded or dense QRs, and the
/// order of the coordinates the banded ones take.
pub fn solver_layout(model: &Model) -> Layout {
    let solver = LoopSolver::new(model);
    ordering::layout(model, solver.envelope, solver.order())
}
