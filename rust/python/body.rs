//! `RigidBody` and its seven point masses.
use crate::python::Obj;
use nalgebra::DMatrix;
use pyo3::prelude::*;

use super::convert::{mat3, mat3_to_array, points, real, vec3, vector};
use super::errors::IntoPyResult;
use crate::model::body::RigidBody;
use crate::model::point_masses::EquimomentalSet;

#[pyclass(
    name = "RigidBody",
    module = "pointmass_dyn._core",
    frozen,
    from_py_object
)]
#[derive(Clone)]
pub struct PyRigidBody {
    pub inner: RigidBody,
}

#[pymethods]
impl PyRigidBody {
    #[new]
    #[pyo3(signature = (mass, com, inertia))]
    fn new(py: Python<'_>, mass: &Obj, com: &Obj, inertia: &Obj) -> PyResult<Self> {
        let mass = real(mass, "mass")?;
        let inner = RigidBody::new(mass, vec3(com, "com")?, mat3(inertia, "inertia")?).py(py)?;
        Ok(PyRigidBody { inner })
    }

    /// Mass, COM and inertia about the COM of a set of point masses.
    #[staticmethod]
    fn from_point_masses(py: Python<'_>, masses: &Obj, positions: &Obj) -> PyResult<Self> {
        let m = vector(masses, "masses", None)?;
        let p = points(positions, "positions")?;
        Ok(PyRigidBody {
            inner: RigidBody::from_point_masses(&m, &p).py(py)?,
        })
    }

    /// Inertia about `point` (body frame), by the parallel-axis theorem.
    fn inertia_about<'py>(&self, py: Python<'py>, point: &Obj) -> PyResult<Obj<'py>> {
        let i = self.inner.inertia_about_checked(&vec3(point, "point")?);
        mat3_to_array(py, &i.py(py)?)
    }

    /// The equimomental seven point masses, box centred at `center` (default: the COM).
    #[pyo3(signature = (center=None))]
    fn point_masses(&self, py: Python<'_>, center: Option<&Obj>) -> PyResult<PyPointMasses> {
        let center = crate::support::args::opt(center, |c| vec3(c, "center"))?;
        let inner = EquimomentalSet::around(&self.inner, center).py(py)?;
        Ok(PyPointMasses { inner })
    }

    fn __repr__(&self) -> String {
        self.inner.repr()
    }
}

crate::python::getters!(PyRigidBody |b| {
    mass: b.inner.mass;
    com: b.inner.com.as_slice().to_vec();
    inertia: DMatrix::from_fn(3, 3, |i, j| b.inner.inertia[(i, j)]);
});

#[pyclass(name = "PointMasses", module = "pointmass_dyn._core", frozen)]
pub struct PyPointMasses {
    pub inner: EquimomentalSet,
}

#[pymethods]
impl PyPointMasses {
    /// The rigid body these points represent (mass, COM, inertia rebuilt from them).
    fn to_body(&self, py: Python<'_>) -> PyResult<PyRigidBody> {
        let inner = self.inner.body().py(py)?;
        Ok(PyRigidBody { inner })
    }
    fn __repr__(&self) -> String {
        self.inner.repr()
    }
}

crate::python::getters!(PyPointMasses |p| {
    /// The seven masses (kg); some may be negative.
    masses: p.inner.masses.to_vec();
    /// Positions in the body frame, shape (7, 3).
    positions: DMatrix::from_fn(7, 3, |i, j| p.inner.positions[i][j]);
    half_sides: p.inner.half_sides.as_slice().to_vec();
    center: p.inner.center.as_slice().to_vec();
});
