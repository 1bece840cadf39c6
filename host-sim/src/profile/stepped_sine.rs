//! `stepped-sine`: the stepped sines of seed 000 Fig. 3.3 and Table B.2.

use bushing::excitation::sin_cycles;
use serde::Deserialize;

use super::check::{below_nyquist, finite, finite_non_negative, finite_positive, list_len};
use super::{MAX_SINE_STEPS, Profile, SineAt};

/// Stepped sines (seed 000 Fig. 3.3, Table B.2): at each preload, for
/// each frequency, a step of whole `cycles` at each amplitude in turn,
/// each step starting and ending at the preload with zero phase.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteppedSine {
    /// A single preload in mm (default 0); not with `preloads`.
    #[serde(default)]
    pub preload: Option<f64>,
    /// Several preloads in mm, visited in order; not with `preload`.
    #[serde(default)]
    pub preloads: Option<Vec<f64>>,
    /// Frequencies in Hz, outer loop at each preload.
    pub frequencies_hz: Vec<f64>,
    /// Amplitudes in mm, inner loop.
    pub amplitudes: Vec<f64>,
    /// Whole number of cycles per step.
    pub cycles: f64,
    /// Rest at the preload after each step, in s; not with
    /// `settle_cycles`.
    #[serde(default)]
    pub settle_s: Option<f64>,
    /// Rest at the preload after each step, in periods of that step's
    /// frequency; not with `settle_s`.
    #[serde(default)]
    pub settle_cycles: Option<f64>,
    /// Ramp between preloads in s (needed with two or more preloads).
    #[serde(default)]
    pub ramp_s: Option<f64>,
    /// Hold after each preload change in s (default 0).
    #[serde(default)]
    pub hold_s: Option<f64>,
}

impl Profile for SteppedSine {
    fn duration(&self, dt: f64) -> Result<f64, String> {
        let Self {
            preload,
            preloads,
            frequencies_hz,
            amplitudes,
            cycles,
            settle_s,
            settle_cycles,
            ramp_s,
            hold_s,
        } = self;
        let (preload, cycles, settle_s, settle_cycles, ramp_s, hold_s) = (
            *preload,
            *cycles,
            *settle_s,
            *settle_cycles,
            *ramp_s,
            *hold_s,
        );

        match (preload, preloads) {
            (Some(_), Some(_)) => {
                return Err("give preload or preloads, not both".into());
            }
            (Some(v), None) => finite("preload", v)?,
            (None, Some(list)) => {
                list_len("preloads", list.len())?;
                for (i, &v) in list.iter().enumerate() {
                    finite(&format!("preloads[{i}]"), v)?;
                }
            }
            (None, None) => {}
        }
        list_len("frequencies_hz", frequencies_hz.len())?;
        for (i, &f) in frequencies_hz.iter().enumerate() {
            let name = format!("frequencies_hz[{i}]");
            finite_positive(&name, f)?;
            below_nyquist(&name, f, dt)?;
        }
        list_len("amplitudes", amplitudes.len())?;
        for (i, &a) in amplitudes.iter().enumerate() {
            finite_positive(&format!("amplitudes[{i}]"), a)?;
        }
        if !(cycles.is_finite() && cycles >= 1.0 && cycles.fract() == 0.0) {
            return Err(format!(
                "cycles must be a whole number >= 1 (each step ends at the preload), got {cycles}"
            ));
        }
        match (settle_s, settle_cycles) {
            (Some(_), Some(_)) => {
                return Err("give settle_s or settle_cycles, not both".into());
            }
            (Some(s), None) => finite_non_negative("settle_s", s)?,
            (None, Some(c)) => finite_non_negative("settle_cycles", c)?,
            (None, None) => {}
        }
        let n_preloads = preloads.as_ref().map_or(1, Vec::len);
        if n_preloads > 1 {
            match ramp_s {
                Some(r) => finite_positive("ramp_s", r)?,
                None => {
                    return Err(format!(
                        "ramp_s (s) is needed to go from one preload to the next ({n_preloads} preloads)"
                    ));
                }
            }
            if let Some(h) = hold_s {
                finite_non_negative("hold_s", h)?;
            }
        } else if ramp_s.is_some() || hold_s.is_some() {
            return Err(
                "ramp_s and hold_s apply between preloads: give two or more preloads, or remove them"
                    .into(),
            );
        }
        let count = n_preloads
            .saturating_mul(frequencies_hz.len())
            .saturating_mul(amplitudes.len());
        if count > MAX_SINE_STEPS {
            return Err(format!(
                "{count} sine steps (preloads x frequencies_hz x amplitudes), more than the limit of {MAX_SINE_STEPS}"
            ));
        }
        Ok(self.schedule().duration())
    }

    fn displacement(&self, t: f64) -> f64 {
        match self.schedule().locate(t) {
            Where::Sine {
                preload,
                amplitude,
                frequency_hz,
                tau,
            } => preload + amplitude * sin_cycles(frequency_hz * tau),
            Where::At(x) => x,
        }
    }

    fn sine_at(&self, t: f64) -> Option<SineAt> {
        match self.schedule().locate(t) {
            Where::Sine {
                frequency_hz,
                amplitude,
                ..
            } => Some(SineAt {
                frequency_hz,
                amplitude,
            }),
            Where::At(_) => None,
        }
    }
}

impl SteppedSine {
    fn schedule(&self) -> Stepped<'_> {
        let preloads: &[f64] = match (&self.preloads, &self.preload) {
            (Some(list), _) => list,
            (None, Some(v)) => std::slice::from_ref(v),
            (None, None) => &[0.0],
        };
        Stepped {
            preloads,
            frequencies: &self.frequencies_hz,
            amplitudes: &self.amplitudes,
            cycles: self.cycles,
            settle_s: self.settle_s.unwrap_or(0.0),
            settle_cycles: self.settle_cycles.unwrap_or(0.0),
            ramp: self.ramp_s.unwrap_or(0.0),
            hold: self.hold_s.unwrap_or(0.0),
        }
    }
}

/// Where a stepped-sine profile is at some time.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Where {
    /// In a sine step, `tau` s after its start.
    Sine {
        preload: f64,
        amplitude: f64,
        frequency_hz: f64,
        tau: f64,
    },
    /// Resting, ramping or holding at this displacement.
    At(f64),
}

/// The schedule of a stepped-sine profile.
struct Stepped<'a> {
    preloads: &'a [f64],
    frequencies: &'a [f64],
    amplitudes: &'a [f64],
    cycles: f64,
    settle_s: f64,
    settle_cycles: f64,
    ramp: f64,
    hold: f64,
}

impl Stepped<'_> {
    /// Length of the sine of a step at `f`.
    fn sine_len(&self, f: f64) -> f64 {
        self.cycles / f
    }

    /// Rest after a step at `f`.
    fn rest(&self, f: f64) -> f64 {
        self.settle_s + self.settle_cycles / f
    }

    /// Length of the sine steps (with their rests) at one preload.
    fn block(&self) -> f64 {
        let n = self.amplitudes.len() as f64;
        self.frequencies
            .iter()
            .map(|&f| n * (self.sine_len(f) + self.rest(f)))
            .sum()
    }

    /// Total duration: every block, the ramps and holds between them, and
    /// no rest after the last step.
    fn duration(&self) -> f64 {
        let gaps = self.preloads.len().saturating_sub(1) as f64;
        let last_rest = self.frequencies.last().map_or(0.0, |&f| self.rest(f));
        self.block() + gaps * (self.ramp + self.hold + self.block()) - last_rest
    }

    fn locate(&self, t: f64) -> Where {
        let first = self.preloads.first().copied().unwrap_or(0.0);
        let last = self.preloads.last().copied().unwrap_or(first);
        if t.is_nan() || t < 0.0 {
            return Where::At(first);
        }
        let block = self.block();
        if t < block {
            return self.in_block(first, t);
        }
        let unit = self.ramp + self.hold + block;
        let u = t - block;
        let k = (u / unit).floor();
        if k + 1.0 >= self.preloads.len() as f64 {
            return Where::At(last);
        }
        // Block k + 1, after the ramp from preload k and the hold.
        let k = k as usize;
        let from = self.preloads.get(k).copied().unwrap_or(last);
        let to = self.preloads.get(k + 1).copied().unwrap_or(last);
        let w = u - k as f64 * unit;
        if w < self.ramp {
            Where::At(from + (to - from) * (w / self.ramp))
        } else if w < self.ramp + self.hold {
            Where::At(to)
        } else {
            self.in_block(to, w - self.ramp - self.hold)
        }
    }

    /// Inside the block of sine steps at `preload`, `tau` s after its start.
    fn in_block(&self, preload: f64, tau: f64) -> Where {
        let n = self.amplitudes.len();
        let mut start = 0.0;
        for &f in self.frequencies {
            let len = self.sine_len(f) + self.rest(f);
            let end = start + n as f64 * len;
            if tau < end {
                let local = tau - start;
                let j = ((local / len).floor().max(0.0) as usize).min(n.saturating_sub(1));
                let s = local - j as f64 * len;
                return match self.amplitudes.get(j) {
                    Some(&amplitude) if s < self.sine_len(f) => Where::Sine {
                        preload,
                        amplitude,
                        frequency_hz: f,
                        tau: s.max(0.0),
                    },
                    _ => Where::At(preload),
                };
            }
            start = end;
        }
        Where::At(preload)
    }
}
