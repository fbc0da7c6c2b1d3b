//! The time variation `J̇` of a frame Jacobian (Pinocchio's
//! `getFrameJacobianTimeVariation`): in every reference frame the exact time derivative of
//! [`super::jacobian::frame_jacobian`], so `J̇ v` is the velocity-product part of the frame's
//! acceleration in that frame (`J a + J̇ v` = d/dt of `J v`). For a column `[a; l + a × (x − O)]`
//! about the reference point `x`: `[ȧ; l̇ + ȧ × (x − O) + a × (ẋ − Ȯ)]`, with `ṡ = [ȧ; l̇]`
//! the joint column's rate; LOCAL turns it into the frame's axes and subtracts the rotation of
//! those axes, `Rᵀ (ẏ − ω × y)` for each half `y`.
use crate::model::Model;
use crate::support::spatial::{angular, linear, Vec3};

use super::motion::FrameKinematics;
use super::{FrameRef, ReferenceFrame};

/// Writes `J̇` of frame `f` (6 × nv, row-major) into `out`; needs
/// [`FrameKinematics::velocities`].
pub fn frame_jacobian_dot(
    model: &Model,
    kin: &FrameKinematics,
    f: &FrameRef,
    rf: ReferenceFrame,
    out: &mut [f64],
) {
    let nv = model.nv;
    out[..6 * nv].fill(0.0);
    let pose = kin.frame_pose(f);
    let (x, xdot) = match rf {
        ReferenceFrame::World => (Vec3::zeros(), Vec3::zeros()),
        _ => (
            pose.translation,
            linear(&kin.point_velocity(f.link, &pose.translation)),
        ),
    };
    let w = match f.link {
        Some(l) => angular(&kin.links[l].twist),
        None => Vec3::zeros(),
    };
    for j in model.support(f.link) {
        let l = &model.links[j];
        let st = &kin.links[j];
        let (o, odot) = (st.origin, linear(&st.twist));
        for k in 0..l.joint.nv() {
            let (s, sd) = (&st.s[k], &kin.sdot[j][k]);
            let (a, ad) = (angular(s), angular(sd));
            let mut ang = ad;
            let mut lin = linear(sd) + ad.cross(&(x - o)) + a.cross(&(xdot - odot));
            if rf == ReferenceFrame::Local {
                let lin_col = linear(s) + a.cross(&(x - o));
                ang = pose.rotation.tr_mul(&(ang - w.cross(&a)));
                lin = pose.rotation.tr_mul(&(lin - w.cross(&lin_col)));
            }
            let c = l.v_index + k;
            for i in 0..3 {
                out[i * nv + c] = ang[i];
                out[(3 + i) * nv + c] = lin[i];
            }
        }
    }
}
