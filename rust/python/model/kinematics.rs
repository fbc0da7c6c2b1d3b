//! `Model`'s kinematics: placements, poses and point masses at a configuration, and the
//! DeNOC matrices and the explicit products built from them.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::{load_state, PyModel};
use crate::dynamics::denoc;
use crate::kinematics;
use crate::model::Model;
use crate::python::convert::{dmatrix_to_array, points, to_array, to_array1};
use crate::python::errors::check_result;
use crate::python::record::{record, Field};
use crate::python::signals::detach_interruptible;

#[pymethods]
impl PyModel {
    fn placements<'py>(&self, py: Python<'py>, q: &Obj) -> PyResult<(Obj<'py>, Obj<'py>)> {
        self.with_workspace(|ws| {
            load_state(ws, py, q, None)?;
            let model: &Model = &ws.version.model;
            let nb = model.nbodies();
            let (rots, origins) = kinematics::body_placements(model, &ws.q, &mut ws.data.links)?;
            Ok((
                to_array(py, rots, &[nb, 3, 3])?,
                to_array(py, origins, &[nb, 3])?,
            ))
        })
    }

    fn body_poses<'py>(&self, py: Python<'py>, q: &Obj) -> PyResult<Bound<'py, PyDict>> {
        let model = self.model();
        let (rows, qs, stacked) = super::frames::configurations(&model, q, "q")?;
        let poses = detach_interruptible(py, || {
            crate::kinematics::poses::Poses::at(&model, &qs, rows, stacked)?.keyed(&model, stacked)
        })?;
        let d = PyDict::new(py);
        for (key, buf, shape) in poses {
            d.set_item(key, to_array(py, buf, &shape)?)?;
        }
        Ok(d)
    }

    fn point_masses<'py>(&self, py: Python<'py>, q: &Obj) -> PyResult<(Obj<'py>, Obj<'py>)> {
        let (model, q) = self.state_only(q)?;
        let (masses, pts) = crate::dynamics::calls::point_masses(&model, &q)?;
        let n = model.links.len();
        Ok((
            to_array(py, masses, &[n, 7])?,
            to_array(py, pts, &[n, 7, 3])?,
        ))
    }

    fn denoc(&self, py: Python<'_>, q: &Obj) -> PyResult<PyDenoc> {
        let (model, qv) = self.state_only(q)?;
        let den = detach_interruptible(py, || denoc::matrices(&model, &qv))?;
        den.check_finite("denoc")?;
        Ok(PyDenoc(den))
    }

    fn denoc_rates(&self, py: Python<'_>, q: &Obj, v: &Obj) -> PyResult<PyDenocRates> {
        let (model, qv, vv) = self.state(q, v)?;
        let (_, rates) = detach_interruptible(py, || denoc::matrices_and_rates(&model, &qv, &vv))?;
        rates.check_finite("denoc_rates")?;
        Ok(PyDenocRates(rates))
    }

    fn convective_matrix<'py>(&self, py: Python<'py>, q: &Obj, v: &Obj) -> PyResult<Obj<'py>> {
        let (model, qv, vv) = self.state(q, v)?;
        let c = detach_interruptible(py, || denoc::convective_matrix(&model, &qv, &vv))?;
        check_result(py, "convective_matrix", c.as_slice())?;
        dmatrix_to_array(py, &c)
    }

    fn gravity_forces<'py>(&self, py: Python<'py>, q: &Obj, gravity: &Obj) -> PyResult<Obj<'py>> {
        let g = crate::model::args::gravity(Some(gravity))?;
        let (model, qv) = self.state_only(q)?;
        let tg = detach_interruptible(py, || denoc::gravity_forces(&model, &qv, &g))?;
        check_result(py, "gravity_forces", tg.as_slice())?;
        Ok(to_array1(py, tg.as_slice()).into_any())
    }

    fn generalized_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        forces: &Obj,
    ) -> PyResult<Obj<'py>> {
        let (model, qv) = self.state_only(q)?;
        let f = points(forces, "forces")?;
        let tau = detach_interruptible(py, || denoc::generalized_forces(&model, &qv, &f))?;
        check_result(py, "generalized_forces", tau.as_slice())?;
        Ok(to_array1(py, tau.as_slice()).into_any())
    }

    fn velocity_to_qdot<'py>(&self, py: Python<'py>, q: &Obj, v: &Obj) -> PyResult<Obj<'py>> {
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
            let mut qd = vec![0.0; ws.model().nq];
            ws.model().velocity_to_qdot(&ws.q, &ws.v, &mut qd);
            check_result(py, "velocity_to_qdot", &qd)?;
            Ok(to_array1(py, &qd).into_any())
        })
    }
}

record!(
    /// The DeNOC matrices at one configuration (`Model.denoc`), keys as the paper's names.
    PyDenoc("Denoc", denoc::Denoc) {
        D: |r: &denoc::Denoc, py| r.d.field(py),
        Nl: |r: &denoc::Denoc, py| r.nl.field(py),
        Nd: |r: &denoc::Denoc, py| r.nd.field(py),
        N: |r: &denoc::Denoc, py| r.n.field(py),
        masses,
        points,
    }
);

record!(
    /// The DeNOC matrices' time derivatives (`Model.denoc_rates`).
    PyDenocRates("DenocRates", denoc::DenocRates) {
        D: |r: &denoc::DenocRates, py| r.d.field(py),
        Nl: |r: &denoc::DenocRates, py| r.nl.field(py),
        Nd: |r: &denoc::DenocRates, py| r.nd.field(py),
        N: |r: &denoc::DenocRates, py| r.n.field(py),
    }
);
