//! The frame algorithms assembled for one call (what the bindings call): a frame's
//! Jacobian at many configurations, its velocity and acceleration, the centre of mass and the
//! centroidal quantities. Each checks its inputs and allocates its own buffers once.
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::error::{check_result, Error, Result};
use crate::support::spatial::{Vec3, Vec6};

use super::com::{self, Composite};

use super::motion::FrameKinematics;
use super::rows::{self, check_block};
use super::{batch, centroidal, jacobian, jacobian_dot, FrameRef, ReferenceFrame};

/// `J` of `f` at `rows` configurations (row-major `rows × 6 × nv` into `out`, every entry
/// written), checked here once for the whole block. One row is computed in the caller's
/// `links` (a pooled workspace's: no allocation, no thread hand-off), from the support's
/// poses alone; large blocks are split over threads (`rows::split`).
#[allow(clippy::too_many_arguments)]
pub fn frame_jacobians(
    model: &Model,
    links: &mut [LinkState],
    f: &FrameRef,
    rf: ReferenceFrame,
    qs: &[f64],
    rows: usize,
    stacked: bool,
    out: &mut [f64],
) -> Result<()> {
    check_block(model, qs, rows, stacked, "q")?;
    if rows == 1 {
        crate::kinematics::plan::frame_poses_for(model, qs, links, f.link);
        jacobian::frame_jacobian_links(model, links, f, rf, out);
        return check_result("frame_jacobian", out);
    }
    let nv = model.nv;
    let threads = rows::threads_for(model, rows);
    // The frame's support alone (a Jacobian needs no other link, nor any inertia), its
    // per-link decisions made once for the whole block.
    let mut support: Vec<usize> = model.support(f.link).collect();
    support.reverse();
    let walk = batch::Walk::new(model, &support);
    let block = |first: usize,
                 count: usize,
                 out: &mut [f64],
                 _: &mut [f64],
                 poll: &dyn Fn() -> Result<()>| {
        batch::frame_jacobian_rows(model, &walk, f, rf, qs, first, count, out, poll)
    };
    rows::split(
        "frame_jacobian",
        rows,
        threads,
        out,
        6 * nv,
        &mut [],
        0,
        block,
    )
}

/// `J̇` of `f` (row-major 6 × nv) at `(q, v)` (checked by the caller), checked finite.
pub fn frame_jacobian_dot(
    model: &Model,
    f: &FrameRef,
    rf: ReferenceFrame,
    q: &[f64],
    v: &[f64],
) -> Result<Vec<f64>> {
    let mut kin = FrameKinematics::new(model);
    kin.positions(model, q);
    kin.velocities(model, q, v);
    let mut out = vec![0.0; 6 * model.nv];
    jacobian_dot::frame_jacobian_dot(model, &kin, f, rf, &mut out);
    check_result("frame_jacobian_dot", &out)?;
    Ok(out)
}

fn mat_vec(m: &[f64], x: &[f64], nv: usize) -> Vec6 {
    Vec6::from_fn(|i, _| (0..nv).map(|c| m[i * nv + c] * x[c]).sum())
}

/// The frame's velocity `J v` and acceleration `J a + J̇ v` (a = None: zero) in `rf`
/// (checked inputs; the result checked finite). In LOCAL_WORLD_ALIGNED the linear parts are
/// the velocity and the classical acceleration of the frame origin.
pub fn frame_motion(
    model: &Model,
    f: &FrameRef,
    rf: ReferenceFrame,
    q: &[f64],
    v: &[f64],
    a: Option<&[f64]>,
) -> Result<(Vec6, Vec6)> {
    let nv = model.nv;
    let mut kin = FrameKinematics::new(model);
    kin.positions(model, q);
    kin.velocities(model, q, v);
    let mut j = vec![0.0; 6 * nv];
    jacobian::frame_jacobian(model, &kin, f, rf, &mut j);
    let mut jd = vec![0.0; 6 * nv];
    jacobian_dot::frame_jacobian_dot(model, &kin, f, rf, &mut jd);
    let vel = mat_vec(&j, v, nv);
    let mut acc = mat_vec(&jd, v, nv);
    if let Some(a) = a {
        acc += mat_vec(&j, a, nv);
    }
    check_result("frame_motion", acc.as_slice())?;
    Ok((vel, acc))
}

fn no_mass() -> Error {
    Error::model(
        "model",
        "no moving body has mass: the centre of mass of the moving links is undefined",
    )
}

/// Centre of mass and, when `jac` is given, the COM Jacobian (row-major `rows × 3 × nv`) at
/// `rows` configurations; `com_out` gets `rows × 3`. Checked once for the block; large
/// blocks are split over threads (`rows::split`); one row is computed in the caller's
/// `links` ([`com_one`]).
pub fn com_batch(
    model: &Model,
    links: &mut [LinkState],
    qs: &[f64],
    rows: usize,
    stacked: bool,
    com_out: &mut [f64],
    jac: Option<&mut [f64]>,
) -> Result<()> {
    check_block(model, qs, rows, stacked, "q")?;
    if rows == 1 {
        let c = com_one(model, qs, links, jac)?;
        com_out.copy_from_slice(c.as_slice());
        return check_result("center_of_mass", com_out);
    }
    let nv = model.nv;
    if !model.links.iter().any(|l| l.rigid.mass > 0.0) {
        return Err(no_mass());
    }
    let with_jac = jac.is_some();
    let per_j = if with_jac { 3 * nv } else { 0 };
    let threads = rows::threads_for(model, rows);
    let all: Vec<usize> = (0..model.links.len()).collect();
    let walk = batch::Walk::new(model, &all);
    let block = |first: usize,
                 count: usize,
                 com: &mut [f64],
                 j: &mut [f64],
                 poll: &dyn Fn() -> Result<()>| {
        let j = with_jac.then_some(j);
        batch::com_rows(model, &walk, qs, first, count, com, j, poll)
    };
    let jac = jac.unwrap_or(&mut []);
    rows::split(
        "center_of_mass",
        rows,
        threads,
        com_out,
        3,
        jac,
        per_j,
        block,
    )
}

/// The centre of mass at one checked `q` and, with `jac`, its 3 × nv Jacobian (every entry
/// written); `links` and `moments` (4 per link) are the caller's buffers.
pub fn com_at(
    model: &Model,
    q: &[f64],
    links: &mut [LinkState],
    moments: &mut [f64],
    jac: Option<&mut [f64]>,
) -> Result<Vec3> {
    // Poses and joint columns only: the COM needs no inertias.
    crate::kinematics::frame_poses(model, q, links);
    com::subtree_moments(model, links, moments);
    let (m, c) = com::com_of_moments(model, moments).ok_or_else(no_mass)?;
    if let Some(j) = jac {
        j.fill(0.0);
        com::com_jacobian(model, links, moments, m, j);
    }
    Ok(c)
}

/// [`com_at`] with its moments on the stack for models of up to 64 links (a Python call's
/// pooled workspace has the links' buffers, not these).
pub fn com_one(
    model: &Model,
    q: &[f64],
    links: &mut [LinkState],
    jac: Option<&mut [f64]>,
) -> Result<Vec3> {
    let n = 4 * model.links.len();
    if n <= 256 {
        let mut moments = [0.0; 256];
        com_at(model, q, links, &mut moments[..n], jac)
    } else {
        com_at(model, q, links, &mut vec![0.0; n], jac)
    }
}

/// The COM's position, velocity and acceleration (a = None: zero) at a checked state,
/// checked finite.
pub fn com_motion(model: &Model, q: &[f64], v: &[f64], a: Option<&[f64]>) -> Result<[Vec3; 3]> {
    let mut kin = FrameKinematics::new(model);
    kin.positions(model, q);
    let (_, c) = com::com(model, &kin).ok_or_else(no_mass)?;
    kin.velocities(model, q, v);
    kin.accelerations(model, a);
    let (vc, ac) = com::com_motion(model, &kin, true);
    check_result("center_of_mass_motion", ac.as_slice())?;
    Ok([c, vc, ac])
}

/// `A_g` (row-major 6 × nv) and, with `v`, the momentum and its rate.
pub type Centroidal = (Vec<f64>, Option<(Vec6, Vec6)>);

/// Centroidal quantities at a checked `q` (and `v`, `a`): `A_g` (row-major 6 × nv), and with
/// `v` the momentum `h_G = A_g v` and its rate `A_g a + Ȧ_g v` (a = None: the bias `Ȧ_g v`),
/// checked finite.
pub fn centroidal(
    model: &Model,
    q: &[f64],
    v: Option<&[f64]>,
    a: Option<&[f64]>,
) -> Result<Centroidal> {
    if a.is_some() && v.is_none() {
        return Err(Error::arg("v", "the speeds (nv,) when a is given", "None"));
    }
    let nv = model.nv;
    let mut kin = FrameKinematics::new(model);
    kin.positions(model, q);
    let (_, g) = com::com(model, &kin).ok_or_else(no_mass)?;
    let mut comp = vec![Composite::default(); model.links.len()];
    com::composites(model, &kin, &mut comp);
    let mut ag = vec![0.0; 6 * nv];
    centroidal::centroidal_map(model, &kin, &comp, &g, &mut ag);
    check_result("centroidal", &ag)?;
    let Some(v) = v else { return Ok((ag, None)) };
    kin.velocities(model, q, v);
    kin.accelerations(model, a);
    let h = mat_vec(&ag, v, nv);
    let hdot = centroidal::momentum_rate(model, &kin, &g);
    check_result("centroidal", hdot.as_slice())?;
    Ok((ag, Some((h, hdot))))
}
