//! The inverse kinematics' damped step with loop or coupling constraints, without
//! allocating: `min ½ δᵀHδ + gᵀδ` subject to `J_c δ = −c` as `δ = δ_c + N z`, with `δ_c`
//! the minimum-norm correction of the constraints and `N` an orthonormal basis of the null
//! space of `J_c`, both from a Householder QR of `J_cᵀ` with column pivoting (rank
//! revealing: a loop's rows are often dependent, a planar four-bar's three of five). Every
//! buffer is sized once per solve.

/// Workspace for [`NullStep::solve`] on `nv` speeds and `m` constraint rows.
#[derive(Debug, Clone)]
pub struct NullStep {
    nv: usize,
    m: usize,
    /// `J_cᵀ` (nv × m, column-major), overwritten by the reflectors (on and below the
    /// diagonal) and `R` (above it).
    a: Vec<f64>,
    tau: Vec<f64>,
    rdiag: Vec<f64>,
    perm: Vec<usize>,
    /// The null-space basis `N` (nv × k, column-major), then `H N`.
    n: Vec<f64>,
    hn: Vec<f64>,
    /// `Nᵀ H N` (k × k) and its Cholesky factor.
    nhn: Vec<f64>,
    chol: Vec<f64>,
    y: Vec<f64>,
    gn: Vec<f64>,
    z: Vec<f64>,
}

impl NullStep {
    pub fn new(nv: usize, m: usize) -> NullStep {
        NullStep {
            nv,
            m,
            a: vec![0.0; nv * m],
            tau: vec![0.0; m],
            rdiag: vec![0.0; m],
            perm: vec![0; m],
            n: vec![0.0; nv * nv],
            hn: vec![0.0; nv * nv],
            nhn: vec![0.0; nv * nv],
            chol: vec![0.0; nv * nv],
            y: vec![0.0; nv],
            gn: vec![0.0; nv],
            z: vec![0.0; nv],
        }
    }

    /// Householder QR of `J_cᵀ` with column pivoting; returns the rank (columns whose
    /// remaining norm exceeds `tol`).
    fn factor(&mut self, jc: &[f64], tol: f64) -> usize {
        let (nv, m) = (self.nv, self.m);
        // jc is m × nv column-major: J_cᵀ[i, j] = jc[j + i m].
        for j in 0..m {
            for i in 0..nv {
                self.a[i + j * nv] = jc[j + i * m];
            }
            self.perm[j] = j;
        }
        let steps = nv.min(m);
        for k in 0..steps {
            let norm2 = |a: &[f64], j: usize| (k..nv).map(|i| a[i + j * nv].powi(2)).sum::<f64>();
            let (mut p, mut best) = (k, -1.0);
            for j in k..m {
                let s = norm2(&self.a, j);
                if s > best {
                    (p, best) = (j, s);
                }
            }
            if best.sqrt() <= tol {
                return k;
            }
            if p != k {
                for i in 0..nv {
                    self.a.swap(i + k * nv, i + p * nv);
                }
                self.perm.swap(k, p);
            }
            // v = x − α e₁ with α = −sign(x₀) ‖x‖ (no cancellation), H = 1 − τ v vᵀ.
            let norm = best.sqrt();
            let x0 = self.a[k + k * nv];
            let alpha = if x0 >= 0.0 { -norm } else { norm };
            self.a[k + k * nv] = x0 - alpha;
            let vv: f64 = (k..nv).map(|i| self.a[i + k * nv].powi(2)).sum();
            self.tau[k] = if vv > 0.0 { 2.0 / vv } else { 0.0 };
            self.rdiag[k] = alpha;
            for j in k + 1..m {
                let w: f64 = (k..nv)
                    .map(|i| self.a[i + k * nv] * self.a[i + j * nv])
                    .sum();
                let f = self.tau[k] * w;
                for i in k..nv {
                    self.a[i + j * nv] -= f * self.a[i + k * nv];
                }
            }
        }
        steps
    }

    /// `x ← H_0 ⋯ H_{r−1} x` (the `Q` of the factorisation applied to `x`).
    fn apply_q(&self, r: usize, x: &mut [f64]) {
        let nv = self.nv;
        for k in (0..r).rev() {
            let w: f64 = (k..nv).map(|i| self.a[i + k * nv] * x[i]).sum();
            let f = self.tau[k] * w;
            for i in k..nv {
                x[i] -= f * self.a[i + k * nv];
            }
        }
    }

    /// The step `δ` into `out` for the damped Gauss–Newton matrix `h` (nv × nv, symmetric),
    /// gradient `g`, constraint residual `c` and Jacobian `jc` (m × nv, column-major, as
    /// nalgebra's `DMatrix` stores it). Where `N h N` is not positive definite the step is
    /// the constraints' correction alone.
    pub fn solve(&mut self, h: &[f64], g: &[f64], c: &[f64], jc: &[f64], out: &mut [f64]) {
        let nv = self.nv;
        let amax = jc.iter().fold(0.0f64, |s, x| s.max(x.abs()));
        let r = self.factor(jc, 1e-10 * (1.0 + amax));
        // δ_c = Q [y₁; 0] with R₁₁ᵀ y₁ = −(Pᵀ c)₁ (forward substitution; R's column j above
        // the diagonal is `a[i + j nv]`, i < j).
        self.y.fill(0.0);
        for i in 0..r {
            let mut s = -c[self.perm[i]];
            for k in 0..i {
                s -= self.a[k + i * nv] * self.y[k];
            }
            self.y[i] = s / self.rdiag[i];
        }
        let mut y = std::mem::take(&mut self.y);
        self.apply_q(r, &mut y);
        out.copy_from_slice(&y);
        self.y = y;
        // N: the last nv − r columns of Q.
        let k = nv - r;
        let mut n = std::mem::take(&mut self.n);
        for j in 0..k {
            let col = &mut n[j * nv..(j + 1) * nv];
            col.fill(0.0);
            col[r + j] = 1.0;
            self.apply_q(r, col);
        }
        self.n = n;
        // H N, Nᵀ H N and Nᵀ (g + H δ_c).
        for j in 0..k {
            for i in 0..nv {
                self.hn[i + j * nv] = (0..nv).map(|l| h[i + l * nv] * self.n[l + j * nv]).sum();
            }
        }
        for a in 0..k {
            for b in 0..k {
                self.nhn[a * k + b] = (0..nv)
                    .map(|i| self.n[i + a * nv] * self.hn[i + b * nv])
                    .sum();
            }
            self.gn[a] = (0..nv)
                .map(|i| {
                    let hd: f64 = (0..nv).map(|l| h[i + l * nv] * out[l]).sum();
                    self.n[i + a * nv] * (g[i] + hd)
                })
                .sum();
        }
        let solved = super::ik::cholesky_solve(
            &self.nhn[..k * k],
            &self.gn[..k],
            &mut self.chol[..k * k],
            &mut self.z[..k],
        );
        if !solved {
            return;
        }
        for (j, zj) in self.z[..k].iter().enumerate() {
            for i in 0..nv {
                out[i] += self.n[i + j * nv] * zj;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// Against the KKT conditions on a rank-deficient constraint matrix (a repeated row and
    /// a row that is a combination of two others): the constraints hold, the step is
    /// stationary in the null space, and the correction is the minimum-norm one (no
    /// component along a null direction when `h` is the identity and `g` is zero).
    #[test]
    fn step_satisfies_the_constraints_and_is_stationary() {
        let nv = 6;
        let j0 = DMatrix::from_row_slice(
            5,
            nv,
            &[
                1.0, 0.5, 0.0, -0.3, 0.2, 0.0, //
                0.0, 1.0, 2.0, 0.1, 0.0, -1.0, //
                1.0, 0.5, 0.0, -0.3, 0.2, 0.0, //
                1.0, 1.5, 2.0, -0.2, 0.2, -1.0, //
                0.3, 0.0, 0.0, 0.7, -0.4, 0.2, //
            ],
        );
        // A consistent right-hand side (c in the range of J_c).
        let c = &j0 * DVector::from_vec(vec![0.3, -0.2, 0.5, 0.1, -0.7, 0.4]);
        let b = DMatrix::from_fn(nv, nv, |i, j| ((i * 7 + j * 3) % 5) as f64 * 0.1);
        let h = &b * b.transpose() + DMatrix::identity(nv, nv);
        let g = DVector::from_vec(vec![0.2, -0.1, 0.4, 0.0, 0.3, -0.5]);
        let mut ns = NullStep::new(nv, 5);
        let mut d = vec![0.0; nv];
        ns.solve(
            h.as_slice(),
            g.as_slice(),
            c.as_slice(),
            j0.as_slice(),
            &mut d,
        );
        let d = DVector::from_vec(d);
        assert!((&j0 * &d + &c).amax() < 1e-13, "{}", (&j0 * &d + &c).amax());
        // Stationary: H δ + g is in the row space of J_c (orthogonal to its null space).
        let grad = &h * &d + &g;
        let svd = j0.clone().svd(true, true);
        let vt = svd.v_t.unwrap();
        for (k, s) in svd.singular_values.iter().enumerate() {
            if *s < 1e-10 {
                assert!(vt.row(k).dot(&grad.transpose()).abs() < 1e-13);
            }
        }
        // The minimum-norm correction alone: h = 1, g = 0 gives the pseudo-inverse's.
        let eye = DMatrix::<f64>::identity(nv, nv);
        let mut d0 = vec![0.0; nv];
        ns.solve(
            eye.as_slice(),
            &[0.0; 6],
            c.as_slice(),
            j0.as_slice(),
            &mut d0,
        );
        let want = j0.clone().pseudo_inverse(1e-12).unwrap() * -&c;
        let err = (DVector::from_vec(d0) - want).amax();
        assert!(err < 1e-13, "{err}");
    }
}
