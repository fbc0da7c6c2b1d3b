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
            if $crate::support::cpu::has_avx2() {
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

        /// The body for the baseline instruction set, whatever the CPU. Out of line, so that
        /// the dispatcher stays small enough to inline where it is called (with the body
        /// inlined into it, a small kernel's dispatcher stayed a call of its own).
        #[allow(clippy::too_many_arguments, dead_code)]
        #[inline(never)]
        pub(crate) fn $base<$($gen)*>($($arg: $ty),*) $(-> $ret)? {
            $body($($arg),*)
        }
    };
}
pub(crate) use multiversion;

/// x86-64 features the compiler may have been told to assume (`RUSTFLAGS="-C
/// target-cpu=native"` or `-C target-feature=...`), beyond the x86-64 baseline that the
/// shipped builds target. Their instructions may appear anywhere in such a build.
#[cfg(target_arch = "x86_64")]
const COMPILED_FOR: [(&str, bool); 12] = [
    ("sse3", cfg!(target_feature = "sse3")),
    ("ssse3", cfg!(target_feature = "ssse3")),
    ("sse4.1", cfg!(target_feature = "sse4.1")),
    ("sse4.2", cfg!(target_feature = "sse4.2")),
    ("popcnt", cfg!(target_feature = "popcnt")),
    ("avx", cfg!(target_feature = "avx")),
    ("avx2", cfg!(target_feature = "avx2")),
    ("fma", cfg!(target_feature = "fma")),
    ("bmi1", cfg!(target_feature = "bmi1")),
    ("bmi2", cfg!(target_feature = "bmi2")),
    ("f16c", cfg!(target_feature = "f16c")),
    ("avx512f", cfg!(target_feature = "avx512f")),
];

/// Why this build cannot run here (the features it was compiled to assume and the running CPU
/// lacks, and what to do), or `Ok` where it can: the Python module refuses to load with this
/// message (an ImportError) instead of dying on an illegal instruction later.
pub fn check_cpu_features() -> Result<(), String> {
    let missing = missing_cpu_features();
    if missing.is_empty() {
        return Ok(());
    }
    Err(format!(
        "pointmass_dyn was compiled for CPU features this processor lacks: {} (built with \
         RUSTFLAGS such as -C target-cpu=native on another machine); rebuild it here, or \
         install a wheel built without them",
        missing.join(", ")
    ))
}

/// The features this build was compiled to assume and the running CPU lacks: the Python
/// module refuses to load (an ImportError naming them) instead of dying on an illegal
/// instruction later. Empty for the shipped builds (baseline x86-64, AVX2 by dispatch).
pub fn missing_cpu_features() -> Vec<&'static str> {
    #[cfg(target_arch = "x86_64")]
    {
        missing(&COMPILED_FOR, |f| match f {
            "sse3" => std::is_x86_feature_detected!("sse3"),
            "ssse3" => std::is_x86_feature_detected!("ssse3"),
            "sse4.1" => std::is_x86_feature_detected!("sse4.1"),
            "sse4.2" => std::is_x86_feature_detected!("sse4.2"),
            "popcnt" => std::is_x86_feature_detected!("popcnt"),
            "avx" => std::is_x86_feature_detected!("avx"),
            "avx2" => std::is_x86_feature_detected!("avx2"),
            "fma" => std::is_x86_feature_detected!("fma"),
            "bmi1" => std::is_x86_feature_detected!("bmi1"),
            "bmi2" => std::is_x86_feature_detected!("bmi2"),
            "f16c" => std::is_x86_feature_detected!("f16c"),
            "avx512f" => std::is_x86_feature_detected!("avx512f"),
            _ => false,
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec::new()
    }
}

#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
fn missing(compiled: &[(&'static str, bool)], has: impl Fn(&str) -> bool) -> Vec<&'static str> {
    compiled
        .iter()
        .filter(|(name, assumed)| *assumed && !has(name))
        .map(|(name, _)| *name)
        .collect()
}

/// Whether the AVX-512 copies (the batched frame kernels, `frames/batch.rs`) run: the AVX2
/// ones would (so `POINTMASS_DYN_BASELINE` turns both off) and the CPU has AVX-512F. Read once.
#[cfg(target_arch = "x86_64")]
pub fn has_avx512() -> bool {
    static AVX512: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *AVX512.get_or_init(|| has_avx2() && std::is_x86_feature_detected!("avx512f"))
}

/// The widest copy of the multiversioned loops that runs: `"avx512"` (the batched frame
/// kernels in AVX-512F, the rest in AVX2), `"avx2"` or `"baseline"`.
pub fn dispatch() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if has_avx512() {
            return "avx512";
        }
        if has_avx2() {
            return "avx2";
        }
    }
    "baseline"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_build_runs_on_this_cpu() {
        assert!(missing_cpu_features().is_empty());
    }

    #[test]
    fn missing_lists_assumed_features_the_cpu_lacks() {
        let compiled = [("avx", true), ("avx2", true), ("fma", false)];
        assert_eq!(missing(&compiled, |f| f == "avx"), vec!["avx2"]);
        assert!(missing(&compiled, |_| true).is_empty());
        assert!(missing(&[("fma", false)], |_| false).is_empty());
    }

    #[test]
    fn dispatch_follows_the_environment() {
        // Read once per process: whatever it decided, it names one of the copies, and a
        // wider one only where the CPU has it and the environment allows it.
        let d = dispatch();
        assert!(["avx512", "avx2", "baseline"].contains(&d));
        #[cfg(target_arch = "x86_64")]
        if d != "baseline" {
            assert!(std::is_x86_feature_detected!("avx2"));
            assert!(std::env::var_os("POINTMASS_DYN_BASELINE").is_none());
            assert_eq!(d == "avx512", std::is_x86_feature_detected!("avx512f"));
        }
    }
}
