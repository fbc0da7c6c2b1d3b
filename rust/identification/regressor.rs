//! The joint torque regressor `τ = Y π` (docs/identification.md): per link the ten inertial
//! parameters in Pinocchio's order and frame (`computeJointTorqueRegressor`: mass, first
//! moment `m c`, then the inertia about the link origin `Ixx, Ixy, Iyy, Ixz, Iyz, Izz`, link
//! axes), then per 1-dof joint the columns of the joint-space terms the inverse dynamics
//! leaves out: viscous friction (`v`), Coulomb friction (`sign v`), armature (`a`) and a
//! constant offset.
//!
//! Built on the world-axes kinematics the design maps use ([`link_accelerations`]): each
//! link's wrench about its origin is linear in its ten parameters (Newton–Euler in the link
//! frame), and a joint carries the wrenches of the links after it.
use nalgebra::DMatrix;

use crate::dynamics::reactions::link_accelerations;
use crate::joint::MotionClass;
use crate::model::Model;
use crate::recursive::reference::Workspace;
use crate::support::error::{Error, Result};
use crate::support::spatial::{angular, linear, Mat3, Vec3};

/// Parameters per link.
pub const NPARAM: usize = 10;

/// Names of a link's parameters, in column order (Pinocchio's).
pub const PARAMETER_NAMES: [&str; NPARAM] = [
    "m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz",
];

/// Which joint-space columns follow the links' parameters: one block per kind, each with
/// one column per 1-dof joint (revolute or prismatic), in v order.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Extras {
    pub viscous: bool,
    pub coulomb: bool,
    pub armature: bool,
    pub offset: bool,
}

impl Extras {
    fn kinds(&self) -> impl Iterator<Item = &'static str> {
        [
            (self.viscous, "fv"),
            (self.coulomb, "fc"),
            (self.armature, "armature"),
            (self.offset, "offset"),
        ]
        .into_iter()
        .filter(|(on, _)| *on)
        .map(|(_, n)| n)
    }
}

/// The v indices of the 1-dof joints (those that get friction, armature and offset columns).
pub fn extra_joints(model: &Model) -> Vec<usize> {
    model
        .links
        .iter()
        .filter(|l| {
            matches!(
                l.joint.motion(),
                MotionClass::Angular1 | MotionClass::Linear1
            )
        })
        .map(|l| l.v_index)
        .collect()
}

/// The column names: `"<body>.<parameter>"` for the links (the body that defines the link),
/// then `"<body>.fv"`, `.fc`, `.armature`, `.offset` for the joint of that body.
pub fn parameter_names(model: &Model, extras: &Extras) -> Vec<String> {
    let mut out = Vec::new();
    for l in &model.links {
        let b = &model.bodies[l.body].name;
        out.extend(PARAMETER_NAMES.iter().map(|p| format!("{b}.{p}")));
    }
    let joints: Vec<&str> = model
        .links
        .iter()
        .filter(|l| {
            matches!(
                l.joint.motion(),
                MotionClass::Angular1 | MotionClass::Linear1
            )
        })
        .map(|l| model.bodies[l.body].name.as_str())
        .collect();
    for kind in extras.kinds() {
        out.extend(joints.iter().map(|b| format!("{b}.{kind}")));
    }
    out
}

/// Every column's name and the model's own value of it (the links' ten each, the extra
/// columns zero).
pub fn parameters(model: &Model, extras: &Extras) -> (Vec<String>, Vec<f64>) {
    let names = parameter_names(model, extras);
    let mut values = model_parameters(model);
    values.resize(names.len(), 0.0);
    (names, values)
}

/// The links' parameters of a model (Pinocchio's order, link frames), its merged bodies.
pub fn model_parameters(model: &Model) -> Vec<f64> {
    let mut out = Vec::with_capacity(NPARAM * model.links.len());
    for l in &model.links {
        out.extend(body_parameters(
            l.rigid.mass,
            &l.rigid.com,
            &l.rigid.inertia_about(&Vec3::zeros()),
        ));
    }
    out
}

/// `(m, m c, I_origin)` in Pinocchio's order.
pub fn body_parameters(mass: f64, com: &Vec3, inertia_origin: &Mat3) -> [f64; NPARAM] {
    let i = inertia_origin;
    [
        mass,
        mass * com.x,
        mass * com.y,
        mass * com.z,
        i[(0, 0)],
        i[(0, 1)],
        i[(1, 1)],
        i[(0, 2)],
        i[(1, 2)],
        i[(2, 2)],
    ]
}

/// Number of columns for `model` with `extras`.
pub fn ncolumns(model: &Model, extras: &Extras) -> usize {
    NPARAM * model.links.len() + extras.kinds().count() * extra_joints(model).len()
}

/// A link's wrench about its origin, link axes, per unit parameter: `(n, f)` for each of the
/// ten columns, from the link's angular velocity `w`, angular acceleration `dw` and origin
/// acceleration minus gravity `acc` (link axes).
fn link_columns(w: &Vec3, dw: &Vec3, acc: &Vec3) -> [(Vec3, Vec3); NPARAM] {
    let z = Vec3::zeros();
    let mut out = [(z, z); NPARAM];
    out[0] = (z, *acc);
    for k in 0..3 {
        let h = Vec3::ith(k, 1.0);
        out[1 + k] = (h.cross(acc), dw.cross(&h) + w.cross(&w.cross(&h)));
    }
    // Unit symmetric tensors in Pinocchio's order: xx, xy, yy, xz, yz, zz.
    const IJ: [(usize, usize); 6] = [(0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)];
    for (c, &(r, s)) in IJ.iter().enumerate() {
        let mut e = Mat3::zeros();
        e[(r, s)] = 1.0;
        e[(s, r)] = 1.0;
        out[4 + c] = (e * dw + w.cross(&(e * w)), z);
    }
    out
}

/// Checks `q, v, a` as `samples` stacked states; returns `samples`.
pub fn check_states(model: &Model, q: &[f64], v: &[f64], a: &[f64]) -> Result<usize> {
    let (nq, nv) = (model.nq, model.nv);
    let samples = q.len().checked_div(nq).unwrap_or(0);
    if q.len() != samples * nq || v.len() != samples * nv || a.len() != samples * nv {
        return Err(Error::arg(
            "q, v, a",
            "the same number of states (N × nq, N × nv, N × nv)",
            format!("{}, {}, {} values", q.len(), v.len(), a.len()),
        ));
    }
    crate::support::error::check_finite("q", q)?;
    crate::support::error::check_finite("v", v)?;
    crate::support::error::check_finite("a", a)?;
    Ok(samples)
}

/// `Y` along `samples` stacked states (`q` N × nq, `v`, `a` N × nv, row after row) with
/// gravity `g`: (N · nv) × [`ncolumns`], sample-major rows (sample k's joint forces in rows
/// `k nv .. (k+1) nv`). The joint forces of the tree: for a model with couplings, each
/// joint's own force, as `inverse_dynamics` without `actuated`. A model with loops is
/// refused: its joint forces depend on which joints drive it
/// ([`super::actuated::actuated_regressor`]).
pub fn torque_regressor(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    extras: &Extras,
) -> Result<DMatrix<f64>> {
    if !model.loops.is_empty() {
        return Err(Error::arg(
            "actuated",
            "the driven joints of a mechanism with loops (its joint forces depend on which joints drive it)",
            format!("none, for a model with {} loop(s)", model.loops.len()),
        ));
    }
    tree_regressor(model, q, v, a, g, extras)
}

/// [`torque_regressor`] of the spanning tree, loops or not (the cut joints' forces left out).
pub(super) fn tree_regressor(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    extras: &Extras,
) -> Result<DMatrix<f64>> {
    let samples = check_states(model, q, v, a)?;
    let (nq, nv) = (model.nq, model.nv);
    let cols = ncolumns(model, extras);
    let mut out = crate::support::alloc::try_zeros(samples * nv, cols, "torque regressor")?;
    let mut ws = Workspace::new(model);
    let joints = extra_joints(model);
    for k in 0..samples {
        if k % 1024 == 0 {
            crate::support::interrupt::check("torque regressor")?;
        }
        let (qk, vk, ak) = (
            &q[k * nq..(k + 1) * nq],
            &v[k * nv..(k + 1) * nv],
            &a[k * nv..(k + 1) * nv],
        );
        link_accelerations(model, &mut ws, qk, vk, ak);
        fill_sample(model, &ws, g, &mut out, k * nv);
        let mut col = NPARAM * model.links.len();
        let row = k * nv;
        let mut block = |f: &dyn Fn(usize) -> f64| {
            for &j in &joints {
                out[(row + j, col)] = f(j);
                col += 1;
            }
        };
        if extras.viscous {
            block(&|j| vk[j]);
        }
        if extras.coulomb {
            block(&|j| coulomb(vk[j]));
        }
        if extras.armature {
            block(&|j| ak[j]);
        }
        if extras.offset {
            block(&|_| 1.0);
        }
    }
    Ok(out)
}

/// `sign v`, zero at rest (no friction force is known there).
pub fn coulomb(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// One sample's link columns into rows `row .. row + nv` (kinematics in `ws`).
fn fill_sample(model: &Model, ws: &Workspace, g: &Vec3, out: &mut DMatrix<f64>, row: usize) {
    for i in 0..model.links.len() {
        let s = &ws.links[i];
        let rt = s.rotation.transpose();
        let w = rt * angular(&s.twist);
        let dw = rt * angular(&ws.accel[i]);
        // Gravity as an upward acceleration of the base (the design maps' `acc − g`).
        let acc = rt * (linear(&ws.accel[i]) - g);
        let cols = link_columns(&w, &dw, &acc);
        let mut j = Some(i);
        while let Some(jj) = j {
            let lj = &model.links[jj];
            let sj = &ws.links[jj];
            let d = s.origin - sj.origin;
            for c in 0..lj.joint.nv() {
                let col = &sj.s[c];
                let u = angular(col);
                // τ = u·(n + d × f) + v·f = u·n + (v + u × d)·f, in link i's axes.
                let ub = rt * u;
                let wb = rt * (linear(col) + u.cross(&d));
                for (p, (n, f)) in cols.iter().enumerate() {
                    out[(row + lj.v_index + c, NPARAM * i + p)] = ub.dot(n) + wb.dot(f);
                }
            }
            j = lj.parent;
        }
    }
}
