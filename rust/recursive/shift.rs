//! Carrying quantities across a joint, from the child's origin and axes to the parent's:
//! articulated (or composite) inertias `AᵀMA` with `A = [[1, 0], [−r̃, 1]]`, wrenches
//! `[E n + r × E f; E f]`, and `w × r`. The offset's form ([`OffsetForm`], a model constant)
//! picks the cheapest exact product.
use super::algebra::{cross, sidx, six, LocalInertia, Rot, Sym3};
use crate::support::spatial::{Mat3, Vec3, Vec6};

/// How a link's origin lies from its parent's (in parent axes): picks the shift's form.
/// Always `Anywhere` for a prismatic joint, whose offset moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(u8)]
pub enum OffsetForm {
    /// Coincident origins (common in robot descriptions: intersecting wrist axes).
    Zero,
    AlongX,
    AlongY,
    AlongZ,
    Anywhere,
}

impl OffsetForm {
    /// The form of a fixed offset `t`.
    pub fn of(t: &Vec3) -> OffsetForm {
        match (t.x == 0.0, t.y == 0.0, t.z == 0.0) {
            (true, true, true) => OffsetForm::Zero,
            (false, true, true) => OffsetForm::AlongX,
            (true, false, true) => OffsetForm::AlongY,
            (true, true, false) => OffsetForm::AlongZ,
            _ => OffsetForm::Anywhere,
        }
    }
}

/// `$body` with `$f` bound to `$form`, a constant in each arm when `$fixed` (a compile-time
/// flag): the inlined body is then compiled once per form with its `match form`s folded
/// away, which for the common joint cases keeps values in registers across the shift.
macro_rules! with_form {
    ($fixed:expr, $form:expr, |$f:ident| $body:expr) => {{
        use $crate::recursive::shift::OffsetForm as F;
        if !$fixed {
            #[allow(clippy::redundant_locals)] // the callers' own name, rebound as is
            let $f = $form;
            $body
        } else {
            match $form {
                F::Zero => {
                    let $f = F::Zero;
                    $body
                }
                F::AlongX => {
                    let $f = F::AlongX;
                    $body
                }
                F::AlongY => {
                    let $f = F::AlongY;
                    $body
                }
                F::AlongZ => {
                    let $f = F::AlongZ;
                    $body
                }
                F::Anywhere => {
                    let $f = F::Anywhere;
                    $body
                }
            }
        }
    }};
}
pub(super) use with_form;

/// Shifts articulated-inertia blocks (parent axes, about the child origin) to the parent
/// origin, which sits at `−r` from the child origin: `AᵀMA` with `A = [[1, 0], [K, 1]]`,
/// `K = −r̃` (`[[P + QK + (QK)ᵀ − KRK, Q − KR], [·, R]]`), and deposits the result in `out`
/// (see [`deposit`], which `PICK` steers). `ZR < 3`: row and column `ZR` of `p` and row `ZR`
/// of `q` are zero (and not read). `form` picks the product: coincident origins need no
/// shift, and an offset along one coordinate axis makes `K` two entries (a third of the
/// products).
#[inline(always)]
pub(super) fn shift_add<const ZR: usize, const PICK: bool>(
    p: &Sym3,
    q: &Mat3,
    rr: &Sym3,
    r: &Vec3,
    form: OffsetForm,
    start: Option<&LocalInertia>,
    out: &mut LocalInertia,
) {
    match form {
        OffsetForm::Zero => deposit::<PICK>(out, start, p, q, rr),
        OffsetForm::AlongX => shift_on_axis::<ZR, PICK, 0, 1, 2>(p, q, rr, r.x, start, out),
        OffsetForm::AlongY => shift_on_axis::<ZR, PICK, 1, 2, 0>(p, q, rr, r.y, start, out),
        OffsetForm::AlongZ => shift_on_axis::<ZR, PICK, 2, 0, 1>(p, q, rr, r.z, start, out),
        OffsetForm::Anywhere => shift_general::<ZR, PICK>(p, q, rr, r, start, out),
    }
}

/// `out = start + (P, Q, R)` when this child writes first, else `out += (P, Q, R)`. `PICK`
/// (the ABA): the base is picked as a whole rather than by a branch around the sums, so that
/// (P, Q, R) are not stored to memory first; for the GIM's composite inertias the branch
/// measured cheaper.
#[inline(always)]
fn deposit<const PICK: bool>(
    out: &mut LocalInertia,
    start: Option<&LocalInertia>,
    p: &Sym3,
    q: &Mat3,
    r: &Sym3,
) {
    if PICK {
        let base = *start.unwrap_or(out);
        for k in 0..6 {
            out.p.0[k] = base.p.0[k] + p.0[k];
            out.r.0[k] = base.r.0[k] + r.0[k];
        }
        out.q = base.q + q;
        return;
    }
    match start {
        Some(s) => {
            for k in 0..6 {
                out.p.0[k] = s.p.0[k] + p.0[k];
                out.r.0[k] = s.r.0[k] + r.0[k];
            }
            out.q = s.q + q;
        }
        None => {
            for k in 0..6 {
                out.p.0[k] += p.0[k];
                out.r.0[k] += r.0[k];
            }
            out.q += q;
        }
    }
}

/// [`shift_add`] for an offset `t e_A` ((A, B, C) cyclic): `K` has only `K_BC = t`,
/// `K_CB = −t`, so `QK` has two columns, `KR` two rows and `KRK` the (B, C) block
/// `−t² [[R_CC, −R_BC], [−R_BC, R_BB]]`.
#[inline(always)]
fn shift_on_axis<
    const ZR: usize,
    const PICK: bool,
    const A: usize,
    const B: usize,
    const C: usize,
>(
    p: &Sym3,
    q: &Mat3,
    rr: &Sym3,
    t: f64,
    start: Option<&LocalInertia>,
    out: &mut LocalInertia,
) {
    let tt = t * t;
    // Known zeros (row/column ZR) are `None` and left out at compile time, not added as 0.0.
    let pz = |a: usize, b: usize| (a != ZR && b != ZR).then(|| p.at(a, b));
    let qt = |a: usize, b: usize, k: f64| (a != ZR).then(|| q[(a, b)] * k);
    let mut dp = Sym3::default();
    // (QK)_aC = t Q_aB, (QK)_aB = −t Q_aC, (QK)_aA = 0.
    dp.0[sidx(A, A)] = sum([pz(A, A)]);
    dp.0[sidx(B, B)] = sum([pz(B, B), qt(B, C, -2.0 * t), Some(tt * rr.at(C, C))]);
    dp.0[sidx(C, C)] = sum([pz(C, C), qt(C, B, 2.0 * t), Some(tt * rr.at(B, B))]);
    dp.0[sidx(B, C)] = sum([
        pz(B, C),
        qt(B, B, t),
        qt(C, C, -t),
        Some(-(tt * rr.at(B, C))),
    ]);
    dp.0[sidx(A, B)] = sum([pz(A, B), qt(A, C, -t)]);
    dp.0[sidx(A, C)] = sum([pz(A, C), qt(A, B, t)]);
    // Q − KR: row B − t R_C·, row C + t R_B·.
    let mut dq = Mat3::zeros();
    for col in 0..3 {
        dq[(A, col)] = sum([qt(A, col, 1.0)]);
        dq[(B, col)] = sum([qt(B, col, 1.0), Some(-(t * rr.at(C, col)))]);
        dq[(C, col)] = sum([qt(C, col, 1.0), Some(t * rr.at(B, col))]);
    }
    deposit::<PICK>(out, start, &dp, &dq, rr);
}

/// The sum, left to right, of the terms that are not known zeros (`None`); 0 if none is left.
#[inline(always)]
fn sum<const N: usize>(terms: [Option<f64>; N]) -> f64 {
    let mut acc: Option<f64> = None;
    #[allow(clippy::needless_range_loop)] // an index loop unrolls; `into_iter().flatten()` did not
    for k in 0..N {
        if let Some(x) = terms[k] {
            acc = Some(match acc {
                Some(a) => a + x,
                None => x,
            });
        }
    }
    acc.unwrap_or(0.0)
}

/// [`shift_add`] for an offset anywhere.
#[inline(always)]
fn shift_general<const ZR: usize, const PICK: bool>(
    p: &Sym3,
    q: &Mat3,
    rr: &Sym3,
    r: &Vec3,
    start: Option<&LocalInertia>,
    out: &mut LocalInertia,
) {
    // K = skew(−r) = [[0, z, −y], [−z, 0, x], [y, −x, 0]].
    let (x, y, z) = (r.x, r.y, r.z);
    let mut qk = Mat3::zeros();
    let mut kr = Mat3::zeros();
    for a in 0..3 {
        if a != ZR {
            qk[(a, 0)] = -q[(a, 1)] * z + q[(a, 2)] * y;
            qk[(a, 1)] = q[(a, 0)] * z - q[(a, 2)] * x;
            qk[(a, 2)] = -q[(a, 0)] * y + q[(a, 1)] * x;
        }
        kr[(0, a)] = z * rr.at(1, a) - y * rr.at(2, a);
        kr[(1, a)] = -z * rr.at(0, a) + x * rr.at(2, a);
        kr[(2, a)] = y * rr.at(0, a) - x * rr.at(1, a);
    }
    // (KR)K, symmetric.
    let krk = |a: usize, b: usize| match b {
        0 => -kr[(a, 1)] * z + kr[(a, 2)] * y,
        1 => kr[(a, 0)] * z - kr[(a, 2)] * x,
        _ => -kr[(a, 0)] * y + kr[(a, 1)] * x,
    };
    let mut dp = Sym3::default();
    for (k, (a, b)) in [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
        .into_iter()
        .enumerate()
    {
        dp.0[k] = if a == ZR && b == ZR {
            -krk(a, b)
        } else if a == ZR {
            qk[(b, a)] - krk(a, b)
        } else if b == ZR {
            qk[(a, b)] - krk(a, b)
        } else {
            p.0[k] + qk[(a, b)] + qk[(b, a)] - krk(a, b)
        };
    }
    let mut dq = Mat3::zeros();
    for b in 0..3 {
        for a in 0..3 {
            dq[(a, b)] = if a == ZR {
                -kr[(a, b)]
            } else {
                q[(a, b)] - kr[(a, b)]
            };
        }
    }
    deposit::<PICK>(out, start, &dp, &dq, rr);
}

/// A wrench `[n; f]` about the child origin in child axes, as seen at the parent origin in
/// parent axes: `[E n + r × E f; E f]` (`form`: the offset's).
#[inline(always)]
pub(super) fn to_parent<R: Rot>(e: R, r: &Vec3, form: OffsetForm, n: &Vec3, f: &Vec3) -> Vec6 {
    let n = e.mul(n);
    let f = e.mul(f);
    six(&(n - cross_offset(&f, r, form)), &f)
}

/// `w × r` for an offset `r` of the given form: along one axis it takes two products instead of six.
/// The values are `cross(w, r)`'s (only the signs of exact zeros may differ).
#[inline(always)]
pub(super) fn cross_offset(w: &Vec3, r: &Vec3, form: OffsetForm) -> Vec3 {
    match form {
        OffsetForm::Zero => Vec3::zeros(),
        OffsetForm::AlongX => Vec3::new(0.0, w.z * r.x, -(w.y * r.x)),
        OffsetForm::AlongY => Vec3::new(-(w.z * r.y), 0.0, w.x * r.y),
        OffsetForm::AlongZ => Vec3::new(w.y * r.z, -(w.x * r.z), 0.0),
        OffsetForm::Anywhere => cross(w, r),
    }
}
