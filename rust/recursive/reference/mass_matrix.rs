//! Generalized inertia matrix by composite bodies in world axes (O(n·depth)), kept as a
//! cross-check of the link-frame default (`mass_matrix_local`): each link's subtree welded
//! into one rigid body about its origin, then `I_ij = P_iᵀ (A_jiᵀ M^c_j P_j)`.
use nalgebra::DMatrix;

use super::Workspace;
use crate::kinematics;
use crate::model::Model;
use crate::support::spatial::shift_wrench;

/// Fills `gim` (nv × nv, symmetric).
pub fn mass_matrix_world(model: &Model, ws: &mut Workspace, q: &[f64], gim: &mut DMatrix<f64>) {
    kinematics::positions(model, q, &mut ws.links);
    for (i, s) in ws.links.iter().enumerate() {
        ws.composite[i] = s.inertia;
    }
    for (i, l) in model.links.iter().enumerate().rev() {
        if let Some(p) = l.parent {
            let moved = ws.composite[i].shifted(&(ws.links[i].origin - ws.links[p].origin));
            ws.composite[p].add(&moved);
        }
    }
    gim.fill(0.0);
    for (i, l) in model.links.iter().enumerate() {
        for k in 0..l.joint.nv() {
            let col = l.v_index + k;
            let mut f = ws.composite[i].mul_twist(&ws.links[i].s[k]);
            for m in 0..l.joint.nv() {
                gim[(l.v_index + m, col)] = ws.links[i].s[m].dot(&f);
            }
            let mut j = i;
            while let Some(p) = model.links[j].parent {
                f = shift_wrench(&f, &(ws.links[j].origin - ws.links[p].origin));
                let lp = &model.links[p];
                for m in 0..lp.joint.nv() {
                    let x = ws.links[p].s[m].dot(&f);
                    gim[(lp.v_index + m, col)] = x;
                    gim[(col, lp.v_index + m)] = x;
                }
                j = p;
            }
        }
    }
}
