//! Many (model, point) pairs, every condition each, as one engine call.

use super::condition::Condition;
use super::objective;
use super::space::Space;
use crate::engine::BatchEvaluator;
use crate::model::Scenario;

/// The simulation side of a calibration.
pub struct Simulator<'a> {
    pub engine: &'a dyn BatchEvaluator,
    pub conditions: &'a [Condition],
}

/// Simulated bins (teeth, then lost) per condition as its measurement sees them
/// ([`Condition::observe`]); None when the engine rejected one.
pub type Bins = Option<Vec<Vec<f64>>>;

impl Simulator<'_> {
    /// Simulate every point in every condition with `particles` particles and `seed`
    /// (common random numbers: the same streams for every point), as one
    /// `evaluate_groups` call of |points| × |conditions| one-design groups.
    pub fn simulate(&self, points: &[(&Space, Vec<f64>)], particles: u32, seed: u64) -> Vec<Bins> {
        let nc = self.conditions.len();
        let groups: Vec<(Scenario, Vec<crate::model::Design>)> = points
            .iter()
            .flat_map(|(space, x)| {
                self.conditions.iter().map(move |c| {
                    let mut s = space.scenario_at(c, x);
                    s.sim.particles = particles;
                    s.sim.seed = seed;
                    (s, vec![c.design])
                })
            })
            .collect();
        let results = self.engine.evaluate_groups(&groups);
        results
            .chunks(nc)
            .map(|per_cond| {
                per_cond
                    .iter()
                    .zip(self.conditions)
                    .map(|(r, c)| {
                        r.first().and_then(|e| e.as_ref().ok()).map(|e| c.observe(objective::simulated_bins(&e.sim)))
                    })
                    .collect()
            })
            .collect()
    }
}
