//! The calibration solver: several models fitted in lockstep, each stage's points of every
//! model simulated as one engine call ([`Simulator::simulate`]).
//!
//! 1. **Screen** at a small particle budget: differential evolution (DE/rand-to-best/1/bin,
//!    F dithered in [0.5, 0.9] per generation, CR 0.9; Storn & Price 1997) in the unit box of
//!    each model's space, the population seeded with uniform points and the model's starts
//!    (e.g. the baseline's optimum with the effect switched off, so a nested model is never
//!    screened worse than the baseline). DE needs no gradient and tolerates the
//!    piecewise-constant objective of a finite-particle simulation.
//! 2. **Polish** at the full budget: the screen's best point and the starts are re-scored
//!    with the full particle count, and a compass search (Kolda, Lewis & Torczon 2003) moves
//!    from the best of them: the 2d points ±step along each axis, move to the best that
//!    improves and double the step (up to 0.2 of the box), else halve it. Each iteration of
//!    every model is one engine call. [`Solver::polish`] runs this stage alone (the
//!    bootstrap refits of `fit`, each replicate a model of its own).
//!
//!    With [`PolishMethod::LevenbergMarquardt`] and the SSE objective the polish takes
//!    Levenberg–Marquardt steps instead ([`super::levenberg`]): a Jacobian of the bins by
//!    forward differences (d simulations), then three damped steps tried at once, the best
//!    that improves kept; a model stops once a step gains less than [`LM_MIN_GAIN`] or two
//!    in a row fail.
//!
//! The objective ([`ObjectiveKind`]) is summed over the conditions: the SSE of Eq. 4.62 or
//! the Dirichlet-multinomial likelihood of the runs. Every point of a stage sees the same
//! particle streams (common random numbers), so differences between points are differences
//! of physics, not of noise.

use anyhow::bail;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::batch::{Bins, Simulator};
use super::levenberg;
use super::objective;
use super::space::Space;
use super::target::{ObjectiveKind, Target};

/// What the polishes report of each evaluation: the model's index, the model, its point, its bins.
type Recorder<'a> = dyn FnMut(usize, &Model, &[f64], &Bins) + 'a;
/// A Levenberg-Marquardt step's normal equations: JᵀJ and Jᵀr.
type NormalEquations = (Vec<Vec<f64>>, Vec<f64>);

/// One model to fit: its space, what it is fitted to, extra starting points (parameter
/// units) and how it is searched.
pub struct Model<'a> {
    pub space: &'a Space,
    /// One target per condition of the simulator.
    pub targets: &'a [Target],
    pub starts: Vec<Vec<f64>>,
    pub search: Search,
}

/// How the solver searches a model's space before the polish.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Search {
    /// Differential evolution over the whole box, then the polish from its best point and
    /// the model's starts. The evolution draws from random stream `stream` (with the
    /// solver's seed): a model's fit depends on its own stream, not on which other models
    /// share the batch or where it stands in it, so a caller that drops a model from a
    /// batch changes no other fit.
    Global { stream: u64 },
    /// The polish from the model's starts alone (at least one), for a model whose starts
    /// come from a global search of its own (the diagnosis's motion screen). It shares the
    /// batch's polish, one engine call per iteration with the others.
    FromStarts,
}

/// How the polish at the full budget searches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PolishMethod {
    /// Compass search: ±step along each axis (any objective).
    Compass,
    /// Levenberg–Marquardt steps on the bins' residuals (the SSE objective; the likelihood
    /// is polished by the compass search).
    LevenbergMarquardt,
}

/// The solver's settings: what it minimises and how hard it works.
#[derive(Clone, Copy, Debug)]
pub struct Solver {
    pub objective: ObjectiveKind,
    /// DE population per model (at least 5).
    pub pop: usize,
    /// DE generations after the initial population.
    pub generations: usize,
    /// Particles per simulation while screening.
    pub screen_particles: u32,
    /// Particles per simulation while polishing (the budget the fit is reported at).
    pub particles: u32,
    /// Compass-search iterations.
    pub polish_iterations: usize,
    /// The compass search's first and smallest step, as fractions of the box (it stops
    /// probing below the smallest).
    pub first_step: f64,
    pub min_step: f64,
    pub seed: u64,
    /// The polish's search.
    pub polish_method: PolishMethod,
}

/// One point simulated at the full budget, with its bins per condition.
#[derive(Clone, Debug)]
pub struct Probe {
    pub x: Vec<f64>,
    pub bins: Vec<Vec<f64>>,
}

/// One model's screen ([`Solver::screen`]): its population, best first.
#[derive(Clone, Debug)]
pub struct Screened {
    /// Points in parameter units with their objective at the screen's particle count.
    pub members: Vec<(Vec<f64>, f64)>,
    /// Simulations of the whole condition set the screen used.
    pub evaluations: u64,
}

/// One fitted model.
#[derive(Clone, Debug)]
pub struct Fit {
    pub x: Vec<f64>,
    /// The objective at `x` with the full particle count (SSE in %², or NLL).
    pub value: f64,
    /// Simulated bins per condition at `x`.
    pub bins: Vec<Vec<f64>>,
    /// Simulations of the whole condition set this fit used.
    pub evaluations: u64,
    /// Every point the polish simulated at the full budget (the starts of refits).
    pub archive: Vec<Probe>,
}

impl Solver {
    /// The objective summed over the conditions at `particles` per simulation; +inf when not
    /// simulable.
    pub fn value(&self, bins: &Bins, targets: &[Target], particles: u32) -> f64 {
        let eps = objective::floor_for(particles);
        match bins {
            None => f64::INFINITY,
            Some(b) => b.iter().zip(targets).map(|(b, t)| t.value(self.objective, Some(b), eps)).sum(),
        }
    }

    /// Score every model's unit-box points (`per_model[m]` for model m) in one engine call
    /// and hand the values and bins back per model, in order.
    fn score(
        &self,
        sim: &Simulator,
        models: &[Model],
        per_model: &[Vec<Vec<f64>>],
        particles: u32,
    ) -> Vec<Vec<(f64, Bins)>> {
        let points: Vec<(&Space, Vec<f64>)> = per_model
            .iter()
            .zip(models)
            .flat_map(|(us, model)| us.iter().map(|u| (model.space, model.space.from_unit(u))))
            .collect();
        let bins = sim.simulate(&points, particles, self.seed);
        // the likelihood profiles a concentration per point: worth the threads
        let owners: Vec<&Model> =
            per_model.iter().zip(models).flat_map(|(us, model)| us.iter().map(move |_| model)).collect();
        let mut it = bins
            .into_par_iter()
            .zip(owners)
            .map(|(b, model)| (self.value(&b, model.targets, particles), b))
            .collect::<Vec<_>>()
            .into_iter();
        per_model.iter().map(|us| us.iter().map(|_| it.next().expect("one result per point")).collect()).collect()
    }
}

/// The compass search's default first and smallest steps in the unit box, and its largest
/// (also the largest move of one Levenberg–Marquardt step in each coordinate).
pub const FIRST_STEP: f64 = 0.05;
pub const MIN_STEP: f64 = 0.05 / 32.0;
const MAX_STEP: f64 = 0.2;

/// The Levenberg–Marquardt polish: the forward-difference step of its Jacobian in the unit
/// box (wide enough that, with common random numbers, many particles change their tooth), the
/// damping it starts with (relative to diag(JᵀJ)), the damping factors tried at once around
/// the current one, and the smallest gain (%²) of an accepted step that does not stop the
/// model: below it the steps fit the particle streams' noise, not the physics.
const LM_DIFF_STEP: f64 = 0.01;
const LM_LAMBDA0: f64 = 0.01;
const LM_TRIALS: [f64; 3] = [0.1, 1.0, 10.0];
pub const LM_MIN_GAIN: f64 = 0.05;

impl Solver {
    fn check(&self, sim: &Simulator, models: &[Model]) -> anyhow::Result<()> {
        if self.pop < 5 {
            bail!("the calibration's population must be >= 5, got {}", self.pop);
        }
        if let Some(m) = models.iter().find(|m| m.targets.len() != sim.conditions.len()) {
            bail!("a model has {} targets for {} conditions", m.targets.len(), sim.conditions.len());
        }
        Ok(())
    }

    /// Fit every model: screen, then polish. `log` receives progress lines.
    pub fn fit(&self, sim: &Simulator, models: &[Model], log: &mut dyn FnMut(String)) -> anyhow::Result<Vec<Fit>> {
        self.check(sim, models)?;
        if let Some(m) = models.iter().position(|m| m.search == Search::FromStarts && m.starts.is_empty()) {
            bail!("model {m} is searched from its starts alone and has none");
        }
        let members = self.evolve(sim, models, log);
        // the polish starts from the screen's best (where there was a screen) and the
        // model's own starts
        let starts: Vec<Vec<Vec<f64>>> = members
            .iter()
            .zip(models)
            .map(|(mem, model)| {
                let best = mem.pop.iter().min_by(|a, b| a.1.total_cmp(&b.1)).map(|b| b.0.clone());
                best.into_iter().chain(model.starts.iter().map(|x| model.space.to_unit(x))).collect()
            })
            .collect();
        let screened: Vec<u64> = members.iter().map(|m| m.evaluations).collect();
        self.polish_from(sim, models, starts, &screened, log)
    }

    /// The screen stage alone: every model's differential-evolution population after the
    /// generations, in parameter units with its objective at the screen's particle count,
    /// best first. For a search that ranks several models' screens before polishing any
    /// (the diagnosis's motion screen).
    pub fn screen(
        &self,
        sim: &Simulator,
        models: &[Model],
        log: &mut dyn FnMut(String),
    ) -> anyhow::Result<Vec<Screened>> {
        self.check(sim, models)?;
        let members = self.evolve(sim, models, log);
        Ok(members
            .into_iter()
            .zip(models)
            .map(|(mem, model)| {
                let mut pop: Vec<(Vec<f64>, f64)> =
                    mem.pop.into_iter().map(|(u, v)| (model.space.from_unit(&u), v)).collect();
                pop.sort_by(|a, b| a.1.total_cmp(&b.1));
                Screened { members: pop, evaluations: mem.evaluations }
            })
            .collect())
    }

    /// The differential evolution of every model in lockstep, from its starts (the first
    /// `pop` of them) and uniform points; a model searched from its starts alone gets an
    /// empty population.
    fn evolve(&self, sim: &Simulator, models: &[Model], log: &mut dyn FnMut(String)) -> Vec<Member> {
        let seed = self.seed;
        let mut members: Vec<Member> = models
            .iter()
            .map(|model| {
                let stream = match model.search {
                    Search::Global { stream } => stream,
                    // an empty population, whose generator never draws
                    Search::FromStarts => {
                        return Member { pop: Vec::new(), rng: ChaCha8Rng::seed_from_u64(seed), evaluations: 0 }
                    }
                };
                let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (0xCA11_B000 + stream));
                let d = model.space.dim();
                let mut pop: Vec<Vec<f64>> =
                    model.starts.iter().map(|x| model.space.to_unit(x)).take(self.pop).collect();
                while pop.len() < self.pop {
                    pop.push((0..d).map(|_| rng.random::<f64>()).collect());
                }
                Member { pop: pop.into_iter().map(|u| (u, f64::INFINITY)).collect(), rng, evaluations: 0 }
            })
            .collect();
        if members.iter().all(|m| m.pop.is_empty()) {
            return members;
        }
        let initial: Vec<Vec<Vec<f64>>> =
            members.iter().map(|mem| mem.pop.iter().map(|(u, _)| u.clone()).collect()).collect();
        for (mem, scored) in members.iter_mut().zip(self.score(sim, models, &initial, self.screen_particles)) {
            for (ind, (v, _)) in mem.pop.iter_mut().zip(scored) {
                ind.1 = v;
            }
            mem.evaluations += mem.pop.len() as u64;
        }
        let screen_start = std::time::Instant::now();
        for g in 0..self.generations {
            let trials: Vec<Vec<Vec<f64>>> = members.iter_mut().map(Member::trials).collect();
            let scored = self.score(sim, models, &trials, self.screen_particles);
            for ((mem, t), scored) in members.iter_mut().zip(trials).zip(scored) {
                mem.evaluations += t.len() as u64;
                for (i, (u, (v, _))) in t.into_iter().zip(scored).enumerate() {
                    if v <= mem.pop[i].1 {
                        mem.pop[i] = (u, v);
                    }
                }
            }
            if (g + 1) % 10 == 0 || g + 1 == self.generations {
                let best: Vec<String> = members
                    .iter()
                    .filter(|m| !m.pop.is_empty())
                    .map(|m| format!("{:.1}", m.pop.iter().map(|p| p.1).fold(f64::INFINITY, f64::min)))
                    .collect();
                log(format!(
                    "calibrate: screen generation {}/{} (best {}), {}",
                    g + 1,
                    self.generations,
                    best.join(", "),
                    crate::io::progress::eta(screen_start.elapsed(), (g + 1) as u64, self.generations as u64)
                ));
            }
        }
        members
    }

    /// The polish stage alone, from each model's starts (at least one each). `log` receives
    /// progress lines.
    pub fn polish(&self, sim: &Simulator, models: &[Model], log: &mut dyn FnMut(String)) -> anyhow::Result<Vec<Fit>> {
        self.check(sim, models)?;
        if models.iter().any(|m| m.starts.is_empty()) {
            bail!("the polish needs a start for every model");
        }
        let starts = models.iter().map(|m| m.starts.iter().map(|x| m.space.to_unit(x)).collect()).collect();
        self.polish_from(sim, models, starts, &vec![0; models.len()], log)
    }

    fn polish_from(
        &self,
        sim: &Simulator,
        models: &[Model],
        starts: Vec<Vec<Vec<f64>>>,
        evaluations: &[u64],
        log: &mut dyn FnMut(String),
    ) -> anyhow::Result<Vec<Fit>> {
        let n = models.len();
        let mut evaluations = evaluations.to_vec();
        let mut archives: Vec<Vec<Probe>> = vec![Vec::new(); n];
        let mut record = |m: usize, model: &Model, u: &[f64], b: &Bins| {
            if let Some(b) = b {
                archives[m].push(Probe { x: model.space.from_unit(u), bins: b.clone() });
            }
        };
        // the best start at the full budget
        let mut current: Vec<(Vec<f64>, f64, Bins)> = Vec::with_capacity(n);
        let scored = self.score(sim, models, &starts, self.particles);
        for (m, (c, scored)) in starts.into_iter().zip(scored).enumerate() {
            evaluations[m] += c.len() as u64;
            let mut best: Option<(Vec<f64>, f64, Bins)> = None;
            for (u, (v, b)) in c.into_iter().zip(scored) {
                record(m, &models[m], &u, &b);
                if best.as_ref().is_none_or(|best| v < best.1) {
                    best = Some((u, v, b));
                }
            }
            current.push(best.expect("at least one start"));
        }
        if self.polish_method == PolishMethod::LevenbergMarquardt && self.objective == ObjectiveKind::Sse {
            self.levenberg_marquardt(sim, models, &mut current, &mut evaluations, &mut record, log);
        } else {
            self.compass(sim, models, &mut current, &mut evaluations, &mut record, log);
        }
        let mut fits = Vec::with_capacity(n);
        for (((u, value, bins), model), (evaluations, archive)) in
            current.into_iter().zip(models).zip(evaluations.into_iter().zip(archives))
        {
            let Some(bins) = bins.filter(|_| value.is_finite()) else {
                bail!("no candidate could be simulated (every evaluation was rejected by the engine)");
            };
            fits.push(Fit { x: model.space.from_unit(&u), value, bins, evaluations, archive });
        }
        Ok(fits)
    }

    /// The compass search from each model's current point, every iteration of every model one
    /// engine call.
    fn compass(
        &self,
        sim: &Simulator,
        models: &[Model],
        current: &mut [(Vec<f64>, f64, Bins)],
        evaluations: &mut [u64],
        record: &mut Recorder<'_>,
        log: &mut dyn FnMut(String),
    ) {
        let n = models.len();
        let mut steps = vec![self.first_step; n];
        let (polish_start, mut lines) = (std::time::Instant::now(), crate::io::progress::Lines::new());
        let total = self.polish_iterations as u64;
        let mut done = 0;
        for k in 1..=total {
            let probes: Vec<Vec<Vec<f64>>> = current
                .iter()
                .zip(&steps)
                .map(|((u, _, _), step)| if *step >= self.min_step { compass_points(u, *step) } else { Vec::new() })
                .collect();
            if probes.iter().all(Vec::is_empty) {
                log(format!(
                    "calibrate: polish done after {done}/{total} iterations (every step below the minimum, best {}), {}",
                    best_of(current),
                    crate::io::progress::eta(polish_start.elapsed(), 0, 0)
                ));
                break;
            }
            let scored = self.score(sim, models, &probes, self.particles);
            for (m, (p, scored)) in probes.into_iter().zip(scored).enumerate() {
                evaluations[m] += p.len() as u64;
                let mut moved = false;
                for (y, (v, b)) in p.into_iter().zip(scored) {
                    record(m, &models[m], &y, &b);
                    if v < current[m].1 {
                        current[m] = (y, v, b);
                        moved = true;
                    }
                }
                // expand after a success (the screen's best can lie several steps away),
                // contract after a failure
                steps[m] = if moved { (steps[m] * 2.0).min(MAX_STEP) } else { steps[m] * 0.5 };
            }
            done = k;
            if lines.due(k, total) {
                log(format!(
                    "calibrate: polish iteration {k}/{total} (best {}), {}{}",
                    best_of(current),
                    crate::io::progress::eta(polish_start.elapsed(), k, total),
                    if k < total { " (at most: the search stops once every step is below the minimum)" } else { "" }
                ));
            }
        }
    }

    /// Levenberg–Marquardt steps from each model's current point ([`super::levenberg`]), in
    /// lockstep: per iteration one engine call for the Jacobians of the models that moved and
    /// one for every model's three damped trial steps.
    fn levenberg_marquardt(
        &self,
        sim: &Simulator,
        models: &[Model],
        current: &mut [(Vec<f64>, f64, Bins)],
        evaluations: &mut [u64],
        record: &mut Recorder<'_>,
        log: &mut dyn FnMut(String),
    ) {
        let n = models.len();
        // the residuals of the bins as the objective compares them: after the handling loss
        // each target allows (`Target::after_handling`), so that the step minimises the SSE the
        // screen and the trials are scored on
        let residuals = |m: usize, b: &Bins| {
            b.as_ref().map(|b| {
                let targets = models[m].targets;
                let observed: Vec<Vec<f64>> = b.iter().zip(targets).map(|(b, t)| t.after_handling(b).1).collect();
                let measured: Vec<&[f64]> = targets.iter().map(|t| t.bins.as_slice()).collect();
                levenberg::residuals(&observed, &measured)
            })
        };
        let mut lambda = vec![LM_LAMBDA0; n];
        let mut failures = vec![0usize; n];
        let mut active: Vec<bool> = current.iter().map(|c| c.2.is_some() && !c.0.is_empty()).collect();
        let mut normal: Vec<Option<NormalEquations>> = vec![None; n];
        let (started, mut lines) = (std::time::Instant::now(), crate::io::progress::Lines::new());
        let total = self.polish_iterations as u64;
        for k in 1..=total {
            // the Jacobians of the models whose point moved: one forward step per coordinate,
            // backwards where the box ends
            let probes: Vec<Vec<Vec<f64>>> = (0..n)
                .map(|m| if active[m] && normal[m].is_none() { forward_points(&current[m].0) } else { Vec::new() })
                .collect();
            if probes.iter().any(|p| !p.is_empty()) {
                let scored = self.score(sim, models, &probes, self.particles);
                for (m, (p, scored)) in probes.into_iter().zip(scored).enumerate() {
                    if p.is_empty() {
                        continue;
                    }
                    evaluations[m] += p.len() as u64;
                    let r0 = residuals(m, &current[m].2).expect("an active model's point was simulated");
                    let columns: Vec<Vec<f64>> = p
                        .iter()
                        .zip(scored)
                        .enumerate()
                        .map(|(j, (y, (_, b)))| {
                            record(m, &models[m], y, &b);
                            let h = y[j] - current[m].0[j];
                            match residuals(m, &b) {
                                Some(r) => r.iter().zip(&r0).map(|(a, q)| (a - q) / h).collect(),
                                // a neighbour the engine refused: this parameter holds still
                                None => vec![0.0; r0.len()],
                            }
                        })
                        .collect();
                    normal[m] = Some(levenberg::normal_equations(&columns, &r0));
                }
            }
            // three damped steps per model, tried at once
            let trials: Vec<Vec<(Vec<f64>, f64)>> = (0..n)
                .map(|m| {
                    let Some((a, g)) = normal[m].as_ref().filter(|_| active[m]) else { return Vec::new() };
                    let mut t: Vec<(Vec<f64>, f64)> = Vec::new();
                    for f in LM_TRIALS {
                        let Some(du) = levenberg::step(a, g, lambda[m] * f, MAX_STEP) else { continue };
                        let u: Vec<f64> = current[m].0.iter().zip(&du).map(|(x, d)| (x + d).clamp(0.0, 1.0)).collect();
                        if u != current[m].0 && !t.iter().any(|(v, _)| *v == u) {
                            t.push((u, f));
                        }
                    }
                    t
                })
                .collect();
            if trials.iter().all(Vec::is_empty) {
                break;
            }
            let points: Vec<Vec<Vec<f64>>> =
                trials.iter().map(|t| t.iter().map(|(u, _)| u.clone()).collect()).collect();
            let scored = self.score(sim, models, &points, self.particles);
            for (m, (t, scored)) in trials.into_iter().zip(scored).enumerate() {
                if t.is_empty() {
                    // no step leaves the point (every one clamped back onto it): done
                    active[m] = false;
                    continue;
                }
                evaluations[m] += t.len() as u64;
                let mut best: Option<(Vec<f64>, f64, Bins, f64)> = None;
                for ((u, f), (v, b)) in t.into_iter().zip(scored) {
                    record(m, &models[m], &u, &b);
                    if v < current[m].1 && best.as_ref().is_none_or(|best| v < best.1) {
                        best = Some((u, v, b, f));
                    }
                }
                match best {
                    Some((u, v, b, f)) => {
                        let gain = current[m].1 - v;
                        current[m] = (u, v, b);
                        normal[m] = None;
                        failures[m] = 0;
                        lambda[m] *= f;
                        if gain < LM_MIN_GAIN {
                            active[m] = false;
                        }
                    }
                    None => {
                        // every trial worse: damp harder (beyond the largest tried), same Jacobian
                        lambda[m] *= 100.0;
                        failures[m] += 1;
                        if failures[m] >= 2 {
                            active[m] = false;
                        }
                    }
                }
            }
            let left = active.iter().filter(|a| **a).count();
            if lines.due(k, total) || left == 0 {
                log(format!(
                    "calibrate: polish (Levenberg-Marquardt) iteration {k}/{total} (best {}; {left} of {n} models still \
                     moving), {}",
                    best_of(current),
                    crate::io::progress::eta(started.elapsed(), k, total),
                ));
            }
            if left == 0 {
                break;
            }
        }
    }
}

/// The best values of the first models, for progress lines.
fn best_of(current: &[(Vec<f64>, f64, Bins)]) -> String {
    let mut b: Vec<String> = current.iter().take(6).map(|c| format!("{:.1}", c.1)).collect();
    if current.len() > 6 {
        b.push(format!("... {} models", current.len()));
    }
    b.join(", ")
}

/// The forward-difference neighbours of `u`: one step along each axis, backwards where the
/// unit box ends.
fn forward_points(u: &[f64]) -> Vec<Vec<f64>> {
    (0..u.len())
        .map(|j| {
            let mut y = u.to_vec();
            y[j] = if u[j] + LM_DIFF_STEP <= 1.0 { u[j] + LM_DIFF_STEP } else { u[j] - LM_DIFF_STEP };
            y
        })
        .collect()
}

/// The compass points around `u`: ±`step` along each axis, clamped to the unit box (points
/// that the box leaves where they were are dropped).
fn compass_points(u: &[f64], step: f64) -> Vec<Vec<f64>> {
    let mut p = Vec::with_capacity(2 * u.len());
    for j in 0..u.len() {
        for sign in [-1.0, 1.0] {
            let mut y = u.to_vec();
            y[j] = (y[j] + sign * step).clamp(0.0, 1.0);
            if y[j] != u[j] {
                p.push(y);
            }
        }
    }
    p
}

/// One model's differential-evolution population in the unit box.
struct Member {
    pop: Vec<(Vec<f64>, f64)>,
    rng: ChaCha8Rng,
    evaluations: u64,
}

impl Member {
    /// One generation's trial points (DE/rand-to-best/1/bin, F dithered, CR 0.9); none for
    /// an empty population.
    fn trials(&mut self) -> Vec<Vec<f64>> {
        let n = self.pop.len();
        if n == 0 {
            return Vec::new();
        }
        let d = self.pop[0].0.len();
        let best = (0..n).min_by(|a, b| self.pop[*a].1.total_cmp(&self.pop[*b].1)).expect("population");
        let f = 0.5 + 0.4 * self.rng.random::<f64>();
        let mut t = Vec::with_capacity(n);
        for i in 0..n {
            let (r1, r2) = loop {
                let r1 = self.rng.random_range(0..n);
                let r2 = self.rng.random_range(0..n);
                if r1 != r2 && r1 != i && r2 != i {
                    break (r1, r2);
                }
            };
            let jrand = self.rng.random_range(0..d);
            let xi = &self.pop[i].0;
            let y: Vec<f64> = (0..d)
                .map(|j| {
                    if j == jrand || self.rng.random::<f64>() < 0.9 {
                        let v = xi[j] + f * (self.pop[best].0[j] - xi[j]) + f * (self.pop[r1].0[j] - self.pop[r2].0[j]);
                        // bounce back halfway to the bound it crossed
                        if v < 0.0 {
                            0.5 * xi[j]
                        } else if v > 1.0 {
                            0.5 * (xi[j] + 1.0)
                        } else {
                            v
                        }
                    } else {
                        xi[j]
                    }
                })
                .collect();
            t.push(y);
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use super::*;
    use crate::calibrate::{shared_params, Condition};
    use crate::engine::{make_engine, BatchEvaluator, EngineKind, Evaluation};
    use crate::model::{Design, Invalid, Scenario};

    /// The CPU engine, recording how many groups each `evaluate_groups` call carries.
    struct Counting {
        inner: Box<dyn BatchEvaluator>,
        calls: Mutex<Vec<usize>>,
    }

    impl BatchEvaluator for Counting {
        fn backend(&self) -> &'static str {
            "counting"
        }
        fn evaluate(&self, s: &Scenario, d: &[Design]) -> Vec<Result<Evaluation, Invalid>> {
            self.calls.lock().unwrap().push(usize::MAX);
            self.inner.evaluate(s, d)
        }
        fn evaluate_groups(&self, groups: &[(Scenario, Vec<Design>)]) -> Vec<Vec<Result<Evaluation, Invalid>>> {
            self.calls.lock().unwrap().push(groups.len());
            self.inner.evaluate_groups(groups)
        }
    }

    fn test3() -> Condition {
        crate::calibrate::condition::test3()
    }

    /// A solver small enough for a unit test: 6 members, 3 generations, tens of particles.
    fn small_solver(seed: u64) -> Solver {
        Solver {
            objective: ObjectiveKind::Sse,
            pop: 6,
            generations: 3,
            screen_particles: 40,
            particles: 60,
            polish_iterations: 2,
            first_step: FIRST_STEP,
            min_step: MIN_STEP,
            seed,
            polish_method: PolishMethod::Compass,
        }
    }

    #[test]
    fn every_generation_of_every_model_is_one_engine_call() {
        let conditions = vec![test3(), test3()];
        let engine = Counting { inner: make_engine(EngineKind::Cpu).unwrap(), calls: Mutex::new(Vec::new()) };
        let sim = Simulator { engine: &engine, conditions: &conditions };
        let space = Space::new(shared_params(&conditions), &[], &conditions);
        let targets: Vec<Target> = conditions.iter().map(Condition::target_all).collect();
        let models = [
            Model { space: &space, targets: &targets, starts: vec![], search: Search::Global { stream: 0 } },
            Model {
                space: &space,
                targets: &targets,
                starts: vec![vec![0.5, 0.5, 5.0]],
                search: Search::Global { stream: 1 },
            },
        ];
        let solver = small_solver(1);
        let fits = solver.fit(&sim, &models, &mut |_| {}).unwrap();
        let calls = engine.calls.lock().unwrap().clone();
        // initial population + 3 generations (2 models x 6 points x 2 conditions each), the
        // polish's starts (the screen's best; the second model's own start too), then at
        // most 2 compass iterations (up to 2 models x 6 probes x 2 conditions)
        assert_eq!(calls[..4], [24, 24, 24, 24], "{calls:?}");
        assert_eq!(calls[4], 2 * (1 + 2), "{calls:?}");
        assert!(calls.len() <= 7 && calls[5..].iter().all(|&g| g > 0 && g <= 2 * 6 * 2), "{calls:?}");
        for f in &fits {
            assert!(f.value.is_finite() && f.bins.len() == 2);
            assert!(f.archive.iter().any(|p| p.x == f.x && p.bins == f.bins), "the fit's point is in its archive");
        }
        // the same settings give the same fits (common random numbers, seeded solver)
        let again = solver.fit(&sim, &models, &mut |_| {}).unwrap();
        assert_eq!(
            again.iter().map(|f| f.x.clone()).collect::<Vec<_>>(),
            fits.iter().map(|f| f.x.clone()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_models_fit_follows_its_own_stream_not_its_place_in_the_batch() {
        let conditions = vec![test3()];
        let engine = make_engine(EngineKind::Cpu).unwrap();
        let sim = Simulator { engine: &*engine, conditions: &conditions };
        let space = Space::new(shared_params(&conditions), &[], &conditions);
        let targets: Vec<Target> = conditions.iter().map(Condition::target_all).collect();
        let model =
            |stream| Model { space: &space, targets: &targets, starts: vec![], search: Search::Global { stream } };
        let solver = small_solver(3);
        let together = solver.fit(&sim, &[model(3), model(4)], &mut |_| {}).unwrap();
        let alone = solver.fit(&sim, &[model(4)], &mut |_| {}).unwrap();
        assert_eq!(together[1].x, alone[0].x, "dropping a batch-mate must not change a fit");
        assert_eq!(together[1].value, alone[0].value);
        // the stream is what decides: another one evolves another population
        assert_ne!(together[0].x, together[1].x);
    }

    #[test]
    fn a_model_searched_from_its_starts_gets_no_evolution_and_shares_the_batchs_polish() {
        let conditions = vec![test3()];
        let engine = Counting { inner: make_engine(EngineKind::Cpu).unwrap(), calls: Mutex::new(Vec::new()) };
        let sim = Simulator { engine: &engine, conditions: &conditions };
        let space = Space::new(shared_params(&conditions), &[], &conditions);
        let targets: Vec<Target> = conditions.iter().map(Condition::target_all).collect();
        let start = vec![0.5, 0.5, 5.0];
        let searched = Model { space: &space, targets: &targets, starts: vec![], search: Search::Global { stream: 0 } };
        let from_start =
            || Model { space: &space, targets: &targets, starts: vec![start.clone()], search: Search::FromStarts };
        let solver = small_solver(5);
        let fits = solver.fit(&sim, &[searched, from_start()], &mut |_| {}).unwrap();
        let calls = engine.calls.lock().unwrap().clone();
        // initial population + 3 generations of the first model alone (6 points each), then
        // the polish's starts: the first model's screened best and the second's start
        assert_eq!(calls[..5], [6, 6, 6, 6, 2], "{calls:?}");
        // exactly the polish of that model alone, evaluations included
        let alone = solver.polish(&sim, &[from_start()], &mut |_| {}).unwrap();
        assert_eq!(
            (&fits[1].x, fits[1].value, fits[1].evaluations),
            (&alone[0].x, alone[0].value, alone[0].evaluations)
        );
        assert!(fits[1].evaluations < fits[0].evaluations);
        // such a model needs a start
        let bare = Model { space: &space, targets: &targets, starts: vec![], search: Search::FromStarts };
        assert!(solver.fit(&sim, &[bare], &mut |_| {}).unwrap_err().to_string().contains("starts"));
    }

    /// The Levenberg–Marquardt polish starts where the compass search would, never ends worse
    /// than that start, stays in the box, and says it is the one polishing; the likelihood,
    /// no sum of squares, keeps the compass search.
    #[test]
    fn a_levenberg_marquardt_polish_never_ends_worse_than_its_start() {
        let conditions = vec![test3()];
        let engine = make_engine(EngineKind::Cpu).unwrap();
        let sim = Simulator { engine: &*engine, conditions: &conditions };
        let space = Space::new(shared_params(&conditions), &[], &conditions);
        let targets: Vec<Target> = conditions.iter().map(Condition::target_all).collect();
        let start = vec![0.5, 0.5, 5.0];
        let model =
            || Model { space: &space, targets: &targets, starts: vec![start.clone()], search: Search::FromStarts };
        let lm = Solver { polish_method: PolishMethod::LevenbergMarquardt, particles: 400, ..small_solver(7) };
        let at_start = Solver { polish_iterations: 0, ..lm };
        let before = at_start.polish(&sim, &[model()], &mut |_| {}).unwrap().remove(0);
        let mut lines = Vec::new();
        let fit = lm.polish(&sim, &[model()], &mut |l| lines.push(l)).unwrap().remove(0);
        assert!(fit.value <= before.value, "{} > {}", fit.value, before.value);
        assert!(fit.x.iter().zip(space.bounds()).all(|(x, (lo, hi))| (lo..=hi).contains(x)), "{:?}", fit.x);
        assert!(lines.iter().any(|l| l.contains("Levenberg-Marquardt")), "{lines:?}");
        // a Jacobian (3 neighbours) and up to three trials per iteration, after the start
        assert!(fit.evaluations <= 1 + lm.polish_iterations as u64 * 6, "{}", fit.evaluations);
        let likelihood = Solver { objective: ObjectiveKind::Likelihood, ..lm };
        let mut lines = Vec::new();
        likelihood.polish(&sim, &[model()], &mut |l| lines.push(l)).unwrap();
        assert!(lines.iter().all(|l| !l.contains("Levenberg-Marquardt")), "{lines:?}");
    }

    #[test]
    fn polish_refits_many_targets_in_lockstep() {
        let conditions = vec![test3()];
        let engine = Counting { inner: make_engine(EngineKind::Cpu).unwrap(), calls: Mutex::new(Vec::new()) };
        let sim = Simulator { engine: &engine, conditions: &conditions };
        let space = Space::new(vec![crate::calibrate::Param::KDrag], &[], &conditions);
        let targets: Vec<[Target; 1]> = (0..5).map(|i| [conditions[0].target(&[i, i + 1, i + 2])]).collect();
        let models: Vec<Model> = targets
            .iter()
            .map(|t| Model { space: &space, targets: t, starts: vec![vec![5.0]], search: Search::FromStarts })
            .collect();
        let solver = Solver {
            objective: ObjectiveKind::Likelihood,
            pop: 5,
            generations: 0,
            screen_particles: 50,
            particles: 50,
            polish_iterations: 3,
            first_step: FIRST_STEP,
            min_step: MIN_STEP,
            seed: 2,
            polish_method: PolishMethod::Compass,
        };
        let mut lines = Vec::new();
        let fits = solver.polish(&sim, &models, &mut |l| lines.push(l)).unwrap();
        // a progress line at the first iteration (and at the last, when the search gets there)
        assert!(lines[0].starts_with("calibrate: polish iteration 1/3 (best "), "{lines:?}");
        assert_eq!(fits.len(), 5);
        let calls = engine.calls.lock().unwrap().clone();
        // one call for the five starts, then one per iteration with both probes of each
        assert_eq!(calls[0], 5, "{calls:?}");
        assert!(calls.len() <= 4 && calls[1..].iter().all(|&g| g <= 10), "{calls:?}");
        for f in &fits {
            assert_eq!(f.value, solver.value(&Some(f.bins.clone()), models[0].targets, 50).min(f.value));
        }
        // a model without a start is refused
        let bare = [Model { space: &space, targets: &targets[0], starts: vec![], search: Search::FromStarts }];
        assert!(solver.polish(&sim, &bare, &mut |_| {}).unwrap_err().to_string().contains("start"));
    }
}
