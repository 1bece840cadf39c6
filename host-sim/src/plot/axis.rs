//! Axis ranges, ticks and tick labels. The drawing works in *axis units*:
//! the values themselves on a linear axis, their base-10 logarithms on a
//! logarithmic one, so that both are linear maps to pixels.

/// One axis of a panel, in axis units.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Axis {
    /// Logarithmic.
    pub log: bool,
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Labelled ticks (with grid lines).
    pub ticks: Vec<f64>,
    /// Unlabelled minor grid lines (the 2..9 of a log axis).
    pub minor: Vec<f64>,
}

/// Largest magnitude an axis end takes, so that its span stays finite.
const LIMIT: f64 = 1e300;

/// A value in axis units, or `None` if it cannot be drawn (non-finite, or
/// not positive on a log axis).
pub(super) fn to_axis(log: bool, v: f64) -> Option<f64> {
    if !v.is_finite() {
        None
    } else if log {
        (v > 0.0).then(|| v.log10())
    } else {
        Some(v)
    }
}

impl Axis {
    /// The axis over `values` (axis units, finite), widened by `pad` times
    /// the span at both ends; a default range when there are none, a
    /// readable one around a constant.
    pub(super) fn new(log: bool, values: impl Iterator<Item = f64>, pad: f64) -> Self {
        let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let (lo, hi) = if !(lo.is_finite() && hi.is_finite()) {
            if log { (0.0, 1.0) } else { (-1.0, 1.0) }
        } else if log {
            if hi - lo < 1e-9 {
                (lo - 0.5, hi + 0.5)
            } else {
                (lo, hi)
            }
        } else {
            let (lo, hi) = (lo.clamp(-LIMIT, LIMIT), hi.clamp(-LIMIT, LIMIT));
            let scale = lo.abs().max(hi.abs());
            if hi - lo <= 1e-9 * scale || hi <= lo {
                let half = if scale > 0.0 { 0.05 * scale } else { 1.0 };
                let mid = 0.5 * (lo + hi);
                (mid - half, mid + half)
            } else {
                (lo, hi)
            }
        };
        let span = hi - lo;
        let (lo, hi) = (lo - pad * span, hi + pad * span);
        let (ticks, minor) = if log {
            log_axis_ticks(lo, hi)
        } else {
            (ticks(lo, hi, 8), Vec::new())
        };
        Self {
            log,
            lo,
            hi,
            ticks: ticks.into_iter().filter(|t| t.is_finite()).collect(),
            minor,
        }
    }

    /// The label of the tick at `v` (axis units).
    pub(super) fn label(&self, v: f64) -> String {
        if self.log {
            fmt_log(10f64.powf(v))
        } else {
            fmt_tick(v)
        }
    }

    /// Where `v` (axis units) falls, 0 at `lo` and 1 at `hi`.
    pub(super) fn fraction(&self, v: f64) -> f64 {
        (v - self.lo) / (self.hi - self.lo)
    }
}

/// Tick positions covering [lo, hi] with a 1-2-5 step, about `target` of
/// them; the ends alone when the range is too narrow for its magnitude.
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
    let mantissas: &[f64] = if hi - lo <= 3.0 {
        &[1.0, 2.0, 5.0]
    } else {
        &[1.0]
    };
    decade_multiples(lo, hi, mantissas)
}

/// `m · 10^k` for every mantissa `m` and decade `k` with its logarithm in
/// [lo, hi] (at most 64).
fn decade_multiples(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi < lo {
        return Vec::new();
    }
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

/// Labelled and minor ticks of a log axis over [lo, hi] (exponents), in
/// exponents: the powers of ten and, over a narrower range, their 2 and 5
/// (or every) multiple; more than ten decades, every other power. A range
/// inside one decade with fewer than two such ticks gets linear ones.
fn log_axis_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let span = hi - lo;
    let mut values = if span <= 1.0 {
        decade_multiples(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    } else {
        log_ticks(lo, hi)
    };
    if span > 10.0 {
        values.retain(|v| (v.log10().round() as i64) % 2 == 0);
    }
    if values.len() < 2 {
        values = ticks(10f64.powf(lo), 10f64.powf(hi), 4)
            .into_iter()
            .filter(|v| *v > 0.0)
            .collect();
    }
    let labelled: Vec<f64> = values.iter().map(|v| v.log10()).collect();
    let minor = if span <= 6.0 {
        decade_multiples(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
            .into_iter()
            .map(f64::log10)
            .filter(|m| labelled.iter().all(|t| (t - m).abs() > 1e-9))
            .collect()
    } else {
        Vec::new()
    };
    (labelled, minor)
}

/// A linear axis' tick label: up to 4 decimals, scientific far from 1.
fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else {
        trim(format!("{v:.4}"))
    }
}

/// A log axis' tick label: the value with its significant digits (four at
/// most), `1e-6` style beyond 10^-3 .. 10^5.
fn fmt_log(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return String::new();
    }
    let k = (v.log10() + 1e-9).floor();
    let m = (v / 10f64.powf(k) * 1000.0).round() / 1000.0;
    if (-3.0..5.0).contains(&k) {
        let decimals = (3.0 - k).max(0.0) as usize;
        trim(format!("{:.*}", decimals, m * 10f64.powf(k)))
    } else {
        format!("{}e{}", trim(format!("{m:.3}")), k as i64)
    }
}

/// Trailing zeros (and a trailing point) of a decimal removed.
fn trim(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
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

    #[test]
    fn log_ticks_take_1_2_5_over_three_decades() {
        assert_eq!(
            log_ticks(0.05f64.log10(), 0.0),
            vec![0.05, 0.1, 0.2, 0.5, 1.0]
        );
        assert_eq!(
            log_ticks(-3.0, 2.0),
            vec![1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0]
        );
    }

    #[test]
    fn log_axes_label_their_ticks_plainly() {
        let a = Axis::new(true, [0.0, 50f64.log10()].into_iter(), 0.0);
        let labels: Vec<String> = a.ticks.iter().map(|t| a.label(*t)).collect();
        assert_eq!(labels, ["1", "2", "5", "10", "20", "50"]);
        assert!(a.minor.len() > 5);
        // Inside one decade: every multiple, or linear ticks.
        let a = Axis::new(true, [2f64.log10(), 8f64.log10()].into_iter(), 0.0);
        let labels: Vec<String> = a.ticks.iter().map(|t| a.label(*t)).collect();
        assert_eq!(labels, ["2", "3", "4", "5", "6", "7", "8"]);
        let a = Axis::new(true, [21f64.log10(), 22f64.log10()].into_iter(), 0.0);
        assert!(a.ticks.len() >= 2, "{:?}", a.ticks);
        // Many decades: every other power, `1e-8` style.
        let a = Axis::new(true, [-10.0, 2.0].into_iter(), 0.0);
        let labels: Vec<String> = a.ticks.iter().map(|t| a.label(*t)).collect();
        assert_eq!(labels[0], "1e-10");
        assert!(labels.contains(&"0.01".to_string()) && labels.contains(&"100".to_string()));
        assert_eq!(fmt_log(2e-5), "2e-5");
        assert_eq!(fmt_log(0.05000000000000001), "0.05");
        assert_eq!(fmt_log(2.5e6), "2.5e6");
    }

    #[test]
    fn ranges_of_nothing_constants_and_huge_values_are_usable() {
        let a = Axis::new(false, std::iter::empty(), 0.04);
        assert!(a.lo < a.hi && a.lo.is_finite());
        let a = Axis::new(false, [5.0, 5.0].into_iter(), 0.0);
        assert_eq!((a.lo, a.hi), (4.75, 5.25));
        let a = Axis::new(false, [-1e308, 1e308].into_iter(), 0.04);
        assert!((a.hi - a.lo).is_finite() && !a.ticks.is_empty());
        let a = Axis::new(true, [3.0, 3.0].into_iter(), 0.0);
        assert_eq!((a.lo, a.hi), (2.5, 3.5));
    }
}
