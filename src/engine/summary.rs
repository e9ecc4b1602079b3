//! The JSON object of one simulated design (`sawtooth simulate --json`, Python's
//! `sawtooth.simulate`): the scenario, the design in user units, the distribution over the
//! teeth and the performance figures. One shape, written here, for both.

use serde_json::json;

use super::Detailed;
use crate::model::design::DesignRow;
use crate::model::outcome::centre_and_dispersion;
use crate::model::{Design, Scenario};

/// `engine` is the engine's name as the user knows it (`cpu`, `listing`, `gpu`).
pub fn simulation_json(s: &Scenario, d: &Design, engine: &str, det: &Detailed) -> serde_json::Value {
    let sim = &det.evaluation.sim;
    let (ex, sx) = centre_and_dispersion(&sim.distribution);
    json!({
        "engine": engine,
        "mode": s.mode,
        "scenario": s,
        "design": DesignRow::of(d),
        "distribution": sim.distribution,
        "d_avg_m": sim.d_avg_m,
        "advance_m": sim.advance_m,
        "lost_fraction": sim.lost_fraction,
        "unsettled_fraction": sim.unsettled_fraction,
        "fill_area_mm2": sim.fill_area_mm2,
        "bounces": sim.bounces,
        "mean_bounces": sim.mean_bounces,
        "centre_of_mass_teeth": ex,
        "dispersion_teeth": sx,
        "performance": det.evaluation.performance,
    })
}
