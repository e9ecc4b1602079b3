//! Batch evaluators behind one interface.
//!
//! An evaluator takes a scenario and a batch of designs (one GA generation) and returns one
//! result per design. The particle engines (`listing`, `cpu`) differ only in how they follow
//! particles; preparation (validity, profile, fill, launch points), aggregation and the
//! performance model are shared, so both engines see the same problem.

pub mod conformance;
pub mod cpu;
pub mod gpu;
pub mod kernel;
pub mod lanes;
pub mod listing;
pub mod slopes;
pub mod summary;

use rayon::prelude::*;
use serde::Serialize;

use crate::model::collision::Restitution;
use crate::model::outcome::{summarise, ParticleEnd};
use crate::model::performance::{performance, Performance};
use crate::model::rng::seed_word;
use crate::model::{prepare, Design, Invalid, PhysicsMode, Prepared, Scenario, SimOutcome};

/// Scenario-wide constants every particle engine needs, derived once per batch.
#[derive(Clone, Debug, PartialEq)]
pub struct Context {
    pub mode: PhysicsMode,
    pub g: f64,
    /// 0 = vacuum.
    pub k_drag: f64,
    pub restitution: Restitution<f64>,
    pub randomise: u32,
    pub band: f64,
    pub seed: u64,
    pub seed_word: u32,
    pub rest_threshold: f64,
    pub max_bounces: u32,
    pub effects: crate::model::effects::Effects,
}

impl Context {
    pub fn new(s: &Scenario) -> Self {
        let randomise = match (s.sim.randomise, s.mode) {
            (false, _) => kernel::RANDOMISE_OFF,
            (true, PhysicsMode::Listing) => kernel::RANDOMISE_FIRST_LAUNCH,
            (true, PhysicsMode::Physical) => kernel::RANDOMISE_EVERY_LAUNCH,
        };
        Context {
            mode: s.mode,
            g: s.environment.g,
            k_drag: s.environment.k_drag.unwrap_or(0.0),
            restitution: Restitution::new(s.mode, &s.collision, &s.material),
            randomise,
            band: s.sim.random_band,
            seed: s.sim.seed,
            seed_word: seed_word(s.sim.seed),
            rest_threshold: s.sim.rest_threshold,
            max_bounces: s.sim.max_bounces,
            effects: s.effects,
        }
    }
}

/// One flight of one particle, for trajectory files and plots (global coordinates).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FlightRecord {
    pub particle: u32,
    /// 0 = the launch from the fill.
    pub bounce: u32,
    pub from: [f64; 2],
    pub vel: [f64; 2],
    /// Flight time to the impact, s; 0 when nothing was hit.
    pub t: f64,
    /// State after this flight.
    pub state: crate::model::ParticleState,
}

/// What a particle engine returns for one design.
#[derive(Clone, Debug)]
pub struct Run {
    pub particles: Vec<ParticleEnd>,
    pub iterations: u32,
}

/// A particle engine: follows one prepared design's particles.
pub trait ParticleEngine: Sync {
    fn name(&self) -> &'static str;
    fn run(&self, prep: &Prepared, ctx: &Context, trace: Option<&mut Vec<FlightRecord>>) -> Run;
}

/// One evaluated design.
#[derive(Clone, Debug, Serialize)]
pub struct Evaluation {
    pub sim: SimOutcome,
    pub performance: Performance,
}

/// One evaluated design with its per-particle end states.
#[derive(Clone, Debug)]
pub struct Detailed {
    pub prepared: Prepared,
    pub evaluation: Evaluation,
    pub particles: Vec<ParticleEnd>,
    pub flights: Vec<FlightRecord>,
}

/// The host CPU's model name (Linux: /proc/cpuinfo's first `model name`; "unknown model"
/// elsewhere), so that a timing or a run manifest names the machine it came from.
pub fn host_cpu() -> &'static str {
    static NAME: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    NAME.get_or_init(|| {
        std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|t| {
                let line = t.lines().find(|l| l.starts_with("model name"))?;
                Some(line.split_once(':')?.1.trim().to_string())
            })
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| "unknown model".to_string())
    })
}

/// The interface every evaluator implements, GPU included: a whole generation per call.
pub trait BatchEvaluator: Sync {
    /// The backend's name, as `--engine` spells it.
    fn backend(&self) -> &'static str;
    /// What runs it, for run manifests (the GPU's name and driver for `gpu`).
    fn device(&self) -> String {
        format!("{} engine on the host CPU ({}; {} threads)", self.backend(), host_cpu(), rayon::current_num_threads())
    }
    fn evaluate(&self, scenario: &Scenario, designs: &[Design]) -> Vec<Result<Evaluation, Invalid>>;
    /// Whether a first evaluation also compiles kernels (the gpu engine builds a pipeline per
    /// kernel variant on first use), so that a timing runs the batch once untimed first.
    fn compiles_on_first_use(&self) -> bool {
        false
    }
    /// Several (scenario, designs) groups, e.g. the populations of several conveyor angles.
    /// The GPU runs them as one job when their batch-wide physics is the same (per-design
    /// physics such as restitution, drag and effect parameters may differ; `GpuEngine::run_jobs`).
    fn evaluate_groups(&self, groups: &[(Scenario, Vec<Design>)]) -> Vec<Vec<Result<Evaluation, Invalid>>> {
        groups.iter().map(|(s, d)| self.evaluate(s, d)).collect()
    }
}

/// Designs in parallel (rayon); each design's particles on one thread.
pub fn evaluate_batch(
    engine: &dyn ParticleEngine,
    scenario: &Scenario,
    designs: &[Design],
) -> Vec<Result<Evaluation, Invalid>> {
    let ctx = Context::new(scenario);
    designs
        .par_iter()
        .map(|d| {
            let prep = prepare(scenario, d)?;
            let run = engine.run(&prep, &ctx, None);
            Ok(finish(scenario, &prep, &run))
        })
        .collect()
}

/// Several groups as one parallel job: every (group, design) pair is a task, so groups of one
/// design each (a calibration: candidates × conditions) keep every core busy.
pub fn evaluate_groups_flat(
    engine: &dyn ParticleEngine,
    groups: &[(Scenario, Vec<Design>)],
) -> Vec<Vec<Result<Evaluation, Invalid>>> {
    let contexts: Vec<Context> = groups.iter().map(|(s, _)| Context::new(s)).collect();
    let tasks: Vec<(usize, &Design)> =
        groups.iter().enumerate().flat_map(|(g, (_, ds))| ds.iter().map(move |d| (g, d))).collect();
    let mut flat: Vec<Result<Evaluation, Invalid>> = tasks
        .par_iter()
        .with_max_len(1)
        .map(|(g, d)| {
            let scenario = &groups[*g].0;
            let prep = prepare(scenario, d)?;
            let run = engine.run(&prep, &contexts[*g], None);
            Ok(finish(scenario, &prep, &run))
        })
        .collect();
    let mut out = Vec::with_capacity(groups.len());
    for (_, ds) in groups.iter().rev() {
        out.push(flat.split_off(flat.len() - ds.len()));
    }
    out.reverse();
    out
}

impl BatchEvaluator for cpu::CpuEngine {
    fn backend(&self) -> &'static str {
        ParticleEngine::name(self)
    }
    fn device(&self) -> String {
        format!(
            "{} engine on the host CPU ({}; {} threads, {})",
            self.backend(),
            host_cpu(),
            rayon::current_num_threads(),
            crate::simd::selected().describe()
        )
    }
    fn evaluate(&self, scenario: &Scenario, designs: &[Design]) -> Vec<Result<Evaluation, Invalid>> {
        evaluate_batch(self, scenario, designs)
    }
    fn evaluate_groups(&self, groups: &[(Scenario, Vec<Design>)]) -> Vec<Vec<Result<Evaluation, Invalid>>> {
        evaluate_groups_flat(self, groups)
    }
}

impl BatchEvaluator for listing::ListingEngine {
    fn backend(&self) -> &'static str {
        ParticleEngine::name(self)
    }
    fn evaluate(&self, scenario: &Scenario, designs: &[Design]) -> Vec<Result<Evaluation, Invalid>> {
        evaluate_batch(self, scenario, designs)
    }
}

/// An engine usable both for whole generations and for one design with its particles.
pub trait Engine: ParticleEngine + BatchEvaluator + Send {}
impl<T: ParticleEngine + BatchEvaluator + Send> Engine for T {}

/// Attach the performance model to a simulated design.
pub fn finish_outcome(scenario: &Scenario, prep: &Prepared, sim: SimOutcome) -> Evaluation {
    let performance = performance(scenario, &prep.design, sim.d_avg_m, prep.fill.area);
    Evaluation { sim, performance }
}

fn finish(scenario: &Scenario, prep: &Prepared, run: &Run) -> Evaluation {
    finish_outcome(scenario, prep, summarise(&prep.profile, prep.fill.area, &run.particles, run.iterations))
}

/// Evaluate one design and keep every particle (and optionally every flight).
pub fn evaluate_detailed(
    engine: &dyn ParticleEngine,
    scenario: &Scenario,
    design: &Design,
    trace: bool,
) -> Result<Detailed, Invalid> {
    let ctx = Context::new(scenario);
    let prepared = prepare(scenario, design)?;
    let mut flights = Vec::new();
    let run = engine.run(&prepared, &ctx, if trace { Some(&mut flights) } else { None });
    let evaluation = finish(scenario, &prepared, &run);
    Ok(Detailed { prepared, evaluation, particles: run.particles, flights })
}

/// [`evaluate_detailed`] with the caller's launch points instead of the fill polygon's (the
/// DEM's settled bed, `dem compare`): particle i starts at `launches[i % len]`.
pub fn evaluate_detailed_from(
    engine: &dyn ParticleEngine,
    scenario: &Scenario,
    design: &Design,
    launches: &[[f64; 2]],
) -> Result<Detailed, Invalid> {
    assert!(!launches.is_empty(), "launch points to start from");
    let ctx = Context::new(scenario);
    let mut prepared = prepare(scenario, design)?;
    prepared.launches = (0..prepared.launches.len()).map(|i| launches[i % launches.len()]).collect();
    let run = engine.run(&prepared, &ctx, None);
    let evaluation = finish(scenario, &prepared, &run);
    Ok(Detailed { prepared, evaluation, particles: run.particles, flights: Vec::new() })
}

/// Engines selectable by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EngineKind {
    /// Port of the listing's algorithm (segment scan + bisection): baseline.
    Listing,
    /// Fast reference: closed-form flights, reachable teeth only, f64.
    Cpu,
    /// WGSL kernels on wgpu (Vulkan); a software adapter (lavapipe) is accepted.
    Gpu,
    /// A hardware GPU when one exists, else `cpu`; says which on stderr.
    Auto,
}

/// The CPU engines, which cannot fail to start. Use `make_engine` for `gpu` and `auto`.
pub fn particle_engine(kind: EngineKind) -> Box<dyn Engine> {
    match kind {
        EngineKind::Listing => Box::new(listing::ListingEngine),
        EngineKind::Cpu => Box::new(cpu::CpuEngine::default()),
        EngineKind::Gpu | EngineKind::Auto => {
            panic!("particle_engine covers the CPU engines; use make_engine for {kind:?}")
        }
    }
}

/// Effects only the `cpu` kernel follows: its piecewise flights (sled motion, quadratic drag)
/// and the uniform size law.
pub fn cpu_only_effects(e: &crate::model::effects::Effects) -> Vec<&'static str> {
    use crate::model::effects::{EffectKind, SizeForm, TiltForm};
    let mut v: Vec<&'static str> = [EffectKind::SledMotion, EffectKind::QuadraticDrag]
        .into_iter()
        .filter(|k| e.is_on(*k))
        .map(EffectKind::name)
        .collect();
    if e.polydisperse.is_some_and(|p| p.form == SizeForm::Uniform) {
        v.push("polydisperse (uniform sizes)");
    }
    if e.impact_scatter.is_some_and(|p| p.form == TiltForm::Uniform) {
        v.push("impact-scatter (uniform tilt)");
    }
    v
}

/// "X is in the cpu engine only" or "X, Y are in the cpu engine only": what the messages about
/// [`cpu_only_effects`] say, in one place.
pub fn in_cpu_engine_only(cpu_only: &[&str]) -> String {
    let verb = if cpu_only.len() == 1 { "is" } else { "are" };
    format!("{} {verb} in the cpu engine only", cpu_only.join(", "))
}

/// The engine for a scenario: the effects of issue 5 live in the `cpu` and `gpu` kernels;
/// the `listing` port (the thesis's algorithm) refuses a scenario that switches one on.
pub fn make_engine_for(kind: EngineKind, scenario: &Scenario) -> anyhow::Result<Box<dyn Engine>> {
    if scenario.effects.any() && kind == EngineKind::Listing {
        let active = scenario.effects.active().join(", ");
        anyhow::bail!("the listing engine does not model the effects ({active}): they are in the cpu and gpu engines only; use the cpu engine");
    }
    let cpu_only = cpu_only_effects(&scenario.effects);
    if !cpu_only.is_empty() {
        let only = in_cpu_engine_only(&cpu_only);
        match kind {
            EngineKind::Gpu => anyhow::bail!("{only}, not in the gpu engine; use the cpu engine"),
            EngineKind::Auto => {
                eprintln!("engine auto: {only}, using it");
                return Ok(particle_engine(EngineKind::Cpu));
            }
            _ => {}
        }
    }
    make_engine(kind)
}

/// Any engine by name. `gpu` without an adapter is an error; `auto` falls back to `cpu`.
pub fn make_engine(kind: EngineKind) -> anyhow::Result<Box<dyn Engine>> {
    // a SAWTOOTH_SIMD path this CPU lacks (or a retired setting) is refused before any work
    crate::simd::check().map_err(anyhow::Error::msg)?;
    if kind == EngineKind::Auto {
        // a malformed setting is the user's error, not a missing GPU to fall back from
        gpu::slice_designs_from_env()?;
    }
    Ok(match kind {
        EngineKind::Listing | EngineKind::Cpu => particle_engine(kind),
        EngineKind::Gpu => {
            let g = gpu::GpuEngine::new(gpu::AdapterChoice::Any)?;
            eprintln!("engine: gpu on {}", g.describe());
            Box::new(g)
        }
        EngineKind::Auto => match gpu::GpuEngine::new(gpu::AdapterChoice::HardwareOnly) {
            Ok(g) => {
                eprintln!("engine auto: gpu on {}", g.describe());
                Box::new(g)
            }
            Err(_) => {
                eprintln!("engine auto: no hardware GPU, using the cpu engine");
                particle_engine(EngineKind::Cpu)
            }
        },
    })
}

impl ParticleEngine for Box<dyn Engine> {
    fn name(&self) -> &'static str {
        self.as_ref().name()
    }
    fn run(&self, prep: &Prepared, ctx: &Context, trace: Option<&mut Vec<FlightRecord>>) -> Run {
        self.as_ref().run(prep, ctx, trace)
    }
}

impl BatchEvaluator for Box<dyn Engine> {
    fn backend(&self) -> &'static str {
        self.as_ref().backend()
    }
    fn device(&self) -> String {
        self.as_ref().device()
    }
    fn compiles_on_first_use(&self) -> bool {
        self.as_ref().compiles_on_first_use()
    }
    fn evaluate(&self, scenario: &Scenario, designs: &[Design]) -> Vec<Result<Evaluation, Invalid>> {
        self.as_ref().evaluate(scenario, designs)
    }
    fn evaluate_groups(&self, groups: &[(Scenario, Vec<Design>)]) -> Vec<Vec<Result<Evaluation, Invalid>>> {
        self.as_ref().evaluate_groups(groups)
    }
}
