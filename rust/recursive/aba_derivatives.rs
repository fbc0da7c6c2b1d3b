//! Analytic derivatives of the forward dynamics `q̈ = FD(q, v, τ)` (Pinocchio's
//! `computeABADerivatives`): since `ID(q, v, FD(q, v, τ)) = τ`,
//! `∂q̈/∂q = −M⁻¹ ∂τ/∂q`, `∂q̈/∂v = −M⁻¹ ∂τ/∂v` (both at `a = q̈`) and `∂q̈/∂τ = M⁻¹`:
//! the accelerations by the articulated-body recursion, the inverse-dynamics derivatives
//! ([`super::rnea_derivatives`], which also give `M`), then `M⁻¹` from an in-place Cholesky
//! factor and two matrix products. docs/derivatives.md.
use super::rnea_derivatives::inverse_dynamics_derivatives;
use super::workspace::{Data, DerivativeData};
use crate::error::{Error, Result};
use crate::loops::factor::cholesky;
use crate::model::Model;
use crate::spatial::Vec3;
use nalgebra::DMatrix;

/// `∂q̈/∂q`, `∂q̈/∂v`, `M⁻¹` into `dd.ddq_dq`, `dd.ddq_dv`, `dd.minv` (and `q̈` into
/// `dd.qdd`, `∂τ/∂q`, `∂τ/∂v`, `M` as [`inverse_dynamics_derivatives`] leaves them). `tau`
/// holds the joint forces (gravity `g`, no external wrenches). Errors where the forward
/// dynamics does (a ZYZ singularity, a singular mass matrix). No allocation.
#[allow(clippy::too_many_arguments)]
pub fn forward_dynamics_derivatives(
    model: &Model,
    data: &mut Data,
    dd: &mut DerivativeData,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    g: &Vec3,
) -> Result<()> {
    let mut qdd = std::mem::take(&mut dd.qdd);
    let done = super::forward_dynamics(model, data, q, v, tau, g, None, &mut qdd);
    if done.is_ok() {
        inverse_dynamics_derivatives(model, data, dd, q, v, &qdd, g);
    }
    dd.qdd = qdd;
    done?;
    dd.minv.copy_from(&dd.mass);
    spd_inverse(&mut dd.minv).map_err(|k| {
        Error::Singular(format!(
            "the mass matrix is not positive definite (pivot {k} of the Cholesky factor)"
        ))
    })?;
    dd.ddq_dq.gemm(-1.0, &dd.minv, &dd.dtau_dq, 0.0);
    dd.ddq_dv.gemm(-1.0, &dd.minv, &dd.dtau_dv, 0.0);
    Ok(())
}

/// The inverse of a symmetric positive definite matrix, in place: `M = L Lᵀ`, `L⁻¹`, then
/// `M⁻¹ = L⁻ᵀ L⁻¹`. `Err(k)` at a non-positive pivot `k`.
pub(crate) fn spd_inverse(m: &mut DMatrix<f64>) -> std::result::Result<(), usize> {
    let n = m.nrows();
    cholesky(m)?;
    // L⁻¹ by columns, left to right: column j reads only L's columns > j, not yet overwritten.
    for j in 0..n {
        let djj = 1.0 / m[(j, j)];
        for i in j + 1..n {
            let mut s = m[(i, j)] * djj;
            for k in j + 1..i {
                s += m[(i, k)] * m[(k, j)];
            }
            m[(i, j)] = -s / m[(i, i)];
        }
        m[(j, j)] = djj;
    }
    // (L⁻ᵀ L⁻¹)_ij = Σ_{k ≥ i} L⁻¹_ki L⁻¹_kj (j ≤ i), rows top to bottom: entry (i, j) is the
    // last reader of L⁻¹_ij, and later rows read only rows below them.
    for i in 0..n {
        for j in 0..=i {
            let mut s = 0.0;
            for k in i..n {
                s += m[(k, i)] * m[(k, j)];
            }
            m[(i, j)] = s;
        }
    }
    for j in 0..n {
        for i in 0..j {
            m[(i, j)] = m[(j, i)];
        }
    }
    Ok(())
}
