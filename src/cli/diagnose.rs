//! `sawtooth diagnose`: locate the sim-to-real gap in one or more measured conditions and
//! rank the candidate effects by held-out error (issue 5 §2). The work is in
//! [`crate::diagnose::diagnose`].

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;

use super::args::EffortArgs;
use super::measured_condition::{self, stem};
use crate::calibrate::Normalise;
use crate::diagnose::diagnose::{
    applicable_effects, diagnose, parse_effects, to_json, Condition, Settings, NO_EFFECT_APPLIES,
};
use crate::diagnose::render;
use crate::engine::{make_engine, EngineKind};
use crate::io::run_dir::{Access, RunDir};

#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Measured runs (CSV, as data/validation), repeatable; the i-th --data goes with the
    /// i-th --setup.
    #[arg(long, required = true)]
    pub data: Vec<PathBuf>,
    /// The rig's setup for each --data (config TOML with [design], optional [measurement]).
    #[arg(long, required = true)]
    pub setup: Vec<PathBuf>,
    #[arg(long, default_value = "all", help = format!(
        "Candidate effects: `all` or a comma list of their names (see `sawtooth simulate --help` for each): {}",
        crate::model::effects::known_effects()))]
    pub effects: String,
    /// Seed of the particle streams, the solver and the bootstrap (default: the first setup's
    /// sim.seed).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Particle engine for the fits: cpu, gpu or auto (the listing port has no effects).
    #[arg(long, value_enum, default_value = "cpu")]
    pub engine: EngineKind,
    #[command(flatten)]
    pub effort: EffortArgs,
    /// What the compared fractions are fractions of: `loaded` (the input mass: the weighed
    /// teeth plus a "not recovered" bin; the default when every run records input_mass) or
    /// `recovered` (listing D.4: the weighed teeth's sum).
    #[arg(long, value_enum)]
    pub normalise: Option<Normalise>,
    /// Fresh particle streams every fitted model is re-scored with.
    #[arg(long, default_value_t = 4, value_parser = super::args::count::<usize>(&crate::schema::RESCORE_STREAMS))]
    pub rescore_streams: usize,
    /// Bootstrap replicates for the intervals (resampling held-out runs).
    #[arg(long, default_value_t = 400, value_parser = super::args::count::<usize>(&crate::schema::DIAGNOSE_BOOTSTRAP))]
    pub bootstrap: usize,
    /// Write report.md, diagnosis.json and the figures residuals, ranking, distributions (.svg and .png) here.
    #[arg(long)]
    pub out: PathBuf,
    /// Print diagnosis.json's object instead of a summary.
    #[arg(long)]
    pub json: bool,
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
    let effects = parse_effects(&a.effects).context("--effects")?;
    if a.engine == EngineKind::Listing {
        bail!("--engine listing: the effects are in the cpu and gpu engines only; use --engine cpu or auto");
    }
    a.effort.validate()?;
    let mut conditions: Vec<Condition> = Vec::with_capacity(a.data.len());
    for (data, setup) in a.data.iter().zip(&a.setup) {
        let mut name = stem(data);
        if conditions.iter().any(|c| c.name == name) {
            name = format!("{name}#{}", conditions.len() + 1);
        }
        // every condition runs on the first setup's seed unless --seed is given
        let seed = a.seed.or(conditions.first().map(|c| c.base.sim.seed));
        let mut c = measured_condition::load(data, setup, name, a.normalise, seed)?;
        if c.base.effects.any() {
            eprintln!(
                "diagnose: {}: the setup's [effects] ({}) are switched off; the diagnosis fits them itself",
                setup.display(),
                c.base.effects.active().join(", ")
            );
            c.base.effects = Default::default();
        }
        if c.runs.runs.len() < 2 {
            bail!(
                "--data {}: has {} run(s); the diagnosis needs at least 2 (their spread is the measurement's uncertainty)",
                data.display(),
                c.runs.runs.len()
            );
        }
        conditions.push(c);
    }
    if applicable_effects(&effects, &conditions).0.is_empty() {
        bail!("--effects: {NO_EFFECT_APPLIES}");
    }
    let seed = conditions[0].base.sim.seed;
    // the output folder is owned before the work, so a busy or foreign folder costs nothing
    let _owned = RunDir::acquire(&a.out, "diagnose", Access::Exclusive).context("--out")?;
    let engine = make_engine(a.engine)?;
    let settings =
        Settings { effects, effort: a.effort.effort(seed), rescore_streams: a.rescore_streams, bootstrap: a.bootstrap };
    let started = std::time::Instant::now();
    let d = diagnose(engine.as_ref(), conditions, settings, &mut |line| eprintln!("{line}"))?;
    eprintln!("diagnose: done in {:.1} s", started.elapsed().as_secs_f64());
    let json = to_json(&d);
    render::write_dir(&a.out, &d, &json).context("--out")?;
    if a.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&json)?).context("writing output")?;
    } else {
        let b = &d.baseline;
        writeln!(out, "baseline gap {:.1} %² [{:.1}, {:.1}]", b.gap, b.interval[0], b.interval[1])?;
        // the ranking is by the penalised score, not the gap: say so, and show it
        writeln!(out, "ranked by {}", crate::diagnose::diagnose::RANKING_RULE)?;
        for (i, m) in d.ranking.iter().enumerate() {
            writeln!(
                out,
                "{}. {:<15} gap {:>8.1} %² [{:.1}, {:.1}]  reduction {:>6.1} %  score {:>8.1}",
                i + 1,
                m.name(),
                m.gap,
                m.interval[0],
                m.interval[1],
                100.0 * (1.0 - m.gap / b.gap),
                m.score
            )?;
        }
        writeln!(out, "best: {}", d.best.map_or("none (the data cannot tell)", |e| e.name()))?;
        writeln!(out, "verdict: {}: {}", d.verdict.kind.name(), d.verdict.text)?;
        if !d.indistinguishable.is_empty() {
            writeln!(
                out,
                "indistinguishable: {}",
                d.indistinguishable.iter().map(|e| e.name()).collect::<Vec<_>>().join(", ")
            )?;
        }
        for n in &d.notes {
            writeln!(out, "note: {n}")?;
        }
        writeln!(out, "wrote {0}/report.md, {0}/diagnosis.json and the plots (SVG and PNG)", a.out.display())?;
    }
    Ok(ExitCode::SUCCESS)
}
