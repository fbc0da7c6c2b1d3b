//! A link's material as cubic cells inside an envelope (body frame): a box, a planar polygon
//! extruded along z, or a closed triangle mesh. Each cell is a small solid cube whose mass
//! the design chooses; its mass, first and second moments are linear in that mass
//! ([`cube_moments`]), so a designed link's inertia is linear in the cell masses.
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec3;

/// The most cells one envelope may hold (a guard against a cell size in the wrong unit).
pub const MAX_CELLS: usize = 2_000_000;

/// The region a link's material may occupy, in the body frame.
#[derive(Debug, Clone)]
pub enum Envelope {
    /// An axis-aligned box between two corners.
    Box { lower: Vec3, upper: Vec3 },
    /// A simple polygon in the x–y plane (vertices in order), extruded from `z.0` to `z.1`.
    Prism {
        polygon: Vec<[f64; 2]>,
        z: (f64, f64),
    },
    /// A closed, consistently oriented triangle mesh.
    Mesh { triangles: Vec<[Vec3; 3]> },
}

impl Envelope {
    /// The smallest axis-aligned box holding the envelope.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Envelope::Box { lower, upper } => (*lower, *upper),
            Envelope::Prism { polygon, z } => {
                let (mut lo, mut hi) = (
                    Vec3::new(f64::MAX, f64::MAX, z.0),
                    Vec3::new(f64::MIN, f64::MIN, z.1),
                );
                for p in polygon {
                    lo.x = lo.x.min(p[0]);
                    lo.y = lo.y.min(p[1]);
                    hi.x = hi.x.max(p[0]);
                    hi.y = hi.y.max(p[1]);
                }
                (lo, hi)
            }
            Envelope::Mesh { triangles } => {
                let mut lo = Vec3::repeat(f64::MAX);
                let mut hi = Vec3::repeat(f64::MIN);
                for t in triangles {
                    for p in t {
                        lo = lo.inf(p);
                        hi = hi.sup(p);
                    }
                }
                (lo, hi)
            }
        }
    }

    /// Whether `p` lies inside (the boundary counts as inside to round-off).
    pub fn contains(&self, p: &Vec3) -> bool {
        let (lo, hi) = self.bounds();
        let slack = 1e-9 * (hi - lo).amax().max(1e-300);
        if (0..3).any(|k| p[k] < lo[k] - slack || p[k] > hi[k] + slack) {
            return false;
        }
        match self {
            Envelope::Box { .. } => true,
            Envelope::Prism { polygon, .. } => in_polygon(polygon, p.x, p.y, slack),
            Envelope::Mesh { triangles } => in_mesh(triangles, p),
        }
    }

    /// Checks the envelope's own form: finite numbers, a box of positive size, a polygon of
    /// at least three vertices, a mesh of at least four triangles.
    pub fn check(&self) -> Result<()> {
        let (lo, hi) = self.bounds();
        crate::support::error::check_finite("envelope", lo.as_slice())?;
        crate::support::error::check_finite("envelope", hi.as_slice())?;
        match self {
            Envelope::Prism { polygon, .. } if polygon.len() < 3 => {
                return Err(Error::arg(
                    "polygon",
                    "at least three (x, y) vertices",
                    format!("{} vertices", polygon.len()),
                ))
            }
            Envelope::Mesh { triangles } if triangles.len() < 4 => {
                return Err(Error::arg(
                    "mesh",
                    "a closed triangle mesh (at least four triangles)",
                    format!("{} triangles", triangles.len()),
                ))
            }
            _ => {}
        }
        if (0..3).any(|k| hi[k] <= lo[k]) {
            return Err(Error::arg(
                "envelope",
                "a region of positive size along x, y and z",
                format!("from {:?} to {:?}", lo.as_slice(), hi.as_slice()),
            ));
        }
        Ok(())
    }
}

/// Even–odd rule, with points on an edge (within `slack`) inside.
fn in_polygon(poly: &[[f64; 2]], x: f64, y: f64, slack: f64) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        // On the edge: distance to the segment within slack.
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 {
            (((x - a[0]) * dx + (y - a[1]) * dy) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (ex, ey) = (a[0] + t * dx - x, a[1] + t * dy - y);
        if ex * ex + ey * ey <= slack * slack {
            return true;
        }
        if (a[1] > y) != (b[1] > y) {
            let cross = a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if x < cross {
                inside = !inside;
            }
        }
    }
    inside
}

/// Parity of a ray's crossings with the mesh (Möller–Trumbore), along a direction no
/// axis-aligned face or edge of a voxel grid shares.
fn in_mesh(triangles: &[[Vec3; 3]], p: &Vec3) -> bool {
    let dir = Vec3::new(0.577_215_664_9, std::f64::consts::LOG10_2, 0.758_863_542_1).normalize();
    let mut crossings = 0usize;
    for t in triangles {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let h = dir.cross(&e2);
        let det = e1.dot(&h);
        if det.abs() < 1e-300 {
            continue;
        }
        let s = p - t[0];
        let u = s.dot(&h) / det;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let qv = s.cross(&e1);
        let w = dir.dot(&qv) / det;
        if w < 0.0 || u + w > 1.0 {
            continue;
        }
        if e2.dot(&qv) / det > 0.0 {
            crossings += 1;
        }
    }
    crossings % 2 == 1
}

/// Centres of the cubes of side `side` on a grid centred in the envelope's bounding box
/// whose centre and eight corners all lie inside the envelope (so each cube is inside a
/// convex envelope, and inside any other to the grid's resolution).
pub fn fill(envelope: &Envelope, side: f64) -> Result<Vec<Vec3>> {
    envelope.check()?;
    if !(side.is_finite() && side > 0.0) {
        return Err(Error::arg(
            "cell",
            "a positive finite cell side",
            format!("{side}"),
        ));
    }
    let (lo, hi) = envelope.bounds();
    let span = hi - lo;
    let counts: Vec<usize> = (0..3)
        .map(|k| ((span[k] / side) * (1.0 + 1e-12)).floor().max(0.0) as usize)
        .collect();
    let total = counts.iter().map(|&c| c as u128).product::<u128>();
    if total > MAX_CELLS as u128 {
        return Err(Error::arg(
            "cell",
            format!("a side giving at most {MAX_CELLS} cells in the envelope"),
            format!("{side} ({total} cells in a box of {:?})", span.as_slice()),
        ));
    }
    if counts.contains(&0) {
        return Err(Error::arg(
            "cell",
            "a side no larger than the envelope (at least one cell along x, y and z)",
            format!("{side} for an envelope of {:?}", span.as_slice()),
        ));
    }
    let offset = Vec3::new(
        lo.x + 0.5 * (span.x - counts[0] as f64 * side),
        lo.y + 0.5 * (span.y - counts[1] as f64 * side),
        lo.z + 0.5 * (span.z - counts[2] as f64 * side),
    );
    let mut out = Vec::new();
    // Corners a hair inside, so that a face of the envelope through them counts as inside.
    let h = 0.5 * side * (1.0 - 1e-9);
    for k in 0..counts[2] {
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let c = offset + Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * side;
                let inside = match envelope {
                    Envelope::Box { .. } => true,
                    _ => {
                        envelope.contains(&c)
                            && (0..8).all(|b| {
                                let corner = c + Vec3::new(
                                    if b & 1 == 0 { -h } else { h },
                                    if b & 2 == 0 { -h } else { h },
                                    if b & 4 == 0 { -h } else { h },
                                );
                                envelope.contains(&corner)
                            })
                    }
                };
                if inside {
                    out.push(c);
                }
            }
        }
    }
    Ok(out)
}

/// The ten inertial parameters of a unit point mass at `p`: mass, first moment and the
/// second moments `Σ m p pᵀ` (xx, yy, zz, xy, xz, yz) about the frame's origin.
pub fn point_moments(p: &Vec3) -> [f64; 10] {
    [
        1.0,
        p.x,
        p.y,
        p.z,
        p.x * p.x,
        p.y * p.y,
        p.z * p.z,
        p.x * p.y,
        p.x * p.z,
        p.y * p.z,
    ]
}

/// The same for a solid cube of unit mass and side `side` centred at `c`: a point mass at
/// `c` plus the cube's own `side²/12` on each diagonal second moment (its inertia about its
/// centre is isotropic, so the cube's orientation does not matter).
pub fn cube_moments(c: &Vec3, side: f64) -> [f64; 10] {
    let mut m = point_moments(c);
    let own = side * side / 12.0;
    for d in &mut m[4..7] {
        *d += own;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn a_box_fills_with_whole_cells_centred() {
        let env = Envelope::Box {
            lower: Vec3::new(-0.1, -0.02, -0.005),
            upper: Vec3::new(0.1, 0.02, 0.005),
        };
        let cells = fill(&env, 0.01).unwrap();
        assert_eq!(cells.len(), 20 * 4);
        let mean: Vec3 = cells.iter().sum::<Vec3>() / cells.len() as f64;
        assert!(mean.norm() < 1e-15);
        // Filled uniformly, the cells have the box's volume, COM and second moments.
        let mut m = [0.0; 10];
        for c in &cells {
            for (a, b) in m.iter_mut().zip(cube_moments(c, 0.01)) {
                *a += b * 1e-6; // unit density: mass = side³
            }
        }
        let (a, b, c) = (0.2, 0.04, 0.01);
        let mass = a * b * c;
        assert_relative_eq!(m[0], mass, max_relative = 1e-12);
        assert_relative_eq!(m[4], mass * a * a / 12.0, max_relative = 1e-12);
        assert_relative_eq!(m[5], mass * b * b / 12.0, max_relative = 1e-12);
        assert_relative_eq!(m[6], mass * c * c / 12.0, max_relative = 1e-12);
    }

    #[test]
    fn a_triangle_prism_keeps_only_cells_inside() {
        let env = Envelope::Prism {
            polygon: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            z: (0.0, 0.1),
        };
        let cells = fill(&env, 0.1).unwrap();
        // Cubes wholly under the hypotenuse x + y ≤ 1: 9 + 8 + … + 1.
        assert_eq!(cells.len(), 45);
        assert!(cells.iter().all(|c| c.x + c.y + 0.1 <= 1.0 + 1e-12));
    }

    #[test]
    fn a_mesh_cube_holds_the_same_cells_as_the_box() {
        // The unit cube as 12 outward triangles.
        let v = |i: usize| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64);
        let faces = [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        let triangles = faces.iter().map(|f| [v(f[0]), v(f[1]), v(f[2])]).collect();
        let mesh = fill(&Envelope::Mesh { triangles }, 0.25).unwrap();
        assert_eq!(mesh.len(), 64);
        assert!(Envelope::Mesh { triangles: vec![] }.check().is_err());
    }

    #[test]
    fn bad_cells_are_refused() {
        let env = Envelope::Box {
            lower: Vec3::zeros(),
            upper: Vec3::repeat(1.0),
        };
        assert!(fill(&env, 0.0).is_err());
        assert!(fill(&env, f64::NAN).is_err());
        assert!(fill(&env, 1e-4).is_err()); // 1e12 cells
        assert!(fill(&env, 2.0).is_err());
    }
}
