//! `sawtooth fit`: calibrate k_elastic, mu_fric and k_drag against measured tooth masses
//! (thesis 4.3.4-4.3.5, listing D.4). The work is in [`crate::fit`].

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;

use super::args::EngineArgs;
use crate::engine::make_engine;
use crate::fit::report::{self, Meta};
use crate::fit::{objective, parse_assignments, parse_params, FitSettings, GaSettings, ObjectiveKind, Problem};
use crate::io::config::ConfigFile;
use crate::io::measured;

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Measured runs: CSV `run,tooth_1,..,tooth_n[,input_mass]` (grams), as data/validation.
    #[arg(long)]
    pub data: PathBuf,
    /// The rig's setup: a config TOML with [design] (and optionally [measurement]).
    #[arg(long)]
    pub setup: PathBuf,
    /// Parameters to fit, a comma list of k_elastic, mu_fric, k_drag; the others keep the
    /// setup's values.
    #[arg(long, default_value = "k_elastic,mu_fric,k_drag")]
    pub params: String,
    /// What the GA minimises.
    #[arg(long, value_enum, default_value = "sse")]
    pub objective: ObjectiveKind,
    /// GA population size (>= 4).
    #[arg(long, default_value_t = 40)]
    pub pop: usize,
    /// GA generations after the initial population.
    #[arg(long, default_value_t = 30)]
    pub generations: u64,
    /// Particles per simulation (the same streams for every candidate).
    #[arg(long, default_value_t = 1000)]
    pub particles: u32,
    /// Seed of the particle streams, the GA and the bootstrap (default: the setup's sim.seed).
    #[arg(long)]
    pub seed: Option<u64>,
    #[command(flatten)]
    pub engine: EngineArgs,
    /// Hold out the last K runs: fit on the others, score on them (0 = off).
    #[arg(long, default_value_t = 3)]
    pub holdout: usize,
    /// Bootstrap replicates over the runs for the parameter uncertainty (0 = off).
    #[arg(long, default_value_t = 20)]
    pub bootstrap: usize,
    /// Do not fit: score these values (`k_elastic=0.854,mu_fric=0.133,k_drag=5.347`) against
    /// the runs; the parameters not named keep the setup's values.
    #[arg(long, conflicts_with = "params")]
    pub at: Option<String>,
    /// Write fit.json, fit.csv and fit.svg into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: FitArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    // cheap checks first: nothing is simulated before every input is known to be good
    let (params, at) = match &a.at {
        Some(list) => {
            let (p, v) = parse_assignments(list)?;
            (p, Some(v))
        }
        None => (parse_params(&a.params)?, None),
    };
    if a.pop < 4 {
        bail!("--pop must be >= 4, got {}", a.pop);
    }
    if a.particles == 0 {
        bail!("--particles must be >= 1, got 0");
    }
    let runs = measured::load(&a.data).context("--data")?;
    let config = ConfigFile::load(&a.setup).context("--setup")?;
    let Some(design) = config.design() else {
        bail!("--setup {}: no [design] table (the rig's sawtooth design is required)", a.setup.display());
    };
    let mut scenario = config.scenario().with_context(|| format!("--setup {}", a.setup.display()))?;
    let n = runs.runs.len();
    if a.holdout >= n {
        bail!("--holdout must be < the number of runs in {} ({n}), got {}", a.data.display(), a.holdout);
    }
    if runs.teeth > scenario.sim.teeth as usize {
        bail!(
            "--data {} has {} teeth but the setup simulates only {} (sim.teeth): raise sim.teeth in {}",
            a.data.display(),
            runs.teeth,
            scenario.sim.teeth,
            a.setup.display()
        );
    }
    let seed = a.seed.unwrap_or(scenario.sim.seed);
    scenario.sim.particles = a.particles;
    scenario.sim.seed = seed;
    if let Err(e) = scenario.validate() {
        bail!("--setup {}: invalid setting: {e}", a.setup.display());
    }
    let resolution_g = config
        .measurement
        .as_ref()
        .and_then(|m| m.scale_resolution_g)
        .unwrap_or_else(|| objective::infer_resolution(runs.runs.iter().flat_map(|r| r.teeth_g.iter().copied())));

    let engine = make_engine(a.engine.engine)?;
    let problem = Problem::new(engine.as_ref(), scenario, design, params)
        .with_context(|| format!("--setup {}", a.setup.display()))?;
    let settings = FitSettings {
        objective: a.objective,
        ga: GaSettings { pop: a.pop, generations: a.generations, seed },
        bootstrap: a.bootstrap,
        holdout: a.holdout,
    };
    let report = match &at {
        Some(x) => crate::fit::evaluate_at(&problem, &runs, resolution_g, a.objective, x)?,
        None => {
            let started = std::time::Instant::now();
            let r = crate::fit::fit(&problem, &runs, resolution_g, settings, &mut |line| eprintln!("{line}"))?;
            eprintln!("fit: done in {:.1} s", started.elapsed().as_secs_f64());
            r
        }
    };

    let meta = Meta {
        data: a.data.display().to_string(),
        setup: a.setup.display().to_string(),
        engine: engine.backend().to_string(),
        particles: a.particles,
        seed,
        teeth: problem.teeth(),
        measured_teeth: runs.teeth,
        run_ids: runs.runs.iter().map(|r| r.id.clone()).collect(),
    };
    let json = report::to_json(&report, &meta);
    if let Some(dir) = &a.out {
        report::write_dir(dir, &report, &meta, &json)?;
    }
    if a.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&json)?).context("writing output")?;
    } else {
        report::write_table(out, &report, &meta).context("writing output")?;
        if let Some(dir) = &a.out {
            writeln!(out, "\nwrote {0}/fit.json, {0}/fit.csv, {0}/fit.svg", dir.display()).context("writing output")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
