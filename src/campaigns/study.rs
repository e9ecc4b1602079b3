//! The summaries of the optimiser studies (5.4.1-5.4.2, Tables C.1-C.3, Figure 5.3): many
//! optimisation runs, each compared at the target mass flow: repeatability (independent
//! seeds: runs.csv, summary.csv, repeatability.svg) and sensitivity (a grid of collision and
//! drag parameters: grid.csv, sensitivity.svg), each with its table.

use std::io::Write;
use std::path::Path;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::panels::{Panel, PanelsPlot, Series};
use super::plan::Plan;
use crate::io::table::{optional_columns, write_table};
use crate::model::design::DesignRow;
use crate::optim::front::{closest_to_mass_flow, FrontPoint};
use crate::plot;

/// Mean, sample standard deviation, coefficient of variation, half-width of the 95 %
/// confidence interval of the mean (normal approximation).
fn stats(v: &[f64]) -> (f64, f64, f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let sd = if v.len() > 1 { (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() } else { f64::NAN };
    (m, sd, sd / m, 1.96 * sd / n.sqrt())
}

/// The figures of the front point a run is compared at: the columns runs.csv and grid.csv
/// share, in place in each (empty, with the design's, where the run's front holds no design).
#[derive(Debug, Default, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointFigures {
    pub f_stroke_hz: f64,
    pub w_spec_j_kg: f64,
    pub m_dot_kg_s: f64,
    pub d_avg_m: f64,
    pub n_wire: u32,
}

impl PointFigures {
    fn of(p: &FrontPoint) -> Self {
        PointFigures {
            f_stroke_hz: p.f_stroke_hz,
            w_spec_j_kg: p.w_spec_j_kg,
            m_dot_kg_s: p.m_dot_kg_s,
            d_avg_m: p.d_avg_m,
            n_wire: p.n_wire,
        }
    }
}

/// One row of runs.csv (study repeatability): a run's front point closest to the target.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct RunRow {
    pub run: usize,
    pub seed: u64,
    #[serde(flatten, serialize_with = "optional_columns")]
    pub figures: Option<PointFigures>,
    #[serde(flatten, serialize_with = "optional_columns")]
    pub design: Option<DesignRow>,
    /// (m_dot - target) / target, -.
    pub m_dot_from_target_rel: Option<f64>,
    /// Within ±AT_TARGET_REL of the target.
    pub at_target: Option<bool>,
}

/// One row of grid.csv (study sensitivity): a grid point's front point closest to the target.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct GridRow {
    pub point: usize,
    pub k_elastic: f64,
    pub mu_friction: f64,
    /// Stokes drag, 1/s (0 = vacuum).
    pub k_drag_per_s: f64,
    #[serde(flatten, serialize_with = "optional_columns")]
    pub figures: Option<PointFigures>,
    #[serde(flatten, serialize_with = "optional_columns")]
    pub design: Option<DesignRow>,
    /// W_spec inside the repeatability study's 95 % interval (with --repeatability).
    pub w_spec_within_repeatability_ci: Option<bool>,
}

/// One row of a study's summary.csv: a metric over the runs.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct SummaryRow {
    /// The figure summarised, its unit in its name (f_stroke_hz, w_spec_j_kg, m_dot_kg_s).
    pub metric: String,
    pub mean: f64,
    pub sd: f64,
    /// sd / mean, -.
    pub cv: f64,
    pub ci95_half_width: f64,
    pub n: usize,
}

/// How near the target mass flow a run's chosen point must lie to count as "at" it: runs
/// whose fronts hold nothing nearer are still compared, but the report says they are not at
/// the target (relative distance).
pub const AT_TARGET_REL: f64 = 0.10;

/// runs.csv, summary.csv, repeatability.svg and the table of a finished repeatability study.
pub fn summarise_repeatability(
    root: &Path,
    plan: &Plan,
    t: f64,
    fronts: &[Vec<FrontPoint>],
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    let (mut f, mut w, mut m) = (Vec::new(), Vec::new(), Vec::new());
    let mut far = Vec::new();
    for (i, (member, front)) in plan.members.iter().zip(fronts).enumerate() {
        let p = closest_to_mass_flow(front, t);
        // a run's front may hold nothing near the target: say how far its chosen point is
        let distance = p.map(|p| (p.m_dot_kg_s - t) / t);
        let at_target = distance.map(|d| d.abs() <= AT_TARGET_REL);
        if let (Some(p), Some(false)) = (p, at_target) {
            far.push(format!("run {i} at {:.4} kg/s", p.m_dot_kg_s));
        }
        rows.push(RunRow {
            run: i,
            seed: member.manifest.scenario.sim.seed,
            figures: p.map(PointFigures::of),
            design: p.map(|p| DesignRow::of(&p.design)),
            m_dot_from_target_rel: distance,
            at_target,
        });
        if let Some(p) = p {
            f.push(p.f_stroke_hz);
            w.push(p.w_spec_j_kg);
            m.push(p.m_dot_kg_s);
        }
    }
    write_table(&root.join("runs.csv"), &rows)?;
    let mut summary = Vec::new();
    if far.is_empty() {
        writeln!(
            out,
            "{} runs compared at {t} kg/s (each at its front design within ±{:.0} % of it):",
            f.len(),
            AT_TARGET_REL * 100.0
        )?;
    } else {
        writeln!(
            out,
            "{} runs compared at their front designs closest to {t} kg/s; NOT at the target for {} of them ({}; more than ±{:.0} % away), so the spread below mixes operating points:",
            f.len(),
            far.len(),
            far.join(", "),
            AT_TARGET_REL * 100.0
        )?;
    }
    for (name, v) in [("f_stroke_hz", &f), ("w_spec_j_kg", &w), ("m_dot_kg_s", &m)] {
        let (mean, sd, cv, ci) = stats(v);
        summary.push(SummaryRow { metric: name.to_string(), mean, sd, cv, ci95_half_width: ci, n: v.len() });
        writeln!(out, "  {name:<12} mean {mean:.5e}  sd {sd:.3e}  CV {:.3} %  95% CI ± {ci:.3e}", cv * 100.0)?;
    }
    write_table(&root.join("summary.csv"), &summary)?;
    // independent runs: each a point, with the mean and its 95 % interval as a band
    let panel = |y_desc: &str, v: Vec<f64>| {
        let (mean, _, _, ci) = stats(&v);
        Panel {
            y_desc: y_desc.into(),
            series: vec![Series { label: "run (closest to the target mass flow)".into(), y: v, se: None }],
            band: Some((mean, ci, "mean ± 95 % confidence interval".into())),
        }
    };
    let figure = PanelsPlot {
        title: format!("Repeatability: {} runs at {t} kg/s", f.len()),
        x_desc: "run".into(),
        x: (0..f.len()).map(|i| i as f64).collect(),
        x_categories: Some((0..f.len()).map(|i| i.to_string()).collect()),
        panels: vec![panel("f_stroke [Hz]", f), panel("W_spec [J/kg]", w), panel("mass flow [kg/s]", m)],
        joined: false,
    };
    plot::write_figure_files(root, "repeatability", &figure)?;
    Ok(())
}

/// Mean and CI half-width of W_spec from a repeatability study's summary.csv.
/// The repeatability study's W_spec mean and 95 % half-width, read back from its
/// summary.csv (the sensitivity study is judged against it).
pub fn read_ci(dir: &Path) -> anyhow::Result<(f64, f64)> {
    let path = dir.join("summary.csv");
    let text = crate::io::bounded::read_text(&path, &crate::schema::SUMMARY_FILE).context("--repeatability")?;
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    for row in reader.deserialize::<SummaryRow>() {
        let row = row.with_context(|| format!("--repeatability: reading {}", path.display()))?;
        if row.metric == "w_spec_j_kg" {
            return Ok((row.mean, row.ci95_half_width));
        }
    }
    bail!("{}: no w_spec_j_kg row", path.display())
}

/// The sensitivity study's grid (Tables C.2-C.3): factors on (k_elastic, mu, k_drag), five
/// steps of 5 % on the two collision parameters in vacuum, three of 10 % on all three with
/// drag.
pub fn sensitivity_grid(with_drag: bool) -> Vec<[f64; 3]> {
    if with_drag {
        let f = [0.9, 1.0, 1.1];
        let mut g = Vec::new();
        for ke in f {
            for mu in f {
                for kd in f {
                    g.push([ke, mu, kd]);
                }
            }
        }
        g
    } else {
        let f = [0.9, 0.95, 1.0, 1.05, 1.1];
        f.iter().flat_map(|&ke| f.iter().map(move |&mu| [ke, mu, 1.0])).collect()
    }
}

/// grid.csv, sensitivity.svg and the table of a finished sensitivity study.
pub fn summarise_sensitivity(
    root: &Path,
    plan: &Plan,
    t: f64,
    ci: Option<(f64, f64)>,
    fronts: &[Vec<FrontPoint>],
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    let mut w = Vec::new();
    writeln!(
        out,
        "{:>5} {:>9} {:>9} {:>9} {:>14} {:>12}",
        "point", "k_elastic", "mu", "k_drag", "W_spec [J/kg]", "in CI"
    )?;
    for (i, (member, front)) in plan.members.iter().zip(fronts).enumerate() {
        let s = &member.manifest.scenario;
        let p = closest_to_mass_flow(front, t);
        let within = match (ci, p) {
            (Some((mean, half)), Some(p)) => Some((p.w_spec_j_kg - mean).abs() <= half),
            _ => None,
        };
        rows.push(GridRow {
            point: i,
            k_elastic: s.collision.k_elastic,
            mu_friction: s.collision.mu_friction,
            k_drag_per_s: s.environment.k_drag.unwrap_or(0.0),
            figures: p.map(PointFigures::of),
            design: p.map(|p| DesignRow::of(&p.design)),
            w_spec_within_repeatability_ci: within,
        });
        let wv = p.map_or(f64::NAN, |p| p.w_spec_j_kg);
        w.push(wv);
        writeln!(
            out,
            "{i:>5} {:>9.4} {:>9.4} {:>9.3} {:>14.1} {:>12}",
            s.collision.k_elastic,
            s.collision.mu_friction,
            s.environment.k_drag.unwrap_or(0.0),
            wv,
            within.map_or(String::new(), |w| w.to_string())
        )?;
    }
    write_table(&root.join("grid.csv"), &rows)?;
    let figure = PanelsPlot {
        title: format!("Sensitivity at {t} kg/s"),
        x_desc: "grid point (see grid.csv)".into(),
        x: (0..w.len()).map(|i| i as f64).collect(),
        x_categories: Some((0..w.len()).map(|i| i.to_string()).collect()),
        panels: vec![Panel {
            y_desc: "W_spec [J/kg]".into(),
            series: vec![Series { label: "grid point (closest to the target mass flow)".into(), y: w, se: None }],
            band: ci.map(|(mean, half)| (mean, half, "repeatability: mean ± 95 % confidence interval".into())),
        }],
        joined: false,
    };
    plot::write_figure_files(root, "sensitivity", &figure)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::table::table_text;
    use crate::model::Design;

    /// A run whose front holds no design keeps its figure and design cells, empty, so the
    /// columns after them stay in place; both rows read back as written.
    #[test]
    fn a_run_without_a_design_has_empty_figure_and_design_cells_and_reads_back() {
        let design = DesignRow::of(&Design::lunar_solution_c());
        let figures =
            PointFigures { f_stroke_hz: 0.03, w_spec_j_kg: 350.5, m_dot_kg_s: 0.0133, d_avg_m: 0.25, n_wire: 20 };
        let rows = [
            RunRow { run: 0, seed: 7, at_target: None, ..Default::default() },
            RunRow {
                run: 1,
                seed: 8,
                figures: Some(figures),
                design: Some(design),
                m_dot_from_target_rel: Some(-0.25),
                at_target: Some(false),
            },
        ];
        let text = table_text(&rows).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "run,seed,f_stroke_hz,w_spec_j_kg,m_dot_kg_s,d_avg_m,n_wire,\
             l_c_mm,l_a_mm,l_b_mm,r_mm,omega_deg,delta_deg,v0_m_s,a_m_s2,m_dot_from_target_rel,at_target"
        );
        assert_eq!(lines[1], "0,7,,,,,,,,,,,,,,,");
        assert!(lines[2].starts_with("1,8,0.03,350.5,0.0133,0.25,20,47.346,46.898,32.183,43.687,"), "{text}");
        assert!(lines[2].ends_with(",32.051,-0.25,false"), "{text}");
        let back: Vec<RunRow> =
            csv::Reader::from_reader(text.as_bytes()).deserialize().collect::<Result<_, _>>().unwrap();
        assert_eq!((back[0].figures, back[0].design), (None, None));
        assert_eq!((back[1].figures, back[1].design), (Some(figures), Some(design)));
        assert_eq!(back[1].at_target, Some(false));
    }

    /// grid.csv holds the same figure columns in its own place, after the grid's parameters.
    #[test]
    fn a_grid_row_puts_the_shared_figures_after_its_parameters() {
        let header = crate::io::table::csv_header::<GridRow>().unwrap();
        assert!(
            header.starts_with(
                "point,k_elastic,mu_friction,k_drag_per_s,f_stroke_hz,w_spec_j_kg,m_dot_kg_s,d_avg_m,n_wire,l_c_mm,"
            ),
            "{header}"
        );
        assert!(header.ends_with(",a_m_s2,w_spec_within_repeatability_ci\n"), "{header}");
    }
}
