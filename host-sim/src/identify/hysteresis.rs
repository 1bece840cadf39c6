//! The second stage of the identification (seed 000 §3.4, Figs
//! 3.20-3.21): Jenkins cells placed on the instantaneous-modulus curve.
//!
//! Along a branch of a slow triangle, a Jenkins cell that still sticks
//! adds its stiffness `g_j K^∞(x)` to the long-term one `g⁰ K^∞(x)`; it
//! slips at a distance D_j from the turning point (twice its slip
//! distance from rest, Masing's rule, on a linear backbone). Divided by
//! the long-term modulus at the same x, the curve is a staircase
//! `R(d) = 1 + Σ_{D_j > d} g_j / g⁰`. The seed places the steps by eye;
//! here a least-squares staircase of a chosen number of steps is fitted
//! by dynamic programming over the binned curve.

use super::triangle::Triangles;

/// Width of the distance bins the curve is averaged over on a part (its
/// largest triangle 4.5 mm), mm; [`super::report::Scale`] scales it.
pub const BIN_MM: f64 = 0.02;

/// One placed cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// Distance from the turning point where it slips, mm (twice its slip
    /// distance on a linear backbone).
    pub distance_mm: f64,
    /// Its stiffness over the long-term one, g_j / g⁰.
    pub drop: f64,
}

/// The normalised curve `(d, K_inst / K_long(x))` of every reversal
/// branch (the first loading left out), `long_term_modulus(x)` giving the
/// long-term modulus g⁰ K^∞(x) in N/mm where it is known, for x in
/// `known` (mm; points elsewhere are left out); binned every `bin_mm` (on
/// a part [`BIN_MM`]) as `(bin centre, mean, count)`.
pub fn normalised(
    triangles: &[Triangles],
    long_term_modulus: impl Fn(f64) -> f64,
    known: (f64, f64),
    bin_mm: f64,
) -> Vec<(f64, f64, usize)> {
    let mut bins: Vec<(f64, usize)> = Vec::new();
    for t in triangles {
        for b in t.branches.iter().skip(1) {
            for (i, &(d, k)) in b.modulus.iter().enumerate() {
                // The modulus point i sits at sample i + 1 of the branch.
                let Some(&(x, _)) = b.samples.get(i + 1) else {
                    continue;
                };
                if !(known.0..=known.1).contains(&x) {
                    continue;
                }
                let r = k / long_term_modulus(x);
                if !(r.is_finite() && d >= 0.0) {
                    continue;
                }
                let bin = (d / bin_mm) as usize;
                if bins.len() <= bin {
                    bins.resize(bin + 1, (0.0, 0));
                }
                bins[bin].0 += r;
                bins[bin].1 += 1;
            }
        }
    }
    bins.iter()
        .enumerate()
        .filter(|(_, b)| b.1 > 0)
        .map(|(i, b)| ((i as f64 + 0.5) * bin_mm, b.0 / b.1 as f64, b.1))
        .collect()
}

/// `cells` steps fitted to the binned curve by least squares (weights: the
/// points per bin), each level the weighted mean of its bins: the cells'
/// slip distances from the turning point and their drops, nearest first.
/// Bins below `from_mm` (the filter's start-up after a turning point) are
/// left out, and once the steps are placed each level is taken again from
/// its bins at least `from_mm` clear of them. `None` when there are fewer
/// bins than levels.
pub fn place(curve: &[(f64, f64, usize)], cells: usize, from_mm: f64) -> Option<Vec<Placed>> {
    let pts: Vec<&(f64, f64, usize)> = curve.iter().filter(|p| p.0 >= from_mm).collect();
    let (n, levels) = (pts.len(), cells + 1);
    if n < levels || cells == 0 {
        return None;
    }
    // Prefix sums of w, w r, w r² for the cost of a segment.
    let mut sw = vec![0.0; n + 1];
    let mut swr = vec![0.0; n + 1];
    let mut swr2 = vec![0.0; n + 1];
    for (i, p) in pts.iter().enumerate() {
        let w = p.2 as f64;
        sw[i + 1] = sw[i] + w;
        swr[i + 1] = swr[i] + w * p.1;
        swr2[i + 1] = swr2[i] + w * p.1 * p.1;
    }
    let cost = |a: usize, b: usize| {
        let w = sw[b] - sw[a];
        let m = swr[b] - swr[a];
        (swr2[b] - swr2[a]) - if w > 0.0 { m * m / w } else { 0.0 }
    };
    let mean = |a: usize, b: usize| (swr[b] - swr[a]) / (sw[b] - sw[a]);
    // best[l][j]: least cost of the first j bins in l + 1 segments.
    let mut best = vec![vec![f64::INFINITY; n + 1]; levels];
    let mut cut = vec![vec![0usize; n + 1]; levels];
    for (j, b) in best[0].iter_mut().enumerate().skip(1) {
        *b = cost(0, j);
    }
    for l in 1..levels {
        for j in (l + 1)..=n {
            for i in l..j {
                let c = best[l - 1][i] + cost(i, j);
                if c < best[l][j] {
                    best[l][j] = c;
                    cut[l][j] = i;
                }
            }
        }
    }
    // Walk back the cuts.
    let mut bounds = vec![n];
    let mut j = n;
    for l in (1..levels).rev() {
        j = cut[l][j];
        bounds.push(j);
    }
    bounds.push(0);
    bounds.reverse();
    // The steps: between the last bin of one level and the first of the
    // next.
    let steps: Vec<f64> = bounds[1..levels]
        .iter()
        .map(|&at| 0.5 * (pts[at - 1].0 + pts[at].0))
        .collect();
    // Each level again, from its bins at least `from_mm` clear of its steps
    // (the low-pass rounds each step over about as much as it delays the
    // start), or from all its bins when none is that far.
    let level: Vec<f64> = bounds
        .windows(2)
        .enumerate()
        .map(|(s, w)| {
            let lo = if s == 0 {
                f64::NEG_INFINITY
            } else {
                steps[s - 1] + from_mm
            };
            let hi = steps.get(s).map_or(f64::INFINITY, |d| d - from_mm);
            let (mut sum, mut weight) = (0.0, 0.0);
            for p in &pts[w[0]..w[1]] {
                if p.0 >= lo && p.0 <= hi {
                    sum += p.1 * p.2 as f64;
                    weight += p.2 as f64;
                }
            }
            if weight > 0.0 {
                sum / weight
            } else {
                mean(w[0], w[1])
            }
        })
        .collect();
    Some(
        steps
            .iter()
            .enumerate()
            .map(|(s, &distance_mm)| Placed {
                distance_mm,
                drop: level[s] - level[s + 1],
            })
            .collect(),
    )
}
