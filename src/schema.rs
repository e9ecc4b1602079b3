//! The one declaration of every bounded input (issue 34): each count that sizes an
//! allocation or a loop, each bounded real number without a home in `Scenario::validate`,
//! and each file the project reads, with the names a user meets it by (the CLI flag, the
//! key in a config file, run.toml, plan.json or checkpoint.json, the Python argument), its
//! unit and its bounds. The CLI's value parsers, the config reader, plan, manifest and
//! checkpoint loading and the Python package all check against these constants, so a bound
//! cannot exist in one path and be missing in another. docs/reliability.md lists them (a
//! test keeps that list and this one equal).
//!
//! This module imports nothing of the crate: every layer may use it.

/// Halton points the listing samples (D.5 line 31-32: haltonset(2,'Skip',1), net(p, 2000)).
pub const LISTING_HALTON_POINTS: u64 = 2000;
/// Cap on the Halton points the physical mode draws to find n launch points in a small fill
/// (4.2.3): the loop's bound, so a particle count the fill cannot seat ends in an error.
pub const MAX_HALTON_POINTS: u64 = 20_000_000;

/// An integer input: a population, a number of runs, particles, generations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Count {
    /// The command-line flags that set it.
    pub flags: &'static [&'static str],
    /// Its keys in files (`[sim] particles` in a config; `config.pop` in run.toml and in a
    /// plan member's manifest).
    pub keys: &'static [&'static str],
    /// Its name as a Python argument, where the package takes it.
    pub python: Option<&'static str>,
    pub min: u64,
    pub max: u64,
    /// Why the upper bound is where it is (what the machine could hold, or what is a typo).
    pub why: &'static str,
}

impl Count {
    /// `v` when it lies in `[min, max]`, else the rule naming the field as the user spelled
    /// it (`spelled`: a flag, a key or an argument).
    pub fn check(&self, spelled: &str, v: u64) -> Result<u64, String> {
        if (self.min..=self.max).contains(&v) {
            Ok(v)
        } else {
            Err(format!("{spelled} {}, got {v}", self.rule()))
        }
    }

    /// The rule in words: `must lie in [4, 100000] (why)`.
    pub fn rule(&self) -> String {
        format!("must lie in [{}, {}] ({})", self.min, self.max, self.why)
    }

    /// As [`Count::check`] for a `usize`.
    pub fn check_usize(&self, spelled: &str, v: usize) -> Result<usize, String> {
        self.check(spelled, v as u64).map(|_| v)
    }

    /// As [`Count::check`] for a `u32`.
    pub fn check_u32(&self, spelled: &str, v: u32) -> Result<u32, String> {
        self.check(spelled, u64::from(v)).map(|_| v)
    }
}

/// A real input with an interval; `min_open`/`max_open`: the end itself is excluded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Real {
    /// Its name in the library (`performance.f_max`), where it has one.
    pub lib: &'static str,
    pub flags: &'static [&'static str],
    pub keys: &'static [&'static str],
    pub python: Option<&'static str>,
    pub unit: &'static str,
    pub min: f64,
    pub min_open: bool,
    pub max: f64,
    pub max_open: bool,
    pub why: &'static str,
}

impl Real {
    /// The interval in mathematical notation, `[0.001, 1000000]`, `(-90, 90)`, `[1e-15, 1000]`.
    pub fn interval(&self) -> String {
        format!(
            "{}{}, {}{}",
            if self.min_open { '(' } else { '[' },
            bound_text(self.min),
            bound_text(self.max),
            if self.max_open { ')' } else { ']' }
        )
    }

    pub fn contains(&self, v: f64) -> bool {
        let above = if self.min_open { v > self.min } else { v >= self.min };
        let below = if self.max_open { v < self.max } else { v <= self.max };
        v.is_finite() && above && below
    }

    /// `v` when finite and inside the interval, else the rule naming the field as spelled.
    pub fn check(&self, spelled: &str, v: f64) -> Result<f64, String> {
        if self.contains(v) {
            Ok(v)
        } else {
            let unit = if self.unit.is_empty() { String::new() } else { format!(" {}", self.unit) };
            Err(format!("{spelled} must lie in {}{unit} ({}), got {v:?}", self.interval(), self.why))
        }
    }
}

/// A bound as a reader writes it: plain digits from 0.001 up to ten million, powers of ten
/// beyond (`1e-15`, `1e13`), not twenty zeros.
fn bound_text(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e7) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A text field of a plan that is printed in messages and tables and copied into the Slurm
/// scripts' comments (a command, a label, a folder): one line of at most 4096 bytes, so that
/// a line break cannot start a command in a script.
pub fn one_line(field: &str, text: &str) -> Result<(), String> {
    if text.len() > 4096 || text.chars().any(char::is_control) {
        return Err(format!("{field} must be one line of at most 4096 bytes, without control characters"));
    }
    Ok(())
}

/// A file the project reads, bounded in size so that `--config /dev/zero` or a runaway
/// file is refused by name instead of read until memory runs out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileLimit {
    /// What the file is, for the message (`config file`, `measured data`).
    pub what: &'static str,
    pub flags: &'static [&'static str],
    pub max_bytes: u64,
}

const MIB: u64 = 1 << 20;

// ---- the scenario's counts (`Scenario::validate`) ----------------------------------------

pub const SIM_PARTICLES: Count = Count {
    flags: &["--particles"],
    keys: &["[sim] particles", "scenario.sim.particles"],
    python: Some("particles"),
    min: 1,
    max: 10_000_000,
    why: "the per-design particle buffers of ten million grains already take gigabytes in a batch",
};
pub const SIM_TEETH: Count = Count {
    flags: &["--teeth"],
    keys: &["[sim] teeth", "scenario.sim.teeth"],
    python: Some("teeth"),
    min: 2,
    max: 100_000,
    why: "a conveyor of more teeth is longer than any the thesis sizes",
};
pub const SIM_MAX_BOUNCES: Count = Count {
    flags: &["--bounces"],
    keys: &["[sim] max_bounces", "scenario.sim.max_bounces"],
    python: Some("max_bounces"),
    min: 1,
    max: 100_000,
    why: "a grain that has not settled after this many bounces never will",
};

// ---- the optimiser (`optimize`, `gpu-sweep`, `study`, plans, run.toml) --------------------

pub const POP: Count = Count {
    flags: &["--pop"],
    keys: &["config.pop"],
    python: None,
    min: 4,
    max: 100_000,
    why: "one generation is one engine batch of that many designs",
};
pub const GENERATIONS: Count = Count {
    flags: &["--generations"],
    keys: &["config.max_generations"],
    python: None,
    min: 0,
    max: 1_000_000,
    why: "the thesis's runs stop within 1000",
};
pub const STALL_GENERATIONS: Count = Count {
    flags: &["--stall-generations"],
    keys: &["config.mode.stall_generations"],
    python: None,
    min: 1,
    max: 1_000_000,
    why: "at most the generation bound",
};
pub const FINAL_PARTICLES: Count = Count {
    flags: &["--final-particles"],
    keys: &["final_particles"],
    python: None,
    min: 1,
    max: SIM_PARTICLES.max,
    why: "the bound of sim.particles",
};
pub const REPLICATES: Count = Count {
    flags: &["--replicates"],
    keys: &["replicates"],
    python: None,
    min: 1,
    max: 1000,
    why: "standard errors do not need more streams",
};
pub const CHECKPOINT_EVERY: Count = Count {
    flags: &["--checkpoint-every"],
    keys: &["checkpoint_every"],
    python: None,
    min: 1,
    max: GENERATIONS.max,
    why: "at most the generation bound",
};
pub const STUDY_RUNS: Count = Count {
    flags: &["--runs"],
    keys: &[],
    python: None,
    min: 2,
    max: 10_000,
    why: "each run is a member of the plan with its own folder",
};
pub const PLAN_MEMBERS: Count = Count {
    flags: &[],
    keys: &["members"],
    python: None,
    min: 1,
    max: 100_000,
    why: "each member is a run with its own folder",
};

// ---- calibration (`fit`, `diagnose`) -----------------------------------------------------

pub const FIT_POP: Count = Count {
    flags: &["--pop"],
    keys: &[],
    python: None,
    min: 5,
    max: 10_000,
    why: "differential evolution needs five members; more than this is a typo",
};
pub const FIT_GENERATIONS: Count = Count {
    flags: &["--generations"],
    keys: &[],
    python: None,
    min: 0,
    max: 100_000,
    why: "the calibration converges within a few hundred",
};
pub const FIT_POLISH: Count = Count {
    flags: &["--polish"],
    keys: &[],
    python: None,
    min: 0,
    max: 100_000,
    why: "the compass search converges within a few hundred",
};
pub const FIT_PARTICLES: Count = Count {
    flags: &["--particles"],
    keys: &[],
    python: None,
    min: 1,
    max: SIM_PARTICLES.max,
    why: "the bound of sim.particles",
};
pub const FIT_MAX_PARTICLES: Count = Count {
    flags: &["--max-particles"],
    keys: &[],
    python: None,
    min: 1000,
    max: SIM_PARTICLES.max,
    why: "the bound of sim.particles",
};

pub const FIT_BOOTSTRAP: Count = Count {
    flags: &["--bootstrap"],
    keys: &[],
    python: None,
    min: 0,
    max: 10_000,
    why: "each replicate is a whole refit of the model; 0 switches the bootstrap off",
};
pub const DIAGNOSE_BOOTSTRAP: Count = Count {
    flags: &["--bootstrap"],
    keys: &[],
    python: None,
    min: 2,
    max: 100_000,
    why: "each replicate resamples the runs' gaps without simulating; two make an interval",
};
pub const RESCORE_STREAMS: Count = Count {
    flags: &["--rescore-streams"],
    keys: &[],
    python: None,
    min: 1,
    max: 1000,
    why: "each stream re-simulates every candidate once more; standard errors need no more",
};
pub const ALPHA_POINTS: Count = Count {
    flags: &["--alpha-points"],
    keys: &[],
    python: None,
    min: 2,
    max: 41,
    why: "one point per degree over the thesis's 0-40 degree slope range",
};

// ---- `dem` ---------------------------------------------------------------------------------

pub const DEM_RUNS: Count = Count {
    flags: &["--runs"],
    keys: &["runs"],
    python: None,
    min: 1,
    max: 10_000,
    why: "each run is a LIGGGHTS simulation of minutes with its own folder",
};
pub const DEM_SEEDS: Count = Count {
    flags: &["--seeds"],
    keys: &["seeds"],
    python: None,
    min: 1,
    max: 1000,
    why: "each seed is a LIGGGHTS run of every checked design",
};
pub const DEM_FRONT: Count = Count {
    flags: &["--front"],
    keys: &[],
    python: None,
    min: 0,
    max: 100,
    why: "each front design is a DEM campaign of --seeds runs; a hundred cover any front",
};
pub const DEM_DESIGNS: Count = Count {
    flags: &["--designs"],
    keys: &[],
    python: None,
    min: 1,
    max: 100,
    why: "each design is a DEM campaign of --seeds runs; a hundred fill the eight-variable space",
};
pub const JOBS: Count = Count {
    flags: &["--jobs"],
    keys: &[],
    python: None,
    min: 1,
    max: 4096,
    why: "LIGGGHTS processes at a time; more than any machine has cores",
};
pub const DEM_PARTICLES: Count = Count {
    flags: &["--particles", "--draw-particles"],
    keys: &["[dem] particles"],
    python: None,
    min: 1,
    max: 200_000,
    why: "a serial LIGGGHTS stroke of more grains takes days",
};
pub const DEM_TEETH: Count = Count {
    flags: &[],
    keys: &["[dem] teeth"],
    python: None,
    min: 2,
    max: 1000,
    why: "the mesh holds a facet row per tooth; a longer slab is a typo",
};

// ---- `campaign slurm` ----------------------------------------------------------------------

pub const SLURM_CPUS_PER_TASK: Count = Count {
    flags: &["--cpus-per-task"],
    keys: &[],
    python: None,
    min: 1,
    max: 4096,
    why: "more cores than any node has",
};
pub const SLURM_GPUS_PER_TASK: Count =
    Count { flags: &["--gpus-per-task"], keys: &[], python: None, min: 1, max: 64, why: "more GPUs than any node has" };
pub const SLURM_MAX_PARALLEL: Count = Count {
    flags: &["--max-parallel"],
    keys: &[],
    python: None,
    min: 1,
    max: PLAN_MEMBERS.max,
    why: "at most one task per member",
};

// ---- `synth`, `bench`, `conformance` -----------------------------------------------------

pub const SYNTH_RUNS: Count = Count {
    flags: &["--runs"],
    keys: &[],
    python: None,
    min: 1,
    max: 10_000,
    why: "each run is one simulation of the setup and one row set of the output",
};
pub const SYNTH_PARTICLES: Count = Count {
    flags: &["--particles"],
    keys: &[],
    python: None,
    min: 1,
    max: SIM_PARTICLES.max,
    why: "the bound of sim.particles",
};
pub const BENCH_DESIGNS: Count = Count {
    flags: &["--designs"],
    keys: &[],
    python: None,
    min: 1,
    max: 100_000,
    why: "one batch of that many designs; the optimiser's batches are smaller",
};
pub const BENCH_REPEATS: Count = Count {
    flags: &["--repeats"],
    keys: &[],
    python: None,
    min: 1,
    max: 1000,
    why: "the best of a thousand repeats is as good as it gets",
};
pub const CONFORMANCE_DESIGNS: Count = Count {
    flags: &["--designs"],
    keys: &[],
    python: None,
    min: 1,
    max: 10_000,
    why: "each design is simulated on both engines, particle by particle",
};

// ---- the scenario's reals (`Scenario::validate`: every path, CLI, config, run.toml, plan
// member and Python, builds a Scenario and validates it) -----------------------------------

pub const ENV_G: Real = Real {
    lib: "environment.g",
    flags: &[],
    keys: &["[environment] g_m_s2"],
    python: None,
    unit: "m/s^2",
    min: 0.001,
    min_open: false,
    max: 100.0,
    max_open: false,
    why: "from below the surface gravity of Phobos (0.0057 m/s^2) to ten times the Earth's: the bodies with regolith to move",
};
pub const ENV_ALPHA: Real = Real {
    lib: "environment.alpha_deg",
    flags: &["--alpha"],
    keys: &["[environment] alpha_deg"],
    python: Some("alpha_deg"),
    unit: "degrees",
    min: 0.0,
    min_open: false,
    max: 80.0,
    max_open: false,
    why: "a steeper conveyor is a wall; the thesis sizes 0-40 degrees",
};
pub const ENV_K_DRAG: Real = Real {
    lib: "environment.k_drag",
    flags: &["--k-drag"],
    keys: &["[environment] k_drag_per_s"],
    python: Some("k_drag_per_s"),
    unit: "1/s",
    min: 1e-4,
    min_open: false,
    max: 10000.0,
    max_open: false,
    why: "below 1e-4 1/s drag changes a second's flight by less than 0.01 % and the Stokes closed form (Eq. 4.55) loses its digits (k_drag 1e-9 moves lunar C's d_avg by 7 %); 0 in a file or flag means vacuum; 10^4 1/s stops a grain within microns",
};
pub const MATERIAL_AOR: Real = Real {
    lib: "material.aor_deg",
    flags: &["--aor"],
    keys: &["[material] aor_deg"],
    python: Some("aor_deg"),
    unit: "degrees",
    min: 0.0,
    min_open: false,
    max: 89.0,
    max_open: false,
    why: "an angle of repose is below vertical",
};
pub const MATERIAL_BULK_DENSITY: Real = Real {
    lib: "material.bulk_density",
    flags: &[],
    keys: &["[material] bulk_density_kg_m3"],
    python: None,
    unit: "kg/m^3",
    min: 1.0,
    min_open: false,
    max: 25000.0,
    max_open: false,
    why: "a bulk lighter than air (1.2 kg/m^3) is no solid; denser than osmium is a typo",
};
pub const SOLID_YOUNGS_MODULUS: Real = Real {
    lib: "material.particle.youngs_modulus",
    flags: &[],
    keys: &["material.particle.youngs_modulus", "material.conveyor.youngs_modulus"],
    python: None,
    unit: "Pa",
    min: 1e3,
    min_open: false,
    max: 1e13,
    max_open: false,
    why: "softer than a gel (1 kPa) is no grain or conveyor; stiffer than diamond is a typo",
};
pub const SOLID_POISSON_RATIO: Real = Real {
    lib: "material.particle.poisson_ratio",
    flags: &[],
    keys: &["material.particle.poisson_ratio", "material.conveyor.poisson_ratio"],
    python: None,
    unit: "",
    min: -1.0,
    min_open: false,
    max: 0.5,
    max_open: false,
    why: "the thermodynamic bounds of an isotropic solid",
};
pub const SOLID_STRENGTH: Real = Real {
    lib: "material.particle.strength",
    flags: &[],
    keys: &["material.particle.strength", "material.conveyor.strength"],
    python: None,
    unit: "Pa",
    min: 1e3,
    min_open: false,
    max: 1e12,
    max_open: false,
    why: "weaker than a gel (1 kPa) is no solid; stronger than any solid is a typo",
};
pub const SOLID_DENSITY: Real = Real {
    lib: "material.particle.density",
    flags: &[],
    keys: &["material.particle.density", "material.conveyor.density"],
    python: None,
    unit: "kg/m^3",
    min: 1.0,
    min_open: false,
    max: 25000.0,
    max_open: false,
    why: "a solid lighter than air (1.2 kg/m^3) does not exist; denser than osmium is a typo",
};
pub const COLLISION_K_ELASTIC: Real = Real {
    lib: "collision.k_elastic",
    flags: &["--k-elastic"],
    keys: &["[collision] k_elastic"],
    python: Some("k_elastic"),
    unit: "",
    min: 0.0,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "a bounce keeps at most all of its normal speed (Eq. 4.31)",
};
pub const COLLISION_MU_FRICTION: Real = Real {
    lib: "collision.mu_friction",
    flags: &["--mu-fric"],
    keys: &["[collision] mu_friction"],
    python: Some("mu_fric"),
    unit: "",
    min: 0.0,
    min_open: false,
    max: 10.0,
    max_open: false,
    why: "a friction coefficient beyond 10 is a typo (Eq. 4.32)",
};
pub const COLLISION_V_LIMIT: Real = Real {
    lib: "collision.v_limit_m_s",
    flags: &[],
    keys: &["[collision] v_limit_m_s"],
    python: None,
    unit: "m/s",
    min: 1e-6,
    min_open: false,
    max: 100.0,
    max_open: false,
    why: "from a micrometre a second (a law plastic at every impact) to beyond any impact on the conveyor (one constant COR); Eq. 4.7 gives 0.0135 m/s for lunar regolith",
};
pub const SIM_RANDOM_BAND: Real = Real {
    lib: "sim.random_band",
    flags: &[],
    keys: &["[sim] random_band"],
    python: None,
    unit: "",
    min: 0.0,
    min_open: false,
    max: 0.9,
    max_open: false,
    why: "the randomised share of a bounce keeps a tenth deterministic",
};
pub const SIM_REST_THRESHOLD: Real = Real {
    lib: "sim.rest_threshold",
    flags: &[],
    keys: &["[sim] rest_threshold_m"],
    python: None,
    unit: "m",
    min: 0.0,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "a grain hopping less than a metre per bounce is at rest for any threshold up to this",
};
pub const SIM_LAUNCH_OFFSET: Real = Real {
    lib: "sim.launch_offset_deg",
    flags: &["--launch-offset"],
    keys: &["[sim] launch_offset_deg"],
    python: Some("launch_offset_deg"),
    unit: "degrees",
    min: -90.0,
    min_open: false,
    max: 90.0,
    max_open: false,
    why: "a launch within the half-plane above the tooth face",
};
pub const MOTION_DELAY: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[measurement] motion_delay_s"],
    python: None,
    unit: "s",
    min: 0.0,
    min_open: false,
    max: 100.0,
    max_open: false,
    why: "the bound of the sled-motion effect's delay",
};
pub const MOTION_RETURN_SPEED: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[measurement] motion_return_speed_m_s"],
    python: None,
    unit: "m/s",
    min: 1e-6,
    min_open: false,
    max: 10.0,
    max_open: false,
    why: "the bound of the sled-motion effect's return speed",
};

// ---- the optimiser's settings (`optimize` flags and run.toml's `config`) ---------------------

pub const OPT_TOL: Real = Real {
    lib: "",
    flags: &["--tol"],
    keys: &["config.mode.tol"],
    python: None,
    unit: "",
    min: 1e-12,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "below 1e-12 the spread changes by less than its rounding, so no run would stall; at 1 every generation already counts as a stall",
};
pub const PARETO_FRACTION: Real = Real {
    lib: "",
    flags: &[],
    keys: &["config.mode.pareto_fraction"],
    python: None,
    unit: "",
    min: 1e-5,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "a share of the population: from one member of the largest (100 000) to all",
};
pub const CROSSOVER_PROB: Real = Real {
    lib: "",
    flags: &[],
    keys: &["config.crossover_prob"],
    python: None,
    unit: "",
    min: 0.0,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "a probability",
};
pub const DISTRIBUTION_INDEX: Real = Real {
    lib: "",
    flags: &[],
    keys: &["config.crossover_eta", "config.mutation_eta"],
    python: None,
    unit: "",
    min: 0.0,
    min_open: false,
    max: 1000000.0,
    max_open: false,
    why: "an SBX or polynomial-mutation index beyond 10^6 makes every child its parent",
};

// ---- bounded reals -----------------------------------------------------------------------

pub const SYNTH_MASS_G: Real = Real {
    lib: "",
    flags: &["--mass-g"],
    keys: &[],
    python: None,
    unit: "g",
    min: 1e-3,
    min_open: false,
    max: 1e6,
    max_open: false,
    why: "from a milligram, below any laboratory test's load, to a tonne of regolith, beyond any",
};

/// The `[performance]` table's values (Eq. 4.45-4.60, D.7-D.8): positive and below a bound
/// past which a value is a typo that makes `n_wire` overflow or the mass flow infinite.
pub const PERF_CONVEYOR_LENGTH: Real = Real {
    lib: "performance.conveyor_length",
    flags: &[],
    keys: &["[performance] conveyor_length_m"],
    python: None,
    unit: "m",
    min: 0.01,
    min_open: false,
    max: 1000.0,
    max_open: false,
    why: "a conveyor shorter than a centimetre holds no tooth; beyond a kilometre is a typo, and makes the wire count overflow",
};
pub const PERF_REGOLITH_WIDTH: Real = Real {
    lib: "performance.regolith_width",
    flags: &[],
    keys: &["[performance] regolith_width_m"],
    python: None,
    unit: "m",
    min: 1e-3,
    min_open: false,
    max: 100.0,
    max_open: false,
    why: "a bed narrower than a millimetre is no bed of grains; wider than 100 m is a typo",
};
pub const PERF_SLED_WIDTH: Real = Real {
    lib: "performance.sled_width",
    flags: &[],
    keys: &["[performance] sled_width_m"],
    python: None,
    unit: "m",
    min: 1e-3,
    min_open: false,
    max: 100.0,
    max_open: false,
    why: "a sled narrower than a millimetre carries no bed; wider than 100 m is a typo",
};
pub const PERF_SLED_THICKNESS: Real = Real {
    lib: "performance.sled_thickness",
    flags: &[],
    keys: &["[performance] sled_thickness_m"],
    python: None,
    unit: "m",
    min: 1e-5,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "a plate thinner than 10 um is a foil; thicker than a metre is a typo",
};
pub const PERF_SLED_DENSITY: Real = Real {
    lib: "performance.sled_density",
    flags: &[],
    keys: &["[performance] sled_density_kg_m3"],
    python: None,
    unit: "kg/m^3",
    min: 1.0,
    min_open: false,
    max: 100000.0,
    max_open: false,
    why: "a solid lighter than air does not exist; denser than any solid is a typo",
};
pub const PERF_WIRE_FORCE: Real = Real {
    lib: "performance.wire_force",
    flags: &[],
    keys: &["scenario.performance.wire_force"],
    python: None,
    unit: "N",
    min: 1e-3,
    min_open: false,
    max: 1000000.0,
    max_open: false,
    why: "a wire pulling less than a millinewton moves no sled; beyond any shape-memory wire",
};
pub const PERF_WIRE_DIAMETER: Real = Real {
    lib: "performance.wire_diameter",
    flags: &[],
    keys: &["scenario.performance.wire_diameter"],
    python: None,
    unit: "m",
    min: 1e-6,
    min_open: false,
    max: 0.1,
    max_open: false,
    why: "a wire thinner than a micrometre is not drawn; thicker than 10 cm is a typo",
};
pub const PERF_WIRE_DENSITY: Real = Real {
    lib: "performance.wire_density",
    flags: &[],
    keys: &["scenario.performance.wire_density"],
    python: None,
    unit: "kg/m^3",
    min: 1.0,
    min_open: false,
    max: 100000.0,
    max_open: false,
    why: "a solid lighter than air does not exist; denser than any solid is a typo",
};
pub const PERF_WIRE_HEAT_CAPACITY: Real = Real {
    lib: "performance.wire_heat_capacity",
    flags: &[],
    keys: &["scenario.performance.wire_heat_capacity"],
    python: None,
    unit: "J/(kg K)",
    min: 1.0,
    min_open: false,
    max: 100000.0,
    max_open: false,
    why: "below 1 J/(kg K) no solid stores heat near room temperature; beyond any solid's",
};
pub const PERF_WIRE_DELTA_T: Real = Real {
    lib: "performance.wire_delta_t",
    flags: &[],
    keys: &["scenario.performance.wire_delta_t"],
    python: None,
    unit: "K",
    min: 0.01,
    min_open: false,
    max: 10000.0,
    max_open: false,
    why: "a transformation within a hundredth of a kelvin is no shape-memory cycle; beyond any wire's melting point",
};
pub const PERF_CONTRACTION_RATIO: Real = Real {
    lib: "performance.contraction_ratio",
    flags: &[],
    keys: &["[performance] contraction_ratio"],
    python: None,
    unit: "",
    min: 1e-4,
    min_open: false,
    max: 1.0,
    max_open: true,
    why: "a strain below 0.01 % moves no sled; a contracting wire's strain lies below 1",
};
pub const PERF_WIRE_EMISSIVITY: Real = Real {
    lib: "performance.wire_emissivity",
    flags: &[],
    keys: &["scenario.performance.wire_emissivity"],
    python: None,
    unit: "",
    min: 1e-3,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "an emissivity lies in (0, 1]; below 0.001 is a mirror no wire is",
};
pub const PERF_T_LOW: Real = Real {
    lib: "performance.t_low",
    flags: &[],
    keys: &["scenario.performance.t_low"],
    python: None,
    unit: "K",
    min: 1.0,
    min_open: false,
    max: 10000.0,
    max_open: false,
    why: "a temperature below 1 K is no wire's; beyond any wire's melting point",
};
pub const PERF_T_HIGH: Real = Real {
    lib: "performance.t_high",
    flags: &[],
    keys: &["scenario.performance.t_high"],
    python: None,
    unit: "K",
    min: 1.0,
    min_open: false,
    max: 10000.0,
    max_open: false,
    why: "a temperature below 1 K is no wire's; beyond any wire's melting point",
};
pub const PERF_DOWNSTROKE_SPEED: Real = Real {
    lib: "performance.downstroke_speed",
    flags: &[],
    keys: &["[performance] downstroke_speed_m_s"],
    python: None,
    unit: "m/s",
    min: 1e-4,
    min_open: false,
    max: 1000.0,
    max_open: false,
    why: "slower than 0.1 mm/s a downstroke takes hours; faster than sound is a typo",
};
pub const PERF_F_MAX: Real = Real {
    lib: "performance.f_max",
    flags: &[],
    keys: &["[performance] f_max_hz"],
    python: None,
    unit: "Hz",
    min: 1e-4,
    min_open: false,
    max: 10000.0,
    max_open: false,
    why: "below one stroke in three hours no conveyor runs; beyond any wire's cycling rate",
};
pub const PERF_WIRE_BIAS_STRESS: Real = Real {
    lib: "performance.wire_bias_stress",
    flags: &[],
    keys: &["scenario.performance.wire_bias_stress"],
    python: None,
    unit: "Pa",
    min: 0.0,
    min_open: false,
    max: 1e10,
    max_open: false,
    why: "a bias stress lies between none and beyond any wire's strength (10 GPa)",
};
pub const PERF_SPILL_CHECK_G: Real = Real {
    lib: "performance.spill_check_g",
    flags: &[],
    keys: &["scenario.performance.spill_check_g"],
    python: None,
    unit: "m/s^2",
    min: 0.001,
    min_open: false,
    max: 100.0,
    max_open: false,
    why: "the gravity of the listing's spill check (erratum 9): the bounds of environment.g",
};

/// Every `[performance]` bound, in the order `Scenario::validate` checks them.
pub const PERFORMANCE: &[&Real] = &[
    &PERF_CONVEYOR_LENGTH,
    &PERF_REGOLITH_WIDTH,
    &PERF_SLED_WIDTH,
    &PERF_SLED_THICKNESS,
    &PERF_SLED_DENSITY,
    &PERF_WIRE_FORCE,
    &PERF_WIRE_DIAMETER,
    &PERF_WIRE_DENSITY,
    &PERF_WIRE_HEAT_CAPACITY,
    &PERF_WIRE_DELTA_T,
    &PERF_CONTRACTION_RATIO,
    &PERF_WIRE_EMISSIVITY,
    &PERF_T_LOW,
    &PERF_T_HIGH,
    &PERF_DOWNSTROKE_SPEED,
    &PERF_F_MAX,
    &PERF_WIRE_BIAS_STRESS,
    &PERF_SPILL_CHECK_G,
];

/// Recovered over loaded mass of one measured run (`input_mass` against the teeth's sum):
/// real runs exceed 1 a little (Test 3's run 7 recovers 2.05 g of 2.02 g: grains left from
/// the previous run, the scale), `synth` draws recoveries up to this bound; beyond it the
/// column is not the loaded mass.
pub const RECOVERY: Real = Real {
    lib: "",
    flags: &[],
    keys: &["input_mass (against the teeth's sum)"],
    python: None,
    unit: "",
    min: 0.0,
    min_open: false,
    max: 1.5,
    max_open: false,
    why: "a run recovers at most half again what was loaded",
};

// ---- a design (CLI units: `--design`, `[design]`), a setup's `[measurement]`, `study`,
// `[requirements]` ------------------------------------------------------------------------

const TOOTH_LENGTH_WHY: &str =
    "a tooth feature under a tenth of a millimetre is finer than the grains it carries; one beyond a metre is no sawtooth";

/// The eight design variables in the units users write them (`Design::check_sensible`):
/// what a sawtooth can be, far beyond the optimiser's bounds (Table 5.1, erratum 2), short of
/// values no conveyor has. Signs, the chain l_b <= r <= l_a <= l_c and the constraints of
/// 5.2 are the model's (`model::geometry::check_design`).
pub const DESIGN: [Real; 8] = [
    design_length("design.l_c", &["[design] l_c_mm"]),
    design_length("design.l_a", &["[design] l_a_mm"]),
    design_length("design.l_b", &["[design] l_b_mm"]),
    design_length("design.r", &["[design] r_mm"]),
    Real {
        lib: "design.omega_deg",
        flags: &["--design"],
        keys: &["[design] omega_deg"],
        python: None,
        unit: "degrees",
        min: 1.0,
        min_open: false,
        max: 179.0,
        max_open: false,
        why: "a catch arc meeting its base within a degree of flat is no catch",
    },
    Real {
        lib: "design.delta_deg",
        flags: &["--design"],
        keys: &["[design] delta_deg"],
        python: None,
        unit: "degrees",
        min: -90.0,
        min_open: true,
        max: 90.0,
        max_open: true,
        why: "the offset added to the launch angle alpha + launch offset (D.1 line 35) turns it less than a right angle either way; 0 is Table 5.1's lower bound",
    },
    Real {
        lib: "design.v0",
        flags: &["--design"],
        keys: &["[design] v0_m_s"],
        python: None,
        unit: "m/s",
        min: 0.01,
        min_open: false,
        max: 100.0,
        max_open: false,
        why: "a launch slower than 1 cm/s rises less than 31 um on the Moon (v0^2/2g), less than a grain; faster than 100 m/s is no sled",
    },
    Real {
        lib: "design.a",
        flags: &["--design"],
        keys: &["[design] a_m_s2"],
        python: None,
        unit: "m/s^2",
        min: 0.01,
        min_open: false,
        max: 10000.0,
        max_open: false,
        why: "a sled accelerating at less than 0.01 m/s^2 needs over a minute to reach the optimiser's slowest launch (0.8 m/s); beyond 10^4 m/s^2 (1000 g) is no conveyor",
    },
];

const fn design_length(lib: &'static str, keys: &'static [&'static str]) -> Real {
    Real {
        lib,
        flags: &["--design"],
        keys,
        python: None,
        unit: "mm",
        min: 0.1,
        min_open: false,
        max: 1000.0,
        max_open: false,
        why: TOOTH_LENGTH_WHY,
    }
}

pub const SCALE_RESOLUTION_G: Real = Real {
    lib: "",
    flags: &["--resolution-g"],
    keys: &["[measurement] scale_resolution_g"],
    python: None,
    unit: "g",
    min: 1e-15,
    min_open: false,
    max: 1000.0,
    max_open: false,
    why: "from the femtogram of one micrometre grain (the DEM's smallest, whose setup states one grain as the resolution) to a kilogram, which weighs no tooth",
};
pub const HANDLING_LOSS_MAX: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[measurement] handling_loss_max"],
    python: None,
    unit: "",
    min: 0.0,
    min_open: false,
    max: 1.0,
    max_open: false,
    why: "a share of the loaded mass: none (a DEM campaign, whose every lost grain is physics) to all of it",
};
pub const PARTICLE_MASS_G: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[measurement] particle_mass_g"],
    python: None,
    unit: "g",
    min: 1e-12,
    min_open: false,
    max: 1e6,
    max_open: false,
    why: "the mass loaded per run: from a few micrometre grains to a tonne, beyond any rig",
};
pub const TARGET_MASS_FLOW: Real = Real {
    lib: "",
    flags: &["--target-mass-flow"],
    keys: &["study.target_mass_flow"],
    python: None,
    unit: "kg/s",
    min: 1e-6,
    min_open: false,
    max: 100.0,
    max_open: false,
    why: "from a few grams an hour to 360 t/h, beyond any regolith conveyor (Table 2.2 asks 6-48 kg/h)",
};
pub const REQ_FEED_RATE: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[requirements] feed_rate_min_kg_h", "[requirements] feed_rate_target_kg_h"],
    python: None,
    unit: "kg/h",
    min: 1e-3,
    min_open: false,
    max: 1e6,
    max_open: false,
    why: "from a gram an hour to a thousand tonnes an hour (Table 2.2: 6-48 kg/h)",
};
pub const REQ_POWER: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[requirements] power_max_w"],
    python: None,
    unit: "W",
    min: 1e-3,
    min_open: false,
    max: 1e6,
    max_open: false,
    why: "from a milliwatt to a megawatt (Table 2.2: 5 W)",
};
pub const REQ_TRANSPORT_LENGTH: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[requirements] transport_length_m"],
    python: None,
    unit: "m",
    min: 0.01,
    min_open: false,
    max: 1000.0,
    max_open: false,
    why: "the bounds of a conveyor's length (performance.conveyor_length)",
};
pub const REQ_SLOPE: Real = Real {
    lib: "",
    flags: &[],
    keys: &["[requirements] slope_min_deg", "[requirements] slope_max_deg"],
    python: None,
    unit: "degrees",
    min: 0.0,
    min_open: false,
    max: 80.0,
    max_open: false,
    why: "the bounds of environment.alpha_deg",
};

// ---- files -------------------------------------------------------------------------------

pub const CONFIG_FILE: FileLimit =
    FileLimit { what: "config file", flags: &["--config", "--setup", "--requirements"], max_bytes: 4 * MIB };
pub const MEASURED_FILE: FileLimit = FileLimit { what: "measured data", flags: &["--data"], max_bytes: 64 * MIB };
pub const MANIFEST_FILE: FileLimit = FileLimit { what: "run manifest (run.toml)", flags: &[], max_bytes: 4 * MIB };
pub const PLAN_FILE: FileLimit = FileLimit { what: "campaign plan (plan.json)", flags: &[], max_bytes: 256 * MIB };
/// A checkpoint of the largest population (100 000 members of ~0.5 kB) fits well within.
pub const CHECKPOINT_FILE: FileLimit = FileLimit { what: "checkpoint", flags: &[], max_bytes: 512 * MIB };
/// A front of the largest population: 100 000 rows of ~600 bytes.
pub const PARETO_FILE: FileLimit = FileLimit { what: "front (pareto.csv)", flags: &[], max_bytes: 256 * MIB };
/// A run's every evaluation, ~300 bytes a row: over ten million rows.
pub const EVALUATIONS_FILE: FileLimit =
    FileLimit { what: "evaluation log (evaluations.csv)", flags: &[], max_bytes: 4096 * MIB };
/// One row of ~150 bytes per generation, at most a million generations.
pub const GENERATIONS_FILE: FileLimit =
    FileLimit { what: "generation log (generations.csv)", flags: &[], max_bytes: 256 * MIB };
/// A study's summary: a few rows per metric.
pub const SUMMARY_FILE: FileLimit =
    FileLimit { what: "study summary (summary.csv)", flags: &["--repeatability"], max_bytes: 16 * MIB };
/// One DEM run's result: tooth masses of at most 1000 teeth and the settled bed's positions
/// (two numbers of ~25 bytes pretty-printed for each of at most 200 000 grains).
pub const DEM_RESULT_FILE: FileLimit = FileLimit { what: "DEM result (result.json)", flags: &[], max_bytes: 32 * MIB };
/// The engine's end positions: at most 200 000 grains of ~250 bytes.
pub const DEM_DUMP_FILE: FileLimit = FileLimit { what: "DEM dump (final.dump)", flags: &[], max_bytes: 128 * MIB };
/// One number: the stroke time at which a DEM run ended.
pub const DEM_STROKE_TIME_FILE: FileLimit =
    FileLimit { what: "DEM stroke time (stroke_time.txt)", flags: &[], max_bytes: MIB };
/// One whole number: the LIGGGHTS step at which a DEM run's stroke began.
pub const DEM_STROKE_START_FILE: FileLimit =
    FileLimit { what: "DEM stroke start (stroke_start.txt)", flags: &[], max_bytes: MIB };
/// Every grain's position and velocity at every rest check of one DEM run, read line by line;
/// a case whose track would be larger writes none (`dem::case::Case::tracked`).
pub const DEM_TRACK_FILE: FileLimit = FileLimit { what: "DEM track (track.dump)", flags: &[], max_bytes: 256 * MIB };
/// A DEM campaign's convergence ladder: at most three levels of a few numbers each.
pub const DEM_REFINE_FILE: FileLimit = FileLimit { what: "DEM refinement (refine.json)", flags: &[], max_bytes: MIB };
/// A folder's marker: a few lines and the names of the files its run wrote.
pub const MARKER_FILE_LIMIT: FileLimit =
    FileLimit { what: "folder marker (.sawtooth-run)", flags: &[], max_bytes: MIB };
/// The job ids of a campaign's last Slurm submission.
pub const SUBMISSION_FILE: FileLimit =
    FileLimit { what: "Slurm submission record (slurm/last-submit)", flags: &[], max_bytes: MIB };

/// Every declared count, for the documentation and its test.
pub const COUNTS: &[&Count] = &[
    &SIM_PARTICLES,
    &SIM_TEETH,
    &SIM_MAX_BOUNCES,
    &POP,
    &GENERATIONS,
    &STALL_GENERATIONS,
    &FINAL_PARTICLES,
    &REPLICATES,
    &CHECKPOINT_EVERY,
    &STUDY_RUNS,
    &PLAN_MEMBERS,
    &FIT_POP,
    &FIT_GENERATIONS,
    &FIT_POLISH,
    &FIT_PARTICLES,
    &FIT_MAX_PARTICLES,
    &SYNTH_RUNS,
    &SYNTH_PARTICLES,
    &BENCH_DESIGNS,
    &BENCH_REPEATS,
    &CONFORMANCE_DESIGNS,
    &FIT_BOOTSTRAP,
    &DIAGNOSE_BOOTSTRAP,
    &RESCORE_STREAMS,
    &ALPHA_POINTS,
    &DEM_RUNS,
    &DEM_SEEDS,
    &DEM_FRONT,
    &DEM_DESIGNS,
    &JOBS,
    &SLURM_CPUS_PER_TASK,
    &SLURM_GPUS_PER_TASK,
    &SLURM_MAX_PARALLEL,
    &DEM_PARTICLES,
    &DEM_TEETH,
];

/// Every declared real interval.
pub const REALS: &[&Real] = &[
    &DESIGN[0],
    &DESIGN[1],
    &DESIGN[2],
    &DESIGN[3],
    &DESIGN[4],
    &DESIGN[5],
    &DESIGN[6],
    &DESIGN[7],
    &SCALE_RESOLUTION_G,
    &PARTICLE_MASS_G,
    &HANDLING_LOSS_MAX,
    &TARGET_MASS_FLOW,
    &REQ_FEED_RATE,
    &REQ_POWER,
    &REQ_TRANSPORT_LENGTH,
    &REQ_SLOPE,
    &PERF_WIRE_BIAS_STRESS,
    &PERF_SPILL_CHECK_G,
    &SYNTH_MASS_G,
    &RECOVERY,
    &PERF_CONVEYOR_LENGTH,
    &PERF_REGOLITH_WIDTH,
    &PERF_SLED_WIDTH,
    &PERF_SLED_THICKNESS,
    &PERF_SLED_DENSITY,
    &PERF_WIRE_FORCE,
    &PERF_WIRE_DIAMETER,
    &PERF_WIRE_DENSITY,
    &PERF_WIRE_HEAT_CAPACITY,
    &PERF_WIRE_DELTA_T,
    &PERF_CONTRACTION_RATIO,
    &PERF_WIRE_EMISSIVITY,
    &PERF_T_LOW,
    &PERF_T_HIGH,
    &PERF_DOWNSTROKE_SPEED,
    &PERF_F_MAX,
    &ENV_G,
    &ENV_ALPHA,
    &ENV_K_DRAG,
    &MATERIAL_AOR,
    &MATERIAL_BULK_DENSITY,
    &SOLID_YOUNGS_MODULUS,
    &SOLID_POISSON_RATIO,
    &SOLID_STRENGTH,
    &SOLID_DENSITY,
    &COLLISION_K_ELASTIC,
    &COLLISION_MU_FRICTION,
    &COLLISION_V_LIMIT,
    &SIM_RANDOM_BAND,
    &SIM_REST_THRESHOLD,
    &SIM_LAUNCH_OFFSET,
    &MOTION_DELAY,
    &MOTION_RETURN_SPEED,
    &OPT_TOL,
    &PARETO_FRACTION,
    &CROSSOVER_PROB,
    &DISTRIBUTION_INDEX,
];

/// Every declared file limit.
pub const FILES: &[&FileLimit] = &[
    &CONFIG_FILE,
    &MEASURED_FILE,
    &MANIFEST_FILE,
    &PLAN_FILE,
    &CHECKPOINT_FILE,
    &PARETO_FILE,
    &EVALUATIONS_FILE,
    &GENERATIONS_FILE,
    &SUMMARY_FILE,
    &DEM_RESULT_FILE,
    &DEM_DUMP_FILE,
    &DEM_STROKE_TIME_FILE,
    &DEM_STROKE_START_FILE,
    &DEM_TRACK_FILE,
    &DEM_REFINE_FILE,
    &MARKER_FILE_LIMIT,
    &SUBMISSION_FILE,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_count_outside_its_bounds_is_refused_naming_the_field_and_the_rule() {
        assert_eq!(POP.check("--pop", 4), Ok(4));
        let e = POP.check("--pop", 1_000_000_000).unwrap_err();
        assert!(e.starts_with("--pop must lie in [4, 100000]"), "{e}");
        assert!(e.ends_with("got 1000000000"), "{e}");
        assert!(STUDY_RUNS.check_u32("--runs", u32::MAX).is_err());
    }

    #[test]
    fn a_real_outside_its_interval_or_not_finite_is_refused() {
        assert!(PERF_CONTRACTION_RATIO.check("x", 0.5).is_ok());
        for bad in [0.0, 1.0, 2.0, f64::NAN, f64::INFINITY] {
            let e = PERF_CONTRACTION_RATIO.check("`[performance] contraction_ratio`", bad).unwrap_err();
            assert!(e.contains("must lie in [1e-4, 1)"), "{e}");
        }
        assert!(SYNTH_MASS_G.check("--mass-g", 1e308).unwrap_err().contains("[0.001, 1000000] g"));
        // issue 45: an open bound at 0 let 1e-300 through; each bound is now the least physical value
        assert!(ENV_G.check("g", 1e-300).unwrap_err().contains("g must lie in [0.001, 100] m/s^2"));
        assert!(MATERIAL_BULK_DENSITY.check("rho", 1e-300).is_err());
        for p in PERFORMANCE {
            assert!(p.check("x", 1e-300).is_err() || p.min == 0.0, "{p:?}");
            assert!(p.check("x", 1e308).is_err(), "{p:?}");
        }
    }

    /// docs/reliability.md lists every declared bound: each name a user meets it by, and
    /// its interval, so the documentation cannot keep a bound the code has moved.
    #[test]
    fn the_documentation_lists_every_bound() {
        let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/reliability.md")).unwrap();
        for c in COUNTS {
            let row = doc.lines().find(|l| {
                c.flags.iter().chain(c.keys).all(|n| l.contains(&format!("`{n}`")))
                    && l.contains(&format!("| {} | {} |", c.min, c.max))
            });
            assert!(row.is_some(), "docs/reliability.md has no row for {c:?}");
        }
        for r in REALS {
            let row = doc.lines().find(|l| {
                r.keys.iter().chain(r.flags).all(|n| l.contains(&format!("`{n}`"))) && l.contains(&r.interval())
            });
            assert!(row.is_some(), "docs/reliability.md has no row for {r:?}");
        }
        for f in FILES {
            assert!(
                doc.contains(&format!("| {} |", f.what)) && doc.contains(&format!("{} MiB", f.max_bytes >> 20)),
                "{f:?}"
            );
        }
    }

    #[test]
    fn every_bound_is_an_interval_and_every_count_has_a_name() {
        for c in COUNTS {
            assert!(c.min <= c.max, "{c:?}");
            assert!(!(c.flags.is_empty() && c.keys.is_empty()), "{c:?}");
        }
        for r in REALS {
            assert!(r.min < r.max, "{r:?}");
        }
    }
}
