//! The end of an optimisation: the final front re-evaluated with more particles over
//! independent particle streams (Monte-Carlo standard errors), pareto.csv like Table C.6,
//! the picks A/B/C of 5.5 printed like Table 5.2, and a Pareto plot.

use std::io::Write;
use std::path::Path;

use anyhow::Context as _;

use super::nsga2::{Nsga2, State};
use super::runner::Manifest;
use super::sawtooth::{design_of, slope_scenarios, violation};
use crate::engine::BatchEvaluator;
use crate::io::atomic::write_atomic;
use crate::model::requirements::{Assessment, Limit};
use crate::model::{Design, Scenario};
use serde::{Deserialize, Serialize};

/// Target mass flow of solution A (5.5): 48 kg/h, in kg/s.
pub const TARGET_MASS_FLOW_KG_S: f64 = 48.0 / 3600.0;

#[derive(Clone, Debug, PartialEq)]
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
    /// Average heating power at the full (cooling-limited) frequency, W.
    pub p_avg_w: f64,
    /// SMA wire length l_stroke / ε (5.5), m.
    pub wire_length_m: f64,
    /// The slope these figures are at, degrees: the worst one where the run judged several.
    pub alpha_deg: f64,
    /// The requirements' verdict there, when the run had requirements.
    pub compliance: Option<Compliance>,
}

/// A front design against the run's requirements (`model::requirements`), at the slope
/// where it does worst.
#[derive(Clone, Debug, PartialEq)]
pub struct Compliance {
    pub f_op_hz: f64,
    pub m_dot_op_kg_h: f64,
    pub p_op_w: f64,
    pub operating_limit: Limit,
    /// Compliant at every slope the run judged.
    pub compliant: bool,
    /// The requirement that fails worst, if any.
    pub binding: Option<String>,
}

/// One row of pareto.csv (like Table C.6): header and row from this one type, units in
/// every name, floats written exactly (shortest round trip) so that summaries made from the
/// file equal those made in the run.
#[derive(Debug, Serialize, Deserialize)]
struct ParetoRow {
    l_c_mm: f64,
    l_a_mm: f64,
    l_b_mm: f64,
    r_mm: f64,
    omega_deg: f64,
    delta_deg: f64,
    v0_m_s: f64,
    a_m_s2: f64,
    f_stroke_hz: f64,
    w_spec_j_kg: f64,
    m_dot_kg_s: f64,
    stroke_m: f64,
    n_wire: u32,
    d_avg_m: f64,
    w_spec_se_j_kg: f64,
    m_dot_se_kg_s: f64,
    d_avg_se_m: f64,
    // columns added with issue 13; absent in older files
    #[serde(default = "nan")]
    p_avg_w: f64,
    #[serde(default = "nan")]
    wire_length_m: f64,
    #[serde(default = "nan")]
    alpha_deg: f64,
    #[serde(default)]
    f_op_hz: Option<f64>,
    #[serde(default)]
    m_dot_op_kg_h: Option<f64>,
    #[serde(default)]
    p_op_w: Option<f64>,
    #[serde(default)]
    operating_limit: Option<Limit>,
    #[serde(default)]
    compliant: Option<bool>,
    #[serde(default)]
    binding_requirement: Option<String>,
}

fn nan() -> f64 {
    f64::NAN
}

impl From<&FrontPoint> for ParetoRow {
    fn from(p: &FrontPoint) -> Self {
        let x = p.design.to_cli_units();
        let c = p.compliance.as_ref();
        ParetoRow {
            l_c_mm: x[0],
            l_a_mm: x[1],
            l_b_mm: x[2],
            r_mm: x[3],
            omega_deg: x[4],
            delta_deg: x[5],
            v0_m_s: x[6],
            a_m_s2: x[7],
            f_stroke_hz: p.f_stroke_hz,
            w_spec_j_kg: p.w_spec_j_kg,
            m_dot_kg_s: p.m_dot_kg_s,
            stroke_m: p.stroke_m,
            n_wire: p.n_wire,
            d_avg_m: p.d_avg_m,
            w_spec_se_j_kg: p.w_spec_se,
            m_dot_se_kg_s: p.m_dot_se,
            d_avg_se_m: p.d_avg_se,
            p_avg_w: p.p_avg_w,
            wire_length_m: p.wire_length_m,
            alpha_deg: p.alpha_deg,
            f_op_hz: c.map(|c| c.f_op_hz),
            m_dot_op_kg_h: c.map(|c| c.m_dot_op_kg_h),
            p_op_w: c.map(|c| c.p_op_w),
            operating_limit: c.map(|c| c.operating_limit),
            compliant: c.map(|c| c.compliant),
            binding_requirement: c.and_then(|c| c.binding.clone()),
        }
    }
}

impl From<ParetoRow> for FrontPoint {
    fn from(r: ParetoRow) -> Self {
        let compliance = match (r.f_op_hz, r.m_dot_op_kg_h, r.p_op_w, r.operating_limit, r.compliant) {
            (Some(f_op_hz), Some(m_dot_op_kg_h), Some(p_op_w), Some(operating_limit), Some(compliant)) => {
                Some(Compliance {
                    f_op_hz,
                    m_dot_op_kg_h,
                    p_op_w,
                    operating_limit,
                    compliant,
                    binding: r.binding_requirement,
                })
            }
            _ => None,
        };
        FrontPoint {
            design: Design::from_cli_units([
                r.l_c_mm,
                r.l_a_mm,
                r.l_b_mm,
                r.r_mm,
                r.omega_deg,
                r.delta_deg,
                r.v0_m_s,
                r.a_m_s2,
            ]),
            f_stroke_hz: r.f_stroke_hz,
            w_spec_j_kg: r.w_spec_j_kg,
            w_spec_se: r.w_spec_se_j_kg,
            m_dot_kg_s: r.m_dot_kg_s,
            m_dot_se: r.m_dot_se_kg_s,
            stroke_m: r.stroke_m,
            n_wire: r.n_wire,
            d_avg_m: r.d_avg_m,
            d_avg_se: r.d_avg_se_m,
            p_avg_w: r.p_avg_w,
            wire_length_m: r.wire_length_m,
            alpha_deg: r.alpha_deg,
            compliance,
        }
    }
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
/// batch one job with its own particle streams (and every slope of the run in that job).
pub fn final_front(engine: &dyn BatchEvaluator, m: &Manifest, state: &State) -> anyhow::Result<Vec<FrontPoint>> {
    let mut designs: Vec<Design> = Vec::new();
    for ind in Nsga2::pareto_front(state) {
        // Under Deb's rules the first front holds infeasible designs only when no design met
        // the constraints: with requirements those are still reported, with what binds (they
        // must pass the geometric constraints to be simulated at all)
        let reportable = m.requirements.is_some() && violation(&ind.x) == 0.0;
        if ind.eval.violation > 0.0 && !reportable {
            continue;
        }
        let d = design_of(&ind.x);
        if !designs.contains(&d) {
            designs.push(d);
        }
    }
    let scenarios = slope_scenarios(&m.scenario, &m.slopes_deg);
    // per[slope][design]: the replicates' evaluations
    let mut per: Vec<Vec<Vec<crate::engine::Evaluation>>> = vec![vec![Vec::new(); designs.len()]; scenarios.len()];
    for r in 0..m.replicates.max(1) {
        let groups: Vec<(Scenario, Vec<Design>)> = scenarios
            .iter()
            .map(|s| {
                let mut s = s.clone();
                s.sim.particles = m.final_particles;
                s.sim.seed = m.seed ^ 0xF1A1_F00D_0000_0000u64.wrapping_add(r as u64);
                (s, designs.clone())
            })
            .collect();
        let results = match groups.as_slice() {
            [(s, d)] => vec![engine.evaluate(s, d)],
            _ => engine.evaluate_groups(&groups),
        };
        for (k, group) in results.into_iter().enumerate() {
            for (i, res) in group.into_iter().enumerate() {
                if let Ok(e) = res {
                    per[k][i].push(e);
                }
            }
        }
    }
    let mut out = Vec::new();
    'design: for (i, d) in designs.iter().enumerate() {
        // each slope's figures, averaged over the replicates
        let mut at_slopes = Vec::with_capacity(scenarios.len());
        for (k, s) in scenarios.iter().enumerate() {
            let evals = &per[k][i];
            let w: Vec<f64> = evals.iter().filter_map(|e| e.performance.w_spec_j_kg).collect();
            if w.is_empty() {
                continue 'design; // no mass flow at some slope: not a front design after all
            }
            let (w_spec, w_se) = mean_se(&w);
            let (m_dot, m_se) = mean_se(&evals.iter().map(|e| e.performance.m_dot_kg_s).collect::<Vec<_>>());
            let (d_avg, d_se) = mean_se(&evals.iter().map(|e| e.sim.d_avg_m).collect::<Vec<_>>());
            let lost = evals.iter().map(|e| e.sim.lost_fraction).sum::<f64>() / evals.len() as f64;
            let mut perf = evals[0].performance.clone();
            perf.m_dot_kg_s = m_dot;
            perf.w_spec_j_kg = Some(w_spec);
            let assessment = m.requirements.as_ref().map(|r| r.assess(&perf, &s.performance, lost));
            let p = &evals[0].performance;
            let point = FrontPoint {
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
                p_avg_w: p.p_avg_w,
                wire_length_m: p.stroke_m / s.performance.contraction_ratio,
                alpha_deg: s.environment.alpha_deg,
                compliance: None,
            };
            at_slopes.push((point, assessment));
        }
        out.push(worst_slope(at_slopes));
    }
    out.sort_by(|a, b| b.m_dot_kg_s.total_cmp(&a.m_dot_kg_s)); // D.5 sorts by mass flow
    Ok(out)
}

/// The figures at the slope where a design does worst: the one failing the requirements
/// most, else the highest W_spec; compliant only if compliant at every slope.
fn worst_slope(at_slopes: Vec<(FrontPoint, Option<Assessment>)>) -> FrontPoint {
    let all_compliant = at_slopes.iter().all(|(_, a)| a.as_ref().is_some_and(|a| a.compliant()));
    let badness = |(p, a): &(FrontPoint, Option<Assessment>)| {
        let c = a.as_ref().map_or(f64::NEG_INFINITY, |a| a.constraints().into_iter().fold(f64::NEG_INFINITY, f64::max));
        (if c > 0.0 { c } else { f64::NEG_INFINITY }, p.w_spec_j_kg)
    };
    let (mut point, assessment) = at_slopes
        .into_iter()
        .max_by(|a, b| {
            let (ca, wa) = badness(a);
            let (cb, wb) = badness(b);
            ca.total_cmp(&cb).then(wa.total_cmp(&wb))
        })
        .expect("at least one slope");
    point.compliance = assessment.map(|a| Compliance {
        f_op_hz: a.operating_point.f_stroke_hz,
        m_dot_op_kg_h: a.operating_point.m_dot_kg_h,
        p_op_w: a.operating_point.p_avg_w,
        operating_limit: a.operating_point.limit,
        compliant: all_compliant,
        binding: a.binding().map(str::to_string),
    });
    point
}

pub fn write_outputs(dir: &Path, front: &[FrontPoint], evaluations_csv: &Path) -> anyhow::Result<()> {
    write_atomic(&dir.join("pareto.csv"), &pareto_csv(front)?)?;
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

/// Picks A (closest to 48 kg/h), B (highest mass flow), C (lowest W_spec) as in Table 5.2;
/// where the run judged requirements, among the compliant designs only (all designs when
/// none complies, which [`print_picks`] says), and A is the one with the highest feed rate
/// at its operating point.
pub fn picks(front: &[FrontPoint]) -> Vec<(&'static str, &FrontPoint)> {
    let compliant: Vec<&FrontPoint> =
        front.iter().filter(|p| p.compliance.as_ref().is_some_and(|c| c.compliant)).collect();
    let pool: Vec<&FrontPoint> = if compliant.is_empty() { front.iter().collect() } else { compliant };
    let mut out = Vec::new();
    // A: with requirements, the highest feed rate at the operating point (which stops at the
    // target), lower W_spec breaking ties; without, the full-frequency mass flow closest to it
    let a = if pool.iter().all(|p| p.compliance.is_some()) {
        pool.iter().max_by(|a, b| {
            let (ca, cb) = (a.compliance.as_ref().expect("judged"), b.compliance.as_ref().expect("judged"));
            ca.m_dot_op_kg_h.total_cmp(&cb.m_dot_op_kg_h).then(b.w_spec_j_kg.total_cmp(&a.w_spec_j_kg))
        })
    } else {
        pool.iter().min_by(|a, b| {
            (a.m_dot_kg_s - TARGET_MASS_FLOW_KG_S).abs().total_cmp(&(b.m_dot_kg_s - TARGET_MASS_FLOW_KG_S).abs())
        })
    };
    if let Some(a) = a {
        out.push(("A", *a));
    }
    if let Some(b) = pool.iter().max_by(|a, b| a.m_dot_kg_s.total_cmp(&b.m_dot_kg_s)) {
        out.push(("B", *b));
    }
    if let Some(c) = pool.iter().min_by(|a, b| a.w_spec_j_kg.total_cmp(&b.w_spec_j_kg)) {
        out.push(("C", *c));
    }
    out
}

/// What a reader of the picks must know: whether they meet the requirements, and whether
/// "closest to 48 kg/h" is anywhere near it.
pub fn pick_notes(front: &[FrontPoint]) -> Vec<String> {
    let mut notes = Vec::new();
    let judged = front.iter().filter(|p| p.compliance.is_some()).count();
    if judged > 0 {
        let compliant = front.iter().filter(|p| p.compliance.as_ref().is_some_and(|c| c.compliant)).count();
        if compliant == 0 {
            let mut binding: Vec<&str> =
                front.iter().filter_map(|p| p.compliance.as_ref()?.binding.as_deref()).collect();
            binding.sort();
            binding.dedup();
            notes.push(format!(
                "no front design meets the requirements (failing: {}); the picks are among all of them",
                binding.join(", ")
            ));
        } else {
            notes.push(format!(
                "picks among the {compliant} of {} front designs that meet the requirements",
                front.len()
            ));
        }
    }
    let (lo, hi) = (6.0 / 3600.0, TARGET_MASS_FLOW_KG_S); // Table 2.2 req. 1.1
    let unjudged = front.iter().all(|p| p.compliance.is_none());
    if unjudged && !front.is_empty() && !front.iter().any(|p| (lo..=hi * 1.001).contains(&p.m_dot_kg_s)) {
        let nearest = picks(front).first().map_or(0.0, |(_, p)| p.m_dot_kg_s * 3600.0);
        notes.push(format!(
            "no front design delivers 6-48 kg/h at full frequency; A ({nearest:.1} kg/h) is only the closest to 48 kg/h"
        ));
    }
    notes
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
    if front.iter().any(|p| p.compliance.is_some()) {
        writeln!(
            out,
            "{:<4} {:>8} {:>14} {:>9} {:>10} {:>11} {:>10}",
            "", "alpha", "m_dot_op", "P_op", "set by", "wire [m]", "verdict"
        )?;
        for (name, p) in picks(front) {
            let c = p.compliance.as_ref().expect("judged");
            writeln!(
                out,
                "{name:<4} {:>8.1} {:>9.2} kg/h {:>7.3} W {:>10} {:>11.4} {:>10}",
                p.alpha_deg,
                c.m_dot_op_kg_h,
                c.p_op_w,
                c.operating_limit.as_str(),
                p.wire_length_m,
                if c.compliant {
                    "compliant".to_string()
                } else {
                    format!("fails {}", c.binding.as_deref().unwrap_or("?"))
                }
            )?;
        }
    }
    for note in pick_notes(front) {
        writeln!(out, "note: {note}")?;
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
/// pareto.csv's bytes: one header, one row per front design.
pub fn pareto_csv(front: &[FrontPoint]) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    if front.is_empty() {
        // serde writes the header with the first row; an empty front still gets its header
        w.write_record(PARETO_HEADER)?;
    }
    for p in front {
        w.serialize(ParetoRow::from(p))?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("writing pareto.csv: {e}"))
}

/// pareto.csv's columns, in order (a test checks it against `ParetoRow`).
const PARETO_HEADER: [&str; 26] = [
    "l_c_mm",
    "l_a_mm",
    "l_b_mm",
    "r_mm",
    "omega_deg",
    "delta_deg",
    "v0_m_s",
    "a_m_s2",
    "f_stroke_hz",
    "w_spec_j_kg",
    "m_dot_kg_s",
    "stroke_m",
    "n_wire",
    "d_avg_m",
    "w_spec_se_j_kg",
    "m_dot_se_kg_s",
    "d_avg_se_m",
    "p_avg_w",
    "wire_length_m",
    "alpha_deg",
    "f_op_hz",
    "m_dot_op_kg_h",
    "p_op_w",
    "operating_limit",
    "compliant",
    "binding_requirement",
];

pub fn read_pareto_csv(path: &Path) -> anyhow::Result<Vec<FrontPoint>> {
    let mut r = csv::Reader::from_path(path).with_context(|| format!("reading {}", path.display()))?;
    let mut out = Vec::new();
    for (i, row) in r.deserialize::<ParetoRow>().enumerate() {
        let row = row.with_context(|| format!("{}: row {}", path.display(), i + 2))?;
        out.push(FrontPoint::from(row));
    }
    Ok(out)
}

/// The front point whose mass flow is closest to `target` (kg/s): how 5.4 and Tables
/// C.1-C.5 compare runs.
pub fn closest_to_mass_flow(front: &[FrontPoint], target: f64) -> Option<&FrontPoint> {
    front.iter().min_by(|a, b| (a.m_dot_kg_s - target).abs().total_cmp(&(b.m_dot_kg_s - target).abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(m_dot_kg_h: f64, w_spec: f64, compliant: Option<bool>) -> FrontPoint {
        FrontPoint {
            design: Design::lunar_solution_c(),
            f_stroke_hz: 0.1 / 3.0,
            w_spec_j_kg: w_spec,
            w_spec_se: 1.0 / 7.0,
            m_dot_kg_s: m_dot_kg_h / 3600.0,
            m_dot_se: 1e-5,
            stroke_m: 0.011,
            n_wire: 37,
            d_avg_m: 0.17,
            d_avg_se: f64::NAN,
            p_avg_w: 9.5,
            wire_length_m: 0.22,
            alpha_deg: 35.0,
            compliance: compliant.map(|ok| Compliance {
                f_op_hz: 0.018,
                m_dot_op_kg_h: 48.0,
                p_op_w: 4.75,
                operating_limit: Limit::Target,
                compliant: ok,
                binding: (!ok).then(|| "1.4 power".to_string()),
            }),
        }
    }

    #[test]
    fn pareto_csv_round_trips_exactly_with_its_header() {
        let front = vec![point(95.9, 356.6, Some(true)), point(20.0, 1234.5, Some(false)), point(7.0, 99.0, None)];
        let d = tempfile::tempdir().unwrap();
        let path = d.path().join("pareto.csv");
        std::fs::write(&path, pareto_csv(&front).unwrap()).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().next().unwrap(), PARETO_HEADER.join(","));
        let back = read_pareto_csv(&path).unwrap();
        assert_eq!(back.len(), 3);
        for (a, b) in front.iter().zip(&back) {
            // exact, not rounded (1/7 and 0.1/3 have no short decimal form); NaN stays NaN
            assert_eq!(a.w_spec_se.to_bits(), b.w_spec_se.to_bits());
            assert_eq!(a.f_stroke_hz.to_bits(), b.f_stroke_hz.to_bits());
            assert!(b.d_avg_se.is_nan());
            assert_eq!(a.compliance, b.compliance);
            assert_eq!(a.design, b.design);
        }
        // an empty front still has the header
        std::fs::write(&path, pareto_csv(&[]).unwrap()).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap().trim_end(), PARETO_HEADER.join(","));
    }

    #[test]
    fn picks_come_from_the_compliant_designs_and_say_so() {
        let front =
            vec![point(131.0, 300.0, Some(false)), point(40.0, 500.0, Some(true)), point(30.0, 400.0, Some(true))];
        let chosen = picks(&front);
        assert!(chosen.iter().all(|(_, p)| p.compliance.as_ref().unwrap().compliant), "{chosen:?}");
        assert_eq!(chosen[1].1.m_dot_kg_s, 40.0 / 3600.0); // B: the highest compliant mass flow
        assert!(pick_notes(&front)[0].contains("2 of 3"));
        let none = vec![point(131.0, 300.0, Some(false))];
        assert_eq!(picks(&none).len(), 3);
        let notes = pick_notes(&none);
        assert!(notes[0].contains("no front design meets the requirements") && notes[0].contains("1.4 power"));
        // without requirements, A far from the target is named as such
        let unjudged = vec![point(131.0, 300.0, None), point(95.0, 200.0, None)];
        let notes = pick_notes(&unjudged);
        assert!(notes[0].contains("no front design delivers 6-48 kg/h") && notes[0].contains("95.0"), "{notes:?}");
    }
}
