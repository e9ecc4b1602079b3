//! The next measurement (issue 46, item 3; `diagnose --suggest`): where the data leave
//! candidates that cannot be told apart (an indistinguishable set, a partial or no
//! explanation, or no gap at all), which additional condition would separate them.
//!
//! Each proposal is one condition of the campaign with one thing changed — the launch speed
//! v0 or the acceleration a over the optimiser's bounds, the conveyor's slope α over Table
//! 2.2's 0-40°, or as many runs again of the condition as it is — and every remaining model
//! is simulated there from its own fit (common random numbers). Its **expected separation**
//! for two models is the SSE between their predicted bins (%², the measurement's bins, the
//! handling loss allowed) over the noise floor such a condition would have: the base
//! condition's run-to-run scatter per bin, scaled to the predicted bins as binomial-like
//! (k·p(1−p)/runs, k fitted to the base condition's runs), the scale's quantisation and the
//! fresh streams' Monte-Carlo variance — the verdict's "gap over floor" for the difference
//! of the two. A proposal separates a pair where it exceeds [`FLOOR_FACTOR`]; proposals are
//! ranked by their worst pair (every remaining pair separated, the hardest one first).
//!
//! What it does not do: refit the models with the new condition. A joint refit can move the
//! shared parameters to make two models agree a little better there, so the separation is an
//! upper bound of what the new data would show; the check in tests/diagnose_beyond.rs
//! measures it on a campaign.

use super::candidates::Ranked;
use super::limits::DetectionLimits;
use super::run::Run;
use super::verdict::{self, Verdict, VerdictKind, FLOOR_FACTOR};
use crate::calibrate::{Condition, Simulator, Space};
use crate::model::design::{LOWER_BOUND_CLI, UPPER_BOUND_CLI};

/// Values tried per changed variable (evenly over its range).
const GRID_POINTS: usize = 5;
/// Table 2.2's slope range, degrees.
pub const SLOPE_RANGE_DEG: (f64, f64) = (0.0, 40.0);
/// The smallest noise floor a separation is measured against, %².
pub const MIN_FLOOR: f64 = 1e-6;
/// At most this many ranked candidates are separated when no indistinguishable set says which.
const TOP_CANDIDATES: usize = 3;

/// What a proposal changes in its base condition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    V0(f64),
    Acceleration(f64),
    Slope(f64),
    /// As many runs again of the base condition as it has.
    MoreRuns(usize),
}

impl Change {
    pub fn label(&self) -> String {
        match self {
            Change::V0(v) => format!("v0 {v:.2} m/s"),
            Change::Acceleration(a) => format!("a {a:.0} m/s²"),
            Change::Slope(s) => format!("α {s:.0}°"),
            Change::MoreRuns(n) => format!("{n} more runs"),
        }
    }
    /// The variable's name and value as diagnosis.json writes them.
    pub fn field(&self) -> (&'static str, f64) {
        match self {
            Change::V0(v) => ("v0_m_s", *v),
            Change::Acceleration(a) => ("a_m_s2", *a),
            Change::Slope(s) => ("alpha_deg", *s),
            Change::MoreRuns(n) => ("runs", *n as f64),
        }
    }
}

/// Two remaining models' expected separation at one proposal.
#[derive(Clone, Debug)]
pub struct Separation {
    pub a: String,
    pub b: String,
    /// SSE between the two predictions (loss-adjusted), %².
    pub sse: f64,
    /// The proposal's noise floor, %².
    pub floor: f64,
}

impl Separation {
    /// The SSE over the floor; 0 where the two predictions agree, and against a floor of at
    /// least [`MIN_FLOOR`] (a condition whose every grain lands in one bin scatters nothing,
    /// and 0/0 or x/0 would rank nothing).
    pub fn ratio(&self) -> f64 {
        if self.sse > 0.0 {
            self.sse / self.floor.max(MIN_FLOOR)
        } else {
            0.0
        }
    }
}

/// One proposed condition and what it would separate.
#[derive(Clone, Debug)]
pub struct Proposal {
    /// The condition it changes.
    pub base: String,
    pub change: Change,
    /// Every pair of remaining models.
    pub pairs: Vec<Separation>,
}

impl Proposal {
    /// The worst pair's separation, × its floor.
    pub fn worst(&self) -> f64 {
        self.pairs.iter().map(Separation::ratio).fold(f64::INFINITY, f64::min)
    }
    pub fn separates(&self) -> bool {
        self.worst() > FLOOR_FACTOR
    }
}

/// The suggestions: the models to separate, why those, and the proposals, best first.
#[derive(Clone, Debug)]
pub struct Suggestions {
    pub models: Vec<String>,
    pub why: String,
    pub proposals: Vec<Proposal>,
    /// The separation every pair has already in the campaign's own conditions (the sum of
    /// the conditions' ratios), for comparison.
    pub current: Vec<Separation>,
}

/// A model to simulate: its name, space and point.
struct Remaining {
    name: String,
    space: Space,
    x: Vec<f64>,
}

/// The models left to separate: the indistinguishable set; else, where the verdict leaves
/// the cause open (`partly-explained`, `unexplained`, `undecided`), the top-ranked
/// candidates; for `no-gap`, the baseline against every candidate at its detection limit
/// (which condition would show an effect the data cannot yet resolve). None when `best`
/// stands alone and explains the gap.
fn remaining(
    run: &Run,
    ranked: &Ranked,
    verdict: &Verdict,
    limits: Option<&DetectionLimits>,
) -> Option<(Vec<Remaining>, String)> {
    let conditions = run.conditions();
    let fitted = |effects: &[crate::model::effects::EffectKind], x: &[f64], name: String| Remaining {
        name,
        space: Space::new(run.shared.clone(), effects, conditions),
        x: x.to_vec(),
    };
    if ranked.indistinguishable.len() >= 2 {
        let models = ranked
            .indistinguishable
            .iter()
            .filter_map(|e| ranked.ranking.iter().find(|m| m.single() == Some(*e)))
            .map(|m| fitted(&m.effects, &m.full.x, m.name()))
            .collect();
        return Some((models, "the candidates the data cannot tell apart (indistinguishable)".into()));
    }
    match verdict.kind {
        VerdictKind::NoGap => {
            let limits = limits?;
            let base = &ranked.baseline;
            let mut models = vec![fitted(&[], &base.full.x, "baseline".into())];
            for l in limits.limits.iter() {
                let Some(s) = l.limit else { continue };
                let space = Space::new(run.shared.clone(), &[l.effect], conditions);
                let x: Vec<f64> = space
                    .names()
                    .iter()
                    .map(|n| {
                        if *n == l.param {
                            s
                        } else if let Some((_, v)) = l.held.iter().find(|(m, _)| m == n) {
                            *v
                        } else {
                            base.names.iter().position(|m| m == n).map_or(f64::NAN, |p| base.full.x[p])
                        }
                    })
                    .collect();
                if x.iter().all(|v| v.is_finite()) {
                    models.push(Remaining {
                        name: format!("{} {} {}", l.effect.name(), l.param, super::limits::sig3(s)),
                        space,
                        x,
                    });
                }
            }
            (models.len() >= 2).then(|| (models, "the baseline against each candidate at its detection limit".into()))
        }
        VerdictKind::Explained => None,
        _ => {
            let models: Vec<Remaining> =
                ranked.ranking.iter().take(TOP_CANDIDATES).map(|m| fitted(&m.effects, &m.full.x, m.name())).collect();
            let why = format!("the {} top-ranked candidates (the verdict leaves the cause open)", models.len());
            (models.len() >= 2).then_some((models, why))
        }
    }
}

/// The proposals: each condition with one variable moved over its range (its own value left
/// out) or its runs doubled.
fn proposals(conditions: &[Condition]) -> Vec<(usize, Change)> {
    let grid = |lo: f64, hi: f64| (0..GRID_POINTS).map(move |k| lo + (hi - lo) * k as f64 / (GRID_POINTS - 1) as f64);
    let mut out = Vec::new();
    for (i, c) in conditions.iter().enumerate() {
        let differs = |a: f64, b: f64| (a - b).abs() > 1e-9 * b.abs().max(1.0);
        out.extend(
            grid(LOWER_BOUND_CLI[6], UPPER_BOUND_CLI[6])
                .filter(|v| differs(*v, c.design.v0))
                .map(|v| (i, Change::V0(v))),
        );
        out.extend(
            grid(LOWER_BOUND_CLI[7], UPPER_BOUND_CLI[7])
                .filter(|v| differs(*v, c.design.a))
                .map(|v| (i, Change::Acceleration(v))),
        );
        out.extend(
            grid(SLOPE_RANGE_DEG.0, SLOPE_RANGE_DEG.1)
                .filter(|v| differs(*v, c.base.environment.alpha_deg))
                .map(|v| (i, Change::Slope(v))),
        );
        out.push((i, Change::MoreRuns(c.runs.runs.len())));
    }
    out
}

/// The base condition with the change made (more runs change nothing simulated).
fn changed(c: &Condition, change: Change) -> Condition {
    let mut c = c.clone();
    match change {
        Change::V0(v) => c.design.v0 = v,
        Change::Acceleration(a) => c.design.a = a,
        Change::Slope(s) => c.base.environment.alpha_deg = s,
        Change::MoreRuns(_) => {}
    }
    c
}

/// The noise floor (%²) of a condition like `c` whose bins are `bins`: `c`'s run-to-run
/// variance per bin scaled as k·p(1−p) (k from `c`'s own runs and means), over its runs, with
/// the scale's quantisation and the Monte-Carlo variance of `draws` simulated particles.
fn floor_like(c: &Condition, bins: &[f64], draws: f64) -> f64 {
    let measured = c.target_all().bins;
    let var = c.mean_variance();
    let runs = c.runs.runs.len().max(1) as f64;
    let binomial: f64 = measured.iter().map(|p| p * (1.0 - p)).sum();
    let k = if binomial > 0.0 { var.iter().sum::<f64>() * runs / binomial } else { 0.0 };
    1e4 * bins.iter().map(|p| (p * (1.0 - p)).max(0.0) * (k / runs + 1.0 / draws)).sum::<f64>()
}

/// The SSE (%²) between two models' bins in a condition like `c`, after the handling loss
/// that brings the first closest to the second (a spill the data would not tell from either).
fn difference(c: &Condition, a: &[f64], b: &[f64]) -> f64 {
    verdict::loss_adjusted_sse(c, b, a)
}

/// `diagnose --suggest`: which additional condition would separate the models the diagnosis
/// leaves, simulated from each one's fit as one engine call.
pub fn suggest(
    run: &Run,
    ranked: &Ranked,
    verdict: &Verdict,
    limits: Option<&DetectionLimits>,
    log: &mut dyn FnMut(String),
) -> Option<Suggestions> {
    let started = std::time::Instant::now();
    let Some((models, why)) = remaining(run, ranked, verdict, limits) else {
        log("diagnose: suggest: nothing left to separate (`best` explains the gap alone)".to_string());
        return None;
    };
    let conditions = run.conditions();
    let plan = proposals(conditions);
    let proposed: Vec<Condition> = plan.iter().map(|(i, ch)| changed(&conditions[*i], *ch)).collect();
    let sim = Simulator { engine: run.sim.engine, conditions: &proposed };
    let points: Vec<(&Space, Vec<f64>)> = models.iter().map(|m| (&m.space, m.x.clone())).collect();
    let particles = run.particles();
    let draws = particles as f64 * run.rescore_streams.max(1) as f64;
    let bins = sim.simulate(&points, particles, run.seed ^ 0x5EC0_0D05);
    let pairs: Vec<(usize, usize)> =
        (0..models.len()).flat_map(|a| (a + 1..models.len()).map(move |b| (a, b))).collect();
    let mut out = Vec::with_capacity(plan.len());
    for (p, ((i, change), cond)) in plan.iter().zip(&proposed).enumerate() {
        let per_model: Option<Vec<&Vec<f64>>> = bins.iter().map(|b| b.as_ref().map(|b| &b[p])).collect();
        // a design the engine refuses (outside the rig's geometry) is no proposal
        let Some(per_model) = per_model else { continue };
        let separations = pairs
            .iter()
            .map(|(a, b)| {
                let mean: Vec<f64> = per_model[*a].iter().zip(per_model[*b]).map(|(x, y)| 0.5 * (x + y)).collect();
                Separation {
                    a: models[*a].name.clone(),
                    b: models[*b].name.clone(),
                    sse: difference(cond, per_model[*a], per_model[*b]),
                    floor: floor_like(&conditions[*i], &mean, draws),
                }
            })
            .collect();
        out.push(Proposal { base: conditions[*i].name.clone(), change: *change, pairs: separations });
    }
    out.sort_by(|a, b| b.worst().total_cmp(&a.worst()));
    // what the campaign's own conditions already separate: the same measure at the
    // conditions as they are (their "more runs" proposals hold their own predictions)
    let current = pairs
        .iter()
        .map(|(a, b)| {
            let (mut sse, mut floor) = (0.0, 0.0);
            for p in out.iter().filter(|p| matches!(p.change, Change::MoreRuns(_))) {
                if let Some(s) = p.pairs.iter().find(|s| s.a == models[*a].name && s.b == models[*b].name) {
                    sse += s.sse;
                    floor += s.floor;
                }
            }
            Separation { a: models[*a].name.clone(), b: models[*b].name.clone(), sse, floor }
        })
        .collect();
    log(format!(
        "diagnose: suggest: {} proposals for {} models ({} simulations, {:.1} s); best: {}",
        out.len(),
        models.len(),
        plan.len() * models.len(),
        started.elapsed().as_secs_f64(),
        out.first().map_or("none".to_string(), |p| format!(
            "{} {} ({:.1}× the floor)",
            p.base,
            p.change.label(),
            p.worst()
        ))
    ));
    Some(Suggestions { models: models.into_iter().map(|m| m.name).collect(), why, proposals: out, current })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_condition_gets_each_variable_over_its_range_and_more_runs() {
        let c = crate::calibrate::condition::test3();
        let p = proposals(std::slice::from_ref(&c));
        let count = |f: fn(&Change) -> bool| p.iter().filter(|(_, ch)| f(ch)).count();
        // five values each, the condition's own left out where it is one of them
        let own_v0 = (0..GRID_POINTS).any(|k| (0.8 + 0.3 * k as f64 - c.design.v0).abs() < 1e-9);
        assert_eq!(count(|c| matches!(c, Change::V0(_))), GRID_POINTS - usize::from(own_v0));
        assert!(count(|c| matches!(c, Change::Slope(_))) >= GRID_POINTS - 1);
        assert_eq!(count(|c| matches!(c, Change::MoreRuns(_))), 1);
        let slopes: Vec<f64> =
            p.iter().filter_map(|(_, ch)| if let Change::Slope(s) = ch { Some(*s) } else { None }).collect();
        assert!(slopes.iter().all(|s| (0.0..=40.0).contains(s)), "{slopes:?}");
        // a changed condition carries the change and nothing else
        let moved = changed(&c, Change::Slope(10.0));
        assert_eq!(moved.base.environment.alpha_deg, 10.0);
        assert_eq!(moved.design.v0, c.design.v0);
    }

    #[test]
    fn the_floor_of_a_like_condition_scales_with_its_bins() {
        let c = crate::calibrate::condition::test3();
        let own = c.target_all().bins;
        let f = floor_like(&c, &own, f64::INFINITY);
        // at the condition's own bins: its measured means' variance without the scale's part
        let measured: f64 = 1e4 * c.mean_variance().iter().sum::<f64>();
        assert!((f / measured - 1.0).abs() < 0.2, "{f} {measured}");
        // all mass in one bin: nothing scatters
        let mut one = vec![0.0; own.len()];
        one[0] = 1.0;
        assert_eq!(floor_like(&c, &one, 1e6), 0.0);
    }

    #[test]
    fn proposals_rank_by_their_worst_pair() {
        let sep = |a: &str, b: &str, sse: f64| Separation { a: a.into(), b: b.into(), sse, floor: 1.0 };
        let wide = Proposal {
            base: "c".into(),
            change: Change::Slope(10.0),
            pairs: vec![sep("x", "y", 9.0), sep("x", "z", 2.0)],
        };
        let even =
            Proposal { base: "c".into(), change: Change::V0(1.4), pairs: vec![sep("x", "y", 4.0), sep("x", "z", 4.0)] };
        assert_eq!(wide.worst(), 2.0);
        assert!(!wide.separates() && even.separates());
        let mut all = [wide, even];
        all.sort_by(|a, b| b.worst().total_cmp(&a.worst()));
        assert_eq!(all[0].change, Change::V0(1.4));
        // predictions that agree separate nothing, even where nothing scatters; a difference
        // where nothing scatters is measured against the smallest floor, finite
        let agree = Separation { a: "x".into(), b: "y".into(), sse: 0.0, floor: 0.0 };
        assert_eq!(agree.ratio(), 0.0);
        let differ = Separation { a: "x".into(), b: "y".into(), sse: 1.0, floor: 0.0 };
        assert_eq!(differ.ratio(), 1.0 / MIN_FLOOR);
    }
}
