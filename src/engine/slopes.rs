//! One design over several conveyor slopes (Table 2.2's slope range, req. 1.6.3): its figures
//! at every slope, and with requirements each slope's verdict and the worst one. `sawtooth
//! simulate --alpha FROM..TO` and Python's `sawtooth.simulate(..., slopes_deg=[...])` are
//! both this, and write one JSON object ([`slopes_json`]); the CLI prints its table from the
//! same rows.

use serde_json::json;

use super::{evaluate_detailed, Detailed, ParticleEngine};
use crate::model::design::DesignRow;
use crate::model::requirements::{worst_over_slopes, Assessment, Requirements, NOT_ASSESSED};
use crate::model::validity::Invalid;
use crate::model::{Design, Scenario};

/// The design at one slope.
pub struct SlopeRow {
    pub alpha_deg: f64,
    /// The simulation, or why the model rejects the design at this slope.
    pub result: Result<Detailed, Invalid>,
    /// The requirements' verdict at this slope (a rejected design fails them here).
    pub assessment: Option<Assessment>,
}

/// Simulate `design` under `scenario` at each of `slopes` (degrees). A design the model
/// rejects at one slope (e.g. the 5.3.1 spill check on a level conveyor) is reported there
/// and fails the requirements there, not the whole run.
pub fn over_slopes(
    engine: &dyn ParticleEngine,
    scenario: &Scenario,
    design: &Design,
    slopes: &[f64],
    requirements: Option<&Requirements>,
) -> Vec<SlopeRow> {
    slopes
        .iter()
        .map(|&alpha_deg| {
            let mut s = scenario.clone();
            s.environment.alpha_deg = alpha_deg;
            let result = evaluate_detailed(engine, &s, design, false);
            let assessment = requirements.map(|r| match &result {
                Ok(det) => r.assess(&det.evaluation.performance, &s.performance, det.evaluation.sim.lost_fraction),
                Err(_) => r.assess_rejected(&s, design),
            });
            SlopeRow { alpha_deg, result, assessment }
        })
        .collect()
}

/// Each assessed slope with its verdict.
pub fn assessed(rows: &[SlopeRow]) -> Vec<(f64, Assessment)> {
    rows.iter().filter_map(|r| r.assessment.clone().map(|x| (r.alpha_deg, x))).collect()
}

/// Req. 1.6.3 over the slopes evaluated: covered when they span the required range; and
/// what was evaluated, in words.
pub fn slope_coverage(r: &Requirements, per_slope: &[(f64, Assessment)]) -> (bool, String) {
    let lo = per_slope.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = per_slope.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let covered = lo <= r.slope_min_deg + 1e-9 && hi >= r.slope_max_deg - 1e-9;
    let what = if per_slope.len() == 1 {
        format!("evaluated at {lo} deg only (give --alpha {}..{} to judge the range)", r.slope_min_deg, r.slope_max_deg)
    } else {
        format!("evaluated at {} slopes over {lo}..{hi} deg", per_slope.len())
    };
    (covered, what)
}

/// The requirements' verdicts over the slopes evaluated: the `requirements` object of
/// `simulate --json`.
pub fn requirements_json(r: &Requirements, per_slope: &[(f64, Assessment)]) -> serde_json::Value {
    let worst = worst_over_slopes(per_slope);
    let (covered, coverage) = slope_coverage(r, per_slope);
    json!({
        "requirements": r,
        "compliant": per_slope.iter().all(|(_, x)| x.compliant()),
        "slope_range_assessed": covered,
        "slope_coverage": coverage,
        "worst_alpha_deg": worst.as_ref().map(|w| w.0),
        "worst": worst.as_ref().map(|w| &w.1),
        "binding": worst.as_ref().and_then(|w| w.1.binding()),
        "per_slope": per_slope.iter().map(|(alpha, x)| json!({"alpha_deg": alpha, "assessment": x})).collect::<Vec<_>>(),
        "not_assessed": NOT_ASSESSED.iter().map(|(id, n)| json!({"id": id, "requirement": n})).collect::<Vec<_>>(),
    })
}

/// The JSON object of `design` over the slopes of `rows` (`engine`: the engine's name as the
/// user knows it).
pub fn slopes_json(
    engine: &str,
    scenario: &Scenario,
    design: &Design,
    rows: &[SlopeRow],
    requirements: Option<&Requirements>,
) -> serde_json::Value {
    let per_slope: Vec<serde_json::Value> = rows
        .iter()
        .map(|r| match &r.result {
            Ok(det) => {
                let e = &det.evaluation;
                json!({
                    "alpha_deg": r.alpha_deg,
                    "distribution": e.sim.distribution,
                    "d_avg_m": e.sim.d_avg_m,
                    "lost_fraction": e.sim.lost_fraction,
                    "performance": e.performance,
                })
            }
            Err(invalid) => json!({"alpha_deg": r.alpha_deg, "invalid": invalid.rule(), "reason": invalid.to_string()}),
        })
        .collect();
    let mut v = json!({
        "engine": engine,
        "mode": scenario.mode,
        "scenario": scenario,
        "design": DesignRow::of(design),
        "slopes": per_slope,
    });
    if let Some(r) = requirements {
        v["requirements"] = requirements_json(r, &assessed(rows));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{make_engine, EngineKind};

    /// Each slope is the design simulated at that slope alone; the worst slope binds.
    #[test]
    fn each_slope_is_the_design_at_that_slope_and_the_worst_one_is_judged() {
        let mut s = Scenario::lunar();
        s.sim.particles = 40;
        let d = Design::lunar_solution_c();
        let engine = make_engine(EngineKind::Cpu).unwrap();
        let r = Requirements::preset("table-2.2").unwrap();
        let rows = over_slopes(engine.as_ref(), &s, &d, &[0.0, 20.0, 40.0], Some(&r));
        assert_eq!(rows.len(), 3);
        for row in &rows {
            let mut one = s.clone();
            one.environment.alpha_deg = row.alpha_deg;
            let alone = evaluate_detailed(engine.as_ref(), &one, &d, false);
            match (&row.result, alone) {
                (Ok(a), Ok(b)) => assert_eq!(a.evaluation.sim.distribution, b.evaluation.sim.distribution),
                (Err(a), Err(b)) => assert_eq!(a, &b),
                _ => panic!("slope {}: one of the two was rejected", row.alpha_deg),
            }
        }
        let v = slopes_json("cpu", &s, &d, &rows, Some(&r));
        assert_eq!(v["slopes"].as_array().unwrap().len(), 3);
        assert_eq!(v["requirements"]["per_slope"].as_array().unwrap().len(), 3);
        assert_eq!(v["requirements"]["slope_range_assessed"], true);
        let worst = worst_over_slopes(&assessed(&rows)).unwrap();
        assert_eq!(v["requirements"]["worst_alpha_deg"], worst.0);
    }
}
