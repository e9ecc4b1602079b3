//! What determines an optimisation run, as its folder's run.toml records it: the engine,
//! seed, algorithm and every setting ([`Manifest`]), the bounds a stored or new run's settings
//! must keep, and reading a manifest back (for `--resume`, campaigns and `--config RUN.toml`).
//! The runner writes it and the final front reads it; neither owns it, so neither imports the
//! other for it.

use std::path::Path;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::nsga2::{Config, Mode};
use crate::engine::EngineKind;
use crate::model::requirements::Requirements;
use crate::model::Scenario;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Algorithm {
    /// NSGA-II (Deb et al. 2002) with Deb's constraint domination; stops at --generations.
    Nsga2,
    /// gamultiobj-like: ParetoFraction 0.35, stops when the average relative change of the
    /// front's spread over --stall-generations falls below --tol (or at --generations).
    MatlabLike,
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
    /// Slopes every design is evaluated at (`--alpha FROM..TO --alpha-points K`), degrees;
    /// empty: the scenario's α.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slopes_deg: Vec<f64>,
    /// Requirements the designs are constrained by (`optimize --requirements`, issue 13).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub requirements: Option<Requirements>,
}

/// Smallest population (NSGA-II's tournaments and crowding need a few members), and the
/// largest population, generation count, particle count and replicate count a run accepts:
/// beyond these a value is a typo, not a run (a population of a billion needs tens of GB
/// before the first generation).
/// (Declared in `schema`, here under the names the commands use.)
pub const MIN_POP: usize = crate::schema::POP.min as usize;
pub const MAX_POP: usize = crate::schema::POP.max as usize;
pub const MAX_GENERATIONS: u64 = crate::schema::GENERATIONS.max;
pub const MAX_PARTICLES: u32 = crate::schema::FINAL_PARTICLES.max as u32;
pub const MAX_REPLICATES: u32 = crate::schema::REPLICATES.max as u32;

impl Manifest {
    /// The rules a new run's settings are checked by, applied to stored ones: a run.toml
    /// edited by hand (or damaged) is refused before anything runs, naming its key.
    pub fn validate(&self) -> Result<(), String> {
        self.scenario.validate().map_err(|e| format!("scenario: {e}"))?;
        use crate::schema::{FINAL_PARTICLES, GENERATIONS, POP, REPLICATES, STALL_GENERATIONS};
        let c = &self.config;
        POP.check_usize("`config.pop`", c.pop)?;
        GENERATIONS.check("`config.max_generations`", c.max_generations)?;
        if let Mode::MatlabLike { stall_generations, .. } = c.mode {
            STALL_GENERATIONS.check("`config.mode.stall_generations`", stall_generations)?;
        }
        if let Mode::MatlabLike { pareto_fraction, tol, .. } = c.mode {
            crate::schema::OPT_TOL.check("`config.mode.tol`", tol)?;
            crate::schema::PARETO_FRACTION.check("`config.mode.pareto_fraction`", pareto_fraction)?;
        }
        for (name, v) in [("config.crossover_eta", c.crossover_eta), ("config.mutation_eta", c.mutation_eta)] {
            crate::schema::DISTRIBUTION_INDEX.check(&format!("`{name}`"), v)?;
        }
        crate::schema::CROSSOVER_PROB.check("`config.crossover_prob`", c.crossover_prob)?;
        FINAL_PARTICLES.check_u32("`final_particles`", self.final_particles)?;
        REPLICATES.check_u32("`replicates`", self.replicates)?;
        for &alpha in &self.slopes_deg {
            let mut s = self.scenario.clone();
            s.environment.alpha_deg = alpha;
            s.validate().map_err(|e| format!("`slopes_deg`: slope {alpha}: {e}"))?;
        }
        if let Some(r) = &self.requirements {
            r.validate()?;
        }
        Ok(())
    }
}

/// Read a run's manifest (for --resume).
pub fn read_manifest(dir: &Path) -> anyhow::Result<Manifest> {
    let path = dir.join("run.toml");
    if !path.exists() {
        bail!("no run manifest at {}", path.display());
    }
    let text = crate::io::bounded::read_text(&path, &crate::schema::MANIFEST_FILE)?;
    let m: Manifest = toml::from_str(&text).with_context(|| format!("reading {}", path.display()))?;
    m.validate().map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(m)
}

/// The run manifest in `path` when the file is one (a run folder's run.toml: it has a
/// `version` and a `[scenario]`), validated; None for any other file (e.g. a scenario config).
pub fn manifest_in(path: &Path) -> anyhow::Result<Option<Manifest>> {
    let text = crate::io::bounded::read_text(path, &crate::schema::CONFIG_FILE)?;
    let Ok(table) = text.parse::<toml::Table>() else { return Ok(None) };
    if !(table.contains_key("version") && table.get("scenario").is_some_and(toml::Value::is_table)) {
        return Ok(None);
    }
    let m: Manifest = toml::from_str(&text).with_context(|| format!("reading the run manifest {}", path.display()))?;
    m.validate().map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(Some(m))
}
