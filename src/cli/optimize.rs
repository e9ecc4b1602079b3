//! `sawtooth optimize`: the thesis's constrained multi-objective optimisation (5.2-5.5) with
//! NSGA-II, one batch evaluation per generation, incremental CSV output and exact resume.
//!
//! Output directory: run.toml (manifest: version, engine, device, seed, every setting),
//! evaluations.csv (every evaluation, appended per generation), generations.csv,
//! checkpoint.json (atomic, every N generations and on Ctrl-C), and at the end pareto.csv
//! (re-evaluated with more particles, with Monte-Carlo standard errors), pareto.svg.

use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context as _};
use clap::Args;
use serde::{Deserialize, Serialize};

use super::args::{EngineArgs, ScenarioArgs};
use crate::engine::{make_engine, BatchEvaluator, EngineKind};
use crate::optim::hypervolume::hypervolume_2d;
use crate::optim::nsga2::{load_checkpoint, save_checkpoint, Config, Mode, Nsga2, State};
use crate::optim::sawtooth::{design_of, Logged, SawtoothProblem};
use crate::model::Scenario;

/// Hypervolume reference point (f_stroke Hz, W_spec J/kg): the 2 Hz limit and a specific
/// energy well above every published front point.
pub const HV_REFERENCE: [f64; 2] = [2.0, 20_000.0];

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Algorithm {
    /// NSGA-II (Deb et al. 2002) with Deb's constraint domination; stops at --generations.
    Nsga2,
    /// gamultiobj-like: ParetoFraction 0.35, stops when the average relative change of the
    /// front's spread over --stall-generations falls below --tol (or at --generations).
    MatlabLike,
}

#[derive(Debug, Args)]
pub struct OptimizeArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
    /// Population size (thesis: 500, high fidelity 1000).
    #[arg(long, default_value_t = 1000)]
    pub pop: usize,
    /// Maximum generations (D.5: MaxGenerations 1000).
    #[arg(long, default_value_t = 1000)]
    pub generations: u64,
    #[arg(long, value_enum, default_value = "matlab-like")]
    pub algorithm: Algorithm,
    /// Function tolerance of the spread-stall stop (thesis: 1e-4, high fidelity 1e-6).
    #[arg(long, default_value_t = 1e-6)]
    pub tol: f64,
    /// Generations over which the spread change is averaged (MATLAB: MaxStallGenerations 100).
    #[arg(long, default_value_t = 100)]
    pub stall_generations: u64,
    /// Particles per design when re-evaluating the final front.
    #[arg(long, default_value_t = 1000)]
    pub final_particles: u32,
    /// Independent particle streams for the final re-evaluation (standard errors).
    #[arg(long, default_value_t = 8)]
    pub replicates: u32,
    /// Save a checkpoint every N generations (always on Ctrl-C and at the end).
    #[arg(long, default_value_t = 1)]
    pub checkpoint_every: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Continue the run in --out from its checkpoint (settings come from its run.toml).
    #[arg(long)]
    pub resume: bool,
    /// No progress bar (logs one line per 10 generations instead).
    #[arg(long)]
    pub quiet: bool,
}

/// Everything that determines a run: written to run.toml, read back by --resume.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    pub version: String,
    pub engine: EngineKind,
    pub device: String,
    pub seed: u64,
    pub algorithm: Algorithm,
    pub config: Config,
    pub final_particles: u32,
    pub replicates: u32,
    pub scenario: Scenario,
    pub termination: Option<String>,
}

fn csv_header_evaluations() -> &'static str {
    "generation,l_c_mm,l_a_mm,l_b_mm,r_mm,omega_deg,delta_deg,v0_m_s,a_m_s2,objective_1,objective_2,violation,f_stroke_hz,w_spec_j_kg,m_dot_kg_s,stroke_m,n_wire,d_avg_m,lost_fraction,invalid"
}

fn evaluation_row(l: &Logged) -> String {
    let x = l.x;
    let mut row = format!(
        "{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.9e},{:.9e},{:.6e}",
        l.generation, x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], l.objectives[0], l.objectives[1], l.violation
    );
    match &l.evaluation {
        Some(e) => {
            let p = &e.performance;
            row.push_str(&format!(
                ",{:.9e},{},{:.9e},{:.9e},{},{:.9e},{:.6},",
                p.f_dynamic_hz,
                p.w_spec_j_kg.map_or(String::new(), |w| format!("{w:.9e}")),
                p.m_dot_kg_s,
                p.stroke_m,
                p.n_wire,
                e.sim.d_avg_m,
                e.sim.lost_fraction
            ));
        }
        None => row.push_str(&format!(",,,,,,,,{}", l.invalid.as_deref().unwrap_or(if l.violation > 0.0 { "infeasible" } else { "" }))),
    }
    row
}

/// Keep the header and the rows of generations <= `last` (a crash may have logged a
/// generation that the checkpoint does not hold yet).
fn truncate_csv(path: &Path, last: u64) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.lines().enumerate() {
        let keep = i == 0 || line.split(',').next().and_then(|g| g.parse::<u64>().ok()).is_some_and(|g| g <= last);
        if keep {
            out.push_str(line);
            out.push('\n');
        }
    }
    write_atomic(path, out.as_bytes())
}

pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = path.with_extension("tmp");
    {
        let mut f = std::fs::File::create(&tmp).with_context(|| format!("writing {}", tmp.display()))?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
    Ok(())
}

fn append(path: &Path, lines: &str) -> anyhow::Result<()> {
    let mut f = OpenOptions::new().append(true).create(true).open(path).with_context(|| format!("appending to {}", path.display()))?;
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

pub fn run(a: OptimizeArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let dir = &a.out;
    let manifest_path = dir.join("run.toml");
    let checkpoint_path = dir.join("checkpoint.json");
    let eval_path = dir.join("evaluations.csv");
    let gen_path = dir.join("generations.csv");

    let (manifest, mut state) = if a.resume {
        let text = std::fs::read_to_string(&manifest_path).with_context(|| format!("--resume: no run manifest at {}", manifest_path.display()))?;
        let m: Manifest = toml::from_str(&text).with_context(|| format!("--resume: reading {}", manifest_path.display()))?;
        let state = load_checkpoint(&checkpoint_path).with_context(|| format!("--resume: reading {}", checkpoint_path.display()))?;
        truncate_csv(&eval_path, state.generation)?;
        truncate_csv(&gen_path, state.generation)?;
        (m, Some(state))
    } else {
        if checkpoint_path.exists() {
            bail!("{} already holds a run: pass --resume to continue it, or choose another --out", dir.display());
        }
        if a.pop < 4 {
            bail!("--pop must be at least 4, got {}", a.pop);
        }
        let (scenario, _) = a.scenario.resolve()?;
        let mode = match a.algorithm {
            Algorithm::Nsga2 => Mode::Standard,
            Algorithm::MatlabLike => Mode::MatlabLike { pareto_fraction: 0.35, tol: a.tol, stall_generations: a.stall_generations },
        };
        let config = Config { pop: a.pop, seed: scenario.sim.seed, max_generations: a.generations, mode, ..Config::default() };
        let m = Manifest {
            version: env!("CARGO_PKG_VERSION").to_string(),
            engine: a.engine.engine,
            device: String::new(),
            seed: scenario.sim.seed,
            algorithm: a.algorithm,
            config,
            final_particles: a.final_particles,
            replicates: a.replicates,
            scenario,
            termination: None,
        };
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        (m, None)
    };
    let engine = make_engine(manifest.engine)?;
    let mut manifest = Manifest { device: engine.device(), ..manifest };
    if state.is_none() {
        write_atomic(&manifest_path, toml::to_string_pretty(&manifest)?.as_bytes())?;
        write_atomic(&eval_path, format!("{}\n", csv_header_evaluations()).as_bytes())?;
        write_atomic(&gen_path, b"generation,hypervolume,spread,feasible_fraction,front_size,evaluations,elapsed_s\n")?;
    }

    let log_error: std::cell::RefCell<Option<anyhow::Error>> = std::cell::RefCell::new(None);
    let log = |rows: &[Logged]| {
        let text: String = rows.iter().map(|r| evaluation_row(r) + "\n").collect();
        if let Err(e) = append(&eval_path, &text) {
            log_error.borrow_mut().get_or_insert(e);
        }
    };
    let mut problem = SawtoothProblem { scenario: manifest.scenario.clone(), engine: &engine, base_seed: manifest.seed, log: Some(Box::new(log)) };
    let ga = Nsga2 { config: manifest.config.clone() };
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        // A second handler registration (e.g. in tests) is not an error worth failing on.
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    let start = Instant::now();
    let mut state = match state.take() {
        Some(s) => s,
        None => {
            let s = ga.init(&mut problem);
            save_checkpoint(&checkpoint_path, &s)?;
            s
        }
    };
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(manifest.config.max_generations);
        b.set_style(indicatif::ProgressStyle::with_template("{bar:30} gen {pos}/{len} {msg} eta {eta}").expect("valid template"));
        b.set_position(state.generation);
        b
    };
    let termination = loop {
        if let Some(t) = ga.should_stop(&state) {
            break format!("{t:?}");
        }
        let stats = ga.step(&mut state, &mut problem);
        if let Some(e) = log_error.borrow_mut().take() {
            return Err(e);
        }
        let hv = hypervolume_2d(&front_points(&state), HV_REFERENCE);
        append(
            &gen_path,
            &format!(
                "{},{:.9e},{:.6e},{:.4},{},{},{:.3}\n",
                stats.generation,
                hv,
                stats.spread,
                stats.feasible_fraction,
                stats.front_size,
                stats.evaluations,
                start.elapsed().as_secs_f64()
            ),
        )?;
        if state.generation % a.checkpoint_every.max(1) == 0 {
            save_checkpoint(&checkpoint_path, &state)?;
        }
        bar.set_position(state.generation);
        bar.set_message(format!("HV {hv:.4e} feasible {:.0}% front {}", stats.feasible_fraction * 100.0, stats.front_size));
        if a.quiet && state.generation % 10 == 0 {
            eprintln!("generation {} HV {hv:.4e} feasible {:.0}%", state.generation, stats.feasible_fraction * 100.0);
        }
        if interrupted.load(Ordering::SeqCst) {
            save_checkpoint(&checkpoint_path, &state)?;
            bar.abandon();
            eprintln!("interrupted: checkpoint saved at generation {}; continue with --resume", state.generation);
            return Ok(ExitCode::from(130));
        }
    };
    save_checkpoint(&checkpoint_path, &state)?;
    bar.finish_and_clear();
    drop(problem);
    manifest.termination = Some(termination.clone());
    write_atomic(&manifest_path, toml::to_string_pretty(&manifest)?.as_bytes())?;
    let front = super::pareto::final_front(&engine, &manifest, &state)?;
    super::pareto::write_outputs(dir, &front, &eval_path)?;
    super::pareto::print_picks(out, &front, &termination, state.generation)?;
    Ok(ExitCode::SUCCESS)
}

/// For tests and callers: the design vectors of a checkpoint's final front.
pub fn front_designs(state: &State) -> Vec<crate::model::Design> {
    Nsga2::pareto_front(state).iter().map(|i| design_of(&i.x)).collect()
}
