//! Derivatives of the constrained forward dynamics (docs/mechanisms.md §4).
//!
//! `M(q) q̈ + C(q, v) − τ_e(q, v) − J(q)ᵀ λ = τ`, `J(q) q̈ + γ(q, v) = 0`, differentiated at
//! a solution with respect to a state coordinate `x`:
//! `M ∂q̈ − Jᵀ ∂λ = r_x + ∂(Jᵀλ)/∂x|_λ` and `J ∂q̈ = −∂(J q̈ + γ)/∂x|_q̈`, with
//! `r_x = ∂τ_e/∂x − ∂ID/∂x` the tree's (analytic, `recursive::inverse_dynamics_derivatives`
//! at the constrained `q̈`, and the effects'). That is the constrained solve of
//! [`super::solve`] again, with other right-hand sides: `∂q̈ = x' ` for `x = M⁻¹ (…)` and
//! `J_B x' = b_B` ([`super::solve::constrained_correction`]), the same independent rows.
//!
//! The cut joints' own terms: in `v` exactly (`γ` is a quadratic form in `v`, so its
//! central difference with any step is its derivative, to rounding); in `q` (`∂(Jᵀλ)/∂q`,
//! `∂(J q̈ + γ)/∂q`, kinematics only, O(nv · (n + m)) per column) by the five-point
//! central difference along `q ⊕ s eᵢ` (the exact exponential), whose error is
//! `h⁴/30 · f⁽⁵⁾` ≈ 1e-13 relative at `h = 1e-3` plus rounding `ε/h` ≈ 1e-13 — not exact,
//! but far below what a Newton iteration or a sensitivity needs (measured against central
//! differences of the whole constrained dynamics: tests/test_iftomm.py).
use nalgebra::DMatrix;

use super::constraints::{self, Constraints, LoopKinematics};
use super::solve::{constrained_correction, mass_solve, LoopSolver};
use crate::model::Model;
use crate::recursive::tangent;

/// Buffers of the loop derivatives, sized once per model.
pub struct LoopDerivativeWork {
    kin: LoopKinematics,
    cons: Constraints,
    q_shift: Vec<f64>,
    delta: Vec<f64>,
    v_shift: Vec<f64>,
    col: Vec<f64>,
    rhs: Vec<f64>,
    gamma_plus: Vec<f64>,
    /// `∂(J q̈ + γ)/∂δ` and `∂γ/∂v` (m × nv).
    dc_dq: DMatrix<f64>,
    dc_dv: DMatrix<f64>,
}

impl LoopDerivativeWork {
    pub fn new(model: &Model) -> Self {
        let (m, nv) = (model.nconstraints(), model.nv);
        LoopDerivativeWork {
            kin: LoopKinematics::new(model),
            cons: Constraints::new(model),
            q_shift: vec![0.0; model.nq],
            delta: vec![0.0; nv],
            v_shift: vec![0.0; nv],
            col: vec![0.0; nv],
            rhs: vec![0.0; m],
            gamma_plus: vec![0.0; m],
            dc_dq: DMatrix::zeros(m, nv),
            dc_dv: DMatrix::zeros(m, nv),
        }
    }
}

/// Step of the five-point difference in `q` (radians, metres).
const H: f64 = 1e-3;
/// `f'(0) ≈ Σ wₖ f(sₖ h) / h`.
const STENCIL: [(f64, f64); 4] = [
    (-2.0, 1.0 / 12.0),
    (-1.0, -8.0 / 12.0),
    (1.0, 8.0 / 12.0),
    (2.0, -1.0 / 12.0),
];

/// The constrained `∂q̈/∂q` (tangent columns), `∂q̈/∂v` and `∂q̈/∂τ`, overwriting the
/// tree's `rq = ∂τ_e/∂q − ∂ID/∂q`, `rv = ∂τ_e/∂v − ∂ID/∂v` (both at the constrained
/// accelerations `a`) with them and writing `dtau` (nv × nv). `solver` holds the
/// factorisations and multipliers of [`super::constrained_forward_dynamics`] at `(q, v)`.
#[allow(clippy::too_many_arguments)]
pub fn constrained_derivatives(
    model: &Model,
    solver: &mut LoopSolver,
    w: &mut LoopDerivativeWork,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    rq: &mut DMatrix<f64>,
    rv: &mut DMatrix<f64>,
    dtau: &mut DMatrix<f64>,
) {
    let (nv, m) = (model.nv, model.nconstraints());
    w.dc_dq.fill(0.0);
    w.dc_dv.fill(0.0);
    // q: ∂(Jᵀλ)/∂δ into rq, ∂(J a + γ)/∂δ into dc_dq.
    for i in 0..nv {
        for &(s, weight) in &STENCIL {
            w.delta.fill(0.0);
            w.delta[i] = s * H;
            tangent::integrate(model, q, &w.delta, &mut w.q_shift);
            w.kin.positions(model, &w.q_shift);
            constraints::jacobian(model, &w.kin, &mut w.cons.jacobian);
            w.kin.velocities(model, &w.q_shift, v);
            constraints::gamma(model, &w.kin, w.cons.gamma.as_mut_slice());
            let c = weight / H;
            let j = &w.cons.jacobian;
            for col in 0..nv {
                let g: f64 = (0..m).map(|r| j[(r, col)] * solver.lambda[r]).sum();
                rq[(col, i)] += c * g;
            }
            for r in 0..m {
                let ja: f64 = (0..nv).map(|col| j[(r, col)] * a[col]).sum();
                w.dc_dq[(r, i)] += c * (ja + w.cons.gamma[r]);
            }
        }
    }
    // v: γ(q, ·) is quadratic, so (γ(v + s eᵢ) − γ(v − s eᵢ)) / 2s is exact for any s.
    let s = v.iter().fold(1.0_f64, |x, y| x.max(y.abs()));
    w.kin.positions(model, q);
    for i in 0..nv {
        for (sign, out) in [(1.0, true), (-1.0, false)] {
            w.v_shift.copy_from_slice(v);
            w.v_shift[i] += sign * s;
            w.kin.velocities(model, q, &w.v_shift);
            let g = if out { &mut w.gamma_plus } else { &mut w.rhs };
            constraints::gamma(model, &w.kin, g);
        }
        for r in 0..m {
            w.dc_dv[(r, i)] = (w.gamma_plus[r] - w.rhs[r]) / (2.0 * s);
        }
    }
    // The constrained solves, column by column.
    let mut solve = |w: &mut LoopDerivativeWork, x: &mut DMatrix<f64>, dc: Option<usize>| {
        for i in 0..nv {
            w.col.copy_from_slice(x.column(i).as_slice());
            mass_solve(solver, &mut w.col);
            match dc {
                Some(0) => (0..m).for_each(|r| w.rhs[r] = -w.dc_dq[(r, i)]),
                Some(_) => (0..m).for_each(|r| w.rhs[r] = -w.dc_dv[(r, i)]),
                None => w.rhs.fill(0.0),
            }
            let rhs = std::mem::take(&mut w.rhs);
            constrained_correction(solver, &mut w.col, &rhs);
            w.rhs = rhs;
            x.column_mut(i).copy_from_slice(&w.col);
        }
    };
    solve(w, rq, Some(0));
    solve(w, rv, Some(1));
    dtau.fill_with_identity();
    solve(w, dtau, None);
}
