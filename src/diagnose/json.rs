//! diagnosis.json: the file's layout as types that borrow from a [`Diagnosis`] and derive
//! `Serialize`, one per object of the file. Numbers that are not finite are written as
//! null (serde_json's rule for f64); keys come out sorted, as serde_json's map keeps them.

use std::collections::BTreeMap;

use serde::Serialize;
use serde_json::Value;

use super::candidates::RANKING_RULE;
use super::diagnose::{about_as_well, Diagnosis, ScreenedMotion};
use super::limits::{DetectionLimits, PROBABILITY};
use super::locate::Residual;
use super::model_result::{ModelResult, Z_FLAG};
use super::scoring::INTERVAL;
use super::suggest::{Separation, Suggestions};
use super::verdict::{Judged, Verdict, CAUSE_SHARE, FLOOR_FACTOR};
use crate::calibrate::Condition;

/// The `diagnosis.json` object.
pub fn to_json(d: &Diagnosis) -> Value {
    serde_json::to_value(DiagnosisJson::new(d)).expect("diagnosis.json's types serialise to a JSON value")
}

/// A model's fitted parameters by name.
fn params(m: &ModelResult) -> BTreeMap<&'static str, f64> {
    m.names.iter().copied().zip(m.full.x.iter().copied()).collect()
}

/// A bin's label: its tooth number, or the last bin's name with `_` for spaces
/// (`not_recovered`).
#[derive(Serialize)]
#[serde(untagged)]
enum Tooth {
    Number(usize),
    Name(String),
}

impl Tooth {
    /// Bin `j` of `c` where the bins before `teeth` are teeth and the one there is the last.
    fn of(j: usize, teeth: usize, c: &Condition) -> Tooth {
        if j < teeth {
            Tooth::Number(j + 1)
        } else {
            Tooth::Name(c.last_bin_label().replace(' ', "_"))
        }
    }
}

#[derive(Serialize)]
struct DiagnosisJson<'a> {
    gap: Gap<'a>,
    ranking: Vec<Ranked>,
    best: Option<&'static str>,
    verdict: &'static str,
    verdict_detail: VerdictJson<'a>,
    indistinguishable: Vec<&'static str>,
    combined: Option<CombinedJson<'a>>,
    baseline: BaselineJson<'a>,
    #[serde(rename = "where")]
    where_: WhereJson<'a>,
    detection_limits: Option<LimitsJson<'a>>,
    suggestions: Option<SuggestionsJson<'a>>,
    motion_screen: Option<MotionScreenJson>,
}

impl<'a> DiagnosisJson<'a> {
    fn new(d: &'a Diagnosis) -> Self {
        let b = &d.baseline;
        DiagnosisJson {
            gap: Gap::new(d),
            ranking: d.ranking.iter().map(|m| Ranked::new(m, b)).collect(),
            best: d.best.map(|e| e.name()),
            verdict: d.verdict.kind.name(),
            verdict_detail: VerdictJson::new(&d.verdict, &d.conditions),
            indistinguishable: d.indistinguishable.iter().map(|e| e.name()).collect(),
            combined: d.combined.as_ref().map(|cb| CombinedJson {
                effects: cb.model.effects.iter().map(|e| e.name()).collect(),
                gap: cb.model.gap,
                interval: cb.model.interval,
                reduction: 1.0 - cb.model.gap / b.gap,
                improvement_interval: cb.model.improvement_interval,
                improvement_over_singles: cb
                    .model
                    .effects
                    .iter()
                    .zip(&cb.improvement_over_singles)
                    .map(|(e, i)| OverSingle { effect: e.name(), interval: *i })
                    .collect(),
                params: params(&cb.model),
                in_sample_sse: cb.model.full.value,
                bins: &cb.model.full.bins,
            }),
            baseline: BaselineJson {
                params: params(b),
                in_sample_sse: b.full.value,
                gap: b.gap,
                interval: b.interval,
                se: b.se,
                rescore_streams: d.settings.rescore_streams,
                bootstrap: d.settings.bootstrap,
                interval_percentiles: [INTERVAL.0, INTERVAL.1],
                particles: d.particles,
                engine: &d.engine,
                shared_params: d.shared.iter().map(|p| p.name()).collect(),
                ranking_rule: RANKING_RULE,
                scores: d.ranking.iter().map(|m| (m.name(), m.score)).collect(),
                gap_by_condition: d.conditions.iter().zip(&b.gap_by_condition).map(|(c, v)| (&*c.name, *v)).collect(),
            },
            where_: WhereJson {
                params: params(b),
                in_sample_sse: b.full.value,
                conditions: d.conditions.iter().zip(&d.where_).map(|(c, w)| WhereConditionJson::new(c, w)).collect(),
                z_flag: Z_FLAG,
            },
            detection_limits: d.limits.as_ref().map(LimitsJson::new),
            suggestions: d.suggestions.as_ref().map(SuggestionsJson::new),
            motion_screen: MotionScreenJson::new(d),
        }
    }
}

/// `motion_screen`: every unstated motion the screen tried, best first, and whether it fits
/// about as well as the best (its SSE within `within`, the noise floor, of the best's): more
/// than one such point is a ridge the data do not resolve. Null where the screen did not run.
#[derive(Serialize)]
struct MotionScreenJson {
    within: f64,
    points: Vec<MotionPointJson>,
}

#[derive(Serialize)]
struct MotionPointJson {
    /// The return direction assumed (absent where every setup states it).
    direction: Option<&'static str>,
    /// The grid's values of the unstated motion parameters (`delay_s`, `return_speed_m_s`).
    motion: BTreeMap<&'static str, f64>,
    /// Loss-adjusted SSE at the full budget on the fit's streams, %².
    sse: f64,
    polished: bool,
    about_as_well: bool,
}

impl MotionScreenJson {
    fn new(d: &Diagnosis) -> Option<Self> {
        if d.motion_screen.is_empty() {
            return None;
        }
        let within = d.verdict.remaining.floor;
        let near = about_as_well(&d.motion_screen, within);
        let point = |p: &ScreenedMotion| MotionPointJson {
            direction: p.direction.map(|r| r.name()),
            motion: p.motion.iter().copied().collect(),
            sse: p.sse,
            polished: p.polished,
            about_as_well: near.iter().any(|q| std::ptr::eq(*q, p)),
        };
        Some(MotionScreenJson { within, points: d.motion_screen.iter().map(point).collect() })
    }
}

/// One candidate of the ranking.
#[derive(Serialize)]
struct Ranked {
    effect: String,
    gap: f64,
    reduction: f64,
    interval: [f64; 2],
    improvement_interval: [f64; 2],
    improvement_sd: ImprovementSd,
    extra_params: usize,
    score: f64,
    params: BTreeMap<&'static str, f64>,
}

impl Ranked {
    fn new(m: &ModelResult, baseline: &ModelResult) -> Self {
        Ranked {
            effect: m.name(),
            gap: m.gap,
            reduction: 1.0 - m.gap / baseline.gap,
            interval: m.interval,
            improvement_interval: m.improvement_interval,
            improvement_sd: ImprovementSd {
                both: m.improvement_sd[0],
                runs: m.improvement_sd[1],
                simulation: m.improvement_sd[2],
            },
            extra_params: m.extra_params,
            score: m.score,
            params: params(m),
        }
    }
}

#[derive(Serialize)]
struct ImprovementSd {
    both: f64,
    runs: f64,
    simulation: f64,
}

/// "How far": the top-ranked effect against the baseline per condition, or only the notes
/// when nothing was ranked.
#[derive(Serialize)]
#[serde(untagged)]
enum Gap<'a> {
    Top(Box<TopGap<'a>>),
    NotesOnly { notes: &'a [String] },
}

#[derive(Serialize)]
struct TopGap<'a> {
    effect: String,
    is_best: bool,
    gap_before: f64,
    gap_before_interval: [f64; 2],
    gap_after: f64,
    gap_after_interval: [f64; 2],
    reduction: f64,
    improvement_interval: [f64; 2],
    in_sample_before: f64,
    in_sample_after: f64,
    conditions: Vec<GapConditionJson<'a>>,
    notes: &'a [String],
}

impl<'a> Gap<'a> {
    fn new(d: &'a Diagnosis) -> Self {
        let b = &d.baseline;
        let Some(t) = d.gap_model() else { return Gap::NotesOnly { notes: &d.notes } };
        let conditions = d
            .conditions
            .iter()
            .zip(&d.gap)
            .zip(&d.where_)
            .map(|((c, g), w)| {
                let teeth = c.teeth();
                GapConditionJson {
                    name: &c.name,
                    teeth: (0..w.shown_teeth)
                        .chain(std::iter::once(teeth))
                        .map(|j| GapTooth {
                            tooth: Tooth::of(j, teeth, c),
                            measured: 100.0 * g.measured[j],
                            before: 100.0 * g.before[j],
                            after: 100.0 * g.after[j],
                            residual_before: 100.0 * (g.before[j] - g.measured[j]),
                            residual_before_interval: g.before_interval[j],
                            residual_after: 100.0 * (g.after[j] - g.measured[j]),
                            residual_after_interval: g.after_interval[j],
                        })
                        .collect(),
                    centre_of_mass: BeforeAfter {
                        measured: g.centre[0],
                        measured_interval: g.centre_interval,
                        before: g.centre[1],
                        after: g.centre[2],
                    },
                    dispersion: BeforeAfter {
                        measured: g.dispersion[0],
                        measured_interval: g.dispersion_interval,
                        before: g.dispersion[1],
                        after: g.dispersion[2],
                    },
                }
            })
            .collect();
        Gap::Top(Box::new(TopGap {
            effect: t.name(),
            is_best: d.best.is_some(),
            gap_before: b.gap,
            gap_before_interval: b.interval,
            gap_after: t.gap,
            gap_after_interval: t.interval,
            reduction: 1.0 - t.gap / b.gap,
            improvement_interval: t.improvement_interval,
            in_sample_before: b.full.value,
            in_sample_after: t.full.value,
            conditions,
            notes: &d.notes,
        }))
    }
}

#[derive(Serialize)]
struct GapConditionJson<'a> {
    name: &'a str,
    teeth: Vec<GapTooth>,
    centre_of_mass: BeforeAfter,
    dispersion: BeforeAfter,
}

#[derive(Serialize)]
struct GapTooth {
    tooth: Tooth,
    measured: f64,
    before: f64,
    after: f64,
    residual_before: f64,
    residual_before_interval: [f64; 2],
    residual_after: f64,
    residual_after_interval: [f64; 2],
}

#[derive(Serialize)]
struct BeforeAfter {
    measured: f64,
    measured_interval: [f64; 2],
    before: f64,
    after: f64,
}

#[derive(Serialize)]
struct CombinedJson<'a> {
    effects: Vec<&'static str>,
    gap: f64,
    interval: [f64; 2],
    reduction: f64,
    improvement_interval: [f64; 2],
    improvement_over_singles: Vec<OverSingle>,
    params: BTreeMap<&'static str, f64>,
    in_sample_sse: f64,
    bins: &'a [Vec<f64>],
}

#[derive(Serialize)]
struct OverSingle {
    effect: &'static str,
    interval: [f64; 2],
}

#[derive(Serialize)]
struct BaselineJson<'a> {
    params: BTreeMap<&'static str, f64>,
    in_sample_sse: f64,
    gap: f64,
    interval: [f64; 2],
    se: f64,
    rescore_streams: usize,
    bootstrap: usize,
    interval_percentiles: [f64; 2],
    particles: u32,
    engine: &'a str,
    shared_params: Vec<&'static str>,
    ranking_rule: &'static str,
    scores: BTreeMap<String, f64>,
    gap_by_condition: BTreeMap<&'a str, f64>,
}

#[derive(Serialize)]
struct WhereJson<'a> {
    params: BTreeMap<&'static str, f64>,
    in_sample_sse: f64,
    conditions: Vec<WhereConditionJson<'a>>,
    z_flag: f64,
}

/// A residual with its uncertainty and the parts it is made of.
#[derive(Serialize)]
struct ResidualJson {
    measured: f64,
    simulated: f64,
    residual: f64,
    uncertainty: f64,
    uncertainty_parts: UncertaintyParts,
    z: f64,
    flag: bool,
}

impl From<&Residual> for ResidualJson {
    fn from(r: &Residual) -> Self {
        ResidualJson {
            measured: r.measured,
            simulated: r.simulated,
            residual: r.residual,
            uncertainty: r.uncertainty,
            uncertainty_parts: UncertaintyParts { run_to_run: r.parts[0], scale: r.parts[1], monte_carlo: r.parts[2] },
            z: r.z,
            flag: r.flagged(),
        }
    }
}

#[derive(Serialize)]
struct UncertaintyParts {
    run_to_run: f64,
    scale: f64,
    monte_carlo: f64,
}

/// A bin's residual, with first flight and bounce chain where it is a tooth.
#[derive(Serialize)]
struct ToothResidual {
    #[serde(flatten)]
    residual: ResidualJson,
    tooth: Tooth,
    #[serde(skip_serializing_if = "Option::is_none")]
    first_flight: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    bounce_chain: Option<f64>,
}

#[derive(Serialize)]
struct WhereConditionJson<'a> {
    name: &'a str,
    data: &'a str,
    setup: &'a str,
    runs: usize,
    motion_profile: Option<&'a str>,
    stated_motion: StatedMotion,
    teeth: Vec<ToothResidual>,
    centre_of_mass: ResidualJson,
    dispersion: ResidualJson,
    simulated_lost_percent: f64,
    first_flight_percent: f64,
    bounce_chain_percent: f64,
    launch_depth: Vec<LayerJson<'a>>,
    flagged_teeth: Vec<usize>,
}

impl<'a> WhereConditionJson<'a> {
    fn new(c: &'a Condition, w: &'a super::locate::WhereCondition) -> Self {
        WhereConditionJson {
            name: &c.name,
            data: &c.data,
            setup: &c.setup,
            runs: c.runs.runs.len(),
            motion_profile: c.motion_profile.as_deref(),
            stated_motion: StatedMotion { delay_s: c.motion.delay_s, return_speed_m_s: c.motion.return_speed_m_s },
            teeth: w
                .teeth_residuals
                .iter()
                .enumerate()
                .map(|(j, r)| ToothResidual {
                    residual: r.into(),
                    // the residuals are the shown teeth, then the last bin
                    tooth: Tooth::of(j, w.shown_teeth, c),
                    first_flight: (j < w.shown_teeth).then(|| w.first_flight[j]),
                    bounce_chain: (j < w.shown_teeth).then(|| w.bounce_chain[j]),
                })
                .collect(),
            centre_of_mass: (&w.centre).into(),
            dispersion: (&w.dispersion).into(),
            simulated_lost_percent: w.lost_percent,
            first_flight_percent: w.first_flight.iter().sum(),
            bounce_chain_percent: w.bounce_chain.iter().sum(),
            launch_depth: w
                .launch_depth
                .iter()
                .map(|l| LayerJson {
                    layer: l.label,
                    depth_mm: l.depth_mm,
                    particles: l.particles,
                    teeth_percent: &l.teeth_percent,
                    further_or_lost_percent: l.further_or_lost_percent,
                })
                .collect(),
            flagged_teeth: w.teeth_residuals[..w.shown_teeth]
                .iter()
                .enumerate()
                .filter(|(_, r)| r.flagged())
                .map(|(j, _)| j + 1)
                .collect(),
        }
    }
}

#[derive(Serialize)]
struct StatedMotion {
    delay_s: Option<f64>,
    return_speed_m_s: Option<f64>,
}

#[derive(Serialize)]
struct LayerJson<'a> {
    layer: &'static str,
    depth_mm: [f64; 2],
    particles: usize,
    teeth_percent: &'a [f64],
    further_or_lost_percent: f64,
}

/// `verdict_detail`: the verdict with what it rests on.
#[derive(Serialize)]
struct VerdictJson<'a> {
    verdict: &'static str,
    text: &'a str,
    floor_factor: f64,
    cause_share: f64,
    baseline: JudgedJson<'a>,
    remaining: JudgedJson<'a>,
    by_condition: Vec<ConditionVerdictJson<'a>>,
    conditions_well_above: Vec<&'a str>,
    demoted: Option<&'static str>,
    partial: Vec<PartialJson>,
    not_removed: Vec<NotRemovedJson<'a>>,
}

impl<'a> VerdictJson<'a> {
    fn new(v: &'a Verdict, conds: &'a [Condition]) -> Self {
        VerdictJson {
            verdict: v.kind.name(),
            text: &v.text,
            floor_factor: FLOOR_FACTOR,
            cause_share: CAUSE_SHARE,
            baseline: JudgedJson::new(&v.baseline, conds),
            remaining: JudgedJson::new(&v.remaining, conds),
            by_condition: v
                .conditions
                .iter()
                .map(|c| ConditionVerdictJson {
                    name: &c.name,
                    model: &c.model,
                    gap: c.gap,
                    floor: c.floor,
                    gap_over_floor: c.ratio(),
                    well_above: c.well_above(),
                })
                .collect(),
            conditions_well_above: v.conditions.iter().filter(|c| c.well_above()).map(|c| &*c.name).collect(),
            demoted: v.demoted.map(|e| e.name()),
            partial: v
                .partial
                .iter()
                .map(|p| PartialJson {
                    effect: p.effect.name(),
                    reduction: p.reduction,
                    excess_share: p.excess_share,
                    improvement_interval: p.improvement_interval,
                })
                .collect(),
            not_removed: conds
                .iter()
                .zip(&v.persistent)
                .map(|(c, p)| NotRemovedJson {
                    name: &c.name,
                    sse: p.sse,
                    floor: p.floor,
                    bins: p
                        .bins
                        .iter()
                        .map(|b| NotRemovedBin {
                            bin: &b.label,
                            residual: b.residual,
                            uncertainty: b.uncertainty,
                            z: b.z,
                            flag: b.flagged(),
                            from_depth_percent: b.from_depth.iter().copied().collect(),
                        })
                        .collect(),
                })
                .collect(),
        }
    }
}

#[derive(Serialize)]
struct JudgedJson<'a> {
    model: &'a str,
    gap: f64,
    floor: f64,
    gap_over_floor: f64,
    by_condition: Vec<JudgedCondition<'a>>,
}

impl<'a> JudgedJson<'a> {
    fn new(j: &'a Judged, conds: &'a [Condition]) -> Self {
        JudgedJson {
            model: &j.model,
            gap: j.gap,
            floor: j.floor,
            gap_over_floor: j.ratio(),
            by_condition: conds
                .iter()
                .enumerate()
                .map(|(c, cond)| JudgedCondition {
                    name: &cond.name,
                    gap: j.gap_by_condition[c],
                    floor: j.floor_by_condition[c],
                    gap_over_floor: j.gap_by_condition[c] / j.floor_by_condition[c],
                    handling_loss_percent: 100.0 * j.handling_loss[c],
                })
                .collect(),
        }
    }
}

#[derive(Serialize)]
struct JudgedCondition<'a> {
    name: &'a str,
    gap: f64,
    floor: f64,
    gap_over_floor: f64,
    handling_loss_percent: f64,
}

#[derive(Serialize)]
struct ConditionVerdictJson<'a> {
    name: &'a str,
    model: &'a str,
    gap: f64,
    floor: f64,
    gap_over_floor: f64,
    well_above: bool,
}

#[derive(Serialize)]
struct PartialJson {
    effect: &'static str,
    reduction: f64,
    excess_share: f64,
    improvement_interval: [f64; 2],
}

#[derive(Serialize)]
struct NotRemovedJson<'a> {
    name: &'a str,
    sse: f64,
    floor: f64,
    bins: Vec<NotRemovedBin<'a>>,
}

#[derive(Serialize)]
struct NotRemovedBin<'a> {
    bin: &'a str,
    residual: f64,
    uncertainty: f64,
    z: f64,
    flag: bool,
    from_depth_percent: BTreeMap<&'static str, f64>,
}

/// `detection_limits`: each candidate parameter's smallest strength the diagnosis detects
/// with the probability, how it was found, and the ladder it was found on.
#[derive(Serialize)]
struct LimitsJson<'a> {
    probability: f64,
    method: &'static str,
    particles: u32,
    draws: usize,
    floor: f64,
    limits: Vec<LimitJson>,
    skipped: &'a [String],
}

#[derive(Serialize)]
struct LimitJson {
    effect: &'static str,
    param: &'static str,
    held: BTreeMap<&'static str, f64>,
    limit: Option<f64>,
    found: &'static str,
    ladder: Vec<RungJson>,
}

#[derive(Serialize)]
struct RungJson {
    strength: f64,
    probability: f64,
    expected_gap: f64,
    /// The baseline refitted to the rung by simulation, not only to first order.
    refitted: bool,
}

/// How the limits are found, in one line (src/diagnose/limits.rs has the method).
pub const LIMITS_METHOD: &str = "the fitted baseline with the candidate at a ladder of strengths on common particle \
     streams; the part of its signature no linearised refit of the baseline (nor a handling loss) removes, and \
     around the 90 % crossing no simulated refit (the baseline polished to the rung's bins) removes, with \
     Gaussian draws of the measured means' and the fresh streams' noise; detected where the judged gap exceeds \
     3x its floor; the limit where the signal, grown as a power of the strength between the two rungs around \
     the crossing, is detected with 90 % probability";

impl<'a> LimitsJson<'a> {
    fn new(l: &'a DetectionLimits) -> Self {
        LimitsJson {
            probability: PROBABILITY,
            method: LIMITS_METHOD,
            particles: l.particles,
            draws: l.draws,
            floor: l.floor,
            limits: l
                .limits
                .iter()
                .map(|d| LimitJson {
                    effect: d.effect.name(),
                    param: d.param,
                    held: d.held.iter().copied().collect(),
                    limit: d.limit,
                    found: d.found,
                    ladder: d
                        .ladder
                        .iter()
                        .map(|r| RungJson {
                            strength: r.strength,
                            probability: r.probability,
                            expected_gap: r.expected_gap,
                            refitted: r.refitted,
                        })
                        .collect(),
                })
                .collect(),
            skipped: &l.skipped,
        }
    }
}

/// `suggestions` (`--suggest`): the models left to separate, why those, what the campaign
/// already separates, and every proposed condition, best first.
#[derive(Serialize)]
struct SuggestionsJson<'a> {
    models: &'a [String],
    why: &'a str,
    current: Vec<SeparationJson<'a>>,
    proposals: Vec<ProposalJson<'a>>,
}

#[derive(Serialize)]
struct SeparationJson<'a> {
    a: &'a str,
    b: &'a str,
    sse: f64,
    floor: f64,
    separation: f64,
}

impl<'a> From<&'a Separation> for SeparationJson<'a> {
    fn from(s: &'a Separation) -> Self {
        SeparationJson { a: &s.a, b: &s.b, sse: s.sse, floor: s.floor, separation: s.ratio() }
    }
}

#[derive(Serialize)]
struct ProposalJson<'a> {
    condition: &'a str,
    change: BTreeMap<&'static str, f64>,
    label: String,
    separation: f64,
    separates: bool,
    pairs: Vec<SeparationJson<'a>>,
}

impl<'a> SuggestionsJson<'a> {
    fn new(s: &'a Suggestions) -> Self {
        SuggestionsJson {
            models: &s.models,
            why: &s.why,
            current: s.current.iter().map(Into::into).collect(),
            proposals: s
                .proposals
                .iter()
                .map(|p| ProposalJson {
                    condition: &p.base,
                    change: std::iter::once(p.change.field()).collect(),
                    label: p.change.label(),
                    separation: p.worst(),
                    separates: p.separates(),
                    pairs: p.pairs.iter().map(Into::into).collect(),
                })
                .collect(),
        }
    }
}
