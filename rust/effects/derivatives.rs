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
use crate::support::spatial::{Vec3, Vec6};
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

#[cfg(test)]
mod tests {
    //! Each analytic law against central differences of its own `apply`, including the
    //! series branches (a ball spring near its rest, ball friction near rest).
    use super::super::{Damper, Effect, Friction, JointRef, PerJoint, Spring};
    use super::*;
    use crate::joint::Joint;
    use crate::model::body::RigidBody;
    use crate::support::spatial::{Mat3, Placement};

    fn model() -> Model {
        let mut m = Model::new();
        let b = RigidBody::new(1.0, Vec3::new(0.1, 0.0, 0.0), Mat3::identity() * 0.02).unwrap();
        let place = Placement::new(Mat3::identity(), Vec3::new(0.2, 0.0, 0.0));
        m.add_body(
            b,
            Joint::revolute(Vec3::z()).unwrap(),
            None,
            Placement::identity(),
            Some("r".into()),
            None,
        )
        .unwrap();
        m.add_body(b, Joint::Spherical, Some(0), place, Some("s".into()), None)
            .unwrap();
        m
    }

    /// `(analytic, numerical)` `∂τ/∂q`, `∂τ/∂v` of one effect at `(q, v)`.
    fn both(model: &Model, e: &Effect, q: &[f64], v: &[f64]) -> [(DMatrix<f64>, DMatrix<f64>); 2] {
        let nv = model.nv;
        let mut law = e.build(model).unwrap();
        let cx = Context {
            model,
            t: 0.0,
            q,
            v,
        };
        let (mut aq, mut av) = (DMatrix::zeros(nv, nv), DMatrix::zeros(nv, nv));
        assert!(law.add_derivatives(&cx, &mut aq, &mut av).unwrap());
        let mut probe = Probe::new(model);
        let (mut nq, mut nvm) = (DMatrix::zeros(nv, nv), DMatrix::zeros(nv, nv));
        let (mut qp, mut d, mut vp) = (q.to_vec(), vec![0.0; nv], v.to_vec());
        let (mut fp, mut fm) = (vec![0.0; nv], vec![0.0; nv]);
        let h = 1e-6;
        for c in 0..nv {
            for (s, out) in [(1.0, &mut fp), (-1.0, &mut fm)] {
                d[c] = s * h;
                integrate(model, q, &d, &mut qp);
                let at = Context { q: &qp, ..cx };
                generalized_force(&mut probe, law.as_mut(), &at, out).unwrap();
            }
            d[c] = 0.0;
            for r in 0..nv {
                nq[(r, c)] = (fp[r] - fm[r]) / (2.0 * h);
            }
            for (s, out) in [(1.0, &mut fp), (-1.0, &mut fm)] {
                vp[c] = v[c] + s * h;
                let at = Context { v: &vp, ..cx };
                generalized_force(&mut probe, law.as_mut(), &at, out).unwrap();
            }
            vp[c] = v[c];
            for r in 0..nv {
                nvm[(r, c)] = (fp[r] - fm[r]) / (2.0 * h);
            }
        }
        [(aq, nq), (av, nvm)]
    }

    #[test]
    fn analytic_effect_derivatives_match_central_differences() {
        let m = model();
        let s = 0.3f64.sin();
        let turned = [0.6 * s, -0.3 * s, 0.1 * s, 0.3f64.cos()];
        let n = turned.iter().map(|x| x * x).sum::<f64>().sqrt();
        let states: [(Vec<f64>, Vec<f64>); 3] = [
            // General, near rest (ball spring and ball friction series), far from rest.
            (
                vec![
                    0.4,
                    turned[0] / n,
                    turned[1] / n,
                    turned[2] / n,
                    turned[3] / n,
                ],
                vec![0.7, 0.5, -0.4, 0.2],
            ),
            (
                vec![0.1, 1e-6, 0.0, 0.0, 1.0],
                vec![1e-9, 1e-9, -2e-9, 1e-9],
            ),
            (vec![-2.0, 0.0, 0.9, 0.0, 0.3], vec![-3.0, 2.0, 1.0, -1.5]),
        ];
        let all = Some(vec![JointRef::Index(0), JointRef::Index(1)]);
        let effects = [
            Effect::Spring(Spring::new(None, all.clone(), PerJoint::All(2.5), None).unwrap()),
            Effect::Damper(Damper::new(None, all.clone(), PerJoint::All(0.7)).unwrap()),
            Effect::Friction(Friction::new(None, all, PerJoint::All(0.4), Some(0.05)).unwrap()),
        ];
        for (q, v) in &states {
            for e in &effects {
                for (k, (a, n)) in both(&m, e, q, v).iter().enumerate() {
                    let scale = a.amax().max(1.0);
                    let err = (a - n).amax();
                    assert!(err < 1e-6 * scale, "{e:?} {k} at {q:?}: {err}\n{a}\n{n}");
                }
            }
        }
    }
}
