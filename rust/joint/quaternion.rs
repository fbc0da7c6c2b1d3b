//! The tangent space of a unit quaternion `(x, y, z, w)` as the quaternion joints need it for
//! derivatives (docs/derivatives.md): the step `q ⊗ exp(δ)`, the map `∂δ/∂q`, and the
//! derivatives of `q̇ = ½ q ⊗ (ω, 0)`.
use nalgebra::DMatrixViewMut;

use super::JacobianRows;

/// The unit quaternion `(x, y, z, w)` of `q` and its norm.
#[inline]
fn unit(q: &[f64]) -> ([f64; 4], f64) {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    ([q[0] / n, q[1] / n, q[2] / n, q[3] / n], n)
}

/// `q ⊗ exp(δ)`: the quaternion turned by the body-axes rotation vector `δ` (unit result).
pub(super) fn step(q: &[f64], d: &[f64], out: &mut [f64]) {
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

/// `∂δ/∂q` of a quaternion at `q` (3 × 4, `(x, y, z, w)` columns): `δ = (2/|q|) vec(q̂* ⊗ dq)`
/// (the radial part of `dq` changes nothing: the dynamics normalise quaternions).
#[inline]
pub(super) fn tangent(q: &[f64]) -> [[f64; 4]; 3] {
    let (u, n) = unit(q);
    let (x, y, z, w) = (u[0], u[1], u[2], u[3]);
    let k = 2.0 / n;
    [
        [k * w, k * z, -k * y, -k * x],
        [-k * z, k * w, k * x, -k * y],
        [k * y, -k * x, k * w, -k * z],
    ]
}

/// [`tangent`] into the block `t` (rows `r0..r0 + 3`, columns `c0..c0 + 4`).
pub(super) fn tangent_into(q: &[f64], t: &mut DMatrixViewMut<'_, f64>, r0: usize, c0: usize) {
    let m = tangent(q);
    for r in 0..3 {
        for c in 0..4 {
            t[(r0 + r, c0 + c)] = m[r][c];
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

/// The quaternion block of `∂q̇/∂q` (`Ω(ω)/2 · (1 − q̂q̂ᵀ)/|q|`) and of `∂q̇/∂ω` into rows
/// `r0..r0 + 4` of `jac`, from `q` column and `v` column `c0` (quaternion, ω).
pub(super) fn rate_blocks(q: &[f64], w: &[f64], jac: &mut JacobianRows<'_>, r0: usize, c0: usize) {
    let (u, n) = unit(q);
    let om = omega(w[0], w[1], w[2]);
    for r in 0..4 {
        for c in 0..4 {
            // (Ω (1 − û ûᵀ))_rc / n
            let mut x = om[r][c];
            let ou: f64 = (0..4).map(|k| om[r][k] * u[k]).sum();
            x -= ou * u[c];
            jac.set_q(r0 + r, c0 + c, x / n);
        }
    }
    let (x, y, z, ww) = (u[0], u[1], u[2], u[3]);
    let dv = [[ww, -z, y], [z, ww, -x], [-y, x, ww], [-x, -y, -z]];
    for r in 0..4 {
        for c in 0..3 {
            jac.set_v(r0 + r, c0 + c, 0.5 * dv[r][c]);
        }
    }
}
