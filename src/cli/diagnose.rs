//! `sawtooth diagnose`: locate the sim-to-real gap in one or more measured conditions and
//! rank the candidate effects by held-out error (issue 5 §2). The flags become a
//! [`DiagnoseRequest`], which the library checks and runs ([`crate::diagnose::request`], as
//! the Python package does); the work is in [`crate::diagnose::diagnose`].

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;

use super::args::EffortArgs;
use crate::calibrate::{parse_params, Normalise, Spelling};
use crate::diagnose::diagnose::parse_effects;
use crate::diagnose::request::{self, DiagnoseRequest};
use crate::engine::EngineKind;

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
    #[arg(long, default_value_t = DiagnoseRequest::DEFAULT_RESCORE_STREAMS, value_parser = super::args::count::<usize>(&crate::schema::RESCORE_STREAMS))]
    pub rescore_streams: usize,
    /// Bootstrap replicates for the intervals (resampling held-out runs).
    #[arg(long, default_value_t = DiagnoseRequest::DEFAULT_BOOTSTRAP, value_parser = super::args::count::<usize>(&crate::schema::DIAGNOSE_BOOTSTRAP))]
    pub bootstrap: usize,
    /// Leave out each candidate's detection limit for this campaign (the smallest strength
    /// the diagnosis detects with 90 % probability; diagnosis.json's `detection_limits`).
    #[arg(long)]
    pub no_detection_limits: bool,
    /// Rank additional conditions (v0, a, slope, more runs) by how well they would separate
    /// the candidates the diagnosis leaves, simulated from each one's fit (diagnosis.json's
    /// `suggestions`, report.md's "Next measurement").
    #[arg(long)]
    pub suggest: bool,
    /// The parameters every model fits, shared by the conditions, as a comma list (default:
    /// k_elastic,mu_fric, plus k_drag where any setup has air); add v_limit to fit the contact
    /// law's plastic limit speed (Eq. 4.9) in the baseline and every candidate.
    #[arg(long)]
    pub params: Option<String>,
    /// Write report.md, diagnosis.json and the figures residuals, ranking, distributions (.svg and .png) here.
    #[arg(long)]
    pub out: PathBuf,
    /// Print diagnosis.json's object instead of a summary.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: DiagnoseArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let mut r = DiagnoseRequest::new(a.data.clone(), a.setup.clone(), a.out.clone(), Spelling::Flags);
    r.effects = parse_effects(&a.effects).context("--effects")?;
    r.seed = a.seed;
    r.engine = a.engine;
    r.effort = a.effort.settings(DiagnoseRequest::DEFAULT_EFFORT);
    r.normalise = a.normalise;
    r.rescore_streams = a.rescore_streams;
    r.bootstrap = a.bootstrap;
    r.detection_limits = !a.no_detection_limits;
    r.suggest = a.suggest;
    r.params = a.params.as_deref().map(parse_params).transpose().context("--params")?;
    let (d, json) = request::run(&r, &mut |line| eprintln!("{line}"))?;
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
        if let Some(g) = d.suggestions.as_ref() {
            for (i, p) in g.proposals.iter().take(3).enumerate() {
                writeln!(
                    out,
                    "suggested {}: {} {} ({:.1}x the floor between the least separated pair{})",
                    i + 1,
                    p.base,
                    p.change.label(),
                    p.worst(),
                    if p.separates() { ": separates them" } else { "" }
                )?;
            }
        }
        for n in &d.notes {
            writeln!(out, "note: {n}")?;
        }
        writeln!(out, "wrote {0}/report.md, {0}/diagnosis.json and the plots (SVG and PNG)", a.out.display())?;
    }
    Ok(ExitCode::SUCCESS)
}
