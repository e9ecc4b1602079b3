//! Every figure sawtooth writes goes through this layer: the output format (SVG or PNG, chosen
//! by the file's extension), the embedded font, text styles, ranges, tick labels and legends.
//!
//! Why `plotters`: it gives real axes (tick marks, tick numbers, logarithmic scales, rotated
//! axis titles) and draws one figure to either an SVG document or a bitmap through the same
//! code, so the five hand-written SVG writers (each with its own XML escaping and tick
//! arithmetic) became one. It is pure Rust; with its `ab_glyph` feature the text is laid out
//! and rasterised from a font compiled into the binary (assets/fonts/DejaVuSans.ttf), so a PNG
//! renders the same on a fresh machine without system fonts and no font-kit/fontconfig/freetype
//! is linked. SVG keeps its text as `<text font-family="sans-serif">`; the embedded font is
//! still needed there, because plotters measures every label to place the axes.
//!
//! The figures themselves live beside their data (`plot::flight` for flights, `optim::front` for
//! the Pareto plot, `fit::report`, `diagnose::render`, `campaigns::panels` for campaign summaries):
//! what a figure shows is part of that module's idea; how any figure is drawn is this one's.

pub mod flight;

use std::ops::Range;
use std::path::Path;
use std::sync::Once;

use anyhow::{anyhow, bail, Context as _};
use plotters::chart::MeshStyle;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::io::atomic::write_atomic;

/// The font every figure uses, compiled in (its licence: assets/fonts/LICENSE-DejaVu.txt).
const FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// The family name the font is registered under, and what SVG text names as its font.
pub const FONT: &str = "sans-serif";

/// The rule every figure path follows; errors quote it.
pub const EXTENSION_RULE: &str = "the figure's format follows the file name's extension: .svg or .png";

/// Matplotlib's tab10: distinct colours for series and particles.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x7f, 0x7f, 0x7f),
    RGBColor(0xbc, 0xbd, 0x22),
    RGBColor(0x17, 0xbe, 0xcf),
];

/// Grid lines: opaque light grey (some SVG renderers ignore opacity and would draw
/// plotters' default translucent black as solid black).
pub const GRID: RGBColor = RGBColor(0xe0, 0xe0, 0xe0);

/// Text sizes in pixels (plotters' font size: the line height).
pub const TITLE_SIZE: f64 = 20.0;
pub const LABEL_SIZE: f64 = 15.0;
pub const SMALL_SIZE: f64 = 13.0;

/// Output format of a figure file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Svg,
    Png,
}

impl Format {
    /// The format `path`'s extension asks for; `flag` names where the path came from (a CLI
    /// flag or output file) so the error says what to change.
    pub fn of(path: &Path, flag: &str) -> anyhow::Result<Format> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => bail!("{flag} {}: {EXTENSION_RULE}", path.display()),
        }
    }
}

/// A figure: its size and how to draw it on any plotters backend (SVG or bitmap).
pub trait Figure {
    /// Width and height in pixels.
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>;
}

/// Turns a plotters error (generic over the backend) into an `anyhow` error.
pub trait Drawn<T> {
    fn drawn(self) -> anyhow::Result<T>;
}

impl<T, E: std::fmt::Display> Drawn<T> for Result<T, E> {
    fn drawn(self) -> anyhow::Result<T> {
        self.map_err(|e| anyhow!("drawing the figure: {e}"))
    }
}

/// Registers the embedded font once per process (plotters keeps a global font table).
fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // the bytes are a valid TrueType font compiled in: failure is a build defect
        if plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_err() {
            panic!("the embedded font assets/fonts/DejaVuSans.ttf does not parse");
        }
    });
}

/// The figure as an SVG document.
pub fn render_svg(figure: &impl Figure) -> anyhow::Result<String> {
    register_font();
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, figure.size()).into_drawing_area();
        root.fill(&WHITE).drawn()?;
        figure.draw(&root)?;
        root.present().drawn()?;
    }
    Ok(text)
}

/// The figure as PNG bytes (RGB, 8 bits per channel).
pub fn render_png(figure: &impl Figure) -> anyhow::Result<Vec<u8>> {
    register_font();
    let (w, h) = figure.size();
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).drawn()?;
        figure.draw(&root)?;
        root.present().drawn()?;
    }
    let mut png = Vec::new();
    let mut encoder = ::png::Encoder::new(&mut png, w, h);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_depth(::png::BitDepth::Eight);
    let mut writer = encoder.write_header().context("encoding PNG")?;
    writer.write_image_data(&rgb).context("encoding PNG")?;
    writer.finish().context("encoding PNG")?;
    Ok(png)
}

/// Write `figure` to `path` atomically, as SVG or PNG by the extension; `flag` names the
/// path's origin for the error on any other extension (checked before drawing anything).
pub fn write_figure(path: &Path, flag: &str, figure: &impl Figure) -> anyhow::Result<()> {
    let bytes = match Format::of(path, flag)? {
        Format::Svg => render_svg(figure)?.into_bytes(),
        Format::Png => render_png(figure)?,
    };
    write_atomic(path, &bytes).with_context(|| format!("writing figure {}", path.display()))
}

/// A run folder's figure in both formats: `stem.svg` (vector, for papers and zooming) and
/// `stem.png` (for viewers, notebooks and documents that take no SVG), each written
/// atomically from the same drawing.
pub fn write_figure_files(dir: &Path, stem: &str, figure: &impl Figure) -> anyhow::Result<()> {
    for extension in ["svg", "png"] {
        let name = format!("{stem}.{extension}");
        write_figure(&dir.join(&name), &name, figure)?;
    }
    Ok(())
}

/// Text in the figure font.
pub fn text_style(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().into()
}

/// Plain text in a line slot whose top is at pixel `at.1` of `area`, starting at `at.0` (or
/// centred on it).
pub fn draw_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    at: (i32, i32),
    size: f64,
    centred: bool,
) -> anyhow::Result<()> {
    // anchored at the line's middle: SVG renderers that ignore `dy` (ImageMagick) then still
    // draw the line inside its slot, where a top anchor would put it above its slot
    let pos = Pos::new(if centred { HPos::Center } else { HPos::Left }, VPos::Center);
    area.draw_text(text, &text_style(size).pos(pos), (at.0, at.1 + (0.6 * size) as i32)).drawn()
}

/// Text wrapped at word boundaries to the width of `area`, from its top left corner (captions
/// and footers: wrapping keeps them inside the figure whatever its width).
pub fn draw_wrapped<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str, size: f64) -> anyhow::Result<()> {
    let (w, _) = area.dim_in_pixel();
    let style = text_style(size);
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        let candidate = match lines.last() {
            Some(line) => format!("{line} {word}"),
            None => word.to_string(),
        };
        let (tw, _) = area.estimate_text_size(&candidate, &style).drawn()?;
        match lines.last_mut() {
            Some(line) if tw + 20 <= w => *line = candidate,
            None => lines.push(candidate),
            Some(_) => lines.push(word.to_string()),
        }
    }
    for (i, line) in lines.iter().enumerate() {
        draw_text(area, line, (10, (i as f64 * size * 1.25) as i32), size, false)?;
    }
    Ok(())
}

/// Rows `text` wraps onto at `width` pixels in `size` (for sizing a caption's area; the
/// estimate errs wide, so the area is never too short).
pub fn wrapped_rows(width: u32, text: &str, size: f64) -> u32 {
    let chars_per_row = ((width as f64 - 20.0) / (0.6 * size)).max(10.0) as usize;
    let mut rows = 1;
    let mut used = 0;
    for word in text.split_whitespace() {
        let n = word.chars().count();
        if used > 0 && used + 1 + n > chars_per_row {
            rows += 1;
            used = n;
        } else {
            used += n + usize::from(used > 0);
        }
    }
    rows
}

/// Height in pixels of a caption area for `text`.
pub fn wrapped_height(width: u32, text: &str, size: f64) -> u32 {
    (wrapped_rows(width, text, size) as f64 * size * 1.25 + 6.0).ceil() as u32
}

/// Height in pixels of the line [`title`] takes.
pub fn title_height() -> u32 {
    (TITLE_SIZE * 1.6) as u32
}

/// A title line centred at the top of `area`; returns the area below it.
pub fn title<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str) -> anyhow::Result<DrawingArea<DB, Shift>> {
    let (w, _) = area.dim_in_pixel();
    let (top, rest) = area.split_vertically(title_height());
    // a long title (a design's eight parameters) shrinks to fit rather than run off the edge
    let (tw, _) = top.estimate_text_size(text, &text_style(TITLE_SIZE)).drawn()?;
    let size = if tw + 20 > w { (TITLE_SIZE * (w - 20) as f64 / tw as f64).max(9.0) } else { TITLE_SIZE };
    draw_text(&top, text, (w as i32 / 2, (TITLE_SIZE * 0.35) as i32), size, true)?;
    Ok(rest)
}

/// What a legend entry shows beside its text.
#[derive(Clone, Copy, Debug)]
pub enum Mark {
    Line(RGBColor),
    Point(RGBColor),
    /// A filled square, for bars and areas.
    Block(RGBColor),
    /// A vertical bar with caps, for intervals.
    Interval(RGBColor),
    /// A hollow circle, for highlighted points.
    Ring(RGBColor),
    Diamond(RGBColor),
}

/// One row of legend entries drawn in `area` (outside the plotting box, so it never covers
/// data or lines); entries wrap onto further rows when the width runs out.
pub fn legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, entries: &[(Mark, &str)]) -> anyhow::Result<()> {
    let (w, _) = area.dim_in_pixel();
    let style = text_style(LABEL_SIZE);
    let row = (LABEL_SIZE * 1.5) as i32;
    let (mut x, mut y) = (10i32, 4i32);
    for (mark, label) in entries {
        let (tw, _) = area.estimate_text_size(label, &style).drawn()?;
        let width = 28 + tw as i32 + 24;
        if x > 10 && x + width > w as i32 {
            x = 10;
            y += row;
        }
        let c = (x + 10, y + row / 2 - 2);
        draw_mark(area, *mark, c)?;
        area.draw_text(label, &style.pos(Pos::new(HPos::Left, VPos::Center)), (x + 26, c.1)).drawn()?;
        x += width;
    }
    Ok(())
}

/// Rows a legend of these entries needs at `width` pixels (for sizing its area).
pub fn legend_rows(width: u32, entries: &[(Mark, &str)]) -> u32 {
    // the font's average advance is about 0.55 of its size; a slight overestimate is harmless
    let mut rows = 1;
    let mut x = 10.0;
    for (_, label) in entries {
        let wide = 52.0 + 0.6 * LABEL_SIZE * label.chars().count() as f64;
        if x > 10.0 && x + wide > width as f64 {
            rows += 1;
            x = 10.0;
        }
        x += wide;
    }
    rows
}

/// Height in pixels of a legend area for these entries.
pub fn legend_height(width: u32, entries: &[(Mark, &str)]) -> u32 {
    legend_rows(width, entries) * (LABEL_SIZE * 1.5) as u32 + 8
}

fn draw_mark<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, mark: Mark, (x, y): (i32, i32)) -> anyhow::Result<()> {
    match mark {
        Mark::Line(c) => area.draw(&PathElement::new(vec![(x - 9, y), (x + 9, y)], c.stroke_width(3))),
        Mark::Point(c) => area.draw(&Circle::new((x, y), 4, c.filled())),
        Mark::Block(c) => area.draw(&Rectangle::new([(x - 7, y - 6), (x + 7, y + 6)], c.filled())),
        Mark::Interval(c) => {
            area.draw(&PathElement::new(vec![(x, y - 7), (x, y + 7)], c.stroke_width(2))).drawn()?;
            area.draw(&PathElement::new(vec![(x - 4, y - 7), (x + 4, y - 7)], c.stroke_width(2))).drawn()?;
            area.draw(&PathElement::new(vec![(x - 4, y + 7), (x + 4, y + 7)], c.stroke_width(2)))
        }
        Mark::Ring(c) => area.draw(&Circle::new((x, y), 7, c.stroke_width(2))),
        Mark::Diamond(c) => area.draw(&Polygon::new(vec![(x - 6, y), (x, y - 6), (x + 6, y), (x, y + 6)], c.filled())),
    }
    .drawn()
}

/// The mesh of `chart` in the style every figure shares: tick labels in the small size,
/// axis titles in `axis_title_size`, the light grid with one light line between bold ones.
/// The caller adds its axis titles and label formatters, and draws it.
pub fn styled_mesh<'a, 'b, DB, X, Y, XT, YT>(
    chart: &'b mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    axis_title_size: f64,
) -> MeshStyle<'a, 'b, X, Y, DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = XT> + ValueFormatter<XT>,
    Y: Ranged<ValueType = YT> + ValueFormatter<YT>,
{
    let mut mesh = chart.configure_mesh();
    mesh.label_style(text_style(SMALL_SIZE))
        .axis_desc_style(text_style(axis_title_size))
        .bold_line_style(GRID)
        .max_light_lines(1);
    mesh
}

/// The axes of a chart with numbers along both (the Pareto plot, the flights): [`tick`]
/// numbers, the axis titles `x_desc` and `y_desc` in the label size, drawn.
pub fn draw_numeric_axes<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    x_desc: &str,
    y_desc: &str,
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    styled_mesh(chart, LABEL_SIZE)
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .draw()
        .drawn()
}

/// Tick labels of a category axis: categories sit at 0, 1, 2, ... on an f64 axis spanning
/// `-0.5..n - 0.5` (see [`category_range`]); ticks between them stay unlabelled.
pub fn category_label(labels: &[String]) -> impl Fn(&f64) -> String + '_ {
    move |v: &f64| {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 0.0 {
            labels.get(i as usize).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    }
}

/// A chart of categories along x (teeth, bins) and values up y, as the diagnosis, the fit
/// and the DEM comparison draw them: the categories' labels under their bars, no vertical grid
/// lines, `tick` numbers up the side, small text, the light grid; `caption` above the plot
/// area, if any.
pub fn category_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: Option<&str>,
    labels: &[String],
    y: Range<f64>,
    x_desc: &str,
    y_desc: &str,
) -> anyhow::Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>> {
    let mut builder = ChartBuilder::on(area);
    if let Some(c) = caption {
        builder.caption(c, text_style(LABEL_SIZE));
    }
    let mut chart = builder
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(75)
        .build_cartesian_2d(category_range(labels.len()), y)
        .drawn()?;
    let x_label = category_label(labels);
    styled_mesh(&mut chart, SMALL_SIZE)
        .disable_x_mesh()
        .x_labels(labels.len() + 1)
        .x_label_formatter(&x_label)
        .y_label_formatter(&tick)
        .x_desc(x_desc)
        .y_desc(y_desc)
        .draw()
        .drawn()?;
    Ok(chart)
}

/// The axis range of `n` categories, each one unit wide around its index.
pub fn category_range(n: usize) -> Range<f64> {
    -0.5..n.max(1) as f64 - 0.5
}

/// Smallest and largest finite value, or `None` when there is none.
pub fn extent(values: impl IntoIterator<Item = f64>) -> Option<(f64, f64)> {
    values.into_iter().filter(|v| v.is_finite()).fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}

/// A linear axis range around `lo..hi` with `pad` of the span added at each end; an empty
/// or zero-width span gets a unit (or 10 %) width so the axis still has ticks.
pub fn padded(lo: f64, hi: f64, pad: f64) -> Range<f64> {
    if !(lo.is_finite() && hi.is_finite()) {
        return 0.0..1.0;
    }
    let span = hi - lo;
    if span <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        let half = if lo == 0.0 { 0.5 } else { 0.1 * lo.abs() };
        return lo - half..hi + half;
    }
    lo - pad * span..hi + pad * span
}

/// A logarithmic axis range around positive `lo..hi`, padded by `pad` of the span in decades.
pub fn padded_log(lo: f64, hi: f64, pad: f64) -> Range<f64> {
    let (l, h) = (lo.log10(), hi.log10());
    let span = (h - l).max(0.1);
    10f64.powf(l - pad * span)..10f64.powf(h + pad * span)
}

/// Whether positive values over `lo..hi` span at least a decade (then a log axis reads better).
pub fn spans_decades(lo: f64, hi: f64) -> bool {
    lo > 0.0 && hi / lo >= 10.0
}

/// A tick number without float noise: "0.1" not "0.10000000000000002", "2e-5" for tiny,
/// "1.5e6" for huge values.
pub fn tick(v: &f64) -> String {
    let v = *v;
    if v == 0.0 || !v.is_finite() {
        return if v.is_finite() { "0".into() } else { format!("{v}") };
    }
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        let s = format!("{v:.2e}");
        // 1.50e6 -> 1.5e6
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{e}");
    }
    let s = format!("{:.6}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

#[cfg(test)]
pub mod tests {
    use super::*;

    /// A small figure with a linear chart, legend and title: the layer alone.
    pub struct Sample;

    impl Figure for Sample {
        fn size(&self) -> (u32, u32) {
            (400, 300)
        }
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
            let area = title(root, "sample title")?;
            let (plot, key) = area.split_vertically(240);
            let mut chart = ChartBuilder::on(&plot)
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .build_cartesian_2d(0.0..10.0, 0.0..1.0)
                .drawn()?;
            draw_numeric_axes(&mut chart, "x [mm]", "y [-]")?;
            chart
                .draw_series(LineSeries::new((0..=10).map(|i| (i as f64, (i as f64 / 10.0).powi(2))), PALETTE[0]))
                .drawn()?;
            legend(&key, &[(Mark::Line(PALETTE[0]), "square")])
        }
    }

    /// Decoded PNG: (width, height, RGB bytes).
    pub fn decode_png(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
        let decoder = ::png::Decoder::new(bytes);
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    /// Number of distinct RGB colours in decoded pixels (a blank image has one).
    pub fn distinct_colours(rgb: &[u8]) -> usize {
        rgb.chunks(3).map(|p| (p[0], p[1], p[2])).collect::<std::collections::HashSet<_>>().len()
    }

    /// The PNG bytes are a real, non-blank image of `size`.
    pub fn assert_real_png(bytes: &[u8], size: (u32, u32)) {
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "PNG signature");
        let (w, h, rgb) = decode_png(bytes);
        assert_eq!((w, h), size);
        let colours = distinct_colours(&rgb);
        assert!(colours > 20, "only {colours} colours: blank or nearly so");
    }

    /// The `<text>` contents of an SVG document, unescaped enough for comparisons.
    pub fn svg_texts(svg: &str) -> Vec<String> {
        let mut out = Vec::new();
        let mut rest = svg;
        while let Some(i) = rest.find("<text") {
            let body = &rest[i..];
            let Some(open) = body.find('>') else { break };
            let Some(close) = body.find("</text>") else { break };
            out.push(body[open + 1..close].trim().replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&"));
            rest = &body[close..];
        }
        out
    }

    /// At least `n` texts are plain numbers (tick labels).
    pub fn assert_has_ticks(svg: &str, n: usize) {
        let numbers = svg_texts(svg).iter().filter(|t| t.parse::<f64>().is_ok()).count();
        assert!(numbers >= n, "{numbers} numeric tick labels, expected at least {n}: {:?}", svg_texts(svg));
    }

    #[test]
    fn extension_chooses_format_and_others_name_the_rule() {
        assert_eq!(Format::of(Path::new("a/b.svg"), "--plot").unwrap(), Format::Svg);
        assert_eq!(Format::of(Path::new("b.PNG"), "--plot").unwrap(), Format::Png);
        for bad in ["b.pdf", "b", "b.svg.txt"] {
            let e = Format::of(Path::new(bad), "--plot").unwrap_err().to_string();
            assert!(e.contains("--plot") && e.contains(bad) && e.contains(EXTENSION_RULE), "{e}");
        }
    }

    #[test]
    fn bad_extension_writes_nothing() {
        let dir = std::env::temp_dir().join(format!("sawtooth-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("figure.jpg");
        let e = write_figure(&path, "figure", &Sample).unwrap_err().to_string();
        assert!(e.contains(".svg or .png"), "{e}");
        assert!(!path.exists());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn svg_has_text_ticks_and_the_font_family() {
        let svg = render_svg(&Sample).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        let texts = svg_texts(&svg);
        for want in ["sample title", "x [mm]", "y [-]", "square"] {
            assert!(texts.iter().any(|t| t == want), "{want} missing from {texts:?}");
        }
        assert_has_ticks(&svg, 6);
        assert!(svg.contains(r#"font-family="sans-serif""#));
    }

    #[test]
    fn png_is_a_real_image_of_the_figure_size() {
        assert_real_png(&render_png(&Sample).unwrap(), (400, 300));
    }

    #[test]
    fn png_without_text_would_fail_the_colour_check() {
        // the check above can fail: a blank white image has one colour
        let w = vec![255u8; 30];
        assert_eq!(distinct_colours(&w), 1);
    }

    #[test]
    fn ticks_read_cleanly() {
        assert_eq!(tick(&0.30000000000000004), "0.3");
        assert_eq!(tick(&-0.0), "0");
        assert_eq!(tick(&2.0), "2");
        assert_eq!(tick(&1.5e7), "1.5e7");
        assert_eq!(tick(&2e-5), "2e-5");
    }

    #[test]
    fn ranges_are_never_empty() {
        let r = padded(3.0, 3.0, 0.1);
        assert!(r.start < 3.0 && r.end > 3.0);
        let r = padded(0.0, 10.0, 0.1);
        assert_eq!((r.start, r.end), (-1.0, 11.0));
        assert!(spans_decades(10.0, 1000.0) && !spans_decades(10.0, 50.0));
    }
}
