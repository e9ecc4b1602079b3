//! `sawtooth campaign run|gather|status|slurm DIR`: a campaign folder written by
//! `gpu-sweep --plan`, `study … --plan` or `dem check --plan`, run member by member (one
//! process per member, e.g. one Slurm array task), or all at once here; summarised by
//! `gather` with the same code and bytes as the one-process commands. Whatever the kind of
//! campaign (`campaigns::open` tells it), the library's campaign protocol (`crate::protocol`)
//! does the work; this module parses the flags and prints. A shared filesystem is assumed:
//! every task reads the plan and writes its member's folder under DIR.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Args, Subcommand};

use crate::campaigns::open;
use crate::campaigns::plan::{write_plan, Plan, PLAN_FILE};
use crate::campaigns::slurm::{array_spec, submit, submit_command, write_scripts, SlurmSettings};
use crate::protocol::{self, Campaign, Ran};

#[derive(Debug, Subcommand)]
pub enum CampaignCommand {
    /// Run member --task alone (default: $SLURM_ARRAY_TASK_ID); with neither, every
    /// unfinished member here in one process (batched per generation), then gather.
    Run(RunArgs),
    /// Build the summary and figures from the finished members; refuses (exit 2) and lists
    /// the unfinished ones if any member is not finished.
    Gather(DirArgs),
    /// Each member: finished, running, stopped at a checkpoint, or not started.
    Status(DirArgs),
    /// Write an sbatch script for a job array (one task per member) and a gather job that
    /// depends on it; print the sbatch commands (--submit runs them).
    Slurm(SlurmArgs),
}

#[derive(Debug, Args)]
pub struct DirArgs {
    /// The campaign folder (holds plan.json).
    pub dir: PathBuf,
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The campaign folder (holds plan.json).
    pub dir: PathBuf,
    /// Member index, 0-based (default: $SLURM_ARRAY_TASK_ID when set).
    #[arg(long)]
    pub task: Option<usize>,
}

#[derive(Debug, Args)]
pub struct SlurmArgs {
    /// The campaign folder (holds plan.json); must be on a filesystem every node sees.
    pub dir: PathBuf,
    /// Slurm partition (default: the cluster's default partition).
    #[arg(long)]
    pub partition: Option<String>,
    /// Wall-time limit per task, in Slurm's format (MM, HH:MM:SS, D-HH:MM, …).
    #[arg(long)]
    pub time: Option<String>,
    /// CPU cores per task (the CPU engine's threads).
    #[arg(long, default_value_t = 1, value_parser = super::args::count::<u32>(&crate::schema::SLURM_CPUS_PER_TASK))]
    pub cpus_per_task: u32,
    /// GPUs per task (for --engine gpu/auto plans).
    #[arg(long, value_parser = super::args::count::<u32>(&crate::schema::SLURM_GPUS_PER_TASK))]
    pub gpus_per_task: Option<u32>,
    /// At most K tasks of the array running at once (`--array=…%K`).
    #[arg(long, value_parser = super::args::count::<u32>(&crate::schema::SLURM_MAX_PARALLEL))]
    pub max_parallel: Option<u32>,
    /// Only the members that are not finished (to resubmit after a cancel or a failure).
    #[arg(long)]
    pub unfinished: bool,
    /// Submit with sbatch instead of only printing the commands.
    #[arg(long)]
    pub submit: bool,
}

impl SlurmArgs {
    /// The library's settings from the flags.
    pub fn settings(&self) -> SlurmSettings {
        SlurmSettings {
            partition: self.partition.clone(),
            time: self.time.clone(),
            cpus_per_task: self.cpus_per_task,
            gpus_per_task: self.gpus_per_task,
            max_parallel: self.max_parallel,
            unfinished: self.unfinished,
        }
    }
}

pub fn run(c: CampaignCommand, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    match c {
        CampaignCommand::Run(a) => run_cmd(a, out),
        CampaignCommand::Gather(a) => gather(&a.dir, out),
        CampaignCommand::Status(a) => status(&a.dir, out),
        CampaignCommand::Slurm(a) => slurm(a, out),
    }
}

/// What `gpu-sweep` and `study` do with their plan: with `plan_only` write it and stop;
/// otherwise run it here in one process and summarise from the members' files (the same
/// code `campaign gather` runs, so both give the same bytes).
pub fn plan_or_run(root: &Path, plan: &Plan, plan_only: bool, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let _owned = write_plan(root, plan)?;
    if plan_only {
        let n = plan.members.len();
        writeln!(out, "wrote {} ({n} members); nothing run yet", root.join(PLAN_FILE).display())?;
        writeln!(
            out,
            "  one member:      sawtooth campaign run {} --task I   (I in 0..{})",
            root.display(),
            n.saturating_sub(1)
        )?;
        writeln!(out, "  all, here:       sawtooth campaign run {}", root.display())?;
        writeln!(
            out,
            "  Slurm job array: sawtooth campaign slurm {} [--partition P --time T] --submit",
            root.display()
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    Ok(exit_code(&plan.run_all(root, out)?))
}

/// 130 (as for Ctrl-C) when the run was interrupted, its state saved for the same command.
fn exit_code(ran: &Ran) -> ExitCode {
    match ran {
        Ran::Interrupted => ExitCode::from(130),
        _ => ExitCode::SUCCESS,
    }
}

fn task_from_env() -> anyhow::Result<Option<usize>> {
    match std::env::var("SLURM_ARRAY_TASK_ID") {
        Ok(v) => v
            .trim()
            .parse::<usize>()
            .map(Some)
            .with_context(|| format!("SLURM_ARRAY_TASK_ID=`{v}` is not a member index (expected 0, 1, 2, …)")),
        Err(_) => Ok(None),
    }
}

fn run_cmd(a: RunArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let task = match a.task {
        Some(t) => Some(t),
        None => task_from_env()?,
    };
    let c = open(&a.dir)?;
    let ran = match task {
        Some(i) => protocol::run_task(c.as_ref(), &a.dir, i, out)?,
        None => protocol::run_here(c.as_ref(), &a.dir, out)?,
    };
    Ok(exit_code(&ran))
}

fn gather(dir: &Path, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    protocol::gather(open(dir)?.as_ref(), dir, out)?;
    Ok(ExitCode::SUCCESS)
}

fn status(dir: &Path, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    protocol::status(open(dir)?.as_ref(), dir, out)?;
    Ok(ExitCode::SUCCESS)
}

fn slurm(a: SlurmArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let exe = std::env::current_exe().and_then(std::fs::canonicalize).context("locating the sawtooth executable")?;
    let w = write_scripts(open(&a.dir)?.as_ref(), &a.dir, &a.settings(), &exe)?;
    writeln!(
        out,
        "wrote {} ({} tasks: {}) and {}",
        w.array.display(),
        w.tasks.len(),
        array_spec(&w.tasks),
        w.gather.display()
    )?;
    if let Some(g) = &w.stale_gather {
        writeln!(out, "note: the gather job of the last submission ({g}) can never start once a task of its array failed or was cancelled; if squeue still shows it: scancel {g}")?;
    }
    if !a.submit {
        writeln!(out, "submit with:")?;
        writeln!(out, "  {}", submit_command(&w)?)?;
        return Ok(ExitCode::SUCCESS);
    }
    let (jid, gid) = submit(&w)?;
    writeln!(
        out,
        "submitted array job {jid} (tasks {}) and gather job {gid} (--dependency=afterok:{jid})",
        array_spec(&w.tasks)
    )?;
    let root = w.root.display();
    writeln!(out, "logs in {root}/logs; follow with `sawtooth campaign status {root}`")?;
    Ok(ExitCode::SUCCESS)
}
