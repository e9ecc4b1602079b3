//! Scenario resolution: a config file (or a run folder's run.toml) and the settings a user
//! lays over it, turned into one validated [`Scenario`] (and the config's design, if any).
//! The CLI's scenario flags and the Python package's `Scenario(...)` keywords both make a
//! [`ScenarioRequest`] and resolve it here, so both read files, apply overrides and name
//! errors the same way. The messages name the CLI's flags (`--alpha`, `--effect`), as they
//! did when this lived in the CLI.

use std::path::PathBuf;

use anyhow::{bail, Context as _};

use crate::io::config::ConfigFile;
use crate::model::scenario::{EnvPreset, Material};
use crate::model::{Design, Scenario};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Compat {
    /// Reproduce listing D.1-D.8 where determinable (errata 4-9, 13, 15, 16, 18-20).
    Listing,
}

/// The settings a user lays over a config file: each `Some` (or `true`, or a non-empty list)
/// replaces the file's value. Angles in degrees, `k_drag` in 1/s (0 = vacuum).
#[derive(Debug, Clone, Default)]
pub struct ScenarioRequest {
    /// TOML config, or a run folder's run.toml (its complete scenario).
    pub config: Option<PathBuf>,
    pub env: Option<EnvPreset>,
    /// Conveyor angle α, degrees: one angle (FROM == TO), or a range for
    /// [`ScenarioRequest::resolve_over_slopes`].
    pub alpha: Option<(f64, f64)>,
    pub k_elastic: Option<f64>,
    pub mu_fric: Option<f64>,
    /// Stokes drag parameter, 1/s; 0 is vacuum.
    pub k_drag: Option<f64>,
    /// Angle of repose, degrees.
    pub aor: Option<f64>,
    /// Material preset by name.
    pub material: Option<String>,
    pub particles: Option<u32>,
    pub teeth: Option<u32>,
    pub bounces: Option<u32>,
    pub seed: Option<u64>,
    /// Launch-angle offset, degrees.
    pub launch_offset: Option<f64>,
    pub no_randomise: bool,
    pub compat: Option<Compat>,
    /// `NAME=PARAMS` effect specifications.
    pub effects: Vec<String>,
}

/// The steepest conveyor the thesis designs for (Table 2.2 req. 1.6.3), degrees.
pub const THESIS_MAX_SLOPE_DEG: f64 = 40.0;

/// Switch on the `--effect NAME=PARAMS` flags, each effect once (as `diagnose --effects`
/// asks), and refuse one that cannot act on `s`: quadratic drag in vacuum would change
/// nothing (and `diagnose` refuses it there too).
pub fn set_effects(s: &mut Scenario, specs: &[String]) -> anyhow::Result<()> {
    let mut seen: Vec<&str> = Vec::new();
    for spec in specs {
        let name = spec.split_once('=').map_or(spec.as_str(), |(n, _)| n).trim();
        if seen.contains(&name) {
            bail!("--effect {spec}: effect `{name}` given twice; give each effect once");
        }
        seen.push(name);
        s.effects.set_from_cli(spec).map_err(|e| anyhow::anyhow!("--effect {spec}: {e}"))?;
    }
    if s.effects.quadratic_drag.is_some() && s.environment.k_drag.is_none() {
        bail!(
            "effect quadratic-drag (--effect or [effects.quadratic_drag]): it only changes drag, and this scenario is in vacuum (k_drag 0), so it would do nothing; give a drag rate (--k-drag, [environment] k_drag_per_s) or leave the effect out"
        );
    }
    Ok(())
}

/// Most slopes `--alpha-points` may ask for: each is one more simulation per design.
pub const MAX_ALPHA_POINTS: u32 = crate::schema::ALPHA_POINTS.max as u32;

impl ScenarioRequest {
    /// Config file (if any), then flags; validated.
    pub fn resolve(&self) -> anyhow::Result<(Scenario, Option<Design>)> {
        // a run folder's run.toml holds a complete scenario: start from it (flags still
        // override), so that a run's settings can be simulated or optimised again
        let run = match &self.config {
            Some(p) => crate::optim::manifest::manifest_in(p).context("--config")?,
            None => None,
        };
        let (mut s, file) = if let Some(run) = run {
            if self.env.is_some() || self.compat.is_some() {
                bail!(
                    "--config {}: a run's run.toml holds a complete scenario; --env and --compat would replace it, not adjust it (give the other flags, or no run.toml)",
                    self.config.as_ref().expect("a config").display()
                );
            }
            (run.scenario, ConfigFile::default())
        } else {
            let mut file = match &self.config {
                Some(p) => ConfigFile::load(p)?,
                None => ConfigFile::default(),
            };
            if let Some(e) = self.env {
                file.env = Some(e);
            }
            if self.compat == Some(Compat::Listing) {
                file.mode = Some(crate::model::PhysicsMode::Listing);
            }
            (file.scenario()?, file)
        };
        if let Some(m) = &self.material {
            s.material = Material::by_name(m).with_context(|| {
                format!("--material: unknown material `{m}` (known: lunar-regolith, quartz-sand, glass-beads)")
            })?;
        }
        if let Some((a, b)) = self.alpha {
            if !(a.is_finite() && b.is_finite()) {
                bail!("--alpha must be a finite number of degrees, got {a}");
            }
            if a != b {
                bail!(
                    "--alpha: a range ({a}..{b}) is for gpu-sweep (one run per angle) and for simulate and optimize (one design over the slopes); give one angle here"
                );
            }
            s.environment.alpha_deg = a;
            if a > THESIS_MAX_SLOPE_DEG {
                // valid for the model (up to 80 deg), but outside what the thesis designed for
                eprintln!(
                    "note: --alpha {a} lies beyond the thesis's slope range 0..{THESIS_MAX_SLOPE_DEG} deg (Table 2.2 req. 1.6.3; its angle study, 5.4.3, stops at 40 deg)"
                );
            }
        }
        if let Some(v) = self.k_elastic {
            s.collision.k_elastic = v;
        }
        if let Some(v) = self.mu_fric {
            s.collision.mu_friction = v;
        }
        if let Some(v) = self.k_drag {
            // 0 is vacuum, so the rule is >= 0 (the library's `k_drag` > 0 is the drag itself)
            if !(v >= 0.0 && v.is_finite()) {
                bail!("--k-drag must be a finite number >= 0 1/s (0 = vacuum), got {v}");
            }
            s.environment.k_drag = if v == 0.0 { None } else { Some(v) };
        }
        if let Some(v) = self.aor {
            s.material.aor_deg = v;
        }
        if let Some(v) = self.particles {
            s.sim.particles = v;
        }
        if let Some(v) = self.teeth {
            s.sim.teeth = v;
        }
        if let Some(v) = self.bounces {
            s.sim.max_bounces = v;
        }
        if let Some(v) = self.seed {
            s.sim.seed = v;
        }
        if let Some(v) = self.launch_offset {
            s.sim.launch_offset_deg = v;
        }
        if self.no_randomise {
            s.sim.randomise = false;
        }
        set_effects(&mut s, &self.effects)?;
        if let Err(e) = s.validate() {
            bail!("invalid setting: {}", in_user_terms(&e));
        }
        Ok((s, file.design()))
    }

    /// Like [`Self::resolve`], but `--alpha FROM..TO` is allowed and gives `points` evenly
    /// spaced slopes (default 5) at which every design is evaluated; one angle gives none
    /// (the scenario's α is the only slope).
    pub fn resolve_over_slopes(&self, points: Option<u32>) -> anyhow::Result<(Scenario, Option<Design>, Vec<f64>)> {
        let Some((from, to)) = self.alpha.filter(|(a, b)| a != b) else {
            if points.is_some() {
                bail!("--alpha-points needs a slope range: --alpha FROM..TO (degrees)");
            }
            let (s, d) = self.resolve()?;
            return Ok((s, d, Vec::new()));
        };
        let k = points.unwrap_or(5);
        crate::schema::ALPHA_POINTS.check_u32("--alpha-points", k).map_err(anyhow::Error::msg)?;
        let mut single = self.clone();
        single.alpha = Some((from, from));
        let (scenario, design) = single.resolve()?;
        let slopes: Vec<f64> = (0..k).map(|i| from + (to - from) * i as f64 / (k - 1) as f64).collect();
        for &alpha in &slopes {
            let mut s = scenario.clone();
            s.environment.alpha_deg = alpha;
            s.validate().map_err(|e| anyhow::anyhow!("--alpha {from}..{to}: slope {alpha}: {e}"))?;
        }
        Ok((scenario, design, slopes))
    }
}

/// The library's field names in a validation message (`environment.g`) replaced by what the
/// user wrote: the config key with its table and unit suffix, and the flag where one exists
/// (`[environment] g_m_s2`; `[collision] k_elastic` (--k-elastic)).
pub fn in_user_terms(message: &str) -> String {
    // library name, config key (with its table), flag where one exists
    const NAMES: &[(&str, &str, Option<&str>)] = &[
        ("environment.g", "[environment] g_m_s2", None),
        ("environment.alpha_deg", "[environment] alpha_deg", Some("--alpha")),
        ("environment.k_drag", "[environment] k_drag_per_s", Some("--k-drag")),
        ("material.aor_deg", "[material] aor_deg", Some("--aor")),
        ("material.bulk_density", "[material] bulk_density_kg_m3", None),
        ("collision.k_elastic", "[collision] k_elastic", Some("--k-elastic")),
        ("collision.mu_friction", "[collision] mu_friction", Some("--mu-fric")),
        ("sim.teeth", "[sim] teeth", Some("--teeth")),
        ("sim.particles", "[sim] particles", Some("--particles")),
        ("sim.max_bounces", "[sim] max_bounces", Some("--bounces")),
        ("sim.random_band", "[sim] random_band", None),
        ("sim.rest_threshold", "[sim] rest_threshold_m", None),
        ("sim.launch_offset_deg", "[sim] launch_offset_deg", Some("--launch-offset")),
        ("performance.conveyor_length", "[performance] conveyor_length_m", None),
        ("performance.regolith_width", "[performance] regolith_width_m", None),
        ("performance.sled_width", "[performance] sled_width_m", None),
        ("performance.sled_thickness", "[performance] sled_thickness_m", None),
        ("performance.sled_density", "[performance] sled_density_kg_m3", None),
        ("performance.downstroke_speed", "[performance] downstroke_speed_m_s", None),
        ("performance.f_max", "[performance] f_max_hz", None),
        ("performance.contraction_ratio", "[performance] contraction_ratio", None),
    ];
    let mut m = message.to_string();
    for (library, key, flag) in NAMES {
        let user = match flag {
            Some(flag) => format!("`{key}` ({flag})"),
            None => format!("`{key}`"),
        };
        m = m.replace(&format!("`{library}`"), &user);
    }
    m
}
