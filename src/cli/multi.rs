//! Shared machinery of the multi-run commands (`gpu-sweep`, `study`): a list of runs, each in
//! its own directory, run in lockstep threads so each generation is one engine job;
//! finished runs are read back, unfinished ones resumed, missing ones started.

use std::path::{Path, PathBuf};

use anyhow::Context as _;

use super::optimize::GaArgs;
use crate::engine::{make_engine_for, BatchEvaluator, EngineKind};
use crate::optim::front::{read_pareto_csv, FrontPoint};
use crate::optim::lockstep::Lockstep;
use crate::optim::runner::{is_finished, run, Manifest, RunOptions};

pub struct Planned {
    pub label: String,
    pub dir: PathBuf,
    pub manifest: Manifest,
}

/// Run every planned optimisation; returns each run's final front (None if interrupted).
pub fn run_all(engine: &dyn BatchEvaluator, plans: &[Planned], opts: &RunOptions) -> anyhow::Result<Vec<Option<Vec<FrontPoint>>>> {
    let mut fronts: Vec<Option<Vec<FrontPoint>>> = vec![None; plans.len()];
    let mut todo = Vec::new();
    for (i, p) in plans.iter().enumerate() {
        if is_finished(&p.dir) {
            fronts[i] = Some(read_pareto_csv(&p.dir.join("pareto.csv"))?);
        } else {
            todo.push(i);
        }
    }
    let group = Lockstep::new(engine, todo.len());
    let results: Vec<(usize, anyhow::Result<Option<Vec<FrontPoint>>>)> = std::thread::scope(|scope| {
        let handles: Vec<_> = todo
            .iter()
            .enumerate()
            .map(|(slot, &i)| {
                let (group, plan) = (&group, &plans[i]);
                let opts = RunOptions { label: format!("{}{} ", opts.label, plan.label), ..opts.clone() };
                scope.spawn(move || {
                    let member = group.member(slot);
                    let resume = plan.dir.join("checkpoint.json").exists();
                    let r = run(&plan.dir, (!resume).then(|| plan.manifest.clone()), resume, &member, &opts)
                        .with_context(|| format!("run {}", plan.label))
                        .map(|o| (!o.interrupted).then_some(o.front));
                    (i, r)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("run thread panicked")).collect()
    });
    for (i, r) in results {
        fronts[i] = r?;
    }
    Ok(fronts)
}

/// Create `out`, start the engine and run every plan in lockstep (log lines, no bars: they
/// would interleave). `None` when Ctrl-C stopped the runs (checkpoints are saved; rerunning
/// the same command resumes them).
pub fn execute(out: &Path, kind: EngineKind, ga: &GaArgs, plans: &[Planned]) -> anyhow::Result<Option<Vec<Vec<FrontPoint>>>> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let engine = match plans.first() {
        Some(p) => make_engine_for(kind, &p.manifest.scenario)?,
        None => return Ok(Some(Vec::new())),
    };
    let opts = RunOptions { progress: false, ..ga.options("") };
    let fronts: Option<Vec<Vec<FrontPoint>>> = run_all(&engine, plans, &opts)?.into_iter().collect();
    if fronts.is_none() {
        eprintln!("interrupted: rerun the same command to resume every unfinished run");
    }
    Ok(fronts)
}

/// One panel of `panels_svg`: its name and named series (one y value per x).
pub type Panel<'a> = (&'a str, Vec<(&'a str, Vec<f64>)>);

/// A small multi-panel line plot (x, several named series per panel), hand-written SVG.
pub fn panels_svg(title: &str, x_label: &str, x: &[f64], panels: &[Panel]) -> String {
    let (w, ph, m) = (640.0, 200.0, 60.0);
    let h = 40.0 + panels.len() as f64 * (ph + 30.0) + 30.0;
    let colours = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e"];
    let (x0, x1) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let span = (x1 - x0).max(1e-12);
    let mut s = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="11">"#);
    s.push_str(&format!(r#"<rect width="{w}" height="{h}" fill="white"/><text x="{m}" y="22" font-size="13">{title}</text>"#));
    for (k, (name, series)) in panels.iter().enumerate() {
        let top = 40.0 + k as f64 * (ph + 30.0);
        let vals: Vec<f64> = series.iter().flat_map(|(_, v)| v.iter().cloned()).filter(|v| v.is_finite()).collect();
        let (y0, y1) = vals.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        let (y0, y1) = if y0.is_finite() { (y0, y1.max(y0 + 1e-12)) } else { (0.0, 1.0) };
        let sx = |v: f64| m + (v - x0) / span * (w - 2.0 * m);
        let sy = |v: f64| top + ph - (v - y0) / (y1 - y0) * ph;
        s.push_str(&format!(r#"<rect x="{m}" y="{top}" width="{}" height="{ph}" fill="none" stroke="black"/>"#, w - 2.0 * m));
        s.push_str(&format!(r#"<text x="{}" y="{}">{name}: {y0:.4e} .. {y1:.4e}</text>"#, m + 4.0, top + 12.0));
        for (c, (label, v)) in series.iter().enumerate() {
            let pts: Vec<String> = x.iter().zip(v).filter(|(_, y)| y.is_finite()).map(|(a, b)| format!("{:.2},{:.2}", sx(*a), sy(*b))).collect();
            let col = colours[c % colours.len()];
            s.push_str(&format!(r#"<polyline points="{}" fill="none" stroke="{col}" stroke-width="1.5"/>"#, pts.join(" ")));
            s.push_str(&format!(r#"<text x="{}" y="{}" fill="{col}">{label}</text>"#, w - m - 120.0, top + 14.0 + 12.0 * c as f64));
        }
    }
    s.push_str(&format!(r#"<text x="{}" y="{}" text-anchor="middle">{x_label} ({x0} .. {x1})</text></svg>"#, w / 2.0, h - 10.0));
    s.push('\n');
    s
}
