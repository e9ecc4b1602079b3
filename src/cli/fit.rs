//! `sawtooth fit`: calibrate k_elastic, mu_fric and k_drag against measured tooth masses
//! (thesis 4.3.4-4.3.5, listing D.4). The work is in [`crate::fit`], on the calibration
//! engine `diagnose` uses ([`crate::calibrate`]).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;

use super::args::{EffortArgs, EngineArgs};
use super::measured_condition::{self, stem};
use crate::calibrate::{parse_assignments, parse_params, shared_params, Normalise, ObjectiveKind};
use crate::engine::make_engine;
use crate::fit::report::{self, Meta};
use crate::fit::FitSettings;
use crate::io::run_dir::{Access, RunDir};

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Measured runs: CSV `run,tooth_1,..,tooth_n[,input_mass]` (grams), as data/validation.
    #[arg(long)]
    pub data: PathBuf,
    /// The rig's setup: a config TOML with [design] (and optionally [measurement]).
    #[arg(long)]
    pub setup: PathBuf,
    /// Parameters to fit, a comma list of k_elastic, mu_fric, k_drag; the others keep the
    /// setup's values. Default: k_elastic,mu_fric, and k_drag where the setup has drag.
    #[arg(long)]
    pub params: Option<String>,
    /// What the solver minimises.
    #[arg(long, value_enum, default_value = "sse")]
    pub objective: ObjectiveKind,
    #[command(flatten)]
    pub effort: EffortArgs,
    /// What the compared fractions are fractions of: `loaded` (the input mass: the weighed
    /// teeth plus a "not recovered" bin; the default when every run records input_mass) or
    /// `recovered` (listing D.4: the weighed teeth's sum, plus a lost bin).
    #[arg(long, value_enum)]
    pub normalise: Option<Normalise>,
    /// Seed of the particle streams, the solver and the bootstrap (default: the setup's
    /// sim.seed).
    #[arg(long)]
    pub seed: Option<u64>,
    #[command(flatten)]
    pub engine: EngineArgs,
    /// Hold out the last K runs: fit on the others, score on them (0 = off).
    #[arg(long, default_value_t = 3)]
    pub holdout: usize,
    /// Bootstrap replicates over the runs for the parameter uncertainty (0 = off).
    #[arg(long, default_value_t = 20, value_parser = super::args::count::<usize>(&crate::schema::FIT_BOOTSTRAP))]
    pub bootstrap: usize,
    /// Do not fit: score these values (`k_elastic=0.854,mu_fric=0.133,k_drag=5.347`) against
    /// the runs; the parameters not named keep the setup's values.
    #[arg(long, conflicts_with = "params")]
    pub at: Option<String>,
    /// Write fit.json, fit.csv, fit.svg and fit.png into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: FitArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    // cheap checks first: nothing is simulated before every input is known to be good
    let (params, at) = match (&a.at, &a.params) {
        (Some(list), _) => {
            let (p, v) = parse_assignments(list).context("--at")?;
            (Some(p), Some(v))
        }
        (None, Some(list)) => (Some(parse_params(list).context("--params")?), None),
        (None, None) => (None, None),
    };
    a.effort.validate()?;
    let condition = measured_condition::load(&a.data, &a.setup, stem(&a.data), a.normalise, a.seed)?;
    let n = condition.runs.runs.len();
    if a.holdout >= n {
        bail!("--holdout must be < the number of runs in {} ({n}), got {}", a.data.display(), a.holdout);
    }
    // the output folder is owned before the work, so a busy or foreign folder costs nothing
    let _owned = match &a.out {
        Some(dir) => Some(RunDir::acquire(dir, "fit", Access::Exclusive).context("--out")?),
        None => None,
    };
    let params = params.unwrap_or_else(|| shared_params(std::slice::from_ref(&condition)));
    let seed = condition.base.sim.seed;
    let effort = a.effort.effort(seed);
    let engine = make_engine(a.engine.kind())?;
    let started = std::time::Instant::now();
    let report = match &at {
        Some(x) => crate::fit::evaluate_at(engine.as_ref(), &condition, &params, x, a.objective, effort)
            .map_err(|e| anyhow::anyhow!("--at: {e}"))?,
        None => {
            let settings = FitSettings { objective: a.objective, effort, bootstrap: a.bootstrap, holdout: a.holdout };
            let r = crate::fit::fit(engine.as_ref(), &condition, &params, settings, &mut |line| eprintln!("{line}"))
                .with_context(|| format!("--data {}", a.data.display()))?;
            eprintln!("fit: done in {:.1} s", started.elapsed().as_secs_f64());
            r
        }
    };

    let meta = Meta {
        data: a.data.display().to_string(),
        setup: a.setup.display().to_string(),
        engine: engine.backend().to_string(),
        particles: report.particles,
        seed,
        teeth: condition.teeth(),
        measured_teeth: condition.runs.teeth,
        run_ids: condition.runs.runs.iter().map(|r| r.id.clone()).collect(),
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
            writeln!(out, "\nwrote {0}/fit.json, {0}/fit.csv, {0}/fit.svg, {0}/fit.png", dir.display())
                .context("writing output")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
