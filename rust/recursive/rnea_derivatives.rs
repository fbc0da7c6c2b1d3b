//! Analytic derivatives of the inverse dynamics `τ = ID(q, v, a)` (Carpentier & Mansard,
//! "Analytical derivatives of rigid body dynamics algorithms", RSS 2018; Pinocchio's
//! `computeRNEADerivatives`): `∂τ/∂q`, `∂τ/∂v` and `∂τ/∂a = M`, in O(nv · depth), with the
//! configuration perturbed in the tangent space (`q ⊕ δ`: a quaternion joint turns its body
//! by `R exp(δ)`, the other joints add `δ` to their coordinates). docs/derivatives.md.
//!
//! Everything is in world axes about the world origin (Plücker coordinates), where a joint
//! column `S_k` is carried rigidly by the bodies it moves: perturbing speed direction `k`
//! turns every quantity attached to the bodies downstream of it by `S_k ×`. With
//! `v⁻_k`, `a⁻_k` the velocity and acceleration of the frame the column is fixed in (the
//! parent's for every joint; for the ZYZ joint, a chain of three revolutes, the frame after
//! the joint's earlier angles), and for a body `i` moved by `k`:
//!
//! * `∂v_i/∂q_k = S_k × v_i + dV_k`, `dV_k = v⁻_k × S_k`;
//! * `∂a_i/∂q_k = S_k × a_i + dV_k × v_i + dA_k`, `dA_k = a⁻_k × S_k + v⁻_k × dV_k`;
//! * `∂v_i/∂v_k = S_k`, `∂a_i/∂v_k = S_k × v_i + dAv_k`, `dAv_k = (v⁻_k + v_b) × S_k`
//!   (`v_b`: the velocity of the column's body).
//!
//! The body wrench `f_i = Y_i a_i + v_i ×* Y_i v_i` then changes by its rigid turn plus
//! `Y_i dA_k + B_i dV_k` (q) or `Y_i dAv_k + B_i S_k` (v), where `B_i x = −Y_i(v_i × x) +
//! x ×* Y_i v_i + v_i ×* Y_i x` is linear in the angular part of `x` only (Galilean
//! invariance). Composite sums `Y`, `B`, `F` over each subtree give, for `τ_j = S_jᵀ F_j`:
//! `∂τ_j/∂q_k = S_jᵀ g_k` with `g_k = S_k ×* F_k + Y_k dA_k + B_k dV_k` when `j` is upstream
//! of `k` (`S_j` does not move), and `(Y_j S_j)ᵀ dA_k + (B_jᵀ S_j)ᵀ dV_k` when `k` moves `j`
//! (the rigid turns of `S_j` and `F_j` cancel in the pairing); the same with `dAv_k`, `S_k`
//! for `∂τ/∂v`.
use super::base_accel;
use super::workspace::{Data, DerivativeData, DofWork};
use crate::kinematics;
use crate::model::Model;
use crate::support::spatial::{angular, linear, stack, BodyInertia, Mat3, Vec3, Vec6};

/// No dof (above the root).
pub(crate) const NO_DOF: usize = usize::MAX;

/// Spatial motion cross product `a × b` (angular part first).
#[inline(always)]
pub(crate) fn cross_motion(a: &Vec6, b: &Vec6) -> Vec6 {
    let (wa, va, wb, vb) = (angular(a), linear(a), angular(b), linear(b));
    stack(&wa.cross(&wb), &(wa.cross(&vb) + va.cross(&wb)))
}

/// Spatial force cross product `a ×* f` (moment part first).
#[inline(always)]
pub(crate) fn cross_force(a: &Vec6, f: &Vec6) -> Vec6 {
    let (wa, va, n, fl) = (angular(a), linear(a), angular(f), linear(f));
    stack(&(wa.cross(&n) + va.cross(&fl)), &wa.cross(&fl))
}

/// `B x = [B_aa x_a; B_la x_a]`, `B_la x_a = −2 b_l × x_a`.
#[inline(always)]
fn b_mul(baa: &Mat3, bl: &Vec3, x: &Vec6) -> Vec6 {
    let xa = angular(x);
    stack(&(baa * xa), &(bl.cross(&xa) * -2.0))
}

crate::support::cpu::multiversion! {
    /// `∂τ/∂q`, `∂τ/∂v` and `M = ∂τ/∂a` of `τ = ID(q, v, a)` (gravity `g`, no external
    /// wrenches) into `dd.dtau_dq`, `dd.dtau_dv`, `dd.mass`; `τ` itself into `dd.tau`. Columns
    /// are tangent directions (nv of them). `data.links` is overwritten with the positions at
    /// `q`. No allocation. Compiled for AVX2 where the CPU has it (see [`crate::support::cpu`]).
    pub fn inverse_dynamics_derivatives / derivatives_avx2 / derivatives_baseline [] (
        model: &Model,
        data: &mut Data,
        dd: &mut DerivativeData,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        g: &Vec3,
    ) => derivatives_body
}

crate::support::cpu::multiversion! {
    /// [`inverse_dynamics_derivatives`] by rows straight into `out` (`∂τ/∂q`, `∂τ/∂v`, `M`,
    /// each nv × nv in C order, every entry written): the caller's arrays, so nothing is
    /// copied after. `dd.row_major` is set; `dd`'s own matrices are left as they were.
    pub fn inverse_dynamics_derivatives_into / rows_avx2 / rows_baseline [] (
        model: &Model,
        data: &mut Data,
        dd: &mut DerivativeData,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        g: &Vec3,
        out: [&mut [f64]; 3],
    ) => rows_body
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn rows_body(
    model: &Model,
    data: &mut Data,
    dd: &mut DerivativeData,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    out: [&mut [f64]; 3],
) {
    dd.row_major = true;
    vectors::<true>(model, data, dd, q, v, a, g);
    let [dq, dv, mm] = out;
    super::deriv_rows::fill_rows_into(model, dd, (dq, dv, mm));
    if !model.armature.is_empty() {
        super::armature::add_to_forces(model, a, &mut dd.tau);
        for (k, arm) in model.armature.iter().enumerate() {
            mm[k * model.nv + k] += arm;
        }
    }
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn derivatives_body(
    model: &Model,
    data: &mut Data,
    dd: &mut DerivativeData,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
) {
    if dd.row_major {
        by_rows(model, data, dd, (q, v, a), g);
    } else {
        vectors::<false>(model, data, dd, q, v, a, g);
        fill_matrices(model, dd);
    }
    if !model.armature.is_empty() {
        super::armature::add_to_forces(model, a, &mut dd.tau);
        super::armature::add_to_mass_matrix(model, &mut dd.mass);
    }
}

crate::support::cpu::multiversion! {
    /// The by-rows passes and fill, out of line (their own AVX2 copy): the column path
    /// (small models) carries none of their code.
    fn by_rows / by_rows_avx2 / by_rows_baseline [] (
        model: &Model,
        data: &mut Data,
        dd: &mut DerivativeData,
        qva: (&[f64], &[f64], &[f64]),
        g: &Vec3,
    ) => by_rows_body
}

#[inline(always)]
fn by_rows_body(
    model: &Model,
    data: &mut Data,
    dd: &mut DerivativeData,
    (q, v, a): (&[f64], &[f64], &[f64]),
    g: &Vec3,
) {
    vectors::<true>(model, data, dd, q, v, a, g);
    super::deriv_rows::fill_rows(model, dd);
}

/// The outward and inward passes: every dof's vectors, `τ`, and the tree's shape, for the
/// fills; `ROWS`: also the per-dof arrays the fill by rows reads
/// ([`super::deriv_rows`]), a separate copy so that the column path tests nothing per dof.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn vectors<const ROWS: bool>(
    model: &Model,
    data: &mut Data,
    dd: &mut DerivativeData,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
) {
    let n = model.links.len();
    let nvt = model.nv;
    // The poses without the world-axes inertias (each is rotated where the outward pass
    // shifts it), revolute joints about a coordinate axis by two turned columns: equal to
    // `positions`' to rounding.
    kinematics::frame_poses(model, q, &mut data.links);
    let base = base_accel(g);

    // Outward: velocities, accelerations, the dof directions and each body's wrench.
    for i in 0..n {
        outward_link(model, data, dd, i, (v, a), base);
    }

    // Inward: composite sums, and each dof's `Y S`, `Bᵀ S`, `g`, `g_v` and `τ`.
    for i in (0..n).rev() {
        let l = &model.links[i];
        let lk = dd.links[i];
        for j in l.v_index..l.v_index + l.joint.nv() {
            let d = &mut dd.dofs[j];
            let s = d.s;
            d.ys = lk.y.mul_twist(&s);
            // `B_laᵀ = 2 [b_l]×`.
            d.bts = lk.baa.tr_mul(&angular(&s)) + lk.bl.cross(&linear(&s)) * 2.0;
            d.g = cross_force(&s, &lk.f) + lk.y.mul_twist(&d.da) + b_mul(&lk.baa, &lk.bl, &d.dv);
            d.gv = lk.y.mul_twist(&d.dav) + b_mul(&lk.baa, &lk.bl, &s);
            dd.tau[j] = s.dot(&lk.f);
            for m in 0..6 {
                dd.columns[(6 + m) * nvt + j] = d.ys[m];
            }
            for m in 0..3 {
                dd.columns[(12 + m) * nvt + j] = d.bts[m];
            }
            if ROWS {
                // By rows, the other dof of each pair is the one that varies along a row.
                for m in 0..6 {
                    dd.columns[(15 + m) * nvt + j] = d.g[m];
                    dd.columns[(21 + m) * nvt + j] = d.gv[m];
                    dd.columns[(27 + m) * nvt + j] = d.da[m];
                    dd.columns[(33 + m) * nvt + j] = d.dav[m];
                }
                for m in 0..3 {
                    dd.columns[(39 + m) * nvt + j] = d.dv[m];
                }
            }
        }
        if let Some(pa) = l.parent {
            let parent = &mut dd.links[pa];
            parent.y.add(&lk.y);
            parent.baa += lk.baa;
            parent.bl += lk.bl;
            parent.f += lk.f;
            dd.subtree_count[pa] += dd.subtree_count[i];
            dd.subtree_end[pa] = dd.subtree_end[pa].max(dd.subtree_end[i]);
        }
    }
}

/// `∂τ/∂q`, `∂τ/∂v` and `M` from the dofs' vectors, column by column: in column `c`, the
/// rows upstream of `c` are `S_rᵀ g_c` (and `S_rᵀ g_v,c`, `S_rᵀ Y S_c`), the rows `c` moves
/// are `(Y S_r)ᵀ dA_c + (Bᵀ S_r)ᵀ dV_c` (and the `v` and `M` counterparts), the rows of
/// neither are zero. Upstream rows that are `0..` (a chain) and moved rows that are one range
/// (children numbered after their parent, subtree by subtree) are written by loops over
/// contiguous memory, vectorised; other trees walk the upstream path and, for the moved
/// rows, write row by row. `M` is exactly symmetric: both triangles take the same products
/// in the same order.
#[inline(always)]
fn fill_matrices(model: &Model, dd: &mut DerivativeData) {
    let nvt = model.nv;
    let links = &model.links;
    let related_everywhere = links
        .iter()
        .enumerate()
        .all(|(i, l)| l.joint.nv() == 0 || dd.above_count[i] + dd.subtree_count[i] == nvt);
    let preorder = links
        .iter()
        .enumerate()
        .all(|(i, l)| dd.subtree_count[i] == dd.subtree_end[i] - l.v_index);
    if !related_everywhere {
        dd.dtau_dq.as_mut_slice().fill(0.0);
        dd.dtau_dv.as_mut_slice().fill(0.0);
        dd.mass.as_mut_slice().fill(0.0);
    }
    let (dq, dv, mm) = (
        dd.dtau_dq.as_mut_slice(),
        dd.dtau_dv.as_mut_slice(),
        dd.mass.as_mut_slice(),
    );
    let dofs = &dd.dofs;
    // The structure-of-arrays rows `S`, `Y S`, `Bᵀ S`, sliced once here rather than for every
    // column (their set-up cost more than chain7's short row loops).
    let soa: [&[f64]; 15] = std::array::from_fn(|m| &dd.columns[m * nvt..(m + 1) * nvt]);
    for (i, l) in links.iter().enumerate() {
        let r = l.v_index..l.v_index + l.joint.nv();
        let chain = l.joint.chained_columns();
        // The joint's own block.
        for j in r.clone() {
            let dj = &dofs[j];
            for k in r.clone() {
                let dk = &dofs[k];
                let at = k * nvt + j;
                dq[at] = if chain && k > j {
                    dj.s.dot(&dk.g)
                } else {
                    moved_q(dj, dk)
                };
                dv[at] = moved_v(dj, dk);
                if k >= j {
                    let m = dot6(&dj.s, &dk.ys);
                    mm[at] = m;
                    mm[j * nvt + k] = m;
                }
            }
        }
        let contiguous_above = dd.above_count[i] == l.v_index;
        let moved = r.end..dd.subtree_end[i];
        for c in r.clone() {
            let dc = &dofs[c];
            let col = c * nvt;
            // Upstream rows.
            if contiguous_above {
                upstream_rows(&soa, dc, 0..l.v_index, col, (dq, dv, mm));
            } else {
                let mut k = dd.dof_parent[l.v_index];
                while k != NO_DOF {
                    let dk = &dofs[k];
                    dq[col + k] = dk.s.dot(&dc.g);
                    dv[col + k] = dk.s.dot(&dc.gv);
                    mm[col + k] = dot6(&dk.s, &dc.ys);
                    k = dd.dof_parent[k];
                }
            }
            if preorder {
                moved_rows(&soa, dc, moved.clone(), col, (dq, dv, mm));
            }
        }
    }
    if !preorder {
        // Moved rows one by one: row `j`, the dofs `k` upstream of it.
        for l in links {
            for j in l.v_index..l.v_index + l.joint.nv() {
                let dj = &dofs[j];
                let mut k = dd.dof_parent[l.v_index];
                while k != NO_DOF {
                    let dk = &dofs[k];
                    let at = k * nvt + j;
                    dq[at] = moved_q(dj, dk);
                    dv[at] = moved_v(dj, dk);
                    mm[at] = dot6(&dk.s, &dj.ys);
                    k = dd.dof_parent[k];
                }
            }
        }
    }
}

/// `k` moves `j`: `(Y S_j)ᵀ dA_k + (Bᵀ S_j)ᵀ dV_k`.
#[inline(always)]
pub(crate) fn moved_q(dj: &DofWork, dk: &DofWork) -> f64 {
    dj.ys.dot(&dk.da) + dj.bts.dot(&angular(&dk.dv))
}

/// The same for `∂τ/∂v`: `(Y S_j)ᵀ dAv_k + (Bᵀ S_j)ᵀ S_k`.
#[inline(always)]
pub(crate) fn moved_v(dj: &DofWork, dk: &DofWork) -> f64 {
    dj.ys.dot(&dk.dav) + dj.bts.dot(&angular(&dk.s))
}

/// `aᵀ b` summed in index order (the order [`upstream_rows`] and [`moved_rows`] use, so that
/// both triangles of `M` round alike).
#[inline(always)]
pub(crate) fn dot6(a: &Vec6, b: &Vec6) -> f64 {
    let mut x = a[0] * b[0];
    for m in 1..6 {
        x += a[m] * b[m];
    }
    x
}

/// Column `c` (from `col`), rows `rows` upstream of it: `S_rᵀ g_c`, `S_rᵀ g_v,c`, `S_rᵀ Y S_c`.
#[inline(always)]
fn upstream_rows(
    soa: &[&[f64]; 15],
    dc: &DofWork,
    rows: std::ops::Range<usize>,
    col: usize,
    (dq, dv, mm): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let len = rows.len();
    if len == 0 {
        return;
    }
    let s: [&[f64]; 6] = std::array::from_fn(|m| &soa[m][rows.clone()]);
    let (dq, dv, mm) = (
        &mut dq[col + rows.start..][..len],
        &mut dv[col + rows.start..][..len],
        &mut mm[col + rows.start..][..len],
    );
    let (g, gv, ys) = (dc.g, dc.gv, dc.ys);
    for r in 0..len {
        let (mut x, mut y, mut z) = (s[0][r] * g[0], s[0][r] * gv[0], s[0][r] * ys[0]);
        for m in 1..6 {
            x += s[m][r] * g[m];
            y += s[m][r] * gv[m];
            z += s[m][r] * ys[m];
        }
        dq[r] = x;
        dv[r] = y;
        mm[r] = z;
    }
}

/// Column `c` (from `col`), rows `rows` that `c` moves: `(Y S_r)ᵀ dA_c + (Bᵀ S_r)ᵀ dV_c`,
/// `(Y S_r)ᵀ dAv_c + (Bᵀ S_r)ᵀ S_c`, `S_cᵀ Y S_r`.
#[inline(always)]
fn moved_rows(
    soa: &[&[f64]; 15],
    dc: &DofWork,
    rows: std::ops::Range<usize>,
    col: usize,
    (dq, dv, mm): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let len = rows.len();
    if len == 0 {
        return;
    }
    let ys: [&[f64]; 6] = std::array::from_fn(|m| &soa[6 + m][rows.clone()]);
    let bts: [&[f64]; 3] = std::array::from_fn(|m| &soa[12 + m][rows.clone()]);
    let (dq, dv, mm) = (
        &mut dq[col + rows.start..][..len],
        &mut dv[col + rows.start..][..len],
        &mut mm[col + rows.start..][..len],
    );
    let (da, dav, s, dvc) = (dc.da, dc.dav, dc.s, dc.dv);
    for r in 0..len {
        let (mut x, mut y, mut z) = (ys[0][r] * da[0], ys[0][r] * dav[0], s[0] * ys[0][r]);
        for m in 1..6 {
            x += ys[m][r] * da[m];
            y += ys[m][r] * dav[m];
            z += s[m] * ys[m][r];
        }
        for m in 0..3 {
            x += bts[m][r] * dvc[m];
            y += bts[m][r] * s[m];
        }
        dq[r] = x;
        dv[r] = y;
        mm[r] = z;
    }
}

/// One link of the outward pass: its velocity and acceleration, its dofs' directions and
/// their `dV`, `dA`, `dAv`, and its wrench and `B` (`data.links` holds the positions).
#[inline(always)]
fn outward_link(
    model: &Model,
    data: &mut Data,
    dd: &mut DerivativeData,
    i: usize,
    (v, a): (&[f64], &[f64]),
    base: Vec6,
) {
    let z6 = Vec6::zeros();
    let l = &model.links[i];
    let st = &mut data.links[i];
    st.inertia = l.inertia.rotated_inlined(&st.rotation);
    let st = &*st;
    let p = st.origin;
    let (vp, ap) = match l.parent {
        Some(pi) => (dd.links[pi].v, dd.links[pi].a),
        None => (z6, base),
    };
    let nv = l.joint.nv();
    // The last dof at or above this link, and each dof's upstream neighbour.
    let above = l.parent.map_or(NO_DOF, |p| dd.last_dof[p]);
    for k in 0..nv {
        dd.dof_parent[l.v_index + k] = if k == 0 { above } else { l.v_index + k - 1 };
    }
    dd.last_dof[i] = if nv > 0 { l.v_index + nv - 1 } else { above };
    dd.above_count[i] = l
        .parent
        .map_or(0, |p| dd.above_count[p] + model.links[p].joint.nv());
    dd.subtree_count[i] = nv;
    dd.subtree_end[i] = l.v_index + nv;
    let (vi, ai) = (&v[l.v_index..l.v_index + nv], &a[l.v_index..l.v_index + nv]);
    // ZYZ: three revolutes in a chain, each column fixed in the frame of the angles
    // before it; every other joint's columns are fixed in the parent (one column) or in
    // the body (the quaternion joints), and all of them move together.
    // One column is a chain of one: `v⁻ × (S v̇)` is `dV v̇` and `(v⁻ + v) × S` is `2 dV`
    // (`S × S = 0`), so the chain's update saves two cross products.
    let chain = l.joint.chained_columns() || nv == 1;
    let (mut vc, mut ac) = (vp, ap);
    let (mut vd, mut ad) = (z6, z6);
    for k in 0..nv {
        let sk = st.s[k];
        let sa = angular(&sk);
        let s = stack(&sa, &(linear(&sk) + p.cross(&sa)));
        let d = &mut dd.dofs[l.v_index + k];
        d.s = s;
        for m in 0..6 {
            dd.columns[m * model.nv + l.v_index + k] = s[m];
        }
        d.dv = cross_motion(&vc, &s);
        d.da = cross_motion(&ac, &s) + cross_motion(&vc, &d.dv);
        if chain {
            d.dav = d.dv * 2.0;
            ac += s * ai[k] + d.dv * vi[k];
            vc += s * vi[k];
        } else {
            vd += s * vi[k];
            ad += s * ai[k];
        }
    }
    if !chain {
        vc = vp + vd;
        ac = ap + ad + cross_motion(&vp, &vd);
        let vsum = vp + vc;
        for d in &mut dd.dofs[l.v_index..l.v_index + nv] {
            d.dav = cross_motion(&vsum, &d.s);
        }
    }
    let y = about_origin(&st.inertia, &p);
    let yv = y.mul_twist(&vc);
    let w = angular(&vc);
    let u = linear(&vc);
    let iw = y.rotational * w;
    let h = &y.first_moment;
    // `[w]× R − R [w]× = A + Aᵀ` with `A = [w]× R` (`R` symmetric), its columns `w × R_c`;
    // `[h]× [u]× = u hᵀ − (h · u) I`: no 3 × 3 products.
    let r = &y.rotational;
    let swr = Mat3::from_columns(&[
        w.cross(&r.column(0).into_owned()),
        w.cross(&r.column(1).into_owned()),
        w.cross(&r.column(2).into_owned()),
    ]);
    // `A + Aᵀ − [Iw]× − 2 u hᵀ + 2 (h · u) I` entry by entry: no additions of zeros.
    let (u2, hu2) = (u * 2.0, 2.0 * h.dot(&u));
    let mut baa = Mat3::zeros();
    for a in 0..3 {
        baa[(a, a)] = swr[(a, a)] * 2.0 - u2[a] * h[a] + hu2;
        for b in a + 1..3 {
            let sym = swr[(a, b)] + swr[(b, a)];
            // `[Iw]×`'s entry (a, b) is `−Iw_c` for (a, b, c) in cyclic order.
            let c = 3 - a - b;
            let k = if (b + 3 - a) % 3 == 1 { -iw[c] } else { iw[c] };
            baa[(a, b)] = sym - k - u2[a] * h[b];
            baa[(b, a)] = sym + k - u2[b] * h[a];
        }
    }
    let lk = &mut dd.links[i];
    lk.v = vc;
    lk.a = ac;
    lk.f = y.mul_twist(&ac) + cross_force(&vc, &yv);
    lk.baa = baa;
    lk.bl = u * y.mass - y.first_moment.cross(&w);
    lk.y = y;
}

/// `y` (about the body's origin `p`) about the world origin: `BodyInertia::shifted(p)`
/// on the upper triangle only (the rotational part is symmetric), without its products by
/// the identity's zeros.
#[inline(always)]
fn about_origin(y: &BodyInertia, s: &Vec3) -> BodyInertia {
    let (h, m) = (&y.first_moment, y.mass);
    let diag = 2.0 * h.dot(s) + s.norm_squared() * m;
    let mut rot = y.rotational;
    for a in 0..3 {
        rot[(a, a)] += diag;
        for b in a..3 {
            let x = rot[(a, b)] - (h[a] * s[b] + s[a] * h[b]) - s[a] * s[b] * m;
            rot[(a, b)] = x;
            rot[(b, a)] = x;
        }
    }
    BodyInertia {
        mass: m,
        first_moment: h + s * m,
        rotational: rot,
    }
}
