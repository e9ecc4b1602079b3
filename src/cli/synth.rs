//! `sawtooth synth`: measurement-like runs from the (extended) model, in the measured-data
//! CSV format, for checking a diagnosis on data whose effect is known.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;

use crate::diagnose::synth::{synthesise, to_csv, SynthSettings};
use crate::engine::{make_engine_for, EngineKind};
use crate::io::atomic::write_atomic;
use crate::io::config::ConfigFile;

#[derive(Debug, Args)]
pub struct SynthArgs {
    /// Setup TOML (the measured-data setup format).
    #[arg(long)]
    pub setup: PathBuf,
    #[arg(long = "effect", value_name = "NAME=PARAMS", help = super::args::effect_help())]
    pub effects: Vec<String>,
    /// Measured runs to synthesise (rows of the CSV).
    #[arg(long, default_value_t = 10, value_parser = super::args::count::<u32>(&crate::schema::SYNTH_RUNS))]
    pub runs: u32,
    /// Seed of the particle streams and of the mass and scale noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Particles simulated per run (the run's finite grain count).
    #[arg(long, default_value_t = 2000, value_parser = super::args::count::<u32>(&crate::schema::SYNTH_PARTICLES))]
    pub particles: u32,
    /// Loaded mass per run, g (run-to-run sd 0.03 g).
    #[arg(long, allow_negative_numbers = true, default_value_t = 2.0)]
    pub mass_g: f64,
    /// Scale resolution, g (default: the setup's [measurement] scale_resolution_g, else 0.01).
    #[arg(long, allow_negative_numbers = true)]
    pub resolution_g: Option<f64>,
    /// Output CSV.
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(a: SynthArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    crate::io::atomic::refuse_input_as_output(&a.out, "--out", &[("--setup", &a.setup)])?;
    let file = ConfigFile::load(&a.setup)?;
    let mut scenario = file.scenario()?;
    let design = file.design().with_context(|| format!("{}: the setup has no [design]", a.setup.display()))?;
    super::args::set_effects(&mut scenario, &a.effects)?;
    scenario.validate().map_err(|e| {
        anyhow::anyhow!("--setup {}: invalid setting: {}", a.setup.display(), super::args::in_user_terms(&e))
    })?;
    // (the setup's own resolution is checked when the file is read)
    if let Some(r) = a.resolution_g {
        crate::schema::SCALE_RESOLUTION_G.check("--resolution-g", r).map_err(anyhow::Error::msg)?;
    }
    let resolution = a.resolution_g.or(file.measurement.as_ref().and_then(|m| m.scale_resolution_g)).unwrap_or(0.01);
    crate::schema::SYNTH_MASS_G.check("--mass-g", a.mass_g).map_err(anyhow::Error::msg)?;
    let set = SynthSettings {
        runs: a.runs,
        seed: a.seed,
        particles: a.particles,
        mass_g: a.mass_g,
        resolution_g: resolution,
        ..Default::default()
    };
    let engine = make_engine_for(EngineKind::Cpu, &scenario)?;
    let runs = synthesise(&engine, &scenario, &design, &set)?;
    let effects = if scenario.effects.any() { a.effects.join(" ") } else { "none".into() };
    let provenance = vec![format!(
        "synthetic: sawtooth synth --setup {} --effect [{effects}] --runs {} --seed {} --particles {}; masses in grams, resolution {resolution} g",
        a.setup.display(),
        a.runs,
        a.seed,
        a.particles
    )];
    write_atomic(&a.out, to_csv(&runs, &provenance, set.min_teeth, resolution).as_bytes())?;
    writeln!(out, "wrote {} runs to {}", runs.len(), a.out.display())?;
    Ok(ExitCode::SUCCESS)
}
