//! Arguments shared by every command that evaluates designs.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use crate::calibrate::EffortSettings;
use crate::engine::EngineKind;
use crate::io::config::{load_requirements, ConfigFile};
use crate::model::requirements::Requirements;
use crate::model::scenario::EnvPreset;
use crate::model::{Design, Scenario};
use crate::schema;

pub use crate::scenario_request::{
    in_user_terms, set_effects, Compat, ScenarioRequest, MAX_ALPHA_POINTS, THESIS_MAX_SLOPE_DEG,
};

/// `[default: …]` of a scenario flag, read from the presets themselves so that the help
/// cannot drift from them: one value, or the lunar and Earth presets' values.
fn preset_default(text: &str, value: impl Fn(&Scenario) -> String) -> String {
    let (lunar, earth) = (value(&Scenario::lunar()), value(&Scenario::earth()));
    let default = if lunar == earth { lunar } else { format!("{lunar} with --env lunar, {earth} with --env earth") };
    format!("{text} [default: the --config file's, else {default}]")
}

pub fn effect_help() -> String {
    format!(
        "Switch on an effect beyond the thesis's model, repeatable (cpu and gpu engines unless said; \
         a config file takes them as [effects.impact_scatter] sigma_deg = …, and so on):\n{}",
        crate::model::effects::effects_help()
    )
}

// Help texts are built from the presets (`preset_default`) and the effects' registry
// (`effect_help`), so each flag's `help` is an expression, not a doc comment.
#[derive(Debug, Clone, Args)]
pub struct ScenarioArgs {
    /// TOML file with `env`, `mode`, [design], [environment], [material], [collision], [sim],
    /// [performance], [effects], [requirements], or a run folder's run.toml (its scenario and
    /// requirements); flags override it.
    #[arg(long)]
    pub config: Option<PathBuf>,
    #[arg(long, value_enum, help = "Environment preset (listing D.5) [default: the --config file's, else lunar]")]
    pub env: Option<EnvPreset>,
    #[arg(long, value_parser = parse_alpha, allow_negative_numbers = true, help = preset_default(
        "Conveyor angle α, degrees; `gpu-sweep`, `simulate` and `optimize` take a range `FROM..TO` (the latter two with --alpha-points)",
        |s| format!("{} deg", s.environment.alpha_deg)))]
    pub alpha: Option<(f64, f64)>,
    #[arg(long, allow_negative_numbers = true, help = preset_default("Elastic normal coefficient of restitution (-)", |s| s.collision.k_elastic.to_string()))]
    pub k_elastic: Option<f64>,
    #[arg(long, allow_negative_numbers = true, help = preset_default("Friction coefficient of the tangential COR (-, Eq. 4.14)", |s| s.collision.mu_friction.to_string()))]
    pub mu_fric: Option<f64>,
    #[arg(long, allow_negative_numbers = true, help = preset_default("Stokes drag parameter k_drag, 1/s (0 = vacuum)", |s| match s.environment.k_drag {
        Some(k) => format!("{k} 1/s"),
        None => "0 (vacuum)".to_string(),
    }))]
    pub k_drag: Option<f64>,
    #[arg(long, allow_negative_numbers = true, help = preset_default("Angle of repose, degrees", |s| format!("{} deg", s.material.aor_deg)))]
    pub aor: Option<f64>,
    #[arg(long, help = preset_default("Material preset: lunar-regolith, quartz-sand, glass-beads", |s| s.material.name.clone()))]
    pub material: Option<String>,
    #[arg(long, help = preset_default("Particles per design", |s| s.sim.particles.to_string()))]
    pub particles: Option<u32>,
    #[arg(long, help = preset_default("Simulated teeth", |s| s.sim.teeth.to_string()))]
    pub teeth: Option<u32>,
    #[arg(long, help = preset_default("Maximum bounce iterations", |s| s.sim.max_bounces.to_string()))]
    pub bounces: Option<u32>,
    #[arg(long, help = preset_default("Seed of the counter-based random numbers", |s| s.sim.seed.to_string()))]
    pub seed: Option<u64>,
    #[arg(long, allow_negative_numbers = true, help = preset_default("Launch-angle offset added to α + δ, degrees (listing: 18.434)",
        |s| format!("{} deg", s.sim.launch_offset_deg)))]
    pub launch_offset: Option<f64>,
    /// Switch off the launch randomisation (±10 % on the launch angle and speed, Eq. 4.38).
    #[arg(long)]
    pub no_randomise: bool,
    /// Compatibility mode [default: physical, the thesis's text with its errata repaired].
    #[arg(long, value_enum)]
    pub compat: Option<Compat>,
    #[arg(long = "effect", value_name = "NAME=PARAMS", help = effect_help())]
    pub effects: Vec<String>,
}

impl ScenarioArgs {
    /// The flags given on the command line (for refusing them where they cannot apply).
    pub fn given_flags(&self) -> Vec<&'static str> {
        let f = |given: bool, name: &'static str| given.then_some(name);
        [
            f(self.config.is_some(), "--config"),
            f(self.env.is_some(), "--env"),
            f(self.alpha.is_some(), "--alpha"),
            f(self.k_elastic.is_some(), "--k-elastic"),
            f(self.mu_fric.is_some(), "--mu-fric"),
            f(self.k_drag.is_some(), "--k-drag"),
            f(self.aor.is_some(), "--aor"),
            f(self.material.is_some(), "--material"),
            f(self.particles.is_some(), "--particles"),
            f(self.teeth.is_some(), "--teeth"),
            f(self.bounces.is_some(), "--bounces"),
            f(self.seed.is_some(), "--seed"),
            f(self.launch_offset.is_some(), "--launch-offset"),
            f(self.no_randomise, "--no-randomise"),
            f(self.compat.is_some(), "--compat"),
            f(!self.effects.is_empty(), "--effect"),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// The request these flags make of the library's scenario resolution.
    pub fn request(&self) -> ScenarioRequest {
        ScenarioRequest {
            config: self.config.clone(),
            env: self.env,
            alpha: self.alpha,
            k_elastic: self.k_elastic,
            mu_fric: self.mu_fric,
            k_drag: self.k_drag,
            aor: self.aor,
            material: self.material.clone(),
            particles: self.particles,
            teeth: self.teeth,
            bounces: self.bounces,
            seed: self.seed,
            launch_offset: self.launch_offset,
            no_randomise: self.no_randomise,
            compat: self.compat,
            effects: self.effects.clone(),
        }
    }

    /// Config file (if any), then flags; validated ([`ScenarioRequest::resolve`]).
    pub fn resolve(&self) -> anyhow::Result<(Scenario, Option<Design>)> {
        self.request().resolve()
    }

    /// [`ScenarioRequest::resolve_over_slopes`] of these flags.
    pub fn resolve_over_slopes(&self, points: Option<u32>) -> anyhow::Result<(Scenario, Option<Design>, Vec<f64>)> {
        self.request().resolve_over_slopes(points)
    }
}

#[derive(Debug, Clone, Args)]
pub struct EngineArgs {
    /// Evaluation engine [default: cpu].
    #[arg(long, value_enum)]
    pub engine: Option<EngineKind>,
}

impl EngineArgs {
    /// The engine asked for, else the default (cpu). `engine` itself says whether the flag
    /// was given, so that `--resume --engine gpu` on a cpu run is refused, not ignored.
    pub fn kind(&self) -> EngineKind {
        self.engine.unwrap_or(EngineKind::Cpu)
    }
}

/// Designing to requirements (issue 13): what a design must meet.
#[derive(Debug, Clone, Args)]
pub struct RequirementArgs {
    /// Judge designs against requirements: `table-2.2` (the thesis's Table 2.2: feed rate at
    /// least 6 kg/h with a 48 kg/h target, power at most 5 W, slopes 0-40 deg, wire within the
    /// 1.3054 m sled) or a TOML file with a [requirements] table. Default: the --config
    /// file's [requirements] table, if it has one.
    #[arg(long, value_name = "table-2.2|FILE")]
    pub requirements: Option<String>,
    /// With --alpha FROM..TO: evaluate every design at this many evenly spaced slopes
    /// (default 5) and judge its worst slope.
    #[arg(long)]
    pub alpha_points: Option<u32>,
}

impl RequirementArgs {
    /// The flags given on the command line.
    pub fn given_flags(&self) -> Vec<&'static str> {
        [
            self.requirements.is_some().then_some("--requirements"),
            self.alpha_points.is_some().then_some("--alpha-points"),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    pub fn resolve(&self, scenario: &ScenarioArgs) -> anyhow::Result<Option<Requirements>> {
        if let Some(spec) = &self.requirements {
            return load_requirements(spec).map(Some).context("--requirements");
        }
        let Some(path) = &scenario.config else { return Ok(None) };
        if let Some(run) = crate::optim::manifest::manifest_in(path)? {
            return Ok(run.requirements);
        }
        match ConfigFile::load(path)?.requirements {
            Some(t) => t.requirements(&path.display().to_string()).map(Some),
            None => Ok(None),
        }
    }
}

/// A clap value parser for a count declared in [`crate::schema`]: the flag's rule is the
/// schema's, so the flag cannot drift from the file keys that share it. Refused before
/// anything is read or allocated: clap names the flag, the rule follows.
pub fn count<T>(c: &'static crate::schema::Count) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: TryFrom<u64> + Clone + Send + Sync + 'static,
{
    move |text: &str| {
        let v: u64 = text.trim().parse().map_err(|_| format!("`{text}` is not a whole number; it {}", c.rule()))?;
        c.check("it", v)?;
        T::try_from(v).map_err(|_| format!("it {}, got {v}", c.rule()))
    }
}

/// `35` or `1..40` (degrees, inclusive range).
pub fn parse_alpha(v: &str) -> Result<(f64, f64), String> {
    let num = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("`{t}` is not a number of degrees"));
    let (a, b) = match v.split_once("..") {
        Some((a, b)) => (num(a)?, num(b)?),
        None => {
            let a = num(v)?;
            (a, a)
        }
    };
    if !(a.is_finite() && b.is_finite()) || a > b {
        return Err(format!("`{v}`: expected DEG or FROM..TO with FROM <= TO"));
    }
    Ok((a, b))
}

/// How hard `fit` and `diagnose` work: the calibration engine's flags, one definition for
/// both commands ([`crate::calibrate::Effort`]).
#[derive(Debug, Clone, Args)]
pub struct EffortArgs {
    /// Particles per simulation at the full budget (the same streams for every candidate);
    /// default: what the data call for (Monte-Carlo variance per tooth at most a quarter of
    /// the measured mean's), up to --max-particles.
    #[arg(long, value_parser = count::<u32>(&schema::FIT_PARTICLES))]
    pub particles: Option<u32>,
    /// The most particles per simulation the data may call for.
    #[arg(long, default_value_t = EffortSettings::DEFAULT_MAX_PARTICLES, value_parser = count::<u32>(&schema::FIT_MAX_PARTICLES))]
    pub max_particles: u32,
    /// Differential-evolution population per model (>= 5), screening at 1/8 of the particles.
    #[arg(long, default_value_t = EffortSettings::DEFAULT_POP, value_parser = count::<usize>(&schema::FIT_POP))]
    pub pop: usize,
    /// Differential-evolution generations per model [default: 20 for `fit`, 10 for
    /// `diagnose`, whose candidates start from the baseline's optimum].
    #[arg(long, value_parser = count::<usize>(&schema::FIT_GENERATIONS))]
    pub generations: Option<usize>,
    /// Compass-search iterations polishing each fit (and each bootstrap refit of `fit`) at
    /// the full budget.
    #[arg(long, default_value_t = EffortSettings::DEFAULT_POLISH, value_parser = count::<usize>(&schema::FIT_POLISH))]
    pub polish: usize,
}

impl EffortArgs {
    /// The library's effort settings (checked by the library, naming these flags), over the
    /// command's `defaults` where a flag is not given.
    pub fn settings(&self, defaults: EffortSettings) -> EffortSettings {
        EffortSettings {
            particles: self.particles,
            max_particles: self.max_particles,
            pop: self.pop,
            generations: self.generations.unwrap_or(defaults.generations),
            polish: self.polish,
        }
    }
}
