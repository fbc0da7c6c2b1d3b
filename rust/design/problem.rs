//! The design as a conic program for Clarabel: RMS objectives make a QP, peak (minimax over
//! time of vector norms) objectives an SOCP, `limits` are ε-constraints in the same norm.
//!
//! Variables: the design masses `x` (bounded), the change `δ = M x` of the designed links'
//! inertial parameters (the objectives depend on `x` only through it: ten numbers per link,
//! so the dense rows stay narrow however many cells or candidates there are), and one
//! epigraph variable per peak objective. Each quantity is `y = R δ + c` (blocks of `dim`
//! rows, one vector per block) divided by its `reference` (its unbalanced value), so the
//! weights compare relative changes.
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Norm {
    /// Root mean square over the samples of the blocks' squared norms: a QP.
    Rms,
    /// The largest block norm over the motion: an SOCP.
    Peak,
}

/// One quantity along the motion, `y = rows · δ + constant`.
#[derive(Debug, Clone)]
pub struct Quantity {
    pub name: String,
    /// (blocks · dim) × nδ.
    pub rows: DMatrix<f64>,
    pub constant: DVector<f64>,
    /// Rows per vector whose norm counts (3 for a force, na for the driving forces).
    pub dim: usize,
    /// Samples of the motion (RMS: the mean is over them, summing a sample's blocks).
    pub samples: usize,
    pub weight: f64,
    /// Its value before the design, in the problem's norm (the scale of the weight).
    pub reference: f64,
    /// ε-constraint: at most this, in the problem's norm (absolute units).
    pub limit: Option<f64>,
    /// Must vanish at every sample (linear equalities).
    pub zero: bool,
}

/// A design problem: bounds and maps of the design masses, and the quantities.
#[derive(Debug, Clone)]
pub struct Problem {
    pub lower: Vec<f64>,
    /// `f64::INFINITY` for no upper bound.
    pub upper: Vec<f64>,
    /// `δ = M x`, M (nδ × nx) as `(row, column, value)` triplets.
    pub map: Vec<(usize, usize, f64)>,
    pub ndelta: usize,
    /// `lo ≤ Σ_{j ∈ set} x_j ≤ hi` (a link's mass range).
    pub groups: Vec<(Vec<usize>, f64, f64)>,
    /// `x_a = x_b` (a planar link kept symmetric about its plane).
    pub equal: Vec<(usize, usize)>,
    pub quantities: Vec<Quantity>,
    pub norm: Norm,
    /// Weight of the design's total mass `Σ x / mass_reference` in the objective.
    pub mass_weight: f64,
    pub mass_reference: f64,
    pub mass_limit: Option<f64>,
    /// After the optimum, take the least total mass among the optima (a second solve).
    pub least_mass: bool,
}

/// What the solver found.
#[derive(Debug, Clone)]
pub struct Solution {
    pub x: Vec<f64>,
    pub delta: Vec<f64>,
    /// Each quantity's value in the problem's norm (absolute units).
    pub values: Vec<f64>,
    pub status: String,
    pub objective: f64,
    pub gap_abs: f64,
    pub gap_rel: f64,
    pub iterations: u32,
    pub solve_time: f64,
    /// Whether the final active-set refinement was kept (RMS problems without limits).
    pub refined: bool,
}

/// Rows and values of the conic program, built block by block (cones in order).
#[derive(Default)]
struct Builder {
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
}

impl Builder {
    fn m(&self) -> usize {
        self.b.len()
    }
    /// Starts a row with right-hand side `b` (entries added with `put`).
    fn row(&mut self, b: f64) -> usize {
        self.b.push(b);
        self.b.len() - 1
    }
    fn put(&mut self, r: usize, c: usize, v: f64) {
        if v != 0.0 {
            self.rows.push(r);
            self.cols.push(c);
            self.vals.push(v);
        }
    }
    fn cone(&mut self, cone: SupportedConeT<f64>) {
        // Merge runs of zero and nonnegative rows.
        match (self.cones.last_mut(), &cone) {
            (Some(SupportedConeT::ZeroConeT(n)), SupportedConeT::ZeroConeT(k)) => *n += k,
            (Some(SupportedConeT::NonnegativeConeT(n)), SupportedConeT::NonnegativeConeT(k)) => {
                *n += k
            }
            _ => self.cones.push(cone),
        }
    }
}

/// `U_rᵀ [R | c]` for the rows of R that matter: an orthonormal basis of R's row space with
/// the matching right-hand side, and the part of `c` outside R's column space (which no
/// design removes).
fn row_space(r: &DMatrix<f64>, c: &DVector<f64>) -> (DMatrix<f64>, DVector<f64>, f64) {
    // Tall: first a QR (its R factor has the same row space), then an SVD of the square.
    let (rr, cc, lost) = if r.nrows() > r.ncols() + 1 {
        let mut aug = DMatrix::zeros(r.nrows(), r.ncols() + 1);
        aug.view_mut((0, 0), (r.nrows(), r.ncols())).copy_from(r);
        aug.column_mut(r.ncols()).copy_from(c);
        let t = aug.qr().r();
        let n = r.ncols();
        let lost = if t.nrows() > n { t[(n, n)].abs() } else { 0.0 };
        let rr = t.view((0, 0), (n.min(t.nrows()), n)).into_owned();
        let cc = t.view((0, n), (n.min(t.nrows()), 1)).column(0).into_owned();
        (rr, cc, lost)
    } else {
        (r.clone(), c.clone(), 0.0)
    };
    let svd = rr.clone().svd(true, true);
    let (u, vt) = (svd.u.unwrap_or_default(), svd.v_t.unwrap_or_default());
    let smax = svd.singular_values.amax();
    let keep: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&k| svd.singular_values[k] > 1e-11 * smax)
        .collect();
    let mut rows = DMatrix::zeros(keep.len(), r.ncols());
    let mut rhs = DVector::zeros(keep.len());
    let mut inside = DVector::zeros(cc.len());
    for (k, &j) in keep.iter().enumerate() {
        let uj = u.column(j);
        let s = svd.singular_values[j];
        rows.row_mut(k).copy_from(&(vt.row(j) * s));
        rhs[k] = uj.dot(&cc);
        inside += uj * rhs[k];
    }
    let outside = (lost * lost + (cc - inside).norm_squared()).sqrt();
    (rows, rhs, outside)
}

/// `T` with `‖T [δ; 1]‖² = Σ ‖R δ + c‖²` (the R factor of `[R | c]`), scaled by `scale`.
fn compress(r: &DMatrix<f64>, c: &DVector<f64>, scale: f64) -> DMatrix<f64> {
    let n = r.ncols();
    let mut aug = DMatrix::zeros(r.nrows().max(n + 1), n + 1);
    aug.view_mut((0, 0), (r.nrows(), n)).copy_from(r);
    aug.view_mut((0, n), (r.nrows(), 1)).copy_from(c);
    aug.qr().r() * scale
}

/// Each quantity's value at `δ` in `norm` (absolute units).
pub fn values(problem: &Problem, delta: &[f64]) -> Vec<f64> {
    let d = DVector::from_column_slice(delta);
    problem
        .quantities
        .iter()
        .map(|q| {
            let y = &q.rows * &d + &q.constant;
            let blocks = y.len() / q.dim.max(1);
            let norms = (0..blocks).map(|b| y.rows(b * q.dim, q.dim).norm_squared());
            match problem.norm {
                Norm::Rms => (norms.sum::<f64>() / q.samples.max(1) as f64).sqrt(),
                Norm::Peak => norms.fold(0.0_f64, f64::max).sqrt(),
            }
        })
        .collect()
}

fn check(problem: &Problem) -> Result<()> {
    let nx = problem.lower.len();
    if problem.upper.len() != nx {
        return Err(Error::arg(
            "upper",
            format!("{nx} bounds"),
            format!("{}", problem.upper.len()),
        ));
    }
    for (j, (&lo, &hi)) in problem.lower.iter().zip(&problem.upper).enumerate() {
        if !lo.is_finite() || hi.is_nan() || hi < lo {
            return Err(Error::arg(
                "bounds",
                "finite lower bounds not above the upper ones",
                format!("[{lo}, {hi}] for design mass {j}"),
            ));
        }
    }
    for &(r, c, v) in &problem.map {
        if r >= problem.ndelta || c >= nx || !v.is_finite() {
            return Err(Error::arg(
                "map",
                "finite entries inside (nδ × nx)",
                format!("({r}, {c}, {v})"),
            ));
        }
    }
    for q in &problem.quantities {
        if q.rows.ncols() != problem.ndelta || q.rows.nrows() != q.constant.len() || q.dim == 0 {
            return Err(Error::arg(
                format!("quantity '{}'", q.name),
                format!("rows × {} with a constant per row", problem.ndelta),
                format!("{:?}, {} constants", q.rows.shape(), q.constant.len()),
            ));
        }
        crate::error::check_finite(&q.name, q.rows.as_slice())?;
        crate::error::check_finite(&q.name, q.constant.as_slice())?;
    }
    Ok(())
}

/// Builds and solves the program (twice with `least_mass`). Errors: infeasible limits or
/// equalities (naming them and by how much where it can), or the solver's status.
pub fn solve(problem: &Problem) -> Result<Solution> {
    check(problem)?;
    let first = solve_stage(problem, None)?;
    if !problem.least_mass {
        return Ok(first);
    }
    // Among the optima, the least mass: the objective held at its optimum (to the solver's
    // accuracy) and the total mass minimised.
    match solve_stage(problem, Some(&first)) {
        Ok(second) => Ok(second),
        // The second solve only refines; its failure leaves the optimum found.
        Err(Error::Interrupted(w)) => Err(Error::Interrupted(w)),
        Err(_) => Ok(first),
    }
}

/// What no design meets, named: the zero quantities, the limits, the masses' bounds.
fn infeasible(problem: &Problem) -> Error {
    let zero: Vec<&str> = problem
        .quantities
        .iter()
        .filter(|q| q.zero)
        .map(|q| q.name.as_str())
        .collect();
    let mut limits: Vec<String> = problem
        .quantities
        .iter()
        .filter_map(|q| {
            q.limit
                .map(|l| format!("{} <= {l:.4e} (before: {:.4e})", q.name, q.reference))
        })
        .collect();
    if let Some(m) = problem.mass_limit {
        limits.push(format!("mass <= {m:.4e} kg"));
    }
    let arg = if zero.is_empty() { "limits" } else { "zero" };
    Error::arg(
        arg,
        "requirements some design within the masses' bounds (and link mass ranges) meets",
        format!(
            "zero {zero:?} and limits [{}] that none meets (Clarabel's certificate of primal \
             infeasibility): relax them, or give the design more room (candidates, envelopes, \
             mass ranges)",
            limits.join(", ")
        ),
    )
}

struct Layout {
    nx: usize,
    nd: usize,
    /// Peak objectives: quantity index and its epigraph variable.
    peaks: Vec<(usize, usize)>,
}

#[allow(clippy::too_many_lines)]
fn solve_stage(problem: &Problem, optimum: Option<&Solution>) -> Result<Solution> {
    // One function: the blocks of the program in cone order (zero, nonnegative, SOC);
    // splitting it would pass the same builder and layout through every piece.
    let (nx, nd) = (problem.lower.len(), problem.ndelta);
    let weighted: Vec<usize> = (0..problem.quantities.len())
        .filter(|&k| problem.quantities[k].weight > 0.0 && !problem.quantities[k].zero)
        .collect();
    let peaks: Vec<(usize, usize)> = match problem.norm {
        Norm::Peak => weighted
            .iter()
            .enumerate()
            .map(|(j, &k)| (k, nx + nd + j))
            .collect(),
        Norm::Rms => vec![],
    };
    let lay = Layout { nx, nd, peaks };
    let nz = lay.nx + lay.nd + lay.peaks.len();
    let mut bld = Builder::default();
    // Zero cone: δ = M x, the zero quantities, equal pairs.
    for j in 0..nd {
        let r = bld.row(0.0);
        bld.put(r, nx + j, 1.0);
    }
    for &(r, c, v) in &problem.map {
        bld.put(r, c, -v);
    }
    bld.cone(SupportedConeT::ZeroConeT(nd));
    for q in problem.quantities.iter().filter(|q| q.zero) {
        let scale = 1.0 / q.reference.max(1e-300);
        let (rows, rhs, outside) = row_space(&(&q.rows * scale), &(&q.constant * scale));
        let total = (&q.constant * scale).norm();
        if outside > 1e-9 * (1.0 + total) {
            return Err(Error::arg(
                "zero",
                format!(
                    "a quantity the design masses can make vanish ('{}')",
                    q.name
                ),
                format!(
                    "a part no design reaches ({:.3e} of its unbalanced value)",
                    outside / total.max(1e-300)
                ),
            ));
        }
        for k in 0..rows.nrows() {
            let r = bld.row(-rhs[k]);
            for j in 0..nd {
                bld.put(r, nx + j, rows[(k, j)]);
            }
        }
        bld.cone(SupportedConeT::ZeroConeT(rows.nrows()));
    }
    for &(a, b) in &problem.equal {
        let r = bld.row(0.0);
        bld.put(r, a, 1.0);
        bld.put(r, b, -1.0);
        bld.cone(SupportedConeT::ZeroConeT(1));
    }
    // The RMS optimum's objective vector is unique: the second stage holds it.
    let mut p_dense = DMatrix::<f64>::zeros(nd, nd);
    let mut q_vec = vec![0.0; nz];
    let mut constant = 0.0;
    if problem.norm == Norm::Rms {
        let mut stacked: Vec<DMatrix<f64>> = Vec::new();
        for &k in &weighted {
            let q = &problem.quantities[k];
            let s = 1.0 / (q.reference.max(1e-300) * (q.samples.max(1) as f64).sqrt());
            let t = compress(&q.rows, &q.constant, s * q.weight.sqrt());
            let (td, t1) = (t.columns(0, nd).into_owned(), t.column(nd).into_owned());
            p_dense += td.transpose() * &td * 2.0;
            let g = td.transpose() * &t1 * 2.0;
            for j in 0..nd {
                q_vec[nx + j] += g[j];
            }
            constant += t1.norm_squared();
            stacked.push(t);
        }
        if let Some(opt) = optimum {
            let d = DVector::from_column_slice(&opt.delta);
            for t in &stacked {
                let td = t.columns(0, nd);
                let target = td * &d;
                let (rows, rhs, _) = row_space(&td.into_owned(), &(-target));
                for k in 0..rows.nrows() {
                    let r = bld.row(-rhs[k]);
                    for j in 0..nd {
                        bld.put(r, nx + j, rows[(k, j)]);
                    }
                }
                bld.cone(SupportedConeT::ZeroConeT(rows.nrows()));
            }
        }
    }
    // Nonnegative cone: bounds, groups, mass limit, peak limits with a weight.
    let n0 = bld.m();
    for j in 0..nx {
        let r = bld.row(-problem.lower[j]);
        bld.put(r, j, -1.0);
        if problem.upper[j].is_finite() {
            let r = bld.row(problem.upper[j]);
            bld.put(r, j, 1.0);
        }
    }
    for (set, lo, hi) in &problem.groups {
        let r = bld.row(*hi);
        set.iter().for_each(|&j| bld.put(r, j, 1.0));
        let r = bld.row(-*lo);
        set.iter().for_each(|&j| bld.put(r, j, -1.0));
    }
    if let Some(limit) = problem.mass_limit {
        let r = bld.row(limit);
        (0..nx).for_each(|j| bld.put(r, j, 1.0));
    }
    for &(k, t) in &lay.peaks {
        let q = &problem.quantities[k];
        if let Some(limit) = q.limit {
            let r = bld.row(limit / q.reference.max(1e-300));
            bld.put(r, t, 1.0);
        }
        q_vec[t] += q.weight;
    }
    if let (Some(opt), Norm::Peak) = (optimum, problem.norm) {
        // Σ w t ≤ the optimum, with the solver's own slack.
        let bound = opt.objective * (1.0 + 1e-9) + 1e-12;
        let r = bld.row(bound);
        for &(k, t) in &lay.peaks {
            bld.put(r, t, problem.quantities[k].weight);
        }
    }
    let nonneg = bld.m() - n0;
    bld.cone(SupportedConeT::NonnegativeConeT(nonneg));
    // Second-order cones: peak objectives and limits, RMS limits.
    for (k, q) in problem.quantities.iter().enumerate() {
        if q.zero {
            continue;
        }
        let s = 1.0 / q.reference.max(1e-300);
        let t_var = lay.peaks.iter().find(|(kk, _)| *kk == k).map(|(_, t)| *t);
        match problem.norm {
            Norm::Peak if t_var.is_some() || q.limit.is_some() => {
                let blocks = q.rows.nrows() / q.dim;
                for b in 0..blocks {
                    match t_var {
                        Some(t) => {
                            let r = bld.row(0.0);
                            bld.put(r, t, -1.0);
                        }
                        None => {
                            bld.row(q.limit.unwrap_or(0.0) * s);
                        }
                    }
                    for i in 0..q.dim {
                        let row = b * q.dim + i;
                        let r = bld.row(q.constant[row] * s);
                        for j in 0..nd {
                            bld.put(r, nx + j, -q.rows[(row, j)] * s);
                        }
                    }
                    bld.cone(SupportedConeT::SecondOrderConeT(q.dim + 1));
                }
            }
            Norm::Rms if q.limit.is_some() => {
                let scale = s / (q.samples.max(1) as f64).sqrt();
                let t = compress(&q.rows, &q.constant, scale);
                bld.row(q.limit.unwrap_or(0.0) * s);
                for i in 0..t.nrows() {
                    let r = bld.row(t[(i, nd)]);
                    for j in 0..nd {
                        bld.put(r, nx + j, -t[(i, j)]);
                    }
                }
                bld.cone(SupportedConeT::SecondOrderConeT(t.nrows() + 1));
            }
            _ => {}
        }
    }
    // The mass term: the objective's own, or the whole objective of the second stage.
    let mass_scale = 1.0 / problem.mass_reference.max(1e-300);
    let (p_dense, q_vec, constant) = if optimum.is_some() {
        let mut q2 = vec![0.0; nz];
        q2[..nx].iter_mut().for_each(|x| *x = mass_scale);
        (DMatrix::zeros(nd, nd), q2, 0.0)
    } else {
        let mut q1 = q_vec;
        q1[..nx]
            .iter_mut()
            .for_each(|x| *x += problem.mass_weight * mass_scale);
        (p_dense, q1, constant)
    };
    let mut pr = vec![];
    let mut pc = vec![];
    let mut pv = vec![];
    for c in 0..nd {
        for r in 0..=c {
            let v = 0.5 * (p_dense[(r, c)] + p_dense[(c, r)]);
            if v != 0.0 {
                pr.push(nx + r);
                pc.push(nx + c);
                pv.push(v);
            }
        }
    }
    let p = CscMatrix::new_from_triplets(nz, nz, pr, pc, pv);
    let a = CscMatrix::new_from_triplets(bld.m(), nz, bld.rows, bld.cols, bld.vals);
    let mut settings = DefaultSettings::<f64>::default();
    settings.verbose = false;
    settings.max_iter = 200;
    settings.tol_gap_abs = 1e-10;
    settings.tol_gap_rel = 1e-10;
    settings.tol_feas = 1e-10;
    settings.max_threads = 1;
    let mut solver =
        DefaultSolver::new(&p, &q_vec, &a, &bld.b, &bld.cones, settings).map_err(|e| {
            Error::Singular(format!(
                "design: the conic program could not be set up: {e}"
            ))
        })?;
    solver.set_termination_callback(|_info| crate::interrupt::check("design").is_err());
    solver.solve();
    let sol = &solver.solution;
    let status = sol.status;
    match status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        SolverStatus::CallbackTerminated => return Err(Error::Interrupted("design".into())),
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            return Err(infeasible(problem));
        }
        other => {
            return Err(Error::Singular(format!(
                "design: the conic solver stopped with status {other:?} after {} iterations (gap {:.2e})",
                sol.iterations, solver.info.gap_rel
            )))
        }
    }
    let x: Vec<f64> = sol.x[..nx].to_vec();
    let delta: Vec<f64> = sol.x[nx..nx + nd].to_vec();
    let mut out = Solution {
        values: values(problem, &delta),
        x,
        delta,
        status: format!("{status:?}"),
        objective: sol.obj_val + constant,
        gap_abs: solver.info.gap_abs,
        gap_rel: solver.info.gap_rel,
        iterations: sol.iterations,
        solve_time: sol.solve_time,
        refined: false,
    };
    if let Some(first) = optimum {
        // The objective is that of the first stage.
        out.objective = first.objective;
    }
    Ok(out)
}
