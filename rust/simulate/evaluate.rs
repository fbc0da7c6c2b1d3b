//! A scene's equations evaluated at one state and checked, as `effect_forces` and
//! `energies` return them.
use super::Dynamics;
use crate::support::error::{check_result, Error, Result};

impl Dynamics<'_> {
    /// The generalized force (nv) of each enabled effect at `(t, q, v)`, by its label.
    pub fn labelled_effect_forces(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<Vec<(String, Vec<f64>)>> {
        let nv = self.model.nv;
        let mut out = vec![0.0; self.effects.len() * nv];
        self.effect_forces(t, q, v, &mut out)
            .map_err(Error::Numerical)?;
        let labels = self.effects.labels();
        let force = |k: usize| out[k * nv..(k + 1) * nv].to_vec();
        let forces: Vec<_> = labels
            .into_iter()
            .enumerate()
            .map(|(k, l)| (l, force(k)))
            .collect();
        for (label, f) in &forces {
            check_result(&format!("effect_forces['{label}']"), f)?;
        }
        Ok(forces)
    }

    /// `kinetic`, the potential energy of each enabled conservative effect (gravity,
    /// springs) by its label, and their sum `total`.
    pub fn labelled_energies(&mut self, q: &[f64], v: &[f64]) -> Result<Vec<(String, f64)>> {
        let (kinetic, potentials) = self.energies(q, v);
        let mut out = vec![("kinetic".to_string(), kinetic)];
        out.extend(potentials);
        let total = out.iter().fold(0.0, |sum, (_, e)| sum + e);
        out.push(("total".to_string(), total));
        for (label, e) in &out {
            check_result(&format!("energies['{label}']"), &[*e])?;
        }
        Ok(out)
    }
}
