//! Runtime CPU dispatch. The hot loops (the body-frame recursions, the RK45 stage
//! combinations) are compiled twice, for the baseline x86-64 instruction set and for AVX2,
//! and the AVX2 copy runs where the CPU has it. Only the instructions differ (three-operand
//! forms with fewer register moves, packed lanes in element-wise loops); the arithmetic does
//! not: Rust never fuses `a * b + c` into an FMA nor reorders a floating-point sum, so every
//! IEEE operation and its rounding are the baseline build's and results are bit for bit the
//! same (`recursive::tests::avx2_copy_is_bit_identical`, `integrator::stepper` tests).

/// Whether the CPU has AVX2 (a cached flag after the first call).
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_avx2() -> bool {
    std::is_x86_feature_detected!("avx2")
}
