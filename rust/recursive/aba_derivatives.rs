//! Analytic derivatives of the forward dynamics `q̈ = FD(q, v, τ)` (Pinocchio's
//! `computeABADerivatives`): since `ID(q, v, FD(q, v, τ)) = τ`,
//! `∂q̈/∂q = −M⁻¹ ∂τ/∂q`, `∂q̈/∂v = −M⁻¹ ∂τ/∂v` (both at `a = q̈`) and `∂q̈/∂τ = M⁻¹`:
//! the accelerations by the articulated-body recursion, the inverse-dynamics derivatives
//! ([`super::rnea_derivatives`], which also give `M`), then `M⁻¹` from an in-place Cholesky
//! factor and two matrix products (up to 12 dofs at a compile-time size,
//! [`super::aba_derivatives_small`]). docs/derivatives.md.
use super::rnea_derivatives::inverse_dynamics_derivatives;
use super::workspace::{Data, DerivativeData};
use crate::linalg::spd::product;
use crate::linalg::spd_inverse;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec3;

/// `∂q̈/∂q`, `∂q̈/∂v`, `M⁻¹` into `dd.ddq_dq`, `dd.ddq_dv`, `dd.minv` (and `q̈` into
/// `dd.qdd`, `∂τ/∂q`, `∂τ/∂v`, `M` as [`inverse_dynamics_derivatives`] leaves them). `tau`
/// holds the joint forces (gravity `g`, no external wrenches). Errors where the forward
/// dynamics does (a ZYZ singularity, a singular mass matrix). Every buffer is in `dd`; from
/// [`crate::linalg::spd::SMALL`] dofs on, faer's products keep their packing buffers per thread
/// (allocated on a thread's first call); below, by rows, nalgebra's `gemm` allocates its own.
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
    let singular = |k| {
        Error::Singular(format!(
            "the mass matrix is not positive definite (pivot {k} of the Cholesky factor)"
        ))
    };
    if !dd.row_major && model.nv <= super::aba_derivatives_small::MAX_FIXED {
        // Small: the inverse and both products at a compile-time size, in one pass.
        let fixed = super::aba_derivatives_small::inverse_and_products(
            model.nv,
            dd.mass.as_slice(),
            [dd.dtau_dq.as_slice(), dd.dtau_dv.as_slice()],
            dd.minv.as_mut_slice(),
            [dd.ddq_dq.as_mut_slice(), dd.ddq_dv.as_mut_slice()],
        );
        if let Some(r) = fixed {
            return r.map_err(singular);
        }
    }
    dd.minv.as_mut_slice().copy_from_slice(dd.mass.as_slice());
    spd_inverse(
        &mut dd.minv,
        &mut dd.ddq_dv,
        &mut dd.inv_diag,
        &mut dd.spd_scratch,
    )
    .map_err(singular)?;
    let n = model.nv;
    if n < crate::linalg::spd::SMALL && !dd.row_major {
        // Small: `−M⁻¹ D` column by column as sums of `M⁻¹`'s (contiguous) columns, no
        // packing buffers (see [`crate::linalg::spd::SMALL`]).
        let minv = dd.minv.as_slice();
        for (d, out) in [
            (dd.dtau_dq.as_slice(), dd.ddq_dq.as_mut_slice()),
            (dd.dtau_dv.as_slice(), dd.ddq_dv.as_mut_slice()),
        ] {
            neg_product_small(minv, d, out, n);
        }
        return Ok(());
    }
    if dd.row_major {
        // Stored transposed: (−M⁻¹ D)ᵀ = −Dᵀ M⁻¹ (M⁻¹ symmetric).
        product(&mut dd.ddq_dq, -1.0, &dd.dtau_dq, &dd.minv);
        product(&mut dd.ddq_dv, -1.0, &dd.dtau_dv, &dd.minv);
    } else {
        product(&mut dd.ddq_dq, -1.0, &dd.minv, &dd.dtau_dq);
        product(&mut dd.ddq_dv, -1.0, &dd.minv, &dd.dtau_dv);
    }
    Ok(())
}

crate::support::cpu::multiversion! {
    /// `out = −A D` for n × n column-major `A` (symmetric), `D`. AVX2 where the CPU has it.
    fn neg_product_small / neg_product_avx2 / neg_product_baseline [] (
        a: &[f64],
        d: &[f64],
        out: &mut [f64],
        n: usize,
    ) => neg_product_body
}

/// Column `j` of `out` is `−Σ_k D_kj A[:, k]`, four rows at a time in fixed-size
/// accumulators (one vector register with AVX2): short variable-length loops (n = 7) cost
/// more in their vector set-up than in the products.
#[inline(always)]
fn neg_product_body(a: &[f64], d: &[f64], out: &mut [f64], n: usize) {
    let (a, d, out) = (&a[..n * n], &d[..n * n], &mut out[..n * n]);
    for j in 0..n {
        let dj = &d[j * n..(j + 1) * n];
        let mut i = 0;
        while i + 4 <= n {
            let mut acc = [0.0; 4];
            for (k, x) in dj.iter().enumerate() {
                let ak = &a[k * n + i..k * n + i + 4];
                for r in 0..4 {
                    acc[r] -= x * ak[r];
                }
            }
            out[j * n + i..j * n + i + 4].copy_from_slice(&acc);
            i += 4;
        }
        for i in i..n {
            // `A` symmetric: row `i` is column `i`, contiguous.
            let ai = &a[i * n..(i + 1) * n];
            let mut acc = 0.0;
            for (x, y) in dj.iter().zip(ai) {
                acc -= x * y;
            }
            out[j * n + i] = acc;
        }
    }
}
