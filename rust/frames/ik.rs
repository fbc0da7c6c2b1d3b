//! Inverse kinematics: damped least squares (Levenberg–Marquardt) on the targets' stacked
//! errors, `min ‖W (e + E δ)‖² + λ ‖δ‖²` per step, with `λ = μ ‖W e‖²` (Yamashita–Fukushima:
//! Gauss–Newton near a solution, gradient-like far from it) and `μ` raised on a rejected step.
//! The loops' and couplings' constraints hold to first order in every step (`J_c δ = −c`,
//! the minimum-norm correction plus a step in the null space of `J_c`, `null_step`); where
//! a step would leave the joint limits, the step is the same quadratic program with the
//! limits as bounds (a box QP on a tree, Clarabel with constraints). A run that does not converge restarts from pseudo-random
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
use super::null_step::NullStep;
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

/// Every buffer of a solve, allocated once in [`solve`]: an iteration allocates nothing,
/// with loops and couplings too, unless a step meets the joint limits with constraints
/// present (Clarabel's QP, [`bounded_step`]).
struct Work {
    kin: FrameKinematics,
    jac: Vec<f64>,
    /// Stacked errors `e` (target − current) and their derivative `E = ∂e/∂δ`.
    e: DVector<f64>,
    ejac: DMatrix<f64>,
    w: DVector<f64>,
    qp: BoxQp,
    /// `W E`, the Gauss–Newton matrix `EᵀW²E`, the damped one and the gradient `EᵀW²e`.
    wj: DMatrix<f64>,
    h0: DMatrix<f64>,
    h: DMatrix<f64>,
    g: DVector<f64>,
    step: DVector<f64>,
    /// Cholesky factor of `h` (row-major, lower).
    chol: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    trial: Vec<f64>,
    /// The constraints' residual and Jacobian at the iterate, the residual at a trial.
    c: DVector<f64>,
    jc: DMatrix<f64>,
    c_trial: DVector<f64>,
    loop_kin: Option<crate::loops::LoopKinematics>,
    /// The constrained step's factorisation and buffers (loops or couplings only).
    null: Option<NullStep>,
}

impl Work {
    fn new(model: &Model, rows: usize) -> Work {
        let (nv, m) = (model.nv, model.nconstraints());
        Work {
            kin: FrameKinematics::new(model),
            jac: vec![0.0; 6 * nv],
            e: DVector::zeros(rows),
            ejac: DMatrix::zeros(rows, nv),
            w: DVector::zeros(rows),
            qp: BoxQp::new(nv),
            wj: DMatrix::zeros(rows, nv),
            h0: DMatrix::zeros(nv, nv),
            h: DMatrix::zeros(nv, nv),
            g: DVector::zeros(nv),
            step: DVector::zeros(nv),
            chol: vec![0.0; nv * nv],
            lo: vec![0.0; nv],
            hi: vec![0.0; nv],
            trial: vec![0.0; model.nq],
            c: DVector::zeros(m),
            jc: DMatrix::zeros(m, nv),
            c_trial: DVector::zeros(m),
            loop_kin: (m > 0).then(|| crate::loops::LoopKinematics::new(model)),
            null: (m > 0).then(|| NullStep::new(nv, m)),
        }
    }
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
                // e_R = log(R_t Rᵀ): d(R_t Rᵀ) = −R_e [ω]× δt (world axes), so
                // de = −Jr⁻¹(e) R_eᵀ ω: each angular column of J turned by D.
                let d = jr_inv(&phi) * re.transpose();
                for c in 0..nv {
                    let jw = Vec3::new(wk.jac[c], wk.jac[nv + c], wk.jac[2 * nv + c]);
                    let col = d * jw;
                    for i in 0..3 {
                        wk.ejac[(row + i, c)] = -col[i];
                    }
                }
                for i in 0..3 {
                    wk.e[row + i] = phi[i];
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

/// The constraint residual into `c` (and with `jc` the Jacobian) at `q`; the largest
/// residual (0 without constraints).
fn constraints(
    model: &Model,
    q: &[f64],
    kin: &mut Option<crate::loops::LoopKinematics>,
    c: &mut DVector<f64>,
    jc: Option<&mut DMatrix<f64>>,
) -> f64 {
    let Some(kin) = kin else { return 0.0 };
    kin.positions(model, q);
    crate::loops::residual(model, kin, c.as_mut_slice());
    if let Some(jc) = jc {
        crate::loops::jacobian(model, kin, jc);
    }
    c.amax()
}

/// Solves `h x = −g` (`h` n × n symmetric, either storage order) by its Cholesky factor in
/// `chol`; false when `h` is not positive definite.
pub(super) fn cholesky_solve(h: &[f64], g: &[f64], chol: &mut [f64], x: &mut [f64]) -> bool {
    let n = g.len();
    for i in 0..n {
        for j in 0..=i {
            let mut s = h[i * n + j];
            for k in 0..j {
                s -= chol[i * n + k] * chol[j * n + k];
            }
            if i == j {
                if !(s > 0.0) {
                    return false;
                }
                chol[i * n + i] = s.sqrt();
            } else {
                chol[i * n + j] = s / chol[j * n + j];
            }
        }
    }
    for i in 0..n {
        let mut s = -g[i];
        for k in 0..i {
            s -= chol[i * n + k] * x[k];
        }
        x[i] = s / chol[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in i + 1..n {
            s -= chol[k * n + i] * x[k];
        }
        x[i] = s / chol[i * n + i];
    }
    true
}

/// The step as a QP with the bounds `lo ≤ δ ≤ hi` (and `J_c δ = −c`) on Clarabel. This
/// allocates (the problem's sparse matrices, Clarabel's solver and its factorisation are
/// built per call; Clarabel has no way to refill a solver's matrices in place): it is taken
/// only where a step with loops or couplings would leave the limits, or where the box QP
/// gives up (docs/kinematics.md §4).
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
    let c = constraints(model, q, &mut wk.loop_kin, &mut wk.c_trial, None);
    let cost =
        wk.e.iter()
            .zip(wk.w.iter())
            .map(|(e, w)| (e * w) * (e * w))
            .sum();
    (err.max(c), cost)
}

/// `W E`, `h0 = (W E)ᵀ W E` and `g = (W E)ᵀ W e` from the last [`evaluate`].
fn normal_equations(wk: &mut Work) {
    let (rows, nv) = wk.ejac.shape();
    for c in 0..nv {
        for i in 0..rows {
            wk.wj[(i, c)] = wk.ejac[(i, c)] * wk.w[i];
        }
    }
    for a in 0..nv {
        for b in 0..=a {
            let x: f64 = (0..rows).map(|i| wk.wj[(i, a)] * wk.wj[(i, b)]).sum();
            wk.h0[(a, b)] = x;
            wk.h0[(b, a)] = x;
        }
        wk.g[a] = (0..rows).map(|i| wk.wj[(i, a)] * (wk.e[i] * wk.w[i])).sum();
    }
}

/// The damped step from `wk.h`, `wk.g` (and the constraints at the iterate) into
/// `wk.step`, the limits' box applied; false when no step could be found.
fn damped_step(model: &Model, opts: &Options, q: &[f64], wk: &mut Work) -> bool {
    let nv = model.nv;
    if wk.jc.nrows() == 0 {
        let solved = cholesky_solve(
            wk.h.as_slice(),
            wk.g.as_slice(),
            &mut wk.chol,
            wk.step.as_mut_slice(),
        );
        if !solved {
            wk.step.fill(0.0);
        }
    } else if let Some(null) = &mut wk.null {
        null.solve(
            wk.h.as_slice(),
            wk.g.as_slice(),
            wk.c.as_slice(),
            wk.jc.as_slice(),
            wk.step.as_mut_slice(),
        );
    }
    let Some(limits) = &opts.limits else {
        return true;
    };
    step_bounds(model, q, limits, &mut wk.lo, &mut wk.hi);
    let (lo, hi) = (&wk.lo, &wk.hi);
    let outside = (0..nv).any(|k| wk.step[k] < lo[k] - 1e-15 || wk.step[k] > hi[k] + 1e-15);
    if !outside {
        return true;
    }
    // Without loop constraints, a box: the active-set solve (Clarabel where it gives up).
    let boxed = wk.jc.nrows() == 0
        && wk.qp.solve(
            wk.h.as_slice(),
            wk.g.as_slice(),
            lo,
            hi,
            wk.step.as_mut_slice(),
        );
    if !boxed {
        match bounded_step(&wk.h, &wk.g, &wk.c, &wk.jc, lo, hi) {
            Some(s) => wk.step.copy_from(&s),
            None => return false,
        }
    }
    for k in 0..nv {
        wk.step[k] = wk.step[k].clamp(lo[k].min(0.0), hi[k].max(0.0));
    }
    true
}

/// One Levenberg–Marquardt run from `q`; returns the iterations used. Allocates nothing
/// on a model without constraints (`wk` holds every buffer).
fn run(
    model: &Model,
    tasks: &[Task],
    opts: &Options,
    q: &mut [f64],
    wk: &mut Work,
) -> Result<usize> {
    let nv = model.nv;
    let mut mu = 1e-3;
    let (mut res, mut cost) = measure(model, tasks, q, wk);
    for it in 0..opts.max_iterations {
        crate::support::interrupt::check("inverse_kinematics")?;
        if res <= opts.tol {
            return Ok(it);
        }
        evaluate(model, tasks, q, wk);
        constraints(model, q, &mut wk.loop_kin, &mut wk.c, Some(&mut wk.jc));
        normal_equations(wk);
        let mut accepted = false;
        for _ in 0..12 {
            let lambda = mu * cost + 1e-14;
            wk.h.copy_from(&wk.h0);
            for k in 0..nv {
                wk.h[(k, k)] += lambda;
            }
            if !damped_step(model, opts, q, wk) {
                break;
            }
            let mut trial = std::mem::take(&mut wk.trial);
            crate::recursive::tangent::integrate(model, q, wk.step.as_slice(), &mut trial);
            model.normalize(&mut trial);
            let (r_new, c_new) = measure(model, tasks, &trial, wk);
            let better = c_new < cost || r_new < res && c_new <= cost * (1.0 + 1e-12);
            if better {
                q.copy_from_slice(&trial);
            }
            wk.trial = trial;
            if better {
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
    let mut wk = Work::new(model, rows);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The iteration allocates nothing: a whole Levenberg–Marquardt run on a 7-link chain,
    /// its steps against tight joint limits (the box QP) and a pose target, counted by the
    /// tests' counting allocator.
    #[test]
    fn iterations_allocate_nothing() {
        let model = crate::benchmark_models::chain(7);
        let nv = model.nv;
        let f = model.body_frame(model.nbodies() - 1, &Placement::identity());
        let mut goal_q = vec![0.25; nv];
        goal_q[0] = -0.4;
        let mut kin = FrameKinematics::new(&model);
        kin.positions(&model, &goal_q);
        let tasks = [Task {
            frame: f,
            target: Target::Pose(kin.frame_pose(&f)),
            weights: vec![1.0; 6],
        }];
        let opts = Options {
            tol: 1e-12,
            max_iterations: 40,
            restarts: 0,
            limits: Some((vec![-0.45; nv], vec![0.3; nv])),
            seed: 0,
        };
        let mut wk = Work::new(&model, 6);
        let mut q = vec![0.0; nv];
        // Built once per model, on first use: not the iteration's.
        model.compiled();
        let (its, allocations) =
            crate::support::alloc::counting::count(|| run(&model, &tasks, &opts, &mut q, &mut wk));
        let its = its.unwrap();
        assert!(its >= 3, "{its} iterations");
        assert_eq!(
            allocations, 0,
            "{allocations} allocations in {its} iterations"
        );
        // The limits were active on the way (else the box QP was not exercised) and hold.
        assert!(q.iter().all(|x| (-0.45..=0.3).contains(x)), "{q:?}");
    }

    /// A planar four-bar (revolute cut joint: five rows of rank two) whose coupler point
    /// reaches a point of its coupler curve, and a chain with a coupling: the constrained
    /// steps (`NullStep`) allocate nothing either, and the constraints hold at the end.
    #[test]
    fn constrained_iterations_allocate_nothing() {
        use crate::joint::Joint;
        use crate::model::body::RigidBody;
        let at = |x: f64| Placement::new(Mat3::identity(), Vec3::new(x, 0.0, 0.0));
        let rod = |l: f64| {
            let i = Mat3::from_diagonal(&Vec3::new(1e-6, l * l / 12.0, l * l / 12.0));
            RigidBody::new(1.0, Vec3::new(l / 2.0, 0.0, 0.0), i).unwrap()
        };
        let z = || Joint::revolute(Vec3::z()).unwrap();
        let mut fourbar = Model::new();
        fourbar
            .add_body(rod(0.3), z(), None, at(0.0), None, None)
            .unwrap();
        fourbar
            .add_body(rod(0.8), z(), Some(0), at(0.3), None, None)
            .unwrap();
        fourbar
            .add_body(rod(0.5), z(), None, at(0.6), None, None)
            .unwrap();
        fourbar
            .add_loop(Some(1), Some(2), z(), at(0.8), at(0.5), None)
            .unwrap();
        let mut chain = crate::benchmark_models::chain(7);
        chain.add_coupling(3, 2, 0.5, 0.1, None).unwrap();
        let mut only_3 = vec![true; chain.nv];
        only_3[3] = false;
        let cases = [
            (
                &fourbar,
                vec![true, false, false],
                [1.2, -0.9, 1.9],
                [1.5, -1.0, 2.0],
                1,
            ),
            (&chain, only_3, [0.1; 3], [0.3, -0.2, 0.4], 6),
        ];
        for (model, fixed, start, goal, body) in cases {
            let nv = model.nv;
            let closed = |x: &[f64; 3]| {
                let mut q = vec![0.2; nv];
                q[..3].copy_from_slice(x);
                crate::loops::assemble(model, &q, &fixed, 1e-14, 50).unwrap()
            };
            let goal_q = closed(&goal);
            let point = Placement::new(Mat3::identity(), Vec3::new(0.4, 0.1, 0.0));
            let f = model.body_frame(body, &point);
            let mut kin = FrameKinematics::new(model);
            kin.positions(model, &goal_q);
            let tasks = [Task {
                frame: f,
                target: Target::Position(kin.frame_pose(&f).translation),
                weights: vec![1.0; 3],
            }];
            let opts = Options {
                tol: 1e-11,
                max_iterations: 60,
                restarts: 0,
                limits: None,
                seed: 0,
            };
            let mut wk = Work::new(model, 3);
            let mut q = closed(&start);
            model.compiled();
            // The loops' row records are made on the first evaluation, not per iteration.
            measure(model, &tasks, &q, &mut wk);
            let (its, allocations) = crate::support::alloc::counting::count(|| {
                run(model, &tasks, &opts, &mut q, &mut wk)
            });
            let its = its.unwrap();
            assert!(its >= 2, "{its} iterations");
            assert_eq!(
                allocations, 0,
                "{allocations} allocations in {its} iterations"
            );
            let (res, _) = measure(model, &tasks, &q, &mut wk);
            assert!(res <= 1e-11, "residual {res}");
        }
    }
}
