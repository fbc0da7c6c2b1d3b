//! What a model's source file says of its joints beyond the dynamics: the URDF joints (names,
//! limits, damping, friction, mimics) and the inertia repairs a load made. Kept in the model
//! ([`crate::model::Model::records`]) so that every copy of it (a scene's, a pickle, a model
//! with a body added) keeps its joints' names and limits; no computation reads them.
use std::sync::Arc;

use crate::support::spatial::Vec3;

/// The records of one model (empty for a model built body by body).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointRecords {
    /// Every URDF joint (fixed ones included), in the model's order.
    pub joints: Vec<UrdfJoint>,
    /// What `from_urdf(..., repair=...)` changed, one record per link or welded joint.
    pub repairs: Vec<RepairRecord>,
}

impl JointRecords {
    pub fn new(joints: Vec<UrdfJoint>, repairs: Vec<RepairRecord>) -> Arc<Self> {
        Arc::new(JointRecords { joints, repairs })
    }
}

/// `<limit>` of a joint. A continuous joint has `lower = −∞`, `upper = +∞`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Limit {
    pub lower: f64,
    pub upper: f64,
    pub effort: f64,
    pub velocity: f64,
}

/// `<mimic joint multiplier offset>`: loaded as a coupling (`build::add_mimics`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Mimic {
    pub joint: String,
    pub multiplier: f64,
    pub offset: f64,
}

/// One URDF joint, in the model's order (depth first; the moving ones in q/v order).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UrdfJoint {
    pub name: String,
    /// "revolute", "continuous", "prismatic" or "fixed" (or "floating": the root joint a
    /// floating-base load adds, which is no element of the file).
    pub kind: &'static str,
    /// Parent and child link names.
    pub parent: String,
    pub child: String,
    /// Index of the child link's body in `model.bodies`.
    pub body: usize,
    /// The model link the child belongs to (`None`: welded to the world).
    pub link: Option<usize>,
    /// Position of this joint's coordinate in q and v (`None` for fixed joints).
    pub q_index: Option<usize>,
    pub v_index: Option<usize>,
    /// Unit axis in the joint frame (as given, or x, for fixed joints).
    pub axis: Vec3,
    pub limit: Option<Limit>,
    /// `<dynamics damping>` (N·m·s/rad or N·s/m) and `friction` (N·m or N); 0 when absent.
    pub damping: f64,
    pub friction: f64,
    pub mimic: Option<Mimic>,
}

/// A deserialised [`UrdfJoint`], its `kind` owned until matched to one of the four names.
#[derive(serde::Deserialize)]
struct UrdfJointData {
    name: String,
    kind: String,
    parent: String,
    child: String,
    body: usize,
    link: Option<usize>,
    q_index: Option<usize>,
    v_index: Option<usize>,
    axis: Vec3,
    limit: Option<Limit>,
    damping: f64,
    friction: f64,
    mimic: Option<Mimic>,
}

// By hand: a derived impl would require `'de: 'static` for the `&'static str`.
impl<'de> serde::Deserialize<'de> for UrdfJoint {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        <UrdfJointData as serde::Deserialize>::deserialize(d)?
            .try_into()
            .map_err(serde::de::Error::custom)
    }
}

impl TryFrom<UrdfJointData> for UrdfJoint {
    type Error = String;
    fn try_from(j: UrdfJointData) -> std::result::Result<UrdfJoint, String> {
        let kind = [
            "revolute",
            "continuous",
            "prismatic",
            "fixed",
            "floating",
            "spherical",
            "spherical_zyz",
        ]
        .into_iter()
        .find(|k| *k == j.kind)
        .ok_or_else(|| format!("joint '{}': unknown kind '{}'", j.name, j.kind))?;
        Ok(UrdfJoint {
            name: j.name,
            kind,
            parent: j.parent,
            child: j.child,
            body: j.body,
            link: j.link,
            q_index: j.q_index,
            v_index: j.v_index,
            axis: j.axis,
            limit: j.limit,
            damping: j.damping,
            friction: j.friction,
            mimic: j.mimic,
        })
    }
}

impl UrdfJoint {
    pub fn is_moving(&self) -> bool {
        self.kind != "fixed"
    }
}

/// One link changed by a repair.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RepairRecord {
    /// The link whose `<inertial>` changed, or the child link of a welded joint.
    pub link: String,
    /// The welded joint (`weld_massless`), else `None`.
    pub joint: Option<String>,
    /// The rules that changed it: "bound_mass", "bound_inertia", "balance_inertia",
    /// "weld_massless".
    pub rules: Vec<String>,
    /// Mass before and after (kg); equal when only the tensor changed.
    pub mass: (f64, f64),
    /// Principal moments about the COM before and after, ascending (kg m²).
    pub principal_moments: ([f64; 3], [f64; 3]),
    /// Joint type before and after (`weld_massless` only).
    pub joint_type: Option<(String, String)>,
}

impl RepairRecord {
    /// One line of the warning: `link 'x': balance_inertia: mass …; moments (…) → (…)`.
    pub fn describe(&self) -> String {
        if let (Some(j), Some((from, to))) = (&self.joint, &self.joint_type) {
            return format!(
                "joint '{j}' (child link '{}'): {}: {from} → {to} (it moves no mass)",
                self.link,
                self.rules.join(", ")
            );
        }
        let (m0, m1) = self.mass;
        let (a, b) = self.principal_moments;
        let mass = if m0 == m1 {
            format!("mass {m0:e}")
        } else {
            format!("mass {m0:e} → {m1:e}")
        };
        format!(
            "link '{}': {}: {mass}; principal moments ({:.6e}, {:.6e}, {:.6e}) → ({:.6e}, {:.6e}, {:.6e})",
            self.link,
            self.rules.join(", "),
            a[0],
            a[1],
            a[2],
            b[0],
            b[1],
            b[2]
        )
    }
}

impl crate::model::Model {
    /// The source file's joint of each moving link, in q/v order (`None` for a link built
    /// body by body): one pass, not a search per link.
    pub fn link_joints(&self) -> impl Iterator<Item = Option<&UrdfJoint>> + '_ {
        let by_body: std::collections::HashMap<usize, &UrdfJoint> =
            self.records.joints.iter().map(|j| (j.body, j)).collect();
        self.links
            .iter()
            .map(move |l| by_body.get(&l.body).copied())
    }

    /// Names of the moving joints in q/v order: the source file's joint names, otherwise the
    /// names of the bodies that define each link.
    pub fn joint_names(&self) -> Vec<String> {
        self.links
            .iter()
            .zip(self.link_joints())
            .map(|(l, joint)| match joint {
                Some(j) => j.name.clone(),
                None => self.bodies[l.body].name.clone(),
            })
            .collect()
    }
}
