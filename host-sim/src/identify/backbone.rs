//! The first stage of the identification (seed 000 §3.4): the long-term
//! backbone from the triangles once the hysteretic relaxation is past.
//!
//! Far enough from its turning point, a branch of a slow triangle carries
//! the long-term elastic force plus forces that change sign with the
//! direction: the Jenkins cells at their slip forces, the x_f cells at
//! their saturation, the Maxwell cells at their small rate forces. The
//! mean of a loading and an unloading branch at the same displacement (the
//! midline) keeps the long-term force `g⁰ F^∞(x)` alone. The seed fits
//! it with a C² cubic spline (Figs 3.18-3.19); here it becomes the knots
//! of the core's monotone spline.

use super::triangle::{Branch, Triangles};

/// Distance from a turning point within which a branch is still in its
/// hysteretic relaxation, for the part (§3.4: 1.5 mm in both directions).
pub const PART_THRESHOLD_MM: f64 = 1.5;

/// The force of a branch at `x`, linearly interpolated between its
/// samples (a branch is monotone in x), or `None` outside it.
fn force_at(b: &Branch, x: f64) -> Option<f64> {
    let s = &b.samples;
    let key = |p: &(f64, f64)| p.0 * b.direction;
    let at = x * b.direction;
    let i = s.partition_point(|p| key(p) < at);
    match (i.checked_sub(1).and_then(|j| s.get(j)), s.get(i)) {
        (Some(&(x0, f0)), Some(&(x1, f1))) if x1 != x0 => {
            Some(f0 + (f1 - f0) * (x - x0) / (x1 - x0))
        }
        (_, Some(&(x1, f1))) if x1 == x => Some(f1),
        _ => None,
    }
}

/// Midline points `(x, (F_up + F_down) / 2)` every `step_mm`, from each
/// pair of consecutive branches of opposite directions (the first loading
/// from rest left out: it is no reversal), where both are farther than
/// `threshold_mm` from their turning points.
pub fn midline(triangles: &[Triangles], threshold_mm: f64, step_mm: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    if !(step_mm > 0.0 && step_mm.is_finite()) {
        return out;
    }
    for t in triangles {
        for pair in t.branches.get(1..).unwrap_or(&[]).windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            if a.direction == b.direction {
                continue;
            }
            // The settled part of a branch: beyond threshold from its start,
            // up to its end; none when the branch is shorter.
            let settled = |br: &Branch| {
                let start = br.turning_mm + br.direction * threshold_mm;
                let end = br.samples.last()?.0;
                ((end - start) * br.direction > 0.0).then(|| (start.min(end), start.max(end)))
            };
            let (Some((a_lo, a_hi)), Some((b_lo, b_hi))) = (settled(a), settled(b)) else {
                continue;
            };
            let (lo, hi) = (a_lo.max(b_lo), a_hi.min(b_hi));
            if hi <= lo {
                continue;
            }
            let mut x = (lo / step_mm).ceil() * step_mm;
            while x <= hi {
                if let (Some(fa), Some(fb)) = (force_at(a, x), force_at(b, x)) {
                    out.push((x, 0.5 * (fa + fb)));
                }
                x += step_mm;
            }
        }
    }
    out.sort_by(|p, q| p.0.total_cmp(&q.0));
    out
}

/// Knots of the long-term backbone: `knots` abscissae evenly spread over
/// the midline's range, each knot's force the value at the knot of the
/// least-squares line through the midline points within one knot spacing
/// (a knot with fewer than 3 points is dropped). `None` when fewer than 2
/// knots remain or the forces do not increase (the core's monotone spline
/// needs increasing forces).
pub fn knots(points: &[(f64, f64)], knots: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let (lo, hi) = (points.first()?.0, points.last()?.0);
    if knots < 2 || hi <= lo {
        return None;
    }
    let h = (hi - lo) / (knots - 1) as f64;
    let (mut xs, mut fs) = (Vec::new(), Vec::new());
    for k in 0..knots {
        let xk = lo + k as f64 * h;
        let near: Vec<&(f64, f64)> = points.iter().filter(|p| (p.0 - xk).abs() <= h).collect();
        if near.len() < 3 {
            continue;
        }
        let n = near.len() as f64;
        let (mx, mf) = (
            near.iter().map(|p| p.0).sum::<f64>() / n,
            near.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let sxx: f64 = near.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
        let sxf: f64 = near.iter().map(|p| (p.0 - mx) * (p.1 - mf)).sum();
        let slope = if sxx > 0.0 { sxf / sxx } else { 0.0 };
        xs.push(xk);
        fs.push(mf + slope * (xk - mx));
    }
    (xs.len() >= 2 && fs.windows(2).all(|w| w[1] > w[0])).then_some((xs, fs))
}
