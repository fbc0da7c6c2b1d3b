//! Inverse dynamics by the recursive Newton–Euler algorithm in body frames (docs/method.md
//! §4): the outward pass of [`super::aba`] (hence bit-for-bit the same joint rotations,
//! offsets, columns, twists and `ξ`), then twist rates outward
//! (`ṫ_i = E_iᵀ-carried ṫ_λ + ξ_i + S_i a_i`), link wrenches
//! `M_i ṫ_i + [ω × I ω; ω × (ω × h)] − f_ext`, and wrenches inward (`τ_i = S_iᵀ w_i`,
//! `w_λ += [E n + r × E f; E f]`). Because forward and inverse dynamics round the geometry
//! identically, `inverse(forward(τ))` returns τ to the recursion's own rounding even on long
//! chains.
use super::algebra::{cross, six, v3, General};
use super::base_accel;
use super::compiled::{match_axis_kind, with_rot, with_rot_arm};
use super::outward::{carry, outward_pass};
use super::shift::{to_parent, OffsetForm};
use super::workspace::Data;
use crate::joint::MotionClass;
use crate::model::Model;
use crate::support::spatial::{Vec3, Vec6};

crate::support::cpu::multiversion! {
    /// `τ = I a + C v − τ_g − Nᵀ f_ext`, in body frames. Same contract as
    /// `reference::inverse_dynamics_world`: `external` holds one wrench per link, `[moment
    /// about the link origin; force]` in world axes, applied to the link; gravity enters as the
    /// base twist rate `[0; −g]`. Writes `tau` (length nv). No allocation: works in
    /// `data.local`. Compiled for AVX2 where the CPU has it, bit for bit the same results (see
    /// [`crate::support::cpu`]).
    pub fn inverse_dynamics_local / inverse_dynamics_avx2 / inverse_dynamics_baseline [] (
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        g: &Vec3,
        external: Option<&[Vec6]>,
        tau: &mut [f64],
    ) => inverse_dynamics_body
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn inverse_dynamics_body(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    tau: &mut [f64],
) {
    let n = model.links.len();
    let compiled = model.compiled();
    let consts = &compiled.links[..n];
    let work = &mut data.local[..n];
    // ZYZ singularities are not refused here (no articulated inertia to invert).
    outward_pass::<false>(model, consts, work, &compiled.axis_angles, q, v, external);

    // Outward: twist rates and each link's own wrench (added into `bias`).
    let base = base_accel(g);
    for i in 0..n {
        let c = &consts[i];
        let (head, tail) = work.split_at_mut(i);
        let w = &mut tail[0];
        let pacc = match c.parent {
            Some(p) => &head[p].accel,
            None => &base,
        };
        let ai = &a[c.v_index..c.v_index + c.nv];
        let (ya, yl) = if c.motion == MotionClass::Free {
            // S = 1₆: the joint's accelerations are (linear, angular) in body axes.
            let (ya, yl) = carry(General(w.rot), c.offset_form, &w.offset, w, pacc);
            let at = |k: usize| Vec3::new(ai[k], ai[k + 1], ai[k + 2]);
            (ya + at(3), yl + at(0))
        } else {
            with_rot!(c, w, e, r, s => {
            let (mut ya, mut yl) = carry(e, c.offset_form, r, w, pacc);
            let y = if c.angular { &mut ya } else { &mut yl };
            for (s, x) in s.iter().zip(ai) {
                *y += s * *x;
            }
            (ya, yl)
            })
        };
        w.accel = six(&ya, &yl);
        // M ṫ with M = [[I, h̃], [−h̃, m]] about the origin (in the recursion's link frame).
        let own = &c.inertia;
        let h = &own.first_moment();
        let fa = own.p.mul(&ya) + cross(h, &yl);
        let fl = yl * own.r.0[0] + cross(&ya, h);
        w.bias += six(&fa, &fl);
    }

    // Inward: joint forces, then the wrench handed to the parent.
    for i in (0..n).rev() {
        let c = &consts[i];
        let (head, tail) = work.split_at_mut(i);
        let w = &tail[0];
        let (wa, wl) = (v3(&w.bias, 0), v3(&w.bias, 3));
        let parent = c.parent.map(|p| &mut head[p]);
        if c.motion == MotionClass::Free {
            // τ = Sᵀ w = (force, moment) in body axes.
            tau[c.v_index..c.v_index + 3].copy_from_slice(wl.as_slice());
            tau[c.v_index + 3..c.v_index + 6].copy_from_slice(wa.as_slice());
            if let Some(p) = parent {
                p.bias += to_parent(General(w.rot), &w.offset, OffsetForm::Anywhere, &wa, &wl);
            }
            continue;
        }
        let wrench = if c.angular { &wa } else { &wl };
        with_rot!(c, w, e, r, s => {
            for k in 0..c.nv {
                tau[c.v_index + k] = s[k].dot(wrench);
            }
            if let Some(p) = parent {
                // One wrench per step: the general cross product counts fewer instructions
                // than the offset-form branch here.
                p.bias += to_parent(e, r, OffsetForm::Anywhere, &wa, &wl);
            }
        });
    }
    if !model.armature.is_empty() {
        super::armature::add_to_forces(model, a, tau);
    }
}
