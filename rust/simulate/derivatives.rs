//! Derivatives of the scene's equations of motion (docs/derivatives.md): the accelerations
//! `q̈ = FD(q, v, τ + τ_e(t, q, v))` with every enabled effect, differentiated as
//! `∂q̈/∂x = M⁻¹ (∂τ_e/∂x − ∂ID/∂x)` at `a = q̈` (the effects' part from
//! [`Effects::add_derivatives`](crate::effects::Effects::add_derivatives), gravity through
//! the base acceleration), and the state Jacobian `∂ẏ/∂y` for implicit integrators,
//! `y = [q; v]` in the coordinates of `q` (nq of them): `[[∂q̇/∂q, ∂q̇/∂v], [∂q̈/∂δ · ∂δ/∂q,
//! ∂q̈/∂v]]`. With closed loops the forward derivatives are those of the constrained
//! dynamics ([`crate::loops::constrained_derivatives`]); the inverse ones are refused (the
//! driving forces of a mechanism depend on which joints are actuated).
use super::dynamics::Dynamics;
use crate::effects::derivatives::EffectDerivatives;
use crate::effects::Context;
use crate::linalg::spd::product;
use crate::linalg::spd_inverse;
use crate::loops::{self, LoopDerivativeWork};
use crate::recursive::{self, tangent, DerivativeData};
use crate::support::error::Error;
use crate::support::spatial::Vec6;
use nalgebra::DMatrix;

/// Everything the derivatives of one scene's dynamics need, allocated once.
pub struct DerivativeWork {
    /// The recursions' derivatives; after [`Dynamics::derivatives`], `ddq_dq`, `ddq_dv` and
    /// `minv` hold the scene's `∂q̈/∂q`, `∂q̈/∂v`, `∂q̈/∂τ = M⁻¹`, `qdd` its accelerations.
    pub dd: DerivativeData,
    pub effects: EffectDerivatives,
    tau: Vec<f64>,
    wrenches: Vec<Vec6>,
    /// `∂τ_e/∂q − ∂ID/∂q`, `∂τ_e/∂v − ∂ID/∂v`.
    rq: DMatrix<f64>,
    rv: DMatrix<f64>,
    /// `∂δ/∂q` (nv × nq) and `∂q̈/∂q` in coordinates (nv × nq).
    tmap: DMatrix<f64>,
    ddq_dcoords: DMatrix<f64>,
    /// nv zeros: the joint forces of the state Jacobian (the effects' only).
    zeros: Vec<f64>,
    /// The cut joints' terms (models with loops only).
    loops: Option<Box<LoopDerivativeWork>>,
}

impl DerivativeWork {
    pub fn new(sys: &Dynamics<'_>) -> Self {
        let m = sys.model;
        let (nq, nv) = (m.nq, m.nv);
        DerivativeWork {
            dd: DerivativeData::new(m),
            effects: EffectDerivatives::new(m, &sys.effects),
            tau: vec![0.0; nv],
            wrenches: vec![Vec6::zeros(); m.links.len()],
            rq: DMatrix::zeros(nv, nv),
            rv: DMatrix::zeros(nv, nv),
            tmap: DMatrix::zeros(nv, nq),
            ddq_dcoords: DMatrix::zeros(nv, nq),
            zeros: vec![0.0; nv],
            loops: m
                .has_constraints()
                .then(|| Box::new(LoopDerivativeWork::new(m))),
        }
    }
}

impl Dynamics<'_> {
    /// `∂q̈/∂q` (tangent columns), `∂q̈/∂v`, `M⁻¹` of the scene's accelerations at
    /// `(t, q, v)` with the extra joint forces `tau` (length nv) on top of the effects'; into
    /// `w.dd.ddq_dq`, `w.dd.ddq_dv`, `w.dd.minv` (accelerations into `w.dd.qdd`). Which
    /// effects were differentiated numerically: `w.effects.numerical`. With closed loops,
    /// those of the constrained dynamics. Errors at a singular configuration, a locked
    /// mechanism, or when an effect fails.
    pub fn derivatives(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        w: &mut DerivativeWork,
    ) -> crate::support::error::Result<()> {
        let model = self.model;
        let cx = Context { model, t, q, v };
        w.tau.fill(0.0);
        let applied = self.effects.apply(&cx, &mut w.tau, &mut w.wrenches);
        let ext = if applied.map_err(Error::Numerical)? {
            Some(w.wrenches.as_slice())
        } else {
            None
        };
        for (a, b) in w.tau.iter_mut().zip(tau) {
            *a += b;
        }
        let g = self.effects.gravity;
        let dd = &mut w.dd;
        let mut qdd = std::mem::take(&mut dd.qdd);
        let mut fd =
            recursive::forward_dynamics(model, &mut self.data, q, v, &w.tau, &g, ext, &mut qdd);
        if let (Ok(()), Some(solver)) = (&fd, self.loops.as_mut()) {
            fd = loops::constrained_forward_dynamics(model, &mut self.data, solver, q, v, &mut qdd);
        }
        if fd.is_ok() {
            recursive::inverse_dynamics_derivatives(model, &mut self.data, dd, q, v, &qdd, &g);
        }
        dd.qdd = qdd;
        fd?; // typed: a singular configuration (or a locked mechanism) stays `Singular`
        w.rq.as_mut_slice().fill(0.0);
        w.rv.as_mut_slice().fill(0.0);
        self.effects
            .add_derivatives(&cx, &mut w.effects, &mut w.rq, &mut w.rv)
            .map_err(Error::Numerical)?;
        for (r, x) in w.rq.as_mut_slice().iter_mut().zip(dd.dtau_dq.as_slice()) {
            *r -= x;
        }
        for (r, x) in w.rv.as_mut_slice().iter_mut().zip(dd.dtau_dv.as_slice()) {
            *r -= x;
        }
        if let (Some(solver), Some(lw)) = (self.loops.as_mut(), w.loops.as_mut()) {
            loops::constrained_derivatives(
                model,
                solver,
                lw,
                q,
                v,
                &dd.qdd,
                &mut w.rq,
                &mut w.rv,
                &mut dd.minv,
            );
            dd.ddq_dq.copy_from(&w.rq);
            dd.ddq_dv.copy_from(&w.rv);
            return Ok(());
        }
        dd.minv.as_mut_slice().copy_from_slice(dd.mass.as_slice());
        spd_inverse(
            &mut dd.minv,
            &mut dd.ddq_dv,
            &mut dd.inv_diag,
            &mut dd.spd_scratch,
        )
        .map_err(|k| {
            Error::Singular(format!(
                "the mass matrix is not positive definite (pivot {k})"
            ))
        })?;
        product(&mut dd.ddq_dq, 1.0, &dd.minv, &w.rq);
        product(&mut dd.ddq_dv, 1.0, &dd.minv, &w.rv);
        Ok(())
    }

    /// `∂τ/∂q` (tangent columns), `∂τ/∂v`, `M` of the joint forces that give accelerations
    /// `a` at `(t, q, v)` on top of the enabled effects, `τ = ID(q, v, a) − τ_e(t, q, v)`:
    /// into `w.dd.dtau_dq`, `w.dd.dtau_dv`, `w.dd.mass` (the effects' part subtracted).
    pub fn inverse_derivatives(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        w: &mut DerivativeWork,
    ) -> crate::support::error::Result<()> {
        let model = self.model;
        if model.has_constraints() {
            return Err(Error::Numerical(format!(
                "the inverse dynamics derivatives are for trees: this model has {} closed loop(s) and {} coupling(s) (a mechanism's driving forces depend on which joints are actuated)",
                model.loops.len(),
                model.couplings.len()
            )));
        }
        let g = self.effects.gravity;
        recursive::inverse_dynamics_derivatives(model, &mut self.data, &mut w.dd, q, v, a, &g);
        w.rq.as_mut_slice().fill(0.0);
        w.rv.as_mut_slice().fill(0.0);
        let cx = Context { model, t, q, v };
        self.effects
            .add_derivatives(&cx, &mut w.effects, &mut w.rq, &mut w.rv)
            .map_err(Error::Numerical)?;
        for (d, x) in w.dd.dtau_dq.as_mut_slice().iter_mut().zip(w.rq.as_slice()) {
            *d -= x;
        }
        for (d, x) in w.dd.dtau_dv.as_mut_slice().iter_mut().zip(w.rv.as_slice()) {
            *d -= x;
        }
        Ok(())
    }

    /// The state Jacobian (see the module) into the row-major `jac`.
    pub fn state_jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        jac: &mut [f64],
        w: &mut DerivativeWork,
    ) -> Result<bool, String> {
        let model = self.model;
        let (nq, nv) = (model.nq, model.nv);
        let dim = nq + nv;
        let (q, v) = y.split_at(nq);
        let zeros = std::mem::take(&mut w.zeros);
        let r = self.derivatives(t, q, v, &zeros, w);
        w.zeros = zeros;
        r.map_err(|e| e.to_string())?;
        tangent::qdot_jacobian(model, q, v, jac);
        tangent::tangent_map(model, q, &mut w.tmap);
        w.ddq_dcoords.gemm(1.0, &w.dd.ddq_dq, &w.tmap, 0.0);
        for r in 0..nv {
            let (left, right) = jac[(nq + r) * dim..(nq + r + 1) * dim].split_at_mut(nq);
            for (c, x) in left.iter_mut().enumerate() {
                *x = w.ddq_dcoords[(r, c)];
            }
            for (c, x) in right.iter_mut().enumerate() {
                *x = w.dd.ddq_dv[(r, c)];
            }
        }
        Ok(true)
    }
}

/// A scene's derivatives as a caller gets them: three nv × nv matrices (forward: `∂q̈/∂q`,
/// `∂q̈/∂v`, `M⁻¹`; inverse: `∂τ/∂q`, `∂τ/∂v`, `M`), checked finite, and the labels of the
/// effects differentiated by central differences.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneDerivatives {
    pub dq: DMatrix<f64>,
    pub dv: DMatrix<f64>,
    pub third: DMatrix<f64>,
    pub numerical: Vec<String>,
}

impl Dynamics<'_> {
    /// [`Dynamics::derivatives`] with a workspace of its own (`tau`: zero if `None`); errors
    /// name `forward_dynamics_derivatives`.
    pub fn forward_derivatives(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        tau: Option<&[f64]>,
    ) -> crate::support::error::Result<SceneDerivatives> {
        const NAME: &str = "forward_dynamics_derivatives";
        let zeros = vec![0.0; self.model.nv];
        let tau = tau.unwrap_or(&zeros);
        crate::support::error::check_finite("tau", tau)?;
        let mut w = DerivativeWork::new(self);
        let r = self.derivatives(t, q, v, tau, &mut w);
        r.map_err(|e| e.in_arg(NAME))?;
        let dd = &mut w.dd;
        let m = [&mut dd.ddq_dq, &mut dd.ddq_dv, &mut dd.minv].map(std::mem::take);
        self.collect(NAME, ["dq", "dv", "dtau"], m, &w.effects.numerical)
    }

    /// [`Dynamics::inverse_derivatives`] with a workspace of its own; refused for a scene
    /// with closed loops or couplings (a mechanism's driving forces depend on which joints
    /// are actuated).
    pub fn inverse_derivatives_of(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &[f64],
    ) -> crate::support::error::Result<SceneDerivatives> {
        const NAME: &str = "inverse_dynamics_derivatives";
        let model = self.model;
        if model.has_constraints() {
            return Err(Error::arg(
                "scene",
                format!("a scene without closed loops or couplings for {NAME}"),
                format!(
                    "a model with {} loop(s) and {} coupling(s)",
                    model.loops.len(),
                    model.couplings.len()
                ),
            ));
        }
        crate::support::error::check_finite("a", a)?;
        let mut w = DerivativeWork::new(self);
        let r = self.inverse_derivatives(t, q, v, a, &mut w);
        r.map_err(|e| e.in_arg(NAME))?;
        let dd = &mut w.dd;
        let m = [&mut dd.dtau_dq, &mut dd.dtau_dv, &mut dd.mass].map(std::mem::take);
        self.collect(NAME, ["dq", "dv", "da"], m, &w.effects.numerical)
    }

    /// The three matrices checked finite (errors name `name['key']`) with the labels of the
    /// effects `numerical` marks.
    fn collect(
        &self,
        name: &str,
        keys: [&str; 3],
        m: [DMatrix<f64>; 3],
        numerical: &[bool],
    ) -> crate::support::error::Result<SceneDerivatives> {
        for (key, m) in keys.iter().zip(&m) {
            if m.iter().any(|x| !x.is_finite()) {
                // The index in C order, as the caller's array has it.
                crate::support::error::check_result(
                    &format!("{name}['{key}']"),
                    m.transpose().as_slice(),
                )?;
            }
        }
        let labels = self.effects.labels().into_iter().zip(numerical);
        let numerical = labels.filter(|(_, n)| **n).map(|(l, _)| l).collect();
        let [dq, dv, third] = m;
        Ok(SceneDerivatives {
            dq,
            dv,
            third,
            numerical,
        })
    }

    /// `∂ẏ/∂y` (row-major, (nq + nv)²) at `(t, y)`, checked finite; `None` where the system
    /// has none.
    pub fn checked_state_jacobian(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> crate::support::error::Result<Option<Vec<f64>>> {
        use crate::integrator::OdeSystem;
        let mut jac = vec![0.0; y.len() * y.len()];
        let filled = self.jacobian(t, y, &mut jac);
        let filled = filled.map_err(|m| Error::Numerical(format!("state_jacobian: {m}")))?;
        if !filled {
            return Ok(None);
        }
        crate::support::error::check_result("state_jacobian", &jac)?;
        Ok(Some(jac))
    }
}
