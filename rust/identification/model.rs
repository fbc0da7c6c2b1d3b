//! The identified model: each identified link's body from its ten parameters (on the body
//! that defines the link; the bodies welded to it then carry nothing, their share being in
//! the estimate), validated as any body.
use super::regressor::NPARAM;
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Mat3, Vec3};

/// Mass, centre of mass and inertia about it from ten parameters (Pinocchio's order).
pub fn body_from_parameters(p: &[f64]) -> (f64, Vec3, Mat3) {
    let m = p[0];
    let c = if m != 0.0 {
        Vec3::new(p[1], p[2], p[3]) / m
    } else {
        Vec3::zeros()
    };
    let io = Mat3::new(p[4], p[5], p[7], p[5], p[6], p[8], p[7], p[8], p[9]);
    let ic = io - (Mat3::identity() * c.norm_squared() - c * c.transpose()) * m;
    (m, c, ic)
}

/// A copy of `model` with links `links` given the parameters `pi` (10 per link, all links)
/// and, when given, the armature of every 1-dof joint (v order of
/// [`super::regressor::extra_joints`]).
pub fn identified_model(
    model: &Model,
    pi: &[f64],
    links: &[usize],
    armature: Option<&[f64]>,
) -> Result<Model> {
    let n = model.links.len();
    if pi.len() < NPARAM * n || links.iter().any(|&l| l >= n) {
        let expected = format!("{} values and link indices below {n}", NPARAM * n);
        let got = format!("{} values, links {links:?}", pi.len());
        return Err(Error::arg("parameters", expected, got));
    }
    let mut out = model.clone();
    for &l in links {
        let (m, c, ic) = body_from_parameters(&pi[NPARAM * l..NPARAM * (l + 1)]);
        let own = model.links[l].body;
        let body = RigidBody::new(m, c, ic).map_err(|e| {
            Error::inertia(
                "parameters",
                format!(
                    "the estimate of body '{}' is not a rigid body: {e}",
                    model.bodies[own].name
                ),
            )
        })?;
        for (b, rec) in model.bodies.iter().enumerate() {
            if rec.link == Some(l) && b != own {
                out.set_body_inertial(
                    b,
                    RigidBody {
                        mass: 0.0,
                        com: Vec3::zeros(),
                        inertia: Mat3::zeros(),
                    },
                );
            }
        }
        out.set_body_inertial(own, body);
        out.set_link_body(l, body)?;
    }
    if let Some(arm) = armature {
        let joints = super::regressor::extra_joints(model);
        for (k, &v) in joints.iter().enumerate() {
            let l = model
                .links
                .iter()
                .position(|l| l.v_index == v)
                .unwrap_or_default();
            out.set_armature(model.links[l].body, &[arm[k].max(0.0)])?;
        }
    }
    Ok(out)
}
