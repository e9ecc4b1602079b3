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
use crate::model::{Invalid, Scenario};

/// MATLAB's default ConstraintTolerance (5.2).
pub const CONSTRAINT_TOLERANCE: f64 = 1e-3;
/// f_limit of 5.3.1, Hz.
pub const F_LIMIT: f64 = 2.0;
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
    pub evaluation: Option<Evaluation>,
    pub invalid: Option<String>,
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
}

impl SawtoothProblem<'_> {
    pub fn seed_for(&self, generation: u64) -> u64 {
        self.base_seed.wrapping_add(generation.wrapping_mul(0x9E37_79B9_7F4A_7C15))
    }
}

impl BatchProblem for SawtoothProblem<'_> {
    fn dim(&self) -> usize {
        8
    }
    fn n_objectives(&self) -> usize {
        2
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        (LOWER_BOUND_CLI.to_vec(), UPPER_BOUND_CLI.to_vec())
    }
    /// Sort the four lengths so the chain l_b <= r <= l_a <= l_c holds where the bounds allow
    /// (gamultiobj keeps linear constraints satisfied in creation and mutation).
    fn repair(&self, x: &mut [f64]) {
        let mut v = [x[0], x[1], x[3], x[2]]; // l_c, l_a, r, l_b in chain order
        v.sort_by(|a, b| b.total_cmp(a));
        x[0] = v[0].clamp(LOWER_BOUND_CLI[0], UPPER_BOUND_CLI[0]);
        x[1] = v[1].clamp(LOWER_BOUND_CLI[1], UPPER_BOUND_CLI[1]);
        x[3] = v[2].clamp(LOWER_BOUND_CLI[3], UPPER_BOUND_CLI[3]);
        x[2] = v[3].clamp(LOWER_BOUND_CLI[2], UPPER_BOUND_CLI[2]);
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], generation: u64) -> Vec<GaEvaluation> {
        let mut s = self.scenario.clone();
        s.sim.seed = self.seed_for(generation);
        let violations: Vec<f64> = xs.iter().map(|x| violation(x)).collect();
        // Infeasible individuals are not simulated: Deb's rules rank them by violation alone.
        let to_eval: Vec<usize> = (0..xs.len()).filter(|&i| violations[i] == 0.0).collect();
        let designs: Vec<Design> = to_eval.iter().map(|&i| design_of(&xs[i])).collect();
        let mut results = self.engine.evaluate(&s, &designs).into_iter();
        let mut logged = Vec::with_capacity(xs.len());
        let mut out = Vec::with_capacity(xs.len());
        for (i, x) in xs.iter().enumerate() {
            let (objs, evaluation, invalid) = if violations[i] == 0.0 {
                let r = results.next().expect("one result per design");
                let o = objectives(&r);
                match r {
                    Ok(e) => (o, Some(e), None),
                    Err(e) => (o, None, Some(e.rule().to_string())),
                }
            } else {
                // finite so JSON checkpoints can hold it; Deb's rules rank by violation anyway
                ([1e12, 1e12], None, None)
            };
            logged.push(Logged {
                generation,
                x: design_of(x).to_cli_units(),
                objectives: objs,
                violation: violations[i],
                evaluation,
                invalid,
            });
            out.push(GaEvaluation { objectives: objs.to_vec(), violation: violations[i] });
        }
        if let Some(log) = self.log.as_mut() {
            log(&logged);
        }
        out
    }
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
        let p = SawtoothProblem { scenario: Scenario::lunar(), engine: &e, base_seed: 0, log: None };
        let mut x = vec![10.0, 30.0, 20.0, 5.0, 60.0, 10.0, 1.0, 30.0];
        p.repair(&mut x);
        assert!(x[2] <= x[3] && x[3] <= x[1] && x[1] <= x[0], "{x:?}");
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
