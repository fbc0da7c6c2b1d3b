//! What a moving mechanism does to its supports, from its point masses: the motion of every
//! point mass, the **shaking force and moment** (the resultant the mechanism exerts on its
//! ground, gravity excluded: `F = −Σ m_ij a_ij`, `M_O = −Σ m_ij (r_ij − O) × a_ij`), and the
//! **bearing forces** (the wrench each joint transmits, tree and cut joints alike).
//!
//! Only Newton's translational equations of point masses enter: a link's seven point masses
//! have its mass, first and second moments, so these sums equal the rates of the
//! mechanism's linear and angular momenta exactly (docs/balancing.md). The quantities are
//! linear in the point masses for a given motion, which is what makes balancing a least
//! squares problem.
use crate::kinematics::{self, body_placement};
use crate::loops::{self, LoopSolver};
use crate::model::Model;
use crate::recursive::reference::{inverse_dynamics_world, Workspace};
use crate::recursive::{self, Data};
use crate::support::alloc::try_zeros_vec;
use crate::support::error::Result;
use crate::support::spatial::{angular, linear, shift_twist, stack, Mat3, Placement, Vec3, Vec6};

/// World positions, velocities and accelerations of points carried by the links, with
/// their masses; index `7 i + j` for point `j` of link `i` when filled by [`point_motion`].
#[derive(Debug, Clone, Default)]
pub struct PointMotion {
    pub masses: Vec<f64>,
    /// The link carrying each point.
    pub link: Vec<usize>,
    pub positions: Vec<Vec3>,
    pub velocities: Vec<Vec3>,
    pub accelerations: Vec<Vec3>,
}

/// Links' twists `[ω; v_O]` and twist rates `[ω̇; a_O]` (world axes, link origins) at
/// `(q, v, a)`, with no gravity: kinematics in `ws.links`, rates in `ws.accel`.
pub fn link_accelerations(model: &Model, ws: &mut Workspace, q: &[f64], v: &[f64], a: &[f64]) {
    kinematics::positions(model, q, &mut ws.links);
    kinematics::velocities(model, q, v, &mut ws.links);
    for (i, l) in model.links.iter().enumerate() {
        let s = &ws.links[i];
        let carried = match l.parent {
            Some(p) => shift_twist(&ws.accel[p], &(s.origin - ws.links[p].origin)),
            None => Vec6::zeros(),
        };
        let mut acc = carried + s.xi;
        for k in 0..l.joint.nv() {
            acc += s.s[k] * a[l.v_index + k];
        }
        ws.accel[i] = acc;
    }
}

/// The motion of a point at offset `d` (world axes) from the origin of a link moving with
/// twist `t` and twist rate `dt`: `(v + ω × d, a + ω̇ × d + ω × (ω × d))`.
#[inline]
fn carried_point(t: &Vec6, dt: &Vec6, d: &Vec3) -> (Vec3, Vec3) {
    let (w, wd) = (angular(t), angular(dt));
    (
        linear(t) + w.cross(d),
        linear(dt) + wd.cross(d) + w.cross(&w.cross(d)),
    )
}

/// Every link's seven point masses in motion at `(q, v, a)`.
pub fn point_motion(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    out: &mut PointMotion,
) {
    link_accelerations(model, ws, q, v, a);
    let n = 7 * model.links.len();
    out.masses.clear();
    out.link.clear();
    out.positions.clear();
    out.velocities.clear();
    out.accelerations.clear();
    out.masses.reserve(n);
    for (i, l) in model.links.iter().enumerate() {
        let s = &ws.links[i];
        for (m, p) in l.points.masses.iter().zip(&l.points.positions) {
            let d = s.rotation * p;
            let (vel, acc) = carried_point(&s.twist, &ws.accel[i], &d);
            out.masses.push(*m);
            out.link.push(i);
            out.positions.push(s.origin + d);
            out.velocities.push(vel);
            out.accelerations.push(acc);
        }
    }
}

/// The motion of given points `(link, offset in the link frame)` at the state of the last
/// [`link_accelerations`] (or [`point_motion`]) call: `(position, velocity, acceleration)`.
pub fn carried_points<'a>(
    ws: &'a Workspace,
    points: &'a [(usize, Vec3)],
) -> impl Iterator<Item = (Vec3, Vec3, Vec3)> + 'a {
    points.iter().map(|(i, p)| {
        let s = &ws.links[*i];
        let d = s.rotation * p;
        let (vel, acc) = carried_point(&s.twist, &ws.accel[*i], &d);
        (s.origin + d, vel, acc)
    })
}

/// Shaking force and moment about `about` (world): `(−Σ m a, −Σ m (r − O) × a)`.
pub fn shaking(points: &PointMotion, about: &Vec3) -> (Vec3, Vec3) {
    let mut force = Vec3::zeros();
    let mut moment = Vec3::zeros();
    for ((m, r), acc) in points
        .masses
        .iter()
        .zip(&points.positions)
        .zip(&points.accelerations)
    {
        let f = acc * *m;
        force -= f;
        moment -= (r - about).cross(&f);
    }
    (force, moment)
}

/// Adds each cut joint's wrench (`cut[k] = [force; moment]` on body b at frame b's origin in
/// frame a's axes, minus it on body a: what `loops::constraint_forces` returns) to
/// `external`, one wrench per link `[moment about the link origin; force]` in world axes.
/// Needs the positions in `ws.links` (after [`link_accelerations`]).
pub fn add_cut_wrenches(model: &Model, ws: &Workspace, cut: &[[f64; 6]], external: &mut [Vec6]) {
    let frame = |body: Option<usize>, local: &Placement| match body {
        Some(b) => body_placement(model, &ws.links, b).compose(local),
        None => *local,
    };
    for (lp, w) in model.loops.iter().zip(cut) {
        let fa = frame(lp.body_a, &lp.frame_a);
        let fb = frame(lp.body_b, &lp.frame_b);
        let ra: Mat3 = fa.rotation;
        let f = ra * Vec3::new(w[0], w[1], w[2]);
        let m = ra * Vec3::new(w[3], w[4], w[5]);
        // Both act at frame b's origin: exactly so for the force on body a too (its rows'
        // directions turn with a, docs/loops.md §3).
        let at = fb.translation;
        for (body, sign) in [(lp.body_b, 1.0), (lp.body_a, -1.0)] {
            let Some(link) = body.and_then(|b| model.bodies[b].link) else {
                continue;
            };
            let arm = at - ws.links[link].origin;
            external[link] += stack(&(m + arm.cross(&f)), &f) * sign;
        }
    }
}

/// The wrench each joint transmits to its link's subtree at `(q, v, a)`: per link,
/// `[moment about the link origin; force]` in world axes, gravity `g` and the `external`
/// wrenches (one per link, as [`inverse_dynamics_world`] takes them; cut joints' wrenches
/// added by [`add_cut_wrenches`]) included. Also writes the joint forces `tau` (the wrench's
/// components along the joint's motion).
#[allow(clippy::too_many_arguments)]
pub fn joint_wrenches(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    tau: &mut [f64],
) -> Vec<Vec6> {
    inverse_dynamics_world(model, ws, q, v, a, g, external, tau);
    ws.wrench.clone()
}

/// A world wrench `[n; f]` about a link origin as `[f; n]` in the link's axes.
pub fn in_link_frame(rotation: &Mat3, w: &Vec6) -> [f64; 6] {
    let f = rotation.transpose() * linear(w);
    let n = rotation.transpose() * angular(w);
    [f.x, f.y, f.z, n.x, n.y, n.z]
}

/// Adds `J_pᵀ f` to `out` (length nv): the joint forces of a world force `f` applied at the
/// world point `point` of `link`, walking the joints from `link` to the root (world columns
/// and origins from the last [`link_accelerations`] call).
pub fn add_point_force(
    model: &Model,
    ws: &Workspace,
    link: usize,
    point: &Vec3,
    f: &Vec3,
    out: &mut [f64],
) {
    let mut k = Some(link);
    while let Some(i) = k {
        let l = &model.links[i];
        let s = &ws.links[i];
        let wrench = stack(&(point - s.origin).cross(f), f);
        for c in 0..l.joint.nv() {
            out[l.v_index + c] += s.s[c].dot(&wrench);
        }
        k = l.parent;
    }
}

/// Stacked states: `rows` rows of `q` (nq each), `v` and `a` (nv each), row-major.
#[derive(Clone, Copy)]
pub struct States<'a> {
    pub rows: usize,
    pub q: &'a [f64],
    pub v: &'a [f64],
    pub a: &'a [f64],
}

impl<'a> States<'a> {
    /// Row `k`: `(q, v, a)`.
    pub fn row(&self, model: &Model, k: usize) -> (&'a [f64], &'a [f64], &'a [f64]) {
        let (nq, nv) = (model.nq, model.nv);
        (
            &self.q[k * nq..(k + 1) * nq],
            &self.v[k * nv..(k + 1) * nv],
            &self.a[k * nv..(k + 1) * nv],
        )
    }
}

/// A computation over stacked states that may stop early (an interrupt): `value` holds the
/// results of the first `rows` states, and `stopped` why it stopped, if it did.
pub struct Rows<T> {
    pub value: T,
    pub rows: usize,
    pub stopped: Option<crate::support::error::Error>,
}

/// Shaking force and moment about `about` at every state: `(forces, moments)`, 3 per row
/// (of the states done when interrupted).
pub fn shaking_of_states(
    model: &Model,
    states: &States<'_>,
    about: &Vec3,
) -> Rows<(Vec<f64>, Vec<f64>)> {
    let mut ws = Workspace::new(model);
    let mut pm = PointMotion::default();
    let rows = states.rows;
    let (mut force, mut moment) = (Vec::with_capacity(3 * rows), Vec::with_capacity(3 * rows));
    for k in 0..rows {
        if let Err(e) = crate::support::interrupt::check("shaking") {
            return Rows {
                value: (force, moment),
                rows: k,
                stopped: Some(e),
            };
        }
        let (q, v, a) = states.row(model, k);
        point_motion(model, &mut ws, q, v, a, &mut pm);
        let (f, m) = shaking(&pm, about);
        force.extend_from_slice(f.as_slice());
        moment.extend_from_slice(m.as_slice());
    }
    Rows {
        value: (force, moment),
        rows,
        stopped: None,
    }
}

/// What the balancing regressors need per point and state ([`point_regressor`]), row-major
/// (state, point, component).
pub struct PointRegressor {
    /// World positions (rows × P × 3).
    pub positions: Vec<f64>,
    /// World accelerations (rows × P × 3).
    pub accelerations: Vec<f64>,
    /// `J_pᵀ (a_p − g)` (rows × P × nv): the joint forces a unit mass at the point needs.
    pub generalized: Vec<f64>,
}

/// Per state and point `(link, offset in the link frame)`: its world position, acceleration
/// and the joint forces a unit mass there needs under gravity `g` (docs/balancing.md).
/// `Err` only when the arrays cannot be allocated; an interrupt keeps the states done (the
/// arrays are cut to them).
pub fn point_regressor(
    model: &Model,
    states: &States<'_>,
    points: &[(usize, Vec3)],
    g: &Vec3,
) -> Result<Rows<PointRegressor>> {
    let (rows, nv, np) = (states.rows, model.nv, points.len());
    // The sizes are the caller's to choose: requested fallibly (OutOfMemory, not an abort).
    let entries = |width: usize| {
        rows.checked_mul(np)
            .and_then(|x| x.checked_mul(width))
            .unwrap_or(usize::MAX)
    };
    let what = |name: &str| format!("point_regressor['{name}'] ({rows} states × {np} points)");
    let mut out = PointRegressor {
        positions: try_zeros_vec(entries(3), &what("positions"))?,
        accelerations: try_zeros_vec(entries(3), &what("accelerations"))?,
        generalized: try_zeros_vec(entries(nv), &what("generalized"))?,
    };
    let mut ws = Workspace::new(model);
    for k in 0..rows {
        if let Err(e) = crate::support::interrupt::check("point_regressor") {
            out.positions.truncate(k * np * 3);
            out.accelerations.truncate(k * np * 3);
            out.generalized.truncate(k * np * nv);
            return Ok(Rows {
                value: out,
                rows: k,
                stopped: Some(e),
            });
        }
        let (q, v, a) = states.row(model, k);
        link_accelerations(model, &mut ws, q, v, a);
        for (j, (r, _, ap)) in carried_points(&ws, points).enumerate() {
            let at = (k * np + j) * 3;
            out.positions[at..at + 3].copy_from_slice(r.as_slice());
            out.accelerations[at..at + 3].copy_from_slice(ap.as_slice());
            let row = &mut out.generalized[(k * np + j) * nv..(k * np + j + 1) * nv];
            add_point_force(model, &ws, points[j].0, &r, &(ap - g), row);
        }
    }
    Ok(Rows {
        value: out,
        rows,
        stopped: None,
    })
}

/// What every joint transmits at one state ([`bearing_forces`]).
pub struct BearingForces {
    /// Per moving link `[force; moment]` the parent applies to the link's subtree at the
    /// link origin, in the link's axes or the world's (nlinks × 6, row-major).
    pub joints: Vec<f64>,
    /// The cut joints' wrenches as `loops::constraint_forces` gives them (empty for a tree).
    pub loops: Vec<[f64; 6]>,
    /// The joint forces: with loops the `actuated` ones' as solved (exact zeros at the
    /// passive joints, as the inverse dynamics), not the wrenches' projections (zero only to
    /// round-off).
    pub tau: Vec<f64>,
}

/// The bearing forces at `(q, v, a)` under gravity `g` and `external` link wrenches: the
/// inverse dynamics, for a model with loops the forces of the `actuated` coordinates and the
/// cut joints' wrenches that produce the motion (`loops::driving_forces`), then the joint
/// wrenches with the cut wrenches applied; `world` gives them in world axes.
#[allow(clippy::too_many_arguments)]
pub fn bearing_forces(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    actuated: Option<&[usize]>,
    world: bool,
) -> Result<BearingForces> {
    let mut cut: Vec<[f64; 6]> = Vec::new();
    let mut tau_loops: Option<Vec<f64>> = None;
    if let Some(act) = actuated {
        let mut data = Data::new(model);
        let mut tree = vec![0.0; model.nv];
        recursive::inverse_dynamics(model, &mut data, q, v, a, g, external, &mut tree);
        let mut solver = LoopSolver::new(model);
        let (tau_act, c) = loops::driving_forces(model, &mut solver, q, v, a, &tree, act)?;
        (cut, tau_loops) = (c, Some(tau_act));
    }
    let mut ws = Workspace::new(model);
    link_accelerations(model, &mut ws, q, v, a);
    let mut all_ext =
        external.map_or_else(|| vec![Vec6::zeros(); model.links.len()], <[_]>::to_vec);
    add_cut_wrenches(model, &ws, &cut, &mut all_ext);
    let mut tau = vec![0.0; model.nv];
    let wrenches = joint_wrenches(model, &mut ws, q, v, a, g, Some(&all_ext), &mut tau);
    let joints = wrenches
        .iter()
        .zip(&ws.links)
        .flat_map(|(w, s)| {
            let rot = if world { Mat3::identity() } else { s.rotation };
            in_link_frame(&rot, w)
        })
        .collect();
    Ok(BearingForces {
        joints,
        loops: cut,
        tau: tau_loops.unwrap_or(tau),
    })
}

/// `frame`: "joint" (each link's own axes) or "world": whether in world axes.
pub fn world_frame(frame: &str) -> Result<bool> {
    match frame {
        "joint" => Ok(false),
        "world" => Ok(true),
        other => Err(crate::support::error::Error::arg(
            "frame",
            "\"joint\" or \"world\"",
            format!("'{other}'"),
        )),
    }
}

impl PointMotion {
    /// Refuses a motion that is not finite (from finite inputs), naming the field.
    pub fn check_finite(&self, what: &str) -> Result<()> {
        for (k, x) in [
            ("positions", &self.positions),
            ("velocities", &self.velocities),
            ("accelerations", &self.accelerations),
        ] {
            let flat: Vec<f64> = x.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
            crate::support::error::check_result(&format!("{what}['{k}']"), &flat)?;
        }
        Ok(())
    }
}
