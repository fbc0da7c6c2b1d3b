//! Inverse kinematics: damped least squares (Levenberg–Marquardt) on the targets' stacked
//! errors, `min ‖W (e + E δ)‖² + λ ‖δ‖²` per step, with `λ = μ ‖W e‖²` (Yamashita–Fukushima:
//! Gauss–Newton near a solution, gradient-like far from it) and `μ` raised on a rejected step.
//! The loops' and couplings' constraints hold to first order in every step (`J_c δ = −c`,
//! the minimum-norm correction plus a step in the null space of `J_c`); where a step would
//! leave the joint limits, the step is the same quadratic program with the limits as bounds,
//! solved by Clarabel. A run that does not converge restarts from pseudo-random
//! configurations within the limits and returns the best it found, saying it did not converge.
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use nalgebra::{DMatrix, DVector};

use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::{skew, Mat3, Placement, Vec3};

use super::box_qp::BoxQp;
use super::jacobian::point_jacobian_at;
use super::motion::FrameKinematics;
use super::FrameRef;

/// What a frame should reach.
#[derive(Debug, Clone, Copy)]
pub enum Target {
    /// Its origin at this world point (3 residual rows).
    Position(Vec3),
    /// Its placement (6 rows: rotation error `log(R_t Rᵀ)`, world axes, then position).
    Pose(Placement),
}

/// One target with the weights of its rows (angular then linear for a pose).
#[derive(Debug, Clone)]
pub struct Task {
    pub frame: FrameRef,
    pub target: Target,
    pub weights: Vec<f64>,
}

impl Task {
    fn rows(&self) -> usize {
        match self.target {
            Target::Position(_) => 3,
            Target::Pose(_) => 6,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Options {
    /// Converged when every row's error (unweighted, m and rad) and every constraint's
    /// residual is at most this.
    pub tol: f64,
    pub max_iterations: usize,
    /// Restarts from pseudo-random configurations after a failed run.
    pub restarts: usize,
    /// Bounds per speed (`±∞` where none); `None`: no limits.
    pub limits: Option<(Vec<f64>, Vec<f64>)>,
    pub seed: u64,
}

#[derive(Debug, Clone)]
pub struct Solution {
    pub q: Vec<f64>,
    /// The largest row error (m, rad) and constraint residual at `q`.
    pub residual: f64,
    /// Per target, its error rows at `q` (angular then linear for a pose).
    pub errors: Vec<Vec<f64>>,
    pub iterations: usize,
    pub restarts: usize,
    pub converged: bool,
    pub message: String,
}

/// `Jr⁻¹(φ)`, the inverse right Jacobian of SO(3): `log(R exp(δ)) ≈ log R + Jr⁻¹ δ`.
fn jr_inv(phi: &Vec3) -> Mat3 {
    let t = phi.norm();
    let k = skew(phi);
    let c = if t < 1e-6 {
        1.0 / 12.0 + t * t / 720.0
    } else {
        1.0 / (t * t) - (1.0 + t.cos()) / (2.0 * t * t.sin())
    };
    Mat3::identity() + k * 0.5 + k * k * c
}

/// `log R` as a rotation vector, accurate at small angles (from the skew part and the
/// trace by `atan2`, not `acos` of the trace) and near a half turn (the axis from the
/// symmetric part).
pub fn log3(r: &Mat3) -> Vec3 {
    let w = Vec3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) * 0.5;
    let (s, c) = (w.norm(), (r.trace() - 1.0) * 0.5);
    let theta = s.atan2(c);
    if c > -0.9 {
        // θ / sin θ, by its series where sin θ is tiny.
        let f = if s > 1e-6 {
            theta / s
        } else {
            1.0 + s * s / 6.0
        };
        return w * f;
    }
    // Near π: the symmetric part of R less c·1 is (1 − c) a aᵀ; its largest column gives
    // the axis, w its sign.
    let b = (r + r.transpose()) * 0.5 - Mat3::identity() * c;
    let k = (0..3)
        .max_by(|&i, &j| b[(i, i)].total_cmp(&b[(j, j)]))
        .unwrap_or(0);
    let mut a = b.column(k).into_owned();
    a /= a.norm();
    if a.dot(&w) < 0.0 {
        a = -a;
    }
    a * theta
}

struct Work {
    kin: FrameKinematics,
    jac: Vec<f64>,
    /// Stacked errors `e` (target − current) and their derivative `E = ∂e/∂δ`.
    e: DVector<f64>,
    ejac: DMatrix<f64>,
    w: DVector<f64>,
    qp: BoxQp,
}

/// The stacked errors and `E` at `q`; returns the largest unweighted error.
fn evaluate(model: &Model, tasks: &[Task], q: &[f64], wk: &mut Work) -> f64 {
    let nv = model.nv;
    // Poses and joint columns only (no inertias), revolute turns by their columns.
    crate::kinematics::frame_poses(model, q, &mut wk.kin.links);
    let mut row = 0;
    for t in tasks {
        let pose = wk.kin.frame_pose(&t.frame);
        point_jacobian_at(
            model,
            &wk.kin.links,
            t.frame.link,
            &pose.translation,
            None,
            &mut wk.jac,
        );
        let put_lin = |wk: &mut Work, row: usize, target: &Vec3| {
            let err = target - pose.translation;
            for i in 0..3 {
                wk.e[row + i] = err[i];
                for c in 0..nv {
                    wk.ejac[(row + i, c)] = -wk.jac[(3 + i) * nv + c];
                }
            }
        };
        match t.target {
            Target::Position(p) => put_lin(wk, row, &p),
            Target::Pose(p) => {
                let re = p.rotation * pose.rotation.transpose();
                let phi = log3(&re);
                // e_R = log(R_t Rᵀ): R_t Rᵀ changes by exp(−Rᵀ... ) on the right, i.e.
                // de = −Jr⁻¹(e) R_e ... in world axes: d(R_t Rᵀ) = −R_e [ω]×.
                let d = jr_inv(&phi) * re.transpose();
                let jw = DMatrix::from_fn(3, nv, |i, c| wk.jac[i * nv + c]);
                let dm = DMatrix::from_fn(3, 3, |i, j| d[(i, j)]);
                let block = -(dm * jw);
                for i in 0..3 {
                    wk.e[row + i] = phi[i];
                    for c in 0..nv {
                        wk.ejac[(row + i, c)] = block[(i, c)];
                    }
                }
                put_lin(wk, row + 3, &p.translation);
            }
        }
        for i in 0..t.rows() {
            wk.w[row + i] = t.weights[i];
        }
        row += t.rows();
    }
    wk.e.amax()
}

/// The constraint residual `c` and Jacobian `J_c` at `q` (empty without constraints).
fn constraints(model: &Model, q: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let m = model.nconstraints();
    if m == 0 {
        return (DVector::zeros(0), DMatrix::zeros(0, model.nv));
    }
    let mut kin = crate::loops::LoopKinematics::new(model);
    kin.positions(model, q);
    let mut c = DVector::zeros(m);
    crate::loops::residual(model, &kin, c.as_mut_slice());
    let mut jc = DMatrix::zeros(m, model.nv);
    crate::loops::jacobian(model, &kin, &mut jc);
    (c, jc)
}

/// The damped step, unconstrained by limits: `δ = δ_c + N z` (`δ_c` the minimum-norm
/// correction of the constraints, `N` a basis of their null space).
fn free_step(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    c: &DVector<f64>,
    jc: &DMatrix<f64>,
) -> DVector<f64> {
    let nv = h.nrows();
    if jc.nrows() == 0 {
        return match h.clone().cholesky() {
            Some(ch) => ch.solve(&(-g)),
            None => DVector::zeros(nv),
        };
    }
    let scale = 1e-10 * (1.0 + jc.amax());
    let svd = jc.clone().svd(true, true);
    let dc = svd
        .solve(&(-c), scale)
        .unwrap_or_else(|_| DVector::zeros(nv));
    let basis = null_basis(jc);
    let hn = basis.transpose() * h * &basis;
    let gn = basis.transpose() * (g + h * &dc);
    let z = match hn.cholesky() {
        Some(ch) => ch.solve(&(-gn)),
        None => DVector::zeros(basis.ncols()),
    };
    dc + basis * z
}

/// An orthonormal basis of the null space of `jc` (eigenvectors of `J_cᵀ J_c` at zero).
fn null_basis(jc: &DMatrix<f64>) -> DMatrix<f64> {
    let nv = jc.ncols();
    let eig = (jc.transpose() * jc).symmetric_eigen();
    let tol = 1e-12 * (1.0 + jc.amax()).powi(2);
    let keep: Vec<usize> = (0..nv).filter(|&k| eig.eigenvalues[k] <= tol).collect();
    eig.eigenvectors.select_columns(keep.iter())
}

/// The step as a QP with the bounds `lo ≤ δ ≤ hi` (and `J_c δ = −c`) on Clarabel.
fn bounded_step(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    c: &DVector<f64>,
    jc: &DMatrix<f64>,
    lo: &[f64],
    hi: &[f64],
) -> Option<DVector<f64>> {
    let nv = h.nrows();
    let (mut pr, mut pc, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..nv {
        for i in 0..=j {
            if h[(i, j)] != 0.0 {
                pr.push(i);
                pc.push(j);
                pv.push(h[(i, j)]);
            }
        }
    }
    let p = CscMatrix::new_from_triplets(nv, nv, pr, pc, pv);
    let (mut ar, mut ac, mut av, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut cones = Vec::new();
    let m = jc.nrows();
    for i in 0..m {
        for j in 0..nv {
            if jc[(i, j)] != 0.0 {
                ar.push(i);
                ac.push(j);
                av.push(jc[(i, j)]);
            }
        }
        b.push(-c[i]);
    }
    if m > 0 {
        cones.push(SupportedConeT::ZeroConeT(m));
    }
    let mut rows = m;
    for j in 0..nv {
        for (bound, sign) in [(hi[j], 1.0), (lo[j], -1.0)] {
            if bound.is_finite() {
                ar.push(rows);
                ac.push(j);
                av.push(sign);
                b.push(sign * bound);
                rows += 1;
            }
        }
    }
    cones.push(SupportedConeT::NonnegativeConeT(rows - m));
    let a = CscMatrix::new_from_triplets(rows, nv, ar, ac, av);
    let settings = DefaultSettings::<f64> {
        verbose: false,
        max_iter: 100,
        tol_gap_abs: 1e-12,
        tol_gap_rel: 1e-12,
        tol_feas: 1e-12,
        max_threads: 1,
        ..Default::default()
    };
    let mut solver = DefaultSolver::new(&p, g.as_slice(), &a, &b, &cones, settings).ok()?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            Some(DVector::from_vec(solver.solution.x.clone()))
        }
        _ => None,
    }
}

/// Speed-space bounds of a step from `q` (the coordinates with a bound have nq = nv = 1).
fn step_bounds(
    model: &Model,
    q: &[f64],
    limits: &(Vec<f64>, Vec<f64>),
    lo: &mut [f64],
    hi: &mut [f64],
) {
    for l in &model.links {
        let n = l.joint.nv();
        for k in 0..n {
            let iv = l.v_index + k;
            let (a, b) = (limits.0[iv], limits.1[iv]);
            if n == l.joint.nq() && (a.is_finite() || b.is_finite()) {
                let x = q[l.q_index + k];
                lo[iv] = a - x;
                hi[iv] = b - x;
            } else {
                lo[iv] = f64::NEG_INFINITY;
                hi[iv] = f64::INFINITY;
            }
        }
    }
}

/// `q` moved into the limits (coordinates with nq = nv = 1 only).
fn clamp(model: &Model, q: &mut [f64], limits: &(Vec<f64>, Vec<f64>)) {
    for l in &model.links {
        if l.joint.nq() == l.joint.nv() {
            for k in 0..l.joint.nv() {
                let (a, b) = (limits.0[l.v_index + k], limits.1[l.v_index + k]);
                let x = &mut q[l.q_index + k];
                if a <= b {
                    *x = x.clamp(a, b);
                }
            }
        }
    }
}

/// The largest error and constraint residual at `q`, and the weighted cost.
fn measure(model: &Model, tasks: &[Task], q: &[f64], wk: &mut Work) -> (f64, f64) {
    let err = evaluate(model, tasks, q, wk);
    let (c, _) = constraints(model, q);
    let cost = wk.e.component_mul(&wk.w).norm_squared();
    (err.max(c.amax()), cost)
}

/// One Levenberg–Marquardt run from `q`; returns the iterations used.
fn run(
    model: &Model,
    tasks: &[Task],
    opts: &Options,
    q: &mut Vec<f64>,
    wk: &mut Work,
) -> Result<usize> {
    let nv = model.nv;
    let (mut lo, mut hi) = (vec![0.0; nv], vec![0.0; nv]);
    let mut mu = 1e-3;
    let mut trial = q.clone();
    let (mut res, mut cost) = measure(model, tasks, q, wk);
    for it in 0..opts.max_iterations {
        crate::support::interrupt::check("inverse_kinematics")?;
        if res <= opts.tol {
            return Ok(it);
        }
        evaluate(model, tasks, q, wk);
        let (c, jc) = constraints(model, q);
        let we = wk.ejac.clone();
        let mut wj = we.clone();
        for (i, w) in wk.w.iter().enumerate() {
            wj.row_mut(i).scale_mut(*w);
        }
        let werr = wk.e.component_mul(&wk.w);
        let h0 = wj.transpose() * &wj;
        let g = wj.transpose() * &werr;
        let mut accepted = false;
        for _ in 0..12 {
            let lambda = mu * cost + 1e-14;
            let h = &h0 + DMatrix::identity(nv, nv) * lambda;
            let mut step = free_step(&h, &g, &c, &jc);
            if let Some(limits) = &opts.limits {
                step_bounds(model, q, limits, &mut lo, &mut hi);
                let outside = (0..nv).any(|k| step[k] < lo[k] - 1e-15 || step[k] > hi[k] + 1e-15);
                if outside {
                    // Without loop constraints, a box: the active-set solve (Clarabel
                    // where it gives up).
                    let boxed = jc.nrows() == 0
                        && wk
                            .qp
                            .solve(h.as_slice(), g.as_slice(), &lo, &hi, step.as_mut_slice());
                    if !boxed {
                        match bounded_step(&h, &g, &c, &jc, &lo, &hi) {
                            Some(s) => step = s,
                            None => break,
                        }
                    }
                    for k in 0..nv {
                        step[k] = step[k].clamp(lo[k].min(0.0), hi[k].max(0.0));
                    }
                }
            }
            crate::recursive::tangent::integrate(model, q, step.as_slice(), &mut trial);
            model.normalize(&mut trial);
            let (r_new, c_new) = measure(model, tasks, &trial, wk);
            if c_new < cost || r_new < res && c_new <= cost * (1.0 + 1e-12) {
                q.copy_from_slice(&trial);
                (res, cost) = (r_new, c_new);
                mu = (mu * 0.3).max(1e-8);
                accepted = true;
                break;
            }
            mu *= 10.0;
        }
        if !accepted {
            return Ok(it + 1);
        }
    }
    Ok(opts.max_iterations)
}

/// A small deterministic generator (SplitMix64) for the restarts.
fn next_uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// A pseudo-random configuration: within the limits where there are any, angles in
/// (−π, π] elsewhere; quaternions and free-flyer positions as in `q0`.
fn random_start(model: &Model, q0: &[f64], opts: &Options, state: &mut u64) -> Vec<f64> {
    let mut q = q0.to_vec();
    for l in &model.links {
        if l.joint.nq() != l.joint.nv() {
            continue;
        }
        for k in 0..l.joint.nv() {
            let u = next_uniform(state);
            let (a, b) = match &opts.limits {
                Some((lo, hi))
                    if lo[l.v_index + k].is_finite() && hi[l.v_index + k].is_finite() =>
                {
                    (lo[l.v_index + k], hi[l.v_index + k])
                }
                _ => (-std::f64::consts::PI, std::f64::consts::PI),
            };
            q[l.q_index + k] = a + (b - a) * u;
        }
    }
    q
}

/// Solves the tasks from `q0` (checked by the caller). Never loops forever: at most
/// `(restarts + 1) · max_iterations` iterations.
pub fn solve(model: &Model, tasks: &[Task], q0: &[f64], opts: &Options) -> Result<Solution> {
    if tasks.is_empty() {
        return Err(Error::arg("targets", "at least one target", "none"));
    }
    let rows: usize = tasks.iter().map(Task::rows).sum();
    let mut wk = Work {
        kin: FrameKinematics::new(model),
        jac: vec![0.0; 6 * model.nv],
        e: DVector::zeros(rows),
        ejac: DMatrix::zeros(rows, model.nv),
        w: DVector::zeros(rows),
        qp: BoxQp::new(model.nv),
    };
    let mut state = opts.seed ^ 0x5EED;
    let mut best: Option<(f64, Vec<f64>)> = None;
    let mut iterations = 0;
    let mut restarts = 0;
    for attempt in 0..=opts.restarts {
        let mut q = match attempt {
            0 => q0.to_vec(),
            _ => random_start(model, q0, opts, &mut state),
        };
        if let Some(limits) = &opts.limits {
            clamp(model, &mut q, limits);
        }
        iterations += run(model, tasks, opts, &mut q, &mut wk)?;
        let (res, _) = measure(model, tasks, &q, &mut wk);
        if best.as_ref().is_none_or(|(r, _)| res < *r) {
            best = Some((res, q));
        }
        restarts = attempt;
        if res <= opts.tol {
            break;
        }
    }
    let (residual, q) = best.expect("at least one attempt");
    measure(model, tasks, &q, &mut wk);
    let mut errors = Vec::with_capacity(tasks.len());
    let mut row = 0;
    for t in tasks {
        errors.push(wk.e.as_slice()[row..row + t.rows()].to_vec());
        row += t.rows();
    }
    let converged = residual <= opts.tol;
    let message = if converged {
        format!(
            "converged: largest error {residual:.3e} <= tol {:.1e}",
            opts.tol
        )
    } else {
        format!(
            "not converged: the closest configuration found leaves an error of {residual:.3e} (> tol {:.1e}) after {iterations} iterations and {restarts} restarts; the target may be out of reach, outside the joint limits or at a singular configuration",
            opts.tol
        )
    };
    Ok(Solution {
        q,
        residual,
        errors,
        iterations,
        restarts,
        converged,
        message,
    })
}

/// The position limits of the model's joints per speed (its records': URDF `<limit>`, MJCF
/// ranges), `±∞` where none.
pub fn joint_limits(model: &Model) -> (Vec<f64>, Vec<f64>) {
    let mut lo = vec![f64::NEG_INFINITY; model.nv];
    let mut hi = vec![f64::INFINITY; model.nv];
    for j in &model.records.joints {
        if let (Some(v), Some(lim), "revolute" | "prismatic") = (j.v_index, j.limit, j.kind) {
            if v < model.nv && lim.lower <= lim.upper {
                lo[v] = lim.lower;
                hi[v] = lim.upper;
            }
        }
    }
    (lo, hi)
}
