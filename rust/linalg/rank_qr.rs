//! The loop solver's rank-revealing QR of `Jᵀ` (and its QR of `L⁻¹ J_Bᵀ`): dense with column
//! pivoting ([`PivotedQr`]) for small mechanisms, or banded in the caller's order
//! ([`EnvelopeQr`]) for long ones with sparse Jacobians; chosen once per model.
use nalgebra::DMatrix;

use super::envelope_qr::EnvelopeQr;
use super::pivoted_qr::PivotedQr;

pub enum RankQr {
    Dense(PivotedQr),
    Envelope(EnvelopeQr),
}

impl RankQr {
    pub fn new(rows: usize, max_cols: usize, envelope: bool) -> Self {
        if envelope {
            RankQr::Envelope(EnvelopeQr::new(rows, max_cols))
        } else {
            RankQr::Dense(PivotedQr::new(rows, max_cols))
        }
    }

    /// The buffer the caller fills before [`RankQr::factor`].
    pub fn a_mut(&mut self) -> &mut DMatrix<f64> {
        match self {
            RankQr::Dense(q) => &mut q.a,
            RankQr::Envelope(q) => &mut q.a,
        }
    }

    /// `perm()[k]`: the input column of `R`'s column k.
    pub fn perm(&self) -> &[usize] {
        match self {
            RankQr::Dense(q) => &q.perm,
            RankQr::Envelope(q) => &q.perm,
        }
    }

    /// Column `j` of the buffer is zero outside rows `lo..hi` (the banded form's envelope;
    /// set for each column before [`RankQr::factor`]).
    pub fn set_envelope(&mut self, j: usize, lo: usize, hi: usize) {
        if let RankQr::Envelope(q) = self {
            q.set_envelope(j, lo, hi);
        }
    }

    pub fn rank(&self) -> usize {
        match self {
            RankQr::Dense(q) => q.rank,
            RankQr::Envelope(q) => q.rank,
        }
    }

    /// Factors the first `cols` columns: with `pivot` rank-revealing at the tolerance
    /// `max(rel_tol · largest column norm, abs_tol)` (the dense form by column pivoting, the
    /// banded one by setting aside the columns that fall to it); without, in order, every
    /// nonzero column kept. Returns the rank.
    pub fn factor(&mut self, cols: usize, pivot: bool, rel_tol: f64, abs_tol: f64) -> usize {
        match self {
            RankQr::Dense(q) => q.factor(cols, pivot, rel_tol, abs_tol),
            RankQr::Envelope(q) if pivot => q.factor(cols, rel_tol, abs_tol),
            RankQr::Envelope(q) => q.factor(cols, 0.0, 0.0),
        }
    }

    /// `min |R_kk| / max |R_kk|` over the kept columns (1 with none): small when the kept
    /// rows are close to dependent, as near a singular position (`σ_min ≤ min |R_kk|`, and
    /// with pivoting the two are close).
    pub fn pivot_ratio(&self) -> f64 {
        match self {
            RankQr::Dense(q) => q.pivot_ratio(),
            RankQr::Envelope(q) => q.pivot_ratio(),
        }
    }

    /// `Σ ln |R_kk|` over the kept columns: the log of their volume (the product of their
    /// singular values), which falls like `|t − t*|^k` as a motion nears a position where
    /// `k` of them become dependent at once (−inf with a zero pivot).
    pub fn log_volume(&self) -> f64 {
        let rank = self.rank();
        match self {
            RankQr::Dense(q) => (0..rank).map(|k| q.diagonal(k).abs().ln()).sum(),
            RankQr::Envelope(q) => (0..rank).map(|k| q.diagonal(k).abs().ln()).sum(),
        }
    }

    /// With `rank = rows − 1` (one direction left): `x ← Q e_rank`, the unit vector
    /// orthogonal to the kept columns; returns `det[A_kept, x] = (−1)^rank Π R_kk`'s sign
    /// (each kept column has a true reflector, `det H = −1`), which orients `x` against the
    /// kept columns in their factored order. 0 (and `x` untouched) otherwise.
    pub fn kernel_sign(&self, x: &mut [f64]) -> f64 {
        let rank = self.rank();
        if rank + 1 != x.len() {
            return 0.0;
        }
        x.fill(0.0);
        x[rank] = 1.0;
        let mut sign = if rank % 2 == 0 { 1.0 } else { -1.0 };
        match self {
            RankQr::Dense(q) => {
                q.apply_q_full(x);
                for k in 0..rank {
                    sign *= q.diagonal(k).signum();
                }
            }
            RankQr::Envelope(q) => {
                q.apply_q_full(x);
                for k in 0..rank {
                    sign *= q.diagonal(k).signum();
                }
            }
        }
        sign
    }

    /// `R₁₁ᵀ w = b` in place.
    pub fn solve_rt(&self, w: &mut [f64]) {
        match self {
            RankQr::Dense(q) => q.solve_rt(w),
            RankQr::Envelope(q) => q.solve_rt(w),
        }
    }

    /// `R₁₁ y = w` in place.
    pub fn solve_r(&self, w: &mut [f64]) {
        match self {
            RankQr::Dense(q) => q.solve_r(w),
            RankQr::Envelope(q) => q.solve_r(w),
        }
    }

    /// `x = Q [w; 0]`.
    pub fn apply_q(&self, w: &[f64], x: &mut [f64]) {
        match self {
            RankQr::Dense(q) => q.apply_q(w, x),
            RankQr::Envelope(q) => q.apply_q(w, x),
        }
    }
}

/// `min |d| / max |d|` of a factor's diagonal (1 when empty).
pub(super) fn pivot_ratio(diagonal: impl Iterator<Item = f64>) -> f64 {
    let (lo, hi) = diagonal.fold((f64::INFINITY, 0.0_f64), |(lo, hi), d| {
        (lo.min(d.abs()), hi.max(d.abs()))
    });
    if hi > 0.0 {
        lo / hi
    } else {
        1.0
    }
}
