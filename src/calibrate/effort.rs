//! How hard a calibration works: the user's request ([`Effort`]) turned into the solver's
//! settings for the measured conditions, with the particle count chosen from the data.

use super::condition::Condition;
use super::fields::Spelling;
use super::solver::{PolishMethod, Solver, FIRST_STEP, MIN_STEP};
use super::target::ObjectiveKind;

/// Fewest particles per simulation a calibration uses at the full budget, and while
/// screening.
pub const MIN_PARTICLES: u32 = 2000;

/// What a user asks of a calibration (the flags of `fit` and `diagnose`).
#[derive(Clone, Copy, Debug)]
pub struct Effort {
    /// Particles per simulation at the full budget; None: chosen from the data
    /// ([`particles_from_data`]).
    pub particles: Option<u32>,
    /// The most particles the data may call for.
    pub max_particles: u32,
    /// Differential-evolution population and generations of the screen.
    pub pop: usize,
    pub generations: usize,
    /// Compass-search iterations of the polish at the full budget.
    pub polish: usize,
    pub seed: u64,
}

/// The effort a user asks for before the seed is known (`fit` and `diagnose` take it from
/// the setup): the flags `--particles`, `--max-particles`, `--pop`, `--generations`,
/// `--polish`, or the Python package's keywords of the same names. [`Default`] is the
/// CLI's defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EffortSettings {
    pub particles: Option<u32>,
    pub max_particles: u32,
    pub pop: usize,
    pub generations: usize,
    pub polish: usize,
}

impl EffortSettings {
    pub const DEFAULT_MAX_PARTICLES: u32 = 12_000;
    pub const DEFAULT_POP: usize = 20;
    pub const DEFAULT_GENERATIONS: usize = 20;
    pub const DEFAULT_POLISH: usize = 12;

    /// Each setting within its bounds (`schema`), checked before anything is read or
    /// simulated; an error names the field as `spelling` writes it.
    pub fn validate(&self, spelling: Spelling) -> Result<(), String> {
        use crate::schema::{FIT_GENERATIONS, FIT_MAX_PARTICLES, FIT_PARTICLES, FIT_POLISH, FIT_POP};
        let name = |f: &str| spelling.name(f);
        FIT_POP.check_usize(&name("pop"), self.pop)?;
        FIT_GENERATIONS.check_usize(&name("generations"), self.generations)?;
        FIT_POLISH.check_usize(&name("polish"), self.polish)?;
        if let Some(p) = self.particles {
            FIT_PARTICLES.check_u32(&name("particles"), p)?;
        }
        FIT_MAX_PARTICLES.check_u32(&name("max_particles"), self.max_particles)?;
        Ok(())
    }

    /// The effort with the calibration's seed.
    pub fn with_seed(&self, seed: u64) -> Effort {
        Effort {
            particles: self.particles,
            max_particles: self.max_particles,
            pop: self.pop,
            generations: self.generations,
            polish: self.polish,
            seed,
        }
    }
}

impl Default for EffortSettings {
    fn default() -> Self {
        EffortSettings {
            particles: None,
            max_particles: Self::DEFAULT_MAX_PARTICLES,
            pop: Self::DEFAULT_POP,
            generations: Self::DEFAULT_GENERATIONS,
            polish: Self::DEFAULT_POLISH,
        }
    }
}

/// Particles per simulation that the data call for: the Monte-Carlo variance of every
/// tooth holding ≥ 2 % of a condition's mass at most a quarter of the variance of its
/// measured mean ([`Condition::particles_for`]), rounded up to a thousand, within
/// [`MIN_PARTICLES`, `max`]. Returns the count and whether `max` limited it.
pub fn particles_from_data(conditions: &[Condition], max: u32) -> (u32, bool) {
    let want = conditions.iter().map(|c| c.particles_for(0.25)).fold(0.0, f64::max);
    let rounded = ((want / 1000.0).ceil() * 1000.0).max(MIN_PARTICLES as f64);
    if rounded > max as f64 {
        (max, true)
    } else {
        (rounded as u32, false)
    }
}

impl Effort {
    /// The solver for `conditions`, and a note when the particle count keeps the
    /// simulation's noise above what the data resolve. The screen runs at an eighth of the
    /// particles (at least [`MIN_PARTICLES`]).
    pub fn solver(&self, objective: ObjectiveKind, conditions: &[Condition]) -> (Solver, Option<String>) {
        let (particles, limited) = match self.particles {
            Some(n) => (n, false),
            None => particles_from_data(conditions, self.max_particles),
        };
        let wanted = conditions.iter().map(|c| c.particles_for(0.25)).fold(0.0, f64::max);
        let note = (limited || (particles as f64) < wanted).then(|| {
            format!(
                "Monte-Carlo budget: {particles} particles per simulation; keeping the simulation's noise per tooth at half \
                 the measured mean's would take {wanted:.0}. The simulation's noise, not the data, limits how small a gap \
                 can be told apart (allow more particles, or use a GPU engine)"
            )
        });
        let screen_particles = (particles / 8).clamp(MIN_PARTICLES.min(particles), particles);
        let solver = Solver {
            objective,
            pop: self.pop,
            generations: self.generations,
            screen_particles,
            particles,
            polish_iterations: self.polish,
            first_step: FIRST_STEP,
            min_step: MIN_STEP,
            seed: self.seed,
            polish_method: PolishMethod::Compass,
        };
        (solver, note)
    }
}
