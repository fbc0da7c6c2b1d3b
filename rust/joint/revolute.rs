//! Revolute joint: one angle `q` about a fixed unit axis `a` of the joint frame; the body
//! turns by `R_a(q)` (Rodrigues), its origin stays at the joint frame's. `P = [a; 0]` in the
//! joint frame (docs/method.md §2).
use super::{turn_columns, JointType, LocalMotion, MotionClass, Subspace};
use crate::joint::rotation::axis_angle;
use crate::support::spatial::{stack, Mat3, Vec3, Vec6};

pub struct Revolute {
    pub axis: Vec3,
}

impl JointType for Revolute {
    const NAME: &'static str = "Revolute";
    const NQ: usize = 1;
    const MOTION: MotionClass = MotionClass::Angular1;
    const URDF_TYPE: &'static str = "revolute";

    fn q_is_angle(&self, _k: usize) -> bool {
        true
    }
    fn revolute_axis(&self) -> Option<Vec3> {
        Some(self.axis)
    }
    fn axis(&self) -> Option<Vec3> {
        Some(self.axis)
    }
    fn pin(&self) -> Option<Vec3> {
        Some(self.axis)
    }
    #[inline]
    fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        (axis_angle(&self.axis, q[0]), Vec3::zeros())
    }
    #[inline]
    fn subspace(&self, _q: &[f64], r_joint: &Mat3, _r_body: &Mat3) -> Subspace {
        let mut s = [Vec6::zeros(); 6];
        s[0] = stack(&(r_joint * self.axis), &Vec3::zeros());
        s
    }
    /// The axis is fixed in the joint frame: it turns with the parent.
    #[inline]
    fn subspace_rate(
        &self,
        _q: &[f64],
        _v: &[f64],
        s: &Subspace,
        _r: &Mat3,
        w_parent: &Vec3,
        _w_body: &Vec3,
    ) -> Subspace {
        turn_columns::<1>(s, w_parent, true)
    }
    fn local_columns(&self) -> [Vec3; 3] {
        [self.axis, Vec3::zeros(), Vec3::zeros()]
    }
    /// The axis is the same in the joint and the body frame (the turn keeps it).
    #[inline]
    fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion {
        LocalMotion {
            rotation: Some(axis_angle(&self.axis, q[0])),
            w: self.axis * v[0],
            ..LocalMotion::default()
        }
    }
}
