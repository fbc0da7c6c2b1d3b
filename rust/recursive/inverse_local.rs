//! Body-frame recursive inverse dynamics (Newton–Euler in link frames).
//!
//! The partner of `forward_local::forward_dynamics_local`: the same outward kinematic pass
//! (`forward_local::outward_pass`, hence bit-for-bit the same joint rotations, offsets, joint
//! columns, twists and `ξ`), then twist rates outward (`ṫ_i = E_iᵀ-carried ṫ_λ + ξ_i + S_i a_i`),
//! link wrenches `M_i ṫ_i + [ω × I ω; ω × (ω × h)] − f_ext`, and wrenches inward
//! (`τ_i = S_iᵀ w_i`, `w_λ += [E n + r × E f; E f]`). Because forward and inverse dynamics
//! round the geometry identically, `inverse_dynamics_local(forward_dynamics_local(τ))`
//! returns τ to the recursion's own rounding even on long chains.
use super::forward_local::{
    carry, cross, match_axis_kind, outward_pass, six, to_parent, v3, with_rot, with_rot_arm,
    General, Identity, Placed, Plane, ANYWHERE,
};
use super::{base_accel, Data};
use crate::model::Model;
use crate::spatial::{Vec3, Vec6};

crate::cpu::multiversion! {
    /// `τ = I a + C v − τ_g − Nᵀ f_ext`, in body frames. Same contract as
    /// `inverse::inverse_dynamics_world`: `external` holds one wrench per link, `[moment about the
    /// link origin; force]` in world axes, applied to the link; gravity enters as the base twist
    /// rate `[0; −g]`. Writes `tau` (length nv). No allocation: works in `data.local`. Compiled
    /// for AVX2 where the CPU has it, bit for bit the same results (see [`crate::cpu`]).
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
    let loc = &mut data.local[..n];
    // ZYZ singularities are not refused here (no articulated inertia to invert).
    let (body, angles) = (&data.local_body[..n], &data.axis_angles[..]);
    outward_pass::<false>(model, loc, body, angles, q, v, external);

    // Outward: twist rates and each link's own wrench (added into `bias`).
    let base = base_accel(g);
    for i in 0..n {
        let l = &model.links[i];
        let (head, tail) = loc.split_at_mut(i);
        let cur = &mut tail[0];
        let pacc = match l.parent {
            Some(p) => &head[p].accel,
            None => &base,
        };
        let (mut ya, mut yl) = with_rot!(cur, e => carry(e, cur, pacc));
        let ai = &a[l.v_index..l.v_index + l.joint.nv()];
        let y = if l.joint.moves_angular() {
            &mut ya
        } else {
            &mut yl
        };
        for (s, x) in cur.s.iter().zip(ai) {
            *y += s * *x;
        }
        cur.accel = six(&ya, &yl);
        // M ṫ with M = [[I, h̃], [−h̃, m]] about the origin (in the recursion's link frame).
        let own = &data.local_body[i];
        let h = &own.first_moment();
        let fa = own.p.mul(&ya) + cross(h, &yl);
        let fl = yl * own.r.0[0] + cross(&ya, h);
        cur.bias += six(&fa, &fl);
    }

    // Inward: joint forces, then the wrench handed to the parent.
    for i in (0..n).rev() {
        let l = &model.links[i];
        let (head, tail) = loc.split_at_mut(i);
        let cur = &tail[0];
        let (wa, wl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
        let nv = l.joint.nv();
        let w = if l.joint.moves_angular() { &wa } else { &wl };
        for k in 0..nv {
            tau[l.v_index + k] = cur.s[k].dot(w);
        }
        if let Some(p) = l.parent {
            let up = with_rot!(cur, e => to_parent(e, &cur.offset, ANYWHERE, &wa, &wl));
            head[p].bias += up;
        }
    }
}
