//! A fitted model's gap and its uncertainty: re-scored on fresh particle streams
//! ([`rescore`]) and bootstrapped over the runs and the streams, paired across models
//! ([`bootstrap_gaps`]); the paired intervals and standard deviations that the ranking, the
//! verdict and the pair compare models by.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::model_result::ModelResult;
use super::verdict;
use crate::calibrate::stats::{percentile, sample_sd};
use crate::calibrate::{Condition, Fit, Simulator, Space, Target};

/// Lower and upper percentile of every bootstrap interval.
pub const INTERVAL: (f64, f64) = (0.05, 0.95);

/// The 5-95 % interval ([`INTERVAL`]) of bootstrap replicates.
pub fn interval(v: &[f64]) -> [f64; 2] {
    [percentile(v, INTERVAL.0), percentile(v, INTERVAL.1)]
}

/// Paired bootstrap interval of `a`'s gap minus `b`'s (the replicates share their
/// resamples, `bootstrap_gaps`): above 0 when `b` improves on `a`.
pub fn paired_interval(a: &ModelResult, b: &ModelResult) -> [f64; 2] {
    let d: Vec<f64> = a.replicates.iter().zip(&b.replicates).map(|(x, y)| x - y).collect();
    interval(&d)
}

/// The bootstrap sd of `a`'s gap minus `b`'s with both sources of noise, the runs' alone and
/// the simulation's alone ([`ModelResult::improvement_sd`]).
pub fn paired_sd(a: &ModelResult, b: &ModelResult) -> [f64; 3] {
    let sd = |x: &[f64], y: &[f64]| sample_sd(&x.iter().zip(y).map(|(p, q)| p - q).collect::<Vec<_>>());
    [
        sd(&a.replicates, &b.replicates),
        sd(&a.replicates_runs, &b.replicates_runs),
        sd(&a.replicates_streams, &b.replicates_streams),
    ]
}

/// A fitted model before it is re-scored: its fit, nothing measured on fresh streams yet.
pub fn new_result(space: &Space, fit: Fit, baseline_dim: usize) -> ModelResult {
    ModelResult {
        effects: space.effects.clone(),
        names: space.names(),
        evaluations: fit.evaluations,
        full: fit,
        fresh: Vec::new(),
        gap: f64::NAN,
        gap_by_condition: Vec::new(),
        replicates: Vec::new(),
        replicates_runs: Vec::new(),
        replicates_streams: Vec::new(),
        interval: [f64::NAN; 2],
        se: f64::NAN,
        improvement_interval: [f64::NAN; 2],
        improvement_sd: [f64::NAN; 3],
        // parameters beyond the baseline's (quadratic drag trades k_drag for its own two)
        extra_params: space.dim().saturating_sub(baseline_dim),
        score: f64::NAN,
    }
}

/// Re-score fitted models with fresh particle streams up to `streams` of them: one engine
/// call per stream for every model. Streams the models already have are kept (stream r
/// always comes from the same seed, so a second rescore extends the first, common random
/// numbers throughout). Fills `fresh`, `gap` and `gap_by_condition`.
pub fn rescore(
    sim: &Simulator,
    spaces: &[&Space],
    models: &mut [ModelResult],
    particles: u32,
    streams: usize,
    seed: u64,
) {
    let conds = sim.conditions;
    let mut points = Vec::with_capacity(models.len());
    for (space, m) in spaces.iter().zip(models.iter()) {
        points.push((*space, m.full.x.clone()));
    }
    let have = models.iter().map(|m| m.fresh.len()).min().unwrap_or(0).min(streams);
    for m in models.iter_mut() {
        m.fresh.truncate(have);
    }
    for r in have..streams {
        // stream r + 1: the fit used `seed` itself
        let bins =
            sim.simulate(&points, particles, seed.wrapping_add(1 + r as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        for (m, b) in models.iter_mut().zip(bins) {
            // a point the fit simulated cannot fail on another stream; keep the fit's bins
            m.fresh.push(b.unwrap_or_else(|| m.full.bins.clone()));
        }
    }
    let targets: Vec<Target> = conds.iter().map(Condition::target_all).collect();
    for m in models.iter_mut() {
        let mean = m.mean_fresh_bins();
        m.gap_by_condition =
            (0..conds.len()).map(|c| verdict::loss_adjusted_sse(&conds[c], &targets[c].bins, &mean[c])).collect();
        m.gap = m.gap_by_condition.iter().sum();
    }
}

/// One bootstrap replicate of a model's fresh-mean bins in one condition: the mean of the
/// streams `draw` picked (with replacement), its deviation from the mean of all streams
/// widened by √(k/(k−1)) — a resample of k streams spreads (k−1)/k of their mean's variance
/// — so that the replicates carry the mean's Monte-Carlo variance, neither less nor one
/// stream's k-fold. With one stream there is no spread to resample: the mean is held.
fn resampled_bins(fresh: &[Vec<Vec<f64>>], mean: &[f64], c: usize, draw: &[usize]) -> Vec<f64> {
    let k = fresh.len();
    if k < 2 || draw.is_empty() {
        return mean.to_vec();
    }
    let widen = (k as f64 / (k - 1) as f64).sqrt();
    (0..mean.len())
        .map(|j| {
            let drawn = draw.iter().map(|r| fresh[*r][c][j]).sum::<f64>() / draw.len() as f64;
            mean[j] + widen * (drawn - mean[j])
        })
        .collect()
}

/// The bootstrap replicates of every model's gap, paired: per replicate one resample of the
/// runs of every condition and one resample of the fresh streams' indices, the same for
/// all models (the streams are common random numbers: stream r of every model comes from
/// the same seed). Besides the replicates that resample both, those that resample one
/// source alone (`replicates_runs`, `replicates_streams`): what part of an interval is the
/// data's run-to-run noise and what part the simulation's. The resamples depend only on
/// `seed`, the conditions and the stream count, so calls with the same ones pair their
/// models too. Fills the intervals, the standard errors and the ranking scores.
pub fn bootstrap_gaps(conds: &[Condition], models: &mut [ModelResult], replicates: usize, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xD1A6_0005);
    let streams = models.iter().map(|m| m.fresh.len()).min().unwrap_or(0);
    let means: Vec<Vec<Vec<f64>>> = models.iter().map(ModelResult::mean_fresh_bins).collect();
    let all: Vec<Vec<f64>> = conds.iter().map(|c| c.target_all().bins).collect();
    for m in models.iter_mut() {
        m.replicates = Vec::with_capacity(replicates);
        m.replicates_runs = Vec::with_capacity(replicates);
        m.replicates_streams = Vec::with_capacity(replicates);
    }
    for _ in 0..replicates {
        let draw: Vec<usize> = (0..streams).map(|_| rng.random_range(0..streams)).collect();
        // per model: both sources, the runs alone, the streams alone
        let mut totals = vec![[0.0; 3]; models.len()];
        for (c, cond) in conds.iter().enumerate() {
            let n = cond.runs.runs.len();
            let idx: Vec<usize> = (0..n).map(|_| rng.random_range(0..n)).collect();
            let t = cond.target(&idx);
            for ((m, mean), total) in models.iter().zip(&means).zip(totals.iter_mut()) {
                let sim = resampled_bins(&m.fresh[..streams.min(m.fresh.len())], &mean[c], c, &draw);
                total[0] += verdict::loss_adjusted_sse(cond, &t.bins, &sim);
                total[1] += verdict::loss_adjusted_sse(cond, &t.bins, &mean[c]);
                total[2] += verdict::loss_adjusted_sse(cond, &all[c], &sim);
            }
        }
        for (m, t) in models.iter_mut().zip(totals) {
            m.replicates.push(t[0]);
            m.replicates_runs.push(t[1]);
            m.replicates_streams.push(t[2]);
        }
    }
    for m in models.iter_mut() {
        m.interval = interval(&m.replicates);
        m.se = sample_sd(&m.replicates);
        m.score = m.gap + 2.0 * m.extra_params as f64 * if m.se.is_finite() { m.se } else { 0.0 };
    }
}
