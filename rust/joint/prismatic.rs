//! Prismatic joint: one displacement `q` along a fixed unit axis `a` of the joint frame; the
//! body does not turn. `P = [0; a]` (docs/method.md §2).
use super::{turn_columns, JointType, LocalMotion, MotionClass, Subspace};
use crate::support::spatial::{stack, Mat3, Vec3, Vec6};

pub struct Prismatic {
    pub axis: Vec3,
}

impl JointType for Prismatic {
    const NAME: &'static str = "Prismatic";
    const NQ: usize = 1;
    const MOTION: MotionClass = MotionClass::Linear1;
    const URDF_TYPE: &'static str = "prismatic";

    fn axis(&self) -> Option<Vec3> {
        Some(self.axis)
    }
    fn q_is_angle(&self, _k: usize) -> bool {
        false
    }
    #[inline]
    fn transform(&self, q: &[f64]) -> (Mat3, Vec3) {
        (Mat3::identity(), self.axis * q[0])
    }
    #[inline]
    fn subspace(&self, _q: &[f64], r_joint: &Mat3, _r_body: &Mat3) -> Subspace {
        let mut s = [Vec6::zeros(); 6];
        s[0] = stack(&Vec3::zeros(), &(r_joint * self.axis));
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
        turn_columns::<1>(s, w_parent, false)
    }
    fn local_columns(&self) -> [Vec3; 3] {
        [self.axis, Vec3::zeros(), Vec3::zeros()]
    }
    #[inline]
    fn local_motion(&self, q: &[f64], v: &[f64]) -> LocalMotion {
        LocalMotion {
            displacement: Some(self.axis * q[0]),
            v: self.axis * v[0],
            ..LocalMotion::default()
        }
    }
}
