//! The physically consistent estimate: each identified link made of non-negative masses on
//! cells (small solid cubes, [`crate::design::fill`]) inside its envelope, so every estimate
//! is a body that can exist (positive semidefinite pseudo-inertia, centre of mass and
//! inertia inside the envelope's convex hull). A link's ten parameters are linear in its cell
//! masses, so the fit `min ‖R π(m, x) − z‖² + prior` with `m ≥ 0` (and friction and
//! armature `≥ 0`) is a convex quadratic program, solved by Clarabel; then polished on the
//! cells it uses by an unconstrained least-squares step that keeps them non-negative (so
//! exact data are fitted to rounding, not to the solver's tolerance).
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use nalgebra::{DMatrix, DVector};

use super::base_parameters::{Base, Reduced};
use super::regressor::{body_parameters, Extras, NPARAM};
use super::solve::{ols, Fit};
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Mat3, Vec3};

/// The cells of one link: centres (link frame) of cubes of side `side`.
#[derive(Debug, Clone)]
pub struct LinkCells {
    pub link: usize,
    pub centres: Vec<Vec3>,
    pub side: f64,
}

/// The ten parameters (Pinocchio's order) of a solid cube of unit mass, side `side`, centred
/// at `c`: its inertia about the origin is a point mass's plus `side²/6` on the diagonal.
pub fn cell_parameters(c: &Vec3, side: f64) -> [f64; NPARAM] {
    let i = Mat3::identity() * (c.norm_squared() + side * side / 6.0) - c * c.transpose();
    body_parameters(1.0, c, &i)
}

/// The variables: every cell's mass, then each free joint-space column (friction, armature,
/// offset). `t` maps them to the free parameters (free index × variable); `nonneg` marks
/// those that must be `≥ 0`; `cells` gives each link's range of variables.
struct Variables {
    t: DMatrix<f64>,
    nonneg: Vec<bool>,
    ranges: Vec<std::ops::Range<usize>>,
}

fn variables(
    free: &[usize],
    links: &[LinkCells],
    extras: &Extras,
    model: &Model,
) -> Result<Variables> {
    let nlp = NPARAM * model.links.len();
    let ncells: usize = links.iter().map(|l| l.centres.len()).sum();
    let nextra = free.iter().filter(|&&c| c >= nlp).count();
    let mut t = DMatrix::zeros(free.len(), ncells + nextra);
    let pos = |c: usize| free.iter().position(|&f| f == c);
    let mut ranges = Vec::new();
    let mut var = 0;
    for l in links {
        let start = var;
        for c in &l.centres {
            for (j, x) in cell_parameters(c, l.side).iter().enumerate() {
                // Every column of a cells link is free (checked below).
                if let Some(k) = pos(NPARAM * l.link + j) {
                    t[(k, var)] = *x;
                }
            }
            var += 1;
        }
        ranges.push(start..var);
    }
    for (k, &c) in free.iter().enumerate() {
        if c < nlp && !links.iter().any(|l| l.link == c / NPARAM) {
            return Err(Error::arg(
                "bodies",
                "an envelope (cells) for every body identified with method='cells'",
                format!(
                    "body '{}' without one",
                    model.bodies[model.links[c / NPARAM].body].name
                ),
            ));
        }
        let _ = k;
    }
    let nj = super::regressor::extra_joints(model).len();
    let kinds: Vec<bool> = [
        (extras.viscous, true),
        (extras.coulomb, true),
        (extras.armature, true),
        (extras.offset, false),
    ]
    .iter()
    .filter(|(on, _)| *on)
    .map(|(_, nn)| *nn)
    .collect();
    let mut nonneg = vec![true; ncells];
    for (k, &c) in free.iter().enumerate() {
        if c >= nlp {
            t[(k, var)] = 1.0;
            nonneg.push(kinds[(c - nlp) / nj.max(1)]);
            var += 1;
        }
    }
    Ok(Variables { t, nonneg, ranges })
}

/// Fits the cells (and the free joint-space columns) to a reduced regressor over the free
/// columns; returns the fit (β, the free parameters; standard deviations and condition
/// number of the least-squares problem) and the cell masses per link.
#[allow(clippy::too_many_arguments)]
pub fn fit_cells(
    red: &Reduced,
    base: &Base,
    free: &[usize],
    prior: &[f64],
    prior_weight: f64,
    links: &[LinkCells],
    extras: &Extras,
    model: &Model,
) -> Result<(Fit, Vec<Vec<f64>>)> {
    let vars = variables(free, links, extras, model)?;
    let g = &red.r * &vars.t;
    // The prior's rows: √w n_c (π_c − π̄_c) for each free column c, n_c the column's norm, or
    // the median norm of its kind (the same parameter of the other links, the same
    // joint-space term of the other joints) where the data hardly reach it: those are
    // exactly the directions the prior is for.
    let nprior = if prior_weight > 0.0 { free.len() } else { 0 };
    let pw = prior_scales(red, free, model)
        .into_iter()
        .map(|n| prior_weight.sqrt() * n)
        .take(nprior)
        .collect::<Vec<f64>>();
    let mut a = DMatrix::zeros(g.nrows() + nprior, g.ncols());
    a.view_mut((0, 0), g.shape()).copy_from(&g);
    let mut b = DVector::zeros(g.nrows() + nprior);
    b.rows_mut(0, g.nrows()).copy_from(&red.z);
    for c in 0..nprior {
        for v in 0..g.ncols() {
            a[(g.nrows() + c, v)] = pw[c] * vars.t[(c, v)];
        }
        b[g.nrows() + c] = pw[c] * prior[c];
    }
    let mut fit = ols(red, base, Some(prior))?;
    // The objective's unit: least squares' own residual (the noise), so that the optimum's
    // value is O(1) whatever the data's size; a fraction of the data's norm for exact data.
    let sigma = fit.rss.sqrt().max(1e-6 * b.norm()).max(1e-300);
    // Clarabel can stall (InsufficientProgress) on a badly scaled objective; the same program
    // with a coarser unit is solved, and the polish takes it to the optimum's precision.
    let mut x = solve_qp(&a, &b, &vars.nonneg, sigma)
        .or_else(|e| match e {
            Error::Singular(_) => solve_qp(&a, &b, &vars.nonneg, 100.0 * sigma),
            other => Err(other),
        })
        .or_else(|e| match e {
            Error::Singular(_) => solve_qp(&a, &b, &vars.nonneg, 1e4 * sigma),
            other => Err(other),
        })?;
    polish(&a, &b, &vars.nonneg, &vars.ranges, &mut x);
    let pi_free = &vars.t * &x;
    fit.pi = pi_free.iter().copied().collect();
    fit.beta = base.of(&fit.pi);
    let masses = vars
        .ranges
        .iter()
        .map(|r| x.as_slice()[r.clone()].to_vec())
        .collect();
    Ok((fit, masses))
}

/// Column norms of the reduced regressor, those below `1e-3` of their kind's median replaced
/// by the median (kinds: the ten link parameters by position, each joint-space term).
fn prior_scales(red: &Reduced, free: &[usize], model: &Model) -> Vec<f64> {
    let nlp = NPARAM * model.links.len();
    let nj = super::regressor::extra_joints(model).len().max(1);
    let kind = |c: usize| {
        if c < nlp {
            c % NPARAM
        } else {
            NPARAM + (c - nlp) / nj
        }
    };
    let norms: Vec<f64> = (0..free.len()).map(|k| red.r.column(k).norm()).collect();
    let mut out = norms.clone();
    for (k, &c) in free.iter().enumerate() {
        let mut same: Vec<f64> = free
            .iter()
            .enumerate()
            .filter(|&(_, &d)| kind(d) == kind(c))
            .map(|(j, _)| norms[j])
            .filter(|n| *n > 0.0)
            .collect();
        if same.is_empty() {
            continue;
        }
        same.sort_by(f64::total_cmp);
        let median = same[same.len() / 2];
        if norms[k] < 1e-3 * median {
            out[k] = median;
        }
    }
    out
}

/// `min ‖A x − b‖²` with `x_k ≥ 0` where `nonneg[k]`, on Clarabel: variables scaled to unit
/// columns, the residual `e = A x − b` as variables of a diagonal objective (so the
/// matrices stay sparse however many cells), and a tiny `‖x‖²` that makes the
/// solution unique (the polish removes its bias).
fn solve_qp(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    nonneg: &[bool],
    sigma: f64,
) -> Result<DVector<f64>> {
    let (m, n) = a.shape();
    let scale: Vec<f64> = (0..n)
        .map(|v| {
            let c = a.column(v).norm();
            if c > 0.0 {
                1.0 / c
            } else {
                1.0
            }
        })
        .collect();
    let nz = n + m;
    // Objective ½ zᵀ P z: ‖e‖² + ε ‖u‖².
    let eps = 1e-10;
    let (mut pr, mut pc, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..nz {
        pr.push(k);
        pc.push(k);
        pv.push(if k < n { 2.0 * eps } else { 2.0 });
    }
    let p = CscMatrix::new_from_triplets(nz, nz, pr, pc, pv);
    let q = vec![0.0; nz];
    let (mut ar, mut ac, mut av) = (Vec::new(), Vec::new(), Vec::new());
    let mut rhs = Vec::new();
    for i in 0..m {
        for v in 0..n {
            let x = a[(i, v)] * scale[v] / sigma;
            if x != 0.0 {
                ar.push(i);
                ac.push(v);
                av.push(x);
            }
        }
        ar.push(i);
        ac.push(n + i);
        av.push(-1.0);
        rhs.push(b[i] / sigma);
    }
    let mut row = m;
    for (v, &nn) in nonneg.iter().enumerate() {
        if nn {
            ar.push(row);
            ac.push(v);
            av.push(-1.0);
            rhs.push(0.0);
            row += 1;
        }
    }
    let cones = [
        SupportedConeT::ZeroConeT(m),
        SupportedConeT::NonnegativeConeT(row - m),
    ];
    let amat = CscMatrix::new_from_triplets(row, nz, ar, ac, av);
    let mut settings = DefaultSettings::<f64> {
        verbose: false,
        ..Default::default()
    };
    settings.max_iter = 300;
    settings.tol_gap_abs = 1e-11;
    settings.tol_gap_rel = 1e-11;
    settings.tol_feas = 1e-11;
    settings.max_threads = 1;
    let mut solver = DefaultSolver::new(&p, &q, &amat, &rhs, &cones, settings).map_err(|e| {
        Error::Singular(format!(
            "identification: the cells' program could not be set up: {e}"
        ))
    })?;
    solver.set_termination_callback(|_info| {
        crate::support::interrupt::check("identification").is_err()
    });
    solver.solve();
    let sol = &solver.solution;
    match sol.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        SolverStatus::CallbackTerminated => {
            return Err(Error::Interrupted("identification".into()))
        }
        other => {
            return Err(Error::Singular(format!(
            "identification: the cells' program stopped with status {other:?} after {} iterations",
            sol.iterations
        )))
        }
    }
    Ok(DVector::from_fn(n, |v, _| {
        let x = sol.x[v] * scale[v];
        if nonneg[v] {
            x.max(0.0)
        } else {
            x
        }
    }))
}

/// Least-squares steps on the variables in use (cells above a relative threshold of their
/// link's largest, and every joint-space variable): Lawson–Hanson's inner loop, each step
/// cut where a variable reaches zero, which then leaves the set, while the residual falls.
fn polish(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    nonneg: &[bool],
    ranges: &[std::ops::Range<usize>],
    x: &mut DVector<f64>,
) {
    let n = x.len();
    let mut cost = (a * &*x - b).norm_squared();
    let mut used = vec![true; n];
    for r in ranges {
        let top = x.as_slice()[r.clone()]
            .iter()
            .fold(0.0f64, |m, v| m.max(*v));
        for v in r.clone() {
            used[v] = x[v] > 1e-9 * top;
        }
    }
    for _ in 0..30 {
        let cols: Vec<usize> = (0..n).filter(|&v| used[v]).collect();
        let sub = DMatrix::from_fn(a.nrows(), cols.len(), |i, j| a[(i, cols[j])]);
        let resid = b - a * &*x;
        let Ok(step) = sub
            .clone()
            .svd(true, true)
            .solve(&resid, 1e-13 * sub.amax())
        else {
            return;
        };
        let mut alpha = 1.0f64;
        let mut blocking = None;
        for (j, &v) in cols.iter().enumerate() {
            if nonneg[v] && step[j] < 0.0 && x[v] / -step[j] < alpha {
                alpha = x[v] / -step[j];
                blocking = Some(v);
            }
        }
        let mut trial = x.clone();
        for (j, &v) in cols.iter().enumerate() {
            trial[v] = x[v] + alpha * step[j];
            if nonneg[v] {
                trial[v] = trial[v].max(0.0);
            }
        }
        if let Some(v) = blocking {
            trial[v] = 0.0;
            used[v] = false;
        }
        let c = (a * &trial - b).norm_squared();
        if !(c <= cost) {
            return;
        }
        *x = trial;
        cost = c;
        if blocking.is_none() {
            return;
        }
    }
}
