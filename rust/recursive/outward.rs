//! The outward kinematic pass shared by the body-frame forward and inverse dynamics (and,
//! position part only, the mass matrix): per link, the joint's rotation `E` (child axes in
//! parent axes) and offset `r`, the twist `[Eᵀ ω_p; Eᵀ (v_p + ω_p × r)] + [w_J; v_J]`, the
//! velocity-dependent twist rate `ξ`, and the velocity-product wrench
//! `[ω × I ω; ω × (ω × h)]` minus the external wrench (docs/method.md §4).
use super::algebra::{cross, mat_mul, mul, six, tr_mul, v3, General, Placed, Rot};
use super::compiled::{match_axis_kind, LinkConsts};
use super::shift::{cross_offset, OffsetForm};
use super::workspace::LinkWork;
use crate::joint::Joint;
use crate::model::Model;
use crate::support::spatial::{Mat3, Vec3, Vec6};
use crate::support::trig::{sin_cos, sin_cos4};

/// The outward pass over all links; returns the first link whose joint is at a coordinate
/// singularity (`check_singularities`), if any. `ABI`: also start each leaf's articulated
/// inertia at its own.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn outward_pass<const ABI: bool>(
    model: &Model,
    consts: &[LinkConsts],
    work: &mut [LinkWork],
    angles: &[(usize, usize)],
    q: &[f64],
    v: &[f64],
    external: Option<&[Vec6]>,
) -> Option<usize> {
    let n = model.links.len();
    let (consts, work) = (&consts[..n], &mut work[..n]);
    plane_turns(consts, work, angles, q);
    let mut singular = None;
    for i in 0..n {
        let c = &consts[i];
        let (head, tail) = work.split_at_mut(i);
        let w = &mut tail[0];
        let parent = c.parent.map(|p| &head[p]);
        let vi = &v[c.v_index..];
        let fext = external.map(|f| &f[i]);
        // A revolute joint about coordinate axis K (the offset, the column e_K and the
        // placement are model constants).
        macro_rules! axis {
            ($pl:expr, $k:tt, $i:tt, $j:tt) => {{
                let mut w_j = Vec3::zeros();
                w_j[$k] = vi[0] * c.sign;
                let e = Placed($pl, Plane::<$i, $j>::new(w.cs));
                let z = Vec3::zeros();
                outward(e, c.offset_form, &c.offset, w, parent, &w_j, &z, &z, fext);
            }};
        }
        match_axis_kind!(c, axis, {
            if outward_other(
                &model.links[i].joint,
                c,
                w,
                parent,
                &q[c.q_index..],
                vi,
                fext,
            ) && singular.is_none()
            {
                singular = Some(i);
            }
        });
        let own = &c.inertia;
        if ABI && c.leaf {
            // A leaf's articulated inertia is its own; other links' are written by their
            // first child inward (`LinkConsts::first_child`).
            w.inertia = *own;
        }
        let h = own.first_moment();
        let wb = v3(&w.twist, 0);
        let iw = own.p.mul(&wb);
        let vp = six(&cross(&wb, &iw), &cross(&wb, &cross(&wb, &h)));
        // Without external wrenches `outward` leaves `bias` unwritten (no zeros to add to).
        w.bias = if external.is_some() { w.bias + vp } else { vp };
    }
    singular
}

/// The (cos, sin) of every revolute joint about a coordinate axis
/// (`Compiled::axis_angles`), four joints at a time (the last group padded).
#[inline(always)]
pub(super) fn plane_turns(
    consts: &[LinkConsts],
    work: &mut [LinkWork],
    angles: &[(usize, usize)],
    q: &[f64],
) {
    for group in angles.chunks(4) {
        let x: [f64; 4] = std::array::from_fn(|j| group.get(j).map_or(0.0, |g| q[g.1]));
        let (s, c) = sin_cos4(x).unwrap_or_else(|| {
            let one = x.map(sin_cos);
            (one.map(|p| p.0), one.map(|p| p.1))
        });
        for (j, &(i, _)) in group.iter().enumerate() {
            // About ±e_K (`sign`): sin turns sign with the angle, cos does not.
            work[i].cs = (c[j], s[j] * consts[i].sign);
        }
    }
}

/// The outward step of every joint but a revolute one about a coordinate axis, from the
/// joint's own motion ([`crate::joint::JointType::local_motion`]) and the constant
/// placement; true when the joint sits at a coordinate singularity.
#[inline(never)]
pub(super) fn outward_other(
    joint: &Joint,
    c: &LinkConsts,
    w: &mut LinkWork,
    parent: Option<&LinkWork>,
    qi: &[f64],
    vi: &[f64],
    fext: Option<&Vec6>,
) -> bool {
    let m = joint.local_motion(qi, vi);
    w.rot = match m.rotation {
        Some(rq) if c.placement_rotated => mat_mul(&c.placement, &rq),
        Some(rq) => rq,
        None => c.placement,
    };
    w.offset = match m.displacement {
        Some(d) => c.offset + mul(&c.placement, &d),
        None => c.offset,
    };
    w.s = m.columns.unwrap_or(c.columns);
    let r = w.offset;
    outward(
        General(w.rot),
        c.offset_form,
        &r,
        w,
        parent,
        &m.w,
        &m.v,
        &m.sdot_qd,
        fext,
    );
    joint.singularity(qi).is_some()
}

/// Twist, `ξ`, and the external wrench in body axes (stored negated in `bias`; `bias` is
/// left as it is without one).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn outward<R: Rot>(
    e: R,
    form: OffsetForm,
    offset: &Vec3,
    cur: &mut LinkWork,
    parent: Option<&LinkWork>,
    w_j: &Vec3,
    v_j: &Vec3,
    sdot_qd: &Vec3,
    fext: Option<&Vec6>,
) {
    let (wpc, vpc) = match parent {
        Some(p) => {
            // Parent twist carried to this origin, in this frame.
            let wp = v3(&p.twist, 0);
            let vp = v3(&p.twist, 3) + cross_offset(&wp, offset, form);
            (e.tr_mul(&wp), e.tr_mul(&vp))
        }
        None => (Vec3::zeros(), Vec3::zeros()),
    };
    // ξ = [ω × w_J + Ṡ q̇; ω_p × (v − v_p) + ω × v_J], with ω × w_J = ω_p × w_J and
    // v − v_p = ω_p × r + v_J (this frame).
    let vp_here = match parent {
        Some(p) => e.tr_mul(&v3(&p.twist, 3)),
        None => Vec3::zeros(),
    };
    if R::AXIS < 3 {
        // Revolute about e_K: the same sums with the known zeros left out.
        let k = R::AXIS;
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        let qd = w_j[k];
        let mut w = wpc;
        w[k] += qd;
        cur.twist = six(&w, &vpc);
        let mut xa = Vec3::zeros();
        xa[k1] = wpc[k2] * qd;
        xa[k2] = -(wpc[k1] * qd);
        cur.xi = six(&xa, &cross(&wpc, &(vpc - vp_here)));
    } else {
        let w = wpc + w_j;
        let vlin = vpc + v_j;
        cur.twist = six(&w, &vlin);
        let xa = cross(&wpc, w_j) + sdot_qd;
        let xl = cross(&wpc, &(vlin - vp_here)) + cross(&w, v_j);
        cur.xi = six(&xa, &xl);
    }
    if let Some(f) = fext {
        let rw = match parent {
            Some(p) => e.after(&p.world_rot),
            None => e.after(&Mat3::identity()),
        };
        cur.world_rot = rw;
        cur.bias = -six(&tr_mul(&rw, &v3(f, 0)), &tr_mul(&rw, &v3(f, 3)));
    }
}

/// The parent's twist rate carried to this link plus `ξ` (this frame).
#[inline(always)]
pub(super) fn carry<R: Rot>(
    e: R,
    form: OffsetForm,
    offset: &Vec3,
    cur: &LinkWork,
    pacc: &Vec6,
) -> (Vec3, Vec3) {
    let ap = v3(pacc, 0);
    let lp = v3(pacc, 3) + cross_offset(&ap, offset, form);
    (
        e.tr_mul(&ap) + v3(&cur.xi, 0),
        e.tr_mul(&lp) + v3(&cur.xi, 3),
    )
}
