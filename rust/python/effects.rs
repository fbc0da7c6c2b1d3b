//! `Effect`: the constructors of the effect families and the parsers of their arguments;
//! Python torque functions as Rust callbacks.
use std::cell::RefCell;
use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;

use super::convert::{array, int_arg, opt_real, real, shape_str, vec3, vector};
use super::errors::{invalid, IntoPyResult};
use super::options::given;
use crate::effects::{
    ContactPoint, Damper, Effect, External, Frame, Friction, GroundContact, JointLimit, JointRef,
    Matrix, PerJoint, PointSpring, Spring, Table, Torque, TorqueFunction, TorqueLimit,
};

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

impl From<Effect> for PyEffect {
    fn from(inner: Effect) -> Self {
        PyEffect { inner }
    }
}

thread_local! {
    /// The first exception a Python torque function raised during the current call (the
    /// integration runs on the calling thread, detached from the interpreter).
    static CALLBACK_ERROR: RefCell<Option<PyErr>> = const { RefCell::new(None) };
}

pub(super) fn take_callback_error() -> Option<PyErr> {
    CALLBACK_ERROR.with(|c| c.borrow_mut().take())
}

pub(super) fn repr_of(obj: &Bound<'_, PyAny>) -> String {
    obj.repr().map(|r| r.to_string()).unwrap_or_default()
}

/// A body name or index.
pub(super) fn joint_ref(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<JointRef> {
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

/// Contact points: a sequence of `(body, [x, y, z])` or `(body, [x, y, z], radius)`.
fn contact_points_arg(obj: &Bound<'_, PyAny>) -> PyResult<Vec<ContactPoint>> {
    const EXPECTED: &str =
        "a sequence of (body, [x, y, z]) or (body, [x, y, z], radius): a body name or index, a point in its frame";
    let py = obj.py();
    if obj.extract::<String>().is_ok() {
        return Err(invalid(py, "points", EXPECTED, repr_of(obj)));
    }
    let items = obj
        .try_iter()
        .map_err(|_| invalid(py, "points", EXPECTED, repr_of(obj)))?;
    let mut out = Vec::new();
    for (k, item) in items.enumerate() {
        let item = item?;
        let arg = format!("points[{k}]");
        let parts: Vec<Bound<'_, PyAny>> = match item.try_iter() {
            Ok(it) if item.extract::<String>().is_err() => it.collect::<PyResult<_>>()?,
            _ => return Err(invalid(py, &arg, EXPECTED, repr_of(&item))),
        };
        let (body, point, radius) = match parts.as_slice() {
            [b, p] => (b, p, 0.0),
            [b, p, r] => (b, p, real(r, &format!("{arg} radius"))?),
            _ => return Err(invalid(py, &arg, EXPECTED, repr_of(&item))),
        };
        out.push(ContactPoint {
            body: joint_ref(body, &arg)?,
            point: vec3(point, &arg)?,
            radius,
        });
    }
    Ok(out)
}

/// A torque limit: None, `"effort"` or one number / one per speed.
fn torque_limit_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<TorqueLimit>> {
    Ok(match given(obj) {
        None => None,
        Some(x) if x.extract::<String>().is_ok_and(|s| s == "effort") => Some(TorqueLimit::Effort),
        Some(x) => Some(TorqueLimit::given(per_joint_arg(x, "limit")?).py(x.py())?),
    })
}

/// A body name or index, or the world (`"world"`, −1 or `None`): `None` for the world.
fn body_or_world(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Option<JointRef>> {
    const EXPECTED: &str =
        "a body name (str) or index (int >= 0), or 'world' / -1 / None for the ground";
    if obj.is_none() {
        return Ok(None);
    }
    if let Ok(s) = obj.extract::<String>() {
        return Ok((s != "world").then_some(JointRef::Name(s)));
    }
    if obj.is_instance_of::<pyo3::types::PyBool>() || obj.extract::<i64>().is_err() {
        return Err(invalid(obj.py(), arg, EXPECTED, repr_of(obj)));
    }
    match int_arg(obj, arg, -1, i64::MAX, EXPECTED)? {
        -1 => Ok(None),
        i => Ok(Some(JointRef::Index(i as usize))),
    }
}

/// `None` (every moving joint), one body name or index, or a sequence of them.
pub(super) fn joints_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<JointRef>>> {
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
pub(super) fn per_joint_arg(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<PerJoint> {
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
pub(super) fn matrix_arg(obj: &Bound<'_, PyAny>, arg: &str) -> PyResult<Matrix> {
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

pub(super) fn table_arg(
    py: Python<'_>,
    time: &Bound<'_, PyAny>,
    values: &Bound<'_, PyAny>,
    values_arg: &str,
) -> PyResult<Table> {
    let t = vector(time, "time", None)?;
    let m = matrix_arg(values, values_arg)?;
    Table::new(t, m, "time", values_arg).py(py)
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
                        crate::support::error::check_finite("torque function f(t, q, v)", &x)
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
            _ => crate::support::spatial::Vec3::new(0.0, 0.0, -9.81),
        };
        Ok(Effect::gravity(g).py(py)?.into())
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
        let rest = given(rest).map(|r| per_joint_arg(r, "rest")).transpose()?;
        Ok(Effect::Spring(Spring::new(name, joints, k, rest).py(py)?).into())
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
        Ok(Effect::Damper(Damper::new(name, joints, c).py(py)?).into())
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
        Ok(Effect::Friction(Friction::new(name, joints, f, v_eps).py(py)?).into())
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
        Ok(Effect::Torque(Torque::constant(name, joints, tau).py(py)?).into())
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
        Ok(Effect::Torque(Torque::tabulated(name, joints, table).py(py)?).into())
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
        Ok(Effect::Torque(Torque::pd(name, joints, kp, kd, table).py(py)?).into())
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
        Ok(Effect::Torque(Torque::function(name, torque_callback(f.clone().unbind()))).into())
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
        let point = match given(point) {
            Some(p) => vec3(p, "point")?,
            None => crate::support::spatial::Vec3::zeros(),
        };
        let frame = Frame::parse(frame, "frame").py(py)?;
        let (force, moment) = (given(force), given(moment));
        if force.is_none() && moment.is_none() {
            return Err(invalid(py, "force", "a force (or a moment)", "None"));
        }
        let inner = match given(time) {
            Some(t) => {
                let t = vector(t, "time", None)?;
                let f = force.map(|f| matrix_arg(f, "force")).transpose()?;
                let m = moment.map(|m| matrix_arg(m, "moment")).transpose()?;
                External::tabulated(name, body, point, t, f, m, frame).py(py)?
            }
            None => {
                let zero = crate::support::spatial::Vec3::zeros();
                let f = force.map(|f| vec3(f, "force")).transpose()?.unwrap_or(zero);
                let m = moment
                    .map(|m| vec3(m, "moment"))
                    .transpose()?
                    .unwrap_or(zero);
                External::constant(name, body, point, f, m, frame).py(py)?
            }
        };
        Ok(Effect::External(inner).into())
    }

    /// A linear spring–damper between a point of body a and a point of body b (each in its
    /// body's frame; the world: `"world"`, −1 or `None`).
    #[staticmethod]
    #[pyo3(signature = (body_a, point_a, body_b, point_b, stiffness, rest_length=None, damping=None, name=None))]
    #[allow(clippy::too_many_arguments)]
    fn point_spring(
        py: Python<'_>,
        body_a: &Bound<'_, PyAny>,
        point_a: &Bound<'_, PyAny>,
        body_b: &Bound<'_, PyAny>,
        point_b: &Bound<'_, PyAny>,
        stiffness: &Bound<'_, PyAny>,
        rest_length: Option<&Bound<'_, PyAny>>,
        damping: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let body_a = body_or_world(body_a, "body_a")?;
        let point_a = vec3(point_a, "point_a")?;
        let body_b = body_or_world(body_b, "body_b")?;
        let point_b = vec3(point_b, "point_b")?;
        let k = real(stiffness, "stiffness")?;
        let rest = opt_real(rest_length, "rest_length")?.unwrap_or(0.0);
        let c = opt_real(damping, "damping")?.unwrap_or(0.0);
        let inner = PointSpring::new(name, body_a, point_a, body_b, point_b, k, rest, c).py(py)?;
        Ok(Effect::PointSpring(inner).into())
    }

    /// Compliant contact of body points (or spheres) with a plane: Hunt–Crossley normal
    /// force, regularised Coulomb friction. `stiffness`/`damping` `None`: the defaults from
    /// the model's weight, filled in when a scene is built.
    #[staticmethod]
    #[pyo3(signature = (points, normal, height, stiffness, exponent, damping, friction, v_eps, name=None))]
    #[allow(clippy::too_many_arguments)]
    fn ground_contact(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        normal: &Bound<'_, PyAny>,
        height: &Bound<'_, PyAny>,
        stiffness: Option<&Bound<'_, PyAny>>,
        exponent: &Bound<'_, PyAny>,
        damping: Option<&Bound<'_, PyAny>>,
        friction: &Bound<'_, PyAny>,
        v_eps: &Bound<'_, PyAny>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let inner = GroundContact::new(
            name,
            contact_points_arg(points)?,
            vec3(normal, "normal")?,
            real(height, "height")?,
            opt_real(stiffness, "stiffness")?,
            real(exponent, "exponent")?,
            opt_real(damping, "damping")?,
            real(friction, "friction")?,
            real(v_eps, "v_eps")?,
        )
        .py(py)?;
        Ok(Effect::GroundContact(inner).into())
    }

    /// Compliant joint ranges (one-sided spring–dampers outside `[lower, upper]`); bounds
    /// `None`: the model's own, filled in when a scene is built.
    #[staticmethod]
    #[pyo3(signature = (joints, lower, upper, stiffness, damping, name=None))]
    fn joint_limit(
        py: Python<'_>,
        joints: Option<&Bound<'_, PyAny>>,
        lower: Option<&Bound<'_, PyAny>>,
        upper: Option<&Bound<'_, PyAny>>,
        stiffness: &Bound<'_, PyAny>,
        damping: &Bound<'_, PyAny>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let joints = joints_arg(joints)?;
        let lower = given(lower)
            .map(|x| per_joint_arg(x, "lower"))
            .transpose()?;
        let upper = given(upper)
            .map(|x| per_joint_arg(x, "upper"))
            .transpose()?;
        let k = per_joint_arg(stiffness, "stiffness")?;
        let c = per_joint_arg(damping, "damping")?;
        Ok(Effect::JointLimit(JointLimit::new(name, joints, lower, upper, k, c).py(py)?).into())
    }

    /// A ground contact's points along states `q` (N, nq), `v` (N, nv): a dict of
    /// `position` (N, P, 3), `penetration` (N, P), `normal_force` (N, P), `force` (N, P, 3).
    fn contact_state<'py>(
        &self,
        py: Python<'py>,
        model: PyRef<'_, super::model::PyModel>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let Effect::GroundContact(c) = &self.inner else {
            return Err(invalid(
                py,
                "self",
                "a GroundContact effect",
                format!("a {} effect", self.inner.kind().name()),
            ));
        };
        let m = model.model();
        let (qs, qv) = array(q, "q")?;
        let (vs, vv) = array(v, "v")?;
        if qs.len() != 2 || qs[1] != m.nq || vs.len() != 2 || vs[1] != m.nv || vs[0] != qs[0] {
            return Err(invalid(
                py,
                "q, v",
                format!("arrays (N, {}) and (N, {})", m.nq, m.nv),
                format!("{} and {}", shape_str(&qs), shape_str(&vs)),
            ));
        }
        let s = c.states(&m, &qv, &vv).py(py)?;
        // Finite states, but a law whose numbers overflow there (a damping of 1e307).
        for (what, x) in [
            ("position", &s.position),
            ("penetration", &s.penetration),
            ("normal_force", &s.normal_force),
            ("force", &s.force),
        ] {
            super::errors::check_result(py, &format!("contact_state['{what}']"), x)?;
        }
        let (n, np) = (qs[0], s.points);
        let d = pyo3::types::PyDict::new(py);
        let to = super::convert::to_array;
        d.set_item("position", to(py, s.position, &[n, np, 3])?)?;
        d.set_item("penetration", to(py, s.penetration, &[n, np])?)?;
        d.set_item("normal_force", to(py, s.normal_force, &[n, np])?)?;
        d.set_item("force", to(py, s.force, &[n, np, 3])?)?;
        Ok(d)
    }

    /// A torque effect clamped per speed at `limit`: one number or one per speed of its
    /// joints (all `nv` for a torque function), or `"effort"` (the model's URDF `effort`,
    /// filled in when a scene is built); None removes the limit.
    fn with_torque_limit(
        &self,
        py: Python<'_>,
        limit: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let Effect::Torque(t) = &self.inner else {
            return Err(invalid(
                py,
                "limit",
                "a torque effect (JointTorque, TabulatedTorque, PDTorque, TorqueFunction)",
                format!("a {} effect", self.inner.kind().name()),
            ));
        };
        let limit = torque_limit_arg(limit)?;
        Ok(Effect::Torque(t.clone().with_limit(limit)).into())
    }

    /// A torque effect's limit on each of `model`'s speeds (inf where unlimited or not
    /// driven; all inf for another effect).
    fn torque_limit_per_speed<'py>(
        &self,
        py: Python<'py>,
        model: PyRef<'_, super::model::PyModel>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let m = model.model();
        let out = match &self.inner {
            Effect::Torque(t) => t.limit_per_speed(&m).py(py)?,
            _ => vec![f64::INFINITY; m.nv],
        };
        Ok(super::convert::to_array1(py, &out).into_any())
    }

    /// A torque effect's limit: a number or an array (per speed), `"effort"` (until a scene
    /// fills it in), or None.
    #[getter]
    fn torque_limit<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        let Effect::Torque(t) = &self.inner else {
            return None;
        };
        Some(match t.limit.as_ref()? {
            TorqueLimit::Effort => pyo3::types::PyString::new(py, "effort").into_any(),
            TorqueLimit::Given(PerJoint::All(x)) => pyo3::types::PyFloat::new(py, *x).into_any(),
            TorqueLimit::Given(PerJoint::Each(v)) => super::convert::to_array1(py, v).into_any(),
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
    /// A copy with one parameter replaced (checked as the factory checks it): gravity `g`;
    /// a spring's `stiffness`, `rest`; a damper's `damping`; friction's `friction`, `v_eps`;
    /// a point spring's `stiffness`, `rest_length`, `damping`.
    fn with_parameter(
        &self,
        py: Python<'_>,
        name: &str,
        value: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let (_, values) = super::convert::array(value, name)?;
        Ok(self.inner.with_parameter(name, &values).py(py)?.into())
    }
    /// A ground contact's law parameters: a dict of `height`, `stiffness`, `exponent`,
    /// `damping`, `friction`, `v_eps` (`stiffness`/`damping` None until a scene fills in
    /// their defaults: the scene's effects hold the values it runs with); `None` for other
    /// effects.
    #[getter]
    fn contact_parameters<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<Bound<'py, pyo3::types::PyDict>>> {
        let Effect::GroundContact(c) = &self.inner else {
            return Ok(None);
        };
        let d = pyo3::types::PyDict::new(py);
        d.set_item("height", c.height)?;
        d.set_item("stiffness", c.stiffness)?;
        d.set_item("exponent", c.exponent)?;
        d.set_item("damping", c.damping)?;
        d.set_item("friction", c.friction)?;
        d.set_item("v_eps", c.v_eps)?;
        Ok(Some(d))
    }
    /// A gravity effect's acceleration `g` (3,); `None` for other effects.
    #[getter]
    #[pyo3(name = "g")]
    fn gravity_vector<'py>(&self, py: Python<'py>) -> Option<Bound<'py, numpy::PyArray1<f64>>> {
        match &self.inner {
            Effect::Gravity { g } => Some(super::convert::to_array1(py, g.as_slice())),
            _ => None,
        }
    }
    /// A ground contact's plane `n · x = height`: `(n, height)`, `n` (3,) the unit normal out
    /// of the ground; `None` for other effects.
    #[getter]
    fn plane<'py>(&self, py: Python<'py>) -> Option<(Bound<'py, numpy::PyArray1<f64>>, f64)> {
        match &self.inner {
            Effect::GroundContact(c) => {
                Some((super::convert::to_array1(py, c.normal.as_slice()), c.height))
            }
            _ => None,
        }
    }
    /// The effect's scene-file `[[effect]]` table as a dict (`type`, `name`, its keys;
    /// docs/scenes.md): every parameter it holds, SI units and radians. Raises
    /// `InvalidInputError` for a torque function (Python code no file can state).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let table = self.inner.to_toml().py(py)?;
        toml_to_py(py, &toml::Value::Table(table))
    }
    fn __repr__(&self) -> String {
        self.inner.repr()
    }
    fn __eq__(&self, other: PyRef<'_, PyEffect>) -> bool {
        self.inner == other.inner
    }
}

/// A TOML value as Python data (dicts, lists, str, int, float, bool).
fn toml_to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    use pyo3::IntoPyObjectExt;
    Ok(match v {
        toml::Value::String(s) => s.into_bound_py_any(py)?,
        toml::Value::Integer(i) => i.into_bound_py_any(py)?,
        toml::Value::Float(x) => x.into_bound_py_any(py)?,
        toml::Value::Boolean(b) => b.into_bound_py_any(py)?,
        toml::Value::Datetime(d) => d.to_string().into_bound_py_any(py)?,
        toml::Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| toml_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            pyo3::types::PyList::new(py, items)?.into_any()
        }
        toml::Value::Table(t) => {
            let d = pyo3::types::PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, toml_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}
