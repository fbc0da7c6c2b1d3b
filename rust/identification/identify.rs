//! The whole identification: regressor along the measured states, the fixed parameters
//! moved to the right-hand side, reduction, base parameters (checked against the model's
//! structural ones), then least squares or the cells' program.
use nalgebra::DMatrix;

use super::actuated::{closed_state, joint_force_regressor};
use super::base_parameters::{base_parameters, reduce, Base, Reduced};
use super::cells::{fit_cells, LinkCells};
use super::regressor::{ncolumns, parameter_names, Extras};
use super::solve::{ols, residual};
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec3;

/// How to estimate.
#[derive(Debug, Clone)]
pub enum Method {
    /// Least squares on the base parameters.
    Ols,
    /// Non-negative cell masses for the listed links (the other links' parameters fixed).
    Cells(Vec<LinkCells>),
}

#[derive(Debug, Clone)]
pub struct Options {
    pub extras: Extras,
    /// Which columns are estimated; the others keep `prior`'s value.
    pub free: Vec<bool>,
    /// Values of every column: the fixed ones, the prior of the free ones.
    pub prior: Vec<f64>,
    /// Weight of the pull towards `prior` (cells only; 0: none).
    pub prior_weight: f64,
    /// One weight per joint (`1/σ_j`), or empty.
    pub weights: Vec<f64>,
    /// Rank tolerance of the unit-norm-column QR.
    pub rank_tol: f64,
    pub method: Method,
    /// The driven joints (v indices): `tau` holds their forces alone
    /// ([`super::actuated::actuated_regressor`]); empty: every joint's (tree) force.
    pub actuated: Vec<usize>,
}

#[derive(Debug, Clone)]
pub struct Identified {
    pub names: Vec<String>,
    /// Free column indices (the base parameters index into these).
    pub free: Vec<usize>,
    pub base: Base,
    pub base_names: Vec<String>,
    /// The fit's values ([`super::Fit`]'s, as the binding hands them over): the base parameters,
    /// their standard deviations, every parameter, the residual sum of squares and the
    /// condition number.
    pub beta: Vec<f64>,
    pub std: Vec<f64>,
    pub pi: Vec<f64>,
    pub rss: f64,
    pub condition: f64,
    /// Cell masses per [`LinkCells`] (cells only).
    pub masses: Vec<Vec<f64>>,
    /// `τ − Y π`, sample-major.
    pub residuals: Vec<f64>,
    /// The base parameters' count for a rich motion (the model's structural rank).
    pub structural_rank: usize,
}

/// Identifies the free parameters from stacked states and joint forces `tau` (N × nv, or
/// N × na for the `actuated` joints).
#[allow(clippy::too_many_arguments)]
pub fn identify(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    tau: &[f64],
    g: &Vec3,
    opt: &Options,
) -> Result<Identified> {
    let p = ncolumns(model, &opt.extras);
    if opt.free.len() != p || opt.prior.len() != p {
        return Err(Error::arg(
            "prior",
            format!("{p} values (one per regressor column)"),
            format!("{} and {}", opt.free.len(), opt.prior.len()),
        ));
    }
    crate::support::error::check_finite("prior", &opt.prior)?;
    crate::support::error::check_finite("tau", tau)?;
    let y = joint_force_regressor(model, q, v, a, g, &opt.extras, &opt.actuated)?;
    if tau.len() != y.nrows() {
        let width = if opt.actuated.is_empty() {
            "nv"
        } else {
            "na (the actuated joints)"
        };
        return Err(Error::arg(
            "tau",
            format!("{} values (N × {width} for the N states)", y.nrows()),
            format!("{}", tau.len()),
        ));
    }
    let free: Vec<usize> = (0..p).filter(|&c| opt.free[c]).collect();
    let fixed: Vec<usize> = (0..p).filter(|&c| !opt.free[c]).collect();
    let mut b = tau.to_vec();
    for &c in &fixed {
        let x = opt.prior[c];
        if x != 0.0 {
            for (bi, yi) in b.iter_mut().zip(y.column(c).iter()) {
                *bi -= yi * x;
            }
        }
    }
    let red = reduce(&y, &free, Some(&b), &opt.weights);
    let base = base_parameters(&red.r, opt.rank_tol);
    let names = parameter_names(model, &opt.extras);
    let free_names: Vec<String> = free.iter().map(|&c| names[c].clone()).collect();
    let structural = structural_base(model, g, opt, &free, q)?;
    if base.rank < structural.rank {
        return Err(unidentifiable(&base, &structural, &free_names, y.nrows()));
    }
    let prior_free: Vec<f64> = free.iter().map(|&c| opt.prior[c]).collect();
    let (fit_free, masses) = match &opt.method {
        Method::Ols => (ols(&red, &base, Some(&prior_free))?, Vec::new()),
        Method::Cells(links) => fit_cells(
            &red,
            &base,
            &free,
            &prior_free,
            opt.prior_weight,
            links,
            &opt.extras,
            model,
        )?,
    };
    let mut pi = opt.prior.clone();
    for (k, &c) in free.iter().enumerate() {
        pi[c] = fit_free.pi[k];
    }
    let resid = &y * nalgebra::DVector::from_column_slice(&pi);
    let residuals = tau.iter().zip(resid.iter()).map(|(t, r)| t - r).collect();
    Ok(Identified {
        base_names: base.names(&free_names),
        names,
        free,
        base,
        beta: fit_free.beta,
        std: fit_free.std,
        pi,
        rss: residual(&red, &fit_free.pi),
        condition: fit_free.condition,
        masses,
        residuals,
        structural_rank: structural.rank,
    })
}

/// The base parameters for a rich motion: random states (a fixed seed), enough rows for
/// every column three times over. With loops or couplings, each random state is closed
/// onto the constraints from a guess near one of the measured positions `q_data` (which are
/// closed: the random offsets move it along the mechanism's freedom).
fn structural_base(
    model: &Model,
    g: &Vec3,
    opt: &Options,
    free: &[usize],
    q_data: &[f64],
) -> Result<Base> {
    let (nq, nv) = (model.nq, model.nv);
    let rows = if opt.actuated.is_empty() {
        nv
    } else {
        opt.actuated.len()
    };
    let samples = (3 * free.len()).div_ceil(rows.max(1)) + 8;
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut rand = move || {
        // xorshift64*: a deterministic spread in (−1, 1).
        seed ^= seed >> 12;
        seed ^= seed << 25;
        seed ^= seed >> 27;
        let x = seed.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    };
    let neutral = model.neutral();
    // Couplings without `actuated`: the tree's forces, sampled as before (unconstrained).
    let constrained = model.has_constraints() && !opt.actuated.is_empty();
    let measured = q_data.len() / nq.max(1);
    let mut q = Vec::with_capacity(samples * nq);
    let (mut v, mut a) = (Vec::new(), Vec::new());
    for k in 0..samples {
        let centre = if constrained && measured > 0 {
            let s = k * measured / samples;
            &q_data[s * nq..(s + 1) * nq]
        } else {
            &neutral[..]
        };
        let mut qk: Vec<f64> = centre.iter().map(|x| x + 0.8 * rand()).collect();
        model.normalize(&mut qk);
        let mut vk: Vec<f64> = (0..nv).map(|_| 2.0 * rand()).collect();
        let mut ak: Vec<f64> = (0..nv).map(|_| 5.0 * rand()).collect();
        if constrained {
            // Not closable from there: the measured position itself (closed already).
            let closed = closed_state(model, &qk, &mut vk, &mut ak)
                .or_else(|| closed_state(model, centre, &mut vk, &mut ak));
            match closed {
                Some(c) => qk = c,
                None => continue,
            }
        }
        q.extend(qk);
        v.extend(vk);
        a.extend(ak);
    }
    let y = joint_force_regressor(model, &q, &v, &a, g, &opt.extras, &opt.actuated)?;
    let red: Reduced = reduce(&y, free, None, &[]);
    Ok(base_parameters(&red.r, opt.rank_tol))
}

/// The error for a motion that identifies fewer base parameters than the model has.
fn unidentifiable(data: &Base, rich: &Base, names: &[String], rows: usize) -> Error {
    let lost: Vec<&str> = data
        .dependent
        .iter()
        .filter(|c| rich.independent.contains(c))
        .map(|&c| names[c].as_str())
        .collect();
    Error::arg(
        "data",
        format!(
            "a motion that excites all {} base parameters of the model (more samples, or a richer motion: see excitation_trajectory)",
            rich.rank
        ),
        format!(
            "{rows} rows identifying {} of them; not identifiable from it: {}",
            data.rank,
            lost.join(", ")
        ),
    )
}

/// `R` of the full regressor, for callers who want it (benches, tests).
pub fn reduced(y: &DMatrix<f64>) -> Reduced {
    let cols: Vec<usize> = (0..y.ncols()).collect();
    reduce(y, &cols, None, &[])
}
