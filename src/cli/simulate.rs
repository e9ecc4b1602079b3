//! `sawtooth simulate`: one design, readable table or `--json`.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;
use serde_json::json;

use super::args::{EngineArgs, ScenarioArgs};
use crate::engine::{evaluate_detailed, make_engine_for, Detailed, EngineKind};
use crate::model::outcome::centre_and_dispersion;
use crate::model::{Design, PhysicsMode, Scenario};

#[derive(Debug, Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
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
    let (scenario, file_design) = a.scenario.resolve()?;
    let design = match (&a.design, file_design) {
        (Some(s), _) => Design::parse_cli(s).map_err(anyhow::Error::msg)?,
        (None, Some(d)) => d,
        (None, None) => {
            bail!("no design: pass --design l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a or a config file with [design]")
        }
    };
    if let Some(p) = &a.plot {
        // checked before simulating: a wrong name should not cost a run
        crate::plot::Format::of(p, "--plot")?;
    }
    let trace = a.trajectories.is_some() || a.plot.is_some();
    if trace && (scenario.effects.sled_motion.is_some() || scenario.effects.quadratic_drag.is_some()) {
        bail!("--trajectories and --plot redraw each flight as one closed-form arc; with the sled-motion or quadratic-drag effects that would be wrong, so they are not offered");
    }
    if trace && matches!(a.engine.engine, EngineKind::Gpu | EngineKind::Auto) {
        bail!(
            "--trajectories and --plot record every flight, which only the CPU engines do: use --engine cpu or listing"
        );
    }
    let engine = make_engine_for(a.engine.engine, &scenario)?;
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
        crate::io::plot::write_plot(p, "--plot", &det, scenario.environment.g, k_drag, &title)?;
    }
    if a.json {
        let v = to_json(&scenario, &design, engine.name(), &det);
        writeln!(out, "{}", serde_json::to_string_pretty(&v)?).context("writing output")?;
    } else {
        write_table(out, &scenario, &design, engine.name(), &det).context("writing output")?;
    }
    Ok(ExitCode::SUCCESS)
}

fn describe(d: &Design) -> String {
    let v = d.to_cli_units();
    format!(
        "l_c {:.3} l_a {:.3} l_b {:.3} r {:.3} mm, omega {:.2} delta {:.2} deg, v0 {:.3} m/s, a {:.2} m/s2",
        v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]
    )
}

pub fn to_json(s: &Scenario, d: &Design, engine: &str, det: &Detailed) -> serde_json::Value {
    let sim = &det.evaluation.sim;
    let (ex, sx) = centre_and_dispersion(&sim.distribution);
    json!({
        "engine": engine,
        "mode": s.mode,
        "design": {
            "l_c_mm": d.l_c * 1e3, "l_a_mm": d.l_a * 1e3, "l_b_mm": d.l_b * 1e3, "r_mm": d.r * 1e3,
            "omega_deg": d.omega_deg, "delta_deg": d.delta_deg, "v0_m_s": d.v0, "a_m_s2": d.a,
        },
        "distribution": sim.distribution,
        "d_avg_m": sim.d_avg_m,
        "advance_m": sim.advance_m,
        "lost_fraction": sim.lost_fraction,
        "unsettled_fraction": sim.unsettled_fraction,
        "fill_area_mm2": sim.fill_area_mm2,
        "bounces": sim.bounces,
        "mean_bounces": sim.mean_bounces,
        "centre_of_mass_teeth": ex,
        "dispersion_teeth": sx,
        "performance": det.evaluation.performance,
    })
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
