//! The model beside the DEM for one campaign: per tooth share of the loaded mass, lost mass,
//! d_avg, centre of mass and dispersion (Eq. 4.56-4.59), with the DEM's spread over its
//! seeds, and what each cost.
//!
//! The model's particles past the mesh's last tooth are what the DEM counts lost there, so
//! the model's "lost" here is its own lost fraction plus its share beyond the mesh.

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use super::gather::RunResult;
use crate::engine::{evaluate_detailed, make_engine_for, EngineKind};
use crate::model::design::DesignRow;
use crate::model::outcome::centre_and_dispersion;
use crate::model::{Design, Scenario};
use crate::plot::{self, Drawn, Figure, Mark};

#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    pub mean: f64,
    /// Sample standard deviation over the runs (0 for one run).
    pub sd: f64,
}

fn spread(v: &[f64]) -> Spread {
    let n = v.len().max(1) as f64;
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
}

/// Fewest model particles a comparison uses: the model's launch randomisation (Eq. 4.38)
/// makes its distribution a sample too, and at a setup's 100 particles its noise (a few
/// percentage points per tooth) would count as model-vs-DEM error. 10 000 cost ~50 ms.
pub const COMPARE_PARTICLES: u32 = 10_000;

/// Compare the DEM `runs` (tooth masses over the mesh's teeth) with the model on `scenario`
/// (at least [`COMPARE_PARTICLES`] particles).
pub fn compare(scenario: &Scenario, design: &Design, runs: &[RunResult]) -> anyhow::Result<Comparison> {
    anyhow::ensure!(!runs.is_empty(), "no DEM runs to compare");
    let mut scenario = scenario.clone();
    scenario.sim.particles = scenario.sim.particles.max(COMPARE_PARTICLES);
    let scenario = &scenario;
    let teeth = runs[0].teeth_g.len();
    let engine = make_engine_for(EngineKind::Cpu, scenario)?;
    let started = std::time::Instant::now();
    let det = evaluate_detailed(engine.as_ref(), scenario, design, false)
        .map_err(|e| anyhow::anyhow!("invalid design ({}): {e}", e.rule()))?;
    let model_s = started.elapsed().as_secs_f64();
    let sim = &det.evaluation.sim;
    let model: Vec<f64> = (0..teeth).map(|j| sim.distribution.get(j).copied().unwrap_or(0.0)).collect();
    let beyond: f64 = sim.distribution.iter().skip(teeth).sum();
    let fractions: Vec<Vec<f64>> =
        runs.iter().map(|r| r.teeth_g.iter().map(|m| m / r.input_mass_g).collect()).collect();
    let dem_pct: Vec<Spread> =
        (0..teeth).map(|j| spread(&fractions.iter().map(|f| 100.0 * f[j]).collect::<Vec<_>>())).collect();
    let model_pct: Vec<f64> = model.iter().map(|f| 100.0 * f).collect();
    let errors: Vec<f64> = model_pct.iter().zip(&dem_pct).map(|(m, d)| (m - d.mean).abs()).collect();
    let (mc, md) = centre_and_dispersion(&model);
    let com: Vec<(f64, f64)> = fractions.iter().map(|f| centre_and_dispersion(f)).collect();
    let dem_d: Vec<f64> = runs.iter().map(|r| r.d_avg_m * 1e3).collect();
    let dem_d_avg_mm = spread(&dem_d);
    let model_d_avg_mm = sim.d_avg_m * 1e3;
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
        model_lost_pct: 100.0 * (sim.lost_fraction + beyond),
        dem_pct,
        mean_abs_tooth_error_pp: errors.iter().sum::<f64>() / teeth.max(1) as f64,
        max_abs_tooth_error_pp: errors.iter().copied().fold(0.0, f64::max),
        d_avg_error_pct: (model_d_avg_mm > 0.0).then(|| 100.0 * (dem_d_avg_mm.mean - model_d_avg_mm) / model_d_avg_mm),
        model_d_avg_mm,
        dem_d_avg_mm,
        model_centre: mc,
        dem_centre: spread(&com.iter().map(|c| c.0).collect::<Vec<_>>()),
        model_dispersion: md,
        dem_dispersion: spread(&com.iter().map(|c| c.1).collect::<Vec<_>>()),
        model_s,
        dem_s: spread(&runs.iter().map(|r| r.wall_s).collect::<Vec<_>>()),
        model_particles: scenario.sim.particles,
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
