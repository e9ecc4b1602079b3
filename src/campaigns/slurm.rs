//! Slurm job arrays for a campaign (`sawtooth campaign slurm`): an sbatch script whose task I
//! runs member I alone (`campaign run DIR --task I`), and a gather job that depends on the
//! whole array. The scripts are text made here from the plan and the settings; the CLI
//! only reads its flags and prints. A shared filesystem is assumed: every task reads the
//! plan and writes its member's folder under DIR.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};

use crate::io::atomic::write_atomic;
use crate::io::run_dir::mark_subfolder;
use crate::protocol::{unfinished, Campaign};

/// What the array asks of Slurm (`campaign slurm`'s flags).
#[derive(Clone, Debug, PartialEq)]
pub struct SlurmSettings {
    /// Slurm partition (None: the cluster's default).
    pub partition: Option<String>,
    /// Wall-time limit per task, in Slurm's format.
    pub time: Option<String>,
    /// CPU cores per task (the CPU engine's threads).
    pub cpus_per_task: u32,
    pub gpus_per_task: Option<u32>,
    /// At most this many tasks of the array at once (`--array=…%K`).
    pub max_parallel: Option<u32>,
    /// Only the members that are not finished.
    pub unfinished: bool,
}

impl Default for SlurmSettings {
    fn default() -> Self {
        SlurmSettings {
            partition: None,
            time: None,
            cpus_per_task: 1,
            gpus_per_task: None,
            max_parallel: None,
            unfinished: false,
        }
    }
}

impl SlurmSettings {
    /// Every setting Slurm can take as written: the partition and time go into the script
    /// verbatim, so they are held to Slurm's own alphabet.
    pub fn validate(&self) -> anyhow::Result<()> {
        if let Some(p) = &self.partition {
            check_token(
                "--partition",
                p,
                |c| c.is_ascii_alphanumeric() || "_-.,".contains(c),
                "a partition name is letters, digits, `_-.` (comma-separated)",
            )?;
        }
        if let Some(t) = &self.time {
            check_token(
                "--time",
                t,
                |c| c.is_ascii_digit() || c == ':' || c == '-',
                "Slurm's time format: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS",
            )?;
        }
        if self.cpus_per_task == 0 {
            bail!("--cpus-per-task must be at least 1");
        }
        if self.gpus_per_task == Some(0) {
            bail!("--gpus-per-task must be at least 1 (leave it out for none)");
        }
        if self.max_parallel == Some(0) {
            bail!("--max-parallel must be at least 1");
        }
        Ok(())
    }
}

/// `s` quoted for a POSIX shell; paths with a quote or a newline are refused.
pub fn shell_quote(what: &str, s: &str) -> anyhow::Result<String> {
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
pub fn array_spec(tasks: &[usize]) -> String {
    let contiguous = tasks.windows(2).all(|w| w[1] == w[0] + 1);
    match (tasks.first(), tasks.last()) {
        (Some(a), Some(b)) if contiguous && a != b => format!("{a}-{b}"),
        _ => tasks.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(","),
    }
}

/// The array script (one task per member in `tasks`) and the gather script, for the campaign
/// at `root` (absolute) planned by `command` with `members` members (an optimisation
/// campaign's plan or a DEM check's: both run through `campaign run/gather`), run by the
/// executable `exe`.
pub fn scripts(
    a: &SlurmSettings,
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
pub const LAST_SUBMIT: &str = "last-submit";

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

/// The scripts written for a campaign, ready to submit.
#[derive(Clone, Debug)]
pub struct Written {
    /// The campaign folder, absolute.
    pub root: PathBuf,
    pub array: PathBuf,
    pub gather: PathBuf,
    /// The members the array runs.
    pub tasks: Vec<usize>,
    /// With `unfinished`: the gather job of the last submission, which can never start once
    /// a task of its array failed or was cancelled.
    pub stale_gather: Option<String>,
}

/// For the campaign `c` planned in `dir`: check `s`, choose the tasks, and write
/// `dir/slurm/array.sbatch`, `dir/slurm/gather.sbatch` (run by `exe`) and the `dir/logs`
/// folder the tasks log to.
pub fn write_scripts(c: &dyn Campaign, dir: &Path, s: &SlurmSettings, exe: &Path) -> anyhow::Result<Written> {
    s.validate()?;
    let tasks: Vec<usize> = if s.unfinished { unfinished(c, dir) } else { (0..c.members()).collect() };
    if tasks.is_empty() {
        bail!(
            "every member of {} is finished: nothing to submit; summarise with `sawtooth campaign gather {}`",
            dir.display(),
            dir.display()
        );
    }
    let root = std::fs::canonicalize(dir).with_context(|| format!("resolving {}", dir.display()))?;
    let (root_s, exe_s) = (root.to_string_lossy().into_owned(), exe.to_string_lossy().into_owned());
    let (array, gather) = scripts(s, c.command(), c.members(), &root_s, &exe_s, &tasks)?;
    let sdir = root.join("slurm");
    // folders of the campaign's own, marked so that the campaign's folder counts them as its
    mark_subfolder(&sdir, "slurm")?;
    mark_subfolder(&root.join("logs"), "slurm-logs")?;
    let (array_path, gather_path) = (sdir.join("array.sbatch"), sdir.join("gather.sbatch"));
    write_atomic(&array_path, array.as_bytes())?;
    write_atomic(&gather_path, gather.as_bytes())?;
    let stale_gather = if s.unfinished {
        crate::io::bounded::read_text(&sdir.join(LAST_SUBMIT), &crate::schema::SUBMISSION_FILE)
            .ok()
            .and_then(|t| t.split_whitespace().find_map(|w| w.strip_prefix("gather=").map(String::from)))
    } else {
        None
    };
    Ok(Written { root, array: array_path, gather: gather_path, tasks, stale_gather })
}

/// The shell line that submits the array and then the gather job after it.
pub fn submit_command(w: &Written) -> anyhow::Result<String> {
    Ok(format!(
        "jid=$(sbatch --parsable {}) && sbatch --dependency=afterok:${{jid%%;*}} {}",
        shell_quote("path", &w.array.to_string_lossy())?,
        shell_quote("path", &w.gather.to_string_lossy())?
    ))
}

/// Submit the array, then the gather job depending on it; the two job ids, also kept in
/// `slurm/last-submit`.
pub fn submit(w: &Written) -> anyhow::Result<(String, String)> {
    let (ap, gp) = (w.array.to_string_lossy().into_owned(), w.gather.to_string_lossy().into_owned());
    let jid = sbatch(&[&ap])?;
    let dependency = format!("--dependency=afterok:{jid}");
    let gid = sbatch(&[&dependency, &gp])?;
    write_atomic(&w.root.join("slurm").join(LAST_SUBMIT), format!("array={jid} gather={gid}\n").as_bytes())?;
    Ok((jid, gid))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaigns::plan::{Plan, Study};
    use crate::engine::EngineKind;

    #[test]
    fn array_specs_are_ranges_or_lists() {
        assert_eq!(array_spec(&[0, 1, 2, 3]), "0-3");
        assert_eq!(array_spec(&[2]), "2");
        assert_eq!(array_spec(&[0, 2, 3]), "0,2,3");
    }

    fn plan() -> Plan {
        Plan::new("sawtooth gpu-sweep --alpha 0..10 --plan", Study::Sweep, EngineKind::Cpu, 5, vec![])
    }

    /// The array script runs one member per task from the campaign folder, with the cores
    /// Slurm gave it, resuming when requeued; the gather script runs once after it.
    #[test]
    fn the_array_script_runs_one_member_per_task() {
        let s = SlurmSettings {
            partition: Some("short".into()),
            time: Some("0-01:00:00".into()),
            cpus_per_task: 4,
            gpus_per_task: Some(1),
            max_parallel: Some(2),
            unfinished: false,
        };
        let (array, gather) =
            scripts(&s, &plan().command, plan().members.len(), "/scratch/sweep 1", "/opt/bin/sawtooth", &[0, 1, 2])
                .unwrap();
        let lines: Vec<&str> = array.lines().collect();
        assert_eq!(lines[0], "#!/bin/bash");
        for want in [
            "#SBATCH --job-name=sawtooth-sweep_1",
            "#SBATCH --array=0-2%2",
            "#SBATCH --output=/scratch/sweep 1/logs/%A_%a.out",
            "#SBATCH --requeue",
            "#SBATCH --cpus-per-task=4",
            "#SBATCH --gpus-per-task=1",
            "#SBATCH --partition=short",
            "#SBATCH --time=0-01:00:00",
            "export RAYON_NUM_THREADS=\"${SLURM_CPUS_PER_TASK:-1}\"",
            "exec '/opt/bin/sawtooth' campaign run '/scratch/sweep 1' --task \"$SLURM_ARRAY_TASK_ID\"",
        ] {
            assert!(lines.contains(&want), "missing `{want}` in\n{array}");
        }
        // every #SBATCH line comes before the first command, or sbatch ignores it
        let first_command = lines.iter().position(|l| l.starts_with("set -eu")).unwrap();
        assert!(lines.iter().rposition(|l| l.starts_with("#SBATCH")).unwrap() < first_command, "{array}");
        assert!(gather.contains("#SBATCH --job-name=sawtooth-sweep_1-gather\n"), "{gather}");
        assert!(gather.contains("#SBATCH --partition=short\n#SBATCH --time=0-01:00:00\n"), "{gather}");
        assert!(gather.ends_with("exec '/opt/bin/sawtooth' campaign gather '/scratch/sweep 1'\n"), "{gather}");
        assert!(!gather.contains("--gpus-per-task"), "the gather job needs no GPU: {gather}");
    }

    #[test]
    fn a_sparse_array_lists_its_tasks_and_defaults_ask_for_one_core() {
        let (array, _) =
            scripts(&SlurmSettings::default(), &plan().command, plan().members.len(), "/c", "/s", &[1, 4]).unwrap();
        assert!(array.contains("#SBATCH --array=1,4\n#SBATCH"), "{array}");
        assert!(array.contains("#SBATCH --cpus-per-task=1\n"), "{array}");
        assert!(!array.contains("--partition") && !array.contains("--time") && !array.contains("--gpus"), "{array}");
    }

    #[test]
    fn paths_that_a_shell_cannot_hold_quoted_are_refused() {
        let e = scripts(&SlurmSettings::default(), &plan().command, plan().members.len(), "/c/it's", "/s", &[0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("the campaign folder") && e.contains("quote"), "{e}");
    }

    #[test]
    fn settings_slurm_would_misread_are_refused_by_flag() {
        let bad = |f: fn(&mut SlurmSettings)| {
            let mut s = SlurmSettings::default();
            f(&mut s);
            s.validate().unwrap_err().to_string()
        };
        assert!(bad(|s| s.partition = Some("a b".into())).starts_with("--partition `a b`"));
        assert!(bad(|s| s.time = Some("1h".into())).starts_with("--time `1h`"));
        assert!(bad(|s| s.cpus_per_task = 0).starts_with("--cpus-per-task"));
        assert!(bad(|s| s.gpus_per_task = Some(0)).starts_with("--gpus-per-task"));
        assert!(bad(|s| s.max_parallel = Some(0)).starts_with("--max-parallel"));
        assert!(SlurmSettings::default().validate().is_ok());
    }
}
