//! A point fixed in a body (or in the world) and its Jacobian along the body's path from the
//! root: per speed the joint-motion column and the point's velocity per unit speed, so a force
//! at the point becomes generalized forces `Jᵀ f` in O(depth) with no link wrench. Shared by
//! the effects that act at body points (point springs, ground contact), with the pieces their
//! analytic derivatives need (how a column turns under another, `Column::moved_by`).
use super::{resolve_body, JointRef};
use crate::error::Result;
use crate::kinematics::{body_placement, LinkState};
use crate::model::Model;
use crate::spatial::{angular, linear, Mat3, Vec3, Vec6};

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
                r * l.placement.rotation
            } else {
                r
            };
            let (r_q, t_q) = l.joint.transform(qi);
            o += r * l.placement.translation + r_joint * t_q;
            r = r_joint * r_q;
            let s = l.joint.subspace(qi, &r_joint, &r);
            for (k, s) in s.iter().take(l.joint.nv()).enumerate() {
                let col = &mut self.columns[c];
                col.v = l.v_index + k;
                col.link = i;
                col.chain = matches!(l.joint, crate::joint::Joint::SphericalZYZ);
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
        self.columns
            .iter()
            .fold(Vec3::zeros(), |acc, col| acc + col.j * v[col.v])
    }

    /// Adds `Jᵀ f` to `tau` (after `place`).
    #[inline]
    pub(super) fn add_force(&self, f: &Vec3, tau: &mut [f64]) {
        for col in &self.columns {
            tau[col.v] += col.j.dot(f);
        }
    }

    /// The point's world position from the links' poses.
    pub(super) fn position(&self, links: &[LinkState]) -> Vec3 {
        match self.link {
            Some(l) => links[l].origin + links[l].rotation * self.point,
            None => self.point,
        }
    }
}
