//! The flight plot of one design (like Figure 5.7): profile, fill area, launch points,
//! flights and resting points, in millimetres at equal scale, drawn through `crate::plot`
//! (SVG or PNG by the file's extension).

use std::ops::Range;
use std::path::Path;

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::engine::{Detailed, FlightRecord};
use crate::io::trajectories::trajectory_points;
use crate::model::flight::Flight;
use crate::model::geometry::{Profile, V2};
use crate::model::ParticleState;
use crate::plot::{self, Drawn as _, Figure, Mark, PALETTE};

const FILL_COLOUR: RGBColor = RGBColor(0xe3, 0xc9, 0xa0);
const RESTING_COLOUR: RGBColor = RGBColor(0x22, 0x22, 0x22);
const ARC_SAMPLES: usize = 32;
const FLIGHT_SAMPLES: usize = 24;
/// Width of the picture in pixels; the height follows the equal-aspect data.
const WIDTH_PX: u32 = 1200;
/// Pixels around the plotting box: margin, y tick labels and title, x tick labels and title.
const MARGIN_PX: u32 = 15;
const Y_LABELS_PX: u32 = 80;
const X_LABELS_PX: u32 = 55;
/// The plotting box's height is kept within these bounds (the other range grows to keep the
/// scale equal), so a long flat conveyor or a single tall tooth still reads.
const MIN_BOX_PX: f64 = 220.0;
const MAX_BOX_PX: f64 = 1100.0;

fn colour(particle: u32) -> RGBColor {
    PALETTE[particle as usize % PALETTE.len()]
}

fn mm(p: V2) -> (f64, f64) {
    (p[0] * 1e3, p[1] * 1e3)
}

/// Number of teeth to draw: up to one past the furthest launch or impact point.
fn teeth_to_draw(profile: &Profile, det: &Detailed, g: f64, k_drag: f64) -> u32 {
    let x_max =
        trajectory_points(det, g, k_drag).iter().map(|p| p.pos[0]).filter(|x| x.is_finite()).fold(0.0, f64::max);
    let last = (x_max / profile.pitch[0]).floor().max(0.0) as u32 + 1;
    (last + 1).min(profile.teeth).max(1)
}

/// The profile polyline (global m): per tooth p1 -> p2 -> catch arc -> p4 -> next p1.
fn profile_points(profile: &Profile, n: u32) -> Vec<V2> {
    let (a2, a4) = profile.catch_arc_angles();
    let mut pts = Vec::new();
    for j in 0..n {
        pts.push(profile.p1_of(j));
        for k in 0..ARC_SAMPLES {
            let a = a2 + (a4 - a2) * k as f64 / (ARC_SAMPLES - 1) as f64;
            pts.push(
                profile
                    .point_of(j, [profile.p3[0] + profile.radius * a.cos(), profile.p3[1] + profile.radius * a.sin()]),
            );
        }
    }
    // Base on to the next tooth's p1; the profile ends at p4 after its last tooth.
    if n < profile.teeth {
        pts.push(profile.p1_of(n));
    }
    pts
}

/// Sampled path of one flight (global m); empty when it hit nothing.
fn flight_points(r: &FlightRecord, g: f64, k_drag: f64) -> Vec<V2> {
    if r.t <= 0.0 {
        return Vec::new();
    }
    let f = Flight { p0: r.from, v0: r.vel, g, k: k_drag, drift: [0.0; 2] };
    (0..=FLIGHT_SAMPLES).map(|i| f.pos(r.t * i as f64 / FLIGHT_SAMPLES as f64)).collect()
}

/// Everything drawn, in millimetres, with equal-scale axis ranges.
pub struct FlightPlot<'a> {
    det: &'a Detailed,
    title: String,
    profile: Vec<(f64, f64)>,
    flights: Vec<(u32, Vec<(f64, f64)>)>,
    x: Range<f64>,
    y: Range<f64>,
    box_px: (u32, u32),
}

const LEGEND: [(Mark, &str); 4] = [
    (Mark::Point(PALETTE[0]), "launch point"),
    (Mark::Line(PALETTE[1]), "flight (colour = particle)"),
    (Mark::Ring(RESTING_COLOUR), "resting"),
    (Mark::Block(FILL_COLOUR), "fill"),
];

impl<'a> FlightPlot<'a> {
    pub fn new(det: &'a Detailed, g: f64, k_drag: f64, title: &str) -> FlightPlot<'a> {
        let profile = &det.prepared.profile;
        let profile_pts = profile_points(profile, teeth_to_draw(profile, det, g, k_drag));
        let flights: Vec<(u32, Vec<V2>)> = det
            .flights
            .iter()
            .map(|r| (r.particle, flight_points(r, g, k_drag)))
            .filter(|(_, v)| !v.is_empty())
            .collect();
        let all: Vec<(f64, f64)> = profile_pts
            .iter()
            .chain(&det.prepared.fill.polygon)
            .chain(flights.iter().flat_map(|(_, v)| v))
            .map(|&p| mm(p))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let (x0, x1) = plot::extent(all.iter().map(|p| p.0)).unwrap_or((0.0, 1.0));
        let (y0, y1) = plot::extent(all.iter().map(|p| p.1)).unwrap_or((0.0, 1.0));
        let (mut x, mut y) = (plot::padded(x0, x1, 0.02), plot::padded(y0, y1, 0.04));
        // equal scale: mm per pixel the same on both axes, within the box-height bounds
        let box_w = (WIDTH_PX - 2 * MARGIN_PX - Y_LABELS_PX) as f64;
        let per_px = (x.end - x.start) / box_w;
        let mut box_h = (y.end - y.start) / per_px;
        if box_h < MIN_BOX_PX {
            let grow = (MIN_BOX_PX * per_px - (y.end - y.start)) / 2.0;
            y = y.start - grow..y.end + grow;
            box_h = MIN_BOX_PX;
        } else if box_h > MAX_BOX_PX {
            let per_px = (y.end - y.start) / MAX_BOX_PX;
            let grow = (box_w * per_px - (x.end - x.start)) / 2.0;
            x = x.start - grow..x.end + grow;
            box_h = MAX_BOX_PX;
        }
        let conv = |v: &Vec<V2>| v.iter().map(|&p| mm(p)).collect::<Vec<_>>();
        FlightPlot {
            det,
            title: title.to_string(),
            profile: conv(&profile_pts),
            flights: flights.iter().map(|(p, v)| (*p, conv(v))).collect(),
            x,
            y,
            box_px: (box_w as u32, box_h.round() as u32),
        }
    }

    fn legend_px(&self) -> u32 {
        plot::legend_height(WIDTH_PX, &LEGEND)
    }
}

impl Figure for FlightPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let title = (plot::TITLE_SIZE * 1.6) as u32;
        (WIDTH_PX, title + 2 * MARGIN_PX + self.box_px.1 + X_LABELS_PX + self.legend_px())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let area = plot::title(root, &self.title)?;
        let (_, h) = area.dim_in_pixel();
        let (chart_area, key) = area.split_vertically(h - self.legend_px());
        let mut chart = ChartBuilder::on(&chart_area)
            .margin(MARGIN_PX)
            .x_label_area_size(X_LABELS_PX)
            .y_label_area_size(Y_LABELS_PX)
            .build_cartesian_2d(self.x.clone(), self.y.clone())
            .drawn()?;
        plot::draw_numeric_axes(&mut chart, "x [mm]", "y [mm]")?;
        let fill: Vec<(f64, f64)> = self.det.prepared.fill.polygon.iter().map(|&p| mm(p)).collect();
        chart.draw_series(std::iter::once(Polygon::new(fill, FILL_COLOUR.filled()))).drawn()?;
        chart.draw_series(std::iter::once(PathElement::new(self.profile.clone(), BLACK.stroke_width(2)))).drawn()?;
        chart
            .draw_series(
                self.flights.iter().map(|(p, pts)| PathElement::new(pts.clone(), colour(*p).mix(0.8).stroke_width(1))),
            )
            .drawn()?;
        let launches = self.det.flights.iter().filter(|r| r.bounce == 0);
        chart.draw_series(launches.map(|r| Circle::new(mm(r.from), 3, colour(r.particle).filled()))).drawn()?;
        let resting = self
            .det
            .particles
            .iter()
            .enumerate()
            .filter(|(_, e)| e.state == ParticleState::Resting)
            .collect::<Vec<_>>();
        chart.draw_series(resting.iter().map(|(_, e)| Circle::new(mm(e.end), 5, RESTING_COLOUR.filled()))).drawn()?;
        chart
            .draw_series(resting.iter().map(|(i, e)| Circle::new(mm(e.end), 5, colour(*i as u32).stroke_width(2))))
            .drawn()?;
        plot::legend(&key, &LEGEND)
    }
}

/// Write the flight plot of one design, atomically; SVG or PNG by `path`'s extension (`flag`
/// names where the path came from, for the error on any other).
pub fn write_plot(path: &Path, flag: &str, det: &Detailed, g: f64, k_drag: f64, title: &str) -> Result<()> {
    plot::write_figure(path, flag, &FlightPlot::new(det, g, k_drag, title))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::trajectories::tests::{small_lunar, temp_dir};
    use crate::plot::tests::{assert_has_ticks, assert_real_png, svg_texts};

    #[test]
    fn svg_of_small_lunar_case_has_axes_title_and_legend() {
        let (s, det) = small_lunar();
        let dir = temp_dir("plot");
        let path = dir.join("flights.svg");
        let title = "Solution C <lunar> & co";
        write_plot(&path, "--plot", &det, s.environment.g, s.environment.k_drag.unwrap_or(0.0), title).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        assert!(text.contains("Solution C &lt;lunar&gt; &amp; co"), "the title is escaped");
        let texts = svg_texts(&text);
        for want in [title, "x [mm]", "y [mm]", "launch point", "resting", "fill"] {
            assert!(texts.iter().any(|t| t == want), "{want} missing: {texts:?}");
        }
        assert_has_ticks(&text, 6);
        assert!(!text.contains("NaN") && !text.contains("inf"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn png_of_small_lunar_case_is_a_real_image() {
        let (s, det) = small_lunar();
        let dir = temp_dir("plot-png");
        let path = dir.join("flights.png");
        write_plot(&path, "--plot", &det, s.environment.g, s.environment.k_drag.unwrap_or(0.0), "t").unwrap();
        let fig = FlightPlot::new(&det, s.environment.g, s.environment.k_drag.unwrap_or(0.0), "t");
        assert_real_png(&std::fs::read(&path).unwrap(), fig.size());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn other_extension_is_refused_naming_the_flag() {
        let (s, det) = small_lunar();
        let e = write_plot(Path::new("/tmp/never.pdf"), "--plot", &det, s.environment.g, 0.0, "t").unwrap_err();
        assert!(e.to_string().contains("--plot") && e.to_string().contains(".svg or .png"), "{e}");
    }
}
