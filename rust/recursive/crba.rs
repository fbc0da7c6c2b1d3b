//! The generalized inertia matrix by composite bodies in link frames (Pinocchio's CRBA;
//! docs/method.md §4). The same link frames, joint rotations and offsets as [`super::aba`]
//! (only the position-level part of its outward pass), the same rotate-and-shift of 3×3
//! blocks that carries an articulated inertia to the parent, here carrying each link's
//! composite inertia (its subtree welded, about its origin). Column `j` of the GIM is then
//! `F = I^c_j S_j` carried up the chain as a wrench, `I_ij = S_iᵀ F` at each ancestor `i`.
//! O(n·depth); nothing allocated.
use nalgebra::DMatrix;

use super::algebra::{mul, tr_mul, v3, LocalInertia, Rot};
use super::compiled::{match_axis_kind, with_rot, with_rot_arm, LinkConsts, LinkKind};
use super::outward::{outward_other, plane_turns};
use super::shift::{shift_add, to_parent, OffsetForm};
use super::workspace::{Data, LinkWork};
use crate::joint::MotionClass;
use crate::model::Model;
use crate::support::spatial::Vec3;

crate::support::cpu::multiversion! {
    /// Fills `gim` (nv × nv, symmetric) at `q`. Runs its AVX2 copy where the CPU has it
    /// ([`crate::support::cpu`]; the same rounding).
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
    let compiled = model.compiled();
    let consts = &compiled.links[..n];
    let work = &mut data.local[..n];
    positions(model, consts, work, &compiled.axis_angles, q, &data.zero_v);
    composites(consts, work);
    // Models without a free flyer get a column walk with no free-flyer test in it.
    if compiled.has_free_flyer {
        columns::<true>(consts, work, gim);
    } else {
        columns::<false>(consts, work, gim);
    }
    if !model.armature.is_empty() {
        super::armature::add_to_mass_matrix(model, gim);
    }
}

/// Joint rotations and offsets: the plane turns' (cos, sin), the other joints' matrices
/// (their twists come out zero, as `still` is); leaves start from their own inertia.
#[inline(always)]
fn positions(
    model: &Model,
    consts: &[LinkConsts],
    work: &mut [LinkWork],
    angles: &[(usize, usize)],
    q: &[f64],
    still: &[f64],
) {
    let n = consts.len();
    plane_turns(consts, work, angles, q);
    for i in 0..n {
        let c = &consts[i];
        let (head, tail) = work.split_at_mut(i);
        let w = &mut tail[0];
        if c.kind == LinkKind::Other {
            let parent = c.parent.map(|p| &head[p]);
            outward_other(
                &model.links[i].joint,
                c,
                w,
                parent,
                &q[c.q_index..],
                &still[c.v_index..],
                None,
            );
        } else {
            // The column walk below reads every link's columns from the workspace.
            w.s[0] = c.columns[0];
        }
        if c.leaf {
            w.inertia = c.inertia;
        }
    }
}

/// Composite inertias, children into parents (the first child writes, see `first_child`).
#[inline(always)]
fn composites(consts: &[LinkConsts], work: &mut [LinkWork]) {
    let n = consts.len();
    for i in (1..n).rev() {
        let Some(p) = consts[i].parent else {
            continue;
        };
        let c = &consts[i];
        let (head, tail) = work.split_at_mut(i);
        let w = &tail[0];
        let start = Some(&consts[p].inertia).filter(|_| c.first_child);
        let m = &w.inertia;
        with_rot!(c, w, e, r, _s => shift_add::<3, false>(
            &e.conj_sym(&m.p),
            &e.conj::<false>(&m.q),
            &e.conj_sym(&m.r),
            r,
            c.offset_form,
            start,
            &mut head[p].inertia,
        ));
    }
}

/// Columns: F = I^c S, then up the chain as a wrench. `FREE`: the model may have free
/// flyers.
#[inline(always)]
fn columns<const FREE: bool>(consts: &[LinkConsts], work: &[LinkWork], gim: &mut DMatrix<f64>) {
    let n = consts.len();
    let dim = gim.nrows();
    let g = gim.as_mut_slice();
    g.fill(0.0);
    for i in 0..n {
        let (c, w) = (&consts[i], &work[i]);
        let (nv, angular) = (c.nv, c.angular);
        let free = FREE && c.motion == MotionClass::Free;
        let s_i = &w.s;
        let m = &w.inertia;
        for k in 0..nv {
            let col = c.v_index + k;
            let (mut fa, mut fl) = if free {
                free_column(m, k)
            } else {
                let s = &s_i[k];
                if angular {
                    (m.p.mul(s), tr_mul(&m.q, s))
                } else {
                    (mul(&m.q, s), m.r.mul(s))
                }
            };
            if free {
                for r in 0..6 {
                    g[c.v_index + r + col * dim] = free_row(r, &fa, &fl);
                }
            } else {
                let f = if angular { &fa } else { &fl };
                for r in 0..nv {
                    g[c.v_index + r + col * dim] = s_i[r].dot(f);
                }
            }
            let mut j = i;
            while let Some(p) = consts[j].parent {
                let (cj, wj) = (&consts[j], &work[j]);
                // One wrench per step: the general cross product, without the form branch.
                let up =
                    with_rot!(cj, wj, e, r, _s => to_parent(e, r, OffsetForm::Anywhere, &fa, &fl));
                (fa, fl) = (v3(&up, 0), v3(&up, 3));
                let (cp, wp) = (&consts[p], &work[p]);
                let (nvp, angular_p) = (cp.nv, cp.angular);
                let vp = cp.v_index;
                if FREE && cp.motion == MotionClass::Free {
                    for r in 0..6 {
                        let x = free_row(r, &fa, &fl);
                        g[vp + r + col * dim] = x;
                        g[col + (vp + r) * dim] = x;
                    }
                } else {
                    let f = if angular_p { &fa } else { &fl };
                    for r in 0..nvp {
                        let x = wp.s[r].dot(f);
                        g[vp + r + col * dim] = x;
                        g[col + (vp + r) * dim] = x;
                    }
                }
                j = p;
            }
        }
    }
}

/// `I^c S_k` for a free flyer's speed `k` (`S = 1₆`, linear speeds first): a column of the
/// composite inertia, as `(moment, force)`.
#[inline(never)]
fn free_column(m: &LocalInertia, k: usize) -> (Vec3, Vec3) {
    let e = |j: usize| Vec3::ith(j, 1.0);
    if k < 3 {
        (mul(&m.q, &e(k)), m.r.mul(&e(k)))
    } else {
        (m.p.mul(&e(k - 3)), tr_mul(&m.q, &e(k - 3)))
    }
}

/// `S_rᵀ [n; f]` for a free flyer's speed `r`: the force components, then the moment's.
#[inline(always)]
fn free_row(r: usize, n: &Vec3, f: &Vec3) -> f64 {
    if r < 3 {
        f[r]
    } else {
        n[r - 3]
    }
}
