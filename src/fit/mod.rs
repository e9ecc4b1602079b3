//! Calibration of the collision and drag parameters against measured tooth masses: the
//! thesis's "fitment optimiser" (4.3.4-4.3.5, listing D.4), with an uncertainty estimate and
//! a held-out score it did not have.
//!
//! - Parameters ([`Param`]): `k_elastic`, `mu_fric` (collision.mu_friction) and `k_drag`
//!   (environment.k_drag), within listing D.4's bounds ([0.01, 1], [0.01, 1], [0.1, 15]);
//!   the ones not fitted keep the setup's values.
//! - Every candidate is simulated with the setup's scenario and design, the same particle
//!   count and the same seed: common random numbers, so the objective is a deterministic
//!   (piecewise-constant) function of the parameters.
//! - Objectives ([`objective`]): the SSE of Eq. 4.62 over the setup's teeth plus a lost bin
//!   (D.4), or a Dirichlet-multinomial negative log-likelihood of the individual runs.
//! - Optimiser: the crate's GA ([`crate::optim::nsga2`] with one objective: elitist
//!   (μ + λ) survival, SBX and polynomial mutation), uniform initial population, fixed seed;
//!   every generation is evaluated as one batch (one engine call per candidate, in parallel);
//!   the GA's best is then polished by a bounded Nelder-Mead ([`polish`]).
//! - Uncertainty ([`bootstrap`]): runs resampled with replacement; each replicate is refitted
//!   by a bounded Nelder-Mead ([`nelder_mead`]) started from the GA archive's best point
//!   under the replicate's objective; standard deviation and the 16-84 % percentile interval.
//!   It measures how much the run-to-run scatter moves the optimum with the particle streams
//!   held fixed; it does not include the Monte-Carlo noise of a finite particle count (rerun
//!   with other `--seed`s for that) nor the misfit of a model that cannot reach the data,
//!   and a parameter pinned at a bound gets a one-sided, possibly degenerate interval.
//! - Held-out score ([`holdout`]): the last K runs (file order) are left out, a full GA fit
//!   on the others is scored on them.

pub mod nelder_mead;
pub mod objective;
pub mod report;

use anyhow::{bail, Context as _};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::engine::BatchEvaluator;
use crate::io::measured::MeasuredRuns;
use crate::model::{Design, Scenario};
use crate::optim::nsga2::{BatchProblem, Config, Evaluation as GaEvaluation, Mode, Nsga2};

use objective::Profiled;

/// A fitted scenario parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// Elastic normal coefficient of restitution, `collision.k_elastic`.
    KElastic,
    /// Friction coefficient of the tangential COR, `collision.mu_friction`.
    MuFric,
    /// Stokes drag parameter, 1/s, `environment.k_drag`.
    KDrag,
}

impl Param {
    pub const ALL: [Param; 3] = [Param::KElastic, Param::MuFric, Param::KDrag];

    /// The name on the command line and in the outputs.
    pub fn name(self) -> &'static str {
        match self {
            Param::KElastic => "k_elastic",
            Param::MuFric => "mu_fric",
            Param::KDrag => "k_drag",
        }
    }

    /// Listing D.4's bounds (`lb = [0.01, 0.01, 0.1]`, `ub = [1, 1, 15]`).
    pub fn bounds(self) -> (f64, f64) {
        match self {
            Param::KElastic | Param::MuFric => (0.01, 1.0),
            Param::KDrag => (0.1, 15.0),
        }
    }

    pub fn apply(self, s: &mut Scenario, v: f64) {
        match self {
            Param::KElastic => s.collision.k_elastic = v,
            Param::MuFric => s.collision.mu_friction = v,
            Param::KDrag => s.environment.k_drag = Some(v),
        }
    }

    /// The scenario's value (k_drag 0 in vacuum).
    pub fn get(self, s: &Scenario) -> f64 {
        match self {
            Param::KElastic => s.collision.k_elastic,
            Param::MuFric => s.collision.mu_friction,
            Param::KDrag => s.environment.k_drag.unwrap_or(0.0),
        }
    }
}

fn known_names() -> String {
    Param::ALL.iter().map(|p| p.name()).collect::<Vec<_>>().join(", ")
}

/// A comma list of parameter names (`k_elastic,mu_fric,k_drag`), each once.
pub fn parse_params(list: &str) -> anyhow::Result<Vec<Param>> {
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim) {
        if name.is_empty() {
            bail!("--params: empty parameter name in `{list}` (known: {})", known_names());
        }
        let Some(p) = Param::ALL.iter().copied().find(|p| p.name() == name) else {
            bail!("--params: unknown parameter `{name}` (known: {})", known_names());
        };
        if out.contains(&p) {
            bail!("--params: parameter `{name}` given twice");
        }
        out.push(p);
    }
    Ok(out)
}

/// Which objective the optimiser minimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectiveKind {
    /// Eq. 4.62 / listing D.4: Σ (simulated % − measured %)² over the teeth and a lost bin.
    Sse,
    /// Dirichlet-multinomial negative log-likelihood of the runs, concentration profiled out.
    Likelihood,
}

/// What a set of measured runs offers the objectives.
#[derive(Clone, Debug)]
pub struct Target {
    /// Mean distribution (fraction of the mean masses), padded to the setup's teeth, plus a
    /// lost bin of 0.
    pub bins: Vec<f64>,
    /// Per run: tooth masses in scale units, padded the same way.
    pub counts: Vec<Vec<f64>>,
}

impl Target {
    /// Fractions of the *loaded* mass (every run must record `input_mass`): the weighed teeth
    /// (Σ masses / Σ input masses), zeros for the teeth not weighed, and a last bin for what
    /// was not recovered (grains beyond the weighed teeth or lost, and spill), which
    /// [`collapse_to_weighed`] makes of the simulated bins. Unlike [`Target::new`] (D.4's
    /// normalisation to the recovered mass, with simulated mass beyond the weighed teeth
    /// counted as misfit), it stays right when the weighed teeth do not hold every grain.
    pub fn of_loaded_mass(runs: &MeasuredRuns, teeth: usize, resolution_g: f64) -> Option<Self> {
        let input: f64 = runs.runs.iter().map(|r| r.input_mass_g).sum::<Option<f64>>()?;
        if !(input > 0.0) {
            return None;
        }
        let mut bins = vec![0.0; teeth + 1];
        for r in &runs.runs {
            for (b, m) in bins.iter_mut().zip(&r.teeth_g) {
                *b += m / input;
            }
        }
        bins[teeth] = (1.0 - bins[..runs.teeth].iter().sum::<f64>()).max(0.0);
        Some(Target { bins, counts: runs.runs.iter().map(|r| objective::quantised_counts(&r.teeth_g, teeth, resolution_g)).collect() })
    }

    pub fn new(runs: &MeasuredRuns, teeth: usize, resolution_g: f64) -> Self {
        Target {
            bins: objective::measured_bins(&runs.mean_fractions(), teeth),
            counts: runs.runs.iter().map(|r| objective::quantised_counts(&r.teeth_g, teeth, resolution_g)).collect(),
        }
    }

    /// The objective for simulated bins; +inf for a candidate that could not be simulated.
    pub fn value(&self, kind: ObjectiveKind, bins: Option<&[f64]>, eps: f64) -> f64 {
        match (kind, bins) {
            (_, None) => f64::INFINITY,
            (ObjectiveKind::Sse, Some(b)) => objective::sse_percent2(b, &self.bins),
            (ObjectiveKind::Likelihood, Some(b)) => objective::profile_nll(&self.counts, b, eps).nll,
        }
    }

    pub fn sse(&self, bins: &[f64]) -> f64 {
        objective::sse_percent2(bins, &self.bins)
    }

    pub fn likelihood(&self, bins: &[f64], eps: f64) -> Profiled {
        objective::profile_nll(&self.counts, bins, eps)
    }

    /// The likelihood with the mean set to the measured mean distribution (a perfect mean
    /// model): its NLL is the reference a fitted model's NLL is compared with, its
    /// concentration the one the runs' scatter alone implies. A fit whose profiled α0 is
    /// far below that explains misfit of the mean as over-dispersion.
    pub fn measured_mean_likelihood(&self) -> Profiled {
        objective::profile_nll(&self.counts, &self.bins, 1e-12)
    }
}

/// Simulated bins (teeth, then lost) as a rig that weighs only the first `weighed` teeth
/// sees them: those teeth, zeros for the others, and everything else in the last bin (the
/// counterpart of [`Target::of_loaded_mass`]).
pub fn collapse_to_weighed(bins: &[f64], weighed: usize) -> Vec<f64> {
    let n = bins.len();
    let mut out = vec![0.0; n];
    out[..weighed].copy_from_slice(&bins[..weighed]);
    out[n - 1] = (1.0 - bins[..weighed].iter().sum::<f64>()).max(0.0);
    out
}

/// `runs` restricted to the given indices (repeats allowed, for the bootstrap).
pub fn subset(runs: &MeasuredRuns, indices: &[usize]) -> MeasuredRuns {
    MeasuredRuns { runs: indices.iter().map(|&i| runs.runs[i].clone()).collect(), ..runs.clone() }
}

/// The simulation side: an engine, the setup's scenario and design, the fitted parameters.
pub struct Problem<'a> {
    pub engine: &'a dyn BatchEvaluator,
    /// The setup's scenario with the fit's particle count and seed.
    pub base: Scenario,
    pub design: Design,
    pub params: Vec<Param>,
}

impl<'a> Problem<'a> {
    /// Checks the scenario and that the design can be simulated at all.
    pub fn new(
        engine: &'a dyn BatchEvaluator,
        base: Scenario,
        design: Design,
        params: Vec<Param>,
    ) -> anyhow::Result<Self> {
        if params.is_empty() {
            bail!("--params: no parameter to fit (known: {})", known_names());
        }
        base.validate().map_err(anyhow::Error::msg).context("invalid setup")?;
        if let Err(invalid) = crate::model::prepare(&base, &design) {
            bail!("the setup's design cannot be simulated ({}): {invalid}", invalid.rule());
        }
        Ok(Problem { engine, base, design, params })
    }

    pub fn teeth(&self) -> usize {
        self.base.sim.teeth as usize
    }

    /// The probability floor of the likelihood for this particle count.
    pub fn eps(&self) -> f64 {
        objective::floor_for(self.base.sim.particles)
    }

    pub fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        self.params.iter().map(|p| p.bounds()).unzip()
    }

    /// The setup's values of the fitted parameters.
    pub fn setup_values(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.get(&self.base)).collect()
    }

    pub fn scenario_at(&self, x: &[f64]) -> Scenario {
        let mut s = self.base.clone();
        for (p, v) in self.params.iter().zip(x) {
            p.apply(&mut s, *v);
        }
        s
    }

    /// Simulated bins (teeth, then lost) at parameters `x`; None when the engine rejects it.
    pub fn bins_at(&self, x: &[f64]) -> Option<Vec<f64>> {
        let s = self.scenario_at(x);
        self.engine
            .evaluate(&s, std::slice::from_ref(&self.design))
            .pop()
            .and_then(|r| r.ok())
            .map(|e| objective::simulated_bins(&e.sim))
    }

    /// [`Self::bins_at`] for a whole generation as one engine call (one one-design group per
    /// candidate: the engine runs them together, as the calibration engine does).
    pub fn bins_many(&self, xs: &[Vec<f64>]) -> Vec<Option<Vec<f64>>> {
        let groups: Vec<(Scenario, Vec<Design>)> = xs.iter().map(|x| (self.scenario_at(x), vec![self.design])).collect();
        self.engine
            .evaluate_groups(&groups)
            .into_iter()
            .map(|r| r.into_iter().next().and_then(|e| e.ok()).map(|e| objective::simulated_bins(&e.sim)))
            .collect()
    }

    /// Parameters from unit-box coordinates.
    pub fn from_unit(&self, u: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(u)
            .map(|(p, u)| {
                let (lo, hi) = p.bounds();
                lo + u.clamp(0.0, 1.0) * (hi - lo)
            })
            .collect()
    }

    pub fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(x)
            .map(|(p, x)| {
                let (lo, hi) = p.bounds();
                ((x - lo) / (hi - lo)).clamp(0.0, 1.0)
            })
            .collect()
    }
}

/// GA settings.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct GaSettings {
    pub pop: usize,
    pub generations: u64,
    pub seed: u64,
}

/// One evaluated candidate.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub x: Vec<f64>,
    /// None when the engine rejected it.
    pub bins: Option<Vec<f64>>,
}

/// A GA fit.
#[derive(Clone, Debug)]
pub struct GaFit {
    pub x: Vec<f64>,
    pub value: f64,
    pub bins: Vec<f64>,
    pub evaluations: u64,
    /// Every candidate evaluated, in order.
    pub archive: Vec<Candidate>,
}

struct GaProblem<'p, 'a> {
    problem: &'p Problem<'a>,
    target: &'p Target,
    kind: ObjectiveKind,
    archive: Vec<Candidate>,
    progress: &'p mut dyn FnMut(u64, f64),
}

impl BatchProblem for GaProblem<'_, '_> {
    fn dim(&self) -> usize {
        self.problem.params.len()
    }
    fn n_objectives(&self) -> usize {
        1
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        self.problem.bounds()
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], generation: u64) -> Vec<GaEvaluation> {
        let bins = self.problem.bins_many(xs);
        let eps = self.problem.eps();
        let values: Vec<f64> = bins.par_iter().map(|b| self.target.value(self.kind, b.as_deref(), eps)).collect();
        let best = values.iter().copied().fold(f64::INFINITY, f64::min);
        (self.progress)(generation, best);
        self.archive.extend(xs.iter().cloned().zip(bins).map(|(x, bins)| Candidate { x, bins }));
        values.into_iter().map(|v| GaEvaluation { objectives: vec![v], violation: 0.0 }).collect()
    }
}

/// Minimise the objective over the parameters' bounds with the GA. `progress` sees each
/// generation's number and its best objective value.
pub fn ga_fit(
    problem: &Problem,
    target: &Target,
    kind: ObjectiveKind,
    settings: GaSettings,
    progress: &mut dyn FnMut(u64, f64),
) -> anyhow::Result<GaFit> {
    if settings.pop < 4 {
        bail!("--pop must be >= 4, got {}", settings.pop);
    }
    let ga = Nsga2::new(Config {
        pop: settings.pop,
        seed: settings.seed,
        max_generations: settings.generations,
        mode: Mode::Standard,
        ..Config::default()
    });
    let mut gp = GaProblem { problem, target, kind, archive: Vec::new(), progress };
    let (state, _) = ga.run(&mut gp, |_, _| {});
    let best = state
        .population
        .iter()
        .min_by(|a, b| a.eval.objectives[0].total_cmp(&b.eval.objectives[0]))
        .context("empty population")?;
    let value = best.eval.objectives[0];
    let bins =
        gp.archive.iter().find(|c| c.x == best.x).and_then(|c| c.bins.clone()).or_else(|| problem.bins_at(&best.x));
    let Some(bins) = bins.filter(|_| value.is_finite()) else {
        bail!("no candidate could be simulated (every evaluation was rejected by the engine)");
    };
    Ok(GaFit { x: best.x.clone(), value, bins, evaluations: state.evaluations, archive: gp.archive })
}

/// Polish a GA result with a bounded Nelder-Mead (the same local search the bootstrap
/// refits use, so the estimate and its replicates come from one procedure). Keeps the GA's
/// point unless the polish is strictly better; the archive is left as the GA's.
pub fn polish(problem: &Problem, target: &Target, kind: ObjectiveKind, fit: GaFit, max_evals: usize) -> GaFit {
    let eps = problem.eps();
    let m = nelder_mead::minimise(
        |u| target.value(kind, problem.bins_at(&problem.from_unit(u)).as_deref(), eps),
        &problem.to_unit(&fit.x),
        0.05,
        max_evals,
        1e-4,
    );
    let x = problem.from_unit(&m.x);
    let evaluations = fit.evaluations + m.evaluations as u64;
    match problem.bins_at(&x) {
        Some(bins) if m.value < fit.value => GaFit { x, value: m.value, bins, evaluations: evaluations + 1, ..fit },
        _ => GaFit { evaluations, ..fit },
    }
}

/// [`ga_fit`], then [`polish`] with the bootstrap's budget.
pub fn global_fit(
    problem: &Problem,
    target: &Target,
    kind: ObjectiveKind,
    settings: GaSettings,
    progress: &mut dyn FnMut(u64, f64),
) -> anyhow::Result<GaFit> {
    let fit = ga_fit(problem, target, kind, settings, progress)?;
    Ok(polish(problem, target, kind, fit, bootstrap_evals(problem.params.len())))
}

/// Bootstrap settings.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct BootstrapSettings {
    pub replicates: usize,
    pub seed: u64,
    /// Nelder-Mead evaluations per replicate.
    pub max_evals: usize,
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
    pub evaluations: usize,
}

/// Percentile `q` in [0, 1] of `v` (linear interpolation between order statistics).
pub fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < s.len() {
        s[i] + f * (s[i + 1] - s[i])
    } else {
        s[i]
    }
}

fn sample_sd(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return f64::NAN;
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// Resample the runs with replacement `replicates` times and refit each resample: start at
/// the archive point (GA evaluations, best `ARCHIVE_STARTS` under the full data) that is best
/// under the resample's objective, then a bounded Nelder-Mead with `max_evals` evaluations.
pub fn bootstrap(
    problem: &Problem,
    runs: &MeasuredRuns,
    resolution_g: f64,
    kind: ObjectiveKind,
    full: &GaFit,
    full_target: &Target,
    settings: BootstrapSettings,
) -> Uncertainty {
    const ARCHIVE_STARTS: usize = 200;
    let eps = problem.eps();
    // distinct archive points, best first under the full data
    let mut starts: Vec<(Vec<f64>, Vec<f64>, f64)> = Vec::new();
    for c in &full.archive {
        if let Some(b) = &c.bins {
            if !starts.iter().any(|(x, _, _)| *x == c.x) {
                starts.push((c.x.clone(), b.clone(), 0.0));
            }
        }
    }
    starts.par_iter_mut().for_each(|(_, b, v)| *v = full_target.value(kind, Some(b), eps));
    starts.sort_by(|a, b| a.2.total_cmp(&b.2));
    starts.truncate(ARCHIVE_STARTS);

    let n = runs.runs.len();
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0xB007_5742);
    let draws: Vec<Vec<usize>> =
        (0..settings.replicates).map(|_| (0..n).map(|_| rng.random_range(0..n)).collect()).collect();
    let refits: Vec<(Vec<f64>, usize)> = draws
        .par_iter()
        .map(|idx| {
            let target = Target::new(&subset(runs, idx), problem.teeth(), resolution_g);
            let start = starts
                .iter()
                .map(|(x, b, _)| (x, target.value(kind, Some(b), eps)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(x, _)| x.clone())
                .unwrap_or_else(|| full.x.clone());
            let m = nelder_mead::minimise(
                |u| target.value(kind, problem.bins_at(&problem.from_unit(u)).as_deref(), eps),
                &problem.to_unit(&start),
                0.05,
                settings.max_evals,
                1e-4,
            );
            (problem.from_unit(&m.x), m.evaluations)
        })
        .collect();
    let values: Vec<Vec<f64>> = refits.iter().map(|r| r.0.clone()).collect();
    let d = problem.params.len();
    let column = |j: usize| values.iter().map(|v| v[j]).collect::<Vec<f64>>();
    Uncertainty {
        replicates: settings.replicates,
        sd: (0..d).map(|j| sample_sd(&column(j))).collect(),
        interval: (0..d).map(|j| [percentile(&column(j), 0.16), percentile(&column(j), 0.84)]).collect(),
        evaluations: refits.iter().map(|r| r.1).sum(),
        values,
    }
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

/// Fit on all runs but the last `k` and score the fit on those `k`.
pub fn holdout(
    problem: &Problem,
    runs: &MeasuredRuns,
    resolution_g: f64,
    kind: ObjectiveKind,
    k: usize,
    settings: GaSettings,
    progress: &mut dyn FnMut(u64, f64),
) -> anyhow::Result<Heldout> {
    let n = runs.runs.len();
    if k == 0 || k >= n {
        bail!("--holdout must be >= 1 and < the number of runs ({n}), got {k}");
    }
    let fit_idx: Vec<usize> = (0..n - k).collect();
    let held_idx: Vec<usize> = (n - k..n).collect();
    let (fit_runs, held_runs) = (subset(runs, &fit_idx), subset(runs, &held_idx));
    let teeth = problem.teeth();
    let fit_target = Target::new(&fit_runs, teeth, resolution_g);
    let held_target = Target::new(&held_runs, teeth, resolution_g);
    let fit = global_fit(problem, &fit_target, kind, settings, progress)?;
    let eps = problem.eps();
    let in_sample = fit_target.likelihood(&fit.bins, eps);
    let nll_heldout = -objective::dm_log_likelihood(
        &held_target.counts,
        &objective::model_probabilities(&held_target.counts, &fit.bins, eps),
        in_sample.concentration,
    );
    Ok(Heldout {
        k,
        heldout_runs: held_runs.runs.iter().map(|r| r.id.clone()).collect(),
        fit_runs: fit_runs.runs.iter().map(|r| r.id.clone()).collect(),
        params: fit.x.clone(),
        sse_in_sample_percent2: fit_target.sse(&fit.bins),
        sse_heldout_percent2: held_target.sse(&fit.bins),
        sse_measured_fit_vs_heldout_percent2: objective::sse_percent2(&fit_target.bins, &held_target.bins),
        nll_heldout,
        nll_heldout_per_run: nll_heldout / k as f64,
        nll_in_sample_per_run: in_sample.nll / (n - k) as f64,
        evaluations: fit.evaluations,
    })
}

/// Per-tooth statistics of the runs' fractions (padded to the setup's teeth with zeros).
#[derive(Clone, Debug, Serialize)]
pub struct MeasuredSummary {
    /// Fraction of the mean masses ([`MeasuredRuns::mean_fractions`]).
    pub mean: Vec<f64>,
    /// Sample standard deviation of the run fractions (NaN with one run).
    pub sd: Vec<f64>,
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

impl MeasuredSummary {
    pub fn new(runs: &MeasuredRuns, teeth: usize) -> Self {
        let pad = |v: Vec<f64>| {
            let mut p = vec![0.0; teeth];
            p[..v.len()].copy_from_slice(&v);
            p
        };
        let fr = runs.fractions();
        let col = |j: usize| fr.iter().map(move |f| f[j]);
        MeasuredSummary {
            mean: pad(runs.mean_fractions()),
            sd: pad(runs.std_fractions()),
            min: pad((0..runs.teeth).map(|j| col(j).fold(f64::INFINITY, f64::min)).collect()),
            max: pad((0..runs.teeth).map(|j| col(j).fold(f64::NEG_INFINITY, f64::max)).collect()),
        }
    }
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
    pub mae_percent: f64,
    pub likelihood: Profiled,
    /// [`Target::measured_mean_likelihood`] of all runs.
    pub measured_mean_likelihood: Profiled,
    pub runs: usize,
    pub resolution_g: f64,
    pub measured: MeasuredSummary,
    /// Fitted bins: the setup's teeth, then lost.
    pub fitted: Vec<f64>,
    pub uncertainty: Option<Uncertainty>,
    pub heldout: Option<Heldout>,
    /// Simulations run by the main fit (GA and polish).
    pub evaluations: u64,
    /// None when the parameters were given ([`evaluate_at`]), not fitted.
    pub ga: Option<GaSettings>,
}

/// What `fit` does besides the GA.
#[derive(Clone, Copy, Debug)]
pub struct FitSettings {
    pub objective: ObjectiveKind,
    pub ga: GaSettings,
    pub bootstrap: usize,
    pub holdout: usize,
}

/// Bootstrap Nelder-Mead budget for `d` parameters.
pub fn bootstrap_evals(d: usize) -> usize {
    10 + 15 * d
}

/// The whole fit: the GA on all runs, the bootstrap, the held-out fit. `log` receives
/// progress lines.
pub fn fit(
    problem: &Problem,
    runs: &MeasuredRuns,
    resolution_g: f64,
    settings: FitSettings,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<FitReport> {
    let teeth = problem.teeth();
    if runs.teeth > teeth {
        bail!(
            "the measured data has {} teeth but the setup simulates only {teeth} (sim.teeth): raise sim.teeth",
            runs.teeth
        );
    }
    let n = runs.runs.len();
    if settings.holdout >= n {
        bail!("--holdout must be < the number of runs ({n}), got {}", settings.holdout);
    }
    if !(resolution_g.is_finite() && resolution_g > 0.0) {
        bail!("scale resolution must be > 0 g, got {resolution_g}");
    }
    let target = Target::new(runs, teeth, resolution_g);
    let generations = settings.ga.generations;
    let fit = global_fit(problem, &target, settings.objective, settings.ga, &mut |g, best| {
        if g == generations || g % 10 == 0 {
            log(format!("fit: generation {g}/{generations}, best objective {best:.4}"));
        }
    })?;
    let eps = problem.eps();
    let uncertainty = (settings.bootstrap > 0).then(|| {
        log(format!("fit: bootstrap, {} replicates", settings.bootstrap));
        bootstrap(
            problem,
            runs,
            resolution_g,
            settings.objective,
            &fit,
            &target,
            BootstrapSettings {
                replicates: settings.bootstrap,
                seed: settings.ga.seed,
                max_evals: bootstrap_evals(problem.params.len()),
            },
        )
    });
    let heldout = if settings.holdout > 0 {
        log(format!("fit: held-out fit without the last {} runs", settings.holdout));
        Some(holdout(problem, runs, resolution_g, settings.objective, settings.holdout, settings.ga, &mut |_, _| {})?)
    } else {
        None
    };
    Ok(FitReport {
        params: problem.params.clone(),
        setup_values: problem.setup_values(),
        objective: settings.objective,
        objective_value: fit.value,
        sse_percent2: target.sse(&fit.bins),
        mae_percent: objective::mae_percent(&fit.bins, &target.bins),
        likelihood: target.likelihood(&fit.bins, eps),
        measured_mean_likelihood: target.measured_mean_likelihood(),
        runs: n,
        resolution_g,
        measured: MeasuredSummary::new(runs, teeth),
        fitted: fit.bins.clone(),
        uncertainty,
        heldout,
        evaluations: fit.evaluations,
        ga: Some(settings.ga),
        x: fit.x,
    })
}

/// `NAME=VALUE,...` (e.g. `k_elastic=0.854,mu_fric=0.133,k_drag=5.347`): the parameters
/// and their values, for [`evaluate_at`].
pub fn parse_assignments(list: &str) -> anyhow::Result<(Vec<Param>, Vec<f64>)> {
    let mut names = Vec::new();
    let mut values = Vec::new();
    for item in list.split(',').map(str::trim) {
        let Some((name, value)) = item.split_once('=') else {
            bail!("--at: expected NAME=VALUE, got `{item}` (known names: {})", known_names());
        };
        let v: f64 = value
            .trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--at: `{}`: not a number: `{}`", name.trim(), value.trim()))?;
        if !v.is_finite() {
            bail!("--at: `{}` must be finite, got {v}", name.trim());
        }
        names.push(name.trim().to_string());
        values.push(v);
    }
    let params = parse_params(&names.join(","))
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().replacen("--params", "--at", 1)))?;
    Ok((params, values))
}

/// Score given parameter values against all runs, without fitting: the same report as
/// [`fit`] with no uncertainty and no held-out score.
pub fn evaluate_at(
    problem: &Problem,
    runs: &MeasuredRuns,
    resolution_g: f64,
    kind: ObjectiveKind,
    x: &[f64],
) -> anyhow::Result<FitReport> {
    let teeth = problem.teeth();
    if runs.teeth > teeth {
        bail!(
            "the measured data has {} teeth but the setup simulates only {teeth} (sim.teeth): raise sim.teeth",
            runs.teeth
        );
    }
    problem.scenario_at(x).validate().map_err(|e| anyhow::anyhow!("--at: {e}"))?;
    let target = Target::new(runs, teeth, resolution_g);
    let Some(bins) = problem.bins_at(x) else {
        bail!("the engine rejected the setup at these parameters");
    };
    let eps = problem.eps();
    Ok(FitReport {
        params: problem.params.clone(),
        x: x.to_vec(),
        setup_values: problem.setup_values(),
        objective: kind,
        objective_value: target.value(kind, Some(&bins), eps),
        sse_percent2: target.sse(&bins),
        mae_percent: objective::mae_percent(&bins, &target.bins),
        likelihood: target.likelihood(&bins, eps),
        measured_mean_likelihood: target.measured_mean_likelihood(),
        runs: runs.runs.len(),
        resolution_g,
        measured: MeasuredSummary::new(runs, teeth),
        fitted: bins,
        uncertainty: None,
        heldout: None,
        evaluations: 1,
        ga: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_parse_and_unknown_names_are_named() {
        assert_eq!(parse_params("k_elastic,mu_fric,k_drag").unwrap(), Param::ALL.to_vec());
        assert_eq!(parse_params(" k_drag ").unwrap(), vec![Param::KDrag]);
        let e = parse_params("k_drag,gravity").unwrap_err().to_string();
        assert!(e.contains("`gravity`") && e.contains("k_elastic, mu_fric, k_drag"), "{e}");
        assert!(parse_params("k_drag,k_drag").unwrap_err().to_string().contains("twice"));
        assert!(parse_params("").unwrap_err().to_string().contains("empty"));
    }

    #[test]
    fn params_apply_to_the_scenario() {
        let mut s = Scenario::preset(crate::model::EnvPreset::Lunar);
        Param::KDrag.apply(&mut s, 3.0);
        Param::MuFric.apply(&mut s, 0.2);
        Param::KElastic.apply(&mut s, 0.5);
        assert_eq!(s.environment.k_drag, Some(3.0));
        assert_eq!((s.collision.k_elastic, s.collision.mu_friction), (0.5, 0.2));
        assert_eq!(Param::ALL.map(|p| p.get(&s)), [0.5, 0.2, 3.0]);
    }

    #[test]
    fn assignments_parse() {
        let (p, v) = parse_assignments("k_elastic=0.854, mu_fric=0.133,k_drag=5.347").unwrap();
        assert_eq!(p, Param::ALL.to_vec());
        assert_eq!(v, vec![0.854, 0.133, 5.347]);
        for (bad, needle) in
            [("k_drag", "NAME=VALUE"), ("k_drag=x", "not a number"), ("g=1", "`g`"), ("k_drag=inf", "finite")]
        {
            let e = parse_assignments(bad).unwrap_err().to_string();
            assert!(e.contains("--at") && e.contains(needle), "{bad}: {e}");
        }
    }

    #[test]
    fn percentiles_interpolate() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert_eq!(percentile(&v, 0.5), 3.0);
        assert!((percentile(&v, 0.16) - 1.64).abs() < 1e-12);
        assert!((sample_sd(&[1.0, 3.0]) - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn target_pads_and_objectives_agree_on_a_perfect_fit() {
        let runs = crate::io::measured::parse("run,tooth_1,tooth_2\na,1.0,1.0\nb,1.2,0.8\n", "t.csv").unwrap();
        let t = Target::new(&runs, 5, 0.1);
        assert_eq!(t.bins.len(), 6);
        assert_eq!(t.counts[1], vec![12.0, 8.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(t.value(ObjectiveKind::Sse, Some(&t.bins.clone()), 1e-3), 0.0);
        assert!(t.value(ObjectiveKind::Likelihood, Some(&t.bins.clone()), 1e-3).is_finite());
        assert_eq!(t.value(ObjectiveKind::Sse, None, 1e-3), f64::INFINITY);
        let s = MeasuredSummary::new(&runs, 5);
        assert_eq!(s.min[..3], [0.5, 0.4, 0.0]);
        assert_eq!(s.max[..2], [0.6, 0.5]);
    }
}
