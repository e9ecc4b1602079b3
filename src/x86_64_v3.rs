//! Hot loops compiled a second time for x86-64-v3 (AVX2, FMA, BMI1/2, SSE4.1-4.2, ...) and
//! taken at run time on CPUs that have it: the cpu engine's bounce loop
//! (`engine::cpu::run_design`) and the launch points' candidate tests
//! (`model::fill::launch_points`). Each such function carries
//! `#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2")]`,
//! the features [`available`] checks, and inlines everything it calls, so all of it gets
//! three-operand and 256-bit instructions and inline `floor`/`ceil`. The results are the same
//! to the bit: Rust never contracts `a * b + c` into a fused multiply-add, so the features
//! change which instructions compute each IEEE operation, not the operations (tested in
//! both places).

/// Whether this CPU has every feature of the x86-64-v3 compilations.
pub fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("bmi2")
            && std::is_x86_feature_detected!("lzcnt")
            && std::is_x86_feature_detected!("movbe")
            && std::is_x86_feature_detected!("popcnt")
            && std::is_x86_feature_detected!("sse4.2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
