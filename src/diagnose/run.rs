//! What every stage of one diagnosis works with ([`Run`]): the measured conditions checked,
//! the candidate effects that can act on them, the solver the user's effort gives for them,
//! and the notes that say what was left out or what limits the answer.

use anyhow::bail;

use crate::calibrate::{Condition, Effort, ObjectiveKind, Param, PolishMethod, Simulator, Solver, Target};
use crate::engine::BatchEvaluator;
use crate::model::effects::{known_effects, EffectKind};

pub use crate::calibrate::space::shared_params;

/// `all` or a comma list of effect names, each once.
pub fn parse_effects(list: &str) -> anyhow::Result<Vec<EffectKind>> {
    if list.trim() == "all" {
        return Ok(EffectKind::ALL.to_vec());
    }
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim) {
        if name == "all" {
            bail!("`all` stands alone (it names every effect): give `all`, or a list of effects without it");
        }
        let Some(e) = EffectKind::from_name(name) else {
            bail!("unknown effect `{name}` (known: all, {})", known_effects());
        };
        if out.contains(&e) {
            bail!("effect `{name}` given twice");
        }
        out.push(e);
    }
    Ok(out)
}

/// Settings of a diagnosis.
#[derive(Clone, Debug)]
pub struct Settings {
    pub effects: Vec<EffectKind>,
    pub effort: Effort,
    /// Fresh particle streams every fitted model is re-scored with.
    pub rescore_streams: usize,
    pub bootstrap: usize,
    /// Each candidate's detection limit for this campaign ([`super::limits`]).
    pub detection_limits: bool,
    /// The additional conditions that would separate what the diagnosis leaves
    /// ([`super::suggest`]).
    pub suggest: bool,
    /// The parameters every model fits, shared by the conditions (None: k_elastic, mu_fric,
    /// and k_drag where any setup has air, [`shared_params`]). `v_limit` among them fits the
    /// contact law's plastic limit speed too, in the baseline and every candidate.
    pub shared: Option<Vec<Param>>,
}

/// What is said when none of the candidate effects can act on the setups.
pub const NO_EFFECT_APPLIES: &str = "no candidate effect applies to these setups";

/// A sled motion that sets in this late after the launch is no motion for the flights: the
/// top of the sled-motion candidate's delay box ("a delay beyond the flights is the same as no
/// motion", `EffectKind::search_bounds`).
pub fn motion_past_the_flights_s() -> f64 {
    EffectKind::SledMotion.search_bounds()[0].1
}

/// The candidate effects that can change these setups' outcome, and a note for each left out:
/// an effect that only changes drag does nothing when every setup is in vacuum, and the
/// sled-motion candidate is the baseline itself when every setup states a motion that sets in
/// only after the flights (the practice rig's sled rests 5 s: fitting it again costs a sixth of
/// the candidates' simulations, each flight searched in pieces, for the baseline's answer).
/// The CLI asks this before any simulation, so that an empty list is an error about its own
/// flag.
pub fn applicable_effects(candidates: &[EffectKind], conditions: &[Condition]) -> (Vec<EffectKind>, Vec<String>) {
    let any_drag = conditions.iter().any(Condition::has_drag);
    let late = motion_past_the_flights_s();
    let inert_motion = !conditions.is_empty()
        && conditions
            .iter()
            .all(|c| c.motion.return_speed_m_s.is_some() && c.motion.delay_s.is_some_and(|d| d >= late));
    let (mut effects, mut notes) = (Vec::new(), Vec::new());
    for e in candidates {
        if e.needs_air() && !any_drag {
            notes.push(format!("{} skipped: it only changes drag, and every setup is in vacuum (k_drag 0)", e.name()));
        } else if *e == EffectKind::SledMotion && inert_motion {
            notes.push(format!(
                "sled-motion skipped: every setup states a sled that rests at least {late} s after the launch, past the \
                 flights, so the candidate is the baseline"
            ));
        } else {
            effects.push(*e);
        }
    }
    (effects, notes)
}

/// What the sled-motion candidate can and cannot use of the setups' stated motions.
fn sled_motion_notes(conditions: &[Condition]) -> Vec<String> {
    let mut notes = Vec::new();
    if !conditions.iter().any(|c| c.motion.any()) {
        notes.push(
            "sled-motion: no setup states the sled's motion (measurement.motion_delay_s, motion_return_speed_m_s); \
             its delay and return speed are fitted and shared by every condition"
                .to_string(),
        );
    }
    for (i, name) in ["motion_delay_s", "motion_return_speed_m_s"].iter().enumerate() {
        let mut labels: Vec<&str> = conditions
            .iter()
            .filter(|c| c.motion.get(i).is_none())
            .map(|c| c.motion_profile.as_deref().unwrap_or("unlabelled"))
            .collect();
        labels.sort_unstable();
        labels.dedup();
        if labels.len() > 1 {
            notes.push(format!(
                "sled-motion: conditions with different motion profiles ({}) share one fitted {name}; state the known \
                 value in each profile's setup",
                labels.join(", ")
            ));
        }
    }
    notes
}

/// Every condition's data fit for a diagnosis: at least two runs (their spread is the
/// measurement's uncertainty), no more teeth than the setup simulates, a scale resolution,
/// a recovered mass in every run.
fn check_conditions(conditions: &[Condition]) -> anyhow::Result<()> {
    if conditions.is_empty() {
        bail!("at least one measured condition is required");
    }
    for c in conditions {
        let n = c.runs.runs.len();
        if n < 2 {
            bail!("measured data {}: has {n} run(s); the diagnosis needs at least 2 (their spread is the measurement's uncertainty)", c.data);
        }
        if c.runs.teeth > c.teeth() {
            bail!(
                "measured data {} has {} teeth but the setup simulates only {} (sim.teeth): raise sim.teeth in {}",
                c.data,
                c.runs.teeth,
                c.teeth(),
                c.setup
            );
        }
        if !(c.resolution_g.is_finite() && c.resolution_g > 0.0) {
            bail!("{}: measurement.scale_resolution_g must be > 0, got {}", c.setup, c.resolution_g);
        }
        if c.runs.runs.iter().any(|r| r.recovered_g() <= 0.0) {
            bail!("measured data {}: every run needs a positive recovered mass", c.data);
        }
    }
    Ok(())
}

/// One diagnosis's inputs, checked, with the solver and targets every stage shares.
pub struct Run<'a> {
    /// The engine over the conditions: many (model, point) pairs as one engine call.
    pub sim: Simulator<'a>,
    /// The fits' solver: its `particles` are the full budget every gap is judged at.
    pub solver: Solver,
    /// Every condition's measured bins (all runs), as the fits compare them.
    pub targets: Vec<Target>,
    /// The parameters every model fits, shared by the conditions.
    pub shared: Vec<Param>,
    /// The candidate effects that can act on these setups.
    pub effects: Vec<EffectKind>,
    pub rescore_streams: usize,
    pub bootstrap: usize,
    pub seed: u64,
}

impl<'a> Run<'a> {
    /// Check the conditions and settings, and say what limits the answer before anything is
    /// simulated: the candidates left out, what the sled-motion candidate can use, a single
    /// condition's blind spot, a Monte-Carlo budget below what the data resolve.
    pub fn new(
        engine: &'a dyn BatchEvaluator,
        conditions: &'a [Condition],
        settings: &Settings,
    ) -> anyhow::Result<(Run<'a>, Vec<String>)> {
        check_conditions(conditions)?;
        if settings.bootstrap < 2 {
            bail!("settings.bootstrap (resamples) must be >= 2, got {}", settings.bootstrap);
        }
        if settings.rescore_streams < 1 {
            bail!("settings.rescore_streams must be >= 1, got 0");
        }
        let mut notes = Vec::new();
        let (effects, skipped) = applicable_effects(&settings.effects, conditions);
        notes.extend(skipped);
        if effects.is_empty() {
            bail!("settings.effects: {NO_EFFECT_APPLIES} ({})", notes.join("; "));
        }
        if effects.contains(&EffectKind::SledMotion) {
            notes.extend(sled_motion_notes(conditions));
        }
        if conditions.len() == 1 {
            notes.push(
                "single condition: a shift of the whole distribution cannot be separated from refitted collision/drag \
                 parameters; an effect is only identified by the shape it gives the distribution"
                    .to_string(),
            );
        }
        let (mut solver, budget_note) = settings.effort.solver(ObjectiveKind::Sse, conditions);
        notes.extend(budget_note);
        // the SSE is a sum of squares of the bins: Levenberg-Marquardt steps polish it with
        // a fraction of the compass search's simulations (docs/diagnosis-report.md, "Time")
        solver.polish_method = PolishMethod::LevenbergMarquardt;
        let run = Run {
            sim: Simulator { engine, conditions },
            solver,
            targets: conditions.iter().map(Condition::target_all).collect(),
            shared: settings.shared.clone().unwrap_or_else(|| shared_params(conditions)),
            effects,
            rescore_streams: settings.rescore_streams,
            bootstrap: settings.bootstrap,
            seed: settings.effort.seed,
        };
        Ok((run, notes))
    }

    pub fn conditions(&self) -> &'a [Condition] {
        self.sim.conditions
    }

    /// Particles per simulation at the full budget.
    pub fn particles(&self) -> u32 {
        self.solver.particles
    }
}
