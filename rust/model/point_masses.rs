//! The equimomental set of seven point masses of a rigid body (paper, Sections II and V).
//!
//! Seven masses at seven vertices of a box of half-sides `h`, centred at a chosen point `p`,
//! edges along the body axes. Written with the right-hand sides divided by `h` (docs/method.md
//! §1.1, paper eqs 1–7) the 7×7 system is a ±1 sign matrix: the first seven rows and columns of
//! the 8×8 Hadamard matrix of the box's vertices. Its solution is closed-form — `H Hᵀ = 8 I`,
//! and the missing eighth equation is chosen so the unused vertex (−,−,−) gets zero mass — with
//! entries 0 and ±1/4 and condition number 2.83, whatever the body's shape. The paper's
//! h-scaled form has condition number ~(h_max/h_min)² and is never used.
use crate::model::body::RigidBody;
use crate::support::error::{check_finite, check_result, Result};
use crate::support::spatial::Vec3;

/// Vertex signs (paper Table I); the eighth vertex (−,−,−) is not used.
pub const SIGNS: [[f64; 3]; 7] = [
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, 1.0, 1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
];

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EquimomentalSet {
    pub masses: [f64; 7],
    /// Positions in the body frame.
    pub positions: [Vec3; 7],
    pub half_sides: Vec3,
    pub center: Vec3,
}

/// The eight moment functions of a vertex: 1, sx, sy, sz, sx·sy, sy·sz, sx·sz, sx·sy·sz.
#[inline]
fn moment_row(s: &[f64; 3]) -> [f64; 8] {
    let [x, y, z] = *s;
    [1.0, x, y, z, x * y, y * z, x * z, x * y * z]
}

/// `num / den`, bounded by `limit` in magnitude. Mathematically `|num| ≤ limit·den` (a first
/// moment is bounded by the second moment, a product by Cauchy–Schwarz); a zero half-side
/// (rod without axial inertia, flat plate, point mass) has `num = den = 0` and contributes 0.
#[inline]
fn bounded_ratio(num: f64, den: f64, limit: f64) -> f64 {
    if den > 0.0 {
        (num / den).clamp(-limit, limit)
    } else {
        0.0
    }
}

impl EquimomentalSet {
    /// The set of `body` around a caller's `center` (default: the COM): the centre checked
    /// finite, the result too (a centre far enough away overflows the second moments).
    pub fn around(body: &RigidBody, center: Option<Vec3>) -> Result<Self> {
        if let Some(c) = &center {
            check_finite("center", c.as_slice())?;
        }
        let set = Self::solve(body, &center.unwrap_or(body.com));
        check_result("point_masses", &set.masses)?;
        check_result("point_masses", set.half_sides.as_slice())?;
        Ok(set)
    }

    /// Solves for the seven masses with the box centred at `center` (body frame).
    pub fn solve(body: &RigidBody, center: &Vec3) -> Self {
        let m = body.mass;
        let r = body.com - center;
        // Shift second moments, not inertias, to the centre: J_p = J_c + m r rᵀ.
        let mut j = body.second_moments_about_com() + r * r.transpose() * m;
        // Rounding can leave |J_ik| just above sqrt(J_ii J_kk) for a degenerate body (a rod or
        // plate turned off the axes, a point mass with noise in its products). Make the pair
        // consistent by the smaller of two changes: raise the smaller diagonal to J_ik²/J_large,
        // or shrink |J_ik| to sqrt(J_ii J_kk). Clamping the ratio below instead would cost √eps.
        for (i, k) in [(0, 1), (1, 2), (0, 2)] {
            let off = j[(i, k)];
            let bound = (j[(i, i)] * j[(k, k)]).max(0.0).sqrt();
            if off.abs() > bound {
                let (small, large) = if j[(i, i)] <= j[(k, k)] {
                    (i, k)
                } else {
                    (k, i)
                };
                let raise = if j[(large, large)] > 0.0 {
                    off * off / j[(large, large)] - j[(small, small)]
                } else {
                    f64::INFINITY
                };
                if raise <= off.abs() - bound {
                    j[(small, small)] += raise;
                } else {
                    j[(i, k)] = bound.copysign(off);
                    j[(k, i)] = j[(i, k)];
                }
            }
        }
        let h = Vec3::new(
            (j[(0, 0)].max(0.0) / m).sqrt(),
            (j[(1, 1)].max(0.0) / m).sqrt(),
            (j[(2, 2)].max(0.0) / m).sqrt(),
        );
        let rhs = [
            m,
            bounded_ratio(m * r.x, h.x, m),
            bounded_ratio(m * r.y, h.y, m),
            bounded_ratio(m * r.z, h.z, m),
            bounded_ratio(j[(0, 1)], h.x * h.y, m),
            bounded_ratio(j[(1, 2)], h.y * h.z, m),
            bounded_ratio(j[(0, 2)], h.x * h.z, m),
        ];
        // Eighth equation's right-hand side, chosen so the (−,−,−) vertex has zero mass.
        let unused = moment_row(&[-1.0, -1.0, -1.0]);
        let t: f64 = (0..7).map(|k| unused[k] * rhs[k]).sum();
        let mut masses = [0.0; 7];
        let mut positions = [Vec3::zeros(); 7];
        for (j, s) in SIGNS.iter().enumerate() {
            let row = moment_row(s);
            let dot: f64 = (0..7).map(|k| row[k] * rhs[k]).sum();
            masses[j] = 0.125 * (dot + row[7] * t);
            positions[j] = center + Vec3::new(s[0] * h.x, s[1] * h.y, s[2] * h.z);
        }
        EquimomentalSet {
            masses,
            positions,
            half_sides: h,
            center: *center,
        }
    }

    /// The rigid body these points represent (mass, COM and inertia rebuilt from them).
    pub fn body(&self) -> Result<RigidBody> {
        RigidBody::from_point_masses(&self.masses, &self.positions)
    }

    /// `PointMasses(masses=[...], half_sides=[...])`, as Python shows the set.
    pub fn repr(&self) -> String {
        let h = self.half_sides.as_slice();
        format!("PointMasses(masses={:?}, half_sides={h:?})", self.masses)
    }

    /// The 7×7 sign matrix of the system (rows: Σm, Σm·sx, Σm·sy, Σm·sz, Σm·sx·sy,
    /// Σm·sy·sz, Σm·sx·sz; columns: the seven vertices).
    pub fn sign_matrix() -> [[f64; 7]; 7] {
        let mut a = [[0.0; 7]; 7];
        for (j, s) in SIGNS.iter().enumerate() {
            let row = moment_row(s);
            for k in 0..7 {
                a[k][j] = row[k];
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::support::spatial::Mat3;
    use proptest::prelude::*;

    fn rod(a: f64, d: f64) -> RigidBody {
        let m = 2.51;
        RigidBody::new(
            m,
            Vec3::new(a / 2.0, 0.0, 0.0),
            Mat3::from_diagonal(&Vec3::new(
                m * d * d / 8.0,
                m * d * d / 16.0 + m * a * a / 12.0,
                m * d * d / 16.0 + m * a * a / 12.0,
            )),
        )
        .unwrap()
    }

    #[test]
    fn paper_values_far_end() {
        let set = EquimomentalSet::solve(&rod(1.0, 0.02), &Vec3::new(1.0, 0.0, 0.0));
        let printed = [0.628, -0.543, 1.17, 0.0, 1.17, -0.543, 0.628];
        for (m, p) in set.masses.iter().zip(printed) {
            assert!((m - p).abs() <= 0.0015, "{m} vs printed {p}");
        }
        let m = 2.51;
        let exact = [m / 4.0, -m * 3f64.sqrt() / 8.0];
        assert!((set.masses[0] - exact[0]).abs() < 1e-15);
        assert!((set.masses[1] - exact[1]).abs() < 1e-15);
        assert!((set.half_sides - Vec3::new(1.0 / 3f64.sqrt(), 0.005, 0.005)).norm() < 1e-15);
    }

    #[test]
    fn com_centred_rod_is_a_tetrahedron() {
        let b = rod(1.0, 0.02);
        let set = EquimomentalSet::solve(&b, &b.com);
        let q = b.mass / 4.0;
        let expect = [q, 0.0, q, 0.0, q, 0.0, q];
        for (m, e) in set.masses.iter().zip(expect) {
            assert!((m - e).abs() < 1e-15, "{:?}", set.masses);
        }
    }

    #[test]
    fn inconsistent_rounding_is_corrected_by_the_smaller_change() {
        // A flat body (second moments ~1e-30 along x and z) whose product J_xz = 1e-10 is
        // inconsistent within the validation tolerance: the fix must not invent a huge moment
        // (J_small raised to J_xz²/J_large) but shrink the product instead.
        let i = Mat3::new(1.0, 0.0, -1e-10, 0.0, 2e-30, 0.0, -1e-10, 0.0, 1.0);
        let b = RigidBody::new(1.0, Vec3::new(0.1, 0.0, 0.0), i).unwrap();
        let set = EquimomentalSet::solve(&b, &b.com);
        assert!(set.half_sides.norm() < 2.0, "{}", set.half_sides);
        let back = RigidBody::from_point_masses(&set.masses, &set.positions).unwrap();
        assert!((back.inertia - b.inertia).norm() < 1e-9, "{}", back.inertia);
    }

    #[test]
    fn sign_matrix_inverse_is_quarter_entries() {
        // Columns of the closed form: solve with unit right-hand sides.
        let a = EquimomentalSet::sign_matrix();
        let unused = moment_row(&[-1.0, -1.0, -1.0]);
        for e in 0..7 {
            let mut rhs = [0.0; 7];
            rhs[e] = 1.0;
            let t: f64 = (0..7).map(|k| unused[k] * rhs[k]).sum();
            let x: Vec<f64> = SIGNS
                .iter()
                .map(|s| {
                    let row = moment_row(s);
                    0.125 * ((0..7).map(|k| row[k] * rhs[k]).sum::<f64>() + row[7] * t)
                })
                .collect();
            for xi in &x {
                assert!([0.0, 0.25, -0.25].contains(xi), "{x:?}");
            }
            for k in 0..7 {
                let ax: f64 = (0..7).map(|j| a[k][j] * x[j]).sum();
                assert_eq!(ax, if k == e { 1.0 } else { 0.0 });
            }
        }
    }

    #[test]
    fn degenerate_bodies_have_finite_sets() {
        let c = Vec3::new(0.1, -0.2, 0.3);
        let bodies = [
            // Rod with zero axial inertia, a flat plate, a point mass.
            RigidBody::new(1.0, c, Mat3::from_diagonal(&Vec3::new(0.0, 1.0, 1.0))).unwrap(),
            RigidBody::new(1.0, c, Mat3::from_diagonal(&Vec3::new(1.0, 2.0, 3.0))).unwrap(),
            RigidBody::new(1.0, c, Mat3::zeros()).unwrap(),
        ];
        for b in bodies {
            for center in [b.com, Vec3::new(1.0, 2.0, -1.0)] {
                let set = EquimomentalSet::solve(&b, &center);
                assert!(set.masses.iter().all(|m| m.is_finite()));
                let back = RigidBody::from_point_masses(&set.masses, &set.positions).unwrap();
                assert!((back.mass - b.mass).abs() < 1e-14);
                assert!((back.com - b.com).norm() < 1e-14);
                assert!(
                    (back.inertia - b.inertia).norm() < 1e-13,
                    "{} vs {}",
                    back.inertia,
                    b.inertia
                );
            }
        }
    }

    fn random_body() -> impl Strategy<Value = (RigidBody, Vec3)> {
        (
            0.01f64..100.0,
            prop::array::uniform3(-2.0f64..2.0),
            prop::array::uniform3(0.01f64..1.0),
            prop::array::uniform3(-3.2f64..3.2),
            prop::array::uniform3(-3.0f64..3.0),
        )
            .prop_map(|(m, c, ext, ang, center)| {
                // Physical principal moments from a box of random extents, rotated.
                let (a, b, cc) = (ext[0] * ext[0], ext[1] * ext[1], ext[2] * ext[2]);
                let d = Vec3::new(b + cc, a + cc, a + b) * (m / 3.0);
                let r = nalgebra::Rotation3::from_euler_angles(ang[0], ang[1], ang[2]);
                let i = r.matrix() * Mat3::from_diagonal(&d) * r.matrix().transpose();
                let body = RigidBody::new(m, Vec3::from(c), i).unwrap();
                (body, Vec3::from(center))
            })
    }

    proptest! {
        #[test]
        fn round_trip_any_center((body, center) in random_body()) {
            let set = EquimomentalSet::solve(&body, &center);
            let back = RigidBody::from_point_masses(&set.masses, &set.positions).unwrap();
            let scale = body.inertia.norm() + body.mass * (body.com - center).norm_squared();
            prop_assert!((back.mass - body.mass).abs() <= 1e-14 * body.mass);
            prop_assert!((back.com - body.com).norm() <= 1e-14 * (1.0 + body.com.norm() + (body.com - center).norm()));
            prop_assert!((back.inertia - body.inertia).norm() <= 1e-13 * scale,
                "{} vs {}", back.inertia, body.inertia);
        }
    }
}
