//! A scene along a trajectory: the accelerations and each enabled effect's generalized force
//! at N states in one call, so that analyses along a result (the shaking of a run, where its
//! torques saturate) run here rather than in a per-sample loop from Python.
use super::Dynamics;
use crate::support::error::{Error, Result};

/// The scene at N states, what was asked for: `accelerations` (N × nv, row after row; empty
/// when not asked for) and each enabled effect's generalized force (`forces[k]`: N × nv for
/// effect `labels[k]`; none when not asked for).
#[derive(Debug, Clone, Default)]
pub struct Along {
    pub samples: usize,
    pub accelerations: Vec<f64>,
    pub labels: Vec<String>,
    pub forces: Vec<Vec<f64>>,
}

impl Dynamics<'_> {
    /// With `accelerations`, the accelerations, and with `forces`, every enabled effect's
    /// force, at the states `(t[k], q[k], v[k])`; `q` is N × nq and `v` N × nv, row after
    /// row. Ctrl-C is heard between samples. A sample whose effects or dynamics fail is an
    /// error naming it.
    pub fn along(
        &mut self,
        t: &[f64],
        q: &[f64],
        v: &[f64],
        accelerations: bool,
        forces: bool,
    ) -> Result<Along> {
        let (nq, nv, n) = (self.model.nq, self.model.nv, t.len());
        if q.len() != n * nq || v.len() != n * nv {
            return Err(Error::arg(
                "t, q, v",
                format!("N times, N × {nq} positions and N × {nv} speeds"),
                format!("{n} times, {} positions, {} speeds", q.len(), v.len()),
            ));
        }
        let labels = if forces {
            self.effects.labels()
        } else {
            Vec::new()
        };
        let ne = labels.len();
        let mut out = Along {
            samples: n,
            accelerations: crate::support::alloc::try_zeros_vec(
                n * nv,
                "accelerations along the trajectory",
            )?,
            forces: (0..ne)
                .map(|_| {
                    crate::support::alloc::try_zeros_vec(
                        n * nv,
                        "effect forces along the trajectory",
                    )
                })
                .collect::<Result<_>>()?,
            labels,
        };
        let mut row = vec![0.0; ne * nv];
        for k in 0..n {
            crate::support::interrupt::check("the scene along a trajectory")?;
            let (qk, vk) = (&q[k * nq..(k + 1) * nq], &v[k * nv..(k + 1) * nv]);
            let at = |e: String| Error::Numerical(format!("sample {k} (t = {}): {e}", t[k]));
            if accelerations {
                self.accelerations(t[k], qk, vk, &mut out.accelerations[k * nv..(k + 1) * nv])
                    .map_err(at)?;
            }
            if ne > 0 {
                self.effect_forces(t[k], qk, vk, &mut row).map_err(at)?;
                for (e, f) in out.forces.iter_mut().enumerate() {
                    f[k * nv..(k + 1) * nv].copy_from_slice(&row[e * nv..(e + 1) * nv]);
                }
            }
        }
        Ok(out)
    }
}
