//! Measurement-like tooth masses from the model (issue 5 §3): per run, the setup is simulated
//! with a finite particle count and its own particle streams; the loaded mass is drawn near
//! the setup's (≈ 2 g), a share of it is not recovered (App. B: 94.5-101.5 %, mean 97.7 %),
//! grains that left the conveyor are lost, and masses are rounded to the scale's resolution.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::engine::BatchEvaluator;
use crate::model::{Design, Scenario};

#[derive(Clone, Debug)]
pub struct SynthSettings {
    pub runs: u32,
    pub seed: u64,
    /// Particles simulated per run (the finite grain count of one run).
    pub particles: u32,
    /// Nominal loaded mass, g.
    pub mass_g: f64,
    /// Run-to-run sd of the loaded mass, g.
    pub mass_sd_g: f64,
    /// Recovered share of the mass that stayed on the conveyor: uniform in [lo, hi].
    pub recovery: (f64, f64),
    /// Scale resolution, g.
    pub resolution_g: f64,
    /// Teeth written (at least those with mass).
    pub min_teeth: usize,
}

impl Default for SynthSettings {
    fn default() -> Self {
        SynthSettings {
            runs: 10,
            seed: 0,
            particles: 2000,
            mass_g: 2.0,
            mass_sd_g: 0.03,
            recovery: (0.96, 1.0),
            resolution_g: 0.01,
            min_teeth: 4,
        }
    }
}

/// One synthetic run: tooth masses and the loaded mass, g.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthRun {
    pub teeth_g: Vec<f64>,
    pub input_mass_g: f64,
}

fn quantise(x: f64, step: f64) -> f64 {
    ((x / step).round() * step * 1e9).round() / 1e9
}

pub fn synthesise(
    engine: &dyn BatchEvaluator,
    scenario: &Scenario,
    design: &Design,
    set: &SynthSettings,
) -> anyhow::Result<Vec<SynthRun>> {
    if set.runs == 0 || set.particles == 0 {
        anyhow::bail!("SynthSettings: runs and particles must be at least 1, got {} and {}", set.runs, set.particles);
    }
    if !(set.resolution_g > 0.0
        && set.mass_g > 0.0
        && set.recovery.0 > 0.0
        && set.recovery.0 <= set.recovery.1
        && set.recovery.1 <= crate::schema::RECOVERY.max)
    {
        anyhow::bail!(
            "SynthSettings: resolution_g ({}) and mass_g ({}) must be positive, recovery ({}, {}) must satisfy 0 < lo <= hi <= 1.5",
            set.resolution_g,
            set.mass_g,
            set.recovery.0,
            set.recovery.1
        );
    }
    let mut rng = ChaCha8Rng::seed_from_u64(set.seed);
    let mut runs = Vec::with_capacity(set.runs as usize);
    for r in 0..set.runs {
        let mut s = scenario.clone();
        s.sim.particles = set.particles;
        s.sim.seed = set.seed.wrapping_mul(0x9E37_79B9).wrapping_add(r as u64 + 1);
        let e = engine
            .evaluate(&s, std::slice::from_ref(design))
            .pop()
            .expect("one design")
            .map_err(|e| anyhow::anyhow!("synth: invalid setup design ({}): {e}", e.rule()))?;
        let input = (set.mass_g + set.mass_sd_g * standard_normal(&mut rng)).max(set.resolution_g);
        let recovery = rng.random_range(set.recovery.0..=set.recovery.1);
        let teeth_g = e.sim.distribution.iter().map(|f| quantise(f * input * recovery, set.resolution_g)).collect();
        runs.push(SynthRun { teeth_g, input_mass_g: quantise(input, set.resolution_g) });
    }
    Ok(runs)
}

fn standard_normal(rng: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// The runs in the measured-data CSV format (`io::measured`), with provenance lines.
pub fn to_csv(runs: &[SynthRun], provenance: &[String], min_teeth: usize, resolution_g: f64) -> String {
    let used = runs
        .iter()
        .map(|r| r.teeth_g.iter().rposition(|m| *m > 0.0).map_or(0, |i| i + 1))
        .max()
        .unwrap_or(0)
        .max(min_teeth);
    let decimals = (-resolution_g.log10()).ceil().max(0.0) as usize;
    let mut out = String::new();
    for p in provenance {
        out.push_str(&format!("# {p}\n"));
    }
    out.push_str("run");
    for j in 1..=used {
        out.push_str(&format!(",tooth_{j}"));
    }
    out.push_str(",input_mass\n");
    for (i, r) in runs.iter().enumerate() {
        out.push_str(&format!("{}", i + 1));
        for j in 0..used {
            out.push_str(&format!(",{:.*}", decimals, r.teeth_g.get(j).copied().unwrap_or(0.0)));
        }
        out.push_str(&format!(",{:.*}\n", decimals, r.input_mass_g));
    }
    out
}
