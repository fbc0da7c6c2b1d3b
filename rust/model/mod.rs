//! The kinematic tree. Bodies are kept as the user added them; bodies on `Fixed` joints are
//! welded into their moving ancestor (a "link"), so dynamics runs over links only. Each link
//! carries its merged rigid body, its seven point masses and the 6×6 mass matrix about its
//! origin built once from those points, in the link frame.
pub mod args;
pub mod body;
pub mod constraints;
pub mod frame;
pub mod joint_records;
mod listing;
pub mod point_masses;
pub mod visual;

use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::joint_records::JointRecords;
use crate::model::point_masses::EquimomentalSet;
use crate::recursive::Compiled;
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::{BodyInertia, Mat3, Placement, Vec3};

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct BodyRecord {
    pub name: String,
    pub body: RigidBody,
    pub joint: Joint,
    pub parent: Option<usize>,
    /// Joint frame in the parent body's frame.
    pub placement: Placement,
    /// Link this body belongs to (`None`: welded to the world).
    pub link: Option<usize>,
    /// This body's frame in its link's frame.
    pub in_link: Placement,
    pub point_mass_center: Option<Vec3>,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Link {
    /// Index of the moving body that defines the link.
    pub body: usize,
    pub parent: Option<usize>,
    pub joint: Joint,
    /// Joint frame in the parent link's frame.
    pub placement: Placement,
    /// Whether `placement.rotation` differs from the identity (kinematics skips it if not).
    pub placement_rotated: bool,
    pub q_index: usize,
    pub v_index: usize,
    /// The link's rigid body (with welded children), link frame.
    pub rigid: RigidBody,
    pub points: EquimomentalSet,
    /// Mass, first moment and inertia about the link origin, summed from the seven points.
    pub inertia: BodyInertia,
}

/// Serialised whole, derived link data included, so a round trip is bit-identical for every
/// model (those the URDF loader finishes with `set_link_body` too); deserialising checks the tree's indices.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "ModelData")]
pub struct Model {
    pub bodies: Vec<BodyRecord>,
    pub links: Vec<Link>,
    pub nq: usize,
    pub nv: usize,
    /// Cut joints closing kinematic loops (`crate::loops`); empty for a tree.
    #[serde(default)]
    pub loops: Vec<crate::model::constraints::LoopJoint>,
    /// Joint couplings `q_joint = ratio · q_reference + offset` (`crate::loops::coupling`),
    /// holonomic constraints solved with the loops; empty for most models.
    #[serde(default)]
    pub couplings: Vec<crate::model::constraints::Coupling>,
    /// Rotor inertia (armature) per speed, added to the mass matrix's diagonal in every
    /// algorithm (`crate::recursive::armature`); empty when no joint has any.
    #[serde(default)]
    pub armature: Vec<f64>,
    /// What a viewer draws for each body (URDF `<visual>`, MJCF geoms); no part of the
    /// dynamics. Checked against `bodies` by `check_structure`.
    #[serde(default)]
    pub visuals: Vec<crate::model::visual::Visual>,
    /// The model's name (URDF `<robot name>`, MJCF `<mujoco model>`; empty if none): titles.
    #[serde(default)]
    pub name: String,
    /// The source file's joints (names, limits, damping, friction) and repairs
    /// (`crate::model::joint_records`): no part of the dynamics, shared by every copy of the model.
    #[serde(default)]
    pub records: Arc<JointRecords>,
    /// Frames added on bodies (`crate::frames`): tool points, sites; every body is a frame
    /// too. No part of the dynamics.
    #[serde(default)]
    pub frames: Vec<crate::model::frame::Frame>,
    /// Body index by name, kept by `add_body` (the only place bodies are added or named), so
    /// name lookups and duplicate checks cost O(1) and building a model is linear. Derived
    /// from `bodies`: not serialised, rebuilt when deserialising.
    #[serde(skip_serializing)]
    names: HashMap<String, usize>,
    /// The recursions' constants (`recursive::Compiled`), built on first use and dropped by
    /// `add_body`. Derived: not serialised.
    #[serde(skip_serializing)]
    compiled: OnceLock<Compiled>,
}

/// A deserialised model, checked by [`Model::check_structure`] before use.
#[derive(serde::Deserialize)]
struct ModelData {
    bodies: Vec<BodyRecord>,
    links: Vec<Link>,
    nq: usize,
    nv: usize,
    #[serde(default)]
    loops: Vec<crate::model::constraints::LoopJoint>,
    #[serde(default)]
    couplings: Vec<crate::model::constraints::Coupling>,
    #[serde(default)]
    armature: Vec<f64>,
    #[serde(default)]
    visuals: Vec<crate::model::visual::Visual>,
    #[serde(default)]
    name: String,
    #[serde(default)]
    records: Arc<JointRecords>,
    #[serde(default)]
    frames: Vec<crate::model::frame::Frame>,
}

impl TryFrom<ModelData> for Model {
    type Error = Error;
    fn try_from(d: ModelData) -> Result<Model> {
        let names = d
            .bodies
            .iter()
            .enumerate()
            .map(|(k, b)| (b.name.clone(), k))
            .collect();
        let m = Model {
            bodies: d.bodies,
            links: d.links,
            nq: d.nq,
            nv: d.nv,
            loops: d.loops,
            couplings: d.couplings,
            armature: d.armature,
            visuals: d.visuals,
            name: d.name,
            records: d.records,
            frames: d.frames,
            names,
            compiled: OnceLock::new(),
        };
        m.check_structure()?;
        m.check_loops()?;
        m.check_couplings()?;
        m.check_armature()?;
        m.check_records()?;
        m.check_frames()?;
        Ok(m)
    }
}

/// Checks that `r` is a proper rotation (to 1e-9) and returns it re-orthonormalised.
pub fn checked_rotation(r: &Mat3, arg: &str) -> Result<Mat3> {
    check_finite(arg, r.as_slice())?;
    let err = (r.transpose() * r - Mat3::identity()).abs().max();
    if err > 1e-9 || r.determinant() <= 0.0 {
        return Err(Error::arg(
            arg,
            "a 3x3 rotation matrix (orthonormal, determinant +1, to 1e-9)",
            format!(
                "a matrix with |RᵀR − 1| = {err:.3e} and determinant {:.6}",
                r.determinant()
            ),
        ));
    }
    if let Some(q) = snapped_signed_permutation(r) {
        return Ok(q);
    }
    if err <= 4.0 * f64::EPSILON {
        return Ok(*r);
    }
    // Polar projection onto SO(3) so that rounding in the input does not accumulate.
    let svd = r.svd(true, true);
    match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => Ok(u * vt),
        _ => Ok(*r),
    }
}

/// A rotation within 4ε, entry by entry, of a signed permutation (an exact quarter or half
/// turn about coordinate axes, as URDF `rpy = (±π/2, 0, 0)` means) is taken as exactly that
/// matrix. The decimal angle in a file cannot state π/2 exactly and leaves 6e-17 where the
/// rotation has a zero; exact zeros are what the robot means, and they let the body-frame
/// dynamics absorb the placement into the link frame (`recursive::compiled`).
fn snapped_signed_permutation(r: &Mat3) -> Option<Mat3> {
    const TOL: f64 = 4.0 * f64::EPSILON;
    let mut out = Mat3::zeros();
    for (o, &x) in out.iter_mut().zip(r.iter()) {
        if x.abs() <= TOL {
            *o = 0.0;
        } else if (x.abs() - 1.0).abs() <= TOL {
            *o = x.signum();
        } else {
            return None;
        }
    }
    // One ±1 per row and column, determinant +1.
    let ones_per_row = (0..3).all(|i| out.row(i).iter().filter(|x| **x != 0.0).count() == 1);
    let ones_per_col = (0..3).all(|j| out.column(j).iter().filter(|x| **x != 0.0).count() == 1);
    (ones_per_row && ones_per_col && out.determinant() == 1.0).then_some(out)
}

/// Bodies summed in one frame; unlike [`RigidBody::merged`] any of them (or all) may have
/// zero mass.
fn sum_bodies(parts: &[RigidBody]) -> RigidBody {
    let mass: f64 = parts.iter().map(|b| b.mass).sum();
    let com = if mass > 0.0 {
        parts.iter().fold(Vec3::zeros(), |a, b| a + b.com * b.mass) / mass
    } else {
        Vec3::zeros()
    };
    let mut inertia = Mat3::zeros();
    for b in parts {
        inertia += if b.mass > 0.0 {
            b.inertia_about(&com)
        } else {
            b.inertia
        };
    }
    RigidBody {
        mass,
        com,
        inertia: (inertia + inertia.transpose()) * 0.5,
    }
}

/// Refuses a link whose derived quantities (merged body, seven point masses, inertia about
/// the link origin) overflow double precision, although each body's numbers are finite.
fn check_link(link: &Link, body: &str, link_body: &str) -> Result<()> {
    let p = &link.points;
    let i = &link.inertia;
    let finite = link.rigid.mass.is_finite()
        && link.rigid.com.iter().all(|x| x.is_finite())
        && link.rigid.inertia.iter().all(|x| x.is_finite())
        && p.masses.iter().all(|x| x.is_finite())
        && p.half_sides.iter().all(|x| x.is_finite())
        && p.positions.iter().all(|x| x.iter().all(|y| y.is_finite()))
        && i.mass.is_finite()
        && i.first_moment.iter().all(|x| x.is_finite())
        && i.rotational.iter().all(|x| x.is_finite());
    if finite {
        return Ok(());
    }
    let whose = if body == link_body {
        format!("body '{body}'")
    } else {
        format!("body '{body}' (welded into the link of body '{link_body}')")
    };
    Err(Error::inertia(
        "body",
        format!(
            "{whose}: its seven point masses or its inertia about the link origin overflow double precision (mass {:e}, largest inertia entry {:e}, centre of mass at distance {:e}); use smaller units",
            link.rigid.mass,
            link.rigid.inertia.abs().max(),
            link.rigid.com.norm()
        ),
    ))
}

impl Model {
    pub fn new() -> Self {
        Self::default()
    }

    /// The recursions' model constants, computed on the first call after the model last
    /// changed (through [`add_body`](Model::add_body)).
    #[inline]
    pub fn compiled(&self) -> &Compiled {
        self.compiled.get_or_init(|| Compiled::new(self))
    }

    /// Checks that the joint records point at bodies and coordinates of this model (a
    /// deserialised model's may not).
    pub(crate) fn check_records(&self) -> Result<()> {
        let bad = self.records.joints.iter().find(|j| {
            j.body >= self.bodies.len()
                || j.link.is_some_and(|l| l >= self.links.len())
                || j.q_index.is_some_and(|i| i >= self.nq)
                || j.v_index.is_some_and(|i| i >= self.nv)
        });
        match bad {
            Some(j) => Err(Error::model(
                format!("joint record '{}'", j.name),
                "its body or coordinate indices are outside the model",
            )),
            None => Ok(()),
        }
    }

    /// Drops the recursions' constants after a change they depend on (armature).
    pub(crate) fn drop_compiled(&mut self) {
        self.compiled = OnceLock::new();
    }

    pub fn nbodies(&self) -> usize {
        self.bodies.len()
    }

    pub fn body_index(&self, name: &str) -> Option<usize> {
        match self.names.get(name) {
            Some(&k) if self.bodies.get(k).is_some_and(|b| b.name == name) => Some(k),
            // `bodies` is public: if it was changed behind `add_body`'s back, scan.
            _ if self.names.len() != self.bodies.len() => {
                self.bodies.iter().position(|b| b.name == name)
            }
            _ => None,
        }
    }

    /// The index of the body named `name`, or an error on argument `arg` listing the
    /// model's body names (the first 20 of them) and `'world'`.
    pub fn body_named(&self, arg: &str, name: &str) -> Result<usize> {
        self.body_index(name).ok_or_else(|| {
            let mut names: Vec<String> = self
                .bodies
                .iter()
                .take(20)
                .map(|b| format!("'{}'", b.name))
                .collect();
            if self.bodies.len() > 20 {
                names.push(format!("… ({} bodies)", self.bodies.len()));
            }
            names.push("'world'".into());
            Error::model(
                arg,
                format!(
                    "no body named '{name}': expected one of {}",
                    names.join(", ")
                ),
            )
        })
    }

    /// Adds a body on `joint` below `parent` (None: the world). `placement` puts the joint
    /// frame in the parent body's frame; the body frame equals the joint frame at the neutral
    /// configuration. `point_mass_center` (body frame) is where the seven-point box is
    /// centred; the default is the COM. Returns the body's index.
    pub fn add_body(
        &mut self,
        body: RigidBody,
        joint: Joint,
        parent: Option<usize>,
        placement: Placement,
        name: Option<String>,
        point_mass_center: Option<Vec3>,
    ) -> Result<usize> {
        let index = self.bodies.len();
        self.compiled = OnceLock::new();
        if let Some(p) = parent {
            if p >= index {
                return Err(Error::model(
                    "parent",
                    format!(
                        "no body with index {p}: the model has {index} bodies (indices 0..{index}), or -1 for the world"
                    ),
                ));
            }
        }
        check_finite("translation", placement.translation.as_slice())?;
        let rotation = checked_rotation(&placement.rotation, "rotation")?;
        let placement = Placement::new(rotation, placement.translation);
        if let Some(c) = &point_mass_center {
            check_finite("point_mass_center", c.as_slice())?;
        }
        crate::support::error::check_name("body", name.as_deref())?;
        let name = name.unwrap_or_else(|| format!("body{index}"));
        if self.body_index(&name).is_some() || self.frames.iter().any(|f| f.name == name) {
            return Err(Error::model(
                "name",
                format!("a body or frame named '{name}' already exists"),
            ));
        }
        let (parent_link, parent_in_link) = match parent {
            Some(p) => (self.bodies[p].link, self.bodies[p].in_link),
            None => (None, Placement::identity()),
        };
        let joint_in_link = parent_in_link.compose(&placement);
        let (link, in_link) = if let Joint::Fixed = joint {
            if let Some(l) = parent_link {
                let mut link = self.links[l].clone();
                let welded = body.transformed(&joint_in_link.rotation, &joint_in_link.translation);
                link.rigid = link.rigid.merged(&welded);
                let center = self.bodies[link.body].point_mass_center;
                Self::refresh_points(&mut link, center);
                check_link(&link, &name, &self.bodies[link.body].name)?;
                self.links[l] = link;
            }
            (parent_link, joint_in_link)
        } else {
            let mut link = Link {
                body: index,
                parent: parent_link,
                joint,
                placement: joint_in_link,
                placement_rotated: joint_in_link.rotation != Mat3::identity(),
                q_index: self.nq,
                v_index: self.nv,
                rigid: body,
                points: EquimomentalSet::solve(&body, &body.com),
                inertia: BodyInertia::zero(),
            };
            Self::refresh_points(&mut link, point_mass_center);
            check_link(&link, &name, &name)?;
            self.nq += joint.nq();
            self.nv += joint.nv();
            if !self.armature.is_empty() {
                self.armature.resize(self.nv, 0.0);
            }
            self.links.push(link);
            (Some(self.links.len() - 1), Placement::identity())
        };
        self.names.insert(name.clone(), index);
        self.bodies.push(BodyRecord {
            name,
            body,
            joint,
            parent,
            placement,
            link,
            in_link,
            point_mass_center,
        });
        Ok(index)
    }

    fn refresh_points(link: &mut Link, center: Option<Vec3>) {
        let c = center.unwrap_or(link.rigid.com);
        link.points = EquimomentalSet::solve(&link.rigid, &c);
        link.inertia = BodyInertia::from_points(&link.points.masses, &link.points.positions);
    }

    /// Replaces the own rigid body of body `index` (its record only: the link it belongs to
    /// keeps its merged body until [`Model::set_link_body`] sets it, e.g. from
    /// [`Model::link_bodies`]). For loaders that build the tree first and set the inertials
    /// after, which may have zero mass (the URDF loader).
    pub fn set_body_inertial(&mut self, index: usize, body: RigidBody) {
        self.bodies[index].body = body;
    }

    /// Replaces body `index`'s own rigid body and updates the link it belongs to (its merged
    /// body and seven point masses); a body welded to the world changes no link.
    pub fn replace_body(&mut self, index: usize, body: RigidBody) -> Result<()> {
        self.set_body_inertial(index, body);
        match self.bodies[index].link {
            Some(l) => {
                let merged = self.link_bodies().swap_remove(l);
                self.set_link_body(l, merged)
            }
            None => Ok(()),
        }
    }

    /// Each link's body summed from the records of its bodies (its own and those welded to
    /// it), in the link frame. Unlike the merging `add_body` does, any or all of them may
    /// have zero mass (then the sum has mass 0, centre of mass 0).
    pub fn link_bodies(&self) -> Vec<RigidBody> {
        let mut parts: Vec<Vec<RigidBody>> = vec![Vec::new(); self.links.len()];
        for b in &self.bodies {
            if let Some(l) = b.link {
                parts[l].push(
                    b.body
                        .transformed(&b.in_link.rotation, &b.in_link.translation),
                );
            }
        }
        parts.iter().map(|p| sum_bodies(p)).collect()
    }

    /// Sets link `l`'s rigid body and, from it, its seven point masses (centred at the
    /// body's centre of mass) and its inertia about the link origin. A body without mass (the
    /// intermediate link of a multi-axis joint in a URDF) gets seven zero masses; it must
    /// then have no rotational inertia either, which seven point masses cannot carry.
    pub fn set_link_body(&mut self, l: usize, body: RigidBody) -> Result<()> {
        // The recursions' constants hold each link's inertia.
        self.compiled = OnceLock::new();
        let link = &mut self.links[l];
        if body.mass > 0.0 {
            link.rigid = body;
            link.points = EquimomentalSet::solve(&body, &body.com);
            link.inertia = BodyInertia::from_points(&link.points.masses, &link.points.positions);
            return Ok(());
        }
        if body.inertia.abs().max() > 0.0 {
            return Err(Error::inertia(
                "body",
                format!(
                    "body '{}': zero mass with a non-zero rotational inertia: seven point masses cannot represent it",
                    self.bodies[link.body].name
                ),
            ));
        }
        link.rigid = body;
        link.points = EquimomentalSet {
            masses: [0.0; 7],
            positions: [Vec3::zeros(); 7],
            half_sides: Vec3::zeros(),
            center: Vec3::zeros(),
        };
        link.inertia = BodyInertia::zero();
        Ok(())
    }

    /// Checks the tree's bookkeeping as `add_body` keeps it (parents before children, links
    /// and bodies pointing at each other, coordinate slots in order, unique names), so that a
    /// model assembled from outside data (deserialised) indexes nothing out of range.
    pub fn check_structure(&self) -> Result<()> {
        let bad = |reason: String| Err(Error::model("model", reason));
        let mut names = std::collections::HashSet::new();
        for (i, b) in self.bodies.iter().enumerate() {
            if !names.insert(b.name.as_str()) {
                return bad(format!("two bodies named '{}'", b.name));
            }
            if b.parent.is_some_and(|p| p >= i) {
                return bad(format!(
                    "body {i} has parent {:?}, not an earlier body",
                    b.parent
                ));
            }
            if b.link.is_some_and(|l| l >= self.links.len()) {
                return bad(format!(
                    "body {i} belongs to link {:?} of {}",
                    b.link,
                    self.links.len()
                ));
            }
            let parent_link = b.parent.and_then(|p| self.bodies[p].link);
            let own_link = |l: usize| self.links[l].body == i;
            if matches!(b.joint, Joint::Fixed) && b.link != parent_link
                || !matches!(b.joint, Joint::Fixed) && !b.link.is_some_and(own_link)
            {
                return bad(format!("body {i} is not in the link its joint gives it"));
            }
        }
        let (mut nq, mut nv) = (0, 0);
        for (l, link) in self.links.iter().enumerate() {
            let owner = self.bodies.get(link.body);
            if owner.is_none_or(|b| b.link != Some(l) || b.joint != link.joint) {
                return bad(format!("link {l} and its body {} disagree", link.body));
            }
            let parent_link = owner
                .and_then(|b| b.parent)
                .and_then(|p| self.bodies[p].link);
            if link.parent != parent_link || link.parent.is_some_and(|p| p >= l) {
                return bad(format!("link {l} has parent {:?}", link.parent));
            }
            if matches!(link.joint, Joint::Fixed) || link.q_index != nq || link.v_index != nv {
                return bad(format!("link {l}: joint or coordinate slots out of order"));
            }
            nq += link.joint.nq();
            nv += link.joint.nv();
        }
        if (nq, nv) != (self.nq, self.nv) {
            return bad(format!(
                "nq = {}, nv = {} where the joints give {nq}, {nv}",
                self.nq, self.nv
            ));
        }
        for (k, v) in self.visuals.iter().enumerate() {
            v.check(self.bodies.len(), &format!("visuals[{k}]"))?;
        }
        Ok(())
    }

    pub fn neutral(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.nq];
        for l in &self.links {
            l.joint.neutral(&mut q[l.q_index..l.q_index + l.joint.nq()]);
        }
        q
    }

    /// Validates a configuration and a velocity (lengths, finite, quaternion norms).
    pub fn check_state(&self, q: &[f64], v: Option<&[f64]>) -> Result<()> {
        if q.len() != self.nq {
            return Err(Error::arg(
                "q",
                format!("shape ({},)", self.nq),
                format!("shape ({},)", q.len()),
            ));
        }
        self.check_finite_coordinates("q", q, |l| l.q_index..l.q_index + l.joint.nq())?;
        for l in &self.links {
            l.joint
                .check_configuration(&q[l.q_index..l.q_index + l.joint.nq()], "q")?;
        }
        if let Some(v) = v {
            self.check_vector("v", v)?;
        }
        Ok(())
    }

    pub fn check_vector(&self, arg: &str, x: &[f64]) -> Result<()> {
        if x.len() != self.nv {
            return Err(Error::arg(
                arg,
                format!("shape ({},)", self.nv),
                format!("shape ({},)", x.len()),
            ));
        }
        self.check_finite_coordinates(arg, x, |l| l.v_index..l.v_index + l.joint.nv())
    }

    /// A non-finite entry of `x` (q-sized or v-sized, as `range` says) as an error naming its
    /// index in `x` and the joint it belongs to.
    fn check_finite_coordinates(
        &self,
        arg: &str,
        x: &[f64],
        range: impl Fn(&Link) -> std::ops::Range<usize>,
    ) -> Result<()> {
        let Err(e) = check_finite(arg, x) else {
            return Ok(());
        };
        let Some(k) = x.iter().position(|v| !v.is_finite()) else {
            return Err(e);
        };
        match self.links.iter().position(|l| range(l).contains(&k)) {
            Some(link) => Err(Error::arg(
                arg,
                "finite numbers",
                format!(
                    "{} at index {k} (joint '{}')",
                    x[k],
                    self.joint_names()[link]
                ),
            )),
            None => Err(e),
        }
    }

    /// `q̇` from `v` for the whole model.
    #[inline]
    pub fn velocity_to_qdot(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) {
        // Only quaternion joints have nq ≠ nv; without them q̇ = v (the RHS's common case).
        if self.nq == self.nv {
            qdot.copy_from_slice(v);
        } else {
            self.velocity_to_qdot_by_joint(q, v, qdot);
        }
    }

    fn velocity_to_qdot_by_joint(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) {
        for l in &self.links {
            let (iq, iv) = (l.q_index, l.v_index);
            l.joint.velocity_to_qdot(
                &q[iq..iq + l.joint.nq()],
                &v[iv..iv + l.joint.nv()],
                &mut qdot[iq..iq + l.joint.nq()],
            );
        }
    }

    /// Normalises the quaternions of `q` in place.
    #[inline]
    pub fn normalize(&self, q: &mut [f64]) {
        // Only quaternion joints have nq > nv (every other joint has nq = nv): with nq = nv
        // there is nothing to normalise, and this runs at every accepted step.
        if self.nq != self.nv {
            self.normalize_quaternions(q);
        }
    }

    fn normalize_quaternions(&self, q: &mut [f64]) {
        for l in &self.links {
            if let Some(at) = l.joint.quaternion_at() {
                let s = &mut q[l.q_index + at..l.q_index + at + 4];
                let n = crate::joint::rotation::quat_norm(s);
                if n > 0.0 && n.is_finite() {
                    s.iter_mut().for_each(|x| *x /= n);
                }
            }
        }
    }

    /// Total number of point masses taking part in the dynamics (7 per link).
    pub fn npoints(&self) -> usize {
        7 * self.links.len()
    }

    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(|l| l.rigid.mass).sum()
    }
}
