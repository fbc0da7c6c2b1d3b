//! Derivatives of the effects' generalized forces `τ_e(t, q, v)` (docs/derivatives.md): each
//! law's own analytic [`ForceLaw::add_derivatives`] where it has one (springs, point
//! springs, dampers, smooth friction, constant, tabulated and PD torques); otherwise (a
//! Python torque callback; external loads, wrenches whose generalized force goes through the
//! inverse dynamics) central differences of the law's generalized force, in the tangent
//! space, flagged in [`EffectDerivatives::numerical`]. Gravity rides on the dynamics' own
//! derivatives (the base acceleration), not here.
use super::{Context, Effects, Probe};
use crate::model::Model;
use crate::recursive::tangent::integrate;
use crate::spatial::{Vec3, Vec6};
use nalgebra::DMatrix;

/// Central-difference step relative to `1 + |x|`: `ε^(1/3)`, balancing the `h²` truncation
/// against the rounding of the difference.
const STEP: f64 = 6e-6;

/// Buffers of the effects' derivatives for one model.
pub struct EffectDerivatives {
    probe: Probe,
    q: Vec<f64>,
    v: Vec<f64>,
    delta: Vec<f64>,
    plus: Vec<f64>,
    minus: Vec<f64>,
    /// Per enabled effect (declaration order): whether the last call differentiated it
    /// numerically.
    pub numerical: Vec<bool>,
}

impl EffectDerivatives {
    pub fn new(model: &Model, effects: &Effects) -> Self {
        let (nq, nv) = (model.nq, model.nv);
        EffectDerivatives {
            probe: Probe::new(model),
            q: vec![0.0; nq],
            v: vec![0.0; nv],
            delta: vec![0.0; nv],
            plus: vec![0.0; nv],
            minus: vec![0.0; nv],
            numerical: vec![false; effects.len()],
        }
    }
}

/// One law's generalized force at `cx` into `out`: its joint forces plus the joint forces its
/// wrenches make, `−ID(q, 0, 0; wrenches)` (as [`Probe::forces`]).
fn generalized_force(
    probe: &mut Probe,
    law: &mut dyn super::ForceLaw,
    cx: &Context<'_>,
    out: &mut [f64],
) -> Result<(), String> {
    probe.tau.fill(0.0);
    probe.wrenches.fill(Vec6::zeros());
    let wrote = law.apply(cx, &mut probe.tau, &mut probe.wrenches)?;
    out.copy_from_slice(&probe.tau);
    if wrote {
        probe.inverse_at_rest(cx, &Vec3::zeros(), true);
        for (r, x) in out.iter_mut().zip(&probe.id_out) {
            *r -= x;
        }
    }
    Ok(())
}

impl Effects {
    /// Adds `∂τ_e/∂q` (tangent columns) and `∂τ_e/∂v` of every enabled effect in the
    /// right-hand side to `dq`, `dv` (nv × nv), analytically where the law can, otherwise by
    /// central differences (recorded in `w.numerical`).
    pub fn add_derivatives(
        &mut self,
        cx: &Context<'_>,
        w: &mut EffectDerivatives,
        dq: &mut DMatrix<f64>,
        dv: &mut DMatrix<f64>,
    ) -> Result<(), String> {
        let model = cx.model;
        let nv = model.nv;
        for (k, item) in self.items.iter_mut().enumerate() {
            w.numerical[k] = false;
            if !item.in_rhs || item.law.add_derivatives(cx, dq, dv)? {
                continue;
            }
            w.numerical[k] = true;
            w.v.copy_from_slice(cx.v);
            w.delta.fill(0.0);
            for c in 0..nv {
                // q ⊕ ±h e_c.
                let h = STEP;
                for (sign, out) in [(1.0, 0), (-1.0, 1)] {
                    w.delta[c] = sign * h;
                    integrate(model, cx.q, &w.delta, &mut w.q);
                    let at = Context { q: &w.q, ..*cx };
                    let buf = if out == 0 { &mut w.plus } else { &mut w.minus };
                    generalized_force(&mut w.probe, item.law.as_mut(), &at, buf)?;
                }
                w.delta[c] = 0.0;
                for r in 0..nv {
                    dq[(r, c)] += (w.plus[r] - w.minus[r]) / (2.0 * h);
                }
                let h = STEP * (1.0 + cx.v[c].abs());
                for (sign, out) in [(1.0, 0), (-1.0, 1)] {
                    w.v[c] = cx.v[c] + sign * h;
                    let at = Context { v: &w.v, ..*cx };
                    let buf = if out == 0 { &mut w.plus } else { &mut w.minus };
                    generalized_force(&mut w.probe, item.law.as_mut(), &at, buf)?;
                }
                w.v[c] = cx.v[c];
                for r in 0..nv {
                    dv[(r, c)] += (w.plus[r] - w.minus[r]) / (2.0 * h);
                }
            }
        }
        Ok(())
    }
}
