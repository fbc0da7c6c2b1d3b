//! One conic program of a design (crate::design::problem) for Clarabel, built block by block
//! in cone order (zero, nonnegative, second-order), and solved.
//!
//! Variables: the design masses `x` (bounded), the change `δ = M x` of the designed links'
//! inertial parameters (the objectives depend on `x` only through it: ten numbers per link,
//! so the dense rows stay narrow however many cells or candidates there are), one epigraph
//! variable per peak objective, and in phase 1 one slack per relaxed requirement. Each
//! quantity is `y = R δ + c` (blocks of `dim` rows, one vector per block) divided by its
//! `reference` (its unbalanced value), so the weights compare relative changes.
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use nalgebra::{DMatrix, DVector};

use super::problem::{Norm, Problem, Quantity, Solution};
use crate::support::error::{Error, Result};

/// What a stage of the design minimises.
#[derive(Clone, Copy)]
pub(crate) enum Stage<'a> {
    /// The weighted objectives (and the mass term).
    Optimum,
    /// The least total mass among the optima the first stage found.
    LeastMass(&'a Solution),
    /// Phase 1 of an infeasible program: the least summed relaxation of the limits and the
    /// zero quantities (each relative to its value before; the mass limit relative to the
    /// model's mass) that some design meets; `Some(j)`: only the j-th of them relaxed (the
    /// others held).
    Relax(Option<usize>),
}

/// The blocks (a sample's vector) of each quantity whose cones are in a peak program: the
/// cutting-plane loop's active samples (unused with RMS, where no block has a cone).
pub(crate) type Active = Vec<Vec<usize>>;

/// Where the variables are: `[x | δ | epigraphs | slacks]`.
pub(crate) struct Layout {
    pub nx: usize,
    pub nd: usize,
    /// (quantity, its epigraph variable) of each peak objective.
    peaks: Vec<(usize, usize)>,
    /// (quantity, or None for the mass limit; its slack variable) in phase 1.
    pub slacks: Vec<(Option<usize>, usize)>,
    /// The first of the connected links' flow variables (super::connectivity).
    flows: usize,
    nz: usize,
}

impl Layout {
    pub fn new(problem: &Problem, stage: Stage) -> Self {
        let (nx, nd) = (problem.lower.len(), problem.ndelta);
        let (mut peaks, mut slacks, mut next) = (vec![], vec![], nx + nd);
        for (k, q) in problem.quantities.iter().enumerate() {
            let own = match stage {
                Stage::Relax(_) => q.zero || q.limit.is_some(),
                _ => problem.norm == Norm::Peak && q.weight > 0.0 && !q.zero,
            };
            if own {
                match stage {
                    Stage::Relax(_) => slacks.push((Some(k), next)),
                    _ => peaks.push((k, next)),
                }
                next += 1;
            }
        }
        if matches!(stage, Stage::Relax(_)) && problem.mass_limit.is_some() {
            slacks.push((None, next));
            next += 1;
        }
        let flows = next;
        next += problem.flows.iter().map(|f| f.count()).sum::<usize>();
        Layout {
            nx,
            nd,
            peaks,
            slacks,
            flows,
            nz: next,
        }
    }
    fn epigraph(&self, k: usize) -> Option<usize> {
        self.peaks.iter().find(|p| p.0 == k).map(|p| p.1)
    }
    fn slack(&self, k: Option<usize>) -> Option<usize> {
        self.slacks.iter().find(|s| s.0 == k).map(|s| s.1)
    }
}

/// The right-hand side of a quantity's norm constraint `‖y / reference‖ ≤ bound`.
pub(crate) enum Bound {
    Epigraph(usize),
    /// A limit (relative to the reference), plus a slack variable in phase 1.
    Limit(f64, Option<usize>),
}

impl Bound {
    /// Its value at the solution `z`.
    pub fn value(&self, z: &[f64]) -> f64 {
        match *self {
            Bound::Epigraph(t) => z[t],
            Bound::Limit(l, s) => l + s.map_or(0.0, |s| z[s]),
        }
    }
}

/// `1 / reference`: quantities enter the program relative to their value before.
pub(crate) fn scale(q: &Quantity) -> f64 {
    1.0 / q.reference.max(1e-300)
}

/// Quantity k's norm constraint in this stage, if it has one.
pub(crate) fn bound(problem: &Problem, lay: &Layout, stage: Stage, k: usize) -> Option<Bound> {
    let q = &problem.quantities[k];
    if let Some(sl) = lay.slack(Some(k)) {
        let asked = if q.zero { 0.0 } else { q.limit.unwrap_or(0.0) };
        return Some(Bound::Limit(asked * scale(q), Some(sl)));
    }
    if matches!(stage, Stage::Relax(_)) || q.zero {
        return None;
    }
    if let Some(t) = lay.epigraph(k) {
        return Some(Bound::Epigraph(t));
    }
    q.limit.map(|l| Bound::Limit(l * scale(q), None))
}

/// What Clarabel returned for one program.
pub(crate) struct Raw {
    pub z: Vec<f64>,
    pub status: SolverStatus,
    pub objective: f64,
    pub gap_abs: f64,
    pub gap_rel: f64,
    pub iterations: u32,
    pub solve_time: f64,
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
    /// Rows `rhs_k − rows_k · δ` (δ from column `at`).
    fn dense(&mut self, at: usize, rows: &DMatrix<f64>, rhs: &DVector<f64>) {
        for k in 0..rows.nrows() {
            let r = self.row(rhs[k]);
            for j in 0..rows.ncols() {
                self.put(r, at + j, rows[(k, j)]);
            }
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

/// The RMS objective's factors: `Σ_k T_k` squared is the weighted sum of mean squares.
fn rms_factors(problem: &Problem) -> Vec<DMatrix<f64>> {
    if problem.norm != Norm::Rms {
        return vec![];
    }
    problem
        .quantities
        .iter()
        .filter(|q| q.weight > 0.0 && !q.zero && !q.peak)
        .map(|q| {
            let s = scale(q) / (q.samples.max(1) as f64).sqrt();
            compress(&q.rows, &q.constant, s * q.weight.sqrt())
        })
        .collect()
}

/// Zero cone: δ = M x, the zero quantities, equal pairs, and (second RMS stage) the
/// objective vector held at the optimum's (it is unique).
fn equalities(bld: &mut Builder, problem: &Problem, lay: &Layout, stage: Stage) -> Result<()> {
    let (nx, nd) = (lay.nx, lay.nd);
    for j in 0..nd {
        let r = bld.row(0.0);
        bld.put(r, nx + j, 1.0);
    }
    for &(r, c, v) in &problem.map {
        bld.put(r, c, -v);
    }
    bld.cone(SupportedConeT::ZeroConeT(nd));
    let zero = problem.quantities.iter().filter(|q| q.zero);
    for q in zero.filter(|_| !matches!(stage, Stage::Relax(_))) {
        let s = scale(q);
        let (rows, rhs, outside) = row_space(&(&q.rows * s), &(&q.constant * s));
        let total = (&q.constant * s).norm();
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
        bld.dense(nx, &rows, &(-rhs));
        bld.cone(SupportedConeT::ZeroConeT(rows.nrows()));
    }
    for &(a, b) in &problem.equal {
        let r = bld.row(0.0);
        bld.put(r, a, 1.0);
        bld.put(r, b, -1.0);
        bld.cone(SupportedConeT::ZeroConeT(1));
    }
    if let (Stage::LeastMass(opt), Norm::Rms) = (stage, problem.norm) {
        let d = DVector::from_column_slice(&opt.delta);
        for t in rms_factors(problem) {
            let td = t.columns(0, nd).into_owned();
            let target = &td * &d;
            let (rows, rhs, _) = row_space(&td, &(-target));
            bld.dense(nx, &rows, &(-rhs));
            bld.cone(SupportedConeT::ZeroConeT(rows.nrows()));
        }
    }
    Ok(())
}

/// Nonnegative cone: bounds, link mass ranges, the mass limit, limits on peak objectives,
/// (second peak stage) the objective held at its optimum, (phase 1) slacks ≥ 0.
fn inequalities(bld: &mut Builder, problem: &Problem, lay: &Layout, stage: Stage) {
    let (n0, nx) = (bld.m(), lay.nx);
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
        if let Some(sl) = lay.slack(None) {
            bld.put(r, sl, -1.0);
        }
    }
    for &(k, t) in &lay.peaks {
        let q = &problem.quantities[k];
        if let Some(limit) = q.limit {
            let r = bld.row(limit * scale(q));
            bld.put(r, t, 1.0);
        }
    }
    if let (Stage::LeastMass(opt), Norm::Peak) = (stage, problem.norm) {
        // Σ w t ≤ the optimum relaxed by LEAST_MASS_HOLD (relative; plus twice the first
        // stage's relative gap, and an absolute floor for an optimum of zero): held to 1e-9
        // it leaves the program no interior and Clarabel stops numerically (issue 39).
        let hold = LEAST_MASS_HOLD + 2.0 * opt.gap_rel.max(0.0);
        let weights: f64 = lay
            .peaks
            .iter()
            .map(|&(k, _)| problem.quantities[k].weight)
            .sum();
        let r = bld.row(opt.objective * (1.0 + hold) + LEAST_MASS_FLOOR * weights);
        for &(k, t) in &lay.peaks {
            bld.put(r, t, problem.quantities[k].weight);
        }
    }
    for (j, &(_, sl)) in lay.slacks.iter().enumerate() {
        let r = bld.row(0.0);
        bld.put(r, sl, -1.0);
        if matches!(stage, Stage::Relax(Some(only)) if only != j) {
            let r = bld.row(0.0);
            bld.put(r, sl, 1.0);
        }
    }
    let count = bld.m() - n0;
    bld.cone(SupportedConeT::NonnegativeConeT(count));
}

/// Second-order cones: each quantity's norm against its bound — one cone per active block
/// (peak), or one for the whole motion (RMS).
fn cones(bld: &mut Builder, problem: &Problem, lay: &Layout, stage: Stage, active: &Active) {
    let (nx, nd) = (lay.nx, lay.nd);
    for (k, q) in problem.quantities.iter().enumerate() {
        let Some(bound) = bound(problem, lay, stage, k) else {
            continue;
        };
        let head = |bld: &mut Builder| match bound {
            Bound::Epigraph(t) => {
                let r = bld.row(0.0);
                bld.put(r, t, -1.0);
            }
            Bound::Limit(l, sl) => {
                let r = bld.row(l);
                if let Some(sl) = sl {
                    bld.put(r, sl, -1.0);
                }
            }
        };
        let s = scale(q);
        match q.norm(problem.norm) {
            Norm::Peak => {
                for &b in &active[k] {
                    head(bld);
                    for row in b * q.dim..(b + 1) * q.dim {
                        let r = bld.row(q.constant[row] * s);
                        for j in 0..nd {
                            bld.put(r, nx + j, -q.rows[(row, j)] * s);
                        }
                    }
                    bld.cone(SupportedConeT::SecondOrderConeT(q.dim + 1));
                }
            }
            Norm::Rms => {
                let t = compress(&q.rows, &q.constant, s / (q.samples.max(1) as f64).sqrt());
                head(bld);
                let rows = -t.columns(0, nd).into_owned();
                bld.dense(nx, &rows, &t.column(nd).into_owned());
                bld.cone(SupportedConeT::SecondOrderConeT(t.nrows() + 1));
            }
        }
    }
}

/// The objective `½ zᵀ P z + qᵀ z + constant` of the stage.
fn objective(problem: &Problem, lay: &Layout, stage: Stage) -> (CscMatrix<f64>, Vec<f64>, f64) {
    let (nx, nd) = (lay.nx, lay.nd);
    let mass_scale = 1.0 / problem.mass_reference.max(1e-300);
    let mut p_dense = DMatrix::<f64>::zeros(nd, nd);
    let mut q = vec![0.0; lay.nz];
    let mut constant = 0.0;
    match stage {
        Stage::Relax(_) => {
            for &(k, sl) in &lay.slacks {
                q[sl] = if k.is_some() { 1.0 } else { mass_scale };
            }
        }
        Stage::LeastMass(_) => q[..nx].iter_mut().for_each(|x| *x = mass_scale),
        Stage::Optimum => {
            for t in rms_factors(problem) {
                let (td, t1) = (t.columns(0, nd), t.column(nd));
                p_dense += td.transpose() * td * 2.0;
                let g = td.transpose() * t1 * 2.0;
                (0..nd).for_each(|j| q[nx + j] += g[j]);
                constant += t1.norm_squared();
            }
            for &(k, t) in &lay.peaks {
                q[t] += problem.quantities[k].weight;
            }
            let w = problem.mass_weight * mass_scale;
            q[..nx].iter_mut().for_each(|x| *x += w);
        }
    }
    let (mut pr, mut pc, mut pv) = (vec![], vec![], vec![]);
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
    let p = CscMatrix::new_from_triplets(lay.nz, lay.nz, pr, pc, pv);
    (p, q, constant)
}

/// How far (relative) the least-mass stage of a peak program may raise the first stage's
/// optimal objective (docs/design.md §3): room for the interior point method, far below any
/// trade-off a designer sees.
pub const LEAST_MASS_HOLD: f64 = 1e-6;
/// The hold's absolute part per unit weight (peaks are relative to their values before).
const LEAST_MASS_FLOOR: f64 = 1e-9;

/// Solves of one program before a numerical failure is reported (see [`settings`]).
const ATTEMPTS: usize = 3;

/// Clarabel's settings for the `attempt`-th solve of a program: tolerances 1e-10, then
/// Clarabel's defaults (1e-8), then those with a hundred times its static regularisation.
fn settings(attempt: usize) -> DefaultSettings<f64> {
    let tol = if attempt == 0 { 1e-10 } else { 1e-8 };
    let mut settings = DefaultSettings::<f64> {
        verbose: false,
        max_iter: 200,
        tol_gap_abs: tol,
        tol_gap_rel: tol,
        tol_feas: tol,
        max_threads: 1,
        ..Default::default()
    };
    if attempt >= 2 {
        settings.static_regularization_constant *= 100.0;
    }
    settings
}

/// Builds and solves one program; `None` when Clarabel certifies it infeasible.
pub(crate) fn solve_program(
    problem: &Problem,
    lay: &Layout,
    stage: Stage,
    active: &Active,
) -> Result<Option<Raw>> {
    let mut bld = Builder::default();
    equalities(&mut bld, problem, lay, stage)?;
    inequalities(&mut bld, problem, lay, stage);
    cones(&mut bld, problem, lay, stage, active);
    // Connected links: flows through the cells' faces (linear rows; docs/design.md §3).
    let mut rows = super::connectivity::Rows {
        rows: &mut bld.rows,
        cols: &mut bld.cols,
        vals: &mut bld.vals,
        b: &mut bld.b,
        cones: &mut bld.cones,
    };
    super::connectivity::append(&mut rows, &problem.flows, &problem.upper, lay.flows);
    let (p, mut q, constant) = objective(problem, lay, stage);
    let cs = column_scales(problem, lay);
    for (v, &c) in bld.vals.iter_mut().zip(&bld.cols) {
        *v *= cs[c];
    }
    q.iter_mut().zip(&cs).for_each(|(v, s)| *v *= s);
    let p = scale_quadratic(p, &cs);
    let a = CscMatrix::new_from_triplets(bld.m(), lay.nz, bld.rows, bld.cols, bld.vals);
    // Tight tolerances first; a program with many degenerate rows (connected links' flows
    // through empty cells, limits at the edge of what is reachable) can stop Clarabel with a
    // numerical error there, so it is solved again at Clarabel's default tolerances (1e-8),
    // then with more static regularisation, before the failure is reported.
    // The least-mass stage of connected links starts with the third (more regularisation):
    // with the objective held at its optimum the flows' degenerate rows have little
    // interior, and there it converges in as many iterations to "Solved" where the first
    // often reaches only "AlmostSolved" (issue 39's four-bar and fronts).
    let order: [usize; ATTEMPTS] = match stage {
        Stage::LeastMass(_) if !problem.flows.is_empty() => [2, 0, 1],
        _ => [0, 1, 2],
    };
    let (mut tried, mut spent) = (0, (0, 0.0));
    let (solver, status) = loop {
        let attempt = order[tried];
        let mut solver = DefaultSolver::new(&p, &q, &a, &bld.b, &bld.cones, settings(attempt))
            .map_err(|e| {
                Error::Singular(format!(
                    "design: the conic program could not be set up: {e}"
                ))
            })?;
        solver
            .set_termination_callback(|_info| crate::support::interrupt::check("design").is_err());
        solver.solve();
        let status = solver.solution.status;
        let numerical = matches!(
            status,
            SolverStatus::NumericalError
                | SolverStatus::InsufficientProgress
                | SolverStatus::MaxIterations
        );
        if !numerical || tried == ATTEMPTS - 1 {
            break (solver, status);
        }
        // (The failed attempts' work is counted in the report.)
        spent = (
            spent.0 + solver.solution.iterations,
            spent.1 + solver.solution.solve_time,
        );
        tried += 1;
    };
    let sol = &solver.solution;
    match status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        SolverStatus::CallbackTerminated => return Err(Error::Interrupted("design".into())),
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => return Ok(None),
        other => {
            return Err(Error::Singular(format!(
                "design: the conic solver stopped with status {other:?} after {} iterations (gap {:.2e})",
                sol.iterations, solver.info.gap_rel
            )))
        }
    }
    Ok(Some(Raw {
        z: sol.x.iter().zip(&cs).map(|(z, s)| z * s).collect(),
        status: sol.status,
        objective: sol.obj_val + constant,
        gap_abs: solver.info.gap_abs,
        gap_rel: solver.info.gap_rel,
        iterations: sol.iterations + spent.0,
        solve_time: sol.solve_time + spent.1,
    }))
}

/// Each variable's scale: the program is solved in `z / scale` (Clarabel's equilibration
/// scales rows and columns of the constraints only within bounds; design masses of 1e-4 kg
/// beside second moments of 1e-7 kg m² leave it ill-conditioned). Cells and bounded
/// candidates: their upper bound (the fill); δ: the most its parameter can change.
pub(crate) fn column_scales(problem: &Problem, lay: &Layout) -> Vec<f64> {
    let mut cs = vec![1.0; lay.nz];
    let finite: Vec<f64> = problem
        .upper
        .iter()
        .copied()
        .filter(|u| u.is_finite() && *u > 0.0)
        .collect();
    let typical = if finite.is_empty() {
        1.0
    } else {
        finite.iter().sum::<f64>() / finite.len() as f64
    };
    for j in 0..lay.nx {
        let u = problem.upper[j];
        cs[j] = if u.is_finite() && u > 0.0 { u } else { typical };
    }
    let mut reach = vec![0.0; lay.nd];
    for &(r, c, v) in &problem.map {
        reach[r] += v.abs() * cs[c];
    }
    for (j, r) in reach.iter().enumerate() {
        if *r > 0.0 && r.is_finite() {
            cs[lay.nx + j] = *r;
        }
    }
    cs
}

fn scale_quadratic(p: CscMatrix<f64>, cs: &[f64]) -> CscMatrix<f64> {
    let mut p = p;
    for c in 0..p.n {
        for k in p.colptr[c]..p.colptr[c + 1] {
            p.nzval[k] *= cs[p.rowval[k]] * cs[c];
        }
    }
    p
}
