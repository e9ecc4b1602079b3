//! A checkpoint read back is input like any other (issue 34): an edited or damaged
//! checkpoint.json must be refused naming its field and the rule, not believed (a
//! `generation` of 999999) nor left to panic deep in the solver (an empty population, an `x`
//! of five entries). The rules follow from how [`super::nsga2::Nsga2`] builds its state:
//! `init` evaluates `pop` candidates and records one spread; each step evaluates `pop`
//! offspring, keeps `pop` survivors and records one more spread.

use super::nsga2::{Config, State};

/// The shape of the problem a checkpoint must fit: its variables and objectives, and where
/// known the box the solver keeps every variable in and the least value each objective takes.
#[derive(Debug, Clone, Copy)]
pub struct Shape {
    pub dim: usize,
    pub objectives: usize,
    /// Lower and upper bounds of the variables (`BatchProblem::bounds`).
    pub bounds: Option<(&'static [f64], &'static [f64])>,
    /// The least value of each objective the problem can give.
    pub objective_min: Option<&'static [f64]>,
}

impl Shape {
    /// A problem of `dim` variables and `objectives` objectives, nothing more known.
    pub const fn new(dim: usize, objectives: usize) -> Shape {
        Shape { dim, objectives, bounds: None, objective_min: None }
    }
}

/// Check `state` against the run's `config` and the problem's `shape`.
pub fn validate_state(state: &State, config: &Config, shape: Shape) -> Result<(), String> {
    let pop = config.pop;
    if state.population.len() != pop {
        return Err(format!(
            "`population` holds {} members, but the run's population (config.pop) is {pop}",
            state.population.len()
        ));
    }
    if state.generation > config.max_generations {
        return Err(format!(
            "`generation` {} lies beyond the run's last generation (config.max_generations = {})",
            state.generation, config.max_generations
        ));
    }
    let expected = (pop as u64).checked_mul(state.generation.saturating_add(1));
    if expected != Some(state.evaluations) {
        return Err(format!(
            "`evaluations` {} disagrees with `generation` {}: a run of population {pop} has evaluated {} candidates by then",
            state.evaluations,
            state.generation,
            expected.map_or("more than 2^64".to_string(), |e| e.to_string())
        ));
    }
    if state.spread_history.len() as u64 != state.generation.saturating_add(1) {
        return Err(format!(
            "`spread_history` holds {} entries; generation {} has {} (one per generation and the initial one)",
            state.spread_history.len(),
            state.generation,
            state.generation.saturating_add(1)
        ));
    }
    if !(state.prev_extremes.is_empty() || state.prev_extremes.len() == shape.objectives)
        || state.prev_extremes.iter().any(|e| e.len() != shape.objectives)
    {
        return Err(format!(
            "`prev_extremes` must be empty or {m} points of {m} objectives each",
            m = shape.objectives
        ));
    }
    for (i, ind) in state.population.iter().enumerate() {
        if ind.x.len() != shape.dim {
            return Err(format!("`population[{i}].x` has {} entries; a design has {}", ind.x.len(), shape.dim));
        }
        if let Some(v) = ind.x.iter().find(|v| !v.is_finite()) {
            return Err(format!("`population[{i}].x` holds {v}; a design's variables are finite"));
        }
        // the solver keeps every candidate inside the problem's box (creation, crossover and
        // mutation clamp to it)
        if let Some((lo, hi)) = shape.bounds {
            if let Some(k) = (0..shape.dim).find(|&k| !(lo[k]..=hi[k]).contains(&ind.x[k])) {
                return Err(format!(
                    "`population[{i}].x[{k}]` is {:?}; the problem keeps it within [{}, {}]",
                    ind.x[k], lo[k], hi[k]
                ));
            }
        }
        // a NaN objective is stored as +inf (`Evaluation::sanitised`), so NaN is an edit
        for (k, f) in ind.eval.objectives.iter().enumerate() {
            let least = shape.objective_min.map_or(f64::NEG_INFINITY, |m| m[k]);
            if f.is_nan() || *f < least {
                return Err(format!(
                    "`population[{i}].eval.objectives[{k}]` is {f:?}; the problem's objectives are numbers >= {least}"
                ));
            }
        }
        if ind.eval.objectives.len() != shape.objectives {
            return Err(format!(
                "`population[{i}].eval.objectives` has {} entries; the problem has {}",
                ind.eval.objectives.len(),
                shape.objectives
            ));
        }
        if ind.eval.violation.is_nan() || ind.eval.violation < 0.0 {
            return Err(format!("`population[{i}].eval.violation` is {}; it is a number >= 0", ind.eval.violation));
        }
        if ind.rank >= pop.max(1) * 2 {
            return Err(format!("`population[{i}].rank` {} is beyond any front of {} candidates", ind.rank, pop * 2));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::test_problems::Zdt1;
    use crate::optim::{Mode, Nsga2};

    fn a_real_state() -> (State, Config, Shape) {
        let config = Config { pop: 8, max_generations: 3, mode: Mode::Standard, ..Config::default() };
        let ga = Nsga2::new(config.clone());
        let mut problem = Zdt1 { n: 5 };
        let mut state = ga.init(&mut problem);
        for _ in 0..2 {
            ga.step(&mut state, &mut problem);
        }
        (state, config, Shape::new(5, 2))
    }

    #[test]
    fn a_state_the_solver_made_is_accepted() {
        let (state, config, shape) = a_real_state();
        validate_state(&state, &config, shape).unwrap();
    }

    #[test]
    fn edited_states_are_refused_naming_the_field() {
        let (state, config, shape) = a_real_state();
        type Edit = Box<dyn Fn(&mut State)>;
        let cases: Vec<(&str, Edit)> = vec![
            ("`population` holds 0", Box::new(|s| s.population.clear())),
            ("`population[3].x` has 0", Box::new(|s| s.population[3].x.clear())),
            ("`population[0].x` has 9", Box::new(|s| s.population[0].x.extend([1.0; 4]))),
            ("`population[1].x` holds NaN", Box::new(|s| s.population[1].x[0] = f64::NAN)),
            ("`generation` 999999", Box::new(|s| s.generation = 999_999)),
            ("`evaluations` 7", Box::new(|s| s.evaluations = 7)),
            ("`spread_history` holds 1", Box::new(|s| s.spread_history.truncate(1))),
            ("`population[2].eval.objectives` has 1", Box::new(|s| s.population[2].eval.objectives.truncate(1))),
            ("`prev_extremes`", Box::new(|s| s.prev_extremes = vec![vec![1.0]])),
            ("`population[4].eval.objectives[1]` is NaN", Box::new(|s| s.population[4].eval.objectives[1] = f64::NAN)),
        ];
        for (want, edit) in cases {
            let mut s = state.clone();
            edit(&mut s);
            let e = validate_state(&s, &config, shape).unwrap_err();
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    /// Issue 45: a checkpoint of the thesis's problem with `x[0]` = 1e308 or an objective of
    /// -1e308 is refused; the solver never makes either.
    #[test]
    fn variables_outside_the_box_and_objectives_below_their_least_are_refused() {
        let (state, config, _) = a_real_state();
        let shape =
            Shape { dim: 5, objectives: 2, bounds: Some((&[0.0; 5], &[1.0; 5])), objective_min: Some(&[0.0, 0.0]) };
        validate_state(&state, &config, shape).unwrap();
        let mut s = state.clone();
        s.population[0].x[0] = 1e308;
        assert!(validate_state(&s, &config, shape).unwrap_err().contains("`population[0].x[0]` is 1e308"));
        let mut s = state.clone();
        s.population[2].eval.objectives[0] = -1e308;
        let e = validate_state(&s, &config, shape).unwrap_err();
        assert!(e.contains("`population[2].eval.objectives[0]` is -1e308"), "{e}");
        let mut s = state;
        s.population[2].eval.objectives[0] = f64::INFINITY;
        validate_state(&s, &config, shape).unwrap();
    }
}
