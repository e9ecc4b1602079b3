//! A measured condition: the runs and the setup they were measured with.

use super::stats::sample_sd;
use super::target::{collapse_to_weighed, subset, MeasuredSummary, Target};
use crate::io::measured::MeasuredRuns;
use crate::model::{Design, Scenario};

/// What a setup states of the sled's motion after the launch ([measurement]
/// motion_delay_s, motion_return_speed_m_s, motion_direction): the sled-motion effect holds
/// these fixed for the condition and fits the delay and speed left out.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KnownMotion {
    pub delay_s: Option<f64>,
    pub return_speed_m_s: Option<f64>,
    /// Along what the sled returns ([measurement] motion_direction); not fitted: down the
    /// slope where no setup says.
    pub direction: Option<crate::model::effects::MotionDirection>,
}

impl KnownMotion {
    pub fn get(&self, i: usize) -> Option<f64> {
        [self.delay_s, self.return_speed_m_s][i]
    }
    pub fn any(&self) -> bool {
        self.delay_s.is_some() || self.return_speed_m_s.is_some()
    }
}

/// A gap is "well above" its noise floor ([`Condition::noise_floor`]) beyond this multiple
/// of it: for noise alone the gap is a sum of a few χ²-like terms with that floor as its
/// mean, and three times the mean is rarely reached (P(χ²₆ > 18) ≈ 0.6 %).
pub const FLOOR_FACTOR: f64 = 3.0;

/// One measured condition: runs and the setup they were measured with.
#[derive(Clone, Debug)]
pub struct Condition {
    /// Short name (the data file's stem).
    pub name: String,
    pub data: String,
    pub setup: String,
    pub runs: MeasuredRuns,
    /// The setup's scenario (effects off); particle count and seed are set per simulation.
    pub base: Scenario,
    pub design: Design,
    pub resolution_g: f64,
    /// The sled's motion as far as the setup knows it.
    pub motion: KnownMotion,
    /// The setup's motion-profile label (`poc`, `delayed`), if any.
    pub motion_profile: Option<String>,
    /// How tooth masses become the compared fractions.
    pub normalise: Normalise,
    /// The largest share of the loaded mass the runs may have lost in handling
    /// (`[measurement] handling_loss_max`; 1 where the setup states none: all they did not
    /// recover).
    pub handling_loss_max: f64,
}

/// The measurement model: what the compared fractions are fractions of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Normalise {
    /// Of the loaded mass (`input_mass`): the weighed teeth and a "not recovered" bin that
    /// the simulation fills with what rests beyond the weighed teeth or is lost
    /// ([`Target::of_loaded_mass`]).
    Loaded,
    /// Of the recovered mass, with simulated mass beyond the weighed teeth as misfit
    /// (listing D.4; right when the weighed teeth hold every grain).
    Recovered,
}

impl Condition {
    pub fn teeth(&self) -> usize {
        self.base.sim.teeth as usize
    }
    pub fn has_drag(&self) -> bool {
        self.base.environment.k_drag.is_some()
    }
    /// The target of the runs `idx` (repeats allowed: bootstrap).
    pub fn target(&self, idx: &[usize]) -> Target {
        self.target_of(&subset(&self.runs, idx))
    }
    pub fn target_all(&self) -> Target {
        self.target_of(&self.runs)
    }
    fn target_of(&self, runs: &MeasuredRuns) -> Target {
        match self.normalise {
            Normalise::Loaded => {
                let mut t = Target::of_loaded_mass(runs, self.teeth(), self.resolution_g)
                    .expect("Normalise::Loaded is chosen only when every run records input_mass");
                t.max_handling_loss = t.max_handling_loss.min(self.handling_loss_max);
                t
            }
            Normalise::Recovered => Target::new(runs, self.teeth(), self.resolution_g),
        }
    }
    /// Simulated bins (teeth, then lost) as this condition's measurement sees them.
    pub fn observe(&self, bins: Vec<f64>) -> Vec<f64> {
        match self.normalise {
            Normalise::Loaded => collapse_to_weighed(&bins, self.runs.teeth),
            Normalise::Recovered => bins,
        }
    }
    /// Each run's fractions as this condition's measurement compares them: the setup's teeth
    /// (zeros beyond the weighed ones), then the last bin (what the run did not recover of
    /// its loaded mass under `Normalise::Loaded`; D.4's lost bin, 0, otherwise).
    pub fn run_fractions(&self) -> Vec<Vec<f64>> {
        let teeth = self.teeth();
        self.runs
            .runs
            .iter()
            .map(|r| {
                let total = match (self.normalise, r.input_mass_g) {
                    (Normalise::Loaded, Some(m)) => m,
                    _ => r.recovered_g(),
                };
                let mut f = vec![0.0; teeth + 1];
                for (fj, m) in f.iter_mut().zip(&r.teeth_g) {
                    *fj = m / total;
                }
                f[teeth] = (1.0 - r.recovered_g() / total).max(0.0);
                f
            })
            .collect()
    }

    /// Per-bin statistics of the runs as the fits compare them: the mean is the target's
    /// (mean masses over their sum, or over the summed loaded masses), sd, min and max those
    /// of [`Self::run_fractions`].
    pub fn summary(&self) -> MeasuredSummary {
        let fr = self.run_fractions();
        let bins = self.teeth() + 1;
        let col = |j: usize| fr.iter().map(|f| f[j]).collect::<Vec<f64>>();
        MeasuredSummary {
            mean: self.target_all().bins,
            sd: (0..bins).map(|j| sample_sd(&col(j))).collect(),
            min: (0..bins).map(|j| col(j).into_iter().fold(f64::INFINITY, f64::min)).collect(),
            max: (0..bins).map(|j| col(j).into_iter().fold(f64::NEG_INFINITY, f64::max)).collect(),
        }
    }

    /// What the last bin holds, for reports: "lost" (D.4's bins) or "not recovered"
    /// (beyond the weighed teeth, lost, or spilled).
    pub fn last_bin_label(&self) -> &'static str {
        match self.normalise {
            Normalise::Loaded => "not recovered",
            Normalise::Recovered => "lost",
        }
    }

    /// Whether every run records its loaded mass (so `Normalise::Loaded` is possible).
    pub fn has_input_mass(runs: &MeasuredRuns) -> bool {
        runs.runs.iter().all(|r| r.input_mass_g.is_some_and(|m| m > 0.0))
    }

    /// Variance of the measured mean fraction per bin (teeth, then the last bin): the
    /// run-to-run variance of [`Self::run_fractions`] — the bins as the fits compare them,
    /// the "not recovered" share included — over the number of runs, plus the scale's
    /// quantisation (resolution²/12 relative to the mean recovered mass², per run, over the
    /// runs). Why the compared bins and not the teeth's fractions of the recovered mass: under
    /// `Normalise::Loaded` each run spills a different share in handling, which moves every
    /// tooth's fraction of the loaded mass and the last bin itself; a floor that saw only the
    /// teeth's recovered fractions gave that bin the scale's quantisation alone and flagged
    /// a DEM campaign's lost grains at z −6 to −10 (docs/diagnosis-report.md).
    pub fn mean_variance(&self) -> Vec<f64> {
        let fractions = self.run_fractions();
        let n = fractions.len().max(1) as f64;
        let recovered = self.runs.runs.iter().map(|r| r.recovered_g()).sum::<f64>() / n;
        let scale = (self.resolution_g / recovered).powi(2) / 12.0 / n;
        (0..=self.teeth())
            .map(|j| {
                let column: Vec<f64> = fractions.iter().map(|f| f[j]).collect();
                // one run has no spread: the scale's quantisation alone
                let s = Some(sample_sd(&column)).filter(|s| s.is_finite()).unwrap_or(0.0);
                s * s / n + scale
            })
            .collect()
    }

    /// Variance (fractions²) per bin of a model's simulated bins (`sim`, as compared) against
    /// the measured mean: the measured mean's variance ([`Self::mean_variance`]) and the
    /// simulation's Monte-Carlo variance p(1−p)/draws, `draws` the particles behind `sim`
    /// (particles × streams where it is the mean of several).
    pub fn bin_variance(&self, sim: &[f64], draws: f64) -> Vec<f64> {
        let draws = draws.max(1.0);
        self.mean_variance().iter().zip(sim).map(|(v, p)| v + (p * (1.0 - p)).max(0.0) / draws).collect()
    }

    /// The noise floor (%²) of a model's simulated bins: the SSE that a model right in every
    /// respect would leave on these runs, Σ [`Self::bin_variance`] · 10⁴. A gap is "well
    /// above" it beyond [`FLOOR_FACTOR`] times.
    pub fn noise_floor(&self, sim: &[f64], draws: f64) -> f64 {
        1e4 * self.bin_variance(sim, draws).iter().sum::<f64>()
    }

    /// The particle count whose Monte-Carlo variance p(1−p)/N stays at or below
    /// `ratio` × the measured mean's variance in every tooth holding ≥ 2 % of the mass.
    pub fn particles_for(&self, ratio: f64) -> f64 {
        let t = self.target_all();
        let var = self.mean_variance();
        t.bins
            .iter()
            .zip(&var)
            .filter(|(p, _)| **p >= 0.02)
            .map(|(p, v)| p * (1.0 - p) / (ratio * v.max(1e-12)))
            .fold(0.0, f64::max)
    }
}

/// The thesis's Test 3 as a condition (data/validation), for the calibration's unit tests.
#[cfg(test)]
pub(crate) fn test3() -> Condition {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/validation");
    crate::calibrate::measured::load(
        &dir.join("test3.csv"),
        &dir.join("test3.toml"),
        "test3".into(),
        None,
        Some(0),
        crate::calibrate::Spelling::Flags,
    )
    .unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Test 3's setup with `csv`'s runs.
    fn test3_with(csv: &str) -> Condition {
        let mut c = test3();
        c.runs = crate::io::measured::parse(csv, "runs").unwrap();
        c
    }

    /// A rig's runs may have spilled all they did not recover (the judged bins may move it to
    /// "not recovered"); a setup that states `handling_loss_max` caps that share, and a DEM
    /// campaign's 0 judges every lost grain as the model's to predict.
    #[test]
    fn the_handling_loss_allowed_is_what_the_runs_did_not_recover_at_most_the_stated_cap() {
        let csv = "run,tooth_1,tooth_2,tooth_3,tooth_4,input_mass\n1,1.00,0.50,0.30,0.10,2.00\n";
        let mut c = test3_with(csv);
        assert!((c.target_all().max_handling_loss - 0.05).abs() < 1e-12);
        c.handling_loss_max = 0.02;
        assert!((c.target_all().max_handling_loss - 0.02).abs() < 1e-12);
        c.handling_loss_max = 0.0;
        let t = c.target_all();
        assert_eq!(t.max_handling_loss, 0.0);
        // nothing is moved to the lost bin: the simulated bins are judged as they are
        let mut sim = vec![0.0; t.bins.len()];
        sim[..3].copy_from_slice(&[0.5, 0.3, 0.2]);
        assert_eq!(t.after_handling(&sim).0, 0.0);
    }

    /// Two runs that put the same shares of what they recovered in the same teeth but spill
    /// 0 % and 10 % of their loaded mass: the "not recovered" bin (and every tooth's share
    /// of the loaded mass) varies from run to run, and the noise floor of each bin counts
    /// that variance, not the scale's quantisation alone.
    #[test]
    fn the_noise_floor_counts_the_run_to_run_variance_of_every_compared_bin() {
        let c = test3_with(
            "run,tooth_1,tooth_2,tooth_3,tooth_4,input_mass\n1,1.00,0.50,0.40,0.10,2.00\n2,0.90,0.45,0.36,0.09,2.00\n",
        );
        assert_eq!(c.normalise, Normalise::Loaded);
        let var = c.mean_variance();
        let fractions = c.run_fractions();
        let scale = (c.resolution_g / 1.9).powi(2) / 12.0 / 2.0;
        for (j, v) in var.iter().enumerate() {
            let column: Vec<f64> = fractions.iter().map(|f| f[j]).collect();
            let want = sample_sd(&column).powi(2) / 2.0 + scale;
            assert!((v - want).abs() < 1e-15, "bin {j}: {v} against {want}");
        }
        let last = var[c.teeth()];
        assert!(
            last > 100.0 * scale,
            "the not-recovered bin (0 % and 10 %) varies: {last} against the scale's {scale}"
        );
    }

    /// With the recovered mass as the denominator (D.4) the last bin is 0 in every run and
    /// keeps the scale's floor; a single run has no spread and keeps it in every bin.
    #[test]
    fn a_bin_that_never_varies_keeps_the_scale_floor() {
        let mut c = test3_with(
            "run,tooth_1,tooth_2,tooth_3,tooth_4,input_mass\n1,1.00,0.50,0.40,0.10,2.00\n2,0.90,0.45,0.36,0.09,2.00\n",
        );
        c.normalise = Normalise::Recovered;
        let scale = (c.resolution_g / 1.9).powi(2) / 12.0 / 2.0;
        let var = c.mean_variance();
        assert!((var[c.teeth()] - scale).abs() < 1e-18, "{var:?}");
        assert!((var[0] - scale).abs() < 1e-18, "tooth 1 holds 50 % of what both runs recovered: {var:?}");
        let one = test3_with("run,tooth_1,tooth_2,tooth_3,tooth_4,input_mass\n1,1.00,0.50,0.40,0.10,2.00\n");
        let scale_one = (one.resolution_g / 2.0).powi(2) / 12.0;
        assert!(one.mean_variance().iter().all(|v| (v - scale_one).abs() < 1e-18));
    }
}
