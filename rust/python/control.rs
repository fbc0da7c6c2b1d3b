//! `_Simulator`: the stepping simulator (`crate::control`), converted; `pointmass_dyn.Simulator`
//! wraps it.
use crate::python::Obj;
use std::ops::{Deref, DerefMut};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, TryLockError};

use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{to_array, to_array1};
use super::errors::IntoPyResult;
use super::scene::PyScene;
use super::simulate::callbacks;
use super::trajectory::PyRunResult;
use crate::control::{OwnedSimulator, Simulator};

#[pyclass(name = "_Simulator", module = "pointmass_dyn._core")]
pub struct PySimulator {
    // A class must be `Sync`; the effects' laws are `Send` only. One call at a time.
    inner: Mutex<OwnedSimulator>,
    /// The thread inside a call ([`this_thread`]), 0 when none.
    holder: AtomicUsize,
}

thread_local!(static THREAD_TOKEN: u8 = const { 0 });

/// A number unique to the calling thread while it lives (its token's address).
fn this_thread() -> usize {
    THREAD_TOKEN.with(|t| t as *const u8 as usize)
}

/// The simulator, held by one call; clears the holder when the call ends.
struct Held<'a> {
    guard: MutexGuard<'a, OwnedSimulator>,
    holder: &'a AtomicUsize,
}

impl Drop for Held<'_> {
    fn drop(&mut self) {
        self.holder.store(0, Ordering::Release);
    }
}

impl Deref for Held<'_> {
    type Target = OwnedSimulator;
    fn deref(&self) -> &OwnedSimulator {
        &self.guard
    }
}

impl DerefMut for Held<'_> {
    fn deref_mut(&mut self) -> &mut OwnedSimulator {
        &mut self.guard
    }
}

impl PySimulator {
    /// The simulator for one call. Busy with another thread's call: waits for it with the
    /// interpreter released (that call's Python torque laws need it; waiting while holding it
    /// deadlocked both threads). Busy with this thread's own call (a torque law of `advance`
    /// using its simulator): refused, as waiting could never end.
    fn lock(&self, py: Python<'_>) -> PyResult<Held<'_>> {
        loop {
            let guard = match self.inner.try_lock() {
                Ok(g) => g,
                // A panic cannot leave it poisoned mid-update in a way we could repair.
                Err(TryLockError::Poisoned(e)) => e.into_inner(),
                Err(TryLockError::WouldBlock) => {
                    if self.holder.load(Ordering::Acquire) == this_thread() {
                        return Err(crate::support::error::Error::arg(
                            "Simulator",
                            "one call at a time (a torque law or event of its step cannot use \
                             the simulator it is driving)",
                            "a call while it is already in a call on this thread",
                        )
                        .into());
                    }
                    py.detach(|| drop(self.inner.lock()));
                    continue;
                }
            };
            self.holder.store(this_thread(), Ordering::Release);
            return Ok(Held {
                guard,
                holder: &self.holder,
            });
        }
    }
}

#[pymethods]
impl PySimulator {
    // The keywords: `control::args::KEYS`, all read in the core (`pointmass_dyn.Simulator`
    // passes them).
    #[new]
    #[pyo3(signature = (scene, **settings))]
    fn new(scene: PyRef<'_, PyScene>, settings: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let inner = OwnedSimulator::from_call(&scene.inner, settings.map(|d| d.as_any()))?;
        Ok(PySimulator {
            inner: Mutex::new(inner),
            holder: AtomicUsize::new(0),
        })
    }

    fn set_control(&self, py: Python<'_>, u: &Obj) -> PyResult<()> {
        self.lock(py)?.with_mut(|s| s.set_control_arg(u))
    }

    fn set_state(&self, py: Python<'_>, q: &Obj, v: &Obj) -> PyResult<()> {
        self.lock(py)?.with_mut(|s| s.set_state_arg(q, v))
    }

    /// Advances to `target` with the interpreter released; returns None, or the failure's
    /// message (the run then stays where it failed). A Python callback that raised is
    /// re-raised.
    fn advance(&self, py: Python<'_>, target: f64) -> PyResult<Option<String>> {
        let run = |sim: &mut Simulator<'_>| {
            let r = py.detach(|| sim.advance(target));
            r.map(|r| r.err().map(|s| s.describe(sim.t())))
        };
        let mut sim = self.lock(py)?;
        callbacks(py, || sim.with_mut(run))
    }

    /// Everything so far, as `simulate_scene` returns it.
    fn trajectory(&self, py: Python<'_>) -> PyResult<PyRunResult> {
        let traj = self.lock(py)?.with(|s| s.trajectory());
        Ok(PyRunResult::new(py, traj, None))
    }

    /// The actuators' joint torques now (nv): the torque control plus the scene's torques.
    fn joint_torques<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let tau = self.lock(py)?.with_mut(|s| s.torques_now()).py(py)?;
        Ok(to_array1(py, &tau).into_any())
    }

    /// IMU readings now, (n, 6): specific force then angular velocity, sensor axes; each IMU
    /// `(body index, position (3,), rotation (3, 3))` in the body's frame.
    fn imu<'py>(&self, py: Python<'py>, imus: &Obj) -> PyResult<Obj<'py>> {
        let (out, n) = self.lock(py)?.with_mut(|s| s.imu_arg(imus))?;
        to_array(py, out, &[n, 6])
    }
}

impl PySimulator {
    fn read<R>(&self, py: Python<'_>, f: impl for<'m> FnOnce(&Simulator<'m>) -> R) -> PyResult<R> {
        Ok(self.lock(py)?.with(f))
    }
}

super::getters!(PySimulator.read {
    t: PyResult<f64> = |s, py| s.t(),
    nq: PyResult<usize> = |s, py| s.nq(),
    control_period: PyResult<f64> = |s, py| s.period(),
    method: PyResult<&'static str> = |s, py| s.method().name(),
    control_len: PyResult<usize> = |s, py| s.control_len(),
    /// The state `[q; v]` (a copy).
    y: PyResult<Obj<'py>> = |s, py| to_array1(py, s.y()).into_any(),
    control: PyResult<Option<Obj<'py>>> = |s, py| s.control().map(|u| to_array1(py, u).into_any()),
});
