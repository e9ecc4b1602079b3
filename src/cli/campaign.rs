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
use crate::campaigns::summarise;
use crate::dem::check::is_check;
use crate::engine::make_engine_for;
use crate::io::atomic::write_atomic;
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
    #[arg(long, default_value_t = 1)]
    pub cpus_per_task: u32,
    /// GPUs per task (for --engine gpu/auto plans).
    #[arg(long)]
    pub gpus_per_task: Option<u32>,
    /// At most K tasks of the array running at once (`--array=…%K`).
    #[arg(long)]
    pub max_parallel: Option<u32>,
    /// Only the members that are not finished (to resubmit after a cancel or a failure).
    #[arg(long)]
    pub unfinished: bool,
    /// Submit with sbatch instead of only printing the commands.
    #[arg(long)]
    pub submit: bool,
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
    // Shared: the other tasks run beside this one; a one-process run or a gather excludes them.
    let _root = RunDir::acquire(&a.dir, CAMPAIGN_KIND, Access::Shared)?;
    let m = &plan.members[i];
    let dir = plan.member_dir(&a.dir, i);
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

/// `s` quoted for a POSIX shell; paths with a quote or a newline are refused.
fn shell_quote(what: &str, s: &str) -> anyhow::Result<String> {
    if s.contains('\'') || s.contains('\n') {
        bail!("{what} `{s}` contains a quote or a newline; move the campaign to a plain path");
    }
    Ok(format!("'{s}'"))
}

fn check_token(flag: &str, v: &str, ok: impl Fn(char) -> bool, rule: &str) -> anyhow::Result<()> {
    if v.is_empty() || !v.chars().all(ok) {
        bail!("{flag} `{v}`: {rule}");
    }
    Ok(())
}

/// `0-3` for a contiguous run, else `0,2,5`.
fn array_spec(tasks: &[usize]) -> String {
    let contiguous = tasks.windows(2).all(|w| w[1] == w[0] + 1);
    match (tasks.first(), tasks.last()) {
        (Some(a), Some(b)) if contiguous && a != b => format!("{a}-{b}"),
        _ => tasks.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(","),
    }
}

/// The array and gather scripts of a plan made by `command` with `members` members (an
/// optimisation campaign's or a DEM check's: both run `campaign run/gather`).
fn scripts(
    a: &SlurmArgs,
    command: &str,
    members: usize,
    root: &str,
    exe: &str,
    tasks: &[usize],
) -> anyhow::Result<(String, String)> {
    let q_root = shell_quote("the campaign folder", root)?;
    let q_exe = shell_quote("the sawtooth executable", exe)?;
    let name =
        Path::new(root).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "campaign".into());
    let name: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect();
    let mut common = String::new();
    if let Some(p) = &a.partition {
        common.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(t) = &a.time {
        common.push_str(&format!("#SBATCH --time={t}\n"));
    }
    let mut array = format!(
        "#!/bin/bash\n\
         # Written by `sawtooth campaign slurm`: one array task per member of the campaign\n\
         # {root} ({}, {} members). Task I runs member I alone and resumes it from its own\n\
         # checkpoint when requeued; DIR and the executable must be on a filesystem every node sees.\n\
         #SBATCH --job-name=sawtooth-{name}\n\
         #SBATCH --array={}{}\n\
         #SBATCH --output={root}/logs/%A_%a.out\n\
         #SBATCH --open-mode=append\n\
         #SBATCH --requeue\n\
         #SBATCH --ntasks=1\n\
         #SBATCH --cpus-per-task={}\n",
        command,
        members,
        array_spec(tasks),
        a.max_parallel.map(|k| format!("%{k}")).unwrap_or_default(),
        a.cpus_per_task
    );
    if let Some(g) = a.gpus_per_task {
        array.push_str(&format!("#SBATCH --gpus-per-task={g}\n"));
    }
    array.push_str(&common);
    array.push_str(&format!(
        "set -eu\n\
         # the CPU engine's threads: the cores Slurm gave this task\n\
         export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-1}}\"\n\
         exec {q_exe} campaign run {q_root} --task \"$SLURM_ARRAY_TASK_ID\"\n"
    ));
    let gather = format!(
        "#!/bin/bash\n\
         # Written by `sawtooth campaign slurm`: the summary of {root}, run once every array\n\
         # task has succeeded (submitted with --dependency=afterok:ARRAY_JOB).\n\
         #SBATCH --job-name=sawtooth-{name}-gather\n\
         #SBATCH --output={root}/logs/gather_%j.out\n\
         #SBATCH --ntasks=1\n\
         #SBATCH --cpus-per-task=1\n\
         {common}\
         set -eu\n\
         exec {q_exe} campaign gather {q_root}\n"
    );
    Ok((array, gather))
}

/// The job ids of the last `--submit`, in DIR/slurm.
const LAST_SUBMIT: &str = "last-submit";

/// Run sbatch; the job id it prints with --parsable (`ID` or `ID;CLUSTER`).
fn sbatch(args: &[&str]) -> anyhow::Result<String> {
    let o = std::process::Command::new("sbatch").arg("--parsable").args(args).output().context(
        "--submit: running sbatch (is this a Slurm login node? without --submit the scripts are only written)",
    )?;
    if !o.status.success() {
        bail!("--submit: sbatch {} failed: {}", args.join(" "), String::from_utf8_lossy(&o.stderr).trim());
    }
    let text = String::from_utf8_lossy(&o.stdout);
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        bail!("--submit: sbatch printed `{}`, not a job id", text.trim());
    }
    Ok(id)
}

fn slurm(a: SlurmArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    // what the scripts need of the plan: its command, its members, which are finished
    let (command, members, finished): (String, usize, Vec<bool>) = if is_check(&a.dir) {
        let p = crate::dem::check::read_plan(&a.dir)?;
        (p.command.clone(), p.members(), (0..p.members()).map(|i| p.member_done(&a.dir, i)).collect())
    } else {
        let p = read_plan(&a.dir)?;
        let done = (0..p.members.len()).map(|i| member_state(&p.member_dir(&a.dir, i)) == MemberState::Finished);
        (p.command.clone(), p.members.len(), done.collect())
    };
    if let Some(p) = &a.partition {
        check_token(
            "--partition",
            p,
            |c| c.is_ascii_alphanumeric() || "_-.,".contains(c),
            "a partition name is letters, digits, `_-.` (comma-separated)",
        )?;
    }
    if let Some(t) = &a.time {
        check_token(
            "--time",
            t,
            |c| c.is_ascii_digit() || c == ':' || c == '-',
            "Slurm's time format: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS",
        )?;
    }
    if a.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    if a.gpus_per_task == Some(0) {
        bail!("--gpus-per-task must be at least 1 (leave it out for none)");
    }
    if a.max_parallel == Some(0) {
        bail!("--max-parallel must be at least 1");
    }
    let tasks: Vec<usize> = (0..members).filter(|&i| !a.unfinished || !finished[i]).collect();
    if tasks.is_empty() {
        bail!(
            "every member of {} is finished: nothing to submit; summarise with `sawtooth campaign gather {}`",
            a.dir.display(),
            a.dir.display()
        );
    }
    let root = std::fs::canonicalize(&a.dir).with_context(|| format!("resolving {}", a.dir.display()))?;
    let exe = std::env::current_exe().and_then(std::fs::canonicalize).context("locating the sawtooth executable")?;
    let (root_s, exe_s) = (root.to_string_lossy().into_owned(), exe.to_string_lossy().into_owned());
    let (array, gather) = scripts(&a, &command, members, &root_s, &exe_s, &tasks)?;
    let sdir = root.join("slurm");
    std::fs::create_dir_all(&sdir).with_context(|| format!("creating {}", sdir.display()))?;
    std::fs::create_dir_all(root.join("logs")).with_context(|| format!("creating {}", root.join("logs").display()))?;
    let (array_path, gather_path) = (sdir.join("array.sbatch"), sdir.join("gather.sbatch"));
    write_atomic(&array_path, array.as_bytes())?;
    write_atomic(&gather_path, gather.as_bytes())?;
    let (ap, gp) = (array_path.to_string_lossy().into_owned(), gather_path.to_string_lossy().into_owned());
    writeln!(out, "wrote {ap} ({} tasks: {}) and {gp}", tasks.len(), array_spec(&tasks))?;
    let last = sdir.join(LAST_SUBMIT);
    if a.unfinished {
        if let Some(g) = std::fs::read_to_string(&last)
            .ok()
            .and_then(|t| t.split_whitespace().find_map(|w| w.strip_prefix("gather=").map(String::from)))
        {
            writeln!(out, "note: the gather job of the last submission ({g}) can never start once a task of its array failed or was cancelled; if squeue still shows it: scancel {g}")?;
        }
    }
    if !a.submit {
        writeln!(out, "submit with:")?;
        writeln!(
            out,
            "  jid=$(sbatch --parsable {}) && sbatch --dependency=afterok:${{jid%%;*}} {}",
            shell_quote("path", &ap)?,
            shell_quote("path", &gp)?
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    let jid = sbatch(&[&ap])?;
    let dependency = format!("--dependency=afterok:{jid}");
    let gid = sbatch(&[&dependency, &gp])?;
    write_atomic(&last, format!("array={jid} gather={gid}\n").as_bytes())?;
    writeln!(out, "submitted array job {jid} (tasks {}) and gather job {gid} ({dependency})", array_spec(&tasks))?;
    writeln!(out, "logs in {}/logs; follow with `sawtooth campaign status {}`", root_s, root_s)?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::array_spec;

    #[test]
    fn array_specs_are_ranges_or_lists() {
        assert_eq!(array_spec(&[0, 1, 2, 3]), "0-3");
        assert_eq!(array_spec(&[2]), "2");
        assert_eq!(array_spec(&[0, 2, 3]), "0,2,3");
    }
}
