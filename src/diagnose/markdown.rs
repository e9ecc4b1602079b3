//! report.md, section by section: the conditions and settings, the verdict, where the
//! baseline misses, which candidate closes the gap, how far it goes, and the two best
//! together. Each section is a function of the diagnosis; `to_markdown` joins them.

use std::fmt::Write as _;

use super::diagnose::{about_as_well, Diagnosis, ModelResult, Residual, INTERVAL, Z_FLAG};
use super::limits::{sig3, PROBABILITY};

pub(super) fn f(v: f64, d: usize) -> String {
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

pub(super) fn tooth_label(j: usize, shown: usize, last: &str) -> String {
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
    for section in [conditions, verdict, limits, where_, which, motion_ridge, how_far, pair, next_measurement, plots] {
        section(&mut s, d);
    }
    s
}

/// The conditions, the settings and the notes.
fn conditions(s: &mut String, d: &Diagnosis) {
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
}

/// The verdict, each model judged against its noise floor, and what no fitted model removes.
fn verdict(s: &mut String, d: &Diagnosis) {
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
}

/// Where: the baseline's residuals per condition.
fn where_(s: &mut String, d: &Diagnosis) {
    let b = &d.baseline;
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
}

/// Which: the candidates ranked by their gap on fresh streams; best and indistinguishable.
fn which(s: &mut String, d: &Diagnosis) {
    let b = &d.baseline;
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
}

/// The motion screen's ridge: the unstated motions that fit about as well as the best.
fn motion_ridge(s: &mut String, d: &Diagnosis) {
    if d.motion_screen.is_empty() {
        return;
    }
    let floor = d.verdict.remaining.floor;
    let near = about_as_well(&d.motion_screen, floor);
    let _ = writeln!(s, "## The unstated motion: what the screen could tell apart\n");
    let _ = writeln!(
        s,
        "The motion screen tried {} sled motions (the fitted shared parameters at each, loss-adjusted SSE at the full \
         budget on the fit's streams; diagnosis.json's `motion_screen`). Those within the noise floor ({} %²) of the \
         best fit about as well:\n",
        d.motion_screen.len(),
        f(floor, 1)
    );
    let _ = writeln!(s, "| return direction | motion held | SSE (%²) |");
    let _ = writeln!(s, "|---|---|---|");
    for p in &near {
        let motion: Vec<String> = p.motion.iter().map(|(n, v)| format!("{n} {v}")).collect();
        // a campaign that states the delay and speed but not the direction screens directions only
        let motion = if motion.is_empty() { "delay and speed as stated".to_string() } else { motion.join(", ") };
        let _ = writeln!(
            s,
            "| {} | {} | {}{} |",
            p.direction.map_or("as stated", |r| r.name()),
            motion,
            f(p.sse, 1),
            if p.polished { " (polished)" } else { "" }
        );
    }
    let _ = writeln!(
        s,
        "\n{}\n",
        if near.len() > 1 {
            "These data do not tell these motions apart (a later return against a faster one moves the sled about as \
             far during the flights): the fitted motion is one of this ridge, not the motion itself."
        } else {
            "Only the best grid point fits that well: the data place the motion near it (the fit moves it from there)."
        }
    );
}

/// How far: baseline against the top-ranked effect per condition and tooth.
fn how_far(s: &mut String, d: &Diagnosis) {
    let b = &d.baseline;
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
}

/// The two best effects fitted together, where they were.
fn pair(s: &mut String, d: &Diagnosis) {
    let b = &d.baseline;
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
}

/// Detection limits: the smallest strength of each candidate these data detect, and the
/// ladder it was read from.
fn limits(s: &mut String, d: &Diagnosis) {
    let Some(l) = &d.limits else { return };
    let _ = writeln!(s, "## Detection limits\n");
    let _ = writeln!(
        s,
        "The smallest strength of each candidate at which this campaign's baseline gap would be well above its \
         noise floor (not `no-gap`) with {:.0} % probability: the fitted baseline with the candidate at a ladder of \
         strengths ({} particles, common random numbers), less what a refit of the baseline and a handling loss \
         absorb (linearised; around the crossing, marked *, the baseline refitted to the rung by simulation), \
         against {} Gaussian draws of the measured means' and the fresh streams' noise (floor {} %²); the limit \
         where the signal, grown as a power of the strength between the two rungs around the crossing, is \
         detected with that probability.\n",
        100.0 * PROBABILITY,
        l.particles,
        l.draws,
        f(l.floor, 2)
    );
    let _ = writeln!(s, "| candidate | parameter | held | limit | P(detect) on the ladder (strength: probability) |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for x in &l.limits {
        let held: Vec<String> = x.held.iter().map(|(n, v)| format!("{n} {}", sig3(*v))).collect();
        let ladder: Vec<String> = x
            .ladder
            .iter()
            .map(|r| format!("{}: {:.2}{}", sig3(r.strength), r.probability, if r.refitted { "*" } else { "" }))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            x.effect.name(),
            x.param,
            if held.is_empty() { "–".to_string() } else { held.join(", ") },
            x.limit.map_or("above the search box".to_string(), sig3),
            ladder.join(", ")
        );
    }
    for k in &l.skipped {
        let _ = writeln!(s, "\n> Note: {k}");
    }
    let _ = writeln!(s);
}

/// The next measurement (`--suggest`): the proposed conditions that would separate what the
/// diagnosis leaves, best first.
fn next_measurement(s: &mut String, d: &Diagnosis) {
    let Some(g) = &d.suggestions else { return };
    let _ = writeln!(s, "## Next measurement\n");
    let _ = writeln!(
        s,
        "Separating {}: {}. Each proposal is one condition of this campaign with one thing changed, every model \
         simulated there from its own fit; the separation of two models is the SSE between their predictions over \
         the noise floor such a condition would have (× floor; above {} separates them). Not refitted: an upper \
         bound of what the new data would show.\n",
        g.models.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", "),
        g.why,
        super::verdict::FLOOR_FACTOR
    );
    let current: Vec<String> = g.current.iter().map(|c| format!("{} / {} {}×", c.a, c.b, f(c.ratio(), 1))).collect();
    let _ = writeln!(s, "In the campaign's own conditions: {}.\n", current.join(", "));
    let _ = writeln!(s, "| rank | condition | change | worst pair (× floor) | every pair |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (i, p) in g.proposals.iter().take(10).enumerate() {
        let pairs: Vec<String> = p.pairs.iter().map(|c| format!("{} / {} {}×", c.a, c.b, f(c.ratio(), 1))).collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {}{} | {} |",
            i + 1,
            p.base,
            p.change.label(),
            f(p.worst(), 1),
            if p.separates() { " (separates)" } else { "" },
            pairs.join(", ")
        );
    }
    let _ = writeln!(s, "\nEvery proposal: `diagnosis.json`'s `suggestions`.\n");
}

/// Where the figures and numbers are.
fn plots(s: &mut String, _: &Diagnosis) {
    let _ = writeln!(
        s,
        "Plots: `residuals.svg`, `ranking.svg`, `distributions.svg` (each also as `.png`); numbers: `diagnosis.json`."
    );
}
