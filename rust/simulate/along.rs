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
use crate::dynamics::link_shaking::{link_rates, shaking_of_links};
use crate::effects::{Disabled, Effect, TorqueLaw};
use crate::io::scene::Scene;
use crate::kinematics;
use crate::model::Model;
use crate::support::alloc::try_zeros_vec;
use crate::support::args::Arg;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Vec3, Vec6};

/// Fewer samples per thread than this run on fewer threads (a thread's start and its
/// workspaces cost about as much as this many samples of a small model).
const MIN_SAMPLES_PER_THREAD: usize = 64;

/// The scene at N states, what was asked for: `accelerations` (N × nv, row after row; empty
/// when not asked for), each enabled effect's generalized force (`forces[k]`: N × nv for
/// effect `labels[k]`; none when not asked for) and the shaking force and moment at those
/// accelerations (`shaking`: N × 6, `[force; moment]` per row, world axes; empty when not
/// asked for).
#[derive(Debug, Clone, Default)]
pub struct Along {
    pub samples: usize,
    pub accelerations: Vec<f64>,
    pub labels: Vec<String>,
    pub forces: Vec<Vec<f64>>,
    pub shaking: Vec<f64>,
}

/// What [`along`] computes: the accelerations, every enabled effect's force, and the
/// shaking force and moment about a world point (`reactions::shaking`, at the scene's
/// accelerations: folded into the same pass, so the samples are walked once).
#[derive(Debug, Clone, Copy, Default)]
pub struct Asked {
    pub accelerations: bool,
    pub forces: bool,
    pub shaking: Option<Vec3>,
}

/// Samples between two looks for Ctrl-C (the calling thread's poller, the others' `stop`).
const POLL_EVERY: usize = 16;

/// One thread's rows of the output (empty slices: not asked for).
struct Part<'s> {
    acc: &'s mut [f64],
    forces: Vec<&'s mut [f64]>,
    shaking: &'s mut [f64],
}

/// [`Dynamics::along`] of `model` with `effects` (minus `disabled`) on up to `threads`
/// threads (the calling thread one of them): the same result, bit for bit, whatever
/// `threads`. Ctrl-C (the calling thread's interrupt poller) stops every thread.
pub fn along(
    model: &Model,
    effects: &[Effect],
    disabled: Disabled,
    (t, q, v): (&[f64], &[f64], &[f64]),
    asked: Asked,
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
    let mut out = sys.along_output(t, q, v, asked)?;
    let nv = model.nv;
    let chunk = n.div_ceil(threads).max(1);
    // Each thread's rows of the accelerations, of every effect's forces and of the shaking.
    let rows_of = |x, w| split(x, chunk * w, threads);
    let mut parts: Vec<Part<'_>> = rows_of(&mut out.accelerations, nv)
        .into_iter()
        .zip(rows_of(&mut out.shaking, 6))
        .map(|(acc, shaking)| Part {
            acc,
            forces: Vec::new(),
            shaking,
        })
        .collect();
    for f in out.forces.iter_mut() {
        for (part, rows) in parts.iter_mut().zip(f.chunks_mut((chunk * nv).max(1))) {
            part.forces.push(rows);
        }
    }
    let about = asked.shaking;
    let stop = AtomicBool::new(false);
    let mut results: Vec<Result<()>> = Vec::with_capacity(threads);
    std::thread::scope(|s| {
        let mut handles = Vec::new();
        let mut parts = parts.drain(..).enumerate();
        let first = parts.next();
        for (c, mut part) in parts {
            let stop = &stop;
            handles.push(s.spawn(move || {
                let mut sys = Dynamics::try_new(model, effects, disabled)?;
                sys.along_rows(c * chunk, (t, q, v), &mut part, about, stop, false)
            }));
        }
        if let Some((_, mut part)) = first {
            results.push(sys.along_rows(0, (t, q, v), &mut part, about, &stop, true));
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

/// A caller's request for a scene along its samples, read and checked: the samples `t`
/// (N,), `q` (N, nq), `v` (N, nv), the families `disable`d (the caller's, else the scene's)
/// and the thread count (`None`: one per core). Read while the caller's objects are at
/// hand, then [`SceneAlong::run`] with the interpreter released.
pub struct SceneAlong {
    states: [Vec<f64>; 3],
    disabled: Disabled,
    asked: Asked,
    threads: usize,
}

impl SceneAlong {
    pub fn new<A: Arg>(
        scene: &Scene,
        (t, q, v): (&A, &A, &A),
        disable: Option<&A>,
        asked: Asked,
        threads: Option<usize>,
    ) -> std::result::Result<SceneAlong, A::Err> {
        let states = crate::model::args::samples(&scene.model, t, q, v)?;
        let disabled = crate::effects::args::disable(disable)?;
        let disabled = super::disabled(disabled, &scene.settings);
        let threads =
            threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        Ok(SceneAlong {
            states,
            disabled,
            asked,
            threads,
        })
    }

    /// [`along`] of `scene` (the one the request was read against).
    pub fn run(&self, scene: &Scene) -> Result<Along> {
        let [t, q, v] = &self.states;
        let (model, effects, asked) = (&*scene.model, &scene.effects[..], self.asked);
        along(
            model,
            effects,
            self.disabled,
            (t, q, v),
            asked,
            self.threads,
        )
    }
}

impl Asked {
    pub fn new(accelerations: bool, forces: bool, shaking: Option<Vec3>) -> Asked {
        Asked {
            accelerations,
            forces,
            shaking,
        }
    }
}

impl Along {
    /// The shaking force and moment apart, each N × 3.
    pub fn shaking_parts(&self) -> [Vec<f64>; 2] {
        let rows = self.shaking.chunks_exact(6);
        let part =
            |r: std::ops::Range<usize>| rows.clone().flat_map(move |x| x[r.clone()].to_vec());
        [part(0..3).collect(), part(3..6).collect()]
    }
}

/// `x` in `threads` parts of `width` entries (the last ones shorter or empty).
fn split(x: &mut [f64], width: usize, threads: usize) -> Vec<&mut [f64]> {
    let mut p: Vec<&mut [f64]> = x.chunks_mut(width.max(1)).collect();
    p.resize_with(threads, Default::default);
    p
}

impl Dynamics<'_> {
    /// With `accelerations`, the accelerations, and with `forces`, every enabled effect's
    /// force, at the states `(t[k], q[k], v[k])`; `q` is N × nq and `v` N × nv, row after
    /// row. Ctrl-C is heard between samples. A sample whose effects or dynamics fail, or
    /// give a value that is not finite, is an error naming it.
    pub fn along(&mut self, t: &[f64], q: &[f64], v: &[f64], asked: Asked) -> Result<Along> {
        let mut out = self.along_output(t, q, v, asked)?;
        let mut part = Part {
            acc: &mut out.accelerations,
            forces: out.forces.iter_mut().map(|f| &mut f[..]).collect(),
            shaking: &mut out.shaking,
        };
        let stop = AtomicBool::new(false);
        self.along_rows(0, (t, q, v), &mut part, asked.shaking, &stop, true)?;
        Ok(out)
    }

    /// The output of [`Dynamics::along`], zeroed, after checking the inputs' sizes.
    fn along_output(&self, t: &[f64], q: &[f64], v: &[f64], asked: Asked) -> Result<Along> {
        let (nq, nv, n) = (self.model.nq, self.model.nv, t.len());
        if q.len() != n * nq || v.len() != n * nv {
            return Err(Error::arg(
                "t, q, v",
                format!("N times, N × {nq} positions and N × {nv} speeds"),
                format!("{n} times, {} positions, {} speeds", q.len(), v.len()),
            ));
        }
        let labels = match asked.forces {
            true => self.effects.labels(),
            false => Vec::new(),
        };
        let rows = if asked.accelerations { n * nv } else { 0 };
        let shaking = if asked.shaking.is_some() { n * 6 } else { 0 };
        Ok(Along {
            samples: n,
            accelerations: try_zeros_vec(rows, "accelerations along the trajectory")?,
            forces: (0..labels.len())
                .map(|_| try_zeros_vec(n * nv, "effect forces along the trajectory"))
                .collect::<Result<_>>()?,
            labels,
            shaking: try_zeros_vec(shaking, "shaking along the trajectory")?,
        })
    }

    /// Samples `k0 ..` (as many as `acc` or the forces' rows hold) into `acc` (empty: not
    /// asked for) and `forces` (one slice per effect; empty: not asked for). `main`: the
    /// calling thread, which hears Ctrl-C and tells the others through `stop`.
    fn along_rows(
        &mut self,
        k0: usize,
        (t, q, v): (&[f64], &[f64], &[f64]),
        part: &mut Part<'_>,
        about: Option<Vec3>,
        stop: &AtomicBool,
        main: bool,
    ) -> Result<()> {
        let (nq, nv) = (self.model.nq, self.model.nv);
        let rows = match (part.acc.is_empty(), part.forces.first()) {
            (false, _) => part.acc.len() / nv.max(1),
            (true, Some(f)) => f.len() / nv.max(1),
            (true, None) => part.shaking.len() / 6,
        };
        let ne = part.forces.len();
        let mut row = vec![0.0; ne * nv];
        // The shaking needs the accelerations even when they are not returned, and the links'
        // motion at the sample: the loop solver's (it has just moved its links there), else
        // its own, built once per thread; the links' twist rates in `rates`.
        let shakes = about.is_some();
        let mut own_acc = vec![0.0; if shakes { nv } else { 0 }];
        let nl = if shakes { self.model.links.len() } else { 0 };
        let mut own_links = vec![kinematics::LinkState::default(); nl];
        let mut rates = vec![Vec6::zeros(); nl];
        for i in 0..rows {
            let what = "the scene along a trajectory";
            // Every `POLL_EVERY` samples: the poller reads a clock (tens of ns, a few percent
            // of a small model's sample), and Ctrl-C is still heard within microseconds.
            let poll = i % POLL_EVERY == 0;
            if poll && main {
                if let Err(e) = crate::support::interrupt::check(what) {
                    stop.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            } else if poll && stop.load(Ordering::Relaxed) {
                return Err(Error::Interrupted(what.into()));
            }
            let k = k0 + i;
            let (qk, vk) = (&q[k * nq..(k + 1) * nq], &v[k * nv..(k + 1) * nv]);
            let at = |e: String| Error::Numerical(format!("sample {k} (t = {}): {e}", t[k]));
            if !part.acc.is_empty() || about.is_some() {
                let a = match part.acc.is_empty() {
                    false => &mut part.acc[i * nv..(i + 1) * nv],
                    true => &mut own_acc[..],
                };
                self.accelerations(t[k], qk, vk, a).map_err(at)?;
                if a.iter().any(|x| !x.is_finite()) {
                    return Err(at("the accelerations are not finite".into()));
                }
                if let Some(o) = &about {
                    let links = match self.loops.as_ref() {
                        Some(solver) => &solver.kin.links[..],
                        None => {
                            kinematics::frames(self.model, qk, &mut own_links);
                            kinematics::velocities(self.model, qk, vk, &mut own_links);
                            &own_links[..]
                        }
                    };
                    link_rates(self.model, links, a, &mut rates);
                    let (f, m) = shaking_of_links(self.model, links, &rates, o);
                    let out = &mut part.shaking[i * 6..(i + 1) * 6];
                    out[..3].copy_from_slice(f.as_slice());
                    out[3..].copy_from_slice(m.as_slice());
                }
            }
            if ne > 0 {
                self.effect_forces(t[k], qk, vk, &mut row).map_err(at)?;
                if row.iter().any(|x| !x.is_finite()) {
                    return Err(at("an effect's force is not finite".into()));
                }
                for (e, f) in part.forces.iter_mut().enumerate() {
                    f[i * nv..(i + 1) * nv].copy_from_slice(&row[e * nv..(e + 1) * nv]);
                }
            }
        }
        Ok(())
    }
}
