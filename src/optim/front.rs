//! The end of an optimisation: the final front re-evaluated with more particles over
//! independent particle streams (Monte-Carlo standard errors), pareto.csv like Table C.6,
//! the picks A/B/C of 5.5 printed like Table 5.2, and a Pareto plot (through `crate::plot`).

use std::io::Write;
use std::path::Path;

use anyhow::Context as _;

use super::nsga2::{Nsga2, State};
use super::runner::Manifest;
use super::sawtooth::design_of;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::engine::BatchEvaluator;
use crate::io::atomic::write_atomic;
use crate::model::Design;
use crate::plot::{self, Drawn as _, Figure, Mark};

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
    plot::write_figure(&dir.join("pareto.svg"), "pareto.svg", &ParetoPlot::new(&cloud, front))
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
            "grey: {} feasible evaluations, {} of them outside these axes (zoomed onto the front); red: the final front ({} designs) re-evaluated, bars ±1 standard error",
            self.cloud.len(),
            self.outside(),
            self.front.len()
        )
    }

    fn legend(&self) -> [(Mark, &'static str); 3] {
        [
            (Mark::Point(CLOUD_COLOUR), "all evaluations"),
            (Mark::Point(FRONT_COLOUR), "final front (re-evaluated)"),
            (Mark::Ring(PICK_COLOUR), "picks: A closest to 48 kg/h, B highest mass flow, C lowest W_spec"),
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
        chart
            .configure_mesh()
            .x_desc("stroke frequency f_stroke [Hz]")
            .y_desc(if self.log_y { "specific work W_spec [J/kg] (log)" } else { "specific work W_spec [J/kg]" })
            .x_label_formatter(&plot::tick)
            .y_label_formatter(&plot::tick)
            .label_style(plot::text_style(plot::SMALL_SIZE))
            .axis_desc_style(plot::text_style(plot::LABEL_SIZE))
            .bold_line_style(plot::GRID)
            .max_light_lines(1)
            .draw()
            .drawn()?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::tests::{assert_has_ticks, assert_real_png, svg_texts};

    fn point(f: f64, w: f64, m_dot: f64) -> FrontPoint {
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
        }
    }

    /// A front spanning two decades of W_spec and a cloud with far outliers.
    fn example() -> (Vec<[f64; 2]>, Vec<FrontPoint>) {
        // B: highest mass flow, A: closest to 48 kg/h (0.0133 kg/s), C: lowest W_spec
        let front = vec![point(0.2, 2000.0, 0.03), point(0.1, 150.0, 0.013), point(0.05, 20.0, 0.005)];
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
        let front = vec![point(0.2, 20.0, 0.05), point(0.1, 150.0, 0.013)];
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
