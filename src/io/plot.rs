//! Standalone SVG of one design's particle flights over the sawtooth (like Figure 5.7):
//! profile, fill area, launch points, flights and resting points, in millimetres.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context as _, Result};

use super::atomic::write_atomic;
use super::trajectories::trajectory_points;
use crate::engine::{Detailed, FlightRecord};
use crate::model::flight::Flight;
use crate::model::geometry::{Profile, V2};
use crate::model::ParticleState;

/// Particle colours, by index (matplotlib's tab10).
const PALETTE: [&str; 10] =
    ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"];
const FILL_COLOUR: &str = "#e3c9a0";
const ARC_SAMPLES: usize = 32;
const FLIGHT_SAMPLES: usize = 24;
/// Width of the picture in pixels; the height follows the equal-aspect data.
const WIDTH_PX: f64 = 1200.0;

fn colour(particle: u32) -> &'static str {
    PALETTE[particle as usize % PALETTE.len()]
}

fn mm(p: V2) -> V2 {
    [p[0] * 1e3, p[1] * 1e3]
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

/// Bounding box of points in mm.
#[derive(Clone, Copy, Debug)]
struct Frame {
    min: V2,
    max: V2,
}

impl Frame {
    fn of<'a>(pts: impl IntoIterator<Item = &'a V2>) -> Frame {
        let mut f = Frame { min: [f64::INFINITY; 2], max: [f64::NEG_INFINITY; 2] };
        for p in pts.into_iter().map(|&p| mm(p)).filter(|p| p[0].is_finite() && p[1].is_finite()) {
            f.min = [f.min[0].min(p[0]), f.min[1].min(p[1])];
            f.max = [f.max[0].max(p[0]), f.max[1].max(p[1])];
        }
        f
    }
    fn size(&self) -> V2 {
        [self.max[0] - self.min[0], self.max[1] - self.min[1]]
    }
}

/// "x,y x,y ..." in SVG coordinates (mm, y flipped).
fn svg_points(pts: &[V2]) -> String {
    let mut s = String::new();
    for p in pts.iter().map(|&p| mm(p)) {
        let _ = write!(s, "{:.4},{:.4} ", p[0], -p[1]);
    }
    s.trim_end().to_string()
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// A 1-2-5 tick step giving about six ticks over `range`.
fn tick_step(range: f64) -> f64 {
    let raw = (range / 6.0).max(1e-9);
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag)
}

/// Frame, ticks and axis labels around the data box `f`; `u` is the size unit.
fn axes(s: &mut String, f: &Frame, u: f64) {
    let [w, h] = f.size();
    let fs = 2.2 * u;
    let _ = writeln!(
        s,
        r##"<rect x="{:.4}" y="{:.4}" width="{w:.4}" height="{h:.4}" fill="none" stroke="#444" stroke-width="{:.4}"/>"##,
        f.min[0],
        -f.max[1],
        0.15 * u
    );
    let step = tick_step(w.max(h));
    let mut x = (f.min[0] / step).ceil() * step;
    while x <= f.max[0] + 1e-9 * step {
        let y = -f.min[1];
        let _ = writeln!(
            s,
            r##"<line x1="{x:.4}" y1="{y:.4}" x2="{x:.4}" y2="{:.4}" stroke="#444" stroke-width="{:.4}"/>"##,
            y + u,
            0.15 * u
        );
        let _ = writeln!(
            s,
            r##"<text x="{x:.4}" y="{:.4}" font-size="{fs:.4}" text-anchor="middle">{}</text>"##,
            y + 1.2 * u + fs,
            fmt_tick(x)
        );
        x += step;
    }
    let mut y = (f.min[1] / step).ceil() * step;
    while y <= f.max[1] + 1e-9 * step {
        let x = f.min[0];
        let _ = writeln!(
            s,
            r##"<line x1="{x:.4}" y1="{:.4}" x2="{:.4}" y2="{:.4}" stroke="#444" stroke-width="{:.4}"/>"##,
            -y,
            x - u,
            -y,
            0.15 * u
        );
        let _ = writeln!(
            s,
            r##"<text x="{:.4}" y="{:.4}" font-size="{fs:.4}" text-anchor="end">{}</text>"##,
            x - 1.5 * u,
            -y + 0.35 * fs,
            fmt_tick(y)
        );
        y += step;
    }
    let (cx, cy) = (f.min[0] + w / 2.0, -(f.min[1] + h / 2.0));
    let _ = writeln!(
        s,
        r##"<text x="{cx:.4}" y="{:.4}" font-size="{:.4}" text-anchor="middle">x [mm]</text>"##,
        -f.min[1] + 2.5 * u + 2.0 * fs,
        1.2 * fs
    );
    let lx = f.min[0] - 9.0 * u;
    let _ = writeln!(
        s,
        r##"<text x="{lx:.4}" y="{cy:.4}" font-size="{:.4}" text-anchor="middle" transform="rotate(-90 {lx:.4} {cy:.4})">y [mm]</text>"##,
        1.2 * fs
    );
}

fn fmt_tick(v: f64) -> String {
    let v = if v.abs() < 1e-9 { 0.0 } else { v };
    format!("{}", (v * 1e6).round() / 1e6)
}

/// One legend line below the axes: launch, flight, resting point, fill.
fn legend(s: &mut String, f: &Frame, u: f64) {
    let fs = 2.2 * u;
    let y = -f.min[1] + 5.0 * u + 3.0 * fs;
    let mut x = f.min[0];
    let label = |s: &mut String, x: &mut f64, text: &str| {
        let _ = writeln!(
            s,
            r##"<text x="{:.4}" y="{:.4}" font-size="{fs:.4}">{text}</text>"##,
            *x + 1.5 * u,
            y + 0.35 * fs
        );
        *x += 1.5 * u + 0.52 * fs * text.len() as f64 + 3.0 * u;
    };
    let _ = writeln!(s, r##"<circle cx="{x:.4}" cy="{y:.4}" r="{:.4}" fill="{}"/>"##, 0.5 * u, colour(0));
    label(s, &mut x, "launch point");
    let _ = writeln!(
        s,
        r##"<line x1="{:.4}" y1="{y:.4}" x2="{:.4}" y2="{y:.4}" stroke="{}" stroke-width="{:.4}"/>"##,
        x - u,
        x + u,
        colour(1),
        0.3 * u
    );
    label(s, &mut x, "flight (colour = particle)");
    let _ = writeln!(
        s,
        r##"<circle cx="{x:.4}" cy="{y:.4}" r="{:.4}" fill="#222" stroke="{}" stroke-width="{:.4}"/>"##,
        0.7 * u,
        colour(2),
        0.2 * u
    );
    label(s, &mut x, "resting");
    let _ = writeln!(
        s,
        r##"<rect x="{:.4}" y="{:.4}" width="{:.4}" height="{:.4}" fill="{FILL_COLOUR}"/>"##,
        x - u,
        y - 0.6 * u,
        2.0 * u,
        1.2 * u
    );
    label(s, &mut x, "fill");
}

/// The drawing itself: fill, profile, flights, launch and resting points.
fn content(s: &mut String, det: &Detailed, profile_pts: &[V2], flights: &[(u32, Vec<V2>)], u: f64) {
    let poly = svg_points(&det.prepared.fill.polygon);
    let _ = writeln!(s, r##"<polygon points="{poly}" fill="{FILL_COLOUR}" stroke="none"/>"##);
    let _ = writeln!(
        s,
        r##"<polyline points="{}" fill="none" stroke="#000" stroke-width="{:.4}"/>"##,
        svg_points(profile_pts),
        0.25 * u
    );
    for (p, pts) in flights {
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="{}" stroke-width="{:.4}" stroke-opacity="0.8"/>"##,
            svg_points(pts),
            colour(*p),
            0.15 * u
        );
    }
    for r in det.flights.iter().filter(|r| r.bounce == 0) {
        let p = mm(r.from);
        let _ = writeln!(
            s,
            r##"<circle cx="{:.4}" cy="{:.4}" r="{:.4}" fill="{}"/>"##,
            p[0],
            -p[1],
            0.35 * u,
            colour(r.particle)
        );
    }
    for (i, end) in det.particles.iter().enumerate().filter(|(_, e)| e.state == ParticleState::Resting) {
        let p = mm(end.end);
        let _ = writeln!(
            s,
            r##"<circle cx="{:.4}" cy="{:.4}" r="{:.4}" fill="#222" stroke="{}" stroke-width="{:.4}"/>"##,
            p[0],
            -p[1],
            0.5 * u,
            colour(i as u32),
            0.15 * u
        );
    }
}

/// The whole SVG document as text.
pub fn render_svg(det: &Detailed, g: f64, k_drag: f64, title: &str) -> String {
    let profile = &det.prepared.profile;
    let profile_pts = profile_points(profile, teeth_to_draw(profile, det, g, k_drag));
    let flights: Vec<(u32, Vec<V2>)> =
        det.flights.iter().map(|r| (r.particle, flight_points(r, g, k_drag))).filter(|(_, v)| !v.is_empty()).collect();
    let all = profile_pts.iter().chain(&det.prepared.fill.polygon).chain(flights.iter().flat_map(|(_, v)| v));
    let f = Frame::of(all);
    let [w, h] = f.size();
    let u = w.max(h).max(1e-6) / 100.0; // size unit for strokes and text
    let (left, right, top, bottom) = (12.0 * u, 3.0 * u, 8.0 * u, 16.0 * u);
    let (vx, vy, vw, vh) = (f.min[0] - left, -f.max[1] - top, w + left + right, h + top + bottom);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH_PX:.0}" height="{:.0}" viewBox="{vx:.4} {vy:.4} {vw:.4} {vh:.4}" font-family="sans-serif">"##,
        (WIDTH_PX * vh / vw).ceil()
    );
    let _ = writeln!(s, r##"<rect x="{vx:.4}" y="{vy:.4}" width="{vw:.4}" height="{vh:.4}" fill="#fff"/>"##);
    let _ = writeln!(
        s,
        r##"<text x="{:.4}" y="{:.4}" font-size="{:.4}" text-anchor="middle">{}</text>"##,
        f.min[0] + w / 2.0,
        vy + 5.0 * u,
        3.0 * u,
        escape(title)
    );
    content(&mut s, det, &profile_pts, &flights, u);
    axes(&mut s, &f, u);
    legend(&mut s, &f, u);
    s.push_str("</svg>\n");
    s
}

/// Write the flight plot of one design as a standalone SVG, atomically.
pub fn write_svg(path: &Path, det: &Detailed, g: f64, k_drag: f64, title: &str) -> Result<()> {
    let svg = render_svg(det, g, k_drag, title);
    write_atomic(path, svg.as_bytes()).with_context(|| format!("writing plot to {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::trajectories::tests::{small_lunar, temp_dir};

    /// Every opened tag is closed in order (self-closing tags count as closed).
    fn tags_balanced(s: &str) -> bool {
        let mut stack = Vec::new();
        let mut rest = s;
        while let Some(i) = rest.find('<') {
            let Some(j) = rest[i..].find('>') else { return false };
            let tag = &rest[i + 1..i + j];
            rest = &rest[i + j + 1..];
            let name = |t: &str| t.split(|c: char| c.is_whitespace() || c == '/').next().unwrap_or("").to_string();
            if let Some(closing) = tag.strip_prefix('/') {
                if stack.pop() != Some(name(closing)) {
                    return false;
                }
            } else if !tag.ends_with('/') {
                stack.push(name(tag));
            }
        }
        stack.is_empty()
    }

    #[test]
    fn svg_of_small_lunar_case_is_well_formed() {
        let (s, det) = small_lunar();
        let dir = temp_dir("plot");
        let path = dir.join("flights.svg");
        write_svg(&path, &det, s.environment.g, s.environment.k_drag.unwrap_or(0.0), "Solution C <lunar> & co")
            .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<svg"));
        assert!(text.contains("<polyline"));
        assert!(text.contains("x [mm]") && text.contains("y [mm]"));
        assert_eq!(text.matches("<svg").count(), 1);
        assert_eq!(text.matches("</svg>").count(), 1);
        assert!(tags_balanced(&text));
        assert!(!text.contains("NaN") && !text.contains("inf"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn tag_checker_rejects_unclosed_tags() {
        assert!(tags_balanced("<svg><g/><text>a</text></svg>"));
        assert!(!tags_balanced("<svg><text>a</svg>"));
    }
}
