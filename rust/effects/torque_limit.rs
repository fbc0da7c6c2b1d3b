//! Actuator limits: a torque law whose output is clamped per speed, `τ_i = clamp(τ_raw,i,
//! −L_i, L_i)` (MuJoCo's `forcerange`, a URDF joint's `effort`). A wrapper around any torque
//! law, so constant, tabulated, PD and callback torques saturate alike; the derivatives are the
//! inner law's with the saturated rows zeroed (the clamp's slope there).
use super::{Context, ForceLaw, PerJoint};
use crate::support::error::{num, Error, Result};
use crate::support::spatial::Vec6;

/// How a torque effect is limited.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum TorqueLimit {
    /// `L` per speed of the selected joints (one number for all).
    Given(PerJoint),
    /// The model's `effort` (URDF `<limit effort>`), filled in when a scene is built.
    Effort,
}

impl TorqueLimit {
    /// `limit`: numbers > 0, inf allowed (no limit on that speed); NaN, 0 and negatives
    /// are refused, and the message says what is allowed.
    pub fn given(limit: PerJoint) -> Result<TorqueLimit> {
        const EXPECTED: &str = "numbers > 0, one or one per speed (inf: no limit on that speed)";
        let bad = |x: f64, at: String| Error::arg("limit", EXPECTED, format!("{}{at}", num(x)));
        match &limit {
            PerJoint::All(x) if !(*x > 0.0) => return Err(bad(*x, String::new())),
            PerJoint::Each(v) if v.is_empty() => return Err(Error::arg("limit", EXPECTED, "[]")),
            PerJoint::Each(v) => {
                if let Some(k) = v.iter().position(|x| !(*x > 0.0)) {
                    return Err(bad(v[k], format!(" at index {k}")));
                }
            }
            PerJoint::All(_) => {}
        }
        Ok(TorqueLimit::Given(limit))
    }
}

/// The clamped law: the inner law's forces are written into `raw`, then clamped into `tau`.
pub struct Saturated {
    inner: Box<dyn ForceLaw>,
    /// `(speed, L)` of the limited speeds.
    limits: Vec<(usize, f64)>,
    raw: Vec<f64>,
    dq: nalgebra::DMatrix<f64>,
    dv: nalgebra::DMatrix<f64>,
}

impl Saturated {
    /// `per_speed`: `L > 0` on each of the model's speeds (inf: unlimited).
    pub fn new(inner: Box<dyn ForceLaw>, per_speed: &[f64]) -> Saturated {
        let nv = per_speed.len();
        Saturated {
            inner,
            limits: per_speed
                .iter()
                .enumerate()
                .filter(|(_, l)| l.is_finite())
                .map(|(s, l)| (s, *l))
                .collect(),
            raw: vec![0.0; nv],
            dq: nalgebra::DMatrix::zeros(nv, nv),
            dv: nalgebra::DMatrix::zeros(nv, nv),
        }
    }
}

impl ForceLaw for Saturated {
    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        self.raw.fill(0.0);
        let wrote = self.inner.apply(cx, &mut self.raw, wrenches)?;
        for &(i, l) in &self.limits {
            self.raw[i] = self.raw[i].clamp(-l, l);
        }
        for (t, r) in tau.iter_mut().zip(&self.raw) {
            *t += r;
        }
        Ok(wrote)
    }

    fn reference_joints(&self) -> usize {
        self.inner.reference_joints()
    }
    fn hold_reference(&mut self, target: Option<&[f64]>) {
        self.inner.hold_reference(target)
    }

    fn add_derivatives(
        &mut self,
        cx: &Context<'_>,
        dq: &mut nalgebra::DMatrix<f64>,
        dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        self.dq.fill(0.0);
        self.dv.fill(0.0);
        if !self.inner.add_derivatives(cx, &mut self.dq, &mut self.dv)? {
            return Ok(false);
        }
        self.raw.fill(0.0);
        let mut w = [];
        // The raw forces decide which rows are clamped (a law that writes wrenches has no
        // analytic derivatives, so it never gets here with wrenches to write).
        self.inner.apply(cx, &mut self.raw, &mut w)?;
        for &(i, l) in &self.limits {
            if self.raw[i].abs() > l {
                self.dq.row_mut(i).fill(0.0);
                self.dv.row_mut(i).fill(0.0);
            }
        }
        *dq += &self.dq;
        *dv += &self.dv;
        Ok(true)
    }
}
