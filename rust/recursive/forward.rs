//! Recursive forward dynamics: the articulated-body recursion written with DeNOC twists
//! about moving link origins (equivalent to Saha's UDUᵀ decomposition of the GIM). O(n), no
//! n × n matrix, no allocation.
use super::{base_accel, singular_message, Data};
use crate::error::{Error, Result};
use crate::kinematics;
use crate::model::Model;
use crate::spatial::{angular, shift_twist, shift_wrench, skew, Mat3, Mat6, Vec3, Vec6};

/// `AᵀMA` for the twist shift `A = [[1, 0], [K, 1]]`, `K = ã`, written by 3×3 blocks of
/// `M = [[P, Q], [Qᵀ, R]]`: `[[P + QK − KQᵀ − KRK, Q − KR], [Qᵀ + RK, R]]`.
#[inline]
fn shift_inertia(m: &Mat6, a: &Vec3) -> Mat6 {
    let k = skew(a);
    let p = m.fixed_view::<3, 3>(0, 0).into_owned();
    let q = m.fixed_view::<3, 3>(0, 3).into_owned();
    let r = m.fixed_view::<3, 3>(3, 3).into_owned();
    let qk = q * k;
    let kr = k * r;
    let top_left = p + qk + qk.transpose() - kr * k;
    let top_right = q - kr;
    let mut out = Mat6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&top_left);
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&top_right);
    out.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&top_right.transpose());
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    out
}

/// Inverts the dof × dof block `D = Pᵀ M̂ P`; `None` if it is not positive definite.
#[inline]
fn invert_joint_inertia(d: &Mat3, dof: usize) -> Option<Mat3> {
    match dof {
        1 => {
            if d[(0, 0)] > 0.0 {
                let mut out = Mat3::zeros();
                out[(0, 0)] = 1.0 / d[(0, 0)];
                Some(out)
            } else {
                None
            }
        }
        // Coordinate singularities are refused before the recursion; an ill-conditioned but
        // positive block (a slender body) is solved, to the accuracy its conditioning allows.
        3 => Some(d.cholesky()?.inverse()),
        _ => None,
    }
}

/// Accelerations `a` from `I a + C v − τ_g − Nᵀ f_ext = τ`. Errors at a singular joint
/// (a SphericalZYZ joint at sin θ = 0).
pub fn forward_dynamics(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    a: &mut [f64],
) -> Result<()> {
    super::check_singularities(model, q)?;
    kinematics::positions(model, q, &mut data.links);
    kinematics::velocities(model, q, v, &mut data.links);
    for (i, s) in data.links.iter().enumerate() {
        data.art_inertia[i] = s.inertia.to_matrix();
        let mut b = s.inertia.bias(&angular(&s.twist));
        if let Some(f) = external {
            b -= f[i];
        }
        data.art_bias[i] = b;
    }
    for (i, l) in model.links.iter().enumerate().rev() {
        let dof = l.joint.nv();
        let m = data.art_inertia[i];
        let b = data.art_bias[i];
        let s = data.links[i].s;
        let mut u = [Vec6::zeros(); 3];
        let mut d = Mat3::identity();
        let mut ut = Vec3::zeros();
        for k in 0..dof {
            u[k] = m * s[k];
            ut[k] = tau[l.v_index + k] - s[k].dot(&b);
        }
        for r in 0..dof {
            for c in 0..dof {
                d[(r, c)] = s[r].dot(&u[c]);
            }
        }
        let d_inv = invert_joint_inertia(&d, dof)
            .ok_or_else(|| Error::Singular(singular_message(model, i, q)))?;
        data.u[i] = u;
        data.d_inv[i] = d_inv;
        data.u_tau[i] = ut;
        if let Some(p) = l.parent {
            // Articulated inertia and bias seen through the joint:
            // M^a = M̂ − U D⁻¹ Uᵀ, b^a = b̂ + M^a ξ + U D⁻¹ (τ − Pᵀ b̂).
            let mut ma = m;
            let dut = d_inv * ut;
            let mut ud_u = Vec6::zeros();
            for r in 0..dof {
                let mut ud = Vec6::zeros();
                for c in 0..dof {
                    ud += u[c] * d_inv[(c, r)];
                }
                ma -= ud * u[r].transpose();
                ud_u += u[r] * dut[r];
            }
            let ba = b + ma * data.links[i].xi + ud_u;
            let arm = data.links[i].origin - data.links[p].origin;
            data.art_inertia[p] += shift_inertia(&ma, &(-arm));
            data.art_bias[p] += shift_wrench(&ba, &arm);
        }
    }
    let base = base_accel(g);
    for (i, l) in model.links.iter().enumerate() {
        let dof = l.joint.nv();
        let s = &data.links[i];
        let y = match l.parent {
            Some(p) => shift_twist(&data.accel[p], &(s.origin - data.links[p].origin)),
            None => base,
        } + s.xi;
        let mut rhs = Vec3::zeros();
        for k in 0..dof {
            rhs[k] = data.u_tau[i][k] - data.u[i][k].dot(&y);
        }
        let qdd = data.d_inv[i] * rhs;
        let mut acc = y;
        for k in 0..dof {
            a[l.v_index + k] = qdd[k];
            acc += s.s[k] * qdd[k];
        }
        data.accel[i] = acc;
    }
    Ok(())
}
