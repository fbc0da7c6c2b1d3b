//! Recursive forward dynamics: the articulated-body recursion written with DeNOC twists
//! about moving link origins (equivalent to Saha's UDUᵀ decomposition of the GIM). O(n), no
//! n × n matrix, no allocation. Every joint but the free flyer moves along a purely angular
//! or purely linear subspace (`P = [A; 0]` or `[0; A]`), so its products are 3×3 blocks; the
//! free flyer's six columns are taken whole.
use super::Workspace;
use crate::kinematics;
use crate::model::Model;
use crate::recursive::{base_accel, singular_message};
use crate::support::error::{Error, Result};
use crate::support::spatial::{
    angular, linear, shift_twist, shift_wrench, stack, ArticulatedInertia, Mat3, Mat6, Vec3, Vec6,
};

/// Inverts the dof × dof block `D = Pᵀ M̂ P`; `None` if it is not positive definite.
#[inline]
fn invert_joint_inertia(d: &Mat3, dof: usize) -> Option<Mat3> {
    match dof {
        1 => (d[(0, 0)] > 0.0).then(|| Mat3::from_diagonal(&Vec3::new(1.0 / d[(0, 0)], 0.0, 0.0))),
        // Coordinate singularities are refused before the recursion; an ill-conditioned but
        // positive block (a slender body) is solved, to the accuracy its conditioning allows.
        3 => Some(d.cholesky()?.inverse()),
        _ => None,
    }
}

/// `M̂ [a; 0]` (angular motion) or `M̂ [0; a]` (linear motion).
#[inline]
fn mul_axis(m: &ArticulatedInertia, a: &Vec3, angular_motion: bool) -> Vec6 {
    if angular_motion {
        stack(&(m.p * a), &m.q.tr_mul(a))
    } else {
        stack(&(m.q * a), &(m.r * a))
    }
}

/// `[a; 0]ᵀ w` or `[0; a]ᵀ w`.
#[inline]
fn dot_axis(a: &Vec3, w: &Vec6, angular_motion: bool) -> f64 {
    if angular_motion {
        a.dot(&angular(w))
    } else {
        a.dot(&linear(w))
    }
}

/// Accelerations `a` from `I a + C v − τ_g − Nᵀ f_ext = τ`, all in world axes. Errors at a
/// singular joint (a SphericalZYZ joint at sin θ = 0). Not the default (that is the
/// body-frame `forward_dynamics_local`); kept as an independent cross-check.
#[allow(clippy::too_many_arguments)]
pub fn forward_dynamics_world(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    a: &mut [f64],
) -> Result<()> {
    crate::recursive::check_singularities(model, q)?;
    kinematics::positions(model, q, &mut ws.links);
    kinematics::velocities(model, q, v, &mut ws.links);
    // Each link's own inertia and velocity-product wrench start its articulated ones.
    for (i, s) in ws.links.iter().enumerate() {
        ws.art_inertia[i] = ArticulatedInertia::from_body(&s.inertia);
        let mut b = s.inertia.bias(&angular(&s.twist));
        if let Some(f) = external {
            b -= f[i];
        }
        ws.art_bias[i] = b;
    }
    for i in (0..model.links.len()).rev() {
        inward_step(model, ws, i, q, tau)?;
    }
    accelerations(model, ws, g, a);
    Ok(())
}

/// Link `i` inward: `U = M̂ P`, `D = Pᵀ U`, `u = τ − Pᵀ b̂`, and its articulated inertia and
/// bias carried into the parent.
fn inward_step(model: &Model, ws: &mut Workspace, i: usize, q: &[f64], tau: &[f64]) -> Result<()> {
    let l = &model.links[i];
    let dof = l.joint.nv();
    let ang = l.joint.moves_angular();
    let m = ws.art_inertia[i];
    let b = ws.art_bias[i];
    let link = &ws.links[i];
    let mut u = [Vec6::zeros(); 6];
    let mut d_inv = Mat6::zeros();
    let mut ut = Vec6::zeros();
    let singular = || Error::Singular(singular_message(model, i, q));
    if dof == 6 {
        // The free flyer: P is the body's six unit twists.
        let mut d = Mat6::zeros();
        for k in 0..6 {
            u[k] = m.mul_twist(&link.s[k]);
            ut[k] = tau[l.v_index + k] - link.s[k].dot(&b);
        }
        for r in 0..6 {
            for c in 0..6 {
                d[(r, c)] = link.s[r].dot(&u[c]);
            }
        }
        d_inv = d.cholesky().ok_or_else(singular)?.inverse();
    } else {
        let mut axes = [Vec3::zeros(); 3];
        let mut d = Mat3::identity();
        for k in 0..dof {
            axes[k] = if ang {
                angular(&link.s[k])
            } else {
                linear(&link.s[k])
            };
            u[k] = mul_axis(&m, &axes[k], ang);
            ut[k] = tau[l.v_index + k] - dot_axis(&axes[k], &b, ang);
        }
        for r in 0..dof {
            for c in r..dof {
                let x = dot_axis(&axes[r], &u[c], ang);
                d[(r, c)] = x;
                d[(c, r)] = x;
            }
        }
        let small = invert_joint_inertia(&d, dof).ok_or_else(singular)?;
        d_inv.fixed_view_mut::<3, 3>(0, 0).copy_from(&small);
    }
    ws.u[i] = u;
    ws.d_inv[i] = d_inv;
    ws.u_tau[i] = ut;
    let Some(p) = l.parent else {
        return Ok(());
    };
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
        let (ua, ul) = (angular(&u[r]), linear(&u[r]));
        let (da, dl) = (angular(&ud), linear(&ud));
        ma.p -= da * ua.transpose();
        ma.q -= da * ul.transpose();
        ma.r -= dl * ul.transpose();
        ud_u += u[r] * dut[r];
    }
    let link = &ws.links[i];
    let ba = b + ma.mul_twist(&link.xi) + ud_u;
    let arm = link.origin - ws.links[p].origin;
    let moved = ma.shifted(&(-arm));
    ws.art_inertia[p].add(&moved);
    ws.art_bias[p] += shift_wrench(&ba, &arm);
    Ok(())
}

/// Outward: `q̈ = D⁻¹ (u − Uᵀ ṫ_carried)`, `ṫ = ṫ_carried + P q̈`.
fn accelerations(model: &Model, ws: &mut Workspace, g: &Vec3, a: &mut [f64]) {
    let base = base_accel(g);
    for (i, l) in model.links.iter().enumerate() {
        let dof = l.joint.nv();
        let s = &ws.links[i];
        let y = match l.parent {
            Some(p) => shift_twist(&ws.accel[p], &(s.origin - ws.links[p].origin)),
            None => base,
        } + s.xi;
        let mut rhs = Vec6::zeros();
        for k in 0..dof {
            rhs[k] = ws.u_tau[i][k] - ws.u[i][k].dot(&y);
        }
        let qdd = ws.d_inv[i] * rhs;
        let mut acc = y;
        for k in 0..dof {
            a[l.v_index + k] = qdd[k];
            acc += s.s[k] * qdd[k];
        }
        ws.accel[i] = acc;
    }
}
