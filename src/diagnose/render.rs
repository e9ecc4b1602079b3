//! Outputs of `diagnose`: report.md, diagnosis.json and three hand-written SVG plots
//! (residuals with error bars, the effect ranking with intervals, fitted vs measured
//! distributions), every file written atomically.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;
use serde_json::Value;

use super::diagnose::{Diagnosis, ModelResult, Residual, INTERVAL, Z_FLAG};
use crate::io::atomic::write_atomic;

fn f(v: f64, d: usize) -> String {
    if v.is_finite() {
        format!("{v:.d$}")
    } else {
        "–".into()
    }
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
         on); the gap is the SSE (%²) summed over conditions, averaged over the streams. Ranked by score = gap + 2 × \
         (extra parameters) × SE (bootstrap standard error of the gap, runs and streams resampled). Reduction = \
         1 − gap / baseline gap; the improvement interval is the paired bootstrap interval of (baseline − effect). \
         `best` must also remove at least {:.0} % of the baseline's gap.\n",
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
            writeln!(s, "**Indistinguishable:** none (no other effect's interval overlaps the top-ranked one's).\n");
    } else {
        let _ = writeln!(
            s,
            "**Indistinguishable** (intervals overlap the top-ranked effect's): {}.\n",
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
    let _ = writeln!(s, "Plots: `residuals.svg`, `ranking.svg`, `distributions.svg`; numbers: `diagnosis.json`.");
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

fn nice_step(range: f64) -> f64 {
    let raw = (range / 5.0).max(1e-9);
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag)
}

/// A plot frame: pixel box and data ranges, with y ticks and grid.
struct Frame {
    x0: f64,
    y0: f64,
    w: f64,
    h: f64,
    lo: f64,
    hi: f64,
}

impl Frame {
    fn y(&self, v: f64) -> f64 {
        self.y0 + self.h - (v.clamp(self.lo, self.hi) - self.lo) / (self.hi - self.lo) * self.h
    }
    fn axes(&self, s: &mut String, title: &str, ylabel: &str) {
        let _ = writeln!(
            s,
            r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#444"/>"##,
            self.x0, self.y0, self.w, self.h
        );
        let step = nice_step(self.hi - self.lo);
        let mut t = (self.lo / step).ceil() * step;
        while t <= self.hi + 1e-9 {
            let y = self.y(t);
            let _ = writeln!(
                s,
                r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/>"##,
                self.x0,
                self.x0 + self.w
            );
            let _ = writeln!(
                s,
                r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{}</text>"##,
                self.x0 - 4.0,
                y + 4.0,
                fmt_tick(t)
            );
            t += step;
        }
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="13" font-weight="bold">{}</text>"##,
            self.x0,
            self.y0 - 8.0,
            esc(title)
        );
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" transform="rotate(-90 {:.1} {:.1})" text-anchor="middle">{}</text>"##,
            self.x0 - 40.0,
            self.y0 + self.h / 2.0,
            self.x0 - 40.0,
            self.y0 + self.h / 2.0,
            esc(ylabel)
        );
    }
}

fn fmt_tick(v: f64) -> String {
    let r = (v * 1e6).round() / 1e6;
    if r == r.trunc() {
        format!("{r:.0}")
    } else {
        format!("{r}")
    }
}

fn svg_open(w: f64, h: f64) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" viewBox=\"0 0 {w:.0} {h:.0}\" font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    )
}

fn range_of(values: impl Iterator<Item = f64>, pad: f64, include_zero: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if include_zero {
        lo = lo.min(0.0);
        hi = hi.max(0.0);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-9 {
        hi = lo + 1.0;
    }
    let p = (hi - lo) * pad;
    (lo - p, hi + p)
}

/// Residuals (simulated − measured, pp) per tooth with ±uncertainty and ±2 uncertainty bars.
pub fn residuals_svg(d: &Diagnosis) -> String {
    let (pw, ph) = (560.0, 240.0);
    let n = d.conditions.len();
    let mut s = svg_open(pw + 100.0, (ph + 80.0) * n as f64 + 30.0);
    for (i, (c, w)) in d.conditions.iter().zip(&d.where_).enumerate() {
        let rs = &w.teeth_residuals;
        let (lo, hi) = range_of(
            rs.iter().flat_map(|r| [r.residual - 2.0 * r.uncertainty, r.residual + 2.0 * r.uncertainty]),
            0.08,
            true,
        );
        let fr = Frame { x0: 70.0, y0: 40.0 + i as f64 * (ph + 80.0), w: pw, h: ph, lo, hi };
        fr.axes(
            &mut s,
            &format!("{}: baseline residual per tooth (bars ±1 and ±2 uncertainty; red |z| > {Z_FLAG})", c.name),
            "simulated − measured (pp)",
        );
        let y0 = fr.y(0.0);
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{y0:.1}" x2="{:.1}" y2="{y0:.1}" stroke="#000"/>"##,
            fr.x0,
            fr.x0 + fr.w
        );
        let step = fr.w / rs.len() as f64;
        for (j, r) in rs.iter().enumerate() {
            let x = fr.x0 + step * (j as f64 + 0.5);
            let colour = if r.flagged() { "#c0392b" } else { "#2c6fbb" };
            let (a2, b2) = (fr.y(r.residual - 2.0 * r.uncertainty), fr.y(r.residual + 2.0 * r.uncertainty));
            let (a1, b1) = (fr.y(r.residual - r.uncertainty), fr.y(r.residual + r.uncertainty));
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{a2:.1}" x2="{x:.1}" y2="{b2:.1}" stroke="{colour}" stroke-width="1"/>"##
            );
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{a1:.1}" x2="{x:.1}" y2="{b1:.1}" stroke="{colour}" stroke-width="4"/>"##
            );
            let _ = writeln!(s, r##"<circle cx="{x:.1}" cy="{:.1}" r="4" fill="{colour}"/>"##, fr.y(r.residual));
            let _ = writeln!(
                s,
                r##"<text x="{x:.1}" y="{:.1}" font-size="11" text-anchor="middle">{}</text>"##,
                fr.y0 + fr.h + 16.0,
                tooth_label(j, w.shown_teeth, c.last_bin_label())
            );
        }
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">tooth (E_x residual {:+.3}, z {:+.1}; σ_x residual {:+.3}, z {:+.1})</text>"##,
            fr.x0 + fr.w / 2.0,
            fr.y0 + fr.h + 34.0,
            w.centre.residual,
            w.centre.z,
            w.dispersion.residual,
            w.dispersion.z
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Held-out gap of every model with its bootstrap interval, best score first.
pub fn ranking_svg(d: &Diagnosis) -> String {
    let mut models: Vec<&ModelResult> = vec![&d.baseline];
    models.extend(d.ranking.iter());
    let row = 34.0;
    let (x0, w) = (150.0, 440.0);
    let h = row * models.len() as f64;
    let mut s = svg_open(x0 + w + 60.0, h + 110.0);
    let (lo, hi) = range_of(models.iter().flat_map(|m| [m.interval[0], m.interval[1], m.gap]), 0.08, true);
    let xp = |v: f64| x0 + (v.clamp(lo, hi) - lo) / (hi - lo) * w;
    let y0 = 40.0;
    let _ = writeln!(
        s,
        r##"<text x="{x0:.1}" y="24" font-size="13" font-weight="bold">Held-out gap (SSE %², {:.0}-{:.0} % bootstrap intervals)</text>"##,
        100.0 * INTERVAL.0,
        100.0 * INTERVAL.1
    );
    let _ =
        writeln!(s, r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{h:.1}" fill="none" stroke="#444"/>"##);
    let step = nice_step(hi - lo);
    let mut t = (lo / step).ceil() * step;
    while t <= hi + 1e-9 {
        let x = xp(t);
        let _ = writeln!(s, r##"<line x1="{x:.1}" y1="{y0:.1}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/>"##, y0 + h);
        let _ = writeln!(
            s,
            r##"<text x="{x:.1}" y="{:.1}" font-size="11" text-anchor="middle">{}</text>"##,
            y0 + h + 15.0,
            fmt_tick(t)
        );
        t += step;
    }
    let bx = xp(d.baseline.gap);
    let _ = writeln!(
        s,
        r##"<line x1="{bx:.1}" y1="{y0:.1}" x2="{bx:.1}" y2="{:.1}" stroke="#888" stroke-dasharray="4 3"/>"##,
        y0 + h
    );
    for (i, m) in models.iter().enumerate() {
        let y = y0 + row * (i as f64 + 0.5);
        let best = m.single().is_some() && m.single() == d.best;
        let colour = if m.effects.is_empty() {
            "#555"
        } else if best {
            "#1e8449"
        } else if m.single().is_some_and(|e| d.indistinguishable.contains(&e)) {
            "#d68910"
        } else {
            "#2c6fbb"
        };
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="end">{}</text>"##,
            x0 - 8.0,
            y + 4.0,
            esc(&m.name())
        );
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{colour}" stroke-width="3"/>"##,
            xp(m.interval[0]),
            xp(m.interval[1])
        );
        let _ = writeln!(s, r##"<circle cx="{:.1}" cy="{y:.1}" r="5" fill="{colour}"/>"##, xp(m.gap));
    }
    let _ = writeln!(
        s,
        r##"<text x="{x0:.1}" y="{:.1}" font-size="11">dashed: baseline; green: best; orange: indistinguishable from the top-ranked effect. best = {}</text>"##,
        y0 + h + 36.0,
        d.best.map_or("none", |e| e.name())
    );
    s.push_str("</svg>\n");
    s
}

/// Measured (with the runs' min-max), baseline and top-ranked effect distributions.
pub fn distributions_svg(d: &Diagnosis) -> String {
    let (pw, ph) = (560.0, 240.0);
    let n = d.conditions.len();
    let mut s = svg_open(pw + 100.0, (ph + 80.0) * n as f64 + 30.0);
    let effect = d.gap_model().map_or("effect".to_string(), |m| m.name());
    for (i, ((c, g), w)) in d.conditions.iter().zip(&d.gap).zip(&d.where_).enumerate() {
        let teeth = c.teeth();
        let idx: Vec<usize> = (0..w.shown_teeth).chain(std::iter::once(teeth)).collect();
        let sum = &w.measured_summary;
        let hi = idx
            .iter()
            .flat_map(|&j| [g.measured[j], g.before[j], g.after[j], sum.max.get(j).copied().unwrap_or(0.0)])
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max)
            * 100.0
            * 1.1;
        let fr = Frame { x0: 70.0, y0: 40.0 + i as f64 * (ph + 80.0), w: pw, h: ph, lo: 0.0, hi: hi.max(1.0) };
        fr.axes(
            &mut s,
            &format!("{}: measured (grey, runs' min-max), baseline (blue), {effect} (green)", c.name),
            "share of mass (%)",
        );
        let step = fr.w / idx.len() as f64;
        let bw = step / 4.0;
        for (k, &j) in idx.iter().enumerate() {
            let xc = fr.x0 + step * (k as f64 + 0.5);
            for (m, (v, colour)) in
                [(g.measured[j], "#999"), (g.before[j], "#2c6fbb"), (g.after[j], "#1e8449")].into_iter().enumerate()
            {
                let x = xc + (m as f64 - 1.5) * bw;
                let y = fr.y(100.0 * v);
                let _ = writeln!(
                    s,
                    r##"<rect x="{x:.1}" y="{y:.1}" width="{bw:.1}" height="{:.1}" fill="{colour}"/>"##,
                    fr.y0 + fr.h - y
                );
            }
            // the runs' spread, the last bin's too (what each run did not recover)
            if j < sum.min.len() && sum.min[j].is_finite() && sum.max[j].is_finite() {
                let x = xc - bw;
                let _ = writeln!(
                    s,
                    r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="#000"/>"##,
                    fr.y(100.0 * sum.min[j]),
                    fr.y(100.0 * sum.max[j])
                );
            }
            let label = if j < teeth { format!("{}", j + 1) } else { c.last_bin_label().into() };
            let _ = writeln!(
                s,
                r##"<text x="{xc:.1}" y="{:.1}" font-size="11" text-anchor="middle">{label}</text>"##,
                fr.y0 + fr.h + 16.0
            );
        }
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">tooth</text>"##,
            fr.x0 + fr.w / 2.0,
            fr.y0 + fr.h + 32.0
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Write report.md, diagnosis.json and the SVGs into `dir` (created if missing).
pub fn write_dir(dir: &Path, d: &Diagnosis, json: &Value) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("--out: cannot create directory {}", dir.display()))?;
    write_atomic(&dir.join("diagnosis.json"), format!("{}\n", serde_json::to_string_pretty(json)?).as_bytes())?;
    write_atomic(&dir.join("report.md"), to_markdown(d).as_bytes())?;
    write_atomic(&dir.join("residuals.svg"), residuals_svg(d).as_bytes())?;
    write_atomic(&dir.join("ranking.svg"), ranking_svg(d).as_bytes())?;
    write_atomic(&dir.join("distributions.svg"), distributions_svg(d).as_bytes())
}
