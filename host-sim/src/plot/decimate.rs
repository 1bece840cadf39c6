//! Decimation of dense lines to what a pixel grid can show.

/// `points` reduced to at most four per pixel column, in their order: of
/// each run of consecutive points that fall in one of `columns` equal
/// columns over `x_range`, the first, the lowest, the highest and the last.
/// Drawn as a line, the result covers the same pixels vertically in every
/// column as the full line (a dense oscillation becomes its envelope), and
/// keeps the data's extremes exactly. Lines with no more points than
/// columns are returned as they are.
///
/// The points are expected finite (the writer splits lines at the others).
pub fn decimate(points: &[(f64, f64)], x_range: (f64, f64), columns: usize) -> Vec<(f64, f64)> {
    let columns = columns.max(1);
    if points.len() <= columns {
        return points.to_vec();
    }
    let (x0, x1) = x_range;
    let width = x1 - x0;
    let column = |x: f64| -> i64 {
        let c = (x - x0) / width * columns as f64;
        if c.is_finite() {
            c.floor().clamp(-1.0, columns as f64) as i64
        } else {
            0
        }
    };
    let mut out = Vec::with_capacity(4 * columns + 4);
    let mut keep = |run: &Run| {
        let mut idx = [run.first, run.min, run.max, run.last];
        idx.sort_unstable();
        let mut previous = None;
        for i in idx {
            if previous != Some(i) {
                out.extend(points.get(i).copied());
                previous = Some(i);
            }
        }
    };
    let mut run: Option<Run> = None;
    for (i, &(x, y)) in points.iter().enumerate() {
        let c = column(x);
        match &mut run {
            Some(r) if r.column == c => {
                if y < r.low {
                    (r.min, r.low) = (i, y);
                }
                if y > r.high {
                    (r.max, r.high) = (i, y);
                }
                r.last = i;
            }
            _ => {
                if let Some(r) = run.take() {
                    keep(&r);
                }
                run = Some(Run {
                    column: c,
                    first: i,
                    min: i,
                    max: i,
                    last: i,
                    low: y,
                    high: y,
                });
            }
        }
    }
    if let Some(r) = run {
        keep(&r);
    }
    out
}

/// Consecutive points in one column.
struct Run {
    column: i64,
    first: usize,
    min: usize,
    max: usize,
    last: usize,
    low: f64,
    high: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dense_sine_keeps_its_extremes_and_order() {
        let n = 100_000;
        let pts: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64;
                (t, (std::f64::consts::TAU * 300.0 * t).sin() * (1.0 + t))
            })
            .collect();
        let d = decimate(&pts, (0.0, 1.0), 500);
        assert!(d.len() <= 4 * 500 && d.len() >= 2 * 500, "{}", d.len());
        let extent = |p: &[(f64, f64)]| {
            p.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
                    (a.min(q.1), b.max(q.1))
                })
        };
        assert_eq!(extent(&d), extent(&pts));
        assert!(d.windows(2).all(|w| w[0].0 < w[1].0));
        assert_eq!((d[0], d[d.len() - 1]), (pts[0], pts[n - 1]));
    }

    #[test]
    fn sparse_lines_and_loops_stay_whole() {
        let pts = vec![(0.0, 0.0), (1.0, 1.0), (0.0, 2.0)];
        assert_eq!(decimate(&pts, (0.0, 1.0), 10), pts);
        // A loop run back and forth: each pass through a column is its own
        // run, so the return path is kept.
        let pts: Vec<(f64, f64)> = (0..2000)
            .map(|i| {
                let a = i as f64 / 2000.0 * std::f64::consts::TAU;
                (a.cos(), a.sin())
            })
            .collect();
        let d = decimate(&pts, (-1.0, 1.0), 100);
        assert!(d.len() < 1000);
        assert!(d.iter().any(|p| p.1 > 0.99) && d.iter().any(|p| p.1 < -0.99));
        // A degenerate range puts everything in one column.
        let d = decimate(&pts, (0.0, 0.0), 100);
        assert!(d.len() <= 4);
    }
}
