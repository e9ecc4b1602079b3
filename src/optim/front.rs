//! The end of an optimisation: the final front re-evaluated with more particles over
//! independent particle streams (Monte-Carlo standard errors), pareto.csv like Table C.6,
//! the picks A/B/C of 5.5 printed like Table 5.2, and a Pareto plot (through `crate::plot`).

use std::io::Write;
use std::path::Path;

use anyhow::Context as _;

use super::manifest::Manifest;
use super::nsga2::{Nsga2, State};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::sawtooth::{design_of, shown_slope, slope_scenarios, violation};
use crate::engine::BatchEvaluator;
use crate::io::atomic::write_atomic;
use crate::model::design::DesignRow;
use crate::model::requirements::{Assessment, Limit};
use crate::model::{Design, Scenario};
use crate::plot::{self, Drawn as _, Figure, Mark};

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
#[derive(Debug, Default, Serialize, Deserialize)]
struct ParetoRow {
    #[serde(flatten)]
    design: DesignRow,
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
        let c = p.compliance.as_ref();
        ParetoRow {
            design: DesignRow::of(&p.design),
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
            design: r.design.design(),
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

/// The figures at the slope where a design does worst (`shown_slope`: the one failing the
/// requirements most, else the highest W_spec); compliant only if compliant at every slope.
fn worst_slope(mut at_slopes: Vec<(FrontPoint, Option<Assessment>)>) -> FrontPoint {
    let all_compliant = at_slopes.iter().all(|(_, a)| a.as_ref().is_some_and(|a| a.compliant()));
    let keys: Vec<(Option<f64>, f64)> =
        at_slopes.iter().map(|(p, a)| (a.as_ref().map(Assessment::worst_constraint), p.w_spec_j_kg)).collect();
    let (mut point, assessment) = at_slopes.swap_remove(shown_slope(&keys));
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
    plot::write_figure_files(dir, "pareto", &ParetoPlot::new(&evaluation_cloud(evaluations_csv)?, front))
}

/// Every simulated design's (f_stroke, W_spec) from evaluations.csv, read by column name;
/// designs without mass flow (or not simulated) have empty cells there and are left out.
fn evaluation_cloud(evaluations_csv: &Path) -> anyhow::Result<Vec<[f64; 2]>> {
    let mut r =
        csv::Reader::from_reader(crate::io::bounded::open_bounded(evaluations_csv, &crate::schema::EVALUATIONS_FILE)?);
    let headers = r.headers()?.clone();
    let column = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .with_context(|| format!("{}: no column {name}", evaluations_csv.display()))
    };
    let (f, w) = (column("f_stroke_hz")?, column("w_spec_j_kg")?);
    let mut cloud = Vec::new();
    for row in r.records() {
        let row = row?;
        if let (Some(Ok(f)), Some(Ok(w))) = (row.get(f).map(str::parse::<f64>), row.get(w).map(str::parse::<f64>)) {
            cloud.push([f, w]);
        }
    }
    Ok(cloud)
}

/// Objective space like Figure 5.2: every evaluation grey, the re-evaluated front red with its
/// Monte-Carlo standard errors, the picks A/B/C ringed and labelled. The axes are zoomed onto
/// the front (outlying evaluations would squash it flat); the caption counts what lies outside.
/// W_spec gets a log axis when the front spans a decade or more.
struct ParetoPlot<'a> {
    cloud: &'a [[f64; 2]],
    front: &'a [FrontPoint],
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    log_y: bool,
}

const PARETO_SIZE: (u32, u32) = (900, 640);
const CLOUD_COLOUR: RGBColor = RGBColor(0xb0, 0xb0, 0xb0);
const FRONT_COLOUR: RGBColor = RGBColor(0xd6, 0x27, 0x28);
const PICK_COLOUR: RGBColor = RGBColor(0x10, 0x10, 0x10);

impl<'a> ParetoPlot<'a> {
    fn new(cloud: &'a [[f64; 2]], front: &'a [FrontPoint]) -> ParetoPlot<'a> {
        // zoom onto the front; with no front, onto the cloud
        let focus: Vec<[f64; 2]> = if front.is_empty() {
            cloud.to_vec()
        } else {
            front.iter().map(|p| [p.f_stroke_hz, p.w_spec_j_kg]).collect()
        };
        let (x0, x1) = plot::extent(focus.iter().map(|p| p[0])).unwrap_or((0.0, 1.0));
        let (y0, y1) = plot::extent(focus.iter().map(|p| p[1])).unwrap_or((1.0, 10.0));
        let log_y = plot::spans_decades(y0, y1);
        let y = if log_y { plot::padded_log(y0, y1, 0.12) } else { plot::padded(y0, y1, 0.15) };
        ParetoPlot { cloud, front, x: plot::padded(x0, x1, 0.15), y, log_y }
    }

    fn outside(&self) -> usize {
        self.cloud.iter().filter(|p| !self.x.contains(&p[0]) || !self.y.contains(&p[1])).count()
    }

    fn caption(&self) -> String {
        format!(
            "grey: {} simulated evaluations with mass flow, {} of them outside these axes (zoomed onto the front); red: the final front ({} designs) re-evaluated, bars ±1 standard error",
            self.cloud.len(),
            self.outside(),
            self.front.len()
        )
    }

    fn legend(&self) -> [(Mark, &'static str); 3] {
        [
            (Mark::Point(CLOUD_COLOUR), "all evaluations"),
            (Mark::Point(FRONT_COLOUR), "final front (re-evaluated)"),
            (
                Mark::Ring(PICK_COLOUR),
                if self.front.iter().any(|p| p.compliance.is_some()) {
                    "picks among compliant designs: A most feed at its operating point, B highest mass flow, C lowest W_spec"
                } else {
                    "picks: A closest to 48 kg/h, B highest mass flow, C lowest W_spec"
                },
            ),
        ]
    }

    fn draw_on<DB: DrawingBackend, Y>(&self, area: &DrawingArea<DB, Shift>, y: Y) -> anyhow::Result<()>
    where
        Y: AsRangedCoord<Value = f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let mut chart = ChartBuilder::on(area)
            .margin(15)
            .margin_right(30)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(self.x.clone(), y)
            .drawn()?;
        let y_desc = if self.log_y { "specific work W_spec [J/kg] (log)" } else { "specific work W_spec [J/kg]" };
        plot::draw_numeric_axes(&mut chart, "stroke frequency f_stroke [Hz]", y_desc)?;
        let inside = |p: &(f64, f64)| self.x.contains(&p.0) && self.y.contains(&p.1);
        let cloud = self.cloud.iter().map(|p| (p[0], p[1])).filter(inside);
        chart.draw_series(cloud.map(|p| Circle::new(p, 2, CLOUD_COLOUR.filled()))).drawn()?;
        let (ylo, yhi) = (self.y.start, self.y.end);
        let bars = self.front.iter().filter(|p| p.w_spec_se.is_finite() && p.w_spec_se > 0.0).map(|p| {
            let (a, b) = ((p.w_spec_j_kg - p.w_spec_se).max(ylo), (p.w_spec_j_kg + p.w_spec_se).min(yhi));
            PathElement::new(vec![(p.f_stroke_hz, a), (p.f_stroke_hz, b)], FRONT_COLOUR.stroke_width(1))
        });
        chart.draw_series(bars).drawn()?;
        let front = self.front.iter().map(|p| (p.f_stroke_hz, p.w_spec_j_kg));
        chart.draw_series(front.map(|p| Circle::new(p, 4, FRONT_COLOUR.filled()))).drawn()?;
        // one ring per picked design; a design picked twice gets both names ("B, C")
        let mut marked: Vec<(&FrontPoint, String)> = Vec::new();
        for (name, p) in picks(self.front) {
            match marked.iter_mut().find(|(q, _)| std::ptr::eq(*q, p)) {
                Some((_, names)) => *names = format!("{names}, {name}"),
                None => marked.push((p, name.to_string())),
            }
        }
        let label = plot::text_style(plot::LABEL_SIZE);
        chart
            .draw_series(marked.iter().map(|(p, names)| {
                EmptyElement::at((p.f_stroke_hz, p.w_spec_j_kg))
                    + Circle::new((0, 0), 9, PICK_COLOUR.stroke_width(2))
                    + Text::new(names.clone(), (10, -22), label.clone())
            }))
            .drawn()?;
        Ok(())
    }
}

impl Figure for ParetoPlot<'_> {
    fn size(&self) -> (u32, u32) {
        PARETO_SIZE
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let area = plot::title(root, "Objective space: stroke frequency vs specific work")?;
        let (w, h) = area.dim_in_pixel();
        let legend = self.legend();
        let key_h = plot::legend_height(w, &legend);
        let caption_h = plot::wrapped_height(w, &self.caption(), plot::SMALL_SIZE);
        let (chart_area, rest) = area.split_vertically(h - key_h - caption_h);
        let (key, caption) = rest.split_vertically(key_h);
        if self.log_y {
            self.draw_on(&chart_area, self.y.clone().log_scale())?;
        } else {
            self.draw_on(&chart_area, self.y.clone())?;
        }
        plot::legend(&key, &legend)?;
        plot::draw_wrapped(&caption, &self.caption(), plot::SMALL_SIZE)
    }
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
    // a standard error needs two replicates: with one it is NaN, shown as "n/a"
    let se = |v: f64, digits: usize| if v.is_finite() { format!("{v:<4.digits$}") } else { "n/a ".to_string() };
    for (name, p) in picks(front) {
        writeln!(
            out,
            "{name:<4} {:>12.3} {:>9.1} ± {:<4} {:>8.2} ± {:<4} {:>10.2} {:>7} {:>10.2}",
            p.f_stroke_hz * 100.0,
            p.w_spec_j_kg,
            se(p.w_spec_se, 1),
            p.m_dot_kg_s * 3600.0,
            se(p.m_dot_se * 3600.0, 2),
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
        writeln!(out, "{name}: --design {}", DesignRow::of(&p.design).cli_argument())?;
    }
    Ok(())
}

/// pareto.csv's bytes: one header, one row per front design (`io::table`: the header from
/// `ParetoRow`, also for an empty front).
pub fn pareto_csv(front: &[FrontPoint]) -> anyhow::Result<Vec<u8>> {
    let rows: Vec<ParetoRow> = front.iter().map(ParetoRow::from).collect();
    Ok(crate::io::table::table_text(&rows)?.into_bytes())
}

/// Read a finished run's pareto.csv back (resuming sweeps and studies skip finished runs).
pub fn read_pareto_csv(path: &Path) -> anyhow::Result<Vec<FrontPoint>> {
    let text = crate::io::bounded::read_text(path, &crate::schema::PARETO_FILE)?;
    parse_pareto_csv(&text, &path.display().to_string())
}

/// The rows of a pareto.csv's `text` (`name`: the file, for messages).
pub fn parse_pareto_csv(text: &str, name: &str) -> anyhow::Result<Vec<FrontPoint>> {
    let path = Path::new(name);
    let mut r = csv::Reader::from_reader(text.as_bytes());
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
    /// pareto.csv's columns, in order: what users' scripts read.
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

    use super::*;
    use crate::plot::tests::{assert_has_ticks, assert_real_png, svg_texts};

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
    fn picks_without_replicates_show_no_nan() {
        // one replicate: no standard error to show
        let mut p = point(30.0, 500.0, None);
        (p.w_spec_se, p.m_dot_se) = (f64::NAN, f64::NAN);
        let mut out = Vec::new();
        print_picks(&mut out, &[p.clone()], "generation limit", 3).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(!text.contains("NaN"), "{text}");
        assert!(text.contains("500.0 ± n/a"), "{text}");
        // with replicates the standard errors are printed as before
        let mut out = Vec::new();
        print_picks(&mut out, &[point(30.0, 500.0, None)], "generation limit", 3).unwrap();
        assert!(String::from_utf8(out).unwrap().contains("500.0 ± 0.1"));
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

    fn plot_point(f: f64, w: f64, m_dot: f64) -> FrontPoint {
        FrontPoint {
            design: Design::from_cli_units([47.0, 46.0, 32.0, 43.0, 94.0, 11.0, 0.84, 32.0]),
            f_stroke_hz: f,
            w_spec_j_kg: w,
            w_spec_se: 0.05 * w,
            m_dot_kg_s: m_dot,
            m_dot_se: 0.0,
            stroke_m: 0.01,
            n_wire: 1,
            d_avg_m: 1e-3,
            d_avg_se: 0.0,
            p_avg_w: 1.0,
            wire_length_m: 0.2,
            alpha_deg: 35.0,
            compliance: None,
        }
    }

    /// A front spanning two decades of W_spec and a cloud with far outliers.
    fn example() -> (Vec<[f64; 2]>, Vec<FrontPoint>) {
        // B: highest mass flow, A: closest to 48 kg/h (0.0133 kg/s), C: lowest W_spec
        let front = vec![plot_point(0.2, 2000.0, 0.03), plot_point(0.1, 150.0, 0.013), plot_point(0.05, 20.0, 0.005)];
        let mut cloud: Vec<[f64; 2]> = (0..50).map(|i| [0.05 + 0.003 * i as f64, 30.0 + 50.0 * i as f64]).collect();
        cloud.push([1.9, 90_000.0]);
        (cloud, front)
    }

    #[test]
    fn pareto_svg_has_ticks_units_picks_and_counts_outliers() {
        let (cloud, front) = example();
        let fig = ParetoPlot::new(&cloud, &front);
        assert!(fig.log_y, "a front over two decades gets a log W_spec axis");
        assert!(fig.y.end < 1e4 && fig.x.end < 1.0, "zoomed onto the front: {:?} {:?}", fig.x, fig.y);
        assert!(fig.caption().contains("outside these axes") && fig.outside() >= 1);
        let svg = plot::render_svg(&fig).unwrap();
        let texts = svg_texts(&svg);
        for want in ["A", "B", "C", "stroke frequency f_stroke [Hz]", "specific work W_spec [J/kg] (log)"] {
            assert!(texts.iter().any(|t| t == want), "{want} missing: {texts:?}");
        }
        assert!(texts.iter().any(|t| t.contains(&format!("{} of them outside", fig.outside()))), "{texts:?}");
        assert_has_ticks(&svg, 5);
    }

    #[test]
    fn a_design_picked_twice_carries_both_names() {
        // one design with the highest flow and the lowest W_spec: B and C
        let front = vec![plot_point(0.2, 20.0, 0.05), plot_point(0.1, 150.0, 0.013)];
        let svg = plot::render_svg(&ParetoPlot::new(&[], &front)).unwrap();
        assert!(svg_texts(&svg).iter().any(|t| t == "B, C"), "{:?}", svg_texts(&svg));
    }

    #[test]
    fn pareto_png_is_a_real_image() {
        let (cloud, front) = example();
        let fig = ParetoPlot::new(&cloud, &front);
        assert_real_png(&plot::render_png(&fig).unwrap(), PARETO_SIZE);
    }
}
