//! TOML configuration files for `simulate` (and later the studies). Every table and key is
//! optional and overrides the chosen preset; unknown keys are errors that name the key.
//! Units are in the key names where they are not SI.

use std::path::Path;

use anyhow::{bail, Context as _};
use serde::Deserialize;

use crate::model::design::DesignRow;
use crate::model::requirements::{Requirements, PRESET_TABLE_2_2};
use crate::model::scenario::{EnvPreset, Material, PhysicsMode, Scenario};
use crate::model::Design;

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigFile {
    /// `lunar` or `earth` (listing D.5 presets); default lunar.
    pub env: Option<EnvPreset>,
    /// `physical` (thesis text) or `listing` (compatibility).
    pub mode: Option<PhysicsMode>,
    /// The design in the units of Table 5.3 (`[design]`, the columns of every table).
    pub design: Option<DesignRow>,
    pub environment: Option<EnvironmentTable>,
    pub material: Option<MaterialTable>,
    pub collision: Option<CollisionTable>,
    pub sim: Option<SimTable>,
    pub performance: Option<PerformanceTable>,
    /// Effects beyond the thesis's model: [effects.impact_scatter] sigma_deg,
    /// [effects.launch_spread] speed_spread + angle_sigma_deg, [effects.polydisperse] sigma_ln,
    /// [effects.sled_motion], [effects.quadratic_drag], [effects.fill_surface_loss]
    /// speed_loss + decay_depth_m (`EffectKind::param_names`).
    pub effects: Option<crate::model::effects::Effects>,
    /// How a validation setup was measured (App. B, 4.3.2); descriptive only, it does not
    /// change the scenario.
    pub measurement: Option<MeasurementTable>,
    /// What the design must meet (Table 2.2); read by `simulate` and `optimize`.
    pub requirements: Option<RequirementsTable>,
    /// How `sawtooth dem` builds a LIGGGHTS case (docs/dem.md); ignored by the model.
    pub dem: Option<DemTable>,
}

/// `[dem]`: the settings of a DEM case that the model has no counterpart for. Every key is
/// optional; `crate::dem::DemSettings` holds the defaults and the rules.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemTable {
    /// Grains in the case (`--particles` overrides).
    pub particles: Option<u32>,
    /// Grain diameter; absent: the diameter at which the grains hold the model's fill mass.
    pub grain_diameter_m: Option<f64>,
    /// Periodic depth of the slab, in grain diameters.
    pub depth_grains: Option<f64>,
    /// Rolling friction coefficient (LIGGGHTS `rolling_friction cdt`).
    pub rolling_friction: Option<f64>,
    /// Largest Hertz overlap at the design impact speed, as a fraction of the grain radius:
    /// sets the softened Young's modulus.
    pub max_overlap_fraction: Option<f64>,
    /// Simulated time after the stroke before the run stops even if grains still move.
    pub max_time_s: Option<f64>,
    /// RMS grain speed below which the grains count as at rest.
    pub rest_speed_m_s: Option<f64>,
    /// Teeth of the mesh; absent: the model's reach plus half of it (at least 3 more).
    pub teeth: Option<u32>,
    /// Where the DEM's constant normal COR comes from: `"k_elastic"` (the default) or
    /// `"model"` (the thesis law's k_n at the design's launch speed).
    pub restitution: Option<DemRestitution>,
}

/// The source of a DEM case's normal coefficient of restitution (LIGGGHTS's is one constant).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DemRestitution {
    /// `[collision] k_elastic` itself, the law's elastic limit (4.1.2).
    #[default]
    KElastic,
    /// The thesis law's k_n (Eq. 4.9) at a normal speed equal to the design's launch speed v0:
    /// the DEM's constant closest to the model's law at the impacts that carry the grains.
    Model,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentTable {
    pub g_m_s2: Option<f64>,
    pub alpha_deg: Option<f64>,
    /// Stokes k_drag in 1/s; 0 switches drag off (vacuum).
    pub k_drag_per_s: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialTable {
    /// `lunar-regolith`, `quartz-sand` or `glass-beads`.
    pub name: Option<String>,
    pub aor_deg: Option<f64>,
    pub bulk_density_kg_m3: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionTable {
    pub k_elastic: Option<f64>,
    pub mu_friction: Option<f64>,
    /// `"thesis"` (default) or `"dem"` (`model::ContactLaw`).
    pub law: Option<crate::model::ContactLaw>,
    /// The DEM law's measured k_t at each ψ of `model::collision::TANGENTIAL_PSI`.
    pub tangential_ratio: Option<Vec<f64>>,
    /// The thesis law's plastic limit speed, m/s (`model::Collision::v_limit_m_s`).
    pub v_limit_m_s: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimTable {
    pub teeth: Option<u32>,
    pub particles: Option<u32>,
    pub max_bounces: Option<u32>,
    pub randomise: Option<bool>,
    pub random_band: Option<f64>,
    pub seed: Option<u64>,
    pub rest_threshold_m: Option<f64>,
    pub launch_offset_deg: Option<f64>,
    /// `halton` (default, Eq. 4.37) or `random`.
    pub launch_points: Option<crate::model::scenario::LaunchPoints>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerformanceTable {
    pub conveyor_length_m: Option<f64>,
    pub regolith_width_m: Option<f64>,
    pub sled_width_m: Option<f64>,
    pub downstroke_speed_m_s: Option<f64>,
    pub f_max_hz: Option<f64>,
    /// The sled's plate thickness (3.4.3, 5.3.1: a 5 mm aluminium plate); the thesis names
    /// the sled's mass as the lever for the power requirement (5.6).
    pub sled_thickness_m: Option<f64>,
    pub sled_density_kg_m3: Option<f64>,
    /// SMA contraction ratio (3.4.3: 3-7 %, 5 % assumed); sets the wire length.
    pub contraction_ratio: Option<f64>,
}

/// `[requirements]`: a whole set, or `preset = "table-2.2"` with the keys that differ.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RequirementsTable {
    pub preset: Option<String>,
    pub feed_rate_min_kg_h: Option<f64>,
    pub feed_rate_target_kg_h: Option<f64>,
    pub power_max_w: Option<f64>,
    pub slope_min_deg: Option<f64>,
    pub slope_max_deg: Option<f64>,
    pub transport_length_m: Option<f64>,
}

impl RequirementsTable {
    /// The requirement set, validated; `source` names where it came from.
    pub fn requirements(&self, source: &str) -> anyhow::Result<Requirements> {
        let base = match &self.preset {
            Some(name) => Some(Requirements::preset(name).with_context(|| {
                format!("requirements.preset: unknown preset `{name}` (known: {PRESET_TABLE_2_2})")
            })?),
            None => None,
        };
        let pick = |v: Option<f64>, from_base: Option<f64>, key: &str| {
            v.or(from_base).with_context(|| {
                format!("requirements.{key} is missing (give it, or start from preset = \"{PRESET_TABLE_2_2}\")")
            })
        };
        let b = base.as_ref();
        let r = Requirements {
            source: source.to_string(),
            feed_rate_min_kg_h: pick(self.feed_rate_min_kg_h, b.map(|b| b.feed_rate_min_kg_h), "feed_rate_min_kg_h")?,
            feed_rate_target_kg_h: pick(
                self.feed_rate_target_kg_h,
                b.map(|b| b.feed_rate_target_kg_h),
                "feed_rate_target_kg_h",
            )?,
            power_max_w: pick(self.power_max_w, b.map(|b| b.power_max_w), "power_max_w")?,
            slope_min_deg: pick(self.slope_min_deg, b.map(|b| b.slope_min_deg), "slope_min_deg")?,
            slope_max_deg: pick(self.slope_max_deg, b.map(|b| b.slope_max_deg), "slope_max_deg")?,
            transport_length_m: pick(self.transport_length_m, b.map(|b| b.transport_length_m), "transport_length_m")?,
        };
        r.validate().map_err(anyhow::Error::msg)?;
        Ok(r)
    }
}

/// Requirements by name (a preset) or from the `[requirements]` table of a TOML file (a
/// scenario config file may hold it beside its other tables); the CLI's `--requirements`.
pub fn load_requirements(spec: &str) -> anyhow::Result<Requirements> {
    if let Some(r) = Requirements::preset(spec) {
        return Ok(r);
    }
    let path = Path::new(spec);
    if !path.exists() {
        bail!("requirements `{spec}`: neither a preset (known: {PRESET_TABLE_2_2}) nor an existing file");
    }
    let file = ConfigFile::load(path)?;
    let table =
        file.requirements.with_context(|| format!("requirements `{spec}`: the file has no [requirements] table"))?;
    table.requirements(&path.display().to_string()).with_context(|| format!("in {}", path.display()))
}

/// Metadata of a measured validation setup (`data/validation/testN.toml`).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasurementTable {
    /// Resolution of the scale in grams: 0.1 for Tests 1-2, 0.01 for Test 3 (4.3.3).
    pub scale_resolution_g: Option<f64>,
    /// Mass loaded into the first tooth per run, in grams ("ca. 2 g", 4.3.2).
    pub particle_mass_g: Option<f64>,
    /// `poc` (single cycle of the proof-of-concept profile, Test 1) or `delayed` (delayed,
    /// decelerated downstroke, Tests 2-3); Table 4.2.
    pub motion_profile: Option<String>,
    /// What is known of the sled's motion after the launch (the thesis's model assumes it
    /// stops): it rests this long, s, ...
    pub motion_delay_s: Option<f64>,
    /// ... then returns down the slope at this speed, m/s, over the stroke. Used only by
    /// `diagnose`'s sled-motion candidate, which holds a value given here fixed for this
    /// condition and fits one left out (shared by the conditions that leave it out).
    pub motion_return_speed_m_s: Option<f64>,
    /// ... along this direction: `slope` (down the slope, the rig's guide; the default) or
    /// `launch` (back along the launch direction).
    pub motion_direction: Option<crate::model::effects::MotionDirection>,
    /// The largest share of the loaded mass the runs may have lost in handling (spilled
    /// between the conveyor and the scale), 0-1; unset: all they did not recover (a rig's
    /// spill). A DEM campaign states 0: every grain it did not recover left the box or the
    /// mesh in the simulation, physics the model must predict, not handling.
    pub handling_loss_max: Option<f64>,
    pub description: Option<String>,
}

impl MeasurementTable {
    /// Numbers must be finite and > 0 (the motion ones inside the sled-motion effect's
    /// bounds); `motion_profile` must be `poc` or `delayed`.
    pub fn validate(&self) -> anyhow::Result<()> {
        for (bound, key, v) in [
            (&crate::schema::SCALE_RESOLUTION_G, "scale_resolution_g", self.scale_resolution_g),
            (&crate::schema::PARTICLE_MASS_G, "particle_mass_g", self.particle_mass_g),
            (&crate::schema::HANDLING_LOSS_MAX, "handling_loss_max", self.handling_loss_max),
        ] {
            if let Some(v) = v {
                bound.check(&format!("measurement.{key}"), v).map_err(anyhow::Error::msg)?;
            }
        }
        // the bounds of the sled-motion effect (`Effects::validate`)
        if let Some(v) = self.motion_delay_s {
            crate::schema::MOTION_DELAY.check("measurement.motion_delay_s", v).map_err(anyhow::Error::msg)?;
        }
        if let Some(v) = self.motion_return_speed_m_s {
            crate::schema::MOTION_RETURN_SPEED
                .check("measurement.motion_return_speed_m_s", v)
                .map_err(anyhow::Error::msg)?;
        }
        if let Some(p) = &self.motion_profile {
            if p != "poc" && p != "delayed" {
                bail!("measurement.motion_profile must be `poc` or `delayed`, got `{p}`");
            }
        }
        Ok(())
    }
}

impl ConfigFile {
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = crate::io::bounded::read_text(path, &crate::schema::CONFIG_FILE)?;
        Self::parse(&text).with_context(|| format!("in config file {}", path.display()))
    }

    pub fn parse(text: &str) -> anyhow::Result<Self> {
        let c: Self = toml::from_str(text)?;
        if let Some(m) = &c.measurement {
            m.validate()?;
        }
        if let Some(d) = &c.design {
            d.checked_design("design.").map_err(anyhow::Error::msg)?;
        }
        Ok(c)
    }

    /// The scenario this file describes (preset, then mode, then overrides).
    pub fn scenario(&self) -> anyhow::Result<Scenario> {
        let mut s = Scenario::preset(self.env.unwrap_or(EnvPreset::Lunar));
        if self.mode == Some(PhysicsMode::Listing) {
            s = s.into_listing_compat();
        }
        if let Some(e) = &self.environment {
            set(&mut s.environment.g, e.g_m_s2);
            set(&mut s.environment.alpha_deg, e.alpha_deg);
            if let Some(k) = e.k_drag_per_s {
                if !(k >= 0.0 && k.is_finite()) {
                    bail!("[environment] k_drag_per_s must be a finite number >= 0 1/s (0 = vacuum), got {k}");
                }
                s.environment.k_drag = if k == 0.0 { None } else { Some(k) };
            }
        }
        if let Some(m) = &self.material {
            if let Some(name) = &m.name {
                match Material::by_name(name) {
                    Some(mat) => s.material = mat,
                    None => bail!(
                        "material.name: unknown material `{name}` (known: lunar-regolith, quartz-sand, glass-beads)"
                    ),
                }
            }
            set(&mut s.material.aor_deg, m.aor_deg);
            set(&mut s.material.bulk_density, m.bulk_density_kg_m3);
        }
        if let Some(c) = &self.collision {
            set(&mut s.collision.k_elastic, c.k_elastic);
            set(&mut s.collision.mu_friction, c.mu_friction);
            set(&mut s.collision.law, c.law);
            if let Some(t) = &c.tangential_ratio {
                s.collision.tangential_ratio = t.clone();
            }
            if c.v_limit_m_s.is_some() {
                s.collision.v_limit_m_s = c.v_limit_m_s;
            }
        }
        if let Some(t) = &self.sim {
            set(&mut s.sim.teeth, t.teeth);
            set(&mut s.sim.particles, t.particles);
            set(&mut s.sim.max_bounces, t.max_bounces);
            set(&mut s.sim.randomise, t.randomise);
            set(&mut s.sim.random_band, t.random_band);
            set(&mut s.sim.seed, t.seed);
            set(&mut s.sim.rest_threshold, t.rest_threshold_m);
            set(&mut s.sim.launch_offset_deg, t.launch_offset_deg);
            set(&mut s.sim.launch_points, t.launch_points);
        }
        if let Some(e) = &self.effects {
            s.effects = *e;
        }
        if let Some(p) = &self.performance {
            set(&mut s.performance.conveyor_length, p.conveyor_length_m);
            set(&mut s.performance.regolith_width, p.regolith_width_m);
            set(&mut s.performance.sled_width, p.sled_width_m);
            set(&mut s.performance.downstroke_speed, p.downstroke_speed_m_s);
            set(&mut s.performance.f_max, p.f_max_hz);
            set(&mut s.performance.sled_thickness, p.sled_thickness_m);
            set(&mut s.performance.sled_density, p.sled_density_kg_m3);
            set(&mut s.performance.contraction_ratio, p.contraction_ratio);
        }
        Ok(s)
    }

    pub fn design(&self) -> Option<Design> {
        self.design.as_ref().map(DesignRow::design)
    }
}

fn set<T: Copy>(slot: &mut T, v: Option<T>) {
    if let Some(v) = v {
        *slot = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_key_is_named() {
        let err = ConfigFile::parse("[sim]\nparticels = 5\n").unwrap_err();
        assert!(format!("{err:#}").contains("particels"), "{err:#}");
    }

    #[test]
    fn wrong_type_is_named() {
        let err = ConfigFile::parse("[collision]\nk_elastic = \"high\"\n").unwrap_err();
        assert!(format!("{err:#}").contains("k_elastic"), "{err:#}");
    }

    #[test]
    fn overrides_apply_on_top_of_the_preset() {
        let c = ConfigFile::parse("env = \"earth\"\n[environment]\nk_drag_per_s = 0\n[sim]\nseed = 7\n").unwrap();
        let s = c.scenario().unwrap();
        assert_eq!(s.environment.g, 9.81);
        assert_eq!(s.environment.k_drag, None);
        assert_eq!(s.sim.seed, 7);
    }

    #[test]
    fn unknown_material_is_an_error() {
        let c = ConfigFile::parse("[material]\nname = \"cheese\"\n").unwrap();
        assert!(c.scenario().unwrap_err().to_string().contains("material.name"));
    }

    #[test]
    fn measurement_table_parses_and_validates() {
        let c = ConfigFile::parse(
            "[measurement]\nscale_resolution_g = 0.01\nparticle_mass_g = 2.0\nmotion_profile = \"delayed\"\ndescription = \"Test 3\"\n",
        )
        .unwrap();
        let m = c.measurement.unwrap();
        assert_eq!(m.scale_resolution_g, Some(0.01));
        assert_eq!(m.motion_profile.as_deref(), Some("delayed"));
        assert_eq!(m.motion_direction, None);
        let c = ConfigFile::parse("[measurement]\nmotion_direction = \"launch\"\n").unwrap();
        assert_eq!(c.measurement.unwrap().motion_direction, Some(crate::model::effects::MotionDirection::Launch));
        for (text, key) in [
            ("motion_direction = \"up\"", "motion_direction"),
            ("motion_direction = \"up\"", "expected `slope` or `launch`"),
            ("scale_resolution_g = 0.0", "measurement.scale_resolution_g must lie in [1e-15, 1000] g"),
            ("scale_resolution_g = 1e308", "measurement.scale_resolution_g must lie in [1e-15, 1000] g"),
            ("particle_mass_g = -2.0", "measurement.particle_mass_g must lie in [1e-12, 1000000] g"),
            ("particle_mass_g = 1e308", "measurement.particle_mass_g must lie in"),
            ("particle_mass_g = nan", "measurement.particle_mass_g must lie in"),
            ("scale_resolution_g = inf", "measurement.scale_resolution_g must lie in"),
            ("motion_profile = \"fast\"", "measurement.motion_profile must be `poc` or `delayed`"),
            ("motion_delay_s = -0.1", "measurement.motion_delay_s must lie in [0, 100]"),
            ("motion_return_speed_m_s = 0.0", "measurement.motion_return_speed_m_s must lie in"),
            ("motion_return_speed_m_s = nan", "measurement.motion_return_speed_m_s must lie in"),
            ("scale = 0.1", "scale"),
        ] {
            let err = ConfigFile::parse(&format!("[measurement]\n{text}\n")).unwrap_err();
            assert!(format!("{err:#}").contains(key), "{text}: {err:#}");
        }
    }

    #[test]
    fn validation_setup_files_load() {
        for n in 1..=3 {
            let path = format!("{}/data/validation/test{n}.toml", env!("CARGO_MANIFEST_DIR"));
            let c = ConfigFile::load(Path::new(&path)).unwrap();
            let s = c.scenario().unwrap();
            assert_eq!(s.material.name, if n == 3 { "glass-beads" } else { "quartz-sand" });
            assert_eq!(s.sim.teeth, 20);
            assert!(c.design().is_some());
            let m = c.measurement.unwrap();
            assert_eq!(m.motion_profile.as_deref(), Some(if n == 1 { "poc" } else { "delayed" }));
            assert_eq!(m.scale_resolution_g, Some(if n == 3 { 0.01 } else { 0.1 }));
        }
    }

    #[test]
    fn requirements_start_from_the_preset_and_name_what_is_missing() {
        let c = ConfigFile::parse("[requirements]\npreset = \"table-2.2\"\npower_max_w = 3.0\n").unwrap();
        let r = c.requirements.unwrap().requirements("x.toml").unwrap();
        assert_eq!(r.power_max_w, 3.0);
        assert_eq!(r.feed_rate_min_kg_h, 6.0);
        assert_eq!(r.source, "x.toml");
        let c = ConfigFile::parse("[requirements]\npower_max_w = 3.0\n").unwrap();
        let e = c.requirements.unwrap().requirements("x.toml").unwrap_err().to_string();
        assert!(e.contains("requirements.feed_rate_min_kg_h is missing"), "{e}");
        let c = ConfigFile::parse("[requirements]\npreset = \"table-9\"\n").unwrap();
        let e = c.requirements.unwrap().requirements("x.toml").unwrap_err().to_string();
        assert!(e.contains("requirements.preset") && e.contains("table-2.2"), "{e}");
        let c = ConfigFile::parse("[requirements]\npreset = \"table-2.2\"\npower_max_w = -1\n").unwrap();
        let e = c.requirements.unwrap().requirements("x.toml").unwrap_err().to_string();
        assert!(e.contains("requirements.power_max_w must lie in [0.001, 1000000] W"), "{e}");
        assert!(load_requirements("table-2.2").is_ok());
        let e = load_requirements("/nonexistent/req.toml").unwrap_err().to_string();
        assert!(e.contains("neither a preset"), "{e}");
    }

    #[test]
    fn the_sled_plate_is_a_setting() {
        let c = ConfigFile::parse("[performance]\nsled_thickness_m = 0.002\n").unwrap();
        assert_eq!(c.scenario().unwrap().performance.sled_thickness, 0.002);
    }
}
