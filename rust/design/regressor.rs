//! The objectives a designer trades, as linear maps of the links' inertial parameters along a
//! prescribed motion.
//!
//! Shaking force and moment, driving forces and every joint's bearing force (cut joints
//! included) are sums of Newton's `m a` over point masses, so for a fixed motion they are
//! linear in the point masses — and, a link's points being rigid, in the ten numbers
//! `φ = Σ m (1, p, p pᵀ)` of each link (mass, first and second moments about its origin,
//! link frame). The map per link is found from ten unit point masses whose `φ` span the
//! ten dimensions (the point motion code, then one 10×10 solve): no separate rigid-body
//! regressor to keep consistent with it.
use nalgebra::{DMatrix, SMatrix};

use super::cells::point_moments;
use crate::dynamics::reactions::{
    add_cut_wrenches, add_point_force, carried_points, link_accelerations,
};
use crate::loops::{self, LoopKinematics};
use crate::model::Model;
use crate::recursive::reference::Workspace;
use crate::support::error::{Error, Result};
use crate::support::spatial::{linear, Vec3, Vec6};

/// Parameters per link.
pub const NPARAM: usize = 10;

/// Which rows of one sample hold which quantity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    pub nactuated: usize,
    pub nlinks: usize,
    pub nloops: usize,
}

impl Layout {
    /// Rows per sample: force (3), moment (3), driving forces, each link's bearing force (3),
    /// each cut joint's force (3).
    pub fn rows(&self) -> usize {
        6 + self.nactuated + 3 * (self.nlinks + self.nloops)
    }
    pub fn force(&self) -> std::ops::Range<usize> {
        0..3
    }
    pub fn moment(&self) -> std::ops::Range<usize> {
        3..6
    }
    pub fn torque(&self) -> std::ops::Range<usize> {
        6..6 + self.nactuated
    }
    /// The bearing force (world axes) the parent applies through link `i`'s joint.
    pub fn bearing(&self, i: usize) -> std::ops::Range<usize> {
        let s = 6 + self.nactuated + 3 * i;
        s..s + 3
    }
    /// Cut joint `k`'s force (its frame a's axes, as `constraint_forces`).
    pub fn cut(&self, k: usize) -> std::ops::Range<usize> {
        let s = 6 + self.nactuated + 3 * (self.nlinks + k);
        s..s + 3
    }
}

/// `y(t_k) = Y_k φ`: `data` is (samples × rows, 10 · nlinks), sample-major; column
/// `10 i + c` is parameter `c` of link `i` ([`point_moments`] order, link frame).
#[derive(Debug, Clone)]
pub struct Regressor {
    pub layout: Layout,
    pub samples: usize,
    pub data: DMatrix<f64>,
}

/// The links' current parameters (from their seven point masses), as one vector.
pub fn model_parameters(model: &Model) -> Vec<f64> {
    let mut out = vec![0.0; NPARAM * model.links.len()];
    for (i, l) in model.links.iter().enumerate() {
        for (m, p) in l.points.masses.iter().zip(&l.points.positions) {
            for (o, v) in out[NPARAM * i..NPARAM * (i + 1)]
                .iter_mut()
                .zip(point_moments(p))
            {
                *o += m * v;
            }
        }
    }
    out
}

/// Ten points whose unit masses span the parameters (origin, ±axes, three face diagonals),
/// and the inverse of their parameter matrix.
fn basis() -> ([Vec3; NPARAM], SMatrix<f64, NPARAM, NPARAM>) {
    let e = |x: f64, y: f64, z: f64| Vec3::new(x, y, z);
    let pts = [
        e(0.0, 0.0, 0.0),
        e(1.0, 0.0, 0.0),
        e(0.0, 1.0, 0.0),
        e(0.0, 0.0, 1.0),
        e(-1.0, 0.0, 0.0),
        e(0.0, -1.0, 0.0),
        e(0.0, 0.0, -1.0),
        e(1.0, 1.0, 0.0),
        e(1.0, 0.0, 1.0),
        e(0.0, 1.0, 1.0),
    ];
    let mut phi = SMatrix::<f64, NPARAM, NPARAM>::zeros();
    for (c, p) in pts.iter().enumerate() {
        for (r, v) in point_moments(p).iter().enumerate() {
            phi[(r, c)] = *v;
        }
    }
    // Invertible by construction (the points are fixed): no user input reaches this.
    let inv = phi.try_inverse().unwrap_or_else(SMatrix::zeros);
    (pts, inv)
}

/// The constraints' (loops' and couplings') share of a change `δτ` of the tree's joint forces:
/// `[S_a | Jᵀ] (τ_a, λ) = δτ`
/// in the least-squares minimum-norm sense, then the cut wrenches' effect on every tree
/// joint's force. Columns per unit `δτ`: `(τ_a (na × nv), cut forces (3 nloops × nv),
/// bearing forces (3 nlinks × nv))`.
struct LoopShare {
    kin: LoopKinematics,
    jac: DMatrix<f64>,
}

impl LoopShare {
    fn new(model: &Model) -> Self {
        LoopShare {
            kin: LoopKinematics::new(model),
            jac: DMatrix::zeros(model.nconstraints(), model.nv),
        }
    }

    fn at(
        &mut self,
        model: &Model,
        ws: &Workspace,
        q: &[f64],
        actuated: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>)> {
        let (n, m, na) = (model.nv, model.nconstraints(), actuated.len());
        self.kin.positions(model, q);
        loops::jacobian(model, &self.kin, &mut self.jac);
        let mut sys = DMatrix::zeros(n, na + m);
        for (k, &c) in actuated.iter().enumerate() {
            sys[(c, k)] = 1.0;
        }
        sys.view_mut((0, na), (n, m)).tr_copy_from(&self.jac);
        let scale = sys.amax().max(1e-300);
        let pinv = sys
            .pseudo_inverse(1e-12 * scale)
            .map_err(|e| Error::Singular(format!("design: the loops' force map: {e}")))?;
        let (nl, nk) = (model.links.len(), model.loops.len());
        let mut tau = DMatrix::zeros(na, n);
        let mut cut = DMatrix::zeros(3 * nk, n);
        let mut bearing = DMatrix::zeros(3 * nl, n);
        let mut ext = vec![Vec6::zeros(); nl];
        let mut acc = vec![Vec3::zeros(); nl];
        for c in 0..n {
            let x = pinv.column(c);
            for k in 0..na {
                tau[(k, c)] = x[k];
            }
            let lambda: Vec<f64> = x.rows(na, m).iter().copied().collect();
            let w = loops::wrenches(model, &self.kin, &lambda);
            for (k, wk) in w.iter().enumerate() {
                for r in 0..3 {
                    cut[(3 * k + r, c)] = wk[r];
                }
            }
            ext.iter_mut().for_each(|e| *e = Vec6::zeros());
            add_cut_wrenches(model, ws, &w, &mut ext);
            // A joint carries minus the external forces on its subtree (links come after
            // their parents).
            for (i, e) in ext.iter().enumerate() {
                acc[i] = -linear(e);
            }
            for i in (0..nl).rev() {
                if let Some(p) = model.links[i].parent {
                    let below = acc[i];
                    acc[p] += below;
                }
            }
            for i in 0..nl {
                for r in 0..3 {
                    bearing[(3 * i + r, c)] = acc[i][r];
                }
            }
        }
        Ok((tau, cut, bearing))
    }
}

/// The number of states in `q`, `v`, `a` (N × nq, N × nv, N × nv), with `actuated` checked
/// against the model.
fn checked_samples(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    actuated: &[usize],
) -> Result<usize> {
    let (nq, nv) = (model.nq, model.nv);
    let samples = q.len().checked_div(nq).unwrap_or(0);
    if q.len() != samples * nq || v.len() != samples * nv || a.len() != samples * nv {
        return Err(Error::arg(
            "q, v, a",
            "the same number of states (N × nq, N × nv, N × nv)",
            format!("{}, {}, {} values", q.len(), v.len(), a.len()),
        ));
    }
    if let Some(&bad) = actuated.iter().find(|&&c| c >= nv) {
        return Err(Error::arg(
            "actuated",
            format!("v indices below {nv}"),
            format!("{bad}"),
        ));
    }
    if !model.loops.is_empty() && actuated.is_empty() {
        return Err(Error::arg(
            "actuated",
            "the driven joints of a mechanism with loops",
            "none",
        ));
    }
    Ok(samples)
}

/// The regressor along `samples` states (`q` samples × nq, `v`, `a` samples × nv, row after
/// row), with gravity `g`, moments about `about`, and the driving forces of `actuated` (v
/// indices; required for a model with loops, the tree's joint forces themselves otherwise).
pub fn regressor(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    about: &Vec3,
    actuated: &[usize],
) -> Result<Regressor> {
    let (nq, nv, nl) = (model.nq, model.nv, model.links.len());
    let samples = checked_samples(model, q, v, a, actuated)?;
    // Loops, or couplings with some joints not driven (those follow through their
    // couplings): the driving forces share δτ with the constraints. Couplings with every
    // joint driven: each joint's own (tree) force, as `inverse_dynamics` without `actuated`.
    let constrained =
        !model.loops.is_empty() || (!model.couplings.is_empty() && actuated.len() < nv);
    let layout = Layout {
        nactuated: actuated.len(),
        nlinks: nl,
        nloops: model.loops.len(),
    };
    let rows = layout.rows();
    let mut data =
        crate::support::alloc::try_zeros(samples * rows, NPARAM * nl, "design regressor")?;
    let (pts, inv) = basis();
    let mut ws = Workspace::new(model);
    let mut share = LoopShare::new(model);
    let mut col = vec![0.0; rows];
    let mut tree = vec![0.0; nv];
    let mut block = DMatrix::<f64>::zeros(rows, NPARAM);
    for k in 0..samples {
        crate::support::interrupt::check("design regressor")?;
        let (qk, vk, ak) = (
            &q[k * nq..(k + 1) * nq],
            &v[k * nv..(k + 1) * nv],
            &a[k * nv..(k + 1) * nv],
        );
        link_accelerations(model, &mut ws, qk, vk, ak);
        let loop_share = if !constrained {
            None
        } else {
            Some(share.at(model, &ws, qk, actuated)?)
        };
        for i in 0..nl {
            for (b, p) in pts.iter().enumerate() {
                let Some((r, _, acc)) = carried_points(&ws, &[(i, *p)]).next() else {
                    continue;
                };
                let f = acc - g;
                col.iter_mut().for_each(|x| *x = 0.0);
                col[0..3].copy_from_slice((-acc).as_slice());
                col[3..6].copy_from_slice((-(r - about).cross(&acc)).as_slice());
                tree.iter_mut().for_each(|x| *x = 0.0);
                add_point_force(model, &ws, i, &r, &f, &mut tree);
                // The point's own weight and inertia pass through every joint from its link
                // to the ground.
                let mut j = Some(i);
                while let Some(jj) = j {
                    col[layout.bearing(jj)]
                        .iter_mut()
                        .zip(f.iter())
                        .for_each(|(c, x)| *c += x);
                    j = model.links[jj].parent;
                }
                match &loop_share {
                    None => {
                        for (t, &c) in layout.torque().zip(actuated) {
                            col[t] = tree[c];
                        }
                    }
                    Some((tau, cut, bearing)) => {
                        let dt = nalgebra::DVectorView::from_slice(&tree, nv);
                        let ta = tau * dt;
                        let cf = cut * dt;
                        let bf = bearing * dt;
                        for (t, x) in layout.torque().zip(ta.iter()) {
                            col[t] = *x;
                        }
                        let c0 = layout.cut(0).start;
                        col[c0..c0 + cf.len()].copy_from_slice(cf.as_slice());
                        let b0 = layout.bearing(0).start;
                        for (c, x) in col[b0..b0 + bf.len()].iter_mut().zip(bf.iter()) {
                            *c += x;
                        }
                    }
                }
                for (r_, x) in col.iter().enumerate() {
                    block[(r_, b)] = *x;
                }
            }
            // Per unit parameter: Y_φ = Y_points Φ⁻¹.
            let yphi = &block * inv;
            data.view_mut((k * rows, NPARAM * i), (rows, NPARAM))
                .copy_from(&yphi);
        }
    }
    Ok(Regressor {
        layout,
        samples,
        data,
    })
}
