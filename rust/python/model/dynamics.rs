//! `Model`'s dynamics: forward and inverse (either path), their derivatives, and the
//! one-state quantities (the mass matrix, bias forces, energies, the loops' residual,
//! Jacobian and forces, the couplings' forces: `crate::dynamics::at_state`), each at a
//! pooled workspace.
use crate::python::Obj;
use pyo3::prelude::*;
use pyo3::IntoPyObjectExt;

use super::{load_state, load_x, sized, PyModel};
use crate::dynamics::at_state::{Given, Quantity};
use crate::dynamics::calls::{worth_detaching, Method};
use crate::dynamics::shared::Direction;
use crate::python::convert::{to_array, to_array1};
use crate::python::errors::{check_result, invalid, IntoPyResult};
use crate::python::signals::detach_interruptible;
use crate::support::error::all_finite;

#[pymethods]
impl PyModel {
    #[pyo3(signature = (q, v, tau, gravity=None, external=None, method="recursive"))]
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
        let how = (Direction::Forward, None);
        self.dynamics(py, how, [q, v, tau], gravity, external, method)
    }

    #[pyo3(signature = (q, v, a, gravity=None, external=None, method="recursive", actuated=None))]
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
        let actuated = crate::model::args::loop_actuation(&self.model(), actuated)?;
        let how = (Direction::Inverse, actuated.as_deref());
        self.dynamics(py, how, [q, v, a], gravity, external, method)
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
        self.derivatives(py, Direction::Inverse, [q, v, a], gravity)
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
        self.derivatives(py, Direction::Forward, [q, v, tau], gravity)
    }

    #[pyo3(signature = (q, method="recursive"))]
    fn mass_matrix<'py>(&self, py: Python<'py>, q: &Obj, method: &str) -> PyResult<Obj<'py>> {
        let what = Quantity::MassMatrix(Method::parse(method)?);
        self.at_state(py, what, Given::q(q))
    }
}

/// The one-state quantities (`crate::dynamics::at_state`), one method each:
/// `name(arguments) = quantity`, an optional argument followed by `= None`.
macro_rules! at_state {
    (@ty) => { &Obj };
    (@ty $default:tt) => { Option<&Obj> };
    (@given $arg:ident) => { Some($arg) };
    (@given $arg:ident $default:tt) => { $arg };
    ($($name:ident($($arg:ident $(= $default:tt)?),*) = $what:ident),* $(,)?) => {
        #[pymethods]
        impl PyModel {$(
            #[pyo3(signature = ($($arg $(= $default)?),*))]
            #[allow(clippy::needless_update)]
            fn $name<'py>(&self, py: Python<'py>, $($arg: at_state!(@ty $($default)?)),*) -> PyResult<Obj<'py>> {
                let given = Given { $($arg: at_state!(@given $arg $($default)?),)* ..Given::none() };
                self.at_state(py, Quantity::$what, given)
            }
        )*}
    };
}

at_state! {
    bias_forces(q, v, gravity = None) = BiasForces,
    kinetic_energy(q, v) = KineticEnergy,
    potential_energy(q, gravity) = PotentialEnergy,
    constraint_residual(q) = ConstraintResidual,
    constraint_jacobian(q) = ConstraintJacobian,
    constraint_forces(q, v, tau, gravity = None, external = None) = ConstraintForces,
    coupling_forces(q, v, tau, gravity = None) = CouplingForces,
    assemble_velocity(q, v_guess, fixed = None) = AssembledVelocity,
    assemble_acceleration(q, v, a_guess, fixed = None) = AssembledAcceleration,
}

impl PyModel {
    /// Forward or inverse dynamics on either path: one place validates, dispatches, releases
    /// the GIL for large models and checks the result. With `actuated` (a model with loops),
    /// the inverse dynamics' joint forces of those joints alone.
    fn dynamics<'py>(
        &self,
        py: Python<'py>,
        (direction, actuated): (Direction, Option<&[usize]>),
        [q, v, x]: [&Obj; 3],
        gravity: Option<&Obj>,
        external: Option<&Obj>,
        method: &str,
    ) -> PyResult<Obj<'py>> {
        let method = Method::parse(method)?;
        let g = crate::model::args::gravity(gravity)?;
        self.with_workspace(|ws| {
            load_state(ws, py, q, Some(v))?;
            load_x(ws, py, x, direction.input())?;
            let ext = crate::model::args::external(ws.model(), external)?;
            let denoc;
            let out = match (method, ext) {
                (Method::Recursive, ext) => {
                    let detach = worth_detaching(ws.model());
                    sized(py, detach, || ws.dynamics(direction, &g, ext.as_deref()))?;
                    &ws.out
                }
                (Method::Denoc, Some(_)) => {
                    let expected =
                        "None with method='denoc' (apply point forces with generalized_forces)";
                    return Err(invalid(py, "external", expected, "wrenches"));
                }
                (Method::Denoc, None) => {
                    denoc = detach_interruptible(py, || ws.denoc_dynamics(direction, &g))?;
                    &denoc
                }
            };
            check_result(py, direction.name(), out)?;
            let Some(actuated) = actuated else {
                return Ok(to_array1(py, out).into_any());
            };
            let tau = ws.driving_forces(&out.to_vec(), actuated)?;
            check_result(py, direction.name(), &tau)?;
            Ok(to_array1(py, &tau).into_any())
        })
    }

    /// A one-state quantity: its arguments read, computed (detached when long) and
    /// converted, a number as a float.
    fn at_state<'py>(
        &self,
        py: Python<'py>,
        what: Quantity,
        given: Given<'_, Obj<'_>>,
    ) -> PyResult<Obj<'py>> {
        self.with_workspace(|ws| {
            let call = ws.load(what, given)?;
            let (x, shape) = match call.long(ws) {
                true => detach_interruptible(py, || ws.compute(&call))?,
                false => ws.compute(&call).py(py)?,
            };
            match shape.is_empty() {
                true => x[0].into_bound_py_any(py),
                false => to_array(py, x, &shape),
            }
        })
    }

    /// Forward or inverse dynamics derivatives: validates, runs (GIL released for large
    /// models) and returns the three nv × nv matrices.
    fn derivatives<'py>(
        &self,
        py: Python<'py>,
        direction: Direction,
        [q, v, x]: [&Obj; 3],
        gravity: Option<&Obj>,
    ) -> PyResult<(Obj<'py>, Obj<'py>, Obj<'py>)> {
        let g = crate::model::args::gravity(gravity)?;
        let name = direction.derivatives_name();
        self.with_workspace(|ws| {
            ws.check_tree(name)?;
            load_state(ws, py, q, Some(v))?;
            load_x(ws, py, x, direction.input())?;
            let (rows, detach) = (
                ws.model().nv >= crate::python::derivatives::ROWS_NV,
                worth_detaching(ws.model()),
            );
            if direction == Direction::Inverse && rows {
                return crate::python::derivatives::inverse_into_arrays(py, ws, &g, name, detach);
            }
            // By rows (large models): the C order NumPy returns is then a plain copy.
            let dd = sized(py, detach, || ws.derivatives(direction, &g, rows))?;
            let (a, b, c) = match direction {
                Direction::Forward => (&dd.ddq_dq, &dd.ddq_dv, &dd.minv),
                Direction::Inverse => (&dd.dtau_dq, &dd.dtau_dv, &dd.mass),
            };
            for m in [a, b, c].map(|m| m.as_slice()) {
                if !all_finite(m) {
                    check_result(py, name, m)?;
                }
            }
            crate::python::derivatives::c_ordered_triple(py, [a, b, c], !rows)
        })
    }
}
