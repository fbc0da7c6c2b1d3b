//! Centre of mass of the moving links (bodies welded to the world do not move and are left
//! out, as Pinocchio leaves out its universe body): position, velocity, acceleration and the
//! COM Jacobian `J_c = Σ_j (M_j l_j + a_j × (h_j − M_j O_j)) / M` over each joint column
//! `[a; l]` of link `j`, with `M_j`, `h_j` the mass and first moment (world) of the subtree
//! below it (inclusive).
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::spatial::{angular, linear, Mat3, Vec3};

use super::motion::FrameKinematics;

/// A link's subtree (itself and every link below): mass, first moment `Σ m c` and rotational
/// inertia about the world origin, world axes.
#[derive(Debug, Clone, Copy)]
pub struct Composite {
    pub mass: f64,
    pub moment: Vec3,
    pub inertia: Mat3,
}

impl Default for Composite {
    fn default() -> Self {
        Composite {
            mass: 0.0,
            moment: Vec3::zeros(),
            inertia: Mat3::zeros(),
        }
    }
}

/// Link `l`'s own centre of mass, world; needs positions.
pub fn link_com(model: &Model, kin: &FrameKinematics, l: usize) -> Vec3 {
    let s = &kin.links[l];
    s.origin + s.rotation * model.links[l].rigid.com
}

/// Every link's subtree composite into `out` (length nlinks), from the links' own rigid
/// bodies (the URDF inertials, not their point masses); needs positions.
pub fn composites(model: &Model, kin: &FrameKinematics, out: &mut [Composite]) {
    for (l, link) in model.links.iter().enumerate() {
        let b = &link.rigid;
        let c = link_com(model, kin, l);
        let r = kin.links[l].rotation;
        let about_c = r * b.inertia * r.transpose();
        out[l] = Composite {
            mass: b.mass,
            moment: c * b.mass,
            inertia: about_c + (Mat3::identity() * c.norm_squared() - c * c.transpose()) * b.mass,
        };
    }
    for l in (0..model.links.len()).rev() {
        if let Some(p) = model.links[l].parent {
            let c = out[l];
            out[p].mass += c.mass;
            out[p].moment += c.moment;
            out[p].inertia += c.inertia;
        }
    }
}

/// Total moving mass and the centre of mass (None without moving mass); needs positions.
pub fn com(model: &Model, kin: &FrameKinematics) -> Option<(f64, Vec3)> {
    let (mut m, mut h) = (0.0, Vec3::zeros());
    for (l, link) in model.links.iter().enumerate() {
        m += link.rigid.mass;
        h += link_com(model, kin, l) * link.rigid.mass;
    }
    (m > 0.0).then(|| (m, h / m))
}

/// COM velocity (needs velocities) and, with accelerations computed, its acceleration.
pub fn com_motion(model: &Model, kin: &FrameKinematics, with_acc: bool) -> (Vec3, Vec3) {
    let (mut m, mut v, mut a) = (0.0, Vec3::zeros(), Vec3::zeros());
    for (l, link) in model.links.iter().enumerate() {
        let c = link_com(model, kin, l);
        let mass = link.rigid.mass;
        m += mass;
        v += linear(&kin.point_velocity(Some(l), &c)) * mass;
        if with_acc {
            a += linear(&kin.point_acceleration(Some(l), &c)) * mass;
        }
    }
    if m > 0.0 {
        (v / m, a / m)
    } else {
        (v, a)
    }
}

/// Every link's subtree (itself and every link below) mass and first moment `Σ m c` (world)
/// into `out` (4 per link: the mass, then the moment), from the links' poses alone
/// (`crate::kinematics::frames`): what the centre of mass and its Jacobian need, without
/// the inertias [`composites`] rotates.
pub fn subtree_moments(model: &Model, links: &[LinkState], out: &mut [f64]) {
    for (l, link) in model.links.iter().enumerate() {
        let (b, s) = (&link.rigid, &links[l]);
        let h = (s.origin + s.rotation * b.com) * b.mass;
        out[4 * l..4 * l + 4].copy_from_slice(&[b.mass, h.x, h.y, h.z]);
    }
    for l in (0..model.links.len()).rev() {
        if let Some(p) = model.links[l].parent {
            for i in 0..4 {
                out[4 * p + i] += out[4 * l + i];
            }
        }
    }
}

/// Total moving mass and the centre of mass from [`subtree_moments`] (None without mass).
pub fn com_of_moments(model: &Model, moments: &[f64]) -> Option<(f64, Vec3)> {
    let (mut m, mut h) = (0.0, Vec3::zeros());
    for (l, link) in model.links.iter().enumerate() {
        if link.parent.is_none() {
            m += moments[4 * l];
            h += Vec3::new(moments[4 * l + 1], moments[4 * l + 2], moments[4 * l + 3]);
        }
    }
    (m > 0.0).then(|| (m, h / m))
}

/// The 3 × nv COM Jacobian (row-major) into `out`, from [`subtree_moments`]; `total` is
/// the total moving mass (> 0).
pub fn com_jacobian(
    model: &Model,
    links: &[LinkState],
    moments: &[f64],
    total: f64,
    out: &mut [f64],
) {
    let nv = model.nv;
    for (j, l) in model.links.iter().enumerate() {
        let st = &links[j];
        let mass = moments[4 * j];
        let h = Vec3::new(moments[4 * j + 1], moments[4 * j + 2], moments[4 * j + 3]);
        let arm = h - st.origin * mass;
        for k in 0..l.joint.nv() {
            let s = &st.s[k];
            let col = (linear(s) * mass + angular(s).cross(&arm)) / total;
            for i in 0..3 {
                out[i * nv + l.v_index + k] = col[i];
            }
        }
    }
}
