//! Error against cost on logarithmic axes, as a [`crate::plot::Plot`]: one
//! marker shape and colour per family, each family's Pareto front drawn as
//! a step line through its front points (ringed), and the 1 % line.

use crate::plot::{Legend, Marker, Plot, Rgb, Series, Shape, palette};

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

/// Smallest error drawn (a smaller one sits at this floor).
const FLOOR: f64 = 1e-10;

/// The plot of `points` with `families` in legend order.
pub fn plot(title: &str, x_label: &str, points: &[Point], families: &[String]) -> Plot {
    let pct = |e: f64| 100.0 * e.max(FLOOR);
    let costs = || points.iter().map(|p| p.cost).filter(|c| *c > 0.0);
    let (lo, hi) = costs().fold((f64::INFINITY, 0.0f64), |(l, h), c| (l.min(c), h.max(c)));
    let ring = |shape| Marker {
        shape,
        radius: 7,
        filled: false,
    };
    let mut series = Vec::new();
    for (i, family) in families.iter().enumerate() {
        let color = palette(i);
        let mine: Vec<&Point> = points.iter().filter(|p| &p.family == family).collect();
        let mut front: Vec<&Point> = mine.iter().copied().filter(|p| p.front).collect();
        front.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        // Step line: along each front point's error to the next front
        // point's cost, then down to its error; on to the largest cost.
        let mut steps = Vec::new();
        for p in &front {
            if let Some(&(_, e)) = steps.last() {
                steps.push((p.cost, e));
            }
            steps.push((p.cost, pct(p.error)));
        }
        if let Some(&(c, e)) = steps.last()
            && hi > c
        {
            steps.push((hi, e));
        }
        series.push(Series::line("", steps).with_color(color));
        series.push(
            Series::markers(
                format!(
                    "{family} ({} points, {} on the front)",
                    mine.len(),
                    front.len()
                ),
                mine.iter().map(|p| (p.cost, pct(p.error))).collect(),
            )
            .with_color(color)
            .with_marker(Marker {
                shape: Shape::nth(i),
                radius: 4,
                filled: true,
            }),
        );
        series.push(
            Series::markers("", front.iter().map(|p| (p.cost, pct(p.error))).collect())
                .with_color(Rgb::BLACK)
                .with_marker(ring(Shape::nth(i))),
        );
    }
    // Legend entries for the rings and the 1 % line.
    series.push(
        Series::markers("Pareto front point (step line)", Vec::new())
            .with_color(Rgb::BLACK)
            .with_marker(ring(Shape::Circle)),
    );
    let one_percent = if lo.is_finite() && hi > 0.0 {
        vec![(lo, 1.0), (hi, 1.0)]
    } else {
        Vec::new()
    };
    series.push(Series::dashed("1 % error", one_percent).with_color(Rgb::GREY));
    Plot {
        title: title.into(),
        x_label: x_label.into(),
        y_label: "error [%] (log)".into(),
        x_log: true,
        y_log: true,
        legend: Legend::Auto,
        series,
    }
}

/// The plot of `points` with `families` in legend order, as SVG.
pub fn render(title: &str, x_label: &str, points: &[Point], families: &[String]) -> String {
    plot(title, x_label, points, families).render()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::well_formed;

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
        let families = ["a <b>".to_string(), "c".to_string()];
        let p = plot("t & t", "cost", &pts, &families);
        assert!(p.x_log && p.y_log);
        // The first family's step line: (10, 10 %) → (40, 10 %) → (40,
        // 0.1 %), on to the largest cost.
        assert_eq!(
            p.series[0].points,
            vec![(10.0, 10.0), (40.0, 10.0), (40.0, 0.1)]
        );
        let svg = render("t & t", "cost", &pts, &families);
        well_formed(&svg).unwrap();
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
        well_formed(&render("many", "cost", &many, &names)).unwrap();
        assert!(svg.contains("a &lt;b&gt; (3 points, 2 on the front)"));
        assert!(svg.contains("1 % error") && svg.contains("Pareto front point"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        let empty = render("e", "cost", &[], &[]);
        well_formed(&empty).unwrap();
    }
}
