//! The inverse-dynamics derivatives' matrices filled by rows (`DerivativeData::row_major`):
//! the same entries and the same products as
//! [`super::rnea_derivatives`]'s column fill, stored transposed, so that a C-ordered copy
//! (NumPy's) is a plain copy instead of a transpose, which on a 300-link chain cost more than
//! the fill itself.
//!
//! For a dof `u` upstream of a dof `d`, row `u` holds `(u, d) = S_uᵀ g_d` (and `S_uᵀ g_v,d`,
//! `S_uᵀ Y S_d`) and row `d` holds `(d, u) = (Y S_d)ᵀ dA_u + (Bᵀ S_d)ᵀ dV_u` (and the `v`
//! and `M` counterparts). Along a row the fixed vectors are the row's, the varying ones the
//! columns' (the structure-of-arrays rows 15.. of `DerivativeData::columns`): the downstream
//! columns are one range when the dofs are numbered subtree by subtree, the upstream ones when
//! the path above is `0..` (a chain), and both are then filled by vectorised loops.
use super::rnea_derivatives::{dot6, moved_q, moved_v, NO_DOF};
use super::workspace::{DerivativeData, DofWork, SOA_ROWS};
use crate::model::Model;

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
    fill_rows_into(
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
    (dq, dv, mm): (&mut [f64], &mut [f64], &mut [f64]),
) {
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
        dq.fill(0.0);
        dv.fill(0.0);
        mm.fill(0.0);
    }
    let dofs = &dd.dofs;
    // The structure-of-arrays rows sliced once a call: sliced for every row instead (twice
    // 21 sub-slices with their bounds checks), they cost ~740 instructions a row on chain100.
    let cols: [&[f64]; SOA_ROWS] = std::array::from_fn(|m| &dd.columns[m * nvt..(m + 1) * nvt]);
    for (i, l) in links.iter().enumerate() {
        let r = l.v_index..l.v_index + l.joint.nv();
        let chain = l.joint.chained_columns();
        // The joint's own block: entry (j, k) at j · nv + k.
        for j in r.clone() {
            let dj = &dofs[j];
            for k in r.clone() {
                let dk = &dofs[k];
                let at = j * nvt + k;
                dq[at] = if chain && k > j {
                    dj.s.dot(&dk.g)
                } else {
                    moved_q(dj, dk)
                };
                dv[at] = moved_v(dj, dk);
                if k >= j {
                    let m = dot6(&dj.s, &dk.ys);
                    mm[at] = m;
                    mm[k * nvt + j] = m;
                }
            }
        }
        let contiguous_above = dd.above_count[i] == l.v_index;
        let moved = r.end..dd.subtree_end[i];
        for j in r.clone() {
            let dj = &dofs[j];
            let row = j * nvt;
            // Upstream columns: `j` is moved by them.
            if contiguous_above {
                upstream_columns(&cols, dj, 0..l.v_index, row, (dq, dv, mm));
            } else {
                let mut k = dd.dof_parent[l.v_index];
                while k != NO_DOF {
                    let dk = &dofs[k];
                    dq[row + k] = moved_q(dj, dk);
                    dv[row + k] = moved_v(dj, dk);
                    mm[row + k] = dot6(&dk.s, &dj.ys);
                    k = dd.dof_parent[k];
                }
            }
            if preorder {
                downstream_columns(&cols, dj, moved.clone(), row, (dq, dv, mm));
            }
        }
    }
    if !preorder {
        // Downstream columns one by one: column `j`, the dofs `k` upstream of it.
        for l in links {
            for j in l.v_index..l.v_index + l.joint.nv() {
                let dj = &dofs[j];
                let mut k = dd.dof_parent[l.v_index];
                while k != NO_DOF {
                    let dk = &dofs[k];
                    let at = k * nvt + j;
                    dq[at] = dk.s.dot(&dj.g);
                    dv[at] = dk.s.dot(&dj.gv);
                    mm[at] = dot6(&dk.s, &dj.ys);
                    k = dd.dof_parent[k];
                }
            }
        }
    }
}

/// Row `j` (from `row`), the columns `c` upstream of it: `(Y S_j)ᵀ dA_c + (Bᵀ S_j)ᵀ dV_c`,
/// `(Y S_j)ᵀ dAv_c + (Bᵀ S_j)ᵀ S_c`, `S_cᵀ Y S_j`.
#[inline(always)]
fn upstream_columns(
    cols: &[&[f64]; SOA_ROWS],
    dj: &DofWork,
    c: std::ops::Range<usize>,
    row: usize,
    (dq, dv, mm): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let len = c.len();
    let soa = |first: usize, m: usize| &cols[first + m][c.clone()];
    let (s, da, dav) = (
        rows6(|m| soa(0, m)),
        rows6(|m| soa(27, m)),
        rows6(|m| soa(33, m)),
    );
    let dvc = [soa(39, 0), soa(39, 1), soa(39, 2)];
    let (dq, dv, mm) = (
        &mut dq[row + c.start..][..len],
        &mut dv[row + c.start..][..len],
        &mut mm[row + c.start..][..len],
    );
    let (ys, bts) = (dj.ys, dj.bts);
    for r in 0..len {
        let (mut x, mut y, mut z) = (ys[0] * da[0][r], ys[0] * dav[0][r], s[0][r] * ys[0]);
        for m in 1..6 {
            x += ys[m] * da[m][r];
            y += ys[m] * dav[m][r];
            z += s[m][r] * ys[m];
        }
        for m in 0..3 {
            x += bts[m] * dvc[m][r];
            y += bts[m] * s[m][r];
        }
        dq[r] = x;
        dv[r] = y;
        mm[r] = z;
    }
}

/// Row `j` (from `row`), the columns `c` it is upstream of: `S_jᵀ g_c`, `S_jᵀ g_v,c`,
/// `S_jᵀ Y S_c`.
#[inline(always)]
fn downstream_columns(
    cols: &[&[f64]; SOA_ROWS],
    dj: &DofWork,
    c: std::ops::Range<usize>,
    row: usize,
    (dq, dv, mm): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let len = c.len();
    let soa = |first: usize, m: usize| &cols[first + m][c.clone()];
    let (ys, g, gv) = (
        rows6(|m| soa(6, m)),
        rows6(|m| soa(15, m)),
        rows6(|m| soa(21, m)),
    );
    let (dq, dv, mm) = (
        &mut dq[row + c.start..][..len],
        &mut dv[row + c.start..][..len],
        &mut mm[row + c.start..][..len],
    );
    let s = dj.s;
    for r in 0..len {
        let (mut x, mut y, mut z) = (s[0] * g[0][r], s[0] * gv[0][r], s[0] * ys[0][r]);
        for m in 1..6 {
            x += s[m] * g[m][r];
            y += s[m] * gv[m][r];
            z += s[m] * ys[m][r];
        }
        dq[r] = x;
        dv[r] = y;
        mm[r] = z;
    }
}

/// Six structure-of-arrays rows. Not `std::array::from_fn`: where that was not inlined (the
/// by-rows copy), the rows' lengths were unknown in the loops, whose bounds checks then kept
/// them scalar (chain100: 1.38M instructions a call, 3.4 times the column fill's).
#[inline(always)]
fn rows6<'a>(f: impl Fn(usize) -> &'a [f64]) -> [&'a [f64]; 6] {
    [f(0), f(1), f(2), f(3), f(4), f(5)]
}

/// Whether every entry [`fill_rows`] writes from `dd`'s per-dof vectors is surely finite: each
/// is a sum of at most 15 products of those vectors' components, so components below 1e100
/// in magnitude cannot overflow (and NaN fails the comparison). O(nv), where checking the
/// written matrices is O(nv²).
pub fn rows_surely_finite(dd: &DerivativeData) -> bool {
    dd.columns.iter().fold(true, |ok, x| ok & (x.abs() < 1e100))
}
