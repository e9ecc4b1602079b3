//! One optimisation run in a directory: manifest, incremental CSVs, checkpoints, resume,
//! final front. The CLI commands (`optimize`, `gpu-sweep`, `study`) are thin layers on it.
//!
//! Output directory: run.toml (manifest: version, engine, device, seed, every setting),
//! evaluations.csv (every evaluation, appended per generation), generations.csv,
//! checkpoint.json (atomic, every N generations and on Ctrl-C), and at the end pareto.csv
//! (re-evaluated with more particles, with Monte-Carlo standard errors), pareto.svg.

use std::cell::RefCell;
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::front::{final_front, write_outputs, FrontPoint};
use super::hypervolume::hypervolume_2d;
use super::manifest::{read_manifest, Manifest};
use super::nsga2::{load_checkpoint, save_checkpoint, Config, GenerationStats, Mode, Nsga2, State};
use super::observe::{drive, install_interrupt_handler, Checkpoints, Ending, Flow, Interrupt, Observer};
use super::sawtooth::{Logged, SawtoothProblem};
use crate::engine::BatchEvaluator;
use crate::io::atomic::write_atomic;
use crate::io::run_dir::{Access, RunDir};
use crate::io::table::{csv_header, csv_text};
use crate::model::design::DesignRow;

/// Hypervolume reference point (f_stroke Hz, W_spec J/kg): the 2 Hz limit and a specific
/// energy well above every published front point.
pub const HV_REFERENCE: [f64; 2] = [2.0, 20_000.0];

/// How a run reports and checkpoints.
#[derive(Debug, Clone)]
pub struct RunOptions {
    pub checkpoint_every: u64,
    /// Report progress on stderr: a bar on a terminal, else a line every few seconds with the
    /// generation and an ETA (`io::progress`); false: silent (`--quiet`).
    pub progress: bool,
    /// Prefix for progress output (e.g. the sweep's angle).
    pub label: String,
}

/// The end of a run.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    pub dir: PathBuf,
    pub manifest: Manifest,
    pub front: Vec<FrontPoint>,
    pub termination: String,
    pub generations: u64,
    /// Stopped by Ctrl-C (checkpoint saved; front empty).
    pub interrupted: bool,
}

/// One row of evaluations.csv: every design evaluated, as the optimiser ranked it. Header and
/// row come from this one type; floats are written exactly (shortest round-trip form).
#[derive(Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct EvaluationRow {
    pub generation: u64,
    /// The design in user units (its eight columns).
    #[serde(flatten)]
    pub design: DesignRow,
    /// The objectives the GA ranks by: f_stroke (Hz) and W_spec (J/kg), with the 2 Hz penalty
    /// of Eq. 5.17-5.18, D.6's 1000003-1000007 for a rejected design, 1e12 where not simulated.
    pub objective_f_stroke_hz: f64,
    pub objective_w_spec_j_kg: f64,
    /// Deb's constraint violation: geometric excess in mm beyond the tolerance, plus with
    /// requirements their relative shortfalls (0 = feasible).
    pub violation: f64,
    /// The simulated figures at `alpha_deg` (empty where the design was not simulated or the
    /// model rejects it).
    pub f_stroke_hz: Option<f64>,
    pub w_spec_j_kg: Option<f64>,
    pub m_dot_kg_s: Option<f64>,
    pub stroke_m: Option<f64>,
    pub n_wire: Option<u32>,
    pub d_avg_m: Option<f64>,
    pub lost_fraction: Option<f64>,
    /// Why the design has no figures: the model's rule (e.g. `fill_spills`), or `infeasible`.
    pub invalid: String,
    /// The slope shown (`sawtooth::shown_slope`), degrees.
    pub alpha_deg: f64,
    /// With requirements: the operating point and the verdict at that slope.
    pub m_dot_op_kg_h: Option<f64>,
    pub p_op_w: Option<f64>,
    pub operating_limit: Option<String>,
    pub compliant: Option<bool>,
}

impl EvaluationRow {
    fn of(l: &Logged) -> Self {
        let e = l.evaluation.as_ref();
        let a = l.assessment.as_ref();
        EvaluationRow {
            generation: l.generation,
            design: DesignRow::from_values(l.x),
            objective_f_stroke_hz: l.objectives[0],
            objective_w_spec_j_kg: l.objectives[1],
            violation: l.violation,
            // the frequency the objective uses (D.7's f_dynamic; equal to f_stroke below f_max)
            f_stroke_hz: e.map(|e| e.performance.f_dynamic_hz),
            w_spec_j_kg: e.and_then(|e| e.performance.w_spec_j_kg),
            m_dot_kg_s: e.map(|e| e.performance.m_dot_kg_s),
            stroke_m: e.map(|e| e.performance.stroke_m),
            n_wire: e.map(|e| e.performance.n_wire),
            d_avg_m: e.map(|e| e.sim.d_avg_m),
            lost_fraction: e.map(|e| e.sim.lost_fraction),
            invalid: match (e, &l.invalid) {
                (Some(_), _) => String::new(),
                (None, Some(rule)) => rule.clone(),
                (None, None) if l.violation > 0.0 => "infeasible".to_string(),
                (None, None) => String::new(),
            },
            alpha_deg: l.alpha_deg,
            m_dot_op_kg_h: a.map(|a| a.operating_point.m_dot_kg_h),
            p_op_w: a.map(|a| a.operating_point.p_avg_w),
            operating_limit: a.map(|a| a.operating_point.limit.as_str().to_string()),
            compliant: a.map(|a| a.compliant()),
        }
    }
}

/// One row of generations.csv: the search's progress after each generation.
#[derive(Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct GenerationRow {
    pub generation: u64,
    /// Of the feasible front w.r.t. `HV_REFERENCE` (2 Hz, 20 000 J/kg), Hz·J/kg.
    pub hypervolume_hz_j_kg: f64,
    /// Deb's spread of the front (-); empty while nothing is feasible.
    pub spread: Option<f64>,
    pub feasible_fraction: f64,
    pub front_size: usize,
    pub evaluations: u64,
    /// Wall time since this process started the run, s.
    pub elapsed_s: f64,
}

/// Keep the header and the rows of generations <= `last` (a crash may have logged a
/// generation that the checkpoint does not hold yet). Rows are appended, not written
/// atomically: a row torn by a kill mid-append has no newline yet and is dropped even
/// where what is left of its generation field reads as an old generation.
fn truncate_csv(path: &Path, limit: &crate::schema::FileLimit, last: u64) -> anyhow::Result<()> {
    let text = crate::io::bounded::read_text(path, limit)?;
    let complete = match text.rfind('\n') {
        Some(i) => &text[..=i],
        None => text.as_str(),
    };
    let mut out = String::with_capacity(text.len());
    for (i, line) in complete.lines().enumerate() {
        let keep = i == 0 || line.split(',').next().and_then(|g| g.parse::<u64>().ok()).is_some_and(|g| g <= last);
        if keep {
            out.push_str(line);
            out.push('\n');
        }
    }
    write_atomic(path, out.as_bytes())
}

fn append(path: &Path, lines: &str) -> anyhow::Result<()> {
    crate::io::run_dir::record_write(path)?;
    let mut f = OpenOptions::new()
        .append(true)
        .create(true)
        .open(path)
        .with_context(|| format!("appending to {}", path.display()))?;
    f.write_all(lines.as_bytes())?;
    f.flush()?;
    Ok(())
}

/// The front's objective points that count for the hypervolume.
fn front_points(state: &State) -> Vec<[f64; 2]> {
    Nsga2::pareto_front(state)
        .iter()
        .filter(|i| i.eval.violation == 0.0)
        .map(|i| [i.eval.objectives[0], i.eval.objectives[1]])
        .collect()
}

/// Ends the run with the first error the problem met appending to evaluations.csv.
struct EvaluationErrors(Rc<RefCell<Option<anyhow::Error>>>);

impl Observer for EvaluationErrors {
    fn observe(&mut self, _: &State, _: &GenerationStats) -> anyhow::Result<Flow> {
        match self.0.borrow_mut().take() {
            Some(e) => Err(e),
            None => Ok(Flow::Continue),
        }
    }
}

/// A row of generations.csv per generation.
struct GenerationsCsv {
    path: PathBuf,
    start: Instant,
}

impl Observer for GenerationsCsv {
    fn observe(&mut self, state: &State, stats: &GenerationStats) -> anyhow::Result<Flow> {
        let row = GenerationRow {
            generation: stats.generation,
            hypervolume_hz_j_kg: hypervolume_2d(&front_points(state), HV_REFERENCE),
            spread: Some(stats.spread).filter(|s| s.is_finite()),
            feasible_fraction: stats.feasible_fraction,
            front_size: stats.front_size,
            evaluations: stats.evaluations,
            // milliseconds are enough for a wall clock, and keep the column readable
            elapsed_s: (self.start.elapsed().as_secs_f64() * 1e3).round() / 1e3,
        };
        append(&self.path, &csv_text(&[row], false)?)?;
        Ok(Flow::Continue)
    }
}

/// A progress bar on a terminal; off one, a line at the start, every 10 s and at the end
/// (`io::progress`); nothing with `opts.progress` off.
struct Progress {
    bar: indicatif::ProgressBar,
    lines: crate::io::progress::Lines,
    on: bool,
    interactive: bool,
    label: String,
    max: u64,
    first_generation: u64,
    start: Instant,
    /// The spread stall may end the run before `max` (the ETA is an upper bound).
    may_stall: bool,
}

impl Progress {
    fn new(opts: &RunOptions, config: &Config, generation: u64, start: Instant) -> Self {
        let interactive = std::io::IsTerminal::is_terminal(&std::io::stderr());
        let bar = if opts.progress && interactive {
            let b = indicatif::ProgressBar::new(config.max_generations);
            b.set_style(
                indicatif::ProgressStyle::with_template("{prefix}{bar:30} gen {pos}/{len} {msg} eta {eta}")
                    .expect("valid template"),
            );
            b.set_prefix(opts.label.clone());
            b.set_position(generation);
            b
        } else {
            indicatif::ProgressBar::hidden()
        };
        Progress {
            bar,
            lines: crate::io::progress::Lines::new(),
            on: opts.progress,
            interactive,
            label: opts.label.clone(),
            max: config.max_generations,
            first_generation: generation,
            start,
            may_stall: matches!(config.mode, Mode::MatlabLike { .. }),
        }
    }
}

impl Observer for Progress {
    fn observe(&mut self, state: &State, stats: &GenerationStats) -> anyhow::Result<Flow> {
        let hv = hypervolume_2d(&front_points(state), HV_REFERENCE);
        self.bar.set_position(state.generation);
        self.bar.set_message(format!(
            "HV {hv:.4e} feasible {:.0}% front {}",
            stats.feasible_fraction * 100.0,
            stats.front_size
        ));
        let max = self.max;
        if self.on && !self.interactive && self.lines.due(state.generation, max) {
            let eta = crate::io::progress::eta(
                self.start.elapsed(),
                state.generation.saturating_sub(self.first_generation),
                max.saturating_sub(self.first_generation),
            );
            eprintln!(
                "{}generation {}/{max}: HV {hv:.4e}, feasible {:.0} %, front {}; {eta}{}",
                self.label,
                state.generation,
                stats.feasible_fraction * 100.0,
                stats.front_size,
                if self.may_stall { " (at most: the spread stall may stop it sooner)" } else { "" }
            );
        }
        Ok(Flow::Continue)
    }
    fn finish(&mut self, _: &State, ending: Ending) -> anyhow::Result<()> {
        match ending {
            Ending::Stopped => self.bar.abandon(),
            Ending::Terminated(_) => self.bar.finish_and_clear(),
        }
        Ok(())
    }
}

/// Paths of a run directory.
struct Paths {
    manifest: PathBuf,
    checkpoint: PathBuf,
    evaluations: PathBuf,
    generations: PathBuf,
}

impl Paths {
    fn new(dir: &Path) -> Self {
        Paths {
            manifest: dir.join("run.toml"),
            checkpoint: dir.join("checkpoint.json"),
            evaluations: dir.join("evaluations.csv"),
            generations: dir.join("generations.csv"),
        }
    }
}

/// The `io::run_dir` kind of an optimisation run's folder.
pub const RUN_KIND: &str = "optimize";

/// True when `dir` holds a finished run (its pareto.csv exists).
/// True when `dir` holds a started run (its checkpoint): a new run there is refused.
pub fn holds_run(dir: &Path) -> bool {
    Paths::new(dir).checkpoint.exists()
}

pub fn is_finished(dir: &Path) -> bool {
    dir.join("pareto.csv").exists() && read_manifest(dir).is_ok_and(|m| m.termination.is_some())
}

/// Run (or with `resume`, continue) the optimisation in `dir`. `manifest` describes a new
/// run; with `resume` it is the directory's own (possibly extended to more generations by
/// the caller), read from the directory when not given.
pub fn run(
    dir: &Path,
    manifest: Option<Manifest>,
    resume: bool,
    engine: &dyn BatchEvaluator,
    opts: &RunOptions,
) -> anyhow::Result<RunOutcome> {
    let paths = Paths::new(dir);
    if resume && !paths.manifest.exists() {
        bail!("no run to resume: no run manifest at {}", paths.manifest.display());
    }
    // Owned for the whole run: a second process started into `dir` is refused, not interleaved.
    let _owned = RunDir::acquire(dir, RUN_KIND, Access::Exclusive)?;
    let (mut manifest, state) = if resume {
        let m = match manifest {
            Some(m) => m,
            None => read_manifest(dir)?,
        };
        if !paths.checkpoint.exists() {
            // killed before its first checkpoint: nothing of the run is kept but its settings
            eprintln!(
                "{}no checkpoint in {} yet (the run stopped before its first generation was saved): starting it again from generation 0 with its run.toml",
                opts.label,
                dir.display()
            );
            (m, None)
        } else {
            let state = load_checkpoint(&paths.checkpoint)
                .with_context(|| format!("resuming: reading {}", paths.checkpoint.display()))?;
            // an edited or damaged checkpoint is refused by its field, not believed
            super::checkpoint::validate_state(&state, &m.config, SawtoothProblem::SHAPE)
                .map_err(|e| anyhow::anyhow!("resuming: {}: {e}", paths.checkpoint.display()))?;
            truncate_csv(&paths.evaluations, &crate::schema::EVALUATIONS_FILE, state.generation)?;
            truncate_csv(&paths.generations, &crate::schema::GENERATIONS_FILE, state.generation)?;
            eprintln!("{}resuming from the checkpoint at generation {}", opts.label, state.generation);
            // an extension (a larger --generations) is on disk before the first new generation
            write_atomic(&paths.manifest, toml::to_string_pretty(&m)?.as_bytes())?;
            (m, Some(state))
        }
    } else {
        if paths.checkpoint.exists() {
            bail!("{} already holds a run: resume it, or start the new run in another folder", dir.display());
        }
        let m = manifest.context("a new run needs its settings")?;
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        (m, None)
    };
    manifest.device = engine.device();
    if state.is_none() {
        write_atomic(&paths.manifest, toml::to_string_pretty(&manifest)?.as_bytes())?;
        write_atomic(&paths.evaluations, csv_header::<EvaluationRow>()?.as_bytes())?;
        write_atomic(&paths.generations, csv_header::<GenerationRow>()?.as_bytes())?;
    }

    // evaluations.csv is appended by the problem as it evaluates; a write error surfaces
    // after the generation (`EvaluationErrors`)
    let log_error: Rc<RefCell<Option<anyhow::Error>>> = Rc::default();
    let log = {
        let (path, log_error) = (paths.evaluations.clone(), log_error.clone());
        move |rows: &[Logged]| {
            let rows: Vec<EvaluationRow> = rows.iter().map(EvaluationRow::of).collect();
            if let Err(e) = csv_text(&rows, false).and_then(|text| append(&path, &text)) {
                log_error.borrow_mut().get_or_insert(e);
            }
        }
    };
    let mut problem = SawtoothProblem {
        scenario: manifest.scenario.clone(),
        engine,
        base_seed: manifest.seed,
        log: Some(Box::new(log)),
        requirements: manifest.requirements.clone(),
        slopes_deg: manifest.slopes_deg.clone(),
    };
    let ga = Nsga2 { config: manifest.config.clone() };
    install_interrupt_handler();
    let start = Instant::now();
    let mut state = match state {
        Some(s) => s,
        None => {
            let s = ga.init(&mut problem);
            save_checkpoint(&paths.checkpoint, &s)?;
            s
        }
    };
    let mut errors = EvaluationErrors(log_error);
    let mut generations = GenerationsCsv { path: paths.generations.clone(), start };
    let mut checkpoints = Checkpoints { path: paths.checkpoint.clone(), every: opts.checkpoint_every };
    let mut progress = Progress::new(opts, &manifest.config, state.generation, start);
    let ending = drive(
        &ga,
        &mut state,
        &mut problem,
        &mut [&mut errors, &mut generations, &mut checkpoints, &mut progress, &mut Interrupt],
    )?;
    let termination = match ending {
        Ending::Terminated(t) => format!("{t:?}"),
        Ending::Stopped => {
            // how to continue is the caller's to say: `optimize --resume`, or the same
            // sweep, study or campaign command again
            eprintln!("{}interrupted: checkpoint saved at generation {}", opts.label, state.generation);
            return Ok(RunOutcome {
                dir: dir.to_path_buf(),
                manifest,
                front: Vec::new(),
                termination: "Interrupted".into(),
                generations: state.generation,
                interrupted: true,
            });
        }
    };
    drop(problem);
    let front = final_front(engine, &manifest, &state)?;
    write_outputs(dir, &front, &paths.evaluations)?;
    manifest.termination = Some(termination.clone());
    write_atomic(&paths.manifest, toml::to_string_pretty(&manifest)?.as_bytes())?;
    Ok(RunOutcome {
        dir: dir.to_path_buf(),
        manifest,
        front,
        termination,
        generations: state.generation,
        interrupted: false,
    })
}

#[cfg(test)]
mod tests {
    use super::truncate_csv;

    #[test]
    fn resuming_drops_rows_past_the_checkpoint_and_a_torn_last_row() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("generations.csv");
        // generation 12's row was torn after its first character by a kill mid-append
        std::fs::write(&p, "generation,x\n1,a\n2,b\n3,c\n1").unwrap();
        truncate_csv(&p, &crate::schema::GENERATIONS_FILE, 2).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "generation,x\n1,a\n2,b\n");
    }
}
