//! A checkpoint read back is input like any other (issue 34): an edited or damaged
//! checkpoint.json must be refused naming its field and the rule, not believed (a
//! `generation` of 999999) nor left to panic deep in the solver (an empty population, an `x`
//! of five entries). The rules follow from how [`super::nsga2::Nsga2`] builds its state:
//! `init` evaluates `pop` candidates and records one spread; each step evaluates `pop`
//! offspring, keeps `pop` survivors and records one more spread.

use super::nsga2::{Config, State};

/// The shape of the problem a checkpoint must fit: its variables and objectives.
#[derive(Debug, Clone, Copy)]
pub struct Shape {
    pub dim: usize,
    pub objectives: usize,
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
        (state, config, Shape { dim: 5, objectives: 2 })
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
        ];
        for (want, edit) in cases {
            let mut s = state.clone();
            edit(&mut s);
            let e = validate_state(&s, &config, shape).unwrap_err();
            assert!(e.contains(want), "{want}: {e}");
        }
    }
}
