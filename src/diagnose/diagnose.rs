//! `diagnose` (issue 5 §2): where the calibrated model misses measured data, which of the
//! optional effects ([`crate::model::effects`]) closes the gap on runs it was not fitted on,
//! and by how much.
//!
//! - **Conditions.** One or more measured campaigns, each with its own setup (geometry,
//!   kinematics, environment). They share the material and collision parameters being fitted:
//!   `k_elastic`, `mu_fric`, and `k_drag` when any setup has drag (applied only to the setups
//!   with drag). The joint objective is the sum over conditions of the SSE of Eq. 4.62 (the
//!   fit module's [`objective::sse_percent2`] over the teeth and a lost bin, against the mean
//!   distribution of the runs used).
//! - **Where.** The baseline (no effect) is fitted on all runs. Per condition and tooth: the
//!   residual sim − measured (percentage points) with an uncertainty combining, in
//!   quadrature, the run-to-run spread (sd of the run fractions / √n), the scale resolution
//!   (resolution/√12 per tooth relative to the mean recovered mass) and the simulation's
//!   Monte-Carlo error (√(p(1−p)/N)); z = residual / uncertainty, flagged when |z| > 2. The
//!   same for the centre of mass and the dispersion (Eq. 4.58-4.59; the sd of the per-run
//!   metric / √n and a Monte-Carlo term). And where the simulated mass comes from: per tooth,
//!   the share of launched particles that rest in the tooth of their first impact ("first
//!   flight") and the share that the bounce chain moved there from another tooth; and per
//!   third of the fill by launch depth below its free surface (`Fill::depth`), where that
//!   third's grains come to rest.
//! - **Which.** K-fold cross-validation over runs (run i of each condition, in file order,
//!   is in fold i mod K). For the baseline and every candidate effect the shared parameters
//!   and the effect's own ones are refitted on the training folds (GA, then a short bounded
//!   Nelder-Mead; an effect's fit also starts from the baseline's fold fit with the effect
//!   switched off, so a nested model is never fitted worse than the baseline; quadratic drag
//!   replaces the linear drag law, so it is not nested and has no such start, and sled
//!   motion stated by a setup stays on in that start), and the
//!   held-out folds' mean distributions are scored: the **held-out gap** is the SSE summed
//!   over conditions and folds. Every candidate sees the same particle streams (common
//!   random numbers: same seed and particle count, effect draws on their own counters).
//! - **Intervals.** A bootstrap over held-out runs: each replicate resamples, with
//!   replacement, the runs of every (condition, fold) cell (so runs are resampled within
//!   conditions and every fold keeps its size) and recomputes every model's held-out gap
//!   from the same predictions (paired across models). Intervals are the 5-95 % percentiles
//!   ([`INTERVAL`]); the standard error is the replicates' sd.
//! - **Ranking.** By the penalised score `held-out gap + 2 × (extra parameters) × SE` (the
//!   parameters beyond the baseline's: the effect's own, less k_drag for quadratic drag, which
//!   replaces the linear law and is fitted without it; SE its held-out gap's bootstrap standard error): an extra
//!   parameter must buy two standard errors of held-out improvement. `best` is the top-ranked
//!   effect only when it beats the baseline beyond the uncertainty: the baseline's held-out
//!   gap lies above the effect's interval and the paired bootstrap interval of the
//!   improvement (baseline − effect) lies above 0; otherwise `best` is null. Effects whose
//!   intervals overlap the top-ranked effect's are `indistinguishable` (the top one included
//!   when any other overlaps).
//! - **How far.** Per tooth, centre of mass and dispersion before and after the top-ranked
//!   effect, with bootstrap intervals over runs; and, when two candidates each beat the
//!   baseline, the two fitted together (GA starts from both single fits and the baseline),
//!   with paired intervals of its improvement over each alone. The combination is reported
//!   beside the ranking, not in it: `best` stays a single effect.
//! - **Known sled motion.** A setup may state the sled's motion after the launch
//!   ([measurement] `motion_delay_s`, `motion_return_speed_m_s`; e.g. the POC profile of Test
//!   1 returns at once at v_d ≈ 0.05 m/s, 5.3.1). The baseline and the other candidates
//!   ignore it, as the thesis's model does; the sled-motion candidate holds the stated values
//!   fixed for that condition and fits the ones left out, shared by the conditions that
//!   leave them out. Conditions that differ only in their motion are what identifies it.
//! - **Limits.** With one condition, a shift of the whole distribution cannot be told apart
//!   from refitted collision/drag parameters; the report says so. The Monte-Carlo noise of
//!   the fixed particle streams is part of every held-out gap (rerun with other `--seed`s).

use anyhow::{bail, Context as _};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde_json::{json, Map, Value};

use crate::engine::{evaluate_detailed, particle_engine, BatchEvaluator, EngineKind};
use crate::fit::{nelder_mead, objective, percentile, subset, MeasuredSummary, Param, Target};
use crate::io::measured::MeasuredRuns;
use crate::model::effects::{ImpactScatter, LaunchSpread, Polydisperse, QuadraticDrag, SledMotion};
use crate::model::outcome::{centre_and_dispersion, end_tooth, ParticleState};
use crate::model::{Design, Scenario};
use crate::optim::nsga2::{BatchProblem, Config, Evaluation as GaEvaluation, Mode, Nsga2};

/// Lower and upper percentile of every bootstrap interval.
pub const INTERVAL: (f64, f64) = (0.05, 0.95);

/// |z| above which a residual is flagged.
pub const Z_FLAG: f64 = 2.0;

/// A candidate effect with its own parameters and diagnosis bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EffectKind {
    ImpactScatter,
    LaunchSpread,
    Polydisperse,
    SledMotion,
    QuadraticDrag,
}

impl EffectKind {
    pub const ALL: [EffectKind; 5] =
        [EffectKind::ImpactScatter, EffectKind::LaunchSpread, EffectKind::Polydisperse, EffectKind::SledMotion, EffectKind::QuadraticDrag];

    /// The name on the command line and in the outputs.
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::ImpactScatter => "impact-scatter",
            EffectKind::LaunchSpread => "launch-spread",
            EffectKind::Polydisperse => "polydisperse",
            EffectKind::SledMotion => "sled-motion",
            EffectKind::QuadraticDrag => "quadratic-drag",
        }
    }

    /// The effect's parameters, as the config file names them.
    pub fn param_names(self) -> &'static [&'static str] {
        match self {
            EffectKind::ImpactScatter => &["sigma_deg"],
            EffectKind::LaunchSpread => &["speed_spread", "angle_sigma_deg"],
            EffectKind::Polydisperse => &["sigma_ln"],
            EffectKind::SledMotion => &["delay_s", "return_speed_m_s"],
            EffectKind::QuadraticDrag => &["diameter_m", "density_kg_m3"],
        }
    }

    /// Bounds of the effect's parameters in the diagnosis (inside `Effects::validate`'s).
    pub fn bounds(self) -> &'static [(f64, f64)] {
        match self {
            EffectKind::ImpactScatter => &[(0.0, 30.0)],
            EffectKind::LaunchSpread => &[(0.0, 0.9), (0.0, 30.0)],
            EffectKind::Polydisperse => &[(0.0, 1.2)],
            // a delay beyond the flights is the same as no motion; the POC's v_d is 0.05 m/s
            EffectKind::SledMotion => &[(0.0, 0.3), (0.01, 1.0)],
            // glass beads 100-200 µm, quartz sand 125-500 µm (4.3.6); soda-lime to quartz
            EffectKind::QuadraticDrag => &[(50e-6, 600e-6), (2000.0, 2700.0)],
        }
    }

    /// Parameters at which the effect does nothing (a nested baseline), where they exist:
    /// quadratic drag replaces the linear drag law, so no setting of it is the baseline; a
    /// sled-motion delay at its bound outlasts the rig's flights.
    pub fn neutral(self) -> Option<&'static [f64]> {
        match self {
            EffectKind::ImpactScatter => Some(&[0.0]),
            EffectKind::LaunchSpread => Some(&[0.0, 0.0]),
            EffectKind::Polydisperse => Some(&[0.0]),
            EffectKind::SledMotion => Some(&[0.3, 0.05]),
            EffectKind::QuadraticDrag => None,
        }
    }

    /// Switch the effect on in `s` with parameters `v` (the others are left as they are).
    pub fn apply(self, s: &mut Scenario, v: &[f64]) {
        match self {
            EffectKind::ImpactScatter => s.effects.impact_scatter = Some(ImpactScatter { sigma_deg: v[0] }),
            EffectKind::LaunchSpread => {
                s.effects.launch_spread = Some(LaunchSpread { speed_spread: v[0], angle_sigma_deg: v[1] })
            }
            EffectKind::Polydisperse => s.effects.polydisperse = Some(Polydisperse { sigma_ln: v[0] }),
            EffectKind::SledMotion => s.effects.sled_motion = Some(SledMotion { delay_s: v[0], return_speed_m_s: v[1] }),
            EffectKind::QuadraticDrag => {
                s.effects.quadratic_drag = Some(QuadraticDrag { diameter_m: v[0], density_kg_m3: v[1] })
            }
        }
    }

    pub fn from_name(name: &str) -> Option<EffectKind> {
        EffectKind::ALL.iter().copied().find(|e| e.name() == name)
    }
}

/// `all` or a comma list of effect names, each once.
pub fn parse_effects(list: &str) -> anyhow::Result<Vec<EffectKind>> {
    let known = || EffectKind::ALL.map(|e| e.name()).join(", ");
    if list.trim() == "all" {
        return Ok(EffectKind::ALL.to_vec());
    }
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim) {
        let Some(e) = EffectKind::from_name(name) else {
            bail!("--effects: unknown effect `{name}` (known: all, {})", known());
        };
        if out.contains(&e) {
            bail!("--effects: effect `{name}` given twice");
        }
        out.push(e);
    }
    Ok(out)
}

/// What a setup states of the sled's motion after the launch ([measurement]
/// motion_delay_s, motion_return_speed_m_s): the sled-motion candidate holds these fixed for
/// the condition and fits the values left out.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KnownMotion {
    pub delay_s: Option<f64>,
    pub return_speed_m_s: Option<f64>,
}

impl KnownMotion {
    fn get(&self, i: usize) -> Option<f64> {
        [self.delay_s, self.return_speed_m_s][i]
    }
    pub fn any(&self) -> bool {
        self.delay_s.is_some() || self.return_speed_m_s.is_some()
    }
}

/// One measured condition: runs and the setup they were measured with.
#[derive(Clone, Debug)]
pub struct Condition {
    /// Short name (the data file's stem).
    pub name: String,
    pub data: String,
    pub setup: String,
    pub runs: MeasuredRuns,
    /// The setup's scenario with the diagnosis's particle count and seed, effects off.
    pub base: Scenario,
    pub design: Design,
    pub resolution_g: f64,
    /// The sled's motion as far as the setup knows it.
    pub motion: KnownMotion,
    /// The setup's motion-profile label (`poc`, `delayed`), if any.
    pub motion_profile: Option<String>,
}

impl Condition {
    pub fn teeth(&self) -> usize {
        self.base.sim.teeth as usize
    }
    fn has_drag(&self) -> bool {
        self.base.environment.k_drag.is_some()
    }
    fn target(&self, idx: &[usize]) -> Target {
        Target::new(&subset(&self.runs, idx), self.teeth(), self.resolution_g)
    }
}

/// The shared parameters the conditions call for: k_elastic, mu_fric, and k_drag when any
/// setup has drag.
pub fn shared_params(conditions: &[Condition]) -> Vec<Param> {
    let mut p = vec![Param::KElastic, Param::MuFric];
    if conditions.iter().any(Condition::has_drag) {
        p.push(Param::KDrag);
    }
    p
}

/// The joint simulation problem of one model (the baseline when `effect` is None).
pub struct Joint<'a> {
    pub engine: &'a dyn BatchEvaluator,
    pub conditions: &'a [Condition],
    pub shared: Vec<Param>,
    /// The effects switched on (none for the baseline, two for a combination).
    pub effects: Vec<EffectKind>,
    /// The effects' fitted parameters, as (index into `effects`, parameter index): all of
    /// them, except sled-motion values that every setup states (`KnownMotion`).
    pub effect_free: Vec<(usize, usize)>,
}

impl<'a> Joint<'a> {
    pub fn new(engine: &'a dyn BatchEvaluator, conditions: &'a [Condition], mut shared: Vec<Param>, effects: &[EffectKind]) -> Self {
        if effects.contains(&EffectKind::QuadraticDrag) {
            // Schiller-Naumann drag replaces the linear law: k_drag would be a dead parameter
            // (the setups' own value only marks which of them are in air)
            shared.retain(|p| *p != Param::KDrag);
        }
        let mut effect_free = Vec::new();
        for (k, e) in effects.iter().enumerate() {
            for i in 0..e.bounds().len() {
                let stated_everywhere = *e == EffectKind::SledMotion && conditions.iter().all(|c| c.motion.get(i).is_some());
                if !stated_everywhere {
                    effect_free.push((k, i));
                }
            }
        }
        Joint { engine, conditions, shared, effects: effects.to_vec(), effect_free }
    }

    pub fn dim(&self) -> usize {
        self.shared.len() + self.effect_free.len()
    }

    pub fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        let mut b: Vec<(f64, f64)> = self.shared.iter().map(|p| p.bounds()).collect();
        b.extend(self.effect_free.iter().map(|(k, i)| self.effects[*k].bounds()[*i]));
        b.into_iter().unzip()
    }

    /// Parameter names, shared first (effect parameter names are unique across effects).
    pub fn names(&self) -> Vec<&'static str> {
        let mut n: Vec<&'static str> = self.shared.iter().map(|p| p.name()).collect();
        n.extend(self.effect_free.iter().map(|(k, i)| self.effects[*k].param_names()[*i]));
        n
    }

    /// A start for this model from another model's point (`names`, `x`): each parameter
    /// takes the other model's value where it has one, an effect parameter the other lacks
    /// its neutral value (`EffectKind::neutral`). From the baseline that is the baseline
    /// itself (a nested model) unless a setup states its sled motion, which stays on; none
    /// when a parameter has no such value (quadratic drag).
    pub fn start_from(&self, names: &[&'static str], x: &[f64]) -> Option<Vec<f64>> {
        let own = self.names();
        let mut v = Vec::with_capacity(own.len());
        for (j, n) in own.iter().enumerate() {
            if let Some(p) = names.iter().position(|m| m == n) {
                v.push(x[p]);
            } else if j >= self.shared.len() {
                let (k, i) = self.effect_free[j - self.shared.len()];
                v.push(self.effects[k].neutral()?[i]);
            } else {
                return None;
            }
        }
        Some(v)
    }

    /// Condition `c`'s scenario at parameters `x` (k_drag only where the setup has drag).
    pub fn scenario_at(&self, c: usize, x: &[f64]) -> Scenario {
        let cond = &self.conditions[c];
        let mut s = cond.base.clone();
        for (p, v) in self.shared.iter().zip(x) {
            if *p == Param::KDrag && !cond.has_drag() {
                continue;
            }
            p.apply(&mut s, *v);
        }
        for (k, e) in self.effects.iter().enumerate() {
            let e = *e;
            // the effect's full parameter vector: fitted values, then what the setup states
            let mut v: Vec<f64> = e.bounds().iter().map(|b| b.0).collect();
            for ((ek, i), xv) in self.effect_free.iter().zip(&x[self.shared.len()..]) {
                if *ek == k {
                    v[*i] = *xv;
                }
            }
            if e == EffectKind::SledMotion {
                for (i, vi) in v.iter_mut().enumerate() {
                    if let Some(known) = cond.motion.get(i) {
                        *vi = known;
                    }
                }
            }
            e.apply(&mut s, &v);
        }
        s
    }

    /// Simulated bins (teeth, then lost) of every condition; None when one is rejected.
    pub fn bins_at(&self, x: &[f64]) -> Option<Vec<Vec<f64>>> {
        (0..self.conditions.len())
            .map(|c| {
                let s = self.scenario_at(c, x);
                self.engine
                    .evaluate(&s, std::slice::from_ref(&self.conditions[c].design))
                    .pop()
                    .and_then(|r| r.ok())
                    .map(|e| objective::simulated_bins(&e.sim))
            })
            .collect()
    }

    fn unit_to_params(&self, u: &[f64]) -> Vec<f64> {
        let (lo, hi) = self.bounds();
        u.iter().zip(lo.iter().zip(&hi)).map(|(u, (l, h))| l + u.clamp(0.0, 1.0) * (h - l)).collect()
    }

    fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        let (lo, hi) = self.bounds();
        x.iter().zip(lo.iter().zip(&hi)).map(|(x, (l, h))| if h > l { ((x - l) / (h - l)).clamp(0.0, 1.0) } else { 0.0 }).collect()
    }
}

/// The joint objective: Σ over conditions of the SSE (%²); +inf when not simulable.
pub fn joint_sse(bins: Option<&[Vec<f64>]>, targets: &[Target]) -> f64 {
    match bins {
        None => f64::INFINITY,
        Some(b) => b.iter().zip(targets).map(|(b, t)| t.sse(b)).sum(),
    }
}

/// Optimiser budget of one fit.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    pub pop: usize,
    pub generations: u64,
    /// Nelder-Mead evaluations of the polish.
    pub polish: usize,
    pub seed: u64,
}

/// One joint fit.
#[derive(Clone, Debug)]
pub struct JointFit {
    pub x: Vec<f64>,
    /// The joint training SSE, %².
    pub value: f64,
    /// Simulated bins per condition at `x`.
    pub bins: Vec<Vec<f64>>,
    pub evaluations: u64,
}

struct JointGa<'p, 'a> {
    joint: &'p Joint<'a>,
    targets: &'p [Target],
    best: Option<(f64, Vec<f64>, Vec<Vec<f64>>)>,
}

impl BatchProblem for JointGa<'_, '_> {
    fn dim(&self) -> usize {
        self.joint.dim()
    }
    fn n_objectives(&self) -> usize {
        1
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        self.joint.bounds()
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], _generation: u64) -> Vec<GaEvaluation> {
        let bins: Vec<Option<Vec<Vec<f64>>>> = xs.par_iter().map(|x| self.joint.bins_at(x)).collect();
        let mut out = Vec::with_capacity(xs.len());
        for (x, b) in xs.iter().zip(bins) {
            let v = joint_sse(b.as_deref(), self.targets);
            if let Some(b) = b {
                if self.best.as_ref().is_none_or(|(bv, _, _)| v < *bv) {
                    self.best = Some((v, x.clone(), b));
                }
            }
            out.push(GaEvaluation { objectives: vec![v], violation: 0.0 });
        }
        out
    }
}

/// Fit the joint model to `targets` (one per condition): the GA, the extra `starts` (e.g. a
/// nested model's optimum), then a bounded Nelder-Mead polish from the best point found.
pub fn fit_joint(joint: &Joint, targets: &[Target], budget: Budget, starts: &[Vec<f64>]) -> anyhow::Result<JointFit> {
    if budget.pop < 4 {
        bail!("--pop must be >= 4, got {}", budget.pop);
    }
    let ga = Nsga2::new(Config {
        pop: budget.pop,
        seed: budget.seed,
        max_generations: budget.generations,
        mode: Mode::Standard,
        ..Config::default()
    });
    let mut gp = JointGa { joint, targets, best: None };
    let (state, _) = ga.run(&mut gp, |_, _| {});
    let mut evaluations = state.evaluations;
    if !starts.is_empty() {
        gp.evaluate_batch(starts, 0);
        evaluations += starts.len() as u64;
    }
    let Some((value, x, bins)) = gp.best else {
        bail!("no candidate could be simulated (every evaluation was rejected by the engine)");
    };
    let m = nelder_mead::minimise(
        |u| joint_sse(joint.bins_at(&joint.unit_to_params(u)).as_deref(), targets),
        &joint.to_unit(&x),
        0.05,
        budget.polish,
        1e-4,
    );
    evaluations += m.evaluations as u64;
    if m.value < value {
        let xp = joint.unit_to_params(&m.x);
        if let Some(bp) = joint.bins_at(&xp) {
            return Ok(JointFit { x: xp, value: m.value, bins: bp, evaluations: evaluations + 1 });
        }
    }
    Ok(JointFit { x, value, bins, evaluations })
}

/// Settings of a diagnosis.
#[derive(Clone, Debug)]
pub struct Settings {
    pub effects: Vec<EffectKind>,
    pub folds: usize,
    pub budget: Budget,
    pub bootstrap: usize,
}

/// One model's cross-validated result.
#[derive(Clone, Debug)]
pub struct ModelResult {
    /// The effects switched on: none for the baseline, one for a candidate, two for the
    /// combination of the two best.
    pub effects: Vec<EffectKind>,
    pub names: Vec<&'static str>,
    /// Fit on all runs.
    pub full: JointFit,
    /// Per fold: the training fit's parameters.
    pub fold_params: Vec<Vec<f64>>,
    /// Predictions `[condition][fold]` (bins) of the fold's training fit.
    pub predictions: Vec<Vec<Vec<f64>>>,
    /// Held-out gap: SSE summed over conditions and folds, %².
    pub heldout: f64,
    /// Held-out gap per condition, %².
    pub heldout_by_condition: Vec<f64>,
    /// Bootstrap replicates of the held-out gap.
    pub replicates: Vec<f64>,
    pub interval: [f64; 2],
    /// Bootstrap standard error of the held-out gap.
    pub se: f64,
    /// Paired bootstrap interval of (baseline − this model)'s held-out gap.
    pub improvement_interval: [f64; 2],
    /// Extra parameters over the baseline.
    pub extra_params: usize,
    /// Held-out gap + 2 × extra parameters × SE.
    pub score: f64,
    pub evaluations: u64,
}

/// A model's name: `baseline`, an effect's name, or the effects' names joined by `+`.
fn model_name(effects: &[EffectKind]) -> String {
    if effects.is_empty() {
        "baseline".into()
    } else {
        effects.iter().map(|e| e.name()).collect::<Vec<_>>().join("+")
    }
}

/// Paired bootstrap interval of `a`'s held-out gap minus `b`'s (the replicates share their
/// resamples, `bootstrap_heldout`): above 0 when `b` improves on `a`.
fn paired_interval(a: &ModelResult, b: &ModelResult) -> [f64; 2] {
    let d: Vec<f64> = a.replicates.iter().zip(&b.replicates).map(|(x, y)| x - y).collect();
    interval(&d)
}

impl ModelResult {
    pub fn name(&self) -> String {
        model_name(&self.effects)
    }
    /// The candidate effect, when this is a one-effect model.
    pub fn single(&self) -> Option<EffectKind> {
        match self.effects[..] {
            [e] => Some(e),
            _ => None,
        }
    }
    pub fn params_object(&self) -> Value {
        let mut m = Map::new();
        for (n, v) in self.names.iter().zip(&self.full.x) {
            m.insert((*n).to_string(), num(*v));
        }
        Value::Object(m)
    }
}

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
        let z = if u > 0.0 { residual / u } else if residual == 0.0 { 0.0 } else { f64::INFINITY.copysign(residual) };
        Residual { measured, simulated, residual, uncertainty: u, parts, z }
    }
    pub fn flagged(&self) -> bool {
        self.z.abs() > Z_FLAG
    }
    fn json(&self) -> Value {
        json!({
            "measured": num(self.measured),
            "simulated": num(self.simulated),
            "residual": num(self.residual),
            "uncertainty": num(self.uncertainty),
            "uncertainty_parts": {"run_to_run": num(self.parts[0]), "scale": num(self.parts[1]), "monte_carlo": num(self.parts[2])},
            "z": num(self.z),
            "flag": self.flagged(),
        })
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

/// The simulated grains launched from one layer of the fill (equal particle counts, by depth
/// below the fill's free surface) and where they come to rest.
#[derive(Clone, Debug)]
pub struct DepthLayer {
    pub label: &'static str,
    /// Depths of the layer's launch points below the fill surface, min and max, mm.
    pub depth_mm: [f64; 2],
    pub particles: usize,
    /// Per shown tooth, % of the layer's particles resting there.
    pub teeth_percent: Vec<f64>,
    /// % of the layer's particles resting beyond the shown teeth or lost.
    pub further_or_lost_percent: f64,
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
    pub notes: Vec<String>,
    pub particles: u32,
    pub engine: String,
}

/// The two best effects switched on together.
#[derive(Clone, Debug)]
pub struct Combined {
    /// Its `improvement_interval` is against the baseline.
    pub model: ModelResult,
    /// Per effect of the pair (in `model.effects` order): paired bootstrap interval of
    /// (that effect alone − the combination)'s held-out gap, %².
    pub improvement_over_singles: Vec<[f64; 2]>,
}

impl Diagnosis {
    /// The effect the "how far" section uses: `best`, else the top-ranked one.
    pub fn gap_model(&self) -> Option<&ModelResult> {
        self.ranking.first()
    }
}

fn fold_indices(n: usize, k: usize, fold: usize) -> (Vec<usize>, Vec<usize>) {
    (0..n).partition(|i| i % k != fold)
}

/// JSON numbers cannot be NaN/inf: those become null.
pub fn num(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

fn sample_sd(v: &[f64]) -> f64 {
    let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.len() < 2 {
        return f64::NAN;
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

fn interval(v: &[f64]) -> [f64; 2] {
    [percentile(v, INTERVAL.0), percentile(v, INTERVAL.1)]
}

/// Cross-validate one model: the fit on all runs and the K training fits.
fn cross_validate(
    joint: &Joint,
    k: usize,
    budget: Budget,
    start_models: &[&ModelResult],
    log: &mut dyn FnMut(String),
) -> anyhow::Result<ModelResult> {
    let conds = joint.conditions;
    // parameters beyond the baseline's (quadratic drag trades k_drag for its own two)
    let extra = joint.dim().saturating_sub(shared_params(conds).len());
    // extra GA starts: the given models' points carried over (`Joint::start_from`), e.g. the
    // baseline's with the effect switched off
    let starts_at = |x_of: &dyn Fn(&ModelResult) -> &[f64]| -> Vec<Vec<f64>> {
        start_models.iter().filter_map(|m| joint.start_from(&m.names, x_of(m))).collect()
    };
    let all_targets: Vec<Target> = conds.iter().map(|c| c.target(&(0..c.runs.runs.len()).collect::<Vec<_>>())).collect();
    let starts = starts_at(&|m| &m.full.x);
    let full = fit_joint(joint, &all_targets, budget, &starts)?;
    let mut evaluations = full.evaluations;
    let mut fold_params = Vec::with_capacity(k);
    let mut predictions = vec![Vec::with_capacity(k); conds.len()];
    for f in 0..k {
        let targets: Vec<Target> = conds.iter().map(|c| c.target(&fold_indices(c.runs.runs.len(), k, f).0)).collect();
        // the start models' fold fits (never their full fits: those have seen the held-out runs)
        let starts = starts_at(&|m| &m.fold_params[f]);
        let b = Budget { seed: budget.seed.wrapping_add(1 + f as u64), ..budget };
        let fit = fit_joint(joint, &targets, b, &starts)?;
        evaluations += fit.evaluations;
        for (c, bins) in fit.bins.into_iter().enumerate() {
            predictions[c].push(bins);
        }
        fold_params.push(fit.x);
    }
    let mut heldout_by_condition = vec![0.0; conds.len()];
    for (c, cond) in conds.iter().enumerate() {
        for (f, pred) in predictions[c].iter().enumerate() {
            heldout_by_condition[c] += cond.target(&fold_indices(cond.runs.runs.len(), k, f).1).sse(pred);
        }
    }
    let heldout = heldout_by_condition.iter().sum();
    let name = model_name(&joint.effects);
    log(format!("diagnose: {name}: in-sample SSE {:.1} %², held-out gap {heldout:.1} %²", full.value));
    Ok(ModelResult {
        effects: joint.effects.clone(),
        names: joint.names(),
        full,
        fold_params,
        predictions,
        heldout,
        heldout_by_condition,
        replicates: Vec::new(),
        interval: [f64::NAN; 2],
        se: f64::NAN,
        improvement_interval: [f64::NAN; 2],
        extra_params: extra,
        score: f64::NAN,
        evaluations,
    })
}

/// The bootstrap replicates of every model's held-out gap (paired: one resample for all; the
/// resamples depend only on `seed`, the conditions and `k`, so calls with the same ones pair
/// their models too).
fn bootstrap_heldout(conds: &[Condition], k: usize, models: &mut [ModelResult], replicates: usize, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xD1A6_0005);
    for m in models.iter_mut() {
        m.replicates = Vec::with_capacity(replicates);
    }
    for _ in 0..replicates {
        let mut totals = vec![0.0; models.len()];
        for (c, cond) in conds.iter().enumerate() {
            for f in 0..k {
                let held = fold_indices(cond.runs.runs.len(), k, f).1;
                let idx: Vec<usize> = (0..held.len()).map(|_| held[rng.random_range(0..held.len())]).collect();
                let t = cond.target(&idx);
                for (m, total) in models.iter().zip(totals.iter_mut()) {
                    *total += t.sse(&m.predictions[c][f]);
                }
            }
        }
        for (m, t) in models.iter_mut().zip(totals) {
            m.replicates.push(t);
        }
    }
    for m in models.iter_mut() {
        m.interval = interval(&m.replicates);
        m.se = sample_sd(&m.replicates);
        m.score = m.heldout + 2.0 * m.extra_params as f64 * if m.se.is_finite() { m.se } else { 0.0 };
    }
}

/// Where the baseline misses, in one condition.
fn where_condition(cond: &Condition, scenario: &Scenario, bins: &[f64], particles: u32) -> anyhow::Result<WhereCondition> {
    let teeth = cond.teeth();
    let runs = &cond.runs;
    let n = runs.runs.len() as f64;
    let measured = objective::measured_bins(&runs.mean_fractions(), teeth);
    let summary = MeasuredSummary::new(runs, teeth);
    let mean_recovered = runs.runs.iter().map(|r| r.recovered_g()).sum::<f64>() / n;
    let scale = 100.0 * cond.resolution_g / 12f64.sqrt() / mean_recovered;
    let np = particles.max(1) as f64;
    let last_sim = bins[..teeth].iter().rposition(|p| *p >= 0.005).map_or(0, |i| i + 1);
    let shown = runs.teeth.max(last_sim).clamp(1, teeth);
    let mut teeth_residuals = Vec::with_capacity(shown + 1);
    for j in (0..shown).chain(std::iter::once(teeth)) {
        let sd = if j < teeth { summary.sd[j] } else { 0.0 };
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
        (0..=teeth)
            .map(|j| interval(&reps.iter().map(|r| 100.0 * (sim[j] - r[j])).collect::<Vec<_>>()))
            .collect()
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
        let mut labels: Vec<&str> =
            conditions.iter().filter(|c| c.motion.get(i).is_none()).map(|c| c.motion_profile.as_deref().unwrap_or("unlabelled")).collect();
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

/// Run the diagnosis. `log` receives progress lines.
pub fn diagnose(
    engine: &dyn BatchEvaluator,
    conditions: Vec<Condition>,
    settings: Settings,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Diagnosis> {
    if conditions.is_empty() {
        bail!("--data/--setup: at least one condition is required");
    }
    let k = settings.folds;
    if k < 2 {
        bail!("--folds must be >= 2, got {k}");
    }
    for c in &conditions {
        let n = c.runs.runs.len();
        if n < k {
            bail!("--folds {k}: {} has only {n} runs (every fold needs at least one held-out run)", c.data);
        }
        if c.runs.teeth > c.teeth() {
            bail!(
                "--data {} has {} teeth but the setup simulates only {} (sim.teeth): raise sim.teeth in {}",
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
            bail!("--data {}: every run needs a positive recovered mass", c.data);
        }
    }
    if settings.bootstrap < 2 {
        bail!("--bootstrap must be >= 2, got {}", settings.bootstrap);
    }
    let mut notes = Vec::new();
    let any_drag = conditions.iter().any(Condition::has_drag);
    let mut effects = Vec::new();
    for e in &settings.effects {
        if matches!(*e, EffectKind::Polydisperse | EffectKind::QuadraticDrag) && !any_drag {
            notes.push(format!("{} skipped: it only changes drag, and every setup is in vacuum (k_drag 0)", e.name()));
        } else {
            effects.push(*e);
        }
    }
    if effects.is_empty() {
        bail!("--effects: no candidate effect applies to these setups");
    }
    if effects.contains(&EffectKind::SledMotion) {
        notes.extend(sled_motion_notes(&conditions));
    }
    if conditions.len() == 1 {
        notes.push(
            "single condition: a shift of the whole distribution cannot be separated from refitted collision/drag \
             parameters; an effect is only identified by the shape it gives the distribution"
                .to_string(),
        );
    }
    let shared = shared_params(&conditions);
    let budget = settings.budget;
    let particles = conditions[0].base.sim.particles;
    let joint_for = |effects: &[EffectKind]| Joint::new(engine, &conditions, shared.clone(), effects);

    log(format!("diagnose: baseline ({} conditions, {k} folds)", conditions.len()));
    let base = cross_validate(&joint_for(&[]), k, budget, &[], log)?;
    let mut models = vec![base];
    for e in &effects {
        log(format!("diagnose: {}", e.name()));
        let m = cross_validate(&joint_for(&[*e]), k, budget, &[&models[0]], log)?;
        models.push(m);
    }
    bootstrap_heldout(&conditions, k, &mut models, settings.bootstrap, budget.seed);
    let mut models = models.into_iter();
    let mut baseline = models.next().context("no baseline")?;
    baseline.improvement_interval = [0.0, 0.0];
    let mut ranking: Vec<ModelResult> = models.collect();
    for m in ranking.iter_mut() {
        m.improvement_interval = paired_interval(&baseline, m);
    }
    ranking.sort_by(|a, b| a.score.total_cmp(&b.score).then(a.heldout.total_cmp(&b.heldout)));
    let top = ranking.first().context("no effect ranked")?;
    let best = (baseline.heldout > top.interval[1] && top.improvement_interval[0] > 0.0 && top.heldout < baseline.heldout)
        .then_some(top.single())
        .flatten();
    let overlaps = |a: [f64; 2], b: [f64; 2]| a[0] <= b[1] && b[0] <= a[1];
    let others: Vec<EffectKind> =
        ranking[1..].iter().filter(|m| overlaps(m.interval, top.interval)).filter_map(|m| m.single()).collect();
    let indistinguishable = if others.is_empty() {
        Vec::new()
    } else {
        std::iter::once(top.single()).flatten().chain(others).collect()
    };

    // How far two effects go together: the two best candidates that each beat the baseline
    // beyond the uncertainty, refitted jointly from both single fits (and the baseline's).
    let beating: Vec<&ModelResult> = ranking.iter().filter(|m| m.improvement_interval[0] > 0.0 && m.heldout < baseline.heldout).take(2).collect();
    let combined = if best.is_some() && beating.len() == 2 {
        let pair: Vec<EffectKind> = beating.iter().filter_map(|m| m.single()).collect();
        log(format!("diagnose: {} together", pair.iter().map(|e| e.name()).collect::<Vec<_>>().join(" + ")));
        let mut m = cross_validate(&joint_for(&pair), k, budget, &[beating[0], beating[1], &baseline], log)?;
        // the resamples depend only on the seed, conditions and folds, so bootstrapping the
        // pair alone pairs it with the models bootstrapped above
        bootstrap_heldout(&conditions, k, std::slice::from_mut(&mut m), settings.bootstrap, budget.seed);
        m.improvement_interval = paired_interval(&baseline, &m);
        let improvement_over_singles = beating.iter().map(|single| paired_interval(single, &m)).collect();
        Some(Combined { model: m, improvement_over_singles })
    } else {
        None
    };

    let base_joint = joint_for(&[]);
    let mut where_ = Vec::new();
    let mut gap = Vec::new();
    for (c, cond) in conditions.iter().enumerate() {
        let s = base_joint.scenario_at(c, &baseline.full.x);
        where_.push(where_condition(cond, &s, &baseline.full.bins[c], particles)?);
        gap.push(gap_condition(cond, &baseline.full.bins[c], &top.full.bins[c], settings.bootstrap, budget.seed));
    }
    Ok(Diagnosis {
        shared,
        settings: Settings { effects, ..settings },
        baseline,
        ranking,
        best,
        indistinguishable,
        combined,
        where_,
        gap,
        notes,
        particles,
        engine: engine.backend().to_string(),
        conditions,
    })
}

/// The `diagnosis.json` object.
pub fn to_json(d: &Diagnosis) -> Value {
    let b = &d.baseline;
    let top = d.gap_model();
    let where_conditions: Vec<Value> = d
        .conditions
        .iter()
        .zip(&d.where_)
        .map(|(c, w)| {
            let teeth: Vec<Value> = w
                .teeth_residuals
                .iter()
                .enumerate()
                .map(|(j, r)| {
                    let mut v = r.json();
                    let o = v.as_object_mut().expect("object");
                    if j < w.shown_teeth {
                        o.insert("tooth".into(), json!(j + 1));
                        o.insert("first_flight".into(), num(w.first_flight[j]));
                        o.insert("bounce_chain".into(), num(w.bounce_chain[j]));
                    } else {
                        o.insert("tooth".into(), json!("lost"));
                    }
                    v
                })
                .collect();
            json!({
                "name": c.name,
                "data": c.data,
                "setup": c.setup,
                "runs": c.runs.runs.len(),
                "motion_profile": c.motion_profile,
                "stated_motion": {"delay_s": c.motion.delay_s, "return_speed_m_s": c.motion.return_speed_m_s},
                "teeth": teeth,
                "centre_of_mass": w.centre.json(),
                "dispersion": w.dispersion.json(),
                "simulated_lost_percent": num(w.lost_percent),
                "first_flight_percent": num(w.first_flight.iter().sum()),
                "bounce_chain_percent": num(w.bounce_chain.iter().sum()),
                "launch_depth": w.launch_depth.iter().map(|l| json!({
                    "layer": l.label,
                    "depth_mm": [num(l.depth_mm[0]), num(l.depth_mm[1])],
                    "particles": l.particles,
                    "teeth_percent": l.teeth_percent.iter().map(|v| num(*v)).collect::<Vec<_>>(),
                    "further_or_lost_percent": num(l.further_or_lost_percent),
                })).collect::<Vec<_>>(),
                "flagged_teeth": w.teeth_residuals[..w.shown_teeth].iter().enumerate().filter(|(_, r)| r.flagged()).map(|(j, _)| j + 1).collect::<Vec<_>>(),
            })
        })
        .collect();
    let ranking: Vec<Value> = d
        .ranking
        .iter()
        .map(|m| {
            json!({
                "effect": m.name(),
                "heldout_gap": num(m.heldout),
                "reduction": num(1.0 - m.heldout / b.heldout),
                "interval": [num(m.interval[0]), num(m.interval[1])],
                "improvement_interval": [num(m.improvement_interval[0]), num(m.improvement_interval[1])],
                "extra_params": m.extra_params,
                "score": num(m.score),
                "params": m.params_object(),
            })
        })
        .collect();
    let gap = match top {
        Some(t) => {
            let conditions: Vec<Value> = d
                .conditions
                .iter()
                .zip(&d.gap)
                .zip(&d.where_)
                .map(|((c, g), w)| {
                    let teeth = c.teeth();
                    let rows: Vec<Value> = (0..w.shown_teeth)
                        .chain(std::iter::once(teeth))
                        .map(|j| {
                            json!({
                                "tooth": if j < teeth { json!(j + 1) } else { json!("lost") },
                                "measured": num(100.0 * g.measured[j]),
                                "before": num(100.0 * g.before[j]),
                                "after": num(100.0 * g.after[j]),
                                "residual_before": num(100.0 * (g.before[j] - g.measured[j])),
                                "residual_before_interval": [num(g.before_interval[j][0]), num(g.before_interval[j][1])],
                                "residual_after": num(100.0 * (g.after[j] - g.measured[j])),
                                "residual_after_interval": [num(g.after_interval[j][0]), num(g.after_interval[j][1])],
                            })
                        })
                        .collect();
                    json!({
                        "name": c.name,
                        "teeth": rows,
                        "centre_of_mass": {"measured": num(g.centre[0]), "measured_interval": [num(g.centre_interval[0]), num(g.centre_interval[1])], "before": num(g.centre[1]), "after": num(g.centre[2])},
                        "dispersion": {"measured": num(g.dispersion[0]), "measured_interval": [num(g.dispersion_interval[0]), num(g.dispersion_interval[1])], "before": num(g.dispersion[1]), "after": num(g.dispersion[2])},
                    })
                })
                .collect();
            json!({
                "effect": t.name(),
                "is_best": d.best.is_some(),
                "heldout_before": num(b.heldout),
                "heldout_before_interval": [num(b.interval[0]), num(b.interval[1])],
                "heldout_after": num(t.heldout),
                "heldout_after_interval": [num(t.interval[0]), num(t.interval[1])],
                "reduction": num(1.0 - t.heldout / b.heldout),
                "improvement_interval": [num(t.improvement_interval[0]), num(t.improvement_interval[1])],
                "in_sample_before": num(b.full.value),
                "in_sample_after": num(t.full.value),
                "conditions": conditions,
                "notes": d.notes,
            })
        }
        None => json!({"notes": d.notes}),
    };
    let scores: Map<String, Value> = d.ranking.iter().map(|m| (m.name().to_string(), num(m.score))).collect();
    json!({
        "gap": gap,
        "ranking": ranking,
        "best": d.best.map(|e| e.name()),
        "indistinguishable": d.indistinguishable.iter().map(|e| e.name()).collect::<Vec<_>>(),
        "combined": d.combined.as_ref().map(|cb| json!({
            "effects": cb.model.effects.iter().map(|e| e.name()).collect::<Vec<_>>(),
            "heldout_gap": num(cb.model.heldout),
            "interval": [num(cb.model.interval[0]), num(cb.model.interval[1])],
            "reduction": num(1.0 - cb.model.heldout / d.baseline.heldout),
            "improvement_interval": [num(cb.model.improvement_interval[0]), num(cb.model.improvement_interval[1])],
            "improvement_over_singles": cb.model.effects.iter().zip(&cb.improvement_over_singles).map(|(e, i)| json!({"effect": e.name(), "interval": [num(i[0]), num(i[1])]})).collect::<Vec<_>>(),
            "params": cb.model.params_object(),
            "in_sample_sse": num(cb.model.full.value),
            "bins": cb.model.full.bins,
        })),
        "baseline": {
            "params": b.params_object(),
            "in_sample_sse": num(b.full.value),
            "heldout_gap": num(b.heldout),
            "interval": [num(b.interval[0]), num(b.interval[1])],
            "se": num(b.se),
            "folds": d.settings.folds,
            "bootstrap": d.settings.bootstrap,
            "interval_percentiles": [INTERVAL.0, INTERVAL.1],
            "particles": d.particles,
            "engine": d.engine,
            "shared_params": d.shared.iter().map(|p| p.name()).collect::<Vec<_>>(),
            "ranking_rule": "score = heldout_gap + 2 x (extra parameters) x bootstrap SE of the held-out gap",
            "scores": scores,
            "heldout_by_condition": d.conditions.iter().zip(&b.heldout_by_condition).map(|(c, v)| (c.name.clone(), num(*v))).collect::<Map<String, Value>>(),
        },
        "where": {
            "params": b.params_object(),
            "in_sample_sse": num(b.full.value),
            "conditions": where_conditions,
            "z_flag": Z_FLAG,
        },
    })
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
