//! The plan of a campaign and its members (`gpu-sweep`, `study` and `campaign` are its CLI):
//! a campaign is a folder with a plan (`plan.json`: the member runs, each an `optimize` run with its own
//! folder, seed and settings). Members run in lockstep threads so each generation is one
//! engine job (the local path), or one per process (`campaign run --task I`, a Slurm array
//! task); either way finished members are read back, unfinished ones resumed from their
//! checkpoints, missing ones started, and the summary is built from the members' files.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use crate::engine::{make_engine_for, BatchEvaluator, EngineKind};
use crate::io::atomic::write_atomic;
use crate::io::run_dir::{self, Access, RunDir};
use crate::optim::front::{read_pareto_csv, FrontPoint};
use crate::optim::lockstep::Lockstep;
use crate::optim::manifest::{read_manifest, Manifest};
use crate::optim::nsga2::load_checkpoint;
use crate::optim::runner::{is_finished, run, RunOptions};
pub use crate::protocol::MemberState;
use crate::protocol::Ran;
use crate::schema::{CHECKPOINT_EVERY, PLAN_MEMBERS};

/// The plan's file in a campaign folder.
pub const PLAN_FILE: &str = "plan.json";
/// The `io::run_dir` kind of a campaign folder.
pub const CAMPAIGN_KIND: &str = "campaign";
const PLAN_FORMAT: u32 = 1;

/// What a campaign's summary is.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Study {
    /// `gpu-sweep`: one member per conveyor angle.
    Sweep,
    /// `study repeatability`: one member per seed, compared at the target mass flow.
    Repeatability { target_mass_flow: f64 },
    /// `study sensitivity`: one member per grid point; `repeatability_ci` is (mean, half
    /// width) of W_spec from `--repeatability`, read when the plan was made.
    Sensitivity { target_mass_flow: f64, repeatability_ci: Option<(f64, f64)> },
}

/// One member run: an `optimize` run in `dir` (relative to the campaign folder).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Member {
    pub label: String,
    pub dir: String,
    pub manifest: Manifest,
}

/// A campaign's plan: everything needed to run any member alone and to summarise them.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Plan {
    pub format: u32,
    /// The command that made it (for people).
    pub command: String,
    pub study: Study,
    pub engine: EngineKind,
    pub checkpoint_every: u64,
    pub members: Vec<Member>,
}

impl Plan {
    pub fn new(command: &str, study: Study, engine: EngineKind, checkpoint_every: u64, members: Vec<Member>) -> Plan {
        Plan { format: PLAN_FORMAT, command: command.into(), study, engine, checkpoint_every, members }
    }

    pub fn member_dir(&self, root: &Path, i: usize) -> PathBuf {
        root.join(&self.members[i].dir)
    }

    fn to_json(&self) -> anyhow::Result<String> {
        Ok(serde_json::to_string_pretty(self)? + "\n")
    }
}

/// Read `root/plan.json`.
pub fn read_plan(root: &Path) -> anyhow::Result<Plan> {
    let path = root.join(PLAN_FILE);
    if !path.is_file() {
        bail!("{} is not a campaign folder: it has no {}", root.display(), path.display());
    }
    let text = crate::io::bounded::read_text(&path, &crate::schema::PLAN_FILE)?;
    parse_plan(&text, &path.display().to_string())
}

/// A plan's text checked by every rule ([`validate_plan`]); `name` is the file named in messages.
pub fn parse_plan(text: &str, name: &str) -> anyhow::Result<Plan> {
    let plan: Plan = serde_json::from_str(text).with_context(|| format!("reading {name}"))?;
    if plan.format != PLAN_FORMAT {
        bail!("{name}: plan format {} (this sawtooth reads format {PLAN_FORMAT})", plan.format);
    }
    validate_plan(&plan).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    Ok(plan)
}

/// Own `root` and write `plan` there; a folder holding a different plan is refused (a
/// campaign's members must all come from one plan).
pub fn write_plan(root: &Path, plan: &Plan) -> anyhow::Result<RunDir> {
    let owned = RunDir::acquire(root, CAMPAIGN_KIND, Access::Exclusive)?;
    let json = plan.to_json()?;
    let path = root.join(PLAN_FILE);
    // the folder is ours (its marker), so a plan.json in it is one we wrote; still read it
    // through the size bound, as a hand-edited or corrupted one may be anything
    if path.exists() {
        let old = crate::io::bounded::read_text(&path, &crate::schema::PLAN_FILE)?;
        if old != json {
            bail!(
                "{} holds a different plan ({}): a campaign's settings are fixed when it is planned; choose another --out",
                root.display(),
                path.display()
            );
        }
    } else {
        write_atomic(&path, json.as_bytes())?;
    }
    Ok(owned)
}

/// Where the member run in `dir` stands: running, finished, stopped at a checkpoint, or not started.
pub fn member_state(dir: &Path) -> MemberState {
    if run_dir::is_held(dir) {
        MemberState::Running
    } else if is_finished(dir) {
        MemberState::Finished
    } else if let Ok(s) = load_checkpoint(dir.join("checkpoint.json")) {
        MemberState::Checkpoint(s.generation)
    } else {
        MemberState::NotStarted
    }
}

/// The settings of a manifest without what a run adds (device, termination).
fn settings(m: &Manifest) -> anyhow::Result<String> {
    let mut m = m.clone();
    m.device.clear();
    m.termination = None;
    Ok(serde_json::to_string(&m)?)
}

/// Every member's final front, read from its folder; an error listing the members that are
/// not finished (a partial member is never summarised) or were run with other settings.
pub fn finished_fronts(root: &Path, plan: &Plan) -> anyhow::Result<Vec<Vec<FrontPoint>>> {
    let mut fronts = Vec::new();
    let mut missing = Vec::new();
    for (i, m) in plan.members.iter().enumerate() {
        let dir = plan.member_dir(root, i);
        match member_state(&dir) {
            MemberState::Finished => {
                let run = read_manifest(&dir)?;
                if settings(&run)? != settings(&m.manifest)? {
                    bail!(
                        "member {i} ({}): {} was run with other settings than the plan's; refusing to summarise it",
                        m.label,
                        dir.join("run.toml").display()
                    );
                }
                fronts.push(read_pareto_csv(&dir.join("pareto.csv"))?);
            }
            s => missing.push(format!("  {i:>4}  {}  {s}", m.label)),
        }
    }
    if !missing.is_empty() {
        bail!(
            "{} of {} members of {} are unfinished; no summary written:\n{}\nrun them (`sawtooth campaign run {} --task I`, or `sawtooth campaign slurm {} --unfinished --submit`) and gather again",
            missing.len(),
            plan.members.len(),
            root.display(),
            missing.join("\n"),
            root.display(),
            root.display()
        );
    }
    Ok(fronts)
}

/// Run member `i` alone in its folder (the caller holds the campaign's folder shared):
/// resumed from its checkpoint where it has one, not run again once finished.
pub fn run_member(root: &Path, plan: &Plan, i: usize) -> anyhow::Result<Ran> {
    let m = &plan.members[i];
    let dir = plan.member_dir(root, i);
    if member_state(&dir) == MemberState::Finished {
        return Ok(Ran::AlreadyFinished);
    }
    let engine = make_engine_for(plan.engine, &m.manifest.scenario)?;
    let resume = dir.join("checkpoint.json").exists();
    let opts = RunOptions {
        checkpoint_every: plan.checkpoint_every,
        progress: false,
        label: format!("member {i} ({}) ", m.label),
    };
    let o = run(&dir, (!resume).then(|| m.manifest.clone()), resume, &engine, &opts)
        .with_context(|| format!("member {i} ({})", m.label))?;
    if o.interrupted {
        return Ok(Ran::Interrupted);
    }
    Ok(Ran::Finished(format!("{} generations ({}), {} front points", o.generations, o.termination, o.front.len())))
}

/// Run every unfinished member in lockstep; `false` when interrupted (Ctrl-C / SIGTERM).
pub fn run_all(engine: &dyn BatchEvaluator, root: &Path, plan: &Plan, opts: &RunOptions) -> anyhow::Result<bool> {
    let todo: Vec<usize> = (0..plan.members.len()).filter(|&i| !is_finished(&plan.member_dir(root, i))).collect();
    let group = Lockstep::new(engine, todo.len());
    let results: Vec<anyhow::Result<bool>> = std::thread::scope(|scope| {
        let handles: Vec<_> = todo
            .iter()
            .enumerate()
            .map(|(slot, &i)| {
                let (group, m, dir) = (&group, &plan.members[i], plan.member_dir(root, i));
                // the runs advance together: the first one speaks for all (N lines would interleave)
                let others = todo.len() - 1;
                let label = if others > 0 {
                    format!("{}{} (+{others} more in lockstep) ", opts.label, m.label)
                } else {
                    format!("{}{} ", opts.label, m.label)
                };
                let opts = RunOptions { label, progress: opts.progress && slot == 0, ..opts.clone() };
                scope.spawn(move || {
                    let member = group.member(slot);
                    let resume = dir.join("checkpoint.json").exists();
                    run(&dir, (!resume).then(|| m.manifest.clone()), resume, &member, &opts)
                        .with_context(|| format!("member {i} ({})", m.label))
                        .map(|o| !o.interrupted)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("run thread panicked")).collect()
    });
    let mut done = true;
    for r in results {
        done &= r?;
    }
    Ok(done)
}

/// The local path: start the engine once and run every unfinished member of `plan` in
/// lockstep (log lines, no bars: they would interleave). `false` when Ctrl-C stopped the
/// runs (checkpoints are saved; rerunning the same command resumes them).
pub fn execute(root: &Path, plan: &Plan) -> anyhow::Result<bool> {
    let engine = match plan.members.first() {
        Some(m) => make_engine_for(plan.engine, &m.manifest.scenario)?,
        None => return Ok(true),
    };
    let opts = RunOptions { checkpoint_every: plan.checkpoint_every, progress: true, label: String::new() };
    let done = run_all(&engine, root, plan, &opts)?;
    if !done {
        eprintln!("interrupted: rerun the same command to resume every unfinished run");
    }
    Ok(done)
}

/// Every rule a plan must meet; the first broken one, naming its field. A plan read back is
/// input like any other (issue 34): a plan.json edited by hand (a member with `"pop":
/// 1000000000`, `particles: 4294967295`, `max_generations: 1e12`, no members at all) is
/// refused naming the member and its field before anything is allocated or run, by the same
/// rules as a new run's settings (`Manifest::validate`, `schema`).
pub fn validate_plan(plan: &Plan) -> Result<(), String> {
    PLAN_MEMBERS.check_usize("`members` (their number)", plan.members.len())?;
    // the command is copied into the Slurm scripts' comments: a line break there would be a command
    crate::schema::one_line("`command`", &plan.command)?;
    match &plan.study {
        Study::Sweep => {}
        Study::Repeatability { target_mass_flow } | Study::Sensitivity { target_mass_flow, .. } => {
            crate::schema::TARGET_MASS_FLOW.check("`study.target_mass_flow`", *target_mass_flow)?;
        }
    }
    if let Study::Sensitivity { repeatability_ci: Some((mean, half)), .. } = &plan.study {
        if !(mean.is_finite() && half.is_finite() && *half >= 0.0) {
            return Err(format!(
                "`study.repeatability_ci` ({mean}, {half}) must be a finite mean and a half-width >= 0"
            ));
        }
    }
    CHECKPOINT_EVERY.check("`checkpoint_every`", plan.checkpoint_every)?;
    let mut dirs = HashSet::new();
    for (i, m) in plan.members.iter().enumerate() {
        let at = |e: String| format!("member {i} ({}): {e}", m.label);
        m.manifest.validate().map_err(|e| at(format!("`manifest`: {e}")))?;
        if m.manifest.engine != plan.engine {
            return Err(at(format!(
                "`manifest.engine` {:?} differs from the plan's `engine` {:?}",
                m.manifest.engine, plan.engine
            )));
        }
        // the folder is named in messages, Slurm scripts and paths: a plain name inside the
        // campaign, no separator, no `..`, no newline or NUL
        let plain = !m.dir.is_empty()
            && m.dir.len() <= 128
            && !m.dir.starts_with('.')
            && m.dir.chars().all(|c| c.is_ascii_alphanumeric() || "._+-=".contains(c));
        if !plain {
            return Err(at(format!(
                "`dir` {:?} must be a plain folder name inside the campaign (at most 128 letters, digits, `._+-=`, not starting with `.`)",
                m.dir
            )));
        }
        crate::schema::one_line("`label`", &m.label).map_err(at)?;
        if !dirs.insert(m.dir.as_str()) {
            return Err(at(format!("`dir` `{}` is another member's too; each member has its own folder", m.dir)));
        }
    }
    Ok(())
}
