//! `sawtooth study repeatability|sensitivity` (5.4.1-5.4.2, Tables C.1-C.3, Figure 5.3):
//! many optimisation runs in lockstep, each compared at the target mass flow. With `--plan`
//! the runs become a campaign (`cli::campaign`) run elsewhere, e.g. as a Slurm job array. The
//! plan's members are built here from the arguments; running and summarising them is
//! [`crate::campaigns`].

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::{Args, Subcommand};

use super::args::{EngineArgs, ScenarioArgs};
use super::campaign::plan_or_run;
use super::optimize::GaArgs;
use crate::campaigns::plan::{Member, Plan, Study};
use crate::campaigns::study::{read_ci, sensitivity_grid};
use crate::engine::EngineKind;
use crate::model::Scenario;

#[derive(Debug, Subcommand)]
pub enum StudyCommand {
    /// Independent seeds; spread of f_stroke and W_spec at the target mass flow (Table C.1).
    Repeatability(RepeatabilityArgs),
    /// k_elastic, μ (and k_drag with drag) at ±5/10 % (Tables C.2-C.3).
    Sensitivity(SensitivityArgs),
}

#[derive(Debug, Args)]
pub struct Common {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
    #[command(flatten)]
    pub ga: GaArgs,
    /// Mass flow the runs are compared at, kg/s (default: 0.022 lunar, 0.008 terrestrial,
    /// as Tables C.2-C.3; erratum 17).
    #[arg(long, allow_negative_numbers = true)]
    pub target_mass_flow: Option<f64>,
    /// Output directory: one run folder per member, then runs.csv/grid.csv, summary.csv and the
    /// figure (.svg and .png); rerunning reads finished members back and resumes the rest.
    #[arg(long)]
    pub out: PathBuf,
    /// Only write the campaign's plan into --out (run it with `sawtooth campaign`).
    #[arg(long)]
    pub plan: bool,
}

impl Common {
    fn plan(&self, command: &str, study: Study, members: Vec<Member>) -> Plan {
        let engine: EngineKind = self.engine.kind();
        Plan::new(command, study, engine, self.ga.checkpoint_every, members)
    }
}

#[derive(Debug, Args)]
pub struct RepeatabilityArgs {
    #[command(flatten)]
    pub common: Common,
    /// Independent runs (thesis: 45).
    #[arg(long, default_value_t = 45, value_parser = super::args::count::<u32>(&crate::schema::STUDY_RUNS))]
    pub runs: u32,
}

#[derive(Debug, Args)]
pub struct SensitivityArgs {
    #[command(flatten)]
    pub common: Common,
    /// A finished repeatability study whose confidence interval the grid is judged against.
    #[arg(long)]
    pub repeatability: Option<PathBuf>,
}

pub fn run(c: StudyCommand, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    match c {
        StudyCommand::Repeatability(a) => repeatability(a, out),
        StudyCommand::Sensitivity(a) => sensitivity(a, out),
    }
}

fn target(c: &Common, s: &Scenario) -> anyhow::Result<f64> {
    let t = c.target_mass_flow.unwrap_or(if s.environment.k_drag.is_some() { 0.008 } else { 0.022 });
    crate::schema::TARGET_MASS_FLOW.check("--target-mass-flow", t).map_err(anyhow::Error::msg)
}

fn repeatability(a: RepeatabilityArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let c = &a.common;
    let (base, _) = c.scenario.resolve()?;
    let t = target(c, &base)?;
    if a.runs < 2 {
        bail!("--runs must be at least 2, got {}", a.runs);
    }
    let members: Vec<Member> = (0..a.runs)
        .map(|i| {
            let mut s = base.clone();
            s.sim.seed = base.sim.seed.wrapping_add(i as u64);
            Ok(Member {
                label: format!("run {i:>3}"),
                dir: format!("run_{i:03}"),
                manifest: c.ga.manifest(s, c.engine.kind())?,
            })
        })
        .collect::<anyhow::Result<_>>()?;
    let plan = c.plan("study repeatability", Study::Repeatability { target_mass_flow: t }, members);
    plan_or_run(&c.out, &plan, c.plan, out)
}

fn sensitivity(a: SensitivityArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let c = &a.common;
    let (base, _) = c.scenario.resolve()?;
    let t = target(c, &base)?;
    let ci = a.repeatability.as_deref().map(read_ci).transpose()?;
    // Tables C.2 (5x5 over k_elastic, mu at ±5/10 %) and C.3 (3x3x3 with k_drag at ±10 %).
    let grid = sensitivity_grid(base.environment.k_drag.is_some());
    let members: Vec<Member> = grid
        .iter()
        .enumerate()
        .map(|(i, g)| {
            let mut s = base.clone();
            s.collision.k_elastic *= g[0];
            s.collision.mu_friction *= g[1];
            s.environment.k_drag = s.environment.k_drag.map(|k| k * g[2]);
            s.validate().map_err(|e| anyhow::anyhow!("grid point {i}: {e}"))?;
            Ok(Member {
                label: format!("grid {i:>2}"),
                dir: format!("grid_{i:02}"),
                manifest: c.ga.manifest(s, c.engine.kind())?,
            })
        })
        .collect::<anyhow::Result<_>>()?;
    let plan = c.plan("study sensitivity", Study::Sensitivity { target_mass_flow: t, repeatability_ci: ci }, members);
    plan_or_run(&c.out, &plan, c.plan, out)
}
