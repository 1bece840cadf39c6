//! Relaxation curves from multi-step tests (seed 000 §3.2.3, §3.2.6): the
//! record is cut into its holds (the displacement still), each giving the
//! force relaxing at one level; the end of each hold is a point of the
//! long-term backbone (the data of the hyperelastic objective, eq 3.1).

use super::campaign::{Kind, Test, TestError};

/// Shortest hold, s: a still displacement for less is a pause in a ramp.
pub const MIN_HOLD_S: f64 = 5.0;
/// Fewest samples of a hold.
pub const MIN_HOLD_SAMPLES: usize = 4;
/// Share of a hold's samples, at its end, averaged into its end force.
pub const END_SHARE: f64 = 0.1;

/// One hold of a multi-step test.
#[derive(Debug, Clone, PartialEq)]
pub struct Hold {
    /// Displacement held, mm (the mean over the hold).
    pub level_mm: f64,
    /// Start of the hold in the record, s.
    pub start_s: f64,
    /// Length of the hold, s.
    pub duration_s: f64,
    /// Force at the hold's first sample, N.
    pub force_start: f64,
    /// Force at its end (the mean over its last tenth), N: a point of the
    /// long-term backbone.
    pub force_end: f64,
    /// (time from the hold's start in s, force in N) over the hold.
    pub curve: Vec<(f64, f64)>,
}

/// The holds of a multi-step test, in time order. The displacement is
/// still where the samples stay within 2e-4 of the
/// test's displacement range (and 1e-6 mm) of a hold's first sample.
pub fn holds(test: &Test) -> Result<Vec<Hold>, TestError> {
    if test.kind != Kind::MultiStep {
        return Err(TestError::Check(format!(
            "a {} test is not a multi-step test",
            test.kind.name()
        )));
    }
    let r = &test.record;
    let (lo, hi) = super::extremes(&r.x);
    let tol = (2e-4 * (hi - lo)).max(1e-6);
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..=r.len() {
        let still = i < r.len() && (r.x[i] - r.x[start]).abs() <= tol;
        if still {
            continue;
        }
        // Samples start..i are within tol of the first one.
        let n = i - start;
        let duration = r.time[i - 1] - r.time[start];
        if n >= MIN_HOLD_SAMPLES && duration >= MIN_HOLD_S {
            let x = &r.x[start..i];
            let f = &r.force[start..i];
            let tail = ((n as f64 * END_SHARE).ceil() as usize).clamp(1, n);
            out.push(Hold {
                level_mm: x.iter().sum::<f64>() / n as f64,
                start_s: r.time[start],
                duration_s: duration,
                force_start: f[0],
                force_end: f[n - tail..].iter().sum::<f64>() / tail as f64,
                curve: r.time[start..i]
                    .iter()
                    .zip(f)
                    .map(|(t, &fv)| (t - r.time[start], fv))
                    .collect(),
            });
        }
        start = i;
    }
    if out.is_empty() {
        return Err(TestError::Check(format!(
            "no hold: no still displacement for {MIN_HOLD_S} s or more"
        )));
    }
    Ok(out)
}
