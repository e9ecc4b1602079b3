//! `sawtooth campaign run|gather|status|slurm DIR`: a campaign folder written by
//! `gpu-sweep --plan`, `study … --plan` or `dem check --plan` (whose members are DEM runs,
//! `crate::dem::check`) run member by member (one process per member, e.g. one Slurm array
//! task), or all at once here; summarised by `gather` with the same
//! code and bytes as the one-process commands. A shared filesystem is assumed: every task
//! reads the plan and writes its member's folder under DIR.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::{Args, Subcommand};

use crate::campaigns::plan::{
    execute, finished_fronts, member_state, read_plan, write_plan, MemberState, Plan, CAMPAIGN_KIND, PLAN_FILE,
};
use crate::campaigns::slurm::{array_spec, submit, submit_command, write_scripts, SlurmSettings};
use crate::campaigns::summarise;
use crate::dem::check::is_check;
use crate::engine::make_engine_for;
use crate::io::run_dir::{Access, RunDir};
use crate::optim::runner::{run as run_optimisation, RunOptions};

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
    if !execute(root, plan)? {
        return Ok(ExitCode::from(130));
    }
    let fronts = finished_fronts(root, plan)?;
    summarise(root, plan, &fronts, out)?;
    Ok(ExitCode::SUCCESS)
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
    if is_check(&a.dir) {
        // a DEM check's plan (`dem check --plan`): its members are DEM runs
        return match task {
            Some(i) => super::dem::campaign_task(&a.dir, i, out),
            None => super::dem::campaign_run_all(&a.dir, out),
        };
    }
    let plan = read_plan(&a.dir)?;
    let Some(i) = task else {
        // Every member here, batched per generation; then the summary.
        let _owned = RunDir::acquire(&a.dir, CAMPAIGN_KIND, Access::Exclusive)?;
        if !execute(&a.dir, &plan)? {
            return Ok(ExitCode::from(130));
        }
        let fronts = finished_fronts(&a.dir, &plan)?;
        summarise(&a.dir, &plan, &fronts, out)?;
        return Ok(ExitCode::SUCCESS);
    };
    let n = plan.members.len();
    if i >= n {
        bail!("--task {i}: the plan in {} has {n} members (tasks 0..={})", a.dir.display(), n.saturating_sub(1));
    }
    let m = &plan.members[i];
    let dir = plan.member_dir(&a.dir, i);
    if let Ok(target) = std::fs::read_link(&dir) {
        bail!(
            "member {i} ({}): its folder {} is a link to {}; a member's folder lies inside its campaign: remove the link and run the task again",
            m.label,
            dir.display(),
            target.display()
        );
    }
    // Shared: the other tasks run beside this one; a one-process run or a gather excludes them.
    let _root = RunDir::acquire(&a.dir, CAMPAIGN_KIND, Access::Shared)?;
    if member_state(&dir) == MemberState::Finished {
        writeln!(out, "member {i} ({}) is already finished", m.label)?;
        return Ok(ExitCode::SUCCESS);
    }
    let engine = make_engine_for(plan.engine, &m.manifest.scenario)?;
    let resume = dir.join("checkpoint.json").exists();
    let opts = RunOptions {
        checkpoint_every: plan.checkpoint_every,
        progress: false,
        label: format!("member {i} ({}) ", m.label),
    };
    let o = run_optimisation(&dir, (!resume).then(|| m.manifest.clone()), resume, &engine, &opts)
        .with_context(|| format!("member {i} ({})", m.label))?;
    if o.interrupted {
        eprintln!("member {i} ({}): run the same command again to continue it", m.label);
        return Ok(ExitCode::from(130));
    }
    writeln!(
        out,
        "member {i} ({}) finished: {} generations ({}), {} front points",
        m.label,
        o.generations,
        o.termination,
        o.front.len()
    )?;
    Ok(ExitCode::SUCCESS)
}

fn gather(dir: &Path, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    if is_check(dir) {
        return super::dem::campaign_gather(dir, out);
    }
    let plan = read_plan(dir)?;
    let _owned = RunDir::acquire(dir, CAMPAIGN_KIND, Access::Exclusive)?;
    let fronts = finished_fronts(dir, &plan)?;
    summarise(dir, &plan, &fronts, out)?;
    Ok(ExitCode::SUCCESS)
}

fn status(dir: &Path, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    if is_check(dir) {
        return super::dem::campaign_status(dir, out);
    }
    let plan = read_plan(dir)?;
    let (mut finished, mut running, mut stopped, mut fresh) = (0, 0, 0, 0);
    writeln!(out, "{} ({}, {} members)", dir.display(), plan.command, plan.members.len())?;
    for (i, m) in plan.members.iter().enumerate() {
        let s = member_state(&plan.member_dir(dir, i));
        match s {
            MemberState::Finished => finished += 1,
            MemberState::Running => running += 1,
            MemberState::Checkpoint(_) => stopped += 1,
            MemberState::NotStarted => fresh += 1,
        }
        writeln!(out, "{i:>5}  {:<12} {s}", m.label)?;
    }
    writeln!(out, "finished {finished}, running {running}, stopped {stopped}, not started {fresh}")?;
    Ok(ExitCode::SUCCESS)
}

fn slurm(a: SlurmArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let exe = std::env::current_exe().and_then(std::fs::canonicalize).context("locating the sawtooth executable")?;
    let w = write_scripts(&a.dir, &a.settings(), &exe)?;
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
