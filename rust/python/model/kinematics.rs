//! `Model`'s kinematics: placements, poses and point masses at a configuration, and the
//! DeNOC matrices and the explicit products built from them (`crate::dynamics::kinematics_calls`).
use crate::python::Obj;
use pyo3::prelude::*;

use super::calls::calls;
use super::PyModel;
use crate::dynamics::denoc;
use crate::dynamics::kinematics_calls as kin;
use crate::python::record::{record, Field};

calls! {
    fn body_poses(q: &Obj) = kin::body_poses => (named) detached;
    fn point_masses(q: &Obj) = kin::point_masses => (masses, points);
    fn denoc(q: &Obj) = kin::matrices => PyDenoc detached;
    fn denoc_rates(q: &Obj, v: &Obj) = kin::rates => PyDenocRates detached;
    fn convective_matrix(q: &Obj, v: &Obj) = kin::convective_matrix => (c) detached;
    fn gravity_forces(q: &Obj, gravity: &Obj) = kin::gravity_forces => (tg) detached;
    fn generalized_forces(q: &Obj, forces: &Obj) = kin::generalized_forces => (tau) detached;
}

calls! { in_workspace
    fn placements(q) = kin::placements => (rotations, origins);
    fn velocity_to_qdot(q, v) = kin::velocity_to_qdot => (qd);
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
