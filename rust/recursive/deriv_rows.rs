//! The inverse-dynamics derivatives' matrices from the dofs' vectors
//! ([`super::rnea_derivatives`]), stored by columns or by rows (`DerivativeData::row_major`):
//! one fill for both, the entries taking the same products in the same order, so that a
//! C-ordered copy (NumPy's) of the transposed storage is a plain copy instead of a transpose,
//! which on a 300-link chain cost more than the fill itself.
//!
//! For a dof `u` upstream of a dof `d`, entry `(u, d) = S_uᵀ g_d` (and `S_uᵀ g_v,d`,
//! `S_uᵀ Y S_d`) and entry `(d, u) = (Y S_d)ᵀ dA_u + (Bᵀ S_d)ᵀ dV_u` (and the `v` and `M`
//! counterparts). Each dof `x` in turn fills the entries that lie along its line in memory
//! (its column, or its row): with the dofs above it where those are `0..` (a chain), with the
//! dofs below where they are one range (numbered subtree by subtree), by vectorised loops over
//! the structure-of-arrays rows of `DerivativeData::columns`, the varying partner's; the
//! other trees walk the path upstream.
use super::rnea_derivatives::NO_DOF;
use super::workspace::{DerivativeData, DofWork};
use crate::model::Model;
use crate::support::spatial::{angular, Vec6};

/// `∂τ/∂q`, `∂τ/∂v` and `M` by rows into `dd.dtau_dq`, `dd.dtau_dv`, `dd.mass` (the
/// transposes of what the column fill gives; `M` bit for bit the same and symmetric).
#[inline(always)]
pub(crate) fn fill_rows(model: &Model, dd: &mut DerivativeData) {
    // Taken out for the fill (an empty matrix does not allocate) and put back.
    let take =
        |m: &mut nalgebra::DMatrix<f64>| std::mem::replace(m, nalgebra::DMatrix::zeros(0, 0));
    let (mut dq, mut dv, mut mm) = (
        take(&mut dd.dtau_dq),
        take(&mut dd.dtau_dv),
        take(&mut dd.mass),
    );
    fill::<true>(
        model,
        dd,
        (dq.as_mut_slice(), dv.as_mut_slice(), mm.as_mut_slice()),
    );
    (dd.dtau_dq, dd.dtau_dv, dd.mass) = (dq, dv, mm);
}

/// [`fill_rows`] into the caller's C-ordered nv × nv buffers.
#[inline(always)]
pub(crate) fn fill_rows_into(
    model: &Model,
    dd: &DerivativeData,
    out: (&mut [f64], &mut [f64], &mut [f64]),
) {
    fill::<true>(model, dd, out);
}

/// The same by columns into `dd`'s own matrices.
#[inline(always)]
pub(crate) fn fill_columns(model: &Model, dd: &mut DerivativeData) {
    let take =
        |m: &mut nalgebra::DMatrix<f64>| std::mem::replace(m, nalgebra::DMatrix::zeros(0, 0));
    let (mut dq, mut dv, mut mm) = (
        take(&mut dd.dtau_dq),
        take(&mut dd.dtau_dv),
        take(&mut dd.mass),
    );
    fill::<false>(
        model,
        dd,
        (dq.as_mut_slice(), dv.as_mut_slice(), mm.as_mut_slice()),
    );
    (dd.dtau_dq, dd.dtau_dv, dd.mass) = (dq, dv, mm);
}

type Out<'a> = (&'a mut [f64], &'a mut [f64], &'a mut [f64]);

/// Where entry `(r, c)` is stored.
#[inline(always)]
fn at<const ROWS: bool>(nvt: usize, r: usize, c: usize) -> usize {
    if ROWS {
        r * nvt + c
    } else {
        c * nvt + r
    }
}

/// Entry `(u, d)` at `at`, `u` upstream of `d`: `S_uᵀ g_d`, `S_uᵀ g_v,d`, `S_uᵀ Y S_d`.
#[inline(always)]
fn upstream(o: &mut Out, at: usize, u: &DofWork, d: &DofWork) {
    o.0[at] = u.s.dot(&d.g);
    o.1[at] = u.s.dot(&d.gv);
    o.2[at] = dot6(&u.s, &d.ys);
}

/// Entry `(d, u)` at `at`, `u` upstream of `d` (it moves `d`).
#[inline(always)]
fn moved(o: &mut Out, at: usize, d: &DofWork, u: &DofWork) {
    o.0[at] = moved_q(d, u);
    o.1[at] = moved_v(d, u);
    o.2[at] = dot6(&u.s, &d.ys);
}

#[inline(always)]
fn fill<const ROWS: bool>(model: &Model, dd: &DerivativeData, mut o: Out) {
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
        o.0.fill(0.0);
        o.1.fill(0.0);
        o.2.fill(0.0);
    }
    let (dofs, cols) = (&dd.dofs, &dd.columns);
    for (i, l) in links.iter().enumerate() {
        let r = l.v_index..l.v_index + l.joint.nv();
        let chain = l.joint.chained_columns();
        // The joint's own block, entry (j, k).
        for j in r.clone() {
            let dj = &dofs[j];
            for k in r.clone() {
                let dk = &dofs[k];
                let e = at::<ROWS>(nvt, j, k);
                o.0[e] = if chain && k > j {
                    dj.s.dot(&dk.g)
                } else {
                    moved_q(dj, dk)
                };
                o.1[e] = moved_v(dj, dk);
                if k >= j {
                    let m = dot6(&dj.s, &dk.ys);
                    o.2[e] = m;
                    o.2[at::<ROWS>(nvt, k, j)] = m;
                }
            }
        }
        let contiguous_above = dd.above_count[i] == l.v_index;
        let below = r.end..dd.subtree_end[i];
        for x in r.clone() {
            let dx = &dofs[x];
            let line = x * nvt;
            // Along the line: (k, x) by columns, (x, k) by rows, for the dofs `k` above.
            if contiguous_above {
                line_above::<ROWS>(cols, nvt, dx, 0..l.v_index, line, &mut o);
            } else {
                let mut k = dd.dof_parent[l.v_index];
                while k != NO_DOF {
                    if ROWS {
                        moved(&mut o, line + k, dx, &dofs[k]);
                    } else {
                        upstream(&mut o, line + k, &dofs[k], dx);
                    }
                    k = dd.dof_parent[k];
                }
            }
            if preorder {
                line_below::<ROWS>(cols, nvt, dx, below.clone(), line, &mut o);
            }
        }
    }
    if !preorder {
        // Off the lines, one by one: for dof `j`, the dofs `k` upstream of it.
        for l in links {
            for j in l.v_index..l.v_index + l.joint.nv() {
                let dj = &dofs[j];
                let mut k = dd.dof_parent[l.v_index];
                while k != NO_DOF {
                    if ROWS {
                        upstream(&mut o, k * nvt + j, &dofs[k], dj);
                    } else {
                        moved(&mut o, k * nvt + j, dj, &dofs[k]);
                    }
                    k = dd.dof_parent[k];
                }
            }
        }
    }
}

/// Dof `x`'s line (from `line`), its partners `p` the dofs `ks` above it: by columns
/// (`p`, `x`) `S_pᵀ g_x`, `S_pᵀ g_v,x`, `S_pᵀ Y S_x`; by rows (`x`, `p`) `(Y S_x)ᵀ dA_p + (Bᵀ
/// S_x)ᵀ dV_p`, `(Y S_x)ᵀ dAv_p + (Bᵀ S_x)ᵀ S_p`, `S_pᵀ Y S_x`.
#[inline(always)]
fn line_above<const ROWS: bool>(
    cols: &[f64],
    nvt: usize,
    x: &DofWork,
    ks: std::ops::Range<usize>,
    line: usize,
    o: &mut Out,
) {
    if ROWS {
        let f: [f64; 9] = std::array::from_fn(|m| if m < 6 { x.ys[m] } else { x.bts[m - 6] });
        let (rq, rv) = (
            [27, 28, 29, 30, 31, 32, 39, 40, 41],
            [33, 34, 35, 36, 37, 38, 0, 1, 2],
        );
        let ys: [f64; 6] = x.ys.into();
        dots::<9>(
            cols,
            nvt,
            ks,
            line,
            (f, f, ys),
            (rq, rv, [0, 1, 2, 3, 4, 5]),
            o,
        );
    } else {
        let s6 = [0, 1, 2, 3, 4, 5];
        let (g, gv, ys) = (x.g.into(), x.gv.into(), x.ys.into());
        dots::<6>(cols, nvt, ks, line, (g, gv, ys), (s6, s6, s6), o);
    }
}

/// Dof `x`'s line, its partners `p` the dofs `ks` below it: by columns (`p`, `x`) `(Y
/// S_p)ᵀ dA_x + (Bᵀ S_p)ᵀ dV_x`, `(Y S_p)ᵀ dAv_x + (Bᵀ S_p)ᵀ S_x`, `S_xᵀ Y S_p`; by rows
/// (`x`, `p`) `S_xᵀ g_p`, `S_xᵀ g_v,p`, `S_xᵀ Y S_p`.
#[inline(always)]
fn line_below<const ROWS: bool>(
    cols: &[f64],
    nvt: usize,
    x: &DofWork,
    ks: std::ops::Range<usize>,
    line: usize,
    o: &mut Out,
) {
    let s: [f64; 6] = x.s.into();
    let ys6 = [6, 7, 8, 9, 10, 11];
    if ROWS {
        let (rq, rv) = ([15, 16, 17, 18, 19, 20], [21, 22, 23, 24, 25, 26]);
        dots::<6>(cols, nvt, ks, line, (s, s, s), (rq, rv, ys6), o);
    } else {
        let fq = std::array::from_fn(|m| if m < 6 { x.da[m] } else { x.dv[m - 6] });
        let fv = std::array::from_fn(|m| if m < 6 { x.dav[m] } else { x.s[m - 6] });
        let r9 = [6, 7, 8, 9, 10, 11, 12, 13, 14];
        dots::<9>(cols, nvt, ks, line, (fq, fv, s), (r9, r9, ys6), o);
    }
}

/// `o[line + r] = Σ_t f[t] · cols[rows[t]][r]` (`t` in order) for `r` in `ks`: `T` terms for
/// `∂τ/∂q` and `∂τ/∂v`, six for `M`.
#[allow(clippy::type_complexity)]
#[inline(always)]
fn dots<const T: usize>(
    cols: &[f64],
    nvt: usize,
    ks: std::ops::Range<usize>,
    line: usize,
    (fq, fv, fm): ([f64; T], [f64; T], [f64; 6]),
    (rq, rv, rm): ([usize; T], [usize; T], [usize; 6]),
    o: &mut Out,
) {
    let len = ks.len();
    let soa = |row: usize| &cols[row * nvt + ks.start..][..len];
    let (sq, sv, sm): ([&[f64]; T], [&[f64]; T], [&[f64]; 6]) = (
        std::array::from_fn(|t| soa(rq[t])),
        std::array::from_fn(|t| soa(rv[t])),
        std::array::from_fn(|t| soa(rm[t])),
    );
    let (dq, dv, mm) = (
        &mut o.0[line + ks.start..][..len],
        &mut o.1[line + ks.start..][..len],
        &mut o.2[line + ks.start..][..len],
    );
    for r in 0..len {
        let (mut x, mut y, mut z) = (fq[0] * sq[0][r], fv[0] * sv[0][r], fm[0] * sm[0][r]);
        for t in 1..T {
            x += fq[t] * sq[t][r];
            y += fv[t] * sv[t][r];
        }
        for t in 1..6 {
            z += fm[t] * sm[t][r];
        }
        dq[r] = x;
        dv[r] = y;
        mm[r] = z;
    }
}

/// `k` moves `j`: `(Y S_j)ᵀ dA_k + (Bᵀ S_j)ᵀ dV_k`.
#[inline(always)]
fn moved_q(dj: &DofWork, dk: &DofWork) -> f64 {
    dj.ys.dot(&dk.da) + dj.bts.dot(&angular(&dk.dv))
}

/// The same for `∂τ/∂v`: `(Y S_j)ᵀ dAv_k + (Bᵀ S_j)ᵀ S_k`.
#[inline(always)]
fn moved_v(dj: &DofWork, dk: &DofWork) -> f64 {
    dj.ys.dot(&dk.dav) + dj.bts.dot(&angular(&dk.s))
}

/// `aᵀ b` summed in index order (the order [`dots`] uses, so that both triangles of `M`
/// round alike).
#[inline(always)]
fn dot6(a: &Vec6, b: &Vec6) -> f64 {
    let mut x = a[0] * b[0];
    for m in 1..6 {
        x += a[m] * b[m];
    }
    x
}

/// Whether every entry [`fill_rows`] writes from `dd`'s per-dof vectors is surely finite: each
/// is a sum of at most 15 products of those vectors' components, so components below 1e100
/// in magnitude cannot overflow (and NaN fails the comparison). O(nv), where checking the
/// written matrices is O(nv²).
pub fn rows_surely_finite(dd: &DerivativeData) -> bool {
    dd.columns.iter().fold(true, |ok, x| ok & (x.abs() < 1e100))
}
