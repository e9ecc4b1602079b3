//! The candidates' stage of a diagnosis: every candidate effect fitted beside the others in
//! lockstep (the sled-motion candidate from the motion screen's point where there was one),
//! every model re-scored on fresh streams and bootstrapped, a second re-scoring where
//! `best` hinges on the simulation's noise, and the ranking: `best` and the effects the
//! data cannot tell from the top-ranked one ([`Ranked`]).

use anyhow::Context as _;

use super::baseline::Baseline;
use super::model_result::{model_name, ModelResult};
use super::motion_screen::{halton_point, MotionStart};
use super::profile::{profile_starts, PROFILE_AT};
use super::run::Run;
use super::scoring::{bootstrap_gaps, new_result, paired_interval, paired_sd, rescore};
use super::verdict;
use crate::calibrate::{Condition, Model, Search, Space};
use crate::model::effects::EffectKind;

/// The ranking rule, as diagnosis.json states it.
pub const RANKING_RULE: &str = "score = gap + 2 x (extra parameters) x bootstrap SE of the gap";

/// The smallest share of the baseline's gap that `best` must remove.
pub const MIN_REDUCTION: f64 = 0.25;

/// The second rescore's stream count, as a multiple of `--rescore-streams`, and at most
/// this many streams (a user who asked for that many already has a precise re-scoring).
pub const SECOND_RESCORE_FACTOR: usize = 4;
pub const SECOND_RESCORE_MAX_STREAMS: usize = 64;

/// The candidates fitted, re-scored and ranked.
#[derive(Clone, Debug)]
pub struct Ranked {
    /// The baseline re-scored like the candidates (its improvement interval is [0, 0]).
    pub baseline: ModelResult,
    /// Every candidate, best penalised score first, with its paired improvement over the
    /// baseline.
    pub ranking: Vec<ModelResult>,
    /// The top-ranked effect where it beats the baseline beyond the uncertainty and by a
    /// material share, and the baseline is well above its floor (before the verdict, which
    /// may demote it).
    pub best: Option<EffectKind>,
    /// The effects not worse than the top-ranked one beyond the paired uncertainty, the top
    /// one first; empty when no other is.
    pub indistinguishable: Vec<EffectKind>,
    /// The fresh streams every model was finally re-scored on.
    pub streams: usize,
    /// What the stage did that the report must say (a second rescore).
    pub notes: Vec<String>,
}

/// Starts for an effect's fit: the baseline's optimum with the effect switched off (when
/// the effect has a neutral setting), and `extra` points that keep the baseline's shared
/// parameters and spread the effect's own over their box (a Halton sequence, bases 2, 3, 5):
/// the shared parameters usually move little when an effect is switched on, so these seed
/// the screen near the answer in the dimensions it knows least.
fn effect_starts(space: &Space, base_names: &[&'static str], base_x: &[f64], extra: usize) -> Vec<Vec<f64>> {
    let mut starts: Vec<Vec<f64>> = space.start_from(base_names, base_x).into_iter().collect();
    let shared: Vec<f64> = space
        .names()
        .iter()
        .take(space.shared.len())
        .map(|n| base_names.iter().position(|m| m == n).map(|p| base_x[p]))
        .collect::<Option<Vec<f64>>>()
        .unwrap_or_default();
    if shared.len() != space.shared.len() {
        return starts;
    }
    let bounds = space.bounds();
    for i in 1..=extra {
        starts.push([shared.clone(), halton_point(i, &bounds[space.shared.len()..])].concat());
    }
    starts
}

/// The random stream of a single candidate's fit: its place in [`EffectKind::ALL`] (where
/// it stood in the batch when every candidate was tried, so a full diagnosis fits as it
/// did when the streams followed the batch). The baseline, fitted alone, is on 0.
fn candidate_stream(effects: &[EffectKind]) -> u64 {
    match effects {
        [e] => EffectKind::ALL.iter().position(|k| k == e).expect("every effect is in ALL") as u64,
        _ => 0,
    }
}

/// Whether `best` hinges on the simulation's noise: the top-ranked effect (by score, of
/// `models[1..]`; `models[0]` is the baseline) passes every other test for `best` — the
/// baseline well above its floor, a reduction of at least [`MIN_REDUCTION`] — but its paired
/// improvement interval over the baseline holds 0. Then more fresh streams narrow what the
/// simulation adds to that interval (it cannot narrow the runs' part); without them an
/// effect at the edge is named or not by which streams were drawn (300 µm quadratic drag:
/// [0.6, 12.6] %² at 6000 particles, [−0.7, 8.5] at 12 000 with one stream per replicate).
/// Returns the words for the notes, naming the interval and its simulation share.
fn best_hinges_on_streams(conds: &[Condition], models: &[ModelResult], particles: u32) -> Option<String> {
    let (baseline, effects) = models.split_first()?;
    let top = effects.iter().min_by(|a, b| a.score.total_cmp(&b.score).then(a.gap.total_cmp(&b.gap)))?;
    let iv = paired_interval(baseline, top);
    let open = iv[0] <= 0.0 && top.gap < baseline.gap;
    let material = top.gap <= (1.0 - MIN_REDUCTION) * baseline.gap;
    if !(open && material && verdict::judge(conds, baseline, particles).well_above()) {
        return None;
    }
    let sd = paired_sd(baseline, top);
    Some(format!(
        "`{}`'s paired improvement over the baseline held 0 on {} fresh streams ([{:.2}, {:.2}] %², sd {:.2}: the \
         runs alone {:.2}, the simulation alone {:.2})",
        top.name(),
        top.fresh.len(),
        iv[0],
        iv[1],
        sd[0],
        sd[1],
        sd[2]
    ))
}

/// Fit every candidate in lockstep, re-score the baseline and the candidates on fresh
/// streams, bootstrap their gaps and rank them.
pub fn rank_candidates(
    run: &Run,
    baseline: Baseline,
    screened: Option<MotionStart>,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Ranked> {
    let conditions = run.conditions();
    let particles = run.particles();
    let baseline_dim = baseline.space.dim();
    let mut spaces: Vec<Space> =
        run.effects.iter().map(|e| Space::new(run.shared.clone(), &[*e], conditions)).collect();
    // a return direction the setups leave out is the one the motion screen chose
    let mut direction_note = None;
    if let Some(d) = screened.as_ref().and_then(|s| s.direction) {
        for sp in spaces.iter_mut().filter(|sp| sp.effects == [EffectKind::SledMotion]) {
            *sp = sp.with_motion_direction(d);
        }
        direction_note = Some(format!(
            "sled-motion: the setups leave the return direction out; the motion screen chose `{}` (both screened)",
            d.name()
        ));
    }
    let base_names = baseline.space.names();
    // Each candidate draws its differential evolution from the stream of its place in the
    // list of every candidate (`EffectKind::ALL`), not in this run's batch: a candidate's fit
    // is the same whichever others are tried with it (vacuum leaves the drag candidates
    // out, `--effects` picks some), and the motion screen can take the sled-motion
    // candidate's evolution over without moving anyone else's.
    let mut models: Vec<Model> = spaces
        .iter()
        .map(|sp| Model {
            space: sp,
            targets: &run.targets,
            starts: effect_starts(sp, &base_names, &baseline.fit.x, run.solver.pop / 2),
            search: Search::Global { stream: candidate_stream(&sp.effects) },
        })
        .collect();
    // an unstated motion is searched by the motion screen, which replaces the candidate's
    // differential evolution: its fit polishes from the screen's point and the baseline's,
    // beside the others' polish
    let mut from_screen = None;
    if let (Some(i), Some(found)) = (models.iter().position(|m| m.space.effects == [EffectKind::SledMotion]), screened)
    {
        let m = &mut models[i];
        m.starts = std::iter::once(found.x).chain(m.starts.drain(..).take(1)).collect();
        m.search = Search::FromStarts;
        from_screen = Some((i, found.evaluations));
        log("diagnose: sled-motion: its fit polishes from the motion screen's point and the baseline's".to_string());
    }
    // the evolution of every candidate in lockstep, then the polish of all from the best
    // member and the first start (the baseline's optimum with the effect off, so that a nested
    // candidate is never polished from worse than the baseline); the other starts only seeded
    // the evolution, and re-scoring each at the full budget would cost a tenth of a diagnosis
    let screened = run.solver.screen(&run.sim, &models, log)?;
    // and from each candidate's profile starts: its strength held across its box while the
    // shared parameters leave the baseline's basin (`profile`)
    let profiles = profile_starts(&run.solver, &run.sim, &spaces, &run.targets, &base_names, &baseline.fit.x)?;
    log(format!(
        "diagnose: profile starts: each candidate's strength held at {} of its box, the shared parameters polished \
         ({} simulations of the conditions)",
        PROFILE_AT.iter().map(|s| format!("{s:.2}")).collect::<Vec<_>>().join(" and "),
        profiles.iter().map(|p| p.1).sum::<u64>()
    ));
    let polished: Vec<Model> = models
        .iter()
        .zip(&screened)
        .zip(&profiles)
        .map(|((m, sc), profile)| {
            let starts = match m.search {
                Search::FromStarts => m.starts.clone(),
                Search::Global { .. } => sc
                    .members
                    .first()
                    .map(|b| b.0.clone())
                    .into_iter()
                    .chain(m.starts.iter().take(1).cloned())
                    .chain(profile.0.iter().cloned())
                    .collect(),
            };
            Model { space: m.space, targets: m.targets, starts, search: Search::FromStarts }
        })
        .collect();
    let mut fits = run.solver.polish(&run.sim, &polished, log)?;
    for ((f, sc), profile) in fits.iter_mut().zip(&screened).zip(&profiles) {
        f.evaluations += sc.evaluations;
        f.evaluations += profile.1;
    }
    if let Some((i, evaluations)) = from_screen {
        fits[i].evaluations += evaluations;
    }
    let mut all: Vec<ModelResult> = vec![new_result(&baseline.space, baseline.fit, baseline_dim)];
    for (sp, f) in spaces.iter().zip(fits) {
        log(format!("diagnose: {}: SSE {:.1} %² (fit streams)", model_name(&sp.effects), f.value));
        all.push(new_result(sp, f, baseline_dim));
    }
    let all_spaces: Vec<&Space> = std::iter::once(&baseline.space).chain(spaces.iter()).collect();
    rescore(&run.sim, &all_spaces, &mut all, particles, run.rescore_streams, run.seed);
    bootstrap_gaps(conditions, &mut all, run.bootstrap, run.seed);
    // an adaptive second rescore: where `best` hinges on an interval that the simulation's
    // noise widens, every model gets more streams (all of them, so that every paired
    // comparison keeps its common random numbers), and everything after is on those
    let mut notes: Vec<String> = direction_note.into_iter().collect();
    let mut streams = run.rescore_streams;
    let more = (SECOND_RESCORE_FACTOR * streams).min(SECOND_RESCORE_MAX_STREAMS);
    if let Some(why) = best_hinges_on_streams(conditions, &all, particles).filter(|_| more > streams) {
        streams = more;
        log(format!("diagnose: {why}; every model re-scored on {streams} streams"));
        notes.push(format!(
            "second rescore: {why}; every model was re-scored on {streams} fresh streams (common random numbers), \
             and the gaps, intervals, ranking and verdict are those of the {streams}"
        ));
        rescore(&run.sim, &all_spaces, &mut all, particles, streams, run.seed);
        bootstrap_gaps(conditions, &mut all, run.bootstrap, run.seed);
    }
    for m in &all {
        log(format!(
            "diagnose: {}: gap {:.1} %² on fresh streams, interval [{:.1}, {:.1}]",
            m.name(),
            m.gap,
            m.interval[0],
            m.interval[1]
        ));
    }
    let mut models = all.into_iter();
    let mut baseline = models.next().context("no baseline")?;
    baseline.improvement_interval = [0.0, 0.0];
    let mut ranking: Vec<ModelResult> = models.collect();
    for m in ranking.iter_mut() {
        m.improvement_interval = paired_interval(&baseline, m);
        m.improvement_sd = paired_sd(&baseline, m);
        log(format!(
            "diagnose: {}: improvement over the baseline [{:.2}, {:.2}] %², sd {:.2} (the runs alone {:.2}, the \
             simulation alone {:.2})",
            m.name(),
            m.improvement_interval[0],
            m.improvement_interval[1],
            m.improvement_sd[0],
            m.improvement_sd[1],
            m.improvement_sd[2]
        ));
    }
    ranking.sort_by(|a, b| a.score.total_cmp(&b.score).then(a.gap.total_cmp(&b.gap)));
    let top = ranking.first().context("no effect ranked")?;
    // paired comparisons throughout: every replicate resamples the same runs for all models,
    // so the runs' common scatter (which moves every model's gap alike) cancels
    // a baseline within its noise floor leaves nothing for an effect to explain: an extra
    // parameter still buys a little of the runs' own scatter, which is no finding
    let gap_to_explain = verdict::judge(conditions, &baseline, particles).well_above();
    let best = (gap_to_explain && top.improvement_interval[0] > 0.0 && top.gap <= (1.0 - MIN_REDUCTION) * baseline.gap)
        .then_some(top.single())
        .flatten();
    let others: Vec<EffectKind> =
        ranking[1..].iter().filter(|m| paired_interval(m, top)[0] <= 0.0).filter_map(|m| m.single()).collect();
    let indistinguishable =
        if others.is_empty() { Vec::new() } else { std::iter::once(top.single()).flatten().chain(others).collect() };
    Ok(Ranked { baseline, ranking, best, indistinguishable, streams, notes })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::Fit;

    /// A fitted model as the ranking sees it: its fresh streams' bins (one stream), gap,
    /// score and paired bootstrap replicates.
    fn ranked(effects: &[EffectKind], bins: Vec<f64>, gap: f64, replicates: Vec<f64>) -> ModelResult {
        let fit = Fit { x: Vec::new(), value: gap, bins: vec![bins.clone()], evaluations: 0, archive: Vec::new() };
        let mut m = new_result(&Space::new(Vec::new(), effects, &[]), fit, 0);
        m.fresh = vec![vec![bins]];
        m.gap = gap;
        m.score = gap;
        m.replicates_runs = replicates.clone();
        m.replicates_streams = replicates.clone();
        m.replicates = replicates;
        m
    }

    /// The second rescore runs only where `best` waits on nothing but an improvement
    /// interval that holds 0: the baseline well above its floor, the top effect removing
    /// at least a quarter of its gap.
    #[test]
    fn more_streams_only_where_best_hinges_on_an_interval_holding_zero() {
        let conds = vec![crate::calibrate::condition::test3()];
        let measured = conds[0].target_all().bins;
        // the baseline moves 10 pp of the modal tooth's mass one tooth on: far above the floor
        let modal = (0..measured.len() - 1).max_by(|a, b| measured[*a].total_cmp(&measured[*b])).unwrap();
        let mut off = measured.clone();
        off[modal] -= 0.10;
        off[modal + 1] += 0.10;
        let base = |reps: Vec<f64>| ranked(&[], off.clone(), 200.0, reps);
        let top = |gap: f64, reps: Vec<f64>| ranked(&[EffectKind::ImpactScatter], measured.clone(), gap, reps);
        // the improvement's replicates straddle 0
        let open = [base(vec![10.0, 20.0, 30.0, 40.0]), top(50.0, vec![30.0, 10.0, 35.0, 20.0])];
        let why = best_hinges_on_streams(&conds, &open, 12_000).expect("hinges");
        assert!(
            why.starts_with("`impact-scatter`'s paired improvement over the baseline held 0 on 1 fresh streams"),
            "{why}"
        );
        // beyond the uncertainty: nothing to re-score
        let clear = [base(vec![10.0, 20.0, 30.0, 40.0]), top(50.0, vec![5.0, 10.0, 15.0, 20.0])];
        assert_eq!(best_hinges_on_streams(&conds, &clear, 12_000), None);
        // a reduction under a quarter: `best` is refused whatever the interval says
        let small = [base(vec![10.0, 20.0, 30.0, 40.0]), top(170.0, vec![30.0, 10.0, 35.0, 20.0])];
        assert_eq!(best_hinges_on_streams(&conds, &small, 12_000), None);
        // a baseline within its floor needs no cause
        let quiet = [
            ranked(&[], measured.clone(), 200.0, vec![10.0, 20.0, 30.0, 40.0]),
            top(50.0, vec![30.0, 10.0, 35.0, 20.0]),
        ];
        assert_eq!(best_hinges_on_streams(&conds, &quiet, 12_000), None);
    }
}
