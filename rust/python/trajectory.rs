//! A run's result as one typed object (`_core.RunResult`, its status a `_core.RunStatus`
//! variant), not a dict: `pointmass_dyn.SimulationResult` is built from its getters.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::convert::{to_array, to_array1};
use crate::integrator::{status_variants, NonFiniteKind, Status};
use crate::simulate::Trajectory;
use crate::support::error::compact_numbers;

macro_rules! declare_py_status {
    ([$($(#[$doc:meta])* $v:ident $({ $($f:ident: $t:ty),* })?,)*]
     [$($(#[$xdoc:meta])* $x:ident { $($xf:ident: $xt:ty),* },)*]) => {
        /// How a run ended, one variant per cause: `t` the time the run reached, `at` where
        /// the failure (or interruption) happened. The core's `Status` variants
        /// (`status_variants!`), plus `NotStarted` for a run of a batch whose input was refused.
        #[pyclass(name = "RunStatus", module = "pointmass_dyn._core", frozen)]
        #[derive(Clone, Debug)]
        pub enum PyRunStatus {
            $($(#[$doc])* $v { $($($f: $t),*)? },)*
            $($(#[$xdoc])* $x { $($xf: $xt),* },)*
        }

        impl From<&Status> for PyRunStatus {
            fn from(s: &Status) -> Self {
                match s.clone() {
                    $(Status::$v $({ $($f),* })? => Self::$v { $($($f),*)? },)*
                }
            }
        }
    };
}
status_variants!(
    declare_py_status,
    /// A run of a batch that never started: its input was refused, or the batch stopped.
    NotStarted { reason: String },
);

/// `NonFinite.what` in Python: "derivative", "state" or "jacobian".
impl<'py> IntoPyObject<'py> for NonFiniteKind {
    type Target = pyo3::types::PyString;
    type Output = Bound<'py, Self::Target>;
    type Error = std::convert::Infallible;
    fn into_pyobject(self, py: Python<'py>) -> Result<Self::Output, Self::Error> {
        Ok(pyo3::types::PyString::new(py, self.name()))
    }
}

impl FromPyObject<'_, '_> for NonFiniteKind {
    type Error = PyErr;
    fn extract(obj: Borrowed<'_, '_, PyAny>) -> PyResult<Self> {
        let name: String = obj.extract()?;
        let kind = NonFiniteKind::ALL.into_iter().find(|k| k.name() == name);
        kind.ok_or_else(|| {
            super::errors::invalid(obj.py(), "what", "derivative, state or jacobian", name)
        })
    }
}

#[pymethods]
impl PyRunStatus {
    /// `RunStatus.Interrupted(t=0.5, at=0.51, reason='...')`: the variant and its fields.
    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let (name, args) = Self::variant(slf)?;
        let fields: Vec<String> = Self::fields(slf)?
            .into_iter()
            .zip(args.iter())
            .map(|(f, v)| Ok(format!("{f}={}", v.repr()?)))
            .collect::<PyResult<_>>()?;
        Ok(format!("RunStatus.{name}({})", fields.join(", ")))
    }

    /// Pickled as its variant called with its fields (a result's `outcome` travels with it).
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Obj<'py>, Bound<'py, pyo3::types::PyTuple>)> {
        Ok((slf.as_any().get_type().into_any(), Self::variant(slf)?.1))
    }
}

impl PyRunStatus {
    /// The variant's field names, in its constructor's order.
    fn fields(slf: &Bound<'_, Self>) -> PyResult<Vec<String>> {
        slf.as_any().get_type().getattr("__match_args__")?.extract()
    }

    /// The variant's name and its fields' values.
    fn variant<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(String, Bound<'py, pyo3::types::PyTuple>)> {
        let values = Self::fields(slf)?
            .iter()
            .map(|f| slf.as_any().getattr(f.as_str()))
            .collect::<PyResult<Vec<_>>>()?;
        let name = slf.as_any().get_type().name()?.to_string();
        Ok((name, pyo3::types::PyTuple::new(slf.py(), values)?))
    }
}

/// One run's trajectory and outcome, the fields `pointmass_dyn.SimulationResult` has of the
/// same names; `error`: the exception a Python callback (or Ctrl-C) stopped the run with,
/// or the one that refused a batch run's input.
#[pyclass(name = "RunResult", module = "pointmass_dyn._core", frozen, get_all)]
pub struct PyRunResult {
    t: Py<PyAny>,
    q: Py<PyAny>,
    v: Py<PyAny>,
    energy: Option<Py<PyAny>>,
    constraint_residual: Option<Py<PyAny>>,
    constraint_drift: Option<f64>,
    singular_passage: Option<(f64, f64)>,
    singular_crossings: Option<(usize, Option<f64>)>,
    /// Power of each enabled effect by its label.
    power: Option<Py<PyDict>>,
    t_events: Py<PyList>,
    q_events: Py<PyList>,
    v_events: Py<PyList>,
    nfev: usize,
    njev: usize,
    nlu: usize,
    n_accepted: usize,
    n_rejected: usize,
    method: &'static str,
    switched_to: Option<&'static str>,
    t_switch: Option<f64>,
    /// SciPy's code: 0 end reached, 1 terminal event, -1 failure.
    status: i32,
    outcome: PyRunStatus,
    message: String,
    success: bool,
    t_reached: f64,
    error: Option<Py<PyAny>>,
}

impl PyRunResult {
    /// `traj` with its events in the caller's order (`slots[k]`: the trajectory's slot of
    /// the caller's event `k`).
    pub(super) fn new(
        py: Python<'_>,
        traj: Trajectory,
        slots: &[usize],
        error: Option<PyErr>,
    ) -> PyResult<Self> {
        let (n, nq, nv) = (traj.t.len(), traj.nq, traj.nv);
        let (te, qe, ve) = (PyList::empty(py), PyList::empty(py), PyList::empty(py));
        for &slot in slots {
            let times = &traj.t_events[slot];
            te.append(to_array1(py, times))?;
            let m = times.len();
            let mut qs = Vec::with_capacity(m * nq);
            let mut vs = Vec::with_capacity(m * nv);
            for row in traj.y_events[slot].chunks_exact(nq + nv) {
                qs.extend_from_slice(&row[..nq]);
                vs.extend_from_slice(&row[nq..]);
            }
            qe.append(to_array(py, qs, &[m, nq])?)?;
            ve.append(to_array(py, vs, &[m, nv])?)?;
        }
        let power = match &traj.power {
            Some(p) => Some(power_dict(py, p, n, &traj.effect_labels)?.unbind()),
            None => None,
        };
        let array1 =
            |x: &Option<Vec<f64>>| x.as_ref().map(|e| to_array1(py, e).into_any().unbind());
        Ok(PyRunResult {
            t: to_array1(py, &traj.t).into_any().unbind(),
            energy: array1(&traj.energy),
            constraint_residual: array1(&traj.constraint_residual),
            q: to_array(py, traj.q, &[n, nq])?.unbind(),
            v: to_array(py, traj.v, &[n, nv])?.unbind(),
            constraint_drift: traj.constraint_drift,
            singular_passage: traj.singular_passage,
            singular_crossings: traj.singular_crossings,
            power,
            t_events: te.unbind(),
            q_events: qe.unbind(),
            v_events: ve.unbind(),
            nfev: traj.nfev,
            njev: traj.njev,
            nlu: traj.nlu,
            n_accepted: traj.n_accepted,
            n_rejected: traj.n_rejected,
            method: traj.method.name(),
            switched_to: traj.switched_to.map(|m| m.name()),
            t_switch: traj.t_switch,
            status: traj.status.code(),
            outcome: PyRunStatus::from(&traj.status),
            // Numbers in exponent form where `{}` wrote hundreds of digits (as our errors').
            message: compact_numbers(&traj.message),
            success: traj.status.is_success(),
            t_reached: traj.t_reached,
            error: error.map(|e| e.into_value(py).into_any()),
        })
    }

    /// A batch run that never started: `error` refused its input (or the batch stopped
    /// before it, `message` then says by what).
    pub(super) fn not_started(
        py: Python<'_>,
        error: PyErr,
        message: Option<String>,
    ) -> PyResult<Self> {
        let message = match message {
            Some(m) => m,
            None => {
                let name = error.get_type(py).name()?.to_string();
                format!("{name}: {}", error.value(py).str()?)
            }
        };
        let mut r = Self::new(
            py,
            Trajectory::not_started(message.clone()),
            &[],
            Some(error),
        )?;
        (r.status, r.success) = (-1, false);
        r.outcome = PyRunStatus::NotStarted { reason: message };
        Ok(r)
    }
}

/// The power columns (row-major N × labels) as a dict from the effect's label to an array.
fn power_dict<'py>(
    py: Python<'py>,
    p: &[f64],
    n: usize,
    labels: &[String],
) -> PyResult<Bound<'py, PyDict>> {
    let m = labels.len();
    let pd = PyDict::new(py);
    for (k, label) in labels.iter().enumerate() {
        let col: Vec<f64> = (0..n).map(|i| p[i * m + k]).collect();
        pd.set_item(label, to_array1(py, &col))?;
    }
    Ok(pd)
}
