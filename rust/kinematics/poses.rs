//! World poses of everything a viewer draws (docs/visualisation.md §2): every body's frame,
//! every joint's frame origin and axis, every link's seven point masses and both ends of
//! every cut joint, for many configurations at once. One state fills one row of
//! preallocated buffers: nothing is allocated per configuration.
use crate::kinematics::{self, body_placement, LinkState};
use crate::model::Model;
use crate::support::error::Result;
use crate::support::spatial::{Placement, Vec3};

/// Values row-major with their shape: an array as a call hands it back to a binding.
pub struct Shaped {
    pub values: Vec<f64>,
    pub shape: Vec<usize>,
}

impl Shaped {
    pub fn new(values: Vec<f64>, shape: &[usize]) -> Shaped {
        let shape = shape.to_vec();
        Shaped { values, shape }
    }
}

/// An array by name (a buffer of [`Poses`], a centroidal quantity).
pub type Keyed = (&'static str, Shaped);

/// Poses of `rows` configurations, row-major, world axes.
pub struct Poses {
    pub rows: usize,
    /// Per body: rotation (row-major 3×3, body axes to world).
    pub rotations: Vec<f64>,
    /// Per body: origin of its frame.
    pub origins: Vec<f64>,
    /// Per body: origin of its joint frame (in the parent's body, `placement` away).
    pub joint_origins: Vec<f64>,
    /// Per body: unit axis of a revolute or prismatic joint, zero for other joints.
    pub joint_axes: Vec<f64>,
    /// Per link: its seven point masses' positions.
    pub points: Vec<f64>,
    /// Per cut joint: origin of frame a, origin of frame b, axis (frame a; zero if none).
    pub loop_a: Vec<f64>,
    pub loop_b: Vec<f64>,
    pub loop_axes: Vec<f64>,
    /// The links' kinematics, reused row to row.
    links: Vec<LinkState>,
}

impl Poses {
    /// Buffers for `rows` configurations of `model` (fails cleanly if they do not fit).
    pub fn new(model: &Model, rows: usize) -> Result<Poses> {
        let (nb, nl, nc) = (model.nbodies(), model.links.len(), model.loops.len());
        let zeros = |per: usize, what: &str| {
            crate::support::alloc::try_zeros_vec(
                rows.saturating_mul(per),
                &format!("body_poses {what}"),
            )
        };
        Ok(Poses {
            rows,
            rotations: zeros(9 * nb, "rotations")?,
            origins: zeros(3 * nb, "origins")?,
            joint_origins: zeros(3 * nb, "joint_origins")?,
            joint_axes: zeros(3 * nb, "joint_axes")?,
            points: zeros(21 * nl, "points")?,
            loop_a: zeros(3 * nc, "loop_a")?,
            loop_b: zeros(3 * nc, "loop_b")?,
            loop_axes: zeros(3 * nc, "loop_axes")?,
            links: vec![LinkState::default(); nl],
        })
    }

    /// The poses at `rows` configurations stacked row-major in `qs`, each checked first
    /// (errors name `q[k]` when `stacked`, `q` otherwise).
    pub fn at(model: &Model, qs: &[f64], rows: usize, stacked: bool) -> Result<Poses> {
        let nq = model.nq;
        for k in 0..rows {
            model
                .check_state(&qs[k * nq..(k + 1) * nq], None)
                .map_err(|e| match stacked {
                    true => e.map_arg(|name| format!("{name}[{k}]")),
                    false => e,
                })?;
        }
        let mut poses = Poses::new(model, rows)?;
        for k in 0..rows {
            crate::support::interrupt::check("body_poses")?;
            poses.fill(model, k, &qs[k * nq..(k + 1) * nq]);
        }
        Ok(poses)
    }

    /// Fills row `k` from `q` (checked by the caller: length nq, finite, unit quaternions).
    pub fn fill(&mut self, model: &Model, k: usize, q: &[f64]) {
        kinematics::positions(model, q, &mut self.links);
        let (nb, nc) = (model.nbodies(), model.loops.len());
        let put = |buf: &mut [f64], per: usize, i: usize, x: &Vec3| {
            buf[(k * per + i) * 3..(k * per + i) * 3 + 3].copy_from_slice(x.as_slice());
        };
        for b in 0..nb {
            let p = body_placement(model, &self.links, b);
            let rec = &model.bodies[b];
            // The joint frame sits at `placement` in the parent's body frame (the world's).
            let parent = match rec.parent {
                Some(pb) => body_placement(model, &self.links, pb),
                None => Placement::identity(),
            };
            let jf = parent.compose(&rec.placement);
            let axis = rec
                .joint
                .axis()
                .map_or_else(Vec3::zeros, |a| jf.rotation * a);
            let r = p.rotation.transpose();
            self.rotations[(k * nb + b) * 9..(k * nb + b) * 9 + 9].copy_from_slice(r.as_slice());
            put(&mut self.origins, nb, b, &p.translation);
            put(&mut self.joint_origins, nb, b, &jf.translation);
            put(&mut self.joint_axes, nb, b, &axis);
        }
        let nl = model.links.len();
        for (i, l) in model.links.iter().enumerate() {
            let s = &self.links[i];
            for (j, pj) in l.points.positions.iter().enumerate() {
                put(
                    &mut self.points,
                    7 * nl,
                    7 * i + j,
                    &(s.origin + s.rotation * pj),
                );
            }
        }
        for (c, lp) in model.loops.iter().enumerate() {
            let end = |body: Option<usize>, frame: &Placement| match body {
                Some(b) => body_placement(model, &self.links, b).compose(frame),
                None => *frame,
            };
            let a = end(lp.body_a, &lp.frame_a);
            let b = end(lp.body_b, &lp.frame_b);
            put(&mut self.loop_a, nc, c, &a.translation);
            put(&mut self.loop_b, nc, c, &b.translation);
            put(&mut self.loop_axes, nc, c, &(a.rotation * lp.axis()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::Joint;
    use crate::model::body::RigidBody;
    use crate::support::spatial::Mat3;

    /// A double pendulum about z, second joint 1 m along the first body's x: the joint
    /// origins and point masses are where plane trigonometry puts them.
    #[test]
    fn double_pendulum_frames() {
        let mut m = Model::new();
        let rod = RigidBody::new(1.0, Vec3::new(0.5, 0.0, 0.0), Mat3::identity() * 0.1).unwrap();
        let z = Joint::revolute(Vec3::z()).unwrap();
        let p = Placement::identity();
        let a = m.add_body(rod, z, None, p, None, None).unwrap();
        let p1 = Placement::new(Mat3::identity(), Vec3::new(1.0, 0.0, 0.0));
        m.add_body(rod, z, Some(a), p1, None, None).unwrap();
        let (t1, t2) = (0.3_f64, -0.7_f64);
        let mut poses = Poses::new(&m, 2).unwrap();
        poses.fill(&m, 1, &[t1, t2]);
        let jo = &poses.joint_origins[6..12];
        assert!((jo[3] - t1.cos()).abs() < 1e-15 && (jo[4] - t1.sin()).abs() < 1e-15);
        assert_eq!(&poses.joint_axes[6..12], &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
        // Row 0 untouched.
        assert!(poses.origins[..6].iter().all(|x| *x == 0.0));
        // Point masses of link 1 keep the first body's COM: Σ m x / Σ m at the rod's middle.
        let masses = &m.links[1].points.masses;
        let pts = &poses.points[21 * 2 + 21..21 * 2 + 42];
        let total: f64 = masses.iter().sum();
        let cx: f64 = (0..7).map(|j| masses[j] * pts[3 * j]).sum::<f64>() / total;
        let want = t1.cos() + 0.5 * (t1 + t2).cos();
        assert!((cx - want).abs() < 1e-12, "{cx} vs {want}");
    }
}

impl Poses {
    /// Each buffer by name with its shape (a leading axis of `rows` when `stacked`), each
    /// checked finite (an error names it as `body_poses['name']`).
    pub fn keyed(self, model: &Model, stacked: bool) -> Result<Vec<Keyed>> {
        let (nb, nl, nc) = (model.nbodies(), model.links.len(), model.loops.len());
        let lead = stacked.then_some(self.rows);
        let shape = |tail: &[usize]| lead.into_iter().chain(tail.iter().copied()).collect();
        let keyed = [
            ("rotations", self.rotations, shape(&[nb, 3, 3])),
            ("origins", self.origins, shape(&[nb, 3])),
            ("joint_origins", self.joint_origins, shape(&[nb, 3])),
            ("joint_axes", self.joint_axes, shape(&[nb, 3])),
            ("points", self.points, shape(&[nl, 7, 3])),
            ("loop_a", self.loop_a, shape(&[nc, 3])),
            ("loop_b", self.loop_b, shape(&[nc, 3])),
            ("loop_axes", self.loop_axes, shape(&[nc, 3])),
        ];
        for (key, buf, _) in &keyed {
            crate::support::error::check_result(&format!("body_poses['{key}']"), buf)?;
        }
        let keyed = keyed.map(|(key, values, shape)| (key, Shaped { values, shape }));
        Ok(keyed.into())
    }
}
