//! The configuration's tangent space, as the derivatives use it (docs/derivatives.md):
//! `q ⊕ δ` (a quaternion joint turns its body by `R exp(δ)`, a free flyer also moves its
//! origin by `R δ_lin`; every other coordinate adds `δ`), the map `∂δ/∂q` that chains a
//! tangent derivative to one in the coordinates of `q`, and the derivatives of the joint
//! kinematics `q̇ = f(q, v)` in those coordinates. Each joint gives its own part
//! ([`crate::joint::JointType`]); these assemble them, into caller buffers.
use crate::joint::JacobianRows;
use crate::model::Model;
use nalgebra::DMatrix;

/// `out = q ⊕ δ` (`δ` of length nv).
pub fn integrate(model: &Model, q: &[f64], delta: &[f64], out: &mut [f64]) {
    out.copy_from_slice(q);
    for l in &model.links {
        let (iq, iv) = (l.q_index, l.v_index);
        let (nq, nv) = (l.joint.nq(), l.joint.nv());
        let q = &q[iq..iq + nq];
        l.joint
            .integrate(q, &delta[iv..iv + nv], &mut out[iq..iq + nq]);
    }
}

/// `T = ∂δ/∂q` (nv × nq) at `q`: the identity for every coordinate but the quaternions' (and a
/// free flyer's origin, `Rᵀ`). Writes all of `t`.
pub fn tangent_map(model: &Model, q: &[f64], t: &mut DMatrix<f64>) {
    t.as_mut_slice().fill(0.0);
    for l in &model.links {
        let (iq, iv) = (l.q_index, l.v_index);
        let (nq, nv) = (l.joint.nq(), l.joint.nv());
        let mut block = t.view_mut((iv, iq), (nv, nq));
        l.joint.tangent_map(&q[iq..iq + nq], &mut block);
    }
}

/// The rows `0..nq` of the state Jacobian of `ẏ = [q̇(q, v); v̇]` (row-major, `dim = nq + nv`
/// columns, `y = [q; v]`): `∂q̇/∂q` and `∂q̇/∂v` of the joint kinematics. Writes every entry of
/// those rows.
pub fn qdot_jacobian(model: &Model, q: &[f64], v: &[f64], jac: &mut [f64]) {
    let (nq, dim) = (model.nq, model.nq + model.nv);
    jac[..nq * dim].fill(0.0);
    for l in &model.links {
        let (iq, iv) = (l.q_index, l.v_index);
        let (lq, lv) = (l.joint.nq(), l.joint.nv());
        let mut rows = JacobianRows {
            data: jac,
            stride: dim,
            row: iq,
            cq: iq,
            cv: nq + iv,
        };
        l.joint
            .qdot_jacobian(&q[iq..iq + lq], &v[iv..iv + lv], &mut rows);
    }
}
