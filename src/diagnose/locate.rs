//! Where the baseline misses, per condition ([`WhereCondition`]: residuals per tooth with
//! their uncertainty, centre of mass and dispersion, first flight against bounce chain,
//! where each third of the fill comes to rest), and how far the top-ranked effect closes it
//! ([`GapCondition`]: before and after, with intervals over the runs): the "where" and "how
//! far" stage of a diagnosis.

use anyhow::Context as _;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::candidates::Ranked;
use super::model_result::{DepthLayer, Z_FLAG};
use super::run::Run;
use super::scoring::interval;
use crate::calibrate::stats::sample_sd;
use crate::calibrate::{Condition, MeasuredSummary, Space};
use crate::engine::{evaluate_detailed, particle_engine, EngineKind};
use crate::model::outcome::{centre_and_dispersion, end_tooth, ParticleState};
use crate::model::Scenario;

/// A per-tooth (or per-metric) residual with its uncertainty.
#[derive(Clone, Debug)]
pub struct Residual {
    /// Measured and simulated values (percent, or teeth for the metrics).
    pub measured: f64,
    pub simulated: f64,
    pub residual: f64,
    /// Combined uncertainty and its parts (run-to-run, scale, Monte-Carlo).
    pub uncertainty: f64,
    pub parts: [f64; 3],
    pub z: f64,
}

impl Residual {
    fn new(measured: f64, simulated: f64, parts: [f64; 3]) -> Self {
        let u = parts.iter().map(|p| if p.is_finite() { p * p } else { 0.0 }).sum::<f64>().sqrt();
        let residual = simulated - measured;
        let z = if u > 0.0 {
            residual / u
        } else if residual == 0.0 {
            0.0
        } else {
            f64::INFINITY.copysign(residual)
        };
        Residual { measured, simulated, residual, uncertainty: u, parts, z }
    }
    pub fn flagged(&self) -> bool {
        self.z.abs() > Z_FLAG
    }
}

/// Where the gap lies in one condition (baseline fitted on all runs).
#[derive(Clone, Debug)]
pub struct WhereCondition {
    /// Teeth shown (1-based count; the lost bin comes after them in `teeth_residuals`).
    pub shown_teeth: usize,
    /// Per shown tooth, then the lost bin: residuals in percentage points.
    pub teeth_residuals: Vec<Residual>,
    pub centre: Residual,
    pub dispersion: Residual,
    /// Per shown tooth: % of launched particles resting in the tooth of their first impact.
    pub first_flight: Vec<f64>,
    /// Per shown tooth: % of launched particles moved there from another tooth by bounces.
    pub bounce_chain: Vec<f64>,
    pub lost_percent: f64,
    /// Where the grains of each third of the fill (by launch depth) end up.
    pub launch_depth: Vec<DepthLayer>,
    pub measured_summary: MeasuredSummary,
}

/// Split the particles into top, middle and bottom thirds of the fill by launch depth and
/// count where each third ends (`end_teeth`: 1-based resting tooth, None when lost).
fn depth_layers(depths_m: &[f64], end_teeth: &[Option<usize>], shown: usize) -> Vec<DepthLayer> {
    let mut order: Vec<usize> = (0..depths_m.len()).collect();
    order.sort_by(|a, b| depths_m[*a].total_cmp(&depths_m[*b]).then(a.cmp(b)));
    let n = order.len();
    ["top third", "middle third", "bottom third"]
        .iter()
        .enumerate()
        .filter_map(|(k, label)| {
            let part = &order[k * n / 3..(k + 1) * n / 3];
            if part.is_empty() {
                return None;
            }
            let mut counts = vec![0usize; shown];
            for i in part {
                if let Some(t) = end_teeth[*i].filter(|t| *t <= shown) {
                    counts[t - 1] += 1;
                }
            }
            let m = part.len() as f64;
            let teeth_percent: Vec<f64> = counts.iter().map(|c| 100.0 * *c as f64 / m).collect();
            Some(DepthLayer {
                label,
                depth_mm: [1e3 * depths_m[part[0]], 1e3 * depths_m[part[part.len() - 1]]],
                particles: part.len(),
                further_or_lost_percent: 100.0 - teeth_percent.iter().sum::<f64>(),
                teeth_percent,
            })
        })
        .collect()
}

/// Per condition "before/after" numbers of the gap section.
#[derive(Clone, Debug)]
pub struct GapCondition {
    pub measured: Vec<f64>,
    pub before: Vec<f64>,
    pub after: Vec<f64>,
    /// Bootstrap intervals (runs resampled) of the residuals before/after, percentage points.
    pub before_interval: Vec<[f64; 2]>,
    pub after_interval: Vec<[f64; 2]>,
    /// (E_x, σ_x): measured, before, after; intervals of the measured values.
    pub centre: [f64; 3],
    pub dispersion: [f64; 3],
    pub centre_interval: [f64; 2],
    pub dispersion_interval: [f64; 2],
}

/// Where the baseline misses and how far the top-ranked effect goes, every condition.
#[derive(Clone, Debug)]
pub struct Located {
    pub where_: Vec<WhereCondition>,
    pub gap: Vec<GapCondition>,
}

impl Located {
    /// Teeth shown per condition.
    pub fn shown(&self) -> Vec<usize> {
        self.where_.iter().map(|w| w.shown_teeth).collect()
    }
    /// Where each third of the fill comes to rest, per condition.
    pub fn layers(&self) -> Vec<Vec<DepthLayer>> {
        self.where_.iter().map(|w| w.launch_depth.clone()).collect()
    }
}

/// The "where" and "how far" stage: the baseline's residuals in every condition (its
/// particles' end states simulated once more, by the cpu engine) and the top-ranked effect's
/// bins against them.
pub fn locate(run: &Run, baseline_space: &Space, ranked: &Ranked) -> anyhow::Result<Located> {
    let baseline = &ranked.baseline;
    let top = ranked.ranking.first().context("no effect ranked")?;
    let particles = run.particles();
    let (mut where_, mut gap) = (Vec::new(), Vec::new());
    for (c, cond) in run.conditions().iter().enumerate() {
        let mut s = baseline_space.scenario_at(cond, &baseline.full.x);
        s.sim.particles = particles;
        s.sim.seed = run.seed;
        where_.push(where_condition(cond, &s, &baseline.full.bins[c], particles)?);
        gap.push(gap_condition(cond, &baseline.full.bins[c], &top.full.bins[c], run.bootstrap, run.seed));
    }
    Ok(Located { where_, gap })
}

/// Where the baseline misses, in one condition.
fn where_condition(
    cond: &Condition,
    scenario: &Scenario,
    bins: &[f64],
    particles: u32,
) -> anyhow::Result<WhereCondition> {
    let teeth = cond.teeth();
    let runs = &cond.runs;
    let n = runs.runs.len() as f64;
    // the measured bins as the fits compare them (fractions of the loaded or recovered mass)
    let measured = cond.target_all().bins;
    let summary = cond.summary();
    let mean_recovered = runs.runs.iter().map(|r| r.recovered_g()).sum::<f64>() / n;
    let scale = 100.0 * cond.resolution_g / 12f64.sqrt() / mean_recovered;
    let np = particles.max(1) as f64;
    let last_sim = bins[..teeth].iter().rposition(|p| *p >= 0.005).map_or(0, |i| i + 1);
    let shown = runs.teeth.max(last_sim).clamp(1, teeth);
    let mut teeth_residuals = Vec::with_capacity(shown + 1);
    for j in (0..shown).chain(std::iter::once(teeth)) {
        let sd = summary.sd[j];
        let run_part = if sd.is_finite() { 100.0 * sd / n.sqrt() } else { 0.0 };
        let p = bins[j];
        let mc = 100.0 * (p * (1.0 - p) / np).max(0.0).sqrt();
        teeth_residuals.push(Residual::new(100.0 * measured[j], 100.0 * p, [run_part, scale, mc]));
    }
    // centre of mass and dispersion
    let per_run: Vec<(f64, f64)> = runs.fractions().iter().map(|f| centre_and_dispersion(f)).collect();
    let (mex, msx) = runs.centre_and_dispersion();
    let (sex, ssx) = centre_and_dispersion(&bins[..teeth]);
    let kept = (1.0 - bins[teeth]).max(1.0 / np) * np;
    let m4: f64 = {
        let total: f64 = bins[..teeth].iter().sum();
        if total > 0.0 {
            bins[..teeth].iter().enumerate().map(|(j, p)| p / total * ((j + 1) as f64 - sex).powi(4)).sum()
        } else {
            f64::NAN
        }
    };
    let mc_ex = ssx / kept.sqrt();
    let mc_sx = if ssx > 0.0 { ((m4 - ssx.powi(4)).max(0.0) / (4.0 * ssx * ssx * kept)).sqrt() } else { 0.0 };
    let sd_ex = sample_sd(&per_run.iter().map(|p| p.0).collect::<Vec<_>>()) / n.sqrt();
    let sd_sx = sample_sd(&per_run.iter().map(|p| p.1).collect::<Vec<_>>()) / n.sqrt();
    let centre = Residual::new(mex, sex, [sd_ex, 0.0, mc_ex]);
    let dispersion = Residual::new(msx, ssx, [sd_sx, 0.0, mc_sx]);
    // first flight vs bounce chain, with the cpu engine's particle end states
    let cpu = particle_engine(EngineKind::Cpu);
    let det = evaluate_detailed(&cpu, scenario, &cond.design, false)
        .map_err(|e| anyhow::anyhow!("{}: the fitted setup cannot be simulated ({}): {e}", cond.setup, e.rule()))?;
    let profile = &det.prepared.profile;
    let (mut first, mut chain, mut lost) = (vec![0usize; teeth], vec![0usize; teeth], 0usize);
    let mut end_teeth = vec![None; det.particles.len()];
    for (i, p) in det.particles.iter().enumerate() {
        if p.state == ParticleState::Lost {
            lost += 1;
            continue;
        }
        let end = end_tooth(profile, p.end) as usize;
        end_teeth[i] = Some(end);
        let start = p.first_impact.map(|fi| end_tooth(profile, fi) as usize);
        if start == Some(end) {
            first[end - 1] += 1;
        } else {
            chain[end - 1] += 1;
        }
    }
    let total = det.particles.len().max(1) as f64;
    // particle i starts from launch point i (engine::cpu)
    let depths: Vec<f64> = det.prepared.launches.iter().map(|l| det.prepared.fill.depth(*l)).collect();
    let launch_depth = depth_layers(&depths, &end_teeth, shown);
    Ok(WhereCondition {
        shown_teeth: shown,
        teeth_residuals,
        centre,
        dispersion,
        first_flight: first[..shown].iter().map(|c| 100.0 * *c as f64 / total).collect(),
        bounce_chain: chain[..shown].iter().map(|c| 100.0 * *c as f64 / total).collect(),
        lost_percent: 100.0 * lost as f64 / total,
        launch_depth,
        measured_summary: summary,
    })
}

/// Before/after per condition with bootstrap intervals over the condition's runs.
fn gap_condition(cond: &Condition, before: &[f64], after: &[f64], replicates: usize, seed: u64) -> GapCondition {
    let teeth = cond.teeth();
    let n = cond.runs.runs.len();
    let all: Vec<usize> = (0..n).collect();
    let measured = cond.target(&all).bins;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6A9_0001);
    let mut reps: Vec<Vec<f64>> = Vec::with_capacity(replicates);
    for _ in 0..replicates.max(1) {
        let idx: Vec<usize> = (0..n).map(|_| rng.random_range(0..n)).collect();
        reps.push(cond.target(&idx).bins);
    }
    let iv = |sim: &[f64]| -> Vec<[f64; 2]> {
        (0..=teeth).map(|j| interval(&reps.iter().map(|r| 100.0 * (sim[j] - r[j])).collect::<Vec<_>>())).collect()
    };
    let ce = |b: &[f64]| centre_and_dispersion(&b[..teeth]);
    let (m, b, a) = (ce(&measured), ce(before), ce(after));
    let metric: Vec<(f64, f64)> = reps.iter().map(|r| ce(r)).collect();
    GapCondition {
        before_interval: iv(before),
        after_interval: iv(after),
        centre: [m.0, b.0, a.0],
        dispersion: [m.1, b.1, a.1],
        centre_interval: interval(&metric.iter().map(|x| x.0).collect::<Vec<_>>()),
        dispersion_interval: interval(&metric.iter().map(|x| x.1).collect::<Vec<_>>()),
        measured,
        before: before.to_vec(),
        after: after.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_layers_split_by_depth_and_count_each_third() {
        // six particles, shuffled depths; the deepest two end in tooth 1, the shallowest in
        // tooth 2 and beyond the shown teeth, the middle ones in tooth 2 and lost
        let depths = [0.003, 0.0001, 0.002, 0.0025, 0.001, 0.0002];
        let ends = [Some(1), Some(2), None, Some(1), Some(2), Some(5)];
        let l = depth_layers(&depths, &ends, 3);
        assert_eq!(l.len(), 3);
        assert_eq!(l.iter().map(|x| x.particles).sum::<usize>(), 6);
        assert_eq!(l[0].depth_mm, [0.1, 0.2]);
        assert_eq!(l[0].teeth_percent, vec![0.0, 50.0, 0.0]);
        assert_eq!(l[0].further_or_lost_percent, 50.0);
        assert_eq!(l[1].depth_mm, [1.0, 2.0]);
        assert_eq!(l[1].teeth_percent, vec![0.0, 50.0, 0.0]);
        assert_eq!(l[2].depth_mm, [2.5, 3.0]);
        assert_eq!(l[2].teeth_percent, vec![100.0, 0.0, 0.0]);
        assert_eq!(l[2].further_or_lost_percent, 0.0);
        // fewer particles than layers: empty thirds are left out, nothing is lost
        let l = depth_layers(&[0.001], &[Some(1)], 3);
        assert_eq!(l.len(), 1);
        assert_eq!(l[0].teeth_percent, vec![100.0, 0.0, 0.0]);
    }
}
