//! An optimisation's finalists held against the DEM: the picks A, B, C (Table 5.2) and K
//! more front designs spread over the front's mass flow, each run in DEM with several seeds;
//! the DEM's d_avg goes through the same performance model (D.7: ṁ ∝ d_avg, W_spec = P/ṁ)
//! and, where the run had requirements, the same verdicts.
//!
//! Every design is run at the slope its front figures are at (the worst slope of a run over
//! several). Each design's campaign is a folder of its own under the check's folder, so a
//! killed check resumes design by design and run by run.

use std::io::Write;
use std::path::Path;

use anyhow::Context as _;
use serde::Serialize;

use super::campaign::{self, Plan};
use super::compare::Spread;
use super::settings::DemSettings;
use crate::io::atomic::write_atomic;
use crate::io::run_dir::{Access, RunDir};
use crate::model::performance::performance;
use crate::model::prepare;
use crate::optim::front::{picks, read_pareto_csv, FrontPoint};
use crate::optim::manifest::read_manifest;

#[derive(Clone, Debug, Serialize)]
pub struct DesignCheck {
    pub label: String,
    /// l_c, l_a, l_b, r, ω, δ, v0, a in mm, mm, mm, mm, deg, deg, m/s, m/s².
    pub design_cli: [f64; 8],
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
    pub dem_s_per_run: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct CheckReport {
    pub run_dir: String,
    pub seeds: u32,
    pub particles: u32,
    pub designs: Vec<DesignCheck>,
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

pub fn check(
    run_dir: &Path,
    out_dir: &Path,
    settings: &DemSettings,
    seeds: u32,
    k: usize,
    jobs: usize,
    say: &(dyn Fn(String) + Sync),
) -> anyhow::Result<CheckReport> {
    let manifest = read_manifest(run_dir)?;
    let front = read_pareto_csv(&run_dir.join("pareto.csv"))
        .with_context(|| format!("{} has no finished front (pareto.csv)", run_dir.display()))?;
    anyhow::ensure!(!front.is_empty(), "{}: the front is empty", run_dir.display());
    let designs = chosen(&front, k);
    let _owned = RunDir::acquire(out_dir, "dem-check", Access::Exclusive).context("--out")?;
    let mut report =
        CheckReport { run_dir: run_dir.display().to_string(), seeds, particles: settings.particles, designs: vec![] };
    for (label, p) in designs {
        let mut scenario = manifest.scenario.clone();
        scenario.environment.alpha_deg = p.alpha_deg;
        let plan = Plan {
            scenario: scenario.clone(),
            design: p.design,
            settings: settings.clone(),
            runs: seeds,
            first_seed: manifest.seed,
            known_return: None,
        };
        let dir = out_dir.join(&label);
        std::fs::create_dir_all(&dir)?;
        say(format!("design {label}: {:?}", p.design.to_cli_units()));
        let results = campaign::run(&dir, &plan, jobs, say)?;
        let d: Vec<f64> = results.iter().map(|r| r.d_avg_m).collect();
        let mean_d = d.iter().sum::<f64>() / d.len() as f64;
        let lost = results.iter().map(|r| r.lost as f64 / r.grains as f64).sum::<f64>() / results.len() as f64;
        let prep = prepare(&scenario, &p.design).map_err(|e| anyhow::anyhow!("design {label}: {e}"))?;
        let perf = performance(&scenario, &p.design, mean_d, prep.fill.area);
        let verdict = manifest.requirements.as_ref().map(|r| r.assess(&perf, &scenario.performance, lost));
        let sd = if d.len() > 1 {
            (d.iter().map(|x| (x - mean_d).powi(2)).sum::<f64>() / (d.len() - 1) as f64).sqrt()
        } else {
            0.0
        };
        report.designs.push(DesignCheck {
            label,
            design_cli: p.design.to_cli_units(),
            alpha_deg: p.alpha_deg,
            model_d_avg_mm: p.d_avg_m * 1e3,
            dem_d_avg_mm: Spread { mean: mean_d * 1e3, sd: sd * 1e3 },
            model_m_dot_kg_h: p.m_dot_kg_s * 3600.0,
            dem_m_dot_kg_h: perf.m_dot_kg_s * 3600.0,
            model_w_spec_j_kg: p.w_spec_j_kg,
            dem_w_spec_j_kg: perf.w_spec_j_kg,
            dem_lost_pct: 100.0 * lost,
            model_compliant: p.compliance.as_ref().map(|c| c.compliant),
            dem_compliant: verdict.as_ref().map(|v| v.compliant()),
            dem_binding: verdict.as_ref().and_then(|v| v.binding().map(str::to_string)),
            dem_s_per_run: results.iter().map(|r| r.wall_s).sum::<f64>() / results.len() as f64,
        });
        write_atomic(&out_dir.join("check.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
    }
    Ok(report)
}

pub fn write_table(out: &mut dyn Write, r: &CheckReport) -> anyhow::Result<()> {
    writeln!(out, "DEM check of {} ({} seeds x {} grains per design)", r.run_dir, r.seeds, r.particles)?;
    writeln!(out, "design     d_avg mm model / DEM      m_dot kg/h model / DEM   W_spec J/kg model / DEM   lost %  verdict model / DEM")?;
    for d in &r.designs {
        let verdict = |v: Option<bool>| match v {
            Some(true) => "meets",
            Some(false) => "fails",
            None => "-",
        };
        writeln!(
            out,
            "{:<9} {:>7.2} / {:>6.2} ± {:<5.2} {:>9.2} / {:<9.2} {:>10.1} / {:<10} {:>6.1}  {} / {}{}",
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
            d.dem_binding.as_ref().map_or(String::new(), |b| format!(" ({b})"))
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
