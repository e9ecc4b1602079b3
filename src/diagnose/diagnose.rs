//! `diagnose` (issues 5 and 11): where the calibrated model misses measured data, which of
//! the optional effects ([`crate::model::effects`]) closes the gap, and by how much.
//!
//! - **Conditions.** One or more measured campaigns, each with its own setup (geometry,
//!   kinematics, environment). They share the material and collision parameters being fitted:
//!   `k_elastic`, `mu_fric`, and `k_drag` when any setup has drag (applied only to the setups
//!   with drag). The joint objective is the sum over conditions of the SSE of Eq. 4.62 (%²).
//! - **Measurement model.** Where every run records its loaded mass, the compared fractions
//!   are fractions of it: the weighed teeth and a "not recovered" bin that the simulation
//!   fills with what rests beyond the weighed teeth or is lost ([`crate::calibrate::Normalise::Loaded`]);
//!   otherwise D.4's fractions of the recovered mass. With varying grain sizes each simulated
//!   grain stands for an equal mass (`effects::Polydisperse`), so simulated fractions are mass
//!   fractions, as a scale weighs them.
//! - **Monte-Carlo budget from the data.** The particle count per simulation is chosen so
//!   that the simulation's variance p(1−p)/N of every tooth holding ≥ 2 % of the mass is at
//!   most a quarter of the variance of the measured mean (run-to-run variance / runs, floored
//!   by the scale's resolution), within [`crate::calibrate::MIN_PARTICLES`, `--max-particles`] ([`crate::calibrate::Effort`]); a note says when
//!   the cap, not the data, limits the answer.
//! - **Fits** ([`crate::calibrate`]): all candidate models are fitted in lockstep, each
//!   stage's points of every model and condition simulated as one engine call: differential
//!   evolution at 1/8 of the particles screens the box (seeded, for a nested effect, with the
//!   baseline's optimum and the effect switched off), a compass search polishes at the full
//!   budget. Common random numbers throughout.
//! - **Gap.** Each fitted model is re-simulated on fresh particle streams (not the ones it
//!   was fitted on) and scored against all runs: the gap is the SSE of the streams' mean
//!   bins, once each condition's handling loss is allowed (a share of the loaded mass
//!   moved to "not recovered", fitted in [0, the measured not-recovered share];
//!   [`verdict::loss_adjusted_sse`]): every run spills a little, differently, and no flight
//!   model makes that. A fit adapts to its own streams' Monte-Carlo noise, and a model with more
//!   parameters adapts more; fresh streams remove that flattery. The mean of the streams, not
//!   the mean of their SSEs: an SSE adds its bins' Monte-Carlo variance to every gap, and the
//!   mean has 1/streams of one stream's. (Holding out runs, as issue 5 did, tests only the
//!   run-to-run noise, which in these rigs is far below the gaps.)
//! - **Intervals.** A bootstrap over runs and streams: each replicate resamples, with
//!   replacement, the runs of every condition and the fresh streams (their mean's deviation
//!   widened by √(k/(k−1)), so that the replicates carry the mean's Monte-Carlo variance),
//!   and recomputes every model's gap (paired across models: the same resamples, and stream r
//!   of every model from the same seed). Until then each replicate drew *one* stream, which
//!   gave every replicate k times the Monte-Carlo variance of the gap it was an interval for.
//!   Intervals are the 5-95 % percentiles ([`INTERVAL`]); the standard error is the
//!   replicates' sd. Each candidate's improvement over the baseline also has its sd with one
//!   source at a time (`improvement_sd`: the runs alone, the simulation alone), which says
//!   whether more particles would sharpen it (on 300 µm quadratic drag at the defaults:
//!   runs 2.1 %², simulation 0.8 %²; docs/diagnosis-report.md). Where `best` waits on
//!   nothing but an improvement interval that holds 0, every model is re-scored on 4× the
//!   streams before anything is decided ([`SECOND_RESCORE_FACTOR`]): which side of 0 an
//!   effect at the edge falls on should not depend on which few streams were drawn.
//! - **Ranking.** By the penalised score `gap + 2 × (extra parameters) × SE` (the parameters
//!   beyond the baseline's: the effect's own, less k_drag for quadratic drag, which replaces
//!   the linear law and is fitted without it). `best` is the top-ranked effect only when it
//!   beats the baseline beyond the uncertainty *and* by a material share: the top-ranked
//!   effect's paired bootstrap interval of the improvement (baseline − effect) lies above 0,
//!   and the effect removes at least [`MIN_REDUCTION`] of the baseline's gap, and the
//!   baseline's gap is well above its noise floor (a gap within the runs' own scatter needs
//!   no cause; [`super::verdict`]). The reduction test
//!   is what keeps a control null when the baseline physics is itself slightly off: an extra
//!   parameter always buys a little of a systematic misfit. Effects that are not worse than
//!   the top-ranked one beyond the uncertainty — the paired interval of (effect − top) reaches
//!   0 or below — are `indistinguishable` (the top one included when there is any other).
//!   Paired, not marginal, intervals (issue 32, item 5): the runs' resampling moves every
//!   model's gap alike, so overlapping marginal intervals said "cannot tell" where the
//!   paired differences were clear (an impact scatter of ~12° or 300 µm beads' quadratic
//!   drag halving the gap came out "all five indistinguishable").
//! - **Verdict** ([`super::verdict`]): the remaining gap against the data's noise floor —
//!   `no-gap`, `explained`, `partly-explained` or `unexplained` ("none of these"), with the
//!   residual pattern that no candidate removes.
//! - **How far.** Per tooth, centre of mass and dispersion before and after the top-ranked
//!   effect, with bootstrap intervals over runs; and, when two candidates each beat the
//!   baseline, the two fitted together (from both single fits and the baseline), with paired
//!   intervals of its improvement over each alone. The combination is reported beside the
//!   ranking, not in it: `best` stays a single effect.
//! - **Known sled motion.** A setup may state the sled's motion after the launch
//!   ([measurement] `motion_delay_s`, `motion_return_speed_m_s`; e.g. the POC profile of Test
//!   1 returns at once at v_d ≈ 0.05 m/s, 5.3.1). The baseline and the other candidates
//!   ignore it, as the thesis's model does; the sled-motion candidate holds the stated values
//!   fixed for that condition and fits the ones left out, shared by the conditions that
//!   leave them out. Conditions that differ only in their motion are what identifies it.
//! - **Limits.** With one condition, a shift of the whole distribution cannot be told apart
//!   from refitted collision/drag parameters; the report says so.
//!
//! The work goes in stages, each a function with its own output, in this order: the
//! inputs checked into a [`Run`] ([`super::run`]), the baseline ([`super::baseline`]), the
//! motion screen ([`super::motion_screen`]), the candidates fitted, re-scored and ranked
//! ([`super::candidates`]), where the baseline misses and how far the top effect goes
//! ([`super::locate`]), the verdict ([`super::verdict`]), and the pair of the two best
//! ([`super::pair`]). diagnosis.json is [`super::json`], report.md [`super::markdown`].

use super::baseline::fit_baseline;
use super::candidates::rank_candidates;
pub use super::candidates::{MIN_REDUCTION, RANKING_RULE};
use super::limits::detection_limits;
pub use super::limits::DetectionLimits;
use super::locate::locate;
pub use super::locate::{GapCondition, Residual, WhereCondition};
pub use super::model_result::{DepthLayer, ModelResult, Z_FLAG};
use super::motion_screen::screen_motion;
pub use super::motion_screen::{about_as_well, ScreenedMotion};
use super::pair::fit_pair;
pub use super::pair::Combined;
pub use super::run::{applicable_effects, parse_effects, shared_params, Run, Settings, NO_EFFECT_APPLIES};
pub use super::scoring::INTERVAL;
use super::suggest::suggest;
pub use super::suggest::Suggestions;
use super::verdict::{self, Verdict};
use crate::calibrate::Param;
pub use crate::calibrate::{Condition, KnownMotion};
use crate::engine::BatchEvaluator;
pub use crate::model::effects::EffectKind;

/// The whole diagnosis.
#[derive(Clone, Debug)]
pub struct Diagnosis {
    pub conditions: Vec<Condition>,
    pub shared: Vec<Param>,
    pub settings: Settings,
    pub baseline: ModelResult,
    /// Effects, ranked (best penalised score first).
    pub ranking: Vec<ModelResult>,
    pub best: Option<EffectKind>,
    pub indistinguishable: Vec<EffectKind>,
    /// The two best effects fitted together, when two beat the baseline.
    pub combined: Option<Combined>,
    pub where_: Vec<WhereCondition>,
    pub gap: Vec<GapCondition>,
    /// Whether the best effect explains the gap, or none does (item 2 of issue 32).
    pub verdict: Verdict,
    /// Each candidate's detection limit for this campaign, when asked for.
    pub limits: Option<DetectionLimits>,
    /// The next measurement, when asked for (`--suggest`) and something is left to separate.
    pub suggestions: Option<Suggestions>,
    /// The motion screen's grid points, best first; empty where it did not run (every setup
    /// states the motion, or sled-motion is not a candidate).
    pub motion_screen: Vec<ScreenedMotion>,
    pub notes: Vec<String>,
    pub particles: u32,
    pub engine: String,
}

impl Diagnosis {
    /// The effect the "how far" section uses: `best`, else the top-ranked one.
    pub fn gap_model(&self) -> Option<&ModelResult> {
        self.ranking.first()
    }
}

/// Run the diagnosis, stage by stage. `log` receives progress lines.
pub fn diagnose(
    engine: &dyn BatchEvaluator,
    conditions: Vec<Condition>,
    settings: Settings,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Diagnosis> {
    let (run, mut notes) = Run::new(engine, &conditions, &settings)?;
    log(format!(
        "diagnose: {} conditions, {} particles per simulation (screen {}), {} candidate effects",
        conditions.len(),
        run.particles(),
        run.solver.screen_particles,
        run.effects.len()
    ));
    // the baseline first: its optimum starts every nested effect and the motion screen
    let baseline = fit_baseline(&run, log)?;
    // what the campaign could not have seen, from the baseline alone
    let limits = settings.detection_limits.then(|| detection_limits(&run, &baseline, log));
    let screened = screen_motion(&run, &baseline, log)?;
    let motion_screen = screened.as_ref().map_or_else(Vec::new, |s| s.points.clone());
    let baseline_space = baseline.space.clone();
    let ranked = rank_candidates(&run, baseline, screened, log)?;
    notes.extend(ranked.notes.iter().cloned());
    let located = locate(&run, &baseline_space, &ranked)?;
    // is the gap there, and does the best effect explain it (or only a part of it)?
    let verdict = verdict::verdict(
        &conditions,
        &ranked.baseline,
        &ranked.ranking,
        ranked.best,
        &ranked.indistinguishable,
        &located.shown(),
        &located.layers(),
        run.particles(),
        limits.as_ref().map(DetectionLimits::clause).as_deref(),
    );
    log(format!("diagnose: verdict {}: {}", verdict.kind.name(), verdict.text));
    let best = ranked.best.filter(|e| verdict.demoted != Some(*e));
    // how far two effects go together
    let combined = fit_pair(&run, &ranked, best, log)?;
    // what to measure next
    let suggestions = if settings.suggest { suggest(&run, &ranked, &verdict, limits.as_ref(), log) } else { None };
    let (particles, effects, shared) = (run.particles(), run.effects.clone(), run.shared.clone());
    let engine = engine.backend().to_string();
    let super::candidates::Ranked { baseline, ranking, indistinguishable, streams, .. } = ranked;
    Ok(Diagnosis {
        shared,
        settings: Settings { effects, rescore_streams: streams, ..settings },
        baseline,
        ranking,
        best,
        indistinguishable,
        combined,
        where_: located.where_,
        gap: located.gap,
        verdict,
        limits,
        suggestions,
        motion_screen,
        notes,
        particles,
        engine,
        conditions,
    })
}
