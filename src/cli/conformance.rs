//! `sawtooth conformance`: the GPU engine against the CPU reference; exit 1 on failure.

use std::io::Write;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;

use crate::engine::conformance::{run, scenarios, Tolerances};
use crate::engine::gpu::{AdapterChoice, GpuEngine};
use crate::model::scenario::EnvPreset;
use crate::model::Scenario;

#[derive(Debug, Args)]
pub struct ConformanceArgs {
    /// Random valid designs per scenario (each environment with drag on and off).
    #[arg(long, default_value_t = 50, value_parser = super::args::count::<usize>(&crate::schema::CONFORMANCE_DESIGNS))]
    pub designs: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// One environment only (default: both).
    #[arg(long, value_enum)]
    pub env: Option<EnvPreset>,
    #[arg(long, default_value_t = 100, value_parser = super::args::count::<u32>(&crate::schema::SIM_PARTICLES))]
    pub particles: u32,
    /// Listing compatibility mode instead of the physical mode.
    #[arg(long)]
    pub compat_listing: bool,
    #[arg(long)]
    pub json: bool,
}

pub fn run_cli(a: ConformanceArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    // the flags' scenarios are checked before a device is opened: `--particles 0` is a rule,
    // not a panic deep in the engine
    for (name, s) in scenarios(&[Scenario::lunar(), Scenario::earth()], a.particles) {
        s.validate().map_err(|e| anyhow::anyhow!("{name}: invalid setting: {}", super::args::in_user_terms(&e)))?;
    }
    let envs: Vec<Scenario> = match a.env {
        Some(e) => vec![Scenario::preset(e)],
        None => vec![Scenario::lunar(), Scenario::earth()],
    };
    let envs: Vec<Scenario> =
        envs.into_iter().map(|s| if a.compat_listing { s.into_listing_compat() } else { s }).collect();
    let cases = scenarios(&envs, a.particles);
    // the designs each case will draw (the same seeds as `run`), checked before a device is
    // opened: a case that seats no design is an error naming why, not a panic in the engine
    for (ci, (name, s)) in cases.iter().enumerate() {
        crate::model::sampling::sample_valid_designs(s, a.designs, a.seed.wrapping_add(ci as u64))
            .map_err(|e| anyhow::anyhow!("{name} (--particles {}, --designs {}): {e}", a.particles, a.designs))?;
    }
    let gpu = GpuEngine::new(AdapterChoice::Any)?;
    let report = run(&gpu, &cases, a.designs, a.seed, Tolerances::default());
    if a.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?).context("writing output")?;
    } else {
        let t = &report.tolerances;
        writeln!(out, "device: {}", report.device)?;
        writeln!(
            out,
            "tolerances: first impact <= {} m for >= {:.1} %; tooth+state agree >= {:.0} %; mean L1 <= {}, mean |d_avg diff| <= {} m, mean |lost diff| <= {}",
            t.first_impact_tol_m,
            t.min_first_impact_agreement * 100.0,
            t.min_particle_agreement * 100.0,
            t.max_mean_distribution_l1,
            t.max_mean_d_avg_diff_m,
            t.max_mean_lost_diff
        )?;
        writeln!(
            out,
            "{:<24} {:>7} {:>9} {:>16} {:>14} {:>12} {:>9} {:>12} {:>10}",
            "scenario",
            "designs",
            "particles",
            "first-impact ok",
            "max diff (m)",
            "tooth+state",
            "mean L1",
            "d_avg diff",
            "lost diff"
        )?;
        for r in &report.scenarios {
            writeln!(
                out,
                "{:<24} {:>7} {:>9} {:>16} {:>14.3e} {:>11.2}% {:>9.4} {:>12.2e} {:>10.4}",
                r.scenario,
                r.designs,
                r.particles,
                format!("{}/{}", r.first_impacts_within_tol, r.first_impacts_compared),
                r.max_first_impact_diff_m,
                100.0 * r.tooth_and_state_agree as f64 / r.particles.max(1) as f64,
                r.mean_distribution_l1,
                r.mean_d_avg_diff_m,
                r.mean_lost_diff
            )?;
        }
        if !report.worst.is_empty() {
            writeln!(out, "worst cases:")?;
            for m in &report.worst {
                let design = m.design.cli_argument();
                writeln!(out, "  [{}] design {design} particle {}: {}", m.scenario, m.particle, m.what)?;
            }
        }
        for f in &report.failures {
            writeln!(out, "FAIL {f}")?;
        }
        writeln!(out, "{}", if report.passed { "conformance: PASS" } else { "conformance: FAIL" })?;
    }
    Ok(if report.passed { ExitCode::SUCCESS } else { ExitCode::from(1) })
}
