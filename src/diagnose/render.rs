//! Outputs of `diagnose`: report.md, diagnosis.json and three figures drawn through
//! `crate::plot` (residuals with error bars, the effect ranking by score with the gaps'
//! intervals, fitted vs measured distributions), every file written atomically.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;
use serde_json::Value;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::diagnose::{Diagnosis, ModelResult, Residual, INTERVAL, RANKING_RULE, Z_FLAG};
use crate::io::atomic::write_atomic;
use crate::plot::{self, Drawn as _, Figure, Mark};

fn f(v: f64, d: usize) -> String {
    if v.is_finite() {
        format!("{v:.d$}")
    } else {
        "–".into()
    }
}

fn capitalised(t: &str) -> String {
    let mut c = t.chars();
    c.next().map_or(String::new(), |first| first.to_uppercase().chain(c).collect())
}

fn iv(v: [f64; 2], d: usize) -> String {
    format!("[{}, {}]", f(v[0], d), f(v[1], d))
}

fn params_text(m: &ModelResult) -> String {
    // small SI values (a grain diameter in m) keep three significant digits
    let show = |v: f64| if v != 0.0 && v.abs() < 0.01 { format!("{v:.3e}") } else { f(v, 3) };
    m.names.iter().zip(&m.full.x).map(|(n, v)| format!("{n} {}", show(*v))).collect::<Vec<_>>().join(", ")
}

fn tooth_label(j: usize, shown: usize, last: &str) -> String {
    if j < shown {
        format!("{}", j + 1)
    } else {
        last.into()
    }
}

fn residual_row(label: &str, r: &Residual, d: usize) -> String {
    format!(
        "| {label} | {} | {} | {} | {} ({} / {} / {}) | {} | {} |",
        f(r.measured, d),
        f(r.simulated, d),
        f(r.residual, d),
        f(r.uncertainty, d),
        f(r.parts[0], d),
        f(r.parts[1], d),
        f(r.parts[2], d),
        f(r.z, 2),
        if r.flagged() { "**yes**" } else { "" }
    )
}

/// report.md.
pub fn to_markdown(d: &Diagnosis) -> String {
    let mut s = String::new();
    let b = &d.baseline;
    let _ = writeln!(s, "# Diagnosis of the sim-to-real gap\n");
    let _ = writeln!(s, "| condition | data | setup | runs | measured teeth | scale resolution (g) | drag | motion profile | stated sled motion (delay s, return m/s) |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    let stated = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v}"));
    for c in &d.conditions {
        let _ = writeln!(
            s,
            "| {} | `{}` | `{}` | {} | {} | {} | {} | {} | {}, {} |",
            c.name,
            c.data,
            c.setup,
            c.runs.runs.len(),
            c.runs.teeth,
            c.resolution_g,
            c.base.environment.k_drag.map_or("vacuum".to_string(), |_| "Stokes".to_string()),
            c.motion_profile.as_deref().unwrap_or("–"),
            stated(c.motion.delay_s),
            stated(c.motion.return_speed_m_s)
        );
    }
    let bu = d.settings.effort;
    let _ = writeln!(
        s,
        "\nShared parameters fitted jointly: {}. Engine `{}`, {} particles (common random numbers, seed {}), \
         differential evolution {} × {} generations at 1/8 of the particles + {} compass-search iterations per fit, \
         every fit re-scored on {} fresh particle streams, {} bootstrap replicates; intervals are the {:.0}-{:.0} % percentiles.\n",
        d.shared.iter().map(|p| p.name()).collect::<Vec<_>>().join(", "),
        d.engine,
        d.particles,
        bu.seed,
        bu.pop,
        bu.generations,
        bu.polish,
        d.settings.rescore_streams,
        d.settings.bootstrap,
        100.0 * INTERVAL.0,
        100.0 * INTERVAL.1
    );
    for n in &d.notes {
        let _ = writeln!(s, "> Note: {n}\n");
    }

    // VERDICT
    let v = &d.verdict;
    let _ = writeln!(s, "## Verdict: {}\n", v.kind.name());
    let _ = writeln!(s, "{}.\n", capitalised(&v.text));
    let _ = writeln!(
        s,
        "Judged on each model's mean bins over its fresh streams, after letting each condition lose in handling up to \
         the share of its loaded mass the runs did not recover (fitted; Table 4.4: Test 3 recovered 97.7 %). Noise \
         floor = Σ over bins of the measured mean's variance (run-to-run / runs, floored by the scale) and the \
         simulation's Monte-Carlo variance; \"well above\" is more than {}× the floor, pooled or in one condition \
         against that condition's own floor.\n",
        super::verdict::FLOOR_FACTOR
    );
    let _ = writeln!(
        s,
        "| model | condition | gap (%², loss-adjusted) | floor (%²) | gap / floor | well above | handling loss % |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    let above = |gap: f64, floor: f64| if gap > super::verdict::FLOOR_FACTOR * floor { "yes" } else { "no" };
    for j in [&v.baseline, &v.remaining] {
        for (c, cond) in d.conditions.iter().enumerate() {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                j.model,
                cond.name,
                f(j.gap_by_condition[c], 1),
                f(j.floor_by_condition[c], 2),
                f(j.gap_by_condition[c] / j.floor_by_condition[c], 1),
                above(j.gap_by_condition[c], j.floor_by_condition[c]),
                f(100.0 * j.handling_loss[c], 2)
            );
        }
        let _ = writeln!(
            s,
            "| {} | all | {} | {} | {} | {} | |",
            j.model,
            f(j.gap, 1),
            f(j.floor, 2),
            f(j.ratio(), 1),
            above(j.gap, j.floor)
        );
    }
    let _ = writeln!(
        s,
        "\nWhat no fitted model removes (per bin, the smallest miss of the baseline and every candidate where all miss \
         on the same side; \"from depth\" is where the baseline's grains in that tooth were launched, top / middle / \
         bottom third of the fill):\n"
    );
    let _ = writeln!(
        s,
        "| condition | bin | residual (pp) | noise (pp) | z | flag | from depth (% top / middle / bottom) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for (c, p) in d.conditions.iter().zip(&v.persistent) {
        for b in &p.bins {
            let depth = b.from_depth.iter().map(|(_, v)| f(*v, 0)).collect::<Vec<_>>().join(" / ");
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                c.name,
                b.label,
                f(b.residual, 2),
                f(b.uncertainty, 2),
                f(b.z, 1),
                if b.flagged() { "**yes**" } else { "" },
                if depth.is_empty() { "–".to_string() } else { depth }
            );
        }
    }
    let _ = writeln!(s);

    // WHERE
    let _ = writeln!(s, "## Where: the baseline's residuals\n");
    let _ = writeln!(
        s,
        "Baseline (no effect) fitted on all runs: {}; joint in-sample SSE {} %².\n",
        params_text(b),
        f(b.full.value, 1)
    );
    let _ = writeln!(
        s,
        "Residual = simulated − measured in percentage points; uncertainty = √(run-to-run² + scale² + Monte-Carlo²) \
         with run-to-run = sd of the run fractions / √n, scale = resolution/√12 over the mean recovered mass, \
         Monte-Carlo = √(p(1−p)/N); flagged when |z| > {Z_FLAG}. \"First flight\" is the share of launched particles \
         resting in the tooth of their first impact, \"bounce chain\" the share moved there by later bounces.\n"
    );
    for (c, w) in d.conditions.iter().zip(&d.where_) {
        let _ = writeln!(s, "### {}\n", c.name);
        let _ = writeln!(s, "| tooth | measured % | simulated % | residual | uncertainty (runs / scale / MC) | z | flag | first flight % | bounce chain % |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
        for (j, r) in w.teeth_residuals.iter().enumerate() {
            let mut row = residual_row(&tooth_label(j, w.shown_teeth, c.last_bin_label()), r, 2);
            if j < w.shown_teeth {
                let _ = write!(row, " {} | {} |", f(w.first_flight[j], 1), f(w.bounce_chain[j], 1));
            } else {
                row.push_str(" | |");
            }
            let _ = writeln!(s, "{row}");
        }
        let _ = writeln!(
            s,
            "\n| metric (teeth) | measured | simulated | residual | uncertainty (runs / – / MC) | z | flag |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        let _ = writeln!(s, "{}", residual_row("centre of mass E_x", &w.centre, 3));
        let _ = writeln!(s, "{}", residual_row("dispersion σ_x", &w.dispersion, 3));
        let flagged: Vec<String> = w.teeth_residuals[..w.shown_teeth]
            .iter()
            .enumerate()
            .filter(|(_, r)| r.flagged())
            .map(|(j, r)| format!("tooth {} ({:+.1} pp, z {:+.1})", j + 1, r.residual, r.z))
            .collect();
        let _ = writeln!(
            s,
            "\nFlagged: {}. Simulated mass: {} % first flight, {} % bounce chain, {} % lost.\n",
            if flagged.is_empty() { "none".to_string() } else { flagged.join(", ") },
            f(w.first_flight.iter().sum(), 1),
            f(w.bounce_chain.iter().sum(), 1),
            f(w.lost_percent, 1)
        );
        if !w.launch_depth.is_empty() {
            let _ = writeln!(s, "Where each third of the fill (by launch depth below its free surface) comes to rest, % of that third:\n");
            let heads: Vec<String> = (1..=w.shown_teeth).map(|j| format!("tooth {j}")).collect();
            let _ = writeln!(s, "| layer | depth (mm) | {} | further or lost |", heads.join(" | "));
            let _ = writeln!(s, "|---|---|{}---|", "---|".repeat(w.shown_teeth));
            for l in &w.launch_depth {
                let cells: Vec<String> = l.teeth_percent.iter().map(|v| f(*v, 1)).collect();
                let _ = writeln!(
                    s,
                    "| {} | {}–{} | {} | {} |",
                    l.label,
                    f(l.depth_mm[0], 2),
                    f(l.depth_mm[1], 2),
                    cells.join(" | "),
                    f(l.further_or_lost_percent, 1)
                );
            }
            let _ = writeln!(s);
        }
    }

    // WHICH
    let _ = writeln!(s, "## Which: candidate effects by their gap on fresh particle streams\n");
    let _ = writeln!(
        s,
        "Each model is fitted on all runs and re-simulated on fresh particle streams (not the ones it was fitted \
         on); the gap is the SSE (%²) of the streams' mean bins summed over conditions, once each condition may \
         have lost up to its measured not-recovered share in handling (loss-adjusted). Ranked by score = gap + 2 × \
         (extra parameters) × SE (bootstrap standard error of the gap, runs and streams resampled). Reduction = \
         1 − gap / baseline gap; the improvement interval is the paired bootstrap interval of (baseline − effect) \
         (diagnosis.json's `improvement_sd` splits its spread into the runs' part and the simulation's). \
         `best` must also remove at least {:.0} % of the baseline's gap, and the baseline must be well above its \
         noise floor (see the verdict).\n",
        100.0 * super::diagnose::MIN_REDUCTION
    );
    let _ = writeln!(s, "| rank | model | fitted parameters (all runs) | gap | interval | SE | score | reduction | improvement interval |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    let _ = writeln!(
        s,
        "| – | baseline | {} | {} | {} | {} | {} | 0 | – |",
        params_text(b),
        f(b.gap, 1),
        iv(b.interval, 1),
        f(b.se, 1),
        f(b.score, 1)
    );
    for (i, m) in d.ranking.iter().enumerate() {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} % | {} |",
            i + 1,
            m.name(),
            params_text(m),
            f(m.gap, 1),
            iv(m.interval, 1),
            f(m.se, 1),
            f(m.score, 1),
            f(100.0 * (1.0 - m.gap / b.gap), 1),
            iv(m.improvement_interval, 1)
        );
    }
    let _ = writeln!(
        s,
        "\n**Best:** {}.",
        match d.best {
            Some(e) => format!("`{}` (it beats the baseline beyond the bootstrap uncertainty and by a material share)", e.name()),
            None => "none — no effect's gap beats the baseline's beyond the uncertainty by a material share (the data cannot tell)".to_string(),
        }
    );
    if d.indistinguishable.is_empty() {
        let _ =
            writeln!(s, "**Indistinguishable:** none (every other effect is worse than the top-ranked one beyond the paired uncertainty).\n");
    } else {
        let _ = writeln!(
            s,
            "**Indistinguishable** (not worse than the top-ranked effect beyond the paired bootstrap uncertainty): {}.\n",
            d.indistinguishable.iter().map(|e| format!("`{}`", e.name())).collect::<Vec<_>>().join(", ")
        );
    }

    // HOW FAR
    if let Some(t) = d.gap_model() {
        let _ = writeln!(
            s,
            "## How far: baseline vs `{}`{}\n",
            t.name(),
            if d.best.is_some() { "" } else { " (top-ranked, not established)" }
        );
        let _ = writeln!(
            s,
            "Held-out gap: {} %² {} before, {} %² {} after (reduction {} %, paired improvement interval {} %²). \
             In sample: {} → {} %².\n",
            f(b.gap, 1),
            iv(b.interval, 1),
            f(t.gap, 1),
            iv(t.interval, 1),
            f(100.0 * (1.0 - t.gap / b.gap), 1),
            iv(t.improvement_interval, 1),
            f(b.full.value, 1),
            f(t.full.value, 1)
        );
        for (ci, ((c, g), w)) in d.conditions.iter().zip(&d.gap).zip(&d.where_).enumerate() {
            let teeth = c.teeth();
            let _ = writeln!(
                s,
                "### {} (gap {} → {} %²)\n",
                c.name,
                f(b.gap_by_condition[ci], 1),
                f(t.gap_by_condition[ci], 1)
            );
            let _ = writeln!(
                s,
                "| tooth | measured % | before % | residual before [interval] | after % | residual after [interval] |"
            );
            let _ = writeln!(s, "|---|---|---|---|---|---|");
            for j in (0..w.shown_teeth).chain(std::iter::once(teeth)) {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} {} | {} | {} {} |",
                    if j < teeth { format!("{}", j + 1) } else { c.last_bin_label().into() },
                    f(100.0 * g.measured[j], 2),
                    f(100.0 * g.before[j], 2),
                    f(100.0 * (g.before[j] - g.measured[j]), 2),
                    iv(g.before_interval[j], 2),
                    f(100.0 * g.after[j], 2),
                    f(100.0 * (g.after[j] - g.measured[j]), 2),
                    iv(g.after_interval[j], 2)
                );
            }
            let _ = writeln!(s, "\n| metric (teeth) | measured [interval] | before | after |");
            let _ = writeln!(s, "|---|---|---|---|");
            let _ = writeln!(
                s,
                "| centre of mass E_x | {} {} | {} | {} |",
                f(g.centre[0], 3),
                iv(g.centre_interval, 3),
                f(g.centre[1], 3),
                f(g.centre[2], 3)
            );
            let _ = writeln!(
                s,
                "| dispersion σ_x | {} {} | {} | {} |\n",
                f(g.dispersion[0], 3),
                iv(g.dispersion_interval, 3),
                f(g.dispersion[1], 3),
                f(g.dispersion[2], 3)
            );
        }
    }
    if let (Some(cb), Some(t)) = (&d.combined, d.gap_model()) {
        let m = &cb.model;
        let _ = writeln!(s, "## Two effects together: `{}`\n", m.name());
        let _ = writeln!(
            s,
            "The two best candidates that each beat the baseline, refitted jointly (starting from both single fits): \
             gap {} %² {} (reduction {} % against the baseline; paired improvement over each effect alone: {}; \
             an improvement only where the interval lies above 0). Fitted on all runs: {}; in-sample SSE {} %².\n",
            f(m.gap, 1),
            iv(m.interval, 1),
            f(100.0 * (1.0 - m.gap / b.gap), 1),
            m.effects
                .iter()
                .zip(&cb.improvement_over_singles)
                .map(|(e, i)| format!("`{}` {} %²", e.name(), iv(*i, 1)))
                .collect::<Vec<_>>()
                .join(", "),
            params_text(m),
            f(m.full.value, 1)
        );
        for (ci, (c, w)) in d.conditions.iter().zip(&d.where_).enumerate() {
            let teeth = c.teeth();
            let idx: Vec<usize> = (0..w.shown_teeth).chain(std::iter::once(teeth)).collect();
            let heads: Vec<String> = idx
                .iter()
                .map(|j| if *j < w.shown_teeth { format!("tooth {}", j + 1) } else { c.last_bin_label().into() })
                .collect();
            let row = |label: &str, bins: &[f64]| {
                format!("| {label} | {} |", idx.iter().map(|j| f(100.0 * bins[*j], 2)).collect::<Vec<_>>().join(" | "))
            };
            let _ = writeln!(s, "{}: % per tooth (fits on all runs)\n", c.name);
            let _ = writeln!(s, "| model | {} |", heads.join(" | "));
            let _ = writeln!(s, "|---|{}", "---|".repeat(idx.len()));
            let _ = writeln!(s, "{}", row("measured", &d.gap[ci].measured));
            let _ = writeln!(s, "{}", row(&t.name(), &t.full.bins[ci]));
            let _ = writeln!(s, "{}\n", row(&m.name(), &m.full.bins[ci]));
        }
    }
    let _ = writeln!(
        s,
        "Plots: `residuals.svg`, `ranking.svg`, `distributions.svg` (each also as `.png`); numbers: `diagnosis.json`."
    );
    s
}

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
