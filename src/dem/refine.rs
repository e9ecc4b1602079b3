//! Convergence of a DEM campaign (issue 42): a DEM figure is a claim only when halving the
//! allowed overlap (the softened modulus, and with it the time step) and doubling the grain
//! count move it by less than its own noise. `dem run --refine` runs the campaign's seeds
//! again at those settings, each a campaign of its own in `DIR/refine-NN-ovF-nN/`, and
//! records the levels, their d_avg and the verdict in `DIR/refine.json`.
//!
//! One level asks two questions of a base (overlap f, N grains): (f/2, N) and (f, 2N). It is
//! converged when both move the mean d_avg by at most max([`REL_TOL`] of it, [`SPREAD_FACTORS`]
//! seed spreads). Otherwise the next level's base is (f/2, 2N), up to the levels asked for.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use anyhow::Context as _;

use super::campaign::{self, Plan};
use super::gather::RunResult;
use crate::io::bounded::read_text_if_present;
use crate::schema;

/// The relative change of d_avg a refinement may make, however small the seed spread.
pub const REL_TOL: f64 = 0.03;
/// Seed spreads (sample sd of the runs, the larger of the two campaigns') a refinement may move d_avg by.
pub const SPREAD_FACTORS: f64 = 2.0;

/// One campaign of the ladder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rung {
    pub max_overlap_fraction: f64,
    pub particles: u32,
    /// Its folder, relative to the base campaign's.
    pub dir: PathBuf,
    pub d_avg_mm: f64,
    pub d_avg_sd_mm: f64,
    /// Mean wall seconds per run.
    pub wall_s: f64,
}

/// One level: a base and its two refinements.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Level {
    pub base: Rung,
    pub half_overlap: Rung,
    pub double_grains: Rung,
    /// What each refinement moved the mean d_avg by, mm, and the allowed move.
    pub overlap_move_mm: f64,
    pub grains_move_mm: f64,
    pub allowed_mm: f64,
    pub converged: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Refinement {
    pub levels: Vec<Level>,
    /// Whether the last level is converged; its base is then the figure to report, with the
    /// larger of its two moves as its discretisation error.
    pub converged: bool,
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    let sd = if v.len() > 1 { (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() } else { 0.0 };
    (m, sd)
}

fn rung(plan: &Plan, dir: PathBuf, runs: &[RunResult]) -> Rung {
    let (m, sd) = mean_sd(&runs.iter().map(|r| r.d_avg_m * 1e3).collect::<Vec<_>>());
    Rung {
        max_overlap_fraction: plan.settings.max_overlap_fraction,
        particles: plan.settings.particles,
        dir,
        d_avg_mm: m,
        d_avg_sd_mm: sd,
        wall_s: mean_sd(&runs.iter().map(|r| r.wall_s).collect::<Vec<_>>()).0,
    }
}

/// The plan with the overlap and grain count of a rung; a stated grain diameter shrinks with
/// the count as the derived one does (`grains::mass_matching_diameter`, d ∝ N^(-1/2)): the
/// slab is `depth_grains` diameters deep, so N grains of d carry a mass per unit depth
/// ∝ N d², which this keeps — the same bed, finer. (Keeping N d³, the grains' volume, put
/// 2^(1/3) = 1.26 times the fill per unit depth into a slab that thinned with the grain.)
fn variant(plan: &Plan, overlap: f64, particles: u32) -> Plan {
    let mut p = plan.clone();
    p.settings.max_overlap_fraction = overlap;
    let ratio = particles as f64 / plan.settings.particles as f64;
    p.settings.grain_diameter_m = plan.settings.grain_diameter_m.map(|d| d / ratio.sqrt());
    p.settings.particles = particles;
    p
}

fn sub_dir(index: usize, overlap: f64, particles: u32) -> PathBuf {
    PathBuf::from(format!("refine-{index:02}-ov{overlap}-n{particles}"))
}

/// Judge one level from its three campaigns.
pub fn judge(base: Rung, half_overlap: Rung, double_grains: Rung) -> Level {
    let overlap_move_mm = half_overlap.d_avg_mm - base.d_avg_mm;
    let grains_move_mm = double_grains.d_avg_mm - base.d_avg_mm;
    let spread = base.d_avg_sd_mm.max(half_overlap.d_avg_sd_mm).max(double_grains.d_avg_sd_mm);
    let allowed_mm = (REL_TOL * base.d_avg_mm.abs()).max(SPREAD_FACTORS * spread);
    let converged = overlap_move_mm.abs() <= allowed_mm && grains_move_mm.abs() <= allowed_mm;
    Level { base, half_overlap, double_grains, overlap_move_mm, grains_move_mm, allowed_mm, converged }
}

/// Refine the finished campaign `plan` in `dir` (its runs `base_runs`) for up to `levels`
/// levels, running each sub-campaign with `jobs` processes (resumable: a sub-campaign done
/// is read back). The ladder is written to `DIR/refine.json` after every level.
pub fn refine(
    dir: &Path,
    plan: &Plan,
    base_runs: &[RunResult],
    levels: u32,
    jobs: usize,
    say: &(dyn Fn(String) + Sync),
) -> anyhow::Result<Refinement> {
    let mut base = rung(plan, PathBuf::from("."), base_runs);
    let mut base_plan = plan.clone();
    let mut out = Refinement { levels: Vec::new(), converged: false };
    let mut index = 0;
    for level in 0..levels {
        let (f, n) = (base_plan.settings.max_overlap_fraction, base_plan.settings.particles);
        let mut run = |overlap: f64, particles: u32| -> anyhow::Result<(Plan, Rung)> {
            index += 1;
            let p = variant(&base_plan, overlap, particles);
            p.settings.validate().map_err(anyhow::Error::msg)?;
            let rel = sub_dir(index, overlap, particles);
            let sub = dir.join(&rel);
            // a campaign of the refinement in the base campaign's folder, marked as a DEM
            // campaign like any other so that `dem compare` reads it (folders marked
            // "dem-refine" by a version before this resume here too)
            campaign::own_subcampaign_folder(&sub)?;
            say(format!("refine level {}: overlap {overlap}, {particles} grains in {}", level + 1, sub.display()));
            let runs = campaign::run(&sub, &p, jobs, say)?;
            let r = rung(&p, rel, &runs);
            Ok((p, r))
        };
        let (_, half) = run(0.5 * f, n)?;
        let (_, double) = run(f, 2 * n)?;
        let judged = judge(base.clone(), half, double);
        say(format!(
            "refine level {}: d_avg {:.1} ± {:.1} mm; half the overlap moves it {:+.1} mm, twice the grains {:+.1} mm (allowed {:.1}): {}",
            level + 1,
            judged.base.d_avg_mm,
            judged.base.d_avg_sd_mm,
            judged.overlap_move_mm,
            judged.grains_move_mm,
            judged.allowed_mm,
            if judged.converged { "converged" } else { "not converged" }
        ));
        let converged = judged.converged;
        out.levels.push(judged);
        out.converged = converged;
        crate::io::atomic::write_atomic(&dir.join(REFINE), serde_json::to_string_pretty(&out)?.as_bytes())?;
        if converged || level + 1 == levels {
            break;
        }
        // the next base: both refinements at once
        let (p, r) = run(0.5 * f, 2 * n)?;
        base_plan = p;
        base = r;
    }
    Ok(out)
}

/// The ladder's record in the base campaign's folder.
pub const REFINE: &str = "refine.json";

/// Most levels a ladder climbs (`dem run --refine` takes 1 to this).
pub const MAX_LEVELS: usize = 3;

impl Refinement {
    /// Every rule a ladder read back must keep: 1 to [`MAX_LEVELS`] levels, finite lengths,
    /// non-negative spreads and allowances, grain counts of at least one, overlaps in (0, 1).
    pub fn validate(&self) -> Result<(), String> {
        if self.levels.is_empty() || self.levels.len() > MAX_LEVELS {
            return Err(format!("`levels` must hold 1 to {MAX_LEVELS} levels, got {}", self.levels.len()));
        }
        for (i, l) in self.levels.iter().enumerate() {
            for (name, r) in [("base", &l.base), ("half_overlap", &l.half_overlap), ("double_grains", &l.double_grains)]
            {
                let at = format!("levels[{i}].{name}");
                if !(r.max_overlap_fraction > 0.0 && r.max_overlap_fraction < 1.0) {
                    return Err(format!(
                        "{at}.max_overlap_fraction must lie in (0, 1), got {}",
                        r.max_overlap_fraction
                    ));
                }
                if r.particles == 0 {
                    return Err(format!("{at}.particles must be at least 1"));
                }
                if !(r.d_avg_mm.is_finite() && r.d_avg_sd_mm.is_finite() && r.d_avg_sd_mm >= 0.0) {
                    return Err(format!("{at}: d_avg_mm must be finite and d_avg_sd_mm finite and >= 0"));
                }
            }
            let finite = l.overlap_move_mm.is_finite() && l.grains_move_mm.is_finite() && l.allowed_mm.is_finite();
            if !(finite && l.allowed_mm >= 0.0) {
                return Err(format!("levels[{i}]: the moves must be finite and allowed_mm finite and >= 0"));
            }
        }
        Ok(())
    }
}

/// The ladder `dem run --refine` left in the campaign folder `dir`, if it left one: read
/// within its bound and checked by every rule; a broken file is refused naming it.
pub fn read_refinement(dir: &Path) -> anyhow::Result<Option<Refinement>> {
    let path = dir.join(REFINE);
    let Some(text) = read_text_if_present(&path, &schema::DEM_REFINE_FILE)? else { return Ok(None) };
    let r: Refinement = serde_json::from_str(&text).with_context(|| format!("reading {}", path.display()))?;
    r.validate().map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(Some(r))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(d: f64, sd: f64) -> Rung {
        Rung { max_overlap_fraction: 0.1, particles: 150, dir: ".".into(), d_avg_mm: d, d_avg_sd_mm: sd, wall_s: 1.0 }
    }

    /// A refined rung of a campaign that states its grain diameter is the same bed in finer
    /// grains: the fill's mass per unit slab depth is the base's, as when the diameter is
    /// derived from the count.
    #[test]
    fn more_grains_of_a_stated_diameter_carry_the_same_fill_per_unit_depth() {
        use crate::dem::settings::DemSettings;
        let base = campaign::tests::lunar(DemSettings {
            particles: 150,
            grain_diameter_m: Some(4.5e-3),
            ..Default::default()
        });
        let per_depth = |p: &Plan| {
            let c = p.case(0).unwrap();
            c.placement.grains.len() as f64 * c.placement.grain_mass_kg / c.placement.depth_m
        };
        let fine = variant(&base, 0.025, 600);
        assert_eq!(fine.settings.particles, 600);
        assert!((fine.settings.grain_diameter_m.unwrap() - 2.25e-3).abs() < 1e-15);
        let (a, b) = (per_depth(&base), per_depth(&fine));
        assert!((b / a - 1.0).abs() < 1e-9, "{a} kg/m, refined {b}");
    }

    #[test]
    fn a_level_is_converged_when_both_refinements_move_d_avg_less_than_its_noise_or_3_percent() {
        // 3 % of 100 mm is the floor when the seeds agree
        assert!(judge(r(100.0, 0.1), r(102.9, 0.1), r(97.1, 0.1)).converged);
        assert!(!judge(r(100.0, 0.1), r(103.2, 0.1), r(100.0, 0.1)).converged);
        assert!(!judge(r(100.0, 0.1), r(100.0, 0.1), r(96.0, 0.1)).converged);
        // a noisy campaign allows two of its spreads
        let noisy = judge(r(100.0, 2.5), r(104.9, 1.0), r(100.0, 1.0));
        assert!(noisy.converged && (noisy.allowed_mm - 5.0).abs() < 1e-12);
        let moved = judge(r(154.6, 1.0), r(172.7, 2.3), r(163.1, 2.8));
        assert!(!moved.converged && (moved.overlap_move_mm - 18.1).abs() < 1e-9);
    }
}
