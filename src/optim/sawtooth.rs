//! The thesis's optimisation problem (5.2-5.3, listing D.5-D.7) as a `BatchProblem`:
//! 8 variables in Table 5.3 units with the listing's bounds (erratum 2), the linear chain
//! l_b <= r <= l_a <= l_c (Eq. 5.2), the nonlinear constraints c1-c4 of D.5 judged with
//! MATLAB's constraint tolerance, the viability checks of D.6 as penalty objectives, and
//! the objectives f_stroke and W_spec with the 2 Hz penalty (Eq. 5.17-5.18, erratum 3).

use serde::Serialize;

use super::nsga2::{BatchProblem, Evaluation as GaEvaluation};
use crate::engine::{BatchEvaluator, Evaluation};
use crate::model::design::{Design, LOWER_BOUND_CLI, UPPER_BOUND_CLI};
use crate::model::geometry::LocalTooth;
use crate::model::requirements::{Assessment, Requirements, REQUIREMENT_TOLERANCE};
use crate::model::{Invalid, Scenario};

/// MATLAB's default ConstraintTolerance (5.2).
pub const CONSTRAINT_TOLERANCE: f64 = 1e-3;
/// f_limit of 5.3.1, Hz.
pub const F_LIMIT: f64 = 2.0;
/// Added to the violation of a design that fails the geometric constraints when the run has
/// requirements: far above any relative requirement shortfall a simulated design can have.
pub const UNSIMULATED_VIOLATION: f64 = 1e6;
/// Penalty weights w_pen,1 and w_pen,2 of Eq. 5.17-5.18.
pub const PENALTY_WEIGHTS: [f64; 2] = [1000.0, 1_000_000.0];

/// The nonlinear constraint values of listing D.5 (mm), c <= 0 is satisfied.
pub fn nonlinear_constraints(x: &[f64]) -> [f64; 4] {
    let (l_c, l_a, l_b, r) = (x[0], x[1], x[2], x[3]);
    let t = LocalTooth::new(&design_of(x));
    let (y2, y3, x3, x4) = (l_b, r * x[4].to_radians().cos(), t.p3[0] * 1e3, t.p4[0] * 1e3);
    let c1 = (y2 - y3).abs() - r;
    if c1 > 0.0 {
        return [c1, 1e6, 1e6, 1e6];
    }
    let ramp_length = l_a.hypot(l_b);
    let phi = (l_b / l_a).atan();
    let p_proj = x3 * phi.cos() + y3 * phi.sin();
    let t2 = 2.0 * p_proj - ramp_length;
    [c1, x4 - l_c, -x4, ramp_length - t2]
}

/// Sum of the constraint excesses beyond the tolerance (0 = feasible, Deb's rules).
pub fn violation(x: &[f64]) -> f64 {
    let lin = [x[2] - x[3], x[3] - x[1], x[1] - x[0]]; // Eq. 5.2 as A x <= 0
    lin.iter().chain(nonlinear_constraints(x).iter()).map(|c| (c - CONSTRAINT_TOLERANCE).max(0.0)).sum()
}

/// Objective values for one evaluated (or rejected) design, as D.6 computes them.
pub fn objectives(result: &Result<Evaluation, Invalid>) -> [f64; 2] {
    let e = match result {
        // D.6 returns distinct penalty values per failed viability check (1000003..1000007).
        Err(invalid) => {
            let code = match invalid {
                Invalid::CatchMissesPeak { .. } => 3.0,
                Invalid::CatchOverlapsNextTooth { .. } => 4.0,
                Invalid::CatchBehindToothStart { .. } => 5.0,
                Invalid::CatchCutsRamp { .. } => 6.0,
                Invalid::FillSpills { .. } => 7.0,
                _ => 8.0,
            };
            return [1e6 + code, 1e6 + code];
        }
        Ok(e) => e,
    };
    let p = &e.performance;
    // D.7 lines 51-56: no mass flow -> W_spec sentinel and an impossible frequency.
    let (f, w) = match p.w_spec_j_kg {
        Some(w) => (p.f_dynamic_hz, w),
        None => (2_000_000.0, 1_000_042.0),
    };
    if f > F_LIMIT {
        let excess = f - F_LIMIT;
        [-F_LIMIT + excess * PENALTY_WEIGHTS[0], w + excess * PENALTY_WEIGHTS[1]]
    } else {
        [f, w]
    }
}

/// One evaluation as logged to evaluations.csv.
#[derive(Clone, Debug, Serialize)]
pub struct Logged {
    pub generation: u64,
    pub x: [f64; 8],
    pub objectives: [f64; 2],
    pub violation: f64,
    /// The evaluation shown: at the worst slope where the design is evaluated at several.
    pub evaluation: Option<Evaluation>,
    pub invalid: Option<String>,
    /// The slope of `evaluation`, degrees.
    pub alpha_deg: f64,
    /// The requirements' verdict at that slope, when the run has requirements.
    pub assessment: Option<Assessment>,
    /// The worst relative shortfall of each requirement over the slopes (feed rate, power,
    /// wire length; c <= 0 met), when the run has requirements and the design was simulated:
    /// the constraint values Deb's rules rank by (the Python `SawtoothProblem`'s G).
    pub requirement_constraints: Option<[f64; 3]>,
}

/// The requirements' verdict on one simulated (or rejected) design at one slope: a design the
/// model rejects delivers nothing there.
pub fn assess(r: &Requirements, scenario: &Scenario, x: &[f64], result: &Result<Evaluation, Invalid>) -> Assessment {
    match result {
        Ok(e) => r.assess(&e.performance, &scenario.performance, e.sim.lost_fraction),
        Err(_) => r.assess_rejected(scenario, &design_of(x)),
    }
}

/// The scenarios a design is judged at: one per slope, or the scenario itself.
pub fn slope_scenarios(scenario: &Scenario, slopes_deg: &[f64]) -> Vec<Scenario> {
    if slopes_deg.is_empty() {
        return vec![scenario.clone()];
    }
    slopes_deg
        .iter()
        .map(|&alpha| {
            let mut s = scenario.clone();
            s.environment.alpha_deg = alpha;
            s
        })
        .collect()
}

/// A sink for every generation's evaluations (CSV logging, progress).
pub type EvaluationLog<'a> = Box<dyn FnMut(&[Logged]) + 'a>;

/// The problem, evaluating whole generations with any engine. Common random numbers: every
/// design of a generation uses the same particle streams (the seed depends on the
/// generation only), and the streams are refreshed between generations.
pub struct SawtoothProblem<'a> {
    pub scenario: Scenario,
    pub engine: &'a dyn BatchEvaluator,
    pub base_seed: u64,
    pub log: Option<EvaluationLog<'a>>,
    /// Requirements as constraints (issue 13): the relative shortfalls of the feed rate,
    /// power and wire length (c <= 0 met) join the violation Deb's rules rank by.
    pub requirements: Option<Requirements>,
    /// Slopes every design is evaluated at in the same engine job (req. 1.6.3), degrees;
    /// empty: the scenario's α only. The objectives and constraints are the worst over them.
    pub slopes_deg: Vec<f64>,
}

impl SawtoothProblem<'_> {
    /// Eight design variables (l_c, l_a, l_b, r, ω, δ, v0, a) and two objectives
    /// (f_stroke, W_spec): what a checkpoint of a run must fit.
    /// The objectives' least values: f_stroke >= 0, or -F_LIMIT + a positive penalty (Eq.
    /// 5.17); W_spec >= 0, or W_spec plus a positive penalty, or a sentinel (D.6, D.7).
    pub const SHAPE: super::checkpoint::Shape = super::checkpoint::Shape {
        dim: 8,
        objectives: 2,
        bounds: Some((&LOWER_BOUND_CLI, &UPPER_BOUND_CLI)),
        objective_min: Some(&[-F_LIMIT, 0.0]),
    };

    pub fn seed_for(&self, generation: u64) -> u64 {
        self.base_seed.wrapping_add(generation.wrapping_mul(0x9E37_79B9_7F4A_7C15))
    }
}

impl BatchProblem for SawtoothProblem<'_> {
    fn dim(&self) -> usize {
        Self::SHAPE.dim
    }
    fn n_objectives(&self) -> usize {
        Self::SHAPE.objectives
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        (LOWER_BOUND_CLI.to_vec(), UPPER_BOUND_CLI.to_vec())
    }
    fn repair(&self, x: &mut [f64]) {
        chain_repair(x);
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], generation: u64) -> Vec<GaEvaluation> {
        let mut base = self.scenario.clone();
        base.sim.seed = self.seed_for(generation);
        let scenarios = slope_scenarios(&base, &self.slopes_deg);
        // the requirements are judged as the final verdict judges them (Verdict::met: exact
        // but for rounding), not with MATLAB's 1e-3 tolerance of the geometric constraints,
        // which would let designs 0.1 % past a limit onto the front
        let excess = |c: f64| if c > REQUIREMENT_TOLERANCE { c } else { 0.0 };
        // only the geometric constraints keep a design from being simulated; the requirements
        // (the wire's length included) are judged on the simulation, so that a design is never
        // ranked by half of its shortfalls
        let violations: Vec<f64> = xs.iter().map(|x| violation(x)).collect();
        // A design that cannot be simulated has unknown requirement shortfalls: with
        // requirements it ranks behind every simulated design (its geometric violation, in
        // mm, would otherwise undercut relative shortfalls and pull the population into
        // designs the model cannot judge). The offset keeps their order among themselves.
        let unsimulated_offset = if self.requirements.is_some() { UNSIMULATED_VIOLATION } else { 0.0 };
        // Infeasible individuals are not simulated: Deb's rules rank them by violation alone.
        let to_eval: Vec<usize> = (0..xs.len()).filter(|&i| violations[i] == 0.0).collect();
        let designs: Vec<Design> = to_eval.iter().map(|&i| design_of(&xs[i])).collect();
        // one engine job for every slope: the same particle streams at each (common random numbers)
        let groups: Vec<(Scenario, Vec<Design>)> = scenarios.iter().map(|s| (s.clone(), designs.clone())).collect();
        let results = match groups.as_slice() {
            [(s, d)] => vec![self.engine.evaluate(s, d)],
            _ => self.engine.evaluate_groups(&groups),
        };
        let mut per_slope: Vec<std::vec::IntoIter<Result<Evaluation, Invalid>>> =
            results.into_iter().map(|g| g.into_iter()).collect();
        let mut logged = Vec::with_capacity(xs.len());
        let mut out = Vec::with_capacity(xs.len());
        for (i, x) in xs.iter().enumerate() {
            let mut violation = violations[i];
            let mut requirement_constraints = None;
            let (objs, evaluation, invalid, alpha_deg, assessment) = if violations[i] == 0.0 {
                let results: Vec<Result<Evaluation, Invalid>> =
                    per_slope.iter_mut().map(|g| g.next().expect("one result per design and slope")).collect();
                let judged = judge(&scenarios, x, &results, self.requirements.as_ref());
                violation += judged.constraints.iter().map(|&c| excess(c)).sum::<f64>();
                requirement_constraints = judged.assessment.is_some().then_some(judged.constraints);
                let worst = results.into_iter().nth(judged.worst).expect("worst slope exists");
                let alpha = scenarios[judged.worst].environment.alpha_deg;
                match worst {
                    Ok(e) => (judged.objectives, Some(e), None, alpha, judged.assessment),
                    Err(e) => (judged.objectives, None, Some(e.rule().to_string()), alpha, judged.assessment),
                }
            } else {
                violation += unsimulated_offset;
                // finite so JSON checkpoints can hold it; Deb's rules rank by violation anyway
                ([1e12, 1e12], None, None, base.environment.alpha_deg, None)
            };
            logged.push(Logged {
                generation,
                x: design_of(x).to_cli_units(),
                objectives: objs,
                violation,
                evaluation,
                invalid,
                alpha_deg,
                assessment,
                requirement_constraints,
            });
            out.push(GaEvaluation { objectives: objs.to_vec(), violation });
        }
        if let Some(log) = self.log.as_mut() {
            log(&logged);
        }
        out
    }
}

/// One design judged over its slopes.
pub struct Judged {
    /// The worst objective values over the slopes (each minimised).
    pub objectives: [f64; 2],
    /// The worst relative shortfall of each requirement over the slopes (c <= 0 met).
    pub constraints: [f64; 3],
    /// Index of the slope shown: the one failing the requirements worst, else the highest W_spec.
    pub worst: usize,
    pub assessment: Option<Assessment>,
}

/// The slope a design is shown at, from each slope's largest relative requirement shortfall
/// (None without requirements) and its W_spec: the slope failing the requirements most,
/// else the one with the highest W_spec (where its objective is worst); a tie goes to the
/// higher W_spec, then to the later slope. One rule for the optimiser's log (`judge`) and the
/// final front (`front::final_front`).
pub fn shown_slope(per_slope: &[(Option<f64>, f64)]) -> usize {
    // failing as the verdict fails (`Verdict::met`: beyond rounding)
    let key = |&(c, w): &(Option<f64>, f64)| (c.filter(|&c| c > REQUIREMENT_TOLERANCE).unwrap_or(f64::NEG_INFINITY), w);
    (0..per_slope.len())
        .max_by(|&a, &b| {
            let ((ca, wa), (cb, wb)) = (key(&per_slope[a]), key(&per_slope[b]));
            ca.total_cmp(&cb).then(wa.total_cmp(&wb))
        })
        .unwrap_or(0)
}

/// The worst case over the slopes: the objectives element-wise, the requirements each on
/// its own (one conveyor must meet every one at every slope, req. 1.6.3).
pub fn judge(
    scenarios: &[Scenario],
    x: &[f64],
    results: &[Result<Evaluation, Invalid>],
    requirements: Option<&Requirements>,
) -> Judged {
    let per: Vec<[f64; 2]> = results.iter().map(objectives).collect();
    let objectives = per.iter().fold([f64::NEG_INFINITY; 2], |w, o| [w[0].max(o[0]), w[1].max(o[1])]);
    let Some(r) = requirements else {
        let worst = shown_slope(&per.iter().map(|o| (None, o[1])).collect::<Vec<_>>());
        return Judged { objectives, constraints: [f64::NEG_INFINITY; 3], worst, assessment: None };
    };
    let assessments: Vec<Assessment> = scenarios.iter().zip(results).map(|(s, res)| assess(r, s, x, res)).collect();
    let constraints = assessments.iter().fold([f64::NEG_INFINITY; 3], |w, a| {
        let c = a.constraints();
        [w[0].max(c[0]), w[1].max(c[1]), w[2].max(c[2])]
    });
    let worst =
        shown_slope(&assessments.iter().zip(&per).map(|(a, o)| (Some(a.worst_constraint()), o[1])).collect::<Vec<_>>());
    Judged { objectives, constraints, worst, assessment: Some(assessments[worst].clone()) }
}

/// Sort the four lengths so the chain l_b <= r <= l_a <= l_c holds where the bounds allow
/// (gamultiobj keeps linear constraints satisfied in creation and mutation; the DEM's design
/// of experiments draws its designs the same way).
pub fn chain_repair(x: &mut [f64]) {
    let mut v = [x[0], x[1], x[3], x[2]]; // l_c, l_a, r, l_b in chain order
    v.sort_by(|a, b| b.total_cmp(a));
    x[0] = v[0].clamp(LOWER_BOUND_CLI[0], UPPER_BOUND_CLI[0]);
    x[1] = v[1].clamp(LOWER_BOUND_CLI[1], UPPER_BOUND_CLI[1]);
    x[3] = v[2].clamp(LOWER_BOUND_CLI[3], UPPER_BOUND_CLI[3]);
    x[2] = v[3].clamp(LOWER_BOUND_CLI[2], UPPER_BOUND_CLI[2]);
}

pub fn design_of(x: &[f64]) -> Design {
    Design::from_cli_units([x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn published_solutions_satisfy_the_constraints() {
        for d in [Design::lunar_solution_c(), Design::earth_solution_c()] {
            let x = d.to_cli_units();
            assert_eq!(violation(&x), 0.0, "{:?}", nonlinear_constraints(&x));
        }
    }

    #[test]
    fn chain_repair_restores_the_order() {
        let e = crate::engine::particle_engine(crate::engine::EngineKind::Cpu);
        let p = SawtoothProblem {
            scenario: Scenario::lunar(),
            engine: &e,
            base_seed: 0,
            log: None,
            requirements: None,
            slopes_deg: Vec::new(),
        };
        let mut x = vec![10.0, 30.0, 20.0, 5.0, 60.0, 10.0, 1.0, 30.0];
        p.repair(&mut x);
        assert!(x[2] <= x[3] && x[3] <= x[1] && x[1] <= x[0], "{x:?}");
    }

    #[test]
    fn a_design_is_shown_at_its_worst_failing_slope_else_at_its_highest_w_spec() {
        // no requirements, or all met: the highest W_spec (a tie: the later slope)
        assert_eq!(shown_slope(&[(None, 300.0), (None, 410.0), (None, 350.0)]), 1);
        assert_eq!(shown_slope(&[(Some(-0.2), 300.0), (Some(-0.1), 410.0), (Some(1e-12), 350.0)]), 1);
        assert_eq!(shown_slope(&[(None, 300.0), (None, 300.0)]), 1);
        // a failing slope wins over any W_spec; the larger shortfall first, then the higher W_spec
        assert_eq!(shown_slope(&[(Some(0.05), 300.0), (Some(-0.5), 900.0), (Some(0.30), 280.0)]), 2);
        assert_eq!(shown_slope(&[(Some(1.0), 1e6 + 7.0), (Some(1.0), 1e6 + 3.0), (Some(0.2), 400.0)]), 0);
        assert_eq!(shown_slope(&[]), 0);
    }

    #[test]
    fn frequency_penalty_follows_eq_5_17() {
        let e = crate::engine::particle_engine(crate::engine::EngineKind::Cpu);
        let mut r = e.evaluate(&Scenario::lunar(), &[Design::lunar_solution_c()]).pop().unwrap();
        assert!((objectives(&r)[0] - 0.03598).abs() < 1e-4);
        if let Ok(ev) = r.as_mut() {
            ev.performance.f_dynamic_hz = 2.5;
        }
        assert!((objectives(&r)[0] - (-2.0 + 0.5 * 1000.0)).abs() < 1e-9);
    }
}
