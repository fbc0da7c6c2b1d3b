//! A scene along a trajectory: the accelerations and each enabled effect's generalized force
//! at N states in one call, so that analyses along a result (the shaking of a run, where its
//! torques saturate) run here rather than in a per-sample loop from Python.
//!
//! The samples are independent, so [`along`] splits them into contiguous chunks, one per
//! thread, each with its own [`Dynamics`] (its own workspaces): every sample is computed by
//! the same arithmetic from the same inputs, so the result is the same bits whatever the
//! thread count. Scenes with a callback torque (a Python function: it needs the
//! interpreter, and its errors are kept per thread) run on the calling thread only.
use std::sync::atomic::{AtomicBool, Ordering};

use super::Dynamics;
use crate::effects::{Disabled, Effect, TorqueLaw};
use crate::model::Model;
use crate::support::alloc::try_zeros_vec;
use crate::support::error::{Error, Result};

/// Fewer samples per thread than this run on fewer threads (a thread's start and its
/// workspaces cost about as much as this many samples of a small model).
const MIN_SAMPLES_PER_THREAD: usize = 64;

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

/// [`Dynamics::along`] of `model` with `effects` (minus `disabled`) on up to `threads`
/// threads (the calling thread one of them): the same result, bit for bit, whatever
/// `threads`. Ctrl-C (the calling thread's interrupt poller) stops every thread.
#[allow(clippy::too_many_arguments)]
pub fn along(
    model: &Model,
    effects: &[Effect],
    disabled: Disabled,
    (t, q, v): (&[f64], &[f64], &[f64]),
    accelerations: bool,
    forces: bool,
    threads: usize,
) -> Result<Along> {
    if threads == 0 {
        return Err(Error::arg("threads", "a thread count >= 1", "0"));
    }
    let mut sys = Dynamics::try_new(model, effects, disabled)?;
    let calls_back = effects
        .iter()
        .any(|e| matches!(e, Effect::Torque(x) if matches!(x.law, TorqueLaw::Function(_))));
    let n = t.len();
    let threads = match calls_back {
        true => 1,
        false => threads.min(n / MIN_SAMPLES_PER_THREAD).max(1),
    };
    let mut out = sys.along_output(t, q, v, accelerations, forces)?;
    let nv = model.nv;
    let chunk = n.div_ceil(threads).max(1);
    let width = (chunk * nv).max(1);
    // Each thread's rows of the accelerations and of every effect's forces.
    let mut acc_parts: Vec<&mut [f64]> = match accelerations {
        true => out.accelerations.chunks_mut(width).collect(),
        false => (0..threads).map(|_| <&mut [f64]>::default()).collect(),
    };
    let mut force_parts: Vec<Vec<&mut [f64]>> = (0..threads).map(|_| Vec::new()).collect();
    for f in out.forces.iter_mut() {
        for (part, rows) in force_parts.iter_mut().zip(f.chunks_mut(width)) {
            part.push(rows);
        }
    }
    let stop = AtomicBool::new(false);
    let mut results: Vec<Result<()>> = Vec::with_capacity(threads);
    std::thread::scope(|s| {
        let mut handles = Vec::new();
        let mut parts = acc_parts.drain(..).zip(force_parts.drain(..)).enumerate();
        let first = parts.next();
        for (c, (acc, mut fs)) in parts {
            let stop = &stop;
            handles.push(s.spawn(move || {
                let mut sys = Dynamics::try_new(model, effects, disabled)?;
                sys.along_rows(c * chunk, (t, q, v), acc, &mut fs, stop, false)
            }));
        }
        if let Some((_, (acc, mut fs))) = first {
            results.push(sys.along_rows(0, (t, q, v), acc, &mut fs, &stop, true));
        }
        for h in handles {
            results.push(h.join().unwrap_or_else(|_| {
                Err(Error::Numerical(
                    "a thread of the analysis along the trajectory panicked".into(),
                ))
            }));
        }
    });
    // The first chunk that failed is the first failing sample's: the serial error. Ctrl-C
    // stops every chunk; any of them says so.
    match results.into_iter().find(|r| r.is_err()) {
        Some(Err(e)) => Err(e),
        _ => Ok(out),
    }
}

impl Dynamics<'_> {
    /// With `accelerations`, the accelerations, and with `forces`, every enabled effect's
    /// force, at the states `(t[k], q[k], v[k])`; `q` is N × nq and `v` N × nv, row after
    /// row. Ctrl-C is heard between samples. A sample whose effects or dynamics fail, or
    /// give a value that is not finite, is an error naming it.
    pub fn along(
        &mut self,
        t: &[f64],
        q: &[f64],
        v: &[f64],
        accelerations: bool,
        forces: bool,
    ) -> Result<Along> {
        let mut out = self.along_output(t, q, v, accelerations, forces)?;
        let mut fs: Vec<&mut [f64]> = out.forces.iter_mut().map(|f| &mut f[..]).collect();
        let stop = AtomicBool::new(false);
        self.along_rows(0, (t, q, v), &mut out.accelerations, &mut fs, &stop, true)?;
        drop(fs);
        Ok(out)
    }

    /// The output of [`Dynamics::along`], zeroed, after checking the inputs' sizes.
    fn along_output(
        &self,
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
        let labels = match forces {
            true => self.effects.labels(),
            false => Vec::new(),
        };
        let rows = if accelerations { n * nv } else { 0 };
        Ok(Along {
            samples: n,
            accelerations: try_zeros_vec(rows, "accelerations along the trajectory")?,
            forces: (0..labels.len())
                .map(|_| try_zeros_vec(n * nv, "effect forces along the trajectory"))
                .collect::<Result<_>>()?,
            labels,
        })
    }

    /// Samples `k0 ..` (as many as `acc` or the forces' rows hold) into `acc` (empty: not
    /// asked for) and `forces` (one slice per effect; empty: not asked for). `main`: the
    /// calling thread, which hears Ctrl-C and tells the others through `stop`.
    fn along_rows(
        &mut self,
        k0: usize,
        (t, q, v): (&[f64], &[f64], &[f64]),
        acc: &mut [f64],
        forces: &mut [&mut [f64]],
        stop: &AtomicBool,
        main: bool,
    ) -> Result<()> {
        let (nq, nv) = (self.model.nq, self.model.nv);
        let rows = match (acc.is_empty(), forces.first()) {
            (false, _) => acc.len() / nv.max(1),
            (true, Some(f)) => f.len() / nv.max(1),
            (true, None) => 0,
        };
        let ne = forces.len();
        let mut row = vec![0.0; ne * nv];
        for i in 0..rows {
            let what = "the scene along a trajectory";
            if main {
                if let Err(e) = crate::support::interrupt::check(what) {
                    stop.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            } else if stop.load(Ordering::Relaxed) {
                return Err(Error::Interrupted(what.into()));
            }
            let k = k0 + i;
            let (qk, vk) = (&q[k * nq..(k + 1) * nq], &v[k * nv..(k + 1) * nv]);
            let at = |e: String| Error::Numerical(format!("sample {k} (t = {}): {e}", t[k]));
            if !acc.is_empty() {
                let a = &mut acc[i * nv..(i + 1) * nv];
                self.accelerations(t[k], qk, vk, a).map_err(at)?;
                if a.iter().any(|x| !x.is_finite()) {
                    return Err(at("the accelerations are not finite".into()));
                }
            }
            if ne > 0 {
                self.effect_forces(t[k], qk, vk, &mut row).map_err(at)?;
                if row.iter().any(|x| !x.is_finite()) {
                    return Err(at("an effect's force is not finite".into()));
                }
                for (e, f) in forces.iter_mut().enumerate() {
                    f[i * nv..(i + 1) * nv].copy_from_slice(&row[e * nv..(e + 1) * nv]);
                }
            }
        }
        Ok(())
    }
}
