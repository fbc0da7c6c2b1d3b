//! A model's listings as a binding shows them: names, joint slices and records, a body's
//! summary, the one-line description, the couplings and the rotor inertias.
use super::Model;
use crate::support::error::{Error, Result};

impl Model {
    /// The moving links' names (their bodies'), in link order.
    pub fn link_names(&self) -> Vec<String> {
        let names = self.links.iter().map(|l| self.bodies[l.body].name.clone());
        names.collect()
    }

    /// Per link: `(q index, v index, nq, nv)` of its joint.
    pub fn joint_slices(&self) -> Vec<(usize, usize, usize, usize)> {
        let slice = |l: &super::Link| (l.q_index, l.v_index, l.joint.nq(), l.joint.nv());
        self.links.iter().map(slice).collect()
    }

    /// Body `index`: its name, joint kind, parent body and link (-1 for none).
    pub fn body_info(&self, index: usize) -> Result<(String, String, i64, i64)> {
        let n = self.nbodies();
        let b = self
            .bodies
            .get(index)
            .ok_or_else(|| Error::model("index", format!("no body {index} (the model has {n})")))?;
        let or_none = |x: Option<usize>| x.map_or(-1, |x| x as i64);
        let kind = b.joint.kind().to_string();
        Ok((b.name.clone(), kind, or_none(b.parent), or_none(b.link)))
    }

    /// Per joint name: `(lower, upper, effort, velocity)` (infinite where the file gave none).
    pub fn joint_limits(&self) -> Vec<(String, (f64, f64, f64, f64))> {
        let inf = f64::INFINITY;
        let limits = self.link_joints().map(|j| match j.and_then(|j| j.limit) {
            Some(x) => (x.lower, x.upper, x.effort, x.velocity),
            None => (-inf, inf, inf, inf),
        });
        self.joint_names().into_iter().zip(limits).collect()
    }

    /// Per joint name: `(damping, friction)` (zero where the file gave none).
    pub fn joint_dynamics(&self) -> Vec<(String, (f64, f64))> {
        let dynamics = self
            .link_joints()
            .map(|j| j.map_or((0.0, 0.0), |j| (j.damping, j.friction)));
        self.joint_names().into_iter().zip(dynamics).collect()
    }

    /// `Model(nbodies=…, nlinks=…, nq=…, nv=…[, nloops=…][, ncouplings=…])`.
    pub fn summary(&self) -> String {
        let (nb, nl, nq, nv) = (self.nbodies(), self.links.len(), self.nq, self.nv);
        let mut s = format!("Model(nbodies={nb}, nlinks={nl}, nq={nq}, nv={nv}");
        if !self.loops.is_empty() {
            s += &format!(", nloops={}", self.loops.len());
        }
        if !self.couplings.is_empty() {
            s += &format!(", ncouplings={}", self.couplings.len());
        }
        s + ")"
    }

    /// Per coupling: `(name, joint body, reference body, ratio, offset)`.
    pub fn coupling_list(&self) -> Vec<(String, String, String, f64, f64)> {
        let name = |b: usize| self.bodies[b].name.clone();
        let row = |c: &super::constraints::Coupling| {
            (
                c.name.clone(),
                name(c.joint),
                name(c.reference),
                c.ratio,
                c.offset,
            )
        };
        self.couplings.iter().map(row).collect()
    }

    /// The rotor inertia per speed (zeros when none was set).
    pub fn armature_per_speed(&self) -> Vec<f64> {
        match self.armature.is_empty() {
            true => vec![0.0; self.nv],
            false => self.armature.clone(),
        }
    }
}
