//! Shared machinery of the multi-run commands (`gpu-sweep`, `study`, `campaign`): a campaign
//! is a folder with a plan (`plan.json`: the member runs, each an `optimize` run with its own
//! folder, seed and settings). Members run in lockstep threads so each generation is one
//! engine job (the local path), or one per process (`campaign run --task I`, a Slurm array
//! task); either way finished members are read back, unfinished ones resumed from their
//! checkpoints, missing ones started, and the summary is built from the members' files.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use crate::engine::{make_engine_for, BatchEvaluator, EngineKind};
use crate::io::atomic::write_atomic;
use crate::io::run_dir::{self, Access, RunDir};
use crate::optim::front::{read_pareto_csv, FrontPoint};
use crate::optim::lockstep::Lockstep;
use crate::optim::nsga2::load_checkpoint;
use crate::optim::runner::{is_finished, read_manifest, run, Manifest, RunOptions};

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
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{} is not a campaign folder: cannot read {}", root.display(), path.display()))?;
    let plan: Plan = serde_json::from_str(&text).with_context(|| format!("reading {}", path.display()))?;
    if plan.format != PLAN_FORMAT {
        bail!("{}: plan format {} (this sawtooth reads format {PLAN_FORMAT})", path.display(), plan.format);
    }
    for (i, m) in plan.members.iter().enumerate() {
        let p = Path::new(&m.dir);
        if m.dir.is_empty() || p.is_absolute() || p.components().any(|c| !matches!(c, std::path::Component::Normal(_)))
        {
            bail!("{}: member {i}: dir `{}` must be a plain folder name inside the campaign", path.display(), m.dir);
        }
    }
    Ok(plan)
}

/// A campaign folder written by sawtooth before plans existed: it holds member runs
/// (`alpha_*`, `run_*`, `grid_*` folders with a run.toml).
fn legacy_campaign(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|es| {
        es.filter_map(|e| e.ok()).any(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            ["alpha_", "run_", "grid_"].iter().any(|p| name.starts_with(p)) && e.path().join("run.toml").exists()
        })
    })
}

/// Own `root` and write `plan` there; a folder holding a different plan is refused (a
/// campaign's members must all come from one plan).
pub fn write_plan(root: &Path, plan: &Plan) -> anyhow::Result<RunDir> {
    let owned = RunDir::acquire(root, CAMPAIGN_KIND, Access::Exclusive, legacy_campaign)?;
    let json = plan.to_json()?;
    let path = root.join(PLAN_FILE);
    match std::fs::read_to_string(&path) {
        Ok(old) if old == json => {}
        Ok(_) => bail!(
            "{} holds a different plan ({}): a campaign's settings are fixed when it is planned; choose another --out",
            root.display(),
            path.display()
        ),
        Err(_) => write_atomic(&path, json.as_bytes())?,
    }
    Ok(owned)
}

/// Where a member stands.
#[derive(Debug, Clone, PartialEq)]
pub enum MemberState {
    Finished,
    /// A process holds its folder now.
    Running,
    /// Stopped (or pre-empted) with a checkpoint at this generation.
    Checkpoint(u64),
    NotStarted,
}

impl std::fmt::Display for MemberState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MemberState::Finished => write!(f, "finished"),
            MemberState::Running => write!(f, "running"),
            MemberState::Checkpoint(g) => write!(f, "stopped at generation {g} (checkpoint)"),
            MemberState::NotStarted => write!(f, "not started"),
        }
    }
}

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
                let opts = RunOptions { label: format!("{}{} ", opts.label, m.label), ..opts.clone() };
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
    let opts = RunOptions { checkpoint_every: plan.checkpoint_every, progress: false, label: String::new() };
    let done = run_all(&engine, root, plan, &opts)?;
    if !done {
        eprintln!("interrupted: rerun the same command to resume every unfinished run");
    }
    Ok(done)
}

/// Summary files and table of a campaign whose members are all finished.
pub fn summarise(root: &Path, plan: &Plan, fronts: &[Vec<FrontPoint>], out: &mut dyn Write) -> anyhow::Result<()> {
    match &plan.study {
        Study::Sweep => super::sweep::summarise(root, plan, fronts, out),
        Study::Repeatability { target_mass_flow } => {
            super::study::summarise_repeatability(root, plan, *target_mass_flow, fronts, out)
        }
        Study::Sensitivity { target_mass_flow, repeatability_ci } => {
            super::study::summarise_sensitivity(root, plan, *target_mass_flow, *repeatability_ci, fronts, out)
        }
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

/// One panel of `panels_svg`: its name and named series (one y value per x).
pub type Panel<'a> = (&'a str, Vec<(&'a str, Vec<f64>)>);

/// A small multi-panel line plot (x, several named series per panel), hand-written SVG.
pub fn panels_svg(title: &str, x_label: &str, x: &[f64], panels: &[Panel]) -> String {
    let (w, ph, m) = (640.0, 200.0, 60.0);
    let h = 40.0 + panels.len() as f64 * (ph + 30.0) + 30.0;
    let colours = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e"];
    let (x0, x1) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let span = (x1 - x0).max(1e-12);
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="11">"#
    );
    s.push_str(&format!(
        r#"<rect width="{w}" height="{h}" fill="white"/><text x="{m}" y="22" font-size="13">{title}</text>"#
    ));
    for (k, (name, series)) in panels.iter().enumerate() {
        let top = 40.0 + k as f64 * (ph + 30.0);
        let vals: Vec<f64> = series.iter().flat_map(|(_, v)| v.iter().cloned()).filter(|v| v.is_finite()).collect();
        let (y0, y1) = vals.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        let (y0, y1) = if y0.is_finite() { (y0, y1.max(y0 + 1e-12)) } else { (0.0, 1.0) };
        let sx = |v: f64| m + (v - x0) / span * (w - 2.0 * m);
        let sy = |v: f64| top + ph - (v - y0) / (y1 - y0) * ph;
        s.push_str(&format!(
            r#"<rect x="{m}" y="{top}" width="{}" height="{ph}" fill="none" stroke="black"/>"#,
            w - 2.0 * m
        ));
        s.push_str(&format!(r#"<text x="{}" y="{}">{name}: {y0:.4e} .. {y1:.4e}</text>"#, m + 4.0, top + 12.0));
        for (c, (label, v)) in series.iter().enumerate() {
            let pts: Vec<String> = x
                .iter()
                .zip(v)
                .filter(|(_, y)| y.is_finite())
                .map(|(a, b)| format!("{:.2},{:.2}", sx(*a), sy(*b)))
                .collect();
            let col = colours[c % colours.len()];
            s.push_str(&format!(
                r#"<polyline points="{}" fill="none" stroke="{col}" stroke-width="1.5"/>"#,
                pts.join(" ")
            ));
            s.push_str(&format!(
                r#"<text x="{}" y="{}" fill="{col}">{label}</text>"#,
                w - m - 120.0,
                top + 14.0 + 12.0 * c as f64
            ));
        }
    }
    s.push_str(&format!(
        r#"<text x="{}" y="{}" text-anchor="middle">{x_label} ({x0} .. {x1})</text></svg>"#,
        w / 2.0,
        h - 10.0
    ));
    s.push('\n');
    s
}
