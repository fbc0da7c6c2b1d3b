//! A scene's `[[loop]]` entries (cut joints closing kinematic loops) and the closing of its
//! initial state: q0 and v0 from the bodies (or `[initial]`) are the guess, the coordinates
//! of the bodies in `[initial] fixed` are held. Errors name `loop[k] ('name').field`.
use serde::Deserialize;

use super::{Ctx, JointFile, Units};
use crate::io::urdf::rpy_matrix;
use crate::joint::Joint;
use crate::model::Model;
use crate::support::error::Result;
use crate::support::spatial::{Mat3, Placement, Vec3};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LoopFile {
    name: Option<String>,
    /// Body names, or "world".
    body_a: String,
    body_b: String,
    joint: JointFile,
    translation_a: Option<[f64; 3]>,
    translation_b: Option<[f64; 3]>,
    rotation_a: Option<[[f64; 3]; 3]>,
    rotation_b: Option<[[f64; 3]; 3]>,
    rpy_a: Option<[f64; 3]>,
    rpy_b: Option<[f64; 3]>,
}

pub(super) fn add_loops(
    ctx: &Ctx,
    model: &mut Model,
    loops: &[LoopFile],
    units: Units,
) -> Result<()> {
    for (k, l) in loops.iter().enumerate() {
        let shown = l
            .name
            .clone()
            .unwrap_or_else(|| format!("loop{}", model.nloops()));
        let key = |field: &str| format!("loop[{k}] ('{shown}').{field}");
        let body = |field: &str, name: &str| -> Result<Option<usize>> {
            if name == "world" {
                return Ok(None);
            }
            model.body_index(name).map(Some).ok_or_else(|| {
                ctx.err(
                    key(field),
                    format!("no body named '{name}' ('world' is the ground)"),
                )
            })
        };
        let a = body("body_a", &l.body_a)?;
        let b = body("body_b", &l.body_b)?;
        let joint = match &l.joint {
            JointFile::Revolute { axis } => Joint::revolute(Vec3::from(*axis)),
            JointFile::Prismatic { axis } => Joint::prismatic(Vec3::from(*axis)),
            JointFile::Spherical => Ok(Joint::Spherical),
            JointFile::Fixed => Ok(Joint::Fixed),
            _ => {
                return Err(ctx.err(
                    key("joint"),
                    "a cut joint is Revolute, Prismatic, Spherical or Fixed",
                ))
            }
        }
        .map_err(|e| ctx.core(key("joint.axis"), e))?;
        let frame =
            |t: Option<[f64; 3]>, r: Option<[[f64; 3]; 3]>, rpy: Option<[f64; 3]>, side: &str| {
                let rotation = match (r, rpy) {
                    (Some(_), Some(_)) => {
                        return Err(ctx.err(
                            key(&format!("rotation_{side}")),
                            format!("give either rotation_{side} or rpy_{side}, not both"),
                        ))
                    }
                    (Some(r), None) => Mat3::from_row_slice(&r.concat()),
                    (None, Some(rpy)) => rpy_matrix(&(Vec3::from(rpy) * units.angle)),
                    (None, None) => Mat3::identity(),
                };
                Ok(Placement::new(rotation, Vec3::from(t.unwrap_or([0.0; 3]))))
            };
        let fa = frame(l.translation_a, l.rotation_a, l.rpy_a, "a")?;
        let fb = frame(l.translation_b, l.rotation_b, l.rpy_b, "b")?;
        model
            .add_loop(a, b, joint, fa, fb, l.name.clone())
            .map_err(|e| ctx.at_arg(format!("loop[{k}] ('{shown}')"), e))?;
    }
    Ok(())
}

/// Closes the loops (and couplings, from URDF mimic joints) from the file's initial state,
/// holding the joint coordinates of the bodies named in `fixed`.
pub(super) fn close_initial_state(
    ctx: &Ctx,
    model: &Model,
    fixed: &[String],
    q0: &mut Vec<f64>,
    v0: &mut [f64],
) -> Result<()> {
    if !model.has_constraints() {
        if !fixed.is_empty() {
            return Err(ctx.err(
                "initial.fixed",
                "only for a scene with [[loop]] entries or couplings (URDF mimic joints)",
            ));
        }
        return Ok(());
    }
    let mut mask = vec![false; model.nv];
    for (k, name) in fixed.iter().enumerate() {
        let link = model
            .body_index(name)
            .and_then(|b| model.bodies[b].link.filter(|&l| model.links[l].body == b));
        let Some(l) = link else {
            return Err(ctx.err(
                format!("initial.fixed[{k}]"),
                format!("expected the name of a body on a moving joint, got '{name}'"),
            ));
        };
        let l = &model.links[l];
        mask[l.v_index..l.v_index + l.joint.nv()].fill(true);
    }
    let closed =
        crate::loops::assemble(model, q0, &mask, 1e-12, 50).map_err(|e| ctx.core("initial", e))?;
    *q0 = closed;
    crate::loops::project_velocity_like(model, q0, None, v0, &mask)
        .map_err(|e| ctx.core("initial", e))?;
    Ok(())
}
