//! Shared machinery of the multi-run commands (`gpu-sweep`, `study`, `campaign`): a campaign
//! is a folder with a plan (`plan.json`: the member runs, each an `optimize` run with its own
//! folder, seed and settings). Members run in lockstep threads so each generation is one
//! engine job (the local path), or one per process (`campaign run --task I`, a Slurm array
//! task); either way finished members are read back, unfinished ones resumed from their
//! checkpoints, missing ones started, and the summary is built from the members' files.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::engine::{make_engine_for, BatchEvaluator, EngineKind};
use crate::io::atomic::write_atomic;
use crate::io::run_dir::{self, Access, RunDir};
use crate::optim::front::{read_pareto_csv, FrontPoint};
use crate::optim::lockstep::Lockstep;
use crate::optim::nsga2::load_checkpoint;
use crate::optim::runner::{is_finished, read_manifest, run, Manifest, RunOptions};
use crate::plot::{self, Drawn as _, Figure, Mark, PALETTE};

/// The plan's file in a campaign folder.
pub const PLAN_FILE: &str = "plan.json";
/// The `io::run_dir` kind of a campaign folder.
pub const CAMPAIGN_KIND: &str = "campaign";
const PLAN_FORMAT: u32 = 1;

/// What a campaign's summary is.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Study {
    /// `gpu-sweep`: one member per conveyor angle.
    Sweep,
    /// `study repeatability`: one member per seed, compared at the target mass flow.
    Repeatability { target_mass_flow: f64 },
    /// `study sensitivity`: one member per grid point; `repeatability_ci` is (mean, half
    /// width) of W_spec from `--repeatability`, read when the plan was made.
    Sensitivity { target_mass_flow: f64, repeatability_ci: Option<(f64, f64)> },
}

/// One member run: an `optimize` run in `dir` (relative to the campaign folder).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Member {
    pub label: String,
    pub dir: String,
    pub manifest: Manifest,
}

/// A campaign's plan: everything needed to run any member alone and to summarise them.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Plan {
    pub format: u32,
    /// The command that made it (for people).
    pub command: String,
    pub study: Study,
    pub engine: EngineKind,
    pub checkpoint_every: u64,
    pub members: Vec<Member>,
}

impl Plan {
    pub fn new(command: &str, study: Study, engine: EngineKind, checkpoint_every: u64, members: Vec<Member>) -> Plan {
        Plan { format: PLAN_FORMAT, command: command.into(), study, engine, checkpoint_every, members }
    }

    pub fn member_dir(&self, root: &Path, i: usize) -> PathBuf {
        root.join(&self.members[i].dir)
    }

    fn to_json(&self) -> anyhow::Result<String> {
        Ok(serde_json::to_string_pretty(self)? + "\n")
    }
}

/// Read `root/plan.json`.
pub fn read_plan(root: &Path) -> anyhow::Result<Plan> {
    let path = root.join(PLAN_FILE);
    if !path.is_file() {
        bail!("{} is not a campaign folder: it has no {}", root.display(), path.display());
    }
    let text = crate::io::bounded::read_text(&path, &crate::schema::PLAN_FILE)?;
    parse_plan(&text, &path.display().to_string())
}

/// A plan's text checked by every rule (`plan_rules`); `name` is the file named in messages.
pub fn parse_plan(text: &str, name: &str) -> anyhow::Result<Plan> {
    let plan: Plan = serde_json::from_str(text).with_context(|| format!("reading {name}"))?;
    if plan.format != PLAN_FORMAT {
        bail!("{name}: plan format {} (this sawtooth reads format {PLAN_FORMAT})", plan.format);
    }
    super::plan_rules::validate_plan(&plan).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    for (i, m) in plan.members.iter().enumerate() {
        let p = Path::new(&m.dir);
        if m.dir.is_empty() || p.is_absolute() || p.components().any(|c| !matches!(c, std::path::Component::Normal(_)))
        {
            bail!("{name}: member {i}: dir `{}` must be a plain folder name inside the campaign", m.dir);
        }
    }
    Ok(plan)
}

/// Own `root` and write `plan` there; a folder holding a different plan is refused (a
/// campaign's members must all come from one plan).
pub fn write_plan(root: &Path, plan: &Plan) -> anyhow::Result<RunDir> {
    let owned = RunDir::acquire(root, CAMPAIGN_KIND, Access::Exclusive)?;
    let json = plan.to_json()?;
    let path = root.join(PLAN_FILE);
    match std::fs::read_to_string(&path) {
        Ok(old) if old == json => {}
        Ok(_) => bail!(
            "{} holds a different plan ({}): a campaign's settings are fixed when it is planned; choose another --out",
            root.display(),
            path.display()
        ),
        Err(_) => write_atomic(&path, json.as_bytes())?,
    }
    Ok(owned)
}

/// Where a member stands.
#[derive(Debug, Clone, PartialEq)]
pub enum MemberState {
    Finished,
    /// A process holds its folder now.
    Running,
    /// Stopped (or pre-empted) with a checkpoint at this generation.
    Checkpoint(u64),
    NotStarted,
}

impl std::fmt::Display for MemberState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MemberState::Finished => write!(f, "finished"),
            MemberState::Running => write!(f, "running"),
            MemberState::Checkpoint(g) => write!(f, "stopped at generation {g} (checkpoint)"),
            MemberState::NotStarted => write!(f, "not started"),
        }
    }
}

pub fn member_state(dir: &Path) -> MemberState {
    if run_dir::is_held(dir) {
        MemberState::Running
    } else if is_finished(dir) {
        MemberState::Finished
    } else if let Ok(s) = load_checkpoint(dir.join("checkpoint.json")) {
        MemberState::Checkpoint(s.generation)
    } else {
        MemberState::NotStarted
    }
}

/// The settings of a manifest without what a run adds (device, termination).
fn settings(m: &Manifest) -> anyhow::Result<String> {
    let mut m = m.clone();
    m.device.clear();
    m.termination = None;
    Ok(serde_json::to_string(&m)?)
}

/// Every member's final front, read from its folder; an error listing the members that are
/// not finished (a partial member is never summarised) or were run with other settings.
pub fn finished_fronts(root: &Path, plan: &Plan) -> anyhow::Result<Vec<Vec<FrontPoint>>> {
    let mut fronts = Vec::new();
    let mut missing = Vec::new();
    for (i, m) in plan.members.iter().enumerate() {
        let dir = plan.member_dir(root, i);
        match member_state(&dir) {
            MemberState::Finished => {
                let run = read_manifest(&dir)?;
                if settings(&run)? != settings(&m.manifest)? {
                    bail!(
                        "member {i} ({}): {} was run with other settings than the plan's; refusing to summarise it",
                        m.label,
                        dir.join("run.toml").display()
                    );
                }
                fronts.push(read_pareto_csv(&dir.join("pareto.csv"))?);
            }
            s => missing.push(format!("  {i:>4}  {}  {s}", m.label)),
        }
    }
    if !missing.is_empty() {
        bail!(
            "{} of {} members of {} are unfinished; no summary written:\n{}\nrun them (`sawtooth campaign run {} --task I`, or `sawtooth campaign slurm {} --unfinished --submit`) and gather again",
            missing.len(),
            plan.members.len(),
            root.display(),
            missing.join("\n"),
            root.display(),
            root.display()
        );
    }
    Ok(fronts)
}

/// Run every unfinished member in lockstep; `false` when interrupted (Ctrl-C / SIGTERM).
pub fn run_all(engine: &dyn BatchEvaluator, root: &Path, plan: &Plan, opts: &RunOptions) -> anyhow::Result<bool> {
    let todo: Vec<usize> = (0..plan.members.len()).filter(|&i| !is_finished(&plan.member_dir(root, i))).collect();
    let group = Lockstep::new(engine, todo.len());
    let results: Vec<anyhow::Result<bool>> = std::thread::scope(|scope| {
        let handles: Vec<_> = todo
            .iter()
            .enumerate()
            .map(|(slot, &i)| {
                let (group, m, dir) = (&group, &plan.members[i], plan.member_dir(root, i));
                // the runs advance together: the first one speaks for all (N lines would interleave)
                let others = todo.len() - 1;
                let label = if others > 0 {
                    format!("{}{} (+{others} more in lockstep) ", opts.label, m.label)
                } else {
                    format!("{}{} ", opts.label, m.label)
                };
                let opts = RunOptions { label, progress: opts.progress && slot == 0, ..opts.clone() };
                scope.spawn(move || {
                    let member = group.member(slot);
                    let resume = dir.join("checkpoint.json").exists();
                    run(&dir, (!resume).then(|| m.manifest.clone()), resume, &member, &opts)
                        .with_context(|| format!("member {i} ({})", m.label))
                        .map(|o| !o.interrupted)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("run thread panicked")).collect()
    });
    let mut done = true;
    for r in results {
        done &= r?;
    }
    Ok(done)
}

/// The local path: start the engine once and run every unfinished member of `plan` in
/// lockstep (log lines, no bars: they would interleave). `false` when Ctrl-C stopped the
/// runs (checkpoints are saved; rerunning the same command resumes them).
pub fn execute(root: &Path, plan: &Plan) -> anyhow::Result<bool> {
    let engine = match plan.members.first() {
        Some(m) => make_engine_for(plan.engine, &m.manifest.scenario)?,
        None => return Ok(true),
    };
    let opts = RunOptions { checkpoint_every: plan.checkpoint_every, progress: true, label: String::new() };
    let done = run_all(&engine, root, plan, &opts)?;
    if !done {
        eprintln!("interrupted: rerun the same command to resume every unfinished run");
    }
    Ok(done)
}

/// Summary files and table of a campaign whose members are all finished.
pub fn summarise(root: &Path, plan: &Plan, fronts: &[Vec<FrontPoint>], out: &mut dyn Write) -> anyhow::Result<()> {
    match &plan.study {
        Study::Sweep => super::sweep::summarise(root, plan, fronts, out),
        Study::Repeatability { target_mass_flow } => {
            super::study::summarise_repeatability(root, plan, *target_mass_flow, fronts, out)
        }
        Study::Sensitivity { target_mass_flow, repeatability_ci } => {
            super::study::summarise_sensitivity(root, plan, *target_mass_flow, *repeatability_ci, fronts, out)
        }
    }
}

/// What `gpu-sweep` and `study` do with their plan: with `plan_only` write it and stop;
/// otherwise run it here in one process and summarise from the members' files (the same
/// code `campaign gather` runs, so both give the same bytes).
pub fn plan_or_run(root: &Path, plan: &Plan, plan_only: bool, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let _owned = write_plan(root, plan)?;
    if plan_only {
        let n = plan.members.len();
        writeln!(out, "wrote {} ({n} members); nothing run yet", root.join(PLAN_FILE).display())?;
        writeln!(
            out,
            "  one member:      sawtooth campaign run {} --task I   (I in 0..{})",
            root.display(),
            n.saturating_sub(1)
        )?;
        writeln!(out, "  all, here:       sawtooth campaign run {}", root.display())?;
        writeln!(
            out,
            "  Slurm job array: sawtooth campaign slurm {} [--partition P --time T] --submit",
            root.display()
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    if !execute(root, plan)? {
        return Ok(ExitCode::from(130));
    }
    let fronts = finished_fronts(root, plan)?;
    summarise(root, plan, &fronts, out)?;
    Ok(ExitCode::SUCCESS)
}

/// One named series of a panel: a y value per x, with optional ± standard errors.
pub struct Series {
    pub label: String,
    pub y: Vec<f64>,
    pub se: Option<Vec<f64>>,
}

/// One panel of [`PanelsPlot`]: its y axis title (with unit), its series and optionally a
/// horizontal band (centre, half width, legend text) such as a mean and its interval.
pub struct Panel {
    pub y_desc: String,
    pub series: Vec<Series>,
    pub band: Option<(f64, f64, String)>,
}

/// The campaign summary figure (sweep.svg, repeatability.svg, sensitivity.svg): stacked
/// panels over one x axis. `joined` draws each series as a line through its markers (a sweep
/// over a continuous parameter); otherwise the points stand alone (independent runs).
pub struct PanelsPlot {
    pub title: String,
    pub x_desc: String,
    pub x: Vec<f64>,
    /// Category labels for x = 0, 1, 2, ... (run numbers, grid points) instead of numeric ticks.
    pub x_categories: Option<Vec<String>>,
    pub panels: Vec<Panel>,
    pub joined: bool,
}

const PANELS_WIDTH_PX: u32 = 900;
const PANEL_PX: u32 = 260;
const BAND_COLOUR: RGBColor = RGBColor(0x99, 0x99, 0x99);

impl PanelsPlot {
    fn legend(&self) -> Vec<(Mark, String)> {
        let mut out: Vec<(Mark, String)> = Vec::new();
        let first = self.panels.first();
        for (c, s) in first.map_or(&[][..], |p| &p.series[..]).iter().enumerate() {
            let colour = PALETTE[c % PALETTE.len()];
            out.push((if self.joined { Mark::Line(colour) } else { Mark::Point(colour) }, s.label.clone()));
        }
        if self.panels.iter().any(|p| p.series.iter().any(|s| s.se.is_some())) {
            out.push((Mark::Interval(BLACK), "±1 standard error (re-evaluation)".into()));
        }
        if let Some((_, _, label)) = self.panels.iter().find_map(|p| p.band.as_ref()) {
            out.push((Mark::Block(BAND_COLOUR), label.clone()));
        }
        out
    }

    fn legend_px(&self) -> u32 {
        let legend = self.legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        plot::legend_height(PANELS_WIDTH_PX, &entries)
    }

    fn draw_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        panel: &Panel,
        last: bool,
    ) -> anyhow::Result<()> {
        let x = match &self.x_categories {
            Some(labels) => plot::category_range(labels.len()),
            None => {
                let (lo, hi) = plot::extent(self.x.iter().copied()).unwrap_or((0.0, 1.0));
                plot::padded(lo, hi, 0.05)
            }
        };
        let values = panel.series.iter().flat_map(|s| {
            s.y.iter().enumerate().flat_map(move |(i, v)| {
                let e = s.se.as_ref().and_then(|e| e.get(i)).copied().filter(|e| e.is_finite()).unwrap_or(0.0);
                [v - e, v + e]
            })
        });
        let band = panel.band.iter().flat_map(|(c, h, _)| [c - h, c + h]);
        let (lo, hi) = plot::extent(values.chain(band)).unwrap_or((0.0, 1.0));
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .margin_right(25)
            .x_label_area_size(if last { 50 } else { 30 })
            .y_label_area_size(90)
            .build_cartesian_2d(x, plot::padded(lo, hi, 0.08))
            .drawn()?;
        let category_label = self.x_categories.as_deref().map(plot::category_label);
        let mut mesh = chart.configure_mesh();
        mesh.y_desc(panel.y_desc.as_str())
            .y_label_formatter(&plot::tick)
            .label_style(plot::text_style(plot::SMALL_SIZE))
            .axis_desc_style(plot::text_style(plot::SMALL_SIZE))
            .bold_line_style(plot::GRID)
            .max_light_lines(1);
        match (&category_label, &self.x_categories) {
            (Some(f), Some(labels)) => {
                mesh.disable_x_mesh().x_labels(labels.len() + 1).x_label_formatter(f);
            }
            _ => {
                mesh.x_label_formatter(&plot::tick);
            }
        }
        if last {
            mesh.x_desc(self.x_desc.as_str());
        }
        mesh.draw().drawn()?;
        let (x0, x1) = (chart.x_range().start, chart.x_range().end);
        if let Some((centre, half, _)) = &panel.band {
            chart
                .draw_series([Rectangle::new(
                    [(x0, centre - half), (x1, centre + half)],
                    BAND_COLOUR.mix(0.3).filled(),
                )])
                .drawn()?;
            chart
                .draw_series([PathElement::new(vec![(x0, *centre), (x1, *centre)], BAND_COLOUR.stroke_width(2))])
                .drawn()?;
        }
        for (c, s) in panel.series.iter().enumerate() {
            let colour = PALETTE[c % PALETTE.len()];
            let points: Vec<(f64, f64)> =
                self.x.iter().zip(&s.y).filter(|(_, y)| y.is_finite()).map(|(x, y)| (*x, *y)).collect();
            if self.joined {
                chart.draw_series(LineSeries::new(points.clone(), colour.stroke_width(2))).drawn()?;
            }
            if let Some(se) = &s.se {
                for ((x, y), e) in self.x.iter().zip(&s.y).zip(se).filter(|((_, y), e)| y.is_finite() && e.is_finite())
                {
                    chart
                        .draw_series([PathElement::new(vec![(*x, y - e), (*x, y + e)], colour.stroke_width(2))])
                        .drawn()?;
                    for end in [y - e, y + e] {
                        chart
                            .draw_series([EmptyElement::at((*x, end))
                                + PathElement::new(vec![(-5, 0), (5, 0)], colour.stroke_width(2))])
                            .drawn()?;
                    }
                }
            }
            chart.draw_series(points.iter().map(|p| Circle::new(*p, 5, colour.filled()))).drawn()?;
        }
        Ok(())
    }
}

impl Figure for PanelsPlot {
    fn size(&self) -> (u32, u32) {
        let title = (plot::TITLE_SIZE * 1.6) as u32;
        (PANELS_WIDTH_PX, title + PANEL_PX * self.panels.len().max(1) as u32 + 20 + self.legend_px())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let area = plot::title(root, &self.title)?;
        let n = self.panels.len().max(1) as u32;
        let (panels, key) = area.split_vertically(PANEL_PX * n + 20);
        // the last panel carries the x axis title: 20 px more
        let mut rest = panels;
        for (k, panel) in self.panels.iter().enumerate() {
            let last = k + 1 == self.panels.len();
            let (this, below) = rest.split_vertically(if last { PANEL_PX + 20 } else { PANEL_PX });
            self.draw_panel(&this, panel, last)?;
            rest = below;
        }
        let legend = self.legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        plot::legend(&key, &entries)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::tests::{assert_has_ticks, assert_real_png, svg_texts};

    fn panels(joined: bool) -> PanelsPlot {
        let series = |label: &str, y: Vec<f64>, se: Option<Vec<f64>>| Series { label: label.into(), y, se };
        PanelsPlot {
            title: "Conveyor-angle sweep".into(),
            x_desc: "conveyor angle alpha [deg]".into(),
            x: vec![5.0, 10.0, 15.0],
            x_categories: None,
            panels: vec![
                Panel {
                    y_desc: "W_spec [J/kg]".into(),
                    series: vec![
                        series("lowest W_spec (C)", vec![300.0, 320.0, 350.0], Some(vec![5.0, 6.0, 7.0])),
                        series("closest to 48 kg/h (A)", vec![700.0, 780.0, f64::NAN], Some(vec![9.0, 9.0, 9.0])),
                    ],
                    band: None,
                },
                Panel {
                    y_desc: "mass flow [kg/h]".into(),
                    series: vec![series("lowest W_spec (C)", vec![400.0, 410.0, 380.0], None)],
                    band: Some((400.0, 20.0, "mean ± 95 % confidence interval".into())),
                },
            ],
            joined,
        }
    }

    #[test]
    fn sweep_panels_have_ticks_units_legend_and_error_bars() {
        let svg = plot::render_svg(&panels(true)).unwrap();
        let texts = svg_texts(&svg);
        for want in [
            "Conveyor-angle sweep",
            "conveyor angle alpha [deg]",
            "W_spec [J/kg]",
            "mass flow [kg/h]",
            "lowest W_spec (C)",
            "closest to 48 kg/h (A)",
            "±1 standard error (re-evaluation)",
            "mean ± 95 % confidence interval",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want} missing: {texts:?}");
        }
        assert_has_ticks(&svg, 10);
        assert!(svg.contains("<polyline"), "a sweep joins its markers");
        assert!(!svg.contains("NaN"));
    }

    #[test]
    fn independent_runs_are_not_joined() {
        let svg = plot::render_svg(&PanelsPlot {
            x_categories: Some(vec!["0".into(), "1".into(), "2".into()]),
            ..panels(false)
        })
        .unwrap();
        // points (circles), the band and error bars, but no line through the runs: every
        // polyline is a two-point segment (an error bar, its caps, the band's centre line)
        assert!(svg.contains("<circle"));
        for line in svg.lines().filter(|l| l.contains("<polyline")) {
            let points = line.split("points=\"").nth(1).unwrap().split('"').next().unwrap();
            assert!(points.split_whitespace().count() <= 2, "a line through the runs: {line}");
        }
        assert!(svg_texts(&svg).iter().any(|t| t == "2"), "run numbers label the x axis");
    }

    #[test]
    fn panels_png_is_a_real_image() {
        let fig = panels(true);
        assert_real_png(&plot::render_png(&fig).unwrap(), fig.size());
    }
}
