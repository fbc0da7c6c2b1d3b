//! Small fixed-size algebra shared by the method: cross-product matrices, rigid placements,
//! and the 6×6 mass matrix of a rigid body about a body-fixed point, all with angular
//! components first (twist `[ω; v]`, wrench `[n; f]`), as the DeNOC matrices use them.
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

pub type Vec3 = Vector3<f64>;
pub type Mat3 = Matrix3<f64>;
pub type Vec6 = Vector6<f64>;
pub type Mat6 = Matrix6<f64>;

/// `r v` written out, summed as nalgebra's product sums it (`(r₀v₀ + r₁v₁) + r₂v₂` with
/// `rₖ` the columns: the same numbers), so that every build profile inlines it (without
/// LTO nalgebra's generic product is a call per use).
#[inline(always)]
pub fn mat_vec(r: &Mat3, v: &Vec3) -> Vec3 {
    Vec3::new(
        r[(0, 0)] * v.x + r[(0, 1)] * v.y + r[(0, 2)] * v.z,
        r[(1, 0)] * v.x + r[(1, 1)] * v.y + r[(1, 2)] * v.z,
        r[(2, 0)] * v.x + r[(2, 1)] * v.y + r[(2, 2)] * v.z,
    )
}

/// `a b` as [`mat_vec`] on each column of `b`.
#[inline(always)]
pub fn mat_mat(a: &Mat3, b: &Mat3) -> Mat3 {
    let c = |j: usize| mat_vec(a, &Vec3::new(b[(0, j)], b[(1, j)], b[(2, j)]));
    Mat3::from_columns(&[c(0), c(1), c(2)])
}

/// Cross-product matrix: `skew(a) * b == a × b`.
#[inline]
pub fn skew(a: &Vec3) -> Mat3 {
    Mat3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

#[inline]
pub fn angular(t: &Vec6) -> Vec3 {
    Vec3::new(t[0], t[1], t[2])
}
#[inline]
pub fn linear(t: &Vec6) -> Vec3 {
    Vec3::new(t[3], t[4], t[5])
}
#[inline]
pub fn stack(a: &Vec3, b: &Vec3) -> Vec6 {
    Vec6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

/// A rigid placement: a point with coordinates `x` in the child frame has coordinates
/// `rotation * x + translation` in the parent frame.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Placement {
    pub rotation: Mat3,
    pub translation: Vec3,
}

impl Placement {
    pub fn identity() -> Self {
        Placement {
            rotation: Mat3::identity(),
            translation: Vec3::zeros(),
        }
    }
    pub fn new(rotation: Mat3, translation: Vec3) -> Self {
        Placement {
            rotation,
            translation,
        }
    }
    /// `self ∘ child`: the placement of a grandchild frame given its placement in the child.
    #[inline]
    pub fn compose(&self, child: &Placement) -> Placement {
        Placement {
            rotation: self.rotation * child.rotation,
            translation: self.rotation * child.translation + self.translation,
        }
    }
    #[inline]
    pub fn act_point(&self, x: &Vec3) -> Vec3 {
        self.rotation * x + self.translation
    }
    pub fn inverse(&self) -> Placement {
        let rt = self.rotation.transpose();
        Placement {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }
}

/// Mass, first moment `h = m c` and rotational inertia `I_O`, all about a reference point O
/// (the body origin). Its 6×6 matrix is `[[I_O, h̃], [−h̃, m 1]]` = `Σ_j D_jᵀ m_j D_j`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyInertia {
    pub mass: f64,
    pub first_moment: Vec3,
    pub rotational: Mat3,
}

impl BodyInertia {
    pub fn zero() -> Self {
        BodyInertia {
            mass: 0.0,
            first_moment: Vec3::zeros(),
            rotational: Mat3::zeros(),
        }
    }

    /// Sums `m_j`, `m_j d_j` and `m_j (|d|² 1 − d dᵀ)` over point masses at `d_j` from O.
    /// Diagonal terms are summed as `m (y² + z²)`, never `|d|² − x²`, so a slender
    /// body keeps its small axial moment.
    pub fn from_points(masses: &[f64], positions: &[Vec3]) -> Self {
        let mut out = BodyInertia::zero();
        for (m, d) in masses.iter().zip(positions) {
            out.mass += m;
            out.first_moment += d * *m;
            let (x, y, z) = (d.x, d.y, d.z);
            out.rotational[(0, 0)] += m * (y * y + z * z);
            out.rotational[(1, 1)] += m * (x * x + z * z);
            out.rotational[(2, 2)] += m * (x * x + y * y);
            out.rotational[(0, 1)] -= m * x * y;
            out.rotational[(1, 2)] -= m * y * z;
            out.rotational[(0, 2)] -= m * x * z;
        }
        out.rotational[(1, 0)] = out.rotational[(0, 1)];
        out.rotational[(2, 1)] = out.rotational[(1, 2)];
        out.rotational[(2, 0)] = out.rotational[(0, 2)];
        out
    }

    /// The same body seen in a frame rotated by `r` (coordinates `x' = r x`).
    #[inline]
    pub fn rotated(&self, r: &Mat3) -> Self {
        self.rotated_inlined(r)
    }

    /// [`BodyInertia::rotated`], always inlined: in the derivatives' outward pass, out of line
    /// it cost ~145 instructions a link, a third more than its arithmetic.
    #[inline(always)]
    pub fn rotated_inlined(&self, r: &Mat3) -> Self {
        // R I Rᵀ, computing the upper triangle only (the result is symmetric).
        let ri = r * self.rotational;
        let mut rot = Mat3::zeros();
        for a in 0..3 {
            for b in a..3 {
                let x = ri[(a, 0)] * r[(b, 0)] + ri[(a, 1)] * r[(b, 1)] + ri[(a, 2)] * r[(b, 2)];
                rot[(a, b)] = x;
                rot[(b, a)] = x;
            }
        }
        BodyInertia {
            mass: self.mass,
            first_moment: r * self.first_moment,
            rotational: rot,
        }
    }

    /// The same body about the point `O' = O − s` (so positions from O' are `d + s`).
    #[inline]
    pub fn shifted(&self, s: &Vec3) -> Self {
        let h = &self.first_moment;
        let hs = h.dot(s);
        let outer = h * s.transpose() + s * h.transpose();
        let parallel =
            Mat3::identity() * (s.norm_squared() * self.mass) - s * s.transpose() * self.mass;
        BodyInertia {
            mass: self.mass,
            first_moment: h + s * self.mass,
            rotational: self.rotational + Mat3::identity() * (2.0 * hs) - outer + parallel,
        }
    }

    #[inline]
    pub fn add(&mut self, other: &BodyInertia) {
        self.mass += other.mass;
        self.first_moment += other.first_moment;
        self.rotational += other.rotational;
    }

    /// `M t` for a twist `t = [ω; v]`.
    #[inline]
    pub fn mul_twist(&self, t: &Vec6) -> Vec6 {
        let w = angular(t);
        let v = linear(t);
        let h = &self.first_moment;
        stack(
            &(self.rotational * w + h.cross(&v)),
            &(v * self.mass - h.cross(&w)),
        )
    }

    /// Velocity-product wrench `[ω × I ω; ω × (ω × h)]` of a body moving with angular
    /// velocity ω about a body-fixed reference point.
    #[inline]
    pub fn bias(&self, w: &Vec3) -> Vec6 {
        stack(
            &w.cross(&(self.rotational * w)),
            &w.cross(&w.cross(&self.first_moment)),
        )
    }

    pub fn to_matrix(&self) -> Mat6 {
        let hs = skew(&self.first_moment);
        let mut m = Mat6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.rotational);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&hs);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-hs));
        m.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Mat3::identity() * self.mass));
        m
    }
}

/// A symmetric 6×6 articulated inertia `[[P, Q], [Qᵀ, R]]` kept as 3×3 blocks, so the
/// articulated-body recursion works on 3×3 products only (every joint here moves along a
/// purely angular or a purely linear subspace).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArticulatedInertia {
    pub p: Mat3,
    pub q: Mat3,
    pub r: Mat3,
}

impl ArticulatedInertia {
    pub fn zero() -> Self {
        ArticulatedInertia {
            p: Mat3::zeros(),
            q: Mat3::zeros(),
            r: Mat3::zeros(),
        }
    }

    #[inline]
    pub fn from_body(b: &BodyInertia) -> Self {
        ArticulatedInertia {
            p: b.rotational,
            q: skew(&b.first_moment),
            r: Mat3::from_diagonal_element(b.mass),
        }
    }

    /// `M t`.
    #[inline]
    pub fn mul_twist(&self, t: &Vec6) -> Vec6 {
        let w = angular(t);
        let v = linear(t);
        stack(
            &(self.p * w + self.q * v),
            &(self.q.tr_mul(&w) + self.r * v),
        )
    }

    /// `AᵀMA` for the twist shift `A = [[1, 0], [K, 1]]`, `K = ã` (moves the reference point
    /// from O to `O + a`... seen from the parent: see `forward`), by blocks:
    /// `[[P + QK − KQᵀ − KRK, Q − KR], [Qᵀ + RK, R]]`.
    #[inline]
    pub fn shifted(&self, a: &Vec3) -> Self {
        let k = skew(a);
        let qk = self.q * k;
        let kr = k * self.r;
        ArticulatedInertia {
            p: self.p + qk + qk.transpose() - kr * k,
            q: self.q - kr,
            r: self.r,
        }
    }

    #[inline]
    pub fn add(&mut self, o: &ArticulatedInertia) {
        self.p += o.p;
        self.q += o.q;
        self.r += o.r;
    }

    pub fn to_matrix(&self) -> Mat6 {
        let mut m = Mat6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.p);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.q);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.q.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.r);
        m
    }
}

/// Moves a wrench `[n; f]` taken about O to the point `O − s`: `n' = n + s × f`.
#[inline]
pub fn shift_wrench(w: &Vec6, s: &Vec3) -> Vec6 {
    let f = linear(w);
    stack(&(angular(w) + s.cross(&f)), &f)
}

/// Twist of a body at point `O + a` given its twist at O: `v' = v + ω × a`.
#[inline]
pub fn shift_twist(t: &Vec6, a: &Vec3) -> Vec6 {
    let w = angular(t);
    stack(&w, &(linear(t) + w.cross(a)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skew_is_cross_product() {
        let a = Vec3::new(1.0, -2.0, 0.5);
        let b = Vec3::new(0.3, 4.0, -1.0);
        assert!((skew(&a) * b - a.cross(&b)).norm() < 1e-15);
    }

    #[test]
    fn inertia_shift_matches_points() {
        let masses = [1.0, 2.0, -0.5, 0.7];
        let pts = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(-0.4, 0.1, 0.0),
            Vec3::new(0.2, -0.3, 0.5),
            Vec3::new(0.0, 0.6, -0.2),
        ];
        let s = Vec3::new(0.3, -0.7, 1.1);
        let moved: Vec<Vec3> = pts.iter().map(|p| p + s).collect();
        let a = BodyInertia::from_points(&masses, &pts).shifted(&s);
        let b = BodyInertia::from_points(&masses, &moved);
        assert!((a.rotational - b.rotational).norm() < 1e-13);
        assert!((a.first_moment - b.first_moment).norm() < 1e-14);
        // The 6×6 matrix is Σ D_jᵀ m_j D_j with D_j = [−d̃_j, 1].
        let mut m6 = Mat6::zeros();
        for (m, d) in masses.iter().zip(&pts) {
            let mut dj = nalgebra::Matrix3x6::<f64>::zeros();
            dj.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(d)));
            dj.fixed_view_mut::<3, 3>(0, 3).copy_from(&Mat3::identity());
            m6 += dj.transpose() * dj * *m;
        }
        let bi = BodyInertia::from_points(&masses, &pts);
        assert!((bi.to_matrix() - m6).norm() < 1e-14);
        let t = Vec6::new(0.3, -1.0, 2.0, 0.5, 0.1, -0.4);
        assert!((bi.mul_twist(&t) - m6 * t).norm() < 1e-14);
        // Articulated blocks: same product, and the shift equals AᵀMA.
        let art = ArticulatedInertia::from_body(&bi);
        assert!((art.mul_twist(&t) - m6 * t).norm() < 1e-14);
        let a = Vec3::new(0.2, -0.5, 0.9);
        let mut shift = Mat6::identity();
        shift.fixed_view_mut::<3, 3>(3, 0).copy_from(&skew(&a));
        let expect = shift.transpose() * m6 * shift;
        assert!((art.shifted(&a).to_matrix() - expect).norm() < 1e-13);
    }
}
