//! The shaking force and moment from each link's motion and its summed point masses, for
//! the per-sample pass along a trajectory (`simulate::along`): the links' poses and twists
//! are taken as the loop solver (or the caller) already has them, and each link's seven
//! point masses enter through their sums `link.inertia` (mass, first moment and inertia about
//! the link origin, summed from the points when the model was built), so the per-sample cost
//! is one twist-rate recursion and one Newton–Euler resultant per link.
//!
//! `Σ_j m_j a_j = m a_O + ω̇ × c + ω × (ω × c)` and `Σ_j m_j d_j × a_j = c × a_O + J ω̇ +
//! ω × (J ω)` (`d_j` a point's offset from the link origin, `c = Σ m_j d_j`, `J` the inertia
//! about the origin, world axes): the same sums as [`super::reactions::shaking`] over the
//! points, grouped before rather than after the motion (equal to rounding).
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::spatial::{angular, linear, shift_twist, Vec3, Vec6};

/// Each link's twist rate `[ω̇; a_O]` (world axes, link origin, no gravity) into `accel`
/// at the accelerations `a`, from links whose poses and twists (`twist`, `xi`, the joint
/// columns `s`) are those of the state: the recursion of
/// [`super::reactions::link_accelerations`] without redoing the kinematics.
pub fn link_rates(model: &Model, links: &[LinkState], a: &[f64], accel: &mut [Vec6]) {
    for (i, l) in model.links.iter().enumerate() {
        let s = &links[i];
        let carried = match l.parent {
            Some(p) => shift_twist(&accel[p], &(s.origin - links[p].origin)),
            None => Vec6::zeros(),
        };
        let mut acc = carried + s.xi;
        for k in 0..l.joint.nv() {
            acc += s.s[k] * a[l.v_index + k];
        }
        accel[i] = acc;
    }
}

/// The shaking force and moment about `about` (world), `(−Σ m a, −Σ m (r − O) × a)` over
/// every point mass, from the links' poses and twists (`links`) and twist rates (`accel`,
/// [`link_rates`]).
pub fn shaking_of_links(
    model: &Model,
    links: &[LinkState],
    accel: &[Vec6],
    about: &Vec3,
) -> (Vec3, Vec3) {
    let mut force = Vec3::zeros();
    let mut moment = Vec3::zeros();
    for (i, l) in model.links.iter().enumerate() {
        let (s, inertia) = (&links[i], &l.inertia);
        let (w, wd) = (angular(&s.twist), angular(&accel[i]));
        let a_o = linear(&accel[i]);
        let c = s.rotation * inertia.first_moment;
        // The rotational inertia about the origin applied in the link's axes.
        let j = |x: &Vec3| s.rotation * (inertia.rotational * (s.rotation.transpose() * x));
        let f = a_o * inertia.mass + wd.cross(&c) + w.cross(&w.cross(&c));
        let m_o = c.cross(&a_o) + j(&wd) + w.cross(&j(&w));
        force -= f;
        moment -= (s.origin - about).cross(&f) + m_o;
    }
    (force, moment)
}
