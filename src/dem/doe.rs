//! A design of experiments in DEM (issue 43, 2): N designs spread over the optimiser's space,
//! each run in DEM with several seeds, so that a calibration can be made on (or checked
//! against) designs that no optimisation chose.
//!
//! The draw: designs uniform in the optimiser's bounds (Table 5.3 units, listing D.5's bounds,
//! erratum 2), the four lengths sorted into the chain l_b <= r <= l_a <= l_c as the optimiser
//! repairs them (Eq. 5.2), kept where the geometric constraints of D.5 hold, the model
//! simulates them with a mass flow, the DEM's grains would be at least `min_grain_m` across
//! (the DEM's step scales with the grain: a fill too small for the grain count costs hours a
//! run), the model's d_avg is at most `max_d_avg_m` where one is given (a long flight is a long
//! mesh and a long run), and, with requirements, the model says the design meets them at the scenario's slope.
//! From that pool the N designs are chosen by greedy maximin distance in the unit cube of the
//! bounds (each next design the one farthest from those chosen), which spreads them where the
//! constraints leave room.
//!
//! The result is a DEM check's plan ([`CheckPlan`]): its finalists are the drawn designs
//! (`doe-01` …) with the model's figures, so `campaign run/status/gather/slurm` run, resume and
//! report it as they do a check, and each design's folder ends with the `dem.csv` and
//! `setup.toml` that `fit` and `diagnose` read.

use anyhow::bail;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::campaign::Plan;
use super::case::fill_grain_diameter;
use super::check::{CheckPlan, Finalist, CHECK_PLAN_FORMAT};
use super::settings::DemSettings;
use crate::engine::{BatchEvaluator, Evaluation};
use crate::model::design::{Design, LOWER_BOUND_CLI, UPPER_BOUND_CLI};
use crate::model::requirements::Requirements;
use crate::model::{prepare, Invalid, Scenario};
use crate::optim::sawtooth::{chain_repair, violation};

/// Uniform draws per batch (each geometrically feasible one simulated in one engine call).
const BATCH: usize = 1024;
/// Most uniform draws before the pool is declared too small: a requirement or grain size
/// that almost no design of the space meets is said so, not searched for forever.
const MAX_DRAWS: usize = 400 * BATCH;
/// Pool per design asked for: enough candidates that the maximin choice spreads them.
const POOL_PER_DESIGN: usize = 40;

/// What to draw.
#[derive(Clone, Debug)]
pub struct DoeRequest {
    pub designs: usize,
    /// DEM seeds per design (seeds 0, 1, …).
    pub seeds: u32,
    /// The draw's seed (the designs; not the DEM's).
    pub draw_seed: u64,
    /// Smallest DEM grain diameter a design may need, m.
    pub min_grain_m: f64,
    /// The grain count that rule is judged at (None: the runs' own): a draw remade at more
    /// grains, to check its convergence, keeps the designs it was drawn with at fewer.
    pub draw_particles: Option<u32>,
    /// Longest model d_avg a design may have, m (None: any): a long flight needs a long mesh
    /// and a long run (pick B's 2 m take hours a run at 2.5 % overlap).
    pub max_d_avg_m: Option<f64>,
    /// Keep only designs the model says meet these at the scenario's slope.
    pub requirements: Option<Requirements>,
}

/// Why drawn designs did not join the pool: each a count, reported beside the plan.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Tally {
    pub drawn: usize,
    pub geometry: usize,
    pub rejected_by_model: usize,
    pub no_mass_flow: usize,
    pub grains_too_small: usize,
    pub flight_too_long: usize,
    pub requirements: usize,
    pub pool: usize,
}

/// One candidate of the pool: its variables, the model's evaluation and verdict.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub x: [f64; 8],
    pub evaluation: Evaluation,
    pub compliant: Option<bool>,
    pub m_dot_op_kg_h: Option<f64>,
    pub grain_m: f64,
}

/// The pool of designs meeting every rule of the draw, and what was refused on the way.
pub fn pool(
    engine: &dyn BatchEvaluator,
    scenario: &Scenario,
    settings: &DemSettings,
    r: &DoeRequest,
) -> (Vec<Candidate>, Tally) {
    let want = (POOL_PER_DESIGN * r.designs).max(200);
    let judged_at = DemSettings { particles: r.draw_particles.unwrap_or(settings.particles), ..settings.clone() };
    let mut rng = ChaCha8Rng::seed_from_u64(r.draw_seed);
    let mut tally = Tally::default();
    let mut pool = Vec::new();
    while pool.len() < want && tally.drawn < MAX_DRAWS {
        let mut feasible = Vec::with_capacity(BATCH);
        for _ in 0..BATCH {
            let mut x = [0.0; 8];
            for (j, v) in x.iter_mut().enumerate() {
                *v = LOWER_BOUND_CLI[j] + rng.random::<f64>() * (UPPER_BOUND_CLI[j] - LOWER_BOUND_CLI[j]);
            }
            chain_repair(&mut x);
            tally.drawn += 1;
            if violation(&x) > 0.0 {
                tally.geometry += 1;
                continue;
            }
            // the grain size first: it needs the geometry only, not a simulation
            match grain_diameter(scenario, &judged_at, &x) {
                None => tally.rejected_by_model += 1,
                Some(d) if d < r.min_grain_m => tally.grains_too_small += 1,
                Some(d) => feasible.push((x, d)),
            }
        }
        if feasible.is_empty() {
            continue;
        }
        let designs: Vec<Design> = feasible.iter().map(|(x, _)| Design::from_cli_units(*x)).collect();
        for (&(x, grain_m), result) in feasible.iter().zip(engine.evaluate(scenario, &designs)) {
            match judge_candidate(scenario, r, x, grain_m, result) {
                Ok(c) => pool.push(c),
                Err(why) => why.count(&mut tally),
            }
        }
    }
    tally.pool = pool.len();
    (pool, tally)
}

enum Refused {
    Model,
    NoMassFlow,
    FlightTooLong,
    Requirements,
}

impl Refused {
    fn count(self, t: &mut Tally) {
        *match self {
            Refused::Model => &mut t.rejected_by_model,
            Refused::NoMassFlow => &mut t.no_mass_flow,
            Refused::FlightTooLong => &mut t.flight_too_long,
            Refused::Requirements => &mut t.requirements,
        } += 1;
    }
}

/// The diameter of the DEM's grains for the design (`[dem] grain_diameter_m`, else the one at
/// which the grain count holds the model's fill mass, as `Case::build` sizes them); None where
/// the model rejects the design's geometry.
fn grain_diameter(scenario: &Scenario, settings: &DemSettings, x: &[f64; 8]) -> Option<f64> {
    let prep = prepare(scenario, &Design::from_cli_units(*x)).ok()?;
    Some(settings.grain_diameter_m.unwrap_or_else(|| fill_grain_diameter(scenario, prep.fill.area, settings)))
}

fn judge_candidate(
    scenario: &Scenario,
    r: &DoeRequest,
    x: [f64; 8],
    grain_m: f64,
    result: Result<Evaluation, Invalid>,
) -> Result<Candidate, Refused> {
    let e = result.map_err(|_| Refused::Model)?;
    if e.performance.w_spec_j_kg.is_none() || e.sim.d_avg_m.is_nan() || e.sim.d_avg_m <= 0.0 {
        return Err(Refused::NoMassFlow);
    }
    if r.max_d_avg_m.is_some_and(|m| e.sim.d_avg_m > m) {
        return Err(Refused::FlightTooLong);
    }
    let assessment =
        r.requirements.as_ref().map(|q| q.assess(&e.performance, &scenario.performance, e.sim.lost_fraction));
    if assessment.as_ref().is_some_and(|a| !a.compliant()) {
        return Err(Refused::Requirements);
    }
    Ok(Candidate {
        x,
        compliant: assessment.as_ref().map(|a| a.compliant()),
        m_dot_op_kg_h: assessment.as_ref().map(|a| a.operating_point.m_dot_kg_h),
        evaluation: e,
        grain_m,
    })
}

/// The candidates' indices in the order of a greedy maximin choice in the unit cube of the
/// bounds: first the candidate nearest the pool's centre, then each time the one whose
/// nearest chosen neighbour is farthest (ties to the earlier drawn).
pub fn maximin_order(xs: &[[f64; 8]]) -> Vec<usize> {
    let unit = |x: &[f64; 8]| -> [f64; 8] {
        std::array::from_fn(|j| (x[j] - LOWER_BOUND_CLI[j]) / (UPPER_BOUND_CLI[j] - LOWER_BOUND_CLI[j]))
    };
    let u: Vec<[f64; 8]> = xs.iter().map(unit).collect();
    let d2 = |a: &[f64; 8], b: &[f64; 8]| a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum::<f64>();
    if u.is_empty() {
        return Vec::new();
    }
    let centre: [f64; 8] = std::array::from_fn(|j| u.iter().map(|v| v[j]).sum::<f64>() / u.len() as f64);
    let mut start = 0;
    for (i, v) in u.iter().enumerate() {
        if d2(v, &centre) < d2(&u[start], &centre) {
            start = i;
        }
    }
    let mut nearest: Vec<f64> = u.iter().map(|v| d2(v, &u[start])).collect();
    let mut order = vec![start];
    let mut taken = vec![false; u.len()];
    taken[start] = true;
    while order.len() < u.len() {
        let mut next = usize::MAX;
        for i in 0..u.len() {
            if !taken[i] && (next == usize::MAX || nearest[i] > nearest[next]) {
                next = i;
            }
        }
        taken[next] = true;
        order.push(next);
        for (i, v) in u.iter().enumerate() {
            nearest[i] = nearest[i].min(d2(v, &u[next]));
        }
    }
    order
}

/// The plan of a design of experiments: `r.designs` designs of the pool in maximin order whose
/// DEM case can be built (a design whose case is refused is skipped and the next taken), each
/// a finalist `doe-NN` with `r.seeds` DEM runs from seed 0; its model figures are the pool's
/// evaluation (the scenario's particle count).
pub fn plan(
    engine: &dyn BatchEvaluator,
    scenario: &Scenario,
    settings: &DemSettings,
    r: &DoeRequest,
    command: &str,
) -> anyhow::Result<(CheckPlan, Tally)> {
    let (pool, tally) = pool(engine, scenario, settings, r);
    if pool.len() < r.designs {
        bail!(
            "only {} of the {} designs drawn meet every rule of the draw, fewer than --designs {} ({} outside the geometric constraints, {} rejected by the model, {} without a mass flow, {} needing grains under {} mm, {} flying further than --max-d-avg-mm, {} failing the requirements); ask for fewer designs, a smaller --min-grain-mm, a larger --max-d-avg-mm, or drop --requirements",
            pool.len(),
            tally.drawn,
            r.designs,
            tally.geometry,
            tally.rejected_by_model,
            tally.no_mass_flow,
            tally.grains_too_small,
            r.min_grain_m * 1e3,
            tally.flight_too_long,
            tally.requirements
        );
    }
    let xs: Vec<[f64; 8]> = pool.iter().map(|c| c.x).collect();
    let mut finalists = Vec::new();
    let mut refused = Vec::new();
    for i in maximin_order(&xs) {
        if finalists.len() == r.designs {
            break;
        }
        let c = &pool[i];
        let design = Design::from_cli_units(c.x);
        let settings = super::case::with_stated_mesh(settings, scenario, &design);
        let campaign = Plan {
            scenario: scenario.clone(),
            design,
            settings,
            runs: r.seeds,
            first_seed: 0,
            known_return: None,
            strokes: 0,
            period_teeth: 0,
        };
        // refused at the run's count, or at the count the draw is judged at: a draw remade at
        // more grains (`draw_particles`) skips the designs the draw skipped, and keeps its own
        let at_draw_count = r
            .draw_particles
            .filter(|&n| n != campaign.settings.particles)
            .map(|n| Plan { settings: DemSettings { particles: n, ..campaign.settings.clone() }, ..campaign.clone() });
        if let Err(e) = campaign.check().and_then(|_| at_draw_count.map_or(Ok(()), |p| p.check().map(drop))) {
            refused.push(e);
            continue;
        }
        let p = &c.evaluation.performance;
        finalists.push(Finalist {
            label: format!("doe-{:02}", finalists.len() + 1),
            model_d_avg_m: c.evaluation.sim.d_avg_m,
            model_m_dot_kg_s: p.m_dot_kg_s,
            model_w_spec_j_kg: p.w_spec_j_kg.expect("the pool holds designs with a mass flow"),
            model_compliant: c.compliant,
            model_m_dot_op_kg_h: c.m_dot_op_kg_h,
            campaign,
        });
    }
    if finalists.len() < r.designs {
        bail!(
            "the DEM cannot build a case for enough of the pool's designs ({} of {} wanted); the first refusal: {}",
            finalists.len(),
            r.designs,
            refused.first().map_or("none", String::as_str)
        );
    }
    let plan = CheckPlan {
        format: CHECK_PLAN_FORMAT,
        command: command.to_string(),
        run_dir: format!(
            "a design of experiments: {} designs drawn over the optimiser's space (draw seed {}, {} of {} draws in the pool)",
            r.designs, r.draw_seed, tally.pool, tally.drawn
        ),
        seeds: r.seeds,
        particles: settings.particles,
        requirements: r.requirements.clone(),
        finalists,
    };
    plan.validate().map_err(anyhow::Error::msg)?;
    Ok((plan, tally))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maximin_starts_at_the_centre_and_takes_the_corners_next() {
        let lo = LOWER_BOUND_CLI;
        let hi = UPPER_BOUND_CLI;
        let mid: [f64; 8] = std::array::from_fn(|j| 0.5 * (lo[j] + hi[j]));
        let near_mid: [f64; 8] = std::array::from_fn(|j| mid[j] + 0.01 * (hi[j] - lo[j]));
        // the centre, a point next to it, and two opposite corners
        let xs = [near_mid, lo, mid, hi];
        let order = maximin_order(&xs);
        assert_eq!(order[0], 2, "{order:?}");
        assert_eq!(order[3], 0, "the point beside the centre comes last: {order:?}");
        assert_eq!(order.len(), 4);
        assert!(maximin_order(&[]).is_empty());
    }

    fn request(designs: usize) -> DoeRequest {
        DoeRequest {
            designs,
            seeds: 2,
            draw_seed: 7,
            min_grain_m: 0.003,
            draw_particles: None,
            max_d_avg_m: None,
            requirements: None,
        }
    }

    /// Every drawn design keeps the optimiser's rules and the draw's own, the plan is a valid
    /// check plan, and the same seed draws the same designs.
    #[test]
    fn a_draw_keeps_every_rule_and_repeats_with_its_seed() {
        let engine = crate::engine::particle_engine(crate::engine::EngineKind::Cpu);
        let mut scenario = Scenario::lunar();
        scenario.sim.particles = 40;
        let settings = DemSettings { particles: 150, ..Default::default() };
        let (plan, tally) = plan(engine.as_ref(), &scenario, &settings, &request(4), "test").unwrap();
        assert_eq!(plan.finalists.len(), 4);
        assert!(tally.pool >= 160 && tally.drawn > tally.pool, "{tally:?}");
        assert!(tally.geometry > 0 && tally.grains_too_small > 0, "both rules bite in the lunar space: {tally:?}");
        let labels: Vec<&str> = plan.finalists.iter().map(|f| f.label.as_str()).collect();
        assert_eq!(labels, ["doe-01", "doe-02", "doe-03", "doe-04"]);
        for f in &plan.finalists {
            let x = f.campaign.design.to_cli_units();
            assert_eq!(violation(&x), 0.0, "{x:?}");
            assert!(f.campaign.design.within_bounds(), "{x:?}");
            let case = f.campaign.check().unwrap();
            assert!(case.placement.diameter_m >= 0.003, "{}", case.placement.diameter_m);
            assert!(f.model_d_avg_m > 0.0 && f.model_m_dot_kg_s > 0.0);
        }
        // spread: no two chosen designs closer than a tenth of the cube's diagonal
        let u = |d: &Design| -> Vec<f64> {
            let x = d.to_cli_units();
            (0..8).map(|j| (x[j] - LOWER_BOUND_CLI[j]) / (UPPER_BOUND_CLI[j] - LOWER_BOUND_CLI[j])).collect()
        };
        for a in &plan.finalists {
            for b in &plan.finalists {
                if a.label < b.label {
                    let (p, q) = (u(&a.campaign.design), u(&b.campaign.design));
                    let d = p.iter().zip(&q).map(|(s, t)| (s - t).powi(2)).sum::<f64>().sqrt();
                    assert!(d > 0.1 * 8f64.sqrt(), "{} and {} are {d:.3} apart", a.label, b.label);
                }
            }
        }
        let (again, _) = super::plan(engine.as_ref(), &scenario, &settings, &request(4), "test").unwrap();
        assert_eq!(again, plan);
        // remade at twice the grains, judged at the count it was drawn at: the same designs,
        // run with the new count (its grains smaller than the rule's 3 mm)
        let finer = DemSettings { particles: 300, ..settings.clone() };
        let remade_request = DoeRequest { draw_particles: Some(150), ..request(4) };
        let (remade, _) = super::plan(engine.as_ref(), &scenario, &finer, &remade_request, "test").unwrap();
        for (a, b) in plan.finalists.iter().zip(&remade.finalists) {
            assert_eq!(a.campaign.design, b.campaign.design);
            assert_eq!(b.campaign.settings.particles, 300);
        }
        let (judged_at_300, _) = super::plan(engine.as_ref(), &scenario, &finer, &request(4), "test").unwrap();
        assert_ne!(
            judged_at_300.finalists.iter().map(|f| &f.campaign.design).collect::<Vec<_>>(),
            plan.finalists.iter().map(|f| &f.campaign.design).collect::<Vec<_>>(),
            "judged at its own count, the rule keeps another pool"
        );
    }

    #[test]
    fn a_draw_no_design_can_meet_says_which_rule_refused_them() {
        let engine = crate::engine::particle_engine(crate::engine::EngineKind::Cpu);
        let mut scenario = Scenario::lunar();
        scenario.sim.particles = 20;
        let settings = DemSettings { particles: 150, ..Default::default() };
        // 5 cm grains: no fill of the space holds 150 of them
        let r = DoeRequest { min_grain_m: 0.05, ..request(2) };
        let e = plan(engine.as_ref(), &scenario, &settings, &r, "test").unwrap_err().to_string();
        assert!(e.contains("fewer than --designs 2") && e.contains("needing grains under 50 mm"), "{e}");
    }
}
