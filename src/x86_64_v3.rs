//! Hot loops compiled a second time for x86-64-v3 (AVX2, FMA, BMI1/2, SSE4.1-4.2, ...) and
//! taken at run time on CPUs that have it: the cpu engine's bounce loop
//! (`engine::cpu::run_design`) and the launch points' candidate tests
//! (`model::fill::launch_points`). Each such function carries `#[target_feature(enable =
//! …)]` with [`FEATURES`] (an attribute takes a literal, so it is spelled out there; a test
//! below holds every copy to this one) and inlines everything it calls, so all of it gets
//! three-operand and 256-bit instructions and inline `floor`/`ceil`. The results are the same
//! to the bit: Rust never contracts `a * b + c` into a fused multiply-add, so the features
//! change which instructions compute each IEEE operation, not the operations (tested in
//! both places).

/// The features every x86-64-v3 compilation enables.
pub const FEATURES: &str = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2";

/// The environment variable that caps the instruction sets the cpu engine takes, to
/// measure the paths other CPUs run: `baseline` (x86-64 without the second compilation or
/// the AVX-512 lanes), `x86-64-v3` (no AVX-512 lanes); unset, whatever the CPU has.
pub const CPU_LEVEL_VAR: &str = "SAWTOOTH_CPU_LEVEL";

/// The instruction-set levels the cpu engine can run at, lowest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    Baseline,
    X86_64V3,
    Avx512,
}

/// The highest level [`CPU_LEVEL_VAR`] allows (read once; an unknown value is named on
/// stderr and caps nothing, so a benchmark never silently runs another path than asked).
pub fn level_cap() -> Level {
    static CAP: std::sync::OnceLock<Level> = std::sync::OnceLock::new();
    *CAP.get_or_init(|| match std::env::var(CPU_LEVEL_VAR).as_deref() {
        Err(_) => Level::Avx512,
        Ok("baseline") => Level::Baseline,
        Ok("x86-64-v3") => Level::X86_64V3,
        Ok("avx512") => Level::Avx512,
        Ok(other) => {
            eprintln!("warning: {CPU_LEVEL_VAR}={other:?} is none of baseline, x86-64-v3, avx512; not capped");
            Level::Avx512
        }
    })
}

/// Whether this CPU has every one of [`FEATURES`] (the SSE and AVX levels not named here
/// come with AVX2) and [`level_cap`] allows them.
pub fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        level_cap() >= Level::X86_64V3
            && std::is_x86_feature_detected!("avx2")
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

#[cfg(test)]
mod tests {
    /// Every `#[target_feature(enable = …)]` of the crate enables [`super::FEATURES`]: the
    /// compilations and the run-time check cannot drift apart.
    #[test]
    fn every_x86_64_v3_compilation_enables_the_same_features() {
        let sources = [
            ("src/engine/cpu.rs", include_str!("engine/cpu.rs")),
            ("src/model/fill.rs", include_str!("model/fill.rs")),
        ];
        let mut seen = 0;
        for (path, text) in sources {
            for (at, _) in text.match_indices("#[target_feature(enable = \"") {
                let rest = &text[at + "#[target_feature(enable = \"".len()..];
                let features = &rest[..rest.find('"').expect("a closed literal")];
                assert_eq!(features, super::FEATURES, "{path}");
                seen += 1;
            }
        }
        assert_eq!(seen, 2, "the bounce loop and the launch points");
    }
}
