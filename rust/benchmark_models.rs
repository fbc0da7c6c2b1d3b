//! The models every benchmark uses (docs/benchmarks.md), so figures are comparable across tools.
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::spatial::{Mat3, Placement, Vec3};

fn chain_link() -> RigidBody {
    RigidBody {
        mass: 1.0,
        com: Vec3::new(0.15, 0.0, 0.0),
        inertia: Mat3::from_diagonal(&Vec3::new(1e-3, 7.5e-3, 7.5e-3)),
    }
}

/// `chainN`: N revolute joints in series, axes alternating y, z, … (joint 0 about y), joint k
/// at (0.3, 0, 0) in body k−1; each body 1 kg, COM (0.15, 0, 0), inertia diag(1e-3, 7.5e-3,
/// 7.5e-3). Start state: q = 0.3 rad for every joint, v = 0.
pub fn chain(n: usize) -> Model {
    let mut model = Model::new();
    let mut parent = None;
    for k in 0..n {
        let axis = if k % 2 == 0 { Vec3::y() } else { Vec3::z() };
        let t = if k == 0 {
            Vec3::zeros()
        } else {
            Vec3::new(0.3, 0.0, 0.0)
        };
        let idx = model
            .add_body(
                chain_link(),
                Joint::Revolute { axis },
                parent,
                Placement::new(Mat3::identity(), t),
                None,
                None,
            )
            .expect("valid chain link");
        parent = Some(idx);
    }
    model
}

/// A branched tree: `branches` chains of `depth` links hanging from one spherical base link.
pub fn tree(branches: usize, depth: usize) -> Model {
    let mut model = Model::new();
    let base = model
        .add_body(
            chain_link(),
            Joint::Spherical,
            None,
            Placement::identity(),
            None,
            None,
        )
        .expect("valid base");
    for b in 0..branches {
        let angle = 2.0 * std::f64::consts::PI * b as f64 / branches as f64;
        let mut parent = base;
        for k in 0..depth {
            let axis = if k % 2 == 0 { Vec3::y() } else { Vec3::z() };
            let t = if k == 0 {
                Vec3::new(0.1 * angle.cos(), 0.1 * angle.sin(), -0.05)
            } else {
                Vec3::new(0.3, 0.0, 0.0)
            };
            let rot = if k == 0 {
                crate::joint::rot_z(angle)
            } else {
                Mat3::identity()
            };
            parent = model
                .add_body(
                    chain_link(),
                    Joint::Revolute { axis },
                    Some(parent),
                    Placement::new(rot, t),
                    None,
                    None,
                )
                .expect("valid branch link");
        }
    }
    model
}

/// The paper's pendulum: a rod (m = 2.51 kg, a = 1 m, d = 0.02 m) on a ZYZ spherical joint,
/// seven-point box centred at the far end.
pub fn paper_pendulum() -> Model {
    let (m, a, d) = (2.51, 1.0, 0.02);
    let rod = RigidBody {
        mass: m,
        com: Vec3::new(a / 2.0, 0.0, 0.0),
        inertia: Mat3::from_diagonal(&Vec3::new(
            m * d * d / 8.0,
            m * d * d / 16.0 + m * a * a / 12.0,
            m * d * d / 16.0 + m * a * a / 12.0,
        )),
    };
    let mut model = Model::new();
    model
        .add_body(
            rod,
            Joint::SphericalZYZ,
            None,
            Placement::identity(),
            Some("rod".into()),
            Some(Vec3::new(a, 0.0, 0.0)),
        )
        .expect("valid pendulum");
    model
}
