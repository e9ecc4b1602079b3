//! Outputs of `fit`: the JSON object, the stdout table, fit.csv and fit.svg (a bar chart like
//! the thesis's Figure 4.14, drawn through `crate::plot`), files written atomically.

use std::io::Write;
use std::path::Path;

use anyhow::Context as _;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Map, Value};

use super::joint::JointReport;
use super::FitReport;
use crate::calibrate::condition::FLOOR_FACTOR;
use crate::calibrate::ObjectiveKind;
use crate::io::atomic::write_atomic;
use crate::model::outcome::centre_and_dispersion;
use crate::plot::{self, Drawn as _, Figure, Mark};

/// Where the numbers came from.
#[derive(Clone, Debug)]
pub struct Meta {
    pub data: String,
    pub setup: String,
    pub engine: String,
    pub particles: u32,
    pub seed: u64,
    pub teeth: usize,
    pub measured_teeth: usize,
    pub run_ids: Vec<String>,
}

fn pct(v: &[f64]) -> Vec<f64> {
    v.iter().map(|x| 100.0 * x).collect()
}

/// JSON numbers cannot be NaN/inf: those become null.
fn num(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

fn nums(v: &[f64]) -> Value {
    Value::Array(v.iter().map(|x| num(*x)).collect())
}

fn params_object(r: &FitReport, x: &[f64]) -> Value {
    let mut m = Map::new();
    for (p, v) in r.params.iter().zip(x) {
        m.insert(p.name().to_string(), num(*v));
    }
    Value::Object(m)
}

/// Centre of mass and dispersion (Eq. 4.58-4.59) of the teeth (lost excluded).
fn centre(teeth: &[f64]) -> Value {
    let (e, s) = centre_and_dispersion(teeth);
    json!({"centre_of_mass_teeth": num(e), "dispersion_teeth": num(s)})
}

/// The `--json` object (also fit.json).
pub fn to_json(r: &FitReport, meta: &Meta) -> Value {
    let teeth = meta.teeth;
    let uncertainty = match &r.uncertainty {
        Some(u) => {
            let mut m = Map::new();
            for (j, p) in r.params.iter().enumerate() {
                m.insert(
                    p.name().to_string(),
                    json!({"sd": num(u.sd[j]), "interval": [num(u.interval[j][0]), num(u.interval[j][1])]}),
                );
            }
            Value::Object(m)
        }
        None => json!({}),
    };
    let heldout = match &r.heldout {
        Some(h) => json!({
            "k": h.k,
            "heldout_runs": h.heldout_runs,
            "fit_runs": h.fit_runs,
            "params": params_object(r, &h.params),
            "sse_in_sample_percent2": num(h.sse_in_sample_percent2),
            "sse_heldout_percent2": num(h.sse_heldout_percent2),
            "sse_measured_fit_vs_heldout_percent2": num(h.sse_measured_fit_vs_heldout_percent2),
            "nll_heldout": num(h.nll_heldout),
            "nll_heldout_per_run": num(h.nll_heldout_per_run),
            "nll_in_sample_per_run": num(h.nll_in_sample_per_run),
            "evaluations": h.evaluations,
        }),
        None => Value::Null,
    };
    let fitted_teeth = &r.fitted[..teeth];
    json!({
        "params": params_object(r, &r.x),
        "objective": num(r.objective_value),
        "objective_kind": r.objective,
        "sse_percent2": num(r.sse_percent2),
        "heldout": heldout,
        "uncertainty": uncertainty,
        "distribution": {
            "unit": "percent",
            "teeth": teeth,
            "measured": pct(&r.measured.mean[..teeth]),
            "measured_sd": nums(&pct(&r.measured.sd[..teeth])),
            "measured_min": pct(&r.measured.min[..teeth]),
            "measured_max": pct(&r.measured.max[..teeth]),
            "fitted": pct(fitted_teeth),
            "last_bin": r.last_bin,
            "last_bin_measured": 100.0 * r.measured.mean[teeth],
            "last_bin_measured_sd": num(100.0 * r.measured.sd[teeth]),
            "last_bin_fitted": 100.0 * r.fitted[teeth],
        },
        "metrics": {
            "measured": centre(&r.measured.mean[..teeth]),
            "fitted": centre(fitted_teeth),
            "sse_percent2": num(r.sse_percent2),
            "mae_percent": num(r.mae_percent),
            "nll": num(r.likelihood.nll),
            "nll_per_run": num(r.likelihood.nll / r.runs as f64),
            "concentration": num(r.likelihood.concentration),
            "nll_measured_mean": num(r.measured_mean_likelihood.nll),
            "concentration_measured_mean": num(r.measured_mean_likelihood.concentration),
            "last_bin_fraction": r.fitted[teeth],
        },
        "setup_values": params_object(r, &r.setup_values),
        "settings": {
            "data": meta.data,
            "setup": meta.setup,
            "runs": r.runs,
            "measured_teeth": meta.measured_teeth,
            "scale_resolution_g": r.resolution_g,
            "engine": meta.engine,
            "particles": meta.particles,
            "seed": meta.seed,
            "fitted": r.solver.is_some(),
            "pop": r.solver.map(|g| g.pop),
            "generations": r.solver.map(|g| g.generations),
            "polish_iterations": r.solver.map(|g| g.polish_iterations),
            "screen_particles": r.solver.map(|g| g.screen_particles),
            "notes": r.notes,
            "evaluations": r.evaluations,
            "bootstrap": r.uncertainty.as_ref().map_or(0, |u| u.replicates),
            "bootstrap_evaluations": r.uncertainty.as_ref().map_or(0, |u| u.evaluations),
            "holdout": r.heldout.as_ref().map_or(0, |h| h.k),
        },
    })
}

/// Teeth shown in the table and the chart: the measured ones and every tooth the fit puts
/// at least 0.05 % in.
fn shown_teeth(r: &FitReport, meta: &Meta) -> usize {
    let last_fitted = r.fitted[..meta.teeth].iter().rposition(|v| *v >= 5e-4).map_or(0, |i| i + 1);
    meta.measured_teeth.max(last_fitted).max(1)
}

/// The human-readable table.
pub fn write_table(out: &mut dyn Write, r: &FitReport, meta: &Meta) -> std::io::Result<()> {
    let kind = match r.objective {
        ObjectiveKind::Sse => "sse (Eq. 4.62, %²)",
        ObjectiveKind::Likelihood => "likelihood (Dirichlet-multinomial NLL)",
    };
    writeln!(
        out,
        "data       {} ({} runs, {} teeth, scale {} g)",
        meta.data, r.runs, meta.measured_teeth, r.resolution_g
    )?;
    writeln!(out, "setup      {} ({} teeth simulated)", meta.setup, meta.teeth)?;
    let how = match r.solver {
        Some(g) => format!(
            "differential evolution {} x {} generations at {} particles + {} compass iterations ({} simulations)",
            g.pop, g.generations, g.screen_particles, g.polish_iterations, r.evaluations
        ),
        None => "evaluated at the given parameters (no fit)".to_string(),
    };
    writeln!(
        out,
        "settings   objective {kind}, engine {}, {} particles, seed {}, {how}",
        meta.engine, meta.particles, meta.seed
    )?;
    writeln!(out)?;
    for n in &r.notes {
        writeln!(out, "note       {n}")?;
    }
    let head = if r.solver.is_some() { "fitted" } else { " given" };
    writeln!(out, "parameter        {head}        sd    68 % interval          bounds       setup")?;
    for (j, p) in r.params.iter().enumerate() {
        let (lo, hi) = p.bounds();
        let (sd, iv) = match &r.uncertainty {
            Some(u) => (format!("{:>9.4}", u.sd[j]), format!("[{:.4}, {:.4}]", u.interval[j][0], u.interval[j][1])),
            None => (format!("{:>9}", "-"), "-".to_string()),
        };
        writeln!(
            out,
            "{:<12} {:>10.4} {} {:<22} {:<12} {:.4}",
            p.name(),
            r.x[j],
            sd,
            iv,
            format!("[{lo}, {hi}]"),
            r.setup_values[j]
        )?;
    }
    if let Some(u) = &r.uncertainty {
        writeln!(
            out,
            "(uncertainty: {} bootstrap resamples of the runs, each refitted locally; {} simulations)",
            u.replicates, u.evaluations
        )?;
    }
    writeln!(out)?;
    writeln!(out, "tooth           measured %      sd     min     max   fitted %")?;
    let m = &r.measured;
    for j in 0..shown_teeth(r, meta) {
        let sd = if m.sd[j].is_finite() { format!("{:>7.2}", 100.0 * m.sd[j]) } else { format!("{:>7}", "-") };
        writeln!(
            out,
            "{:<13}   {:>10.2} {} {:>7.2} {:>7.2} {:>10.2}",
            j + 1,
            100.0 * m.mean[j],
            sd,
            100.0 * m.min[j],
            100.0 * m.max[j],
            100.0 * r.fitted[j]
        )?;
    }
    let rest: f64 = r.fitted[shown_teeth(r, meta)..meta.teeth].iter().sum();
    if rest > 0.0 {
        writeln!(out, "{:<13}   {:>10.2} {:>7} {:>7} {:>7} {:>10.2}", "rest", 0.0, "", "", "", 100.0 * rest)?;
    }
    let t = meta.teeth;
    writeln!(
        out,
        "{:<13}   {:>10.2} {:>7.2} {:>7.2} {:>7.2} {:>10.2}",
        r.last_bin,
        100.0 * m.mean[t],
        if m.sd[t].is_finite() { 100.0 * m.sd[t] } else { 0.0 },
        100.0 * m.min[t],
        100.0 * m.max[t],
        100.0 * r.fitted[t]
    )?;
    writeln!(out)?;
    let (em, sm) = centre_and_dispersion(&m.mean[..meta.teeth]);
    let (ef, sf) = centre_and_dispersion(&r.fitted[..meta.teeth]);
    writeln!(out, "                        measured    fitted")?;
    writeln!(out, "centre of mass (teeth) {:>9.3} {:>9.3}", em, ef)?;
    writeln!(out, "dispersion (teeth)     {:>9.3} {:>9.3}", sm, sf)?;
    writeln!(out)?;
    writeln!(
        out,
        "SSE (in-sample)        {:>9.1} %²   (MAE {:.2} % over the {} weighed teeth)",
        r.sse_percent2, r.mae_percent, meta.measured_teeth
    )?;
    writeln!(
        out,
        "neg. log-likelihood    {:>9.1}      ({:.2} per run, concentration {:.3e})",
        r.likelihood.nll,
        r.likelihood.nll / r.runs as f64,
        r.likelihood.concentration,
    )?;
    writeln!(
        out,
        "  runs' own mean        {:>9.1}      ({:.2} per run, concentration {:.3e}: the reference)",
        r.measured_mean_likelihood.nll,
        r.measured_mean_likelihood.nll / r.runs as f64,
        r.measured_mean_likelihood.concentration,
    )?;
    if let Some(h) = &r.heldout {
        writeln!(out)?;
        writeln!(
            out,
            "held out   last {} runs ({}); fit on the other {}:",
            h.k,
            h.heldout_runs.join(", "),
            h.fit_runs.len()
        )?;
        let params: Vec<String> =
            r.params.iter().zip(&h.params).map(|(p, v)| format!("{} {:.4}", p.name(), v)).collect();
        writeln!(out, "           {}", params.join(", "))?;
        writeln!(out, "SSE in-sample (fit runs)      {:>9.1} %²", h.sse_in_sample_percent2)?;
        writeln!(out, "SSE held-out                  {:>9.1} %²", h.sse_heldout_percent2)?;
        writeln!(
            out,
            "SSE measured fit vs held-out  {:>9.1} %²   (run-to-run floor)",
            h.sse_measured_fit_vs_heldout_percent2
        )?;
        writeln!(
            out,
            "NLL per run in-sample / held-out {:.2} / {:.2}",
            h.nll_in_sample_per_run, h.nll_heldout_per_run
        )?;
    }
    Ok(())
}

/// One row of fit.csv: a simulated tooth (numeric), shares in percent of the loaded (or
/// recovered) mass; the last bin (lost or not recovered) is in fit.json. Empty where the
/// measurement has no value (e.g. the sd of a single run).
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct FitRow {
    pub tooth: usize,
    pub measured_mean_percent: Option<f64>,
    pub measured_sd_percent: Option<f64>,
    pub measured_min_percent: Option<f64>,
    pub measured_max_percent: Option<f64>,
    pub fitted_percent: Option<f64>,
}

/// fit.csv's rows.
pub fn csv_rows(r: &FitReport, meta: &Meta) -> Vec<FitRow> {
    let m = &r.measured;
    let percent = |v: f64| (v.is_finite()).then_some(100.0 * v);
    (0..meta.teeth)
        .map(|j| FitRow {
            tooth: j + 1,
            measured_mean_percent: percent(m.mean[j]),
            measured_sd_percent: percent(m.sd[j]),
            measured_min_percent: percent(m.min[j]),
            measured_max_percent: percent(m.max[j]),
            fitted_percent: percent(r.fitted[j]),
        })
        .collect()
}

/// fit.svg: measured mean per tooth as bars, ±1 sd as a light band, min/max as error bars,
/// the fitted distribution as red diamonds (like Figure 4.14), plus the last bin (lost or not
/// recovered) when either side holds anything there.
pub struct FitPlot {
    title: String,
    subtitle: String,
    /// Per category: label, measured mean, sd, min, max, fitted (fractions).
    categories: Vec<(String, f64, f64, f64, f64, f64)>,
}

const FIT_SIZE: (u32, u32) = (900, 520);
const MEAN_COLOUR: RGBColor = RGBColor(0x1f, 0x5f, 0xa8);
const SD_COLOUR: RGBColor = RGBColor(0x8c, 0xc4, 0xf0);
const FITTED_COLOUR: RGBColor = RGBColor(0xd6, 0x27, 0x28);
const FIT_LEGEND: [(Mark, &str); 4] = [
    (Mark::Block(MEAN_COLOUR), "measured mean"),
    (Mark::Block(SD_COLOUR), "±1 sd of the runs"),
    (Mark::Interval(BLACK), "min / max of the runs"),
    (Mark::Diamond(FITTED_COLOUR), "fitted simulation"),
];

impl FitPlot {
    pub fn new(r: &FitReport, meta: &Meta) -> FitPlot {
        let shown = shown_teeth(r, meta);
        let m = &r.measured;
        let cat = |label: String, j: usize| (label, m.mean[j], m.sd[j], m.min[j], m.max[j], r.fitted[j]);
        let mut categories: Vec<_> = (0..shown).map(|j| cat(format!("{}", j + 1), j)).collect();
        let t = meta.teeth;
        if r.fitted[t] > 0.0 || m.max[t] > 0.0 {
            categories.push(cat(r.last_bin.to_string(), t));
        }
        let params: Vec<String> = r.params.iter().zip(&r.x).map(|(p, v)| format!("{} {:.3}", p.name(), v)).collect();
        let kind = match r.objective {
            ObjectiveKind::Sse => "SSE",
            ObjectiveKind::Likelihood => "likelihood",
        };
        FitPlot {
            title: format!("Measured vs fitted distribution ({} runs) — {}", r.runs, meta.data),
            subtitle: format!("fitted ({kind}): {}; SSE {:.1} %²", params.join(", "), r.sse_percent2),
            categories,
        }
    }
}

impl Figure for FitPlot {
    fn size(&self) -> (u32, u32) {
        FIT_SIZE
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let area = plot::title(root, &self.title)?;
        let (w, h) = area.dim_in_pixel();
        let sub_h = plot::wrapped_height(w, &self.subtitle, plot::LABEL_SIZE);
        let key_h = plot::legend_height(w, &FIT_LEGEND);
        let (sub, rest) = area.split_vertically(sub_h);
        plot::draw_wrapped(&sub, &self.subtitle, plot::LABEL_SIZE)?;
        let (chart_area, key) = rest.split_vertically(h - sub_h - key_h);
        let top = self
            .categories
            .iter()
            .map(|c| c.4.max(c.5).max(c.1 + if c.2.is_finite() { c.2 } else { 0.0 }))
            .fold(0.0, f64::max);
        let labels: Vec<String> = self.categories.iter().map(|c| c.0.clone()).collect();
        let y = 0.0..(100.0 * top * 1.08).max(1.0);
        let mut chart = plot::category_chart(&chart_area, None, &labels, y, "tooth", "particle fraction [%]")?;
        let pct = |v: f64| 100.0 * v;
        let at = |i: usize| i as f64;
        chart
            .draw_series(
                self.categories.iter().enumerate().filter(|(_, c)| c.1 > 0.0).map(|(i, c)| {
                    Rectangle::new([(at(i) - 0.25, 0.0), (at(i) + 0.25, pct(c.1))], MEAN_COLOUR.filled())
                }),
            )
            .drawn()?;
        chart
            .draw_series(self.categories.iter().enumerate().filter(|(_, c)| c.2.is_finite() && c.2 > 0.0).map(
                |(i, c)| {
                    let (a, b) = ((c.1 - c.2).max(0.0), c.1 + c.2);
                    Rectangle::new([(at(i) - 0.15, pct(a)), (at(i) + 0.15, pct(b))], SD_COLOUR.mix(0.7).filled())
                },
            ))
            .drawn()?;
        for (i, c) in self.categories.iter().enumerate().filter(|(_, c)| c.4 > 0.0) {
            let (x, lo, hi) = (at(i), pct(c.3), pct(c.4));
            let lines =
                [vec![(x, lo), (x, hi)], vec![(x - 0.08, lo), (x + 0.08, lo)], vec![(x - 0.08, hi), (x + 0.08, hi)]];
            chart.draw_series(lines.into_iter().map(|l| PathElement::new(l, BLACK.stroke_width(1)))).drawn()?;
        }
        chart
            .draw_series(self.categories.iter().enumerate().map(|(i, c)| {
                EmptyElement::at((at(i), pct(c.5)))
                    + Polygon::new(vec![(-7, 0), (0, -7), (7, 0), (0, 7)], FITTED_COLOUR.filled())
            }))
            .drawn()?;
        plot::legend(&key, &FIT_LEGEND)
    }
}

/// fit.json, fit.csv and fit.svg into `dir` (created if missing).
pub fn write_dir(dir: &Path, r: &FitReport, meta: &Meta, json: &Value) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create the output folder {}", dir.display()))?;
    write_atomic(&dir.join("fit.json"), format!("{}\n", serde_json::to_string_pretty(json)?).as_bytes())?;
    crate::io::table::write_table(&dir.join("fit.csv"), &csv_rows(r, meta))?;
    plot::write_figure_files(dir, "fit", &FitPlot::new(r, meta))
}

/// `joint.json`: the joint fit's parameters (shared, varying with their slopes), each
/// condition against its own noise floor, and each condition's left-out prediction.
pub fn joint_json(r: &JointReport, engine: &str, seed: u64) -> Value {
    let named = |values: &[f64]| -> Map<String, Value> {
        r.params.iter().zip(values).map(|(p, v)| (p.name().to_string(), json!(v))).collect()
    };
    // a condition judged against its own floor, fitted or left out: one set of fields for both
    let judgement = |values: &[f64], sse: f64, floor: f64| -> Map<String, Value> {
        let mut m = Map::new();
        m.insert("params".into(), Value::Object(named(values)));
        m.insert("sse_percent2".into(), json!(sse));
        m.insert("floor_percent2".into(), json!(floor));
        m.insert("ratio".into(), json!(sse / floor));
        m.insert("well_above_floor".into(), json!(sse > FLOOR_FACTOR * floor));
        m
    };
    let varying: Vec<Value> = r
        .varying
        .iter()
        .map(|v| {
            let j = r.names.iter().position(|n| *n == v.slope_name()).expect("a varying parameter has its slope");
            let i = r.params.iter().position(|p| *p == v.param).expect("a varying parameter is fitted");
            json!({
                "param": v.param.name(),
                "variable": v.covariate.name(),
                "form": "linear",
                "centre": v.centre,
                "at_centre": r.x[i],
                "slope": r.x[j],
                "slope_name": v.slope_name(),
            })
        })
        .collect();
    let shared: Vec<&str> =
        r.params.iter().filter(|p| !r.varying.iter().any(|v| v.param == **p)).map(|p| p.name()).collect();
    let conditions: Vec<Value> = r
        .conditions
        .iter()
        .map(|c| {
            let mut fields = judgement(&c.values, c.sse_percent2, c.floor_percent2);
            for (k, v) in [
                ("name", json!(c.name)),
                ("data", json!(c.data)),
                ("setup", json!(c.setup)),
                ("measured", json!(c.measured)),
                ("fitted", json!(c.fitted)),
                (
                    "left_out",
                    json!(c.left_out.as_ref().map(|l| judgement(&l.values, l.sse_percent2, l.floor_percent2))),
                ),
                ("left_out_note", json!(c.left_out_note)),
            ] {
                fields.insert(k.to_string(), v);
            }
            Value::Object(fields)
        })
        .collect();
    json!({
        "kind": "joint",
        "objective": num(r.objective_value),
        "objective_kind": r.objective,
        "engine": engine,
        "particles": r.solver.particles,
        "seed": seed,
        "params": r.params.iter().map(|p| p.name()).collect::<Vec<_>>(),
        "shared": shared,
        "varying": varying,
        "x": r.names.iter().zip(&r.x).map(|(n, v)| (n.to_string(), json!(v))).collect::<Map<String, Value>>(),
        "sse_percent2": r.sse_percent2(),
        "floor_percent2": r.floor_percent2(),
        "floor_factor": FLOOR_FACTOR,
        "conditions": conditions,
        "evaluations": r.evaluations,
        "notes": r.notes,
    })
}

/// The joint fit as a table: the parameters, then each condition against its floor, fitted
/// and left out.
pub fn write_joint_table(out: &mut dyn Write, r: &JointReport) -> std::io::Result<()> {
    let g = &r.solver;
    writeln!(
        out,
        "joint fit of {} conditions: objective {}, {} particles, DE {} x {} generations + {} compass iterations ({} \
         simulations)",
        r.conditions.len(),
        match r.objective {
            ObjectiveKind::Sse => "sse",
            ObjectiveKind::Likelihood => "likelihood",
        },
        g.particles,
        g.pop,
        g.generations,
        g.polish_iterations,
        r.evaluations
    )?;
    for n in &r.notes {
        writeln!(out, "note       {n}")?;
    }
    for (p, v) in r.params.iter().zip(&r.x) {
        match r.varying.iter().find(|w| w.param == *p) {
            Some(w) => {
                let j = r.names.iter().position(|n| *n == w.slope_name()).expect("its slope");
                writeln!(
                    out,
                    "{:<12} {v:.4} at {} = {:.4}, slope {:.4} per unit of {} (varies)",
                    p.name(),
                    w.covariate.name(),
                    w.centre,
                    r.x[j],
                    w.covariate.name()
                )?
            }
            None => writeln!(out, "{:<12} {v:.4} (shared)", p.name())?,
        }
    }
    writeln!(out)?;
    let names: Vec<&str> = r.params.iter().map(|p| p.name()).collect();
    writeln!(out, "condition            {:<24} SSE %²   floor %²  ×floor   left out: SSE %²  ×floor", names.join(" "))?;
    for c in &r.conditions {
        let values: Vec<String> = c.values.iter().map(|v| format!("{v:.4}")).collect();
        let left = match (&c.left_out, &c.left_out_note) {
            (Some(l), _) => format!("{:>10.2} {:>7.1}", l.sse_percent2, l.sse_percent2 / l.floor_percent2),
            (None, Some(note)) => note.clone(),
            (None, None) => "-".into(),
        };
        writeln!(
            out,
            "{:<20} {:<24} {:>8.2} {:>9.2} {:>7.1}   {left}",
            c.name,
            values.join(" "),
            c.sse_percent2,
            c.floor_percent2,
            c.sse_percent2 / c.floor_percent2
        )?;
    }
    writeln!(
        out,
        "all                  {:<24} {:>8.2} {:>9.2} {:>7.1}",
        "",
        r.sse_percent2(),
        r.floor_percent2(),
        r.sse_percent2() / r.floor_percent2()
    )?;
    writeln!(out, "(a condition is fitted to its noise where ×floor ≤ {FLOOR_FACTOR})")
}
