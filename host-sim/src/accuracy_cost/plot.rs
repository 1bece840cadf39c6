//! Error against cost on logarithmic axes: one marker shape and colour per
//! family, each family's Pareto front drawn as a step line through its
//! front points (ringed), and the 1 % line. Text goes through
//! [`svg::escape`](crate::svg::escape) and the ticks are
//! [`svg::log_ticks`](crate::svg::log_ticks); the output passes
//! [`svg::well_formed`](crate::svg::well_formed).

use std::fmt::Write;

use crate::svg;

/// One configuration on the plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Family (legend entry, colour and shape).
    pub family: String,
    /// Cost (horizontal), > 0.
    pub cost: f64,
    /// Error as a fraction (vertical, drawn in %), > 0.
    pub error: f64,
    /// On its family's Pareto front.
    pub front: bool,
}

const PALETTE: [&str; 10] = [
    "#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#7b3294", "#4d4d4d",
    "#b2182b", "#1b7837",
];
/// Width of the axes' box and margins left, top and bottom.
const PLOT_WIDTH: f64 = 720.0;
const HEIGHT: f64 = 640.0;
const MARGIN: (f64, f64, f64) = (90.0, 50.0, 70.0); // left, top, bottom
/// Average glyph width at 13 px, to size the legend.
const GLYPH: f64 = 7.4;

/// Smallest error drawn (a smaller one sits on the bottom edge).
const FLOOR: f64 = 1e-10;

/// A marker of shape `shape` centred at (x, y).
fn marker(shape: usize, x: f64, y: f64, r: f64, style: &str) -> String {
    match shape % 6 {
        0 => format!(r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r:.1}" {style}/>"#),
        1 => format!(
            r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" {style}/>"#,
            x - r,
            y - r,
            2.0 * r,
            2.0 * r
        ),
        2 => format!(
            r#"<polygon points="{x:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" {style}/>"#,
            y - 1.2 * r,
            x + 1.1 * r,
            y + 0.8 * r,
            x - 1.1 * r,
            y + 0.8 * r
        ),
        3 => format!(
            r#"<polygon points="{x:.1},{:.1} {:.1},{y:.1} {x:.1},{:.1} {:.1},{y:.1}" {style}/>"#,
            y - 1.3 * r,
            x + 1.3 * r,
            y + 1.3 * r,
            x - 1.3 * r
        ),
        4 => format!(
            r#"<polygon points="{x:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" {style}/>"#,
            y + 1.2 * r,
            x + 1.1 * r,
            y - 0.8 * r,
            x - 1.1 * r,
            y - 0.8 * r
        ),
        _ => format!(
            r#"<path d="M{:.1} {:.1}L{:.1} {:.1}M{:.1} {:.1}L{:.1} {:.1}" {style}/>"#,
            x - r,
            y - r,
            x + r,
            y + r,
            x - r,
            y + r,
            x + r,
            y - r
        ),
    }
}

/// Decade bounds (log10) covering the finite positive values.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(f64::log10)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let (lo, hi) = (lo.floor(), hi.ceil());
    if hi > lo { (lo, hi) } else { (lo, lo + 1.0) }
}

fn label(v: f64) -> String {
    let e = v.log10();
    if (e - e.round()).abs() < 1e-9 && !(-2.0..=4.0).contains(&e) {
        format!("1e{}", e.round() as i64)
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The plot of `points` with `families` in legend order.
pub fn render(title: &str, x_label: &str, points: &[Point], families: &[String]) -> String {
    let (left, top, bottom) = MARGIN;
    let longest = families
        .iter()
        .map(|f| f.chars().count() + 28)
        .max()
        .unwrap_or(0)
        .max(30);
    let right = 40.0 + GLYPH * longest as f64;
    let width = (left + PLOT_WIDTH + right).ceil();
    let (pw, ph) = (PLOT_WIDTH, HEIGHT - top - bottom);
    let pct = |e: f64| 100.0 * e.max(FLOOR);
    let (x0, x1) = decades(points.iter().map(|p| p.cost));
    let (y0, y1) = decades(
        points
            .iter()
            .map(|p| pct(p.error))
            .chain(std::iter::once(1.0)),
    );
    let sx = |c: f64| left + (c.max(1e-300).log10() - x0) / (x1 - x0) * pw;
    let sy = |e: f64| top + (y1 - pct(e).log10()) / (y1 - y0) * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{HEIGHT}" viewBox="0 0 {width} {HEIGHT}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(
        s,
        r#"<rect width="{width}" height="{HEIGHT}" fill="white"/>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="28" text-anchor="middle" font-size="16">{}</text>"#,
        left + pw / 2.0,
        svg::escape(title)
    );
    for t in svg::log_ticks(x0, x1) {
        let x = sx(t);
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{top}" x2="{x:.1}" y2="{:.1}" stroke="#e3e3e3"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            top + ph,
            top + ph + 18.0,
            label(t)
        );
    }
    for t in svg::log_ticks(y0, y1) {
        let y = top + (y1 - t.log10()) / (y1 - y0) * ph;
        let _ = writeln!(
            s,
            r##"<line x1="{left}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#e3e3e3"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            left + pw,
            left - 6.0,
            y + 4.0,
            label(t)
        );
    }
    // The 1 % line.
    let y1pct = sy(0.01);
    let _ = writeln!(
        s,
        r##"<line x1="{left}" y1="{y1pct:.1}" x2="{:.1}" y2="{y1pct:.1}" stroke="#555" stroke-dasharray="6 4"/>"##,
        left + pw
    );
    let _ = writeln!(
        s,
        r#"<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        left + pw / 2.0,
        HEIGHT - 22.0,
        svg::escape(x_label)
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(24 {:.1}) rotate(-90)" text-anchor="middle">error [%] (log)</text>"#,
        top + ph / 2.0
    );
    let legend_x = left + pw + 16.0;
    for (i, family) in families.iter().enumerate() {
        let color = PALETTE.get(i % PALETTE.len()).copied().unwrap_or("black");
        let mine: Vec<&Point> = points.iter().filter(|p| &p.family == family).collect();
        let mut front: Vec<&Point> = mine.iter().copied().filter(|p| p.front).collect();
        front.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        // Step line: along each front point's error to the next front
        // point's cost, then down to its error.
        if let Some(first) = front.first() {
            let mut d = format!("M{:.1} {:.1}", sx(first.cost), sy(first.error));
            for p in front.iter().skip(1) {
                let _ = write!(d, "H{:.1}V{:.1}", sx(p.cost), sy(p.error));
            }
            let _ = write!(d, "H{:.1}", left + pw);
            let _ = writeln!(
                s,
                r#"<path d="{d}" fill="none" stroke="{color}" stroke-width="1.6" stroke-opacity="0.8"/>"#
            );
        }
        let fill =
            format!(r#"fill="{color}" stroke="{color}" stroke-width="1.5" fill-opacity="0.55""#);
        for p in &mine {
            s.push_str(&marker(i, sx(p.cost), sy(p.error), 4.0, &fill));
            s.push('\n');
        }
        for p in &front {
            s.push_str(&marker(
                i,
                sx(p.cost),
                sy(p.error),
                7.0,
                r#"fill="none" stroke="black" stroke-width="1.3""#,
            ));
            s.push('\n');
        }
        let ly = top + 14.0 + 20.0 * i as f64;
        s.push_str(&marker(i, legend_x + 8.0, ly, 4.5, &fill));
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}">{} ({} points, {} on the front)</text>"#,
            legend_x + 22.0,
            ly + 4.0,
            svg::escape(family),
            mine.len(),
            front.len()
        );
    }
    let ly = top + 14.0 + 20.0 * families.len() as f64 + 10.0;
    let _ = writeln!(
        s,
        r##"{}<text x="{:.1}" y="{:.1}">Pareto front point (step line)</text>"##,
        marker(
            0,
            legend_x + 8.0,
            ly,
            7.0,
            r#"fill="none" stroke="black" stroke-width="1.3""#
        ),
        legend_x + 22.0,
        ly + 4.0
    );
    let _ = writeln!(
        s,
        r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#555" stroke-dasharray="6 4"/><text x="{:.1}" y="{:.1}">1 % error</text>"##,
        legend_x,
        ly + 20.0,
        legend_x + 16.0,
        ly + 20.0,
        legend_x + 22.0,
        ly + 24.0
    );
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_is_well_formed_with_markers_and_fronts() {
        let pts = vec![
            Point {
                family: "a <b>".into(),
                cost: 10.0,
                error: 0.1,
                front: true,
            },
            Point {
                family: "a <b>".into(),
                cost: 20.0,
                error: 0.2,
                front: false,
            },
            Point {
                family: "a <b>".into(),
                cost: 40.0,
                error: 1e-3,
                front: true,
            },
            Point {
                family: "c".into(),
                cost: 5.0,
                error: 0.0,
                front: true,
            },
        ];
        let svg = render("t & t", "cost", &pts, &["a <b>".into(), "c".into()]);
        svg::well_formed(&svg).unwrap();
        // Every marker shape, as data and as front ring.
        let many: Vec<Point> = (0..8)
            .map(|i| Point {
                family: format!("f{i}"),
                cost: 1.0 + i as f64,
                error: 0.01,
                front: true,
            })
            .collect();
        let names: Vec<String> = (0..8).map(|i| format!("f{i}")).collect();
        svg::well_formed(&render("many", "cost", &many, &names)).unwrap();
        assert!(svg.contains("a &lt;b&gt; (3 points, 2 on the front)"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        let empty = render("e", "cost", &[], &[]);
        svg::well_formed(&empty).unwrap();
    }
}
