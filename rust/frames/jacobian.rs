//! Frame Jacobians in Pinocchio's three reference frames (`ReferenceFrame`), angular rows
//! first: `[ω; v] = J v_gen`. Each column of a link on the frame's support is the link's
//! joint column `s = [a; l]` (about the link origin `O`) moved to the reference point:
//! `l − a × O` (WORLD: the body point at the world origin), `l + a × (p − O)` (the frame
//! origin `p`, LOCAL_WORLD_ALIGNED), then in the frame's axes for LOCAL.
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::spatial::{Mat3, Vec3};

use super::motion::FrameKinematics;
use super::{FrameRef, ReferenceFrame};

/// Writes the 6 × nv Jacobian of frame `f` into `out` (row-major, length 6·nv; every
/// entry written); needs [`FrameKinematics::positions`].
pub fn frame_jacobian(
    model: &Model,
    kin: &FrameKinematics,
    f: &FrameRef,
    rf: ReferenceFrame,
    out: &mut [f64],
) {
    frame_jacobian_links(model, &kin.links, f, rf, out);
}

/// [`frame_jacobian`] from the links' poses alone (`crate::kinematics::positions`).
pub fn frame_jacobian_links(
    model: &Model,
    links: &[LinkState],
    f: &FrameRef,
    rf: ReferenceFrame,
    out: &mut [f64],
) {
    let pose = super::motion::pose_on(links, f);
    let (p, r) = match rf {
        ReferenceFrame::World => (Vec3::zeros(), None),
        ReferenceFrame::LocalWorldAligned => (pose.translation, None),
        ReferenceFrame::Local => (pose.translation, Some(pose.rotation)),
    };
    point_jacobian_at(model, links, f.link, &p, r.as_ref(), out);
}

/// The Jacobian of the motion of the point `x` (world) fixed on `link`, in world axes (or
/// in the axes `r` when given): rows `[ω; velocity of x]`. Row-major 6 × nv into `out`.
pub fn point_jacobian_at(
    model: &Model,
    links: &[LinkState],
    link: Option<usize>,
    x: &Vec3,
    r: Option<&Mat3>,
    out: &mut [f64],
) {
    let nv = model.nv;
    out[..6 * nv].fill(0.0);
    for j in model.support(link) {
        let l = &model.links[j];
        let st = &links[j];
        let arm = [x.x - st.origin.x, x.y - st.origin.y, x.z - st.origin.z];
        for k in 0..l.joint.nv() {
            // Entry by entry (nalgebra's generic products stay calls without LTO).
            let s = &st.s[k];
            let a = [s[0], s[1], s[2]];
            let mut lin = [
                s[3] + (a[1] * arm[2] - a[2] * arm[1]),
                s[4] + (a[2] * arm[0] - a[0] * arm[2]),
                s[5] + (a[0] * arm[1] - a[1] * arm[0]),
            ];
            let mut ang = a;
            if let Some(r) = r {
                let tr = |v: &[f64; 3]| {
                    let c = |j: usize| r[(0, j)] * v[0] + r[(1, j)] * v[1] + r[(2, j)] * v[2];
                    [c(0), c(1), c(2)]
                };
                ang = tr(&ang);
                lin = tr(&lin);
            }
            let c = l.v_index + k;
            for i in 0..3 {
                out[i * nv + c] = ang[i];
                out[(3 + i) * nv + c] = lin[i];
            }
        }
    }
}
