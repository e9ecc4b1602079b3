//! `sawtooth simulate`: one design, readable table or `--json`.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;

use super::args::{EngineArgs, RequirementArgs, ScenarioArgs};
use crate::engine::{evaluate_detailed, make_engine_for, Detailed, EngineKind};
use crate::model::design::DesignRow;
use crate::model::outcome::centre_and_dispersion;
use crate::model::requirements::{worst_over_slopes, Assessment, Requirements, NOT_ASSESSED};
use crate::model::{Design, PhysicsMode, Scenario};

#[derive(Debug, Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
    #[command(flatten)]
    pub requirements: RequirementArgs,
    /// Design `l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a` in mm,mm,mm,mm,deg,deg,m/s,m/s^2.
    #[arg(long, allow_hyphen_values = true)]
    pub design: Option<String>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write every launch and impact point as CSV (particle,bounce,x_m,y_m,state).
    #[arg(long)]
    pub trajectories: Option<PathBuf>,
    /// Draw the profile, fill area and trajectories (like Figure 5.7): SVG or PNG by the
    /// file's extension (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

pub fn run(a: SimulateArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let (scenario, file_design, slopes) = a.scenario.resolve_over_slopes(a.requirements.alpha_points)?;
    let requirements = a.requirements.resolve(&a.scenario)?;
    let design = match (&a.design, file_design) {
        (Some(s), _) => Design::parse_cli(s).map_err(|e| anyhow::anyhow!("--design: {e}"))?,
        (None, Some(d)) => d,
        (None, None) => {
            bail!("no design: pass --design l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a or a config file with [design]")
        }
    };
    if let Some(p) = &a.plot {
        // checked before simulating: a wrong name should not cost a run
        crate::plot::Format::of(p, "--plot")?;
    }
    if let Some(config) = &a.scenario.config {
        for (flag, out) in [("--plot", &a.plot), ("--trajectories", &a.trajectories)] {
            if let Some(out) = out {
                crate::io::atomic::refuse_input_as_output(out, flag, &[("--config", config)])?;
            }
        }
    }
    let trace = a.trajectories.is_some() || a.plot.is_some();
    if trace && !slopes.is_empty() {
        bail!("--trajectories and --plot draw one slope: give --alpha a single angle");
    }
    if trace && (scenario.effects.sled_motion.is_some() || scenario.effects.quadratic_drag.is_some()) {
        bail!("--trajectories and --plot redraw each flight as one closed-form arc; with the sled-motion or quadratic-drag effects that would be wrong, so they are not offered");
    }
    if trace && matches!(a.engine.kind(), EngineKind::Gpu | EngineKind::Auto) {
        bail!(
            "--trajectories and --plot record every flight, which only the CPU engines do: use --engine cpu or listing"
        );
    }
    let engine = make_engine_for(a.engine.kind(), &scenario).context("--engine")?;
    if !slopes.is_empty() {
        return over_slopes(out, &scenario, &design, engine.as_ref(), &slopes, requirements.as_ref(), a.json);
    }
    let det = match evaluate_detailed(engine.as_ref(), &scenario, &design, trace) {
        Ok(d) => d,
        Err(invalid) => bail!("invalid design ({}): {invalid}", invalid.rule()),
    };
    let k_drag = scenario.environment.k_drag.unwrap_or(0.0);
    if let Some(p) = &a.trajectories {
        crate::io::trajectories::write_trajectories(p, &det, scenario.environment.g, k_drag)?;
    }
    if let Some(p) = &a.plot {
        let title = format!("{} | {} engine | {:?} mode", describe(&design), engine.name(), scenario.mode);
        crate::plot::flight::write_plot(p, "--plot", &det, scenario.environment.g, k_drag, &title)?;
    }
    let assessment = requirements.as_ref().map(|r| {
        let e = &det.evaluation;
        r.assess(&e.performance, &scenario.performance, e.sim.lost_fraction)
    });
    if a.json {
        let mut v = crate::engine::summary::simulation_json(&scenario, &design, engine.name(), &det);
        if let (Some(r), Some(x)) = (&requirements, &assessment) {
            v["requirements"] =
                crate::engine::slopes::requirements_json(r, &[(scenario.environment.alpha_deg, x.clone())]);
        }
        writeln!(out, "{}", serde_json::to_string_pretty(&v)?).context("writing output")?;
    } else {
        write_table(out, &scenario, &design, engine.name(), &det).context("writing output")?;
        if let (Some(r), Some(x)) = (&requirements, &assessment) {
            write_verdicts(out, r, &[(scenario.environment.alpha_deg, x.clone())], &[]).context("writing output")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `simulate --alpha FROM..TO`: the design's figures at every slope (req. 1.6.3), and with
/// requirements their verdict at the worst slope (`engine::slopes`), as JSON or a table.
fn over_slopes(
    out: &mut dyn Write,
    scenario: &Scenario,
    design: &Design,
    engine: &dyn crate::engine::ParticleEngine,
    slopes: &[f64],
    requirements: Option<&Requirements>,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let rows = crate::engine::slopes::over_slopes(engine, scenario, design, slopes, requirements);
    if json {
        let v = crate::engine::slopes::slopes_json(engine.name(), scenario, design, &rows, requirements);
        writeln!(out, "{}", serde_json::to_string_pretty(&v)?).context("writing output")?;
        return Ok(ExitCode::SUCCESS);
    }
    writeln!(out, "design     {}", describe(design))?;
    writeln!(
        out,
        "scenario   g {} m/s2, drag {}, {} particles, seed {}, engine {}",
        scenario.environment.g,
        scenario.environment.k_drag.map_or("off".to_string(), |k| format!("{k} 1/s")),
        scenario.sim.particles,
        scenario.sim.seed,
        engine.name()
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "{:>9} {:>12} {:>13} {:>10} {:>7} {:>10} {:>9}",
        "alpha_deg", "m_dot_kg_h", "W_spec_J_kg", "P_avg_W", "n_wire", "f_stroke_Hz", "lost"
    )?;
    for row in &rows {
        let alpha = row.alpha_deg;
        let det = match &row.result {
            Ok(det) => det,
            Err(invalid) => {
                writeln!(out, "{alpha:>9.2}  invalid here ({}): {invalid}", invalid.rule())?;
                continue;
            }
        };
        let (p, sim) = (&det.evaluation.performance, &det.evaluation.sim);
        writeln!(
            out,
            "{:>9.2} {:>12.3} {:>13} {:>10.3} {:>7} {:>10.5} {:>9.3}",
            alpha,
            p.m_dot_kg_s * 3600.0,
            p.w_spec_j_kg.map_or("n/a".to_string(), |w| format!("{w:.1}")),
            p.p_avg_w,
            p.n_wire,
            p.f_stroke_hz,
            sim.lost_fraction
        )?;
    }
    if let Some(r) = requirements {
        let rejected: Vec<(f64, &str)> =
            rows.iter().filter_map(|row| row.result.as_ref().err().map(|e| (row.alpha_deg, e.rule()))).collect();
        write_verdicts(out, r, &crate::engine::slopes::assessed(&rows), &rejected)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn status(met: bool) -> &'static str {
    if met {
        "compliant"
    } else {
        "NOT compliant"
    }
}

/// The verdicts of Table 2.2 at the worst slope, each with its margin (like Table 5.5).
fn write_verdicts(
    out: &mut dyn Write,
    r: &Requirements,
    per_slope: &[(f64, Assessment)],
    rejected: &[(f64, &str)],
) -> std::io::Result<()> {
    let Some((alpha, a)) = worst_over_slopes(per_slope) else { return Ok(()) };
    // a power-limited point meets its limit to the last bit: no "-0.000 W" margins
    let tidy = |m: f64| if m.abs() < 1e-9 { 0.0 } else { m };
    let all_compliant = per_slope.iter().all(|(_, x)| x.compliant());
    let (covered, coverage) = crate::engine::slopes::slope_coverage(r, per_slope);
    let op = &a.operating_point;
    writeln!(out)?;
    writeln!(out, "requirements ({}), judged at the worst slope {alpha} deg", r.source)?;
    writeln!(
        out,
        "operating point  {:.3} kg/h at {:.5} Hz drawing {:.3} W (set by: {}; full capacity {:.3} kg/h)",
        op.m_dot_kg_h,
        op.f_stroke_hz,
        op.p_avg_w,
        op.limit.as_str(),
        a.m_dot_max_kg_h
    )?;
    writeln!(
        out,
        "1.1   feed rate >= {} kg/h     {:>10.3} kg/h  margin {:+.3} kg/h  {}",
        r.feed_rate_min_kg_h,
        op.m_dot_kg_h,
        tidy(a.feed_rate.margin),
        status(a.feed_rate.met())
    )?;
    writeln!(
        out,
        "1.1   target {} kg/h           {:>10.3} kg/h  {}",
        r.feed_rate_target_kg_h,
        op.m_dot_kg_h,
        if a.feed_rate_target_met { "target met" } else { "below target" }
    )?;
    writeln!(
        out,
        "1.4   power <= {} W             {:>10.3} W     margin {:+.3} W     {}",
        r.power_max_w,
        op.p_avg_w,
        tidy(a.power.margin),
        status(a.power.met())
    )?;
    writeln!(
        out,
        "5.5   wire <= sled {:.4} m     {:>10.4} m     margin {:+.4} m     {}",
        a.sled_length_m,
        a.wire_length_m,
        a.wire_length.margin,
        status(a.wire_length.met())
    )?;
    writeln!(out, "1.2   material loss            {:>10.3}       reported (Table 2.2: minimised)", a.lost_fraction)?;
    writeln!(
        out,
        "1.6.3 slopes {}..{} deg         {}: {}",
        r.slope_min_deg,
        r.slope_max_deg,
        coverage,
        if !covered { "not assessed over the range" } else { status(all_compliant) }
    )?;
    let names: Vec<String> = NOT_ASSESSED.iter().map(|(id, n)| format!("{id} {n}")).collect();
    writeln!(out, "not assessed by the model: {}", names.join("; "))?;
    let verdict = match (all_compliant, covered) {
        (true, true) => "COMPLIANT with every assessed requirement".to_string(),
        (true, false) => "compliant at the slopes evaluated; the slope range is not assessed".to_string(),
        (false, _) if !rejected.is_empty() => {
            let at: Vec<String> = rejected.iter().map(|(alpha, rule)| format!("{alpha} deg ({rule})")).collect();
            format!("NOT compliant: the model rejects the design at {}", at.join(", "))
        }
        (false, _) => format!("NOT compliant: {} binds", a.binding().unwrap_or("a requirement")),
    };
    writeln!(out, "verdict          {verdict}")
}

fn describe(d: &Design) -> String {
    DesignRow::of(d).to_string()
}

fn write_table(out: &mut dyn Write, s: &Scenario, d: &Design, engine: &str, det: &Detailed) -> std::io::Result<()> {
    let sim = &det.evaluation.sim;
    let p = &det.evaluation.performance;
    let mode = match s.mode {
        PhysicsMode::Physical => "physical (thesis text)",
        PhysicsMode::Listing => "listing compatibility",
    };
    writeln!(out, "design     {}", describe(d))?;
    writeln!(
        out,
        "scenario   g {} m/s2, alpha {} deg, drag {}, AOR {} deg, k_elastic {}, mu {}, {} particles, {} teeth, seed {}",
        s.environment.g,
        s.environment.alpha_deg,
        s.environment.k_drag.map_or("off".to_string(), |k| format!("{k} 1/s")),
        s.material.aor_deg,
        s.collision.k_elastic,
        s.collision.mu_friction,
        s.sim.particles,
        s.sim.teeth,
        s.sim.seed
    )?;
    writeln!(out, "engine     {engine}, mode {mode}")?;
    let effects = s.effects.active();
    writeln!(
        out,
        "effects    {}",
        if effects.is_empty() { "none (the thesis's model)".to_string() } else { effects.join(", ") }
    )?;
    writeln!(out)?;
    writeln!(out, "tooth  fraction")?;
    for (j, f) in sim.distribution.iter().enumerate().filter(|(_, f)| **f > 0.0) {
        writeln!(out, "{:>5}  {:>7.3}", j + 1, f)?;
    }
    writeln!(out, " lost  {:>7.3}", sim.lost_fraction)?;
    let (ex, sx) = centre_and_dispersion(&sim.distribution);
    writeln!(out)?;
    writeln!(out, "d_avg            {:>10.4} m   (listing semantics: x of the resting tooth's p4)", sim.d_avg_m)?;
    writeln!(out, "advance          {:>10.4} m   (teeth advanced x pitch)", sim.advance_m)?;
    writeln!(out, "centre of mass   {:>10.3} teeth, dispersion {:.3}", ex, sx)?;
    writeln!(out, "unsettled        {:>10.3}", sim.unsettled_fraction)?;
    writeln!(out, "fill area        {:>10.1} mm2", sim.fill_area_mm2)?;
    writeln!(out, "bounce loop      {:>10} iterations, {:.1} impacts per particle", sim.bounces, sim.mean_bounces)?;
    writeln!(out)?;
    writeln!(out, "stroke           {:>10.2} mm", p.stroke_m * 1e3)?;
    writeln!(out, "n_wire           {:>10}", p.n_wire)?;
    writeln!(out, "t_cool           {:>10.2} s", p.t_cool_s)?;
    writeln!(out, "f_stroke         {:>10.5} Hz", p.f_stroke_hz)?;
    writeln!(out, "mass flow        {:>10.4} kg/s ({:.2} kg/h)", p.m_dot_kg_s, p.m_dot_kg_s * 3600.0)?;
    match p.w_spec_j_kg {
        Some(w) => writeln!(out, "W_spec           {:>10.1} J/kg", w)?,
        None => writeln!(out, "W_spec                  n/a (no mass flow)")?,
    }
    writeln!(out, "P_avg            {:>10.3} W", p.p_avg_w)?;
    Ok(())
}
