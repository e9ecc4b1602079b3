//! An optimisation's finalists held against the DEM: the picks A, B, C (Table 5.2) and K
//! more front designs spread over the front's mass flow, each run in DEM with several seeds;
//! the DEM's d_avg goes through the same performance model (D.7: ṁ ∝ d_avg, W_spec = P/ṁ)
//! and, where the run had requirements, the same verdicts.
//!
//! Every design is run at the slope its front figures are at (the worst slope of a run over
//! several). A check is a plan ([`CheckPlan`], `plan.json` in the check's folder): its
//! finalists, each with the DEM campaign of its seeds in a folder of its own, and its members,
//! one DEM run each (finalist × seed). It is a kind of `protocol::Campaign`: the members run
//! here one design after another ([`check`], `campaign run DIR`) or one per process
//! (`campaign run DIR --task I`: a Slurm array task, [`run_member`]); either way [`gather`]
//! builds `check.json` from the runs' result files, so both give the same report, and a
//! killed check resumes run by run.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::campaign::{self, Plan};
use super::compare::Spread;
use super::gather::RunResult;
use super::settings::DemSettings;
use crate::io::atomic::write_atomic;
use crate::io::run_dir::{kind_of, Access, RunDir};
use crate::model::design::DesignRow;
use crate::model::performance::performance;
use crate::model::prepare;
use crate::model::requirements::{Limit, Requirements};
use crate::optim::front::{picks, read_pareto_csv, FrontPoint};
use crate::optim::manifest::read_manifest;
use crate::protocol::{Campaign, MemberState, Ran};

/// The `io::run_dir` kind of a check's folder.
pub const CHECK_KIND: &str = "dem-check";
/// The plan's file in a check's folder.
pub const CHECK_PLAN: &str = "plan.json";
/// The report's file in a check's folder.
pub const CHECK_JSON: &str = "check.json";
/// The plan format this sawtooth writes and reads.
pub const CHECK_PLAN_FORMAT: u32 = 1;
/// Most members a plan may hold: beyond this a plan.json is a typo or an edit, not a check
/// (a Slurm array of a million tasks is refused by every cluster anyway).
const MAX_MEMBERS: usize = 100_000;

#[derive(Clone, Debug, Serialize)]
pub struct DesignCheck {
    pub label: String,
    /// The design's eight variables, named with their units as in every file (`l_c_mm` … `a_m_s2`).
    pub design: DesignRow,
    pub alpha_deg: f64,
    pub model_d_avg_mm: f64,
    pub dem_d_avg_mm: Spread,
    pub model_m_dot_kg_h: f64,
    pub dem_m_dot_kg_h: f64,
    pub model_w_spec_j_kg: f64,
    pub dem_w_spec_j_kg: Option<f64>,
    pub dem_lost_pct: f64,
    /// The requirements' verdicts (None without requirements).
    pub model_compliant: Option<bool>,
    pub dem_compliant: Option<bool>,
    pub dem_binding: Option<String>,
    /// The operating point under the requirements (feed rate at the target, or lower where
    /// the power limit binds), kg/h and W: the model's from the run, the DEM's judged again.
    pub model_m_dot_op_kg_h: Option<f64>,
    pub dem_m_dot_op_kg_h: Option<f64>,
    pub dem_p_op_w: Option<f64>,
    pub dem_operating_limit: Option<Limit>,
    pub dem_s_per_run: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct CheckReport {
    pub run_dir: String,
    pub seeds: u32,
    pub particles: u32,
    pub designs: Vec<DesignCheck>,
}

/// One design to check: the optimisation's figures for it and its DEM campaign.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finalist {
    /// `A`, `B`, `C` (a design picked twice: `A+C`) or `front-K`; also its folder's name.
    pub label: String,
    pub model_d_avg_m: f64,
    pub model_m_dot_kg_s: f64,
    pub model_w_spec_j_kg: f64,
    pub model_compliant: Option<bool>,
    /// The model's operating feed rate under the run's requirements, kg/h.
    pub model_m_dot_op_kg_h: Option<f64>,
    /// The design's DEM campaign at the slope of its front figures; its runs are members.
    pub campaign: Plan,
}

/// Everything a member needs to run alone and the gather needs to report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckPlan {
    pub format: u32,
    /// The command that made it (for people).
    pub command: String,
    /// The `optimize` run whose finalists these are.
    pub run_dir: String,
    pub seeds: u32,
    pub particles: u32,
    /// The run's requirements, judged again with the DEM's figures.
    pub requirements: Option<Requirements>,
    pub finalists: Vec<Finalist>,
}

impl CheckPlan {
    /// Members: one DEM run per finalist and seed, finalist by finalist.
    pub fn members(&self) -> usize {
        self.finalists.len() * self.seeds as usize
    }

    /// Member `i` as (finalist index, run index within its campaign).
    pub fn member(&self, i: usize) -> (usize, u32) {
        (i / self.seeds as usize, (i % self.seeds as usize) as u32)
    }

    pub fn member_label(&self, i: usize) -> String {
        let (f, r) = self.member(i);
        let c = &self.finalists[f].campaign;
        format!("{} seed {}", self.finalists[f].label, c.first_seed + r as u64)
    }

    /// The finalist's campaign folder.
    pub fn finalist_dir(&self, root: &Path, f: usize) -> PathBuf {
        root.join(&self.finalists[f].label)
    }

    /// The member's run folder (`LABEL/run-NNN`).
    pub fn member_dir(&self, root: &Path, i: usize) -> PathBuf {
        let (f, r) = self.member(i);
        campaign::run_dir(&self.finalist_dir(root, f), r)
    }

    pub fn member_done(&self, root: &Path, i: usize) -> bool {
        self.member_dir(root, i).join(campaign::RESULT).is_file()
    }

    /// Every rule a plan read back must meet (it is input like any other): the first broken
    /// one, naming its field.
    pub fn validate(&self) -> Result<(), String> {
        if self.format != CHECK_PLAN_FORMAT {
            return Err(format!("`format` {} (this sawtooth reads format {CHECK_PLAN_FORMAT})", self.format));
        }
        crate::schema::DEM_SEEDS.check_u32("`seeds`", self.seeds)?;
        // printed in tables and copied into the Slurm scripts' comments
        crate::schema::one_line("`command`", &self.command)?;
        crate::schema::one_line("`run_dir`", &self.run_dir)?;
        crate::schema::DEM_PARTICLES.check_u32("`particles`", self.particles)?;
        if let Some(r) = &self.requirements {
            r.validate().map_err(|e| format!("`requirements`: {e}"))?;
        }
        if self.finalists.is_empty() || self.members() > MAX_MEMBERS {
            return Err(format!(
                "`finalists` ({}) x `seeds` ({}) must give 1 to {MAX_MEMBERS} members",
                self.finalists.len(),
                self.seeds
            ));
        }
        let mut labels = std::collections::HashSet::new();
        for (i, f) in self.finalists.iter().enumerate() {
            let at = |e: String| format!("finalist {i} ({}): {e}", f.label);
            let plain = !f.label.is_empty()
                && f.label.len() <= 64
                && f.label.chars().all(|c| c.is_ascii_alphanumeric() || "+-_".contains(c));
            if !plain {
                return Err(at("`label` must be a plain folder name (letters, digits, `+-_`)".into()));
            }
            if !labels.insert(f.label.as_str()) {
                return Err(at("`label` is another finalist's too; each has its own folder".into()));
            }
            if f.campaign.runs != self.seeds {
                return Err(at(format!("`campaign.runs` {} differs from `seeds` {}", f.campaign.runs, self.seeds)));
            }
            if f.campaign.settings.particles != self.particles {
                return Err(at(format!(
                    "`campaign.settings.particles` {} differs from `particles` {}",
                    f.campaign.settings.particles, self.particles
                )));
            }
            // the optimisation's figures are printed beside the DEM's: numbers, not NaN
            for (name, v) in [
                ("model_d_avg_m", Some(f.model_d_avg_m)),
                ("model_m_dot_kg_s", Some(f.model_m_dot_kg_s)),
                ("model_w_spec_j_kg", Some(f.model_w_spec_j_kg)),
                ("model_m_dot_op_kg_h", f.model_m_dot_op_kg_h),
            ] {
                if let Some(v) = v.filter(|v| !(v.is_finite() && *v >= 0.0)) {
                    return Err(at(format!("`{name}` is {v}; it is a finite number >= 0")));
                }
            }
            f.campaign.check().map_err(|e| at(format!("`campaign`: {e}")))?;
        }
        Ok(())
    }
}

/// The designs to check: the picks, then `k` front designs evenly spread over the front
/// sorted by mass flow (skipping designs already picked).
fn chosen(front: &[FrontPoint], k: usize) -> Vec<(String, FrontPoint)> {
    // a design picked twice (A is often C) is run once, labelled with both picks
    let mut out: Vec<(String, FrontPoint)> = Vec::new();
    for (l, p) in picks(front) {
        match out.iter_mut().find(|(_, q)| q.design == p.design) {
            Some((label, _)) => label.push_str(&format!("+{l}")),
            None => out.push((l.to_string(), p.clone())),
        }
    }
    let mut sorted: Vec<&FrontPoint> = front.iter().collect();
    sorted.sort_by(|a, b| a.m_dot_kg_s.total_cmp(&b.m_dot_kg_s));
    for i in 0..k {
        if sorted.is_empty() {
            break;
        }
        let idx = ((i as f64 + 0.5) / k as f64 * sorted.len() as f64) as usize;
        let p = sorted[idx.min(sorted.len() - 1)];
        if !out.iter().any(|(_, q)| q.design == p.design) {
            out.push((format!("front-{}", i + 1), p.clone()));
        }
    }
    out
}

/// The plan of a check of `run_dir`'s picks and `k` front designs, `seeds` DEM runs each
/// (seeds from the run's own seed on). The DEM runs `physics` where given (a reference's
/// material, contact and environment, each design at its front slope), else the run's own
/// scenario: a run optimised on a corrected model (fitted coefficients, effects the DEM does
/// not take) is checked against the physics the correction was fitted to. Every case is built
/// once here, so a design the DEM cannot represent is refused before anything is written.
pub fn plan(
    run_dir: &Path,
    physics: Option<&crate::model::Scenario>,
    settings: &DemSettings,
    seeds: u32,
    k: usize,
    command: &str,
) -> anyhow::Result<CheckPlan> {
    let manifest = read_manifest(run_dir)?;
    let front = read_pareto_csv(&run_dir.join("pareto.csv"))
        .with_context(|| format!("{} has no finished front (pareto.csv)", run_dir.display()))?;
    anyhow::ensure!(!front.is_empty(), "{}: the front is empty", run_dir.display());
    let mut finalists = Vec::new();
    for (label, p) in chosen(&front, k) {
        let mut scenario = physics.unwrap_or(&manifest.scenario).clone();
        scenario.environment.alpha_deg = p.alpha_deg;
        let settings = super::case::with_stated_mesh(settings, &scenario, &p.design);
        let campaign = Plan {
            scenario,
            design: p.design,
            settings,
            runs: seeds,
            first_seed: manifest.seed,
            known_return: None,
            strokes: 0,
            period_teeth: 0,
        };
        campaign.check().map_err(|e| anyhow::anyhow!("design {label}: {e}"))?;
        finalists.push(Finalist {
            label,
            model_d_avg_m: p.d_avg_m,
            model_m_dot_kg_s: p.m_dot_kg_s,
            model_w_spec_j_kg: p.w_spec_j_kg,
            model_compliant: p.compliance.as_ref().map(|c| c.compliant),
            model_m_dot_op_kg_h: p.compliance.as_ref().map(|c| c.m_dot_op_kg_h),
            campaign,
        });
    }
    let plan = CheckPlan {
        format: CHECK_PLAN_FORMAT,
        command: command.to_string(),
        run_dir: run_dir.display().to_string(),
        seeds,
        particles: settings.particles,
        requirements: manifest.requirements.clone(),
        finalists,
    };
    plan.validate().map_err(anyhow::Error::msg)?;
    Ok(plan)
}

/// True when `dir` is a check's folder with a plan (what `campaign run/gather/status/slurm`
/// dispatch on).
pub fn is_check(dir: &Path) -> bool {
    kind_of(dir).as_deref() == Some(CHECK_KIND) && dir.join(CHECK_PLAN).is_file()
}

/// Own `root` and write `plan` there, returning the plan the check goes on with; a folder
/// holding another plan is refused (the members of a check must all come from one plan). The
/// plan's `command` is left out of the comparison: the same check made by `dem check --plan`
/// and resumed by `dem check` is one; so is each design's campaign where the new plan states
/// a mesh the recorded one left to the case (`campaign::continues`): the recorded plan, on
/// which its runs were made, goes on.
pub fn write_plan(root: &Path, plan: &CheckPlan) -> anyhow::Result<(RunDir, CheckPlan)> {
    let owned = RunDir::acquire(root, CHECK_KIND, Access::Exclusive).context("--out")?;
    let path = root.join(CHECK_PLAN);
    if path.is_file() {
        let old = CheckPlan { command: plan.command.clone(), ..read_plan(root)? };
        let same_designs = old.finalists.len() == plan.finalists.len()
            && old.finalists.iter().zip(&plan.finalists).all(|(o, n)| {
                campaign::continues(&o.campaign, &n.campaign)
                    && Finalist { campaign: o.campaign.clone(), ..n.clone() } == *o
            });
        let rest_same = CheckPlan { finalists: old.finalists.clone(), ..plan.clone() } == old;
        if !(same_designs && rest_same) {
            bail!(
                "{} holds a DEM check of another plan ({}): resuming needs the same run, --seeds, --front and --particles; choose another --out",
                root.display(),
                path.display()
            );
        }
        return Ok((owned, old));
    }
    write_atomic(&path, (serde_json::to_string_pretty(plan)? + "\n").as_bytes())?;
    Ok((owned, plan.clone()))
}

/// Read and check `root/plan.json`.
pub fn read_plan(root: &Path) -> anyhow::Result<CheckPlan> {
    let path = root.join(CHECK_PLAN);
    let text = crate::io::bounded::read_text(&path, &crate::schema::PLAN_FILE)?;
    parse_plan(&text, &path.display().to_string())
}

/// A check plan's text checked by every rule ([`CheckPlan::validate`]); `name` is the file
/// named in messages.
pub fn parse_plan(text: &str, name: &str) -> anyhow::Result<CheckPlan> {
    let plan: CheckPlan = serde_json::from_str(text).with_context(|| format!("reading {name}"))?;
    plan.validate().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    Ok(plan)
}

/// Run member `i` alone (the caller holds `root`, shared with the other members' tasks);
/// `Ok(false)` when it was done already.
pub fn run_member(root: &Path, plan: &CheckPlan, i: usize, say: &(dyn Fn(String) + Sync)) -> anyhow::Result<bool> {
    if i >= plan.members() {
        bail!(
            "--task {i}: the DEM check in {} has {} members (tasks 0..={})",
            root.display(),
            plan.members(),
            plan.members() - 1
        );
    }
    let (f, r) = plan.member(i);
    let dir = plan.finalist_dir(root, f);
    campaign::own_subcampaign_folder(&dir)?;
    campaign::run_one(&dir, &plan.finalists[f].campaign, r, say)
}

/// The model's and the DEM's figures of one finalist from its runs.
fn design_check(plan: &CheckPlan, f: &Finalist, results: &[RunResult]) -> anyhow::Result<DesignCheck> {
    let (scenario, design) = (&f.campaign.scenario, &f.campaign.design);
    let d: Vec<f64> = results.iter().map(|r| r.d_avg_m).collect();
    let mean_d = d.iter().sum::<f64>() / d.len() as f64;
    let lost = results.iter().map(|r| r.lost as f64 / r.grains as f64).sum::<f64>() / results.len() as f64;
    let prep = prepare(scenario, design).map_err(|e| anyhow::anyhow!("design {}: {e}", f.label))?;
    let perf = performance(scenario, design, mean_d, prep.fill.area);
    let verdict = plan.requirements.as_ref().map(|r| r.assess(&perf, &scenario.performance, lost));
    let sd = if d.len() > 1 {
        (d.iter().map(|x| (x - mean_d).powi(2)).sum::<f64>() / (d.len() - 1) as f64).sqrt()
    } else {
        0.0
    };
    Ok(DesignCheck {
        label: f.label.clone(),
        design: DesignRow::of(design),
        alpha_deg: scenario.environment.alpha_deg,
        model_d_avg_mm: f.model_d_avg_m * 1e3,
        dem_d_avg_mm: Spread { mean: mean_d * 1e3, sd: sd * 1e3 },
        model_m_dot_kg_h: f.model_m_dot_kg_s * 3600.0,
        dem_m_dot_kg_h: perf.m_dot_kg_s * 3600.0,
        model_w_spec_j_kg: f.model_w_spec_j_kg,
        dem_w_spec_j_kg: perf.w_spec_j_kg,
        dem_lost_pct: 100.0 * lost,
        model_compliant: f.model_compliant,
        dem_compliant: verdict.as_ref().map(|v| v.compliant()),
        dem_binding: verdict.as_ref().and_then(|v| v.binding().map(str::to_string)),
        model_m_dot_op_kg_h: f.model_m_dot_op_kg_h,
        dem_m_dot_op_kg_h: verdict.as_ref().map(|v| v.operating_point.m_dot_kg_h),
        dem_p_op_w: verdict.as_ref().map(|v| v.operating_point.p_avg_w),
        dem_operating_limit: verdict.as_ref().map(|v| v.operating_point.limit),
        dem_s_per_run: results.iter().map(|r| r.wall_s).sum::<f64>() / results.len() as f64,
    })
}

fn write_report(root: &Path, report: &CheckReport) -> anyhow::Result<()> {
    write_atomic(&root.join(CHECK_JSON), serde_json::to_string_pretty(report)?.as_bytes())
}

fn empty_report(plan: &CheckPlan) -> CheckReport {
    CheckReport { run_dir: plan.run_dir.clone(), seeds: plan.seeds, particles: plan.particles, designs: vec![] }
}

/// The report from the members' result files, and `check.json` (and each finalist's
/// `dem.csv`/`setup.toml`) written; refused, naming every member without a result, while
/// any is missing. The caller holds `root` exclusively.
pub fn gather(root: &Path, plan: &CheckPlan) -> anyhow::Result<CheckReport> {
    let missing: Vec<String> = (0..plan.members())
        .filter(|&i| !plan.member_done(root, i))
        .map(|i| format!("  {i:>5}  {}", plan.member_label(i)))
        .collect();
    if !missing.is_empty() {
        bail!(
            "{} of {} members of the DEM check in {} have no result; no check.json written:\n{}\nrun them (`sawtooth campaign run {} --task I`, or `sawtooth campaign slurm {} --unfinished --submit`) and gather again",
            missing.len(),
            plan.members(),
            root.display(),
            missing.join("\n"),
            root.display(),
            root.display()
        );
    }
    let mut report = empty_report(plan);
    for (i, f) in plan.finalists.iter().enumerate() {
        campaign::own_subcampaign_folder(&plan.finalist_dir(root, i))?;
        let results = campaign::gather(&plan.finalist_dir(root, i), &f.campaign)?;
        report.designs.push(design_check(plan, f, &results)?);
    }
    write_report(root, &report)?;
    Ok(report)
}

/// The whole check here: the plan written (or checked), then each finalist's campaign run
/// with up to `jobs` LIGGGHTS processes, `check.json` rewritten after every design (so a
/// long check shows its first designs early); the final report is [`gather`]'s.
pub fn check(root: &Path, plan: &CheckPlan, jobs: usize, say: &(dyn Fn(String) + Sync)) -> anyhow::Result<CheckReport> {
    let (_owned, plan) = write_plan(root, plan)?;
    check_owned(root, &plan, jobs, say)
}

/// [`check`] in a folder the caller holds exclusively, its plan there.
fn check_owned(
    root: &Path,
    plan: &CheckPlan,
    jobs: usize,
    say: &(dyn Fn(String) + Sync),
) -> anyhow::Result<CheckReport> {
    let mut report = empty_report(plan);
    for (i, f) in plan.finalists.iter().enumerate() {
        let dir = plan.finalist_dir(root, i);
        campaign::own_subcampaign_folder(&dir)?;
        say(format!("design {}: {}", f.label, DesignRow::of(&f.campaign.design)));
        let results = campaign::run(&dir, &f.campaign, jobs, say)?;
        report.designs.push(design_check(plan, f, &results)?);
        write_report(root, &report)?;
    }
    gather(root, plan)
}

/// The report's table and where its file is: what `dem check` and `campaign run/gather` print.
pub fn write_summary(out: &mut dyn Write, r: &CheckReport, root: &Path) -> anyhow::Result<()> {
    write_table(out, r)?;
    writeln!(out, "\nwrote {}/{}", root.display(), CHECK_JSON)?;
    Ok(())
}

/// A DEM check as a campaign: members are DEM runs (design x seed), each resumed run by run
/// from the results its design's campaign holds.
impl Campaign for CheckPlan {
    fn kind(&self) -> &'static str {
        CHECK_KIND
    }
    fn what(&self) -> &'static str {
        "DEM check"
    }
    fn command(&self) -> &str {
        &self.command
    }
    fn members(&self) -> usize {
        CheckPlan::members(self)
    }
    fn label(&self, i: usize) -> String {
        self.member_label(i)
    }
    fn member_dir(&self, root: &Path, i: usize) -> PathBuf {
        CheckPlan::member_dir(self, root, i)
    }
    fn state(&self, root: &Path, i: usize) -> MemberState {
        if self.member_done(root, i) {
            MemberState::Finished
        } else if CheckPlan::member_dir(self, root, i).is_dir() {
            MemberState::Started
        } else {
            MemberState::NotStarted
        }
    }
    fn run_member(&self, root: &Path, i: usize) -> anyhow::Result<Ran> {
        let label = self.member_label(i);
        Ok(if run_member(root, self, i, &|l| eprintln!("member {i} ({label}): {l}"))? {
            Ran::Finished(CheckPlan::member_dir(self, root, i).display().to_string())
        } else {
            Ran::AlreadyFinished
        })
    }
    fn run_all(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<Ran> {
        let jobs = std::thread::available_parallelism().map_or(1, |n| n.get());
        let report = check_owned(root, self, jobs, &|l| eprintln!("dem check: {l}"))?;
        write_summary(out, &report, root)?;
        Ok(Ran::Finished(String::new()))
    }
    fn gather(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<()> {
        write_summary(out, &gather(root, self)?, root)
    }
    fn label_width(&self) -> usize {
        16
    }
    fn tally(&self, states: &[MemberState]) -> String {
        let finished = states.iter().filter(|s| **s == MemberState::Finished).count();
        format!("finished {finished}, not finished {}", states.len() - finished)
    }
}

pub fn write_table(out: &mut dyn Write, r: &CheckReport) -> anyhow::Result<()> {
    writeln!(out, "DEM check of {} ({} seeds x {} grains per design)", r.run_dir, r.seeds, r.particles)?;
    writeln!(out, "design     d_avg mm model / DEM      m_dot kg/h model / DEM   W_spec J/kg model / DEM   lost %  verdict model / DEM   operating kg/h model / DEM")?;
    for d in &r.designs {
        let verdict = |v: Option<bool>| match v {
            Some(true) => "meets",
            Some(false) => "fails",
            None => "-",
        };
        let kg_h = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
        let limit = match (d.dem_operating_limit, d.dem_p_op_w) {
            (Some(l), Some(p)) => format!(" ({}-limited, {p:.2} W)", format!("{l:?}").to_lowercase()),
            _ => String::new(),
        };
        writeln!(
            out,
            "{:<9} {:>7.2} / {:>6.2} ± {:<5.2} {:>9.2} / {:<9.2} {:>10.1} / {:<10} {:>6.1}  {} / {}{}   {} / {}{}",
            d.label,
            d.model_d_avg_mm,
            d.dem_d_avg_mm.mean,
            d.dem_d_avg_mm.sd,
            d.model_m_dot_kg_h,
            d.dem_m_dot_kg_h,
            d.model_w_spec_j_kg,
            d.dem_w_spec_j_kg.map_or("-".to_string(), |w| format!("{w:.1}")),
            d.dem_lost_pct,
            verdict(d.model_compliant),
            verdict(d.dem_compliant),
            d.dem_binding.as_ref().map_or(String::new(), |b| format!(" ({b})")),
            kg_h(d.model_m_dot_op_kg_h),
            kg_h(d.dem_m_dot_op_kg_h),
            limit
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a_plan() -> CheckPlan {
        let campaign = Plan {
            scenario: crate::model::Scenario::lunar(),
            design: crate::model::Design::lunar_solution_c(),
            settings: DemSettings { particles: 50, ..Default::default() },
            runs: 2,
            first_seed: 5,
            known_return: None,
            strokes: 0,
            period_teeth: 0,
        };
        let finalist = |label: &str| Finalist {
            label: label.into(),
            model_d_avg_m: 0.2,
            model_m_dot_kg_s: 0.01,
            model_w_spec_j_kg: 300.0,
            model_compliant: None,
            model_m_dot_op_kg_h: None,
            campaign: campaign.clone(),
        };
        CheckPlan {
            format: CHECK_PLAN_FORMAT,
            command: "test".into(),
            run_dir: "runs/x".into(),
            seeds: 2,
            particles: 50,
            requirements: None,
            finalists: vec![finalist("A+C"), finalist("B")],
        }
    }

    #[test]
    fn a_check_recorded_with_its_meshes_unset_goes_on_with_that_plan_under_a_command_that_states_them() {
        let d = tempfile::tempdir().unwrap();
        let old = a_plan();
        drop(write_plan(d.path(), &old).unwrap());
        let mut stated = a_plan();
        for f in &mut stated.finalists {
            f.campaign.settings.teeth = Some(40);
        }
        stated.command = "dem check again".into();
        let (_owned, going_on) = write_plan(d.path(), &stated).unwrap();
        assert_eq!(going_on.finalists, old.finalists, "the recorded designs' campaigns go on");
        drop(_owned);
        let mut other = stated.clone();
        other.finalists[1].campaign.first_seed = 6;
        let e = write_plan(d.path(), &other).unwrap_err().to_string();
        assert!(e.contains("another plan"), "{e}");
        let mut fewer = stated.clone();
        fewer.finalists.pop();
        assert!(write_plan(d.path(), &fewer).is_err());
    }

    #[test]
    fn members_are_each_finalists_seeds_in_its_own_folder() {
        let p = a_plan();
        assert_eq!(p.members(), 4);
        assert_eq!(p.member(3), (1, 1));
        assert_eq!(p.member_label(2), "B seed 5");
        assert_eq!(p.member_dir(Path::new("chk"), 1), Path::new("chk/A+C/run-002"));
        assert!(p.validate().is_ok());
    }

    #[test]
    fn a_plan_edited_out_of_its_rules_is_refused_naming_the_field() {
        let mut p = a_plan();
        p.finalists[1].label = "../elsewhere".into();
        assert!(p.validate().unwrap_err().contains("finalist 1 (../elsewhere): `label`"));
        let mut p = a_plan();
        p.finalists[1].label = "A+C".into();
        assert!(p.validate().unwrap_err().contains("another finalist's"));
        let mut p = a_plan();
        p.finalists[0].campaign.runs = 3;
        assert!(p.validate().unwrap_err().contains("`campaign.runs` 3 differs from `seeds` 2"));
        let mut p = a_plan();
        p.finalists[0].campaign.settings.max_overlap_fraction = 2.0;
        assert!(p.validate().unwrap_err().contains("[dem] max_overlap_fraction"));
        let mut p = a_plan();
        p.seeds = 0;
        assert!(p.validate().unwrap_err().contains("`seeds`"));
    }

    /// check.json spells a design as every other file does: the eight named columns with
    /// their units, not a bare array whose order the reader must know.
    #[test]
    fn a_checked_design_is_reported_with_its_named_columns() {
        let p = a_plan();
        let run = |seed: u64, d_avg_m: f64| RunResult {
            seed,
            teeth_g: vec![1.0, 2.0],
            input_mass_g: 3.0,
            grains: 50,
            lost: 0,
            left_box: 0,
            moving: 0,
            d_avg_m,
            wall_s: 10.0,
            past_end: 0,
            settled_xy_m: Vec::new(),
            left_by: None,
        };
        let c = design_check(&p, &p.finalists[0], &[run(5, 0.04), run(6, 0.06)]).unwrap();
        let json = serde_json::to_value(&c).unwrap();
        assert_eq!(json["design"]["l_c_mm"], 47.346, "{json}");
        assert_eq!(json["design"]["a_m_s2"], 32.051, "{json}");
        assert!(json.get("design_cli").is_none(), "{json}");
        assert!((c.dem_d_avg_mm.mean - 50.0).abs() < 1e-9, "{:?}", c.dem_d_avg_mm);
    }

    #[test]
    fn a_design_picked_twice_is_checked_once_under_both_labels() {
        let p = |v0: f64, m_dot: f64, w: f64| FrontPoint {
            design: crate::model::Design { v0, ..crate::model::Design::lunar_solution_c() },
            f_stroke_hz: 0.03,
            w_spec_j_kg: w,
            w_spec_se: 0.0,
            m_dot_kg_s: m_dot,
            m_dot_se: 0.0,
            stroke_m: 0.02,
            n_wire: 20,
            d_avg_m: 0.3,
            d_avg_se: 0.0,
            p_avg_w: 5.0,
            wire_length_m: 0.4,
            alpha_deg: 35.0,
            compliance: None,
        };
        // the first is closest to 48 kg/h and cheapest (A and C), the second delivers most (B)
        let front = [p(1.0, 0.013, 300.0), p(1.8, 0.1, 400.0), p(1.4, 0.05, 350.0)];
        let labels: Vec<String> = chosen(&front, 1).into_iter().map(|(l, _)| l).collect();
        assert_eq!(labels, ["A+C", "B", "front-1"]);
    }
}
