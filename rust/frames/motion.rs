//! The world-frame kinematics every frame algorithm reads: the links' poses and joint columns
//! (`crate::kinematics`), their twists, the rates of their joint columns and (on demand)
//! their accelerations; then a frame's or a body point's velocity and acceleration.
//!
//! A link's twist `t = [ω; v_O]` and its columns `s_k` are about the link origin `O`; its
//! acceleration `[ω̇; a_O]` is the classical one (the second derivative of `O`).
use crate::joint::Subspace;
use crate::kinematics::{self, LinkState};
use crate::model::Model;
use crate::support::spatial::{angular, linear, stack, Vec3, Vec6};

use super::FrameRef;

/// Buffers for one model, reused call to call (nothing allocated after [`FrameKinematics::new`]).
#[derive(Debug, Clone)]
pub struct FrameKinematics {
    pub links: Vec<LinkState>,
    /// Rates of each link's joint columns `ṡ_k` (about the moving link origin, world axes).
    pub sdot: Vec<Subspace>,
    /// Each link's `[ω̇; a_O]`.
    pub acc: Vec<Vec6>,
}

impl FrameKinematics {
    pub fn new(model: &Model) -> Self {
        let n = model.links.len();
        FrameKinematics {
            links: vec![LinkState::default(); n],
            sdot: vec![[Vec6::zeros(); 6]; n],
            acc: vec![Vec6::zeros(); n],
        }
    }

    /// Poses and joint columns at `q` (checked by the caller).
    pub fn positions(&mut self, model: &Model, q: &[f64]) {
        kinematics::positions(model, q, &mut self.links);
    }

    /// Twists and column rates at `(q, v)`; needs [`FrameKinematics::positions`] at `q`.
    pub fn velocities(&mut self, model: &Model, q: &[f64], v: &[f64]) {
        kinematics::velocities(model, q, v, &mut self.links);
        for (i, l) in model.links.iter().enumerate() {
            let w_parent = l
                .parent
                .map_or_else(Vec3::zeros, |p| angular(&self.links[p].twist));
            let s = &self.links[i];
            let nv = l.joint.nv();
            let qi = &q[l.q_index..l.q_index + l.joint.nq()];
            let vi = &v[l.v_index..l.v_index + nv];
            self.sdot[i] = l.joint.subspace_rate(
                qi,
                vi,
                &s.s,
                &s.joint_rotation,
                &w_parent,
                &angular(&s.twist),
            );
        }
    }

    /// Link accelerations from `a` (None: zero, the velocity product terms only); needs
    /// [`FrameKinematics::velocities`].
    pub fn accelerations(&mut self, model: &Model, a: Option<&[f64]>) {
        for (i, l) in model.links.iter().enumerate() {
            let s = &self.links[i];
            // The parent's acceleration carried to O_i (ω × (ω × r) is in ξ through Ȧ t).
            let mut acc = match l.parent {
                Some(p) => {
                    let ap = self.acc[p];
                    let r = s.origin - self.links[p].origin;
                    stack(&angular(&ap), &(linear(&ap) + angular(&ap).cross(&r)))
                }
                None => Vec6::zeros(),
            };
            acc += s.xi;
            if let Some(a) = a {
                for k in 0..l.joint.nv() {
                    acc += s.s[k] * a[l.v_index + k];
                }
            }
            self.acc[i] = acc;
        }
    }

    /// The world position of the frame origin and its rotation (frame axes to world).
    pub fn frame_pose(&self, f: &FrameRef) -> crate::support::spatial::Placement {
        pose_on(&self.links, f)
    }

    /// `[ω; velocity of the world point x fixed on `link`]` (world axes; zero for the world).
    pub fn point_velocity(&self, link: Option<usize>, x: &Vec3) -> Vec6 {
        match link {
            Some(l) => {
                let t = self.links[l].twist;
                let w = angular(&t);
                stack(&w, &(linear(&t) + w.cross(&(x - self.links[l].origin))))
            }
            None => Vec6::zeros(),
        }
    }

    /// `[ω̇; classical acceleration of the world point x fixed on `link`]`; needs
    /// [`FrameKinematics::accelerations`].
    pub fn point_acceleration(&self, link: Option<usize>, x: &Vec3) -> Vec6 {
        match link {
            Some(l) => {
                let (t, a) = (self.links[l].twist, self.acc[l]);
                let (w, wd) = (angular(&t), angular(&a));
                let r = x - self.links[l].origin;
                stack(&wd, &(linear(&a) + wd.cross(&r) + w.cross(&w.cross(&r))))
            }
            None => Vec6::zeros(),
        }
    }
}

/// The world placement of frame `f` from the links' poses.
pub fn pose_on(links: &[LinkState], f: &FrameRef) -> crate::support::spatial::Placement {
    match f.link {
        Some(l) => {
            let s = &links[l];
            crate::support::spatial::Placement::new(s.rotation, s.origin).compose(&f.placement)
        }
        None => f.placement,
    }
}
