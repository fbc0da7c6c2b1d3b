//! Dense LU factorisation with partial pivoting, in place and allocation-free, for the
//! implicit methods' Newton matrices (real `γ/h I − J` and complex `(α + iβ)/h I − J`).
//! Not nalgebra's `LU` (same pivot choice): it takes its matrix by value (an allocation per
//! factorisation in the Newton loop) and steps over a zero pivot where Radau must see a
//! singular matrix.
//!
//! LAPACK's `getrf` pivoting rule (first entry of largest magnitude in the column; for complex
//! entries LAPACK's `|re| + |im|`), so that the factors SciPy's `lu_factor` computes and
//! these agree up to rounding. Row-major storage.

use nalgebra::Complex;
use std::ops::{Mul, Sub};

/// A field the factorisation works in: `f64` or `Complex<f64>`.
pub(crate) trait LuScalar:
    Copy + Sub<Output = Self> + Mul<Output = Self> + std::ops::Div<Output = Self> + PartialEq
{
    const ZERO: Self;
    /// Pivot magnitude (LAPACK `idamax` / `izamax`).
    fn pivot_mag(self) -> f64;
    fn is_finite(self) -> bool;
}

impl LuScalar for f64 {
    const ZERO: Self = 0.0;
    #[inline]
    fn pivot_mag(self) -> f64 {
        self.abs()
    }
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

impl LuScalar for Complex<f64> {
    const ZERO: Self = Complex { re: 0.0, im: 0.0 };
    #[inline]
    fn pivot_mag(self) -> f64 {
        self.re.abs() + self.im.abs()
    }
    #[inline]
    fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

/// An `n × n` LU factorisation `P A = L U` held in its own buffers (allocated once).
pub(crate) struct Lu<T: LuScalar> {
    n: usize,
    /// `L` (unit diagonal, below) and `U` (on and above the diagonal), row-major.
    a: Vec<T>,
    /// Row `k` was swapped with row `piv[k] >= k` at elimination step `k`.
    piv: Vec<usize>,
    /// A factorisation is held (false before the first or after `invalidate`).
    valid: bool,
}

impl<T: LuScalar> Lu<T> {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            a: vec![T::ZERO; n * n],
            piv: vec![0; n],
            valid: false,
        }
    }

    pub(crate) fn is_valid(&self) -> bool {
        self.valid
    }

    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
    }

    /// The matrix to factorise, row-major; write it, then call [`Lu::factor`].
    pub(crate) fn matrix_mut(&mut self) -> &mut [T] {
        self.valid = false;
        &mut self.a
    }

    /// Factorise the matrix written through [`Lu::matrix_mut`] in place. Returns false (and
    /// holds no factorisation) if it is singular to working precision (an exactly zero pivot)
    /// or not finite: LAPACK would go on and its solves return inf/NaN.
    pub(crate) fn factor(&mut self) -> bool {
        let n = self.n;
        let a = &mut self.a;
        if !a.iter().all(|v| v.is_finite()) {
            self.valid = false;
            return false;
        }
        for k in 0..n {
            let mut p = k;
            let mut best = a[k * n + k].pivot_mag();
            for i in k + 1..n {
                let m = a[i * n + k].pivot_mag();
                if m > best {
                    best = m;
                    p = i;
                }
            }
            self.piv[k] = p;
            if best == 0.0 {
                self.valid = false;
                return false;
            }
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
            }
            let pivot = a[k * n + k];
            let (upper, lower) = a.split_at_mut((k + 1) * n);
            let row_k = &upper[k * n..(k + 1) * n];
            for row in lower.chunks_exact_mut(n) {
                let l = row[k] / pivot;
                row[k] = l;
                if l != T::ZERO {
                    for j in k + 1..n {
                        row[j] = row[j] - l * row_k[j];
                    }
                }
            }
        }
        self.valid = true;
        true
    }

    /// Solve `A x = b` in place (`b` becomes `x`). Requires a valid factorisation.
    pub(crate) fn solve(&self, b: &mut [T]) {
        debug_assert!(self.valid);
        let n = self.n;
        let a = &self.a;
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                b.swap(k, p);
            }
        }
        // L y = P b (unit lower triangular).
        for i in 1..n {
            let row = &a[i * n..i * n + i];
            let mut acc = b[i];
            for (j, &l) in row.iter().enumerate() {
                acc = acc - l * b[j];
            }
            b[i] = acc;
        }
        // U x = y.
        for i in (0..n).rev() {
            let row = &a[i * n..(i + 1) * n];
            let mut acc = b[i];
            for j in i + 1..n {
                acc = acc - row[j] * b[j];
            }
            b[i] = acc / row[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A x = b for a random-ish matrix needing pivots, real and complex, against the product.
    #[test]
    fn solves_match_the_matrix_product() {
        let n = 5;
        let m: Vec<f64> = (0..n * n)
            .map(|k| ((k * 7 + 3) % 11) as f64 - 5.0 + if k % 6 == 0 { 0.0 } else { 0.25 })
            .collect();
        let x: Vec<f64> = (0..n).map(|i| i as f64 - 1.5).collect();
        let b: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| m[i * n + j] * x[j]).sum())
            .collect();
        let mut lu = Lu::<f64>::new(n);
        lu.matrix_mut().copy_from_slice(&m);
        assert!(lu.factor());
        let mut s = b.clone();
        lu.solve(&mut s);
        for i in 0..n {
            assert!((s[i] - x[i]).abs() < 1e-12, "{s:?} vs {x:?}");
        }
        let mc: Vec<Complex<f64>> = m
            .iter()
            .enumerate()
            .map(|(k, &v)| Complex::new(v, (k % 3) as f64 - 1.0))
            .collect();
        let xc: Vec<Complex<f64>> = x.iter().map(|&v| Complex::new(v, -0.5 * v)).collect();
        let bc: Vec<Complex<f64>> = (0..n)
            .map(|i| (0..n).map(|j| mc[i * n + j] * xc[j]).sum())
            .collect();
        let mut luc = Lu::<Complex<f64>>::new(n);
        luc.matrix_mut().copy_from_slice(&mc);
        assert!(luc.factor());
        let mut sc = bc.clone();
        luc.solve(&mut sc);
        for i in 0..n {
            assert!((sc[i] - xc[i]).norm() < 1e-12);
        }
    }

    #[test]
    fn singular_and_non_finite_matrices_are_refused() {
        let mut lu = Lu::<f64>::new(2);
        lu.matrix_mut().copy_from_slice(&[1.0, 2.0, 2.0, 4.0]);
        assert!(!lu.factor());
        assert!(!lu.is_valid());
        lu.matrix_mut().copy_from_slice(&[1.0, f64::NAN, 2.0, 4.0]);
        assert!(!lu.factor());
    }
}
