//! `Model`: one class, its methods declared by concept in the files beside this one
//! (pyo3's `multiple-pymethods`): the tree and its names ([`structure`]), importers
//! ([`import`]), kinematics and DeNOC matrices ([`kinematics`]), dynamics and derivatives
//! ([`dynamics`]), closed loops ([`loops`]), shaking and bearing forces ([`reactions`]). Each
//! converts arguments, calls the core (`crate::dynamics::shared` holds the versions and the workspace
//! pool) and converts the result.
use crate::python::Obj;
use std::sync::Arc;

use pyo3::prelude::*;

use crate::dynamics::shared::{SharedModel, Version, Workspace};
use crate::model::Model;
use crate::python::convert::vector_into;
use crate::python::errors::IntoPyResult;

mod calls;
mod couplings;
mod dynamics;
mod frames;
mod ik;
mod import;
mod kinematics;
mod loops;
mod reactions;
mod structure;

#[pyclass(name = "Model", module = "pointmass_dyn._core", frozen)]
pub struct PyModel {
    shared: SharedModel,
}

/// The typed results of `Model`'s methods (rust/python/record.rs), for the module.
pub fn add_records(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<import::PyRepair>()?;
    m.add_class::<ik::PyIkSolution>()?;
    m.add_class::<kinematics::PyDenoc>()?;
    m.add_class::<kinematics::PyDenocRates>()?;
    m.add_class::<loops::PyLoopLayout>()?;
    m.add_class::<reactions::PyPointMotion>()?;
    m.add_class::<reactions::PyBearingForces>()
}

/// `f` here, or detached from the interpreter when `detach` (a long chain:
/// `crate::dynamics::calls::worth_detaching`).
fn sized<T: Send>(py: Python<'_>, detach: bool, f: impl FnOnce() -> T + Send) -> T {
    match detach {
        true => py.detach(f),
        false => f(),
    }
}

/// Reads q (and v) into the workspace's buffers and validates them.
fn load_state(ws: &mut Workspace, py: Python<'_>, q: &Obj, v: Option<&Obj>) -> PyResult<()> {
    vector_into(q, "q", &mut ws.q)?;
    if let Some(v) = v {
        vector_into(v, "v", &mut ws.v)?;
    }
    ws.check_state(v.is_some()).py(py)
}

/// Reads the argument that is not a state (τ or a) into the workspace and validates it.
fn load_x(ws: &mut Workspace, py: Python<'_>, x: &Obj, arg: &str) -> PyResult<()> {
    vector_into(x, arg, &mut ws.x)?;
    crate::support::error::check_finite(arg, &ws.x).py(py)
}

/// A model and a checked state `(q, v)`.
type State = (Arc<Model>, Vec<f64>, Vec<f64>);

impl PyModel {
    pub fn from_model(model: Model) -> Self {
        Self::from_shared(Arc::new(model))
    }

    /// A model sharing `model` (a scene's, another model's), its joint records included:
    /// nothing is copied until one of them adds a body.
    pub fn from_shared(model: Arc<Model>) -> Self {
        PyModel {
            shared: SharedModel::new(model),
        }
    }

    /// Changes what no computation depends on (visuals, name): the dynamics' workspaces
    /// stay valid, so the version is kept.
    pub fn update_model(&self, f: impl FnOnce(&mut Model)) {
        self.shared.update_presentation(f);
    }

    /// The model as it is now (shared, immutable).
    pub fn model(&self) -> Arc<Model> {
        self.shared.model()
    }

    /// The source file's joints and repairs (empty for a model built body by body).
    pub fn records(&self) -> Arc<crate::model::joint_records::JointRecords> {
        self.model().records.clone()
    }

    fn version(&self) -> Version {
        self.shared.version()
    }

    /// Runs `f` with a workspace of the current model (the pool's, `crate::dynamics::shared`).
    fn with_workspace<R>(&self, f: impl FnOnce(&mut Workspace) -> PyResult<R>) -> PyResult<R> {
        self.shared.with_workspace(f)
    }

    /// The current model and a checked `q` (and `v`: empty when `None`), each named in
    /// errors as given (`crate::model::args::state`), for the calls that need no workspace.
    fn state_as(&self, q: (&Obj, &str), v: Option<(&Obj, &str)>) -> PyResult<State> {
        let model = self.model();
        let (q, v) = crate::model::args::state(&model, q, v)?;
        Ok((model, q, v))
    }
}
