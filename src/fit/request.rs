//! One `fit` as the user asks for it: the measured runs, the rig's setup and typed settings,
//! checked, run and written as a whole. The CLI (`sawtooth fit`) and the Python package
//! (`sawtooth.fit`) both build a [`FitRequest`] and call [`run`], so the checks, the numbers,
//! the files and the JSON are the same from either.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use serde_json::Value;

use super::report::{self, Meta};
use super::{FitReport, FitSettings};
use crate::calibrate::measured::{self, condition_names, stem};
use crate::calibrate::{shared_params, Covariate, EffortSettings, Normalise, ObjectiveKind, Param, Spelling};
use crate::engine::{make_engine, EngineKind};
use crate::io::run_dir::{Access, RunDir};

/// The most bootstrap replicates a fit takes (declared in crate::schema).
pub const BOOTSTRAP_MAX: usize = crate::schema::FIT_BOOTSTRAP.max as usize;

/// What a fit needs; [`FitRequest::new`] gives the CLI's defaults.
#[derive(Clone, Debug)]
pub struct FitRequest {
    /// Measured runs: CSV `run,tooth_1,..,tooth_n[,input_mass]` (grams).
    pub data: PathBuf,
    /// The rig's setup: a config TOML with [design] (and optionally [measurement]).
    pub setup: PathBuf,
    /// The parameters to fit; None: k_elastic, mu_fric, and k_drag where the setup has drag.
    pub params: Option<Vec<Param>>,
    /// Score these values instead of fitting (the parameters not named keep the setup's).
    pub at: Option<(Vec<Param>, Vec<f64>)>,
    pub objective: ObjectiveKind,
    pub effort: EffortSettings,
    /// None: fractions of the loaded mass where every run records it, else of the recovered.
    pub normalise: Option<Normalise>,
    /// None: the setup's sim.seed.
    pub seed: Option<u64>,
    pub engine: EngineKind,
    /// Runs held out at the end of the file (0 = off); None: [`FitRequest::default_holdout`].
    pub holdout: Option<usize>,
    /// Bootstrap replicates over the runs (0 = off).
    pub bootstrap: usize,
    /// Write fit.json, fit.csv, fit.svg and fit.png into this directory.
    pub out: Option<PathBuf>,
    /// How the user spelled the fields, for the errors.
    pub spelling: Spelling,
}

/// A finished fit: the report, where its numbers came from, and `fit.json`'s object.
pub struct FitOutcome {
    pub report: FitReport,
    pub meta: Meta,
    pub json: Value,
}

impl FitRequest {
    /// Runs held out by default where the data have at least twice as many.
    pub const DEFAULT_HOLDOUT: usize = 3;
    pub const DEFAULT_BOOTSTRAP: usize = 20;

    /// The held-out runs of a fit on `runs` runs when none is asked for: 3, or half the runs
    /// (rounded down) where fewer than 6 leave 3 too few to fit on (a DEM campaign of 2 seeds
    /// holds 1 out, one run holds none).
    pub fn default_holdout(runs: usize) -> usize {
        Self::DEFAULT_HOLDOUT.min(runs / 2)
    }

    pub fn new(data: PathBuf, setup: PathBuf, spelling: Spelling) -> Self {
        FitRequest {
            data,
            setup,
            params: None,
            at: None,
            objective: ObjectiveKind::Sse,
            effort: EffortSettings::default(),
            normalise: None,
            seed: None,
            engine: EngineKind::Cpu,
            holdout: None,
            bootstrap: Self::DEFAULT_BOOTSTRAP,
            out: None,
            spelling,
        }
    }
}

/// Check, load, fit (or score `at`), and write `out` if asked. Cheap checks come first:
/// nothing is simulated before every input is known to be good. `log` receives the
/// progress lines.
pub fn run(r: &FitRequest, log: &mut dyn FnMut(String)) -> anyhow::Result<FitOutcome> {
    let name = |f: &str| r.spelling.name(f);
    if r.at.is_some() && r.params.is_some() {
        bail!("{} and {} exclude each other: `at` scores given values, `params` fits", name("at"), name("params"));
    }
    r.effort.validate(r.spelling).map_err(anyhow::Error::msg)?;
    crate::schema::FIT_BOOTSTRAP.check_usize(&name("bootstrap"), r.bootstrap).map_err(anyhow::Error::msg)?;
    let condition = measured::load(&r.data, &r.setup, stem(&r.data), r.normalise, r.seed, r.spelling)?;
    let n = condition.runs.runs.len();
    // scoring given values (`at`) holds nothing out: every run is scored
    let holdout = match (r.holdout, &r.at) {
        (_, Some(_)) => 0,
        (Some(k), None) if k >= n => bail!(
            "{} must be < the number of runs in {} ({n}), got {k}: hold out at most {} (or 0: none)",
            name("holdout"),
            r.data.display(),
            n.saturating_sub(1)
        ),
        (Some(k), None) => k,
        (None, None) => FitRequest::default_holdout(n),
    };
    // the output folder is owned before the work, so a busy or foreign folder costs nothing
    let _owned = match &r.out {
        Some(dir) => Some(RunDir::acquire(dir, "fit", Access::Exclusive).with_context(|| name("out"))?),
        None => None,
    };
    let seed = condition.base.sim.seed;
    let effort = r.effort.with_seed(seed);
    let engine = make_engine(r.engine)?;
    let started = std::time::Instant::now();
    let report = match &r.at {
        Some((params, x)) => super::evaluate_at(engine.as_ref(), &condition, params, x, r.objective, effort)
            .map_err(|e| anyhow::anyhow!("{}: {e}", name("at")))?,
        None => {
            let params = r.params.clone().unwrap_or_else(|| shared_params(std::slice::from_ref(&condition)));
            let settings = FitSettings { objective: r.objective, effort, bootstrap: r.bootstrap, holdout };
            let report = super::fit(engine.as_ref(), &condition, &params, settings, log)
                .with_context(|| format!("{} {}", name("data"), r.data.display()))?;
            log(format!("fit: done in {:.1} s", started.elapsed().as_secs_f64()));
            report
        }
    };
    let meta = Meta {
        data: r.data.display().to_string(),
        setup: r.setup.display().to_string(),
        engine: engine.backend().to_string(),
        particles: report.particles,
        seed,
        teeth: condition.teeth(),
        measured_teeth: condition.runs.teeth,
        run_ids: condition.runs.runs.iter().map(|r| r.id.clone()).collect(),
    };
    let json = report::to_json(&report, &meta);
    if let Some(dir) = &r.out {
        report::write_dir(dir, &report, &meta, &json)?;
        if report.solver.is_some() {
            write_corrected(dir, &r.setup, &report, &meta)?;
        }
    }
    Ok(FitOutcome { report, meta, json })
}

/// `corrected.toml` beside the fit's other files: the setup with the fitted values, its
/// provenance as comments ([`super::corrected`]).
fn write_corrected(dir: &Path, setup: &Path, report: &FitReport, meta: &Meta) -> anyhow::Result<()> {
    let text = crate::io::bounded::read_text(setup, &crate::schema::CONFIG_FILE)?;
    let mut provenance = vec![
        format!("sawtooth {}: fit of {} with the setup {}", env!("CARGO_PKG_VERSION"), meta.data, meta.setup),
        format!(
            "{} runs, engine {}, {} particles, seed {}; SSE {:.2} %^2, MAE {:.2} pp over the weighed teeth",
            report.runs, meta.engine, meta.particles, meta.seed, report.sse_percent2, report.mae_percent
        ),
    ];
    if let Some(h) = &report.heldout {
        provenance.push(format!(
            "held-out runs: SSE {:.2} %^2 (in sample {:.2})",
            h.sse_heldout_percent2, h.sse_in_sample_percent2
        ));
    }
    let sd = report.uncertainty.as_ref().map(|u| u.sd.as_slice());
    let body = crate::calibrate::corrected::corrected_toml(&text, &report.params, &report.x, sd, &provenance)
        .with_context(|| format!("the corrected config from {}", setup.display()))?;
    crate::io::atomic::write_atomic(&dir.join(crate::calibrate::corrected::CORRECTED), body.as_bytes())
}

/// A joint fit as the user asks for it: several (data, setup) pairs, one calibration
/// ([`super::joint`]).
#[derive(Clone, Debug)]
pub struct JointRequest {
    /// (measured runs, the setup they were measured with), one pair per condition.
    pub pairs: Vec<(PathBuf, PathBuf)>,
    /// None: k_elastic, mu_fric, and k_drag where any setup has drag.
    pub params: Option<Vec<Param>>,
    /// Parameters that vary linearly with a condition's variable.
    pub varying: Vec<(Param, Covariate)>,
    pub objective: ObjectiveKind,
    pub effort: EffortSettings,
    pub normalise: Option<Normalise>,
    /// None: the first setup's sim.seed.
    pub seed: Option<u64>,
    pub engine: EngineKind,
    /// Predict each condition from a fit of the others.
    pub leave_out: bool,
    /// Write joint.json and the corrected configs into this directory.
    pub out: Option<PathBuf>,
    pub spelling: Spelling,
}

/// The file a joint fit writes beside its corrected configs.
pub const JOINT_JSON: &str = "joint.json";

/// Check, load, fit every condition jointly, and write `out` if asked.
pub fn run_joint(r: &JointRequest, log: &mut dyn FnMut(String)) -> anyhow::Result<(super::joint::JointReport, Value)> {
    let name = |f: &str| r.spelling.name(f);
    r.effort.validate(r.spelling).map_err(anyhow::Error::msg)?;
    if r.pairs.len() < 2 {
        bail!("a joint fit takes at least two {} / {} pairs, got {}", name("data"), name("setup"), r.pairs.len());
    }
    let data: Vec<PathBuf> = r.pairs.iter().map(|(d, _)| d.clone()).collect();
    let conditions = condition_names(&data)
        .into_iter()
        .zip(&r.pairs)
        .map(|(n, (data, setup))| measured::load(data, setup, n, r.normalise, r.seed, r.spelling))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let params = r.params.clone().unwrap_or_else(|| shared_params(&conditions));
    for (p, _) in &r.varying {
        if !params.contains(p) {
            bail!("{}: {} varies but is not fitted ({}: {})", name("vary"), p.name(), name("params"), {
                let n: Vec<&str> = params.iter().map(|p| p.name()).collect();
                n.join(",")
            });
        }
    }
    let _owned = match &r.out {
        Some(dir) => Some(RunDir::acquire(dir, "fit", Access::Exclusive).with_context(|| name("out"))?),
        None => None,
    };
    let seed = conditions[0].base.sim.seed;
    let settings = super::joint::JointSettings {
        objective: r.objective,
        effort: r.effort.with_seed(seed),
        varying: r.varying.clone(),
        leave_out: r.leave_out,
    };
    let engine = make_engine(r.engine)?;
    let started = std::time::Instant::now();
    let report = super::joint::fit_joint(engine.as_ref(), &conditions, &params, &settings, log)
        .map_err(|e| anyhow::anyhow!("{e}").context(format!("the joint fit of {} conditions", conditions.len())))?;
    log(format!("fit: done in {:.1} s", started.elapsed().as_secs_f64()));
    let json = report::joint_json(&report, engine.backend(), seed);
    if let Some(dir) = &r.out {
        crate::io::atomic::write_atomic(&dir.join(JOINT_JSON), serde_json::to_string_pretty(&json)?.as_bytes())?;
        write_joint_corrected(dir, &report, engine.backend(), seed)?;
    }
    Ok((report, json))
}

/// `corrected-NAME.toml` per condition (its setup with its own values of the fitted
/// parameters), and `corrected.toml` (the first setup with the shared values) where no
/// parameter varies: the corrected model any command reads as a config.
fn write_joint_corrected(
    dir: &Path,
    report: &super::joint::JointReport,
    engine: &str,
    seed: u64,
) -> anyhow::Result<()> {
    let all: Vec<String> = report.conditions.iter().map(|c| format!("{} with {}", c.data, c.setup)).collect();
    let provenance = |c: &super::joint::ConditionFit| {
        vec![
            format!("sawtooth {}: joint fit of {} conditions: {}", env!("CARGO_PKG_VERSION"), all.len(), all.join("; ")),
            format!(
                "engine {engine}, {} particles, seed {seed}; SSE {:.2} %^2 over all (floor {:.2}); this condition {}: SSE \
                 {:.2} %^2 (floor {:.2})",
                report.solver.particles,
                report.sse_percent2(),
                report.floor_percent2(),
                c.name,
                c.sse_percent2,
                c.floor_percent2
            ),
        ]
    };
    for c in &report.conditions {
        let text = crate::io::bounded::read_text(Path::new(&c.setup), &crate::schema::CONFIG_FILE)?;
        let body = crate::calibrate::corrected::corrected_toml(&text, &report.params, &c.values, None, &provenance(c))
            .with_context(|| format!("the corrected config from {}", c.setup))?;
        crate::io::atomic::write_atomic(&dir.join(format!("corrected-{}.toml", c.name)), body.as_bytes())?;
    }
    if report.varying.is_empty() {
        let first = &report.conditions[0];
        let text = crate::io::bounded::read_text(Path::new(&first.setup), &crate::schema::CONFIG_FILE)?;
        let mut lines = provenance(first);
        lines.push("every parameter shared by all conditions; the design is the first condition's".into());
        let body = crate::calibrate::corrected::corrected_toml(&text, &report.params, &report.x, None, &lines)
            .with_context(|| format!("the corrected config from {}", first.setup))?;
        crate::io::atomic::write_atomic(&dir.join(crate::calibrate::corrected::CORRECTED), body.as_bytes())?;
    }
    Ok(())
}
