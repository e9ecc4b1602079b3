//! The end of an optimisation: the final front re-evaluated with more particles over
//! independent particle streams (Monte-Carlo standard errors), pareto.csv like Table C.6,
//! the picks A/B/C of 5.5 printed like Table 5.2, and a Pareto plot.

use std::io::Write;
use std::path::Path;

use anyhow::Context as _;

use super::nsga2::{Nsga2, State};
use super::runner::Manifest;
use super::sawtooth::design_of;
use crate::engine::BatchEvaluator;
use crate::io::atomic::write_atomic;
use crate::model::Design;

/// Target mass flow of solution A (5.5): 48 kg/h, in kg/s.
pub const TARGET_MASS_FLOW_KG_S: f64 = 48.0 / 3600.0;

#[derive(Clone, Debug)]
pub struct FrontPoint {
    pub design: Design,
    pub f_stroke_hz: f64,
    pub w_spec_j_kg: f64,
    pub w_spec_se: f64,
    pub m_dot_kg_s: f64,
    pub m_dot_se: f64,
    pub stroke_m: f64,
    pub n_wire: u32,
    pub d_avg_m: f64,
    pub d_avg_se: f64,
}

fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    if v.len() < 2 {
        return (m, f64::NAN);
    }
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Re-evaluate the final front: `replicates` batches with `final_particles` particles, each
/// batch one job with its own particle streams.
pub fn final_front(engine: &dyn BatchEvaluator, m: &Manifest, state: &State) -> anyhow::Result<Vec<FrontPoint>> {
    let mut designs: Vec<Design> = Vec::new();
    for ind in Nsga2::pareto_front(state) {
        if ind.eval.violation > 0.0 {
            continue;
        }
        let d = design_of(&ind.x);
        if !designs.contains(&d) {
            designs.push(d);
        }
    }
    let mut per: Vec<Vec<crate::engine::Evaluation>> = vec![Vec::new(); designs.len()];
    for r in 0..m.replicates.max(1) {
        let mut s = m.scenario.clone();
        s.sim.particles = m.final_particles;
        s.sim.seed = m.seed ^ 0xF1A1_F00D_0000_0000u64.wrapping_add(r as u64);
        for (i, res) in engine.evaluate(&s, &designs).into_iter().enumerate() {
            if let Ok(e) = res {
                per[i].push(e);
            }
        }
    }
    let mut out = Vec::new();
    for (d, evals) in designs.iter().zip(per) {
        let w: Vec<f64> = evals.iter().filter_map(|e| e.performance.w_spec_j_kg).collect();
        if w.is_empty() {
            continue;
        }
        let (w_spec, w_se) = mean_se(&w);
        let (m_dot, m_se) = mean_se(&evals.iter().map(|e| e.performance.m_dot_kg_s).collect::<Vec<_>>());
        let (d_avg, d_se) = mean_se(&evals.iter().map(|e| e.sim.d_avg_m).collect::<Vec<_>>());
        let p = &evals[0].performance;
        out.push(FrontPoint {
            design: *d,
            f_stroke_hz: p.f_dynamic_hz,
            w_spec_j_kg: w_spec,
            w_spec_se: w_se,
            m_dot_kg_s: m_dot,
            m_dot_se: m_se,
            stroke_m: p.stroke_m,
            n_wire: p.n_wire,
            d_avg_m: d_avg,
            d_avg_se: d_se,
        });
    }
    out.sort_by(|a, b| b.m_dot_kg_s.total_cmp(&a.m_dot_kg_s)); // D.5 sorts by mass flow
    Ok(out)
}

pub fn write_outputs(dir: &Path, front: &[FrontPoint], evaluations_csv: &Path) -> anyhow::Result<()> {
    let mut csv = String::from(
        "l_c_mm,l_a_mm,l_b_mm,r_mm,omega_deg,delta_deg,v0_m_s,a_m_s2,f_stroke_hz,w_spec_j_kg,m_dot_kg_s,stroke_m,n_wire,d_avg_m,w_spec_se_j_kg,m_dot_se_kg_s,d_avg_se_m\n",
    );
    for p in front {
        let x = p.design.to_cli_units();
        csv.push_str(&format!(
            "{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.6e},{:.4},{:.6e},{:.6e},{},{:.6e},{:.4},{:.3e},{:.3e}\n",
            x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], p.f_stroke_hz, p.w_spec_j_kg, p.m_dot_kg_s, p.stroke_m, p.n_wire, p.d_avg_m, p.w_spec_se, p.m_dot_se, p.d_avg_se
        ));
    }
    write_atomic(&dir.join("pareto.csv"), csv.as_bytes())?;
    let text =
        std::fs::read_to_string(evaluations_csv).with_context(|| format!("reading {}", evaluations_csv.display()))?;
    let mut cloud = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if let (Some(a), Some(b)) =
            (f.get(9).and_then(|v| v.parse::<f64>().ok()), f.get(10).and_then(|v| v.parse::<f64>().ok()))
        {
            if a > 0.0 && a < 2.0 && b < 1e5 {
                cloud.push([a, b]);
            }
        }
    }
    let pts: Vec<[f64; 2]> = front.iter().map(|p| [p.f_stroke_hz, p.w_spec_j_kg]).collect();
    write_atomic(&dir.join("pareto.svg"), pareto_svg(&cloud, &pts).as_bytes())
}

/// Objective space like Figure 5.2: every evaluation grey, the re-evaluated front red.
fn pareto_svg(cloud: &[[f64; 2]], front: &[[f64; 2]]) -> String {
    let all: Vec<&[f64; 2]> = cloud.iter().chain(front).collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in &all {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let (w, h, m) = (640.0, 440.0, 60.0);
    let sx = |x: f64| m + (x - x0) / (x1 - x0).max(1e-12) * (w - 2.0 * m);
    let sy = |y: f64| h - m - (y - y0) / (y1 - y0).max(1e-12) * (h - 2.0 * m);
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    s.push_str(&format!(r#"<rect x="0" y="0" width="{w}" height="{h}" fill="white"/>"#));
    s.push_str(&format!(
        r#"<rect x="{m}" y="{m}" width="{}" height="{}" fill="none" stroke="black"/>"#,
        w - 2.0 * m,
        h - 2.0 * m
    ));
    for p in cloud {
        s.push_str(&format!(r##"<circle cx="{:.2}" cy="{:.2}" r="1.5" fill="#bbb"/>"##, sx(p[0]), sy(p[1])));
    }
    for p in front {
        s.push_str(&format!(r##"<circle cx="{:.2}" cy="{:.2}" r="3" fill="#d62728"/>"##, sx(p[0]), sy(p[1])));
    }
    s.push_str(&format!(
        r#"<text x="{}" y="{}" text-anchor="middle">f_stroke [Hz]  ({x0:.4} .. {x1:.4})</text>"#,
        w / 2.0,
        h - 20.0
    ));
    s.push_str(&format!(r#"<text x="15" y="{}" transform="rotate(-90 15 {})" text-anchor="middle">W_spec [J/kg]  ({y0:.0} .. {y1:.0})</text>"#, h / 2.0, h / 2.0));
    s.push_str(&format!(r#"<text x="{m}" y="30">grey: all evaluations; red: final front, re-evaluated</text>"#));
    s.push_str("</svg>\n");
    s
}

/// Picks A (closest to 48 kg/h), B (highest mass flow), C (lowest W_spec) as in Table 5.2.
pub fn picks(front: &[FrontPoint]) -> Vec<(&'static str, &FrontPoint)> {
    let mut out = Vec::new();
    if let Some(a) = front.iter().min_by(|a, b| {
        (a.m_dot_kg_s - TARGET_MASS_FLOW_KG_S).abs().total_cmp(&(b.m_dot_kg_s - TARGET_MASS_FLOW_KG_S).abs())
    }) {
        out.push(("A", a));
    }
    if let Some(b) = front.iter().max_by(|a, b| a.m_dot_kg_s.total_cmp(&b.m_dot_kg_s)) {
        out.push(("B", b));
    }
    if let Some(c) = front.iter().min_by(|a, b| a.w_spec_j_kg.total_cmp(&b.w_spec_j_kg)) {
        out.push(("C", c));
    }
    out
}

pub fn print_picks(
    out: &mut dyn Write,
    front: &[FrontPoint],
    termination: &str,
    generations: u64,
) -> anyhow::Result<()> {
    writeln!(
        out,
        "stopped after {generations} generations ({termination}); {} front designs re-evaluated",
        front.len()
    )?;
    writeln!(
        out,
        "{:<4} {:>12} {:>16} {:>14} {:>10} {:>7} {:>10}",
        "", "f [Hz e-2]", "W_spec [J/kg]", "m_dot [kg/h]", "l_str [mm]", "n_wire", "d_avg [mm]"
    )?;
    for (name, p) in picks(front) {
        writeln!(
            out,
            "{name:<4} {:>12.3} {:>9.1} ± {:<4.1} {:>8.2} ± {:<4.2} {:>10.2} {:>7} {:>10.2}",
            p.f_stroke_hz * 100.0,
            p.w_spec_j_kg,
            p.w_spec_se,
            p.m_dot_kg_s * 3600.0,
            p.m_dot_se * 3600.0,
            p.stroke_m * 1e3,
            p.n_wire,
            p.d_avg_m * 1e3
        )?;
    }
    for (name, p) in picks(front) {
        let x = p.design.to_cli_units();
        writeln!(
            out,
            "{name}: --design {:.3},{:.3},{:.3},{:.3},{:.2},{:.2},{:.3},{:.2}",
            x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]
        )?;
    }
    Ok(())
}

/// Read a finished run's pareto.csv back (resuming sweeps and studies skip finished runs).
pub fn read_pareto_csv(path: &Path) -> anyhow::Result<Vec<FrontPoint>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}:{}: not a number", path.display(), i + 1))?;
        if v.len() < 17 {
            anyhow::bail!("{}:{}: expected 17 columns, got {}", path.display(), i + 1, v.len());
        }
        out.push(FrontPoint {
            design: Design::from_cli_units([v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]]),
            f_stroke_hz: v[8],
            w_spec_j_kg: v[9],
            m_dot_kg_s: v[10],
            stroke_m: v[11],
            n_wire: v[12] as u32,
            d_avg_m: v[13],
            w_spec_se: v[14],
            m_dot_se: v[15],
            d_avg_se: v[16],
        });
    }
    Ok(out)
}

/// The front point whose mass flow is closest to `target` (kg/s): how 5.4 and Tables
/// C.1-C.5 compare runs.
pub fn closest_to_mass_flow(front: &[FrontPoint], target: f64) -> Option<&FrontPoint> {
    front.iter().min_by(|a, b| (a.m_dot_kg_s - target).abs().total_cmp(&(b.m_dot_kg_s - target).abs()))
}
