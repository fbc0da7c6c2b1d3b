//! The configuration's tangent space, as the derivatives use it (docs/derivatives.md):
//! `q ⊕ δ` (a quaternion joint turns its body by `R exp(δ)`, a free flyer also moves its
//! origin by `R δ_lin`; every other coordinate adds `δ`), the map `∂δ/∂q` that chains a
//! tangent derivative to one in the coordinates of `q`, and the derivatives of the joint
//! kinematics `q̇ = f(q, v)` in those coordinates. All per joint, written into caller
//! buffers.
use crate::joint::{quat_to_matrix, Joint};
use crate::model::Model;
use crate::spatial::{skew, Mat3, Vec3};
use nalgebra::DMatrix;

/// The unit quaternion `(x, y, z, w)` of `q` and its norm.
#[inline]
fn unit(q: &[f64]) -> ([f64; 4], f64) {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    ([q[0] / n, q[1] / n, q[2] / n, q[3] / n], n)
}

/// `q ⊗ exp(δ)`: the quaternion turned by the body-axes rotation vector `δ` (unit result).
fn quat_step(q: &[f64], d: &[f64], out: &mut [f64]) {
    let (u, _) = unit(q);
    let t = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let (s, c) = if t < 1e-8 {
        (0.5 - t * t / 48.0, 1.0 - t * t / 8.0)
    } else {
        ((0.5 * t).sin() / t, (0.5 * t).cos())
    };
    let (bx, by, bz, bw) = (d[0] * s, d[1] * s, d[2] * s, c);
    let (ax, ay, az, aw) = (u[0], u[1], u[2], u[3]);
    out[0] = aw * bx + bw * ax + (ay * bz - az * by);
    out[1] = aw * by + bw * ay + (az * bx - ax * bz);
    out[2] = aw * bz + bw * az + (ax * by - ay * bx);
    out[3] = aw * bw - (ax * bx + ay * by + az * bz);
}

/// `out = q ⊕ δ` (`δ` of length nv).
pub fn integrate(model: &Model, q: &[f64], delta: &[f64], out: &mut [f64]) {
    out.copy_from_slice(q);
    for l in &model.links {
        let (iq, iv) = (l.q_index, l.v_index);
        match l.joint {
            Joint::Spherical => quat_step(&q[iq..iq + 4], &delta[iv..iv + 3], &mut out[iq..iq + 4]),
            Joint::FreeFlyer => {
                let r = quat_to_matrix(&q[iq + 3..iq + 7]);
                let p = r * Vec3::new(delta[iv], delta[iv + 1], delta[iv + 2]);
                for k in 0..3 {
                    out[iq + k] = q[iq + k] + p[k];
                }
                quat_step(
                    &q[iq + 3..iq + 7],
                    &delta[iv + 3..iv + 6],
                    &mut out[iq + 3..iq + 7],
                );
            }
            j => {
                for k in 0..j.nv() {
                    out[iq + k] = q[iq + k] + delta[iv + k];
                }
            }
        }
    }
}

/// `∂δ/∂q` of a quaternion at `q` (3 × 4, `(x, y, z, w)` columns): `δ = (2/|q|) vec(q̂* ⊗ dq)`
/// (the radial part of `dq` changes nothing: the dynamics normalise quaternions).
#[inline]
fn quat_tangent(q: &[f64]) -> [[f64; 4]; 3] {
    let (u, n) = unit(q);
    let (x, y, z, w) = (u[0], u[1], u[2], u[3]);
    let k = 2.0 / n;
    [
        [k * w, k * z, -k * y, -k * x],
        [-k * z, k * w, k * x, -k * y],
        [k * y, -k * x, k * w, -k * z],
    ]
}

/// `T = ∂δ/∂q` (nv × nq) at `q`: the identity for every coordinate but the quaternions' (and a
/// free flyer's origin, `Rᵀ`). Writes all of `t`.
pub fn tangent_map(model: &Model, q: &[f64], t: &mut DMatrix<f64>) {
    t.as_mut_slice().fill(0.0);
    for l in &model.links {
        let (iq, iv) = (l.q_index, l.v_index);
        match l.joint {
            Joint::Spherical => {
                let m = quat_tangent(&q[iq..iq + 4]);
                for r in 0..3 {
                    for c in 0..4 {
                        t[(iv + r, iq + c)] = m[r][c];
                    }
                }
            }
            Joint::FreeFlyer => {
                let rot = quat_to_matrix(&q[iq + 3..iq + 7]);
                let m = quat_tangent(&q[iq + 3..iq + 7]);
                for r in 0..3 {
                    for c in 0..3 {
                        t[(iv + r, iq + c)] = rot[(c, r)];
                    }
                    for c in 0..4 {
                        t[(iv + 3 + r, iq + 3 + c)] = m[r][c];
                    }
                }
            }
            j => {
                for k in 0..j.nv() {
                    t[(iv + k, iq + k)] = 1.0;
                }
            }
        }
    }
}

/// `q̇ = ½ q̂ ⊗ (ω, 0)` as a matrix on `(x, y, z, w)`: `Ω(ω)/2`.
#[inline]
fn omega(a: f64, b: f64, c: f64) -> [[f64; 4]; 4] {
    [
        [0.0, 0.5 * c, -0.5 * b, 0.5 * a],
        [-0.5 * c, 0.0, 0.5 * a, 0.5 * b],
        [0.5 * b, -0.5 * a, 0.0, 0.5 * c],
        [-0.5 * a, -0.5 * b, -0.5 * c, 0.0],
    ]
}

/// Adds the quaternion block of `∂q̇/∂q` (`Ω(ω)/2 · (1 − q̂q̂ᵀ)/|q|`) and of `∂q̇/∂ω` at rows
/// `row` of the row-major `dim × dim` `jac`, columns `cq` (quaternion) and `cv` (ω).
fn quat_rate_blocks(
    q: &[f64],
    w: &[f64],
    jac: &mut [f64],
    dim: usize,
    row: usize,
    cq: usize,
    cv: usize,
) {
    let (u, n) = unit(q);
    let om = omega(w[0], w[1], w[2]);
    for r in 0..4 {
        for c in 0..4 {
            // (Ω (1 − û ûᵀ))_rc / n
            let mut x = om[r][c];
            let ou: f64 = (0..4).map(|k| om[r][k] * u[k]).sum();
            x -= ou * u[c];
            jac[(row + r) * dim + cq + c] = x / n;
        }
    }
    let (x, y, z, ww) = (u[0], u[1], u[2], u[3]);
    let dv = [[ww, -z, y], [z, ww, -x], [-y, x, ww], [-x, -y, -z]];
    for r in 0..4 {
        for c in 0..3 {
            jac[(row + r) * dim + cv + c] = 0.5 * dv[r][c];
        }
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
        match l.joint {
            Joint::Spherical => {
                quat_rate_blocks(&q[iq..iq + 4], &v[iv..iv + 3], jac, dim, iq, iq, nq + iv)
            }
            Joint::FreeFlyer => {
                let qq = &q[iq + 3..iq + 7];
                let rot = quat_to_matrix(qq);
                let vl = Vec3::new(v[iv], v[iv + 1], v[iv + 2]);
                // ṗ = R v: ∂/∂v = R, ∂/∂quat = −R ṽ ∂δ/∂quat.
                let rv: Mat3 = -rot * skew(&vl);
                let t = quat_tangent(qq);
                for r in 0..3 {
                    for c in 0..3 {
                        jac[(iq + r) * dim + nq + iv + c] = rot[(r, c)];
                    }
                    for c in 0..4 {
                        jac[(iq + r) * dim + iq + 3 + c] =
                            (0..3).map(|k| rv[(r, k)] * t[k][c]).sum::<f64>();
                    }
                }
                quat_rate_blocks(
                    qq,
                    &v[iv + 3..iv + 6],
                    jac,
                    dim,
                    iq + 3,
                    iq + 3,
                    nq + iv + 3,
                );
            }
            j => {
                for k in 0..j.nv() {
                    jac[(iq + k) * dim + nq + iv + k] = 1.0;
                }
            }
        }
    }
}
