//! Forward dynamics by the articulated-body recursion in body frames (Featherstone's ABA as
//! Pinocchio writes it; equivalent to Saha's UDUᵀ of the GIM, never forming it;
//! docs/method.md §4). Three passes:
//!
//! 1. outward ([`outward_pass`]): joint transforms, twists, `ξ`, velocity-product wrenches;
//! 2. inward: `U = M̂ S`, `D = Sᵀ U`, `u = τ − Sᵀ b̂`, then the articulated inertia
//!    `M^a = M̂ − U D⁻¹ Uᵀ` and bias `b^a = b̂ + M^a ξ + U D⁻¹ u` carried into the parent;
//! 3. outward: `q̈ = D⁻¹ (u − Uᵀ ṫ_carried)`, `ṫ = ṫ_carried + S q̈`.
//!
//! Every per-link quantity is in the link's own frame, so the link inertia is the constant
//! one built from the seven point masses and the joint columns are constant for all joints
//! but ZYZ. Going to the parent takes the joint's rotation `E` and offset `r`: twists go down
//! as `[Eᵀ ω; Eᵀ (v + ω × r)]`, wrenches up as `[E n + r × E f; E f]`, inertias up as
//! `E M Eᵀ` by 3×3 blocks and then the shift to the parent origin ([`super::shift`]).
//! Revolute joints about a coordinate axis (the common case) rotate blocks with a plane
//! rotation instead of a full 3×3 product ([`super::compiled::LinkKind`]).
use super::algebra::{
    is_identity, mul, sidx, six, tr_mul, v3, General, LocalInertia, Placed, Plane, Rot, Sym3,
};
use super::compiled::{match_axis_kind, LinkConsts};
use super::outward::{carry, outward_pass};
use super::shift::{shift_add, to_parent, with_form, OffsetForm};
use super::singular_message;
use super::workspace::{Data, LinkWork};
use crate::joint::MotionClass;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Mat3, Vec3, Vec6};

crate::support::cpu::multiversion! {
    /// Accelerations `a` from `I a + C v − τ_g − Nᵀ f_ext = τ`, by the articulated-body
    /// recursion in body frames. Same contract as `reference::forward_dynamics_world`:
    /// `external` holds one wrench per link, `[moment about the link origin; force]` in world
    /// axes; errors at a ZYZ Euler singularity or a non-positive joint block.
    ///
    /// On a CPU with AVX2 the same code runs compiled for it (see [`crate::support::cpu`]); the
    /// results are bit for bit those of the baseline build.
    pub fn forward_dynamics_local / forward_dynamics_avx2 / forward_dynamics_baseline [] (
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        g: &Vec3,
        external: Option<&[Vec6]>,
        a: &mut [f64],
    ) -> Result<()> => forward_dynamics_body
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn forward_dynamics_body(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    a: &mut [f64],
) -> Result<()> {
    let n = model.links.len();
    let compiled = model.compiled();
    let consts = &compiled.links[..n];
    let work = &mut data.local[..n];

    // 1. Outward: kinematics; it also finds the first joint at a coordinate singularity.
    if let Some(i) =
        outward_pass::<true>(model, consts, work, &compiled.axis_angles, q, v, external)
    {
        return Err(Error::Singular(singular_message(model, i, q)));
    }

    // 2. Inward: articulated inertias and biases.
    for i in (0..n).rev() {
        let c = &consts[i];
        let (head, tail) = work.split_at_mut(i);
        let w = &mut tail[0];
        // The parent's own inertia when this child writes its articulated inertia first.
        let (parent, start) = match c.parent {
            Some(p) => (
                Some(&mut head[p]),
                Some(&consts[p].inertia).filter(|_| c.first_child),
            ),
            None => (None, None),
        };
        let ti = &tau[c.v_index..];
        macro_rules! axis {
            ($pl:expr, $k:tt, $i:tt, $j:tt) => {
                backward_axis::<_, $k, $i, $j>(
                    $pl,
                    c.offset_form,
                    &c.offset,
                    w,
                    parent,
                    start,
                    ti[0] * c.sign,
                )
            };
        }
        let ok = match_axis_kind!(c, axis, backward_other(c, w, parent, start, ti));
        if !ok {
            return Err(Error::Singular(singular_message(model, i, q)));
        }
    }

    // 3. Outward: accelerations.
    let base = super::base_accel(g);
    for i in 0..n {
        let c = &consts[i];
        let (head, tail) = work.split_at_mut(i);
        let w = &mut tail[0];
        let pacc = match c.parent {
            Some(p) => &head[p].accel,
            None => &base,
        };
        let out = &mut a[c.v_index..];
        macro_rules! axis {
            ($pl:expr, $k:tt, $i:tt, $j:tt) => {{
                let e = Placed($pl, Plane::<$i, $j>::new(w.cs));
                out[0] = with_form!(is_identity(&$pl), c.offset_form, |form| {
                    forward_1::<_, $k, true>(e, form, &c.offset, w, pacc)
                }) * c.sign;
            }};
        }
        match_axis_kind!(c, axis, forward_other(c, w, pacc, out));
    }
    Ok(())
}

/// The inward step of every joint but a revolute one about a coordinate axis, by its motion
/// class; false at a non-positive joint block.
#[inline(never)]
fn backward_other(
    c: &LinkConsts,
    w: &mut LinkWork,
    parent: Option<&mut LinkWork>,
    start: Option<&LocalInertia>,
    tau: &[f64],
) -> bool {
    let (e, form) = (General(w.rot), c.offset_form);
    let arm = &c.armature;
    match c.motion {
        MotionClass::Angular1 => {
            backward_1::<_, 3, true>(e, form, w, parent, start, tau[0], arm[0])
        }
        MotionClass::Linear1 => {
            backward_1::<_, 3, false>(e, form, w, parent, start, tau[0], arm[0])
        }
        MotionClass::Angular3 => backward_3(form, w, parent, start, tau, arm),
        MotionClass::Free => backward_free(form, w, parent, start, tau),
        MotionClass::Rigid => {
            if let Some(p) = parent {
                let m = w.inertia;
                let (ba, bl) = (v3(&w.bias, 0), v3(&w.bias, 3));
                let z = Vec3::zeros();
                let r = w.offset;
                finish(e, form, &r, &m, &ba, &bl, &z, &z, w, p, start);
            }
            true
        }
    }
}

/// The acceleration step of every joint but a revolute one about a coordinate axis.
#[inline(never)]
fn forward_other(c: &LinkConsts, w: &mut LinkWork, pacc: &Vec6, out: &mut [f64]) {
    let (e, form, r) = (General(w.rot), c.offset_form, w.offset);
    match c.motion {
        MotionClass::Angular1 => out[0] = forward_1::<_, 3, true>(e, form, &r, w, pacc),
        MotionClass::Linear1 => out[0] = forward_1::<_, 3, false>(e, form, &r, w, pacc),
        MotionClass::Angular3 => forward_3(form, w, pacc, out),
        MotionClass::Free => forward_free(form, w, pacc, out),
        MotionClass::Rigid => {
            let (ya, yl) = carry(e, form, &r, w, pacc);
            w.accel = six(&ya, &yl);
        }
    }
}

/// One 1-dof joint inward: `U = M̂ S`, `D = Sᵀ U + armature`, `u`, then `M^a`, `b^a` into
/// the parent. `AX < 3`: a revolute joint about coordinate axis `AX` (S = e_AX, no
/// products); `ANG`: the joint moves along an angular (else linear) axis.
#[inline(always)]
fn backward_1<R: Rot, const AX: usize, const ANG: bool>(
    e: R,
    form: OffsetForm,
    cur: &mut LinkWork,
    parent: Option<&mut LinkWork>,
    start: Option<&LocalInertia>,
    tau: f64,
    armature: f64,
) -> bool {
    let m = &cur.inertia;
    let (ba, bl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
    let s0 = cur.s[0];
    let (ua, ul) = if AX < 3 {
        (
            Vec3::new(m.p.at(0, AX), m.p.at(1, AX), m.p.at(2, AX)),
            Vec3::new(m.q[(AX, 0)], m.q[(AX, 1)], m.q[(AX, 2)]),
        )
    } else if ANG {
        (m.p.mul(&s0), tr_mul(&m.q, &s0))
    } else {
        (mul(&m.q, &s0), m.r.mul(&s0))
    };
    let (d, sb) = if AX < 3 {
        (ua[AX], ba[AX])
    } else if ANG {
        (s0.dot(&ua), s0.dot(&ba))
    } else {
        (s0.dot(&ul), s0.dot(&bl))
    };
    let d = d + armature;
    if d.is_nan() || d <= 0.0 {
        return false;
    }
    let dinv = 1.0 / d;
    let ut = tau - sb;
    cur.u[0] = six(&ua, &ul);
    cur.d_inv[(0, 0)] = dinv;
    cur.u_tau[0] = ut;
    if let Some(parent) = parent {
        // M^a = M̂ − U Uᵀ / d; b^a = b̂ + M^a ξ + U ut / d.
        let da = ua * dinv;
        let mut ma = *m;
        ma.p.sub_outer(&ua, dinv);
        ma.r.sub_outer(&ul, dinv);
        for c in 0..3 {
            for r in 0..3 {
                ma.q[(r, c)] -= da[r] * ul[c];
            }
        }
        let k = ut * dinv;
        let r = cur.offset;
        finish(
            e,
            form,
            &r,
            &ma,
            &ba,
            &bl,
            &(ua * k),
            &(ul * k),
            cur,
            parent,
            start,
        );
    }
    true
}

/// A revolute joint about coordinate axis `K` (plane rotation `Plane<I, J>`, S = e_K) inward.
/// After the rank-1 update `M^a = M̂ − U Uᵀ / d` with `U = M̂ e_K`, row and column `K` of
/// `P^a` and row `K` of `Q^a` vanish, and stay so under the rotation about `e_K`: they are
/// neither formed nor rotated, and `(M^a ξ)_K = 0` leaves `f_K = b_K + u`. Without a
/// placement rotation (`Pl = Identity`) they are not shifted either; otherwise the blocks
/// are turned by the placement `pl` before the shift.
#[inline(always)]
fn backward_axis<Pl: Rot, const K: usize, const I: usize, const J: usize>(
    pl: Pl,
    form: OffsetForm,
    offset: &Vec3,
    cur: &mut LinkWork,
    parent: Option<&mut LinkWork>,
    start: Option<&LocalInertia>,
    tau: f64,
) -> bool {
    // Unplaced joints (the common case): one copy per offset form (`with_form`).
    with_form!(Pl::IDENTITY, form, |form| backward_axis_in::<Pl, K, I, J>(
        pl, form, offset, cur, parent, start, tau
    ))
}

#[inline(always)]
fn backward_axis_in<Pl: Rot, const K: usize, const I: usize, const J: usize>(
    pl: Pl,
    form: OffsetForm,
    offset: &Vec3,
    cur: &mut LinkWork,
    parent: Option<&mut LinkWork>,
    start: Option<&LocalInertia>,
    tau: f64,
) -> bool {
    let m = &cur.inertia;
    let (ba, bl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
    let ua = Vec3::new(m.p.at(0, K), m.p.at(1, K), m.p.at(2, K));
    let ul = Vec3::new(m.q[(K, 0)], m.q[(K, 1)], m.q[(K, 2)]);
    let d = ua[K];
    if d.is_nan() || d <= 0.0 {
        return false;
    }
    let dinv = 1.0 / d;
    let ut = tau - ba[K];
    // `U` is not stored: the acceleration step reads it from `inertia` (`forward_1`).
    cur.d_inv[(0, 0)] = dinv;
    cur.u_tau[0] = ut;
    let Some(parent) = parent else {
        return true;
    };
    let (c, s) = cur.cs;
    // Rows I, J of the projected blocks (rows K vanish).
    let (di, dj) = (ua[I] * dinv, ua[J] * dinv);
    let pii = m.p.at(I, I) - di * ua[I];
    let pjj = m.p.at(J, J) - dj * ua[J];
    let pij = m.p.at(I, J) - di * ua[J];
    let qi = Vec3::new(m.q[(I, 0)], m.q[(I, 1)], m.q[(I, 2)]) - ul * di;
    let qj = Vec3::new(m.q[(J, 0)], m.q[(J, 1)], m.q[(J, 2)]) - ul * dj;
    let mut ra = m.r;
    ra.sub_outer(&ul, dinv);
    // b^a = b̂ + M^a ξ + U ut / d.
    let (xa, xl) = (v3(&cur.xi, 0), v3(&cur.xi, 3));
    let k = ut * dinv;
    let mut fa = Vec3::zeros();
    fa[K] = ba[K] + ut;
    fa[I] = ba[I] + pii * xa[I] + pij * xa[J] + qi.dot(&xl) + ua[I] * k;
    fa[J] = ba[J] + pij * xa[I] + pjj * xa[J] + qj.dot(&xl) + ua[J] * k;
    let fl = bl + qi * xa[I] + qj * xa[J] + ra.mul(&xl) + ul * k;
    // E P^a Eᵀ: the I, J block turned by the plane rotation.
    let (cc, ss, cs) = (c * c, s * s, c * s);
    let cs2b = 2.0 * cs * pij;
    let mut pp = Sym3::default();
    pp.0[sidx(I, I)] = cc * pii - cs2b + ss * pjj;
    pp.0[sidx(J, J)] = ss * pii + cs2b + cc * pjj;
    pp.0[sidx(I, J)] = cs * (pii - pjj) + (cc - ss) * pij;
    // E Q^a Eᵀ: rows I, J mixed, then columns I, J of those rows.
    let ri = qi * c - qj * s;
    let rj = qi * s + qj * c;
    let mut qq = Mat3::zeros();
    for (row, v) in [(I, ri), (J, rj)] {
        qq[(row, I)] = c * v[I] - s * v[J];
        qq[(row, J)] = s * v[I] + c * v[J];
        qq[(row, K)] = v[K];
    }
    let e = Plane::<I, J> { c, s };
    let (r, oa) = (offset, form);
    let rr = e.conj_sym(&ra);
    if Pl::IDENTITY {
        shift_add::<K, true>(&pp, &qq, &rr, r, oa, start, &mut parent.inertia);
    } else {
        let (pp, qq, rr) = (pl.conj_sym(&pp), pl.conj::<false>(&qq), pl.conj_sym(&rr));
        shift_add::<3, true>(&pp, &qq, &rr, r, oa, start, &mut parent.inertia);
    }
    parent.bias += to_parent(Placed(pl, e), r, oa, &fa, &fl);
    true
}

/// One 3-dof (spherical) joint inward.
#[inline(always)]
fn backward_3(
    form: OffsetForm,
    cur: &mut LinkWork,
    parent: Option<&mut LinkWork>,
    start: Option<&LocalInertia>,
    tau: &[f64],
    armature: &[f64; 3],
) -> bool {
    let m = &cur.inertia;
    let (ba, bl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
    let mut u = [Vec6::zeros(); 3];
    let mut d = Mat3::zeros();
    let mut ut = Vec3::zeros();
    for k in 0..3 {
        let sk = cur.s[k];
        u[k] = six(&m.p.mul(&sk), &tr_mul(&m.q, &sk));
        ut[k] = tau[k] - sk.dot(&ba);
    }
    for r in 0..3 {
        for c in r..3 {
            let x = cur.s[r].dot(&v3(&u[c], 0));
            d[(r, c)] = x;
            d[(c, r)] = x;
        }
        d[(r, r)] += armature[r];
    }
    let d_inv = match d.cholesky() {
        Some(ch) => ch.inverse(),
        None => return false,
    };
    cur.u = u;
    cur.d_inv = d_inv;
    cur.u_tau = ut;
    if let Some(parent) = parent {
        let mut ma = *m;
        let dut = d_inv * ut;
        let mut ud_u = Vec6::zeros();
        for r in 0..3 {
            let ud = u[0] * d_inv[(0, r)] + u[1] * d_inv[(1, r)] + u[2] * d_inv[(2, r)];
            let (ua, ul) = (v3(&u[r], 0), v3(&u[r], 3));
            let (da, dl) = (v3(&ud, 0), v3(&ud, 3));
            // U D⁻¹ Uᵀ is symmetric as a whole: its upper triangles suffice.
            for (k, (i, j)) in [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
                .into_iter()
                .enumerate()
            {
                ma.p.0[k] -= da[i] * ua[j];
                ma.r.0[k] -= dl[i] * ul[j];
            }
            for c in 0..3 {
                for rr in 0..3 {
                    ma.q[(rr, c)] -= da[rr] * ul[c];
                }
            }
            ud_u += u[r] * dut[r];
        }
        let e = General(cur.rot);
        let r = cur.offset;
        finish(
            e,
            form,
            &r,
            &ma,
            &ba,
            &bl,
            &v3(&ud_u, 0),
            &v3(&ud_u, 3),
            cur,
            parent,
            start,
        );
    }
    true
}

/// A free-flyer joint inward. With `S = 1₆` the joint block is the whole articulated
/// inertia, `D = U = M̂`: the body's acceleration is `z = M̂⁻¹ (τ − b̂)` whatever its parent
/// does (kept in `u[0]`), `M^a = M̂ − M̂ M̂⁻¹ M̂ = 0`, and `b^a = b̂ + (τ − b̂) = τ`: the parent
/// feels exactly the joint's wrench.
#[inline(always)]
fn backward_free(
    form: OffsetForm,
    cur: &mut LinkWork,
    parent: Option<&mut LinkWork>,
    start: Option<&LocalInertia>,
    tau: &[f64],
) -> bool {
    // τ is (force, moment) in body axes; wrenches here are [moment; force].
    let (ta, tl) = (
        Vec3::new(tau[3], tau[4], tau[5]),
        Vec3::new(tau[0], tau[1], tau[2]),
    );
    let Some(ch) = cur.inertia.to_mat6().cholesky() else {
        return false;
    };
    cur.u[0] = ch.solve(&(six(&ta, &tl) - cur.bias));
    if let Some(parent) = parent {
        if let Some(s) = start {
            parent.inertia = *s;
        }
        parent.bias += to_parent(General(cur.rot), &cur.offset, form, &ta, &tl);
    }
    true
}

/// `b^a = b̂ + M^a ξ + k` (`k = U D⁻¹ u`), then `M^a`, `b^a` carried to the parent (rotated
/// by `E`, shifted by the offset) and added there.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn finish<R: Rot>(
    e: R,
    form: OffsetForm,
    r: &Vec3,
    ma: &LocalInertia,
    ba: &Vec3,
    bl: &Vec3,
    ka: &Vec3,
    kl: &Vec3,
    cur: &LinkWork,
    parent: &mut LinkWork,
    start: Option<&LocalInertia>,
) {
    let xa = v3(&cur.xi, 0);
    let xl = v3(&cur.xi, 3);
    let fa = ba + ma.p.mul(&xa) + mul(&ma.q, &xl) + ka;
    let fl = bl + tr_mul(&ma.q, &xa) + ma.r.mul(&xl) + kl;
    shift_add::<3, true>(
        &e.conj_sym(&ma.p),
        &e.conj::<false>(&ma.q),
        &e.conj_sym(&ma.r),
        r,
        form,
        start,
        &mut parent.inertia,
    );
    parent.bias += to_parent(e, r, form, &fa, &fl);
}

#[inline(always)]
fn forward_1<R: Rot, const AX: usize, const ANG: bool>(
    e: R,
    form: OffsetForm,
    offset: &Vec3,
    cur: &mut LinkWork,
    pacc: &Vec6,
) -> f64 {
    let (mut ya, mut yl) = carry(e, form, offset, cur, pacc);
    // About coordinate axis AX, `U = M̂ e_AX` is still in the articulated inertia.
    let m = &cur.inertia;
    let u = &if AX < 3 {
        Vec6::new(
            m.p.at(0, AX),
            m.p.at(1, AX),
            m.p.at(2, AX),
            m.q[(AX, 0)],
            m.q[(AX, 1)],
            m.q[(AX, 2)],
        )
    } else {
        cur.u[0]
    };
    let uy = u[0] * ya.x + u[1] * ya.y + u[2] * ya.z + u[3] * yl.x + u[4] * yl.y + u[5] * yl.z;
    let qdd = (cur.u_tau[0] - uy) * cur.d_inv[(0, 0)];
    if AX < 3 {
        ya[AX] += qdd;
    } else if ANG {
        ya += cur.s[0] * qdd;
    } else {
        yl += cur.s[0] * qdd;
    }
    cur.accel = six(&ya, &yl);
    qdd
}

/// A free-flyer joint's accelerations: the body's twist rate is `z` (see [`backward_free`]),
/// the joint's the part of it the parent's does not carry.
#[inline(always)]
fn forward_free(form: OffsetForm, cur: &mut LinkWork, pacc: &Vec6, out: &mut [f64]) {
    let (ya, yl) = carry(General(cur.rot), form, &cur.offset, cur, pacc);
    let z = cur.u[0];
    for k in 0..3 {
        out[k] = z[3 + k] - yl[k];
        out[3 + k] = z[k] - ya[k];
    }
    cur.accel = z;
}

#[inline(always)]
fn forward_3(form: OffsetForm, cur: &mut LinkWork, pacc: &Vec6, out: &mut [f64]) {
    let (mut ya, yl) = carry(General(cur.rot), form, &cur.offset, cur, pacc);
    let y = six(&ya, &yl);
    let mut rhs = Vec3::zeros();
    for k in 0..3 {
        rhs[k] = cur.u_tau[k] - cur.u[k].dot(&y);
    }
    let qdd = cur.d_inv * rhs;
    for k in 0..3 {
        out[k] = qdd[k];
        ya += cur.s[k] * qdd[k];
    }
    cur.accel = six(&ya, &yl);
}
