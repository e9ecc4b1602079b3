//! One `diagnose` as the user asks for it: measured conditions (data and setup in pairs),
//! the candidate effects and typed settings, checked, run and written as a whole. The CLI
//! (`sawtooth diagnose`) and the Python package (`sawtooth.diagnose`) both build a
//! [`DiagnoseRequest`] and call [`run`], so the checks, the numbers, report.md and
//! diagnosis.json are the same from either.

use std::path::PathBuf;

use crate::calibrate::corrected::{corrected_config, CORRECTED};

use anyhow::{bail, Context as _};
use serde_json::Value;

use super::diagnose::{applicable_effects, diagnose, Condition, Diagnosis, EffectKind, Settings, NO_EFFECT_APPLIES};
use super::json::to_json;
use super::render;
use crate::calibrate::measured::{self, condition_names};
use crate::calibrate::{EffortSettings, Normalise, Param, Spelling};
use crate::engine::{make_engine, EngineKind};
use crate::io::run_dir::{Access, RunDir};

/// The most bootstrap replicates and fresh particle streams a diagnosis takes (declared in
/// crate::schema, with the CLI's parsers).
pub const BOOTSTRAP_MAX: usize = crate::schema::DIAGNOSE_BOOTSTRAP.max as usize;
pub const STREAMS_MAX: usize = crate::schema::RESCORE_STREAMS.max as usize;

/// What a diagnosis needs; [`DiagnoseRequest::new`] gives the CLI's defaults.
#[derive(Clone, Debug)]
pub struct DiagnoseRequest {
    /// Measured runs (CSV), one per condition; the i-th goes with the i-th setup.
    pub data: Vec<PathBuf>,
    /// The rig's setup of each condition (config TOML with [design], optional [measurement]).
    pub setup: Vec<PathBuf>,
    /// The candidate effects.
    pub effects: Vec<EffectKind>,
    /// None: the first setup's sim.seed.
    pub seed: Option<u64>,
    pub engine: EngineKind,
    pub effort: EffortSettings,
    /// None: fractions of the loaded mass where every run records it, else of the recovered.
    pub normalise: Option<Normalise>,
    /// Fresh particle streams every fitted model is re-scored with.
    pub rescore_streams: usize,
    /// Bootstrap replicates for the intervals.
    pub bootstrap: usize,
    /// Each candidate's detection limit for this campaign.
    pub detection_limits: bool,
    /// Which additional condition would separate the candidates the diagnosis leaves.
    pub suggest: bool,
    /// The shared parameters every model fits (None: k_elastic, mu_fric, and k_drag where
    /// any setup has air).
    pub params: Option<Vec<Param>>,
    /// report.md, diagnosis.json and the figures go here.
    pub out: PathBuf,
    /// How the user spelled the fields, for the errors.
    pub spelling: Spelling,
}

impl DiagnoseRequest {
    pub const DEFAULT_RESCORE_STREAMS: usize = 4;
    pub const DEFAULT_BOOTSTRAP: usize = 400;
    /// The effort of a diagnosis: the calibration's, with half its generations of
    /// differential evolution — every candidate's population starts from the baseline's
    /// optimum (the effect off, and its own parameters spread over their box), its polish
    /// also from its profile starts (`profile`: the strength held, the shared parameters
    /// refitted), and the Levenberg–Marquardt polish takes it from there
    /// (docs/diagnosis-report.md, "Time"). Without the profile starts 10 generations left a
    /// launch spread of 0.3 and 6° at the baseline's point (175 %²; 15 found it), with them
    /// 10 do (1.9 %²) at two thirds of 15's time.
    pub const DEFAULT_EFFORT: EffortSettings = EffortSettings {
        particles: None,
        max_particles: EffortSettings::DEFAULT_MAX_PARTICLES,
        pop: EffortSettings::DEFAULT_POP,
        generations: 10,
        polish: EffortSettings::DEFAULT_POLISH,
    };

    pub fn new(data: Vec<PathBuf>, setup: Vec<PathBuf>, out: PathBuf, spelling: Spelling) -> Self {
        DiagnoseRequest {
            data,
            setup,
            effects: EffectKind::ALL.to_vec(),
            seed: None,
            engine: EngineKind::Cpu,
            effort: Self::DEFAULT_EFFORT,
            normalise: None,
            rescore_streams: Self::DEFAULT_RESCORE_STREAMS,
            bootstrap: Self::DEFAULT_BOOTSTRAP,
            detection_limits: true,
            suggest: false,
            params: None,
            out,
            spelling,
        }
    }
}

/// Check, load every condition, diagnose, and write `out`. Cheap checks come first:
/// nothing is simulated before every input is known to be good. `log` receives the
/// progress lines. Returns the diagnosis and diagnosis.json's object.
pub fn run(r: &DiagnoseRequest, log: &mut dyn FnMut(String)) -> anyhow::Result<(Diagnosis, Value)> {
    let name = |f: &str| r.spelling.name(f);
    if r.data.is_empty() {
        bail!(
            "{}: a diagnosis needs at least one measured condition (a {} and its {})",
            name("data"),
            name("data"),
            name("setup")
        );
    }
    if r.data.len() != r.setup.len() {
        bail!(
            "{} and {} must come in pairs (matched by order): got {} {} and {} {}",
            name("data"),
            name("setup"),
            r.data.len(),
            name("data"),
            r.setup.len(),
            name("setup")
        );
    }
    if r.engine == EngineKind::Listing {
        let e = name("engine");
        bail!("{e} listing: the effects are in the cpu and gpu engines only; use {e} cpu or auto");
    }
    r.effort.validate(r.spelling).map_err(anyhow::Error::msg)?;
    crate::schema::RESCORE_STREAMS
        .check_usize(&name("rescore_streams"), r.rescore_streams)
        .map_err(anyhow::Error::msg)?;
    crate::schema::DIAGNOSE_BOOTSTRAP.check_usize(&name("bootstrap"), r.bootstrap).map_err(anyhow::Error::msg)?;
    let mut conditions: Vec<Condition> = Vec::with_capacity(r.data.len());
    for ((data, setup), short) in r.data.iter().zip(&r.setup).zip(condition_names(&r.data)) {
        // every condition runs on the first setup's seed unless a seed is given
        let seed = r.seed.or(conditions.first().map(|c| c.base.sim.seed));
        let mut c = measured::load(data, setup, short, r.normalise, seed, r.spelling)?;
        if c.base.effects.any() {
            log(format!(
                "diagnose: {}: the setup's [effects] ({}) are switched off; the diagnosis fits them itself",
                setup.display(),
                c.base.effects.active().join(", ")
            ));
            c.base.effects = Default::default();
        }
        if c.runs.runs.len() < 2 {
            bail!(
                "{} {}: has {} run(s); the diagnosis needs at least 2 (their spread is the measurement's uncertainty)",
                name("data"),
                data.display(),
                c.runs.runs.len()
            );
        }
        conditions.push(c);
    }
    if let Some(params) = &r.params {
        if params.is_empty() {
            bail!("{}: no parameter to fit (known: {})", name("params"), crate::calibrate::param::known_names());
        }
        if let Some(why) = params.iter().find_map(|p| conditions.iter().find_map(|c| p.refusal(&c.base, &c.setup))) {
            bail!("{}: {why}", name("params"));
        }
    }
    let (applicable, left_out) = applicable_effects(&r.effects, &conditions);
    if applicable.is_empty() {
        bail!("{}: {NO_EFFECT_APPLIES} ({})", name("effects"), left_out.join("; "));
    }
    let seed = conditions[0].base.sim.seed;
    // the output folder is owned before the work, so a busy or foreign folder costs nothing
    let _owned = RunDir::acquire(&r.out, "diagnose", Access::Exclusive).with_context(|| name("out"))?;
    let engine = make_engine(r.engine)?;
    let settings = Settings {
        effects: r.effects.clone(),
        effort: r.effort.with_seed(seed),
        rescore_streams: r.rescore_streams,
        bootstrap: r.bootstrap,
        detection_limits: r.detection_limits,
        suggest: r.suggest,
        shared: r.params.clone(),
    };
    let started = std::time::Instant::now();
    let d = diagnose(engine.as_ref(), conditions, settings, log)?;
    log(format!("diagnose: done in {:.1} s", started.elapsed().as_secs_f64()));
    let json = to_json(&d);
    render::write_dir(&r.out, &d, &json).with_context(|| name("out"))?;
    write_corrected(r, &d).with_context(|| name("out"))?;
    Ok((d, json))
}

/// `corrected.toml`: the first setup with the fitted values of the diagnosis's best model
/// (the baseline's where no candidate is best), its own `[effects]` replaced by the model's,
/// so that `simulate`, `optimize` and the rest run the corrected model (issue 43, 3).
fn write_corrected(r: &DiagnoseRequest, d: &Diagnosis) -> anyhow::Result<()> {
    let model = d.ranking.iter().find(|m| d.best.is_some() && m.single() == d.best).unwrap_or(&d.baseline);
    let mut keys: Vec<(String, &str)> = Vec::with_capacity(model.names.len());
    for &name in &model.names {
        if let Some(p) = crate::calibrate::Param::ALL.iter().find(|p| p.name() == name) {
            let (section, key) = p.config_key();
            keys.push((section.to_string(), key));
        } else if let Some(kind) = model.effects.iter().find(|e| e.param_names().contains(&name)) {
            keys.push((format!("effects.{}", kind.key()), name));
        } else {
            bail!("the fitted `{name}` of {} has no config key to write it under", model.name());
        }
    }
    let keys: Vec<(&str, &str)> = keys.iter().map(|(s, k)| (s.as_str(), *k)).collect();
    let setup = &r.setup[0];
    let text = crate::io::bounded::read_text(setup, &crate::schema::CONFIG_FILE)?;
    let mut table: toml::Table =
        toml::from_str(&text).with_context(|| format!("{} is not a TOML table", setup.display()))?;
    table.remove("effects");
    let mut provenance = vec![
        format!(
            "sawtooth {}: diagnosis of {} condition(s), verdict {}; the model written: {} (gap {:.2} %^2, floor {:.2})",
            env!("CARGO_PKG_VERSION"),
            d.conditions.len(),
            d.verdict.kind.name(),
            model.name(),
            model.gap,
            d.verdict.baseline.floor
        ),
        format!(
            "conditions: {}",
            r.data
                .iter()
                .zip(&r.setup)
                .map(|(a, b)| format!("{} with {}", a.display(), b.display()))
                .collect::<Vec<_>>()
                .join("; ")
        ),
        format!("every parameter shared by all conditions; the rest of this file is {}'s", setup.display()),
    ];
    if model.effects.contains(&EffectKind::SledMotion) {
        provenance.push("sled-motion's return direction is not written: the setup's, else the model's default".into());
    }
    let body =
        corrected_config(&toml::to_string(&table)?, &keys, &model.full.x, None, "sawtooth diagnose", &provenance)?;
    crate::io::atomic::write_atomic(&r.out.join(CORRECTED), body.as_bytes())
}
