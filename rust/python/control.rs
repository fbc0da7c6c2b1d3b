//! `_Simulator`: the stepping simulator (`crate::control`), converted; `pointmass_dyn.Simulator`
//! wraps it.
use crate::python::Obj;
use std::sync::{Mutex, MutexGuard};

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
    // A class must be `Sync`; the effects' laws are `Send` only. Uncontended: one call at a time.
    inner: Mutex<OwnedSimulator>,
}

impl PySimulator {
    fn lock(&self) -> MutexGuard<'_, OwnedSimulator> {
        // A panic cannot leave it poisoned mid-update in a way we could repair: take it as is.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
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
        })
    }

    fn set_control(&self, u: &Obj) -> PyResult<()> {
        self.lock().with_mut(|s| s.set_control_arg(u))
    }

    fn set_state(&self, q: &Obj, v: &Obj) -> PyResult<()> {
        self.lock().with_mut(|s| s.set_state_arg(q, v))
    }

    /// Advances to `target` with the interpreter released; returns None, or the failure's
    /// message (the run then stays where it failed). A Python callback that raised is
    /// re-raised.
    fn advance(&self, py: Python<'_>, target: f64) -> PyResult<Option<String>> {
        let run = |sim: &mut Simulator<'_>| {
            let r = py.detach(|| sim.advance(target));
            r.map(|r| r.err().map(|s| s.describe(sim.t())))
        };
        callbacks(py, || self.lock().with_mut(run))
    }

    /// Everything so far, as `simulate_scene` returns it.
    fn trajectory(&self, py: Python<'_>) -> PyResult<PyRunResult> {
        let traj = self.lock().with(|s| s.trajectory());
        Ok(PyRunResult::new(py, traj, None))
    }

    /// The actuators' joint torques now (nv): the torque control plus the scene's torques.
    fn joint_torques<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let tau = self.lock().with_mut(|s| s.torques_now()).py(py)?;
        Ok(to_array1(py, &tau).into_any())
    }

    /// IMU readings now, (n, 6): specific force then angular velocity, sensor axes; each IMU
    /// `(body index, position (3,), rotation (3, 3))` in the body's frame.
    fn imu<'py>(&self, py: Python<'py>, imus: &Obj) -> PyResult<Obj<'py>> {
        let (out, n) = self.lock().with_mut(|s| s.imu_arg(imus))?;
        to_array(py, out, &[n, 6])
    }
}

impl PySimulator {
    fn read<R>(&self, f: impl for<'m> FnOnce(&Simulator<'m>) -> R) -> R {
        self.lock().with(f)
    }
}

super::getters!(PySimulator.read {
    t: f64 = |s, py| s.t(),
    nq: usize = |s, py| s.nq(),
    control_period: f64 = |s, py| s.period(),
    method: &'static str = |s, py| s.method().name(),
    control_len: usize = |s, py| s.control_len(),
    /// The state `[q; v]` (a copy).
    y: Obj<'py> = |s, py| to_array1(py, s.y()).into_any(),
    control: Option<Obj<'py>> = |s, py| s.control().map(|u| to_array1(py, u).into_any()),
});
