//! Fixed joint: no coordinates; the body is welded to its parent (the model merges it into
//! the parent's link, so the recursions meet it only as a link's first joint).
use super::{JointType, LocalMotion, MotionClass, Subspace};
use crate::support::spatial::{Mat3, Vec3, Vec6};

pub struct Fixed;

impl JointType for Fixed {
    const NAME: &'static str = "Fixed";
    const NQ: usize = 0;
    const MOTION: MotionClass = MotionClass::Rigid;
    const URDF_TYPE: &'static str = "fixed";

    fn q_is_angle(&self, _k: usize) -> bool {
        false
    }
    fn transform(&self, _q: &[f64]) -> (Mat3, Vec3) {
        (Mat3::identity(), Vec3::zeros())
    }
    fn subspace(&self, _q: &[f64], _r_joint: &Mat3, _r_body: &Mat3) -> Subspace {
        [Vec6::zeros(); 6]
    }
    fn subspace_rate(
        &self,
        _q: &[f64],
        _v: &[f64],
        _s: &Subspace,
        _r: &Mat3,
        _wp: &Vec3,
        _wb: &Vec3,
    ) -> Subspace {
        [Vec6::zeros(); 6]
    }
    fn local_columns(&self) -> [Vec3; 3] {
        [Vec3::zeros(); 3]
    }
    fn local_motion(&self, _q: &[f64], _v: &[f64]) -> LocalMotion {
        LocalMotion::default()
    }
}
