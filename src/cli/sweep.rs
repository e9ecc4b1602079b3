//! `sawtooth gpu-sweep --alpha 1..40`: one optimisation per conveyor angle (5.4.3, Figure
//! 5.5, Tables C.4-C.5), the angles' populations evaluated together each generation (one GPU
//! job: the angle lives in each design's geometry). Resumable per angle. With `--plan` the
//! angles become a campaign (`cli::campaign`) run elsewhere, e.g. as a Slurm job array.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::bail;
use clap::Args;
use serde::{Deserialize, Serialize};

use super::args::{EngineArgs, ScenarioArgs};
use super::multi::{plan_or_run, Member, Panel, PanelsPlot, Plan, Series, Study};
use super::optimize::GaArgs;
use crate::io::table::write_table;
use crate::optim::front::FrontPoint;
use crate::optim::front::{closest_to_mass_flow, picks, TARGET_MASS_FLOW_KG_S};
use crate::plot;

#[derive(Debug, Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
    #[command(flatten)]
    pub ga: GaArgs,
    /// Angle step, degrees.
    #[arg(long, default_value_t = 1.0)]
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

/// One row of a sweep's summary.csv: a pick (A/B/C, Table 5.2) of one angle's front.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct SweepRow {
    pub alpha_deg: f64,
    pub pick: String,
    pub f_stroke_hz: f64,
    pub w_spec_j_kg: f64,
    /// Monte-Carlo standard errors of the re-evaluation.
    pub w_spec_se_j_kg: f64,
    pub m_dot_kg_s: f64,
    pub m_dot_se_kg_s: f64,
    pub d_avg_m: f64,
    pub n_wire: u32,
    pub l_c_mm: f64,
    pub l_a_mm: f64,
    pub l_b_mm: f64,
    pub r_mm: f64,
    pub omega_deg: f64,
    pub delta_deg: f64,
    pub v0_m_s: f64,
    pub a_m_s2: f64,
}

/// summary.csv, sweep.svg and the table of a finished sweep.
pub fn summarise(root: &Path, plan: &Plan, fronts: &[Vec<FrontPoint>], out: &mut dyn Write) -> anyhow::Result<()> {
    let angles: Vec<f64> = plan.members.iter().map(|m| m.manifest.scenario.environment.alpha_deg).collect();
    let mode = plan.members.first().map(|m| m.manifest.scenario.mode);
    let mut rows = Vec::new();
    // per pick (C, then closest to the target): f_stroke, W_spec ± se, mass flow ± se
    let mut series: [Vec<f64>; 10] = Default::default();
    writeln!(out, "{:>6} {:>4} {:>12} {:>14} {:>12}", "alpha", "pick", "f [Hz e-2]", "W_spec [J/kg]", "m_dot [kg/h]")?;
    for (alpha, front) in angles.iter().zip(fronts) {
        let ps = picks(front);
        for (name, p) in &ps {
            let x = p.design.to_cli_units();
            rows.push(SweepRow {
                alpha_deg: *alpha,
                pick: name.to_string(),
                f_stroke_hz: p.f_stroke_hz,
                w_spec_j_kg: p.w_spec_j_kg,
                w_spec_se_j_kg: p.w_spec_se,
                m_dot_kg_s: p.m_dot_kg_s,
                m_dot_se_kg_s: p.m_dot_se,
                d_avg_m: p.d_avg_m,
                n_wire: p.n_wire,
                l_c_mm: x[0],
                l_a_mm: x[1],
                l_b_mm: x[2],
                r_mm: x[3],
                omega_deg: x[4],
                delta_deg: x[5],
                v0_m_s: x[6],
                a_m_s2: x[7],
            });
            writeln!(
                out,
                "{alpha:>6.1} {name:>4} {:>12.3} {:>14.1} {:>12.2}",
                p.f_stroke_hz * 100.0,
                p.w_spec_j_kg,
                p.m_dot_kg_s * 3600.0
            )?;
        }
        let c = ps.iter().find(|(n, _)| *n == "C").map(|(_, p)| *p);
        let t = closest_to_mass_flow(front, TARGET_MASS_FLOW_KG_S);
        for (k, p) in [c, t].into_iter().enumerate() {
            series[5 * k].push(p.map_or(f64::NAN, |p| p.f_stroke_hz));
            series[5 * k + 1].push(p.map_or(f64::NAN, |p| p.w_spec_j_kg));
            series[5 * k + 2].push(p.map_or(f64::NAN, |p| p.w_spec_se));
            series[5 * k + 3].push(p.map_or(f64::NAN, |p| p.m_dot_kg_s * 3600.0));
            series[5 * k + 4].push(p.map_or(f64::NAN, |p| p.m_dot_se * 3600.0));
        }
    }
    write_table(&root.join("summary.csv"), &rows)?;
    let [f_c, w_c, w_c_se, m_c, m_c_se, f_a, w_a, w_a_se, m_a, m_a_se] = series;
    let (c, a) = ("lowest W_spec (C)", "closest to 48 kg/h (A)");
    let pair = |y_desc: &str, yc: Vec<f64>, sc: Option<Vec<f64>>, ya: Vec<f64>, sa: Option<Vec<f64>>| Panel {
        y_desc: y_desc.into(),
        series: vec![Series { label: c.into(), y: yc, se: sc }, Series { label: a.into(), y: ya, se: sa }],
        band: None,
    };
    let figure = PanelsPlot {
        title: format!("Conveyor-angle sweep ({:?} mode)", mode.unwrap_or_default()),
        x_desc: "conveyor angle alpha [deg]".into(),
        x: angles,
        x_categories: None,
        panels: vec![
            pair("f_stroke [Hz]", f_c, None, f_a, None),
            pair("W_spec [J/kg]", w_c, Some(w_c_se), w_a, Some(w_a_se)),
            pair("mass flow [kg/h]", m_c, Some(m_c_se), m_a, Some(m_a_se)),
        ],
        joined: true,
    };
    plot::write_figure_files(root, "sweep", &figure)?;
    writeln!(out, "wrote {} and {} (and .png)", root.join("summary.csv").display(), root.join("sweep.svg").display())?;
    Ok(())
}
