//! Runtime CPU dispatch. The hot loops (the body-frame recursions, the RK45 stage
//! combinations) are compiled twice, for the baseline x86-64 instruction set and for AVX2,
//! and the AVX2 copy runs where the CPU has it. Only the instructions differ (three-operand
//! forms with fewer register moves, packed lanes in element-wise loops); the arithmetic does
//! not: Rust never fuses `a * b + c` into an FMA nor reorders a floating-point sum, so every
//! IEEE operation and its rounding are the baseline build's and results are bit for bit the
//! same (`recursive::tests::avx2_copy_is_bit_identical`, `integrator::stepper` tests).

/// Whether the AVX2 copies run: the CPU has AVX2 and the environment variable
/// `POINTMASS_DYN_BASELINE` is not set (set it to run the baseline build everywhere, e.g.
/// under tools that do not decode every AVX instruction, such as older valgrind). Read once.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_avx2() -> bool {
    static AVX2: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *AVX2.get_or_init(|| {
        std::is_x86_feature_detected!("avx2")
            && std::env::var_os("POINTMASS_DYN_BASELINE").is_none()
    })
}

/// Defines a function twice over one `#[inline(always)]` body: `$name` runs `$avx2` (the body
/// compiled with AVX2) where the CPU has it, else `$base` (the baseline build, kept callable
/// so that tests can compare the two bit for bit).
///
/// ```ignore
/// multiversion! {
///     /// Docs of the dispatching function.
///     pub fn forward / forward_avx2 / forward_baseline [] (model: &Model, a: &mut [f64]) -> Result<()>
///         => forward_body
/// }
/// ```
macro_rules! multiversion {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident / $avx2:ident / $base:ident [$($gen:tt)*]
        ($($arg:ident : $ty:ty),* $(,)?) $(-> $ret:ty)? => $body:ident
    ) => {
        $(#[$meta])*
        #[allow(clippy::too_many_arguments)]
        #[inline]
        $vis fn $name<$($gen)*>($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            if $crate::cpu::has_avx2() {
                // SAFETY: the CPU supports AVX2, checked just above.
                return unsafe { $avx2($($arg),*) };
            }
            $base($($arg),*)
        }

        /// The body compiled for AVX2.
        ///
        /// # Safety
        /// The CPU must support AVX2.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $avx2<$($gen)*>($($arg: $ty),*) $(-> $ret)? {
            $body($($arg),*)
        }

        /// The body for the baseline instruction set, whatever the CPU.
        #[allow(clippy::too_many_arguments, dead_code)]
        pub(crate) fn $base<$($gen)*>($($arg: $ty),*) $(-> $ret)? {
            $body($($arg),*)
        }
    };
}
pub(crate) use multiversion;
