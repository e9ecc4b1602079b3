//! Which SIMD instruction set the cpu engine runs on, chosen at run time: the widest this
//! CPU has, or the one `SAWTOOTH_SIMD` names (to measure the path another CPU takes).
//!
//! | `SAWTOOTH_SIMD` | the flight search | the bounce loop and the launch points |
//! |---|---|---|
//! | `scalar` | one particle at a time (`engine::kernel`) | compiled for the x86-64 baseline |
//! | `avx2` | four particles at once (`lane::avx2`) | compiled for x86-64-v3 as well |
//! | `avx512` | eight at once (`lane::avx512`) | compiled for x86-64-v3 as well |
//! | `neon` | two at once (`lane::neon`, aarch64) | the aarch64 build |
//!
//! Every path gives the same results to the bit (`engine::lanes` and `tests/cli.rs`).
//! The hot loops compiled a second time for x86-64-v3 (the cpu engine's bounce loop,
//! `engine::cpu::run_design`, the launch points' candidate tests and the fill arc's sines and
//! cosines, `model::fill`) carry `#[target_feature(enable = …)]` with
//! [`X86_64_V3_FEATURES`] (an attribute takes a literal, so it is spelled out there; a test
//! below holds every copy to this one) and inline everything they call, so all of it gets
//! three-operand and 256-bit instructions and inline `floor`/`ceil`: Rust never contracts
//! `a * b + c` into a fused multiply-add, so the features change which instructions compute
//! each IEEE operation, not the operations.

use std::sync::OnceLock;

/// The environment variable that forces a path: `scalar`, `avx2`, `avx512` or `neon`.
pub const SIMD_VAR: &str = "SAWTOOTH_SIMD";

/// The variable `SAWTOOTH_SIMD` replaced; a run that sets it is refused, with the value to
/// use instead, rather than run another path than asked.
pub const RETIRED_CPU_LEVEL_VAR: &str = "SAWTOOTH_CPU_LEVEL";

/// The features every x86-64-v3 compilation enables (the AVX2 lanes' too).
pub const X86_64_V3_FEATURES: &str = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2";

/// A path of the cpu engine: the instruction set its flight search runs its lanes on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// One particle at a time, the x86-64 baseline build (or any other CPU's).
    Scalar,
    /// Four f64 lanes, AVX2 (x86-64-v3).
    Avx2,
    /// Eight f64 lanes, AVX-512F.
    Avx512,
    /// Two f64 lanes, NEON (aarch64).
    Neon,
}

impl Simd {
    pub const ALL: [Simd; 4] = [Simd::Scalar, Simd::Avx2, Simd::Avx512, Simd::Neon];

    /// The name `SAWTOOTH_SIMD` takes.
    pub fn name(self) -> &'static str {
        match self {
            Simd::Scalar => "scalar",
            Simd::Avx2 => "avx2",
            Simd::Avx512 => "avx512",
            Simd::Neon => "neon",
        }
    }

    /// How many particles the flight search takes at once.
    pub fn lanes(self) -> usize {
        match self {
            Simd::Scalar => 1,
            Simd::Avx2 => 4,
            Simd::Avx512 => 8,
            Simd::Neon => 2,
        }
    }

    /// The path in words, for the cpu engine's description (`bench`'s `cpu:` line, run
    /// manifests).
    pub fn describe(self) -> &'static str {
        match self {
            Simd::Scalar if cfg!(target_arch = "x86_64") => "SIMD scalar: one particle at a time, baseline build",
            Simd::Scalar => "SIMD scalar: one particle at a time",
            Simd::Avx2 => "SIMD avx2: 4 f64 lanes, x86-64-v3 build",
            Simd::Avx512 => "SIMD avx512: 8 f64 lanes, x86-64-v3 build",
            Simd::Neon => "SIMD neon: 2 f64 lanes",
        }
    }

    /// Whether this CPU has the instruction set.
    pub fn supported(self) -> bool {
        match self {
            Simd::Scalar => true,
            Simd::Avx2 => x86_64_v3_detected(),
            Simd::Avx512 => avx512_detected(),
            Simd::Neon => neon_detected(),
        }
    }

    /// The widest path this CPU has.
    pub fn widest() -> Simd {
        widest_of(Simd::supported)
    }

    /// Whether the hot loops' x86-64-v3 compilation runs on this path.
    pub fn x86_64_v3(self) -> bool {
        matches!(self, Simd::Avx2 | Simd::Avx512)
    }
}

/// Every one of [`X86_64_V3_FEATURES`] (the SSE and AVX levels not named here come with
/// AVX2).
fn x86_64_v3_detected() -> bool {
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

/// AVX-512F on top of x86-64-v3 (the eight lanes run inside the x86-64-v3 bounce loop).
fn avx512_detected() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        x86_64_v3_detected() && std::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

fn neon_detected() -> bool {
    #[cfg(target_arch = "aarch64")]
    {
        std::arch::is_aarch64_feature_detected!("neon")
    }
    #[cfg(not(target_arch = "aarch64"))]
    {
        false
    }
}

/// The widest of the paths `supported`.
fn widest_of(supported: impl Fn(Simd) -> bool) -> Simd {
    [Simd::Avx512, Simd::Avx2, Simd::Neon].into_iter().find(|s| supported(*s)).unwrap_or(Simd::Scalar)
}

/// The path for the values of `SAWTOOTH_SIMD` and `SAWTOOTH_CPU_LEVEL` (None: unset) on a
/// CPU with the paths `supported`: the one named, or the widest; an error naming the
/// variable, its value and the rule otherwise.
pub fn choose(simd: Option<&str>, cpu_level: Option<&str>, supported: impl Fn(Simd) -> bool) -> Result<Simd, String> {
    if let Some(level) = cpu_level {
        return Err(format!(
            "{RETIRED_CPU_LEVEL_VAR}={level:?} is no longer read: {SIMD_VAR} (scalar, avx2, avx512, neon) chooses the path; \
             unset {RETIRED_CPU_LEVEL_VAR} (its `baseline` is {SIMD_VAR}=scalar, its `x86-64-v3` is {SIMD_VAR}=avx2)"
        ));
    }
    let Some(value) = simd else {
        return Ok(widest_of(supported));
    };
    let runs = || {
        let names: Vec<&str> = Simd::ALL.into_iter().filter(|s| supported(*s)).map(Simd::name).collect();
        names.join(", ")
    };
    let Some(simd) = Simd::ALL.into_iter().find(|s| s.name() == value) else {
        return Err(format!("{SIMD_VAR}={value:?} is none of scalar, avx2, avx512, neon (this CPU runs: {})", runs()));
    };
    if !supported(simd) {
        return Err(format!(
            "{SIMD_VAR}={value}: this CPU lacks the {} instructions that path needs (this CPU runs: {})",
            match simd {
                Simd::Avx2 => "AVX2 (x86-64-v3)",
                Simd::Avx512 => "AVX-512F",
                _ => "NEON",
            },
            runs()
        ));
    }
    Ok(simd)
}

/// The path the environment asks for on this CPU ([`choose`]); the command line refuses a
/// run with an error here (exit 2), and `engine::make_engine` returns it.
pub fn check() -> Result<Simd, String> {
    let var = |name| std::env::var(name).ok();
    choose(var(SIMD_VAR).as_deref(), var(RETIRED_CPU_LEVEL_VAR).as_deref(), Simd::supported)
}

/// The path the cpu engine takes (read once). A setting [`check`] refuses was refused
/// before any engine ran where the engine is made by `engine::make_engine` (the command
/// line, the Python package); a program that makes one otherwise gets the error on stderr
/// and the scalar path.
pub fn selected() -> Simd {
    static PATH: OnceLock<Simd> = OnceLock::new();
    *PATH.get_or_init(|| {
        check().unwrap_or_else(|e| {
            eprintln!("error: {e}; the cpu engine runs the scalar path");
            Simd::Scalar
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The path named is taken where the CPU has it, the widest one when none is named, and
    /// every other setting is refused by name with the rule.
    #[test]
    fn the_path_is_the_one_named_or_the_widest() {
        let avx2_cpu = |s: Simd| matches!(s, Simd::Scalar | Simd::Avx2);
        assert_eq!(choose(None, None, avx2_cpu), Ok(Simd::Avx2));
        assert_eq!(choose(None, None, |_| true), Ok(Simd::Avx512));
        assert_eq!(choose(None, None, |s| s == Simd::Scalar), Ok(Simd::Scalar));
        assert_eq!(choose(None, None, |s| matches!(s, Simd::Scalar | Simd::Neon)), Ok(Simd::Neon));
        assert_eq!(choose(Some("scalar"), None, avx2_cpu), Ok(Simd::Scalar));
        assert_eq!(choose(Some("avx2"), None, avx2_cpu), Ok(Simd::Avx2));
        let lacks = choose(Some("avx512"), None, avx2_cpu).unwrap_err();
        assert!(lacks.contains("SAWTOOTH_SIMD=avx512") && lacks.contains("AVX-512F"), "{lacks}");
        assert!(lacks.contains("this CPU runs: scalar, avx2"), "{lacks}");
        let lacks = choose(Some("neon"), None, avx2_cpu).unwrap_err();
        assert!(lacks.contains("NEON"), "{lacks}");
        let unknown = choose(Some("AVX2"), None, avx2_cpu).unwrap_err();
        assert!(unknown.contains("\"AVX2\" is none of scalar, avx2, avx512, neon"), "{unknown}");
        let retired = choose(None, Some("baseline"), avx2_cpu).unwrap_err();
        assert!(retired.contains("SAWTOOTH_CPU_LEVEL") && retired.contains("SAWTOOTH_SIMD=scalar"), "{retired}");
        assert!(choose(Some("avx2"), Some("x86-64-v3"), avx2_cpu).is_err());
    }

    /// The CPU's own answers agree with the rule: scalar everywhere, AVX-512 only with the
    /// AVX2 it runs inside of, and this build's architecture's paths only.
    #[test]
    fn this_cpu_has_the_scalar_path_and_its_own_architectures() {
        assert!(Simd::Scalar.supported());
        assert!(!Simd::Avx512.supported() || Simd::Avx2.supported());
        assert!(cfg!(target_arch = "x86_64") || !(Simd::Avx2.supported() || Simd::Avx512.supported()));
        assert!(cfg!(target_arch = "aarch64") || !Simd::Neon.supported());
        assert!(Simd::widest().supported());
    }

    /// Every `#[target_feature(enable = …)]` of the crate's x86-64-v3 compilations enables
    /// [`X86_64_V3_FEATURES`] (the AVX-512 lanes add `avx512f` to them): the compilations
    /// and the run-time check cannot drift apart.
    #[test]
    fn every_x86_64_v3_compilation_enables_the_same_features() {
        let sources = [
            ("src/engine/cpu.rs", include_str!("engine/cpu.rs")),
            ("src/model/fill.rs", include_str!("model/fill.rs")),
            ("src/engine/lanes/mod.rs", include_str!("engine/lanes/mod.rs")),
        ];
        let mut seen = 0;
        for (path, text) in sources {
            for (at, _) in text.match_indices("target_feature(enable = \"") {
                let rest = &text[at + "target_feature(enable = \"".len()..];
                let features = &rest[..rest.find('"').expect("a closed literal")];
                if features == "neon" {
                    continue;
                }
                let v3 = features.strip_suffix(",avx512f").unwrap_or(features);
                assert_eq!(v3, X86_64_V3_FEATURES, "{path}");
                seen += 1;
            }
        }
        assert_eq!(seen, 5, "the bounce loop, the launch points, the fill arc, the AVX2 and the AVX-512 lanes");
    }
}
