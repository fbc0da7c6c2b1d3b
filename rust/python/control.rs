//! `_Simulator`: the stepping simulator (`crate::control`), converted; `pointmass_dyn.Simulator`
//! wraps it.
use crate::python::Obj;
use std::sync::{Mutex, MutexGuard};

use pyo3::prelude::*;

use super::convert::{to_array, to_array1, vector};
use super::effects::take_callback_error;
use super::errors::IntoPyResult;
use super::record::getters_of;
use super::scene::PyScene;
use super::trajectory::PyRunResult;
use crate::control::{ControlKind, OwnedSimulator, Simulator, Stepping};
use crate::simulate::RunConfig;
use crate::support::args;

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
    #[new]
    #[pyo3(signature = (scene, method=None, rtol=None, atol=None, dt=None, control_period=0.001, control="torque", record=true, disable=None, first_step=None, max_step=None, t0=0.0, t_eval=None))]
    fn new(
        py: Python<'_>,
        scene: PyRef<'_, PyScene>,
        method: Option<&str>,
        rtol: Option<&Obj>,
        atol: Option<&Obj>,
        dt: Option<&Obj>,
        control_period: f64,
        control: &str,
        record: bool,
        disable: Option<&Obj>,
        first_step: Option<&Obj>,
        max_step: Option<&Obj>,
        t0: f64,
        t_eval: Option<&Obj>,
    ) -> PyResult<Self> {
        let kind = ControlKind::from_arg(&pyo3::types::PyString::new(py, control).into_any())?;
        let method = method.map(|m| pyo3::types::PyString::new(py, m).into_any());
        let given = [
            ("method", method.as_ref()),
            ("rtol", rtol),
            ("atol", atol),
            ("dt", dt),
            ("disable", disable),
            ("first_step", first_step),
            ("max_step", max_step),
        ];
        let call = RunConfig::from_call(None, &given)?;
        let t_eval = args::opt(t_eval, |te| vector(te, "t_eval", None))?;
        let at = Stepping {
            t0,
            period: control_period,
            kind,
            record,
            t_eval: t_eval.as_deref(),
        };
        let inner = OwnedSimulator::of_scene(&scene.inner, call, at).py(py)?;
        Ok(PySimulator {
            inner: Mutex::new(inner),
        })
    }

    fn set_control(&self, py: Python<'_>, u: &Obj) -> PyResult<()> {
        let u = vector(u, "control", None)?;
        self.lock().with_mut(|s| s.set_control(&u)).py(py)
    }

    fn set_state(&self, py: Python<'_>, q: &Obj, v: &Obj) -> PyResult<()> {
        let q = vector(q, "q", None)?;
        let v = vector(v, "v", None)?;
        self.lock().with_mut(|s| s.set_state(&q, &v)).py(py)
    }

    /// Advances to `target` with the interpreter released; returns None, or the failure's
    /// message (the run then stays where it failed). A Python callback that raised is
    /// re-raised.
    fn advance(&self, py: Python<'_>, target: f64) -> PyResult<Option<String>> {
        take_callback_error();
        let (r, t) = self
            .lock()
            .with_mut(|sim| (py.detach(|| sim.advance(target)), sim.t()));
        let r = r.py(py)?;
        if let Some(e) = take_callback_error() {
            return Err(e);
        }
        Ok(r.err().map(|s| s.describe(t)))
    }

    /// Everything so far, as `simulate_scene` returns it.
    fn trajectory(&self, py: Python<'_>) -> PyResult<PyRunResult> {
        let traj = self.lock().with(|s| s.trajectory());
        let slots: Vec<usize> = (0..traj.t_events.len()).collect();
        Ok(PyRunResult::new(py, traj, &slots, None))
    }

    /// The actuators' joint torques now (nv): the torque control plus the scene's torques.
    fn joint_torques<'py>(&self, py: Python<'py>) -> PyResult<Obj<'py>> {
        let mut out = vec![0.0; self.lock().with(|s| s.nv())];
        self.lock().with_mut(|s| s.joint_torques(&mut out)).py(py)?;
        Ok(to_array1(py, &out).into_any())
    }

    /// IMU readings now, (n, 6): specific force then angular velocity, sensor axes; each IMU
    /// `(body index, position (3,), rotation (3, 3))` in the body's frame.
    fn imu<'py>(&self, py: Python<'py>, imus: &Obj) -> PyResult<Obj<'py>> {
        let list = crate::control::sensors::imus_arg(imus)?;
        let mut out = vec![0.0; 6 * list.len()];
        self.lock().with_mut(|s| s.imu(&list, &mut out)).py(py)?;
        to_array(py, out, &[list.len(), 6])
    }
}

impl PySimulator {
    fn read<R>(&self, f: impl for<'m> FnOnce(&Simulator<'m>) -> R) -> R {
        self.lock().with(f)
    }
}

getters_of!(PySimulator.read {
    t: f64 = |s, py| s.t(),
    nq: usize = |s, py| s.nq(),
    control_period: f64 = |s, py| s.period(),
    method: &'static str = |s, py| s.method().name(),
    control_len: usize = |s, py| s.control_len(),
    /// The state `[q; v]` (a copy).
    y: Obj<'py> = |s, py| to_array1(py, s.y()).into_any(),
    control: Option<Obj<'py>> = |s, py| s.control().map(|u| to_array1(py, u).into_any()),
});
