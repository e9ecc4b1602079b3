//! One calibration over several conditions (issue 43, item 1): campaigns made at other
//! speeds, slopes or fills, each with its own runs, setup and noise floor, fitted together.
//! The parameters are shared by default; a parameter may vary linearly with a condition's
//! variable where the data ask for it ([`crate::calibrate::varying`]). The report says which
//! are shared, how well each condition is fitted against its own floor, and how each is
//! predicted by a fit that did not see it (leave one condition out, from the setup's values
//! as the main fit starts). The main fit is one calibration of every condition on the batched
//! engine (one engine call per generation across the conditions); each left-out fit is one
//! more of the others.

use anyhow::bail;
use serde::Serialize;

use crate::calibrate::{
    Condition, Covariate, Effort, Model, ObjectiveKind, Param, Search, Simulator, Solver, Space, Target, Varying,
};
use crate::engine::BatchEvaluator;

/// What a joint fit does.
#[derive(Clone, Debug)]
pub struct JointSettings {
    pub objective: ObjectiveKind,
    pub effort: Effort,
    /// Parameters that vary, each with the variable it is linear in.
    pub varying: Vec<(Param, Covariate)>,
    /// Predict each condition from a fit of the others.
    pub leave_out: bool,
}

/// A condition's prediction by the fit of the other conditions.
#[derive(Clone, Debug, Serialize)]
pub struct LeftOut {
    /// The condition's own value of each fitted parameter at the others' fit (a varying one
    /// from the others' shared value and slope, at its variable).
    pub values: Vec<f64>,
    /// Its SSE on this condition, %², and this condition's noise floor at those bins.
    pub sse_percent2: f64,
    pub floor_percent2: f64,
}

/// One condition in the joint fit.
#[derive(Clone, Debug, Serialize)]
pub struct ConditionFit {
    pub name: String,
    pub data: String,
    pub setup: String,
    /// The condition's own value of each fitted parameter (a varying one at its variable).
    pub values: Vec<f64>,
    /// The fit's loss-adjusted SSE on this condition (Eq. 4.62), %², and its noise floor
    /// ([`Condition::noise_floor`]).
    pub sse_percent2: f64,
    pub floor_percent2: f64,
    /// Measured and fitted bins as compared (teeth, then the last bin).
    pub measured: Vec<f64>,
    pub fitted: Vec<f64>,
    pub left_out: Option<LeftOut>,
    /// Why there is no left-out prediction, where there is none.
    pub left_out_note: Option<String>,
}

/// Everything a joint fit settles on.
#[derive(Clone, Debug)]
pub struct JointReport {
    pub params: Vec<Param>,
    /// The searched dimensions: the parameters (at the variables' means where they vary),
    /// then the slopes.
    pub names: Vec<&'static str>,
    pub x: Vec<f64>,
    pub varying: Vec<Varying>,
    pub conditions: Vec<ConditionFit>,
    pub objective: ObjectiveKind,
    pub objective_value: f64,
    pub evaluations: u64,
    pub solver: Solver,
    pub notes: Vec<String>,
}

impl JointReport {
    pub fn sse_percent2(&self) -> f64 {
        self.conditions.iter().map(|c| c.sse_percent2).sum()
    }
    pub fn floor_percent2(&self) -> f64 {
        self.conditions.iter().map(|c| c.floor_percent2).sum()
    }
}

/// The space of `params` over `conditions` with the `varying` ones linear in their
/// variables.
fn space_for(params: &[Param], varying: &[(Param, Covariate)], conditions: &[Condition]) -> Result<Space, String> {
    let v = varying.iter().map(|(p, c)| Varying::new(*p, *c, conditions)).collect::<Result<Vec<_>, _>>()?;
    Space::new(params.to_vec(), &[], conditions).with_varying(v)
}

/// The start of a fit: the first condition's setup values of the parameters, slopes 0.
fn setup_start(space: &Space, conditions: &[Condition]) -> Vec<f64> {
    let mut x: Vec<f64> = space.shared.iter().map(|p| p.get(&conditions[0].base)).collect();
    x.resize(space.dim(), 0.0);
    x
}

/// Fit `params` over every condition, then (if asked) each condition from the others.
pub fn fit_joint(
    engine: &dyn BatchEvaluator,
    conditions: &[Condition],
    params: &[Param],
    settings: &JointSettings,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<JointReport> {
    if conditions.len() < 2 {
        bail!("a joint fit needs at least two conditions, got {}", conditions.len());
    }
    for (i, c) in conditions.iter().enumerate() {
        super::check(c, params).map_err(|e| anyhow::anyhow!("{} ({}): {e}", c.name, c.data))?;
        if conditions[..i].iter().any(|o| o.name == c.name) {
            bail!("two conditions are named `{}`: name each data file differently", c.name);
        }
    }
    let space = space_for(params, &settings.varying, conditions).map_err(anyhow::Error::msg)?;
    let (solver, note) = settings.effort.solver(settings.objective, conditions);
    let notes: Vec<String> = note.into_iter().collect();
    for n in &notes {
        log(format!("fit: note: {n}"));
    }
    log(format!(
        "fit: {} conditions jointly, {} particles per simulation (screen {}), DE {} x {} generations + {} compass \
         iterations",
        conditions.len(),
        solver.particles,
        solver.screen_particles,
        solver.pop,
        solver.generations,
        solver.polish_iterations
    ));
    let targets: Vec<_> = conditions.iter().map(Condition::target_all).collect();
    let sim = Simulator { engine, conditions };
    let main = solver
        .fit(
            &sim,
            &[Model {
                space: &space,
                targets: &targets,
                starts: vec![setup_start(&space, conditions)],
                search: Search::Global { stream: 0 },
            }],
            log,
        )?
        .remove(0);
    let objective_value = solver.value(&Some(main.bins.clone()), &targets, solver.particles);
    let draws = solver.particles as f64;
    let mut fits: Vec<ConditionFit> = conditions
        .iter()
        .zip(&targets)
        .zip(&main.bins)
        .map(|((c, t), bins)| {
            let scenario = space.scenario_at(c, &main.x);
            let compared = t.after_handling(bins).1;
            ConditionFit {
                name: c.name.clone(),
                data: c.data.clone(),
                setup: c.setup.clone(),
                values: params.iter().map(|p| p.get(&scenario)).collect(),
                sse_percent2: t.sse(bins),
                floor_percent2: c.noise_floor(&compared, draws),
                measured: t.bins.clone(),
                fitted: bins.clone(),
                left_out: None,
                left_out_note: None,
            }
        })
        .collect();
    let mut evaluations = main.evaluations;
    if settings.leave_out {
        for (c, fit) in fits.iter_mut().enumerate() {
            let others: Vec<Condition> =
                conditions.iter().enumerate().filter(|(i, _)| *i != c).map(|(_, o)| o.clone()).collect();
            let others_targets: Vec<Target> =
                targets.iter().enumerate().filter(|(i, _)| *i != c).map(|(_, t)| t.clone()).collect();
            let held = (&conditions[c], &targets[c]);
            match leave_out(engine, &solver, (&others, &others_targets), held, params, settings, log)? {
                Ok((left, n)) => {
                    evaluations += n;
                    fit.left_out = Some(left);
                }
                Err(why) => fit.left_out_note = Some(why),
            }
        }
    }
    Ok(JointReport {
        params: params.to_vec(),
        names: space.names(),
        x: main.x,
        varying: space.varying.clone(),
        conditions: fits,
        objective: settings.objective,
        objective_value,
        evaluations,
        solver,
        notes,
    })
}

/// Fit the `others` alone (from the setup's values, as the main fit starts) and score the fit
/// on `held`. The inner error says why no prediction is made (the others do not spread a
/// varying parameter's variable, or the engine rejected the held condition).
fn leave_out(
    engine: &dyn BatchEvaluator,
    solver: &Solver,
    (others, targets): (&[Condition], &[Target]),
    (held, target): (&Condition, &Target),
    params: &[Param],
    settings: &JointSettings,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Result<(LeftOut, u64), String>> {
    let space = match space_for(params, &settings.varying, others) {
        Ok(s) => s,
        Err(e) => return Ok(Err(format!("not predicted: without it, {e}"))),
    };
    log(format!("fit: {} left out, the others fitted alone", held.name));
    let sim = Simulator { engine, conditions: others };
    let model = Model {
        space: &space,
        targets,
        starts: vec![setup_start(&space, others)],
        search: Search::Global { stream: 0 },
    };
    let fit = solver.fit(&sim, &[model], log)?.remove(0);
    // the held condition at that fit: a varying parameter at its variable, from the others'
    // centre and slope
    let one = Simulator { engine, conditions: std::slice::from_ref(held) };
    let Some(Some(bins)) = one.simulate(&[(&space, fit.x.clone())], solver.particles, solver.seed).pop() else {
        return Ok(Err("not predicted: the engine rejected it at the others' fit".into()));
    };
    let compared = target.after_handling(&bins[0]).1;
    let scenario = space.scenario_at(held, &fit.x);
    Ok(Ok((
        LeftOut {
            values: params.iter().map(|p| p.get(&scenario)).collect(),
            sse_percent2: target.sse(&bins[0]),
            floor_percent2: held.noise_floor(&compared, solver.particles as f64),
        },
        fit.evaluations + 1,
    )))
}
