//! `Joint` and `Model`: the tree, kinematics and both dynamics paths.
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::body::PyRigidBody;
use super::convert::{dmatrix_to_array, mat3, points, to_array, to_array1, vec3, vector_into};
use super::errors::{check_result, invalid, IntoPyResult};
use super::signals::detach_interruptible;
use crate::alloc::try_zeros;
use crate::denoc;
use crate::joint::Joint;
use crate::kinematics;
use crate::loops::{self, LoopSolver};
use crate::model::Model;
use crate::reactions;
use crate::recursive::{self, Data};
use crate::spatial::{Placement, Vec3, Vec6};

/// Link count above which the recursive calls release the GIL (below it, the release costs
/// more than it frees).
const DETACH_LINKS: usize = 64;

#[pyclass(name = "Joint", module = "pointmass_dyn._core", frozen, from_py_object)]
#[derive(Clone)]
pub struct PyJoint {
    pub inner: Joint,
}

#[pymethods]
impl PyJoint {
    #[staticmethod]
    fn revolute(py: Python<'_>, axis: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyJoint {
            inner: Joint::revolute(vec3(axis, "axis")?).py(py)?,
        })
    }
    #[staticmethod]
    fn prismatic(py: Python<'_>, axis: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyJoint {
            inner: Joint::prismatic(vec3(axis, "axis")?).py(py)?,
        })
    }
    #[staticmethod]
    fn spherical_zyz() -> Self {
        PyJoint {
            inner: Joint::SphericalZYZ,
        }
    }
    #[staticmethod]
    fn spherical() -> Self {
        PyJoint {
            inner: Joint::Spherical,
        }
    }
    #[staticmethod]
    fn fixed() -> Self {
        PyJoint {
            inner: Joint::Fixed,
        }
    }
    #[staticmethod]
    fn free_flyer() -> Self {
        PyJoint {
            inner: Joint::FreeFlyer,
        }
    }
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }
    #[getter]
    fn nq(&self) -> usize {
        self.inner.nq()
    }
    #[getter]
    fn nv(&self) -> usize {
        self.inner.nv()
    }
    #[getter]
    fn axis<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        match self.inner {
            Joint::Revolute { axis } | Joint::Prismatic { axis } => {
                Some(to_array1(py, axis.as_slice()).into_any())
            }
            _ => None,
        }
    }
    fn __repr__(&self) -> String {
        match self.inner {
            Joint::Revolute { axis } | Joint::Prismatic { axis } => {
                format!(
                    "{}(axis=[{}, {}, {}])",
                    self.inner.kind(),
                    axis.x,
                    axis.y,
                    axis.z
                )
            }
            _ => format!("{}()", self.inner.kind()),
        }
    }
}

/// One version of a model: replaced, never mutated, by `add_body`, so calls in flight, scenes
/// and copies share it without locks.
#[derive(Clone)]
pub struct Version {
    pub model: Arc<Model>,
    /// The URDF joints (names, limits, damping, friction) of a model from `from_urdf`.
    pub urdf_joints: Arc<Vec<crate::urdf::UrdfJoint>>,
    /// What `from_urdf(..., repair=...)` changed (empty otherwise).
    pub repairs: Arc<Vec<crate::urdf::RepairRecord>>,
    id: u64,
}

static NEXT_VERSION: AtomicU64 = AtomicU64::new(1);

fn next_version() -> u64 {
    NEXT_VERSION.fetch_add(1, Ordering::Relaxed)
}

/// The buffers of one call: taken from the model's pool, so any number of threads can use
/// one `Model` at once, and put back for the next call.
struct Workspace {
    version: Version,
    data: Data,
    q: Vec<f64>,
    v: Vec<f64>,
    x: Vec<f64>,
    out: Vec<f64>,
    /// The closed-loop solver's buffers (models with loops only).
    loops: Option<Box<LoopSolver>>,
    /// The derivatives' buffers (built on the first derivative call).
    deriv: Option<Box<recursive::DerivativeData>>,
}

impl Workspace {
    fn new(version: Version) -> Self {
        let m = &version.model;
        let (nq, nv) = (m.nq, m.nv);
        Workspace {
            data: Data::new(m),
            q: vec![0.0; nq],
            v: vec![0.0; nv],
            x: vec![0.0; nv],
            out: vec![0.0; nv],
            loops: (!m.loops.is_empty()).then(|| Box::new(LoopSolver::new(m))),
            deriv: None,
            version,
        }
    }

    fn model(&self) -> &Model {
        &self.version.model
    }

    /// Reads q (and v) into the buffers and validates them.
    fn load_state(
        &mut self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        v: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        vector_into(q, "q", &mut self.q)?;
        if let Some(v) = v {
            vector_into(v, "v", &mut self.v)?;
        }
        self.version
            .model
            .check_state(&self.q, v.map(|_| self.v.as_slice()))
            .py(py)
    }

    fn load_x(&mut self, py: Python<'_>, x: &Bound<'_, PyAny>, arg: &str) -> PyResult<()> {
        vector_into(x, arg, &mut self.x)?;
        crate::error::check_finite(arg, &self.x).py(py)
    }
}

/// Workspaces kept for reuse per model (more threads than this allocate their own).
const POOL: usize = 4;

#[pyclass(name = "Model", module = "pointmass_dyn._core", frozen)]
pub struct PyModel {
    current: Mutex<Version>,
    /// `current.id`, readable without the lock on every call.
    current_id: AtomicU64,
    pool: Mutex<Vec<Box<Workspace>>>,
}

/// `None` means no gravity: a model computes only what it is asked for.
pub fn gravity_arg(py: Python<'_>, gravity: Option<&Bound<'_, PyAny>>) -> PyResult<Vec3> {
    match gravity {
        Some(g) if !g.is_none() => {
            let g = vec3(g, "gravity")?;
            crate::error::check_finite("gravity", g.as_slice()).py(py)?;
            Ok(g)
        }
        _ => Ok(Vec3::zeros()),
    }
}

enum Method {
    Recursive,
    Denoc,
}

fn method_arg(py: Python<'_>, method: &str) -> PyResult<Method> {
    match method {
        "recursive" => Ok(Method::Recursive),
        "denoc" => Ok(Method::Denoc),
        other => Err(invalid(
            py,
            "method",
            "'recursive' or 'denoc'",
            format!("'{other}'"),
        )),
    }
}

#[derive(Clone, Copy)]
enum Direction {
    Forward,
    Inverse,
}

impl Direction {
    fn name(self) -> &'static str {
        match self {
            Direction::Forward => "forward_dynamics",
            Direction::Inverse => "inverse_dynamics",
        }
    }
    /// The argument that is not a state: τ for forward dynamics, a for inverse.
    fn input(self) -> &'static str {
        match self {
            Direction::Forward => "tau",
            Direction::Inverse => "a",
        }
    }
}

impl PyModel {
    /// Forward or inverse dynamics on either path: one place validates, dispatches, releases
    /// the GIL for large models and checks the result.
    #[allow(clippy::too_many_arguments)]
    fn dynamics<'py>(
        &self,
        py: Python<'py>,
        direction: Direction,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        x: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
        external: Option<&Bound<'_, PyAny>>,
        method: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let method = method_arg(py, method)?;
        let g = gravity_arg(py, gravity)?;
        self.with_workspace(|ws| {
            ws.load_state(py, q, Some(v))?;
            ws.load_x(py, x, direction.input())?;
            let ext = external_wrenches(ws.model(), external)?;
            let Workspace {
                version,
                data,
                q: qv,
                v: vv,
                x: xv,
                out,
                loops: solver,
                ..
            } = ws;
            let model: &Model = &version.model;
            // With loops, the tree's accelerations are corrected by the cut joints' forces.
            let mut close = |data: &mut Data, out: &mut [f64]| match (direction, solver.as_mut()) {
                (Direction::Forward, Some(solver)) => {
                    loops::constrained_forward_dynamics(model, data, solver, qv, vv, out).py(py)
                }
                _ => Ok(()),
            };
            match method {
                Method::Recursive => {
                    let mut run = || match direction {
                        Direction::Forward => recursive::forward_dynamics(
                            model,
                            data,
                            qv,
                            vv,
                            xv,
                            &g,
                            ext.as_deref(),
                            out,
                        ),
                        Direction::Inverse => {
                            recursive::inverse_dynamics(
                                model,
                                data,
                                qv,
                                vv,
                                xv,
                                &g,
                                ext.as_deref(),
                                out,
                            );
                            Ok(())
                        }
                    };
                    if model.links.len() >= DETACH_LINKS {
                        py.detach(run)
                    } else {
                        run()
                    }
                    .py(py)?;
                    close(data, out)?;
                    check_result(py, direction.name(), out)?;
                    Ok(to_array1(py, out).into_any())
                }
                Method::Denoc => {
                    if ext.is_some() {
                        return Err(invalid(
                            py,
                            "external",
                            "None with method='denoc' (apply point forces with generalized_forces)",
                            "wrenches",
                        ));
                    }
                    let mut out = detach_interruptible(py, || match direction {
                        Direction::Forward => denoc::forward_dynamics(model, qv, vv, xv, &g),
                        Direction::Inverse => denoc::inverse_dynamics(model, qv, vv, xv, &g),
                    })?;
                    close(data, out.as_mut_slice())?;
                    check_result(py, direction.name(), out.as_slice())?;
                    Ok(to_array1(py, out.as_slice()).into_any())
                }
            }
        })
    }

    /// Forward or inverse dynamics derivatives: validates, runs (GIL released for large
    /// models) and returns the three nv × nv matrices.
    #[allow(clippy::too_many_arguments)]
    fn derivatives<'py>(
        &self,
        py: Python<'py>,
        direction: Direction,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        x: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let g = gravity_arg(py, gravity)?;
        let name = match direction {
            Direction::Forward => "forward_dynamics_derivatives",
            Direction::Inverse => "inverse_dynamics_derivatives",
        };
        self.with_workspace(|ws| {
            if !ws.model().loops.is_empty() {
                return Err(invalid(
                    py,
                    "model",
                    format!("a tree for {name} (closed loops are not differentiated)"),
                    format!("a model with {} loop(s)", ws.model().loops.len()),
                ));
            }
            ws.load_state(py, q, Some(v))?;
            ws.load_x(py, x, direction.input())?;
            let Workspace {
                version,
                data,
                q: qv,
                v: vv,
                x: xv,
                deriv,
                ..
            } = ws;
            let model: &Model = &version.model;
            let dd = deriv.get_or_insert_with(|| Box::new(recursive::DerivativeData::new(model)));
            let mut run = || match direction {
                Direction::Forward => {
                    recursive::forward_dynamics_derivatives(model, data, dd, qv, vv, xv, &g)
                }
                Direction::Inverse => {
                    recursive::inverse_dynamics_derivatives(model, data, dd, qv, vv, xv, &g);
                    Ok(())
                }
            };
            if model.links.len() >= DETACH_LINKS {
                py.detach(run)
            } else {
                run()
            }
            .py(py)?;
            let (a, b, c) = match direction {
                Direction::Forward => (&dd.ddq_dq, &dd.ddq_dv, &dd.minv),
                Direction::Inverse => (&dd.dtau_dq, &dd.dtau_dv, &dd.mass),
            };
            for m in [a, b, c] {
                if !all_finite(m.as_slice()) {
                    check_result(py, name, m.as_slice())?;
                }
            }
            // `c` (M or M⁻¹) is exactly symmetric: its column-major data is its C order.
            Ok((
                square_to_array(py, a).into_any(),
                square_to_array(py, b).into_any(),
                symmetric_to_array(py, c).into_any(),
            ))
        })
    }

    pub fn from_model(model: Model) -> Self {
        Self::from_parts(Arc::new(model), Arc::new(Vec::new()))
    }

    /// A model sharing `model` (a scene's, another model's): nothing is copied until one of
    /// them adds a body.
    pub fn from_parts(model: Arc<Model>, urdf_joints: Arc<Vec<crate::urdf::UrdfJoint>>) -> Self {
        Self::from_parts_repaired(model, urdf_joints, Arc::new(Vec::new()))
    }

    /// [`PyModel::from_parts`] with the repairs a URDF load made.
    pub fn from_parts_repaired(
        model: Arc<Model>,
        urdf_joints: Arc<Vec<crate::urdf::UrdfJoint>>,
        repairs: Arc<Vec<crate::urdf::RepairRecord>>,
    ) -> Self {
        let id = next_version();
        PyModel {
            current: Mutex::new(Version {
                model,
                urdf_joints,
                repairs,
                id,
            }),
            current_id: AtomicU64::new(id),
            pool: Mutex::new(Vec::new()),
        }
    }

    /// The model as it is now (shared, immutable).
    pub fn model(&self) -> Arc<Model> {
        self.version().model.clone()
    }

    /// Changes what no computation depends on (visuals, name): the dynamics' workspaces
    /// stay valid, so the version is kept.
    pub fn update_model(&self, f: impl FnOnce(&mut Model)) {
        f(Arc::make_mut(&mut self.version().model));
    }

    /// The URDF joints of a model from `from_urdf` (empty otherwise).
    pub fn urdf_joints(&self) -> Arc<Vec<crate::urdf::UrdfJoint>> {
        self.version().urdf_joints.clone()
    }

    /// The repairs of a model from `from_urdf(..., repair=...)` (empty otherwise).
    pub fn repair_records(&self) -> Arc<Vec<crate::urdf::RepairRecord>> {
        self.version().repairs.clone()
    }

    fn version(&self) -> MutexGuard<'_, Version> {
        // A thread that panicked while holding the lock left a whole `Version` behind: the
        // value is still consistent, so a poisoned lock is taken as it is.
        self.current.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn pool(&self) -> MutexGuard<'_, Vec<Box<Workspace>>> {
        self.pool.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Runs `f` with a workspace of the current model: one from the pool when there is one
    /// of this version, otherwise a new one (put back afterwards for the next call).
    fn with_workspace<R>(&self, f: impl FnOnce(&mut Workspace) -> PyResult<R>) -> PyResult<R> {
        let id = self.current_id.load(Ordering::Acquire);
        let reused = self.pool().pop().filter(|ws| ws.version.id == id);
        let mut ws = match reused {
            Some(ws) => ws,
            None => Box::new(Workspace::new(self.version().clone())),
        };
        let result = f(&mut ws);
        if ws.version.id == self.current_id.load(Ordering::Acquire) {
            let mut pool = self.pool();
            if pool.len() < POOL {
                pool.push(ws);
            }
        }
        result
    }
}

/// Whether every value is finite, in one vectorisable pass (`x · 0` is NaN exactly for a
/// non-finite `x`; eight independent lanes); `check_result` then names the first bad index.
fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let chunks = x.chunks_exact(8);
    let rest = chunks.remainder();
    for ch in chunks {
        for (a, v) in acc.iter_mut().zip(ch) {
            *a += v * 0.0;
        }
    }
    for (a, v) in acc.iter_mut().zip(rest) {
        *a += v * 0.0;
    }
    acc.iter().all(|a| *a == 0.0)
}

/// A NumPy copy of an exactly symmetric matrix: its column-major data, copied as it is.
fn symmetric_to_array<'py>(
    py: Python<'py>,
    m: &nalgebra::DMatrix<f64>,
) -> Bound<'py, numpy::PyArray2<f64>> {
    use numpy::{PyArray2, PyArrayMethods};
    let (r, c) = (m.nrows(), m.ncols());
    // SAFETY: a new C-contiguous array of exactly r × c elements, all written.
    unsafe {
        let arr = PyArray2::<f64>::new(py, [r, c], false);
        std::ptr::copy_nonoverlapping(m.as_ptr(), arr.data(), r * c);
        arr
    }
}

/// A C-ordered NumPy copy of a (column-major) matrix, written in one pass.
fn square_to_array<'py>(
    py: Python<'py>,
    m: &nalgebra::DMatrix<f64>,
) -> Bound<'py, numpy::PyArray2<f64>> {
    use numpy::{PyArray2, PyArrayMethods};
    let (r, c) = (m.nrows(), m.ncols());
    // SAFETY: a new C-contiguous array of exactly r × c elements, every one written before
    // it is handed to Python.
    unsafe {
        let arr = PyArray2::<f64>::new(py, [r, c], false);
        let src = m.as_slice();
        let dst = arr.data();
        // By 8 × 8 tiles: each tile's reads and writes stay within a few cache lines.
        const T: usize = 8;
        for j0 in (0..c).step_by(T) {
            for i0 in (0..r).step_by(T) {
                for j in j0..(j0 + T).min(c) {
                    for i in i0..(i0 + T).min(r) {
                        // In bounds: i < r, j < c.
                        *dst.add(i * c + j) = *src.get_unchecked(j * r + i);
                    }
                }
            }
        }
        arr
    }
}

fn external_wrenches(model: &Model, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<Vec6>>> {
    match obj {
        Some(f) if !f.is_none() => {
            let (shape, data) = super::convert::array(f, "external")?;
            let n = model.links.len();
            if shape != [n, 6] {
                return Err(invalid(f.py(), "external", format!("shape ({n}, 6): one wrench [moment about the link origin; force] per moving link, world axes"), super::convert::shape_str(&shape)));
            }
            crate::error::check_finite("external", &data).py(f.py())?;
            Ok(Some(
                data.chunks_exact(6).map(Vec6::from_column_slice).collect(),
            ))
        }
        _ => Ok(None),
    }
}

#[pymethods]
impl PyModel {
    #[new]
    fn new() -> Self {
        PyModel::from_model(Model::new())
    }

    /// Adds a body; returns its index. See the package docs for the arguments.
    #[pyo3(signature = (body, joint, parent=None, translation=None, rotation=None, name=None, point_mass_center=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_body(
        &self,
        py: Python<'_>,
        body: PyRef<'_, PyRigidBody>,
        joint: PyRef<'_, PyJoint>,
        parent: Option<&Bound<'_, PyAny>>,
        translation: Option<&Bound<'_, PyAny>>,
        rotation: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
        point_mass_center: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<usize> {
        let t = match translation {
            Some(t) if !t.is_none() => vec3(t, "translation")?,
            _ => Vec3::zeros(),
        };
        let r = match rotation {
            Some(r) if !r.is_none() => mat3(r, "rotation")?,
            _ => crate::spatial::Mat3::identity(),
        };
        let center = match point_mass_center {
            Some(c) if !c.is_none() => Some(vec3(c, "point_mass_center")?),
            _ => None,
        };
        // -1 (or None) is the world; any int is taken (no OverflowError), a non-int is a TypeError.
        let parent = match parent.filter(|p| !p.is_none()) {
            None => -1,
            Some(p) => super::convert::int_arg(
                p,
                "parent",
                i64::MIN,
                i64::MAX,
                "-1 (the world) or a body index >= 0",
            )?,
        };
        let mut version = self.version();
        let parent = match parent {
            -1 => None,
            p if p >= 0 => Some(p as usize),
            p => {
                return Err(super::errors::py_error(
                    py,
                    "ModelStructureError",
                    format!(
                        "parent: expected -1 (the world) or a body index 0..{}, got {p}",
                        version.model.nbodies()
                    ),
                ))
            }
        };
        // Copy-on-write: a model shared with a scene, a copy or a call in flight is copied
        // once; a model built body by body is extended in place (amortised O(1) per body).
        let k = Arc::make_mut(&mut version.model)
            .add_body(
                body.inner,
                joint.inner,
                parent,
                Placement::new(r, t),
                name,
                center,
            )
            .py(py)?;
        version.id = next_version();
        self.current_id.store(version.id, Ordering::Release);
        drop(version);
        self.pool().clear();
        Ok(k)
    }

    #[getter]
    fn nq(&self) -> usize {
        self.version().model.nq
    }
    #[getter]
    fn nv(&self) -> usize {
        self.version().model.nv
    }
    #[getter]
    fn nbodies(&self) -> usize {
        self.version().model.nbodies()
    }
    /// Moving links (bodies on Fixed joints are welded into their parent's link).
    #[getter]
    fn nlinks(&self) -> usize {
        self.version().model.links.len()
    }
    #[getter]
    fn body_names(&self) -> Vec<String> {
        let m = self.model();
        m.bodies.iter().map(|b| b.name.clone()).collect()
    }
    /// Names of the bodies that define each moving link, in q/v order.
    #[getter]
    fn link_names(&self) -> Vec<String> {
        let m = self.model();
        m.links
            .iter()
            .map(|l| m.bodies[l.body].name.clone())
            .collect()
    }
    #[getter]
    fn total_mass(&self) -> f64 {
        self.model().total_mass()
    }
    /// Per body: (name, joint kind, parent index or -1, link index or -1).
    fn body_info(
        &self,
        py: Python<'_>,
        index: &Bound<'_, PyAny>,
    ) -> PyResult<(String, String, i64, i64)> {
        let index = super::convert::count_arg(index, "index", "a body index >= 0")?;
        let m = self.model();
        let b = m.bodies.get(index).ok_or_else(|| {
            super::errors::py_error(
                py,
                "ModelStructureError",
                format!("index: no body {index} (the model has {})", m.nbodies()),
            )
        })?;
        Ok((
            b.name.clone(),
            b.joint.kind().to_string(),
            b.parent.map(|p| p as i64).unwrap_or(-1),
            b.link.map(|p| p as i64).unwrap_or(-1),
        ))
    }
    /// (q index, v index, nq, nv) of each link's joint.
    fn joint_slices(&self) -> Vec<(usize, usize, usize, usize)> {
        self.model()
            .links
            .iter()
            .map(|l| (l.q_index, l.v_index, l.joint.nq(), l.joint.nv()))
            .collect()
    }

    fn neutral<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, &self.model().neutral()).into_any()
    }

    /// World placements of every body at `q`: (rotations (nbodies, 3, 3), origins (nbodies, 3)).
    fn placements<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.with_workspace(|ws| {
            ws.load_state(py, q, None)?;
            let model: &Model = &ws.version.model;
            kinematics::positions(model, &ws.q, &mut ws.data.links);
            let nb = model.nbodies();
            let mut rots = Vec::with_capacity(9 * nb);
            let mut origins = Vec::with_capacity(3 * nb);
            for b in 0..nb {
                let p = kinematics::body_placement(model, &ws.data.links, b);
                rots.extend_from_slice(p.rotation.transpose().as_slice());
                origins.extend_from_slice(p.translation.as_slice());
            }
            check_result(py, "placements", &origins)?;
            Ok((
                to_array(py, rots, &[nb, 3, 3])?,
                to_array(py, origins, &[nb, 3])?,
            ))
        })
    }

    /// Everything a viewer draws, at one configuration (q (nq,)) or N (q (N, nq)): dict of
    /// world-frame arrays `rotations` ((N,) nbodies, 3, 3), `origins`, `joint_origins`,
    /// `joint_axes` ((N,) nbodies, 3), `points` ((N,) nlinks, 7, 3) and per cut joint
    /// `loop_a`, `loop_b`, `loop_axes` ((N,) nloops, 3). (docs/visualisation.md §2)
    fn body_poses<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let model = self.model();
        let (sq, qs) = super::convert::array(q, "q")?;
        let count = match sq.as_slice() {
            [n] if *n == model.nq => None,
            [rows, n] if *n == model.nq => Some(*rows),
            _ => {
                return Err(invalid(
                    py,
                    "q",
                    format!("shape ({0},) or (N, {0})", model.nq),
                    super::convert::shape_str(&sq),
                ))
            }
        };
        let rows = count.unwrap_or(1);
        for k in 0..rows {
            let qk = &qs[k * model.nq..(k + 1) * model.nq];
            model
                .check_state(qk, None)
                .map_err(|e| match count {
                    Some(_) => e.map_arg(|name| format!("{name}[{k}]")),
                    None => e,
                })
                .py(py)?;
        }
        let poses = detach_interruptible(py, || {
            let mut poses = crate::poses::Poses::new(&model, rows)?;
            for k in 0..rows {
                crate::interrupt::check("body_poses")?;
                poses.fill(&model, k, &qs[k * model.nq..(k + 1) * model.nq]);
            }
            Ok(poses)
        })?;
        let (nb, nl, nc) = (model.nbodies(), model.links.len(), model.loops.len());
        let shape = |tail: &[usize]| -> Vec<usize> {
            count
                .map(|n| vec![n])
                .unwrap_or_default()
                .into_iter()
                .chain(tail.iter().copied())
                .collect()
        };
        let d = PyDict::new(py);
        for (key, buf, tail) in [
            ("rotations", poses.rotations, vec![nb, 3, 3]),
            ("origins", poses.origins, vec![nb, 3]),
            ("joint_origins", poses.joint_origins, vec![nb, 3]),
            ("joint_axes", poses.joint_axes, vec![nb, 3]),
            ("points", poses.points, vec![nl, 7, 3]),
            ("loop_a", poses.loop_a, vec![nc, 3]),
            ("loop_b", poses.loop_b, vec![nc, 3]),
            ("loop_axes", poses.loop_axes, vec![nc, 3]),
        ] {
            check_result(py, &format!("body_poses['{key}']"), &buf)?;
            d.set_item(key, to_array(py, buf, &shape(&tail))?)?;
        }
        Ok(d)
    }

    /// The seven point masses of every moving link: (masses (nlinks, 7), world positions
    /// (nlinks, 7, 3)) at `q`.
    fn point_masses<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.with_workspace(|ws| {
            ws.load_state(py, q, None)?;
            let (masses, points) = denoc::point_positions(ws.model(), &ws.q);
            let n = ws.model().links.len();
            let pts = points.transpose().as_slice().to_vec();
            check_result(py, "point_masses", &pts)?;
            Ok((
                to_array(py, masses.as_slice().to_vec(), &[n, 7])?,
                to_array(py, pts, &[n, 7, 3])?,
            ))
        })
    }

    /// The DeNOC matrices at `q`: dict with D, Nl, Nd, N, masses (7n,), points (7n, 3).
    fn denoc<'py>(&self, py: Python<'py>, q: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyDict>> {
        let (model, qv) = self.state_only(py, q)?;
        let den = detach_interruptible(py, || denoc::matrices(&model, &qv))?;
        for (k, m) in [("D", &den.d), ("N", &den.n), ("points", &den.points)] {
            check_result(py, &format!("denoc['{k}']"), m.as_slice())?;
        }
        let d = PyDict::new(py);
        d.set_item("D", dmatrix_to_array(py, &den.d)?)?;
        d.set_item("Nl", dmatrix_to_array(py, &den.nl)?)?;
        d.set_item("Nd", dmatrix_to_array(py, &den.nd)?)?;
        d.set_item("N", dmatrix_to_array(py, &den.n)?)?;
        d.set_item("masses", to_array1(py, den.masses.as_slice()))?;
        d.set_item("points", dmatrix_to_array(py, &den.points)?)?;
        Ok(d)
    }

    /// Time derivatives of the DeNOC matrices at `(q, v)`: dict with D, Nl, Nd, N.
    fn denoc_rates<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (model, qv, vv) = self.state(py, q, v)?;
        let (_, rates) = detach_interruptible(py, || denoc::matrices_and_rates(&model, &qv, &vv))?;
        for (k, m) in [("D", &rates.d), ("N", &rates.n)] {
            check_result(py, &format!("denoc_rates['{k}']"), m.as_slice())?;
        }
        let d = PyDict::new(py);
        d.set_item("D", dmatrix_to_array(py, &rates.d)?)?;
        d.set_item("Nl", dmatrix_to_array(py, &rates.nl)?)?;
        d.set_item("Nd", dmatrix_to_array(py, &rates.nd)?)?;
        d.set_item("N", dmatrix_to_array(py, &rates.n)?)?;
        Ok(d)
    }

    /// Generalized inertia matrix (GIM), nv × nv.
    #[pyo3(signature = (q, method="recursive"))]
    fn mass_matrix<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        method: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let method = method_arg(py, method)?;
        match method {
            Method::Recursive => self.with_workspace(|ws| {
                ws.load_state(py, q, None)?;
                let nv = ws.model().nv;
                let mut gim = try_zeros(nv, nv, "mass_matrix").py(py)?;
                let Workspace {
                    version,
                    data,
                    q: qv,
                    ..
                } = ws;
                let model: &Model = &version.model;
                // O(n·depth): long chains are worth releasing the interpreter for.
                if model.links.len() >= DETACH_LINKS {
                    py.detach(|| recursive::mass_matrix(model, data, qv, &mut gim));
                } else {
                    recursive::mass_matrix(model, data, qv, &mut gim);
                }
                check_result(py, "mass_matrix", gim.as_slice())?;
                dmatrix_to_array(py, &gim)
            }),
            Method::Denoc => {
                let (model, qv) = self.state_only(py, q)?;
                let m = detach_interruptible(py, || denoc::mass_matrix(&model, &qv))?;
                check_result(py, "mass_matrix", m.as_slice())?;
                dmatrix_to_array(py, &m)
            }
        }
    }

    /// Convective matrix `C = Nᵀ M Ṅ` (explicit DeNOC products).
    fn convective_matrix<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (model, qv, vv) = self.state(py, q, v)?;
        let c = detach_interruptible(py, || denoc::convective_matrix(&model, &qv, &vv))?;
        check_result(py, "convective_matrix", c.as_slice())?;
        dmatrix_to_array(py, &c)
    }

    /// Generalized gravity force `Nᵀ f^G` (right-hand side; Pinocchio's
    /// `computeGeneralizedGravity` is its negative).
    fn gravity_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        gravity: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let g = gravity_arg(py, Some(gravity))?;
        let (model, qv) = self.state_only(py, q)?;
        let tg = detach_interruptible(py, || denoc::gravity_forces(&model, &qv, &g))?;
        check_result(py, "gravity_forces", tg.as_slice())?;
        Ok(to_array1(py, tg.as_slice()).into_any())
    }

    /// `Nᵀ f` for forces on the point masses, shape (nlinks, 7, 3) or (7·nlinks, 3), world.
    fn generalized_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        forces: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (model, qv) = self.state_only(py, q)?;
        let f = points(forces, "forces")?;
        for p in &f {
            crate::error::check_finite("forces", p.as_slice()).py(py)?;
        }
        let tau = detach_interruptible(py, || denoc::generalized_forces(&model, &qv, &f))?;
        check_result(py, "generalized_forces", tau.as_slice())?;
        Ok(to_array1(py, tau.as_slice()).into_any())
    }

    /// Bias forces `C v − τ_g` (Pinocchio's `nonLinearEffects`).
    #[pyo3(signature = (q, v, gravity=None))]
    fn bias_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let g = gravity_arg(py, gravity)?;
        self.with_workspace(|ws| {
            ws.load_state(py, q, Some(v))?;
            ws.x.fill(0.0);
            recursive::inverse_dynamics(
                &ws.version.model,
                &mut ws.data,
                &ws.q,
                &ws.v,
                &ws.x,
                &g,
                None,
                &mut ws.out,
            );
            check_result(py, "bias_forces", &ws.out)?;
            Ok(to_array1(py, &ws.out).into_any())
        })
    }

    /// Accelerations from `I a + C v = τ + τ_g + τ_ext`.
    #[pyo3(signature = (q, v, tau, gravity=None, external=None, method="recursive"))]
    #[allow(clippy::too_many_arguments)]
    fn forward_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
        external: Option<&Bound<'_, PyAny>>,
        method: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.dynamics(py, Direction::Forward, q, v, tau, gravity, external, method)
    }

    /// Joint forces `τ = I a + C v − τ_g − τ_ext`. With loops, the forces of the `actuated`
    /// coordinates alone (the cut joints carry the rest).
    #[pyo3(signature = (q, v, a, gravity=None, external=None, method="recursive", actuated=None))]
    #[allow(clippy::too_many_arguments)]
    fn inverse_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
        external: Option<&Bound<'_, PyAny>>,
        method: &str,
        actuated: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let model = self.model();
        let Some(actuated) = super::loops::loop_actuation(py, &model, actuated)? else {
            return self.dynamics(py, Direction::Inverse, q, v, a, gravity, external, method);
        };
        let tree = self.dynamics(py, Direction::Inverse, q, v, a, gravity, external, method)?;
        let tau_tree = super::convert::vector(&tree, "tau", Some(model.nv))?;
        self.with_workspace(|ws| {
            ws.load_state(py, q, Some(v))?;
            ws.load_x(py, a, "a")?;
            let model: &Model = &ws.version.model;
            let solver = ws
                .loops
                .get_or_insert_with(|| Box::new(LoopSolver::new(model)));
            let (tau, _) =
                loops::driving_forces(model, solver, &ws.q, &ws.v, &ws.x, &tau_tree, &actuated)
                    .py(py)?;
            check_result(py, "inverse_dynamics", &tau)?;
            Ok(to_array1(py, &tau).into_any())
        })
    }

    /// `(∂τ/∂q, ∂τ/∂v, ∂τ/∂a = M)` of the inverse dynamics at `(q, v, a)`, each nv × nv;
    /// `q` is perturbed in the tangent space (`q ⊕ δ`, docs/derivatives.md).
    #[pyo3(signature = (q, v, a, gravity=None))]
    fn inverse_dynamics_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.derivatives(py, Direction::Inverse, q, v, a, gravity)
    }

    /// `(∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ = M⁻¹)` of the forward dynamics at `(q, v, τ)`, each nv × nv;
    /// `q` is perturbed in the tangent space (`q ⊕ δ`, docs/derivatives.md).
    #[pyo3(signature = (q, v, tau, gravity=None))]
    fn forward_dynamics_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.derivatives(py, Direction::Forward, q, v, tau, gravity)
    }

    /// Body `body`'s own rigid body (mass, COM and inertia in its frame), as added.
    fn body(&self, py: Python<'_>, body: &Bound<'_, PyAny>) -> PyResult<PyRigidBody> {
        let model = self.model();
        let b = super::loops::body_ref(&model, Some(body), "body")?.ok_or_else(|| {
            invalid(
                py,
                "body",
                "a body of the model (not the world)",
                "the world",
            )
        })?;
        Ok(PyRigidBody {
            inner: model.bodies[b].body,
        })
    }

    /// A copy of this model with body `body`'s own rigid body replaced by `rigid_body` (its
    /// joint, placement, loops and names kept); this model is unchanged.
    fn with_body(
        &self,
        py: Python<'_>,
        body: &Bound<'_, PyAny>,
        rigid_body: PyRef<'_, PyRigidBody>,
    ) -> PyResult<Self> {
        let ver = self.version().clone();
        let b = super::loops::body_ref(&ver.model, Some(body), "body")?.ok_or_else(|| {
            invalid(
                py,
                "body",
                "a body of the model (not the world)",
                "the world",
            )
        })?;
        let mut model = (*ver.model).clone();
        model.replace_body(b, rigid_body.inner).py(py)?;
        Ok(PyModel::from_parts_repaired(
            Arc::new(model),
            ver.urdf_joints.clone(),
            ver.repairs.clone(),
        ))
    }

    /// Every link's seven point masses in motion at `(q, v, a)`: dict with `masses` (n, 7),
    /// `positions`, `velocities`, `accelerations` (n, 7, 3), world axes, no gravity.
    fn point_motion<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let model = self.model();
        let (count, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
        if count.is_some() {
            return Err(invalid(
                py,
                "q",
                format!("shape ({},): one state", model.nq),
                "a stack of states",
            ));
        }
        let mut ws = recursive::reference::Workspace::new(&model);
        let mut pm = reactions::PointMotion::default();
        reactions::point_motion(&model, &mut ws, &qs, &vs, &accs, &mut pm);
        let n = model.links.len();
        let flat = |x: &[Vec3]| x.iter().flat_map(|p| [p.x, p.y, p.z]).collect::<Vec<f64>>();
        let d = PyDict::new(py);
        d.set_item("masses", to_array(py, pm.masses.clone(), &[n, 7])?)?;
        for (k, x) in [
            ("positions", &pm.positions),
            ("velocities", &pm.velocities),
            ("accelerations", &pm.accelerations),
        ] {
            let f = flat(x);
            check_result(py, &format!("point_motion['{k}']"), &f)?;
            d.set_item(k, to_array(py, f, &[n, 7, 3])?)?;
        }
        Ok(d)
    }

    /// Per point and state, what the balancing regressors need (`docs/balancing.md`): world
    /// `positions` and `accelerations` (N, P, 3) and `generalized` (N, P, nv) `= J_pᵀ (a_p − g)`,
    /// the joint forces that a unit mass at the point needs. `points`: None for every link's
    /// seven point masses (P = 7 n, link by link), or `[(body, [x, y, z]), ...]` points given in
    /// their bodies' frames. q (N, nq), v and a (N, nv), or one state (then N is dropped).
    #[pyo3(signature = (q, v, a, points=None, gravity=None))]
    fn point_regressor<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        points: Option<&Bound<'_, PyAny>>,
        gravity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let model = self.model();
        let g = gravity_arg(py, gravity)?;
        let (count, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
        let pts: Vec<(usize, Vec3)> = match points.filter(|p| !p.is_none()) {
            None => model
                .links
                .iter()
                .enumerate()
                .flat_map(|(i, l)| l.points.positions.iter().map(move |p| (i, *p)))
                .collect(),
            Some(list) => super::reactions::body_points(&model, list)?,
        };
        let rows = count.unwrap_or(1);
        let (nq, nv, np) = (model.nq, model.nv, pts.len());
        let (pos, acc, gen) = detach_interruptible(py, || {
            let mut ws = recursive::reference::Workspace::new(&model);
            let mut pos = Vec::with_capacity(rows * np * 3);
            let mut acc = Vec::with_capacity(rows * np * 3);
            let mut gen = vec![0.0; rows * np * nv];
            for k in 0..rows {
                crate::interrupt::check("point_regressor")?;
                let (qk, vk, ak) = (
                    &qs[k * nq..(k + 1) * nq],
                    &vs[k * nv..(k + 1) * nv],
                    &accs[k * nv..(k + 1) * nv],
                );
                reactions::link_accelerations(&model, &mut ws, qk, vk, ak);
                for (j, (r, _, ap)) in reactions::carried_points(&ws, &pts).iter().enumerate() {
                    pos.extend_from_slice(r.as_slice());
                    acc.extend_from_slice(ap.as_slice());
                    let out = &mut gen[(k * np + j) * nv..(k * np + j + 1) * nv];
                    reactions::add_point_force(&model, &ws, pts[j].0, r, &(ap - g), out);
                }
            }
            Ok((pos, acc, gen))
        })?;
        for (k, x) in [
            ("positions", &pos),
            ("accelerations", &acc),
            ("generalized", &gen),
        ] {
            check_result(py, &format!("point_regressor['{k}']"), x)?;
        }
        let lead: Vec<usize> = count.into_iter().collect();
        let shape = |tail: &[usize]| [lead.as_slice(), tail].concat();
        let d = PyDict::new(py);
        d.set_item("positions", to_array(py, pos, &shape(&[np, 3]))?)?;
        d.set_item("accelerations", to_array(py, acc, &shape(&[np, 3]))?)?;
        d.set_item("generalized", to_array(py, gen, &shape(&[np, nv]))?)?;
        Ok(d)
    }

    /// Shaking force and moment about `about` at one state (q (nq,), v, a (nv,)) or at N
    /// (q (N, nq), v, a (N, nv)): `(force, moment)`, each (3,) or (N, 3).
    #[pyo3(signature = (q, v, a, about=None))]
    fn shaking<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        about: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let model = self.model();
        let (count, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
        let about = match about.filter(|x| !x.is_none()) {
            Some(o) => {
                let o = vec3(o, "about")?;
                crate::error::check_finite("about", o.as_slice()).py(py)?;
                o
            }
            None => Vec3::zeros(),
        };
        let rows = count.unwrap_or(1);
        let (nq, nv) = (model.nq, model.nv);
        let (force, moment) = detach_interruptible(py, || {
            let mut ws = recursive::reference::Workspace::new(&model);
            let mut pm = reactions::PointMotion::default();
            let (mut force, mut moment) =
                (Vec::with_capacity(3 * rows), Vec::with_capacity(3 * rows));
            for k in 0..rows {
                crate::interrupt::check("shaking")?;
                let (qk, vk, ak) = (
                    &qs[k * nq..(k + 1) * nq],
                    &vs[k * nv..(k + 1) * nv],
                    &accs[k * nv..(k + 1) * nv],
                );
                reactions::point_motion(&model, &mut ws, qk, vk, ak, &mut pm);
                let (f, m) = reactions::shaking(&pm, &about);
                force.extend_from_slice(f.as_slice());
                moment.extend_from_slice(m.as_slice());
            }
            Ok((force, moment))
        })?;
        check_result(py, "shaking", &force)?;
        check_result(py, "shaking", &moment)?;
        let shape: Vec<usize> = match count {
            Some(n) => vec![n, 3],
            None => vec![3],
        };
        Ok((to_array(py, force, &shape)?, to_array(py, moment, &shape)?))
    }

    /// The wrench every joint transmits at `(q, v, a)`: dict with `joints` (nlinks, 6),
    /// `[force; moment]` that the parent applies to the link's subtree at the link origin, in
    /// the link's axes (`frame="joint"`) or the world's; `loops` (nloops, 6), the cut joints'
    /// wrenches as `constraint_forces` gives them; `tau` (nv,), the joint forces (the actuated
    /// ones' for a model with loops, zero elsewhere).
    #[pyo3(signature = (q, v, a, gravity=None, external=None, actuated=None, frame="joint"))]
    #[allow(clippy::too_many_arguments)]
    fn bearing_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
        external: Option<&Bound<'_, PyAny>>,
        actuated: Option<&Bound<'_, PyAny>>,
        frame: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let world = super::reactions::world_frame(py, frame)?;
        let model = self.model();
        let g = gravity_arg(py, gravity)?;
        let (count, qs, vs, accs) = super::reactions::states(&model, q, v, a)?;
        if count.is_some() {
            return Err(invalid(
                py,
                "q",
                format!("shape ({},): one state", model.nq),
                "a stack of states",
            ));
        }
        let ext = external_wrenches(&model, external)?;
        let mut cut: Vec<[f64; 6]> = Vec::new();
        let mut tau_loops: Option<Vec<f64>> = None;
        if let Some(act) = super::loops::loop_actuation(py, &model, actuated)? {
            // The actuators' forces and the cut joints' wrenches that produce this motion.
            let mut data = Data::new(&model);
            let mut tree = vec![0.0; model.nv];
            recursive::inverse_dynamics(
                &model,
                &mut data,
                &qs,
                &vs,
                &accs,
                &g,
                ext.as_deref(),
                &mut tree,
            );
            let mut solver = LoopSolver::new(&model);
            let (tau_act, c) =
                loops::driving_forces(&model, &mut solver, &qs, &vs, &accs, &tree, &act).py(py)?;
            (cut, tau_loops) = (c, Some(tau_act));
        }
        let mut ws = recursive::reference::Workspace::new(&model);
        reactions::link_accelerations(&model, &mut ws, &qs, &vs, &accs);
        let mut all_ext = ext.unwrap_or_else(|| vec![Vec6::zeros(); model.links.len()]);
        reactions::add_cut_wrenches(&model, &ws, &cut, &mut all_ext);
        let mut tau = vec![0.0; model.nv];
        let wrenches = reactions::joint_wrenches(
            &model,
            &mut ws,
            &qs,
            &vs,
            &accs,
            &g,
            Some(&all_ext),
            &mut tau,
        );
        let joints: Vec<f64> = wrenches
            .iter()
            .zip(&ws.links)
            .flat_map(|(w, s)| {
                let rot = if world {
                    nalgebra::Matrix3::identity()
                } else {
                    s.rotation
                };
                reactions::in_link_frame(&rot, w)
            })
            .collect();
        check_result(py, "bearing_forces", &joints)?;
        let d = PyDict::new(py);
        d.set_item("joints", to_array(py, joints, &[model.links.len(), 6])?)?;
        let flat: Vec<f64> = cut.iter().flatten().copied().collect();
        d.set_item("loops", to_array(py, flat, &[cut.len(), 6])?)?;
        // With loops, the actuators' forces as solved (exact zeros at the passive joints, as
        // inverse_dynamics), not the joint wrenches' projections (zero only to round-off).
        d.set_item("tau", to_array1(py, tau_loops.as_deref().unwrap_or(&tau)))?;
        Ok(d)
    }

    /// Adds a cut joint closing a kinematic loop; returns its index. See the package docs.
    #[pyo3(signature = (body_a, body_b, joint, translation_a=None, translation_b=None, rotation_a=None, rotation_b=None, name=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_loop(
        &self,
        py: Python<'_>,
        body_a: Option<&Bound<'_, PyAny>>,
        body_b: Option<&Bound<'_, PyAny>>,
        joint: PyRef<'_, PyJoint>,
        translation_a: Option<&Bound<'_, PyAny>>,
        translation_b: Option<&Bound<'_, PyAny>>,
        rotation_a: Option<&Bound<'_, PyAny>>,
        rotation_b: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<usize> {
        let frame = |t: Option<&Bound<'_, PyAny>>,
                     r: Option<&Bound<'_, PyAny>>,
                     ta: &str,
                     ra: &str|
         -> PyResult<Placement> {
            let t = match t.filter(|x| !x.is_none()) {
                Some(t) => vec3(t, ta)?,
                None => Vec3::zeros(),
            };
            let r = match r.filter(|x| !x.is_none()) {
                Some(r) => mat3(r, ra)?,
                None => crate::spatial::Mat3::identity(),
            };
            Ok(Placement::new(r, t))
        };
        let fa = frame(translation_a, rotation_a, "translation_a", "rotation_a")?;
        let fb = frame(translation_b, rotation_b, "translation_b", "rotation_b")?;
        let mut version = self.version();
        let a = super::loops::body_ref(&version.model, body_a, "body_a")?;
        let b = super::loops::body_ref(&version.model, body_b, "body_b")?;
        let k = Arc::make_mut(&mut version.model)
            .add_loop(a, b, joint.inner, fa, fb, name)
            .py(py)?;
        version.id = next_version();
        self.current_id.store(version.id, Ordering::Release);
        drop(version);
        self.pool().clear();
        Ok(k)
    }

    /// Number of cut joints (closed loops).
    #[getter]
    fn nloops(&self) -> usize {
        self.model().nloops()
    }

    /// Number of scalar loop constraints (rows of `constraint_jacobian`).
    #[getter]
    fn nconstraints(&self) -> usize {
        self.model().nconstraints()
    }

    #[getter]
    fn loop_names(&self) -> Vec<String> {
        self.model().loops.iter().map(|l| l.name.clone()).collect()
    }

    /// Position-level residual of every cut joint (frame a's axes; zero when closed).
    fn constraint_residual<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (model, q) = self.state_only(py, q)?;
        let mut kin = loops::LoopKinematics::new(&model);
        kin.positions(&model, &q);
        let mut r = vec![0.0; model.nconstraints()];
        loops::residual(&model, &kin, &mut r);
        check_result(py, "constraint_residual", &r)?;
        Ok(to_array1(py, &r).into_any())
    }

    /// Velocity-level constraint Jacobian `J` (nconstraints × nv): `J v = 0` keeps the loops.
    fn constraint_jacobian<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (model, q) = self.state_only(py, q)?;
        let mut kin = loops::LoopKinematics::new(&model);
        kin.positions(&model, &q);
        let mut j = nalgebra::DMatrix::zeros(model.nconstraints(), model.nv);
        loops::jacobian(&model, &kin, &mut j);
        check_result(py, "constraint_jacobian", j.as_slice())?;
        dmatrix_to_array(py, &j)
    }

    /// The closed configuration nearest `q_guess`, the coordinates in `fixed` held.
    #[pyo3(signature = (q_guess, fixed=None, tol=1e-12, max_iterations=50))]
    fn assemble<'py>(
        &self,
        py: Python<'py>,
        q_guess: &Bound<'_, PyAny>,
        fixed: Option<&Bound<'_, PyAny>>,
        tol: f64,
        max_iterations: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (model, q) = self
            .state_only(py, q_guess)
            .map_err(|e| rename(py, e, "q", "q_guess"))?;
        if !(tol > 0.0 && tol.is_finite()) {
            return Err(invalid(py, "tol", "a positive finite number", tol));
        }
        let mask = super::loops::fixed_mask(&model, fixed)?;
        let q = py
            .detach(|| loops::assemble(&model, &q, &mask, tol, max_iterations))
            .py(py)?;
        Ok(to_array1(py, &q).into_any())
    }

    /// `v_guess` projected onto `J v = 0` (nearest, the speeds in `fixed` held).
    #[pyo3(signature = (q, v_guess, fixed=None))]
    fn assemble_velocity<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v_guess: &Bound<'_, PyAny>,
        fixed: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (model, q, mut v) = self
            .state(py, q, v_guess)
            .map_err(|e| rename(py, e, "v", "v_guess"))?;
        let mask = super::loops::fixed_mask(&model, fixed)?;
        loops::project_velocity_like(&model, &q, None, &mut v, &mask).py(py)?;
        Ok(to_array1(py, &v).into_any())
    }

    /// `a_guess` projected onto `J a + J̇ v = 0` (nearest, the entries in `fixed` held).
    #[pyo3(signature = (q, v, a_guess, fixed=None))]
    fn assemble_acceleration<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a_guess: &Bound<'_, PyAny>,
        fixed: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (model, q, v) = self.state(py, q, v)?;
        let mut a = super::convert::vector(a_guess, "a_guess", Some(model.nv))?;
        crate::error::check_finite("a_guess", &a).py(py)?;
        let mask = super::loops::fixed_mask(&model, fixed)?;
        loops::project_velocity_like(&model, &q, Some(&v), &mut a, &mask).py(py)?;
        Ok(to_array1(py, &a).into_any())
    }

    /// Per loop `[force, moment]` the cut joint applies to body b (minus that on body a) at
    /// frame b's origin, in frame a's axes, under the forces `tau` (shape (nloops, 6)).
    #[pyo3(signature = (q, v, tau, gravity=None, external=None))]
    fn constraint_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
        external: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let g = gravity_arg(py, gravity)?;
        self.with_workspace(|ws| {
            ws.load_state(py, q, Some(v))?;
            ws.load_x(py, tau, "tau")?;
            let ext = external_wrenches(ws.model(), external)?;
            let Workspace {
                version,
                data,
                q,
                v,
                x,
                out,
                loops: solver,
                ..
            } = ws;
            let model: &Model = &version.model;
            recursive::forward_dynamics(model, data, q, v, x, &g, ext.as_deref(), out).py(py)?;
            let solver = solver.get_or_insert_with(|| Box::new(LoopSolver::new(model)));
            let w = loops::constraint_forces(model, data, solver, q, v, out).py(py)?;
            let flat: Vec<f64> = w.iter().flatten().copied().collect();
            check_result(py, "constraint_forces", &flat)?;
            to_array(py, flat, &[w.len(), 6])
        })
    }

    /// Kinetic energy `½ vᵀ I v`.
    fn kinetic_energy(
        &self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<f64> {
        self.with_workspace(|ws| {
            ws.load_state(py, q, Some(v))?;
            let model: &Model = &ws.version.model;
            kinematics::positions(model, &ws.q, &mut ws.data.links);
            kinematics::velocities(model, &ws.q, &ws.v, &mut ws.data.links);
            let e = recursive::kinetic_energy(&ws.data);
            check_result(py, "kinetic_energy", &[e])?;
            Ok(e)
        })
    }

    /// Gravitational potential energy `−Σ m_ij g·x_ij` (zero at the world origin).
    fn potential_energy(
        &self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        gravity: &Bound<'_, PyAny>,
    ) -> PyResult<f64> {
        let g = gravity_arg(py, Some(gravity))?;
        self.with_workspace(|ws| {
            ws.load_state(py, q, None)?;
            kinematics::positions(&ws.version.model, &ws.q, &mut ws.data.links);
            let e = recursive::potential_energy(&ws.data, &g);
            check_result(py, "potential_energy", &[e])?;
            Ok(e)
        })
    }

    /// `q̇` from `v` (differs from `v` only for quaternion joints).
    fn velocity_to_qdot<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.with_workspace(|ws| {
            ws.load_state(py, q, Some(v))?;
            let mut qd = vec![0.0; ws.model().nq];
            ws.model().velocity_to_qdot(&ws.q, &ws.v, &mut qd);
            check_result(py, "velocity_to_qdot", &qd)?;
            Ok(to_array1(py, &qd).into_any())
        })
    }

    fn __repr__(&self) -> String {
        let m = self.model();
        let loops = match m.nloops() {
            0 => String::new(),
            n => format!(", nloops={n}"),
        };
        format!(
            "Model(nbodies={}, nlinks={}, nq={}, nv={}{loops})",
            m.nbodies(),
            m.links.len(),
            m.nq,
            m.nv
        )
    }

    /// Loads a robot from a URDF file (joint order and body names as Pinocchio's
    /// `buildModelFromUrdf`), fixed-base or, with `root_joint="free"`, on a free flyer.
    /// `repair` (None/False, True, a dict or `pmd.InertiaRepair`) allows MuJoCo-style
    /// inertia repairs (docs/robots.md); each change is listed in one `UrdfRepairWarning` and
    /// in `model.repairs`. Raises `UrdfError`; warnings go through `warnings.warn` as
    /// `UrdfWarning`. Mesh URIs (`package://...`) are looked for in `package_dirs` (a path
    /// or a list of paths), `ROS_PACKAGE_PATH` and the file's ancestors (`model.visuals`).
    #[staticmethod]
    #[pyo3(signature = (path, *, root_joint=None, repair=None, package_dirs=None))]
    fn from_urdf(
        py: Python<'_>,
        path: std::path::PathBuf,
        root_joint: Option<&Bound<'_, PyAny>>,
        repair: Option<&Bound<'_, PyAny>>,
        package_dirs: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let package_dirs = crate::python::visuals::package_dirs(py, package_dirs)?;
        let root = match root_joint {
            None => crate::urdf::RootJoint::Fixed,
            Some(r) => match r.extract::<String>().ok().as_deref() {
                Some("fixed") => crate::urdf::RootJoint::Fixed,
                Some("free") => crate::urdf::RootJoint::Free,
                _ => {
                    return Err(invalid(
                        py,
                        "root_joint",
                        "None, \"fixed\" or \"free\"",
                        r.repr().map_or_else(|_| "?".to_string(), |x| x.to_string()),
                    ))
                }
            },
        };
        let repair = repair_options(py, repair)?;
        let urdf =
            crate::urdf::load_urdf_with(&path, root, repair.as_ref(), &package_dirs).py(py)?;
        let warnings = py.import("warnings")?;
        if !urdf.warnings.is_empty() {
            let category = py.import("pointmass_dyn.errors")?.getattr("UrdfWarning")?;
            for w in &urdf.warnings {
                warnings.call_method1("warn", (w.as_str(), &category, 1))?;
            }
        }
        if !urdf.repairs.is_empty() {
            let category = py
                .import("pointmass_dyn.errors")?
                .getattr("UrdfRepairWarning")?;
            let lines: Vec<String> = urdf.repairs.iter().map(|r| r.describe()).collect();
            let message = format!(
                "{}: repaired {} link(s)/joint(s) (model.repairs lists them):\n  {}",
                crate::files::display_path(&path),
                urdf.repairs.len(),
                lines.join("\n  ")
            );
            warnings.call_method1("warn", (message, &category, 1))?;
        }
        Ok(PyModel::from_parts_repaired(
            Arc::new(urdf.model),
            Arc::new(urdf.joints),
            Arc::new(urdf.repairs),
        ))
    }

    /// A model of a compiled `mujoco.MjModel` (`pointmass_dyn.from_mujoco`, docs/robots.md).
    /// The importer is Python (it reads MuJoCo's arrays); this is its place beside `from_urdf`.
    #[staticmethod]
    fn from_mujoco(py: Python<'_>, mj_model: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        let importers = py.import("pointmass_dyn.importers")?;
        Ok(importers.call_method1("from_mujoco", (mj_model,))?.unbind())
    }

    /// A model of a `pinocchio.Model` (`pointmass_dyn.from_pinocchio`, docs/robots.md).
    #[staticmethod]
    fn from_pinocchio(py: Python<'_>, pin_model: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        let importers = py.import("pointmass_dyn.importers")?;
        Ok(importers
            .call_method1("from_pinocchio", (pin_model,))?
            .unbind())
    }

    /// For the importers (python/pointmass_dyn/importers.py): a model from bodies in tree
    /// order, each `(name, parent, joint, translation, rotation, joint_name, mass, com,
    /// inertia)` (parent -1: the world); mass 0 is a massless intermediate body.
    #[staticmethod]
    fn _from_parts(py: Python<'_>, parts: Vec<Bound<'_, PyAny>>) -> PyResult<Self> {
        let mut out = Vec::with_capacity(parts.len());
        for (k, p) in parts.iter().enumerate() {
            #[allow(clippy::type_complexity)]
            let (name, parent, joint, t, r, joint_name, mass, com, inertia): (
                String,
                i64,
                PyRef<'_, PyJoint>,
                Bound<'_, PyAny>,
                Bound<'_, PyAny>,
                String,
                f64,
                Bound<'_, PyAny>,
                Bound<'_, PyAny>,
            ) = p.extract().map_err(|_| {
                invalid(
                    py,
                    &format!("parts[{k}]"),
                    "(name, parent, joint, translation, rotation, joint_name, mass, com, inertia)",
                    p.repr().map_or_else(|_| "?".to_string(), |x| x.to_string()),
                )
            })?;
            let parent = match parent {
                -1 => None,
                q if q >= 0 && (q as usize) < k => Some(q as usize),
                q => {
                    return Err(invalid(
                        py,
                        &format!("parts[{k}].parent"),
                        format!("-1 or an earlier part's index 0..{k}"),
                        q,
                    ))
                }
            };
            out.push(crate::urdf::Part {
                name,
                parent,
                placement: Placement::new(mat3(&r, "rotation")?, vec3(&t, "translation")?),
                joint: joint.inner,
                joint_name,
                mass,
                com: vec3(&com, "com")?,
                inertia: mat3(&inertia, "inertia")?,
            });
        }
        let built = crate::urdf::model_from_parts(&out).py(py)?;
        Ok(PyModel::from_parts(
            Arc::new(built.model),
            Arc::new(built.joints),
        ))
    }

    /// What `from_urdf(..., repair=...)` changed: one dict per link or welded joint with
    /// `link`, `joint` (the welded joint, else None), `rules`, `mass` (before, after),
    /// `principal_moments` (before, after; ascending) and `joint_type` (before, after; welds
    /// only). Empty for a model loaded without repairs.
    #[getter]
    fn repairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyList>> {
        let out = pyo3::types::PyList::empty(py);
        for r in self.repair_records().iter() {
            let d = PyDict::new(py);
            d.set_item("link", &r.link)?;
            d.set_item("joint", &r.joint)?;
            d.set_item("rules", &r.rules)?;
            d.set_item("mass", r.mass)?;
            d.set_item(
                "principal_moments",
                (
                    (
                        r.principal_moments.0[0],
                        r.principal_moments.0[1],
                        r.principal_moments.0[2],
                    ),
                    (
                        r.principal_moments.1[0],
                        r.principal_moments.1[1],
                        r.principal_moments.1[2],
                    ),
                ),
            )?;
            d.set_item("joint_type", &r.joint_type)?;
            out.append(d)?;
        }
        Ok(out)
    }

    /// Names of the moving joints in q/v order: the URDF joint names for a model from
    /// `from_urdf`, otherwise the names of the bodies that define each link.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        let v = self.version().clone();
        joint_names(&v.model, &v.urdf_joints)
    }

    /// `{joint name: (lower, upper, effort, velocity)}` for the moving joints in q/v order.
    /// What the file does not give is unbounded: ±inf position bounds (always, for
    /// continuous joints), inf effort and velocity.
    fn joint_limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let ver = self.version().clone();
        let d = PyDict::new(py);
        let names = joint_names(&ver.model, &ver.urdf_joints);
        for (joint, name) in link_joints(&ver.model, &ver.urdf_joints).zip(names) {
            let inf = f64::INFINITY;
            let lim = joint
                .and_then(|j| j.limit)
                .map(|x| (x.lower, x.upper, x.effort, x.velocity))
                .unwrap_or((-inf, inf, inf, inf));
            d.set_item(name, lim)?;
        }
        Ok(d)
    }

    /// `{joint name: (damping, friction)}` from the URDF `<dynamics>` elements, for the
    /// moving joints in q/v order (0 where absent). Not applied by the model itself.
    fn joint_dynamics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let ver = self.version().clone();
        let d = PyDict::new(py);
        let names = joint_names(&ver.model, &ver.urdf_joints);
        for (joint, name) in link_joints(&ver.model, &ver.urdf_joints).zip(names) {
            let dyn_ = joint.map(|j| (j.damping, j.friction)).unwrap_or((0.0, 0.0));
            d.set_item(name, dyn_)?;
        }
        Ok(d)
    }
}

impl PyModel {
    /// The current model and a checked copy of `q`, for the calls that run detached and
    /// need no workspace.
    fn state_only(&self, py: Python<'_>, q: &Bound<'_, PyAny>) -> PyResult<(Arc<Model>, Vec<f64>)> {
        let model = self.model();
        let q = super::convert::vector(q, "q", Some(model.nq))?;
        model.check_state(&q, None).py(py)?;
        Ok((model, q))
    }

    /// As [`PyModel::state_only`] with `v`.
    #[allow(clippy::type_complexity)]
    fn state(
        &self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<(Arc<Model>, Vec<f64>, Vec<f64>)> {
        let model = self.model();
        let q = super::convert::vector(q, "q", Some(model.nq))?;
        let v = super::convert::vector(v, "v", Some(model.nv))?;
        model.check_state(&q, Some(&v)).py(py)?;
        Ok((model, q, v))
    }
}

/// `repair=`: None/False (no repairs), True (the defaults), a dict of the fields, or an
/// object with them as attributes (`pmd.InertiaRepair`).
fn repair_options(
    py: Python<'_>,
    repair: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<crate::urdf::Repair>> {
    const FIELDS: [&str; 4] = [
        "balance_inertia",
        "bound_mass",
        "bound_inertia",
        "weld_massless",
    ];
    let expected = "None, False, True, a dict with keys balance_inertia, bound_mass, bound_inertia, weld_massless, or pmd.InertiaRepair(...)";
    let shown = |x: &Bound<'_, PyAny>| x.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
    let Some(r) = repair else { return Ok(None) };
    if r.is_none() {
        return Ok(None);
    }
    if let Ok(b) = r.cast::<pyo3::types::PyBool>() {
        return Ok(b.is_true().then(crate::urdf::Repair::default));
    }
    let get = |name: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        if let Ok(d) = r.cast::<PyDict>() {
            d.get_item(name)
        } else if r.hasattr(name)? {
            Ok(Some(r.getattr(name)?))
        } else {
            Err(invalid(py, "repair", expected, shown(r)))
        }
    };
    if let Ok(d) = r.cast::<PyDict>() {
        for k in d.keys() {
            let key: Option<String> = k.extract().ok();
            if !key.as_deref().is_some_and(|k| FIELDS.contains(&k)) {
                return Err(invalid(
                    py,
                    "repair",
                    expected,
                    format!("a dict with key {}", shown(&k)),
                ));
            }
        }
    }
    let mut out = crate::urdf::Repair::default();
    for name in FIELDS {
        let Some(v) = get(name)? else { continue };
        let arg = format!("repair.{name}");
        match name {
            "balance_inertia" | "weld_massless" => {
                let b = v
                    .cast::<pyo3::types::PyBool>()
                    .map_err(|_| invalid(py, &arg, "True or False", shown(&v)))?
                    .is_true();
                if name == "balance_inertia" {
                    out.balance_inertia = b;
                } else {
                    out.weld_massless = b;
                }
            }
            _ => {
                let x: f64 = v
                    .extract()
                    .ok()
                    .filter(|x: &f64| x.is_finite() && *x >= 0.0)
                    .ok_or_else(|| invalid(py, &arg, "a finite number >= 0", shown(&v)))?;
                if name == "bound_mass" {
                    out.bound_mass = x;
                } else {
                    out.bound_inertia = x;
                }
            }
        }
    }
    Ok(Some(out))
}

/// An error about argument `from` renamed to `to` (`q` → `q_guess`).
fn rename(py: Python<'_>, e: PyErr, from: &str, to: &str) -> PyErr {
    let msg = e.value(py).to_string();
    match msg.strip_prefix(&format!("{from}:")) {
        Some(rest) => {
            let ty = e.get_type(py);
            PyErr::from_type(ty, (format!("{to}:{rest}"),))
        }
        None => e,
    }
}

fn joint_names(model: &Model, urdf_joints: &[crate::urdf::UrdfJoint]) -> Vec<String> {
    model
        .links
        .iter()
        .zip(link_joints(model, urdf_joints))
        .map(|(l, joint)| match joint {
            Some(j) => j.name.clone(),
            None => model.bodies[l.body].name.clone(),
        })
        .collect()
}

/// The URDF joint (if any) of each moving link, in q/v order: one pass, not a search per link.
fn link_joints<'a>(
    model: &'a Model,
    joints: &'a [crate::urdf::UrdfJoint],
) -> impl Iterator<Item = Option<&'a crate::urdf::UrdfJoint>> + 'a {
    let by_body: std::collections::HashMap<usize, &crate::urdf::UrdfJoint> =
        joints.iter().map(|j| (j.body, j)).collect();
    model
        .links
        .iter()
        .map(move |l| by_body.get(&l.body).copied())
}
