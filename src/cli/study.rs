//! `sawtooth study repeatability|sensitivity` (5.4.1-5.4.2, Tables C.1-C.3, Figure 5.3):
//! many optimisation runs in lockstep, each compared at the target mass flow. With `--plan`
//! the runs become a campaign (`cli::campaign`) run elsewhere, e.g. as a Slurm job array.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::{Args, Subcommand};
use serde::{Deserialize, Serialize};

use super::args::{EngineArgs, ScenarioArgs};
use super::multi::{plan_or_run, Member, Panel, PanelsPlot, Plan, Series, Study};
use super::optimize::GaArgs;
use crate::engine::EngineKind;
use crate::io::table::write_table;
use crate::model::Scenario;
use crate::optim::front::{closest_to_mass_flow, FrontPoint};
use crate::plot;

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
    #[arg(long)]
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
    if !(t > 0.0 && t.is_finite()) {
        bail!("--target-mass-flow must be > 0 kg/s, got {t}");
    }
    Ok(t)
}

/// Mean, sample standard deviation, coefficient of variation, half-width of the 95 %
/// confidence interval of the mean (normal approximation).
fn stats(v: &[f64]) -> (f64, f64, f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let sd = if v.len() > 1 { (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() } else { f64::NAN };
    (m, sd, sd / m, 1.96 * sd / n.sqrt())
}

/// The front point a run is compared at (its design and figures); empty when its front
/// holds no design.
#[derive(Debug, Default, Clone, Copy)]
struct Point {
    f_stroke_hz: Option<f64>,
    w_spec_j_kg: Option<f64>,
    m_dot_kg_s: Option<f64>,
    d_avg_m: Option<f64>,
    n_wire: Option<u32>,
    x: Option<[f64; 8]>,
}

impl Point {
    fn of(p: Option<&FrontPoint>) -> Self {
        match p {
            None => Point::default(),
            Some(p) => Point {
                f_stroke_hz: Some(p.f_stroke_hz),
                w_spec_j_kg: Some(p.w_spec_j_kg),
                m_dot_kg_s: Some(p.m_dot_kg_s),
                d_avg_m: Some(p.d_avg_m),
                n_wire: Some(p.n_wire),
                x: Some(p.design.to_cli_units()),
            },
        }
    }
    fn x(&self, i: usize) -> Option<f64> {
        self.x.map(|x| x[i])
    }
}

/// One row of runs.csv (study repeatability): a run's front point closest to the target.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct RunRow {
    pub run: usize,
    pub seed: u64,
    pub f_stroke_hz: Option<f64>,
    pub w_spec_j_kg: Option<f64>,
    pub m_dot_kg_s: Option<f64>,
    pub d_avg_m: Option<f64>,
    pub n_wire: Option<u32>,
    pub l_c_mm: Option<f64>,
    pub l_a_mm: Option<f64>,
    pub l_b_mm: Option<f64>,
    pub r_mm: Option<f64>,
    pub omega_deg: Option<f64>,
    pub delta_deg: Option<f64>,
    pub v0_m_s: Option<f64>,
    pub a_m_s2: Option<f64>,
    /// (m_dot - target) / target, -.
    pub m_dot_from_target_rel: Option<f64>,
    /// Within ±AT_TARGET_REL of the target.
    pub at_target: Option<bool>,
}

/// One row of grid.csv (study sensitivity): a grid point's front point closest to the target.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct GridRow {
    pub point: usize,
    pub k_elastic: f64,
    pub mu_friction: f64,
    /// Stokes drag, 1/s (0 = vacuum).
    pub k_drag_per_s: f64,
    pub f_stroke_hz: Option<f64>,
    pub w_spec_j_kg: Option<f64>,
    pub m_dot_kg_s: Option<f64>,
    pub d_avg_m: Option<f64>,
    pub n_wire: Option<u32>,
    pub l_c_mm: Option<f64>,
    pub l_a_mm: Option<f64>,
    pub l_b_mm: Option<f64>,
    pub r_mm: Option<f64>,
    pub omega_deg: Option<f64>,
    pub delta_deg: Option<f64>,
    pub v0_m_s: Option<f64>,
    pub a_m_s2: Option<f64>,
    /// W_spec inside the repeatability study's 95 % interval (with --repeatability).
    pub w_spec_within_repeatability_ci: Option<bool>,
}

/// One row of a study's summary.csv: a metric over the runs.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct SummaryRow {
    /// The figure summarised, its unit in its name (f_stroke_hz, w_spec_j_kg, m_dot_kg_s).
    pub metric: String,
    pub mean: f64,
    pub sd: f64,
    /// sd / mean, -.
    pub cv: f64,
    pub ci95_half_width: f64,
    pub n: usize,
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

/// How near the target mass flow a run's chosen point must lie to count as "at" it: runs
/// whose fronts hold nothing nearer are still compared, but the report says they are not at
/// the target (relative distance).
pub const AT_TARGET_REL: f64 = 0.10;

/// runs.csv, summary.csv, repeatability.svg and the table of a finished repeatability study.
pub fn summarise_repeatability(
    root: &Path,
    plan: &Plan,
    t: f64,
    fronts: &[Vec<FrontPoint>],
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    let (mut f, mut w, mut m) = (Vec::new(), Vec::new(), Vec::new());
    let mut far = Vec::new();
    for (i, (member, front)) in plan.members.iter().zip(fronts).enumerate() {
        let p = closest_to_mass_flow(front, t);
        // a run's front may hold nothing near the target: say how far its chosen point is
        let distance = p.map(|p| (p.m_dot_kg_s - t) / t);
        let at_target = distance.map(|d| d.abs() <= AT_TARGET_REL);
        if let (Some(p), Some(false)) = (p, at_target) {
            far.push(format!("run {i} at {:.4} kg/s", p.m_dot_kg_s));
        }
        let q = Point::of(p);
        rows.push(RunRow {
            run: i,
            seed: member.manifest.scenario.sim.seed,
            f_stroke_hz: q.f_stroke_hz,
            w_spec_j_kg: q.w_spec_j_kg,
            m_dot_kg_s: q.m_dot_kg_s,
            d_avg_m: q.d_avg_m,
            n_wire: q.n_wire,
            l_c_mm: q.x(0),
            l_a_mm: q.x(1),
            l_b_mm: q.x(2),
            r_mm: q.x(3),
            omega_deg: q.x(4),
            delta_deg: q.x(5),
            v0_m_s: q.x(6),
            a_m_s2: q.x(7),
            m_dot_from_target_rel: distance,
            at_target,
        });
        if let Some(p) = p {
            f.push(p.f_stroke_hz);
            w.push(p.w_spec_j_kg);
            m.push(p.m_dot_kg_s);
        }
    }
    write_table(&root.join("runs.csv"), &rows)?;
    let mut summary = Vec::new();
    if far.is_empty() {
        writeln!(
            out,
            "{} runs compared at {t} kg/s (each at its front design within ±{:.0} % of it):",
            f.len(),
            AT_TARGET_REL * 100.0
        )?;
    } else {
        writeln!(
            out,
            "{} runs compared at their front designs closest to {t} kg/s; NOT at the target for {} of them ({}; more than ±{:.0} % away), so the spread below mixes operating points:",
            f.len(),
            far.len(),
            far.join(", "),
            AT_TARGET_REL * 100.0
        )?;
    }
    for (name, v) in [("f_stroke_hz", &f), ("w_spec_j_kg", &w), ("m_dot_kg_s", &m)] {
        let (mean, sd, cv, ci) = stats(v);
        summary.push(SummaryRow { metric: name.to_string(), mean, sd, cv, ci95_half_width: ci, n: v.len() });
        writeln!(out, "  {name:<12} mean {mean:.5e}  sd {sd:.3e}  CV {:.3} %  95% CI ± {ci:.3e}", cv * 100.0)?;
    }
    write_table(&root.join("summary.csv"), &summary)?;
    // independent runs: each a point, with the mean and its 95 % interval as a band
    let panel = |y_desc: &str, v: Vec<f64>| {
        let (mean, _, _, ci) = stats(&v);
        Panel {
            y_desc: y_desc.into(),
            series: vec![Series { label: "run (closest to the target mass flow)".into(), y: v, se: None }],
            band: Some((mean, ci, "mean ± 95 % confidence interval".into())),
        }
    };
    let figure = PanelsPlot {
        title: format!("Repeatability: {} runs at {t} kg/s", f.len()),
        x_desc: "run".into(),
        x: (0..f.len()).map(|i| i as f64).collect(),
        x_categories: Some((0..f.len()).map(|i| i.to_string()).collect()),
        panels: vec![panel("f_stroke [Hz]", f), panel("W_spec [J/kg]", w), panel("mass flow [kg/s]", m)],
        joined: false,
    };
    plot::write_figure_files(root, "repeatability", &figure)?;
    Ok(())
}

/// Mean and CI half-width of W_spec from a repeatability study's summary.csv.
fn read_ci(dir: &Path) -> anyhow::Result<(f64, f64)> {
    let path = dir.join("summary.csv");
    let mut reader =
        csv::Reader::from_path(&path).with_context(|| format!("--repeatability: reading {}", path.display()))?;
    for row in reader.deserialize::<SummaryRow>() {
        let row = row.with_context(|| format!("--repeatability: reading {}", path.display()))?;
        if row.metric == "w_spec_j_kg" {
            return Ok((row.mean, row.ci95_half_width));
        }
    }
    bail!("{}: no w_spec_j_kg row", path.display())
}

fn sensitivity(a: SensitivityArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let c = &a.common;
    let (base, _) = c.scenario.resolve()?;
    let t = target(c, &base)?;
    let ci = a.repeatability.as_deref().map(read_ci).transpose()?;
    // Tables C.2 (5x5 over k_elastic, mu at ±5/10 %) and C.3 (3x3x3 with k_drag at ±10 %).
    let grid: Vec<[f64; 3]> = match base.environment.k_drag {
        None => {
            let f = [0.9, 0.95, 1.0, 1.05, 1.1];
            f.iter().flat_map(|&ke| f.iter().map(move |&mu| [ke, mu, 1.0])).collect()
        }
        Some(_) => {
            let f = [0.9, 1.0, 1.1];
            let mut g = Vec::new();
            for ke in f {
                for mu in f {
                    for kd in f {
                        g.push([ke, mu, kd]);
                    }
                }
            }
            g
        }
    };
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

/// grid.csv, sensitivity.svg and the table of a finished sensitivity study.
pub fn summarise_sensitivity(
    root: &Path,
    plan: &Plan,
    t: f64,
    ci: Option<(f64, f64)>,
    fronts: &[Vec<FrontPoint>],
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    let mut w = Vec::new();
    writeln!(
        out,
        "{:>5} {:>9} {:>9} {:>9} {:>14} {:>12}",
        "point", "k_elastic", "mu", "k_drag", "W_spec [J/kg]", "in CI"
    )?;
    for (i, (member, front)) in plan.members.iter().zip(fronts).enumerate() {
        let s = &member.manifest.scenario;
        let p = closest_to_mass_flow(front, t);
        let within = match (ci, p) {
            (Some((mean, half)), Some(p)) => Some((p.w_spec_j_kg - mean).abs() <= half),
            _ => None,
        };
        let q = Point::of(p);
        rows.push(GridRow {
            point: i,
            k_elastic: s.collision.k_elastic,
            mu_friction: s.collision.mu_friction,
            k_drag_per_s: s.environment.k_drag.unwrap_or(0.0),
            f_stroke_hz: q.f_stroke_hz,
            w_spec_j_kg: q.w_spec_j_kg,
            m_dot_kg_s: q.m_dot_kg_s,
            d_avg_m: q.d_avg_m,
            n_wire: q.n_wire,
            l_c_mm: q.x(0),
            l_a_mm: q.x(1),
            l_b_mm: q.x(2),
            r_mm: q.x(3),
            omega_deg: q.x(4),
            delta_deg: q.x(5),
            v0_m_s: q.x(6),
            a_m_s2: q.x(7),
            w_spec_within_repeatability_ci: within,
        });
        let wv = p.map_or(f64::NAN, |p| p.w_spec_j_kg);
        w.push(wv);
        writeln!(
            out,
            "{i:>5} {:>9.4} {:>9.4} {:>9.3} {:>14.1} {:>12}",
            s.collision.k_elastic,
            s.collision.mu_friction,
            s.environment.k_drag.unwrap_or(0.0),
            wv,
            within.map_or(String::new(), |w| w.to_string())
        )?;
    }
    write_table(&root.join("grid.csv"), &rows)?;
    let figure = PanelsPlot {
        title: format!("Sensitivity at {t} kg/s"),
        x_desc: "grid point (see grid.csv)".into(),
        x: (0..w.len()).map(|i| i as f64).collect(),
        x_categories: Some((0..w.len()).map(|i| i.to_string()).collect()),
        panels: vec![Panel {
            y_desc: "W_spec [J/kg]".into(),
            series: vec![Series { label: "grid point (closest to the target mass flow)".into(), y: w, se: None }],
            band: ci.map(|(mean, half)| (mean, half, "repeatability: mean ± 95 % confidence interval".into())),
        }],
        joined: false,
    };
    plot::write_figure_files(root, "sensitivity", &figure)?;
    Ok(())
}
