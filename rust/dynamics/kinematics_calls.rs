//! `Model`'s calls at a configuration beside the dynamics, as a binding asks for them: the
//! bodies' poses, the point masses, the DeNOC matrices and the explicit products built from
//! them. Each reads the method's arguments ([`Arg`], in the order the method lists them, so
//! the first bad one is the one named) with the caller's interpreter held, and returns the
//! computation, which the binding runs (detached from the interpreter, Ctrl-C heard, where it
//! can be long) and converts; every result is checked finite.
use nalgebra::{DMatrix, DVector};

use super::denoc::{self, Denoc, DenocRates};
use super::shared::Workspace;
use crate::kinematics::body_placements;
use crate::kinematics::poses::{Keyed, Poses, Shaped};
use crate::model::args::{configurations, gravity, state};
use crate::model::Model;
use crate::support::args::{points, Arg};
use crate::support::error::{check_result, Result};

/// Arguments read, or the binding's error.
type Read<T, A> = std::result::Result<T, <A as Arg>::Err>;

/// `placements` at the pooled workspace's loaded `q` (computed in its links): every body's
/// world rotation (nbodies, 3, 3) and origin (nbodies, 3).
pub fn placements(ws: &mut Workspace) -> Result<(Shaped, Shaped)> {
    let model: &Model = &ws.version.model;
    let (rots, origins) = body_placements(model, &ws.q, &mut ws.data.links)?;
    let nb = model.nbodies();
    Ok((
        Shaped::new(rots, &[nb, 3, 3]),
        Shaped::new(origins, &[nb, 3]),
    ))
}

/// `velocity_to_qdot` at the pooled workspace's loaded `(q, v)`: `q̇` (nq,).
pub fn velocity_to_qdot(ws: &mut Workspace) -> Result<Vec<f64>> {
    let mut qd = vec![0.0; ws.model().nq];
    ws.model().velocity_to_qdot(&ws.q, &ws.v, &mut qd);
    check_result("velocity_to_qdot", &qd)?;
    Ok(qd)
}

/// `body_poses`: everything a viewer draws, by name ([`Poses::keyed`]), at q (nq,) or (N, nq).
pub fn body_poses<'m, A: Arg>(
    model: &'m Model,
    q: &A,
) -> Read<impl FnOnce() -> Result<Vec<Keyed>> + Send + 'm, A> {
    let (rows, qs, stacked) = configurations(model, q, "q")?;
    Ok(move || Poses::at(model, &qs, rows, stacked)?.keyed(model, stacked))
}

/// `point_masses`: every link's masses (nlinks, 7) and world positions (nlinks, 7, 3).
pub fn point_masses<'m, A: Arg>(
    model: &'m Model,
    q: &A,
) -> Read<impl FnOnce() -> Result<(Shaped, Shaped)> + Send + 'm, A> {
    let (q, _) = state(model, (q, "q"), None)?;
    Ok(move || {
        let (masses, pts) = super::calls::point_masses(model, &q)?;
        let n = model.links.len();
        Ok((Shaped::new(masses, &[n, 7]), Shaped::new(pts, &[n, 7, 3])))
    })
}

/// `denoc`: the DeNOC matrices at `q`.
pub fn matrices<'m, A: Arg>(
    model: &'m Model,
    q: &A,
) -> Read<impl FnOnce() -> Result<Denoc> + Send + 'm, A> {
    let (q, _) = state(model, (q, "q"), None)?;
    Ok(move || {
        let den = denoc::matrices(model, &q)?;
        den.check_finite("denoc")?;
        Ok(den)
    })
}

/// `denoc_rates`: the DeNOC matrices' time derivatives at `(q, v)`.
pub fn rates<'m, A: Arg>(
    model: &'m Model,
    q: &A,
    v: &A,
) -> Read<impl FnOnce() -> Result<DenocRates> + Send + 'm, A> {
    let (q, v) = state(model, (q, "q"), Some((v, "v")))?;
    Ok(move || {
        let (_, rates) = denoc::matrices_and_rates(model, &q, &v)?;
        rates.check_finite("denoc_rates")?;
        Ok(rates)
    })
}

/// `convective_matrix`: `C = Nᵀ M Ṅ` (nv, nv) at `(q, v)`.
pub fn convective_matrix<'m, A: Arg>(
    model: &'m Model,
    q: &A,
    v: &A,
) -> Read<impl FnOnce() -> Result<DMatrix<f64>> + Send + 'm, A> {
    let (q, v) = state(model, (q, "q"), Some((v, "v")))?;
    Ok(move || {
        let c = denoc::convective_matrix(model, &q, &v)?;
        check_result("convective_matrix", c.as_slice())?;
        Ok(c)
    })
}

/// `gravity_forces`: `Nᵀ f^G` (nv,) at `q` for gravity `g` (read first).
pub fn gravity_forces<'m, A: Arg>(
    model: &'m Model,
    q: &A,
    g: &A,
) -> Read<impl FnOnce() -> Result<DVector<f64>> + Send + 'm, A> {
    let g = gravity(Some(g))?;
    let (q, _) = state(model, (q, "q"), None)?;
    Ok(move || {
        let tg = denoc::gravity_forces(model, &q, &g)?;
        check_result("gravity_forces", tg.as_slice())?;
        Ok(tg)
    })
}

/// `generalized_forces`: `Nᵀ f` (nv,) at `q` for world forces on the point masses.
pub fn generalized_forces<'m, A: Arg>(
    model: &'m Model,
    q: &A,
    forces: &A,
) -> Read<impl FnOnce() -> Result<DVector<f64>> + Send + 'm, A> {
    let (q, _) = state(model, (q, "q"), None)?;
    let f = points(forces, "forces")?;
    Ok(move || {
        let tau = denoc::generalized_forces(model, &q, &f)?;
        check_result("generalized_forces", tau.as_slice())?;
        Ok(tau)
    })
}
