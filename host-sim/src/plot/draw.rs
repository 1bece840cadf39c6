//! Drawing with plotters: one panel on any backend, SVG documents made of
//! panels, PNG images.

use std::fmt::Write as _;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters_backend::{BackendCoord, DrawingErrorKind};

use super::axis::{Axis, to_axis};
use super::{
    Legend, Marker, PANEL_HEIGHT, Plot, PlotError, Rgb, Shape, Style, WIDTH, decimate, palette,
    sanitize,
};

/// The family every text uses; DejaVu Sans is registered under it.
const FONT: &str = "sans-serif";
/// Text sizes, in plotters' units (the SVG `font-size` is 1/1.24 of it).
const TITLE_SIZE: f64 = 20.0;
const DESC_SIZE: f64 = 16.0;
const LABEL_SIZE: f64 = 14.0;
const LEGEND_SIZE: f64 = 14.0;
/// Smallest size text is shrunk to before it is cut.
const MIN_SIZE: f64 = 11.0;
/// Width of a line series, px.
const LINE_WIDTH: u32 = 2;
/// Dash and gap of a dashed series, px.
const DASH: (f64, f64) = (8.0, 5.0);
/// Opacity of a filled marker.
const FILL_OPACITY: f64 = 0.55;
/// How far off the plot area a point is drawn at most, px.
const FAR: f64 = 1e5;
/// Characters of a text kept before it is measured.
const MAX_CHARS: usize = 400;

/// Registers the compiled-in font once; the error, if any, every time.
fn font() -> Result<(), PlotError> {
    static FONT_READY: OnceLock<Result<(), String>> = OnceLock::new();
    FONT_READY
        .get_or_init(|| {
            plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
                .map_err(|_| "DejaVu Sans could not be read".to_string())
        })
        .clone()
        .map_err(PlotError::Font)
}

fn draw_err(e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// Plots stacked in one SVG document, one `<g transform>` group each.
pub(super) fn svg(plots: &[Plot]) -> Result<String, PlotError> {
    font()?;
    let height = PANEL_HEIGHT * plots.len().max(1) as u32;
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" viewBox="0 0 {WIDTH} {height}">"#
    );
    for (i, plot) in plots.iter().enumerate() {
        let mut buf = String::new();
        {
            let root = SVGBackend::with_string(&mut buf, (WIDTH, PANEL_HEIGHT)).into_drawing_area();
            panel(&root, plot, false)?;
            root.present().map_err(draw_err)?;
        }
        // The backend's own document: drop its <svg> element around.
        let body = buf.split_once('\n').map_or("", |(_, b)| b);
        let body = body.rfind("</svg>").map_or(body, |end| &body[..end]);
        let _ = writeln!(
            out,
            r#"<g transform="translate(0 {})">"#,
            i as u32 * PANEL_HEIGHT
        );
        compact_text(body, &mut out);
        out.push_str("</g>\n");
    }
    out.push_str("</svg>\n");
    Ok(out)
}

/// Appends `svg` with the line breaks the backend puts around the content
/// of each `<text>` taken out (a renderer drops them anyway), so that the
/// text reads as it was given.
fn compact_text(svg: &str, out: &mut String) {
    let mut rest = svg;
    while let Some(start) = rest.find("<text") {
        let (head, tail) = rest.split_at(start);
        out.push_str(head);
        // Attribute values are escaped: the first '>' ends the tag.
        let (Some(open), Some(close)) = (tail.find('>'), tail.find("</text>")) else {
            rest = tail;
            break;
        };
        let Some(body) = tail.get(open + 1..close) else {
            rest = tail;
            break;
        };
        out.push_str(&tail[..=open]);
        out.push_str(body.trim_matches('\n'));
        out.push_str("</text>");
        rest = &tail[close + "</text>".len()..];
    }
    out.push_str(rest);
}

/// A blank figure that says what went wrong.
pub(super) fn error_svg(message: &str) -> String {
    let text: String = sanitize(message)
        .chars()
        .map(|c| match c {
            '<' => "&lt;".to_string(),
            '>' => "&gt;".to_string(),
            '&' => "&amp;".to_string(),
            c => c.to_string(),
        })
        .collect();
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{PANEL_HEIGHT}\">\n\
         <text x=\"20\" y=\"40\">{text}</text>\n</svg>\n"
    )
}

/// Plots stacked in one PNG image.
pub(super) fn png(plots: &[Plot]) -> Result<Vec<u8>, PlotError> {
    font()?;
    let n = plots.len().max(1);
    let (w, h) = (WIDTH, PANEL_HEIGHT * n as u32);
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        for (area, plot) in root.split_evenly((n, 1)).iter().zip(plots) {
            panel(area, plot, true)?;
        }
        root.present().map_err(draw_err)?;
    }
    let encode = |e: png::EncodingError| PlotError::Encode(e.to_string());
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(encode)?;
    writer.write_image_data(&rgb).map_err(encode)?;
    writer.finish().map_err(encode)?;
    Ok(out)
}

/// A series ready to draw: its colour and its drawable points in axis
/// units, in runs (a line breaks where a point cannot be drawn).
struct Prepared {
    color: Rgb,
    runs: Vec<Vec<(f64, f64)>>,
}

/// The series in axis units and the axes over them.
fn prepare(plot: &Plot) -> (Vec<Prepared>, Axis, Axis) {
    let mut prepared = Vec::with_capacity(plot.series.len());
    for (i, s) in plot.series.iter().enumerate() {
        let mut runs = Vec::new();
        let mut run = Vec::new();
        for &(x, y) in &s.points {
            match (to_axis(plot.x_log, x), to_axis(plot.y_log, y)) {
                (Some(x), Some(y)) => run.push((x, y)),
                _ => {
                    if !run.is_empty() && !matches!(s.style, Style::Markers(_)) {
                        runs.push(std::mem::take(&mut run));
                    }
                }
            }
        }
        if !run.is_empty() {
            runs.push(run);
        }
        prepared.push(Prepared {
            color: s.color.unwrap_or_else(|| palette(i)),
            runs,
        });
    }
    let markers = plot
        .series
        .iter()
        .any(|s| matches!(s.style, Style::Markers(_)));
    let all = || prepared.iter().flat_map(|p| p.runs.iter().flatten());
    let x = Axis::new(
        plot.x_log,
        all().map(|p| p.0),
        if markers { 0.04 } else { 0.0 },
    );
    let y = Axis::new(plot.y_log, all().map(|p| p.1), 0.04);
    (prepared, x, y)
}

/// Width of `text` at `size`, px.
fn text_width(text: &str, size: f64) -> f64 {
    (FONT, size)
        .into_font()
        .box_size(text)
        .map_or(0.6 * size * text.chars().count() as f64, |(w, _)| {
            f64::from(w)
        })
}

/// `text` (safe for XML) fitted into `max` px at most `size`: a smaller
/// size down to [`MIN_SIZE`] if `shrink`, then cut with an ellipsis.
fn fit(text: &str, size: f64, max: f64, shrink: bool) -> (String, f64) {
    let clean = sanitize(text);
    let mut chars: Vec<char> = clean.chars().collect();
    let mut cut = chars.len() > MAX_CHARS;
    chars.truncate(MAX_CHARS);
    let whole = |chars: &[char], cut: bool| {
        let mut s: String = chars.iter().collect();
        if cut {
            s.push('…');
        }
        s
    };
    let text = whole(&chars, cut);
    let width = text_width(&text, size);
    if width <= max {
        return (text, size);
    }
    let smallest = if shrink { MIN_SIZE.min(size) } else { size };
    let shrunk = (size * max / width * 2.0).floor() / 2.0;
    if shrunk >= smallest && text_width(&text, shrunk) <= max {
        return (text, shrunk);
    }
    let at_smallest = text_width(&text, smallest).max(1.0);
    let keep = (chars.len() as f64 * max / at_smallest) as usize;
    chars.truncate(keep.min(chars.len()));
    cut = true;
    loop {
        let text = whole(&chars, cut);
        if chars.is_empty() || text_width(&text, smallest) <= max {
            return (text, smallest);
        }
        chars.pop();
    }
}

/// Draws `plot` on `area`, a bitmap or not (see [`Trace::bitmap`]).
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &Plot,
    bitmap: bool,
) -> Result<(), PlotError> {
    area.fill(&WHITE).map_err(draw_err)?;
    let (width, _) = area.dim_in_pixel();
    let (prepared, x, y) = prepare(plot);
    let (title, title_size) = fit(&plot.title, TITLE_SIZE, f64::from(width) - 30.0, true);
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, title_size))
        .margin(10)
        .margin_right(25)
        .x_label_area_size(52)
        .y_label_area_size(84)
        .build_cartesian_2d(x.clone(), y.clone())
        .map_err(draw_err)?;
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    let (pw, ph) = (f64::from(pw), f64::from(ph));
    let (x_desc, x_size) = fit(&plot.x_label, DESC_SIZE, pw, true);
    let (y_desc, y_size) = fit(&plot.y_label, DESC_SIZE, ph, true);
    let x_format = |v: &f64| x.label(*v);
    let y_format = |v: &f64| y.label(*v);
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style((FONT, x_size.min(y_size)))
        .label_style((FONT, LABEL_SIZE))
        .x_label_formatter(&x_format)
        .y_label_formatter(&y_format)
        .bold_line_style(RGBColor(0xdd, 0xdd, 0xdd))
        .light_line_style(RGBColor(0xf2, 0xf2, 0xf2))
        .axis_style(BLACK)
        .draw()
        .map_err(draw_err)?;
    chart
        .plotting_area()
        .draw(&Rectangle::new([(x.lo, y.lo), (x.hi, y.hi)], BLACK))
        .map_err(draw_err)?;

    // Dense lines down to what the pixel columns can show.
    let columns = pw.max(1.0) as usize;
    let runs: Vec<Vec<Vec<(f64, f64)>>> = prepared
        .iter()
        .zip(&plot.series)
        .map(|(p, s)| match s.style {
            Style::Markers(_) => p.runs.clone(),
            Style::Line | Style::Dashed => p
                .runs
                .iter()
                .map(|r| decimate(r, (x.lo, x.hi), columns))
                .collect(),
        })
        .collect();

    let legend = plot.legend != Legend::Hidden;
    let mut names = Vec::new();
    for ((series, p), runs) in plot.series.iter().zip(&prepared).zip(&runs) {
        let color = RGBColor(p.color.0, p.color.1, p.color.2).to_rgba();
        let name = if legend && !series.name.is_empty() {
            let (name, _) = fit(&series.name, LEGEND_SIZE, 0.45 * pw, false);
            names.push(name.clone());
            Some(name)
        } else {
            None
        };
        match series.style {
            Style::Line | Style::Dashed => {
                let dash = (series.style == Style::Dashed).then_some(DASH);
                let anno = chart
                    .draw_series(runs.iter().map(|r| Trace {
                        points: r.clone(),
                        color,
                        dash,
                        bitmap,
                    }))
                    .map_err(draw_err)?;
                if let Some(name) = name {
                    anno.label(name).legend(move |(lx, ly)| Trace {
                        points: vec![(lx, ly), (lx + 22, ly)],
                        color,
                        dash: dash.map(|_| (6.0, 4.0)),
                        bitmap,
                    });
                }
            }
            Style::Markers(marker) => {
                let anno = chart
                    .draw_series(runs.iter().flatten().map(|&at| Mark { at, marker, color }))
                    .map_err(draw_err)?;
                if let Some(name) = name {
                    anno.label(name).legend(move |(lx, ly)| Mark {
                        at: (lx + 11, ly),
                        marker: Marker {
                            radius: marker.radius.min(6),
                            ..marker
                        },
                        color,
                    });
                }
            }
        }
    }
    if !names.is_empty() {
        let box_w = names
            .iter()
            .map(|n| text_width(n, LEGEND_SIZE))
            .fold(0.0, f64::max)
            + 28.0
            + 16.0;
        let box_h = names.len() as f64 * (LEGEND_SIZE * 1.25) + 16.0;
        let position = match plot.legend {
            Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
            Legend::UpperRight => SeriesLabelPosition::UpperRight,
            Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
            Legend::LowerRight => SeriesLabelPosition::LowerRight,
            Legend::Auto | Legend::Hidden => {
                emptiest_corner(&runs, &x, &y, (box_w + 5.0) / pw, (box_h + 5.0) / ph)
            }
        };
        chart
            .configure_series_labels()
            .position(position)
            .margin(8)
            .legend_area_size(28)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(0x99, 0x99, 0x99))
            .label_font((FONT, LEGEND_SIZE))
            .draw()
            .map_err(draw_err)?;
    }
    Ok(())
}

/// An axis as plotters' coordinate: a linear map of axis units to pixels,
/// ticks (bold grid lines, labelled) and minor ticks (light grid lines).
impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let fraction = self.fraction(*v);
        let (from, to) = (f64::from(limit.0), f64::from(limit.1));
        if !fraction.is_finite() {
            return if fraction > 0.0 { limit.1 } else { limit.0 };
        }
        // Rounded as plotters' own f64 coordinate; a point far off the
        // canvas (only ever a clamped huge value) is kept near it so that
        // no backend arithmetic overflows.
        let offset = (to - from) * fraction;
        let offset = if to >= from {
            (offset + 1e-3).floor()
        } else {
            (offset - 1e-3).ceil()
        };
        (from + offset).clamp(from.min(to) - FAR, from.max(to) + FAR) as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// The corner whose legend box (`w` × `h`, fractions of the plot area)
/// covers the fewest points and line samples; upper right first on a tie.
fn emptiest_corner(
    runs: &[Vec<Vec<(f64, f64)>>],
    x: &Axis,
    y: &Axis,
    w: f64,
    h: f64,
) -> SeriesLabelPosition {
    // Fractions of the plot area, y up: the points, and samples every 1 %
    // of the width along each segment (a long line across a corner counts).
    let mut samples = Vec::new();
    for run in runs.iter().flatten() {
        let f = |p: &(f64, f64)| (x.fraction(p.0), y.fraction(p.1));
        if let Some(first) = run.first() {
            samples.push(f(first));
        }
        for pair in run.windows(2) {
            let (a, b) = (f(&pair[0]), f(&pair[1]));
            let steps = ((b.0 - a.0).hypot(b.1 - a.1) * 100.0).clamp(1.0, 200.0) as u32;
            for k in 1..=steps {
                let t = f64::from(k) / f64::from(steps);
                samples.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
            }
        }
    }
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let mut best = (SeriesLabelPosition::UpperRight, usize::MAX);
    for (position, right, upper) in corners {
        let inside = |(fx, fy): &(f64, f64)| {
            let in_x = if right { *fx >= 1.0 - w } else { *fx <= w };
            let in_y = if upper { *fy >= 1.0 - h } else { *fy <= h };
            in_x && in_y
        };
        let count = samples.iter().filter(|s| inside(s)).count();
        if count < best.1 {
            best = (position, count);
        }
    }
    best.0
}

/// A solid or dashed line; consecutive points on one pixel are drawn once.
struct Trace<C> {
    points: Vec<C>,
    color: RGBAColor,
    /// Dash and gap, px.
    dash: Option<(f64, f64)>,
    /// Drawn on a bitmap: segment by segment, as the bitmap backend fills a
    /// wide path as one polygon, which a zigzag (a decimated oscillation)
    /// makes self-intersecting and fills wrongly.
    bitmap: bool,
}

impl<'b, C: 'b> PointCollection<'b, C> for &'b Trace<C> {
    type Point = &'b C;
    type IntoIter = &'b [C];
    fn point_iter(self) -> &'b [C] {
        &self.points
    }
}

impl<C, DB: DrawingBackend> Drawable<DB> for Trace<C> {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let mut path: Vec<BackendCoord> = Vec::with_capacity(self.points.len());
        for p in pos {
            if path.last() != Some(&p) {
                path.push(p);
            }
        }
        let style = ShapeStyle {
            color: self.color,
            filled: false,
            stroke_width: LINE_WIDTH,
        };
        let pieces = match self.dash {
            Some((on, off)) => dashes(&path, on, off),
            None if path.len() >= 2 => vec![path],
            None => Vec::new(),
        };
        for piece in pieces {
            if self.bitmap {
                for w in piece.windows(2) {
                    backend.draw_line(w[0], w[1], &style)?;
                }
            } else {
                backend.draw_path(piece, &style)?;
            }
        }
        Ok(())
    }
}

/// The dashes of a path: pieces `on` px long every `on + off` px. A path
/// too long to dash (points far off the canvas) stays whole.
fn dashes(path: &[BackendCoord], on: f64, off: f64) -> Vec<Vec<BackendCoord>> {
    let length: f64 = path
        .windows(2)
        .map(|w| {
            (f64::from(w[1].0) - f64::from(w[0].0)).hypot(f64::from(w[1].1) - f64::from(w[0].1))
        })
        .sum();
    if length.is_nan() || length >= FAR {
        return vec![path.to_vec()];
    }
    let period = on + off;
    let mut out = Vec::new();
    let mut dash: Vec<BackendCoord> = Vec::new();
    // Distance into the current period.
    let mut phase = 0.0;
    for w in path.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (dx, dy) = (
            f64::from(b.0) - f64::from(a.0),
            f64::from(b.1) - f64::from(a.1),
        );
        let len = dx.hypot(dy);
        let at = |t: f64| {
            (
                (f64::from(a.0) + dx * t / len).round() as i32,
                (f64::from(a.1) + dy * t / len).round() as i32,
            )
        };
        let mut t = 0.0;
        while t < len {
            let drawing = phase < on;
            let step = (if drawing { on - phase } else { period - phase }).min(len - t);
            if drawing {
                if dash.is_empty() {
                    dash.push(at(t));
                }
                dash.push(at(t + step));
            }
            t += step;
            phase += step;
            if drawing && phase >= on && dash.len() >= 2 {
                out.push(std::mem::take(&mut dash));
            }
            if phase >= period {
                phase -= period;
            }
        }
    }
    if dash.len() >= 2 {
        out.push(dash);
    }
    out
}

/// One marker.
struct Mark<C> {
    at: C,
    marker: Marker,
    color: RGBAColor,
}

impl<'b, C: 'b> PointCollection<'b, C> for &'b Mark<C> {
    type Point = &'b C;
    type IntoIter = std::iter::Once<&'b C>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<C, DB: DrawingBackend> Drawable<DB> for Mark<C> {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = pos.next() else {
            return Ok(());
        };
        let Marker {
            shape,
            radius,
            filled,
        } = self.marker;
        let stroke = ShapeStyle {
            color: self.color,
            filled: false,
            stroke_width: if shape == Shape::Cross { 2 } else { 1 },
        };
        let fill = ShapeStyle {
            color: self.color.mix(FILL_OPACITY),
            filled: true,
            stroke_width: 0,
        };
        let (x, y, r) = (f64::from(x), f64::from(y), f64::from(radius));
        // Saturating: a point far off the canvas cannot overflow.
        let px = |dx: f64, dy: f64| ((x + dx * r).round() as i32, (y + dy * r).round() as i32);
        let vertices = match shape {
            Shape::Circle => {
                if filled {
                    backend.draw_circle(px(0.0, 0.0), radius, &fill, true)?;
                }
                return backend.draw_circle(px(0.0, 0.0), radius, &stroke, false);
            }
            Shape::Cross => {
                backend.draw_line(px(-1.0, -1.0), px(1.0, 1.0), &stroke)?;
                return backend.draw_line(px(-1.0, 1.0), px(1.0, -1.0), &stroke);
            }
            Shape::Square => vec![px(-1.0, -1.0), px(1.0, -1.0), px(1.0, 1.0), px(-1.0, 1.0)],
            Shape::Triangle => vec![px(0.0, -1.25), px(1.1, 0.8), px(-1.1, 0.8)],
            Shape::Diamond => vec![px(0.0, -1.3), px(1.3, 0.0), px(0.0, 1.3), px(-1.3, 0.0)],
            Shape::TriangleDown => vec![px(0.0, 1.25), px(1.1, -0.8), px(-1.1, -0.8)],
        };
        if filled {
            backend.fill_polygon(vertices.clone(), &fill)?;
        }
        let mut outline = vertices;
        outline.extend(outline.first().copied());
        backend.draw_path(outline, &stroke)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dashes_cover_the_path_in_pieces() {
        let d = dashes(&[(0, 0), (100, 0)], 8.0, 5.0);
        assert_eq!(d.len(), 8);
        assert_eq!((d[0][0], d[0][1]), ((0, 0), (8, 0)));
        assert_eq!(d[1][0], (13, 0));
        // Across a corner a dash keeps the corner.
        let d = dashes(&[(0, 0), (4, 0), (4, 4)], 8.0, 5.0);
        assert_eq!(d, vec![vec![(0, 0), (4, 0), (4, 4)]]);
        assert_eq!(dashes(&[(i32::MIN, 0), (i32::MAX, 0)], 8.0, 5.0).len(), 1);
    }

    #[test]
    fn text_is_shrunk_then_cut() {
        font().unwrap();
        let (t, s) = fit("short", 20.0, 700.0, true);
        assert_eq!((t.as_str(), s), ("short", 20.0));
        let long = "w".repeat(60);
        let (t, s) = fit(&long, 20.0, 700.0, true);
        assert!((MIN_SIZE..20.0).contains(&s) && t == long, "{s}");
        let (t, s) = fit(&"w".repeat(5000), 20.0, 700.0, true);
        assert!(t.ends_with('…') && s == MIN_SIZE && text_width(&t, s) <= 700.0);
        let (t, _) = fit("a\u{1}<b>", 20.0, 700.0, false);
        assert_eq!(t, "a<b>");
    }
}
