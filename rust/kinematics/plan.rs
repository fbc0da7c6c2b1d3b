//! What [`super::frame_poses`] decides once per model rather than once per configuration
//! (kept in `Model::compiled`): per link, how its joint frame's orientation follows from its
//! parent's — unchanged, a signed permutation of the parent's columns (the exact quarter
//! turns `rpy = (±π/2, 0, 0)` of robot descriptions) or a general product — and whether its
//! joint turns about a coordinate axis of that frame (two columns turned by sin/cos), with
//! the turns' coordinates listed so their sines and cosines go four at a time.
use crate::joint::Joint;
use crate::model::Model;
use crate::support::spatial::{mat_mat, mat_vec, stack, Mat3, Vec3};

use super::LinkState;

/// The longest support [`frame_poses_along`] takes (deeper frames take the full pass).
pub const MAX_SUPPORT: usize = 64;

/// How a link's joint frame is oriented from its parent's: `R_joint = R_parent P`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Placing {
    /// `P = 1`.
    Identity,
    /// `P` a signed permutation: column `j` of `R_parent P` is `sign[j]` times column
    /// `from[j]` of `R_parent` (exact, as the product is).
    Permutation { from: [usize; 3], sign: [f64; 3] },
    /// Any other rotation: the 3 × 3 product.
    General,
}

impl Placing {
    fn of(p: &Mat3) -> Placing {
        if *p == Mat3::identity() {
            return Placing::Identity;
        }
        let mut from = [0; 3];
        let mut sign = [0.0; 3];
        for j in 0..3 {
            let nonzero: Vec<usize> = (0..3).filter(|&i| p[(i, j)] != 0.0).collect();
            match nonzero.as_slice() {
                [i] if p[(*i, j)].abs() == 1.0 => {
                    from[j] = *i;
                    sign[j] = p[(*i, j)];
                }
                _ => return Placing::General,
            }
        }
        Placing::Permutation { from, sign }
    }

    /// `R_parent P` (`p` the placement's rotation, read for `General` only).
    #[inline(always)]
    pub fn apply(&self, r_parent: &Mat3, p: &Mat3) -> Mat3 {
        match *self {
            Placing::Identity => *r_parent,
            Placing::Permutation { from, sign } => {
                // Entry by entry: nalgebra's column views go through generic iterators.
                let m = |i: usize, j: usize| r_parent[(i, from[j])] * sign[j];
                Mat3::new(
                    m(0, 0),
                    m(0, 1),
                    m(0, 2),
                    m(1, 0),
                    m(1, 1),
                    m(1, 2),
                    m(2, 0),
                    m(2, 1),
                    m(2, 2),
                )
            }
            Placing::General => mat_mat(r_parent, p),
        }
    }
}

/// A revolute joint about `sign · e_axis` of its joint frame; `slot` its index in
/// [`PosePlan::turns`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turn {
    pub axis: usize,
    pub sign: f64,
    pub slot: usize,
}

/// One link's decisions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    pub placing: Placing,
    pub turn: Option<Turn>,
}

/// Every link's [`Step`] and the turns' coordinates.
#[derive(Debug, Clone, Default)]
pub struct PosePlan {
    pub steps: Vec<Step>,
    /// Per turn (link order): its coordinate's index in `q` and its sign.
    pub turns: Vec<(usize, f64)>,
}

/// `(k, ±1)` when `axis` is `±e_k` exactly.
fn coordinate_axis(axis: &Vec3) -> Option<(usize, f64)> {
    let k = (0..3).find(|&k| axis[k].abs() == 1.0)?;
    let others_zero = (0..3).all(|j| j == k || axis[j] == 0.0);
    others_zero.then_some((k, axis[k]))
}

impl PosePlan {
    pub fn new(model: &Model) -> PosePlan {
        let mut turns = Vec::new();
        let steps = model
            .links
            .iter()
            .map(|l| {
                let placing = match l.placement_rotated {
                    true => Placing::of(&l.placement.rotation),
                    false => Placing::Identity,
                };
                let turn = match &l.joint {
                    Joint::Revolute { axis } => coordinate_axis(axis).map(|(axis, sign)| {
                        turns.push((l.q_index, sign));
                        Turn {
                            axis,
                            sign,
                            slot: turns.len() - 1,
                        }
                    }),
                    _ => None,
                };
                Step { placing, turn }
            })
            .collect();
        PosePlan { steps, turns }
    }

    /// Sines and cosines of the turns `slot..slot + 4` (zero angles past the last).
    #[inline(always)]
    pub fn sin_cos4(&self, q: &[f64], slot: usize) -> ([f64; 4], [f64; 4]) {
        let mut x = [0.0; 4];
        for (k, &(iq, sign)) in self.turns[slot..(slot + 4).min(self.turns.len())]
            .iter()
            .enumerate()
        {
            x[k] = sign * q[iq];
        }
        crate::support::trig::sin_cos4(x).unwrap_or_else(|| {
            // An angle beyond the branch-free reduction: one at a time.
            let (mut sn, mut cs) = ([0.0; 4], [0.0; 4]);
            for k in 0..4 {
                (sn[k], cs[k]) = crate::support::trig::sin_cos(x[k]);
            }
            (sn, cs)
        })
    }
}

/// The links from the root down to `link` (parents first) into `out`, their count; None
/// when there are more than [`MAX_SUPPORT`].
pub fn support_of(
    model: &Model,
    link: Option<usize>,
    out: &mut [usize; MAX_SUPPORT],
) -> Option<usize> {
    let mut n = 0;
    for l in model.support(link) {
        if n == MAX_SUPPORT {
            return None;
        }
        out[n] = l;
        n += 1;
    }
    out[..n].reverse();
    Some(n)
}

/// [`super::frame_poses`] of the links `along` only (parents first, each one's parent among
/// them; at most [`MAX_SUPPORT`]): the poses a frame's Jacobian reads, its support alone,
/// as Pinocchio walks it. The other links' states are left as they were.
pub fn frame_poses_along(model: &Model, q: &[f64], st: &mut [LinkState], along: &[usize]) {
    let plan = &model.compiled().poses;
    // The turns' sines and cosines four at a time (bit for bit `sin_cos`), taken from a
    // second walk over the turns that runs ahead of the first: no per-call buffers.
    let mut ahead = along.iter().filter_map(|&i| {
        let t = plan.steps[i].turn?;
        Some(t.sign * q[model.links[i].q_index])
    });
    let (mut sn, mut cs) = ([0.0; 4], [1.0; 4]);
    let mut at = 0;
    for &i in along {
        let l = &model.links[i];
        let (r_parent, o_parent) = match l.parent {
            Some(p) => (st[p].rotation, st[p].origin),
            None => (Mat3::identity(), Vec3::zeros()),
        };
        let step = &plan.steps[i];
        let r_joint = step.placing.apply(&r_parent, &l.placement.rotation);
        let t = mat_vec(&r_parent, &l.placement.translation);
        let origin = Vec3::new(o_parent.x + t.x, o_parent.y + t.y, o_parent.z + t.z);
        let s = &mut st[i];
        s.joint_rotation = r_joint;
        s.origin = origin;
        if let Some(t) = step.turn {
            if at % 4 == 0 {
                let mut four = [0.0; 4];
                for (x, angle) in four.iter_mut().zip(&mut ahead) {
                    *x = angle;
                }
                (sn, cs) = crate::support::trig::sin_cos4(four).unwrap_or_else(|| {
                    let (mut s4, mut c4) = ([0.0; 4], [0.0; 4]);
                    for k in 0..4 {
                        (s4[k], c4[k]) = crate::support::trig::sin_cos(four[k]);
                    }
                    (s4, c4)
                });
            }
            // R_joint R_k(±q): columns a, b of R_joint turn in their plane.
            let (sa, ca) = (sn[at % 4], cs[at % 4]);
            at += 1;
            let (a, b) = ((t.axis + 1) % 3, (t.axis + 2) % 3);
            let mut r = r_joint;
            for row in 0..3 {
                let (xa, xb) = (r_joint[(row, a)], r_joint[(row, b)]);
                r[(row, a)] = xa * ca + xb * sa;
                r[(row, b)] = xb * ca - xa * sa;
            }
            s.rotation = r;
            let k = t.axis;
            let axis = Vec3::new(r_joint[(0, k)], r_joint[(1, k)], r_joint[(2, k)]) * t.sign;
            s.s[0] = stack(&axis, &Vec3::zeros());
            continue;
        }
        let qi = &q[l.q_index..l.q_index + l.joint.nq()];
        let (r_q, t_q) = l.joint.transform(qi);
        s.rotation = mat_mat(&r_joint, &r_q);
        if l.joint.translates() {
            s.origin += mat_vec(&r_joint, &t_q);
        }
        // The columns past the joint's speeds are zero, as they started (as `frame_poses`).
        let columns = l.joint.subspace(qi, &r_joint, &s.rotation);
        let n = l.joint.nv();
        s.s[..n].copy_from_slice(&columns[..n]);
    }
}

/// The poses frame `link`'s Jacobian reads: its support's ([`frame_poses_along`]), or every
/// link's when the support is deeper than [`MAX_SUPPORT`].
pub fn frame_poses_for(model: &Model, q: &[f64], st: &mut [LinkState], link: Option<usize>) {
    let mut along = [0; MAX_SUPPORT];
    match support_of(model, link, &mut along) {
        Some(n) => frame_poses_along(model, q, st, &along[..n]),
        None => super::frame_poses(model, q, st),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A signed permutation's columns are picked, not multiplied: equal to the product.
    #[test]
    fn permutation_equals_product() {
        let p = Mat3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0);
        let placing = Placing::of(&p);
        assert!(matches!(placing, Placing::Permutation { .. }));
        let r = Mat3::new(0.1, 0.2, 0.3, -0.4, 0.5, 0.6, 0.7, -0.8, 0.9);
        assert_eq!(placing.apply(&r, &p), r * p);
        let g = Mat3::new(0.6, -0.8, 0.0, 0.8, 0.6, 0.0, 0.0, 0.0, 1.0);
        assert_eq!(Placing::of(&g), Placing::General);
        assert_eq!(Placing::of(&Mat3::identity()), Placing::Identity);
    }

    /// The support's poses are the full pass's, bit for bit, on a branched tree with
    /// placed joints (quarter turns and general ones).
    #[test]
    fn support_poses_equal_the_full_pass() {
        let model = crate::benchmark_models::tree(3, 4);
        let q: Vec<f64> = (0..model.nq).map(|k| 0.3 + 0.17 * k as f64).collect();
        let mut q = q;
        model.normalize(&mut q);
        let mut full = vec![LinkState::default(); model.links.len()];
        super::super::frame_poses(&model, &q, &mut full);
        for leaf in 0..model.links.len() {
            let mut part = vec![LinkState::default(); model.links.len()];
            frame_poses_for(&model, &q, &mut part, Some(leaf));
            for l in model.support(Some(leaf)) {
                assert_eq!(part[l].rotation, full[l].rotation, "{leaf} {l}");
                assert_eq!(part[l].origin, full[l].origin, "{leaf} {l}");
                assert_eq!(part[l].s, full[l].s, "{leaf} {l}");
            }
        }
    }
}
