//! `sawtooth optimize`: the thesis's constrained multi-objective optimisation (5.2-5.5); the
//! run itself is `optim::runner`.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::Args;

use super::args::{EngineArgs, RequirementArgs, ScenarioArgs};
use crate::engine::make_engine_for;
use crate::optim::front::print_picks;
use crate::optim::nsga2::{Config, Mode, Selection};
use crate::optim::runner::{read_manifest, run as run_optimisation, Algorithm, Manifest, RunOptions};

/// Largest population, generation count, particle count and replicate count the GA flags
/// accept.
pub const MAX_POP: usize = 100_000;
pub const MAX_GENERATIONS: u64 = 1_000_000;
pub const MAX_PARTICLES: u32 = 10_000_000;
pub const MAX_REPLICATES: u32 = 1000;

/// GA settings shared by every command that optimises.
#[derive(Debug, Clone, Args)]
pub struct GaArgs {
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
    /// Mating selection: `deb` (Deb et al. 2002, the default) or `permutation` (pymoo's
    /// NSGA-II tournaments; ahead of `deb` on the lunar problem, BENCHMARKS.md issue 14).
    #[arg(long, value_enum, default_value = "deb")]
    pub selection: Selection,
    /// No progress bar (logs one line per 10 generations instead).
    #[arg(long)]
    pub quiet: bool,
}

impl GaArgs {
    /// A manifest for a new run of `scenario` with these settings.
    pub fn manifest(
        &self,
        scenario: crate::model::Scenario,
        engine: crate::engine::EngineKind,
    ) -> anyhow::Result<Manifest> {
        if self.pop < 4 {
            bail!("--pop must be at least 4, got {}", self.pop);
        }
        // Sizes beyond these are typos, not runs: a population of a billion needs tens of GB
        // before the first generation, a re-evaluation beyond sim.particles' bound seats no
        // grain and would leave an empty front.
        if self.pop > MAX_POP {
            bail!(
                "--pop must be at most {MAX_POP} (one generation is one engine batch of that many designs), got {}",
                self.pop
            );
        }
        if self.generations > MAX_GENERATIONS {
            bail!("--generations must be at most {MAX_GENERATIONS}, got {}", self.generations);
        }
        if !(self.tol > 0.0 && self.tol.is_finite()) {
            bail!("--tol must be a positive number, got {}", self.tol);
        }
        if self.final_particles == 0 || self.replicates == 0 {
            bail!("--final-particles and --replicates must be at least 1");
        }
        if self.final_particles > MAX_PARTICLES {
            bail!(
                "--final-particles must be at most {MAX_PARTICLES} (the bound of sim.particles), got {}",
                self.final_particles
            );
        }
        if self.replicates > MAX_REPLICATES {
            bail!("--replicates must be at most {MAX_REPLICATES}, got {}", self.replicates);
        }
        let mode = match self.algorithm {
            Algorithm::Nsga2 => Mode::Standard,
            Algorithm::MatlabLike => {
                Mode::MatlabLike { pareto_fraction: 0.35, tol: self.tol, stall_generations: self.stall_generations }
            }
        };
        let config = Config {
            pop: self.pop,
            seed: scenario.sim.seed,
            max_generations: self.generations,
            mode,
            selection: self.selection,
            ..Config::default()
        };
        Ok(Manifest {
            version: env!("CARGO_PKG_VERSION").to_string(),
            engine,
            device: String::new(),
            seed: scenario.sim.seed,
            algorithm: self.algorithm,
            config,
            final_particles: self.final_particles,
            replicates: self.replicates,
            scenario,
            termination: None,
            slopes_deg: Vec::new(),
            requirements: None,
        })
    }

    pub fn options(&self, label: &str) -> RunOptions {
        RunOptions { checkpoint_every: self.checkpoint_every, progress: !self.quiet, label: label.to_string() }
    }
}

#[derive(Debug, Args)]
pub struct OptimizeArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
    #[command(flatten)]
    pub ga: GaArgs,
    /// Requirements as constraints (Deb's rules) and the slopes a design must meet them at.
    #[command(flatten)]
    pub requirements: RequirementArgs,
    /// Output directory (created; owned by this run: run.toml, evaluations.csv,
    /// generations.csv, checkpoint.json, pareto.csv, pareto.svg/.png).
    #[arg(long)]
    pub out: PathBuf,
    /// Continue the run in --out from its checkpoint (settings come from its run.toml).
    #[arg(long)]
    pub resume: bool,
}

pub fn run(a: OptimizeArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let (manifest, kind, scenario) = if a.resume {
        let m = read_manifest(&a.out)?;
        (None, m.engine, m.scenario)
    } else {
        let (scenario, _, slopes_deg) = a.scenario.resolve_over_slopes(a.requirements.alpha_points)?;
        let mut manifest = a.ga.manifest(scenario.clone(), a.engine.engine)?;
        manifest.slopes_deg = slopes_deg;
        manifest.requirements = a.requirements.resolve(&a.scenario)?;
        (Some(manifest), a.engine.engine, scenario)
    };
    let engine = make_engine_for(kind, &scenario)?;
    let outcome = run_optimisation(&a.out, manifest, a.resume, &engine, &a.ga.options(""))?;
    if outcome.interrupted {
        return Ok(ExitCode::from(130));
    }
    print_picks(out, &outcome.front, &outcome.termination, outcome.generations)?;
    Ok(ExitCode::SUCCESS)
}
