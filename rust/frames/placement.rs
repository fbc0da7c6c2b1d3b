//! Frame placements and body-point paths over many configurations at once (a coupler
//! curve, a gripper's path along a trajectory): one pass of the poses per row, nothing
//! allocated per row.
use crate::model::Model;
use crate::support::error::Result;
use crate::support::spatial::Vec3;

use super::motion::FrameKinematics;
use super::FrameRef;

/// Checks each row of `qs` (errors name `q[k]` when `stacked`).
pub fn check_rows(model: &Model, qs: &[f64], rows: usize, stacked: bool, arg: &str) -> Result<()> {
    let nq = model.nq;
    for k in 0..rows {
        model
            .check_state(&qs[k * nq..(k + 1) * nq], None)
            .map_err(|e| {
                e.map_arg(|name| {
                    let name = name.replacen('q', arg, 1);
                    match stacked {
                        true => format!("{name}[{k}]"),
                        false => name,
                    }
                })
            })?;
    }
    Ok(())
}

/// For `rows` configurations (row-major in `qs`, checked), the frames' rotations (row-major
/// 3 × 3 each, frame axes to world; `rows × frames.len() × 9`) and origins
/// (`rows × frames.len() × 3`).
pub fn frame_placements(
    model: &Model,
    frames: &[FrameRef],
    qs: &[f64],
    rows: usize,
    rotations: &mut [f64],
    origins: &mut [f64],
) -> Result<()> {
    let mut kin = FrameKinematics::new(model);
    let (nq, nf) = (model.nq, frames.len());
    for k in 0..rows {
        if k % 256 == 0 {
            crate::support::interrupt::check("frame_placement")?;
        }
        kin.positions(model, &qs[k * nq..(k + 1) * nq]);
        for (i, f) in frames.iter().enumerate() {
            let p = kin.frame_pose(f);
            let at = k * nf + i;
            rotations[at * 9..at * 9 + 9].copy_from_slice(p.rotation.transpose().as_slice());
            origins[at * 3..at * 3 + 3].copy_from_slice(p.translation.as_slice());
        }
    }
    Ok(())
}

/// World positions of `point` (in the frame `f`) at `rows` configurations, with its
/// velocities when `vs` is given (row-major `rows × nv`).
#[allow(clippy::too_many_arguments)] // the inputs, then the two outputs
pub fn point_path(
    model: &Model,
    f: &FrameRef,
    point: &Vec3,
    qs: &[f64],
    vs: Option<&[f64]>,
    rows: usize,
    positions: &mut [f64],
    velocities: &mut [f64],
) -> Result<()> {
    let mut kin = FrameKinematics::new(model);
    let (nq, nv) = (model.nq, model.nv);
    for k in 0..rows {
        if k % 256 == 0 {
            crate::support::interrupt::check("point_path")?;
        }
        let q = &qs[k * nq..(k + 1) * nq];
        kin.positions(model, q);
        let x = kin.frame_pose(f).act_point(point);
        positions[k * 3..k * 3 + 3].copy_from_slice(x.as_slice());
        if let Some(vs) = vs {
            crate::kinematics::velocities(model, q, &vs[k * nv..(k + 1) * nv], &mut kin.links);
            let v = crate::support::spatial::linear(&kin.point_velocity(f.link, &x));
            velocities[k * 3..k * 3 + 3].copy_from_slice(v.as_slice());
        }
    }
    Ok(())
}

/// One frame's placements at `rows` configurations (each checked first; errors name `q[k]`
/// when `stacked`): rotations (`rows × 9`) and origins (`rows × 3`), checked finite.
pub fn frame_placement(
    model: &Model,
    f: &FrameRef,
    (qs, rows, stacked): (&[f64], usize, bool),
    rot: &mut [f64],
    org: &mut [f64],
) -> Result<()> {
    check_rows(model, qs, rows, stacked, "q")?;
    frame_placements(model, &[*f], qs, rows, rot, org)?;
    crate::support::error::check_result("frame_placement", org)
}

/// [`point_path`] at checked rows (errors name `q[k]`): the positions and, with `vs`, the
/// velocities.
pub fn point_path_of(
    model: &Model,
    f: &FrameRef,
    point: &Vec3,
    qs: &[f64],
    vs: Option<&[f64]>,
    rows: usize,
) -> Result<(Vec<f64>, Option<Vec<f64>>)> {
    crate::support::error::check_finite("point", point.as_slice())?;
    check_rows(model, qs, rows, true, "q")?;
    let (mut pos, mut vel) = (vec![0.0; 3 * rows], vec![0.0; 3 * rows]);
    point_path(model, f, point, qs, vs, rows, &mut pos, &mut vel)?;
    crate::support::error::check_result("point_path", &pos)?;
    Ok((pos, vs.map(|_| vel)))
}
