//! The 3×3 and 6-vector algebra of the body-frame recursions, written out so each product
//! costs only its non-zero terms: symmetric blocks (`Sym3`), articulated inertias as three
//! 3×3 blocks (`LocalInertia`), and rotations `E` (child axes in parent axes) by type
//! (`Rot`): a general matrix, a plane rotation about a coordinate axis, the identity, and a
//! rotation placed by a constant one. The types let each pass be compiled once per joint
//! case with the known zeros left out.
use crate::support::spatial::{Mat3, Vec3, Vec6};

/// A symmetric 3×3 matrix by its upper triangle: `[xx, yy, zz, xy, xz, yz]`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sym3(pub [f64; 6]);

/// Index of entry `(i, j)` in `Sym3`.
#[inline(always)]
pub(super) const fn sidx(i: usize, j: usize) -> usize {
    if i == j {
        i
    } else {
        i + j + 2 // (0, 1) → 3, (0, 2) → 4, (1, 2) → 5
    }
}

impl Sym3 {
    #[inline(always)]
    pub(super) fn at(&self, i: usize, j: usize) -> f64 {
        self.0[sidx(i, j)]
    }
    #[inline(always)]
    pub(super) fn from_mat(m: &Mat3) -> Self {
        Sym3([
            m[(0, 0)],
            m[(1, 1)],
            m[(2, 2)],
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 2)],
        ])
    }
    #[inline(always)]
    pub(super) fn mul(&self, x: &Vec3) -> Vec3 {
        let [xx, yy, zz, xy, xz, yz] = self.0;
        Vec3::new(
            xx * x.x + xy * x.y + xz * x.z,
            xy * x.x + yy * x.y + yz * x.z,
            xz * x.x + yz * x.y + zz * x.z,
        )
    }
    /// `self − k a aᵀ`.
    #[inline(always)]
    pub(super) fn sub_outer(&mut self, a: &Vec3, k: f64) {
        let ka = a * k;
        self.0[0] -= ka.x * a.x;
        self.0[1] -= ka.y * a.y;
        self.0[2] -= ka.z * a.z;
        self.0[3] -= ka.x * a.y;
        self.0[4] -= ka.x * a.z;
        self.0[5] -= ka.y * a.z;
    }
    pub fn to_mat(self) -> Mat3 {
        let [xx, yy, zz, xy, xz, yz] = self.0;
        Mat3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
    }
}

/// Articulated inertia `[[P, Q], [Qᵀ, R]]` with the symmetric blocks stored as such.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LocalInertia {
    pub p: Sym3,
    pub q: Mat3,
    pub r: Sym3,
}

impl LocalInertia {
    /// The whole 6×6 matrix `[[P, Q], [Qᵀ, R]]`.
    pub(super) fn to_mat6(self) -> crate::support::spatial::Mat6 {
        let mut m = crate::support::spatial::Mat6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.p.to_mat());
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.q);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.q.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.r.to_mat());
        m
    }
    /// The first moment `h` (mass times COM) from the block `Q = h̃`.
    #[inline(always)]
    pub(super) fn first_moment(&self) -> Vec3 {
        Vec3::new(self.q[(2, 1)], self.q[(0, 2)], self.q[(1, 0)])
    }
}

#[inline(always)]
pub(super) fn v3(t: &Vec6, o: usize) -> Vec3 {
    Vec3::new(t[o], t[o + 1], t[o + 2])
}

#[inline(always)]
pub(super) fn six(a: &Vec3, b: &Vec3) -> Vec6 {
    Vec6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

#[inline(always)]
pub(super) fn cross(a: &Vec3, b: &Vec3) -> Vec3 {
    Vec3::new(
        a.y * b.z - a.z * b.y,
        a.z * b.x - a.x * b.z,
        a.x * b.y - a.y * b.x,
    )
}

#[inline(always)]
pub(crate) fn mul(m: &Mat3, x: &Vec3) -> Vec3 {
    Vec3::new(
        m[(0, 0)] * x.x + m[(0, 1)] * x.y + m[(0, 2)] * x.z,
        m[(1, 0)] * x.x + m[(1, 1)] * x.y + m[(1, 2)] * x.z,
        m[(2, 0)] * x.x + m[(2, 1)] * x.y + m[(2, 2)] * x.z,
    )
}

#[inline(always)]
pub(super) fn tr_mul(m: &Mat3, x: &Vec3) -> Vec3 {
    Vec3::new(
        m[(0, 0)] * x.x + m[(1, 0)] * x.y + m[(2, 0)] * x.z,
        m[(0, 1)] * x.x + m[(1, 1)] * x.y + m[(2, 1)] * x.z,
        m[(0, 2)] * x.x + m[(1, 2)] * x.y + m[(2, 2)] * x.z,
    )
}

/// `a b` for 3×3 matrices, written out.
#[inline(always)]
pub(crate) fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = Mat3::zeros();
    for j in 0..3 {
        for i in 0..3 {
            c[(i, j)] = a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)];
        }
    }
    c
}

/// A rotation `E` (child axes in parent axes) applied to vectors and 3×3 blocks.
pub(super) trait Rot: Copy {
    /// The identity (lets callers skip work at compile time).
    const IDENTITY: bool = false;
    /// `K < 3`: the joint's own turn is about coordinate axis `K` (a revolute joint there,
    /// `w_J = q̇ e_K`, no `v_J`, no `Ṡ q̇`); 3: unknown.
    const AXIS: usize = 3;
    /// `E x`.
    fn mul(&self, x: &Vec3) -> Vec3;
    /// `Eᵀ x`.
    fn tr_mul(&self, x: &Vec3) -> Vec3;
    /// `E X Eᵀ`; `SYM` when X (hence the result) is symmetric.
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3;
    /// `E X Eᵀ` for symmetric X.
    fn conj_sym(&self, x: &Sym3) -> Sym3;
    /// `R_p E` (world orientation of the child from its parent's).
    fn after(&self, rp: &Mat3) -> Mat3;
}

/// Whether `_r`'s type is the identity (a compile-time constant, for macros given a value).
#[inline(always)]
pub(super) fn is_identity<R: Rot>(_r: &R) -> bool {
    R::IDENTITY
}

#[derive(Clone, Copy)]
pub(super) struct General(pub(super) Mat3);

impl Rot for General {
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        mul(&self.0, x)
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        tr_mul(&self.0, x)
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        let e = &self.0;
        // Y = X Eᵀ: Y[r][c] = Σ_k X[r][k] E[c][k].
        let mut y = Mat3::zeros();
        for c in 0..3 {
            for r in 0..3 {
                y[(r, c)] = x[(r, 0)] * e[(c, 0)] + x[(r, 1)] * e[(c, 1)] + x[(r, 2)] * e[(c, 2)];
            }
        }
        let mut z = Mat3::zeros();
        for c in 0..3 {
            for r in 0..3 {
                if SYM && r > c {
                    continue;
                }
                let v = e[(r, 0)] * y[(0, c)] + e[(r, 1)] * y[(1, c)] + e[(r, 2)] * y[(2, c)];
                z[(r, c)] = v;
                if SYM {
                    z[(c, r)] = v;
                }
            }
        }
        z
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        let e = &self.0;
        // Y = E X (full), then the upper triangle of Y Eᵀ.
        let mut y = Mat3::zeros();
        for c in 0..3 {
            for r in 0..3 {
                y[(r, c)] =
                    e[(r, 0)] * x.at(0, c) + e[(r, 1)] * x.at(1, c) + e[(r, 2)] * x.at(2, c);
            }
        }
        let z = |r: usize, c: usize| {
            y[(r, 0)] * e[(c, 0)] + y[(r, 1)] * e[(c, 1)] + y[(r, 2)] * e[(c, 2)]
        };
        Sym3([z(0, 0), z(1, 1), z(2, 2), z(0, 1), z(0, 2), z(1, 2)])
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        mat_mul(rp, &self.0)
    }
}

/// Rotation by an angle (cosine `c`, sine `s`) about a coordinate axis, turning `e_I`
/// towards `e_J`: `E e_I = c e_I + s e_J`, `E e_J = −s e_I + c e_J` (x: I, J = 1, 2; y: 2, 0;
/// z: 0, 1).
#[derive(Clone, Copy)]
pub(super) struct Plane<const I: usize, const J: usize> {
    pub(super) c: f64,
    pub(super) s: f64,
}

impl<const I: usize, const J: usize> Plane<I, J> {
    #[inline(always)]
    pub(super) fn new((c, s): (f64, f64)) -> Self {
        Plane { c, s }
    }
}

impl<const I: usize, const J: usize> Rot for Plane<I, J> {
    const AXIS: usize = 3 - I - J;
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        let mut y = *x;
        y[I] = self.c * x[I] - self.s * x[J];
        y[J] = self.s * x[I] + self.c * x[J];
        y
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        let mut y = *x;
        y[I] = self.c * x[I] + self.s * x[J];
        y[J] = -self.s * x[I] + self.c * x[J];
        y
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        let (c, s) = (self.c, self.s);
        // Rows first: Y = E X.
        let mut y = *x;
        for col in 0..3 {
            let (a, b) = (x[(I, col)], x[(J, col)]);
            y[(I, col)] = c * a - s * b;
            y[(J, col)] = s * a + c * b;
        }
        // Then columns: Z = Y Eᵀ.
        let mut z = y;
        for row in 0..3 {
            let (a, b) = (y[(row, I)], y[(row, J)]);
            z[(row, I)] = c * a - s * b;
            z[(row, J)] = s * a + c * b;
        }
        z
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        const { assert!(I < 3 && J < 3 && I != J) };
        let k = 3 - I - J;
        let (c, s) = (self.c, self.s);
        let (a, b, d) = (x.at(I, I), x.at(I, J), x.at(J, J));
        let (cc, ss, cs) = (c * c, s * s, c * s);
        let cs2b = 2.0 * cs * b;
        let mut out = *x;
        out.0[sidx(I, I)] = cc * a - cs2b + ss * d;
        out.0[sidx(J, J)] = ss * a + cs2b + cc * d;
        out.0[sidx(I, J)] = cs * (a - d) + (cc - ss) * b;
        let (ik, jk) = (x.at(I, k), x.at(J, k));
        out.0[sidx(I, k)] = c * ik - s * jk;
        out.0[sidx(J, k)] = s * ik + c * jk;
        out
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        let mut out = *rp;
        for row in 0..3 {
            let (x, y) = (rp[(row, I)], rp[(row, J)]);
            out[(row, I)] = self.c * x + self.s * y;
            out[(row, J)] = -self.s * x + self.c * y;
        }
        out
    }
}

/// No rotation: the placement of a joint frame that is not rotated in its parent.
#[derive(Clone, Copy)]
pub(super) struct Identity;

impl Rot for Identity {
    const IDENTITY: bool = true;
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        *x
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        *x
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        *x
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        *x
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        *rp
    }
}

/// `E = P J`: the joint's rotation `J` in a joint frame placed by the constant `P`.
#[derive(Clone, Copy)]
pub(super) struct Placed<P: Rot, J: Rot>(pub(super) P, pub(super) J);

impl<P: Rot, J: Rot> Rot for Placed<P, J> {
    const IDENTITY: bool = P::IDENTITY && J::IDENTITY;
    const AXIS: usize = J::AXIS;
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        self.0.mul(&self.1.mul(x))
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        self.1.tr_mul(&self.0.tr_mul(x))
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        self.0.conj::<SYM>(&self.1.conj::<SYM>(x))
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        self.0.conj_sym(&self.1.conj_sym(x))
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        self.1.after(&self.0.after(rp))
    }
}
