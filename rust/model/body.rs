//! Rigid bodies: mass, centre of mass and inertia about the COM, validated once.
//!
//! Convention: standard (URDF, Pinocchio, MuJoCo) — `I_xx = Σ m (y² + z²)`,
//! `I_xy = −Σ m x y`. The paper writes products of inertia with the opposite sign; that is
//! converted at the boundary, never here.
use crate::model::point_masses::EquimomentalSet;
use crate::support::error::{check_finite, check_result, Error, Result};
use crate::support::spatial::{BodyInertia, Mat3, Vec3};

/// Relative tolerance for symmetry, definiteness and the triangle inequality, scaled by the
/// trace of the tensor: rounding in a user's numbers must not make a valid body invalid.
pub const INERTIA_RTOL: f64 = 1e-9;

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RigidBody {
    pub mass: f64,
    pub com: Vec3,
    /// Inertia about the COM, body frame, exactly symmetric.
    pub inertia: Mat3,
}

fn overflow(mass: f64, com: &Vec3, inertia: &Mat3) -> Error {
    Error::inertia(
        "inertia",
        format!(
            "the body's derived quantities (principal moments, seven point masses, inertia about the body origin) overflow double precision (mass {mass:e}, largest inertia entry {:e}, centre of mass at distance {:e}); use smaller units",
            inertia.abs().max(),
            com.norm()
        ),
    )
}

impl RigidBody {
    /// How Python shows it: `RigidBody(mass=m, com=[x, y, z], inertia=[[..], [..], [..]])`.
    pub fn repr(&self) -> String {
        let i = &self.inertia;
        let row = |r: usize| format!("[{}, {}, {}]", i[(r, 0)], i[(r, 1)], i[(r, 2)]);
        let c = &self.com;
        let (m, i0, i1, i2) = (self.mass, row(0), row(1), row(2));
        format!(
            "RigidBody(mass={m}, com=[{}, {}, {}], inertia=[{i0}, {i1}, {i2}])",
            c.x, c.y, c.z
        )
    }

    /// Validates and builds a body. Rules, each with its own message: finite numbers,
    /// mass > 0, symmetric tensor, positive semidefinite, triangle inequality of the
    /// principal moments (each ≤ the sum of the other two).
    pub fn new(mass: f64, com: Vec3, inertia: Mat3) -> Result<Self> {
        Self::new_with_scale(mass, com, inertia, 0.0)
    }

    /// As `new`, with the tolerances scaled by `max(|I|, scale)`: for a tensor computed from
    /// quantities of size `scale` (e.g. point masses far from the COM) whose rounding is
    /// larger than the tensor's own size.
    pub fn new_with_scale(mass: f64, com: Vec3, inertia: Mat3, scale: f64) -> Result<Self> {
        if !mass.is_finite() || mass <= 0.0 {
            return Err(Error::inertia(
                "mass",
                format!("expected a finite number > 0, got {mass}"),
            ));
        }
        check_finite("com", com.as_slice())?;
        check_finite("inertia", inertia.as_slice())?;
        let scale = inertia.iter().fold(scale, |a, x| a.max(x.abs()));
        let tol = INERTIA_RTOL * scale;
        let asym = (inertia - inertia.transpose()).abs().max();
        if asym > tol {
            return Err(Error::inertia(
                "inertia",
                format!("expected a symmetric 3x3 tensor, got entries differing from their transposes by up to {asym:.3e}"),
            ));
        }
        // Halves first: the sum of two entries near f64::MAX would overflow.
        let sym = inertia * 0.5 + inertia.transpose() * 0.5;
        let eig = sym.symmetric_eigenvalues();
        let (lo, hi) = (eig.min(), eig.max());
        let trace = eig.sum();
        if !(eig.iter().all(|x| x.is_finite()) && trace.is_finite()) {
            return Err(overflow(mass, &com, &inertia));
        }
        if lo < -tol {
            return Err(Error::inertia(
                "inertia",
                format!("expected a positive semidefinite tensor, got principal moments {:.6e}, {:.6e}, {:.6e}", eig[0], eig[1], eig[2]),
            ));
        }
        if hi > 0.5 * trace + tol {
            return Err(Error::inertia(
                "inertia",
                format!(
                    "principal moments {:.6e}, {:.6e}, {:.6e} violate the triangle inequality (the largest must not exceed the sum of the other two): no rigid body has this inertia",
                    eig[0], eig[1], eig[2]
                ),
            ));
        }
        let body = RigidBody {
            mass,
            com,
            inertia: sym,
        };
        body.check_derived()?;
        Ok(body)
    }

    /// Refuses a body whose derived quantities overflow double precision although its own
    /// numbers are finite: second moments, the seven point masses about the COM and about
    /// the body origin, the inertia about the body origin (where a joint attaches it).
    fn check_derived(&self) -> Result<()> {
        let origin = Vec3::zeros();
        let finite = |m: &Mat3| m.iter().all(|x| x.is_finite());
        let set_ok = |c: &Vec3| {
            let p = EquimomentalSet::solve(self, c);
            p.masses.iter().all(|x| x.is_finite())
                && p.half_sides.iter().all(|x| x.is_finite())
                && p.positions.iter().all(|x| x.iter().all(|y| y.is_finite()))
        };
        let about = self.inertia_at(&origin);
        if finite(&self.second_moments_about_com())
            && finite(&about.rotational)
            && about.first_moment.iter().all(|x| x.is_finite())
            && set_ok(&self.com)
            && set_ok(&origin)
        {
            Ok(())
        } else {
            Err(overflow(self.mass, &self.com, &self.inertia))
        }
    }

    /// Mass, COM and inertia about the COM of a set of point masses (some may be negative,
    /// as in an equimomental set), validated like any body.
    pub fn from_point_masses(masses: &[f64], positions: &[Vec3]) -> Result<Self> {
        if masses.len() != positions.len() || masses.is_empty() {
            return Err(Error::arg(
                "positions",
                format!("one 3-vector per mass ({} masses)", masses.len()),
                format!("{} positions", positions.len()),
            ));
        }
        check_finite("masses", masses)?;
        for p in positions {
            check_finite("positions", p.as_slice())?;
        }
        let mass: f64 = masses.iter().sum();
        if !(mass > 0.0) {
            return Err(Error::inertia(
                "masses",
                format!("expected a positive total mass, got {mass}"),
            ));
        }
        let com = positions
            .iter()
            .zip(masses)
            .fold(Vec3::zeros(), |acc, (p, m)| acc + p * *m)
            / mass;
        let rel: Vec<Vec3> = positions.iter().map(|p| p - com).collect();
        let about_com = BodyInertia::from_points(masses, &rel);
        // Rounding in the masses is relative to Σ|m| (an equimomental set may put rounding-size
        // masses on far vertices), so the sums' noise scales with Σ|m|·max|d|², not with the
        // (possibly zero) result.
        let sum_abs: f64 = masses.iter().map(|m| m.abs()).sum();
        let reach = rel.iter().fold(0.0f64, |a, d| a.max(d.norm_squared()));
        let scale = sum_abs * reach;
        RigidBody::new_with_scale(mass, com, about_com.rotational, 1e-5 * scale)
    }

    /// Inertia about `point` (body frame), by the parallel-axis theorem.
    pub fn inertia_about(&self, point: &Vec3) -> Mat3 {
        let r = self.com - point;
        self.inertia + (Mat3::identity() * r.norm_squared() - r * r.transpose()) * self.mass
    }

    /// [`inertia_about`](Self::inertia_about) a caller's point: the point checked finite, the
    /// result too (a point far enough away overflows it).
    pub fn inertia_about_checked(&self, point: &Vec3) -> Result<Mat3> {
        check_finite("point", point.as_slice())?;
        let i = self.inertia_about(point);
        check_result("inertia_about", i.as_slice())?;
        Ok(i)
    }

    /// Second moments about the COM, `J = Σ m d dᵀ`, without cancellation: each diagonal
    /// term `J_kk = ½(I_ii + I_jj − I_kk)` differences the two nearest moments first, so a
    /// slender rod (`I_yy ≈ I_zz ≫ I_xx`) keeps its small moments.
    pub fn second_moments_about_com(&self) -> Mat3 {
        let i = &self.inertia;
        let d = [i[(0, 0)], i[(1, 1)], i[(2, 2)]];
        let mut j = -*i;
        for k in 0..3 {
            let (a, b) = (d[(k + 1) % 3], d[(k + 2) % 3]);
            // Subtract I_kk from whichever of the two is nearer to it.
            let (near, far) = if (a - d[k]).abs() <= (b - d[k]).abs() {
                (a, b)
            } else {
                (b, a)
            };
            j[(k, k)] = (0.5 * ((near - d[k]) + far)).max(0.0);
        }
        j
    }

    /// Body inertia (mass, first moment, rotational inertia) about `point`, body frame.
    pub fn inertia_at(&self, point: &Vec3) -> BodyInertia {
        BodyInertia {
            mass: self.mass,
            first_moment: (self.com - point) * self.mass,
            rotational: self.inertia_about(point),
        }
    }

    /// The body seen from another frame: `x_parent = r x + t`.
    pub fn transformed(&self, r: &Mat3, t: &Vec3) -> RigidBody {
        RigidBody {
            mass: self.mass,
            com: r * self.com + t,
            inertia: r * self.inertia * r.transpose(),
        }
    }

    /// Two bodies welded together, in the same frame.
    pub fn merged(&self, other: &RigidBody) -> RigidBody {
        let mass = self.mass + other.mass;
        let com = (self.com * self.mass + other.com * other.mass) / mass;
        let inertia = self.inertia_about(&com) + other.inertia_about(&com);
        RigidBody {
            mass,
            com,
            inertia: (inertia + inertia.transpose()) * 0.5,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rod() -> RigidBody {
        let (m, a, d) = (2.51, 1.0, 0.02);
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
    fn each_rule_has_its_error() {
        let i = Mat3::identity();
        let c = Vec3::zeros();
        assert!(
            matches!(RigidBody::new(0.0, c, i), Err(Error::InvalidInertia { ref arg, .. }) if arg == "mass")
        );
        assert!(RigidBody::new(f64::NAN, c, i).is_err());
        assert!(
            matches!(RigidBody::new(1.0, Vec3::new(f64::INFINITY, 0.0, 0.0), i), Err(Error::InvalidArgument { ref arg, .. }) if arg == "com")
        );
        let mut asym = i;
        asym[(0, 1)] = 0.1;
        let e = RigidBody::new(1.0, c, asym).unwrap_err().to_string();
        assert!(e.contains("symmetric"), "{e}");
        let e = RigidBody::new(1.0, c, -i).unwrap_err().to_string();
        assert!(e.contains("semidefinite"), "{e}");
        let e = RigidBody::new(1.0, c, Mat3::from_diagonal(&Vec3::new(1.0, 1.0, 3.0)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("triangle"), "{e}");
        // Exactly on the boundary (a flat plate) is valid.
        assert!(RigidBody::new(1.0, c, Mat3::from_diagonal(&Vec3::new(1.0, 2.0, 3.0))).is_ok());
    }

    #[test]
    fn slender_rod_second_moments_keep_small_terms() {
        let (m, a, d) = (1.0, 1.0, 1e-7);
        let b = RigidBody::new(
            m,
            Vec3::zeros(),
            Mat3::from_diagonal(&Vec3::new(
                m * d * d / 8.0,
                m * d * d / 16.0 + m * a * a / 12.0,
                m * d * d / 16.0 + m * a * a / 12.0,
            )),
        )
        .unwrap();
        let j = b.second_moments_about_com();
        let exact = m * d * d / 16.0;
        // The naive ½ tr(I) − I_yy loses this completely at d/a = 1e-7.
        assert!(
            (j[(1, 1)] - exact).abs() < 1e-6 * exact,
            "{} vs {}",
            j[(1, 1)],
            exact
        );
        assert!((j[(0, 0)] - m * a * a / 12.0).abs() < 1e-15);
    }

    #[test]
    fn merge_and_about_point() {
        let r = rod();
        let io = r.inertia_about(&Vec3::zeros());
        let expect = r.mass / 3.0 + r.mass * 0.02 * 0.02 / 16.0;
        assert!((io[(1, 1)] - expect).abs() < 1e-14);
        let both = r.merged(&r);
        assert!((both.mass - 2.0 * r.mass).abs() < 1e-15);
        assert!((both.inertia - r.inertia * 2.0).norm() < 1e-14);
    }
}
