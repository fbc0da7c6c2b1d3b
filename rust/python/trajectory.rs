//! A run's result as one typed object (`_core.RunResult`, its status a `_core.RunStatus`
//! variant), not a dict: `pointmass_dyn.SimulationResult` is built from its getters.
use crate::python::Obj;
use pyo3::prelude::*;

use super::convert::{to_array, to_array1};
use super::record::Field;
use crate::integrator::{status_variants, NonFiniteKind, Status};
use crate::simulate::Trajectory;
use pyo3::types::{IntoPyDict, PyTuple};
use pyo3::IntoPyObjectExt;

macro_rules! declare_py_status {
    ([$($(#[$doc:meta])* $v:ident $({ $($f:ident: $t:ty),* })?,)*] []) => {
        /// How a run ended, one variant per cause (the core's `Status`, `status_variants!`):
        /// `t` the time the run reached, `at` where the failure (or interruption) happened.
        #[pyclass(name = "RunStatus", module = "pointmass_dyn._core", frozen)]
        #[derive(Clone, Debug)]
        pub enum PyRunStatus {
            $($(#[$doc])* $v { $($($f: $t),*)? },)*
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
status_variants!(declare_py_status);

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
        NonFiniteKind::from_arg(&*obj)
    }
}

#[pymethods]
impl PyRunStatus {
    /// `RunStatus.Interrupted(t=0.5, at=0.51, reason='...')`: the variant and its fields.
    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let slf = slf.as_any();
        let name = format!("RunStatus.{}", slf.get_type().name()?);
        super::record::repr(slf, &name, &Self::fields(slf)?)
    }

    /// Pickled as its variant called with its fields (a result's `outcome` travels with it).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Obj<'py>, Bound<'py, PyTuple>)> {
        let slf = slf.as_any();
        let values = Self::fields(slf)?.into_iter().map(|f| slf.getattr(f));
        let values = PyTuple::new(slf.py(), values.collect::<PyResult<Vec<_>>>()?)?;
        Ok((slf.get_type().into_any(), values))
    }
}

impl PyRunStatus {
    /// The variant's field names, in its constructor's order.
    fn fields(slf: &Obj) -> PyResult<Vec<String>> {
        slf.get_type().getattr("__match_args__")?.extract()
    }
}

/// The fields `RunResult` and `OdeSolution` share: the counters and outcome, named alike in
/// the core's `Trajectory` and `integrator::Solution` (`r.run`), listed here once, and
/// `error`: the exception a Python callback (or Ctrl-C) stopped the run with.
macro_rules! run_record {
    ($(#[$m:meta])* $ty:ident($name:literal, $inner:ty) { $($f:ident: $conv:expr,)* }) => {
        $crate::python::record::record!($(#[$m])* $ty($name, $inner) {
            $($f: $conv,)*
            nfev: |r: &$inner, py| r.run.nfev.field(py),
            njev: |r: &$inner, py| r.run.njev.field(py),
            nlu: |r: &$inner, py| r.run.nlu.field(py),
            n_accepted: |r: &$inner, py| r.run.n_accepted.field(py),
            n_rejected: |r: &$inner, py| r.run.n_rejected.field(py),
            method: |r: &$inner, py| r.run.method.name().into_bound_py_any(py),
            switched_to: |r: &$inner, py| r.run.switched_to.map(|m| m.name()).into_bound_py_any(py),
            t_switch: |r: &$inner, py| r.run.t_switch.into_bound_py_any(py),
            status: |r: &$inner, py| r.run.status.code().into_bound_py_any(py),
            // Numbers in exponent form where `{}` wrote hundreds of digits (as our errors').
            message: |r: &$inner, py| $crate::support::error::compact_numbers(&r.run.message).field(py),
            success: |r: &$inner, py| r.run.status.is_success().into_bound_py_any(py),
            t_reached: |r: &$inner, py| r.run.t_reached.field(py),
            error: |r: &$inner, py| r.error.as_ref().into_bound_py_any(py),
        });
    };
}
pub(super) use run_record;

/// A run of `simulate_scene`, a batch or a `Simulator`: its trajectory, events in the
/// caller's order (a batch run that never started: `RunStatus.NotStarted`, the trajectory's
/// message saying why).
pub struct Run {
    run: Trajectory,
    error: Option<Py<PyAny>>,
}

// One run's result (docstring: `_core.pyi`; `pointmass_dyn.SimulationResult` wraps it).
run_record!(
    PyRunResult("RunResult", Run) {
        t: |r: &Run, py| r.run.t.field(py),
        q: |r: &Run, py| to_array(py, r.run.q.clone(), &[r.run.t.len(), r.run.nq]),
        v: |r: &Run, py| to_array(py, r.run.v.clone(), &[r.run.t.len(), r.run.nv]),
        energy: |r: &Run, py| r.run.energy.as_ref().map(|e| to_array1(py, e)).into_bound_py_any(py),
        constraint_residual: |r: &Run, py| r.run.constraint_residual.as_ref().map(|e| to_array1(py, e)).into_bound_py_any(py),
        constraint_drift: |r: &Run, py| r.run.constraint_drift.into_bound_py_any(py),
        singular_passage: |r: &Run, py| r.run.singular_passage.into_bound_py_any(py),
        singular_crossings: |r: &Run, py| r.run.singular_crossings.into_bound_py_any(py),
        // Power of each enabled effect by its label.
        power: |r: &Run, py| {
            let columns = r.run.power_columns().map(|p| p.into_iter().map(|(l, c)| (l, to_array1(py, &c))));
            columns.map(|c| c.into_py_dict(py)).transpose()?.into_bound_py_any(py)
        },
        t_events: |r: &Run, py| r.run.t_events.field(py),
        q_events: |r: &Run, py| r.run.event_matrices(false).field(py),
        v_events: |r: &Run, py| r.run.event_matrices(true).field(py),
        outcome: |r: &Run, py| PyRunStatus::from(&r.run.status).into_bound_py_any(py),
    }
);

impl PyRunResult {
    /// `traj`, stopped by `error` if a Python callback (or Ctrl-C) raised it.
    pub(super) fn new(py: Python<'_>, traj: Trajectory, error: Option<PyErr>) -> Self {
        let error = error.map(|e| e.into_value(py).into_any());
        PyRunResult(Run { run: traj, error })
    }
}
