//! Whether the AVX2 code paths run. Loops that the compiler vectorises are compiled twice,
//! for the baseline x86-64 target (SSE2) and with AVX2 enabled (`#[target_feature]`), and
//! the AVX2 copy is called where the CPU has it. Only AVX2 is enabled, not FMA, and Rust
//! never fuses a multiply and an add on its own: both copies make the same operations in the
//! same order, so they give the same bits.

/// When the CPU has AVX2, unless the environment variable `CTCAL_SIMD=scalar` asks for the
/// portable paths (to check that both give identical results).
pub fn use_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        static AVX2: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *AVX2.get_or_init(|| {
            std::arch::is_x86_feature_detected!("avx2")
                && std::env::var("CTCAL_SIMD").map_or(true, |v| v != "scalar")
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}
