//! Forward kinematics over links: orientations, origins, joint-motion columns `P_i`, twists
//! `t_i = [ω_i; v_i]` (velocity of the origin `O_i`) and the velocity-dependent part of the
//! twist rate, `ξ_i = Ȧ_{i,λ} t_λ + Ṗ_i q̇_i` — all in world coordinates as in the paper (docs/method.md §2).
pub mod plan;
pub mod poses;

use crate::joint::Subspace;
use crate::model::Model;
use crate::support::spatial::{
    angular, linear, mat_mat, mat_vec, stack, BodyInertia, Mat3, Placement, Vec3, Vec6,
};

#[derive(Debug, Clone)]
pub struct LinkState {
    pub rotation: Mat3,
    pub origin: Vec3,
    /// Orientation of the joint frame (parent orientation × fixed placement).
    pub joint_rotation: Mat3,
    pub s: Subspace,
    pub twist: Vec6,
    pub xi: Vec6,
    /// Link inertia about its origin, world axes.
    pub inertia: BodyInertia,
}

impl Default for LinkState {
    fn default() -> Self {
        LinkState {
            rotation: Mat3::identity(),
            origin: Vec3::zeros(),
            joint_rotation: Mat3::identity(),
            s: [Vec6::zeros(); 6],
            twist: Vec6::zeros(),
            xi: Vec6::zeros(),
            inertia: BodyInertia::zero(),
        }
    }
}

/// Positions: orientation, origin, joint columns and world-axes inertia of every link.
pub fn positions(model: &Model, q: &[f64], st: &mut [LinkState]) {
    poses::<true, false>(model, q, st);
}

/// [`positions`] without the world-axes inertias (`inertia` is left as it was): what the
/// loops' constraints read (orientations, origins, joint columns). Only each joint's own
/// columns `s[..nv]` are written: `st` must have the others zero (as
/// `LinkState::default()` has, and every earlier `frames` of the same model leaves them).
pub fn frames(model: &Model, q: &[f64], st: &mut [LinkState]) {
    poses::<false, false>(model, q, st);
}

/// [`frames`] with a revolute joint about a coordinate axis turning two columns of its joint
/// frame's orientation (12 products instead of Rodrigues' matrix and a 3 × 3 product): the
/// frame Jacobians', centre of mass's and inverse kinematics' poses (equal to [`frames`]'
/// to rounding, not bit for bit). The same precondition on `st` as [`frames`].
pub fn frame_poses(model: &Model, q: &[f64], st: &mut [LinkState]) {
    poses::<false, true>(model, q, st);
}

#[inline(always)]
fn poses<const INERTIA: bool, const TURN: bool>(model: &Model, q: &[f64], st: &mut [LinkState]) {
    // `frame_poses` reads the model's decisions (`plan::PosePlan`, built once per model);
    // the turns' sines and cosines four at a time, so that the polynomial chains of four
    // angles overlap instead of each waiting for the last (bit for bit `sin_cos`).
    let plan = TURN.then(|| &model.compiled().poses);
    let mut sc = ([0.0; 4], [1.0; 4]);
    for (i, l) in model.links.iter().enumerate() {
        let (r_parent, o_parent) = match l.parent {
            Some(p) => (st[p].rotation, st[p].origin),
            None => (Mat3::identity(), Vec3::zeros()),
        };
        let qi = &q[l.q_index..l.q_index + l.joint.nq()];
        let r_joint = match plan {
            Some(plan) => plan.steps[i]
                .placing
                .apply(&r_parent, &l.placement.rotation),
            // Most joints sit at an unrotated placement: skip that product.
            None if l.placement_rotated => r_parent * l.placement.rotation,
            None => r_parent,
        };
        if let Some(t) = plan.and_then(|p| p.steps[i].turn) {
            if t.slot % 4 == 0 {
                sc = plan.map_or(sc, |p| p.sin_cos4(q, t.slot));
            }
            // R_joint R_k(±q): columns a, b of R_joint turn in their plane.
            let (sn, cs) = (sc.0[t.slot % 4], sc.1[t.slot % 4]);
            let (a, b) = ((t.axis + 1) % 3, (t.axis + 2) % 3);
            let (ca, cb) = (r_joint.column(a), r_joint.column(b));
            let s = &mut st[i];
            s.joint_rotation = r_joint;
            s.rotation = r_joint;
            s.rotation.set_column(a, &(ca * cs + cb * sn));
            s.rotation.set_column(b, &(cb * cs - ca * sn));
            s.origin = o_parent + mat_vec(&r_parent, &l.placement.translation);
            s.s[0] = stack(&(r_joint.column(t.axis) * t.sign), &Vec3::zeros());
            continue;
        }
        let (r_q, t_q) = l.joint.transform(qi);
        let s = &mut st[i];
        s.joint_rotation = r_joint;
        if INERTIA {
            s.rotation = r_joint * r_q;
            s.origin = o_parent + r_parent * l.placement.translation;
        } else {
            // The same products, inlined without LTO too.
            s.rotation = mat_mat(&r_joint, &r_q);
            s.origin = o_parent + mat_vec(&r_parent, &l.placement.translation);
        }
        if l.joint.translates() {
            s.origin += r_joint * t_q;
        }
        let columns = l.joint.subspace(qi, &r_joint, &s.rotation);
        if INERTIA {
            s.s = columns;
        } else {
            // The columns past the joint's speeds are zero, as they started.
            let n = l.joint.nv();
            s.s[..n].copy_from_slice(&columns[..n]);
        }
        if INERTIA {
            s.inertia = l.inertia.rotated(&s.rotation);
        }
    }
}

/// Twists and `ξ` from the speeds `v`; needs `positions` first.
pub fn velocities(model: &Model, q: &[f64], v: &[f64], st: &mut [LinkState]) {
    for (i, l) in model.links.iter().enumerate() {
        let (t_parent, o_parent) = match l.parent {
            Some(p) => (st[p].twist, st[p].origin),
            None => (Vec6::zeros(), Vec3::zeros()),
        };
        let nv = l.joint.nv();
        let vi = &v[l.v_index..l.v_index + nv];
        let s = &mut st[i];
        let w_parent = angular(&t_parent);
        // Parent twist carried to O_i, plus the joint's own motion.
        let mut t = stack(
            &w_parent,
            &(linear(&t_parent) + w_parent.cross(&(s.origin - o_parent))),
        );
        for k in 0..nv {
            t += s.s[k] * vi[k];
        }
        let w_body = angular(&t);
        let qi = &q[l.q_index..l.q_index + l.joint.nq()];
        let sdot = l
            .joint
            .subspace_rate(qi, vi, &s.s, &s.joint_rotation, &w_parent, &w_body);
        // Ȧ t_λ = [0; ω_λ × (v_i − v_λ)]
        let mut xi = stack(
            &Vec3::zeros(),
            &w_parent.cross(&(linear(&t) - linear(&t_parent))),
        );
        for k in 0..nv {
            xi += sdot[k] * vi[k];
        }
        s.twist = t;
        s.xi = xi;
    }
}

/// World placement of a user body's frame.
pub fn body_placement(model: &Model, st: &[LinkState], body: usize) -> Placement {
    let b = &model.bodies[body];
    match b.link {
        Some(l) => Placement::new(st[l].rotation, st[l].origin).compose(&b.in_link),
        None => {
            // Welded to the world: compose the chain of fixed placements.
            let mut p = b.placement;
            let mut parent = b.parent;
            while let Some(k) = parent {
                p = model.bodies[k].placement.compose(&p);
                parent = model.bodies[k].parent;
            }
            p
        }
    }
}

/// World placements of every body at `q` (positions into `links`): rotations row-major
/// (nbodies × 3 × 3) and origins (nbodies × 3), checked finite.
pub fn body_placements(
    model: &Model,
    q: &[f64],
    links: &mut [LinkState],
) -> crate::support::error::Result<(Vec<f64>, Vec<f64>)> {
    positions(model, q, links);
    let nb = model.nbodies();
    let mut rots = Vec::with_capacity(9 * nb);
    let mut origins = Vec::with_capacity(3 * nb);
    for b in 0..nb {
        let p = body_placement(model, links, b);
        rots.extend_from_slice(p.rotation.transpose().as_slice());
        origins.extend_from_slice(p.translation.as_slice());
    }
    crate::support::error::check_result("placements", &origins)?;
    Ok((rots, origins))
}
