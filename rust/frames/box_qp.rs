//! The bounded inverse-kinematics step without loop constraints: `min ½ δᵀ H δ + gᵀ δ` with
//! `lo ≤ δ ≤ hi` (`H` symmetric positive definite, `lo ≤ 0 ≤ hi`), by a primal active-set
//! method on the few speeds of a robot. Exact at its end (the KKT conditions of the box hold
//! to rounding), and much cheaper than an interior-point solve of the same program (the IK
//! step of issue 41's ≤ 1 ms target): nothing allocated after [`BoxQp::new`].

/// Buffers for programs of `n` variables.
#[derive(Debug, Clone)]
pub struct BoxQp {
    n: usize,
    /// −1 at the lower bound, +1 at the upper, 0 free.
    state: Vec<i8>,
    grad: Vec<f64>,
    dir: Vec<f64>,
    /// The free variables' indices and their Cholesky factor (row-major, `k × k`).
    free: Vec<usize>,
    chol: Vec<f64>,
    rhs: Vec<f64>,
}

impl BoxQp {
    pub fn new(n: usize) -> Self {
        BoxQp {
            n,
            state: vec![0; n],
            grad: vec![0.0; n],
            dir: vec![0.0; n],
            free: Vec::with_capacity(n),
            chol: vec![0.0; n * n],
            rhs: vec![0.0; n],
        }
    }

    /// Solves into `x` (length n; `h` row- or column-major alike, it is symmetric). Returns
    /// false when it cannot (a free block not positive definite, or no end within its
    /// iteration budget): the caller then solves the program another way.
    pub fn solve(&mut self, h: &[f64], g: &[f64], lo: &[f64], hi: &[f64], x: &mut [f64]) -> bool {
        let n = self.n;
        // A feasible start: δ = 0 (inside when lo ≤ 0 ≤ hi), else moved onto the box.
        for k in 0..n {
            x[k] = 0.0f64.clamp(lo[k].min(hi[k]), hi[k].max(lo[k]));
            self.state[k] = 0;
        }
        // True after a full step: the working set's program is solved, its multipliers
        // decide what comes next.
        let mut solved_on_set = false;
        for _ in 0..(4 * n + 20) {
            self.gradient(h, g, x);
            if solved_on_set {
                // Release the bound whose multiplier has the wrong sign the most (a lower
                // bound holds while the gradient pushes down, an upper one while it pushes up).
                let mut worst = (0.0, None);
                for k in 0..n {
                    let wrong = match self.state[k] {
                        -1 => -self.grad[k],
                        1 => self.grad[k],
                        _ => 0.0,
                    };
                    if wrong > worst.0 {
                        worst = (wrong, Some(k));
                    }
                }
                match worst.1 {
                    Some(k) => self.state[k] = 0,
                    None => return true,
                }
                solved_on_set = false;
                continue;
            }
            if !self.newton_direction(h) {
                return false;
            }
            // The longest step along the direction that stays in the box (at most 1).
            let (mut alpha, mut block) = (1.0, None);
            for k in 0..n {
                let d = self.dir[k];
                let room = if d > 0.0 {
                    hi[k] - x[k]
                } else if d < 0.0 {
                    lo[k] - x[k]
                } else {
                    continue;
                };
                let a = (room / d).max(0.0);
                if a < alpha {
                    (alpha, block) = (a, Some(k));
                }
            }
            for k in 0..n {
                x[k] += alpha * self.dir[k];
            }
            match block {
                Some(k) => {
                    let at_hi = self.dir[k] > 0.0;
                    x[k] = if at_hi { hi[k] } else { lo[k] };
                    self.state[k] = if at_hi { 1 } else { -1 };
                }
                None => solved_on_set = true,
            }
        }
        false
    }

    fn gradient(&mut self, h: &[f64], g: &[f64], x: &[f64]) {
        let n = self.n;
        for i in 0..n {
            let row = &h[i * n..(i + 1) * n];
            self.grad[i] = g[i] + row.iter().zip(x.iter()).map(|(a, b)| a * b).sum::<f64>();
        }
    }

    /// The Newton direction on the free variables (zero on the bound ones): `H_FF d = −∇_F`.
    fn newton_direction(&mut self, h: &[f64]) -> bool {
        let n = self.n;
        self.free.clear();
        self.free.extend((0..n).filter(|&k| self.state[k] == 0));
        self.dir.fill(0.0);
        let m = self.free.len();
        if m == 0 {
            return true;
        }
        // Cholesky of H_FF (lower, row-major m × m).
        for i in 0..m {
            for j in 0..=i {
                let mut s = h[self.free[i] * n + self.free[j]];
                for k in 0..j {
                    s -= self.chol[i * m + k] * self.chol[j * m + k];
                }
                if i == j {
                    if s <= 0.0 || !s.is_finite() {
                        return false;
                    }
                    self.chol[i * m + i] = s.sqrt();
                } else {
                    self.chol[i * m + j] = s / self.chol[j * m + j];
                }
            }
        }
        for i in 0..m {
            let mut s = -self.grad[self.free[i]];
            for k in 0..i {
                s -= self.chol[i * m + k] * self.rhs[k];
            }
            self.rhs[i] = s / self.chol[i * m + i];
        }
        for i in (0..m).rev() {
            let mut s = self.rhs[i];
            for k in i + 1..m {
                s -= self.chol[k * m + i] * self.rhs[k];
            }
            self.rhs[i] = s / self.chol[i * m + i];
        }
        for i in 0..m {
            self.dir[self.free[i]] = self.rhs[i];
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::BoxQp;

    /// Random strictly convex programs: the result meets the KKT conditions of the box, which
    /// determine the unique optimum.
    #[test]
    fn meets_the_box_kkt_conditions() {
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for n in 1..=6 {
            for _ in 0..50 {
                let a: Vec<f64> = (0..n * n).map(|_| rnd()).collect();
                let mut h = vec![0.0; n * n];
                for i in 0..n {
                    for j in 0..n {
                        h[i * n + j] = (0..n).map(|k| a[k * n + i] * a[k * n + j]).sum::<f64>();
                    }
                    h[i * n + i] += 1e-3;
                }
                let g: Vec<f64> = (0..n).map(|_| 3.0 * rnd()).collect();
                let lo: Vec<f64> = (0..n).map(|_| -rnd().abs()).collect();
                let hi: Vec<f64> = (0..n).map(|_| rnd().abs()).collect();
                let mut x = vec![0.0; n];
                assert!(BoxQp::new(n).solve(&h, &g, &lo, &hi, &mut x));
                // KKT: inside the box; the gradient zero on free variables, pushing outwards
                // on bound ones.
                for k in 0..n {
                    assert!(x[k] >= lo[k] - 1e-14 && x[k] <= hi[k] + 1e-14);
                    let gk = g[k] + (0..n).map(|j| h[k * n + j] * x[j]).sum::<f64>();
                    let tol = 1e-9 * (1.0 + g.iter().fold(0.0f64, |m, v| m.max(v.abs())));
                    if x[k] == lo[k] {
                        assert!(gk >= -tol, "n {n}: lower bound with gradient {gk}");
                    } else if x[k] == hi[k] {
                        assert!(gk <= tol, "n {n}: upper bound with gradient {gk}");
                    } else {
                        assert!(gk.abs() <= tol, "n {n}: free with gradient {gk}");
                    }
                }
            }
        }
    }
}
