//! How hard a calibration works: the user's request ([`Effort`]) turned into the solver's
//! settings for the measured conditions, with the particle count chosen from the data.

use super::condition::Condition;
use super::solver::{Solver, FIRST_STEP, MIN_STEP};
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
        };
        (solver, note)
    }
}
