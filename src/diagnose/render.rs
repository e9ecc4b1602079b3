//! Outputs of `diagnose`: the three figures drawn through `crate::plot` (residuals with error
//! bars, the effect ranking by score with the gaps' intervals, fitted vs measured
//! distributions), and every output file (report.md, diagnosis.json, the figures) written
//! atomically.

use std::path::Path;

use anyhow::Context as _;
use serde_json::Value;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::diagnose::{Diagnosis, ModelResult, INTERVAL, RANKING_RULE, Z_FLAG};
use super::markdown::{to_markdown, tooth_label};
use crate::io::atomic::write_atomic;
use crate::plot::{self, Drawn as _, Figure, Mark};

const BLUE: RGBColor = RGBColor(0x2c, 0x6f, 0xbb);
const RED: RGBColor = RGBColor(0xc0, 0x39, 0x2b);
const GREEN: RGBColor = RGBColor(0x1e, 0x84, 0x49);
const ORANGE: RGBColor = RGBColor(0xd6, 0x89, 0x10);
const GREY: RGBColor = RGBColor(0x99, 0x99, 0x99);
const DARK_GREY: RGBColor = RGBColor(0x55, 0x55, 0x55);
/// Width of every diagnose figure and height of one condition's panel, in pixels.
const WIDTH_PX: u32 = 900;
const PANEL_PX: u32 = 330;

/// A vertical interval from `lo` to `hi` at `x`, `width` pixels wide.
fn interval(x: f64, lo: f64, hi: f64, colour: RGBColor, width: u32) -> PathElement<(f64, f64)> {
    PathElement::new(vec![(x, lo), (x, hi)], colour.stroke_width(width))
}

fn range_of(values: impl Iterator<Item = f64>, pad: f64, include_zero: bool) -> std::ops::Range<f64> {
    let (lo, hi) = plot::extent(values).unwrap_or((0.0, 1.0));
    let (lo, hi) = if include_zero { (lo.min(0.0), hi.max(0.0)) } else { (lo, hi) };
    plot::padded(lo, hi, pad)
}

/// residuals.svg: per condition, the baseline's residual (simulated − measured, pp) per tooth
/// with ±1 (thick) and ±2 (thin) uncertainty bars, red where |z| > Z_FLAG.
pub struct ResidualsPlot<'a>(pub &'a Diagnosis);

impl ResidualsPlot<'_> {
    fn legend() -> [(Mark, String); 4] {
        [
            (Mark::Point(BLUE), "residual".to_string()),
            (Mark::Line(BLUE), "±1 uncertainty (thick), ±2 (thin)".to_string()),
            (Mark::Point(RED), format!("flagged: |z| > {Z_FLAG}")),
            (Mark::Line(BLACK), "zero".to_string()),
        ]
    }
}

impl Figure for ResidualsPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let legend = Self::legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        let title = (plot::TITLE_SIZE * 1.6) as u32;
        (WIDTH_PX, title + PANEL_PX * self.0.conditions.len() as u32 + plot::legend_height(WIDTH_PX, &entries))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let d = self.0;
        let area = plot::title(root, "Where: the baseline's residual per tooth")?;
        let (_, h) = area.dim_in_pixel();
        let (panels, key) = area.split_vertically(PANEL_PX * d.conditions.len() as u32);
        let panels = panels.split_evenly((d.conditions.len().max(1), 1));
        for ((c, w), panel) in d.conditions.iter().zip(&d.where_).zip(&panels) {
            let rs = &w.teeth_residuals;
            let y = range_of(
                rs.iter().flat_map(|r| [r.residual - 2.0 * r.uncertainty, r.residual + 2.0 * r.uncertainty]),
                0.08,
                true,
            );
            let labels: Vec<String> =
                (0..rs.len()).map(|j| tooth_label(j, w.shown_teeth, c.last_bin_label())).collect();
            let x_desc = format!(
                "tooth (E_x residual {:+.3}, z {:+.1}; σ_x residual {:+.3}, z {:+.1})",
                w.centre.residual, w.centre.z, w.dispersion.residual, w.dispersion.z
            );
            let mut chart =
                plot::category_chart(panel, Some(&c.name), &labels, y, &x_desc, "simulated − measured [pp]")?;
            let n = labels.len() as f64;
            chart.draw_series(std::iter::once(PathElement::new(vec![(-0.5, 0.0), (n - 0.5, 0.0)], BLACK))).drawn()?;
            for (j, r) in rs.iter().enumerate() {
                let (x, colour) = (j as f64, if r.flagged() { RED } else { BLUE });
                let (v, u) = (r.residual, r.uncertainty);
                if u.is_finite() {
                    chart.draw_series([interval(x, v - 2.0 * u, v + 2.0 * u, colour, 1)]).drawn()?;
                    chart.draw_series([interval(x, v - u, v + u, colour, 4)]).drawn()?;
                }
                if v.is_finite() {
                    chart.draw_series([Circle::new((x, v), 5, colour.filled())]).drawn()?;
                }
            }
        }
        let _ = h;
        let legend = Self::legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        plot::legend(&key, &entries)
    }
}

/// ranking.svg: every model's held-out gap with its bootstrap interval and the score that
/// orders the ranking (gap + the penalty for extra parameters), baseline first, then by rank.
pub struct RankingPlot<'a>(pub &'a Diagnosis);

const RANKING_LEGEND: [(Mark, &str); 3] = [
    (Mark::Point(BLUE), "held-out gap with its bootstrap interval"),
    (Mark::Diamond(BLACK), "score (orders the ranking)"),
    (Mark::Line(GREY), "baseline's gap"),
];
const RANKING_ROW_PX: u32 = 44;

impl RankingPlot<'_> {
    fn models(&self) -> Vec<&ModelResult> {
        std::iter::once(&self.0.baseline).chain(self.0.ranking.iter()).collect()
    }

    /// The row labels: "baseline", then "1. name", "2. name", ...
    fn labels(&self) -> Vec<String> {
        std::iter::once("baseline".to_string())
            .chain(self.0.ranking.iter().enumerate().map(|(i, m)| format!("{}. {}", i + 1, m.name())))
            .collect()
    }

    fn footer(&self) -> String {
        format!(
            "{RANKING_RULE}. Colours: green best, orange indistinguishable from the top-ranked effect, blue other effects, grey baseline. Intervals {:.0}-{:.0} % bootstrap percentiles. best = {}",
            100.0 * INTERVAL.0,
            100.0 * INTERVAL.1,
            self.0.best.map_or("none", |e| e.name())
        )
    }

    fn colour(&self, m: &ModelResult) -> RGBColor {
        let d = self.0;
        if m.effects.is_empty() {
            DARK_GREY
        } else if m.single().is_some() && m.single() == d.best {
            GREEN
        } else if m.single().is_some_and(|e| d.indistinguishable.contains(&e)) {
            ORANGE
        } else {
            BLUE
        }
    }

    fn heights(&self) -> (u32, u32, u32) {
        let chart = RANKING_ROW_PX * self.models().len() as u32 + 110;
        let key = plot::legend_height(WIDTH_PX, &RANKING_LEGEND);
        let footer = plot::wrapped_height(WIDTH_PX, &self.footer(), plot::SMALL_SIZE);
        (chart, key, footer)
    }
}

impl Figure for RankingPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let (chart, key, footer) = self.heights();
        (WIDTH_PX, (plot::TITLE_SIZE * 1.6) as u32 + chart + key + footer)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let area = plot::title(root, "Which: candidate effects ranked by score")?;
        let (chart_h, key_h, _) = self.heights();
        let (chart_area, rest) = area.split_vertically(chart_h);
        let (key, footer) = rest.split_vertically(key_h);
        let models = self.models();
        let n = models.len();
        // the first row (baseline) at the top: row i sits at y = n - 1 - i
        let labels: Vec<String> = self.labels().into_iter().rev().collect();
        let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(8) as f64;
        let x = range_of(models.iter().flat_map(|m| [m.interval[0], m.interval[1], m.gap, m.score]), 0.06, true);
        let mut chart = ChartBuilder::on(&chart_area)
            .margin(15)
            .margin_right(30)
            .x_label_area_size(55)
            .y_label_area_size((0.62 * plot::LABEL_SIZE * longest + 25.0) as u32)
            .build_cartesian_2d(x, plot::category_range(n))
            .drawn()?;
        let y_label = plot::category_label(&labels);
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(n + 1)
            .y_label_formatter(&y_label)
            .x_label_formatter(&plot::tick)
            .x_desc("held-out gap and score: loss-adjusted SSE summed over conditions [%²]")
            .label_style(plot::text_style(plot::LABEL_SIZE))
            .axis_desc_style(plot::text_style(plot::LABEL_SIZE))
            .bold_line_style(plot::GRID)
            .max_light_lines(1)
            .draw()
            .drawn()?;
        let base = self.0.baseline.gap;
        let top = n as f64 - 0.5;
        chart.draw_series([PathElement::new(vec![(base, -0.5), (base, top)], GREY.stroke_width(2))]).drawn()?;
        for (i, m) in models.iter().enumerate() {
            let y = (n - 1 - i) as f64;
            let colour = self.colour(m);
            if m.interval.iter().all(|v| v.is_finite()) {
                let line = vec![(m.interval[0], y), (m.interval[1], y)];
                chart.draw_series([PathElement::new(line, colour.stroke_width(3))]).drawn()?;
            }
            if m.gap.is_finite() {
                chart.draw_series([Circle::new((m.gap, y), 6, colour.filled())]).drawn()?;
            }
            if m.score.is_finite() {
                chart
                    .draw_series([EmptyElement::at((m.score, y))
                        + Polygon::new(vec![(-7, -14), (0, -21), (7, -14), (0, -7)], BLACK.filled())])
                    .drawn()?;
            }
        }
        plot::legend(&key, &RANKING_LEGEND)?;
        plot::draw_wrapped(&footer, &self.footer(), plot::SMALL_SIZE)
    }
}

/// distributions.svg: per condition, measured (with the runs' min-max), baseline and the
/// top-ranked effect's share of mass per tooth.
pub struct DistributionsPlot<'a>(pub &'a Diagnosis);

impl DistributionsPlot<'_> {
    fn legend(&self) -> [(Mark, String); 4] {
        let effect = self.0.gap_model().map_or("effect".to_string(), |m| m.name());
        [
            (Mark::Block(GREY), "measured".to_string()),
            (Mark::Line(BLACK), "runs' min-max".to_string()),
            (Mark::Block(BLUE), "baseline".to_string()),
            (Mark::Block(GREEN), effect),
        ]
    }
}

impl Figure for DistributionsPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let legend = self.legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        let title = (plot::TITLE_SIZE * 1.6) as u32;
        (WIDTH_PX, title + PANEL_PX * self.0.conditions.len() as u32 + plot::legend_height(WIDTH_PX, &entries))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let d = self.0;
        let area = plot::title(root, "How far: measured, baseline and top-ranked effect per tooth")?;
        let (panels, key) = area.split_vertically(PANEL_PX * d.conditions.len() as u32);
        let panels = panels.split_evenly((d.conditions.len().max(1), 1));
        for (((c, g), w), panel) in d.conditions.iter().zip(&d.gap).zip(&d.where_).zip(&panels) {
            let teeth = c.teeth();
            let idx: Vec<usize> = (0..w.shown_teeth).chain(std::iter::once(teeth)).collect();
            let sum = &w.measured_summary;
            let hi = idx
                .iter()
                .flat_map(|&j| [g.measured[j], g.before[j], g.after[j], sum.max.get(j).copied().unwrap_or(0.0)])
                .filter(|v| v.is_finite())
                .fold(0.0f64, f64::max);
            let labels: Vec<String> =
                idx.iter().map(|&j| if j < teeth { format!("{}", j + 1) } else { c.last_bin_label().into() }).collect();
            let y = 0.0..(100.0 * hi * 1.08).max(1.0);
            let mut chart = plot::category_chart(panel, Some(&c.name), &labels, y, "tooth", "share of mass [%]")?;
            const BAR: f64 = 0.25;
            for (k, &j) in idx.iter().enumerate() {
                let xc = k as f64;
                for (m, (v, colour)) in
                    [(g.measured[j], GREY), (g.before[j], BLUE), (g.after[j], GREEN)].into_iter().enumerate()
                {
                    let x = xc + (m as f64 - 1.5) * BAR;
                    if v.is_finite() {
                        chart
                            .draw_series([Rectangle::new([(x, 0.0), (x + BAR, 100.0 * v)], colour.filled())])
                            .drawn()?;
                    }
                }
                // the runs' spread, the last bin's too (what each run did not recover)
                if j < sum.min.len() && sum.min[j].is_finite() && sum.max[j].is_finite() {
                    let x = xc - BAR;
                    chart.draw_series([interval(x, 100.0 * sum.min[j], 100.0 * sum.max[j], BLACK, 2)]).drawn()?;
                }
            }
        }
        let legend = self.legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        plot::legend(&key, &entries)
    }
}

/// Write report.md, diagnosis.json and the SVGs into `dir` (created if missing).
pub fn write_dir(dir: &Path, d: &Diagnosis, json: &Value) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create directory {}", dir.display()))?;
    write_atomic(&dir.join("diagnosis.json"), format!("{}\n", serde_json::to_string_pretty(json)?).as_bytes())?;
    write_atomic(&dir.join("report.md"), to_markdown(d).as_bytes())?;
    plot::write_figure_files(dir, "residuals", &ResidualsPlot(d))?;
    plot::write_figure_files(dir, "ranking", &RankingPlot(d))?;
    plot::write_figure_files(dir, "distributions", &DistributionsPlot(d))
}
