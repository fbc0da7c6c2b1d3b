//! `sin_cos` for joint angles, inlined into the recursions.
//!
//! Every right-hand-side evaluation takes the sine and cosine of every revolute angle; the
//! system `sincos` is an out-of-line call that saves and restores the rounding mode and
//! costs ≈ 130 instructions (≈ 10 % of a 7-link forward dynamics, by callgrind). Angles
//! here are modest, so a Cody–Waite reduction to [−π/4, π/4] (π/2 split in a 33-bit head,
//! so that `n · head` is exact, and a tail) and fdlibm's kernel polynomials (< 1 ulp on that
//! interval) do the same job in ≈ 65, inlined; |x| ≥ 1e5 and non-finite arguments go to
//! the system routine.

// The constants are fdlibm's, digit for digit as published.
#![allow(clippy::excessive_precision)]

/// 2/π.
const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
/// π/2 split as fdlibm's `pio2_1` (its first 33 bits, so `n · PIO2_HI` is exact) and
/// `pio2_1t` (the rest).
const PIO2_HI: f64 = 1.570_796_326_734_125_614_17e0;
const PIO2_LO: f64 = 6.077_100_506_506_192_249_32e-11;
/// 1.5 · 2⁵²: adding and subtracting it rounds to the nearest integer.
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;
/// Above this the reduction is no longer exact (fdlibm's "medium" bound, with margin).
const REDUCE_LIMIT: f64 = 1.0e5;

const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;

const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// `(sin x, cos x)`.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !(x.abs() < REDUCE_LIMIT) {
        // Large, infinite or NaN.
        return x.sin_cos();
    }
    let shifted = x * TWO_OVER_PI + ROUND_MAGIC;
    // The low bits of the shifted mantissa are the quadrant (two's complement for n < 0).
    let quadrant = shifted.to_bits() & 3;
    let n = shifted - ROUND_MAGIC;
    // x − n·PIO2_HI is exact; the tail then brings the error to ~|n|·1e-27.
    let r = (x - n * PIO2_HI) - n * PIO2_LO;
    let (s, c) = kernel(r);
    match quadrant {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// [`sin_cos`] of `N` angles at once, bit for bit the same values, written without
/// branches so that the lanes vectorise (quadrants by selects and sign-bit flips, the
/// range test one packed compare: `&`, not a short-circuiting `all`); `None` when an angle
/// needs the system routine (|x| ≥ 1e5, inf, NaN).
#[inline(always)]
pub fn sin_cos_lanes<const N: usize>(x: [f64; N]) -> Option<([f64; N], [f64; N])> {
    if !x.iter().fold(true, |ok, v| ok & (v.abs() < REDUCE_LIMIT)) {
        return None;
    }
    let mut sin = [0.0; N];
    let mut cos = [0.0; N];
    for l in 0..N {
        let shifted = x[l] * TWO_OVER_PI + ROUND_MAGIC;
        let quadrant = shifted.to_bits() & 3;
        let n = shifted - ROUND_MAGIC;
        let r = (x[l] - n * PIO2_HI) - n * PIO2_LO;
        let (s, c) = kernel(r);
        // Quadrants 0..3 give (s, c), (c, −s), (−s, −c), (−c, s): swap on odd quadrants,
        // negate sin in 2, 3 and cos in 1, 2 (flipping the sign bit is IEEE negation).
        let (a, b) = if quadrant & 1 == 1 { (c, s) } else { (s, c) };
        sin[l] = f64::from_bits(a.to_bits() ^ ((quadrant & 2) << 62));
        cos[l] = f64::from_bits(b.to_bits() ^ (((quadrant + 1) & 2) << 62));
    }
    Some((sin, cos))
}

/// [`sin_cos_lanes`] of four angles (the recursions' groups).
#[inline(always)]
pub fn sin_cos4(x: [f64; 4]) -> Option<([f64; 4], [f64; 4])> {
    sin_cos_lanes(x)
}

/// fdlibm's `__kernel_sin(r, 0)` and `__kernel_cos(r, 0)` for |r| ≤ π/4.
#[inline(always)]
fn kernel(r: f64) -> (f64, f64) {
    let z = r * r;
    let w = z * z;
    let ps = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    let sin = r + z * r * (S1 + z * ps);
    let pc = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let one_minus = 1.0 - hz;
    let cos = one_minus + (((1.0 - one_minus) - hz) + z * pc);
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::{sin_cos, sin_cos_lanes};

    /// Distance in units in the last place of the larger magnitude (absolute near zeros).
    fn ulps(a: f64, b: f64) -> f64 {
        let scale = a.abs().max(b.abs()).max(f64::MIN_POSITIVE);
        let ulp = f64::EPSILON * 2f64.powi(scale.log2().floor() as i32);
        (a - b).abs() / ulp
    }

    #[test]
    fn agrees_with_the_system_routine() {
        // A dense sweep, the neighbourhoods of multiples of π/4 (quadrant edges and the
        // kernel's interval ends) and large angles up to the reduction limit.
        let mut xs: Vec<f64> = (-400_000..=400_000).map(|k| k as f64 * 2.5e-5).collect();
        for k in -200..=200 {
            let m = k as f64 * std::f64::consts::FRAC_PI_4;
            for d in [-1e-9, -1e-15, 0.0, 1e-15, 1e-9] {
                xs.push(m + d);
                xs.push(f64::from_bits(m.to_bits() + 1));
            }
        }
        xs.extend((0..2000).map(|k| -99_990.0 + k as f64 * 99.99));
        let mut worst = 0.0f64;
        for &x in &xs {
            let (s, c) = sin_cos(x);
            let (s0, c0) = x.sin_cos();
            // Absolute error against 1 (the size of a rotation entry), and relative error
            // wherever the value is not near a zero of sin or cos.
            assert!(
                (s - s0).abs() <= 3e-16 && (c - c0).abs() <= 3e-16,
                "x = {x}"
            );
            for (a, b) in [(s, s0), (c, c0)] {
                if b.abs() > 1e-3 {
                    worst = worst.max(ulps(a, b));
                }
            }
            assert!((s * s + c * c - 1.0).abs() <= 4.5e-16, "x = {x}");
        }
        assert!(worst <= 2.0, "worst {worst} ulp");
    }

    #[test]
    fn lanes_at_once_are_bit_identical() {
        // Every quadrant, both signs, the kernel's interval ends, tiny and signed zeros.
        let mut xs: Vec<f64> = (-20_000..20_000).map(|k| k as f64 * 1.37e-3).collect();
        for k in -40..=40 {
            let m = k as f64 * std::f64::consts::FRAC_PI_4;
            xs.extend([m, f64::from_bits(m.to_bits() + 1), m - 1e-15, m + 1e-15]);
        }
        xs.extend([0.0, -0.0, 1e-300, -1e-300, 99_999.9, -99_999.9]);
        let bits = |v: [f64; 4]| v.map(f64::to_bits);
        for quad in xs.chunks_exact(4) {
            let x = [quad[0], quad[1], quad[2], quad[3]];
            let (s4, c4) = sin_cos_lanes(x).expect("moderate angles");
            let one = x.map(sin_cos);
            assert_eq!(bits(s4), bits(one.map(|p| p.0)), "{x:?}");
            assert_eq!(bits(c4), bits(one.map(|p| p.1)), "{x:?}");
        }
        // An angle the kernel does not take sends the whole group to the caller.
        for bad in [1e5, f64::NAN, f64::NEG_INFINITY] {
            assert!(sin_cos_lanes([0.1, bad, 0.2, 0.3]).is_none());
            assert!(sin_cos_lanes([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, bad]).is_none());
        }
    }

    #[test]
    fn tiny_angles_keep_relative_accuracy() {
        for x in [1e-300, -3e-200, 1e-20, 2.5e-9, -7e-5] {
            let (s, c) = sin_cos(x);
            assert!(((s - x.sin()) / x).abs() <= 2.0 * f64::EPSILON, "x = {x}");
            assert!(ulps(c, x.cos()) <= 1.0, "x = {x}");
        }
    }

    #[test]
    fn large_and_non_finite_arguments_use_the_system_routine() {
        for x in [1e5, -3.7e9, 1e300] {
            assert_eq!(sin_cos(x), x.sin_cos());
        }
        let (s, c) = sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, c) = sin_cos(f64::INFINITY);
        assert!(s.is_nan() && c.is_nan());
    }
}
