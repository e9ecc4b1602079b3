//! `sawtooth optimize`: the thesis's constrained multi-objective optimisation (5.2-5.5); the
//! run itself is `optim::runner`.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::{Args, ValueEnum};

use super::args::{count, EngineArgs, RequirementArgs, ScenarioArgs};
use crate::engine::make_engine_for;
use crate::optim::front::print_picks;
use crate::optim::manifest::{read_manifest, Algorithm, Manifest};
use crate::optim::nsga2::{Config, Mode, Selection};
use crate::optim::runner::{run as run_optimisation, RunOptions};
use crate::schema;

pub use crate::optim::manifest::{MAX_GENERATIONS, MAX_PARTICLES, MAX_POP, MAX_REPLICATES, MIN_POP};

/// GA settings shared by every command that optimises. The run settings are options so that
/// `--resume` can tell a flag the user gave (and refuse one that contradicts the run) from a
/// default; the defaults are the `DEFAULT_*` constants, stated in each flag's help.
#[derive(Debug, Clone, Args)]
pub struct GaArgs {
    /// Population size (thesis: 500, high fidelity 1000) [default: 1000].
    #[arg(long, value_parser = count::<usize>(&schema::POP))]
    pub pop: Option<usize>,
    /// Maximum generations (D.5: MaxGenerations 1000) [default: 1000]. With --resume: a larger
    /// value extends the run.
    #[arg(long, value_parser = count::<u64>(&schema::GENERATIONS))]
    pub generations: Option<u64>,
    /// [default: matlab-like]
    #[arg(long, value_enum)]
    pub algorithm: Option<Algorithm>,
    /// Function tolerance of the spread-stall stop, relative (thesis: 1e-4, high fidelity
    /// 1e-6) [default: 1e-6].
    #[arg(long, allow_negative_numbers = true)]
    pub tol: Option<f64>,
    /// Generations over which the spread change is averaged (MATLAB: MaxStallGenerations 100)
    /// [default: 100].
    #[arg(long, value_parser = count::<u64>(&schema::STALL_GENERATIONS))]
    pub stall_generations: Option<u64>,
    /// Particles per design when re-evaluating the final front [default: 1000].
    #[arg(long, value_parser = count::<u32>(&schema::FINAL_PARTICLES))]
    pub final_particles: Option<u32>,
    /// Independent particle streams for the final re-evaluation (standard errors) [default: 8].
    #[arg(long, value_parser = count::<u32>(&schema::REPLICATES))]
    pub replicates: Option<u32>,
    /// Save a checkpoint every N generations (always on Ctrl-C and at the end).
    #[arg(long, default_value_t = 1, value_parser = count::<u64>(&schema::CHECKPOINT_EVERY))]
    pub checkpoint_every: u64,
    /// Mating selection: `deb` (Deb et al. 2002) or `permutation` (pymoo's NSGA-II
    /// tournaments; ahead of `deb` on the lunar problem, docs/optimise.md) [default: deb].
    #[arg(long, value_enum)]
    pub selection: Option<Selection>,
    /// Print nothing while running (default: a progress bar on a terminal, else a line with
    /// the generation, the front and an ETA every few seconds).
    #[arg(long)]
    pub quiet: bool,
}

pub const DEFAULT_POP: usize = 1000;
pub const DEFAULT_GENERATIONS: u64 = 1000;
pub const DEFAULT_ALGORITHM: Algorithm = Algorithm::MatlabLike;
pub const DEFAULT_TOL: f64 = 1e-6;
pub const DEFAULT_STALL_GENERATIONS: u64 = 100;
pub const DEFAULT_FINAL_PARTICLES: u32 = 1000;
pub const DEFAULT_REPLICATES: u32 = 8;

impl GaArgs {
    /// A manifest for a new run of `scenario` with these settings.
    pub fn manifest(
        &self,
        scenario: crate::model::Scenario,
        engine: crate::engine::EngineKind,
    ) -> anyhow::Result<Manifest> {
        let pop = self.pop.unwrap_or(DEFAULT_POP);
        let generations = self.generations.unwrap_or(DEFAULT_GENERATIONS);
        let tol = self.tol.unwrap_or(DEFAULT_TOL);
        let final_particles = self.final_particles.unwrap_or(DEFAULT_FINAL_PARTICLES);
        let replicates = self.replicates.unwrap_or(DEFAULT_REPLICATES);
        if pop < MIN_POP {
            bail!("--pop must be at least {MIN_POP}, got {pop}");
        }
        // Sizes beyond these are typos, not runs: a population of a billion needs tens of GB
        // before the first generation, a re-evaluation beyond sim.particles' bound seats no
        // grain and would leave an empty front.
        if pop > MAX_POP {
            bail!(
                "--pop must be at most {MAX_POP} (one generation is one engine batch of that many designs), got {pop}"
            );
        }
        if generations > MAX_GENERATIONS {
            bail!("--generations must be at most {MAX_GENERATIONS}, got {generations}");
        }
        crate::schema::OPT_TOL.check("--tol", tol).map_err(anyhow::Error::msg)?;
        if final_particles == 0 || replicates == 0 {
            bail!("--final-particles and --replicates must be at least 1");
        }
        if final_particles > MAX_PARTICLES {
            bail!(
                "--final-particles must be at most {MAX_PARTICLES} (the bound of sim.particles), got {final_particles}"
            );
        }
        if replicates > MAX_REPLICATES {
            bail!("--replicates must be at most {MAX_REPLICATES}, got {replicates}");
        }
        let algorithm = self.algorithm.unwrap_or(DEFAULT_ALGORITHM);
        let mode = match algorithm {
            Algorithm::Nsga2 => Mode::Standard,
            Algorithm::MatlabLike => Mode::MatlabLike {
                pareto_fraction: 0.35,
                tol,
                stall_generations: self.stall_generations.unwrap_or(DEFAULT_STALL_GENERATIONS),
            },
        };
        let config = Config {
            pop,
            seed: scenario.sim.seed,
            max_generations: generations,
            mode,
            selection: self.selection.unwrap_or_default(),
            ..Config::default()
        };
        Ok(Manifest {
            version: env!("CARGO_PKG_VERSION").to_string(),
            engine,
            device: String::new(),
            seed: scenario.sim.seed,
            algorithm,
            config,
            final_particles,
            replicates,
            scenario,
            termination: None,
            slopes_deg: Vec::new(),
            requirements: None,
        })
    }

    /// With `--resume`: refuse a run setting given on the command line that differs from the
    /// stored run's (it would be silently ignored otherwise), and apply a larger
    /// `--generations`, which extends the run.
    pub fn apply_to_resumed(&self, m: &mut Manifest) -> anyhow::Result<()> {
        let stored_tol = match m.config.mode {
            Mode::MatlabLike { tol, .. } => Some(tol),
            Mode::Standard => None,
        };
        let stored_stall = match m.config.mode {
            Mode::MatlabLike { stall_generations, .. } => Some(stall_generations),
            Mode::Standard => None,
        };
        let or_none = |v: Option<String>| v.unwrap_or_else(|| "none (nsga2 has no stall stop)".to_string());
        let differs: [(&str, Option<String>, String); 7] = [
            ("--pop", self.pop.filter(|&p| p != m.config.pop).map(|p| p.to_string()), m.config.pop.to_string()),
            ("--algorithm", self.algorithm.filter(|&a| a != m.algorithm).map(cli_name), cli_name(m.algorithm)),
            (
                "--tol",
                self.tol.filter(|&t| Some(t) != stored_tol).map(|t| t.to_string()),
                or_none(stored_tol.map(|t| t.to_string())),
            ),
            (
                "--stall-generations",
                self.stall_generations.filter(|&g| Some(g) != stored_stall).map(|g| g.to_string()),
                or_none(stored_stall.map(|g| g.to_string())),
            ),
            (
                "--final-particles",
                self.final_particles.filter(|&n| n != m.final_particles).map(|n| n.to_string()),
                m.final_particles.to_string(),
            ),
            (
                "--replicates",
                self.replicates.filter(|&n| n != m.replicates).map(|n| n.to_string()),
                m.replicates.to_string(),
            ),
            (
                "--selection",
                self.selection.filter(|&s| s != m.config.selection).map(cli_name),
                cli_name(m.config.selection),
            ),
        ];
        for (flag, given, stored) in differs {
            if let Some(given) = given {
                bail!(
                    "--resume continues the run with its own settings: {flag} {given} differs from the run's {stored} (run.toml); drop the flag, or start a new run in another --out"
                );
            }
        }
        if let Some(g) = self.generations.filter(|&g| g != m.config.max_generations) {
            if g < m.config.max_generations {
                bail!(
                    "--resume --generations {g}: a run can only be extended, and this one was started with --generations {}",
                    m.config.max_generations
                );
            }
            if g > MAX_GENERATIONS {
                bail!("--generations must be at most {MAX_GENERATIONS}, got {g}");
            }
            if m.termination.as_deref() == Some("SpreadStalled") {
                bail!(
                    "--resume --generations {g}: the run stopped because the front's spread stalled (--tol), not at its generation limit; more generations would stop it again at once (start a new run with a smaller --tol)"
                );
            }
            m.config.max_generations = g;
            m.termination = None;
        }
        Ok(())
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

/// A value as the command line spells it (`matlab-like`, `permutation`).
fn cli_name(v: impl ValueEnum) -> String {
    v.to_possible_value().map_or_else(String::new, |p| p.get_name().to_string())
}

/// With `--resume`, scenario and requirement flags may repeat the run's own command (the
/// docs/optimise.md's `… --resume`), but must not describe another run: they would be ignored.
fn refuse_other_scenario(a: &OptimizeArgs, m: &Manifest) -> anyhow::Result<()> {
    let given: Vec<&str> = a.scenario.given_flags().into_iter().chain(a.requirements.given_flags()).collect();
    if given.is_empty() {
        return Ok(());
    }
    // flags that adjust a scenario (`--teeth 50`) are laid over the run's own, so that the
    // difference named is theirs (not every preset value the run had changed, such as `g`)
    let mut flags = a.scenario.clone();
    if flags.config.is_none() && flags.env.is_none() && flags.compat.is_none() {
        flags.config = Some(a.out.join("run.toml"));
    }
    let (scenario, _, slopes) = flags.resolve_over_slopes(a.requirements.alpha_points)?;
    let requirements = match (&a.requirements.requirements, &a.scenario.config) {
        (None, None) => m.requirements.clone(),
        _ => a.requirements.resolve(&a.scenario)?,
    };
    let mut diffs = Vec::new();
    differing_keys("scenario", &serde_json::to_value(&scenario)?, &serde_json::to_value(&m.scenario)?, &mut diffs);
    if slopes != m.slopes_deg {
        diffs.push(format!("slopes_deg ({slopes:?} vs the run's {:?})", m.slopes_deg));
    }
    differing_keys(
        "requirements",
        &serde_json::to_value(&requirements)?,
        &serde_json::to_value(&m.requirements)?,
        &mut diffs,
    );
    if !diffs.is_empty() {
        diffs.truncate(6);
        bail!(
            "--resume continues the run in {} with its own settings, but {} describe another run (differing: {}); give the run's own flags or none, or start a new run in another --out",
            a.out.display(),
            given.join(", "),
            diffs.join(", ")
        );
    }
    Ok(())
}

/// The dotted keys under `path` where `given` and `stored` differ, with both values.
fn differing_keys(path: &str, given: &serde_json::Value, stored: &serde_json::Value, out: &mut Vec<String>) {
    use serde_json::Value;
    match (given, stored) {
        (Value::Object(g), Value::Object(s)) => {
            for key in g.keys().chain(s.keys().filter(|k| !g.contains_key(*k))) {
                let (gv, sv) = (g.get(key).unwrap_or(&Value::Null), s.get(key).unwrap_or(&Value::Null));
                differing_keys(&format!("{path}.{key}"), gv, sv, out);
            }
        }
        _ if given != stored => out.push(format!("{path} = {given} vs the run's {stored}")),
        _ => {}
    }
}

pub fn run(a: OptimizeArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let (manifest, kind, scenario) = if a.resume {
        if !a.out.join("run.toml").exists() && crate::io::run_dir::kind_of(&a.out).is_some() {
            bail!(
                "--resume: {} holds no run.toml: the run was stopped before it wrote its settings; start it again without --resume",
                a.out.display()
            );
        }
        let mut m = read_manifest(&a.out)?;
        refuse_other_scenario(&a, &m)?;
        if let Some(k) = a.engine.engine.filter(|&k| k != m.engine) {
            bail!(
                "--resume continues the run with its own engine: --engine {} differs from the run's {} (run.toml); drop the flag, or start a new run in another --out",
                cli_name(k),
                cli_name(m.engine)
            );
        }
        a.ga.apply_to_resumed(&mut m)?;
        let (kind, scenario) = (m.engine, m.scenario.clone());
        (Some(m), kind, scenario)
    } else {
        if crate::optim::runner::holds_run(&a.out) {
            bail!(
                "--out {} already holds a run: pass --resume to continue it, or choose another --out",
                a.out.display()
            );
        }
        let (scenario, _, slopes_deg) = a.scenario.resolve_over_slopes(a.requirements.alpha_points)?;
        let mut manifest = a.ga.manifest(scenario.clone(), a.engine.kind())?;
        manifest.slopes_deg = slopes_deg;
        manifest.requirements = a.requirements.resolve(&a.scenario)?;
        (Some(manifest), a.engine.kind(), scenario)
    };
    let engine = make_engine_for(kind, &scenario).context("--engine")?;
    let outcome = run_optimisation(&a.out, manifest, a.resume, &engine, &a.ga.options(""))?;
    if outcome.interrupted {
        eprintln!("continue with the same command and --resume");
        return Ok(ExitCode::from(130));
    }
    print_picks(out, &outcome.front, &outcome.termination, outcome.generations)?;
    Ok(ExitCode::SUCCESS)
}
