//! A point fixed in a body (or in the world) and its Jacobian along the body's path from the
//! root: per speed the joint-motion column and the point's velocity per unit speed, so a force
//! at the point becomes generalized forces `Jᵀ f` in O(depth) with no link wrench. Shared by
//! the effects that act at body points (point springs, ground contact), with the pieces their
//! analytic derivatives need (how a column turns under another, `Column::moved_by`).
//!
//! [`End`] walks one point's path (a point spring's two ends); [`PointSet`] walks the union of
//! many points' paths once per evaluation (a robot's feet share its base), and builds a
//! point's columns only when asked (a foot in the air needs none).
use super::{resolve_body, JointRef};
use crate::joint::{axis_angle, Subspace};
use crate::kinematics::{body_placement, LinkState};
use crate::model::Model;
use crate::recursive::algebra::{mat_mul, mul};
use crate::support::error::{Error, Result};
use crate::support::spatial::{angular, linear, stack, Mat3, Vec3, Vec6};

/// One speed's column along an end's path: the joint-motion column `s = [ω; v_O]` (world
/// axes, about the link origin `O`) and, once the point is known, the point's velocity per
/// unit speed `j = v_O + ω × (p − O)`.
#[derive(Clone, Copy)]
pub(super) struct Column {
    pub(super) v: usize,
    origin: Vec3,
    pub(super) s: Vec6,
    pub(super) j: Vec3,
    /// The link of the column's joint, and whether that joint's columns move each other
    /// only forward (ZYZ: a chain of revolutes) rather than all together (quaternion
    /// joints); for the derivatives.
    link: usize,
    chain: bool,
}

impl Column {
    /// Whether perturbing column `c` carries this column along (docs/derivatives.md): `c`'s
    /// joint is upstream, or it is the same joint and not an earlier ZYZ angle. Both on one
    /// root-to-link path, in path order.
    #[inline]
    pub(super) fn moved_by(&self, c: &Column, c_before: bool) -> bool {
        c.link != self.link && c_before || c.link == self.link && (!self.chain || c.v <= self.v)
    }
}

/// One end of the spring, resolved: the link carrying it (`None`: fixed in the world), the
/// links from the root to it, and the point in that link's frame (world for `None`).
pub(super) struct End {
    pub(super) link: Option<usize>,
    path: Vec<usize>,
    point: Vec3,
    /// One per speed of the path's joints; rewritten at every evaluation.
    pub(super) columns: Vec<Column>,
    /// "body 'K3' point [..]" or "the world point [..]", for the errors.
    pub(super) what: String,
}

impl End {
    pub(super) fn resolve(
        model: &Model,
        body: &Option<JointRef>,
        point: &Vec3,
        arg: &str,
    ) -> Result<End> {
        let shown = format!("[{}, {}, {}]", point.x, point.y, point.z);
        let Some(r) = body else {
            return Ok(End {
                link: None,
                path: Vec::new(),
                point: *point,
                columns: Vec::new(),
                what: format!("the world point {shown}"),
            });
        };
        let b = resolve_body(model, r, arg)?;
        let rec = &model.bodies[b];
        let what = format!("body '{}' point {shown}", rec.name);
        let Some(link) = rec.link else {
            // Welded to the world: a fixed world point (its placement needs no link state).
            return Ok(End {
                link: None,
                path: Vec::new(),
                point: body_placement(model, &[], b).act_point(point),
                columns: Vec::new(),
                what,
            });
        };
        let mut path = Vec::new();
        let mut l = Some(link);
        while let Some(i) = l {
            path.push(i);
            l = model.links[i].parent;
        }
        path.reverse();
        let n: usize = path.iter().map(|&i| model.links[i].joint.nv()).sum();
        let zero = Column {
            v: 0,
            origin: Vec3::zeros(),
            s: Vec6::zeros(),
            j: Vec3::zeros(),
            link: 0,
            chain: false,
        };
        Ok(End {
            link: Some(link),
            path,
            point: rec.in_link.act_point(point),
            columns: vec![zero; n],
            what,
        })
    }

    /// The point's world position at `q`, its path's columns filled in. The poses follow
    /// `kinematics::positions` (`O_i = O_λ + R_λ t_i + R_joint t_q`), along one path only.
    #[inline]
    pub(super) fn place(&mut self, model: &Model, q: &[f64]) -> Vec3 {
        let mut r = Mat3::identity();
        let mut o = Vec3::zeros();
        let mut c = 0;
        for &i in &self.path {
            let l = &model.links[i];
            let qi = &q[l.q_index..l.q_index + l.joint.nq()];
            let r_joint = if l.placement_rotated {
                mat_mul(&r, &l.placement.rotation)
            } else {
                r
            };
            let (r_q, t_q) = l.joint.transform(qi);
            o += mul(&r, &l.placement.translation) + mul(&r_joint, &t_q);
            r = mat_mul(&r_joint, &r_q);
            let s = l.joint.subspace(qi, &r_joint, &r);
            for (k, s) in s.iter().take(l.joint.nv()).enumerate() {
                let col = &mut self.columns[c];
                col.v = l.v_index + k;
                col.link = i;
                col.chain = l.joint.chained_columns();
                col.origin = o;
                col.s = *s;
                c += 1;
            }
        }
        let p = match self.link {
            Some(_) => o + r * self.point,
            None => self.point,
        };
        for col in &mut self.columns {
            let w = angular(&col.s);
            col.j = linear(&col.s) + w.cross(&(p - col.origin));
        }
        p
    }

    /// The point's velocity `J v` (after `place`).
    #[inline]
    pub(super) fn velocity(&self, v: &[f64]) -> Vec3 {
        velocity(&self.columns, v)
    }

    /// Adds `Jᵀ f` to `tau` (after `place`).
    #[inline]
    pub(super) fn add_force(&self, f: &Vec3, tau: &mut [f64]) {
        add_force(&self.columns, f, tau)
    }

    /// The point's world position from the links' poses.
    pub(super) fn position(&self, links: &[LinkState]) -> Vec3 {
        match self.link {
            Some(l) => links[l].origin + links[l].rotation * self.point,
            None => self.point,
        }
    }
}

/// A point's velocity `J v` from its columns.
#[inline]
pub(super) fn velocity(columns: &[Column], v: &[f64]) -> Vec3 {
    columns
        .iter()
        .fold(Vec3::zeros(), |acc, col| acc + col.j * v[col.v])
}

/// Adds `Jᵀ f` to `tau`, `f` a force at the point of `columns`.
#[inline]
pub(super) fn add_force(columns: &[Column], f: &Vec3, tau: &mut [f64]) {
    for col in columns {
        tau[col.v] += col.j.dot(f);
    }
}

/// A link on some point's path: its pose and joint columns at the last `place`.
struct PathLink {
    link: usize,
    /// The parent's index in [`PointSet::links`] (`None`: the root).
    parent: Option<usize>,
    rotation: Mat3,
    origin: Vec3,
    s: Subspace,
}

/// One point of a [`PointSet`].
struct SetPoint {
    /// Its link's index in [`PointSet::links`], and the point in that link's frame.
    slot: usize,
    point: Vec3,
    /// Indices in [`PointSet::links`] from the root to its link.
    path: Vec<usize>,
    /// One per speed of the path's joints, filled by [`PointSet::jacobian`].
    columns: Vec<Column>,
}

/// Points on moving bodies, their paths walked together: [`PointSet::place`] computes each
/// path link's pose and joint columns once (the poses as `kinematics::positions`), then
/// [`PointSet::position`] is one rotation and [`PointSet::jacobian`] a point's columns.
pub(super) struct PointSet {
    /// Every link on some point's path, parents before children.
    links: Vec<PathLink>,
    points: Vec<SetPoint>,
}

impl PointSet {
    /// `points`: (body, point in its frame); `arg(k)` names point `k` in the errors. A body
    /// welded to the world is refused (its points never move).
    pub(super) fn resolve<'a>(
        model: &Model,
        points: impl Iterator<Item = (&'a JointRef, &'a Vec3)>,
        arg: impl Fn(usize) -> String,
    ) -> Result<PointSet> {
        let mut on_path = vec![false; model.links.len()];
        let mut found = Vec::new();
        for (k, (r, point)) in points.enumerate() {
            let b = resolve_body(model, r, &arg(k))?;
            let rec = &model.bodies[b];
            let Some(link) = rec.link else {
                return Err(Error::arg(
                    arg(k),
                    "a point on a body that moves (a body welded to the world never touches the ground differently)",
                    format!("body '{}' point [{}, {}, {}]", rec.name, point.x, point.y, point.z),
                ));
            };
            let mut l = Some(link);
            while let Some(i) = l {
                on_path[i] = true;
                l = model.links[i].parent;
            }
            found.push((link, rec.in_link.act_point(point)));
        }
        // Model links are in tree order (a parent is added before its children).
        let mut slot = vec![usize::MAX; model.links.len()];
        let mut links = Vec::new();
        for (i, _) in on_path.iter().enumerate().filter(|(_, on)| **on) {
            slot[i] = links.len();
            links.push(PathLink {
                link: i,
                parent: model.links[i].parent.map(|p| slot[p]),
                rotation: Mat3::identity(),
                origin: Vec3::zeros(),
                s: [Vec6::zeros(); 6],
            });
        }
        let zero = Column {
            v: 0,
            origin: Vec3::zeros(),
            s: Vec6::zeros(),
            j: Vec3::zeros(),
            link: 0,
            chain: false,
        };
        let points = found
            .into_iter()
            .map(|(link, point)| {
                let mut path = Vec::new();
                let mut l = Some(link);
                while let Some(i) = l {
                    path.push(slot[i]);
                    l = model.links[i].parent;
                }
                path.reverse();
                let n = path
                    .iter()
                    .map(|&k| model.links[links[k].link].joint.nv())
                    .sum();
                SetPoint {
                    slot: slot[link],
                    point,
                    path,
                    columns: vec![zero; n],
                }
            })
            .collect();
        Ok(PointSet { links, points })
    }

    pub(super) fn len(&self) -> usize {
        self.points.len()
    }

    /// The path links' poses and joint columns at `q`.
    #[inline]
    pub(super) fn place(&mut self, model: &Model, q: &[f64]) {
        for k in 0..self.links.len() {
            let (r, o) = match self.links[k].parent {
                Some(p) => (self.links[p].rotation, self.links[p].origin),
                None => (Mat3::identity(), Vec3::zeros()),
            };
            let l = &model.links[self.links[k].link];
            let qi = &q[l.q_index..l.q_index + l.joint.nq()];
            let r_joint = if l.placement_rotated {
                mat_mul(&r, &l.placement.rotation)
            } else {
                r
            };
            let at = &mut self.links[k];
            if let Some(axis) = l.joint.revolute_axis() {
                // The common case, written out: one column, no translation.
                at.origin = o + mul(&r, &l.placement.translation);
                at.rotation = mat_mul(&r_joint, &axis_angle(&axis, qi[0]));
                at.s[0] = stack(&mul(&r_joint, &axis), &Vec3::zeros());
                continue;
            }
            let (r_q, t_q) = l.joint.transform(qi);
            at.origin = o + mul(&r, &l.placement.translation) + mul(&r_joint, &t_q);
            at.rotation = mat_mul(&r_joint, &r_q);
            at.s = l.joint.subspace(qi, &r_joint, &at.rotation);
        }
    }

    /// Point `k`'s world position (after `place`).
    #[inline]
    pub(super) fn position(&self, k: usize) -> Vec3 {
        let p = &self.points[k];
        let l = &self.links[p.slot];
        l.origin + mul(&l.rotation, &p.point)
    }

    /// Point `k`'s columns at its position `p` (after `place`).
    #[inline]
    pub(super) fn jacobian(&mut self, model: &Model, k: usize, p: &Vec3) -> &[Column] {
        let point = &mut self.points[k];
        let mut c = 0;
        for &slot in &point.path {
            let at = &self.links[slot];
            let l = &model.links[at.link];
            let chain = l.joint.chained_columns();
            let arm = p - at.origin;
            for (i, s) in at.s.iter().take(l.joint.nv()).enumerate() {
                point.columns[c] = Column {
                    v: l.v_index + i,
                    origin: at.origin,
                    s: *s,
                    j: linear(s) + angular(s).cross(&arm),
                    link: at.link,
                    chain,
                };
                c += 1;
            }
        }
        &point.columns
    }

    /// Point `k`'s columns as the last [`PointSet::jacobian`] left them.
    #[inline]
    pub(super) fn columns(&self, k: usize) -> &[Column] {
        &self.points[k].columns
    }

    /// Point `k`'s world position from the links' poses.
    pub(super) fn position_from(&self, links: &[LinkState], k: usize) -> Vec3 {
        let p = &self.points[k];
        let l = self.links[p.slot].link;
        links[l].origin + links[l].rotation * p.point
    }
}
