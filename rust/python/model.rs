//! `Joint` and `Model`: the tree, kinematics and both dynamics paths.
use nalgebra::DMatrix;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::body::PyRigidBody;
use super::convert::{dmatrix_to_array, mat3, points, to_array, to_array1, vec3, vector_into};
use super::errors::{check_result, invalid, IntoPyResult};
use crate::denoc;
use crate::joint::Joint;
use crate::kinematics;
use crate::model::Model;
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

#[pyclass(name = "Model", module = "pointmass_dyn._core")]
pub struct PyModel {
    pub model: Model,
    pub data: Data,
    q: Vec<f64>,
    v: Vec<f64>,
    x: Vec<f64>,
    out: Vec<f64>,
    gim: DMatrix<f64>,
    /// The URDF joints (names, limits, damping, friction) of a model from `from_urdf`.
    pub urdf_joints: Vec<crate::urdf::UrdfJoint>,
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
        &mut self,
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
        self.load_state(py, q, Some(v))?;
        self.load_x(py, x, direction.input())?;
        let ext = self.external_wrenches(external)?;
        let (model, qv, vv, xv) = (&self.model, &self.q, &self.v, &self.x);
        match method {
            Method::Recursive => {
                let (data, out) = (&mut self.data, &mut self.out);
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
                check_result(py, direction.name(), &self.out)?;
                Ok(to_array1(py, &self.out).into_any())
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
                let out = py
                    .detach(|| match direction {
                        Direction::Forward => denoc::forward_dynamics(model, qv, vv, xv, &g),
                        Direction::Inverse => Ok(denoc::inverse_dynamics(model, qv, vv, xv, &g)),
                    })
                    .py(py)?;
                check_result(py, direction.name(), out.as_slice())?;
                Ok(to_array1(py, out.as_slice()).into_any())
            }
        }
    }

    pub fn from_model(model: Model) -> Self {
        let data = Data::new(&model);
        let (nq, nv) = (model.nq, model.nv);
        PyModel {
            model,
            data,
            q: vec![0.0; nq],
            v: vec![0.0; nv],
            x: vec![0.0; nv],
            out: vec![0.0; nv],
            // Allocated by the first `mass_matrix` call: nv² doubles would make merely
            // loading a long chain cost gigabytes (135k links: 146 GB).
            gim: DMatrix::zeros(0, 0),
            urdf_joints: Vec::new(),
        }
    }

    /// Reads q (and v) into the model's buffers and validates them.
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
        self.model
            .check_state(&self.q, v.map(|_| self.v.as_slice()))
            .py(py)
    }

    fn load_x(&mut self, py: Python<'_>, x: &Bound<'_, PyAny>, arg: &str) -> PyResult<()> {
        vector_into(x, arg, &mut self.x)?;
        crate::error::check_finite(arg, &self.x).py(py)
    }

    fn external_wrenches(&self, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<Vec6>>> {
        match obj {
            Some(f) if !f.is_none() => {
                let (shape, data) = super::convert::array(f, "external")?;
                let n = self.model.links.len();
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
        &mut self,
        py: Python<'_>,
        body: PyRef<'_, PyRigidBody>,
        joint: PyRef<'_, PyJoint>,
        parent: Option<&Bound<'_, PyAny>>,
        translation: Option<&Bound<'_, PyAny>>,
        rotation: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
        point_mass_center: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<usize> {
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
        let parent = match parent {
            -1 => None,
            p if p >= 0 => Some(p as usize),
            p => {
                return Err(super::errors::py_error(
                    py,
                    "ModelStructureError",
                    format!(
                        "parent: expected -1 (the world) or a body index 0..{}, got {p}",
                        self.model.nbodies()
                    ),
                ))
            }
        };
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
        let k = self
            .model
            .add_body(
                body.inner,
                joint.inner,
                parent,
                Placement::new(r, t),
                name,
                center,
            )
            .py(py)?;
        let urdf_joints = std::mem::take(&mut self.urdf_joints);
        *self = PyModel::from_model(std::mem::take(&mut self.model));
        self.urdf_joints = urdf_joints;
        Ok(k)
    }

    #[getter]
    fn nq(&self) -> usize {
        self.model.nq
    }
    #[getter]
    fn nv(&self) -> usize {
        self.model.nv
    }
    #[getter]
    fn nbodies(&self) -> usize {
        self.model.nbodies()
    }
    /// Moving links (bodies on Fixed joints are welded into their parent's link).
    #[getter]
    fn nlinks(&self) -> usize {
        self.model.links.len()
    }
    #[getter]
    fn body_names(&self) -> Vec<String> {
        self.model.bodies.iter().map(|b| b.name.clone()).collect()
    }
    /// Names of the bodies that define each moving link, in q/v order.
    #[getter]
    fn link_names(&self) -> Vec<String> {
        self.model
            .links
            .iter()
            .map(|l| self.model.bodies[l.body].name.clone())
            .collect()
    }
    #[getter]
    fn total_mass(&self) -> f64 {
        self.model.total_mass()
    }
    /// Per body: (name, joint kind, parent index or -1, link index or -1).
    fn body_info(
        &self,
        py: Python<'_>,
        index: &Bound<'_, PyAny>,
    ) -> PyResult<(String, String, i64, i64)> {
        let index = super::convert::count_arg(index, "index", "a body index >= 0")?;
        let b = self.model.bodies.get(index).ok_or_else(|| {
            super::errors::py_error(
                py,
                "ModelStructureError",
                format!(
                    "index: no body {index} (the model has {})",
                    self.model.nbodies()
                ),
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
        self.model
            .links
            .iter()
            .map(|l| (l.q_index, l.v_index, l.joint.nq(), l.joint.nv()))
            .collect()
    }

    fn neutral<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        to_array1(py, &self.model.neutral()).into_any()
    }

    /// World placements of every body at `q`: (rotations (nbodies, 3, 3), origins (nbodies, 3)).
    fn placements<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.load_state(py, q, None)?;
        kinematics::positions(&self.model, &self.q, &mut self.data.links);
        let nb = self.model.nbodies();
        let mut rots = Vec::with_capacity(9 * nb);
        let mut origins = Vec::with_capacity(3 * nb);
        for b in 0..nb {
            let p = kinematics::body_placement(&self.model, &self.data.links, b);
            rots.extend_from_slice(p.rotation.transpose().as_slice());
            origins.extend_from_slice(p.translation.as_slice());
        }
        check_result(py, "placements", &origins)?;
        Ok((
            to_array(py, rots, &[nb, 3, 3])?,
            to_array(py, origins, &[nb, 3])?,
        ))
    }

    /// The seven point masses of every moving link: (masses (nlinks, 7), world positions
    /// (nlinks, 7, 3)) at `q`.
    fn point_masses<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.load_state(py, q, None)?;
        let den = denoc::matrices(&self.model, &self.q);
        let n = self.model.links.len();
        let pts = den.points.transpose().as_slice().to_vec();
        check_result(py, "point_masses", &pts)?;
        Ok((
            to_array(py, den.masses.as_slice().to_vec(), &[n, 7])?,
            to_array(py, pts, &[n, 7, 3])?,
        ))
    }

    /// The DeNOC matrices at `q`: dict with D, Nl, Nd, N, masses (7n,), points (7n, 3).
    fn denoc<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.load_state(py, q, None)?;
        let (model, qv) = (&self.model, &self.q);
        let den = py.detach(|| denoc::matrices(model, qv));
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
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.load_state(py, q, Some(v))?;
        let (model, qv, vv) = (&self.model, &self.q, &self.v);
        let (_, rates) = py.detach(|| denoc::matrices_and_rates(model, qv, vv));
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
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        method: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let method = method_arg(py, method)?;
        self.load_state(py, q, None)?;
        match method {
            Method::Recursive => {
                let nv = self.model.nv;
                if self.gim.nrows() != nv {
                    self.gim = dense_matrix(nv, nv)?;
                }
                let (model, data, qv, gim) = (&self.model, &mut self.data, &self.q, &mut self.gim);
                // O(n·depth): long chains are worth releasing the interpreter for.
                if model.links.len() >= DETACH_LINKS {
                    py.detach(|| recursive::mass_matrix(model, data, qv, gim));
                } else {
                    recursive::mass_matrix(model, data, qv, gim);
                }
                check_result(py, "mass_matrix", self.gim.as_slice())?;
                dmatrix_to_array(py, &self.gim)
            }
            Method::Denoc => {
                let (model, qv) = (&self.model, &self.q);
                let m = py.detach(|| denoc::mass_matrix(model, qv));
                check_result(py, "mass_matrix", m.as_slice())?;
                dmatrix_to_array(py, &m)
            }
        }
    }

    /// Convective matrix `C = Nᵀ M Ṅ` (explicit DeNOC products).
    fn convective_matrix<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.load_state(py, q, Some(v))?;
        let (model, qv, vv) = (&self.model, &self.q, &self.v);
        let c = py.detach(|| denoc::convective_matrix(model, qv, vv));
        check_result(py, "convective_matrix", c.as_slice())?;
        dmatrix_to_array(py, &c)
    }

    /// Generalized gravity force `Nᵀ f^G` (right-hand side; Pinocchio's
    /// `computeGeneralizedGravity` is its negative).
    fn gravity_forces<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        gravity: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let g = gravity_arg(py, Some(gravity))?;
        self.load_state(py, q, None)?;
        let tg = denoc::gravity_forces(&self.model, &self.q, &g);
        check_result(py, "gravity_forces", tg.as_slice())?;
        Ok(to_array1(py, tg.as_slice()).into_any())
    }

    /// `Nᵀ f` for forces on the point masses, shape (nlinks, 7, 3) or (7·nlinks, 3), world.
    fn generalized_forces<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        forces: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.load_state(py, q, None)?;
        let f = points(forces, "forces")?;
        for p in &f {
            crate::error::check_finite("forces", p.as_slice()).py(py)?;
        }
        let tau = denoc::generalized_forces(&self.model, &self.q, &f).py(py)?;
        check_result(py, "generalized_forces", tau.as_slice())?;
        Ok(to_array1(py, tau.as_slice()).into_any())
    }

    /// Bias forces `C v − τ_g` (Pinocchio's `nonLinearEffects`).
    #[pyo3(signature = (q, v, gravity=None))]
    fn bias_forces<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let g = gravity_arg(py, gravity)?;
        self.load_state(py, q, Some(v))?;
        self.x.fill(0.0);
        recursive::inverse_dynamics(
            &self.model,
            &mut self.data,
            &self.q,
            &self.v,
            &self.x,
            &g,
            None,
            &mut self.out,
        );
        check_result(py, "bias_forces", &self.out)?;
        Ok(to_array1(py, &self.out).into_any())
    }

    /// Accelerations from `I a + C v = τ + τ_g + τ_ext`.
    #[pyo3(signature = (q, v, tau, gravity=None, external=None, method="recursive"))]
    #[allow(clippy::too_many_arguments)]
    fn forward_dynamics<'py>(
        &mut self,
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

    /// Joint forces `τ = I a + C v − τ_g − τ_ext`.
    #[pyo3(signature = (q, v, a, gravity=None, external=None, method="recursive"))]
    #[allow(clippy::too_many_arguments)]
    fn inverse_dynamics<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        gravity: Option<&Bound<'_, PyAny>>,
        external: Option<&Bound<'_, PyAny>>,
        method: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.dynamics(py, Direction::Inverse, q, v, a, gravity, external, method)
    }

    /// Kinetic energy `½ vᵀ I v`.
    fn kinetic_energy(
        &mut self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<f64> {
        self.load_state(py, q, Some(v))?;
        kinematics::positions(&self.model, &self.q, &mut self.data.links);
        kinematics::velocities(&self.model, &self.q, &self.v, &mut self.data.links);
        let e = recursive::kinetic_energy(&self.data);
        check_result(py, "kinetic_energy", &[e])?;
        Ok(e)
    }

    /// Gravitational potential energy `−Σ m_ij g·x_ij` (zero at the world origin).
    fn potential_energy(
        &mut self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        gravity: &Bound<'_, PyAny>,
    ) -> PyResult<f64> {
        let g = gravity_arg(py, Some(gravity))?;
        self.load_state(py, q, None)?;
        kinematics::positions(&self.model, &self.q, &mut self.data.links);
        let e = recursive::potential_energy(&self.data, &g);
        check_result(py, "potential_energy", &[e])?;
        Ok(e)
    }

    /// `q̇` from `v` (differs from `v` only for quaternion joints).
    fn velocity_to_qdot<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.load_state(py, q, Some(v))?;
        let mut qd = vec![0.0; self.model.nq];
        self.model.velocity_to_qdot(&self.q, &self.v, &mut qd);
        check_result(py, "velocity_to_qdot", &qd)?;
        Ok(to_array1(py, &qd).into_any())
    }

    fn __repr__(&self) -> String {
        format!(
            "Model(nbodies={}, nlinks={}, nq={}, nv={})",
            self.model.nbodies(),
            self.model.links.len(),
            self.model.nq,
            self.model.nv
        )
    }

    /// Loads a fixed-base robot from a URDF file (joint order and body names as Pinocchio's
    /// `buildModelFromUrdf`). Raises `UrdfError`; warnings go through `warnings.warn` as
    /// `UrdfWarning`.
    #[staticmethod]
    fn from_urdf(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        let urdf = crate::urdf::load_urdf(&path)
            .map_err(|e| super::errors::py_error(py, "UrdfError", e.to_string()))?;
        if !urdf.warnings.is_empty() {
            let category = py.import("pointmass_dyn.errors")?.getattr("UrdfWarning")?;
            let warnings = py.import("warnings")?;
            for w in &urdf.warnings {
                warnings.call_method1("warn", (w.as_str(), &category, 1))?;
            }
        }
        let mut m = PyModel::from_model(urdf.model);
        m.urdf_joints = urdf.joints;
        Ok(m)
    }

    /// Names of the moving joints in q/v order: the URDF joint names for a model from
    /// `from_urdf`, otherwise the names of the bodies that define each link.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.model
            .links
            .iter()
            .map(|l| match urdf_joint(&self.urdf_joints, l.body) {
                Some(j) => j.name.clone(),
                None => self.model.bodies[l.body].name.clone(),
            })
            .collect()
    }

    /// `{joint name: (lower, upper, effort, velocity)}` for the moving joints in q/v order.
    /// What the file does not give is unbounded: ±inf position bounds (always, for
    /// continuous joints), inf effort and velocity.
    fn joint_limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let names = self.joint_names();
        for (l, name) in self.model.links.iter().zip(names) {
            let inf = f64::INFINITY;
            let lim = urdf_joint(&self.urdf_joints, l.body)
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
        let d = PyDict::new(py);
        let names = self.joint_names();
        for (l, name) in self.model.links.iter().zip(names) {
            let dyn_ = urdf_joint(&self.urdf_joints, l.body)
                .map(|j| (j.damping, j.friction))
                .unwrap_or((0.0, 0.0));
            d.set_item(name, dyn_)?;
        }
        Ok(d)
    }
}

/// An all-zero `rows × cols` matrix, or `MemoryError` if it cannot be allocated (instead of
/// the process aborting).
fn dense_matrix(rows: usize, cols: usize) -> PyResult<DMatrix<f64>> {
    let n = rows.checked_mul(cols);
    let mut data: Vec<f64> = Vec::new();
    match n.map(|n| data.try_reserve_exact(n)) {
        Some(Ok(())) => {
            data.resize(rows * cols, 0.0);
            Ok(DMatrix::from_vec(rows, cols, data))
        }
        _ => Err(pyo3::exceptions::PyMemoryError::new_err(format!(
            "mass_matrix: cannot allocate the dense {rows} x {cols} matrix ({:.3e} bytes)",
            rows as f64 * cols as f64 * 8.0
        ))),
    }
}

/// The URDF joint whose child is body `body`.
fn urdf_joint(joints: &[crate::urdf::UrdfJoint], body: usize) -> Option<&crate::urdf::UrdfJoint> {
    joints.iter().find(|j| j.body == body)
}
