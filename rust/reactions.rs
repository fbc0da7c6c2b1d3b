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
use crate::alloc::try_zeros_vec;
use crate::error::Result;
use crate::kinematics::{self, body_placement};
use crate::model::Model;
use crate::recursive::reference::{inverse_dynamics_world, Workspace};
use crate::spatial::{angular, linear, shift_twist, stack, Mat3, Placement, Vec3, Vec6};

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

/// What balancing needs per state `k` and point `j` (C order, `(N, P, ·)`): world positions
/// and accelerations (3 each) and `generalized = J_pᵀ (a_p − g)` (nv), the joint forces a
/// unit mass at the point needs.
#[derive(Debug, Clone, Default)]
pub struct PointRegressor {
    pub positions: Vec<f64>,
    pub accelerations: Vec<f64>,
    pub generalized: Vec<f64>,
}

/// [`PointRegressor`] at the `rows` states stacked in `qs` (rows × nq), `vs`, `accs`
/// (rows × nv), for `points` given as `(link, offset in the link frame)`. The arrays' sizes
/// are the caller's to choose, so they are requested fallibly (an `OutOfMemory` error, not an
/// abort); interruptible between states.
pub fn point_regressor(
    model: &Model,
    states: (&[f64], &[f64], &[f64]),
    rows: usize,
    points: &[(usize, Vec3)],
    g: &Vec3,
) -> Result<PointRegressor> {
    let (qs, vs, accs) = states;
    let (nq, nv, np) = (model.nq, model.nv, points.len());
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
        crate::interrupt::check("point_regressor")?;
        let (qk, vk, ak) = (
            &qs[k * nq..(k + 1) * nq],
            &vs[k * nv..(k + 1) * nv],
            &accs[k * nv..(k + 1) * nv],
        );
        link_accelerations(model, &mut ws, qk, vk, ak);
        for (j, (r, _, ap)) in carried_points(&ws, points).enumerate() {
            let at = (k * np + j) * 3;
            out.positions[at..at + 3].copy_from_slice(r.as_slice());
            out.accelerations[at..at + 3].copy_from_slice(ap.as_slice());
            let gen = &mut out.generalized[(k * np + j) * nv..(k * np + j + 1) * nv];
            add_point_force(model, &ws, points[j].0, &r, &(ap - g), gen);
        }
    }
    Ok(out)
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
