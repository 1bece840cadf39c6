//! A small SVG line-plot writer: axes with "nice" ticks, labels with units,
//! one polyline (or one set of markers) per series and a legend right of
//! the axes. No
//! dependency, deterministic output, well-formed XML whatever the text
//! (titles come from scene files: markup characters are escaped and the
//! control characters XML forbids are dropped). [`well_formed`] checks a
//! document's tags for the tests.

use std::fmt::Write;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Style {
    /// A polyline through the points, in order.
    #[default]
    Line,
    /// One dot per point, not joined (scattered measurements).
    Markers,
}

/// One curve.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// (x, y) points, drawn in order.
    pub points: Vec<(f64, f64)>,
    /// Line or markers.
    pub style: Style,
}

impl Series {
    /// A series drawn as a line.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: Style::Line,
        }
    }

    /// A series drawn as markers.
    pub fn markers(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: Style::Markers,
        }
    }
}

/// A plot with labelled axes.
#[derive(Debug, Clone)]
pub struct Plot {
    /// Title on top.
    pub title: String,
    /// Horizontal axis label, with unit.
    pub x_label: String,
    /// Vertical axis label, with unit.
    pub y_label: String,
    /// Logarithmic horizontal axis (points with x <= 0 are not drawn).
    pub x_log: bool,
    /// Curves.
    pub series: Vec<Series>,
}

const W: f64 = 800.0;
const H: f64 = 560.0;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 30.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 70.0;
const COLORS: [&str; 12] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf", "#393b79", "#ad494a",
];
/// Average glyph width over the font size, to size the title and legend.
const GLYPH: f64 = 0.56;

/// Tick positions covering [lo, hi] with a 1-2-5 step.
pub fn ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return vec![lo];
    }
    let raw = (hi - lo) / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let (first, last) = ((lo / step).ceil(), (hi / step).floor());
    // A range too narrow for its magnitude (subnormal forces, say) leaves
    // no usable step: label its ends only.
    if !(step > 0.0 && step.is_normal() && first.is_finite() && last.is_finite())
        || last - first > 1000.0
    {
        return vec![lo, hi];
    }
    let (first, last) = (first as i64, last as i64);
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Ticks of a logarithmic axis covering [10^lo, 10^hi] (exponents): 1, 2
/// and 5 times the powers of ten over up to three decades, the powers
/// alone beyond; the values, not their logarithms.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi < lo {
        return Vec::new();
    }
    let mantissas: &[f64] = if hi - lo <= 3.0 {
        &[1.0, 2.0, 5.0]
    } else {
        &[1.0]
    };
    let mut out = Vec::new();
    let mut k = lo.floor() as i64;
    while (k as f64) <= hi.ceil() && out.len() < 64 {
        for m in mantissas {
            let v = m * 10f64.powi(k as i32);
            let e = v.log10();
            if e >= lo - 1e-12 && e <= hi + 1e-12 {
                out.push(v);
            }
        }
        k += 1;
    }
    out
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Text made safe for XML content and attribute values: markup characters
/// escaped, control characters XML 1.0 does not allow dropped.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' | '\n' | '\r' => out.push(' '),
            c if c.is_control() || matches!(c, '\u{FFFE}' | '\u{FFFF}') => {}
            c => out.push(c),
        }
    }
    out
}

/// The range of the finite values, widened when empty or too narrow to
/// show ticks (a constant series).
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let scale = lo.abs().max(hi.abs());
    if hi - lo <= 1e-9 * scale || hi <= lo {
        let half = if scale > 0.0 { 0.05 * scale } else { 1.0 };
        let mid = 0.5 * (lo + hi);
        return (mid - half, mid + half);
    }
    (lo, hi)
}

impl Plot {
    /// Renders the plot as a standalone SVG document.
    pub fn render(&self) -> String {
        render_panels(std::slice::from_ref(self))
    }

    /// Width the legend adds right of the plot.
    fn legend_width(&self) -> f64 {
        let longest = self
            .series
            .iter()
            .map(|s| s.name.chars().count())
            .max()
            .unwrap_or(0);
        if longest == 0 {
            0.0
        } else {
            (30.0 + GLYPH * 13.0 * longest as f64).ceil()
        }
    }

    /// Appends the plot's elements, shifted down by `dy`, on a canvas
    /// `width` wide.
    fn draw(&self, s: &mut String, dy: f64, width: f64) {
        let log = self.x_log;
        // Horizontal position in axis units (log10 of x on a log axis).
        let ax = |x: f64| if log { x.log10() } else { x };
        let (x0, x1) = range(
            self.series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| ax(p.0))),
        );
        let (mut y0, mut y1) = range(
            self.series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1)),
        );
        let pad = 0.04 * (y1 - y0);
        (y0, y1) = (y0 - pad, y1 + pad);
        let pw = W - LEFT - RIGHT;
        let ph = H - TOP - BOTTOM;
        let sx = |x: f64| LEFT + (ax(x) - x0) / (x1 - x0) * pw;
        let sy = |y: f64| TOP + (y1 - y) / (y1 - y0) * ph;

        let _ = writeln!(s, r#"<g transform="translate(0 {dy})">"#);
        let _ = writeln!(s, r#"<rect width="{width}" height="{H}" fill="white"/>"#);
        let (title, size) = fit(&self.title, W - 20.0, 16.0);
        let _ = writeln!(
            s,
            r#"<text x="{}" y="28" text-anchor="middle" font-size="{size:.1}">{}</text>"#,
            W / 2.0,
            escape(&title)
        );
        let x_ticks = if log {
            log_ticks(x0, x1)
        } else {
            ticks(x0, x1, 8)
        };
        for t in x_ticks {
            let x = sx(t);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}" stroke="#e5e5e5"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
                TOP + ph,
                TOP + ph + 18.0,
                fmt_tick(t)
            );
        }
        for t in ticks(y0, y1, 8) {
            let y = sy(t);
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#e5e5e5"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
                LEFT + pw,
                LEFT - 6.0,
                y + 4.0,
                fmt_tick(t)
            );
        }
        let _ = writeln!(
            s,
            r#"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            LEFT + pw / 2.0,
            H - 20.0,
            escape(&self.x_label)
        );
        let _ = writeln!(
            s,
            r#"<text transform="translate(22 {:.1}) rotate(-90)" text-anchor="middle">{}</text>"#,
            TOP + ph / 2.0,
            escape(&self.y_label)
        );
        // The legend, right of the axes.
        let lx = W - RIGHT + 12.0;
        for (i, series) in self.series.iter().enumerate() {
            let color = COLORS.get(i % COLORS.len()).copied().unwrap_or("black");
            let finite = series
                .points
                .iter()
                .filter(|p| ax(p.0).is_finite() && p.1.is_finite());
            let ly = TOP + 16.0 + 18.0 * i as f64;
            match series.style {
                Style::Line => {
                    let mut path = String::new();
                    for &(x, y) in finite {
                        let _ = write!(path, "{:.2},{:.2} ", sx(x), sy(y));
                    }
                    let _ = writeln!(
                        s,
                        r#"<polyline fill="none" stroke="{color}" stroke-width="1.4" points="{}"/>"#,
                        path.trim_end()
                    );
                    let _ = writeln!(
                        s,
                        r#"<line x1="{:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{color}" stroke-width="2"/>"#,
                        lx,
                        lx + 24.0,
                    );
                }
                Style::Markers => {
                    let _ = writeln!(s, r#"<g fill="{color}">"#);
                    for &(x, y) in finite {
                        let _ =
                            writeln!(s, r#"<circle cx="{:.2}" cy="{:.2}" r="3"/>"#, sx(x), sy(y));
                    }
                    let _ = writeln!(
                        s,
                        r#"<circle cx="{:.1}" cy="{ly:.1}" r="3"/></g>"#,
                        lx + 12.0
                    );
                }
            }
            let _ = writeln!(
                s,
                r#"<text x="{:.1}" y="{:.1}">{}</text>"#,
                lx + 30.0,
                ly + 4.0,
                escape(&series.name)
            );
        }
        s.push_str("</g>\n");
    }
}

/// `text` shrunk to fit `width` at most `size`: a smaller font down to 10,
/// then cut with an ellipsis.
fn fit(text: &str, width: f64, size: f64) -> (String, f64) {
    let n = text.chars().count().max(1) as f64;
    let needed = (width / (GLYPH * n)).min(size);
    if needed >= 10.0 {
        return (text.to_string(), needed);
    }
    let keep = (width / (GLYPH * 10.0)) as usize;
    let cut: String = text.chars().take(keep.saturating_sub(1)).collect();
    (format!("{cut}…"), 10.0)
}

/// Renders plots stacked top to bottom in one SVG document (panels that
/// share a time axis, for example).
pub fn render_panels(plots: &[Plot]) -> String {
    let height = H * plots.len().max(1) as f64;
    let width = W + plots.iter().map(Plot::legend_width).fold(0.0, f64::max);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="13">"#
    );
    for (i, p) in plots.iter().enumerate() {
        p.draw(&mut s, H * i as f64, width);
    }
    s.push_str("</svg>\n");
    s
}

/// Checks that `xml` is one well-formed element: every tag closed in
/// order, attributes quoted, `<` and `&` only as markup or entities, no
/// forbidden control character. Enough for the documents this module
/// writes (no DTD, no CDATA); returns what is wrong and where.
pub fn well_formed(xml: &str) -> Result<(), String> {
    let mut stack: Vec<&str> = Vec::new();
    let mut roots = 0usize;
    let mut rest = xml;
    let at = |r: &str| xml.len() - r.len();
    while !rest.is_empty() {
        let Some(lt) = rest.find('<') else {
            check_text(rest, at(rest))?;
            if !rest.trim().is_empty() && stack.is_empty() {
                return Err(format!("byte {}: text after the root element", at(rest)));
            }
            break;
        };
        let (text, tail) = rest.split_at(lt);
        check_text(text, at(rest))?;
        if stack.is_empty() && !text.trim().is_empty() {
            return Err(format!("byte {}: text outside the root element", at(rest)));
        }
        rest = tail;
        if let Some(r) = rest.strip_prefix("<?") {
            let end = r
                .find("?>")
                .ok_or_else(|| format!("byte {}: unclosed <?", at(rest)))?;
            rest = r.get(end + 2..).unwrap_or("");
            continue;
        }
        if let Some(r) = rest.strip_prefix("<!--") {
            let end = r
                .find("-->")
                .ok_or_else(|| format!("byte {}: unclosed comment", at(rest)))?;
            rest = r.get(end + 3..).unwrap_or("");
            continue;
        }
        let start = at(rest);
        let end = rest
            .find('>')
            .ok_or_else(|| format!("byte {start}: unclosed tag"))?;
        let inner = rest.get(1..end).unwrap_or("");
        rest = rest.get(end + 1..).unwrap_or("");
        if let Some(name) = inner.strip_prefix('/') {
            let name = name.trim_end();
            check_name(name, start)?;
            match stack.pop() {
                Some(open) if open == name => {}
                Some(open) => {
                    return Err(format!("byte {start}: </{name}> closes <{open}>"));
                }
                None => return Err(format!("byte {start}: </{name}> closes nothing")),
            }
            continue;
        }
        let (body, empty) = match inner.strip_suffix('/') {
            Some(b) => (b, true),
            None => (inner, false),
        };
        let name_end = body.find(|c: char| c.is_whitespace()).unwrap_or(body.len());
        let (name, attrs) = body.split_at(name_end);
        check_name(name, start)?;
        check_attributes(attrs, start)?;
        if stack.is_empty() {
            roots += 1;
            if roots > 1 {
                return Err(format!("byte {start}: a second root element <{name}>"));
            }
        }
        if !empty {
            stack.push(name);
        }
    }
    if let Some(open) = stack.last() {
        return Err(format!("<{open}> is never closed"));
    }
    if roots == 0 {
        return Err("no element".into());
    }
    Ok(())
}

fn check_name(name: &str, at: usize) -> Result<(), String> {
    let ok = name
        .chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_' || c == ':')
        && name
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '_' | ':' | '-' | '.'));
    if ok {
        Ok(())
    } else {
        Err(format!("byte {at}: bad tag name '{name}'"))
    }
}

fn check_attributes(mut s: &str, at: usize) -> Result<(), String> {
    let mut seen: Vec<&str> = Vec::new();
    loop {
        s = s.trim_start();
        if s.is_empty() {
            return Ok(());
        }
        let eq = s
            .find('=')
            .ok_or_else(|| format!("byte {at}: attribute without a value in '{s}'"))?;
        let name = s.get(..eq).unwrap_or("").trim_end();
        check_name(name, at)?;
        if seen.contains(&name) {
            return Err(format!("byte {at}: attribute '{name}' given twice"));
        }
        seen.push(name);
        let value = s.get(eq + 1..).unwrap_or("").trim_start();
        let quote = value
            .chars()
            .next()
            .filter(|c| matches!(c, '"' | '\''))
            .ok_or_else(|| format!("byte {at}: attribute '{name}' is not quoted"))?;
        let body = value.get(1..).unwrap_or("");
        let close = body
            .find(quote)
            .ok_or_else(|| format!("byte {at}: attribute '{name}' is not closed"))?;
        let text = body.get(..close).unwrap_or("");
        if text.contains('<') {
            return Err(format!("byte {at}: '<' in attribute '{name}'"));
        }
        check_text(text, at)?;
        s = body.get(close + 1..).unwrap_or("");
        if !(s.is_empty() || s.starts_with(char::is_whitespace)) {
            return Err(format!("byte {at}: no space after attribute '{name}'"));
        }
    }
}

/// Character data: every `&` starts an entity; no forbidden character.
fn check_text(text: &str, at: usize) -> Result<(), String> {
    if let Some(c) = text
        .chars()
        .find(|c| c.is_control() && !matches!(c, '\t' | '\n' | '\r'))
    {
        return Err(format!("byte {at}: control character {:?}", c));
    }
    let mut rest = text;
    while let Some(amp) = rest.find('&') {
        let tail = rest.get(amp + 1..).unwrap_or("");
        let semi = tail
            .find(';')
            .ok_or_else(|| format!("byte {at}: '&' without ';'"))?;
        let entity = tail.get(..semi).unwrap_or("");
        let known = matches!(entity, "amp" | "lt" | "gt" | "quot" | "apos")
            || entity
                .strip_prefix("#x")
                .is_some_and(|h| !h.is_empty() && h.chars().all(|c| c.is_ascii_hexdigit()))
            || entity
                .strip_prefix('#')
                .is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()));
        if !known {
            return Err(format!("byte {at}: unknown entity '&{entity};'"));
        }
        rest = tail.get(semi + 1..).unwrap_or("");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_of_a_subnormal_range_are_its_ends() {
        assert_eq!(ticks(-3e-322, 3e-322, 5), vec![-3e-322, 3e-322]);
        let t = ticks(0.0, 1.0, 5);
        assert_eq!((t.len(), t[0], t[5]), (6, 0.0, 1.0));
        assert!((t[3] - 0.6).abs() < 1e-15);
    }

    #[test]
    fn ticks_are_nice_and_cover_the_range() {
        assert_eq!(ticks(0.0, 10.0, 5), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(ticks(-1.3, 1.3, 6), vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
        assert_eq!(ticks(1.0, 1.0, 5), vec![1.0]);
    }

    fn sample() -> Plot {
        Plot {
            title: "loop <1> & \"two\" \u{1}".into(),
            x_label: "displacement [mm]".into(),
            y_label: "force [N]".into(),
            x_log: false,
            series: vec![
                Series::line("a", vec![(0.0, 0.0), (1.0, 2.0)]),
                Series::line("b", vec![(0.0, 1.0), (f64::NAN, 3.0), (1.0, 1.0)]),
                Series::markers("c's", vec![(0.5, 1.5), (0.5, 1.5)]),
            ],
        }
    }

    #[test]
    fn plot_has_labels_and_one_polyline_per_line_series() {
        let svg = sample().render();
        assert!(svg.contains("displacement [mm]") && svg.contains("force [N]"));
        assert!(svg.contains("loop &lt;1&gt; &amp; &quot;two&quot; <"));
        assert!(svg.contains("c&apos;s"));
        assert_eq!(svg.matches("<polyline").count(), 2);
        // Two markers and the legend's.
        assert_eq!(svg.matches("<circle").count(), 3);
        assert!(!svg.contains("NaN") && !svg.contains('\u{1}'));
        well_formed(&svg).unwrap();
    }

    #[test]
    fn panels_stack_and_stay_well_formed() {
        let mut empty = sample();
        empty.series.clear();
        let constant = Plot {
            series: vec![Series::line("flat", vec![(0.0, 5.0), (2.0, 5.0)])],
            ..sample()
        };
        let svg = render_panels(&[sample(), empty, constant]);
        well_formed(&svg).unwrap();
        assert!(svg.contains(r#"height="1680""#));
        assert_eq!(svg.matches("<g transform=").count(), 3);
        // The flat series gets a readable axis around 5.
        assert!(svg.contains(">5<") && svg.contains(">5.2<"), "{svg}");
    }

    #[test]
    fn log_axis_and_long_titles() {
        assert_eq!(
            log_ticks(0.05f64.log10(), 0.0),
            vec![0.05, 0.1, 0.2, 0.5, 1.0]
        );
        assert_eq!(
            log_ticks(-3.0, 2.0),
            vec![1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0]
        );
        let p = Plot {
            title: "t".repeat(400),
            x_log: true,
            series: vec![Series::markers(
                "m",
                vec![(0.05, 1.0), (0.25, 2.0), (1.0, 3.0), (0.0, 4.0)],
            )],
            ..sample()
        };
        let svg = p.render();
        well_formed(&svg).unwrap();
        // The point at x = 0 cannot be drawn on a log axis: 3 markers and
        // the legend's.
        assert_eq!(svg.matches("<circle").count(), 4);
        assert!(svg.contains(">0.05<") && svg.contains(">0.5<") && svg.contains(">1<"));
        assert!(svg.contains('…') && svg.contains(r#"font-size="10.0""#));
    }

    #[test]
    fn the_checker_finds_what_breaks_xml() {
        well_formed(r#"<?xml version="1.0"?><a x="1"><!-- c --><b/>t &amp; &#233;</a>"#).unwrap();
        for bad in [
            "<a><b></a></b>",
            "<a>",
            "</a>",
            "<a></a><b/>",
            "<a x=1/>",
            r#"<a x="1" x="2"/>"#,
            r#"<a x="<"/>"#,
            "<a>1 < 2</a>",
            "<a>&nbsp;</a>",
            "<a>fish & chips</a>",
            "<a>\u{1}</a>",
            "<1a/>",
            "text<a/>",
            "",
        ] {
            assert!(well_formed(bad).is_err(), "{bad:?} accepted");
        }
    }
}
