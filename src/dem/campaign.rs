//! A DEM campaign: R runs of one design with seeds s, s+1, …, run in parallel up to a number
//! of jobs, each in its own folder `run-NNN/` (the case, LIGGGHTS's output, `result.json`).
//! The plan is kept in `plan.json`; started again into the same folder with the same plan, a
//! killed campaign skips every run whose `result.json` exists and runs the rest. When all
//! runs are in, `dem.csv` (measured-data format) and `setup.toml` make the campaign readable
//! by `fit`, `diagnose` and `dem compare`.
//!
//! Everything read back is checked as input: the plan by [`Plan::check`] (a `runs` of
//! 4294967295 or `[dem] particles = 0` is refused naming the field before anything is
//! allocated), each run's dump by `gather::check_dump` before it becomes a result (a run
//! that blew up is a failed run, kept with its reason in `failure.txt`, and never a number
//! in `dem.csv`), each `result.json` by `gather::check_result` whenever it is read.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::case::{Case, ALL_LOST, DUMP, SETTLED, STROKE_TIME};
use super::conveyor::{Conveyor, SteadyRun};
use super::gather::{
    check_dump, check_result, measured_csv, parse_dump, parse_positions, reduce, setup_toml, DumpGrain, RunResult,
};
use super::losses::LeftBy;
use super::run::{find_liggghts, run_case};
use super::settings::DemSettings;
use crate::io::atomic::{clean_stale_temps, write_atomic};
use crate::io::bounded::{read_text, read_text_if_present};
use crate::io::run_dir::{declare_writes, hold_subfolder, mark_subfolder};
use crate::model::{Design, Scenario};
use crate::schema;

pub const PLAN: &str = "plan.json";
pub const RESULT: &str = "result.json";
pub const CSV: &str = "dem.csv";
pub const SETUP: &str = "setup.toml";
/// A failed run's reason, beside what it left (kept for inspection; removed when it runs again).
pub const FAILURE: &str = "failure.txt";
/// The `io::run_dir` kind of a campaign's folder (`dem run --out`, a DEM check's design).
pub const KIND: &str = "dem";
/// The `io::run_dir` kind of a run's folder inside a campaign.
pub const RUN_KIND: &str = "dem-run";
/// The DEM's restitution law measured on single grains of the campaign's case
/// (`super::impact::measure_law`), as a `[collision]` table; `dem compare` runs the model with it.
pub const LAW: &str = "law.toml";

/// A campaign's folder inside a run that writes its files from outside it (a DEM check's
/// design, a refinement's level): marked as a DEM campaign and as the owner of the campaign
/// files the run writes there, so that `dem compare`, `fit` and a resumed run read it as a
/// campaign of its own.
pub fn own_subcampaign_folder(dir: &Path) -> anyhow::Result<()> {
    mark_subfolder(dir, KIND)?;
    declare_writes(dir, &[PLAN, CSV, SETUP, LAW])
}

/// What determines a campaign; a folder holds one plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub scenario: Scenario,
    pub design: Design,
    pub settings: DemSettings,
    pub runs: u32,
    pub first_seed: u64,
    /// A stated sled return (delay s, speed m/s) from the setup's `[measurement]`.
    pub known_return: Option<(f64, f64)>,
    /// Steady conveying (`dem run --strokes K`, `super::conveyor`): K cycles on a periodic
    /// conveyor of `period_teeth` full teeth per run; 0: one stroke from a full tooth onto
    /// bare teeth (the model's d_avg).
    #[serde(default)]
    pub strokes: u32,
    #[serde(default)]
    pub period_teeth: u32,
}

impl Plan {
    pub fn case(&self, run: u32) -> Result<Case, String> {
        let seed = self.first_seed.checked_add(u64::from(run)).ok_or("`first_seed` + the run is beyond 2^64")?;
        Case::build(&self.scenario, &self.design, &self.settings, seed, self.known_return)
    }

    /// Every rule a plan must meet, read back or made (it is input like any other): the
    /// first broken one naming its field; else the first run's case (its mesh, grains and
    /// their mass are every run's).
    pub fn check(&self) -> Result<Case, String> {
        schema::DEM_RUNS.check_u32("`runs`", self.runs)?;
        if self.first_seed.checked_add(u64::from(self.runs)).is_none() {
            return Err(format!("`first_seed` {} + `runs` {} is beyond 2^64", self.first_seed, self.runs));
        }
        self.scenario.validate().map_err(|e| format!("`scenario`: {e}"))?;
        // a design of kilometre teeth would mesh into billions of facets before the model
        // refused it: the bounds of a design as a user gives one come first
        self.design.check_sensible(|i| format!("`design` {}", crate::model::design::DesignRow::COLUMNS[i]))?;
        self.settings.validate().map_err(|e| format!("`settings`: {e}"))?;
        // steady conveying's counts, as `dem run --strokes K --period-teeth P` bounds them
        if self.strokes != 0 {
            if !(3..=200).contains(&self.strokes) {
                return Err(format!("`strokes` must lie in [3, 200] (0: single strokes), got {}", self.strokes));
            }
            if !(2..=64).contains(&self.period_teeth) {
                return Err(format!("`period_teeth` must lie in [2, 64], got {}", self.period_teeth));
            }
        } else if self.period_teeth != 0 {
            return Err(format!("`period_teeth` {} belongs to a steady plan (`strokes` > 0)", self.period_teeth));
        }
        if let Some((delay, speed)) = self.known_return {
            schema::MOTION_DELAY.check("`known_return[0]` (motion_delay_s)", delay)?;
            schema::MOTION_RETURN_SPEED.check("`known_return[1]` (motion_return_speed_m_s)", speed)?;
        }
        self.case(0).map_err(|e| format!("`design`/`scenario`: {e}"))
    }
}

/// Read and check `dir/plan.json` (a campaign's plan); an error names the file and the field.
pub fn read_plan(dir: &Path) -> anyhow::Result<(Plan, Case)> {
    let path = dir.join(PLAN);
    parse_plan(&read_text(&path, &schema::PLAN_FILE)?, &path.display().to_string())
}

/// A plan's text checked by every rule ([`Plan::check`]); `name` is the file named in messages.
pub fn parse_plan(text: &str, name: &str) -> anyhow::Result<(Plan, Case)> {
    let plan: Plan = serde_json::from_str(text).with_context(|| format!("reading {name}"))?;
    let case = plan.check().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    Ok((plan, case))
}

/// Relative difference below which two designs' variables are the same design.
const SAME_DESIGN_REL: f64 = 1e-12;

impl Plan {
    /// The plan with the settings it leaves to the case stated as the case derives them:
    /// the mesh's teeth (the model's reach) and the grain diameter (the fill's mass over the
    /// grain count). A campaign's setup.toml states both, so a `dem run --config setup.toml`
    /// of a campaign whose plan left them derived is the same campaign ([`record_plan`]).
    fn resolved(&self) -> Result<Plan, String> {
        let case = self.case(0)?;
        let mut p = self.clone();
        p.settings.teeth = Some(case.teeth);
        p.settings.grain_diameter_m = Some(case.placement.diameter_m);
        Ok(p)
    }

    /// Whether `other` runs the same cases as this plan: equal, or equal once each states
    /// what it left to the case ([`Plan::resolved`]) and the designs agree to
    /// [`SAME_DESIGN_REL`] (setup.toml states the design in mm, and mm read back are not
    /// always the metres written, in the last bit).
    pub fn same_campaign(&self, other: &Plan) -> bool {
        if self == other {
            return true;
        }
        let (x, y) = (self.design.to_cli_units(), other.design.to_cli_units());
        if x.iter().zip(&y).any(|(a, b)| (a - b).abs() > SAME_DESIGN_REL * a.abs().max(b.abs())) {
            return false;
        }
        let other = Plan { design: self.design, ..other.clone() };
        matches!((self.resolved(), other.resolved()), (Ok(a), Ok(b)) if a == b)
    }

    /// Run `run`'s periodic conveyor (a steady plan's).
    pub fn conveyor(&self, run: u32) -> Result<Conveyor, String> {
        Conveyor::build(&self.scenario, self.case(run)?, self.period_teeth, self.strokes)
    }

    /// Whether the runs are steady conveying rather than single strokes.
    pub fn is_steady(&self) -> bool {
        self.strokes > 0
    }
}

/// The runs of a campaign without a result yet, said as a resumption where some have one.
fn runs_to_do<T>(done: &[Option<T>], say: &(dyn Fn(String) + Sync)) -> Vec<u32> {
    let todo: Vec<u32> = (0..done.len() as u32).filter(|r| done[*r as usize].is_none()).collect();
    if todo.len() < done.len() {
        say(format!("resuming: {} of {} runs already done", done.len() - todo.len(), done.len()));
    }
    todo
}

/// A steady run's result file (in place of [`RESULT`]).
pub const STEADY_RESULT: &str = "steady.json";

/// The steady results present in `dir`, in run order (None where a run has none yet).
pub fn steady_results(dir: &Path, runs: u32) -> anyhow::Result<Vec<Option<SteadyRun>>> {
    (0..runs)
        .map(|r| {
            let p = run_dir(dir, r).join(STEADY_RESULT);
            let Some(text) = read_text_if_present(&p, &schema::DEM_RESULT_FILE)? else { return Ok(None) };
            Ok(Some(serde_json::from_str(&text).with_context(|| format!("reading {}", p.display()))?))
        })
        .collect()
}

/// Run the steady campaign in `dir` (owned by the caller): every run's conveyor, up to `jobs`
/// at a time, skipping runs already done; every run's result once all are in.
pub fn run_steady(
    dir: &Path,
    plan: &Plan,
    jobs: usize,
    say: &(dyn Fn(String) + Sync),
) -> anyhow::Result<Vec<SteadyRun>> {
    let first = plan.conveyor(0).map_err(anyhow::Error::msg)?;
    let binary = find_liggghts()?;
    record_plan(dir, plan)?;
    let done = steady_results(dir, plan.runs)?;
    let todo = runs_to_do(&done, say);
    say(format!(
        "{} steady runs to do, {} at a time: {} cycles on a periodic conveyor of {} full teeth, {} grains of {:.0} um, time step {:.2e} s",
        todo.len(),
        jobs.max(1),
        plan.strokes,
        plan.period_teeth,
        first.grains.len(),
        first.tooth.placement.diameter_m * 1e6,
        first.tooth.contact.timestep_s
    ));
    let next = AtomicUsize::new(0);
    let failures: Mutex<Vec<String>> = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1).min(todo.len().max(1)) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(&r) = todo.get(k) else { break };
                if let Err(e) = one_steady_run(dir, plan, r, &binary, say) {
                    say(format!("run {} failed: {e:#}", r + 1));
                    failures.lock().expect("no panic holds it").push(format!("run {}: {e:#}", r + 1));
                }
            });
        }
    });
    let failures = failures.into_inner().expect("no panic holds it");
    if let Some(f) = failures.first() {
        bail!("{} of {} runs failed (rerun the same command to resume); first: {f}", failures.len(), todo.len());
    }
    let found = steady_results(dir, plan.runs)?;
    let missing = found.iter().filter(|r| r.is_none()).count();
    if missing > 0 {
        bail!("{}: {missing} of {} runs have no result", dir.display(), plan.runs);
    }
    Ok(found.into_iter().flatten().collect())
}

fn one_steady_run(dir: &Path, plan: &Plan, r: u32, binary: &Path, say: &(dyn Fn(String) + Sync)) -> anyhow::Result<()> {
    let conveyor = plan.conveyor(r).map_err(anyhow::Error::msg)?;
    let rd = run_dir(dir, r);
    // the run's folder is the campaign's own, as a single stroke's is: unmarked, the
    // campaign's folder held folders it did not write, and both resuming the campaign and
    // `dem compare` refused it
    mark_subfolder(&rd, RUN_KIND)?;
    let _only_writer = hold_subfolder(&rd)?;
    clean_stale_temps(&rd)?;
    conveyor.write(&rd)?;
    say(format!("run {} (seed {}) started", r + 1, conveyor.tooth.seed));
    let mut lines = crate::io::progress::Lines::new();
    let finished = run_case(binary, &rd, &mut |t| {
        if lines.due(0, 1) {
            say(format!("run {}: step {}, {} grains, rms speed {:.3} m/s", r + 1, t.step, t.atoms, t.rms_speed_m_s));
        }
    })?;
    let result = super::conveyor::reduce(&rd, &conveyor, finished.wall_s)?;
    write_atomic(&rd.join(STEADY_RESULT), serde_json::to_string_pretty(&result)?.as_bytes())?;
    let advances: Vec<String> = result.cycles.iter().map(|c| format!("{:.1}", c.advance_m * 1e3)).collect();
    let left = result.left_by.map_or(String::new(), |b| format!("; out of the box: {}", b.describe()));
    say(format!("run {} done in {:.1} s: advance per stroke {} mm{left}", r + 1, finished.wall_s, advances.join(", ")));
    Ok(())
}

pub fn run_dir(dir: &Path, run: u32) -> PathBuf {
    dir.join(format!("run-{:03}", run + 1))
}

/// Run `r`'s result in `dir`, checked against the plan's first case (`None`: not there yet).
/// A result that breaks a rule is an error naming the file and the field.
pub fn read_result(dir: &Path, plan: &Plan, case: &Case, r: u32) -> anyhow::Result<Option<RunResult>> {
    let p = run_dir(dir, r).join(RESULT);
    let Some(text) = read_text_if_present(&p, &schema::DEM_RESULT_FILE)? else { return Ok(None) };
    let result: RunResult = serde_json::from_str(&text).with_context(|| format!("reading {}", p.display()))?;
    check_result(&result, case, plan.first_seed, r).map_err(|e| {
        anyhow::anyhow!(
            "{}: {e}; it is not the result of this run (delete it, and the same command runs that seed again)",
            p.display()
        )
    })?;
    Ok(Some(result))
}

/// The results present in `dir`, in run order (None where a run has none yet), each checked.
pub fn results(dir: &Path, plan: &Plan, case: &Case) -> anyhow::Result<Vec<Option<RunResult>>> {
    (0..plan.runs).map(|r| read_result(dir, plan, case, r)).collect()
}

/// Whether a campaign recorded as `old` continues as `new`: the same campaign
/// ([`Plan::same_campaign`]), also where `new` states a mesh that `old` left to the case (a
/// plan recorded before plans stated their mesh keeps the mesh its runs were made on).
pub fn continues(old: &Plan, new: &Plan) -> bool {
    old.same_campaign(new)
        || (old.settings.teeth.is_none()
            && old
                .same_campaign(&Plan { settings: DemSettings { teeth: None, ..new.settings.clone() }, ..new.clone() }))
}

/// The plan a campaign in `dir` goes on with: the one recorded there where `plan`
/// [`continues`] it (its runs were made on it), else `plan` (which [`record_plan`] then
/// refuses where another is recorded).
pub fn recorded_or(dir: &Path, plan: &Plan) -> anyhow::Result<Plan> {
    let path = dir.join(PLAN);
    let Some(text) = read_text_if_present(&path, &schema::PLAN_FILE)? else { return Ok(plan.clone()) };
    let (old, _) = parse_plan(&text, &path.display().to_string())?;
    Ok(if continues(&old, plan) { old } else { plan.clone() })
}

/// Record `plan` in `dir`, or check that it is the plan already there.
pub fn record_plan(dir: &Path, plan: &Plan) -> anyhow::Result<()> {
    let path = dir.join(PLAN);
    let text = serde_json::to_string_pretty(plan)?;
    if std::fs::symlink_metadata(&path).is_ok() {
        let old: Plan = serde_json::from_str(&read_text(&path, &schema::PLAN_FILE)?)
            .with_context(|| format!("reading {}", path.display()))?;
        if !continues(&old, plan) {
            bail!(
                "{} holds a DEM campaign of another plan ({}): resuming needs the same config, design, [dem] settings, --runs and --seed; choose another --out",
                dir.display(),
                path.display()
            );
        }
        return Ok(());
    }
    write_atomic(&path, text.as_bytes())
}

/// Run the campaign in `dir` (owned by the caller) with up to `jobs` LIGGGHTS processes;
/// `say` gets progress lines. Runs already done are skipped. Every run is tried; the first
/// failure is returned after the others finish (their results are kept for a resume).
pub fn run(dir: &Path, plan: &Plan, jobs: usize, say: &(dyn Fn(String) + Sync)) -> anyhow::Result<Vec<RunResult>> {
    // cheap checks first: the plan holds, the case builds and the engine is there
    let first = plan.check().map_err(anyhow::Error::msg)?;
    let binary = find_liggghts()?;
    record_plan(dir, plan)?;
    let done = results(dir, plan, &first)?;
    let todo = runs_to_do(&done, say);
    say(format!(
        "{} runs to do, {} at a time: {} grains of {:.0} um, slab {:.2} mm, {} teeth, time step {:.2e} s (moduli softened x{:.2e})",
        todo.len(),
        jobs.max(1),
        first.placement.grains.len(),
        first.placement.diameter_m * 1e6,
        first.placement.depth_m * 1e3,
        first.teeth,
        first.contact.timestep_s,
        first.contact.softening
    ));
    let next = AtomicUsize::new(0);
    let failures: Mutex<Vec<String>> = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1).min(todo.len().max(1)) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(&r) = todo.get(k) else { break };
                if let Err(e) = one_run(dir, plan, &first, r, &binary, say) {
                    say(format!("run {} failed: {e:#}", r + 1));
                    failures.lock().expect("no panic holds it").push(format!("run {}: {e:#}", r + 1));
                }
            });
        }
    });
    let failures = failures.into_inner().expect("no panic holds it");
    if let Some(f) = failures.first() {
        bail!("{} of {} runs failed (rerun the same command to resume); first: {f}", failures.len(), todo.len());
    }
    let all = gather_checked(dir, plan, &first)?;
    if !dir.join(LAW).is_file() {
        say("measuring the DEM's restitution law on single grains of the case (dem impact)".into());
        // the impact runs' folder is the campaign's own, marked so that the campaign's folder counts it
        mark_subfolder(&dir.join("law"), "dem-law")?;
        let law = super::impact::measure_law(&first, &binary, &dir.join("law"), jobs)?;
        write_atomic(&dir.join(LAW), super::impact::law_toml(&law, &first).as_bytes())?;
    }
    let lost: usize = all.iter().map(|r| r.lost).sum();
    let left_by = LeftBy::summed(all.iter().map(|r| r.left_by));
    if lost > 0 {
        let grains: usize = all.iter().map(|r| r.grains).sum();
        say(format!(
            "warning: {lost} of {grains} grains were lost (left the mesh: behind tooth 1, past tooth {}, or out of the box{}); they count as not recovered",
            first.teeth,
            left_by.map(|b| format!("; out of the box: {}", b.describe())).unwrap_or_default()
        ));
        if let Some(b) = left_by.filter(|b| b.through_mesh > 0) {
            say(format!(
                "warning: {} grains passed through the mesh (last seen below its surface): a contact too soft or a step too long for these impacts; halve [dem] max_overlap_fraction (a stiffer contact, a shorter step) and compare before trusting this campaign",
                b.through_mesh
            ));
        }
    }
    Ok(all)
}

/// Run `r` of the campaign alone (one task of a job array, `dem check`'s members): the
/// plan recorded (or checked against the one there), the run skipped if its result exists.
/// `Ok(false)` when it was already done. No LIGGGHTS is looked for then, so a finished
/// member needs no engine.
pub fn run_one(dir: &Path, plan: &Plan, r: u32, say: &(dyn Fn(String) + Sync)) -> anyhow::Result<bool> {
    if r >= plan.runs {
        bail!("run {} of a campaign of {} runs", r + 1, plan.runs);
    }
    let first = plan.check().map_err(anyhow::Error::msg)?;
    record_plan(dir, plan)?;
    if read_result(dir, plan, &first, r)?.is_some() {
        return Ok(false);
    }
    let binary = find_liggghts()?;
    one_run(dir, plan, &first, r, &binary, say)?;
    Ok(true)
}

/// The campaign's measured DEM law ([`LAW`]), if it has one.
pub fn law(dir: &Path) -> anyhow::Result<Option<crate::model::Collision>> {
    let path = dir.join(LAW);
    let Some(text) = read_text_if_present(&path, &schema::CONFIG_FILE)? else { return Ok(None) };
    let file = crate::io::config::ConfigFile::parse(&text).with_context(|| format!("reading {}", path.display()))?;
    let collision = file.scenario().with_context(|| format!("reading {}", path.display()))?.collision;
    Ok(Some(collision))
}

/// Every run's result, once all are in, and the campaign's `dem.csv` and `setup.toml` written
/// from them (the same bytes whichever process ran the runs); an error naming the runs
/// without a result otherwise.
pub fn gather(dir: &Path, plan: &Plan) -> anyhow::Result<Vec<RunResult>> {
    let first = plan.check().map_err(anyhow::Error::msg)?;
    gather_checked(dir, plan, &first)
}

/// [`gather`] with the plan checked and its first case built.
fn gather_checked(dir: &Path, plan: &Plan, first: &Case) -> anyhow::Result<Vec<RunResult>> {
    let found = results(dir, plan, first)?;
    let missing: Vec<String> =
        found.iter().enumerate().filter(|(_, r)| r.is_none()).map(|(i, _)| format!("run {}", i + 1)).collect();
    if !missing.is_empty() {
        bail!("{}: {} of {} runs have no result yet ({})", dir.display(), missing.len(), plan.runs, missing.join(", "));
    }
    let all: Vec<RunResult> = found.into_iter().flatten().collect();
    let provenance = vec![
        format!(
            "DEM campaign (LIGGGHTS, `sawtooth dem run`): {} runs, seeds {}..{}; {} grains of {:.1} um in a {:.3} mm periodic slab; {} teeth of the mesh",
            plan.runs,
            plan.first_seed,
            plan.first_seed + plan.runs as u64 - 1,
            first.placement.grains.len(),
            first.placement.diameter_m * 1e6,
            first.placement.depth_m * 1e3,
            first.teeth
        ),
        "tooth masses in grams of the slab's grains after one stroke; input_mass = every grain placed".to_string(),
    ];
    write_atomic(&dir.join(CSV), measured_csv(&provenance, &all)?.as_bytes())?;
    let description = format!("DEM campaign of {} runs (docs/dem.md)", plan.runs);
    write_atomic(&dir.join(SETUP), setup_toml(first, plan.known_return, &description)?.as_bytes())?;
    Ok(all)
}

fn one_run(
    dir: &Path,
    plan: &Plan,
    first: &Case,
    r: u32,
    binary: &Path,
    say: &(dyn Fn(String) + Sync),
) -> anyhow::Result<()> {
    let case = plan.case(r).map_err(anyhow::Error::msg)?;
    let rd = run_dir(dir, r);
    mark_subfolder(&rd, RUN_KIND)?;
    // this run is the folder's only writer (another process on the same run is refused):
    // what a killed attempt left half-written is stale
    let _only_writer = hold_subfolder(&rd)?;
    // a process that held it before this one may have finished the run meanwhile
    if read_result(dir, plan, first, r)?.is_some() {
        return Ok(());
    }
    clean_stale_temps(&rd)?;
    remove_if_present(&rd.join(FAILURE))?;
    case.write(&rd)?;
    say(format!("run {} (seed {}) started", r + 1, case.seed));
    let mut lines = crate::io::progress::Lines::new();
    let finished = run_case(binary, &rd, &mut |t| {
        if lines.due(0, 1) {
            let phase =
                if t.stroke_time_s < 0.0 { "settling".to_string() } else { format!("t = {:.3} s", t.stroke_time_s) };
            say(format!("run {}: {phase}, {} grains, rms speed {:.3} m/s", r + 1, t.atoms, t.rms_speed_m_s));
        }
    })?;
    let result = match read_run(&case, &rd, finished.wall_s) {
        Ok(result) => result,
        Err(reason) => {
            // a failed run: its folder stays as LIGGGHTS left it, with the reason beside it
            write_atomic(&rd.join(FAILURE), format!("{reason}\n").as_bytes())?;
            bail!(
                "the DEM result of {} is not a believable run: {reason}; the folder is kept for inspection ({}), nothing of it enters {CSV}; rerun the same command to try the seed again",
                rd.display(),
                rd.join(FAILURE).display()
            );
        }
    };
    check_result(&result, first, plan.first_seed, r)
        .map_err(|e| anyhow::anyhow!("the DEM result of {}: {e}", rd.display()))?;
    let mut result = result;
    // the bed before the stroke (cases written before it was dumped have none)
    let settled = rd.join(SETTLED);
    if let Some(text) = read_text_if_present(&settled, &schema::DEM_DUMP_FILE)? {
        result.settled_xy_m = parse_positions(&text)
            .with_context(|| format!("reading {}", settled.display()))?
            .into_iter()
            .map(|p| [p[0], p[1]])
            .collect();
    }
    write_atomic(&rd.join(RESULT), serde_json::to_string_pretty(&result)?.as_bytes())?;
    say(format!(
        "run {} done in {:.1} s: d_avg {:.2} mm, {} of {} grains lost{}, {} still moving",
        r + 1,
        finished.wall_s,
        result.d_avg_m * 1e3,
        result.lost,
        result.grains,
        result.left_by.map(|b| format!(" ({} left the box: {})", result.left_box, b.describe())).unwrap_or_default(),
        result.moving
    ));
    Ok(())
}

/// What LIGGGHTS left in `rd`, checked and reduced to a result; the reason it is not a
/// believable run otherwise.
fn read_run(case: &Case, rd: &Path, wall_s: f64) -> Result<RunResult, String> {
    let at = |p: &Path, e: anyhow::Error| format!("{}: {e:#}", p.display());
    // every grain left the box (the deck stopped before a run LIGGGHTS would refuse): a
    // result with everything lost, which the rule credits nothing
    if rd.join(ALL_LOST).is_file() && !rd.join(DUMP).is_file() {
        let mut result = reduce(case, &[], 0.0, wall_s);
        result.left_by = left_by(case, rd, &[])?;
        return Ok(result);
    }
    let dump_path = rd.join(DUMP);
    let dump = read_text(&dump_path, &schema::DEM_DUMP_FILE).map_err(|e| at(&dump_path, e))?;
    let grains = parse_dump(&dump).map_err(|e| at(&dump_path, e))?;
    // a case written before the stop time was recorded ran every movement of the mesh
    let time_path = rd.join(STROKE_TIME);
    let stroke_time = match read_text_if_present(&time_path, &schema::DEM_STROKE_TIME_FILE)
        .map_err(|e| at(&time_path, e))?
    {
        Some(t) => Some(
            t.trim().parse::<f64>().map_err(|_| format!("{}: `{}` is not a number", time_path.display(), t.trim()))?,
        ),
        None => None,
    };
    check_dump(case, &grains, stroke_time)?;
    let mut result = reduce(case, &grains, stroke_time.unwrap_or(f64::INFINITY), wall_s);
    result.left_by = left_by(case, rd, &grains)?;
    Ok(result)
}

/// Where the grains missing from `grains` (the final dump, checked) left the box, from the
/// run's track; None when the case wrote none.
fn left_by(case: &Case, rd: &Path, grains: &[DumpGrain]) -> Result<Option<LeftBy>, String> {
    let mut deleted = vec![true; case.placement.grains.len()];
    for g in grains {
        if let Some(d) = (g.id as usize).checked_sub(1).and_then(|i| deleted.get_mut(i)) {
            *d = false;
        }
    }
    super::losses::read_losses(case, rd, &deleted).map_err(|e| format!("{e:#}"))
}

fn remove_if_present(p: &Path) -> anyhow::Result<()> {
    match std::fs::remove_file(p) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("removing {}", p.display()))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A single-stroke campaign of lunar solution C with `settings` (also refine's tests).
    pub(crate) fn lunar(settings: DemSettings) -> Plan {
        Plan {
            scenario: Scenario::lunar(),
            design: Design::lunar_solution_c(),
            settings,
            runs: 2,
            first_seed: 0,
            known_return: None,
            strokes: 0,
            period_teeth: 0,
        }
    }

    #[test]
    fn a_campaigns_setup_read_back_is_the_same_campaign_as_the_plan_that_left_its_mesh_and_grain_derived() {
        let derived = lunar(DemSettings { particles: 150, ..Default::default() });
        let case = derived.case(0).unwrap();
        // what setup.toml states: the mesh and the grain the case derived
        let stated = lunar(DemSettings {
            particles: 150,
            teeth: Some(case.teeth),
            grain_diameter_m: Some(case.placement.diameter_m),
            ..Default::default()
        });
        assert_ne!(derived, stated);
        assert!(derived.same_campaign(&stated) && stated.same_campaign(&derived));
        // the design as setup.toml's millimetres give it back: the last bit may differ
        let mut x = derived.design.to_cli_units();
        x[2] *= 1.0 + 1e-15;
        let read_back = Plan { design: Design::from_cli_units(x), ..stated.clone() };
        assert_ne!(read_back.design, derived.design);
        assert!(derived.same_campaign(&read_back));
        x[2] *= 1.0 + 1e-9;
        assert!(!derived.same_campaign(&Plan { design: Design::from_cli_units(x), ..stated.clone() }));
        // another mesh, another grain, another count or other seeds are other campaigns
        let longer = lunar(DemSettings { teeth: Some(case.teeth + 1), ..stated.settings.clone() });
        let coarser =
            lunar(DemSettings { grain_diameter_m: Some(case.placement.diameter_m * 1.01), ..stated.settings.clone() });
        let finer = lunar(DemSettings { particles: 300, ..Default::default() });
        for other in [&longer, &coarser, &finer, &Plan { first_seed: 1, ..derived.clone() }] {
            assert!(!derived.same_campaign(other), "{:?}", other.settings);
        }
        // a plan recorded with its mesh unset goes on under a command that now states one
        let mut rule = derived.clone();
        rule.settings.teeth = Some(case.teeth + 4);
        assert!(!derived.same_campaign(&rule) && continues(&derived, &rule));
        assert!(!continues(
            &stated,
            &Plan {
                settings: DemSettings { teeth: Some(case.teeth + 4), ..stated.settings.clone() },
                ..stated.clone()
            }
        ));
        assert!(!continues(&derived, &Plan { first_seed: 1, ..rule.clone() }));
        // and the folder's recorded plan is the one it goes on with
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(recorded_or(dir.path(), &rule).unwrap(), rule, "nothing recorded: the new plan");
        record_plan(dir.path(), &derived).unwrap();
        assert_eq!(recorded_or(dir.path(), &rule).unwrap(), derived);
        record_plan(dir.path(), &rule).unwrap();
        let other = Plan { first_seed: 1, ..rule.clone() };
        assert_eq!(recorded_or(dir.path(), &other).unwrap(), other);
        assert!(record_plan(dir.path(), &other).is_err());
    }
}
