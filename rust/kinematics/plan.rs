//! What [`super::frame_poses`] decides once per model rather than once per configuration
//! (kept in `Model::compiled`): per link, how its joint frame's orientation follows from its
//! parent's — unchanged, a signed permutation of the parent's columns (the exact quarter
//! turns `rpy = (±π/2, 0, 0)` of robot descriptions) or a general product — and whether its
//! joint turns about a coordinate axis of that frame (two columns turned by sin/cos), with
//! the turns' coordinates listed so their sines and cosines go four at a time.
use crate::joint::Joint;
use crate::model::Model;
use crate::support::spatial::{mat_mat, Mat3, Vec3};

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
            Placing::Permutation { from, sign } => Mat3::from_columns(&[
                r_parent.column(from[0]) * sign[0],
                r_parent.column(from[1]) * sign[1],
                r_parent.column(from[2]) * sign[2],
            ]),
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
}
