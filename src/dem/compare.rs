//! The model beside the DEM for one campaign: per tooth share of the loaded mass, lost mass,
//! d_avg, centre of mass and dispersion (Eq. 4.56-4.59), with the DEM's spread over its
//! seeds, and what each cost.
//!
//! Like for like (issue 42): the model is judged on the DEM's mesh (`sim.teeth` = the mesh's
//! teeth, so a grain past the last tooth is lost on both sides and credited nothing), and a
//! comparison warns where either side loses more than [`PAST_END_WARN`] of its mass past the
//! end (a mesh too short for the flights: `[dem] teeth` lengthens it). Beside the model as
//! configured, the model is also run
//! - from the DEM's settled bed (its grains' positions after settling, before the stroke,
//!   as launch points instead of the fill polygon's Halton points): what the fill moves;
//! - with the DEM's restitution law (`ContactLaw::Dem`, when the caller has the table
//!   `dem impact` measured at the case's contact), from the settled bed too: what the
//!   contact law moves;
//! - on a conveyor long enough to lose nothing: what the mesh's truncation moves.

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use super::gather::RunResult;
use super::losses::LeftBy;
use super::refine::{Level, Refinement};
use crate::engine::{evaluate_detailed, evaluate_detailed_from, make_engine_for, EngineKind};
use crate::model::design::DesignRow;
use crate::model::outcome::centre_and_dispersion;
use crate::model::{Collision, Design, Scenario};
use crate::plot::{self, Drawn, Figure, Mark};

#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    pub mean: f64,
    /// Sample standard deviation over the runs (0 for one run).
    pub sd: f64,
}

/// Mean and sample sd of `v` (sd 0 for one value; both NaN for none).
fn spread(v: &[f64]) -> Spread {
    if v.is_empty() {
        return Spread { mean: f64::NAN, sd: f64::NAN };
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = if v.len() > 1 { (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() } else { 0.0 };
    Spread { mean, sd }
}

#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub teeth: usize,
    pub runs: usize,
    /// Per tooth share of the loaded mass, %, tooth 1 first.
    pub model_pct: Vec<f64>,
    pub dem_pct: Vec<Spread>,
    pub model_lost_pct: f64,
    pub dem_lost_pct: Spread,
    /// Mean over the teeth of |model − DEM mean|, percentage points.
    pub mean_abs_tooth_error_pp: f64,
    pub max_abs_tooth_error_pp: f64,
    pub model_d_avg_mm: f64,
    pub dem_d_avg_mm: Spread,
    /// (DEM − model) / model, %; None when the model's d_avg is 0.
    pub d_avg_error_pct: Option<f64>,
    pub model_centre: f64,
    pub dem_centre: Spread,
    pub model_dispersion: f64,
    pub dem_dispersion: Spread,
    /// Wall-clock seconds per design: the model (cpu engine, `model_particles`) and one DEM run.
    pub model_s: f64,
    pub dem_s: Spread,
    pub model_particles: u32,
    /// The model's mass past the mesh's last tooth, % (counted in `model_lost_pct`).
    pub model_past_end_pct: f64,
    /// The DEM's grains past the mesh's last tooth, %: resting beyond it or gone from the box
    /// past it (counted in `dem_lost_pct`).
    pub dem_past_end_pct: Spread,
    /// The model's d_avg on a conveyor of `case::REACH_CONVEYOR_TEETH` teeth (nothing lost
    /// past its end), mm.
    pub model_untruncated_d_avg_mm: f64,
    /// The model launched from the DEM's settled beds (every run's grains, in turn), mm;
    /// None when the runs kept no settled bed.
    pub model_from_bed_d_avg_mm: Option<f64>,
    /// The model with the DEM's restitution law, launched from the settled beds where the
    /// runs kept them (else from the polygon), mm; None without a measured law.
    pub model_dem_law_d_avg_mm: Option<f64>,
    /// Its share of the mass per tooth, %, tooth 1 first (the mesh's teeth).
    pub model_dem_law_pct: Option<Vec<f64>>,
    /// Where the DEM's grains that left the box went, over every run (`losses`); None when a
    /// run wrote no track.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dem_left_by: Option<LeftBy>,
    /// The DEM's numerics: the last level of the campaign's refinement (`dem run --refine`,
    /// refine.json) with its moves and verdict; None when the campaign was not refined (a
    /// warning then says so).
    pub numerics: Option<Level>,
    /// The discretisation error of the DEM's d_avg, mm: the larger of the last level's two
    /// moves; None without a refinement.
    pub numerics_error_mm: Option<f64>,
    /// Why this comparison may not be like for like (a mesh too short, ...).
    pub warnings: Vec<String>,
}

impl Comparison {
    /// Give the comparison the DEM's discretisation error from the campaign's refinement,
    /// or a warning that it has none (issue 42: every DEM figure carries its numerics' error).
    /// A ladder whose base is not these runs (d_avg differs) is not used.
    pub fn attach_numerics(&mut self, refinement: Option<&Refinement>) {
        let Some(r) = refinement else {
            self.warnings.push(
                "the DEM's numerics are not checked on this campaign (no refine.json): `dem run --refine` runs it at \
                 half the overlap and twice the grains; on held-out lunar designs that lose grains down the slope, \
                 each doubling of the grains moved d_avg by a fifth to two fifths (docs/dem.md, \"Converged numerics\")"
                    .into(),
            );
            return;
        };
        let (Some(first), Some(last)) = (r.levels.first(), r.levels.last()) else { return };
        if (first.base.d_avg_mm - self.dem_d_avg_mm.mean).abs() > 1e-6 * self.dem_d_avg_mm.mean.abs().max(1.0) {
            self.warnings.push(format!(
                "refine.json was made from other runs (its base d_avg {:.2} mm, these runs' {:.2} mm): its numerics \
                 are not used; run `dem run --refine` again",
                first.base.d_avg_mm, self.dem_d_avg_mm.mean
            ));
            return;
        }
        if !r.converged {
            self.warnings.push(format!(
                "the DEM's numerics are not converged: at {} grains and {} overlap, half the overlap moved d_avg by \
                 {:+.1} mm and twice the grains by {:+.1} mm, against {:.1} mm allowed (refine.json): the finer \
                 levels' d_avg are the better figures",
                last.base.particles,
                last.base.max_overlap_fraction,
                last.overlap_move_mm,
                last.grains_move_mm,
                last.allowed_mm
            ));
        }
        self.numerics_error_mm = Some(last.overlap_move_mm.abs().max(last.grains_move_mm.abs()));
        self.numerics = Some(last.clone());
    }
}

/// Share of the loaded mass past the mesh's end above which a comparison warns.
pub const PAST_END_WARN: f64 = 0.01;

/// Fewest model particles a comparison uses: the model's launch randomisation (Eq. 4.38)
/// makes its distribution a sample too, and at a setup's 100 particles its noise (a few
/// percentage points per tooth) would count as model-vs-DEM error. 10 000 cost ~50 ms.
pub const COMPARE_PARTICLES: u32 = 10_000;

/// The model's d_avg (m) and distribution over its teeth for `scenario`, launched from the
/// fill polygon or from `launches` (cycled through for the scenario's particle count).
fn model_run(
    scenario: &Scenario,
    design: &Design,
    launches: Option<&[[f64; 2]]>,
) -> anyhow::Result<crate::model::SimOutcome> {
    let engine = make_engine_for(EngineKind::Cpu, scenario)?;
    let det = match launches {
        Some(l) => evaluate_detailed_from(engine.as_ref(), scenario, design, l),
        None => evaluate_detailed(engine.as_ref(), scenario, design, false),
    }
    .map_err(|e| anyhow::anyhow!("invalid design ({}): {e}", e.rule()))?;
    Ok(det.evaluation.sim)
}

/// Compare the DEM `runs` (tooth masses over the mesh's teeth) with the model on `scenario`
/// (at least [`COMPARE_PARTICLES`] particles), judged on the DEM's mesh; `dem_law` is the
/// DEM's restitution law as `dem impact` measured it for the case, if known.
pub fn compare(
    scenario: &Scenario,
    design: &Design,
    runs: &[RunResult],
    dem_law: Option<&Collision>,
) -> anyhow::Result<Comparison> {
    anyhow::ensure!(!runs.is_empty(), "no DEM runs to compare");
    let teeth = runs[0].teeth_g.len();
    let mut on_mesh = scenario.clone();
    on_mesh.sim.particles = on_mesh.sim.particles.max(COMPARE_PARTICLES);
    on_mesh.sim.teeth = teeth as u32;
    let scenario = &on_mesh;
    let started = std::time::Instant::now();
    let sim = model_run(scenario, design, None)?;
    let model_s = started.elapsed().as_secs_f64();
    let mut long = scenario.clone();
    long.sim.teeth = long.sim.teeth.max(super::case::REACH_CONVEYOR_TEETH);
    let untruncated = model_run(&long, design, None)?;
    let model_untruncated_d_avg_mm = untruncated.d_avg_m * 1e3;
    // every run's settled bed in turn (the first grains of each run, then the second, ...)
    let beds: Vec<&Vec<[f64; 2]>> = runs.iter().map(|r| &r.settled_xy_m).filter(|b| !b.is_empty()).collect();
    let bed: Vec<[f64; 2]> = (0..beds.iter().map(|b| b.len()).max().unwrap_or(0))
        .flat_map(|i| beds.iter().filter_map(move |b| b.get(i).copied()))
        .collect();
    let bed = (beds.len() == runs.len() && !bed.is_empty()).then_some(bed);
    let model_from_bed_d_avg_mm = match &bed {
        Some(b) => Some(model_run(scenario, design, Some(b))?.d_avg_m * 1e3),
        None => None,
    };
    let with_law = match dem_law {
        Some(law) => {
            let mut s = scenario.clone();
            s.collision = law.clone();
            s.validate().map_err(|e| anyhow::anyhow!("the DEM's restitution law: {e}"))?;
            Some(model_run(&s, design, bed.as_deref())?)
        }
        None => None,
    };
    let model_dem_law_d_avg_mm = with_law.as_ref().map(|o| o.d_avg_m * 1e3);
    let model_dem_law_pct =
        with_law.as_ref().map(|o| (0..teeth).map(|j| 100.0 * o.distribution.get(j).copied().unwrap_or(0.0)).collect());
    let model: Vec<f64> = (0..teeth).map(|j| sim.distribution.get(j).copied().unwrap_or(0.0)).collect();
    let fractions: Vec<Vec<f64>> =
        runs.iter().map(|r| r.teeth_g.iter().map(|m| m / r.input_mass_g).collect()).collect();
    let dem_pct: Vec<Spread> =
        (0..teeth).map(|j| spread(&fractions.iter().map(|f| 100.0 * f[j]).collect::<Vec<_>>())).collect();
    let model_pct: Vec<f64> = model.iter().map(|f| 100.0 * f).collect();
    let errors: Vec<f64> = model_pct.iter().zip(&dem_pct).map(|(m, d)| (m - d.mean).abs()).collect();
    let (mc, md) = centre_and_dispersion(&model);
    let (dem_centre, dem_dispersion) = centre_spreads(&fractions);
    let dem_d: Vec<f64> = runs.iter().map(|r| r.d_avg_m * 1e3).collect();
    let dem_d_avg_mm = spread(&dem_d);
    let model_d_avg_mm = sim.d_avg_m * 1e3;
    // the model's particles past the end: those lost on the mesh but not on a long conveyor
    let model_past_end_pct = 100.0 * (sim.lost_fraction - untruncated.lost_fraction).max(0.0);
    let dem_past_end_pct = spread(&runs.iter().map(past_end_pct).collect::<Vec<_>>());
    let mut warnings = truncation_warnings(teeth, model_past_end_pct, dem_past_end_pct.mean);
    let dem_left_by = LeftBy::summed(runs.iter().map(|r| r.left_by));
    warnings.extend(through_mesh_warning(dem_left_by));
    Ok(Comparison {
        teeth,
        runs: runs.len(),
        model_pct,
        dem_lost_pct: spread(
            &runs
                .iter()
                .map(|r| 100.0 * (1.0 - r.teeth_g.iter().sum::<f64>() / r.input_mass_g).max(0.0))
                .collect::<Vec<_>>(),
        ),
        model_lost_pct: 100.0 * sim.lost_fraction,
        dem_pct,
        mean_abs_tooth_error_pp: errors.iter().sum::<f64>() / teeth.max(1) as f64,
        max_abs_tooth_error_pp: errors.iter().copied().fold(0.0, f64::max),
        d_avg_error_pct: (model_d_avg_mm > 0.0).then(|| 100.0 * (dem_d_avg_mm.mean - model_d_avg_mm) / model_d_avg_mm),
        model_d_avg_mm,
        dem_d_avg_mm,
        model_centre: mc,
        dem_centre,
        model_dispersion: md,
        dem_dispersion,
        model_s,
        dem_s: spread(&runs.iter().map(|r| r.wall_s).collect::<Vec<_>>()),
        model_particles: scenario.sim.particles,
        model_past_end_pct,
        dem_past_end_pct,
        model_untruncated_d_avg_mm,
        model_from_bed_d_avg_mm,
        model_dem_law_d_avg_mm,
        model_dem_law_pct,
        dem_left_by,
        numerics: None,
        numerics_error_mm: None,
        warnings,
    })
}

/// The share of a DEM run's grains lost past the mesh's last tooth, %: those resting beyond
/// it and those that left the box past it (`left_by`; a grain that flew off the far end is
/// as truncated as one that came to rest there).
fn past_end_pct(r: &RunResult) -> f64 {
    let deleted = r.left_by.map_or(0, |b| b.past_last_tooth);
    100.0 * (r.past_end + deleted) as f64 / r.grains.max(1) as f64
}

/// A warning for each side that loses more than [`PAST_END_WARN`] of its mass past the
/// mesh's last tooth (`teeth`), given each side's share in %.
fn truncation_warnings(teeth: usize, model_pct: f64, dem_pct: f64) -> Vec<String> {
    [("the model", model_pct), ("the DEM", dem_pct)]
        .into_iter()
        .filter(|(_, pct)| *pct > 100.0 * PAST_END_WARN)
        .map(|(who, pct)| format!(
            "{who} loses {pct:.1} % of its mass past the mesh's last tooth ({teeth}): both sides credit it nothing, so d_avg compares two truncations; lengthen the mesh ([dem] teeth, or leave it unset: the model's reach on a long conveyor)"
        ))
        .collect()
}

/// The warning for DEM grains that passed through the mesh, if any did.
fn through_mesh_warning(left_by: Option<LeftBy>) -> Option<String> {
    left_by.map(|b| b.through_mesh).filter(|n| *n > 0).map(|n| format!(
        "{n} DEM grains passed through the mesh (last seen below its surface or heading into it): a numerical failure of the contact, not physics; halve [dem] max_overlap_fraction and compare"
    ))
}

/// Steady conveying beside the model (`dem run --strokes K`): the DEM's advance per stroke
/// once steady, the model's single-stroke advance (teeth advanced × pitch, along the conveyor,
/// the same measure) and d_avg (D.7's horizontal, p4-credited distance, erratum 16), and the
/// feed rates they give by Eq. 5.16 at the design's full stroke frequency.
#[derive(Clone, Debug, Serialize)]
pub struct SteadyComparison {
    pub runs: usize,
    pub strokes: u32,
    pub period_teeth: u32,
    pub dem: super::conveyor::Steady,
    /// Each run's mean advance over its steady cycles, mm.
    pub dem_per_run_mm: Vec<f64>,
    pub model_advance_mm: f64,
    pub model_d_avg_mm: f64,
    pub f_stroke_hz: f64,
    /// Eq. 5.16 with the model's d_avg: what the optimiser designs with, kg/h.
    pub model_m_dot_kg_h: f64,
    /// Eq. 5.16 with the model's advance along the conveyor, kg/h.
    pub model_m_dot_advance_kg_h: f64,
    /// Eq. 5.16 with the DEM's steady advance: the DEM's own feed rate, kg/h.
    pub dem_m_dot_kg_h: f64,
    pub dem_m_dot_sd_kg_h: f64,
    /// (DEM steady advance − model advance) / model advance, %.
    pub advance_error_pct: Option<f64>,
    pub dem_s: Spread,
    /// Where the DEM's grains that left the box went, over every run; None when a run wrote
    /// no track.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dem_left_by: Option<LeftBy>,
    /// Why this comparison may not be trusted (grains through the mesh, ...).
    pub warnings: Vec<String>,
}

/// The steady runs of a `dem run --strokes` campaign beside the model on `scenario`.
pub fn compare_steady(
    scenario: &Scenario,
    design: &Design,
    runs: &[super::conveyor::SteadyRun],
) -> anyhow::Result<SteadyComparison> {
    let st = super::conveyor::steady(runs)?;
    let mut s = scenario.clone();
    s.sim.particles = s.sim.particles.max(COMPARE_PARTICLES);
    s.sim.teeth = s.sim.teeth.max(super::case::REACH_CONVEYOR_TEETH);
    let sim = model_run(&s, design, None)?;
    let prep = crate::model::prepare(&s, design).map_err(|e| anyhow::anyhow!("invalid design ({}): {e}", e.rule()))?;
    let perf = crate::model::performance::performance(&s, design, sim.d_avg_m, prep.fill.area);
    let feed = |x: f64| perf.regolith_mass_kg * (x / s.performance.conveyor_length) * perf.f_stroke_hz * 3600.0;
    let dem_left_by = LeftBy::summed(runs.iter().map(|r| r.left_by));
    let per_run: Vec<f64> = runs
        .iter()
        .map(|r| r.cycles[1..].iter().map(|c| c.advance_m).sum::<f64>() / (r.cycles.len() - 1) as f64)
        .collect();
    Ok(SteadyComparison {
        runs: runs.len(),
        strokes: runs[0].cycles.len() as u32,
        period_teeth: runs[0].period_teeth,
        dem_per_run_mm: per_run.iter().map(|x| x * 1e3).collect(),
        model_advance_mm: sim.advance_m * 1e3,
        model_d_avg_mm: sim.d_avg_m * 1e3,
        f_stroke_hz: perf.f_stroke_hz,
        model_m_dot_kg_h: perf.m_dot_kg_s * 3600.0,
        model_m_dot_advance_kg_h: feed(sim.advance_m),
        dem_m_dot_kg_h: feed(st.advance_m),
        dem_m_dot_sd_kg_h: feed(st.advance_sd_m),
        advance_error_pct: (sim.advance_m > 0.0).then(|| 100.0 * (st.advance_m - sim.advance_m) / sim.advance_m),
        dem: st,
        dem_s: spread(&runs.iter().map(|r| r.wall_s).collect::<Vec<_>>()),
        dem_left_by,
        warnings: through_mesh_warning(dem_left_by).into_iter().collect(),
    })
}

/// The teeth a table or figure shows: up to the last tooth either side fills ≥ 0.5 %.
pub fn shown_teeth(c: &Comparison) -> usize {
    let last = (0..c.teeth).rev().find(|&j| c.model_pct[j] >= 0.5 || c.dem_pct[j].mean >= 0.5).unwrap_or(0);
    (last + 1).max(2).min(c.teeth)
}

/// Bars per tooth: model and DEM (mean, with ±1 sd over the seeds), and the lost mass.
pub struct ComparisonPlot<'a> {
    c: &'a Comparison,
    /// The environment and the number of seeds.
    title: String,
    /// The design, one line with its units under the title (a title that held it too would
    /// shrink to fit and be hard to read).
    design: String,
}

const WIDTH_PX: u32 = 900;
const PANEL_PX: u32 = 420;

impl<'a> ComparisonPlot<'a> {
    /// The figure of `c`, the comparison of `design` in `scenario` over `seeds` DEM runs.
    pub fn new(c: &'a Comparison, scenario: &Scenario, design: &Design, seeds: usize) -> Self {
        let env = &scenario.environment;
        let title = format!(
            "Model vs DEM: alpha {} deg, g {} m/s^2{} | {seeds} seeds",
            env.alpha_deg,
            env.g,
            env.k_drag.map_or(String::new(), |k| format!(", k_drag {k} 1/s")),
        );
        ComparisonPlot { c, title, design: DesignRow::of(design).to_string() }
    }

    fn legend() -> [(Mark, &'static str); 3] {
        [
            (Mark::Block(plot::PALETTE[0]), "model (cpu engine)"),
            (Mark::Block(plot::PALETTE[1]), "DEM (LIGGGHTS), mean of the seeds"),
            (Mark::Line(BLACK), "DEM ±1 sd over the seeds"),
        ]
    }
}

impl Figure for ComparisonPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let heading = plot::title_height() + plot::wrapped_height(WIDTH_PX, &self.design, plot::SMALL_SIZE);
        (WIDTH_PX, heading + PANEL_PX + plot::legend_height(WIDTH_PX, &Self::legend()))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let c = self.c;
        let area = plot::title(root, &self.title)?;
        let (line, area) = area.split_vertically(plot::wrapped_height(WIDTH_PX, &self.design, plot::SMALL_SIZE));
        plot::draw_wrapped(&line, &self.design, plot::SMALL_SIZE)?;
        let (panel, key) = area.split_vertically(PANEL_PX);
        let n = shown_teeth(c);
        let mut labels: Vec<String> = (1..=n).map(|j| j.to_string()).collect();
        labels.push("lost".into());
        let mut model: Vec<f64> = c.model_pct[..n].to_vec();
        model.push(c.model_lost_pct);
        let mut dem: Vec<(f64, f64)> = c.dem_pct[..n].iter().map(|s| (s.mean, s.sd)).collect();
        dem.push((c.dem_lost_pct.mean, c.dem_lost_pct.sd));
        let hi = model.iter().copied().chain(dem.iter().map(|(m, s)| m + s)).fold(1.0f64, f64::max);
        let mut chart =
            plot::category_chart(&panel, None, &labels, 0.0..hi * 1.08, "tooth", "share of the loaded mass [%]")?;
        const BAR: f64 = 0.35;
        for (k, (m, (d, sd))) in model.iter().zip(&dem).enumerate() {
            let x = k as f64;
            chart.draw_series([Rectangle::new([(x - BAR, 0.0), (x, *m)], plot::PALETTE[0].filled())]).drawn()?;
            chart.draw_series([Rectangle::new([(x, 0.0), (x + BAR, *d)], plot::PALETTE[1].filled())]).drawn()?;
            let xm = x + BAR / 2.0;
            chart
                .draw_series([PathElement::new(vec![(xm, (d - sd).max(0.0)), (xm, d + sd)], BLACK.stroke_width(2))])
                .drawn()?;
        }
        plot::legend(&key, &Self::legend())
    }
}

/// The spread over runs of the centre of mass and the dispersion (Eq. 4.57-4.58) of each run's
/// per-tooth fractions. A run that lost every grain has no centre: the spread is over the runs
/// with grains on the teeth (NaN only when no run kept one).
fn centre_spreads(fractions: &[Vec<f64>]) -> (Spread, Spread) {
    let com: Vec<(f64, f64)> =
        fractions.iter().map(|f| centre_and_dispersion(f)).filter(|(c, d)| c.is_finite() && d.is_finite()).collect();
    (spread(&com.iter().map(|c| c.0).collect::<Vec<_>>()), spread(&com.iter().map(|c| c.1).collect::<Vec<_>>()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_that_lost_every_grain_leaves_the_centre_to_the_runs_that_kept_some() {
        let (c, d) = centre_spreads(&[vec![0.0, 1.0, 0.0], vec![0.0; 3], vec![0.0, 0.0, 1.0]]);
        assert_eq!((c.mean, d.mean), (2.5, 0.0));
        assert!((c.sd - 0.5f64.sqrt()).abs() < 1e-12, "{c:?}");
        let (c, d) = centre_spreads(&[vec![0.0; 3], vec![0.0; 3]]);
        assert!(c.mean.is_nan() && c.sd.is_nan() && d.mean.is_nan(), "{c:?} {d:?}");
    }

    #[test]
    fn grains_that_flew_off_the_far_end_count_as_truncated_like_those_resting_there() {
        let run = |past_end, past_last_tooth| RunResult {
            teeth_g: vec![1.0; 4],
            input_mass_g: 10.0,
            grains: 200,
            lost: past_end + past_last_tooth,
            left_box: past_last_tooth,
            past_end,
            left_by: Some(LeftBy { past_last_tooth, ..LeftBy::default() }),
            seed: 0,
            moving: 0,
            d_avg_m: 0.1,
            wall_s: 1.0,
            settled_xy_m: Vec::new(),
        };
        assert_eq!(past_end_pct(&run(0, 0)), 0.0);
        assert_eq!(past_end_pct(&run(2, 0)), 1.0);
        // 2 % gone from the box past the end and none resting there: still a truncation
        assert_eq!(past_end_pct(&run(0, 4)), 2.0);
        assert_eq!(past_end_pct(&run(1, 3)), 2.0);
        // a run without a track counts what rests past the end
        assert_eq!(past_end_pct(&RunResult { left_by: None, ..run(2, 0) }), 1.0);
        let warned = truncation_warnings(18, 0.5, past_end_pct(&run(0, 4)));
        assert_eq!(warned.len(), 1, "{warned:?}");
        assert!(warned[0].starts_with("the DEM loses 2.0 % of its mass past the mesh's last tooth (18)"), "{warned:?}");
        assert!(truncation_warnings(18, 1.0, 1.0).is_empty(), "at the threshold: no warning");
    }

    #[test]
    fn a_comparison_carries_the_numerics_error_of_its_own_refinement_or_warns_that_it_has_none() {
        use crate::dem::refine::{judge, Rung};
        let rung = |d_avg_mm: f64, particles| Rung {
            max_overlap_fraction: 0.025,
            particles,
            dir: ".".into(),
            d_avg_mm,
            d_avg_sd_mm: 2.0,
            wall_s: 1.0,
        };
        let runs = |d: &[f64]| -> Vec<RunResult> {
            d.iter()
                .map(|&d_avg_mm| RunResult {
                    teeth_g: vec![1.0; 4],
                    input_mass_g: 4.0,
                    grains: 10,
                    lost: 0,
                    left_box: 0,
                    past_end: 0,
                    left_by: None,
                    seed: 0,
                    moving: 0,
                    d_avg_m: d_avg_mm * 1e-3,
                    wall_s: 1.0,
                    settled_xy_m: Vec::new(),
                })
                .collect()
        };
        let base = || compare(&Scenario::earth(), &Design::validation_rig(), &runs(&[99.0, 101.0]), None).unwrap();
        // none: a warning that says how to get one
        let mut c = base();
        c.attach_numerics(None);
        assert!(c.numerics.is_none() && c.numerics_error_mm.is_none());
        assert!(c.warnings.iter().any(|w| w.contains("not checked") && w.contains("--refine")), "{:?}", c.warnings);
        // converged: the larger move is the error, no warning
        let ok = judge(rung(100.0, 150), rung(101.0, 150), rung(98.5, 300));
        assert!(ok.converged);
        let mut c = base();
        let before = c.warnings.len();
        c.attach_numerics(Some(&Refinement { levels: vec![ok.clone()], converged: true }));
        assert_eq!(c.numerics_error_mm, Some(1.5));
        assert_eq!(c.numerics.as_ref(), Some(&ok));
        assert_eq!(c.warnings.len(), before, "{:?}", c.warnings);
        // not converged: the moves and the allowance in the warning
        let far = judge(rung(100.0, 150), rung(101.0, 150), rung(139.0, 300));
        let mut c = base();
        c.attach_numerics(Some(&Refinement { levels: vec![far], converged: false }));
        assert_eq!(c.numerics_error_mm, Some(39.0));
        assert!(c.warnings.iter().any(|w| w.contains("not converged") && w.contains("+39.0 mm")), "{:?}", c.warnings);
        // a ladder of other runs is not this campaign's error
        let other = judge(rung(120.0, 150), rung(121.0, 150), rung(119.0, 300));
        let mut c = base();
        c.attach_numerics(Some(&Refinement { levels: vec![other], converged: true }));
        assert!(c.numerics.is_none());
        assert!(c.warnings.iter().any(|w| w.contains("other runs")), "{:?}", c.warnings);
    }
}
