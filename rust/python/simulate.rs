//! Scenes, effects, `simulate` and the generic `rk45`.
use std::cell::RefCell;
use std::sync::{Arc, Mutex};

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

use super::convert::{
    array, count_arg, int_arg, opt_count, opt_real, real, shape_str, to_array, to_array1, vec3,
    vector,
};
use super::errors::{check_result, invalid, py_error, IntoPyResult};
use super::model::PyModel;
use super::signals::Watch;
use crate::effects::{
    Damper, Disabled, Effect, Effects, External, ExternalLoad, Frame, Friction, JointRef, Matrix,
    PerJoint, Spring, Table, Torque, TorqueFunction, TorqueLaw,
};
use crate::integrator::{
    self, Controller, DenseOutput, Event, EventDirection, FnSystem, Rk45Options, Tol,
};
use crate::scene::{Scene, Settings};
use crate::simulate::{simulate, Dynamics, Record, StateEvent};

#[pyclass(
    name = "Effect",
    module = "pointmass_dyn._core",
    frozen,
    from_py_object
)]
#[derive(Clone)]
pub struct PyEffect {
    pub inner: Effect,
}

thread_local! {
    /// The first exception a Python torque function raised during the current call (the
    /// integration runs on the calling thread, detached from the interpreter).
    static CALLBACK_ERROR: RefCell<Option<PyErr>> = const { RefCell::new(None) };
}

fn take_callback_error() -> Option<PyErr> {
    CALLBACK_ERROR.with(|c| c.borrow_mut().take())
}

fn repr_of(obj: &Bound<'_, PyAny>) -> String {
    obj.repr().map(|r| r.to_string()).unwrap_or_default()
}

/// A body name or index.
fn joint_ref(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<JointRef> {
    if let Ok(s) = obj.extract::<String>() {
        return Ok(JointRef::Name(s));
    }
    if !obj.is_instance_of::<pyo3::types::PyBool>() {
        if let Ok(i) = obj.extract::<i64>() {
            if i >= 0 {
                return Ok(JointRef::Index(i as usize));
            }
        }
    }
    Err(invalid(
        obj.py(),
        arg,
        "a body name (str) or body index (int >= 0)",
        repr_of(obj),
    ))
}

/// `None` (every moving joint), one body name or index, or a sequence of them.
fn joints_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<JointRef>>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    if obj.extract::<String>().is_ok() || obj.extract::<i64>().is_ok() {
        return Ok(Some(vec![joint_ref(obj, "joints")?]));
    }
    let mut out = Vec::new();
    let items = obj.try_iter().map_err(|_| {
        invalid(
            obj.py(),
            "joints",
            "None, a body name or index, or a sequence of them",
            repr_of(obj),
        )
    })?;
    for (k, x) in items.enumerate() {
        out.push(joint_ref(&x?, &format!("joints[{k}]"))?);
    }
    Ok(Some(out))
}

/// A number (all joints) or a 1-D array (one per joint).
fn per_joint_arg(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<PerJoint> {
    let (shape, values) = array(obj, arg)?;
    match shape.len() {
        0 => Ok(PerJoint::All(values[0])),
        1 => Ok(PerJoint::Each(values)),
        _ => Err(invalid(
            obj.py(),
            arg,
            "a number or a 1-D array",
            shape_str(&shape),
        )),
    }
}

/// A 1-D or 2-D array, one row per time.
fn matrix_arg(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Matrix> {
    let (shape, values) = array(obj, arg)?;
    match shape.as_slice() {
        [n] => Ok(Matrix {
            values,
            rows: *n,
            cols: 1,
            one_d: true,
        }),
        [n, c] => Ok(Matrix {
            values,
            rows: *n,
            cols: *c,
            one_d: false,
        }),
        _ => Err(invalid(
            obj.py(),
            arg,
            "a 1-D or 2-D array (one row per time)",
            shape_str(&shape),
        )),
    }
}

fn table_arg(
    py: Python<'_>,
    time: &Bound<'_, PyAny>,
    values: &Bound<'_, PyAny>,
    values_arg: &str,
) -> PyResult<Table> {
    let t = vector(time, "time", None)?;
    let m = matrix_arg(values, values_arg)?;
    Table::new(t, m, "time", values_arg).py(py)
}

fn opt<'a, 'py>(obj: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
    obj.filter(|o| !o.is_none())
}

/// A Python `f(t, q, v) -> tau` as a torque callback: re-attaches to the interpreter at
/// every evaluation. An exception it raises (or a result of the wrong shape) is kept for the
/// caller to re-raise; a non-finite torque fails the run like any effect's (`success=False`
/// with the time), so it is not an exception. `func` is also kept as the function's source,
/// which pickling carries (`pickle.rs`).
pub(crate) fn torque_callback(func: Py<PyAny>) -> TorqueFunction {
    let source = Python::attach(|py| func.clone_ref(py));
    let f = TorqueFunction::new(Arc::new(
        move |t: f64, q: &[f64], v: &[f64], out: &mut [f64]| -> Result<(), String> {
            Python::attach(|py| {
                let call = || -> PyResult<Vec<f64>> {
                    let r = func.bind(py).call1((
                        t,
                        PyArray1::from_slice(py, q),
                        PyArray1::from_slice(py, v),
                    ))?;
                    vector(&r, "torque function f(t, q, v)", Some(out.len()))
                };
                match call() {
                    Ok(x) => {
                        crate::error::check_finite("torque function f(t, q, v)", &x)
                            .map_err(|e| e.to_string())?;
                        out.copy_from_slice(&x);
                        Ok(())
                    }
                    Err(e) => {
                        let msg = e.to_string();
                        CALLBACK_ERROR.with(|c| {
                            c.borrow_mut().get_or_insert(e);
                        });
                        Err(msg)
                    }
                }
            })
        },
    ));
    TorqueFunction::with_source(f.0, Arc::new(source))
}

#[pymethods]
impl PyEffect {
    /// Uniform gravity `g` (m/s², world frame).
    #[staticmethod]
    #[pyo3(signature = (g=None))]
    fn gravity(py: Python<'_>, g: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let g = match g {
            Some(g) if !g.is_none() => vec3(g, "g")?,
            _ => crate::spatial::Vec3::new(0.0, 0.0, -9.81),
        };
        Ok(PyEffect {
            inner: Effect::gravity(g).py(py)?,
        })
    }

    /// Joint springs `τ = −k (q − rest)` (rotation-vector spring on quaternion joints).
    #[staticmethod]
    #[pyo3(signature = (joints, stiffness, rest=None, name=None))]
    fn spring(
        py: Python<'_>,
        joints: Option<&Bound<'_, PyAny>>,
        stiffness: &Bound<'_, PyAny>,
        rest: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let joints = joints_arg(joints)?;
        let k = per_joint_arg(stiffness, "stiffness")?;
        let rest = opt(rest).map(|r| per_joint_arg(r, "rest")).transpose()?;
        Ok(PyEffect {
            inner: Effect::Spring(Spring::new(name, joints, k, rest).py(py)?),
        })
    }

    /// Viscous joint dampers `τ = −c v`.
    #[staticmethod]
    #[pyo3(signature = (joints, damping, name=None))]
    fn damper(
        py: Python<'_>,
        joints: Option<&Bound<'_, PyAny>>,
        damping: &Bound<'_, PyAny>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let joints = joints_arg(joints)?;
        let c = per_joint_arg(damping, "damping")?;
        Ok(PyEffect {
            inner: Effect::Damper(Damper::new(name, joints, c).py(py)?),
        })
    }

    /// Regularised Coulomb friction `τ = −F tanh(v / v_eps)`.
    #[staticmethod]
    #[pyo3(signature = (joints, friction, v_eps=None, name=None))]
    fn friction(
        py: Python<'_>,
        joints: Option<&Bound<'_, PyAny>>,
        friction: &Bound<'_, PyAny>,
        v_eps: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let v_eps = opt_real(v_eps, "v_eps")?;
        let joints = joints_arg(joints)?;
        let f = per_joint_arg(friction, "friction")?;
        Ok(PyEffect {
            inner: Effect::Friction(Friction::new(name, joints, f, v_eps).py(py)?),
        })
    }

    /// Constant joint torques (forces on prismatic joints), one per speed or one for all.
    #[staticmethod]
    #[pyo3(signature = (joints, tau, name=None))]
    fn joint_torque(
        py: Python<'_>,
        joints: Option<&Bound<'_, PyAny>>,
        tau: &Bound<'_, PyAny>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let joints = joints_arg(joints)?;
        let tau = per_joint_arg(tau, "tau")?;
        Ok(PyEffect {
            inner: Effect::Torque(Torque::constant(name, joints, tau).py(py)?),
        })
    }

    /// Joint torques tabulated in time: linear between rows, clamped outside.
    #[staticmethod]
    #[pyo3(signature = (joints, time, values, name=None))]
    fn tabulated_torque(
        py: Python<'_>,
        joints: Option<&Bound<'_, PyAny>>,
        time: &Bound<'_, PyAny>,
        values: &Bound<'_, PyAny>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let joints = joints_arg(joints)?;
        let table = table_arg(py, time, values, "values")?;
        Ok(PyEffect {
            inner: Effect::Torque(Torque::tabulated(name, joints, table).py(py)?),
        })
    }

    /// PD torques tracking a tabulated reference on 1-dof joints.
    #[staticmethod]
    #[pyo3(signature = (joints, kp, kd, time, reference, name=None))]
    #[allow(clippy::too_many_arguments)]
    fn pd_torque(
        py: Python<'_>,
        joints: Option<&Bound<'_, PyAny>>,
        kp: &Bound<'_, PyAny>,
        kd: &Bound<'_, PyAny>,
        time: &Bound<'_, PyAny>,
        reference: &Bound<'_, PyAny>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let joints = joints_arg(joints)?;
        let kp = per_joint_arg(kp, "kp")?;
        let kd = per_joint_arg(kd, "kd")?;
        let table = table_arg(py, time, reference, "reference")?;
        Ok(PyEffect {
            inner: Effect::Torque(Torque::pd(name, joints, kp, kd, table).py(py)?),
        })
    }

    /// Generalized forces from a Python callable `f(t, q, v) -> (nv,)`.
    #[staticmethod]
    #[pyo3(signature = (f, name=None))]
    fn torque_function(
        py: Python<'_>,
        f: &Bound<'_, PyAny>,
        name: Option<String>,
    ) -> PyResult<Self> {
        if !f.is_callable() {
            return Err(invalid(py, "f", "a callable f(t, q, v) -> tau", repr_of(f)));
        }
        Ok(PyEffect {
            inner: Effect::Torque(Torque::function(name, torque_callback(f.clone().unbind()))),
        })
    }

    /// A force (and moment) on a body at a body-fixed point, constant or tabulated.
    #[staticmethod]
    #[pyo3(signature = (body, force=None, point=None, moment=None, time=None, frame="world", name=None))]
    #[allow(clippy::too_many_arguments)]
    fn external_force(
        py: Python<'_>,
        body: &Bound<'_, PyAny>,
        force: Option<&Bound<'_, PyAny>>,
        point: Option<&Bound<'_, PyAny>>,
        moment: Option<&Bound<'_, PyAny>>,
        time: Option<&Bound<'_, PyAny>>,
        frame: &str,
        name: Option<String>,
    ) -> PyResult<Self> {
        let body = joint_ref(body, "body")?;
        let point = match opt(point) {
            Some(p) => vec3(p, "point")?,
            None => crate::spatial::Vec3::zeros(),
        };
        let frame = Frame::parse(frame, "frame").py(py)?;
        let (force, moment) = (opt(force), opt(moment));
        if force.is_none() && moment.is_none() {
            return Err(invalid(py, "force", "a force (or a moment)", "None"));
        }
        let inner = match opt(time) {
            Some(t) => {
                let t = vector(t, "time", None)?;
                let f = force.map(|f| matrix_arg(f, "force")).transpose()?;
                let m = moment.map(|m| matrix_arg(m, "moment")).transpose()?;
                External::tabulated(name, body, point, t, f, m, frame).py(py)?
            }
            None => {
                let zero = crate::spatial::Vec3::zeros();
                let f = force.map(|f| vec3(f, "force")).transpose()?.unwrap_or(zero);
                let m = moment
                    .map(|m| vec3(m, "moment"))
                    .transpose()?
                    .unwrap_or(zero);
                External::constant(name, body, point, f, m, frame).py(py)?
            }
        };
        Ok(PyEffect {
            inner: Effect::External(inner),
        })
    }

    /// The user's name, or the family's (`'gravity'`, `'springs'`, ...).
    #[getter]
    fn name(&self) -> String {
        self.inner.name().to_string()
    }
    /// The family, as `disable` names it.
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind().name()
    }
    fn __repr__(&self) -> String {
        let label = match self.inner.label() {
            Some(l) => format!(", name='{l}'"),
            None => String::new(),
        };
        let joints = |j: &Option<Vec<JointRef>>| match j {
            None => "all".to_string(),
            Some(v) => format!(
                "[{}]",
                v.iter()
                    .map(|r| r.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        match &self.inner {
            Effect::Gravity { g } => format!("Gravity(g=[{}, {}, {}])", g.x, g.y, g.z),
            Effect::Spring(e) => format!("Spring(joints={}{label})", joints(&e.joints)),
            Effect::Damper(e) => format!("Damper(joints={}{label})", joints(&e.joints)),
            Effect::Friction(e) => format!(
                "JointFriction(joints={}, v_eps={}{label})",
                joints(&e.joints),
                e.v_eps
            ),
            Effect::Torque(e) => match &e.law {
                TorqueLaw::Constant(_) => {
                    format!("JointTorque(joints={}{label})", joints(&e.joints))
                }
                TorqueLaw::Tabulated(t) => format!(
                    "TabulatedTorque(joints={}, {} rows{label})",
                    joints(&e.joints),
                    t.len()
                ),
                TorqueLaw::Pd { reference, .. } => format!(
                    "PDTorque(joints={}, {} rows{label})",
                    joints(&e.joints),
                    reference.len()
                ),
                TorqueLaw::Function(_) => match self.inner.label() {
                    Some(l) => format!("TorqueFunction(name='{l}')"),
                    None => "TorqueFunction()".to_string(),
                },
            },
            Effect::External(e) => format!(
                "ExternalForce(body={}, point=[{}, {}, {}], frame='{}'{}{label})",
                e.body,
                e.point.x,
                e.point.y,
                e.point.z,
                e.frame.name(),
                match &e.load {
                    ExternalLoad::Constant { .. } => String::new(),
                    ExternalLoad::Tabulated(t) => format!(", {} rows", t.len()),
                }
            ),
        }
    }
    fn __eq__(&self, other: PyRef<'_, PyEffect>) -> bool {
        self.inner == other.inner
    }
}

/// `q[index]` (or `v[index]`) crossing `value`; evaluated in Rust, no GIL needed.
#[pyclass(
    name = "StateEvent",
    module = "pointmass_dyn._core",
    frozen,
    from_py_object
)]
#[derive(Clone)]
pub struct PyStateEvent {
    pub inner: StateEvent,
}

fn terminal_count(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    if let Ok(b) = obj.cast::<pyo3::types::PyBool>() {
        return Ok(b.is_true() as usize);
    }
    match obj.extract::<i64>() {
        Ok(n) if n >= 0 => Ok(n as usize),
        _ => Err(invalid(
            py,
            "terminal",
            "a bool or a count >= 0",
            obj.repr().map(|r| r.to_string()).unwrap_or_default(),
        )),
    }
}

#[pymethods]
impl PyStateEvent {
    #[new]
    #[pyo3(signature = (variable, index, value=None, direction=None, terminal=None))]
    fn new(
        py: Python<'_>,
        variable: &str,
        index: &Bound<'_, PyAny>,
        value: Option<&Bound<'_, PyAny>>,
        direction: Option<&Bound<'_, PyAny>>,
        terminal: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let index = count_arg(index, "index", "a coordinate index >= 0")?;
        let value = opt_real(value, "value")?.unwrap_or(0.0);
        let direction = match direction.filter(|d| !d.is_none()) {
            None => 0,
            Some(d) => int_arg(d, "direction", i64::MIN, i64::MAX, "-1, 0 or 1")?.signum() as i32,
        };
        let on_velocity = match variable {
            "q" => false,
            "v" => true,
            other => return Err(invalid(py, "variable", "'q' or 'v'", format!("'{other}'"))),
        };
        if !value.is_finite() {
            return Err(invalid(py, "value", "a finite number", value));
        }
        let terminal = match terminal {
            Some(t) if !t.is_none() => terminal_count(py, t)?,
            _ => 0,
        };
        Ok(PyStateEvent {
            inner: StateEvent {
                on_velocity,
                index,
                value,
                direction: direction.signum(),
                terminal,
            },
        })
    }
    #[getter]
    fn terminal(&self) -> usize {
        self.inner.terminal
    }
    #[getter]
    fn direction(&self) -> i32 {
        self.inner.direction
    }
    fn __repr__(&self) -> String {
        let e = &self.inner;
        format!(
            "StateEvent('{}', {}, value={}, direction={}, terminal={})",
            if e.on_velocity { "v" } else { "q" },
            e.index,
            e.value,
            e.direction,
            e.terminal
        )
    }
}

#[pyclass(name = "Scene", module = "pointmass_dyn._core", frozen)]
pub struct PyScene {
    pub inner: Scene,
}

fn opt_positive(py: Python<'_>, x: Option<f64>, arg: &str) -> PyResult<Option<f64>> {
    match x {
        Some(v) if !(v > 0.0 && v.is_finite()) => Err(invalid(py, arg, "a finite number > 0", v)),
        other => Ok(other),
    }
}

fn t_span_arg(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<(f64, f64)> {
    let v = vector(obj, "t_span", Some(2))?;
    if !(v[0].is_finite() && v[1].is_finite()) || v[0] == v[1] {
        return Err(invalid(
            py,
            "t_span",
            "two different finite times (t0, t_end)",
            format!("({}, {})", v[0], v[1]),
        ));
    }
    Ok((v[0], v[1]))
}

#[pymethods]
impl PyScene {
    #[new]
    #[pyo3(signature = (model, q0=None, v0=None, effects=None, t_span=None, rtol=None, atol=None, name=None, description=None, disable=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        model: PyRef<'_, PyModel>,
        q0: Option<&Bound<'_, PyAny>>,
        v0: Option<&Bound<'_, PyAny>>,
        effects: Option<&Bound<'_, PyAny>>,
        t_span: Option<&Bound<'_, PyAny>>,
        rtol: Option<&Bound<'_, PyAny>>,
        atol: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
        description: Option<String>,
        disable: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let (rtol, atol) = (opt_real(rtol, "rtol")?, opt_real(atol, "atol")?);
        let m = model.model();
        let mut q = match q0 {
            Some(q) if !q.is_none() => vector(q, "q0", Some(m.nq))?,
            _ => m.neutral(),
        };
        let v = match v0 {
            Some(v) if !v.is_none() => vector(v, "v0", Some(m.nv))?,
            _ => vec![0.0; m.nv],
        };
        m.check_state(&q, Some(&v))
            .map_err(|e| super::errors::to_py(py, rename_arg(e)))?;
        m.normalize(&mut q);
        let mut list = Vec::new();
        if let Some(effs) = effects {
            if !effs.is_none() {
                for (k, e) in effs.try_iter()?.enumerate() {
                    let e = e?;
                    let eff = e.cast::<PyEffect>().map_err(|_| {
                        invalid(
                            py,
                            &format!("effects[{k}]"),
                            "an effect such as pmd.Gravity(...)",
                            e.repr().map(|r| r.to_string()).unwrap_or_default(),
                        )
                    })?;
                    list.push(eff.get().inner.clone());
                }
            }
        }
        // Joint and body names, table widths and effect names must fit the model.
        Effects::new(&m, &list, Disabled::none(), "effects").py(py)?;
        let settings = Settings {
            t_span: match t_span {
                Some(t) if !t.is_none() => Some(t_span_arg(py, t)?),
                _ => None,
            },
            rtol: opt_positive(py, rtol, "rtol")?,
            atol: opt_positive(py, atol, "atol")?,
            disable: disable_arg(py, disable)?,
            ..Settings::default()
        };
        Ok(PyScene {
            inner: Scene {
                name: name.unwrap_or_else(|| "scene".into()),
                description: description.unwrap_or_default(),
                model: m,
                q0: q,
                v0: v,
                effects: list,
                settings,
            },
        })
    }

    /// Parses a scene from TOML text; `file` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, file="<string>"))]
    fn from_toml(py: Python<'_>, text: &str, file: &str) -> PyResult<Self> {
        Scene::from_toml(text, file)
            .map(|inner| PyScene { inner })
            .py(py)
    }

    /// Reads a scene file (a regular file of at most 128 MiB; a FIFO or a device is refused
    /// before it is opened). Raises `SceneError` naming the file.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        Scene::from_file(&path)
            .map(|inner| PyScene { inner })
            .py(py)
    }

    /// The scene's model (shared, not copied: adding a body to it copies it first, so the
    /// scene never changes).
    #[getter]
    fn model(&self) -> PyModel {
        PyModel::from_parts(self.inner.model.clone(), Default::default())
    }
    #[getter]
    fn q0<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, &self.inner.q0).into_any()
    }
    #[getter]
    fn v0<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, &self.inner.v0).into_any()
    }
    #[getter]
    fn effects(&self) -> Vec<PyEffect> {
        self.inner
            .effects
            .iter()
            .map(|e| PyEffect { inner: e.clone() })
            .collect()
    }
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }
    #[getter]
    fn description(&self) -> String {
        self.inner.description.clone()
    }
    #[getter]
    fn t_span(&self) -> Option<(f64, f64)> {
        self.inner.settings.t_span
    }
    #[getter]
    fn rtol(&self) -> Option<f64> {
        self.inner.settings.rtol
    }
    #[getter]
    fn atol(&self) -> Option<f64> {
        self.inner.settings.atol
    }
    #[getter]
    fn max_step(&self) -> Option<f64> {
        self.inner.settings.max_step
    }
    #[getter]
    fn max_steps(&self) -> Option<usize> {
        self.inner.settings.max_steps
    }
    #[getter]
    fn first_step(&self) -> Option<f64> {
        self.inner.settings.first_step
    }
    /// Effect families the scene switches off (`None`: the scene says nothing).
    #[getter]
    fn disable(&self) -> Option<Vec<&'static str>> {
        self.inner.settings.disable.map(|d| d.names())
    }
    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "Scene(name='{}', nbodies={}, nq={}, nv={}, effects=[{}])",
            s.name,
            s.model.nbodies(),
            s.model.nq,
            s.model.nv,
            s.effects
                .iter()
                .map(|e| e.name())
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

/// `None`, one family name, or a sequence of them.
fn disable_arg(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Disabled>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let names: Vec<String> = if let Ok(s) = obj.extract::<String>() {
        vec![s]
    } else {
        let bad = || {
            invalid(
                py,
                "disable",
                "None, an effect family name or a sequence of them",
                repr_of(obj),
            )
        };
        obj.try_iter()
            .map_err(|_| bad())?
            .map(|x| x.and_then(|x| x.extract::<String>()).map_err(|_| bad()))
            .collect::<PyResult<_>>()?
    };
    Disabled::parse(&names, "disable").py(py).map(Some)
}

fn rename_arg(e: crate::error::Error) -> crate::error::Error {
    match e {
        crate::error::Error::InvalidArgument { arg, expected, got } => {
            crate::error::Error::InvalidArgument {
                arg: format!("{arg}0"),
                expected,
                got,
            }
        }
        other => other,
    }
}

fn tol_arg(obj: &Bound<'_, PyAny>, arg: &str, dim: usize) -> PyResult<Tol> {
    let (shape, values) = array(obj, arg)?;
    if shape.is_empty() {
        return Ok(Tol::Scalar(values[0]));
    }
    if shape != [dim] {
        return Err(invalid(
            obj.py(),
            arg,
            format!("a number or shape ({dim},)"),
            shape_str(&shape),
        ));
    }
    Ok(Tol::PerComponent(values))
}

fn controller_arg(py: Python<'_>, name: &str) -> PyResult<Controller> {
    match name {
        "standard" | "scipy" => Ok(Controller::Standard),
        "pi" => Ok(Controller::hairer_pi()),
        other => Err(invalid(
            py,
            "controller",
            "'standard' (SciPy's) or 'pi' (Hairer's PI)",
            format!("'{other}'"),
        )),
    }
}

/// `first_step`, `max_step` (inf: no limit) and `max_steps` as numbers and a count.
#[allow(clippy::type_complexity)]
fn step_args(
    first_step: Option<&Bound<'_, PyAny>>,
    max_step: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Option<f64>, Option<f64>, Option<usize>)> {
    Ok((
        opt_real(first_step, "first_step")?,
        opt_real(max_step, "max_step")?.filter(|x| *x != f64::INFINITY),
        opt_count(max_steps, "max_steps", "a step count >= 0 (or None)")?,
    ))
}

/// Options common to `rk45` and `simulate`.
#[allow(clippy::too_many_arguments)]
fn options(
    py: Python<'_>,
    dim: usize,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    t_eval: Option<&Bound<'_, PyAny>>,
    first_step: Option<f64>,
    max_step: Option<f64>,
    max_steps: Option<usize>,
    dense: bool,
    controller: &str,
) -> PyResult<Rk45Options> {
    let mut o = Rk45Options {
        dense,
        controller: controller_arg(py, controller)?,
        ..Default::default()
    };
    if let Some(r) = rtol.filter(|r| !r.is_none()) {
        o.rtol = tol_arg(r, "rtol", dim)?;
    }
    if let Some(a) = atol.filter(|a| !a.is_none()) {
        o.atol = tol_arg(a, "atol", dim)?;
    }
    if let Some(t) = t_eval.filter(|t| !t.is_none()) {
        o.t_eval = Some(vector(t, "t_eval", None)?);
    }
    o.first_step = first_step;
    if let Some(m) = max_step {
        o.max_step = m;
    }
    if let Some(n) = max_steps {
        o.max_steps = n;
    }
    Ok(o)
}

/// A Python event callable: `(args...) -> float`, with optional `terminal` and `direction`
/// attributes (SciPy's convention).
struct PyEventSpec {
    /// Position in the caller's `events` (named in errors).
    index: usize,
    func: Py<PyAny>,
    terminal: usize,
    direction: f64,
}

fn event_spec(py: Python<'_>, k: usize, e: &Bound<'_, PyAny>) -> PyResult<PyEventSpec> {
    if !e.is_callable() {
        return Err(invalid(
            py,
            &format!("events[{k}]"),
            "a callable or a pmd.StateEvent",
            e.repr().map(|r| r.to_string()).unwrap_or_default(),
        ));
    }
    let terminal = match e.getattr("terminal") {
        Ok(t) if !t.is_none() => terminal_count(py, &t)?,
        _ => 0,
    };
    let direction = match e.getattr("direction") {
        Ok(d) if !d.is_none() => real(&d, &format!("events[{k}].direction"))?,
        _ => 0.0,
    };
    Ok(PyEventSpec {
        index: k,
        func: e.clone().unbind(),
        terminal,
        direction,
    })
}

/// Builds an event that calls Python (re-attaching to the interpreter when called from a
/// detached thread); the first exception is kept in `failure` and re-raised afterwards.
fn python_event<'a>(
    spec: &'a PyEventSpec,
    split: Option<usize>,
    failure: &'a Mutex<Option<PyErr>>,
) -> Event<'a> {
    let f = move |t: f64, y: &[f64]| -> f64 {
        Python::attach(|py| {
            let args = match split {
                Some(nq) => PyTuple::new(
                    py,
                    [
                        t.into_pyobject(py).map(|x| x.into_any()),
                        Ok(PyArray1::from_slice(py, &y[..nq]).into_any()),
                        Ok(PyArray1::from_slice(py, &y[nq..]).into_any()),
                    ]
                    .into_iter()
                    .collect::<Result<Vec<_>, _>>()
                    .unwrap_or_default(),
                ),
                None => PyTuple::new(
                    py,
                    [
                        t.into_pyobject(py).map(|x| x.into_any()),
                        Ok(PyArray1::from_slice(py, y).into_any()),
                    ]
                    .into_iter()
                    .collect::<Result<Vec<_>, _>>()
                    .unwrap_or_default(),
                ),
            };
            // A non-number or NaN would silently hide the event: an error naming it.
            let name = format!("events[{}]", spec.index);
            let out = args
                .and_then(|a| spec.func.bind(py).call1(a))
                .and_then(|r| {
                    real(&r, &name).map_err(|_| {
                        invalid(
                            py,
                            &name,
                            "an event function returning a real number",
                            format!("{} at t = {t}", repr_of(&r)),
                        )
                    })
                })
                .and_then(|x| {
                    if x.is_nan() {
                        Err(py_error(
                            py,
                            "NumericalError",
                            format!("{name}: the event function returned NaN at t = {t}"),
                        ))
                    } else {
                        Ok(x)
                    }
                });
            match out {
                Ok(x) => x,
                Err(e) => {
                    if let Ok(mut slot) = failure.lock() {
                        slot.get_or_insert(e);
                    }
                    f64::NAN
                }
            }
        })
    };
    Event::new(f)
        .direction(EventDirection::from_sign(spec.direction))
        .terminal(spec.terminal)
}

/// Runs a scene: returns a dict that `pointmass_dyn.simulate` wraps.
#[pyfunction]
#[pyo3(signature = (scene, t_span=None, rtol=None, atol=None, t_eval=None, events=None, first_step=None, max_step=None, max_steps=None, energy=false, controller="standard", progress=None, disable=None, power=false, stiffness="warn", progress_interval=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate_scene<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    t_span: Option<&Bound<'_, PyAny>>,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    t_eval: Option<&Bound<'_, PyAny>>,
    events: Option<&Bound<'_, PyAny>>,
    first_step: Option<&Bound<'_, PyAny>>,
    max_step: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
    energy: bool,
    controller: &str,
    progress: Option<Py<PyAny>>,
    disable: Option<&Bound<'_, PyAny>>,
    power: bool,
    stiffness: &str,
    progress_interval: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let (first_step, max_step, max_steps) = step_args(first_step, max_step, max_steps)?;
    let s = &scene.inner;
    let watch = match progress_interval {
        None => Watch::default(),
        Some(x) if (0.0..=3600.0).contains(&x) => {
            Watch::every(std::time::Duration::from_secs_f64(x))
        }
        Some(x) => {
            return Err(invalid(
                py,
                "progress_interval",
                "seconds between progress calls, 0 to 3600",
                x,
            ))
        }
    };
    let disabled = disable_arg(py, disable)?
        .or(s.settings.disable)
        .unwrap_or_default();
    let (nq, nv) = (s.model.nq, s.model.nv);
    let t_span = match t_span.filter(|t| !t.is_none()) {
        Some(t) => t_span_arg(py, t)?,
        None => s
            .settings
            .t_span
            .ok_or_else(|| invalid(py, "t_span", "(t0, t_end): the scene sets none", "None"))?,
    };
    let mut opts = options(
        py,
        nq + nv,
        rtol,
        atol,
        t_eval,
        first_step.or(s.settings.first_step),
        max_step.or(s.settings.max_step),
        max_steps.or(s.settings.max_steps),
        false,
        controller,
    )?;
    opts.stiffness = stiffness_arg(py, stiffness)?; // stiffness detection (integrator)
    if rtol.is_none_or(|r| r.is_none()) {
        if let Some(r) = s.settings.rtol {
            opts.rtol = Tol::Scalar(r);
        }
    }
    if atol.is_none_or(|a| a.is_none()) {
        if let Some(a) = s.settings.atol {
            opts.atol = Tol::Scalar(a);
        }
    }
    let mut state_events = Vec::new();
    let mut py_events = Vec::new();
    // Keep the caller's order: state events first in the result would surprise; record slots.
    let mut order = Vec::new();
    if let Some(evs) = events.filter(|e| !e.is_none()) {
        for (k, e) in evs.try_iter()?.enumerate() {
            let e = e?;
            if let Ok(se) = e.cast::<PyStateEvent>() {
                order.push((false, state_events.len()));
                state_events.push(se.get().inner.clone());
            } else {
                order.push((true, py_events.len()));
                py_events.push(event_spec(py, k, &e)?);
            }
        }
    }
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    let model = &s.model;
    let (q0, v0, effects) = (&s.q0, &s.v0, &s.effects);
    let mut watch = watch;
    take_callback_error();
    let result = py.detach(|| {
        let extra: Vec<Event<'_>> = py_events
            .iter()
            .map(|spec| python_event(spec, Some(nq), &failure))
            .collect();
        // Ctrl-C and progress by elapsed time (signals::INTERVAL), not per evaluation, so a
        // busy Python thread beside the run costs one hand-over of the interpreter per poll.
        let hook: crate::simulate::Progress<'_> = Box::new(|t: f64| {
            watch.poll(|py| match &progress {
                Some(cb) => cb.bind(py).call1((t,)).map(|_| ()),
                None => Ok(()),
            })
        });
        simulate(
            model,
            effects,
            disabled,
            q0,
            v0,
            t_span,
            &opts,
            &state_events,
            extra,
            Record { energy, power },
            Some(hook),
        )
    });
    // A Python callback that raised (or Ctrl-C) ends the run; its exception is re-raised by
    // `pointmass_dyn.simulate` with the trajectory computed so far attached.
    let raised = take_callback_error()
        .or(failure.into_inner().ok().flatten())
        .or(watch.error.take());
    let (traj, raised) = match (result, raised) {
        (Ok(traj), raised) => (traj, raised),
        (Err(_), Some(raised)) => return Err(raised),
        (Err(e), None) => return Err(super::errors::to_py(py, e)),
    };
    let n = traj.t.len();
    let d = PyDict::new(py);
    d.set_item("error", raised.map(|e| e.into_value(py)))?;
    d.set_item("t", to_array1(py, &traj.t))?;
    d.set_item("q", to_array(py, traj.q, &[n, nq])?)?;
    d.set_item("v", to_array(py, traj.v, &[n, nv])?)?;
    d.set_item("energy", traj.energy.map(|e| to_array1(py, &e).into_any()))?;
    match &traj.power {
        Some(p) => {
            let m = traj.effect_labels.len();
            let pd = PyDict::new(py);
            for (k, label) in traj.effect_labels.iter().enumerate() {
                let col: Vec<f64> = (0..n).map(|i| p[i * m + k]).collect();
                pd.set_item(label, to_array1(py, &col))?;
            }
            d.set_item("power", pd)?;
        }
        None => d.set_item("power", py.None())?,
    }
    // Events back in the caller's order: state events were evaluated first.
    let ns = state_events.len();
    let te = PyList::empty(py);
    let qe = PyList::empty(py);
    let ve = PyList::empty(py);
    for (is_py, k) in order {
        let slot = if is_py { ns + k } else { k };
        let times = &traj.t_events[slot];
        let ys = &traj.y_events[slot];
        te.append(to_array1(py, times))?;
        let m = times.len();
        let mut qs = Vec::with_capacity(m * nq);
        let mut vs = Vec::with_capacity(m * nv);
        for row in ys.chunks_exact(nq + nv) {
            qs.extend_from_slice(&row[..nq]);
            vs.extend_from_slice(&row[nq..]);
        }
        qe.append(to_array(py, qs, &[m, nq])?)?;
        ve.append(to_array(py, vs, &[m, nv])?)?;
    }
    d.set_item("t_events", te)?;
    d.set_item("q_events", qe)?;
    d.set_item("v_events", ve)?;
    d.set_item("nfev", traj.nfev)?;
    d.set_item("n_accepted", traj.n_accepted)?;
    d.set_item("n_rejected", traj.n_rejected)?;
    d.set_item("status", traj.status.code())?;
    d.set_item("message", traj.message)?;
    d.set_item("success", traj.success)?;
    d.set_item("t_reached", traj.t_reached)?;
    Ok(d)
}

/// `(q, v)` checked against the scene's model.
fn scene_state(
    py: Python<'_>,
    s: &Scene,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
) -> PyResult<(Vec<f64>, Vec<f64>)> {
    let q = vector(q, "q", Some(s.model.nq))?;
    let v = vector(v, "v", Some(s.model.nv))?;
    s.model.check_state(&q, Some(&v)).py(py)?;
    Ok((q, v))
}

/// The generalized force of each enabled effect of `scene` at `(t, q, v)`: a dict from the
/// effect's name to an (nv,) array (gravity's included).
#[pyfunction]
#[pyo3(signature = (scene, t, q, v, disable=None))]
pub fn effect_forces<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    t: &Bound<'_, PyAny>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    disable: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = &scene.inner;
    let t = real(t, "t")?;
    if !t.is_finite() {
        return Err(invalid(py, "t", "a finite time", t));
    }
    let (q, v) = scene_state(py, s, q, v)?;
    let disabled = disable_arg(py, disable)?
        .or(s.settings.disable)
        .unwrap_or_default();
    let mut sys = Dynamics::try_new(&s.model, &s.effects, disabled).py(py)?;
    let nv = s.model.nv;
    let mut out = vec![0.0; sys.effects.len() * nv];
    take_callback_error();
    let r = sys.effect_forces(t, &q, &v, &mut out);
    if let Some(e) = take_callback_error() {
        return Err(e);
    }
    r.map_err(|m| py_error(py, "NumericalError", m))?;
    for (k, label) in sys.effects.labels().iter().enumerate() {
        check_result(
            py,
            &format!("effect_forces['{label}']"),
            &out[k * nv..(k + 1) * nv],
        )?;
    }
    let d = PyDict::new(py);
    for (k, label) in sys.effects.labels().iter().enumerate() {
        d.set_item(label, to_array1(py, &out[k * nv..(k + 1) * nv]))?;
    }
    Ok(d)
}

/// Kinetic energy, the potential energy of each enabled conservative effect (gravity,
/// springs) under its name, and their sum under `total`.
#[pyfunction]
#[pyo3(signature = (scene, q, v, disable=None))]
pub fn energies<'py>(
    py: Python<'py>,
    scene: PyRef<'_, PyScene>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    disable: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = &scene.inner;
    let (q, v) = scene_state(py, s, q, v)?;
    let disabled = disable_arg(py, disable)?
        .or(s.settings.disable)
        .unwrap_or_default();
    let mut sys = Dynamics::try_new(&s.model, &s.effects, disabled).py(py)?;
    let (kinetic, potentials) = sys.energies(&q, &v);
    let d = PyDict::new(py);
    check_result(py, "energies['kinetic']", &[kinetic])?;
    d.set_item("kinetic", kinetic)?;
    let mut total = kinetic;
    for (label, e) in potentials {
        check_result(py, &format!("energies['{label}']"), &[e])?;
        total += e;
        d.set_item(label, e)?;
    }
    check_result(py, "energies['total']", &[total])?;
    d.set_item("total", total)?;
    Ok(d)
}

/// The dense output of an `rk45` run: `sol(t)` for a scalar (shape (n,)) or an array of
/// times (shape (n, len(t))), as SciPy's `OdeSolution`.
#[pyclass(name = "DenseSolution", module = "pointmass_dyn._core", frozen)]
pub struct PyDenseSolution {
    pub(crate) inner: DenseOutput,
}

#[pymethods]
impl PyDenseSolution {
    fn __call__<'py>(&self, py: Python<'py>, t: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let dim = self.inner.dim();
        if self.inner.n_segments() == 0 {
            return Err(py_error(
                py,
                "SimulationError",
                format!(
                    "sol(t): the run ended at t = {} before its first step, so there is nothing to interpolate",
                    self.inner.breakpoints().first().copied().unwrap_or(f64::NAN)
                ),
            ));
        }
        let (shape, ts) = array(t, "t")?;
        if let Some(bad) = ts.iter().find(|x| !x.is_finite()) {
            return Err(invalid(py, "t", "finite times", bad));
        }
        // Outside the integrated interval the interpolant extrapolates, and overflows far away.
        let check = |x: f64, y: &[f64]| -> PyResult<()> {
            if y.iter().all(|v| v.is_finite()) {
                return Ok(());
            }
            let b = self.inner.breakpoints();
            let (first, last) = (
                b.first().copied().unwrap_or(f64::NAN),
                b.last().copied().unwrap_or(f64::NAN),
            );
            let (lo, hi) = (first.min(last), first.max(last));
            Err(py_error(
                py,
                "NumericalError",
                format!("sol(t): the dense output at t = {x:e} is not finite: it extrapolates the solution on [{lo}, {hi}] far outside it"),
            ))
        };
        if shape.is_empty() {
            let y = self.inner.eval(ts[0]);
            check(ts[0], &y)?;
            return Ok(to_array1(py, &y).into_any());
        }
        if shape.len() != 1 {
            return Err(invalid(
                py,
                "t",
                "a scalar or a 1-D array",
                format!("shape {shape:?}"),
            ));
        }
        let mut out = vec![0.0; dim * ts.len()];
        let mut buf = vec![0.0; dim];
        for (j, x) in ts.iter().enumerate() {
            self.inner.eval_into(*x, &mut buf);
            check(*x, &buf)?;
            for i in 0..dim {
                out[i * ts.len() + j] = buf[i];
            }
        }
        to_array(py, out, &[dim, ts.len()])
    }
    #[getter]
    fn ts<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, self.inner.breakpoints()).into_any()
    }
}

/// Generic Dormand–Prince 5(4) on a Python right-hand side `fun(t, y) -> array`;
/// step for step SciPy's `solve_ivp(method="RK45")`.
#[pyfunction]
#[pyo3(signature = (fun, t_span, y0, rtol=None, atol=None, t_eval=None, events=None, first_step=None, max_step=None, max_steps=None, dense_output=false, controller="standard", stiffness="warn"))]
#[allow(clippy::too_many_arguments)]
pub fn rk45<'py>(
    py: Python<'py>,
    fun: &Bound<'_, PyAny>,
    t_span: &Bound<'_, PyAny>,
    y0: &Bound<'_, PyAny>,
    rtol: Option<&Bound<'_, PyAny>>,
    atol: Option<&Bound<'_, PyAny>>,
    t_eval: Option<&Bound<'_, PyAny>>,
    events: Option<&Bound<'_, PyAny>>,
    first_step: Option<&Bound<'_, PyAny>>,
    max_step: Option<&Bound<'_, PyAny>>,
    max_steps: Option<&Bound<'_, PyAny>>,
    dense_output: bool,
    controller: &str,
    stiffness: &str,
) -> PyResult<Bound<'py, PyDict>> {
    if !fun.is_callable() {
        return Err(invalid(
            py,
            "fun",
            "a callable fun(t, y) -> array",
            fun.repr().map(|r| r.to_string()).unwrap_or_default(),
        ));
    }
    let t_span = t_span_arg(py, t_span)?;
    let y0 = vector(y0, "y0", None)?;
    let dim = y0.len();
    let (first_step, max_step, max_steps) = step_args(first_step, max_step, max_steps)?;
    let mut opts = options(
        py,
        dim,
        rtol,
        atol,
        t_eval,
        first_step,
        max_step,
        max_steps,
        dense_output,
        controller,
    )?;
    opts.stiffness = stiffness_arg(py, stiffness)?; // stiffness detection (integrator)
    let mut specs = Vec::new();
    if let Some(evs) = events.filter(|e| !e.is_none()) {
        if evs.is_callable() {
            specs.push(event_spec(py, 0, evs)?);
        } else {
            for (k, e) in evs.try_iter()?.enumerate() {
                specs.push(event_spec(py, k, &e?)?);
            }
        }
    }
    let failure: Mutex<Option<PyErr>> = Mutex::new(None);
    let mut evs: Vec<Event<'_>> = specs
        .iter()
        .map(|s| python_event(s, None, &failure))
        .collect();
    let rhs_failure: Mutex<Option<PyErr>> = Mutex::new(None);
    let sys = FnSystem::new(
        dim,
        |t: f64, y: &[f64], dydt: &mut [f64]| -> Result<(), String> {
            let mut call = || -> PyResult<()> {
                let out = fun.call1((t, PyArray1::from_slice(py, y)))?;
                let v = vector(&out, "fun(t, y)", Some(dim))?;
                dydt.copy_from_slice(&v);
                Ok(())
            };
            call().map_err(|e| {
                let msg = e.to_string();
                if let Ok(mut slot) = rhs_failure.lock() {
                    slot.get_or_insert(e);
                }
                msg
            })
        },
    );
    let sol =
        integrator::rk45(sys, t_span, &y0, &opts, &mut evs).map_err(|e| invalid_setting(py, e))?;
    drop(evs);
    // An exception from `fun` or an event (Ctrl-C included) is re-raised by
    // `pointmass_dyn.rk45` with the solution computed so far attached.
    let raised = rhs_failure
        .into_inner()
        .ok()
        .flatten()
        .or(failure.into_inner().ok().flatten());
    let n = sol.t.len();
    let mut y_t = vec![0.0; dim * n];
    for i in 0..n {
        for j in 0..dim {
            y_t[j * n + i] = sol.y[i * dim + j];
        }
    }
    let d = PyDict::new(py);
    d.set_item("error", raised.map(|e| e.into_value(py)))?;
    d.set_item("t", to_array1(py, &sol.t))?;
    d.set_item("y", to_array(py, y_t, &[dim, n])?)?;
    let te = PyList::empty(py);
    let ye = PyList::empty(py);
    for (times, ys) in sol.t_events.iter().zip(&sol.y_events) {
        te.append(to_array1(py, times))?;
        ye.append(to_array(py, ys.clone(), &[times.len(), dim])?)?;
    }
    d.set_item(
        "t_events",
        if specs.is_empty() {
            py.None().into_bound(py)
        } else {
            te.into_any()
        },
    )?;
    d.set_item(
        "y_events",
        if specs.is_empty() {
            py.None().into_bound(py)
        } else {
            ye.into_any()
        },
    )?;
    d.set_item("nfev", sol.nfev)?;
    d.set_item("njev", 0)?;
    d.set_item("nlu", 0)?;
    d.set_item("n_accepted", sol.n_accepted)?;
    d.set_item("n_rejected", sol.n_rejected)?;
    d.set_item("status", sol.status.code())?;
    d.set_item("message", sol.message.clone())?;
    d.set_item("success", sol.success())?;
    d.set_item("t_reached", sol.t_reached)?;
    d.set_item("stiff", stiffness_dict(py, sol.stiffness)?)?;
    d.set_item("sol", sol.dense.map(|inner| PyDenseSolution { inner }))?;
    Ok(d)
}

fn invalid_setting(py: Python<'_>, e: integrator::InputError) -> PyErr {
    let class = match e {
        integrator::InputError::OutputTooLarge { .. } => "OutOfMemoryError",
        _ => "InvalidInputError",
    };
    py_error(py, class, e.to_string())
}

// ---------------------------------------------------------------------------------------------
// Stiffness detection (rust/integrator): the `stiffness` keyword of `rk45` and `simulate_scene`,
// and `rk45`'s `stiff` entry.
// ---------------------------------------------------------------------------------------------

/// `"warn"` (default: detect, report, steps unchanged), `"stop"` or `"off"`.
fn stiffness_arg(py: Python<'_>, name: &str) -> PyResult<integrator::StiffnessCheck> {
    match name {
        "warn" => Ok(integrator::StiffnessCheck::Warn),
        "stop" => Ok(integrator::StiffnessCheck::Stop),
        "off" => Ok(integrator::StiffnessCheck::Off),
        other => Err(invalid(
            py,
            "stiffness",
            "'warn' (detect and report), 'stop' (stop at the detection) or 'off'",
            format!("'{other}'"),
        )),
    }
}

/// `None`, or `{"t", "h_lambda", "h", "lambda"}` of the first detection.
fn stiffness_dict<'py>(
    py: Python<'py>,
    s: Option<integrator::Stiffness>,
) -> PyResult<Bound<'py, PyAny>> {
    match s {
        None => Ok(py.None().into_bound(py)),
        Some(s) => {
            let d = PyDict::new(py);
            d.set_item("t", s.t)?;
            d.set_item("h_lambda", s.h_lambda)?;
            d.set_item("h", s.h)?;
            d.set_item("lambda", s.lambda())?;
            Ok(d.into_any())
        }
    }
}
