//! Everything but the design: environment, material, collision parameters, simulation
//! settings, performance constants and the physics mode. Presets follow listing D.5.

use serde::{Deserialize, Serialize};

pub use crate::kernel_codes::TANGENTIAL_PSI;

/// Nodes of the DEM law's tangential table.
pub const TANGENTIAL_NODES: usize = TANGENTIAL_PSI.len();

/// A measured tangential table: one finite ratio per node of [`TANGENTIAL_PSI`], each in
/// [-1, 1] (a rebound keeps at most its tangential speed, and reverses at most all of it).
pub fn check_tangential_table(t: &[f64]) -> Result<(), String> {
    if t.len() != TANGENTIAL_NODES {
        return Err(format!(
            "`[collision] tangential_ratio` must hold {TANGENTIAL_NODES} values (k_t at psi = {TANGENTIAL_PSI:?}; `sawtooth dem impact --law-out` measures them), got {}",
            t.len()
        ));
    }
    match t.iter().position(|v| !(v.is_finite() && (-1.0..=1.0).contains(v))) {
        Some(i) => Err(format!("`[collision] tangential_ratio` value {} must lie in [-1, 1], got {}", i + 1, t[i])),
        None => Ok(()),
    }
}

/// Which physics the engines run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum PhysicsMode {
    /// The thesis text's physics (Ch. 4-5), with the errata fixed. See the deviation table in docs/physics.md.
    #[default]
    Physical,
    /// What listing D.1-D.8 did, where determinable (errata 4-9, 13, 15, 16, 18-20),
    /// so the published figures can be compared.
    Listing,
}

/// Gravity, conveyor angle and the drag model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Environment {
    /// Gravitational acceleration, m/s².
    pub g: f64,
    /// Conveyor angle α, degrees.
    pub alpha_deg: f64,
    /// Stokes drag parameter k_drag = b/m (Eq. 4.20), 1/s; `None` = vacuum.
    pub k_drag: Option<f64>,
}

/// Elastic and strength properties of one collision partner (Table 4.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Solid {
    /// Young's modulus, Pa.
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    /// Yield (conveyor) or compressive (particle) strength, Pa.
    pub strength: f64,
    /// Density, kg/m³ (only the particle's is used).
    pub density: f64,
}

/// The conveyed material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub name: String,
    /// Static angle of repose, degrees (4.1.1).
    pub aor_deg: f64,
    /// Loose bulk density, kg/m³ (rho_regolith,min, 3.4.3).
    pub bulk_density: f64,
    /// Particle properties (Table 4.1: basalt analogue).
    pub particle: Solid,
    /// Conveyor properties (Table 4.1: Al 6061-T6).
    pub conveyor: Solid,
}

/// Which restitution law a bounce follows (`[collision] law`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum ContactLaw {
    /// The thesis's law (4.1.2): k_n = k_elastic, plastic above v_limit (Eq. 4.9), and
    /// k_t = 1 − 3.5 μ (k_n + 1) |v_n|/|v_t| clamped to [0, 1] (Eq. 4.14).
    #[default]
    Thesis,
    /// The DEM's law (`sawtooth dem`, LIGGGHTS's Hertz contact with a constant restitution,
    /// Coulomb and rolling friction): k_n = k_elastic at every speed, and k_t a table over
    /// ψ = |v_t| / (μ (1 + k_n) |v_n|) measured on single impacts (`sawtooth dem impact`).
    Dem,
}

/// The fitted collision parameters (4.1.2), and the law they enter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Collision {
    /// Elastic normal COR k_elastic.
    pub k_elastic: f64,
    /// Friction coefficient μ_friction of Eq. 4.14.
    pub mu_friction: f64,
    /// The restitution law.
    #[serde(default)]
    pub law: ContactLaw,
    /// The DEM law's tangential ratio k_t at each ψ of `collision::TANGENTIAL_PSI`
    /// (measured by `sawtooth dem impact`); empty with the thesis's law.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tangential_ratio: Vec<f64>,
    /// The plastic limit speed of the thesis's law, m/s (Eq. 4.9: k_n = k_elastic below it,
    /// k_elastic (v_limit/|v_n|)^¼ above); None: Eq. 4.7 from the material's strength and
    /// moduli (0.0135 m/s for lunar regolith). Stated, it is a calibration parameter: how fast
    /// the normal COR falls with impact speed, from the thesis's plastic law (small) towards
    /// one constant COR (above every impact's speed, as the DEM's contact).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_limit_m_s: Option<f64>,
}

impl Collision {
    /// The thesis's law with these coefficients.
    pub fn thesis(k_elastic: f64, mu_friction: f64) -> Self {
        Collision { k_elastic, mu_friction, law: ContactLaw::Thesis, tangential_ratio: Vec::new(), v_limit_m_s: None }
    }
}

/// Simulation settings (4.2.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimSettings {
    /// Number of simulated teeth (D.5: 100).
    pub teeth: u32,
    /// Launched particles per design n_launch (D.5: 100).
    pub particles: u32,
    /// Maximum bounce iterations n_bounce (D.5: 100).
    pub max_bounces: u32,
    /// Randomise launch angle and speed (4.2.4).
    pub randomise: bool,
    /// Half-width of the randomisation band: factors in [1-band, 1+band] (D.1: 0.10).
    pub random_band: f64,
    pub seed: u64,
    /// Rest threshold l_limit of Eq. 4.50, metres (D.1: 0.1 mm, erratum 15).
    pub rest_threshold: f64,
    /// Launch-angle offset added to α and the design's δ, degrees (erratum 10: 18.434°).
    pub launch_offset_deg: f64,
    /// How the launch points fill the fill area (Eq. 4.37: Halton).
    #[serde(default, skip_serializing_if = "LaunchPoints::is_halton")]
    pub launch_points: LaunchPoints,
}

/// The launch points' sampling of the fill area.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LaunchPoints {
    /// Halton bases 2 and 3 (Eq. 4.37, listing lines 185-209).
    #[default]
    Halton,
    /// Independent uniform points from the counter-based generator (seeded by `sim.seed`):
    /// a form for synthetic data that differs from the model's Halton points.
    Random,
}

impl LaunchPoints {
    fn is_halton(&self) -> bool {
        *self == LaunchPoints::Halton
    }
}

/// Constants of the performance model (3.4.3, 5.3.1, listing D.5/D.7/D.8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerformanceParams {
    /// Conveyor length along the slope, m (D.7: 1 m).
    pub conveyor_length: f64,
    /// Width of the regolith bed, m (text 0.16; the published tables used 0.15, erratum 13).
    pub regolith_width: f64,
    /// Sled width, m (D.5 w_sled = 0.16).
    pub sled_width: f64,
    /// Sled plate thickness, m (D.5: 5 mm).
    pub sled_thickness: f64,
    /// Sled density, kg/m³ (aluminium 2700).
    pub sled_density: f64,
    /// Recovery force of one SMA wire, N (D.5: 10).
    pub wire_force: f64,
    /// Wire diameter, m (0.25 mm).
    pub wire_diameter: f64,
    /// Bias stress to reset a wire, Pa (D.5: 100 MPa).
    pub wire_bias_stress: f64,
    /// Wire density, kg/m³ (6450).
    pub wire_density: f64,
    /// Wire specific heat, J/(kg K) (320).
    pub wire_heat_capacity: f64,
    /// Heating temperature rise ΔT, K (320).
    pub wire_delta_t: f64,
    /// Wire contraction ratio (0.05).
    pub contraction_ratio: f64,
    /// Wire emissivity (D.8: 0.17).
    pub wire_emissivity: f64,
    /// Martensite finish temperature, K (333).
    pub t_low: f64,
    /// Austenite finish temperature, K (363).
    pub t_high: f64,
    /// Downstroke speed v_d, m/s (0.05).
    pub downstroke_speed: f64,
    /// Stroke frequency limit, Hz (2).
    pub f_max: f64,
    /// Gravity used by the spill check; `None` = the environment's g (listing: 9.81 always, erratum 9).
    pub spill_check_g: Option<f64>,
}

/// A complete problem statement apart from the design.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub mode: PhysicsMode,
    pub environment: Environment,
    pub material: Material,
    pub collision: Collision,
    pub sim: SimSettings,
    pub performance: PerformanceParams,
    /// Effects beyond the thesis's model (issue 5), all off by default.
    #[serde(default, skip_serializing_if = "crate::model::effects::Effects::is_default")]
    pub effects: crate::model::effects::Effects,
}

impl Solid {
    /// Basalt analogue of Table 4.1.
    pub fn basalt() -> Self {
        Solid { youngs_modulus: 80e9, poisson_ratio: 0.225, strength: 224e6, density: 2850.0 }
    }
    /// Al 6061-T6 of Table 4.1.
    pub fn aluminium() -> Self {
        Solid { youngs_modulus: 68.9e9, poisson_ratio: 0.33, strength: 276e6, density: 2700.0 }
    }
}

impl Material {
    /// Lunar regolith: AOR 58° (4.1.1), loose bulk density 890 kg/m³ (D.5).
    pub fn lunar_regolith() -> Self {
        Material {
            name: "lunar-regolith".into(),
            aor_deg: 58.0,
            bulk_density: 890.0,
            particle: Solid::basalt(),
            conveyor: Solid::aluminium(),
        }
    }
    /// Quartz sand for terrestrial runs: AOR 34° (D.5). The listing keeps ρ = 890 kg/m³ for
    /// the mass flow in both environments, so the bulk density stays the regolith's.
    pub fn quartz_sand() -> Self {
        Material { name: "quartz-sand".into(), aor_deg: 34.0, ..Self::lunar_regolith() }
    }
    /// Glass beads of validation Test 3. The thesis selects "glass beads" but never prints
    /// their AOR; 24° is a typical value for dry spherical soda-lime beads (assumption).
    pub fn glass_beads() -> Self {
        Material { name: "glass-beads".into(), aor_deg: 24.0, ..Self::lunar_regolith() }
    }
    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "lunar-regolith" | "regolith" => Some(Self::lunar_regolith()),
            "quartz-sand" | "sand" => Some(Self::quartz_sand()),
            "glass-beads" | "glass" => Some(Self::glass_beads()),
            _ => None,
        }
    }
}

impl Default for SimSettings {
    fn default() -> Self {
        SimSettings {
            teeth: 100,
            particles: 100,
            max_bounces: 100,
            randomise: true,
            random_band: 0.10,
            seed: 0,
            rest_threshold: 1e-4,
            launch_offset_deg: 18.434,
            launch_points: LaunchPoints::Halton,
        }
    }
}

impl Default for PerformanceParams {
    fn default() -> Self {
        PerformanceParams {
            conveyor_length: 1.0,
            regolith_width: 0.16,
            sled_width: 0.16,
            sled_thickness: 0.005,
            sled_density: 2700.0,
            wire_force: 10.0,
            wire_diameter: 0.25e-3,
            wire_bias_stress: 100e6,
            wire_density: 6450.0,
            wire_heat_capacity: 320.0,
            wire_delta_t: 320.0,
            contraction_ratio: 0.05,
            wire_emissivity: 0.17,
            t_low: 333.0,
            t_high: 363.0,
            downstroke_speed: 0.05,
            f_max: 2.0,
            spill_check_g: None,
        }
    }
}

/// Named environments of the CLI.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum EnvPreset {
    Lunar,
    Earth,
}

impl Scenario {
    /// Listing D.5 lunar: g 1.625, vacuum, regolith AOR 58°, k_elastic 0.872, μ 0.106, α 35°.
    pub fn lunar() -> Self {
        Scenario {
            mode: PhysicsMode::Physical,
            environment: Environment { g: 1.625, alpha_deg: 35.0, k_drag: None },
            material: Material::lunar_regolith(),
            collision: Collision::thesis(0.872, 0.106),
            sim: SimSettings::default(),
            performance: PerformanceParams::default(),
            effects: Default::default(),
        }
    }

    /// Listing D.5 terrestrial: g 9.81, Stokes drag k_drag 5.439, sand AOR 34°, same coefficients.
    pub fn earth() -> Self {
        Scenario {
            environment: Environment { g: 9.81, alpha_deg: 35.0, k_drag: Some(5.439) },
            material: Material::quartz_sand(),
            ..Self::lunar()
        }
    }

    pub fn preset(p: EnvPreset) -> Self {
        match p {
            EnvPreset::Lunar => Self::lunar(),
            EnvPreset::Earth => Self::earth(),
        }
    }

    /// Switch to the listing's compatibility mode: the listing's constants where they differ
    /// from the text (erratum 13: 0.15 m regolith width; erratum 9: spill check with g = 9.81).
    pub fn into_listing_compat(mut self) -> Self {
        self.mode = PhysicsMode::Listing;
        self.performance.regolith_width = 0.15;
        self.performance.spill_check_g = Some(9.81);
        self
    }

    /// Check every number for range and finiteness; the error names the field and the rule.
    pub fn validate(&self) -> Result<(), String> {
        // every bound is declared once, in crate::schema, beside the names a user meets it by
        use crate::schema as b;
        let named = |bound: &b::Real, name: &str, v: f64| bound.check(&format!("`{name}`"), v).map(|_| ());
        let e = &self.environment;
        named(&b::ENV_G, "environment.g", e.g)?;
        named(&b::ENV_ALPHA, "environment.alpha_deg", e.alpha_deg)?;
        if let Some(k) = e.k_drag {
            named(&b::ENV_K_DRAG, "environment.k_drag", k)?;
        }
        let m = &self.material;
        named(&b::MATERIAL_AOR, "material.aor_deg", m.aor_deg)?;
        named(&b::MATERIAL_BULK_DENSITY, "material.bulk_density", m.bulk_density)?;
        for (who, s) in [("particle", &m.particle), ("conveyor", &m.conveyor)] {
            named(&b::SOLID_YOUNGS_MODULUS, &format!("material.{who}.youngs_modulus"), s.youngs_modulus)?;
            named(&b::SOLID_POISSON_RATIO, &format!("material.{who}.poisson_ratio"), s.poisson_ratio)?;
            named(&b::SOLID_STRENGTH, &format!("material.{who}.strength"), s.strength)?;
            named(&b::SOLID_DENSITY, &format!("material.{who}.density"), s.density)?;
        }
        named(&b::COLLISION_K_ELASTIC, "collision.k_elastic", self.collision.k_elastic)?;
        named(&b::COLLISION_MU_FRICTION, "collision.mu_friction", self.collision.mu_friction)?;
        if let Some(v) = self.collision.v_limit_m_s {
            named(&b::COLLISION_V_LIMIT, "collision.v_limit_m_s", v)?;
        }
        self.validate_law()?;
        let s = &self.sim;
        b::SIM_TEETH.check_u32("`sim.teeth`", s.teeth)?;
        b::SIM_PARTICLES.check_u32("`sim.particles`", s.particles)?;
        b::SIM_MAX_BOUNCES.check_u32("`sim.max_bounces`", s.max_bounces)?;
        named(&b::SIM_RANDOM_BAND, "sim.random_band", s.random_band)?;
        named(&b::SIM_REST_THRESHOLD, "sim.rest_threshold", s.rest_threshold)?;
        named(&b::SIM_LAUNCH_OFFSET, "sim.launch_offset_deg", s.launch_offset_deg)?;
        let p = &self.performance;
        // each value positive and below the bound past which it is a typo (schema::PERFORMANCE)
        for (bound, v) in [
            (&b::PERF_CONVEYOR_LENGTH, p.conveyor_length),
            (&b::PERF_REGOLITH_WIDTH, p.regolith_width),
            (&b::PERF_SLED_WIDTH, p.sled_width),
            (&b::PERF_SLED_THICKNESS, p.sled_thickness),
            (&b::PERF_SLED_DENSITY, p.sled_density),
            (&b::PERF_WIRE_FORCE, p.wire_force),
            (&b::PERF_WIRE_DIAMETER, p.wire_diameter),
            (&b::PERF_WIRE_DENSITY, p.wire_density),
            (&b::PERF_WIRE_HEAT_CAPACITY, p.wire_heat_capacity),
            (&b::PERF_WIRE_DELTA_T, p.wire_delta_t),
            (&b::PERF_CONTRACTION_RATIO, p.contraction_ratio),
            (&b::PERF_WIRE_EMISSIVITY, p.wire_emissivity),
            (&b::PERF_T_LOW, p.t_low),
            (&b::PERF_T_HIGH, p.t_high),
            (&b::PERF_DOWNSTROKE_SPEED, p.downstroke_speed),
            (&b::PERF_F_MAX, p.f_max),
        ] {
            bound.check(&format!("`{}`", bound.lib), v)?;
        }
        named(&b::PERF_WIRE_BIAS_STRESS, "performance.wire_bias_stress", p.wire_bias_stress)?;
        if p.t_high <= p.t_low {
            return Err(format!("`performance.t_high` ({}) must exceed `performance.t_low` ({})", p.t_high, p.t_low));
        }
        if let Some(g) = p.spill_check_g {
            named(&b::PERF_SPILL_CHECK_G, "performance.spill_check_g", g)?;
        }
        self.effects.validate()
    }
}

impl Scenario {
    /// The contact law's own rules: the DEM law needs its measured tangential table, runs
    /// in the physical mode only (the listing mode reproduces the thesis's published figures
    /// with the thesis's law), and the thesis's law takes no table.
    fn validate_law(&self) -> Result<(), String> {
        let c = &self.collision;
        match c.law {
            ContactLaw::Thesis if !c.tangential_ratio.is_empty() => {
                Err("`[collision] tangential_ratio` belongs to `law = \"dem\"`; the thesis's law (Eq. 4.14) takes none"
                    .into())
            }
            ContactLaw::Thesis => Ok(()),
            ContactLaw::Dem if self.mode == PhysicsMode::Listing => {
                Err("`[collision] law = \"dem\"` runs in the physical mode only (the listing mode is the thesis's law)"
                    .into())
            }
            ContactLaw::Dem => check_tangential_table(&c.tangential_ratio),
        }
    }
}
