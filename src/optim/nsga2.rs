//! Constrained NSGA-II with whole-generation batch evaluation and exact checkpoint/resume.
//!
//! References:
//! - Deb, Pratap, Agarwal, Meyarivan (2002), "A fast and elitist multiobjective genetic
//!   algorithm: NSGA-II", IEEE TEC 6(2) — fast non-dominated sorting, crowding distance,
//!   (mu + lambda) survival, crowded binary tournament, SBX and polynomial mutation.
//! - Deb (2000), "An efficient constraint handling method for genetic algorithms", CMAME
//!   186 — constraint-domination: feasible beats infeasible, the smaller violation wins
//!   between infeasible solutions, Pareto dominance between feasible ones.
//!
//! The layout follows argmin: a problem ([`BatchProblem`]), a serialisable solver state
//! ([`State`]) and a solver ([`Nsga2`]) that advances the state one generation per
//! [`Nsga2::step`]. All randomness is drawn from `State::rng`, in a fixed order, and nothing
//! iterates a hash map, so init + k steps + save + load + more steps reproduces an
//! uninterrupted run bit for bit.

use std::cmp::Ordering;
use std::path::Path;

use anyhow::Context as _;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// A problem evaluated one whole population at a time (a GPU runs one job per generation).
pub trait BatchProblem {
    fn dim(&self) -> usize;
    fn n_objectives(&self) -> usize;
    /// (lower, upper) bounds, each of length `dim()`.
    fn bounds(&self) -> (Vec<f64>, Vec<f64>);
    /// One [`Evaluation`] per candidate, in order. `generation` is 0 for the initial
    /// population and k for the offspring of step k, so the caller can refresh common random
    /// numbers once per generation (every candidate of a batch sees the same ones).
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], generation: u64) -> Vec<Evaluation>;
    /// Called on every new candidate after it is clamped to the bounds (e.g. to snap
    /// integer-valued variables or enforce a cheap geometric relation).
    fn repair(&self, _x: &mut [f64]) {}
}

/// Objectives (all minimised) and total constraint violation of one candidate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    #[serde(with = "exact_f64::vec")]
    pub objectives: Vec<f64>,
    /// Zero means feasible, positive infeasible; conventionally the sum of positive
    /// constraint excesses, scaled as the caller chooses.
    #[serde(with = "exact_f64")]
    pub violation: f64,
}

impl Evaluation {
    pub fn feasible(&self) -> bool {
        self.violation <= 0.0
    }

    /// NaN would make every comparison false and silently break sorting; treat a NaN
    /// objective or violation as infinitely bad and a negative violation as feasible.
    fn sanitised(mut self) -> Self {
        for f in &mut self.objectives {
            if f.is_nan() {
                *f = f64::INFINITY;
            }
        }
        self.violation = if self.violation.is_nan() { f64::INFINITY } else { self.violation.max(0.0) };
        self
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Individual {
    #[serde(with = "exact_f64::vec")]
    pub x: Vec<f64>,
    pub eval: Evaluation,
    /// Non-domination level (0 = best) from the last constrained sort.
    pub rank: usize,
    /// Crowding distance within its front (infinite at the front's extremes).
    #[serde(with = "exact_f64")]
    pub crowding: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Mode {
    /// Deb et al. (2002): fill the next population front by front.
    Standard,
    /// Imitates MATLAB's `gamultiobj` (a "controlled elitist" NSGA-II): keep at most
    /// `pareto_fraction * pop` members of the first front, and stop when the (weighted)
    /// average relative change of the spread over `stall_generations` generations is at most
    /// `tol` and the spread is not rising (see `spread_change`).
    /// MATLAB's defaults are 0.35, 1e-4 and 100.
    MatlabLike { pareto_fraction: f64, tol: f64, stall_generations: u64 },
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Config {
    pub pop: usize,
    pub seed: u64,
    pub max_generations: u64,
    pub mode: Mode,
    /// SBX distribution index (larger = children closer to parents).
    pub crossover_eta: f64,
    /// Polynomial-mutation distribution index; each variable mutates with probability 1/dim.
    pub mutation_eta: f64,
    /// Probability that a pair of parents is crossed at all.
    pub crossover_prob: f64,
    /// How the binary tournaments draw and compare their contestants (issue 14's peer
    /// comparison: `permutation` closes the gap to pymoo's NSGA-II on the lunar problem).
    #[serde(default, skip_serializing_if = "Selection::is_deb")]
    pub selection: Selection,
}

/// Mating selection of [`Config`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Selection {
    /// Deb et al. (2002): both contestants drawn with replacement; constraint-domination,
    /// then rank, then crowding.
    #[default]
    Deb,
    /// pymoo's NSGA-II: contestants taken pairwise from random permutations of the
    /// population (everyone competes equally often); constraint-domination (Pareto dominance
    /// between feasible ones), then crowding.
    Permutation,
}

impl Selection {
    fn is_deb(&self) -> bool {
        *self == Selection::Deb
    }
}

impl Default for Config {
    /// The settings of Deb et al. (2002).
    fn default() -> Self {
        Config {
            pop: 100,
            seed: 0,
            max_generations: 250,
            mode: Mode::Standard,
            crossover_eta: 15.0,
            mutation_eta: 20.0,
            crossover_prob: 0.9,
            selection: Selection::Deb,
        }
    }
}

/// Everything needed to continue a run; serialised as a checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Generations completed (0 after `init`).
    pub generation: u64,
    pub population: Vec<Individual>,
    /// The only source of randomness after `init`.
    pub rng: ChaCha8Rng,
    /// Spread of the front after init and after each step; NaN while no point is feasible.
    #[serde(with = "exact_f64::vec")]
    pub spread_history: Vec<f64>,
    /// Candidates evaluated so far (initial population included).
    pub evaluations: u64,
    /// For each objective, the front point minimising it in the previous generation: the
    /// spread's movement term compares against these.
    #[serde(with = "exact_f64::vec_vec")]
    pub prev_extremes: Vec<Vec<f64>>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GenerationStats {
    pub generation: u64,
    pub evaluations: u64,
    /// Fraction of the current population with zero violation.
    pub feasible_fraction: f64,
    /// Number of points in [`Nsga2::pareto_front`].
    pub front_size: usize,
    /// Spread of the front (see [`spread`]); NaN while nothing is feasible.
    pub spread: f64,
    /// Smallest violation in the population (0 once something is feasible).
    pub min_violation: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Termination {
    MaxGenerations,
    SpreadStalled,
}

pub struct Nsga2 {
    pub config: Config,
}

impl Nsga2 {
    pub fn new(config: Config) -> Self {
        Nsga2 { config }
    }

    /// Uniform random population inside the bounds, repaired, evaluated as one batch
    /// (generation 0).
    pub fn init(&self, problem: &mut impl BatchProblem) -> State {
        let n = self.config.pop;
        assert!(n > 0, "population size must be positive");
        let (lo, hi) = checked_bounds(problem);
        let mut rng = ChaCha8Rng::seed_from_u64(self.config.seed);
        let xs: Vec<Vec<f64>> = (0..n)
            .map(|_| {
                let mut x: Vec<f64> = lo.iter().zip(&hi).map(|(&l, &h)| l + rng.random::<f64>() * (h - l)).collect();
                problem.repair(&mut x);
                x
            })
            .collect();
        let evals = evaluate(problem, &xs, 0);
        let mut population = into_individuals(xs, evals);
        rank_and_crowd(&mut population);
        let mut state = State {
            generation: 0,
            population,
            rng,
            spread_history: Vec::new(),
            evaluations: n as u64,
            prev_extremes: Vec::new(),
        };
        record(&mut state);
        state
    }

    /// One generation: crowded tournaments, SBX + polynomial mutation, one batch evaluation
    /// of the offspring, then (mu + lambda) survival.
    pub fn step(&self, state: &mut State, problem: &mut impl BatchProblem) -> GenerationStats {
        let (lo, hi) = checked_bounds(problem);
        let kids = self.offspring(state, &lo, &hi, problem);
        let generation = state.generation + 1;
        let evals = evaluate(problem, &kids, generation);
        state.evaluations += kids.len() as u64;

        let mut union = std::mem::take(&mut state.population);
        union.extend(into_individuals(kids, evals));
        state.population = self.survive(union);
        state.generation = generation;
        record(state)
    }

    pub fn should_stop(&self, state: &State) -> Option<Termination> {
        if let Mode::MatlabLike { tol, stall_generations, .. } = self.config.mode {
            let h = &state.spread_history;
            if spread_change(h, stall_generations).is_some_and(|c| c <= tol) && spread_not_rising(h, stall_generations)
            {
                return Some(Termination::SpreadStalled);
            }
        }
        (state.generation >= self.config.max_generations).then_some(Termination::MaxGenerations)
    }

    /// `init`, then `step` until `should_stop`; `on_generation` sees each step's statistics
    /// (use it to write checkpoints or log progress).
    pub fn run(
        &self,
        problem: &mut impl BatchProblem,
        mut on_generation: impl FnMut(&State, &GenerationStats),
    ) -> (State, Termination) {
        let mut state = self.init(problem);
        let why = self.resume(&mut state, problem, &mut on_generation);
        (state, why)
    }

    /// Continue a (loaded) state until `should_stop`.
    pub fn resume(
        &self,
        state: &mut State,
        problem: &mut impl BatchProblem,
        mut on_generation: impl FnMut(&State, &GenerationStats),
    ) -> Termination {
        loop {
            if let Some(why) = self.should_stop(state) {
                return why;
            }
            let stats = self.step(state, problem);
            on_generation(state, &stats);
        }
    }

    /// The feasible non-dominated members of the population; if none is feasible, the
    /// members with the smallest violation. Computed directly (not from `rank`) so it also
    /// holds for a hand-edited state.
    pub fn pareto_front(state: &State) -> Vec<Individual> {
        front_indices(&state.population).into_iter().map(|i| state.population[i].clone()).collect()
    }

    fn offspring(&self, state: &mut State, lo: &[f64], hi: &[f64], problem: &impl BatchProblem) -> Vec<Vec<f64>> {
        let n = self.config.pop;
        let mutation_prob = 1.0 / lo.len().max(1) as f64;
        let pop = &state.population;
        let rng = &mut state.rng;
        let mut kids = Vec::with_capacity(n);
        // permutation selection: the contestants of every tournament this generation, drawn
        // up front (two per parent, a parent per child)
        let mut contestants: Vec<usize> = Vec::new();
        if self.config.selection == Selection::Permutation {
            let needed = 2 * (n + n % 2);
            while contestants.len() < needed {
                let mut perm: Vec<usize> = (0..pop.len()).collect();
                // Fisher-Yates with the state's generator (fixed order: resumable)
                for i in (1..perm.len()).rev() {
                    let j = rng.random_range(0..=i);
                    perm.swap(i, j);
                }
                contestants.extend(perm);
            }
        }
        let mut next = 0usize;
        let mut pick = |rng: &mut ChaCha8Rng| match self.config.selection {
            Selection::Deb => tournament(pop, rng),
            Selection::Permutation => {
                let (a, b) = (contestants[next], contestants[next + 1]);
                next += 2;
                dominance_tournament(pop, a, b, rng)
            }
        };
        while kids.len() < n {
            let a = pick(rng);
            let b = pick(rng);
            let (mut c1, mut c2) =
                sbx(&pop[a].x, &pop[b].x, lo, hi, self.config.crossover_eta, self.config.crossover_prob, rng);
            for c in [&mut c1, &mut c2] {
                polynomial_mutation(c, lo, hi, self.config.mutation_eta, mutation_prob, rng);
                problem.repair(c);
            }
            kids.push(c1);
            // Each pair gives two children; an odd population drops the last pair's second
            // (Deb's reference code simply requires an even size).
            if kids.len() < n {
                kids.push(c2);
            }
        }
        kids
    }

    /// (mu + lambda) survival on parents + offspring (Deb et al. 2002, section III-C).
    fn survive(&self, mut union: Vec<Individual>) -> Vec<Individual> {
        let n = self.config.pop;
        let fronts = rank_and_crowd(&mut union);
        let mut chosen: Vec<usize> = Vec::with_capacity(n);
        match self.config.mode {
            Mode::Standard => fill_by_fronts(&fronts, &union, n, &mut chosen),
            Mode::MatlabLike { pareto_fraction, .. } => {
                // MATLAB distributes the population over all fronts geometrically, with the
                // first front capped at ParetoFraction. Approximation: cap the first front
                // (keeping its least crowded members), fill from later fronts as in
                // Standard, and if they run out, top up from the first front's leftovers
                // (MATLAB likewise lets the first front exceed the fraction then).
                let cap = ((pareto_fraction * n as f64).floor() as usize).clamp(1, n);
                let first = by_crowding(&fronts[0], &union);
                let (kept, leftovers) = first.split_at(cap.min(first.len()));
                chosen.extend_from_slice(kept);
                fill_by_fronts(&fronts[1..], &union, n, &mut chosen);
                let missing = n - chosen.len();
                chosen.extend(leftovers.iter().take(missing));
            }
        }
        debug_assert_eq!(chosen.len(), n);
        let mut slots: Vec<Option<Individual>> = union.into_iter().map(Some).collect();
        chosen.into_iter().map(|i| slots[i].take().expect("each individual is chosen once")).collect()
    }
}

/// Same as [`Nsga2::pareto_front`].
pub fn pareto_front(state: &State) -> Vec<Individual> {
    Nsga2::pareto_front(state)
}

/// Deb (2000) constraint-domination: does `a` beat `b`?
/// Feasible beats infeasible; between infeasible, the smaller violation wins; between
/// feasible, Pareto dominance (all objectives <=, one <).
pub fn constrained_dominates(a: &Evaluation, b: &Evaluation) -> bool {
    match (a.feasible(), b.feasible()) {
        (true, false) => true,
        (false, true) => false,
        (false, false) => a.violation < b.violation,
        (true, true) => dominates(&a.objectives, &b.objectives),
    }
}

/// Pareto dominance for minimisation.
pub fn dominates(a: &[f64], b: &[f64]) -> bool {
    let mut strictly = false;
    for (x, y) in a.iter().zip(b) {
        if x > y {
            return false;
        }
        strictly |= x < y;
    }
    strictly
}

/// Non-dominated sort under constraint-domination. Returns fronts of indices into `evals`,
/// best first, each in ascending index order. Two finite objectives (the sawtooth problem)
/// take an O(N log N + N F) path; anything else the O(M N²) sort of Deb et al. 2002.
pub fn non_dominated_sort(evals: &[&Evaluation]) -> Vec<Vec<usize>> {
    let two_d = evals
        .iter()
        .all(|e| e.objectives.len() == 2 && e.objectives.iter().all(|v| v.is_finite()) && !e.violation.is_nan());
    if two_d {
        non_dominated_sort_2d(evals)
    } else {
        non_dominated_sort_generic(evals)
    }
}

/// Two objectives: feasible points sorted by (f1, f2) are placed in the first front whose
/// last member does not dominate them (Zhang et al. 2015, ENS; within a front the last
/// member has the largest f1 and the smallest f2, so it is the only possible dominator).
/// Infeasible points follow, one front per distinct violation (Deb 2000: the smaller
/// violation wins, equal violations are mutually non-dominated). Equal to the generic sort.
fn non_dominated_sort_2d(evals: &[&Evaluation]) -> Vec<Vec<usize>> {
    let (mut feasible, mut infeasible): (Vec<usize>, Vec<usize>) = (0..evals.len()).partition(|&i| evals[i].feasible());
    let obj = |i: usize| (evals[i].objectives[0], evals[i].objectives[1]);
    feasible.sort_by(|&a, &b| obj(a).0.total_cmp(&obj(b).0).then(obj(a).1.total_cmp(&obj(b).1)).then(a.cmp(&b)));
    let mut fronts: Vec<Vec<usize>> = Vec::new();
    let mut last: Vec<usize> = Vec::new();
    for p in feasible {
        let k =
            last.iter().position(|&q| !dominates(&evals[q].objectives, &evals[p].objectives)).unwrap_or(fronts.len());
        if k == fronts.len() {
            fronts.push(Vec::new());
            last.push(p);
        }
        fronts[k].push(p);
        last[k] = p;
    }
    infeasible.sort_by(|&a, &b| evals[a].violation.total_cmp(&evals[b].violation).then(a.cmp(&b)));
    for (i, &p) in infeasible.iter().enumerate() {
        if i == 0 || evals[infeasible[i - 1]].violation < evals[p].violation {
            fronts.push(Vec::new());
        }
        fronts.last_mut().expect("pushed above").push(p);
    }
    for f in fronts.iter_mut() {
        f.sort_unstable();
    }
    fronts
}

/// Fast non-dominated sort (Deb et al. 2002, fig. 1) under constraint-domination, any
/// number of objectives.
pub fn non_dominated_sort_generic(evals: &[&Evaluation]) -> Vec<Vec<usize>> {
    let n = evals.len();
    let mut beaten_by = vec![0usize; n];
    let mut beats: Vec<Vec<usize>> = vec![Vec::new(); n];
    for p in 0..n {
        for q in p + 1..n {
            if constrained_dominates(evals[p], evals[q]) {
                beats[p].push(q);
                beaten_by[q] += 1;
            } else if constrained_dominates(evals[q], evals[p]) {
                beats[q].push(p);
                beaten_by[p] += 1;
            }
        }
    }
    let mut fronts = Vec::new();
    let mut current: Vec<usize> = (0..n).filter(|&i| beaten_by[i] == 0).collect();
    while !current.is_empty() {
        let mut next = Vec::new();
        for &p in &current {
            for &q in &beats[p] {
                beaten_by[q] -= 1;
                if beaten_by[q] == 0 {
                    next.push(q);
                }
            }
        }
        next.sort_unstable();
        fronts.push(std::mem::replace(&mut current, next));
    }
    fronts
}

/// Crowding distance of each point of one front (Deb et al. 2002, fig. 3): the sum over
/// objectives of the normalised gap between its two neighbours; the extremes get infinity
/// so they always survive.
pub fn crowding_distance(objectives: &[&[f64]]) -> Vec<f64> {
    let n = objectives.len();
    let mut dist = vec![0.0; n];
    if n <= 2 {
        dist.fill(f64::INFINITY);
        return dist;
    }
    let m = objectives[0].len();
    let mut order: Vec<usize> = (0..n).collect();
    #[allow(clippy::needless_range_loop)] // k indexes the inner (objective) dimension
    for k in 0..m {
        // Ties broken by index: the order never depends on the previous objective's sort.
        order.sort_by(|&a, &b| objectives[a][k].total_cmp(&objectives[b][k]).then(a.cmp(&b)));
        let (first, last) = (order[0], order[n - 1]);
        dist[first] = f64::INFINITY;
        dist[last] = f64::INFINITY;
        let range = objectives[last][k] - objectives[first][k];
        if !(range > 0.0 && range.is_finite()) {
            continue;
        }
        for w in order.windows(3) {
            dist[w[1]] += (objectives[w[2]][k] - objectives[w[0]][k]) / range;
        }
    }
    dist
}

/// Spread of a front, as MATLAB's `gamultiobj` uses it for stopping: Deb's spread
/// Delta = (d_f + d_l + sum|d_i - d_mean|) / (d_f + d_l + (N-1) d_mean), with two
/// approximations:
/// - The true front's extremes are unknown, so (like MATLAB's mu) d_f + d_l is replaced by
///   the movement of the front's extremes since the previous generation: the sum over
///   objectives k of |e_k(t) - e_k(t-1)|, e_k being the front point minimising objective k.
///   `prev_extremes` empty means no previous generation (movement 0).
/// - d_i are Euclidean distances between neighbours after sorting the front by the first
///   objective (exact for two objectives; only a rough ordering for more). MATLAB uses the
///   standard deviation of the crowding distances instead of sum|d_i - d_mean|.
///
/// Returns (spread, extremes of this front). A front of one point, with no movement, has
/// spread 0. Objectives are not normalised.
pub fn spread(front: &[&[f64]], prev_extremes: &[Vec<f64>]) -> (f64, Vec<Vec<f64>>) {
    if front.is_empty() {
        return (f64::NAN, Vec::new());
    }
    let m = front[0].len();
    let extremes: Vec<Vec<f64>> = (0..m)
        .map(|k| {
            front
                .iter()
                .min_by(|a, b| a[k].total_cmp(&b[k]).then_with(|| lex_cmp(a, b)))
                .expect("front is not empty")
                .to_vec()
        })
        .collect();
    let movement: f64 = if prev_extremes.len() == m {
        extremes.iter().zip(prev_extremes).map(|(e, p)| euclid(e, p)).sum()
    } else {
        0.0
    };
    let mut sorted: Vec<&[f64]> = front.to_vec();
    sorted.sort_by(|a, b| lex_cmp(a, b));
    let gaps: Vec<f64> = sorted.windows(2).map(|w| euclid(w[0], w[1])).collect();
    let (num, den) = if gaps.is_empty() {
        (movement, movement)
    } else {
        let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
        let dev: f64 = gaps.iter().map(|d| (d - mean).abs()).sum();
        (movement + dev, movement + gaps.len() as f64 * mean)
    };
    let s = if den > 0.0 { num / den } else { 0.0 };
    (s, extremes)
}

/// MATLAB's stall measure (gamultiobj's convergence test): over the last `stall + 1`
/// relative spread changes c = |S(t) - S(t-1)| / (1 + S(t-1)), a geometrically weighted sum
/// (weight 1/2 for the newest, 1/4 for the one before, ...) divided by `stall + 1`.
/// Returns None while the history is too short or the window holds NaN (no feasible front
/// yet, which must not count as stalled). Deviation: MATLAB's loop leaves out the newest
/// change; it is included here.
fn spread_change(history: &[f64], stall: u64) -> Option<f64> {
    let window = usize::try_from(stall).ok()?.checked_add(1)?;
    if history.len() <= window {
        return None;
    }
    let tail = &history[history.len() - window - 1..];
    if tail.iter().any(|s| !s.is_finite()) {
        return None;
    }
    let mut weight = 1.0;
    let mut total = 0.0;
    for w in tail.windows(2).rev() {
        weight *= 0.5;
        total += weight * (w[1] - w[0]).abs() / (1.0 + w[0]);
    }
    Some(total / window as f64)
}

/// MATLAB's second stopping condition: the newest spread is no larger than the window mean,
/// so a run does not stop while its front is getting less uniform.
fn spread_not_rising(history: &[f64], stall: u64) -> bool {
    let window = usize::try_from(stall).unwrap_or(usize::MAX).saturating_add(1);
    let tail = &history[history.len().saturating_sub(window + 1)..];
    let mean = tail.iter().sum::<f64>() / tail.len() as f64;
    tail.last().is_some_and(|&last| last <= mean)
}

/// Write `state` as JSON atomically (`io::atomic`): a crash leaves either the old or the
/// new checkpoint, never a torn one.
pub fn save_checkpoint(path: impl AsRef<Path>, state: &State) -> anyhow::Result<()> {
    let path = path.as_ref();
    crate::io::atomic::write_atomic_with(path, |w| Ok(serde_json::to_writer(w, state)?))
        .with_context(|| format!("writing checkpoint {}", path.display()))
}

/// Read a checkpoint written by [`save_checkpoint`]. The state does not carry the
/// [`Config`]: continue it with the same config and problem to reproduce the original run.
pub fn load_checkpoint(path: impl AsRef<Path>) -> anyhow::Result<State> {
    let path = path.as_ref();
    let text = crate::io::bounded::read_text(path, &crate::schema::CHECKPOINT_FILE)?;
    serde_json::from_str(&text).with_context(|| format!("parsing checkpoint {}", path.display()))
}

// ---------------------------------------------------------------------------------------
// Internals

fn checked_bounds(problem: &impl BatchProblem) -> (Vec<f64>, Vec<f64>) {
    let (lo, hi) = problem.bounds();
    let d = problem.dim();
    assert!(lo.len() == d && hi.len() == d, "bounds must have dim() = {d} entries");
    assert!(
        lo.iter().zip(&hi).all(|(l, h)| l <= h && l.is_finite() && h.is_finite()),
        "bounds must be finite with lower <= upper"
    );
    (lo, hi)
}

fn evaluate(problem: &mut impl BatchProblem, xs: &[Vec<f64>], generation: u64) -> Vec<Evaluation> {
    let evals = problem.evaluate_batch(xs, generation);
    assert_eq!(evals.len(), xs.len(), "evaluate_batch must return one Evaluation per candidate");
    let m = problem.n_objectives();
    evals
        .into_iter()
        .map(|e| {
            assert_eq!(e.objectives.len(), m, "expected {m} objectives");
            e.sanitised()
        })
        .collect()
}

fn into_individuals(xs: Vec<Vec<f64>>, evals: Vec<Evaluation>) -> Vec<Individual> {
    xs.into_iter().zip(evals).map(|(x, eval)| Individual { x, eval, rank: 0, crowding: 0.0 }).collect()
}

/// Sort `pop` into fronts and store each member's rank and crowding distance.
fn rank_and_crowd(pop: &mut [Individual]) -> Vec<Vec<usize>> {
    let evals: Vec<&Evaluation> = pop.iter().map(|i| &i.eval).collect();
    let fronts = non_dominated_sort(&evals);
    for (rank, front) in fronts.iter().enumerate() {
        let objs: Vec<&[f64]> = front.iter().map(|&i| pop[i].eval.objectives.as_slice()).collect();
        let cd = crowding_distance(&objs);
        for (&i, d) in front.iter().zip(cd) {
            pop[i].rank = rank;
            pop[i].crowding = d;
        }
    }
    fronts
}

/// Front members, least crowded (largest distance) first; ties keep index order.
fn by_crowding(front: &[usize], pop: &[Individual]) -> Vec<usize> {
    let mut v = front.to_vec();
    v.sort_by(|&a, &b| pop[b].crowding.total_cmp(&pop[a].crowding).then(a.cmp(&b)));
    v
}

/// Take whole fronts while they fit, then the least crowded part of the next one.
fn fill_by_fronts(fronts: &[Vec<usize>], pop: &[Individual], n: usize, chosen: &mut Vec<usize>) {
    for front in fronts {
        let room = n - chosen.len();
        if room == 0 {
            break;
        }
        if front.len() <= room {
            chosen.extend_from_slice(front);
        } else {
            chosen.extend(by_crowding(front, pop).into_iter().take(room));
        }
    }
}

/// Binary tournament (Deb et al. 2002 crowded comparison). Constraint-domination decides
/// first, as in Deb's reference code; then rank (itself from the constrained sort), then the
/// larger crowding distance; a coin decides exact ties.
fn tournament(pop: &[Individual], rng: &mut ChaCha8Rng) -> usize {
    let a = rng.random_range(0..pop.len());
    let b = rng.random_range(0..pop.len());
    let (ia, ib) = (&pop[a], &pop[b]);
    if constrained_dominates(&ia.eval, &ib.eval) {
        return a;
    }
    if constrained_dominates(&ib.eval, &ia.eval) {
        return b;
    }
    match ia.rank.cmp(&ib.rank).then_with(|| ib.crowding.total_cmp(&ia.crowding)) {
        Ordering::Less => a,
        Ordering::Greater => b,
        Ordering::Equal => {
            if rng.random::<f64>() <= 0.5 {
                a
            } else {
                b
            }
        }
    }
}

/// pymoo's NSGA-II comparison (`comp_by_dom_and_crowding`): constraint-domination (the
/// smaller violation between infeasible ones, Pareto dominance between feasible ones), then
/// the larger crowding distance, then a coin.
fn dominance_tournament(pop: &[Individual], a: usize, b: usize, rng: &mut ChaCha8Rng) -> usize {
    let (ia, ib) = (&pop[a], &pop[b]);
    if constrained_dominates(&ia.eval, &ib.eval) {
        return a;
    }
    if constrained_dominates(&ib.eval, &ia.eval) {
        return b;
    }
    match ib.crowding.total_cmp(&ia.crowding) {
        Ordering::Less => a,
        Ordering::Greater => b,
        Ordering::Equal => {
            if rng.random::<f64>() <= 0.5 {
                a
            } else {
                b
            }
        }
    }
}

/// Bounded simulated binary crossover, following Deb's NSGA-II reference code (`realcross`):
/// the spread factor's distribution is truncated so children stay inside the bounds.
fn sbx(
    p1: &[f64],
    p2: &[f64],
    lo: &[f64],
    hi: &[f64],
    eta: f64,
    prob: f64,
    rng: &mut ChaCha8Rng,
) -> (Vec<f64>, Vec<f64>) {
    let mut c1 = p1.to_vec();
    let mut c2 = p2.to_vec();
    if rng.random::<f64>() > prob {
        return (c1, c2);
    }
    let exponent = 1.0 / (eta + 1.0);
    for j in 0..p1.len() {
        // Each variable is crossed with probability 1/2; nearly equal values are left alone
        // because the spread factor divides by their difference.
        if rng.random::<f64>() > 0.5 || (p1[j] - p2[j]).abs() <= 1e-14 {
            continue;
        }
        let (y1, y2) = if p1[j] < p2[j] { (p1[j], p2[j]) } else { (p2[j], p1[j]) };
        let (yl, yu) = (lo[j], hi[j]);
        let u = rng.random::<f64>();
        let betaq = |beta: f64| {
            let alpha = 2.0 - beta.powf(-(eta + 1.0));
            if u <= 1.0 / alpha {
                (u * alpha).powf(exponent)
            } else {
                (1.0 / (2.0 - u * alpha)).powf(exponent)
            }
        };
        let v1 = 0.5 * ((y1 + y2) - betaq(1.0 + 2.0 * (y1 - yl) / (y2 - y1)) * (y2 - y1));
        let v2 = 0.5 * ((y1 + y2) + betaq(1.0 + 2.0 * (yu - y2) / (y2 - y1)) * (y2 - y1));
        let (v1, v2) = (v1.clamp(yl, yu), v2.clamp(yl, yu));
        if rng.random::<f64>() <= 0.5 {
            c1[j] = v2;
            c2[j] = v1;
        } else {
            c1[j] = v1;
            c2[j] = v2;
        }
    }
    (c1, c2)
}

/// Bounded polynomial mutation (Deb's reference code, `real_mutate_ind`): the perturbation
/// shrinks near a bound so the result stays inside it.
fn polynomial_mutation(x: &mut [f64], lo: &[f64], hi: &[f64], eta: f64, prob: f64, rng: &mut ChaCha8Rng) {
    let exponent = 1.0 / (eta + 1.0);
    for j in 0..x.len() {
        if rng.random::<f64>() > prob {
            continue;
        }
        let (yl, yu) = (lo[j], hi[j]);
        if yu <= yl {
            continue;
        }
        let y = x[j];
        let delta1 = (y - yl) / (yu - yl);
        let delta2 = (yu - y) / (yu - yl);
        let u = rng.random::<f64>();
        let deltaq = if u <= 0.5 {
            let val = 2.0 * u + (1.0 - 2.0 * u) * (1.0 - delta1).powf(eta + 1.0);
            val.powf(exponent) - 1.0
        } else {
            let val = 2.0 * (1.0 - u) + 2.0 * (u - 0.5) * (1.0 - delta2).powf(eta + 1.0);
            1.0 - val.powf(exponent)
        };
        x[j] = (y + deltaq * (yu - yl)).clamp(yl, yu);
    }
}

/// Indices of the front reported by `pareto_front`, in population order.
fn front_indices(pop: &[Individual]) -> Vec<usize> {
    let feasible: Vec<usize> = (0..pop.len()).filter(|&i| pop[i].eval.feasible()).collect();
    if feasible.is_empty() {
        let least = pop.iter().map(|i| i.eval.violation).fold(f64::INFINITY, f64::min);
        return (0..pop.len()).filter(|&i| pop[i].eval.violation == least).collect();
    }
    feasible
        .iter()
        .copied()
        .filter(|&i| !feasible.iter().any(|&j| dominates(&pop[j].eval.objectives, &pop[i].eval.objectives)))
        .collect()
}

/// Update the spread history and extremes after init or a step, and summarise.
fn record(state: &mut State) -> GenerationStats {
    let pop = &state.population;
    let front = front_indices(pop);
    let any_feasible = front.first().is_some_and(|&i| pop[i].eval.feasible());
    let s = if any_feasible {
        let objs: Vec<&[f64]> = front.iter().map(|&i| pop[i].eval.objectives.as_slice()).collect();
        let (s, extremes) = spread(&objs, &state.prev_extremes);
        state.prev_extremes = extremes;
        s
    } else {
        f64::NAN
    };
    state.spread_history.push(s);
    let feasible = pop.iter().filter(|i| i.eval.feasible()).count();
    GenerationStats {
        generation: state.generation,
        evaluations: state.evaluations,
        feasible_fraction: feasible as f64 / pop.len() as f64,
        front_size: front.len(),
        spread: s,
        min_violation: pop.iter().map(|i| i.eval.violation).fold(f64::INFINITY, f64::min),
    }
}

fn euclid(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

fn lex_cmp(a: &[f64], b: &[f64]) -> Ordering {
    a.iter().zip(b).map(|(x, y)| x.total_cmp(y)).find(|o| o.is_ne()).unwrap_or(Ordering::Equal)
}

/// Exact f64 (de)serialisation for checkpoints. serde_json without its `float_roundtrip`
/// feature may parse a float one ulp off, and it writes inf/NaN (crowding distances are
/// often infinite) as `null`, which does not read back. So floats are written as strings in
/// Rust's shortest round-trip form ("0.1", "1e-300", "inf") and parsed with `str::parse`,
/// which is correctly rounded; plain JSON numbers are accepted on input too.
mod exact_f64 {
    use serde::de::{self, Deserializer, Visitor};
    use serde::{Deserialize, Serialize, Serializer};
    use std::fmt;

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(&format_args!("{x:?}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        d.deserialize_any(F64Visitor)
    }

    struct F64Visitor;

    impl Visitor<'_> for F64Visitor {
        type Value = f64;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a float as a string or a number")
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<f64, E> {
            v.parse().map_err(|_| E::custom(format!("bad float {v:?}")))
        }
        fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
            Ok(v)
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
            Ok(v as f64)
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
            Ok(v as f64)
        }
    }

    #[derive(Serialize, Deserialize)]
    #[serde(transparent)]
    struct Exact(#[serde(with = "super::exact_f64")] f64);

    pub mod vec {
        use super::*;

        pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
            s.collect_seq(v.iter().map(|&x| Exact(x)))
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
            Ok(Vec::<Exact>::deserialize(d)?.into_iter().map(|e| e.0).collect())
        }
    }

    pub mod vec_vec {
        use super::*;

        pub fn serialize<S: Serializer>(v: &[Vec<f64>], s: S) -> Result<S::Ok, S::Error> {
            s.collect_seq(v.iter().map(|row| row.iter().map(|&x| Exact(x)).collect::<Vec<_>>()))
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Vec<f64>>, D::Error> {
            Ok(Vec::<Vec<Exact>>::deserialize(d)?
                .into_iter()
                .map(|row| row.into_iter().map(|e| e.0).collect())
                .collect())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(objectives: &[f64], violation: f64) -> Evaluation {
        Evaluation { objectives: objectives.to_vec(), violation }
    }

    #[test]
    fn two_objective_sort_equals_the_generic_sort() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for trial in 0..200 {
            let n = 1 + trial % 60;
            // coarse values make ties, duplicates and equal violations common
            let evals: Vec<Evaluation> = (0..n)
                .map(|_| Evaluation {
                    objectives: vec![rng.random_range(0..6) as f64, rng.random_range(0..6) as f64],
                    violation: if rng.random_bool(0.3) { rng.random_range(1..4) as f64 } else { 0.0 },
                })
                .collect();
            let refs: Vec<&Evaluation> = evals.iter().collect();
            assert_eq!(non_dominated_sort_2d(&refs), non_dominated_sort_generic(&refs), "trial {trial}");
        }
    }

    #[test]
    fn constraint_domination_rules() {
        let feasible_bad = ev(&[100.0, 100.0], 0.0);
        let infeasible_good = ev(&[0.0, 0.0], 0.1);
        assert!(constrained_dominates(&feasible_bad, &infeasible_good));
        assert!(!constrained_dominates(&infeasible_good, &feasible_bad));
        let worse = ev(&[0.0, 0.0], 0.5);
        assert!(constrained_dominates(&infeasible_good, &worse));
        assert!(!constrained_dominates(&worse, &infeasible_good));
        // Equal violation: neither wins, whatever the objectives.
        let same = ev(&[5.0, 5.0], 0.1);
        assert!(!constrained_dominates(&same, &infeasible_good));
        assert!(!constrained_dominates(&infeasible_good, &same));
        // Feasible pair: Pareto dominance; equal points do not dominate each other.
        assert!(constrained_dominates(&ev(&[1.0, 2.0], 0.0), &ev(&[1.0, 3.0], 0.0)));
        assert!(!constrained_dominates(&ev(&[1.0, 3.0], 0.0), &ev(&[2.0, 2.0], 0.0)));
        assert!(!constrained_dominates(&ev(&[1.0, 2.0], 0.0), &ev(&[1.0, 2.0], 0.0)));
    }

    #[test]
    fn sort_puts_feasible_first_and_orders_infeasible_by_violation() {
        let evals = [
            ev(&[0.0, 0.0], 2.0),
            ev(&[3.0, 3.0], 0.0),
            ev(&[1.0, 4.0], 0.0),
            ev(&[4.0, 1.0], 0.0),
            ev(&[0.0, 0.0], 1.0),
        ];
        let refs: Vec<&Evaluation> = evals.iter().collect();
        assert_eq!(non_dominated_sort(&refs), vec![vec![1, 2, 3], vec![4], vec![0]]);
    }

    #[test]
    fn crowding_gives_extremes_infinity_and_scales_by_range() {
        let pts: [&[f64]; 4] = [&[0.0, 4.0], &[1.0, 2.0], &[3.0, 1.0], &[4.0, 0.0]];
        let d = crowding_distance(&pts);
        assert!(d[0].is_infinite() && d[3].is_infinite());
        assert!((d[1] - (3.0 / 4.0 + 3.0 / 4.0)).abs() < 1e-12);
        assert!((d[2] - (3.0 / 4.0 + 2.0 / 4.0)).abs() < 1e-12);
    }

    #[test]
    fn spread_is_zero_for_an_even_still_front() {
        let front: Vec<Vec<f64>> = (0..11).map(|i| vec![i as f64, 10.0 - i as f64]).collect();
        let refs: Vec<&[f64]> = front.iter().map(|v| v.as_slice()).collect();
        let (s, extremes) = spread(&refs, &[]);
        assert!(s.abs() < 1e-12);
        let (s2, _) = spread(&refs, &extremes);
        assert!(s2.abs() < 1e-12);
        // Uneven gaps raise it.
        let uneven: [&[f64]; 3] = [&[0.0, 1.0], &[0.1, 0.9], &[1.0, 0.0]];
        assert!(spread(&uneven, &[]).0 > 0.5);
    }

    #[test]
    fn stall_measure_needs_a_full_finite_window() {
        // stall 1 -> window of 2 changes, 3 values.
        assert_eq!(spread_change(&[1.0, 1.0], 1), None);
        assert_eq!(spread_change(&[1.0, 1.0, 1.0], 1), Some(0.0));
        assert_eq!(spread_change(&[f64::NAN, 1.0, 1.0], 1), None);
        // Changes (oldest first) 1/(1+1) = 0.5 and 1/(1+2) = 1/3, weights 1/4 and 1/2, / 2.
        let c = spread_change(&[5.0, 1.0, 2.0, 1.0], 1).unwrap();
        assert!((c - (0.25 * 0.5 + 0.5 / 3.0) / 2.0).abs() < 1e-15);
        assert!(spread_not_rising(&[1.0, 2.0, 1.0], 1));
        assert!(!spread_not_rising(&[1.0, 1.0, 2.0], 1));
    }

    #[test]
    fn variation_stays_in_bounds() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let lo = [0.0, -1.0, 5.0];
        let hi = [1.0, 1.0, 5.0];
        for _ in 0..2000 {
            let p1: Vec<f64> = (0..3).map(|j| lo[j] + rng.random::<f64>() * (hi[j] - lo[j])).collect();
            let p2: Vec<f64> = (0..3).map(|j| lo[j] + rng.random::<f64>() * (hi[j] - lo[j])).collect();
            let (mut c1, mut c2) = sbx(&p1, &p2, &lo, &hi, 15.0, 0.9, &mut rng);
            polynomial_mutation(&mut c1, &lo, &hi, 20.0, 1.0, &mut rng);
            polynomial_mutation(&mut c2, &lo, &hi, 20.0, 1.0, &mut rng);
            for c in [&c1, &c2] {
                for j in 0..3 {
                    assert!(c[j] >= lo[j] && c[j] <= hi[j], "{c:?}");
                }
            }
        }
    }

    #[test]
    fn floats_round_trip_exactly_through_json() {
        let awkward = [
            0.1,
            1.0 / 3.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            0.30000000000000004,
            2.225_073_858_507_201e-308,
            9007199254740993.0,
        ];
        let ind = Individual { x: awkward.to_vec(), eval: ev(&awkward, 0.0), rank: 3, crowding: f64::INFINITY };
        let json = serde_json::to_string(&ind).unwrap();
        let back: Individual = serde_json::from_str(&json).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.x), bits(&ind.x));
        assert_eq!(bits(&back.eval.objectives), bits(&ind.eval.objectives));
        assert_eq!(back.crowding, f64::INFINITY);
        // Plain numbers are accepted too (hand-written files).
        let e: Evaluation = serde_json::from_str(r#"{"objectives":[1.5,2],"violation":0}"#).unwrap();
        assert_eq!(e, ev(&[1.5, 2.0], 0.0));
    }
}
