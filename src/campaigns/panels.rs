//! The campaign figures: panels that share one x axis (angles of a sweep, runs of a study),
//! each with its series, optional standard-error bars and a band, drawn through `crate::plot`.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::plot::{self, Drawn as _, Figure, Mark, PALETTE};

/// One named series of a panel: a y value per x, with optional ± standard errors.
pub struct Series {
    pub label: String,
    pub y: Vec<f64>,
    pub se: Option<Vec<f64>>,
}

/// One panel of [`PanelsPlot`]: its y axis title (with unit), its series and optionally a
/// horizontal band (centre, half width, legend text) such as a mean and its interval.
pub struct Panel {
    pub y_desc: String,
    pub series: Vec<Series>,
    pub band: Option<(f64, f64, String)>,
}

/// The campaign summary figure (sweep.svg, repeatability.svg, sensitivity.svg): stacked
/// panels over one x axis. `joined` draws each series as a line through its markers (a sweep
/// over a continuous parameter); otherwise the points stand alone (independent runs).
pub struct PanelsPlot {
    pub title: String,
    pub x_desc: String,
    pub x: Vec<f64>,
    /// Category labels for x = 0, 1, 2, ... (run numbers, grid points) instead of numeric ticks.
    pub x_categories: Option<Vec<String>>,
    pub panels: Vec<Panel>,
    pub joined: bool,
}

const PANELS_WIDTH_PX: u32 = 900;
const PANEL_PX: u32 = 260;
const BAND_COLOUR: RGBColor = RGBColor(0x99, 0x99, 0x99);

impl PanelsPlot {
    fn legend(&self) -> Vec<(Mark, String)> {
        let mut out: Vec<(Mark, String)> = Vec::new();
        let first = self.panels.first();
        for (c, s) in first.map_or(&[][..], |p| &p.series[..]).iter().enumerate() {
            let colour = PALETTE[c % PALETTE.len()];
            out.push((if self.joined { Mark::Line(colour) } else { Mark::Point(colour) }, s.label.clone()));
        }
        if self.panels.iter().any(|p| p.series.iter().any(|s| s.se.is_some())) {
            out.push((Mark::Interval(BLACK), "±1 standard error (re-evaluation)".into()));
        }
        if let Some((_, _, label)) = self.panels.iter().find_map(|p| p.band.as_ref()) {
            out.push((Mark::Block(BAND_COLOUR), label.clone()));
        }
        out
    }

    fn legend_px(&self) -> u32 {
        let legend = self.legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        plot::legend_height(PANELS_WIDTH_PX, &entries)
    }

    fn draw_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        panel: &Panel,
        last: bool,
    ) -> anyhow::Result<()> {
        let x = match &self.x_categories {
            Some(labels) => plot::category_range(labels.len()),
            None => {
                let (lo, hi) = plot::extent(self.x.iter().copied()).unwrap_or((0.0, 1.0));
                plot::padded(lo, hi, 0.05)
            }
        };
        let values = panel.series.iter().flat_map(|s| {
            s.y.iter().enumerate().flat_map(move |(i, v)| {
                let e = s.se.as_ref().and_then(|e| e.get(i)).copied().filter(|e| e.is_finite()).unwrap_or(0.0);
                [v - e, v + e]
            })
        });
        let band = panel.band.iter().flat_map(|(c, h, _)| [c - h, c + h]);
        let (lo, hi) = plot::extent(values.chain(band)).unwrap_or((0.0, 1.0));
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .margin_right(25)
            .x_label_area_size(if last { 50 } else { 30 })
            .y_label_area_size(90)
            .build_cartesian_2d(x, plot::padded(lo, hi, 0.08))
            .drawn()?;
        let category_label = self.x_categories.as_deref().map(plot::category_label);
        let mut mesh = plot::styled_mesh(&mut chart, plot::SMALL_SIZE);
        mesh.y_desc(panel.y_desc.as_str()).y_label_formatter(&plot::tick);
        match (&category_label, &self.x_categories) {
            (Some(f), Some(labels)) => {
                mesh.disable_x_mesh().x_labels(labels.len() + 1).x_label_formatter(f);
            }
            _ => {
                mesh.x_label_formatter(&plot::tick);
            }
        }
        if last {
            mesh.x_desc(self.x_desc.as_str());
        }
        mesh.draw().drawn()?;
        let (x0, x1) = (chart.x_range().start, chart.x_range().end);
        if let Some((centre, half, _)) = &panel.band {
            chart
                .draw_series([Rectangle::new(
                    [(x0, centre - half), (x1, centre + half)],
                    BAND_COLOUR.mix(0.3).filled(),
                )])
                .drawn()?;
            chart
                .draw_series([PathElement::new(vec![(x0, *centre), (x1, *centre)], BAND_COLOUR.stroke_width(2))])
                .drawn()?;
        }
        for (c, s) in panel.series.iter().enumerate() {
            let colour = PALETTE[c % PALETTE.len()];
            let points: Vec<(f64, f64)> =
                self.x.iter().zip(&s.y).filter(|(_, y)| y.is_finite()).map(|(x, y)| (*x, *y)).collect();
            if self.joined {
                chart.draw_series(LineSeries::new(points.clone(), colour.stroke_width(2))).drawn()?;
            }
            if let Some(se) = &s.se {
                for ((x, y), e) in self.x.iter().zip(&s.y).zip(se).filter(|((_, y), e)| y.is_finite() && e.is_finite())
                {
                    chart
                        .draw_series([PathElement::new(vec![(*x, y - e), (*x, y + e)], colour.stroke_width(2))])
                        .drawn()?;
                    for end in [y - e, y + e] {
                        chart
                            .draw_series([EmptyElement::at((*x, end))
                                + PathElement::new(vec![(-5, 0), (5, 0)], colour.stroke_width(2))])
                            .drawn()?;
                    }
                }
            }
            chart.draw_series(points.iter().map(|p| Circle::new(*p, 5, colour.filled()))).drawn()?;
        }
        Ok(())
    }
}

impl Figure for PanelsPlot {
    fn size(&self) -> (u32, u32) {
        let title = (plot::TITLE_SIZE * 1.6) as u32;
        (PANELS_WIDTH_PX, title + PANEL_PX * self.panels.len().max(1) as u32 + 20 + self.legend_px())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let area = plot::title(root, &self.title)?;
        let n = self.panels.len().max(1) as u32;
        let (panels, key) = area.split_vertically(PANEL_PX * n + 20);
        // the last panel carries the x axis title: 20 px more
        let mut rest = panels;
        for (k, panel) in self.panels.iter().enumerate() {
            let last = k + 1 == self.panels.len();
            let (this, below) = rest.split_vertically(if last { PANEL_PX + 20 } else { PANEL_PX });
            self.draw_panel(&this, panel, last)?;
            rest = below;
        }
        let legend = self.legend();
        let entries: Vec<(Mark, &str)> = legend.iter().map(|(m, t)| (*m, t.as_str())).collect();
        plot::legend(&key, &entries)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::tests::{assert_has_ticks, assert_real_png, svg_texts};

    fn panels(joined: bool) -> PanelsPlot {
        let series = |label: &str, y: Vec<f64>, se: Option<Vec<f64>>| Series { label: label.into(), y, se };
        PanelsPlot {
            title: "Conveyor-angle sweep".into(),
            x_desc: "conveyor angle alpha [deg]".into(),
            x: vec![5.0, 10.0, 15.0],
            x_categories: None,
            panels: vec![
                Panel {
                    y_desc: "W_spec [J/kg]".into(),
                    series: vec![
                        series("lowest W_spec (C)", vec![300.0, 320.0, 350.0], Some(vec![5.0, 6.0, 7.0])),
                        series("closest to 48 kg/h (A)", vec![700.0, 780.0, f64::NAN], Some(vec![9.0, 9.0, 9.0])),
                    ],
                    band: None,
                },
                Panel {
                    y_desc: "mass flow [kg/h]".into(),
                    series: vec![series("lowest W_spec (C)", vec![400.0, 410.0, 380.0], None)],
                    band: Some((400.0, 20.0, "mean ± 95 % confidence interval".into())),
                },
            ],
            joined,
        }
    }

    #[test]
    fn sweep_panels_have_ticks_units_legend_and_error_bars() {
        let svg = plot::render_svg(&panels(true)).unwrap();
        let texts = svg_texts(&svg);
        for want in [
            "Conveyor-angle sweep",
            "conveyor angle alpha [deg]",
            "W_spec [J/kg]",
            "mass flow [kg/h]",
            "lowest W_spec (C)",
            "closest to 48 kg/h (A)",
            "±1 standard error (re-evaluation)",
            "mean ± 95 % confidence interval",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want} missing: {texts:?}");
        }
        assert_has_ticks(&svg, 10);
        assert!(svg.contains("<polyline"), "a sweep joins its markers");
        assert!(!svg.contains("NaN"));
    }

    #[test]
    fn independent_runs_are_not_joined() {
        let svg = plot::render_svg(&PanelsPlot {
            x_categories: Some(vec!["0".into(), "1".into(), "2".into()]),
            ..panels(false)
        })
        .unwrap();
        // points (circles), the band and error bars, but no line through the runs: every
        // polyline is a two-point segment (an error bar, its caps, the band's centre line)
        assert!(svg.contains("<circle"));
        for line in svg.lines().filter(|l| l.contains("<polyline")) {
            let points = line.split("points=\"").nth(1).unwrap().split('"').next().unwrap();
            assert!(points.split_whitespace().count() <= 2, "a line through the runs: {line}");
        }
        assert!(svg_texts(&svg).iter().any(|t| t == "2"), "run numbers label the x axis");
    }

    #[test]
    fn panels_png_is_a_real_image() {
        let fig = panels(true);
        assert_real_png(&plot::render_png(&fig).unwrap(), fig.size());
    }
}
