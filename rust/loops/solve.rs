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
use super::ordering;
use crate::linalg::cholesky::{self as factor, back_substitute, forward_substitute};
use crate::linalg::rank_qr::RankQr;
use crate::model::Model;
use crate::recursive::{self, Data};
use crate::support::error::{Error, Result};

/// Buffers of the constrained dynamics and projections, sized once per model.
pub struct LoopSolver {
    pub kin: LoopKinematics,
    pub cons: Constraints,
    /// The mass matrix, then its Cholesky factor (lower triangle), in the solver's order.
    mass: DMatrix<f64>,
    /// The solver's order of the coordinates (banded QRs: `ordering`): `order[i]` is the
    /// model's v index at position `i`; `J`'s columns, `M`, `L` and `Y` are taken in it.
    order: Vec<usize>,
    /// Whether `order` is not the identity: then `M` is formed in `mass_model` and copied
    /// within each position's tree, `..tree_end[i]`, and the results mapped back.
    permuted: bool,
    tree_end: Vec<usize>,
    mass_model: DMatrix<f64>,
    /// One past the last nonzero row of each column of the Cholesky factor.
    mass_ends: Vec<usize>,
    /// `Jᵀ` of the active rows, factored rank-revealing: the rank and the independent rows,
    /// decided on the Jacobian itself (dense with column pivoting, or banded: [`RankQr`]).
    qr_j: RankQr,
    /// `L⁻¹ J_Bᵀ` of the independent rows, factored (no pivoting) for the multipliers.
    qr_y: RankQr,
    /// Whether the QRs are the banded ones (a long mechanism with a sparse Jacobian).
    pub envelope: bool,
    /// Each constraint row's nonzero positions at the last factorisation: `lo..hi`.
    row_lo: Vec<usize>,
    row_hi: Vec<usize>,
    /// The positions each row can touch (its cut joint's two paths to the root; all for a
    /// coupling): `struct_lo..struct_hi`.
    struct_lo: Vec<usize>,
    struct_hi: Vec<usize>,
    pub lambda: DVector<f64>,
    rhs: DVector<f64>,
    /// Constraint rows with a non-zero Jacobian row at the last solve.
    active: Vec<usize>,
    /// m-long scratch (right-hand sides in pivoted order).
    work: Vec<f64>,
    /// nv-long scratch (a step in v, a column), in the model's order.
    step: Vec<f64>,
    /// nv-long scratch in the solver's order.
    pstep: Vec<f64>,
    /// nq-long scratch (q̇ of a step).
    qdot: Vec<f64>,
    /// Rank of the constraint Jacobian at the last solve.
    pub rank: usize,
    /// Largest residual met before a projection (the integrator's drift).
    pub max_drift: f64,
    /// The configuration `qr_j` was last factored at by [`project_state`]'s velocity step,
    /// when nothing has refactored it nor moved `kin` since: the dynamics at the same `q`
    /// (a projected stage) reuse it, `cons.jacobian` and `kin`'s positions.
    qr_q: Vec<f64>,
    qr_valid: bool,
}

/// Relative size of a pivot of `Jᵀ`'s QR below which its row counts as dependent: exactly
/// dependent rows leave ~1e-16 of the largest, a mechanism 1e-7 from a singular position
/// leaves 1e-7, so anything in between separates them.
pub const RANK_REL_TOL: f64 = 1e-11;

/// Off the constraint manifold by a residual `‖Φ‖`, rows dependent on it are independent by
/// `≤ 0.1 ‖Φ‖₂` (measured on Bricard's mechanism, whose sixth row is redundant only when
/// closed): a pivot below `SPURIOUS · ‖Φ‖₂` is taken as dependent (a margin of 10).
pub const SPURIOUS: f64 = 1.0;

/// The residual-scaled tolerance never exceeds this fraction of the largest row of `J`.
pub const SPURIOUS_CAP: f64 = 1e-3;

impl LoopSolver {
    pub fn new(model: &Model) -> Self {
        Self::with_envelope(model, ordering::envelope_pays(model))
    }

    /// The solver with the banded (`envelope`) or the dense QRs; [`LoopSolver::new`] picks.
    pub fn with_envelope(model: &Model, envelope: bool) -> Self {
        let (m, n) = (model.nconstraints(), model.nv);
        // The dense QRs' cost does not depend on the order: the model's is kept.
        let chosen = if envelope {
            ordering::choose(model)
        } else {
            None
        };
        let permuted = chosen.is_some();
        let (order, tree_end) = match chosen {
            Some(c) => (c.order, c.tree_end),
            None => ((0..n).collect(), vec![n; n]),
        };
        let (mut struct_lo, mut struct_hi) = (vec![0; m], vec![n; m]);
        ordering::structural_rows(
            model,
            &ordering::inverse(&order),
            &mut struct_lo,
            &mut struct_hi,
        );
        let side = if permuted { n } else { 0 };
        LoopSolver {
            kin: LoopKinematics::new(model),
            cons: Constraints::new(model),
            mass: DMatrix::zeros(n, n),
            order,
            permuted,
            tree_end,
            mass_model: DMatrix::zeros(side, side),
            mass_ends: vec![0; n],
            qr_j: RankQr::new(n, m, envelope),
            qr_y: RankQr::new(n, m.min(n), envelope),
            envelope,
            row_lo: vec![0; m],
            row_hi: vec![0; m],
            struct_lo,
            struct_hi,
            lambda: DVector::zeros(m),
            rhs: DVector::zeros(m),
            active: Vec::with_capacity(m),
            work: vec![0.0; m.max(n)],
            step: vec![0.0; n],
            pstep: vec![0.0; n],
            qdot: vec![0.0; model.nq],
            rank: 0,
            max_drift: 0.0,
            qr_q: vec![0.0; model.nq],
            qr_valid: false,
        }
    }

    /// Positions, Jacobian and (with `v`) velocities and `γ` at the state; returns the
    /// position residual's 2-norm.
    fn constraints_at(&mut self, model: &Model, q: &[f64], v: Option<&[f64]>) -> f64 {
        self.kin.positions(model, q);
        constraints::residual(model, &self.kin, self.cons.residual.as_mut_slice());
        self.qr_valid = false;
        self.fill_jacobian(model);
        if let Some(v) = v {
            self.kin.velocities(model, q, v);
            constraints::gamma(model, &self.kin, self.cons.gamma.as_mut_slice());
        }
        self.cons.residual.norm()
    }

    /// How close to dependent the rows kept at the last factorisation are
    /// ([`crate::linalg::rank_qr::RankQr::pivot_ratio`]); after [`project_state`], those of
    /// the projected state.
    pub fn pivot_ratio(&self) -> f64 {
        self.qr_j.pivot_ratio()
    }

    /// The log-volume of the rows kept at the last factorisation
    /// ([`crate::linalg::rank_qr::RankQr::log_volume`]).
    pub fn log_volume(&self) -> f64 {
        self.qr_j.log_volume()
    }

    /// With one degree of freedom left at the last factorisation of `Jᵀ` (after
    /// [`project_state`]: at the projected state): the unit vector spanning the kernel of the
    /// kept rows, oriented as their generalized cross product in increasing row order
    /// (`det[J_B; tᵀ] > 0`), into `kernel` (length nv); the kept rows, sorted, into `rows`;
    /// `order` is scratch. That orientation is a polynomial in `J`'s entries: it turns
    /// continuously along a motion and reverses where the kept rows pass through a
    /// dependence (a singular position of the mechanism), not where one coordinate partition
    /// is singular (a dead point of a crank). False with more (or no) freedom of motion.
    pub fn oriented_kernel(
        &self,
        kernel: &mut [f64],
        rows: &mut Vec<usize>,
        order: &mut Vec<usize>,
    ) -> bool {
        let mut sign = self.qr_j.kernel_sign(kernel);
        if sign == 0.0 {
            return false;
        }
        let rank = self.qr_j.rank();
        rows.clear();
        rows.extend((0..rank).map(|k| self.active[self.qr_j.perm()[k]]));
        // The parity of the permutation that sorts the kept rows: rank minus its cycles.
        order.clear();
        order.extend(0..rank);
        order.sort_unstable_by_key(|&k| rows[k]);
        let mut cycles = 0;
        for start in 0..rank {
            if order[start] == usize::MAX {
                continue;
            }
            cycles += 1;
            let mut k = start;
            while order[k] != usize::MAX {
                let next = order[k];
                order[k] = usize::MAX;
                k = next;
            }
        }
        if (rank - cycles) % 2 == 1 {
            sign = -sign;
        }
        rows.sort_unstable();
        for x in kernel.iter_mut() {
            *x *= sign;
        }
        true
    }

    /// The rank the last factorisation found.
    pub fn rank(&self) -> usize {
        self.qr_j.rank()
    }

    /// The Jacobian at the positions of the last [`LoopSolver::residual_at`] (whose residual
    /// `cons.residual` holds); returns the residual's 2-norm.
    fn jacobian_here(&mut self, model: &Model) -> f64 {
        self.qr_valid = false;
        self.fill_jacobian(model);
        self.cons.residual.norm()
    }

    /// `cons.jacobian` at the positions of `kin`, clearing only the coordinates each row
    /// can touch (the others stay zero).
    fn fill_jacobian(&mut self, model: &Model) {
        constraints::jacobian_within(
            model,
            &self.kin,
            &mut self.cons.jacobian,
            &self.struct_lo,
            &self.struct_hi,
            &self.order,
        );
    }

    fn residual_at(&mut self, model: &Model, q: &[f64]) -> f64 {
        self.qr_valid = false;
        self.kin.positions(model, q);
        constraints::residual(model, &self.kin, self.cons.residual.as_mut_slice());
        self.cons.residual.amax()
    }

    /// The solver's order of the coordinates: `order()[i]` is the model's v index at
    /// position `i` of the factorisations (the identity unless the banded QRs reorder).
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// `M` in the solver's order, factored (`Err(k)`: pivot `k` not positive).
    fn factor_mass(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
    ) -> std::result::Result<(), usize> {
        if !self.permuted {
            recursive::mass_matrix(model, data, q, &mut self.mass);
            return factor::cholesky(&mut self.mass, &mut self.mass_ends);
        }
        recursive::mass_matrix(model, data, q, &mut self.mass_model);
        let n = model.nv;
        let (src, dst) = (self.mass_model.as_slice(), self.mass.as_mut_slice());
        // The lower triangle within each tree's block: outside, `M` is zero and, the
        // positions of a tree being contiguous, so is its factor (never written there).
        for j in 0..n {
            let pj = self.order[j] * n;
            for i in j..self.tree_end[j] {
                dst[j * n + i] = src[pj + self.order[i]];
            }
        }
        let out = factor::cholesky(&mut self.mass, &mut self.mass_ends);
        // A non-finite entry can spread past a block: cleared for the next call.
        let spilled = (0..n).find(|&j| self.mass_ends[j] > self.tree_end[j]);
        if out.is_err() || spilled.is_some() {
            self.mass.as_mut_slice().fill(0.0);
        }
        out.and_then(|()| spilled.map_or(Ok(()), Err))
    }

    /// The rows of `J` (as held in `cons.jacobian`) that are not identically zero, then the
    /// pivoted QR of their transpose with the rank tolerance for a configuration off its
    /// manifold by `residual`. Returns the rank.
    fn factor_jacobian(&mut self, residual: f64) -> usize {
        self.qr_valid = false;
        let (m, n) = self.cons.jacobian.shape();
        let LoopSolver {
            cons,
            qr_j,
            active,
            row_lo,
            row_hi,
            struct_lo,
            struct_hi,
            order,
            ..
        } = self;
        // Each row's nonzero positions, within those it can touch.
        let j = cons.jacobian.as_slice();
        for r in 0..m {
            let nonzero = |&c: &usize| j[order[c] * m + r] != 0.0;
            let mut range = struct_lo[r]..struct_hi[r];
            row_lo[r] = range.clone().find(nonzero).unwrap_or(n);
            row_hi[r] = range.rfind(nonzero).map_or(0, |c| c + 1);
        }
        active.clear();
        active.extend((0..m).filter(|&r| row_hi[r] > 0));
        if self.envelope {
            // By the last position touched: with the solver's order, a banded Jᵀ.
            active.sort_unstable_by_key(|&r| (row_hi[r], row_lo[r], r));
        }
        let mut largest: f64 = 0.0;
        for (k, &r) in active.iter().enumerate() {
            qr_j.set_envelope(k, row_lo[r], row_hi[r]);
            let col = &mut qr_j.a_mut().as_mut_slice()[k * n..(k + 1) * n];
            col.fill(0.0);
            let mut s = 0.0;
            for c in row_lo[r]..row_hi[r] {
                let x = j[order[c] * m + r];
                col[c] = x;
                s += x * x;
            }
            largest = largest.max(s);
        }
        // Far from the manifold (assembling from a guess) the residual says nothing about
        // spurious directions: capped, so that genuine rows are never dropped for it.
        let spurious = (SPURIOUS * residual).min(SPURIOUS_CAP * largest.sqrt());
        self.qr_j
            .factor(self.active.len(), true, RANK_REL_TOL, spurious)
    }
}

/// Corrects the tree's accelerations `a` (from [`recursive::forward_dynamics`] at the same
/// state and forces) so that they satisfy the loops; leaves the multipliers (a basic
/// solution where constraints are redundant: the dependent rows' are zero) in
/// `solver.lambda`. Errors if the mass matrix is singular or the loops leave the mechanism
/// no freedom of motion.
///
/// The rank is decided on `J` itself (pivoted QR of `Jᵀ`, tolerance scaled to the position
/// residual), then `J_B q̈ = −γ_B` on the independent rows `B` is solved through the QR of
/// `Y = L⁻¹ J_Bᵀ` (`M = L Lᵀ`): `q̈ = a₀ + L⁻ᵀ Q R⁻ᵀ (−γ_B − J_B a₀)`. Orthogonal steps and
/// triangular solves only, so a mechanism near a singular position (a small but nonzero
/// singular value of `J`) loses only the digits its own conditioning costs.
pub fn constrained_forward_dynamics(
    model: &Model,
    data: &mut Data,
    solver: &mut LoopSolver,
    q: &[f64],
    v: &[f64],
    a: &mut [f64],
) -> Result<()> {
    let n = model.nv;
    // The velocity projection of this very configuration factored the same J with the
    // same tolerance (a projected stage): the positions, J and its QR stand.
    let reuse = solver.qr_valid && solver.qr_q.as_slice() == q;
    let residual = if reuse {
        solver.kin.velocities(model, q, v);
        constraints::gamma(model, &solver.kin, solver.cons.gamma.as_mut_slice());
        0.0
    } else {
        solver.constraints_at(model, q, Some(v))
    };
    if let Err(k) = solver.factor_mass(model, data, q) {
        return Err(Error::Singular(format!(
            "the mass matrix is not positive definite (pivot {k}): a massless chain, or a body too slender"
        )));
    }
    let rank = if reuse {
        solver.qr_j.rank()
    } else {
        solver.factor_jacobian(residual)
    };
    solver.rank = rank;
    if n > 0 && rank >= n {
        return Err(locked(model, rank));
    }
    let LoopSolver {
        cons,
        mass,
        mass_ends,
        qr_j,
        qr_y,
        lambda,
        work,
        active,
        row_lo,
        row_hi,
        pstep,
        order,
        ..
    } = solver;
    let m = cons.jacobian.nrows();
    let j = cons.jacobian.as_slice();
    for k in 0..rank {
        let r = active[qr_j.perm()[k]];
        let col = &mut qr_y.a_mut().as_mut_slice()[k * n..(k + 1) * n];
        col.fill(0.0);
        let mut ja = 0.0;
        for c in row_lo[r]..row_hi[r] {
            col[c] = j[order[c] * m + r];
            ja += col[c] * a[order[c]];
        }
        work[k] = -cons.gamma[r] - ja;
        let end = forward_substitute(mass, mass_ends, col, row_lo[r], row_hi[r]);
        qr_y.set_envelope(k, row_lo[r], end);
    }
    qr_y.factor(rank, false, 0.0, 0.0);
    // Independent rows of J and a nonsingular L keep every column of Y independent; a
    // NaN state is the only way to lose one.
    if qr_y.rank() < rank {
        return Err(Error::Singular(format!(
            "the constrained dynamics could not be solved at this state (a non-finite configuration?): {} of {rank} independent constraint rows remain",
            qr_y.rank()
        )));
    }
    // Y_Bᵀ z = b for z in range(Y_B): z = Q R⁻ᵀ b; λ_B = R⁻¹ R⁻ᵀ b (Y_B λ_B = z).
    qr_y.solve_rt(work);
    qr_y.apply_q(work, pstep);
    qr_y.solve_r(work);
    lambda.fill(0.0);
    for k in 0..rank {
        lambda[active[qr_j.perm()[k]]] = work[k];
    }
    back_substitute(mass, mass_ends, pstep);
    for (&c, si) in order.iter().zip(pstep.iter()) {
        a[c] += si;
    }
    Ok(())
}

/// With the factorisations of the last [`constrained_forward_dynamics`] (same state): `x`
/// holds `M⁻¹ r` on entry (unconstrained accelerations of some forces `r`) and, on return,
/// the constrained ones, `M x' = r + Jᵀ μ` with `J_B x' = b_B` on the independent rows
/// (`b` indexed by constraint row). The derivatives' solve: the same operator, other
/// right-hand sides.
pub(super) fn constrained_correction(solver: &mut LoopSolver, x: &mut [f64], b: &[f64]) {
    let n = x.len();
    let LoopSolver {
        cons,
        mass,
        mass_ends,
        qr_j,
        qr_y,
        work,
        pstep,
        order,
        active,
        rank,
        ..
    } = solver;
    for k in 0..*rank {
        let r = active[qr_j.perm()[k]];
        let jx: f64 = (0..n).map(|c| cons.jacobian[(r, c)] * x[c]).sum();
        work[k] = b[r] - jx;
    }
    qr_y.solve_rt(work);
    qr_y.apply_q(work, pstep);
    back_substitute(mass, mass_ends, pstep);
    for (&c, si) in order.iter().zip(pstep.iter()) {
        x[c] += si;
    }
}

/// `x = M⁻¹ x` with the Cholesky factor of the last [`constrained_forward_dynamics`].
pub(super) fn mass_solve(solver: &mut LoopSolver, x: &mut [f64]) {
    let LoopSolver {
        mass,
        mass_ends,
        pstep,
        order,
        ..
    } = solver;
    for (p, &c) in pstep.iter_mut().zip(order.iter()) {
        *p = x[c];
    }
    forward_substitute(mass, mass_ends, pstep, 0, x.len());
    back_substitute(mass, mass_ends, pstep);
    for (p, &c) in pstep.iter().zip(order.iter()) {
        x[c] = *p;
    }
}

fn locked(model: &Model, rank: usize) -> Error {
    let names: Vec<String> = model
        .loops
        .iter()
        .map(|l| format!("'{}'", l.name))
        .chain(
            model
                .couplings
                .iter()
                .map(|c| format!("coupling '{}'", c.name)),
        )
        .collect();
    Error::Singular(format!(
        "the cut joint(s) and couplings {} leave the mechanism no freedom of motion: the constraint Jacobian has rank {rank} = nv = {} (a locked mechanism, a structure); remove a cut joint or a constraint",
        names.join(", "),
        model.nv
    ))
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
    let a_tree = a.to_vec();
    constrained_forward_dynamics(model, data, solver, q, v, a)?;
    // `M (q̈ − a₀) = Jᵀ λ`: the minimum-norm λ of that (consistent) system, by a complete
    // orthogonal decomposition of `Jᵀ` on the active rows (no squared form).
    let n = model.nv;
    let LoopSolver {
        kin,
        cons,
        mass,
        lambda,
        active,
        ..
    } = solver;
    let na = active.len();
    let mut jt = DMatrix::zeros(n, na);
    for (k, &r) in active.iter().enumerate() {
        for c in 0..n {
            jt[(c, k)] = cons.jacobian[(r, c)];
        }
    }
    // M Δa = L (Lᵀ Δa), in the solver's order.
    let order = &solver.order;
    let mut p: Vec<f64> = order.iter().map(|&c| a[c] - a_tree[c]).collect();
    for i in 0..n {
        p[i] = (i..n).map(|k| mass[(k, i)] * p[k]).sum();
    }
    for i in (0..n).rev() {
        p[i] = (0..=i).map(|k| mass[(i, k)] * p[k]).sum();
    }
    let mut b = vec![0.0; n];
    for (&c, x) in order.iter().zip(&p) {
        b[c] = *x;
    }
    let mut x = vec![0.0; na];
    let (mut pivots, mut work) = (vec![0; na], vec![0.0; na.max(n)]);
    factor::min_norm_solve(
        jt.view_mut((0, 0), (n, na)),
        &mut b,
        &mut x,
        &mut pivots,
        &mut work,
        RANK_REL_TOL,
    );
    lambda.fill(0.0);
    for (k, &r) in active.iter().enumerate() {
        lambda[r] = x[k];
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
                "J a + J̇ v = {:.3e} in row {row} ({})",
                ja[row],
                model.constraint_name(row)
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

/// `δ = −J_f⁺ c` into `solver.step` for `c` in `solver.rhs`: the minimum-norm step with
/// `J_f δ = −c` on the independent rows (`J_f`: the Jacobian with the `fixed` columns zeroed,
/// which the caller has done), `δ = −Q R⁻ᵀ c_B` from the pivoted QR of `J_fᵀ`. `residual`:
/// the configuration's position residual, which scales the rank tolerance. Returns the rank.
fn min_norm_step(solver: &mut LoopSolver, residual: f64) -> usize {
    let rank = solver.factor_jacobian(residual);
    let LoopSolver {
        qr_j,
        rhs,
        work,
        step,
        pstep,
        order,
        active,
        ..
    } = solver;
    for k in 0..rank {
        work[k] = -rhs[active[qr_j.perm()[k]]];
    }
    qr_j.solve_rt(work);
    qr_j.apply_q(work, pstep);
    for (&c, p) in order.iter().zip(pstep.iter()) {
        step[c] = *p;
    }
    rank
}

/// The step is in the range of `J_fᵀ`, zero in the held coordinates up to the rounding of
/// the reflectors: made exactly zero there.
fn hold_fixed(step: &mut [f64], fixed: &[bool]) {
    for (s, &f) in step.iter_mut().zip(fixed) {
        if f {
            *s = 0.0;
        }
    }
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
        let norm = solver.constraints_at(model, &q, None);
        zero_fixed(&mut solver.cons.jacobian, fixed);
        solver.rhs.copy_from(&solver.cons.residual);
        // Directions weaker than the residual are left for later iterations (Bricard's
        // redundant row is spurious off the manifold): a truncated Gauss-Newton step.
        min_norm_step(&mut solver, norm);
        hold_fixed(&mut solver.step, fixed);
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
        return Err(Error::Closure(format!(
            "{} cannot be closed from this guess: after {iterations} Newton iterations its residual is still {res:.3e} (> tol = {tol:.1e}); the bodies may be unable to reach each other, or the fixed coordinates ask for a position the mechanism cannot take",
            model.constraint_name(row)
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
    let residual = solver.constraints_at(model, q, v_for_gamma);
    let jx = &solver.cons.jacobian * DVector::from_column_slice(x);
    let c = match v_for_gamma {
        Some(_) => &jx + &solver.cons.gamma,
        None => jx.clone(),
    };
    let full = solver.cons.jacobian.clone();
    zero_fixed(&mut solver.cons.jacobian, fixed);
    solver.rhs.copy_from(&c);
    min_norm_step(&mut solver, residual);
    hold_fixed(&mut solver.step, fixed);
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
            "{}: the held (fixed) entries leave no {} that keeps the loop closed (constraint row {row} stays at {:.3e}); hold fewer coordinates, or ones that can move independently",
            model.constraint_name(row),
            if v_for_gamma.is_some() { "acceleration" } else { "velocity" },
            after[row]
        )));
    }
    Ok(())
}

/// Refuses a locked mechanism at `q` (the loops leave no freedom of motion): the check a run
/// makes before it starts.
pub fn check_mobility(model: &Model, solver: &mut LoopSolver, q: &[f64]) -> Result<()> {
    let residual = solver.constraints_at(model, q, None);
    solver.rhs.fill(0.0);
    let rank = min_norm_step(solver, residual);
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
        // At round-off already (an accepted state projected again): a Newton step would only
        // move it by the rounding amplified near a singular position, `~ ε/σ`.
        if res <= ROUND_OFF {
            break;
        }
        // The residual's positions stand: the Jacobian at the same q.
        let norm = solver.jacobian_here(model);
        solver.rhs.copy_from(&solver.cons.residual);
        min_norm_step(solver, norm);
        let mut qdot = std::mem::take(&mut solver.qdot);
        retract(model, q, &solver.step, &mut qdot);
        solver.qdot = qdot;
        let r_new = solver.residual_at(model, q);
        // Quadratic convergence has stopped, or the closure is at round-off.
        let converged = r_new > 0.5 * res || r_new <= ROUND_OFF;
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
    // The last residual was at this q: its positions stand.
    let norm = solver.jacobian_here(model);
    let m = solver.rhs.len();
    let j = solver.cons.jacobian.as_slice();
    for r in 0..m {
        solver.rhs[r] = solver.order[solver.struct_lo[r]..solver.struct_hi[r]]
            .iter()
            .map(|&c| j[c * m + r] * v[c])
            .sum();
    }
    min_norm_step(solver, norm);
    for (x, s) in v.iter_mut().zip(&solver.step[..nv]) {
        *x += s;
    }
    solver.qr_q.copy_from_slice(q);
    solver.qr_valid = true;
    Ok(true)
}

/// A position residual (metres, or radians of axis misalignment) at which Newton stops:
/// round-off of coordinates of order one.
const ROUND_OFF: f64 = 1e-14;
