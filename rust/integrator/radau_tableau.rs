//! The Radau IIA (order 5) coefficients, as SciPy's radau.py defines them: collocation nodes,
//! error weights, the transformation `T`/`T⁻¹` that diagonalises `A⁻¹` into one real
//! eigenvalue and a complex pair, and the dense-output matrix `P`.
// T and TI are SciPy's digits verbatim.
#![allow(clippy::excessive_precision)]

use nalgebra::Complex;

pub(super) const S6: f64 = 2.449_489_742_783_178; // √6
/// Collocation nodes.
pub(crate) const C: [f64; 3] = [(4.0 - S6) / 10.0, (4.0 + S6) / 10.0, 1.0];
/// Error-estimate weights (SciPy `E`).
pub(super) const E: [f64; 3] = [
    (-13.0 - 7.0 * S6) / 3.0,
    (-13.0 + 7.0 * S6) / 3.0,
    -1.0 / 3.0,
];

/// SciPy's `T`, `TI` (eigenvectors of `A⁻¹` and their inverse).
pub(super) const T: [[f64; 3]; 3] = [
    [
        0.094_438_762_488_975_24,
        -0.141_255_295_020_954_21,
        0.030_029_194_105_147_42,
    ],
    [
        0.250_213_122_965_333_32,
        0.204_129_352_293_799_94,
        -0.382_942_112_757_261_92,
    ],
    [1.0, 1.0, 0.0],
];
pub(super) const TI: [[f64; 3]; 3] = [
    [
        4.178_718_591_551_904_28,
        0.327_682_820_761_062_37,
        0.523_376_445_499_449_51,
    ],
    [
        -4.178_718_591_551_904_28,
        -0.327_682_820_761_062_37,
        0.476_623_554_500_550_44,
    ],
    [
        0.502_872_634_945_786_82,
        -2.571_926_949_855_605_22,
        0.596_039_204_828_224_92,
    ],
];

/// Dense-output coefficients (SciPy `P`, 3 stages × powers x, x², x³).
pub(super) const P: [[f64; 3]; 3] = [
    [
        13.0 / 3.0 + 7.0 * S6 / 3.0,
        -23.0 / 3.0 - 22.0 * S6 / 3.0,
        10.0 / 3.0 + 5.0 * S6,
    ],
    [
        13.0 / 3.0 - 7.0 * S6 / 3.0,
        -23.0 / 3.0 + 22.0 * S6 / 3.0,
        10.0 / 3.0 - 5.0 * S6,
    ],
    [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0],
];

/// The real eigenvalue of `A⁻¹`, `3 + 3^(2/3) − 3^(1/3)`, and the complex pair
/// `3 + (3^(1/3) − 3^(2/3))/2 − i (3^(5/6) + 3^(7/6))/2`, evaluated as SciPy does.
pub(super) fn mu_real() -> f64 {
    3.0 + 3f64.powf(2.0 / 3.0) - 3f64.powf(1.0 / 3.0)
}
pub(super) fn mu_complex() -> Complex<f64> {
    Complex::new(
        3.0 + 0.5 * (3f64.powf(1.0 / 3.0) - 3f64.powf(2.0 / 3.0)),
        -(0.5 * (3f64.powf(5.0 / 6.0) + 3f64.powf(7.0 / 6.0))),
    )
}
