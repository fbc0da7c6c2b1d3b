//! Centroidal momentum (Orin and Goswami): `h_G = [k_G; p] = A_g v`, the angular momentum
//! about the centre of mass and the linear momentum, world axes, angular first (Pinocchio's
//! `computeCentroidalMap` puts the linear part first). Column of a joint column `[a; l]` of
//! link `j`, with the subtree's composite (mass `M`, first moment `h`, inertia `I_O` about
//! the world origin) and `l₀ = l − a × O` the velocity of the point at the world origin:
//! `p = M l₀ + a × h`, `k_O = I_O a + h × l₀`, `k_G = k_O − G × p`. The bias `Ȧ_g v` is the
//! momentum rate at zero acceleration, summed link by link about the world origin:
//! `ṗ = Σ m a_c`, `k̇_O = Σ (I_c ω̇ + ω × I_c ω + m c × a_c)`, `k̇_G = k̇_O − G × ṗ`.
use crate::model::Model;
use crate::support::spatial::{angular, linear, Vec3, Vec6};

use super::com::{link_com, Composite};
use super::motion::FrameKinematics;

/// `A_g` (6 × nv, row-major) into `out`, about `g` (the centre of mass), from the composites.
pub fn centroidal_map(
    model: &Model,
    kin: &FrameKinematics,
    comp: &[Composite],
    g: &Vec3,
    out: &mut [f64],
) {
    let nv = model.nv;
    out[..6 * nv].fill(0.0);
    for (j, l) in model.links.iter().enumerate() {
        let st = &kin.links[j];
        let c = &comp[j];
        for k in 0..l.joint.nv() {
            let s = &st.s[k];
            let a = angular(s);
            let l0 = linear(s) - a.cross(&st.origin);
            let p = l0 * c.mass + a.cross(&c.moment);
            let k_o = c.inertia * a + c.moment.cross(&l0);
            let k_g = k_o - g.cross(&p);
            for i in 0..3 {
                out[i * nv + l.v_index + k] = k_g[i];
                out[(3 + i) * nv + l.v_index + k] = p[i];
            }
        }
    }
}

/// The centroidal momentum rate `[k̇_G; ṗ]` from the links' accelerations (with `a = 0`:
/// the bias `Ȧ_g v`); needs accelerations.
pub fn momentum_rate(model: &Model, kin: &FrameKinematics, g: &Vec3) -> Vec6 {
    let (mut k, mut p) = (Vec3::zeros(), Vec3::zeros());
    for (j, l) in model.links.iter().enumerate() {
        let b = &l.rigid;
        let st = &kin.links[j];
        let c = link_com(model, kin, j);
        let acc = kin.point_acceleration(Some(j), &c);
        let (w, wd) = (angular(&st.twist), angular(&acc));
        let i_c = st.rotation * b.inertia * st.rotation.transpose();
        let f = linear(&acc) * b.mass;
        p += f;
        k += i_c * wd + w.cross(&(i_c * w)) + c.cross(&f);
    }
    let mut out = Vec6::zeros();
    out.fixed_rows_mut::<3>(0).copy_from(&(k - g.cross(&p)));
    out.fixed_rows_mut::<3>(3).copy_from(&p);
    out
}
