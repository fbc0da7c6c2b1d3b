//! The design as a conic program: RMS objectives make a QP, peak (minimax over time of
//! vector norms) objectives an SOCP, `limits` are ε-constraints in the same norm. The
//! programs themselves are built in [`super::program`]; peak ones are solved by cutting
//! planes over the motion's samples ([`super::active`]). An infeasible program is followed
//! by a phase-1 program giving the least relaxation of the requirements that some design
//! meets, which names the binding ones and by how much.
use nalgebra::{DMatrix, DVector};

use super::active::{initial, solve_cut};
use super::program::{Layout, Raw, Stage};
use crate::support::error::{Error, Result};

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
    /// Its limit holds at every block whatever the problem's norm (a member's stress,
    /// `design/strength`): one cone per block, weight zero.
    pub peak: bool,
}

impl Quantity {
    /// The norm this quantity is measured in: its own peak, or the problem's.
    pub fn norm(&self, problem_norm: Norm) -> Norm {
        if self.peak {
            Norm::Peak
        } else {
            problem_norm
        }
    }
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
    /// Connected links: each link's cells joined to its bosses by flows (empty: none).
    pub flows: Vec<super::connectivity::Flow>,
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
    /// Interior-point iterations, summed over the programs solved.
    pub iterations: u32,
    /// Clarabel's time, summed over the programs solved.
    pub solve_time: f64,
    /// Programs solved: one per stage for RMS, one per cutting-plane round for peak.
    pub rounds: u32,
    /// Each stage's certificate (the optimum, then the least mass): status, absolute and
    /// relative duality gap of its last program, and the first stage's objective at that
    /// stage's design ([`objective_at`]). `status`/`gap_*` above are the last stage's.
    pub stages: Vec<(String, f64, f64, f64)>,
    /// What did not go as asked without failing the design (a least-mass stage that did not
    /// converge): said to the user, never dropped.
    pub notes: Vec<String>,
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
            match q.norm(problem.norm) {
                Norm::Rms => (norms.sum::<f64>() / q.samples.max(1) as f64).sqrt(),
                Norm::Peak => norms.fold(0.0_f64, f64::max).sqrt(),
            }
        })
        .collect()
}

/// The first stage's objective at a design: `Σ w_q (value_q / reference_q)` over the
/// weighted peak quantities (their squares with RMS, whose objective weighs mean squares),
/// plus the mass term; `values` as [`values`] gives them.
pub fn objective_at(problem: &Problem, x: &[f64], values: &[f64]) -> f64 {
    let weighted = problem.quantities.iter().zip(values);
    let sum: f64 = weighted
        .filter(|(q, _)| q.weight > 0.0 && !q.zero && !q.peak)
        .map(|(q, &v)| {
            let r = v / q.reference.max(1e-300);
            q.weight * if problem.norm == Norm::Rms { r * r } else { r }
        })
        .sum();
    sum + problem.mass_weight * x.iter().sum::<f64>() / problem.mass_reference.max(1e-300)
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
        crate::support::error::check_finite(&q.name, q.rows.as_slice())?;
        crate::support::error::check_finite(&q.name, q.constant.as_slice())?;
    }
    for f in &problem.flows {
        f.check(nx, &problem.upper)?;
    }
    Ok(())
}

/// One requirement relaxed by phase 1: asked, and the least value reachable together with
/// the others' relaxations (in the problem's norm, absolute units; kg for the mass).
#[derive(Debug, Clone)]
pub struct Relaxed {
    /// The quantity's name, or "mass".
    pub name: String,
    /// Zero asked (`zero`), else a limit.
    pub zero: bool,
    pub asked: f64,
    pub needed: f64,
    /// The value before the design (the scale of the relaxation).
    pub before: f64,
    /// The least value when only this requirement is relaxed (the others held); None when
    /// relaxing it alone does not make the design feasible.
    pub alone: Option<f64>,
}

impl Relaxed {
    /// Whether it binds: relaxed by more than the solver's tolerance.
    pub fn binding(&self) -> bool {
        self.needed - self.asked > 1e-8 * self.before.abs().max(self.asked.abs())
    }
}

/// What makes an infeasible design feasible: the least summed relaxation (each relative to
/// its value before) of its limits and zero quantities.
#[derive(Debug, Clone)]
pub struct Relaxation {
    pub items: Vec<Relaxed>,
}

impl Relaxation {
    /// The error naming the binding requirements and by how much.
    pub fn error(&self) -> Error {
        let binding: Vec<&Relaxed> = self.items.iter().filter(|r| r.binding()).collect();
        let arg = if binding.iter().any(|r| !r.zero) || binding.is_empty() {
            "limits"
        } else {
            "zero"
        };
        let what = |r: &Relaxed| {
            if r.zero {
                format!("{} = 0", r.name)
            } else {
                format!("{} <= {:.4e}", r.name, r.asked)
            }
        };
        let needs = |r: &Relaxed, needed: f64| {
            let share = if r.name == "mass" {
                "kg".to_string()
            } else {
                format!(
                    "{:.2} % of its value before, {:.4e}",
                    100.0 * (needed - r.asked) / r.before.max(1e-300),
                    r.before
                )
            };
            format!("{} needs {needed:.4e} at least ({share})", what(r))
        };
        let together: Vec<String> = binding.iter().map(|r| needs(r, r.needed)).collect();
        let alone: Vec<String> = self
            .items
            .iter()
            .map(|r| match r.alone {
                Some(v) => needs(r, v),
                None => format!("{} alone does not suffice", what(r)),
            })
            .collect();
        let got = if together.is_empty() {
            "requirements infeasible by less than the solver's tolerance (Clarabel's certificate)"
                .to_string()
        } else {
            format!(
                "requirements none meets (Clarabel's certificate). Relaxing one alone: {}. The \
                 least summed relaxation (phase 1, each relative to its value before): {}. Or \
                 give the design more room (candidates, envelopes, mass ranges)",
                alone.join("; "),
                together.join("; ")
            )
        };
        Error::arg(
            arg,
            "requirements some design within the masses' bounds (and link mass ranges) meets",
            got,
        )
    }
}

/// The result of a design: a solution, or what an infeasible one needs.
#[derive(Debug, Clone)]
pub enum Outcome {
    Solved(Solution),
    Infeasible(Relaxation),
}

/// Builds and solves the design (twice with `least_mass`). Errors: infeasible limits or
/// equalities (naming the binding ones and by how much), or the solver's status.
pub fn solve(problem: &Problem) -> Result<Solution> {
    match solve_outcome(problem)? {
        Outcome::Solved(s) => Ok(s),
        Outcome::Infeasible(r) => Err(r.error()),
    }
}

/// [`solve`], with an infeasible design's least relaxation as a value.
pub fn solve_outcome(problem: &Problem) -> Result<Outcome> {
    check(problem)?;
    let mut active = initial(problem);
    let first = match solve_cut(problem, Stage::Optimum, &mut active) {
        Ok(Some((raw, rounds))) => solution(problem, raw, rounds),
        Ok(None) => return relax(problem, active).map(Outcome::Infeasible),
        Err(Error::Singular(msg)) if has_requirements(problem) => {
            // Limits at the edge of what any design reaches leave the interior point method
            // (almost) no interior: phase 1 (every requirement with a slack, strictly
            // feasible) says whether some design meets them, and by how much not.
            return match relax(problem, initial(problem)) {
                Ok(r) if r.items.iter().any(Relaxed::binding) => Ok(Outcome::Infeasible(r)),
                Ok(r) => Err(Error::Singular(format!(
                    "{msg}; phase 1 finds the requirements met within the solver's tolerance \
                     (least relaxation {}): they leave no room to optimise, loosen them slightly",
                    r.items
                        .iter()
                        .map(|i| format!("{} {:.3e}", i.name, i.needed - i.asked))
                        .collect::<Vec<_>>()
                        .join(", ")
                ))),
                Err(_) => Err(Error::Singular(msg)),
            };
        }
        Err(e) => return Err(e),
    };
    if !problem.least_mass {
        return Ok(Outcome::Solved(first));
    }
    // Among the optima, the least mass: the objective held at its optimum (to the solver's
    // accuracy) and the total mass minimised.
    match solve_cut(problem, Stage::LeastMass(&first), &mut active) {
        Ok(Some((raw, rounds))) => {
            let mut second = solution(problem, raw, rounds);
            second.objective = first.objective;
            second.iterations += first.iterations;
            second.solve_time += first.solve_time;
            second.rounds += first.rounds;
            second.stages = [first.stages, second.stages].concat();
            Ok(Outcome::Solved(second))
        }
        // The second solve only refines; its failure leaves the optimum found, and says so.
        Err(Error::Interrupted(w)) => Err(Error::Interrupted(w)),
        other => {
            let why = match other {
                Err(e) => e.to_string(),
                _ => "certified infeasible".to_string(),
            };
            let mut first = first;
            first.notes.push(format!(
                "least mass: not found ({why}); the design is an optimum of the first stage, \
                 not the least-mass one"
            ));
            Ok(Outcome::Solved(first))
        }
    }
}

/// Whether the program has requirements phase 1 relaxes (limits, zero quantities, a mass
/// limit).
fn has_requirements(problem: &Problem) -> bool {
    problem.mass_limit.is_some()
        || problem
            .quantities
            .iter()
            .any(|q| q.zero || q.limit.is_some())
}

fn solution(problem: &Problem, raw: Raw, rounds: u32) -> Solution {
    let (nx, nd) = (problem.lower.len(), problem.ndelta);
    let delta = raw.z[nx..nx + nd].to_vec();
    let status = format!("{:?}", raw.status);
    let values = values(problem, &delta);
    let at = objective_at(problem, &raw.z[..nx], &values);
    Solution {
        values,
        x: raw.z[..nx].to_vec(),
        delta,
        stages: vec![(status.clone(), raw.gap_abs, raw.gap_rel, at)],
        status,
        objective: raw.objective,
        gap_abs: raw.gap_abs,
        gap_rel: raw.gap_rel,
        iterations: raw.iterations,
        solve_time: raw.solve_time,
        rounds,
        notes: vec![],
    }
}

/// Phase 1: the least relaxation of the requirements that some design meets, together and
/// each alone.
fn relax(problem: &Problem, active: Vec<Vec<usize>>) -> Result<Relaxation> {
    let lay = Layout::new(problem, Stage::Relax(None));
    let Some((raw, _)) = solve_cut(problem, Stage::Relax(None), &mut active.clone())? else {
        return Err(Error::arg(
            "links, counterweights",
            "bounds, link mass ranges, symmetry and connected links some design masses meet \
             together",
            "ones that conflict (Clarabel's certificate, with every limit and zero relaxed)",
        ));
    };
    let mut items = Vec::with_capacity(lay.slacks.len());
    for (j, &(k, sl)) in lay.slacks.iter().enumerate() {
        let alone = match lay.slacks.len() {
            1 => Some(raw.z[sl].max(0.0)),
            _ => solve_cut(problem, Stage::Relax(Some(j)), &mut active.clone())?
                .map(|(r, _)| r.z[sl].max(0.0)),
        };
        let (name, zero, asked, before, unit) = match k {
            Some(k) => {
                let q = &problem.quantities[k];
                let asked = if q.zero { 0.0 } else { q.limit.unwrap_or(0.0) };
                (q.name.clone(), q.zero, asked, q.reference, q.reference)
            }
            None => (
                "mass".to_string(),
                false,
                problem.mass_limit.unwrap_or(0.0),
                problem.mass_reference,
                1.0,
            ),
        };
        items.push(Relaxed {
            name,
            zero,
            asked,
            needed: asked + raw.z[sl].max(0.0) * unit,
            before,
            alone: alone.map(|s| asked + s * unit),
        });
    }
    Ok(Relaxation { items })
}
