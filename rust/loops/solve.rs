//! Dynamics with loops: the tree's accelerations corrected by the cut joints' multipliers,
//! and the projections onto the constraint manifolds.
//!
//! Forward dynamics (range-space form, docs/loops.md): with `a₀` the tree's accelerations
//! (the body-frame articulated-body recursion, unchanged) and `M = L Lᵀ` (composite bodies),
//! `Y = L⁻¹ Jᵀ`, the multipliers solve `(YᵀY) λ = −γ − J a₀` and `q̈ = a₀ + L⁻ᵀ Y λ`.
//! `YᵀY = J M⁻¹ Jᵀ` is singular exactly when constraints are redundant (a planar loop closed
//! by a spatial joint); its pivoted Cholesky finds the rank and drops the dependent rows,
//! which leaves `q̈` unique. Cost: one `n³/6` factorization, `m` triangular solves and an
//! `m³/6` one for `m` constraint rows, next to the O(n) recursion.
use nalgebra::{DMatrix, DVector};

use super::constraints::{self, Constraints, LoopKinematics};
use super::factor::{self, back_substitute, forward_substitute, solve_semidefinite};
use crate::error::{Error, Result};
use crate::model::Model;
use crate::recursive::{self, Data};

/// Buffers of the constrained dynamics and projections, sized once per model.
pub struct LoopSolver {
    pub kin: LoopKinematics,
    pub cons: Constraints,
    /// The mass matrix, then its Cholesky factor (lower triangle).
    mass: DMatrix<f64>,
    /// `L⁻¹ Jᵀ` (nv × m).
    y: DMatrix<f64>,
    /// The constraint-space matrix (m × m), factored in place.
    a: DMatrix<f64>,
    rhs: DVector<f64>,
    pub lambda: DVector<f64>,
    /// Constraint rows with a non-zero Jacobian row at the last solve.
    active: Vec<usize>,
    perm: Vec<usize>,
    work: Vec<f64>,
    /// nv-long scratch (a step in v, a column).
    step: Vec<f64>,
    /// nq-long scratch (q̇ of a step).
    qdot: Vec<f64>,
    /// Rank of the constraint Jacobian at the last solve.
    pub rank: usize,
    /// Largest residual met before a projection (the integrator's drift).
    pub max_drift: f64,
}

impl LoopSolver {
    pub fn new(model: &Model) -> Self {
        let (m, n) = (model.nconstraints(), model.nv);
        LoopSolver {
            kin: LoopKinematics::new(model),
            cons: Constraints::new(model),
            mass: DMatrix::zeros(n, n),
            y: DMatrix::zeros(n, m),
            a: DMatrix::zeros(m, m),
            rhs: DVector::zeros(m),
            lambda: DVector::zeros(m),
            active: Vec::with_capacity(m),
            perm: vec![0; m],
            work: vec![0.0; m.max(n)],
            step: vec![0.0; n],
            qdot: vec![0.0; model.nq],
            rank: 0,
            max_drift: 0.0,
        }
    }

    /// Positions, Jacobian and (with `v`) velocities and `γ` at the state.
    fn constraints_at(&mut self, model: &Model, q: &[f64], v: Option<&[f64]>) {
        self.kin.positions(model, q);
        constraints::jacobian(model, &self.kin, &mut self.cons.jacobian);
        if let Some(v) = v {
            self.kin.velocities(model, q, v);
            constraints::gamma(model, &self.kin, self.cons.gamma.as_mut_slice());
        }
    }

    fn residual_at(&mut self, model: &Model, q: &[f64]) -> f64 {
        self.kin.positions(model, q);
        constraints::residual(model, &self.kin, self.cons.residual.as_mut_slice());
        self.cons.residual.amax()
    }
}

/// Corrects the tree's accelerations `a` (from [`recursive::forward_dynamics`] at the same
/// state and forces) so that they satisfy the loops; leaves the multipliers (a basic
/// solution where constraints are redundant) in `solver.lambda`. Errors if the mass matrix is
/// singular or the loops leave the mechanism no freedom of motion.
pub fn constrained_forward_dynamics(
    model: &Model,
    data: &mut Data,
    solver: &mut LoopSolver,
    q: &[f64],
    v: &[f64],
    a: &mut [f64],
) -> Result<()> {
    let (n, m) = (model.nv, model.nconstraints());
    solver.constraints_at(model, q, Some(v));
    recursive::mass_matrix(model, data, q, &mut solver.mass);
    if let Err(k) = factor::cholesky(&mut solver.mass) {
        return Err(Error::Singular(format!(
            "the mass matrix is not positive definite (pivot {k}): a massless chain, or a body too slender"
        )));
    }
    // Rows that vanish identically (a planar loop's out-of-plane rows) are left out: they
    // carry no force and would only be dropped by the pivoting.
    solver.active.clear();
    for r in 0..m {
        if (0..n).any(|c| solver.cons.jacobian[(r, c)] != 0.0) {
            solver.active.push(r);
        }
    }
    let LoopSolver {
        cons,
        mass,
        y,
        a: s,
        rhs,
        lambda,
        perm,
        work,
        step,
        active,
        ..
    } = solver;
    let na = active.len();
    for (k, &r) in active.iter().enumerate() {
        for c in 0..n {
            step[c] = cons.jacobian[(r, c)];
        }
        forward_substitute(mass, step);
        y.column_mut(k).copy_from_slice(step);
    }
    constraint_system(y, active, cons, a, s, rhs);
    let rank = solve_semidefinite(s, na, rhs.as_slice(), work_lambda(lambda, na), perm, work);
    solver.rank = rank;
    if n > 0 && rank >= n {
        return Err(locked(model, rank));
    }
    let LoopSolver {
        mass,
        y,
        lambda,
        step,
        active,
        work,
        ..
    } = solver;
    for (c, s) in step.iter_mut().enumerate() {
        *s = (0..na).map(|k| y[(c, k)] * lambda[k]).sum();
    }
    // λ by constraint row: the active rows' values, zero for the vanishing ones.
    work[..na].copy_from_slice(&lambda.as_slice()[..na]);
    lambda.fill(0.0);
    for (k, &r) in active.iter().enumerate() {
        lambda[r] = work[k];
    }
    back_substitute(mass, step);
    for (ai, si) in a.iter_mut().zip(step.iter()) {
        *ai += si;
    }
    Ok(())
}

/// The first `n` entries of the multipliers, as the solve's output slice.
fn work_lambda(lambda: &mut DVector<f64>, n: usize) -> &mut [f64] {
    &mut lambda.as_mut_slice()[..n]
}

fn locked(model: &Model, rank: usize) -> Error {
    Error::Singular(format!(
        "the {} loop(s) leave the mechanism no freedom of motion: the constraint Jacobian has rank {rank} = nv = {} (a locked mechanism, a structure); remove a cut joint or a constraint",
        model.nloops(),
        model.nv
    ))
}

/// The multipliers' system on the active rows: `YᵀY` (`= J M⁻¹ Jᵀ`) into `s` and
/// `−γ − J a` into `rhs`.
fn constraint_system(
    y: &DMatrix<f64>,
    active: &[usize],
    cons: &Constraints,
    a: &[f64],
    s: &mut DMatrix<f64>,
    rhs: &mut DVector<f64>,
) {
    let na = active.len();
    for i in 0..na {
        for j in 0..=i {
            let d = y.column(i).dot(&y.column(j));
            s[(i, j)] = d;
            s[(j, i)] = d;
        }
    }
    for (k, &r) in active.iter().enumerate() {
        let ja: f64 = a
            .iter()
            .enumerate()
            .map(|(c, x)| cons.jacobian[(r, c)] * x)
            .sum();
        rhs[k] = -cons.gamma[r] - ja;
    }
}

/// The cut joints' wrenches at a state: per loop `[force; moment]` on body b in frame a's
/// axes (see [`constraints::wrenches`]), the minimum-norm multipliers where constraints are
/// redundant (statically indeterminate: only their resultant on the mechanism is defined).
/// `a` holds the tree's accelerations on entry and the constrained ones on return.
pub fn constraint_forces(
    model: &Model,
    data: &mut Data,
    solver: &mut LoopSolver,
    q: &[f64],
    v: &[f64],
    a: &mut [f64],
) -> Result<Vec<[f64; 6]>> {
    let a_tree = DVector::from_column_slice(a);
    constrained_forward_dynamics(model, data, solver, q, v, a)?;
    // `J M⁻¹ Jᵀ λ = −γ − J a₀` on the active rows again (`YᵀY` in the constraint-space
    // buffer), now for the minimum-norm λ (same q̈): a complete orthogonal decomposition.
    let LoopSolver {
        kin,
        cons,
        y,
        a: s,
        rhs,
        lambda,
        perm,
        work,
        active,
        ..
    } = solver;
    let na = active.len();
    constraint_system(y, active, cons, a_tree.as_slice(), s, rhs);
    factor::min_norm_solve(
        s.view_mut((0, 0), (na, na)),
        &mut rhs.as_mut_slice()[..na],
        work_lambda(lambda, na),
        perm,
        work,
        factor::RANK_TOL,
    );
    // λ by constraint row, zero for the vanishing ones.
    work[..na].copy_from_slice(&lambda.as_slice()[..na]);
    lambda.fill(0.0);
    for (k, &r) in active.iter().enumerate() {
        lambda[r] = work[k];
    }
    Ok(constraints::wrenches(model, kin, lambda.as_slice()))
}

/// Forces of the `actuated` joint coordinates (v indices) that drive the mechanism with
/// accelerations `a`, given `tau_tree`: the tree's inverse dynamics at `(q, v, a)` with all
/// effects. Solves `S_aᵀ τ_a + Jᵀ λ = τ_tree` (minimum norm); returns `τ` (zero outside the
/// actuated coordinates) and the cut joints' wrenches. Errors if `a` violates the loops or
/// the actuated joints cannot produce the motion.
pub fn driving_forces(
    model: &Model,
    solver: &mut LoopSolver,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    tau_tree: &[f64],
    actuated: &[usize],
) -> Result<(Vec<f64>, Vec<[f64; 6]>)> {
    let (n, m, na) = (model.nv, model.nconstraints(), actuated.len());
    solver.constraints_at(model, q, Some(v));
    let cons = &solver.cons;
    let ja = &cons.jacobian * DVector::from_column_slice(a) + &cons.gamma;
    let scale = 1.0 + cons.gamma.amax() + (&cons.jacobian * DVector::from_column_slice(a)).amax();
    if ja.amax() > 1e-8 * scale {
        let row = ja.iamax();
        return Err(Error::arg(
            "a",
            "accelerations that keep the loops closed (J a + J̇ v = 0; see assemble_acceleration)",
            format!(
                "J a + J̇ v = {:.3e} in row {row} (loop '{}')",
                ja[row],
                model.loops[constraints::loop_of_row(model, row)].name
            ),
        ));
    }
    // `[S_a | Jᵀ] x = τ_tree` for the minimum-norm x = (τ_a, λ).
    let cols = na + m;
    let mut sys = DMatrix::zeros(n, cols);
    for (k, &c) in actuated.iter().enumerate() {
        sys[(c, k)] = 1.0;
    }
    sys.view_mut((0, na), (n, m)).tr_copy_from(&cons.jacobian);
    let mut b = tau_tree.to_vec();
    let mut x = vec![0.0; cols];
    let (mut pivots, mut work) = (vec![0; cols], vec![0.0; cols]);
    factor::min_norm_solve(
        sys.view_mut((0, 0), (n, cols)),
        &mut b,
        &mut x,
        &mut pivots,
        &mut work,
        factor::RANK_TOL,
    );
    let mut tau = vec![0.0; n];
    for (k, &c) in actuated.iter().enumerate() {
        tau[c] += x[k];
    }
    // What the actuators and the loops leave unbalanced, from J itself (the factorization
    // overwrote `sys`); NaN counts as unbalanced.
    let lambda = &x[na..];
    for (c, r) in b.iter_mut().enumerate() {
        *r = tau_tree[c]
            - tau[c]
            - (0..m)
                .map(|k| cons.jacobian[(k, c)] * lambda[k])
                .sum::<f64>();
    }
    let required = tau_tree.iter().fold(0.0_f64, |acc, t| acc.max(t.abs()));
    if !b.iter().all(|r| r.abs() <= 1e-9 * (1.0 + required)) {
        let miss = b.iter().fold(0.0_f64, |acc, r| acc.max(r.abs()));
        return Err(Error::Singular(format!(
            "the actuated coordinates {actuated:?} cannot produce these accelerations: the forces they and the loops can exert leave {miss:.3e} of the required joint forces unbalanced (an under-actuated choice: actuate a joint that moves the mechanism)"
        )));
    }
    Ok((tau, constraints::wrenches(model, &solver.kin, lambda)))
}

/// `q ⊕ δ`: each joint's coordinates moved by the speeds `δ` for unit time, quaternions
/// renormalised (a retraction: exact to first order, all Newton's steps need).
fn retract(model: &Model, q: &mut [f64], delta: &[f64], qdot: &mut [f64]) {
    model.velocity_to_qdot(q, delta, qdot);
    for (x, d) in q.iter_mut().zip(qdot.iter()) {
        *x += d;
    }
    model.normalize(q);
}

/// `δ = −J_fᵀ (J_f J_fᵀ)⁺ c` into `solver.step` for `c` in `solver.rhs`: the minimum-norm
/// step with `J_f δ = −c` (`J_f`: the Jacobian with the `fixed` columns zeroed, which the
/// caller has done). Returns the rank.
fn min_norm_step(solver: &mut LoopSolver) -> usize {
    let LoopSolver {
        cons,
        a,
        rhs,
        lambda,
        perm,
        work,
        step,
        ..
    } = solver;
    let j = &cons.jacobian;
    for r in 0..j.nrows() {
        for c in 0..=r {
            let s = j.row(r).dot(&j.row(c));
            a[(r, c)] = s;
            a[(c, r)] = s;
        }
    }
    let m = j.nrows();
    let rank = solve_semidefinite(a, m, rhs.as_slice(), lambda.as_mut_slice(), perm, work);
    for (col, s) in step.iter_mut().enumerate() {
        *s = -(0..j.nrows()).map(|r| j[(r, col)] * lambda[r]).sum::<f64>();
    }
    rank
}

fn zero_fixed(jac: &mut DMatrix<f64>, fixed: &[bool]) {
    for (c, &f) in fixed.iter().enumerate() {
        if f {
            jac.column_mut(c).fill(0.0);
        }
    }
}

/// The closed configuration near `q_guess`: Gauss–Newton with minimum-norm steps (and step
/// halving) on the position residual, the coordinates whose v slots are `fixed` held.
/// Errors naming the loop that stays open.
pub fn assemble(
    model: &Model,
    q_guess: &[f64],
    fixed: &[bool],
    tol: f64,
    max_iterations: usize,
) -> Result<Vec<f64>> {
    let mut solver = LoopSolver::new(model);
    let mut q = q_guess.to_vec();
    model.normalize(&mut q);
    let mut trial = q.clone();
    let mut res = solver.residual_at(model, &q);
    let mut iterations = 0;
    // Past `tol`, two more steps polish the closure to round-off (Newton converges
    // quadratically; a step that does not improve ends the loop).
    let mut polish = 2;
    while (res > tol || polish > 0) && res > 0.0 && iterations < max_iterations {
        if res <= tol {
            polish -= 1;
        }
        iterations += 1;
        solver.constraints_at(model, &q, None);
        zero_fixed(&mut solver.cons.jacobian, fixed);
        solver.rhs.copy_from(&solver.cons.residual);
        min_norm_step(&mut solver);
        let mut scale = 1.0;
        let mut improved = false;
        for _ in 0..30 {
            trial.copy_from_slice(&q);
            let delta: Vec<f64> = solver.step.iter().map(|d| d * scale).collect();
            retract(model, &mut trial, &delta, &mut solver.qdot);
            let r_new = solver.residual_at(model, &trial);
            if r_new < res {
                res = r_new;
                q.copy_from_slice(&trial);
                improved = true;
                break;
            }
            scale *= 0.5;
        }
        if !improved {
            break;
        }
    }
    // Leave `solver.cons.residual` at `q` for the message.
    res = solver.residual_at(model, &q);
    if res > tol {
        let row = solver.cons.residual.iamax();
        let lp = &model.loops[constraints::loop_of_row(model, row)];
        return Err(Error::Closure(format!(
            "loop '{}' cannot be closed from this guess: after {iterations} Newton iterations its residual is still {res:.3e} (> tol = {tol:.1e}); the bodies may be unable to reach each other, or the fixed coordinates ask for a position the mechanism cannot take",
            lp.name
        )));
    }
    solver.kin.positions(model, &q);
    if let Some(k) = constraints::flipped_axis(model, &solver.kin) {
        return Err(Error::Closure(format!(
            "loop '{}' closes with its revolute axes anti-parallel (frame b's axis points against frame a's): start from a guess nearer the intended assembly",
            model.loops[k].name
        )));
    }
    Ok(q)
}

/// Projects a velocity-like vector `x` (speeds, or accelerations with `with_gamma`) onto
/// `J x (+ γ) = 0`, nearest to the given `x` with the `fixed` entries held; `q` (and `v` for
/// accelerations) must be a closed state. Errors if the held entries make it impossible.
pub fn project_velocity_like(
    model: &Model,
    q: &[f64],
    v_for_gamma: Option<&[f64]>,
    x: &mut [f64],
    fixed: &[bool],
) -> Result<()> {
    let mut solver = LoopSolver::new(model);
    solver.constraints_at(model, q, v_for_gamma);
    let jx = &solver.cons.jacobian * DVector::from_column_slice(x);
    let c = match v_for_gamma {
        Some(_) => &jx + &solver.cons.gamma,
        None => jx.clone(),
    };
    let full = solver.cons.jacobian.clone();
    zero_fixed(&mut solver.cons.jacobian, fixed);
    solver.rhs.copy_from(&c);
    min_norm_step(&mut solver);
    for (xi, s) in x.iter_mut().zip(solver.step.iter()) {
        *xi += s;
    }
    let mut after = &full * DVector::from_column_slice(x);
    if v_for_gamma.is_some() {
        after += &solver.cons.gamma;
    }
    let scale = 1.0 + jx.amax() + solver.cons.gamma.amax();
    if after.amax() > 1e-9 * scale {
        let row = after.iamax();
        return Err(Error::Closure(format!(
            "loop '{}': the held (fixed) entries leave no {} that keeps the loop closed (constraint row {row} stays at {:.3e}); hold fewer coordinates, or ones that can move independently",
            model.loops[constraints::loop_of_row(model, row)].name,
            if v_for_gamma.is_some() { "acceleration" } else { "velocity" },
            after[row]
        )));
    }
    Ok(())
}

/// Refuses a locked mechanism at `q` (the loops leave no freedom of motion): the check a run
/// makes before it starts.
pub fn check_mobility(model: &Model, solver: &mut LoopSolver, q: &[f64]) -> Result<()> {
    solver.constraints_at(model, q, None);
    solver.rhs.fill(0.0);
    let rank = min_norm_step(solver);
    if model.nv > 0 && rank >= model.nv {
        return Err(locked(model, rank));
    }
    Ok(())
}

/// The integrator's projection of `y = [q; v]` onto the position and velocity manifolds
/// (Newton to round-off, then the velocity's minimum-norm correction). Returns whether `y`
/// changed; errors if the loops drifted beyond repair.
pub fn project_state(
    model: &Model,
    solver: &mut LoopSolver,
    y: &mut [f64],
) -> std::result::Result<bool, String> {
    let (nq, nv) = (model.nq, model.nv);
    let (q, v) = y.split_at_mut(nq);
    let mut res = solver.residual_at(model, q);
    solver.max_drift = solver.max_drift.max(res);
    for _ in 0..4 {
        if res == 0.0 {
            break;
        }
        solver.constraints_at(model, q, None);
        solver.rhs.copy_from(&solver.cons.residual);
        min_norm_step(solver);
        let mut qdot = std::mem::take(&mut solver.qdot);
        retract(model, q, &solver.step, &mut qdot);
        solver.qdot = qdot;
        let r_new = solver.residual_at(model, q);
        let converged = r_new > 0.5 * res;
        res = r_new;
        if converged {
            break;
        }
    }
    if res > 1e-6 {
        return Err(format!(
            "the loops drifted open beyond repair (residual {res:.3e} after projection): tighten rtol/atol"
        ));
    }
    solver.constraints_at(model, q, None);
    for r in 0..solver.rhs.len() {
        solver.rhs[r] = (0..nv).map(|c| solver.cons.jacobian[(r, c)] * v[c]).sum();
    }
    min_norm_step(solver);
    for (x, s) in v.iter_mut().zip(&solver.step[..nv]) {
        *x += s;
    }
    Ok(true)
}
