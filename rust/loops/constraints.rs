//! The cut joints' constraints at the position, velocity and acceleration levels, from the
//! tree's world-frame kinematics (`kinematics::positions`/`velocities`).
//!
//! Each cut joint contributes rows, all in frame a's axes so that the multipliers are the
//! joint's force and moment components in that frame:
//! * position rows `eₖ·(p_b − p_a)` (`eₖ` frame a's axes; the two normal to the axis for a
//!   prismatic joint);
//! * orientation rows: the rotation vector `log(R_aᵀ R_b)` for fixed and prismatic joints
//!   (velocity `eₖ·(ω_b − ω_a)`), and `uₖ·a_b` for a revolute joint (`uₖ` normal to the
//!   axis in frame a, `a_b` the axis carried by frame b: zero when the axes are aligned).
//!
//! The velocity rows are the exact time derivatives of the position rows (of the rotation
//! vector at closure), and `γ = J̇ q̇` is the derivative of the velocity rows at `q̈ = 0`.
use nalgebra::{DMatrix, DVector};

use super::{CutKind, LoopJoint};
use crate::kinematics::{self, body_placement, LinkState};
use crate::model::Model;
use crate::support::spatial::{angular, linear, mat_vec, Mat3, Placement, Vec3, Vec6};

/// The tree's world-frame kinematics for the constraints, reused across calls.
pub struct LoopKinematics {
    pub links: Vec<LinkState>,
    /// Each link's twist rate at `q̈ = 0` (no gravity): `[ω̇; v̇ of the origin]`.
    bias: Vec<Vec6>,
    /// Each cut joint's ends and row directions at the last `positions`.
    rows: Vec<LoopRows>,
    /// Each coupling's residual at the last `positions`.
    coupled: Vec<f64>,
    /// Per cut joint, what does not change with `q` (built with the model's loops).
    fixed: Vec<LoopConsts>,
}

/// A cut joint's constant part: its row axes in frame a ([`local_axes`]) and, per end,
/// whether the body's placement in its link and the joint frame turn (the rotation
/// products are skipped for those that do not: the same numbers).
#[derive(Clone, Copy)]
struct LoopConsts {
    axes: Option<[Vec3; 3]>,
    turns_a: [bool; 2],
    turns_b: [bool; 2],
}

impl LoopConsts {
    fn new(model: &Model, lp: &LoopJoint) -> Self {
        let turns = |body: Option<usize>, frame: &crate::support::spatial::Placement| {
            let in_link = body
                .and_then(|b| model.bodies.get(b))
                .is_some_and(|b| b.in_link.rotation != Mat3::identity());
            [in_link, frame.rotation != Mat3::identity()]
        };
        LoopConsts {
            axes: local_axes(lp),
            turns_a: turns(lp.body_a, &lp.frame_a),
            turns_b: turns(lp.body_b, &lp.frame_b),
        }
    }
}

/// Residual, Jacobian (`m × nv`) and `γ = J̇ q̇` of all cut joints.
pub struct Constraints {
    pub residual: DVector<f64>,
    pub jacobian: DMatrix<f64>,
    pub gamma: DVector<f64>,
}

impl Constraints {
    pub fn new(model: &Model) -> Self {
        let m = model.nconstraints();
        Constraints {
            residual: DVector::zeros(m),
            jacobian: DMatrix::zeros(m, model.nv),
            gamma: DVector::zeros(m),
        }
    }
}

/// One end of a cut joint in the world: frame orientation and origin, the link carrying it
/// (`None`: the ground), and that point's velocity and bias acceleration once known.
#[derive(Clone, Copy)]
struct End {
    rotation: Mat3,
    point: Vec3,
    link: Option<usize>,
}

/// Velocity of an end's point and of its body, and their rates at `q̈ = 0`.
#[derive(Clone, Copy, Default)]
struct EndMotion {
    w: Vec3,
    v: Vec3,
    bias_w: Vec3,
    bias_a: Vec3,
}

impl LoopKinematics {
    pub fn new(model: &Model) -> Self {
        LoopKinematics {
            links: vec![LinkState::default(); model.links.len()],
            bias: vec![Vec6::zeros(); model.links.len()],
            rows: Vec::with_capacity(model.loops.len()),
            coupled: vec![0.0; model.couplings.len()],
            fixed: model
                .loops
                .iter()
                .map(|lp| LoopConsts::new(model, lp))
                .collect(),
        }
    }

    /// The links' world poses and, from them, each cut joint's ends and row directions.
    pub fn positions(&mut self, model: &Model, q: &[f64]) {
        kinematics::frames(model, q, &mut self.links);
        if self.fixed.len() != model.loops.len() {
            // Built for another model's loops (never in the solvers).
            self.fixed.clear();
            self.fixed
                .extend(model.loops.iter().map(|lp| LoopConsts::new(model, lp)));
        }
        // In place (a `LoopRows` is a few hundred bytes: no copy through a temporary).
        let mut rows = std::mem::take(&mut self.rows);
        rows.truncate(model.loops.len());
        for (k, (lp, fixed)) in model.loops.iter().zip(&self.fixed).enumerate() {
            let (a, b) = self.ends(model, lp, fixed);
            match rows.get_mut(k) {
                Some(r) => r.set(lp, fixed, a, b),
                None => rows.push(LoopRows::new(lp, fixed, a, b)),
            }
        }
        self.rows = rows;
        super::coupling::residual(model, q, &mut self.coupled);
    }

    /// Twists and the velocity-product twist rates; needs `positions` first.
    pub fn velocities(&mut self, model: &Model, q: &[f64], v: &[f64]) {
        kinematics::velocities(model, q, v, &mut self.links);
        for (i, l) in model.links.iter().enumerate() {
            let parent = match l.parent {
                Some(p) => {
                    let (b, r) = (self.bias[p], self.links[i].origin - self.links[p].origin);
                    let w = angular(&b);
                    crate::support::spatial::stack(&w, &(linear(&b) + w.cross(&r)))
                }
                None => Vec6::zeros(),
            };
            self.bias[i] = parent + self.links[i].xi;
        }
    }

    /// The two ends of `lp` at the last positions.
    #[inline]
    fn ends(&self, model: &Model, lp: &LoopJoint, fixed: &LoopConsts) -> (End, End) {
        (
            self.end(model, lp.body_a, &lp.frame_a, fixed.turns_a),
            self.end(model, lp.body_b, &lp.frame_b, fixed.turns_b),
        )
    }

    /// `turns`: whether body `b`'s placement in its link and `frame` turn ([`LoopConsts`]).
    fn end(
        &self,
        model: &Model,
        body: Option<usize>,
        frame: &crate::support::spatial::Placement,
        turns: [bool; 2],
    ) -> End {
        match body {
            None => End {
                rotation: frame.rotation,
                point: frame.translation,
                link: None,
            },
            Some(b) => {
                let p = match model.bodies[b].link {
                    Some(l) => {
                        let s = &self.links[l];
                        let at_link = Placement::new(s.rotation, s.origin);
                        let in_link = compose(&at_link, &model.bodies[b].in_link, turns[0]);
                        compose(&in_link, frame, turns[1])
                    }
                    None => body_placement(model, &self.links, b).compose(frame),
                };
                End {
                    rotation: p.rotation,
                    point: p.translation,
                    link: model.bodies[b].link,
                }
            }
        }
    }

    fn motion(&self, end: &End) -> EndMotion {
        let Some(l) = end.link else {
            return EndMotion::default();
        };
        let s = &self.links[l];
        let r = end.point - s.origin;
        let (w, bw) = (angular(&s.twist), angular(&self.bias[l]));
        EndMotion {
            w,
            v: linear(&s.twist) + w.cross(&r),
            bias_w: bw,
            bias_a: linear(&self.bias[l]) + bw.cross(&r) + w.cross(&w.cross(&r)),
        }
    }

    /// For each of the `n` rows `(lin, ang) = dirs(k)`, adds `lin · (velocity of point p)`
    /// plus `ang · (angular velocity)` of `link`'s body, as a function of `v`, to row
    /// `first + k` of `jac` (column-major, `m` rows). Each joint column's motion at `p` is
    /// formed once for all the rows.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn add_to_rows(
        &self,
        model: &Model,
        jac: &mut [f64],
        m: usize,
        first: usize,
        link: Option<usize>,
        p: &Vec3,
        n: usize,
        dirs: impl Fn(usize) -> (Vec3, Vec3),
    ) {
        let mut next = link;
        while let Some(j) = next {
            let l = &model.links[j];
            let s = &self.links[j];
            let r = p - s.origin;
            for k in 0..l.joint.nv() {
                let col = &s.s[k];
                let w = angular(col);
                let v = linear(col) + w.cross(&r);
                let column = &mut jac[(l.v_index + k) * m + first..][..n];
                for (i, x) in column.iter_mut().enumerate() {
                    let (lin, ang) = dirs(i);
                    *x += dot3(&lin, &v) + dot3(&ang, &w);
                }
            }
            next = l.parent;
        }
    }
}

/// `a · b` as nalgebra's `dot` forms it for 3-vectors (`a₀b₀ + a₁b₁ + a₂b₂`), inlined in
/// every build profile.
#[inline(always)]
fn dot3(a: &Vec3, b: &Vec3) -> f64 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// `parent ∘ child`; with `turns` false (`child`'s rotation the identity) the rotation
/// product is left out: it would give `parent`'s rotation exactly.
#[inline(always)]
fn compose(parent: &Placement, child: &Placement, turns: bool) -> Placement {
    if turns {
        parent.compose(child)
    } else {
        Placement {
            rotation: parent.rotation,
            translation: mat_vec(&parent.rotation, &child.translation) + parent.translation,
        }
    }
}

/// For revolute and prismatic joints, the row axes in frame a, ordered so that the joint
/// axis comes last: the two normals `u₁, u₂` (`u₁ × u₂ = axis`) and the axis; `None` for
/// the others (frame a's own axes).
fn local_axes(lp: &LoopJoint) -> Option<[Vec3; 3]> {
    match lp.kind() {
        CutKind::Revolute | CutKind::Prismatic => {
            let a = lp.axis().normalize();
            // The coordinate axis least aligned with `a` gives a well-conditioned normal.
            let k = a.iamin();
            let u1 = a.cross(&Vec3::ith(k, 1.0)).normalize();
            let u2 = a.cross(&u1);
            Some([u1, u2, a])
        }
        _ => None,
    }
}

/// Frame a's row axes in the world ([`local_axes`] turned by frame a's orientation).
fn row_axes(local: &Option<[Vec3; 3]>, rotation_a: &Mat3) -> [Vec3; 3] {
    match local {
        Some([u1, u2, a]) => [
            mat_vec(rotation_a, u1),
            mat_vec(rotation_a, u2),
            mat_vec(rotation_a, a),
        ],
        None => [
            rotation_a.column(0).into(),
            rotation_a.column(1).into(),
            rotation_a.column(2).into(),
        ],
    }
}

/// Rows of one loop: which ends, which directions.
#[derive(Clone, Copy)]
struct LoopRows {
    a: End,
    b: End,
    axes: [Vec3; 3],
    /// Frame b's copy of the joint axis, in the world (revolute and prismatic joints).
    axis_b: Vec3,
    /// Number of position rows (the first ones): 3, or 2 for a prismatic joint.
    npos: usize,
}

impl LoopRows {
    fn new(lp: &LoopJoint, fixed: &LoopConsts, a: End, b: End) -> Self {
        let mut rows = LoopRows {
            a,
            b,
            axes: [Vec3::zeros(); 3],
            axis_b: Vec3::zeros(),
            npos: 0,
        };
        rows.set(lp, fixed, a, b);
        rows
    }

    /// The rows for the ends `a`, `b` of `lp`.
    #[inline]
    fn set(&mut self, lp: &LoopJoint, fixed: &LoopConsts, a: End, b: End) {
        self.axes = row_axes(&fixed.axes, &a.rotation);
        if let Some([_, _, axis]) = &fixed.axes {
            self.axis_b = mat_vec(&b.rotation, axis);
        }
        self.a = a;
        self.b = b;
        self.npos = if lp.kind() == CutKind::Prismatic {
            2
        } else {
            3
        };
    }
}

/// The rotation vector (axis × angle) of `r`, accurate near the identity: from the skew part
/// `sin θ · n` and the trace by `atan2` (an `acos` of the trace loses half the digits there).
pub(super) fn rotation_vector(r: &Mat3) -> Vec3 {
    let s = 0.5
        * Vec3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let sin = s.norm();
    let cos = 0.5 * (r.trace() - 1.0);
    if sin < 1e-300 {
        return s;
    }
    let angle = sin.atan2(cos);
    if angle < std::f64::consts::PI - 1e-6 {
        return s * (angle / sin);
    }
    // Near a half turn the skew part vanishes: the axis from the symmetric part.
    let b = (r + r.transpose()) * 0.5 - Mat3::identity() * cos;
    let k = (0..3)
        .max_by(|&i, &j| b[(i, i)].total_cmp(&b[(j, j)]))
        .unwrap_or(0);
    let mut n: Vec3 = b.column(k).into();
    n /= n.norm().max(1e-300);
    if n.dot(&s) < 0.0 {
        n = -n;
    }
    n * angle
}

/// Writes every loop's residual (length `nconstraints`); needs `kin.positions`.
pub fn residual(model: &Model, kin: &LoopKinematics, out: &mut [f64]) {
    let mut r = 0;
    for (lp, rows) in model.loops.iter().zip(&kin.rows) {
        let d = rows.b.point - rows.a.point;
        for e in &rows.axes[..rows.npos] {
            out[r] = e.dot(&d);
            r += 1;
        }
        match lp.kind() {
            CutKind::Spherical => {}
            CutKind::Revolute => {
                let ab = rows.axis_b;
                for u in &rows.axes[..2] {
                    out[r] = u.dot(&ab);
                    r += 1;
                }
            }
            CutKind::Prismatic | CutKind::Fixed => {
                let rel = rows.a.rotation.transpose() * rows.b.rotation;
                let log = rotation_vector(&rel);
                // Components along frame a's axes, in the order of the position rows' axes
                // (for a prismatic joint the axis is the last of the three).
                let log_world = rows.a.rotation * log;
                for e in &rows.axes {
                    out[r] = e.dot(&log_world);
                    r += 1;
                }
            }
        }
    }
    out[r..r + kin.coupled.len()].copy_from_slice(&kin.coupled);
}

/// Fills the velocity Jacobian (`nconstraints × nv`); needs `kin.positions`.
pub fn jacobian(model: &Model, kin: &LoopKinematics, jac: &mut DMatrix<f64>) {
    // On the contiguous storage: a memset (`DMatrix::fill` goes entry by entry).
    jac.as_mut_slice().fill(0.0);
    add_jacobian(model, kin, jac);
}

/// [`jacobian`] into a `jac` that is zero outside each row's coordinates `order[lo[r]..hi[r]]`
/// (those it can touch, in the loop solver's order): only those are cleared.
pub(super) fn jacobian_within(
    model: &Model,
    kin: &LoopKinematics,
    jac: &mut DMatrix<f64>,
    lo: &[usize],
    hi: &[usize],
    order: &[usize],
) {
    let m = jac.nrows();
    let data = jac.as_mut_slice();
    for r in 0..m {
        for &c in &order[lo[r]..hi[r]] {
            data[c * m + r] = 0.0;
        }
    }
    add_jacobian(model, kin, jac);
}

/// Adds each cut joint's and coupling's rows to `jac`: per cut joint, body b's end then
/// body a's, each row's `(lin, ang)` directions for `add_to_rows`.
fn add_jacobian(model: &Model, kin: &LoopKinematics, jac: &mut DMatrix<f64>) {
    let zero = Vec3::zeros();
    let m = jac.nrows();
    let mut r = 0;
    for (lp, rows) in model.loops.iter().zip(&kin.rows) {
        let (a, b) = (&rows.a, &rows.b);
        let d = b.point - a.point;
        let angular_dirs: &[Vec3] = match lp.kind() {
            CutKind::Spherical => &[],
            CutKind::Revolute => &[
                rows.axis_b.cross(&rows.axes[0]),
                rows.axis_b.cross(&rows.axes[1]),
            ],
            CutKind::Prismatic | CutKind::Fixed => &rows.axes,
        };
        let npos = rows.npos;
        let mut moments = [zero; 3];
        for (t, e) in moments.iter_mut().zip(&rows.axes[..npos]) {
            *t = e.cross(&d);
        }
        let n = npos + angular_dirs.len();
        let data = jac.as_mut_slice();
        kin.add_to_rows(model, data, m, r, b.link, &b.point, n, |k| {
            if k < npos {
                (rows.axes[k], zero)
            } else {
                (zero, angular_dirs[k - npos])
            }
        });
        kin.add_to_rows(model, data, m, r, a.link, &a.point, n, |k| {
            if k < npos {
                (-rows.axes[k], moments[k])
            } else {
                (zero, -angular_dirs[k - npos])
            }
        });
        r += n;
    }
    super::coupling::jacobian(model, r, jac);
}

/// Writes `γ = J̇ q̇` (length `nconstraints`): `J q̈ + γ = 0` on the manifold. Needs
/// `kin.positions` and `kin.velocities`.
pub fn gamma(model: &Model, kin: &LoopKinematics, out: &mut [f64]) {
    let mut r = 0;
    for (lp, rows) in model.loops.iter().zip(&kin.rows) {
        let (ma, mb) = (kin.motion(&rows.a), kin.motion(&rows.b));
        let d = rows.b.point - rows.a.point;
        let (dv, dw) = (mb.v - ma.v, mb.w - ma.w);
        let (da, dbw) = (mb.bias_a - ma.bias_a, mb.bias_w - ma.bias_w);
        let wa = ma.w;
        for e in &rows.axes[..rows.npos] {
            let e_rate = wa.cross(e);
            out[r] = 2.0 * e_rate.dot(&dv)
                + e.dot(&da)
                + (ma.bias_w.cross(e) + wa.cross(&e_rate)).dot(&d);
            r += 1;
        }
        match lp.kind() {
            CutKind::Spherical => {}
            CutKind::Revolute => {
                let ab = rows.axis_b;
                let ab_rate = mb.w.cross(&ab);
                for u in &rows.axes[..2] {
                    let c = ab.cross(u);
                    let c_rate = ab_rate.cross(u) + ab.cross(&wa.cross(u));
                    out[r] = dbw.dot(&c) + dw.dot(&c_rate);
                    r += 1;
                }
            }
            CutKind::Prismatic | CutKind::Fixed => {
                for e in &rows.axes {
                    out[r] = wa.cross(e).dot(&dw) + e.dot(&dbw);
                    r += 1;
                }
            }
        }
    }
    // A coupling's row is constant: J̇ = 0.
    out[r..r + model.couplings.len()].fill(0.0);
}

/// The cut joints' wrenches from the multipliers: per loop `[force; moment]` that the cut
/// joint applies to body b (minus that on body a), in frame a's axes. Needs `positions`.
pub fn wrenches(model: &Model, kin: &LoopKinematics, lambda: &[f64]) -> Vec<[f64; 6]> {
    let mut out = Vec::with_capacity(model.loops.len());
    let mut r = 0;
    for (lp, rows) in model.loops.iter().zip(&kin.rows) {
        let mut force = Vec3::zeros();
        for e in &rows.axes[..rows.npos] {
            force += e * lambda[r];
            r += 1;
        }
        let mut moment = Vec3::zeros();
        match lp.kind() {
            CutKind::Spherical => {}
            CutKind::Revolute => {
                let ab = rows.axis_b;
                for u in &rows.axes[..2] {
                    moment += ab.cross(u) * lambda[r];
                    r += 1;
                }
            }
            CutKind::Prismatic | CutKind::Fixed => {
                for e in &rows.axes {
                    moment += e * lambda[r];
                    r += 1;
                }
            }
        }
        let to_a = rows.a.rotation.transpose();
        let (f, m) = (to_a * force, to_a * moment);
        out.push([f.x, f.y, f.z, m.x, m.y, m.z]);
    }
    out
}

/// Index of the loop owning constraint row `row` (a loop's row, not a coupling's).
pub fn loop_of_row(model: &Model, row: usize) -> usize {
    let starts = model.constraint_rows();
    starts.windows(2).position(|w| row < w[1]).unwrap_or(0)
}

/// Whether each revolute cut joint's axes point the same way (`a_b · a_a > 0`): the axis
/// rows vanish for anti-parallel axes too, a closure the joint cannot have.
pub fn flipped_axis(model: &Model, kin: &LoopKinematics) -> Option<usize> {
    model.loops.iter().zip(&kin.rows).position(|(lp, rows)| {
        lp.kind() == CutKind::Revolute && rows.axis_b.dot(&rows.axes[2]) <= 0.0
    })
}
