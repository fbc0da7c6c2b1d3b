//! Recursive inverse dynamics (DeNOC / Newton–Euler): twist rates outward, wrenches inward.
use super::Workspace;
use crate::kinematics;
use crate::model::Model;
use crate::recursive::base_accel;
use crate::support::spatial::{shift_twist, shift_wrench, Vec3, Vec6};

/// `τ = I a + C v − τ_g − Nᵀ f_ext`. `external` holds one wrench per link about its origin
/// (world axes), applied to the link. Writes `tau` (length nv). World-axes version, kept as
/// an independent cross-check of the default (body-frame `inverse_dynamics_local`).
#[allow(clippy::too_many_arguments)]
pub fn inverse_dynamics_world(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    tau: &mut [f64],
) {
    kinematics::positions(model, q, &mut ws.links);
    kinematics::velocities(model, q, v, &mut ws.links);
    let base = base_accel(g);
    for (i, l) in model.links.iter().enumerate() {
        let s = &ws.links[i];
        let parent_accel = match l.parent {
            Some(p) => shift_twist(&ws.accel[p], &(s.origin - ws.links[p].origin)),
            None => base,
        };
        let mut acc = parent_accel + s.xi;
        for k in 0..l.joint.nv() {
            acc += s.s[k] * a[l.v_index + k];
        }
        ws.accel[i] = acc;
        let w = crate::support::spatial::angular(&s.twist);
        let mut wr = s.inertia.mul_twist(&acc) + s.inertia.bias(&w);
        if let Some(f) = external {
            wr -= f[i];
        }
        ws.wrench[i] = wr;
    }
    for (i, l) in model.links.iter().enumerate().rev() {
        let w = ws.wrench[i];
        for k in 0..l.joint.nv() {
            tau[l.v_index + k] = ws.links[i].s[k].dot(&w);
        }
        if let Some(p) = l.parent {
            let arm = ws.links[i].origin - ws.links[p].origin;
            ws.wrench[p] += shift_wrench(&w, &arm);
        }
    }
}
