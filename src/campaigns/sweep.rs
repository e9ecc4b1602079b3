//! The summary of a conveyor-angle sweep (5.4.3, Figure 5.5, Tables C.4-C.5): one
//! optimisation per angle, and per angle the picks A/B/C of its front (summary.csv, sweep.svg
//! and .png, the table).

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::panels::{Panel, PanelsPlot, Series};
use super::plan::Plan;
use crate::io::table::write_table;
use crate::model::design::DesignRow;
use crate::optim::front::FrontPoint;
use crate::optim::front::{closest_to_mass_flow, picks, TARGET_MASS_FLOW_KG_S};
use crate::plot;

#[derive(Debug, Default, Serialize, Deserialize)]
pub struct SweepRow {
    pub alpha_deg: f64,
    pub pick: String,
    pub f_stroke_hz: f64,
    pub w_spec_j_kg: f64,
    /// Monte-Carlo standard errors of the re-evaluation.
    pub w_spec_se_j_kg: f64,
    pub m_dot_kg_s: f64,
    pub m_dot_se_kg_s: f64,
    pub d_avg_m: f64,
    pub n_wire: u32,
    #[serde(flatten)]
    pub design: DesignRow,
}

/// summary.csv, sweep.svg and the table of a finished sweep.
pub fn summarise(root: &Path, plan: &Plan, fronts: &[Vec<FrontPoint>], out: &mut dyn Write) -> anyhow::Result<()> {
    let angles: Vec<f64> = plan.members.iter().map(|m| m.manifest.scenario.environment.alpha_deg).collect();
    let mode = plan.members.first().map(|m| m.manifest.scenario.mode);
    let mut rows = Vec::new();
    // per pick (C, then closest to the target): f_stroke, W_spec ± se, mass flow ± se
    let mut series: [Vec<f64>; 10] = Default::default();
    writeln!(out, "{:>6} {:>4} {:>12} {:>14} {:>12}", "alpha", "pick", "f [Hz e-2]", "W_spec [J/kg]", "m_dot [kg/h]")?;
    for (alpha, front) in angles.iter().zip(fronts) {
        let ps = picks(front);
        for (name, p) in &ps {
            rows.push(SweepRow {
                alpha_deg: *alpha,
                pick: name.to_string(),
                f_stroke_hz: p.f_stroke_hz,
                w_spec_j_kg: p.w_spec_j_kg,
                w_spec_se_j_kg: p.w_spec_se,
                m_dot_kg_s: p.m_dot_kg_s,
                m_dot_se_kg_s: p.m_dot_se,
                d_avg_m: p.d_avg_m,
                n_wire: p.n_wire,
                design: DesignRow::of(&p.design),
            });
            writeln!(
                out,
                "{alpha:>6.1} {name:>4} {:>12.3} {:>14.1} {:>12.2}",
                p.f_stroke_hz * 100.0,
                p.w_spec_j_kg,
                p.m_dot_kg_s * 3600.0
            )?;
        }
        let c = ps.iter().find(|(n, _)| *n == "C").map(|(_, p)| *p);
        let t = closest_to_mass_flow(front, TARGET_MASS_FLOW_KG_S);
        for (k, p) in [c, t].into_iter().enumerate() {
            series[5 * k].push(p.map_or(f64::NAN, |p| p.f_stroke_hz));
            series[5 * k + 1].push(p.map_or(f64::NAN, |p| p.w_spec_j_kg));
            series[5 * k + 2].push(p.map_or(f64::NAN, |p| p.w_spec_se));
            series[5 * k + 3].push(p.map_or(f64::NAN, |p| p.m_dot_kg_s * 3600.0));
            series[5 * k + 4].push(p.map_or(f64::NAN, |p| p.m_dot_se * 3600.0));
        }
    }
    write_table(&root.join("summary.csv"), &rows)?;
    let [f_c, w_c, w_c_se, m_c, m_c_se, f_a, w_a, w_a_se, m_a, m_a_se] = series;
    let (c, a) = ("lowest W_spec (C)", "closest to 48 kg/h (A)");
    let pair = |y_desc: &str, yc: Vec<f64>, sc: Option<Vec<f64>>, ya: Vec<f64>, sa: Option<Vec<f64>>| Panel {
        y_desc: y_desc.into(),
        series: vec![Series { label: c.into(), y: yc, se: sc }, Series { label: a.into(), y: ya, se: sa }],
        band: None,
    };
    let figure = PanelsPlot {
        title: format!("Conveyor-angle sweep ({:?} mode)", mode.unwrap_or_default()),
        x_desc: "conveyor angle alpha [deg]".into(),
        x: angles,
        x_categories: None,
        panels: vec![
            pair("f_stroke [Hz]", f_c, None, f_a, None),
            pair("W_spec [J/kg]", w_c, Some(w_c_se), w_a, Some(w_a_se)),
            pair("mass flow [kg/h]", m_c, Some(m_c_se), m_a, Some(m_a_se)),
        ],
        joined: true,
    };
    plot::write_figure_files(root, "sweep", &figure)?;
    writeln!(out, "wrote {} and {} (and .png)", root.join("summary.csv").display(), root.join("sweep.svg").display())?;
    Ok(())
}
