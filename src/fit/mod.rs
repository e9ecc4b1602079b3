//! Calibration of the collision and drag parameters against measured tooth masses: the
//! thesis's "fitment optimiser" (4.3.4-4.3.5, listing D.4), on the calibration engine that
//! `diagnose` uses ([`crate::calibrate`]), with an uncertainty estimate and a held-out score
//! it did not have.
//!
//! - Parameters ([`crate::calibrate::Param`]): `k_elastic`, `mu_fric`
//!   (collision.mu_friction) and `k_drag` (environment.k_drag), within listing D.4's bounds ([0.01, 1], [0.01, 1], [0.1, 15]);
//!   the ones not fitted keep the setup's values.
//! - Measured bins ([`crate::calibrate::Normalise`]): fractions of the loaded mass with a
//!   "not recovered" bin where every run records its input mass, else D.4's fractions of
//!   the recovered mass with a lost bin.
//! - Objectives ([`crate::calibrate::objective`]): the SSE of Eq. 4.62 over those bins, or a
//!   Dirichlet-multinomial negative log-likelihood of the individual runs.
//! - Solver ([`crate::calibrate::Solver`]): differential evolution at an eighth of the
//!   particles screens D.4's box, a compass search polishes at the full budget; every
//!   generation is one engine call; every candidate sees the same particle streams (common
//!   random numbers), so the objective is a deterministic (piecewise-constant) function of
//!   the parameters. The particle count is chosen from the data's run-to-run scatter
//!   ([`crate::calibrate::Effort`]) unless given.
//! - Held-out score ([`Heldout`]): the last K runs (file order) are left out and a fit on the
//!   others, run in lockstep with the main fit (one engine call per generation for both),
//!   is scored on them.
//! - Uncertainty ([`Uncertainty`]): runs resampled with replacement; each replicate is
//!   refitted by the compass search (all replicates in lockstep, one engine call per
//!   iteration) from the point of the main fit's polish archive that is best under the
//!   replicate's objective; standard deviation and the 16-84 % percentile interval. It
//!   measures how much the run-to-run scatter moves the optimum with the particle streams
//!   held fixed; it does not include the Monte-Carlo noise of a finite particle count (rerun
//!   with other `--seed`s for that) nor the misfit of a model that cannot reach the data,
//!   and a parameter pinned at a bound gets a one-sided, possibly degenerate interval.

pub mod joint;
pub mod report;
pub mod request;

use anyhow::bail;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::calibrate::objective::{self, Profiled};
use crate::calibrate::param::known_names;
use crate::calibrate::solver::MIN_STEP;
use crate::calibrate::stats::{percentile, sample_sd};
use crate::calibrate::{
    Condition, Effort, MeasuredSummary, Model, ObjectiveKind, Param, Search, Simulator, Solver, Space, Target,
};
use crate::engine::BatchEvaluator;
use crate::model::Scenario;

/// What `fit` does.
#[derive(Clone, Copy, Debug)]
pub struct FitSettings {
    pub objective: ObjectiveKind,
    pub effort: Effort,
    /// Bootstrap replicates (0 = off).
    pub bootstrap: usize,
    /// Runs held out at the end of the file (0 = off).
    pub holdout: usize,
}

/// Bootstrap uncertainty per parameter.
#[derive(Clone, Debug, Serialize)]
pub struct Uncertainty {
    pub replicates: usize,
    /// Sample standard deviation (n − 1) of the refitted values, per parameter.
    pub sd: Vec<f64>,
    /// 16th and 84th percentiles (linear interpolation), per parameter.
    pub interval: Vec<[f64; 2]>,
    /// The refitted parameters of every replicate.
    pub values: Vec<Vec<f64>>,
    pub evaluations: u64,
}

/// The setup's values of `params` (the solver's start; the unit box clamps them into bounds).
fn setup_values(params: &[Param], base: &Scenario) -> Vec<f64> {
    params.iter().map(|p| p.get(base)).collect()
}

/// Checks that hold for every fit and scoring of `condition`.
fn check(condition: &Condition, params: &[Param]) -> anyhow::Result<()> {
    let teeth = condition.teeth();
    let runs = &condition.runs;
    if params.is_empty() {
        bail!("no parameter to fit (known: {})", known_names());
    }
    if let Some(why) = params.iter().find_map(|p| p.refusal(&condition.base, &condition.setup)) {
        bail!(why);
    }
    if runs.teeth > teeth {
        bail!(
            "the measured data has {} teeth but the setup simulates only {teeth} (sim.teeth): raise sim.teeth",
            runs.teeth
        );
    }
    if !(condition.resolution_g.is_finite() && condition.resolution_g > 0.0) {
        bail!("scale resolution must be > 0 g, got {}", condition.resolution_g);
    }
    if runs.runs.iter().any(|r| r.recovered_g() <= 0.0) {
        bail!("every run needs a positive recovered mass");
    }
    Ok(())
}

/// The whole fit: the main fit on all runs and the held-out fit in lockstep, then the
/// bootstrap. `log` receives progress lines.
pub fn fit(
    engine: &dyn BatchEvaluator,
    condition: &Condition,
    params: &[Param],
    settings: FitSettings,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<FitReport> {
    check(condition, params)?;
    let n = condition.runs.runs.len();
    let k = settings.holdout;
    if k > 0 && k >= n {
        bail!("the held-out runs must be fewer than the runs ({n}), got {k}");
    }
    let conditions = std::slice::from_ref(condition);
    let (solver, note) = settings.effort.solver(settings.objective, conditions);
    let notes: Vec<String> = note.into_iter().collect();
    for n in &notes {
        log(format!("fit: note: {n}"));
    }
    let space = Space::new(params.to_vec(), &[], conditions);
    let sim = Simulator { engine, conditions };
    let start = setup_values(params, &condition.base);
    let all_targets = [condition.target_all()];
    let fit_idx: Vec<usize> = (0..n - k).collect();
    let held_idx: Vec<usize> = (n - k..n).collect();
    let fit_targets = [condition.target(&fit_idx)];
    let mut models = vec![Model {
        space: &space,
        targets: &all_targets,
        starts: vec![start.clone()],
        search: Search::Global { stream: 0 },
    }];
    if k > 0 {
        models.push(Model {
            space: &space,
            targets: &fit_targets,
            starts: vec![start],
            search: Search::Global { stream: 1 },
        });
    }
    log(format!(
        "fit: {} particles per simulation (screen {}), DE {} x {} generations + {} compass iterations{}",
        solver.particles,
        solver.screen_particles,
        solver.pop,
        solver.generations,
        solver.polish_iterations,
        if k > 0 { ", the held-out fit alongside" } else { "" }
    ));
    let mut fits = solver.fit(&sim, &models, log)?.into_iter();
    let main = fits.next().expect("the main fit");
    let heldout = fits.next().map(|h| {
        let held_target = condition.target(&held_idx);
        let fit_target = &fit_targets[0];
        let eps = objective::floor_for(solver.particles);
        let bins = &h.bins[0];
        let in_sample = fit_target.likelihood(bins, eps);
        let nll_heldout = -objective::dm_log_likelihood(
            &held_target.counts,
            &objective::model_probabilities(&held_target.counts, bins, eps),
            in_sample.concentration,
        );
        let ids = |idx: &[usize]| idx.iter().map(|&i| condition.runs.runs[i].id.clone()).collect();
        Heldout {
            k,
            heldout_runs: ids(&held_idx),
            fit_runs: ids(&fit_idx),
            sse_in_sample_percent2: fit_target.sse(bins),
            sse_heldout_percent2: held_target.sse(bins),
            sse_measured_fit_vs_heldout_percent2: objective::sse_percent2(&fit_target.bins, &held_target.bins),
            nll_heldout,
            nll_heldout_per_run: nll_heldout / k as f64,
            nll_in_sample_per_run: in_sample.nll / (n - k) as f64,
            evaluations: h.evaluations,
            params: h.x,
        }
    });
    let uncertainty = (settings.bootstrap > 0).then(|| {
        log(format!("fit: bootstrap, {} replicates refitted in lockstep", settings.bootstrap));
        bootstrap(&sim, &space, &solver, condition, &main, settings.bootstrap, log)
    });
    let uncertainty = uncertainty.transpose()?;
    Ok(report(
        condition,
        params,
        settings.objective,
        &solver,
        main.x,
        main.bins.into_iter().next().expect("one condition"),
        main.evaluations,
        uncertainty,
        heldout,
        Some(solver),
        notes,
    ))
}

/// Resample the runs with replacement `replicates` times and refit each resample with the
/// compass search, all in lockstep; each starts at the main fit's archive point (full
/// budget) that is best under its own objective.
fn bootstrap(
    sim: &Simulator,
    space: &Space,
    solver: &Solver,
    condition: &Condition,
    full: &crate::calibrate::Fit,
    replicates: usize,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Uncertainty> {
    let n = condition.runs.runs.len();
    let mut rng = ChaCha8Rng::seed_from_u64(solver.seed ^ 0xB007_5742);
    let targets: Vec<[Target; 1]> = (0..replicates)
        .map(|_| {
            let idx: Vec<usize> = (0..n).map(|_| rng.random_range(0..n)).collect();
            [condition.target(&idx)]
        })
        .collect();
    let models: Vec<Model> = targets
        .par_iter()
        .map(|t| {
            let start = full
                .archive
                .iter()
                .map(|p| (p, solver.value(&Some(p.bins.clone()), t, solver.particles)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map_or_else(|| full.x.clone(), |(p, _)| p.x.clone());
            Model { space, targets: t, starts: vec![start], search: Search::FromStarts }
        })
        .collect();
    // a resample's optimum lies near the full data's: finer steps than the main polish's,
    // down to 1/4000 of the box
    let refine = Solver { first_step: MIN_STEP * 4.0, min_step: 2.5e-4, ..*solver };
    let refits = refine.polish(sim, &models, log)?;
    let values: Vec<Vec<f64>> = refits.iter().map(|r| r.x.clone()).collect();
    let d = space.dim();
    let column = |j: usize| values.iter().map(|v| v[j]).collect::<Vec<f64>>();
    Ok(Uncertainty {
        replicates,
        sd: (0..d).map(|j| sample_sd(&column(j))).collect(),
        interval: (0..d).map(|j| [percentile(&column(j), 0.16), percentile(&column(j), 0.84)]).collect(),
        evaluations: refits.iter().map(|r| r.evaluations).sum(),
        values,
    })
}

/// The held-out score.
#[derive(Clone, Debug, Serialize)]
pub struct Heldout {
    /// Number of held-out runs (the last K in file order).
    pub k: usize,
    pub heldout_runs: Vec<String>,
    pub fit_runs: Vec<String>,
    /// Parameters fitted on the other runs.
    pub params: Vec<f64>,
    /// That fit's SSE against the mean of the runs it was fitted on, %².
    pub sse_in_sample_percent2: f64,
    /// That fit's SSE against the held-out runs' mean distribution, %².
    pub sse_heldout_percent2: f64,
    /// SSE between the two measured means (fit runs vs held-out runs): the run-to-run floor
    /// no model can beat, %².
    pub sse_measured_fit_vs_heldout_percent2: f64,
    /// Negative log-likelihood of the held-out runs under that fit, with the concentration
    /// estimated on the fit runs (not re-profiled), total and per run.
    pub nll_heldout: f64,
    pub nll_heldout_per_run: f64,
    /// Negative log-likelihood of the fit runs (concentration profiled), per run.
    pub nll_in_sample_per_run: f64,
    pub evaluations: u64,
}

/// Everything `fit` settles on.
#[derive(Clone, Debug)]
pub struct FitReport {
    pub params: Vec<Param>,
    /// Best parameters (same order as `params`).
    pub x: Vec<f64>,
    /// The setup's values of the fitted parameters.
    pub setup_values: Vec<f64>,
    pub objective: ObjectiveKind,
    /// The minimised objective's value (SSE in %² or NLL).
    pub objective_value: f64,
    pub sse_percent2: f64,
    /// Mean absolute error over the weighed teeth, percentage points.
    pub mae_percent: f64,
    pub likelihood: Profiled,
    /// [`Target::measured_mean_likelihood`] of all runs.
    pub measured_mean_likelihood: Profiled,
    pub runs: usize,
    pub resolution_g: f64,
    /// The measured bins as compared (teeth, then the last bin), with the runs' spread.
    pub measured: MeasuredSummary,
    /// What the last bin holds: "lost" or "not recovered" ([`Condition::last_bin_label`]).
    pub last_bin: &'static str,
    /// Fitted bins as compared: the setup's teeth, then the last bin.
    pub fitted: Vec<f64>,
    pub uncertainty: Option<Uncertainty>,
    pub heldout: Option<Heldout>,
    /// Simulations run by the main fit (screen and polish).
    pub evaluations: u64,
    /// The solver's settings; None when the parameters were given ([`evaluate_at`]).
    pub solver: Option<Solver>,
    /// Particles per simulation of the fitted bins.
    pub particles: u32,
    /// What the user should know about the result (e.g. a Monte-Carlo-limited budget).
    pub notes: Vec<String>,
}

#[allow(clippy::too_many_arguments)]
fn report(
    condition: &Condition,
    params: &[Param],
    kind: ObjectiveKind,
    scored_with: &Solver,
    x: Vec<f64>,
    bins: Vec<f64>,
    evaluations: u64,
    uncertainty: Option<Uncertainty>,
    heldout: Option<Heldout>,
    solver: Option<Solver>,
    notes: Vec<String>,
) -> FitReport {
    let target = condition.target_all();
    let eps = objective::floor_for(scored_with.particles);
    let weighed = condition.runs.teeth;
    FitReport {
        params: params.to_vec(),
        setup_values: setup_values(params, &condition.base),
        objective: kind,
        objective_value: target.value(kind, Some(&bins), eps),
        sse_percent2: target.sse(&bins),
        mae_percent: objective::mae_percent(&bins[..weighed], &target.bins[..weighed]),
        likelihood: target.likelihood(&bins, eps),
        measured_mean_likelihood: target.measured_mean_likelihood(),
        runs: condition.runs.runs.len(),
        resolution_g: condition.resolution_g,
        measured: condition.summary(),
        last_bin: condition.last_bin_label(),
        fitted: bins,
        uncertainty,
        heldout,
        evaluations,
        solver,
        particles: scored_with.particles,
        notes,
        x,
    }
}

/// Score given parameter values against all runs, without fitting: the same report as
/// [`fit`] with no uncertainty and no held-out score, at `particles` per simulation (or
/// what the data call for) and `seed`.
pub fn evaluate_at(
    engine: &dyn BatchEvaluator,
    condition: &Condition,
    params: &[Param],
    x: &[f64],
    kind: ObjectiveKind,
    effort: Effort,
) -> anyhow::Result<FitReport> {
    check(condition, params)?;
    let conditions = std::slice::from_ref(condition);
    let space = Space::new(params.to_vec(), &[], conditions);
    space.scenario_at(condition, x).validate().map_err(anyhow::Error::msg)?;
    let (solver, note) = effort.solver(kind, conditions);
    let sim = Simulator { engine, conditions };
    let Some(mut bins) = sim.simulate(&[(&space, x.to_vec())], solver.particles, solver.seed).pop().flatten() else {
        bail!("the engine rejected the setup at these parameters");
    };
    Ok(report(
        condition,
        params,
        kind,
        &solver,
        x.to_vec(),
        bins.remove(0),
        1,
        None,
        None,
        None,
        note.into_iter().collect(),
    ))
}
