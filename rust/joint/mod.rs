//! Joints: what each joint type does, in one place per type. A joint gives its local
//! transform, its motion columns (the joint-motion propagation matrix `P`, docs/method.md
//! §2) and their rate, in world axes for the reference recursions and in body axes for the
//! body-frame ones, its joint velocity and velocity-product term, which coordinates are
//! angles, and how `q` moves with `v`. Every recursion asks the joint (through [`Joint`]'s
//! methods, which dispatch once to the type's [`JointType`] implementation) rather than
//! matching on it.
//!
//! Coordinates follow Pinocchio so models compare one to one (docs/conventions.md): a
//! revolute/prismatic `q` is the angle/displacement along the axis given in the joint frame;
//! `Spherical` stores a unit quaternion `(x, y, z, w)` and its 3 speeds are the body's
//! angular velocity relative to its parent, in the body frame; `FreeFlyer` stores the body
//! origin then such a quaternion, with the linear then angular velocity in body axes as its
//! six speeds (Pinocchio's `JointModelFreeFlyer`); `SphericalZYZ` is the paper's
//! Euler-angle joint with Euler rates as speeds (singular where sin θ = 0).
//!
//! Adding a joint type: a file here implementing [`JointType`] (with its tests), a variant
//! of [`Joint`] and its line in `dispatch!`, and a constructor; docs/adding-a-joint.md.
mod fixed;
mod free_flyer;
mod prismatic;
mod quaternion;
mod revolute;
pub mod rotation;
mod spherical;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod toy_cardan;
mod zyz;

use crate::support::error::{Error, Result};
use crate::support::spatial::{stack, Mat3, Vec3, Vec6};
use nalgebra::DMatrixViewMut;

pub use rotation::{axis_angle, quat_to_matrix, rot_x, rot_y, rot_z};
pub use zyz::{zyz_rate_matrix, ZYZ_SINGULAR_SIN};

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Joint {
    Revolute {
        axis: Vec3,
    },
    Prismatic {
        axis: Vec3,
    },
    SphericalZYZ,
    Spherical,
    Fixed,
    FreeFlyer,
    #[cfg(test)]
    ToyCardan,
}

/// Columns of `P` (world coordinates), `dof` of them in use.
pub type Subspace = [Vec6; 6];

/// How a joint moves its body, as the body-frame recursions need to know: along one angular
/// or one linear axis, about three angular axes, freely (all six), or not at all. Every
/// joint but the free flyer moves along a purely angular or purely linear subspace
/// (`P = [A; 0]` or `[0; A]`); the free flyer's columns are the body's six unit twists.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionClass {
    Rigid,
    Angular1,
    Linear1,
    Angular3,
    /// Six speeds, linear (body axes) then angular (body axes): `S = 1₆`.
    Free,
}

impl MotionClass {
    pub const fn nv(self) -> usize {
        match self {
            MotionClass::Rigid => 0,
            MotionClass::Angular1 | MotionClass::Linear1 => 1,
            MotionClass::Angular3 => 3,
            MotionClass::Free => 6,
        }
    }
    /// Whether the motion moves the body origin in the joint frame.
    pub const fn translates(self) -> bool {
        matches!(self, MotionClass::Linear1 | MotionClass::Free)
    }
    /// Angular motion columns (`[A; 0]`); false for linear motion and for the free flyer,
    /// whose columns are both (code that reads this handles `Free` first).
    pub const fn angular(self) -> bool {
        !matches!(self, MotionClass::Linear1 | MotionClass::Free)
    }
}

/// A joint's own motion at `(q, v)` in the body-frame recursion: everything in the joint's
/// body axes. `None` means "the identity / zero / the constant columns", which the caller
/// skips.
#[derive(Debug, Clone, Copy, Default)]
pub struct LocalMotion {
    /// Body axes in joint-frame axes.
    pub rotation: Option<Mat3>,
    /// Body origin in the joint frame.
    pub displacement: Option<Vec3>,
    /// Motion columns (their angular part, or linear part for linear motion) when they
    /// depend on `q`; otherwise [`JointType::local_columns`].
    pub columns: Option<[Vec3; 3]>,
    /// Relative angular velocity `w_J = S q̇` (angular motion).
    pub w: Vec3,
    /// Relative linear velocity `v_J` (linear motion).
    pub v: Vec3,
    /// `Ṡ q̇`, the velocity-product term of the columns (angular part).
    pub sdot_qd: Vec3,
}

/// A joint's rows of a row-major matrix with `stride` columns (the state Jacobian of
/// `ẏ = [q̇(q, v); v̇]`): entry `(r, c)` of its `q` columns is `data[(row + r) stride + cq + c]`,
/// of its `v` columns `data[(row + r) stride + cv + c]`.
pub struct JacobianRows<'a> {
    pub data: &'a mut [f64],
    pub stride: usize,
    pub row: usize,
    pub cq: usize,
    pub cv: usize,
}

impl JacobianRows<'_> {
    #[inline]
    pub fn set_q(&mut self, r: usize, c: usize, x: f64) {
        self.data[(self.row + r) * self.stride + self.cq + c] = x;
    }
    #[inline]
    pub fn set_v(&mut self, r: usize, c: usize, x: f64) {
        self.data[(self.row + r) * self.stride + self.cv + c] = x;
    }
}

/// One joint type: everything the model, the recursions and the loaders need to know of it.
pub trait JointType {
    /// The name in files, messages and `repr`.
    const NAME: &'static str;
    const NQ: usize;
    const MOTION: MotionClass;
    /// Whether each motion column is fixed in the frame of the joint's earlier coordinates (a
    /// chain of single-axis rotations, as ZYZ angles) instead of all in one frame that moves
    /// with them together (the derivatives of the recursions differ).
    const CHAINED_COLUMNS: bool = false;

    /// Its `type` in a URDF `<joint>` and in the joint records of a model (`UrdfJoint::kind`,
    /// what the MuJoCo and Pinocchio importers hand over).
    const URDF_TYPE: &'static str;
    /// Where its unit quaternion starts in its `q`, if it has one (normalisation, the
    /// integrator and `assemble` keep it on its manifold).
    const QUATERNION_AT: Option<usize> = None;

    /// The axis of a rotation about one axis fixed in the joint frame (the compiled
    /// recursions specialise it when it is a coordinate axis); `None` for other motions.
    fn revolute_axis(&self) -> Option<Vec3> {
        None
    }
    /// Its parameter: the unit axis (joint frame) a scene file, a URDF record and Python's
    /// `Joint.axis` give for it; `None` for a joint without one.
    fn axis(&self) -> Option<Vec3> {
        None
    }
    /// The pin through its body that a design keeps material around (docs/design.md): the
    /// hinge's axis (joint frame), zero for a ball joint; `None` for a joint without a pin.
    fn pin(&self) -> Option<Vec3> {
        None
    }
    /// `out = q ⊕ δ` on this joint's coordinates (`δ` its nv tangent directions): the sum
    /// where `q` is a vector space.
    fn integrate(&self, q: &[f64], delta: &[f64], out: &mut [f64]) {
        for ((o, q), d) in out.iter_mut().zip(q).zip(delta) {
            *o = q + d;
        }
    }
    /// This joint's block of `T = ∂δ/∂q` (nv × nq, zero on entry): the identity where `q` is a
    /// vector space.
    fn tangent_map(&self, _q: &[f64], t: &mut DMatrixViewMut<'_, f64>) {
        for k in 0..Self::MOTION.nv() {
            t[(k, k)] = 1.0;
        }
    }
    /// This joint's rows of `∂q̇/∂q` and `∂q̇/∂v` (zero on entry): `q̇ = v` where `q` is a
    /// vector space.
    fn qdot_jacobian(&self, _q: &[f64], _v: &[f64], jac: &mut JacobianRows<'_>) {
        for k in 0..Self::MOTION.nv() {
            jac.set_v(k, k, 1.0);
        }
    }

    /// The neutral configuration (zero angles, identity quaternion).
    fn neutral(&self, q: &mut [f64]) {
        q.fill(0.0);
    }
    /// Whether coordinate `k` of `q` is an angle (scaled by a file's angle unit).
    fn q_is_angle(&self, k: usize) -> bool;
    /// Rotation and translation of the body frame in the joint frame at `q`.
    fn transform(&self, q: &[f64]) -> (Mat3, Vec3);
    /// Columns of `P` in world coordinates. `r_joint` is the joint frame's orientation (the
    /// parent's orientation times the fixed placement), `r_body` the body's.
    fn subspace(&self, q: &[f64], r_joint: &Mat3, r_body: &Mat3) -> Subspace;
    /// Time derivative of [`subspace`](JointType::subspace), given the parent's angular
    /// velocity `w_parent`, the body's `w_body` and the joint speeds `v`.
    fn subspace_rate(
        &self,
        q: &[f64],
        v: &[f64],
        s: &Subspace,
        r_joint: &Mat3,
        w_parent: &Vec3,
        w_body: &Vec3,
    ) -> Subspace;
    /// Motion columns in body axes when they do not depend on `q`.
    fn local_columns(&self) -> [Vec3; 3];
    /// The joint's motion in body axes (see [`LocalMotion`]).
    fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion;
    /// `q̇` from the speeds `v` (equal unless `q` is not a vector space, as a quaternion).
    fn velocity_to_qdot(&self, _q: &[f64], v: &[f64], qdot: &mut [f64]) {
        qdot.copy_from_slice(v);
    }
    /// Checks what a finite configuration's coordinates need beyond finiteness (a unit
    /// quaternion's norm); finiteness is the caller's check, once for all of `q`.
    fn check_configuration(&self, _q: &[f64], _arg: &str) -> Result<()> {
        Ok(())
    }
    /// `Some(measure)` when `q` is at (or too near) a coordinate singularity.
    fn singularity(&self, _q: &[f64]) -> Option<f64> {
        None
    }
    /// What is wrong at a singular `q` (`q_index`: the joint's first coordinate).
    fn describe_singularity(&self, _q: &[f64], _q_index: usize) -> String {
        String::new()
    }
}

/// Columns fixed in a frame turning at `w` change as `w ×` them (first `N` in use).
#[inline]
pub(crate) fn turn_columns<const N: usize>(s: &Subspace, w: &Vec3, angular_part: bool) -> Subspace {
    let mut d = [Vec6::zeros(); 6];
    let z = Vec3::zeros();
    for k in 0..N {
        d[k] = if angular_part {
            stack(&w.cross(&s[k].fixed_rows::<3>(0).into_owned()), &z)
        } else {
            stack(&z, &w.cross(&s[k].fixed_rows::<3>(3).into_owned()))
        };
    }
    d
}

/// Runs `$body` with `$j` bound to the joint's [`JointType`]: the one place that matches on
/// the joint type.
macro_rules! dispatch {
    ($joint:expr, $j:ident => $body:expr) => {
        match $joint {
            Joint::Revolute { axis } => {
                let $j = revolute::Revolute { axis: *axis };
                $body
            }
            Joint::Prismatic { axis } => {
                let $j = prismatic::Prismatic { axis: *axis };
                $body
            }
            Joint::SphericalZYZ => {
                let $j = zyz::SphericalZyz;
                $body
            }
            Joint::Spherical => {
                let $j = spherical::Spherical;
                $body
            }
            Joint::Fixed => {
                let $j = fixed::Fixed;
                $body
            }
            Joint::FreeFlyer => {
                let $j = free_flyer::FreeFlyer;
                $body
            }
            #[cfg(test)]
            Joint::ToyCardan => {
                let $j = toy_cardan::ToyCardan;
                $body
            }
        }
    };
}

/// The type's constants, without a value of it.
fn constants<J: JointType>(_: &J) -> (&'static str, usize, MotionClass) {
    (J::NAME, J::NQ, J::MOTION)
}

fn chained_columns<J: JointType>(_: &J) -> bool {
    J::CHAINED_COLUMNS
}

fn urdf_type<J: JointType>(_: &J) -> &'static str {
    J::URDF_TYPE
}

fn quaternion_at<J: JointType>(_: &J) -> Option<usize> {
    J::QUATERNION_AT
}

fn unit_axis(axis: Vec3) -> Result<Vec3> {
    let largest = axis.amax();
    if !axis.iter().all(|x| x.is_finite()) || largest == 0.0 {
        return Err(Error::arg(
            "axis",
            "a finite, non-zero 3-vector",
            format!("[{}, {}, {}]", axis.x, axis.y, axis.z),
        ));
    }
    let n = axis.norm();
    if n.is_finite() && n > 1e-100 {
        return Ok(axis / n);
    }
    // The squares overflow (|x| > 1e154) or underflow: divide by the largest entry first.
    let scaled = axis / largest;
    Ok(scaled / scaled.norm())
}

impl Joint {
    pub fn revolute(axis: Vec3) -> Result<Joint> {
        Ok(Joint::Revolute {
            axis: unit_axis(axis)?,
        })
    }
    pub fn prismatic(axis: Vec3) -> Result<Joint> {
        Ok(Joint::Prismatic {
            axis: unit_axis(axis)?,
        })
    }

    /// The joint type's name ("Revolute", "SphericalZYZ", ...).
    pub fn kind(&self) -> &'static str {
        dispatch!(self, j => constants(&j).0)
    }
    #[inline]
    pub fn nq(&self) -> usize {
        dispatch!(self, j => constants(&j).1)
    }
    #[inline]
    pub fn nv(&self) -> usize {
        self.motion().nv()
    }
    #[inline]
    pub fn motion(&self) -> MotionClass {
        dispatch!(self, j => constants(&j).2)
    }
    /// Its `type` in URDF and in a model's joint records ("revolute", "floating", ...).
    pub fn urdf_type(&self) -> &'static str {
        dispatch!(self, j => urdf_type(&j))
    }
    /// See [`JointType::axis`].
    pub fn axis(&self) -> Option<Vec3> {
        dispatch!(self, j => j.axis())
    }
    /// See [`JointType::pin`].
    pub fn pin(&self) -> Option<Vec3> {
        dispatch!(self, j => j.pin())
    }
    /// How Python shows it: `Revolute(axis=[0, 0, 1])`, `Spherical()`.
    pub fn repr(&self) -> String {
        match self.axis() {
            Some(a) => format!("{}(axis=[{}, {}, {}])", self.kind(), a.x, a.y, a.z),
            None => format!("{}()", self.kind()),
        }
    }
    /// Whether its transform moves the body origin (linear motion, the free flyer): the
    /// kinematics add the transform's translation only then.
    #[inline]
    pub fn translates(&self) -> bool {
        self.motion().translates()
    }
    /// Whether the joint's motion subspace is purely angular (`P = [A; 0]`): true for every
    /// joint but `Prismatic` (purely linear) and `FreeFlyer` (both).
    #[inline]
    pub fn moves_angular(&self) -> bool {
        self.motion().angular()
    }
    /// Whether coordinate `k` of this joint's `q` is an angle (scaled by a file's angle
    /// unit): revolute and ZYZ angles are; quaternion parts and displacements are not.
    #[inline]
    pub fn q_is_angle(&self, k: usize) -> bool {
        k < self.nq() && dispatch!(self, j => j.q_is_angle(k))
    }
    /// Whether speed `k` of this joint is an angular rate (every speed of every joint
    /// but `Prismatic`; the last three of a `FreeFlyer`).
    #[inline]
    pub fn v_is_angular(&self, k: usize) -> bool {
        match self.motion() {
            MotionClass::Free => (3..6).contains(&k),
            m => k < m.nv() && m.angular(),
        }
    }
    pub fn neutral(&self, q: &mut [f64]) {
        dispatch!(self, j => j.neutral(q))
    }
    /// Rotation and translation of the body frame in the joint frame at configuration `q`.
    #[inline]
    pub fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        dispatch!(self, j => j.transform(q))
    }
    /// See [`JointType::subspace`].
    #[inline]
    pub fn subspace(&self, q: &[f64], r_joint: &Mat3, r_body: &Mat3) -> Subspace {
        dispatch!(self, j => j.subspace(q, r_joint, r_body))
    }
    /// See [`JointType::subspace_rate`]: axes fixed in the joint frame turn with the parent;
    /// the quaternion joint's columns turn with the body; the ZYZ columns also change with φ
    /// and θ.
    #[inline]
    pub fn subspace_rate(
        &self,
        q: &[f64],
        v: &[f64],
        s: &Subspace,
        r_joint: &Mat3,
        w_parent: &Vec3,
        w_body: &Vec3,
    ) -> Subspace {
        dispatch!(self, j => j.subspace_rate(q, v, s, r_joint, w_parent, w_body))
    }
    /// See [`JointType::local_columns`].
    pub fn local_columns(&self) -> [Vec3; 3] {
        dispatch!(self, j => j.local_columns())
    }
    /// See [`JointType::local_motion`].
    #[inline]
    pub fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion {
        dispatch!(self, j => j.local_motion(q, v))
    }
    /// See [`JointType::CHAINED_COLUMNS`].
    #[inline]
    pub fn chained_columns(&self) -> bool {
        dispatch!(self, j => chained_columns(&j))
    }
    /// See [`JointType::revolute_axis`].
    pub fn revolute_axis(&self) -> Option<Vec3> {
        dispatch!(self, j => j.revolute_axis())
    }
    /// See [`JointType::integrate`].
    pub fn integrate(&self, q: &[f64], delta: &[f64], out: &mut [f64]) {
        dispatch!(self, j => j.integrate(q, delta, out))
    }
    /// See [`JointType::tangent_map`].
    pub fn tangent_map(&self, q: &[f64], t: &mut DMatrixViewMut<'_, f64>) {
        dispatch!(self, j => j.tangent_map(q, t))
    }
    /// See [`JointType::qdot_jacobian`].
    pub fn qdot_jacobian(&self, q: &[f64], v: &[f64], jac: &mut JacobianRows<'_>) {
        dispatch!(self, j => j.qdot_jacobian(q, v, jac))
    }
    /// Where this joint's unit quaternion starts in its `q`, if it has one.
    #[inline]
    pub fn quaternion_at(&self) -> Option<usize> {
        dispatch!(self, j => quaternion_at(&j))
    }
    /// `q̇` from the speeds `v` (they differ only for the quaternion joints).
    pub fn velocity_to_qdot(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) {
        dispatch!(self, j => j.velocity_to_qdot(q, v, qdot))
    }
    /// Checks a configuration: finite, and a quaternion of usable norm.
    pub fn check_configuration(&self, q: &[f64], arg: &str) -> Result<()> {
        dispatch!(self, j => j.check_configuration(q, arg))
    }
    /// `Some(measure)` when this joint is at (or too near) its coordinate singularity
    /// (`sin θ` for ZYZ).
    #[inline]
    pub fn singularity(&self, q: &[f64]) -> Option<f64> {
        dispatch!(self, j => j.singularity(q))
    }
    /// What is wrong at a singular `q` (see [`JointType::describe_singularity`]).
    pub fn describe_singularity(&self, q: &[f64], q_index: usize) -> String {
        dispatch!(self, j => j.describe_singularity(q, q_index))
    }
}
