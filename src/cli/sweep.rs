//! `sawtooth gpu-sweep --alpha 1..40`: one optimisation per conveyor angle (5.4.3, Figure
//! 5.5, Tables C.4-C.5), the angles' populations evaluated together each generation (one GPU
//! job: the angle lives in each design's geometry). Resumable per angle. With `--plan` the
//! angles become a campaign (`cli::campaign`) run elsewhere, e.g. as a Slurm job array. The
//! plan's members are built here from the arguments; running and summarising them is
//! [`crate::campaigns`].

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::Args;

use super::args::{EngineArgs, ScenarioArgs};
use super::campaign::plan_or_run;
use super::optimize::GaArgs;
use crate::campaigns::plan::{Member, Plan, Study};

#[derive(Debug, Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
    #[command(flatten)]
    pub ga: GaArgs,
    /// Angle step, degrees.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1.0)]
    pub step: f64,
    /// Output directory: one run folder per angle, then summary.csv and sweep.svg/.png;
    /// rerunning reads finished angles back and resumes the rest.
    #[arg(long)]
    pub out: PathBuf,
    /// Only write the campaign's plan into --out (run it with `sawtooth campaign`).
    #[arg(long)]
    pub plan: bool,
}

pub fn run(a: SweepArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let Some((from, to)) = a.scenario.alpha else {
        bail!("gpu-sweep needs --alpha FROM..TO (degrees), e.g. --alpha 1..40")
    };
    if !(a.step > 0.0 && a.step.is_finite()) {
        bail!("--step must be a positive number of degrees, got {}", a.step);
    }
    let mut single = a.scenario.clone();
    single.alpha = None;
    let (base, _) = single.resolve()?;
    let n = ((to - from) / a.step + 1e-9).floor() as usize + 1;
    if n > 400 {
        bail!(
            "--alpha {from}..{to} with --step {}: {n} angles; at most 400 (each angle is one optimisation run)",
            a.step
        );
    }
    let angles: Vec<f64> = (0..n).map(|i| from + i as f64 * a.step).collect();
    let mut members = Vec::new();
    for &alpha in &angles {
        let mut s = base.clone();
        s.environment.alpha_deg = alpha;
        s.validate().map_err(|e| anyhow::anyhow!("--alpha {alpha}: {e}"))?;
        members.push(Member {
            label: format!("alpha {alpha:>5.1}"),
            dir: format!("alpha_{alpha:06.2}"),
            manifest: a.ga.manifest(s, a.engine.kind())?,
        });
    }
    let plan = Plan::new("gpu-sweep", Study::Sweep, a.engine.kind(), a.ga.checkpoint_every, members);
    plan_or_run(&a.out, &plan, a.plan, out)
}
