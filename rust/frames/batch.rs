//! Frame and COM Jacobians over many configurations, [`LANES`] rows at a time ([`V`] lanes).
//!
//! What the one-configuration path decides per call (which links, how each joint frame
//! follows its parent's, which joints turn about a coordinate axis) is resolved once per
//! batch into a [`Walk`]; a row then costs only its arithmetic: per link a pose (rotation,
//! origin) and its joint columns `[a; l]` in a few compact lane arrays, no per-row
//! `LinkState` records. The formulas and their order of operations are those of
//! `kinematics::plan::frame_poses_along` / `kinematics::frame_poses`,
//! `jacobian::point_jacobian_at` and `com::subtree_moments` / `com_jacobian`, so each lane
//! equals the one-configuration result (to the sign of a zero); `tests` check it on fixed and
//! free-base trees. Joints other than revolute or prismatic ones (free flyers, spherical)
//! take the scalar joint code lane by lane.
use crate::joint::Joint;
use crate::kinematics::plan::Placing;
use crate::model::Model;
use crate::support::spatial::{Mat3, Vec3};
use crate::support::trig::{sin_cos, sin_cos_lanes};

use super::lanes::{self, LANES, M3, V, V3};
use super::{FrameRef, ReferenceFrame};

/// How a link's joint moves it, as the lanes compute it.
#[derive(Debug, Clone, Copy)]
enum Move {
    /// Revolute about `sign · e_axis` of the joint frame: columns `a`, `b` (the next two
    /// axes, cyclically; decided here, not per row) turned by sin/cos.
    Turn {
        axis: usize,
        a: usize,
        b: usize,
        sign: f64,
    },
    /// Prismatic along `axis` (joint frame).
    Slide { axis: [f64; 3] },
    /// Any other joint: its scalar code, lane by lane.
    Other,
}

#[derive(Debug, Clone)]
struct Step {
    link: usize,
    /// Index of the parent's step (None: the world).
    parent: Option<usize>,
    placing: Placing,
    /// The placement's rotation (column-major), read by `Placing::General`.
    p: [f64; 9],
    t: [f64; 3],
    mv: Move,
    q: usize,
    /// First column in `Work::cols`.
    col: usize,
}

/// The links a batch walks (parents first), with every per-link decision made.
#[derive(Debug, Clone)]
pub struct Walk {
    steps: Vec<Step>,
    ncols: usize,
}

/// A joint column `[a; l]` about its link's origin, world axes, and its speed's index.
#[derive(Debug, Clone, Copy)]
struct Col {
    ang: V3,
    lin: V3,
    step: usize,
    v: usize,
}

/// The lanes' poses and columns, reused block to block.
pub struct Work {
    rot: Vec<M3>,
    org: Vec<V3>,
    cols: Vec<Col>,
    /// Subtree mass and first moment per step (the COM).
    mass: Vec<f64>,
    moment: Vec<V3>,
    /// The frame's orientation (LOCAL Jacobians).
    local: M3,
    /// One block's Jacobian entries (row-major 6 × nv, or 3 × nv for the COM), lane `l`
    /// row `l`'s: the columns land here as whole lanes, then each row is written out in
    /// one contiguous pass ([`unstage`]). Speeds the walk does not move stay zero.
    stage: Vec<V>,
}

impl Walk {
    /// The walk over `links` (parents first, each link's parent among them or the world).
    pub fn new(model: &Model, links: &[usize]) -> Walk {
        let plan = &model.compiled().poses;
        let mut at = vec![usize::MAX; model.links.len()];
        let mut steps = Vec::with_capacity(links.len());
        let mut ncols = 0;
        for (k, &i) in links.iter().enumerate() {
            let l = &model.links[i];
            at[i] = k;
            let mv = match (&l.joint, plan.steps[i].turn) {
                (_, Some(t)) => Move::Turn {
                    axis: t.axis,
                    a: (t.axis + 1) % 3,
                    b: (t.axis + 2) % 3,
                    sign: t.sign,
                },
                (Joint::Prismatic { axis }, _) => Move::Slide {
                    axis: [axis.x, axis.y, axis.z],
                },
                _ => Move::Other,
            };
            let mut p = [0.0; 9];
            p.copy_from_slice(l.placement.rotation.as_slice());
            let tr = &l.placement.translation;
            steps.push(Step {
                link: i,
                parent: l.parent.map(|p| at[p]),
                placing: plan.steps[i].placing,
                p,
                t: [tr.x, tr.y, tr.z],
                mv,
                q: l.q_index,
                col: ncols,
            });
            ncols += l.joint.nv();
        }
        Walk { steps, ncols }
    }

    /// Buffers for this walk.
    pub fn work(&self, model: &Model) -> Work {
        let n = self.steps.len();
        let zero = [V::ZERO; 3];
        let mut cols = Vec::with_capacity(self.ncols);
        for (k, s) in self.steps.iter().enumerate() {
            let l = &model.links[s.link];
            for c in 0..l.joint.nv() {
                cols.push(Col {
                    ang: zero,
                    lin: zero,
                    step: k,
                    v: l.v_index + c,
                });
            }
        }
        Work {
            rot: vec![[V::ZERO; 9]; n],
            org: vec![zero; n],
            cols,
            mass: self
                .steps
                .iter()
                .map(|s| model.links[s.link].rigid.mass)
                .collect(),
            moment: vec![zero; n],
            local: IDENTITY,
            stage: vec![V::ZERO; 6 * model.nv],
        }
    }
}

/// The configurations of rows `rows` (row-major in `qs`, `nq` each), coordinate `i`.
#[inline(always)]
fn gather(qs: &[f64], nq: usize, rows: &[usize; LANES], i: usize) -> V {
    let mut x = [0.0; LANES];
    for l in 0..LANES {
        x[l] = qs[rows[l] * nq + i];
    }
    V(x)
}

/// Lane `l` of a lane matrix, as a `Mat3`.
fn lane_mat(m: &M3, l: usize) -> Mat3 {
    Mat3::from_column_slice(&std::array::from_fn::<f64, 9, _>(|k| m[k].0[l]))
}

const IDENTITY: M3 = {
    let (o, z) = (V([1.0; LANES]), V([0.0; LANES]));
    [o, z, z, z, o, z, z, z, o]
};

/// Column `j` of the joint frame's orientation `R_parent P` (as `Placing::apply`).
#[inline(always)]
fn joint_column(rp: &M3, placing: &Placing, p: &[f64; 9], j: usize) -> V3 {
    match *placing {
        Placing::Identity => [rp[3 * j], rp[3 * j + 1], rp[3 * j + 2]],
        // Exact: a signed permutation picks and negates the parent's columns.
        Placing::Permutation { from, sign } => {
            let (c, sg) = (3 * from[j], sign[j]);
            [rp[c] * sg, rp[c + 1] * sg, rp[c + 2] * sg]
        }
        Placing::General => lanes::mat_vec_c(rp, &[p[3 * j], p[3 * j + 1], p[3 * j + 2]]),
    }
}

#[inline(always)]
fn set_column(m: &mut M3, j: usize, c: &V3) {
    m[3 * j] = c[0];
    m[3 * j + 1] = c[1];
    m[3 * j + 2] = c[2];
}

/// Poses and joint columns of every step at the rows `rows` (checked configurations).
/// Each rotation is written in place column by column (whole-matrix copies of lanes are
/// calls to `memcpy`).
#[inline(always)]
fn walk_lanes(model: &Model, walk: &Walk, qs: &[f64], rows: &[usize; LANES], w: &mut Work) {
    let nq = model.nq;
    for (k, s) in walk.steps.iter().enumerate() {
        let (done, rest) = w.rot.split_at_mut(k);
        let rk = &mut rest[0];
        let (rp, o_parent) = match s.parent {
            Some(p) => (&done[p], w.org[p]),
            None => (&IDENTITY, [V::ZERO; 3]),
        };
        let origin = lanes::add3(&o_parent, &lanes::mat_vec_c(rp, &s.t));
        match s.mv {
            Move::Turn { axis, a, b, sign } => {
                let x = gather(qs, nq, rows, s.q) * sign;
                let (sn, cs) = sin_cos_lanes(x.0).unwrap_or_else(|| {
                    // An angle beyond the branch-free reduction: one at a time.
                    let mut sc = ([0.0; LANES], [0.0; LANES]);
                    for l in 0..LANES {
                        (sc.0[l], sc.1[l]) = sin_cos(x.0[l]);
                    }
                    sc
                });
                let (sn, cs) = (V(sn), V(cs));
                // R_joint R_k(±q): columns a, b of R_joint turn in their plane.
                let ca = joint_column(rp, &s.placing, &s.p, a);
                let cb = joint_column(rp, &s.placing, &s.p, b);
                let ck = joint_column(rp, &s.placing, &s.p, axis);
                // Written out: `array::from_fn` stayed a call per column (callgrind).
                let turned_a: V3 = [
                    ca[0] * cs + cb[0] * sn,
                    ca[1] * cs + cb[1] * sn,
                    ca[2] * cs + cb[2] * sn,
                ];
                let turned_b: V3 = [
                    cb[0] * cs - ca[0] * sn,
                    cb[1] * cs - ca[1] * sn,
                    cb[2] * cs - ca[2] * sn,
                ];
                set_column(rk, a, &turned_a);
                set_column(rk, b, &turned_b);
                set_column(rk, axis, &ck);
                w.org[k] = origin;
                w.cols[s.col].ang = [ck[0] * sign, ck[1] * sign, ck[2] * sign];
            }
            Move::Slide { axis } => {
                for j in 0..3 {
                    let c = joint_column(rp, &s.placing, &s.p, j);
                    set_column(rk, j, &c);
                }
                let x = gather(qs, nq, rows, s.q);
                let t = [x * axis[0], x * axis[1], x * axis[2]];
                w.org[k] = lanes::add3(&origin, &lanes::mat_vec(rk, &t));
                w.cols[s.col].lin = lanes::mat_vec_c(rk, &axis);
            }
            Move::Other => {
                for j in 0..3 {
                    let c = joint_column(rp, &s.placing, &s.p, j);
                    set_column(rk, j, &c);
                }
                other_lanes(model, s, qs, rows, &origin, k, w);
            }
        }
    }
}

/// A joint the lanes do not specialise: the scalar code of `frame_poses_along`, per lane,
/// from the joint frame's orientation in `w.rot[k]` (replaced by the link's).
fn other_lanes(
    model: &Model,
    s: &Step,
    qs: &[f64],
    rows: &[usize; LANES],
    origin: &V3,
    k: usize,
    w: &mut Work,
) {
    let l = &model.links[s.link];
    let (nq, n) = (model.nq, l.joint.nv());
    for lane in 0..LANES {
        let q = &qs[rows[lane] * nq + s.q..rows[lane] * nq + s.q + l.joint.nq()];
        let rj = lane_mat(&w.rot[k], lane);
        let (r_q, t_q) = l.joint.transform(q);
        let rot = crate::support::spatial::mat_mat(&rj, &r_q);
        let mut o = Vec3::new(origin[0].0[lane], origin[1].0[lane], origin[2].0[lane]);
        if l.joint.translates() {
            o += crate::support::spatial::mat_vec(&rj, &t_q);
        }
        let columns = l.joint.subspace(q, &rj, &rot);
        for e in 0..9 {
            w.rot[k][e].0[lane] = rot[(e % 3, e / 3)];
        }
        for i in 0..3 {
            w.org[k][i].0[lane] = o[i];
        }
        for (c, col) in columns[..n].iter().enumerate() {
            let out = &mut w.cols[s.col + c];
            for i in 0..3 {
                out.ang[i].0[lane] = col[i];
                out.lin[i].0[lane] = col[3 + i];
            }
        }
    }
}

/// The rows `first..first + count` as blocks of [`LANES`] row indices (the last block padded
/// with its last row) and how many of each block are real.
fn blocks(first: usize, count: usize) -> impl Iterator<Item = ([usize; LANES], usize)> {
    (0..count.div_ceil(LANES)).map(move |b| {
        let start = first + b * LANES;
        let real = LANES.min(first + count - start);
        (std::array::from_fn(|l| start + l.min(real - 1)), real)
    })
}

/// [`frame_jacobian_rows`]' body.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn frame_rows(
    model: &Model,
    walk: &Walk,
    f: &FrameRef,
    rf: ReferenceFrame,
    qs: &[f64],
    first: usize,
    count: usize,
    out: &mut [f64],
    poll: &dyn Fn() -> crate::support::error::Result<()>,
) -> crate::support::error::Result<()> {
    let nv = model.nv;
    if f.link.is_none() || walk.steps.is_empty() {
        // Welded to the world: nothing moves it.
        out[..count * 6 * nv].fill(0.0);
        return Ok(());
    }
    let mut w = walk.work(model);
    let tip = walk.steps.len() - 1;
    let fp = &f.placement;
    let ft = [fp.translation.x, fp.translation.y, fp.translation.z];
    let mut fr = [0.0; 9];
    fr.copy_from_slice(fp.rotation.as_slice());
    // Zero in every lane while the results are finite (`x · 0` is NaN for inf and NaN).
    let mut finite = V::ZERO;
    for (b, (rows, real)) in blocks(first, count).enumerate() {
        if b % (256 / LANES) == 256 / LANES - 1 {
            poll()?;
        }
        walk_lanes(model, walk, qs, &rows, &mut w);
        let (r, o) = (&w.rot[tip], &w.org[tip]);
        // The frame's pose, as `Placement::compose`.
        let p = lanes::add3(&lanes::mat_vec_c(r, &ft), o);
        let x = match rf {
            ReferenceFrame::World => [V::ZERO; 3],
            _ => p,
        };
        let local = rf == ReferenceFrame::Local;
        if local {
            // `R P_f` in place, column by column as `mat_mat` (no whole-matrix copy).
            for j in 0..3 {
                let c = lanes::mat_vec_c(r, &[fr[3 * j], fr[3 * j + 1], fr[3 * j + 2]]);
                set_column(&mut w.local, j, &c);
            }
        }
        let base = (rows[0] - first) * 6 * nv;
        let out = &mut out[base..base + real * 6 * nv];
        for c in &w.cols {
            let arm = lanes::sub3(&x, &w.org[c.step]);
            let mut lin = lanes::add3(&c.lin, &lanes::cross(&c.ang, &arm));
            let mut ang = c.ang;
            if local {
                ang = lanes::tr_vec(&w.local, &ang);
                lin = lanes::tr_vec(&w.local, &lin);
            }
            // A revolute or prismatic joint's angular rows are (turned) unit axes or zero,
            // whatever q: only the linear ones can overflow there.
            finite = finite + lin[0] * 0.0 + lin[1] * 0.0 + lin[2] * 0.0;
            if let Move::Other = walk.steps[c.step].mv {
                finite = finite + ang[0] * 0.0 + ang[1] * 0.0 + ang[2] * 0.0;
            }
            for i in 0..3 {
                w.stage[i * nv + c.v] = ang[i];
                w.stage[(3 + i) * nv + c.v] = lin[i];
            }
        }
        unstage(&w.stage, out, real);
    }
    overflowed("frame_jacobian", finite)
}

/// Row `l` of `out` (rows of `stage.len()` entries) gets lane `l` of every entry of
/// `stage`, for the first `real` rows: one pass per row over contiguous memory (the
/// entry-by-entry scatter into strided rows cost a quarter of a Jacobian row).
#[inline(always)]
fn unstage(stage: &[V], out: &mut [f64], real: usize) {
    if stage.is_empty() {
        return; // nv = 0: nothing to write (and no zero-sized chunks)
    }
    for (l, row) in out.chunks_exact_mut(stage.len()).take(real).enumerate() {
        for (o, v) in row.iter_mut().zip(stage) {
            *o = v.0[l];
        }
    }
}

/// The error for results that are not finite from finite inputs (`finite` not all zero).
fn overflowed(what: &str, finite: V) -> crate::support::error::Result<()> {
    match finite.0.iter().all(|x| *x == 0.0) {
        true => Ok(()),
        false => Err(crate::support::error::Error::Numerical(format!(
            "{what}: the result is not finite although the inputs are: a configuration overflows double precision"
        ))),
    }
}

/// [`com_rows`]' body.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn com_rows_impl(
    model: &Model,
    walk: &Walk,
    qs: &[f64],
    first: usize,
    count: usize,
    com: &mut [f64],
    mut jac: Option<&mut [f64]>,
    poll: &dyn Fn() -> crate::support::error::Result<()>,
) -> crate::support::error::Result<()> {
    let nv = model.nv;
    let mut w = walk.work(model);
    mass_sums(walk, &mut w);
    let n = walk.steps.len();
    let mut finite = V::ZERO;
    for (b, (rows, real)) in blocks(first, count).enumerate() {
        if b % (256 / LANES) == 256 / LANES - 1 {
            poll()?;
        }
        walk_lanes(model, walk, qs, &rows, &mut w);
        // Subtree first moments, as `com::subtree_moments`.
        for k in 0..n {
            let rb = &model.links[walk.steps[k].link].rigid;
            let c = [rb.com.x, rb.com.y, rb.com.z];
            let at = lanes::add3(&w.org[k], &lanes::mat_vec_c(&w.rot[k], &c));
            w.moment[k] = lanes::scale3(&at, V::splat(rb.mass));
        }
        for k in (0..n).rev() {
            if let Some(p) = walk.steps[k].parent {
                w.moment[p] = lanes::add3(&w.moment[p], &w.moment[k]);
            }
        }
        // Subtree masses do not change with q: summed once in `mass_sums`.
        let (mut total, mut h) = (0.0, [V::ZERO; 3]);
        for k in 0..n {
            if walk.steps[k].parent.is_none() {
                total += w.mass[k];
                h = lanes::add3(&h, &w.moment[k]);
            }
        }
        let t = V::splat(total);
        let base = rows[0] - first;
        let c = [h[0] / t, h[1] / t, h[2] / t];
        finite = finite + c[0] * 0.0 + c[1] * 0.0 + c[2] * 0.0;
        for l in 0..real {
            for i in 0..3 {
                com[3 * (base + l) + i] = c[i].0[l];
            }
        }
        let Some(jac) = jac.as_deref_mut() else {
            continue;
        };
        let out = &mut jac[base * 3 * nv..(base + real) * 3 * nv];
        let stage = &mut w.stage[..3 * nv];
        for c in &w.cols {
            let m = V::splat(w.mass[c.step]);
            let arm = lanes::sub3(&w.moment[c.step], &lanes::scale3(&w.org[c.step], m));
            let col = lanes::add3(&lanes::scale3(&c.lin, m), &lanes::cross(&c.ang, &arm));
            let col = [col[0] / t, col[1] / t, col[2] / t];
            finite = finite + col[0] * 0.0 + col[1] * 0.0 + col[2] * 0.0;
            for i in 0..3 {
                stage[i * nv + c.v] = col[i];
            }
        }
        unstage(stage, out, real);
    }
    overflowed("center_of_mass", finite)
}

/// `walk`'s work with each step's mass replaced by its subtree's (what [`com_rows`] reads).
fn mass_sums(walk: &Walk, w: &mut Work) {
    for k in (0..walk.steps.len()).rev() {
        if let Some(p) = walk.steps[k].parent {
            w.mass[p] += w.mass[k];
        }
    }
}

#[cfg(target_arch = "x86_64")]
use crate::support::cpu::has_avx512;

/// Defines `$name`, which runs `$wide` (the body compiled for AVX-512F: a lane block in
/// one register) where [`has_avx512`] says so, else the AVX2/baseline dispatcher `$narrow`.
/// As there, only the instructions differ: Rust fuses no multiply-add, so the bits are the
/// baseline build's.
macro_rules! widened {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident / $wide:ident / $narrow:ident
        ($($arg:ident : $ty:ty),* $(,)?) -> $ret:ty => $body:ident
    ) => {
        $(#[$meta])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if has_avx512() {
                // SAFETY: the CPU supports AVX-512F, checked just above.
                return unsafe { $wide($($arg),*) };
            }
            $narrow($($arg),*)
        }

        /// The body compiled for AVX-512F.
        ///
        /// # Safety
        /// The CPU must support AVX-512F.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $wide($($arg: $ty),*) -> $ret {
            $body($($arg),*)
        }
    };
}

widened! {
    /// Frame `f`'s Jacobians (row-major 6 × nv each) at rows `first..first + count` of `qs`
    /// into `out` (its first row is row `first`'s; every entry written). `walk` is
    /// `f.link`'s support; `poll` is asked every 256 rows. The lanes run eight to an
    /// instruction in the AVX-512 copy, four in the AVX2 one (no FMA: the baseline
    /// build's bits).
    pub fn frame_jacobian_rows / frame_rows_avx512 / frame_rows_narrow (
        model: &Model,
        walk: &Walk,
        f: &FrameRef,
        rf: ReferenceFrame,
        qs: &[f64],
        first: usize,
        count: usize,
        out: &mut [f64],
        poll: &dyn Fn() -> crate::support::error::Result<()>
    ) -> crate::support::error::Result<()> => frame_rows
}

widened! {
    /// The centre of mass (`com`, 3 per row) and, with `jac`, its Jacobian (row-major
    /// 3 × nv per row; every entry written) at rows `first..first + count` of `qs`; `walk`
    /// covers every link (in link order) of a model with moving mass.
    pub fn com_rows / com_rows_avx512 / com_rows_narrow (
        model: &Model,
        walk: &Walk,
        qs: &[f64],
        first: usize,
        count: usize,
        com: &mut [f64],
        jac: Option<&mut [f64]>,
        poll: &dyn Fn() -> crate::support::error::Result<()>
    ) -> crate::support::error::Result<()> => com_rows_impl
}

crate::support::cpu::multiversion! {
    /// [`frame_jacobian_rows`] without AVX-512: the AVX2 copy or the baseline one.
    fn frame_rows_narrow / frame_rows_avx2 / frame_rows_baseline [] (
        model: &Model,
        walk: &Walk,
        f: &FrameRef,
        rf: ReferenceFrame,
        qs: &[f64],
        first: usize,
        count: usize,
        out: &mut [f64],
        poll: &dyn Fn() -> crate::support::error::Result<()>
    ) -> crate::support::error::Result<()> => frame_rows
}

crate::support::cpu::multiversion! {
    /// [`com_rows`] without AVX-512: the AVX2 copy or the baseline one.
    fn com_rows_narrow / com_rows_avx2 / com_rows_baseline [] (
        model: &Model,
        walk: &Walk,
        qs: &[f64],
        first: usize,
        count: usize,
        com: &mut [f64],
        jac: Option<&mut [f64]>,
        poll: &dyn Fn() -> crate::support::error::Result<()>
    ) -> crate::support::error::Result<()> => com_rows_impl
}
