//! Explicit DeNOC matrices (paper, Sections III–IV; docs/method.md §2–3) for teaching and verification.
//!
//! `t = N_l N_d q̇`, point velocities `V = D t`, `N = D N_l N_d`, `M = diag(m_ij 1₃)`:
//! GIM `I = Nᵀ M N`, convective matrix `C = Nᵀ M Ṅ`, generalized forces `τ = Nᵀ f`.
//! Everything here is dense and allocates; the recursive algorithms in `recursive` are the
//! fast path and are checked against this one. The matrices grow as n² (`D` alone is
//! 21n × 6n) and their products as n³, so every function first checks that the whole
//! memory can be had (an `OutOfMemory` error naming the size, not an abort) and checks for
//! interruption (`interrupt::check`) between blocks of the products.
use nalgebra::{DMatrix, DVector};

use crate::kinematics::{self, LinkState};
use crate::model::Model;
use crate::support::alloc::{ensure_available, try_zeros, try_zeros_vector};
use crate::support::error::{Error, Result};
use crate::support::interrupt;
use crate::support::spatial::{angular, linear, skew, Mat3, Vec3};

#[derive(Debug, Clone)]
pub struct Denoc {
    /// 21n × 6n, blocks `D_i` with rows `[−d̃_ij, 1]`.
    pub d: DMatrix<f64>,
    /// 6n × 6n, block lower triangular, `A_ik` for each ancestor k of i.
    pub nl: DMatrix<f64>,
    /// 6n × nv, blocks `P_i`.
    pub nd: DMatrix<f64>,
    /// 21n × nv.
    pub n: DMatrix<f64>,
    /// The 7n point masses, link by link.
    pub masses: DVector<f64>,
    /// World positions of the 7n point masses (7n × 3).
    pub points: DMatrix<f64>,
}

#[derive(Debug, Clone)]
pub struct DenocRates {
    pub d: DMatrix<f64>,
    pub nl: DMatrix<f64>,
    pub nd: DMatrix<f64>,
    pub n: DMatrix<f64>,
}

fn states(model: &Model, q: &[f64], v: Option<&[f64]>) -> Vec<LinkState> {
    let mut st = vec![LinkState::default(); model.links.len()];
    kinematics::positions(model, q, &mut st);
    if let Some(v) = v {
        kinematics::velocities(model, q, v, &mut st);
    }
    st
}

fn ancestors_and_self(model: &Model, i: usize) -> Vec<usize> {
    let mut out = vec![i];
    let mut p = model.links[i].parent;
    while let Some(k) = p {
        out.push(k);
        p = model.links[k].parent;
    }
    out
}

/// `d_ij` (world) of each point of link i, from its origin.
fn point_offsets(model: &Model, st: &[LinkState], i: usize) -> [Vec3; 7] {
    let mut d = [Vec3::zeros(); 7];
    for (j, p) in model.links[i].points.positions.iter().enumerate() {
        d[j] = st[i].rotation * p;
    }
    d
}

/// Bytes of the explicit matrices for `model` (with their rates if asked), counted before
/// anything is allocated.
fn dense_bytes(model: &Model, rates: bool) -> u128 {
    let (n, nv) = (model.links.len() as u128, model.nv as u128);
    // D, N_l, N_d, N_l N_d and N, plus masses and points.
    let one = 21 * n * 6 * n + 36 * n * n + 6 * n * nv + 6 * n * nv + 21 * n * nv + 28 * n;
    // Rates: their own D, N_l, N_d and three terms of Ṅ; the callers' products (n × n).
    let total = if rates {
        2 * one + 2 * 21 * n * nv
    } else {
        one
    } + 2 * nv * nv;
    8 * total
}

/// `a b` computed in blocks of columns, checking for interruption between blocks.
fn product(a: &DMatrix<f64>, b: &DMatrix<f64>, what: &str) -> Result<DMatrix<f64>> {
    const BLOCK: usize = 64;
    let mut out = try_zeros(a.nrows(), b.ncols(), what)?;
    let mut j = 0;
    while j < b.ncols() {
        interrupt::check(what)?;
        let w = BLOCK.min(b.ncols() - j);
        out.columns_mut(j, w).gemm(1.0, a, &b.columns(j, w), 0.0);
        j += w;
    }
    Ok(out)
}

/// `D (N_l N_d)`: the association with n³ rather than 21n³ products.
fn chain(
    d: &DMatrix<f64>,
    nl: &DMatrix<f64>,
    nd: &DMatrix<f64>,
    what: &str,
) -> Result<DMatrix<f64>> {
    product(d, &product(nl, nd, what)?, what)
}

/// Link `i`'s rows of `D` (and `Ḋ`), its seven point masses and their world positions.
#[allow(clippy::too_many_arguments)]
fn fill_points(
    model: &Model,
    st: &[LinkState],
    i: usize,
    d: &mut DMatrix<f64>,
    masses: &mut DVector<f64>,
    points: &mut DMatrix<f64>,
    dd: Option<&mut DMatrix<f64>>,
) {
    let offs = point_offsets(model, st, i);
    let w = angular(&st[i].twist);
    let mut dd = dd;
    for (j, dij) in offs.iter().enumerate() {
        let row = 21 * i + 3 * j;
        d.view_mut((row, 6 * i), (3, 3)).copy_from(&(-skew(dij)));
        d.view_mut((row, 6 * i + 3), (3, 3))
            .copy_from(&Mat3::identity());
        masses[7 * i + j] = model.links[i].points.masses[j];
        let x = st[i].origin + dij;
        for c in 0..3 {
            points[(7 * i + j, c)] = x[c];
        }
        if let Some(dd) = dd.as_deref_mut() {
            // d_ij is fixed in the body: ḋ = ω × d.
            dd.view_mut((row, 6 * i), (3, 3))
                .copy_from(&(-skew(&w.cross(dij))));
        }
    }
}

/// Link `i`'s block row of `N_l` (and `Ṅ_l`): the twist-propagation blocks from each
/// ancestor `k` (and itself), `[[1, 0], [ã, 1]]` with `a = O_k − O_i`.
fn fill_coupling(
    model: &Model,
    st: &[LinkState],
    i: usize,
    nl: &mut DMatrix<f64>,
    nld: Option<&mut DMatrix<f64>>,
) {
    let mut nld = nld;
    for k in ancestors_and_self(model, i) {
        let a = st[k].origin - st[i].origin;
        nl.view_mut((6 * i, 6 * k), (6, 6)).fill_with_identity();
        nl.view_mut((6 * i + 3, 6 * k), (3, 3)).copy_from(&skew(&a));
        if let Some(nld) = nld.as_deref_mut() {
            let adot = linear(&st[k].twist) - linear(&st[i].twist);
            nld.view_mut((6 * i + 3, 6 * k), (3, 3))
                .copy_from(&skew(&adot));
        }
    }
}

fn assemble(
    model: &Model,
    st: &[LinkState],
    rates: bool,
    what: &str,
) -> Result<(Denoc, Option<DenocRates>)> {
    ensure_available(
        dense_bytes(model, rates),
        &format!(
            "{what}: the explicit DeNOC matrices of {} links (D alone is {} × {})",
            model.links.len(),
            21 * model.links.len(),
            6 * model.links.len()
        ),
    )?;
    let n = model.links.len();
    let nv = model.nv;
    let mut d = try_zeros(21 * n, 6 * n, "D")?;
    let mut nl = try_zeros(6 * n, 6 * n, "N_l")?;
    let mut nd = try_zeros(6 * n, nv, "N_d")?;
    let mut masses = try_zeros_vector(7 * n, "point masses")?;
    let mut points = try_zeros(7 * n, 3, "point positions")?;
    let (mut dd, mut nld, ndd) = if rates {
        (
            try_zeros(21 * n, 6 * n, "Ḋ")?,
            try_zeros(6 * n, 6 * n, "Ṅ_l")?,
            try_zeros(6 * n, nv, "Ṅ_d")?,
        )
    } else {
        (
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, 0),
        )
    };
    for (i, l) in model.links.iter().enumerate() {
        fill_points(
            model,
            st,
            i,
            &mut d,
            &mut masses,
            &mut points,
            rates.then_some(&mut dd),
        );
        fill_coupling(model, st, i, &mut nl, rates.then_some(&mut nld));
        let dof = l.joint.nv();
        for c in 0..dof {
            nd.view_mut((6 * i, l.v_index + c), (6, 1))
                .copy_from(&st[i].s[c]);
        }
    }
    let n_mat = chain(&d, &nl, &nd, what)?;
    let denoc = Denoc {
        d,
        nl,
        nd,
        n: n_mat,
        masses,
        points,
    };
    if !rates {
        return Ok((denoc, None));
    }
    Ok((
        denoc,
        Some(DenocRates {
            d: dd,
            nl: nld,
            nd: ndd,
            n: DMatrix::zeros(0, 0),
        }),
    ))
}

/// The DeNOC matrices at configuration `q` (checked by the caller).
pub fn matrices(model: &Model, q: &[f64]) -> Result<Denoc> {
    let st = states(model, q, None);
    Ok(assemble(model, &st, false, "denoc")?.0)
}

/// The seven point masses of every link and their world positions (7n × 3) at `q`,
/// without the matrices.
pub fn point_positions(model: &Model, q: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let st = states(model, q, None);
    let n = model.links.len();
    let mut masses = DVector::zeros(7 * n);
    let mut points = DMatrix::zeros(7 * n, 3);
    for (i, l) in model.links.iter().enumerate() {
        for (j, dij) in point_offsets(model, &st, i).iter().enumerate() {
            masses[7 * i + j] = l.points.masses[j];
            let x = st[i].origin + dij;
            for c in 0..3 {
                points[(7 * i + j, c)] = x[c];
            }
        }
    }
    (masses, points)
}

/// The DeNOC matrices and their time derivatives at `(q, v)`.
pub fn matrices_and_rates(model: &Model, q: &[f64], v: &[f64]) -> Result<(Denoc, DenocRates)> {
    rates_for(model, q, v, "denoc_rates")
}

fn rates_for(model: &Model, q: &[f64], v: &[f64], what: &str) -> Result<(Denoc, DenocRates)> {
    let st = states(model, q, Some(v));
    let (den, rates) = assemble(model, &st, true, what)?;
    let Some(mut rates) = rates else {
        return Err(Error::Singular("DeNOC rates were not assembled".into()));
    };
    // Ṗ_i for each joint, in the columns of Ṅ_d.
    for (i, l) in model.links.iter().enumerate() {
        let w_parent = l
            .parent
            .map(|p| angular(&st[p].twist))
            .unwrap_or_else(Vec3::zeros);
        let qi = &q[l.q_index..l.q_index + l.joint.nq()];
        let vi = &v[l.v_index..l.v_index + l.joint.nv()];
        let sdot = l.joint.subspace_rate(
            qi,
            vi,
            &st[i].s,
            &st[i].joint_rotation,
            &w_parent,
            &angular(&st[i].twist),
        );
        for c in 0..l.joint.nv() {
            rates
                .nd
                .view_mut((6 * i, l.v_index + c), (6, 1))
                .copy_from(&sdot[c]);
        }
    }
    rates.n = chain(&rates.d, &den.nl, &den.nd, what)?;
    rates.n += chain(&den.d, &rates.nl, &den.nd, what)?;
    rates.n += chain(&den.d, &den.nl, &rates.nd, what)?;
    Ok((den, rates))
}

/// `Nᵀ M X` for a 21n-row matrix X, with M the diagonal of point masses.
fn nt_m(den: &Denoc, x: &DMatrix<f64>, what: &str) -> Result<DMatrix<f64>> {
    let mut mx = try_zeros(x.nrows(), x.ncols(), what)?;
    mx.copy_from(x);
    for r in 0..mx.nrows() {
        let m = den.masses[r / 3];
        mx.row_mut(r).scale_mut(m);
    }
    product(&den.n.transpose(), &mx, what)
}

/// Generalized inertia matrix `Nᵀ M N` (plus the joints' armature on its diagonal).
pub fn mass_matrix(model: &Model, q: &[f64]) -> Result<DMatrix<f64>> {
    let st = states(model, q, None);
    let (den, _) = assemble(model, &st, false, "mass_matrix")?;
    let gim = nt_m(&den, &den.n, "mass_matrix")?;
    let mut gim = (&gim + gim.transpose()) * 0.5;
    crate::recursive::armature::add_to_mass_matrix(model, &mut gim);
    Ok(gim)
}

/// Convective matrix `C = Nᵀ M Ṅ` (so that `İ − 2C` is skew-symmetric).
pub fn convective_matrix(model: &Model, q: &[f64], v: &[f64]) -> Result<DMatrix<f64>> {
    let (den, rates) = rates_for(model, q, v, "convective_matrix")?;
    nt_m(&den, &rates.n, "convective_matrix")
}

/// `Nᵀ f` for forces `f` on the 7n point masses (world coordinates, one row each).
pub fn generalized_forces(model: &Model, q: &[f64], point_forces: &[Vec3]) -> Result<DVector<f64>> {
    if point_forces.len() != model.npoints() {
        return Err(Error::arg(
            "forces",
            format!(
                "shape ({}, 7, 3) or ({}, 3): one force per point mass",
                model.links.len(),
                model.npoints()
            ),
            format!("{} forces", point_forces.len()),
        ));
    }
    for p in point_forces {
        crate::support::error::check_finite("forces", p.as_slice())?;
    }
    let den = matrices(model, q)?;
    let mut f = DVector::zeros(3 * point_forces.len());
    for (j, p) in point_forces.iter().enumerate() {
        f.fixed_rows_mut::<3>(3 * j).copy_from(p);
    }
    Ok(den.n.transpose() * f)
}

/// Generalized gravity force `Nᵀ f^G`, `f^G_ij = m_ij g` (on the right-hand side:
/// Pinocchio's `computeGeneralizedGravity` is its negative).
pub fn gravity_forces(model: &Model, q: &[f64], g: &Vec3) -> Result<DVector<f64>> {
    let den = matrices(model, q)?;
    let mut f = DVector::zeros(den.n.nrows());
    for j in 0..den.masses.len() {
        f.fixed_rows_mut::<3>(3 * j).copy_from(&(g * den.masses[j]));
    }
    Ok(den.n.transpose() * f)
}

/// `I a + C v − τ_g = τ`.
pub fn inverse_dynamics(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
) -> Result<DVector<f64>> {
    let gim = mass_matrix(model, q)?;
    let c = convective_matrix(model, q, v)?;
    let tg = gravity_forces(model, q, g)?;
    Ok(gim * DVector::from_column_slice(a) + c * DVector::from_column_slice(v) - tg)
}

/// Solves `I a = τ + τ_g − C v` by Cholesky.
pub fn forward_dynamics(
    model: &Model,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    g: &Vec3,
) -> Result<DVector<f64>> {
    crate::recursive::check_singularities(model, q)?;
    let gim = mass_matrix(model, q)?;
    let c = convective_matrix(model, q, v)?;
    let rhs = DVector::from_column_slice(tau) + gravity_forces(model, q, g)?
        - c * DVector::from_column_slice(v);
    match gim.cholesky() {
        Some(ch) => Ok(ch.solve(&rhs)),
        None => Err(Error::Singular(
            "the generalized inertia matrix is not positive definite at this configuration".into(),
        )),
    }
}
