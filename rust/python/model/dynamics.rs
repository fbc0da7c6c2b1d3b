//! `Model`'s dynamics: forward and inverse (either path), their derivatives, the mass
//! matrix, bias forces and energies.
use crate::python::Obj;
use pyo3::prelude::*;

use super::{load_state, load_x, method_arg, Method, PyModel, DETACH_LINKS};
use crate::dynamics::denoc;
use crate::dynamics::shared::{Direction, Workspace};
use crate::kinematics;
use crate::model::Model;
use crate::python::convert::{dmatrix_to_array, to_array1};
use crate::python::errors::{check_result, invalid, IntoPyResult};
use crate::python::signals::detach_interruptible;
use crate::recursive;
use crate::support::alloc::try_zeros;

fn name(direction: Direction) -> &'static str {
    match direction {
        Direction::Forward => "forward_dynamics",
        Direction::Inverse => "inverse_dynamics",
    }
}

/// The argument that is not a state: τ for forward dynamics, a for inverse.
fn input(direction: Direction) -> &'static str {
    match direction {
        Direction::Forward => "tau",
        Direction::Inverse => "a",
    }
}

#[pymethods]
impl PyModel {
    #[pyo3(signature = (q, v, tau, gravity=None, external=None, method="recursive"))]
    #[allow(clippy::too_many_arguments)]
    fn forward_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        tau: &Obj,
        gravity: Option<&Obj>,
        external: Option<&Obj>,
        method: &str,
    ) -> PyResult<Obj<'py>> {
        self.dynamics(py, Direction::Forward, q, v, tau, gravity, external, method)
    }

    #[pyo3(signature = (q, v, a, gravity=None, external=None, method="recursive", actuated=None))]
    #[allow(clippy::too_many_arguments)]
    fn inverse_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        a: &Obj,
        gravity: Option<&Obj>,
        external: Option<&Obj>,
        method: &str,
        actuated: Option<&Obj>,
    ) -> PyResult<Obj<'py>> {
        let model = self.model();
        let Some(actuated) = crate::model::args::loop_actuation(&model, actuated)? else {
            return self.dynamics(py, Direction::Inverse, q, v, a, gravity, external, method);
        };
        let tree = self.dynamics(py, Direction::Inverse, q, v, a, gravity, external, method)?;
        let tau_tree = crate::python::convert::vector(&tree, "tau", Some(model.nv))?;
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
            load_x(ws, py, a, "a")?;
            let tau = ws.driving_forces(&tau_tree, &actuated).py(py)?;
            check_result(py, "inverse_dynamics", &tau)?;
            Ok(to_array1(py, &tau).into_any())
        })
    }

    #[pyo3(signature = (q, v, a, gravity=None))]
    fn inverse_dynamics_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        a: &Obj,
        gravity: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
        self.derivatives(py, Direction::Inverse, q, v, a, gravity)
    }

    #[pyo3(signature = (q, v, tau, gravity=None))]
    fn forward_dynamics_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        tau: &Obj,
        gravity: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
        self.derivatives(py, Direction::Forward, q, v, tau, gravity)
    }

    #[pyo3(signature = (q, method="recursive"))]
    fn mass_matrix<'py>(&self, py: Python<'py>, q: &Obj, method: &str) -> PyResult<Obj<'py>> {
        let method = method_arg(py, method)?;
        match method {
            Method::Recursive => self.with_workspace(|ws| {
                load_state(ws, py, q, None)?;
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

    #[pyo3(signature = (q, v, gravity=None))]
    fn bias_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Obj,
        v: &Obj,
        gravity: Option<&Obj>,
    ) -> PyResult<Obj<'py>> {
        let g = crate::model::args::gravity(gravity)?;
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
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

    fn kinetic_energy(&self, py: Python<'_>, q: &Obj, v: &Obj) -> PyResult<f64> {
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
            let model: &Model = &ws.version.model;
            kinematics::positions(model, &ws.q, &mut ws.data.links);
            kinematics::velocities(model, &ws.q, &ws.v, &mut ws.data.links);
            let e = recursive::kinetic_energy(&ws.data)
                + recursive::armature::kinetic_energy(model, &ws.v);
            check_result(py, "kinetic_energy", &[e])?;
            Ok(e)
        })
    }

    fn potential_energy(&self, py: Python<'_>, q: &Obj, gravity: &Obj) -> PyResult<f64> {
        let g = crate::model::args::gravity(Some(gravity))?;
        self.with_workspace(|ws| {
            load_state(ws, py, q, None)?;
            kinematics::positions(&ws.version.model, &ws.q, &mut ws.data.links);
            let e = recursive::potential_energy(&ws.data, &g);
            check_result(py, "potential_energy", &[e])?;
            Ok(e)
        })
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
        q: &Obj,
        v: &Obj,
        x: &Obj,
        gravity: Option<&Obj>,
        external: Option<&Obj>,
        method: &str,
    ) -> PyResult<Obj<'py>> {
        let method = method_arg(py, method)?;
        let g = crate::model::args::gravity(gravity)?;
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
            load_x(ws, py, x, input(direction))?;
            let ext = crate::model::args::external(ws.model(), external)?;
            match method {
                Method::Recursive => {
                    let ext = ext.as_deref();
                    if ws.model().links.len() >= DETACH_LINKS {
                        py.detach(|| ws.dynamics(direction, &g, ext))
                    } else {
                        ws.dynamics(direction, &g, ext)
                    }
                    .py(py)?;
                    check_result(py, name(direction), &ws.out)?;
                    Ok(to_array1(py, &ws.out).into_any())
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
                    let out = detach_interruptible(py, || ws.denoc_dynamics(direction, &g))?;
                    check_result(py, name(direction), &out)?;
                    Ok(to_array1(py, &out).into_any())
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
        q: &Obj,
        v: &Obj,
        x: &Obj,
        gravity: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
        let g = crate::model::args::gravity(gravity)?;
        let name = match direction {
            Direction::Forward => "forward_dynamics_derivatives",
            Direction::Inverse => "inverse_dynamics_derivatives",
        };
        self.with_workspace(|ws: &mut Workspace| {
            if ws.model().has_constraints() {
                return Err(invalid(
                    py,
                    "model",
                    format!(
                        "a tree for {name} (closed loops and couplings are not differentiated)"
                    ),
                    format!(
                        "a model with {} loop(s) and {} coupling(s)",
                        ws.model().loops.len(),
                        ws.model().couplings.len()
                    ),
                ));
            }
            load_state(ws, py, q, Some(v))?;
            load_x(ws, py, x, input(direction))?;
            let rows = ws.model().nv >= crate::python::derivatives::ROWS_NV;
            if direction == Direction::Inverse && rows {
                let detach = ws.model().links.len() >= DETACH_LINKS;
                return crate::python::derivatives::inverse_into_arrays(py, ws, &g, name, detach);
            }
            // By rows (large models): the C order NumPy returns is then a plain copy.
            let dd = if ws.model().links.len() >= DETACH_LINKS {
                py.detach(|| ws.derivatives(direction, &g, rows))
            } else {
                ws.derivatives(direction, &g, rows)
            }
            .py(py)?;
            let (a, b, c) = match direction {
                Direction::Forward => (&dd.ddq_dq, &dd.ddq_dv, &dd.minv),
                Direction::Inverse => (&dd.dtau_dq, &dd.dtau_dv, &dd.mass),
            };
            for m in [a, b, c] {
                if !super::all_finite(m.as_slice()) {
                    check_result(py, name, m.as_slice())?;
                }
            }
            crate::python::derivatives::c_ordered_triple(py, [a, b, c], !rows)
        })
    }
}
