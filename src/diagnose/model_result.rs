//! What one fitted model of a diagnosis leaves ([`ModelResult`]) and where the grains of each
//! layer of the fill come to rest ([`DepthLayer`]): the vocabulary
//! that the diagnosis (`diagnose`) builds and its verdict (`verdict`) judges, in a module of
//! its own so that neither of the two imports the other.

use crate::calibrate::Fit;
use crate::model::effects::EffectKind;

/// |z| above which a residual is flagged.
pub const Z_FLAG: f64 = 2.0;

/// One model's result.
#[derive(Clone, Debug)]
pub struct ModelResult {
    /// The effects switched on: none for the baseline, one for a candidate, two for the
    /// combination of the two best.
    pub effects: Vec<EffectKind>,
    pub names: Vec<&'static str>,
    /// The fit on all runs (its SSE is on the particle streams it was fitted with).
    pub full: Fit,
    /// `[stream][condition]` bins at the fitted parameters with fresh particle streams.
    pub fresh: Vec<Vec<Vec<f64>>>,
    /// The gap: the joint SSE (%², all runs, loss-adjusted) of the fitted model's mean bins
    /// over its fresh streams. Fresh streams remove the fit's adaptation to its own
    /// Monte-Carlo noise, which flatters a model with more parameters; their mean has 1/streams
    /// of one stream's Monte-Carlo variance, which an SSE adds to every model's gap.
    pub gap: f64,
    pub gap_by_condition: Vec<f64>,
    /// Bootstrap replicates of the gap: the runs resampled within conditions and the fresh
    /// streams resampled (their mean's Monte-Carlo spread), paired across models.
    pub replicates: Vec<f64>,
    /// The same replicates with one source of noise at a time: the runs resampled, the
    /// streams' mean held; the streams resampled, all runs held. What part of an interval's
    /// width is the data's and what part the simulation's.
    pub replicates_runs: Vec<f64>,
    pub replicates_streams: Vec<f64>,
    pub interval: [f64; 2],
    /// Bootstrap standard error of the gap.
    pub se: f64,
    /// Paired bootstrap interval of (baseline − this model)'s gap.
    pub improvement_interval: [f64; 2],
    /// The bootstrap sd of (baseline − this model)'s gap with both sources of noise, with
    /// the runs' alone and with the simulation's (the fresh streams') alone, %².
    pub improvement_sd: [f64; 3],
    /// Extra parameters over the baseline.
    pub extra_params: usize,
    /// The ranking score (see the module's doc).
    pub score: f64,
    pub evaluations: u64,
}

/// A model's name: `baseline`, an effect's name, or the effects' names joined by `+`.
pub(super) fn model_name(effects: &[EffectKind]) -> String {
    if effects.is_empty() {
        "baseline".into()
    } else {
        effects.iter().map(|e| e.name()).collect::<Vec<_>>().join("+")
    }
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
    /// The fresh streams' mean bins per condition (the fit's own bins before any re-scoring).
    pub fn mean_fresh_bins(&self) -> Vec<Vec<f64>> {
        if self.fresh.is_empty() {
            return self.full.bins.clone();
        }
        let streams = self.fresh.len() as f64;
        (0..self.full.bins.len())
            .map(|c| {
                let n = self.fresh[0][c].len();
                (0..n).map(|j| self.fresh.iter().map(|f| f[c][j]).sum::<f64>() / streams).collect()
            })
            .collect()
    }
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
