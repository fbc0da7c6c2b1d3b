//! Recursive inverse dynamics (DeNOC / Newton–Euler): twist rates outward, wrenches inward.
use super::{base_accel, Data};
use crate::kinematics;
use crate::model::Model;
use crate::spatial::{shift_twist, shift_wrench, Vec3, Vec6};

/// `τ = I a + C v − τ_g − Nᵀ f_ext`. `external` holds one wrench per link about its origin
/// (world axes), applied to the link. Writes `tau` (length nv). World-axes version, kept as
/// an independent cross-check of the default (body-frame `inverse_dynamics_local`).
#[allow(clippy::too_many_arguments)]
pub fn inverse_dynamics_world(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    tau: &mut [f64],
) {
    kinematics::positions(model, q, &mut data.links);
    kinematics::velocities(model, q, v, &mut data.links);
    let base = base_accel(g);
    for (i, l) in model.links.iter().enumerate() {
        let s = &data.links[i];
        let parent_accel = match l.parent {
            Some(p) => shift_twist(&data.accel[p], &(s.origin - data.links[p].origin)),
            None => base,
        };
        let mut acc = parent_accel + s.xi;
        for k in 0..l.joint.nv() {
            acc += s.s[k] * a[l.v_index + k];
        }
        data.accel[i] = acc;
        let w = crate::spatial::angular(&s.twist);
        let mut wr = s.inertia.mul_twist(&acc) + s.inertia.bias(&w);
        if let Some(f) = external {
            wr -= f[i];
        }
        data.wrench[i] = wr;
    }
    for (i, l) in model.links.iter().enumerate().rev() {
        let w = data.wrench[i];
        for k in 0..l.joint.nv() {
            tau[l.v_index + k] = data.links[i].s[k].dot(&w);
        }
        if let Some(p) = l.parent {
            let arm = data.links[i].origin - data.links[p].origin;
            data.wrench[p] += shift_wrench(&w, &arm);
        }
    }
}
