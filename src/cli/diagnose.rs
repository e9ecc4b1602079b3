//! `sawtooth diagnose`: locate the sim-to-real gap in one or more measured conditions and
//! rank the candidate effects by held-out error (issue 5 §2). The work is in
//! [`crate::diagnose::diagnose`].

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;

use crate::calibrate::Normalise;
use crate::diagnose::diagnose::{diagnose, parse_effects, to_json, Budget, Condition, KnownMotion, Settings};
use crate::diagnose::render;
use crate::engine::{make_engine, EngineKind};
use crate::fit::objective;
use crate::io::config::ConfigFile;
use crate::io::measured;

#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Measured runs (CSV, as data/validation), repeatable; the i-th --data goes with the
    /// i-th --setup.
    #[arg(long, required = true)]
    pub data: Vec<PathBuf>,
    /// The rig's setup for each --data (config TOML with [design], optional [measurement]).
    #[arg(long, required = true)]
    pub setup: Vec<PathBuf>,
    /// Candidate effects: a comma list of impact-scatter, launch-spread, polydisperse,
    /// sled-motion, quadratic-drag, or `all`.
    #[arg(long, default_value = "all")]
    pub effects: String,
    /// Seed of the particle streams, the solver and the bootstrap (default: the first setup's
    /// sim.seed).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Particle engine for the fits: cpu, gpu or auto (the listing port has no effects).
    #[arg(long, value_enum, default_value = "cpu")]
    pub engine: EngineKind,
    /// Particles per simulation at the full budget (the same streams for every candidate);
    /// default: what the data call for (Monte-Carlo variance per tooth at most a quarter of
    /// the measured mean's), up to --max-particles.
    #[arg(long)]
    pub particles: Option<u32>,
    /// The most particles per simulation the data may call for.
    #[arg(long, default_value_t = 12_000)]
    pub max_particles: u32,
    /// Differential-evolution population per model (>= 5), screening at 1/8 of the particles.
    #[arg(long, default_value_t = 20)]
    pub pop: usize,
    /// Differential-evolution generations per model.
    #[arg(long, default_value_t = 20)]
    pub generations: usize,
    /// Compass-search iterations polishing each fit at the full budget.
    #[arg(long, default_value_t = 12)]
    pub polish: usize,
    /// What the compared fractions are fractions of: `loaded` (the input mass: the weighed
    /// teeth plus a "not recovered" bin; the default when every run records input_mass) or
    /// `recovered` (listing D.4: the weighed teeth's sum).
    #[arg(long, value_enum)]
    pub normalise: Option<Normalise>,
    /// Fresh particle streams every fitted model is re-scored with.
    #[arg(long, default_value_t = 4)]
    pub rescore_streams: usize,
    /// Bootstrap replicates for the intervals (resampling held-out runs).
    #[arg(long, default_value_t = 400)]
    pub bootstrap: usize,
    /// Write report.md, diagnosis.json, residuals.svg, ranking.svg, distributions.svg here.
    #[arg(long)]
    pub out: PathBuf,
    /// Print diagnosis.json's object instead of a summary.
    #[arg(long)]
    pub json: bool,
}

fn stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| p.display().to_string())
}

pub fn run(a: DiagnoseArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    // cheap checks first: nothing is simulated before every input is known to be good
    if a.data.len() != a.setup.len() {
        bail!(
            "--data and --setup must come in pairs (matched by order): got {} --data and {} --setup",
            a.data.len(),
            a.setup.len()
        );
    }
    let effects = parse_effects(&a.effects)?;
    if a.engine == EngineKind::Listing {
        bail!("--engine listing: the effects are in the cpu and gpu engines only; use --engine cpu or auto");
    }
    if a.particles == Some(0) {
        bail!("--particles must be >= 1, got 0");
    }
    if a.max_particles < 1000 {
        bail!("--max-particles must be >= 1000, got {}", a.max_particles);
    }
    if a.pop < 5 {
        bail!("--pop must be >= 5, got {}", a.pop);
    }
    if a.rescore_streams < 1 {
        bail!("--rescore-streams must be >= 1, got 0");
    }
    if a.bootstrap < 2 {
        bail!("--bootstrap must be >= 2, got {}", a.bootstrap);
    }
    let mut conditions = Vec::with_capacity(a.data.len());
    let mut seed = a.seed;
    let mut names: Vec<String> = Vec::new();
    for (data, setup) in a.data.iter().zip(&a.setup) {
        let runs = measured::load(data).with_context(|| format!("--data {}", data.display()))?;
        let config = ConfigFile::load(setup).with_context(|| format!("--setup {}", setup.display()))?;
        let Some(design) = config.design() else {
            bail!("--setup {}: no [design] table (the rig's sawtooth design is required)", setup.display());
        };
        let mut scenario = config.scenario().with_context(|| format!("--setup {}", setup.display()))?;
        if scenario.effects.any() {
            eprintln!(
                "diagnose: {}: the setup's [effects] ({}) are switched off; the diagnosis fits them itself",
                setup.display(),
                scenario.effects.active().join(", ")
            );
            scenario.effects = Default::default();
        }
        let seed = *seed.get_or_insert(scenario.sim.seed);
        scenario.sim.seed = seed;
        if let Err(e) = scenario.validate() {
            bail!("--setup {}: invalid setting: {e}", setup.display());
        }
        if runs.teeth > scenario.sim.teeth as usize {
            bail!(
                "--data {} has {} teeth but the setup simulates only {} (sim.teeth): raise sim.teeth in {}",
                data.display(),
                runs.teeth,
                scenario.sim.teeth,
                setup.display()
            );
        }
        if runs.runs.len() < 2 {
            bail!("--data {}: has {} run(s); the diagnosis needs at least 2 (their spread is the measurement's uncertainty)", data.display(), runs.runs.len());
        }
        if let Err(invalid) = crate::model::prepare(&scenario, &design) {
            bail!("--setup {}: the design cannot be simulated ({}): {invalid}", setup.display(), invalid.rule());
        }
        let measurement = config.measurement.as_ref();
        let resolution_g = measurement
            .and_then(|m| m.scale_resolution_g)
            .unwrap_or_else(|| objective::infer_resolution(runs.runs.iter().flat_map(|r| r.teeth_g.iter().copied())));
        let mut name = stem(data);
        if names.contains(&name) {
            name = format!("{name}#{}", names.len() + 1);
        }
        names.push(name.clone());
        let normalise = match a.normalise {
            Some(Normalise::Loaded) if !Condition::has_input_mass(&runs) => {
                bail!("--normalise loaded: --data {} lacks input_mass in some run", data.display())
            }
            Some(n) => n,
            None if Condition::has_input_mass(&runs) => Normalise::Loaded,
            None => Normalise::Recovered,
        };
        conditions.push(Condition {
            name,
            data: data.display().to_string(),
            setup: setup.display().to_string(),
            runs,
            base: scenario,
            design,
            resolution_g,
            motion: KnownMotion {
                delay_s: measurement.and_then(|m| m.motion_delay_s),
                return_speed_m_s: measurement.and_then(|m| m.motion_return_speed_m_s),
            },
            motion_profile: measurement.and_then(|m| m.motion_profile.clone()),
            normalise,
        });
    }
    let seed = seed.unwrap_or(0);
    let engine = make_engine(a.engine)?;
    let settings = Settings {
        effects,
        budget: Budget {
            particles: a.particles,
            max_particles: a.max_particles,
            pop: a.pop,
            generations: a.generations,
            polish: a.polish,
            rescore_seeds: a.rescore_streams,
            seed,
        },
        bootstrap: a.bootstrap,
    };
    let started = std::time::Instant::now();
    let d = diagnose(engine.as_ref(), conditions, settings, &mut |line| eprintln!("{line}"))?;
    eprintln!("diagnose: done in {:.1} s", started.elapsed().as_secs_f64());
    let json = to_json(&d);
    render::write_dir(&a.out, &d, &json)?;
    if a.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&json)?).context("writing output")?;
    } else {
        let b = &d.baseline;
        writeln!(out, "baseline gap {:.1} %² [{:.1}, {:.1}]", b.gap, b.interval[0], b.interval[1])?;
        for (i, m) in d.ranking.iter().enumerate() {
            writeln!(
                out,
                "{}. {:<15} gap {:>8.1} %² [{:.1}, {:.1}]  reduction {:>6.1} %",
                i + 1,
                m.name(),
                m.gap,
                m.interval[0],
                m.interval[1],
                100.0 * (1.0 - m.gap / b.gap)
            )?;
        }
        writeln!(out, "best: {}", d.best.map_or("none (the data cannot tell)", |e| e.name()))?;
        if !d.indistinguishable.is_empty() {
            writeln!(out, "indistinguishable: {}", d.indistinguishable.iter().map(|e| e.name()).collect::<Vec<_>>().join(", "))?;
        }
        for n in &d.notes {
            writeln!(out, "note: {n}")?;
        }
        writeln!(out, "wrote {0}/report.md, {0}/diagnosis.json and SVG plots", a.out.display())?;
    }
    Ok(ExitCode::SUCCESS)
}
