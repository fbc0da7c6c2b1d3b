//! A scene's `[[body]]` entries: each added to the model below its parent, with its initial
//! state in the file's units. Errors name the key `body[k] ('name').field`.
use super::{BodyFile, Ctx, JointFile, Units};
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Mat3, Placement, Vec3};

/// Adds every body to `model` and appends its joint's initial q and v to `q0`, `v0`.
pub(super) fn add_bodies(
    ctx: &Ctx,
    model: &mut Model,
    bodies: &[BodyFile],
    units: Units,
    q0: &mut Vec<f64>,
    v0: &mut Vec<f64>,
) -> Result<()> {
    let mut massless = Vec::new();
    for (k, b) in bodies.iter().enumerate() {
        let at = At {
            ctx,
            k,
            name: &b.name,
        };
        let (joint, without_mass) = add_body(&at, model, b, units)?;
        if without_mass {
            massless.push(k);
        }
        let (q, v) = initial_coordinates(&at, b, &joint, units)?;
        q0.extend(q);
        v0.extend(v);
    }
    sum_massless_links(ctx, model, bodies, &massless)
}

/// The links holding a body of mass 0 (added with a placeholder, as the URDF loader does)
/// take the sum of their bodies' own inertials; a link left without mass needs links with
/// mass below it, or its joint's acceleration is undetermined.
fn sum_massless_links(
    ctx: &Ctx,
    model: &mut Model,
    bodies: &[BodyFile],
    massless: &[usize],
) -> Result<()> {
    if massless.is_empty() {
        return Ok(());
    }
    let merged = model.link_bodies();
    let mut below = vec![0.0; merged.len()];
    for l in (0..merged.len()).rev() {
        if let Some(p) = model.links[l].parent {
            below[p] += below[l] + merged[l].mass;
        }
    }
    let mut done = vec![false; merged.len()];
    for &k in massless {
        let Some(l) = model.bodies[k].link.filter(|&l| !done[l]) else {
            continue;
        };
        done[l] = true;
        let at = At {
            ctx,
            k,
            name: &bodies[k].name,
        };
        if merged[l].mass <= 0.0 && below[l] <= 0.0 {
            return Err(at.err(
                "mass",
                "mass 0 on a moving body with no body with mass below it: its joint moves nothing (give it a mass > 0)",
            ));
        }
        model
            .set_link_body(l, merged[l])
            .map_err(|e| at.core("inertia", e))?;
    }
    Ok(())
}

/// Error builder for the keys of body `k`.
struct At<'a> {
    ctx: &'a Ctx<'a>,
    k: usize,
    name: &'a str,
}

impl At<'_> {
    fn key(&self, field: &str) -> String {
        format!("body[{}] ('{}').{field}", self.k, self.name)
    }
    fn err(&self, field: &str, message: impl Into<String>) -> Error {
        self.ctx.err(self.key(field), message)
    }
    fn core(&self, field: &str, e: Error) -> Error {
        self.ctx.core(self.key(field), e)
    }
}

/// The field a core error is about: the argument it names if it is an invalid argument, or
/// an invalid inertia (with `inertia`) or model (without); else `default`.
fn field_of(e: &Error, inertia: bool, default: &str) -> String {
    match e {
        Error::InvalidArgument { arg, .. } => arg.clone(),
        Error::InvalidInertia { arg, .. } if inertia => arg.clone(),
        Error::InvalidModel { arg, .. } if !inertia => arg.clone(),
        _ => default.into(),
    }
}

/// Adds body `b`; returns its joint and whether it has mass 0.
fn add_body(at: &At, model: &mut Model, b: &BodyFile, units: Units) -> Result<(Joint, bool)> {
    let parent = match b.parent.as_deref() {
        None | Some("world") => None,
        Some(p) => Some(model.body_index(p).ok_or_else(|| {
            at.err(
                "parent",
                format!("no body named '{p}' before this one (bodies must follow their parents; 'world' is the ground)"),
            )
        })?),
    };
    let joint = match &b.joint {
        JointFile::Revolute { axis } => Joint::revolute(Vec3::from(*axis)),
        JointFile::Prismatic { axis } => Joint::prismatic(Vec3::from(*axis)),
        JointFile::SphericalZYZ => Ok(Joint::SphericalZYZ),
        JointFile::Spherical => Ok(Joint::Spherical),
        JointFile::Fixed => Ok(Joint::Fixed),
        JointFile::FreeFlyer => Ok(Joint::FreeFlyer),
    }
    .map_err(|e| at.core("joint.axis", e))?;
    let rotation = match (b.rotation, b.rpy) {
        (Some(_), Some(_)) => {
            return Err(at.err("rotation", "give either rotation or rpy, not both"))
        }
        (Some(r), None) => Mat3::from_row_slice(&r.concat()),
        (None, Some(rpy)) => crate::io::urdf::rpy_matrix(&(Vec3::from(rpy) * units.angle)),
        (None, None) => Mat3::identity(),
    };
    let (body, massless) = rigid_body(at, b)?;
    let placement = Placement::new(rotation, Vec3::from(b.translation.unwrap_or([0.0; 3])));
    let center = b.point_mass_center.map(Vec3::from);
    // `add_body` merges welded bodies with mass > 0: a massless one gets a placeholder and
    // its own inertial after (`sum_massless_links`).
    let placeholder = RigidBody {
        mass: 1.0,
        com: Vec3::zeros(),
        inertia: Mat3::identity(),
    };
    let added = if massless { placeholder } else { body };
    let index = model
        .add_body(
            added,
            joint,
            parent,
            placement,
            Some(b.name.clone()),
            center,
        )
        .map_err(|e| at.core(&field_of(&e, false, ""), e))?;
    if massless {
        model.set_body_inertial(index, body);
    }
    Ok((joint, massless))
}

/// `mass`, `com` and `inertia` (3x3 about the COM) or `inertia_diag`, and whether the mass
/// is 0 (a massless intermediate body, as a URDF's: then without rotational inertia).
fn rigid_body(at: &At, b: &BodyFile) -> Result<(RigidBody, bool)> {
    let inertia = match (b.inertia, b.inertia_diag) {
        (Some(_), Some(_)) => {
            return Err(at.err("inertia", "give either inertia or inertia_diag, not both"))
        }
        (Some(i), None) => Mat3::from_row_slice(&i.concat()),
        (None, Some(d)) => Mat3::from_diagonal(&Vec3::from(d)),
        (None, None) => {
            return Err(at.err(
                "inertia",
                "missing: give inertia (3x3, about the COM) or inertia_diag",
            ))
        }
    };
    let com = Vec3::from(b.com.unwrap_or([0.0; 3]));
    if b.mass == 0.0 {
        crate::support::error::check_finite("com", com.as_slice())
            .map_err(|e| at.core("com", e))?;
        if inertia.abs().max() > 0.0 {
            return Err(at.err(
                "inertia",
                "a body of mass 0 needs a zero inertia (seven point masses cannot carry one)",
            ));
        }
        return Ok((
            RigidBody {
                mass: 0.0,
                com,
                inertia,
            },
            true,
        ));
    }
    RigidBody::new(b.mass, com, inertia)
        .map(|r| (r, false))
        .map_err(|e| at.core(&field_of(&e, true, "inertia"), e))
}

/// The joint's initial q and v: the body's `q0`/`v0` (angles and angular rates in the file's
/// units), or the neutral configuration and rest.
fn initial_coordinates(
    at: &At,
    b: &BodyFile,
    joint: &Joint,
    units: Units,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut q = vec![0.0; joint.nq()];
    joint.neutral(&mut q);
    let mut v = vec![0.0; joint.nv()];
    for (given, out, field) in [(&b.q0, &mut q, "q0"), (&b.v0, &mut v, "v0")] {
        let Some(given) = given else { continue };
        if given.len() != out.len() {
            return Err(at.err(
                field,
                format!(
                    "expected {} values for a {} joint, got {}",
                    out.len(),
                    joint.kind(),
                    given.len()
                ),
            ));
        }
        out.copy_from_slice(given);
        let checked = if field == "q0" {
            super::to_radians(out, |k| joint.q_is_angle(k), units.angle);
            crate::support::error::check_finite("q0", out)
                .and_then(|()| joint.check_configuration(out, "q0"))
        } else {
            super::to_radians(out, |k| joint.v_is_angular(k), units.rate);
            crate::support::error::check_finite("v0", out)
        };
        checked.map_err(|e| at.core(field, e))?;
    }
    Ok((q, v))
}
