//! Triangles (seed 000 §3.2.4, §3.4): the record cut into branches at its
//! turning points, each branch's force filtered apart by a zero-phase
//! low-pass (a second-order Butterworth run forward and backward, cutoff a
//! tenth of the sampling rate: filtering the whole record at once smears
//! the turning points), and along each branch the instantaneous modulus
//! dF/dx against the distance from the branch's turning point, the data
//! from which hysteresis cells are placed (§3.4, Figs 3.20-3.21).

use std::f64::consts::PI;

use super::campaign::{Kind, Test, TestError};

/// Fewest samples of a branch.
pub const MIN_BRANCH_SAMPLES: usize = 5;
/// Cutoff of the low-pass, over the sampling rate (§3.2.4).
pub const CUTOFF_SHARE: f64 = 0.1;

/// One monotone branch of a triangle test.
#[derive(Debug, Clone, PartialEq)]
pub struct Branch {
    /// +1 loading (x increasing), -1 unloading.
    pub direction: f64,
    /// Displacement at the branch's turning point (its start), mm.
    pub turning_mm: f64,
    /// Samples: (x in mm, filtered force in N).
    pub samples: Vec<(f64, f64)>,
    /// Along the branch: (distance from the turning point in mm, dF/dx in
    /// N/mm), by centred differences of the filtered force.
    pub modulus: Vec<(f64, f64)>,
}

/// What a triangle test gives.
#[derive(Debug, Clone, PartialEq)]
pub struct Triangles {
    /// Half the displacement range, mm.
    pub amplitude_mm: f64,
    /// Middle of the displacement range, mm.
    pub preload_mm: f64,
    /// Median speed, mm/min.
    pub speed_mm_per_min: f64,
    /// The branches long enough to use, in time order (the first loading
    /// from rest included).
    pub branches: Vec<Branch>,
}

/// The branches of a triangle test, filtered, with their instantaneous
/// modulus; nominal amplitude, preload and speed checked (within 10 %, or
/// one sample step of displacement for the amplitude and the preload).
pub fn branches(test: &Test) -> Result<Triangles, TestError> {
    let check = |m: String| TestError::Check(m);
    if test.kind != Kind::Triangle {
        return Err(check(format!(
            "a {} test is not a triangle",
            test.kind.name()
        )));
    }
    let r = &test.record;
    if r.len() < MIN_BRANCH_SAMPLES {
        return Err(check(format!(
            "{} samples, fewer than one branch of {MIN_BRANCH_SAMPLES}",
            r.len()
        )));
    }
    let (lo, hi) = super::extremes(&r.x);
    let (amplitude, preload) = (0.5 * (hi - lo), 0.5 * (hi + lo));
    let mut speeds: Vec<f64> = r
        .time
        .windows(2)
        .zip(r.x.windows(2))
        .map(|(t, x)| ((x[1] - x[0]) / (t[1] - t[0])).abs() * 60.0)
        .collect();
    speeds.sort_by(f64::total_cmp);
    let speed = speeds.get(speeds.len() / 2).copied().unwrap_or(f64::NAN);
    // Branches: runs of one sign of dx; a still sample joins the run.
    let mut cuts = vec![0];
    let mut sign = 0.0;
    for i in 1..r.len() {
        let s = (r.x[i] - r.x[i - 1]).signum();
        if r.x[i] == r.x[i - 1] {
            continue;
        }
        if sign != 0.0 && s != sign {
            cuts.push(i - 1);
        }
        sign = s;
    }
    cuts.push(r.len() - 1);
    let mut out = Vec::new();
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b + 1 - a < MIN_BRANCH_SAMPLES {
            continue;
        }
        let force = zero_phase(&r.force[a..=b], CUTOFF_SHARE);
        let x = &r.x[a..=b];
        let direction = (x[x.len() - 1] - x[0]).signum();
        let samples: Vec<(f64, f64)> = x.iter().copied().zip(force.iter().copied()).collect();
        let modulus = (1..samples.len() - 1)
            .map(|i| {
                let (x0, f0) = samples[i - 1];
                let (x1, f1) = samples[i + 1];
                ((samples[i].0 - x[0]).abs(), (f1 - f0) / (x1 - x0))
            })
            .collect();
        out.push(Branch {
            direction,
            turning_mm: x[0],
            samples,
            modulus,
        });
    }
    if out.is_empty() {
        return Err(check(format!(
            "no branch of {MIN_BRANCH_SAMPLES} samples or more: {} samples for a range of {:.4} mm at {speed:.3} mm/min",
            r.len(),
            hi - lo
        )));
    }
    // The record cannot show a turning point closer than one sample step.
    let mut steps: Vec<f64> = r.x.windows(2).map(|x| (x[1] - x[0]).abs()).collect();
    steps.sort_by(f64::total_cmp);
    let step = steps.get(steps.len() / 2).copied().unwrap_or(0.0);
    let n = &test.nominal;
    let off =
        |seen: f64, nominal: f64, scale: f64| (seen - nominal).abs() > (0.1 * scale).max(step);
    if let Some(a) = n.amplitude_mm
        && off(amplitude, a, a)
    {
        return Err(check(format!(
            "recorded amplitude {amplitude:.4} mm, nominal {a} mm"
        )));
    }
    if let Some(p) = n.preload_mm
        && off(preload, p, amplitude)
    {
        return Err(check(format!(
            "recorded middle of the range {preload:.4} mm, nominal preload {p} mm"
        )));
    }
    if let Some(v) = n.speed_mm_per_min
        && off(speed, v, v)
    {
        return Err(check(format!(
            "recorded speed {speed:.4} mm/min, nominal {v} mm/min"
        )));
    }
    Ok(Triangles {
        amplitude_mm: amplitude,
        preload_mm: preload,
        speed_mm_per_min: speed,
        branches: out,
    })
}

/// Samples of odd extension at each end before filtering: the start-up
/// of a pass decays as the poles' modulus, about 0.64 a sample at a
/// cutoff of a tenth, to below 2e-6 over 30 samples.
const PAD: usize = 30;

/// `v` filtered forward and backward by a second-order Butterworth
/// low-pass of cutoff `share` of the sampling rate (bilinear transform,
/// prewarped): zero phase, gain squared. Each end is first extended by its
/// odd reflection (`2 v_0 - v_k`), so that a ramp runs on through the end
/// and the filter's start-up falls outside the data, and each pass starts
/// at rest on its first value.
pub fn zero_phase(v: &[f64], share: f64) -> Vec<f64> {
    let k = (PI * share).tan();
    let q = std::f64::consts::FRAC_1_SQRT_2;
    let norm = 1.0 / (1.0 + k / q + k * k);
    let b0 = k * k * norm;
    let (b1, b2) = (2.0 * b0, b0);
    let a1 = 2.0 * (k * k - 1.0) * norm;
    let a2 = (1.0 - k / q + k * k) * norm;
    let pass = |input: &mut Vec<f64>| {
        let Some(&first) = input.first() else {
            return;
        };
        // Direct form II transposed, its state at rest on `first`.
        let (mut z1, mut z2) = (first * (1.0 - b0), first * (b2 - a2));
        for y in input.iter_mut() {
            let x = *y;
            let out = b0 * x + z1;
            z1 = b1 * x - a1 * out + z2;
            z2 = b2 * x - a2 * out;
            *y = out;
        }
    };
    let (Some(&first), Some(&last)) = (v.first(), v.last()) else {
        return Vec::new();
    };
    let pad = PAD.min(v.len() - 1);
    let mut out: Vec<f64> = (1..=pad).rev().map(|i| 2.0 * first - v[i]).collect();
    out.extend_from_slice(v);
    out.extend((1..=pad).map(|i| 2.0 * last - v[v.len() - 1 - i]));
    pass(&mut out);
    out.reverse();
    pass(&mut out);
    out.reverse();
    out[pad..pad + v.len()].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_filter_keeps_a_constant_and_a_ramp_and_removes_fast_noise() {
        let c = zero_phase(&[3.0; 50], 0.1);
        assert!(c.iter().all(|v| (v - 3.0).abs() < 1e-12), "{c:?}");
        // A ramp keeps its values, up to its ends (zero phase, and the odd
        // extension carries it through them).
        let ramp: Vec<f64> = (0..200).map(|i| 0.5 * i as f64).collect();
        let f = zero_phase(&ramp, 0.1);
        for i in 0..200 {
            assert!((f[i] - ramp[i]).abs() < 1e-4, "{i}: {} {}", f[i], ramp[i]);
        }
        // The Nyquist alternation is gone; gain at the cutoff is 1/2 (two passes).
        let alt: Vec<f64> = (0..400)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let f = zero_phase(&alt, 0.1);
        assert!(f[100..300].iter().all(|v| v.abs() < 1e-6));
        let w = 2.0 * PI * 0.1;
        let cut: Vec<f64> = (0..2000).map(|i| (w * i as f64).sin()).collect();
        let f = zero_phase(&cut, 0.1);
        let top = |v: &[f64]| v[500..1500].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // The samples miss the crest (10 a period): compare the same samples.
        assert!((top(&f) / top(&cut) - 0.5).abs() < 1e-3, "{}", top(&f));
    }
}
