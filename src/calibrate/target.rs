//! What measured runs offer a calibration's objectives: the measured distribution and the
//! per-run counts ([`Target`]), which objective is minimised ([`ObjectiveKind`]), how a rig
//! that weighs only some teeth sees simulated bins ([`collapse_to_weighed`]) and the per-bin
//! statistics a report shows ([`MeasuredSummary`]).

use serde::Serialize;

use super::objective::{self, Profiled};
use crate::io::measured::MeasuredRuns;

/// Which objective the optimiser minimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectiveKind {
    /// Eq. 4.62 / listing D.4: Σ (simulated % − measured %)² over the teeth and a lost bin.
    Sse,
    /// Dirichlet-multinomial negative log-likelihood of the runs, concentration profiled out.
    Likelihood,
}

/// What a set of measured runs offers the objectives.
#[derive(Clone, Debug)]
pub struct Target {
    /// Mean distribution (fraction of the mean masses), padded to the setup's teeth, plus a
    /// lost bin of 0.
    pub bins: Vec<f64>,
    /// Per run: tooth masses in scale units, padded the same way.
    pub counts: Vec<Vec<f64>>,
}

impl Target {
    /// Fractions of the *loaded* mass (every run must record `input_mass`): the weighed teeth
    /// (Σ masses / Σ input masses), zeros for the teeth not weighed, and a last bin for what
    /// was not recovered (grains beyond the weighed teeth or lost, and spill), which
    /// [`collapse_to_weighed`] makes of the simulated bins. Unlike [`Target::new`] (D.4's
    /// normalisation to the recovered mass, with simulated mass beyond the weighed teeth
    /// counted as misfit), it stays right when the weighed teeth do not hold every grain.
    pub fn of_loaded_mass(runs: &MeasuredRuns, teeth: usize, resolution_g: f64) -> Option<Self> {
        let input: f64 = runs.runs.iter().map(|r| r.input_mass_g).sum::<Option<f64>>()?;
        // NaN and non-positive totals both mean there is no loaded mass to normalise by
        if input.is_nan() || input <= 0.0 {
            return None;
        }
        let mut bins = vec![0.0; teeth + 1];
        for r in &runs.runs {
            for (b, m) in bins.iter_mut().zip(&r.teeth_g) {
                *b += m / input;
            }
        }
        bins[teeth] = (1.0 - bins[..runs.teeth].iter().sum::<f64>()).max(0.0);
        // the likelihood's counts: scale steps per tooth, and the mass not recovered
        let counts = runs
            .runs
            .iter()
            .map(|r| {
                let mut c = objective::quantised_counts(&r.teeth_g, teeth, resolution_g);
                let missing = r.input_mass_g.unwrap_or(0.0) - r.recovered_g();
                c[teeth] = (missing / resolution_g).round().max(0.0);
                c
            })
            .collect();
        Some(Target { bins, counts })
    }

    pub fn new(runs: &MeasuredRuns, teeth: usize, resolution_g: f64) -> Self {
        Target {
            bins: objective::measured_bins(&runs.mean_fractions(), teeth),
            counts: runs.runs.iter().map(|r| objective::quantised_counts(&r.teeth_g, teeth, resolution_g)).collect(),
        }
    }

    /// The objective for simulated bins; +inf for a candidate that could not be simulated.
    pub fn value(&self, kind: ObjectiveKind, bins: Option<&[f64]>, eps: f64) -> f64 {
        match (kind, bins) {
            (_, None) => f64::INFINITY,
            (ObjectiveKind::Sse, Some(b)) => objective::sse_percent2(b, &self.bins),
            (ObjectiveKind::Likelihood, Some(b)) => objective::profile_nll(&self.counts, b, eps).nll,
        }
    }

    pub fn sse(&self, bins: &[f64]) -> f64 {
        objective::sse_percent2(bins, &self.bins)
    }

    pub fn likelihood(&self, bins: &[f64], eps: f64) -> Profiled {
        objective::profile_nll(&self.counts, bins, eps)
    }

    /// The likelihood with the mean set to the measured mean distribution (a perfect mean
    /// model): its NLL is the reference a fitted model's NLL is compared with, its
    /// concentration the one the runs' scatter alone implies. A fit whose profiled α0 is
    /// far below that explains misfit of the mean as over-dispersion.
    pub fn measured_mean_likelihood(&self) -> Profiled {
        objective::profile_nll(&self.counts, &self.bins, 1e-12)
    }
}

/// Simulated bins (teeth, then lost) as a rig that weighs only the first `weighed` teeth
/// sees them: those teeth, zeros for the others, and everything else in the last bin (the
/// counterpart of [`Target::of_loaded_mass`]).
pub fn collapse_to_weighed(bins: &[f64], weighed: usize) -> Vec<f64> {
    let n = bins.len();
    let mut out = vec![0.0; n];
    out[..weighed].copy_from_slice(&bins[..weighed]);
    out[n - 1] = (1.0 - bins[..weighed].iter().sum::<f64>()).max(0.0);
    out
}

/// `runs` restricted to the given indices (repeats allowed, for the bootstrap).
pub fn subset(runs: &MeasuredRuns, indices: &[usize]) -> MeasuredRuns {
    MeasuredRuns { runs: indices.iter().map(|&i| runs.runs[i].clone()).collect(), ..runs.clone() }
}

/// Per-bin statistics of the runs' fractions as a fit compares them (the setup's teeth,
/// zeros beyond the weighed ones, then the last bin): [`super::Condition::summary`].
#[derive(Clone, Debug, Serialize)]
pub struct MeasuredSummary {
    /// The measured mean distribution ([`Target::bins`]).
    pub mean: Vec<f64>,
    /// Sample standard deviation of the run fractions (NaN with one run).
    pub sd: Vec<f64>,
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_pads_and_objectives_agree_on_a_perfect_fit() {
        let runs = crate::io::measured::parse("run,tooth_1,tooth_2\na,1.0,1.0\nb,1.2,0.8\n", "t.csv").unwrap();
        let t = Target::new(&runs, 5, 0.1);
        assert_eq!(t.bins.len(), 6);
        assert_eq!(t.counts[1], vec![12.0, 8.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(t.value(ObjectiveKind::Sse, Some(&t.bins.clone()), 1e-3), 0.0);
        assert!(t.value(ObjectiveKind::Likelihood, Some(&t.bins.clone()), 1e-3).is_finite());
        assert_eq!(t.value(ObjectiveKind::Sse, None, 1e-3), f64::INFINITY);
    }

    #[test]
    fn loaded_mass_counts_hold_what_was_not_recovered() {
        let runs =
            crate::io::measured::parse("run,tooth_1,tooth_2,input_mass\na,1.0,0.5,2.0\nb,1.2,0.6,2.0\n", "t.csv")
                .unwrap();
        let t = Target::of_loaded_mass(&runs, 3, 0.1).unwrap();
        // (1.0 + 1.2) / 4, (0.5 + 0.6) / 4, 0, then the 0.7 g of 4 g not recovered
        for (g, w) in t.bins.iter().zip([0.55, 0.275, 0.0, 0.175]) {
            assert!((g - w).abs() < 1e-12, "{:?}", t.bins);
        }
        assert_eq!(t.counts[0], vec![10.0, 5.0, 0.0, 5.0]);
        assert_eq!(t.counts[1], vec![12.0, 6.0, 0.0, 2.0]);
    }
}
