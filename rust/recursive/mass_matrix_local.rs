//! Generalized inertia matrix by composite bodies in link frames (Pinocchio's CRBA).
//!
//! The partner of `forward_local`: the same link frames, joint rotations and offsets (only
//! the position-level part of its outward pass), the same rotate-and-shift of 3×3 blocks that
//! carries an articulated inertia to the parent, here carrying each link's composite
//! inertia (its subtree welded, about its origin). Column `j` of the GIM is then
//! `F = I^c_j S_j` carried up the chain as a wrench, `I_ij = S_iᵀ F` at each ancestor `i`.
//! O(n·depth); nothing allocated.
use nalgebra::DMatrix;

use super::forward_local::{
    match_axis_kind, mul, outward_other, plane_turns, shift_add, to_parent, tr_mul, v3, with_rot,
    with_rot_arm, General, Identity, Placed, Plane, Rot, ANYWHERE,
};
use super::Data;
use crate::model::Model;

crate::cpu::multiversion! {
    /// Fills `gim` (nv × nv, symmetric) at `q`. Runs its AVX2 copy where the CPU has it
    /// ([`crate::cpu`]; the same rounding).
    pub fn mass_matrix_local / mass_matrix_avx2 / mass_matrix_baseline [] (
        model: &Model,
        data: &mut Data,
        q: &[f64],
        gim: &mut DMatrix<f64>,
    ) => mass_matrix_body
}

#[inline(always)]
fn mass_matrix_body(model: &Model, data: &mut Data, q: &[f64], gim: &mut DMatrix<f64>) {
    let n = model.links.len();
    let loc = &mut data.local[..n];
    let body = &data.local_body[..n];
    // Joint rotations and offsets: the plane turns' (cos, sin), the other joints' matrices
    // (their twists come out zero, as `still` is); leaves start from their own inertia.
    plane_turns(loc, &data.axis_angles, q);
    let still = &data.zero_v[..];
    for i in 0..n {
        let l = &model.links[i];
        let (head, tail) = loc.split_at_mut(i);
        let cur = &mut tail[0];
        if cur.kind == super::forward_local::OTHER_KIND {
            let parent = l.parent.map(|p| &head[p]);
            outward_other(l, cur, parent, &q[l.q_index..], &still[l.v_index..], None);
        }
        if cur.leaf {
            cur.inertia = body[i];
        }
    }

    // Composite inertias, children into parents (the first child writes, see `first_child`).
    for i in (1..n).rev() {
        let Some(p) = model.links[i].parent else {
            continue;
        };
        let (head, tail) = loc.split_at_mut(i);
        let cur = &tail[0];
        let start = Some(&body[p]).filter(|_| cur.first_child);
        let m = &cur.inertia;
        with_rot!(cur, e => shift_add::<3>(
            &e.conj_sym(&m.p),
            &e.conj::<false>(&m.q),
            &e.conj_sym(&m.r),
            &cur.offset,
            cur.offset_axis,
            start,
            &mut head[p].inertia,
        ));
    }

    // Columns: F = I^c S, then up the chain.
    let dim = gim.nrows();
    let g = gim.as_mut_slice();
    g.fill(0.0);
    // (nv, whether the joint moves along angular axes): a revolute joint on an axis is (1, yes).
    let dofs = |i: usize, c: &super::LocalLink| match c.kind {
        super::forward_local::OTHER_KIND => {
            let j = &model.links[i].joint;
            (j.nv(), j.moves_angular())
        }
        _ => (1, true),
    };
    for i in 0..n {
        let l = &model.links[i];
        let cur = &loc[i];
        let (nv, angular) = dofs(i, cur);
        let m = &cur.inertia;
        for k in 0..nv {
            let col = l.v_index + k;
            let s = &cur.s[k];
            let (mut fa, mut fl) = if angular {
                (m.p.mul(s), tr_mul(&m.q, s))
            } else {
                (mul(&m.q, s), m.r.mul(s))
            };
            let w = if angular { &fa } else { &fl };
            for r in 0..nv {
                g[l.v_index + r + col * dim] = cur.s[r].dot(w);
            }
            let mut j = i;
            while let Some(p) = model.links[j].parent {
                let cj = &loc[j];
                let f = with_rot!(cj, e => to_parent(e, &cj.offset, ANYWHERE, &fa, &fl));
                (fa, fl) = (v3(&f, 0), v3(&f, 3));
                let cp = &loc[p];
                let (nvp, angular_p) = dofs(p, cp);
                let vp = model.links[p].v_index;
                let w = if angular_p { &fa } else { &fl };
                for r in 0..nvp {
                    let x = cp.s[r].dot(w);
                    g[vp + r + col * dim] = x;
                    g[col + (vp + r) * dim] = x;
                }
                j = p;
            }
        }
    }
}
