//! What a closed-form reference is compared with: the steady cycle of one
//! effect as `validate` measured it ([`Measured`]), and the lines a
//! family's reference gives back ([`Line`]). Each family's references are
//! in its own module (`family::*`); `validate` steps the scene and prints.

/// A comparison, or its absence.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Reference and measured values.
    Compared {
        /// Closed-form value.
        reference: f64,
        /// Value from the simulation.
        measured: f64,
    },
    /// No closed-form reference, and why.
    NoReference(String),
}

/// One check: what is compared (with the reference's equation), its unit,
/// and the outcome.
pub type Line = (String, &'static str, Outcome);

/// The profile `validate` measures over: periodic and symmetric about its
/// preload.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drive {
    /// A sine of this frequency, Hz.
    Sine(f64),
    /// A triangle of this speed, mm/s.
    Triangle(f64),
}

/// Steps per branch of the asymmetric inner loop.
pub const INNER_STEPS: usize = 10;
/// Span of the asymmetric inner loop, over the amplitude.
pub const INNER_SPAN: f64 = 0.4;

/// One effect's steady cycle, as measured, and the scene around it.
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    /// Amplitude A of the profile, mm.
    pub amplitude: f64,
    /// Sine or triangle.
    pub drive: Drive,
    /// Slope of the backbone when it is linear everywhere, N/mm.
    pub k_lin: Option<f64>,
    /// Long-term fraction g^0 of the bushing.
    pub g0: f64,
    /// Time step, s.
    pub dt: f64,
    /// Start of the least-squares window, s.
    pub t0: f64,
    /// Whether a temperature history re-tunes the Maxwell banks.
    pub retuned: bool,
    /// Half the peak-to-peak force of the effect over the last cycle, N.
    pub swing: f64,
    /// Energy the effect dissipated over the last cycle, mJ.
    pub per_cycle: f64,
    /// First harmonic of `g^0 K x + effect force` over that of x, over the
    /// window: (storage K', loss K'') in N/mm; `None` when the
    /// least-squares fit is singular.
    pub modulus: Option<(f64, f64)>,
    /// Amplitude of the first harmonic of x, mm.
    pub x_amplitude: f64,
    /// Energy of the effect over the asymmetric inner loop, mJ.
    pub inner: f64,
}

/// A line comparing `measured` with `reference`.
pub fn compared(
    what: impl Into<String>,
    unit: &'static str,
    reference: f64,
    measured: f64,
) -> Line {
    (
        what.into(),
        unit,
        Outcome::Compared {
            reference,
            measured,
        },
    )
}

/// The one line of an effect with no reference here, and why.
pub fn no(why: &str) -> Vec<Line> {
    vec![(String::new(), "", Outcome::NoReference(why.into()))]
}

impl Measured {
    /// The asymmetric inner loop's energy against `reference`.
    pub fn inner_loop(&self, reference: f64) -> Line {
        compared(
            format!(
                "energy of an asymmetric inner loop (x0 + 0.2A to x0 + 0.6A after x0 +- A, {INNER_STEPS} steps per branch), Masing loop of span 0.4A"
            ),
            "mJ",
            reference,
            self.inner,
        )
    }
}

/// Composite Simpson rule on `n` (even) intervals.
pub fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let n = n.max(2) & !1;
    let h = (b - a) / n as f64;
    let inner: f64 = (1..n)
        .map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    h / 3.0 * (f(a) + inner + f(b))
}

/// Root of a decreasing `g` on `[lo, hi]` by bisection.
pub fn bisect(g: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-15 * hi.abs() {
            break;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simpson_and_bisect() {
        assert!((simpson(|x| x * x, 0.0, 3.0, 10) - 9.0).abs() < 1e-12);
        let r = bisect(|x| 2.0 - x * x, 0.0, 2.0);
        assert!((r - 2f64.sqrt()).abs() < 1e-14, "{r}");
    }
}
