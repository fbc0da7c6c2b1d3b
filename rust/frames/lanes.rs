//! Eight configurations side by side: a value of [`V`] holds the same quantity at eight
//! rows of a batch, and its arithmetic is lane by lane, so that the batched kinematics
//! (`frames::batch`) run the single-configuration formulas on eight rows at once. The
//! compiler turns the lane loops into vector instructions (two lanes per instruction on
//! baseline x86-64, four where `batch` dispatches to AVX2, all eight in one AVX-512
//! register); there are no fused multiply-adds, so every lane is bit for bit the scalar
//! formula. Eight rather than four so that the AVX-512 copy holds a block's quantity in one
//! register (half the instructions of four-wide AVX2 for the same rows); the AVX2 and
//! baseline copies run each operation as two or four independent halves.
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Rows processed together.
pub const LANES: usize = 8;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct V(pub [f64; LANES]);

impl V {
    pub const ZERO: V = V([0.0; LANES]);

    #[inline(always)]
    pub fn splat(x: f64) -> V {
        V([x; LANES])
    }

    #[inline(always)]
    fn zip(self, o: V, f: impl Fn(f64, f64) -> f64) -> V {
        let mut r = [0.0; LANES];
        for l in 0..LANES {
            r[l] = f(self.0[l], o.0[l]);
        }
        V(r)
    }
}

impl Add for V {
    type Output = V;
    #[inline(always)]
    fn add(self, o: V) -> V {
        self.zip(o, |a, b| a + b)
    }
}

impl Sub for V {
    type Output = V;
    #[inline(always)]
    fn sub(self, o: V) -> V {
        self.zip(o, |a, b| a - b)
    }
}

impl Mul for V {
    type Output = V;
    #[inline(always)]
    fn mul(self, o: V) -> V {
        self.zip(o, |a, b| a * b)
    }
}

impl Mul<f64> for V {
    type Output = V;
    #[inline(always)]
    fn mul(self, o: f64) -> V {
        self.zip(V::splat(o), |a, b| a * b)
    }
}

impl Div for V {
    type Output = V;
    #[inline(always)]
    fn div(self, o: V) -> V {
        self.zip(o, |a, b| a / b)
    }
}

impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        let mut r = self.0;
        for x in r.iter_mut() {
            *x = -*x;
        }
        V(r)
    }
}

/// A 3 × 3 matrix of lanes, column-major as nalgebra's (`m[i + 3 j]` is row i, column j).
pub type M3 = [V; 9];
pub type V3 = [V; 3];

/// `r v` with [`crate::support::spatial::mat_vec`]'s order of operations.
#[inline(always)]
pub fn mat_vec(r: &M3, v: &V3) -> V3 {
    let row = |i: usize| r[i] * v[0] + r[i + 3] * v[1] + r[i + 6] * v[2];
    [row(0), row(1), row(2)]
}

/// `r v` for a constant `v` (the same in every lane), in [`mat_vec`]'s order.
#[inline(always)]
pub fn mat_vec_c(r: &M3, v: &[f64; 3]) -> V3 {
    let row = |i: usize| r[i] * v[0] + r[i + 3] * v[1] + r[i + 6] * v[2];
    [row(0), row(1), row(2)]
}

/// `rᵀ v` (the coordinates of `v` in the axes `r`'s columns), as the frame Jacobians' LOCAL.
#[inline(always)]
pub fn tr_vec(r: &M3, v: &V3) -> V3 {
    let c = |j: usize| r[3 * j] * v[0] + r[3 * j + 1] * v[1] + r[3 * j + 2] * v[2];
    [c(0), c(1), c(2)]
}

/// `a × b` in nalgebra's order of operations.
#[inline(always)]
pub fn cross(a: &V3, b: &V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
pub fn add3(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub fn sub3(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub fn scale3(a: &V3, s: V) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
