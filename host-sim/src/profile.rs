//! Displacement profiles x(t) in mm.
//!
//! Each profile of [`ProfileSpec`] gives the displacement at any time
//! ([`displacement`]), its length in steps after checking every parameter
//! ([`steps`]), and, where a sine is being imposed, its frequency and
//! amplitude ([`frequency_at`], [`amplitude_at`]). The bushing starts
//! relaxed at x(0). The profiles follow the test protocols of seed 000
//! §3.2.3 and Appendix B (Tables B.1-B.2):
//!
//! - `multi-step`: from the preload, a linear ramp of `ramp_s` to each level
//!   in turn, then a hold of `hold_s` (the thesis: 20 s ramps, holds of
//!   360 s or 3600 s);
//! - `stepped-sine`: at each preload, for each frequency, `cycles` whole
//!   periods at each amplitude in turn (Fig. 3.3: the amplitude is swept at
//!   a fixed frequency, then the frequency changes), each step starting and
//!   ending at the preload with zero phase, an optional rest after each
//!   step, and a ramp and hold between preloads;
//! - `sweep`: x = x0 + A sin φ(t), φ(t) = 2π ∫ f, f linear or geometric in
//!   time, so the phase is continuous;
//! - `stop-start`: a displacement proxy of the stop/start transient of
//!   seed 000 §5.2.4 (see [`stop_start_response`]);
//! - `replay`: a measured displacement read from a CSV file, linearly
//!   interpolated onto the scene's step.

use std::f64::consts::TAU;
use std::fmt;
use std::io::Read;
use std::path::Path;

use bushing::excitation::{Sweep, sin_cycles};
use serde::Deserialize;
use serde::de::{self, Visitor};

tagged_table! {
    /// `[profile]`: the imposed displacement x(t) in mm. The formulas, the
    /// defaults and the bounds of each profile are in this module and
    /// `docs/scenes.md`.
    #[derive(Debug, Clone, PartialEq, Deserialize)]
    pub enum ProfileSpec, read by tag as ProfileByTag("ProfileSpec") {
        /// x = preload + amplitude sin(2π f t).
        Sine {
            /// Amplitude in mm.
            amplitude: f64,
            /// Frequency in Hz.
            frequency_hz: f64,
            /// Number of cycles.
            cycles: f64,
            /// Static offset in mm.
            #[serde(default)]
            preload: f64,
        },
        /// Triangle between preload ± amplitude at constant speed, starting
        /// upward from the preload.
        Triangle {
            /// Amplitude in mm.
            amplitude: f64,
            /// Speed in mm/s.
            speed: f64,
            /// Number of cycles.
            cycles: f64,
            /// Static offset in mm.
            #[serde(default)]
            preload: f64,
        },
        /// Multi-step relaxation (seed 000 §3.2.3, Table B.2): from `preload`,
        /// a linear ramp of `ramp_s` to each level in turn, each held `hold_s`.
        MultiStep {
            /// Levels in mm, in the order they are reached.
            levels: Vec<f64>,
            /// Duration of each ramp in s (> 0; the thesis uses 20 s).
            ramp_s: f64,
            /// Hold at each level in s (>= 0; the thesis uses 360 s or 3600 s).
            hold_s: f64,
            /// Starting level in mm (the bushing starts relaxed there).
            #[serde(default)]
            preload: f64,
        },
        /// Stepped sines (seed 000 Fig. 3.3, Table B.2): at each preload, for
        /// each frequency, a step of whole `cycles` at each amplitude in turn,
        /// each step starting and ending at the preload with zero phase.
        SteppedSine {
            /// A single preload in mm (default 0); not with `preloads`.
            #[serde(default)]
            preload: Option<f64>,
            /// Several preloads in mm, visited in order; not with `preload`.
            #[serde(default)]
            preloads: Option<Vec<f64>>,
            /// Frequencies in Hz, outer loop at each preload.
            frequencies_hz: Vec<f64>,
            /// Amplitudes in mm, inner loop.
            amplitudes: Vec<f64>,
            /// Whole number of cycles per step.
            cycles: f64,
            /// Rest at the preload after each step, in s; not with
            /// `settle_cycles`.
            #[serde(default)]
            settle_s: Option<f64>,
            /// Rest at the preload after each step, in periods of that step's
            /// frequency; not with `settle_s`.
            #[serde(default)]
            settle_cycles: Option<f64>,
            /// Ramp between preloads in s (needed with two or more preloads).
            #[serde(default)]
            ramp_s: Option<f64>,
            /// Hold after each preload change in s (default 0).
            #[serde(default)]
            hold_s: Option<f64>,
        },
        /// Sine sweep, phase-continuous: x = preload + amplitude sin(φ(t)) with
        /// φ the integral of 2π f(t), f linear or logarithmic in time from
        /// `f_start_hz` to `f_end_hz` over `duration_s`.
        Sweep {
            /// Amplitude in mm.
            amplitude: f64,
            /// Frequency at t = 0 in Hz.
            f_start_hz: f64,
            /// Frequency at t = duration_s in Hz.
            f_end_hz: f64,
            /// Duration in s.
            duration_s: f64,
            /// Frequency law: "log" (default) or "linear".
            #[serde(default)]
            spacing: Spacing,
            /// Static offset in mm.
            #[serde(default)]
            preload: f64,
        },
        /// Stop/start transient, a displacement proxy of seed 000 §5.2.4: each
        /// event is the response of one mode (`frequency_hz`, `damping`) to a
        /// load ramped over `rise_s` whose static displacement is the event's
        /// `size`.
        StopStart {
            /// Frequency of the mode that rings, in Hz (undamped).
            frequency_hz: f64,
            /// Damping ratio ζ in [0, 1).
            damping: f64,
            /// Rise time of each load change in s (0 for a step).
            rise_s: f64,
            /// Duration in s.
            duration_s: f64,
            /// The events, in time order.
            events: Vec<StopStartEvent>,
            /// Static offset in mm before the first event.
            #[serde(default)]
            preload: f64,
        },
        /// A constant input: x held at `preload` (in an oscillator scene,
        /// a constant force: 0 gives a free decay).
        Hold {
            /// Duration in s.
            duration_s: f64,
            /// The held value, mm (N in an oscillator scene).
            #[serde(default)]
            preload: f64,
        },
        /// Replay of a measured displacement from a CSV file, linearly
        /// interpolated onto the scene's step.
        Replay {
            /// CSV file, relative to the scene file's directory.
            file: String,
            /// Displacement column: a header name or a 1-based index.
            column: crate::profile::Column,
            /// Time column in s (name or 1-based index); not with `rate_hz`.
            #[serde(default)]
            time_column: Option<crate::profile::Column>,
            /// Sampling rate of the file in Hz; not with `time_column`.
            #[serde(default)]
            rate_hz: Option<f64>,
            /// The samples (time from the first sample in s, displacement in
            /// mm), read from `file` when the scene is loaded.
            #[serde(skip)]
            samples: Vec<(f64, f64)>,
        },
    }
}

/// Most entries of a list (levels, preloads, frequencies, amplitudes).
pub const MAX_LIST: usize = 10_000;
/// Most sine steps of a stepped-sine profile (preloads x frequencies x
/// amplitudes).
pub const MAX_SINE_STEPS: usize = 100_000;
/// Most events of a stop/start profile.
pub const MAX_EVENTS: usize = 64;
/// Most samples a replayed CSV file may hold.
pub const MAX_SAMPLES: usize = 10_000_000;
/// Largest replayed CSV file, in bytes.
pub const MAX_CSV_BYTES: u64 = 1 << 30;
/// Highest 1-based column index accepted.
pub const MAX_COLUMN: i64 = 10_000;

/// Frequency law of a sweep.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Spacing {
    /// f(t) = f0 (f1/f0)^(t/T): equal time per octave.
    #[default]
    Log,
    /// f(t) = f0 + (f1 - f0) t/T.
    Linear,
}

impl From<Spacing> for bushing::excitation::Spacing {
    fn from(s: Spacing) -> Self {
        match s {
            Spacing::Log => Self::Log,
            Spacing::Linear => Self::Linear,
        }
    }
}

/// One load change of a stop/start transient.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StopStartEvent {
    /// Start of the load change in s.
    pub at_s: f64,
    /// Static displacement change in mm (positive or negative).
    pub size: f64,
}

/// A CSV column, by header name or 1-based index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Column {
    /// Header name (surrounding blanks and double quotes ignored).
    Name(String),
    /// Index from 1, as written (checked when the file is read).
    Index(i64),
}

impl fmt::Display for Column {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Name(n) => write!(f, "'{n}'"),
            Self::Index(i) => write!(f, "{i}"),
        }
    }
}

impl<'de> Deserialize<'de> for Column {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct ColumnVisitor;
        impl Visitor<'_> for ColumnVisitor {
            type Value = Column;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a column name (string) or a 1-based column index (integer)")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Column, E> {
                Ok(Column::Name(v.to_string()))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Column, E> {
                Ok(Column::Index(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Column, E> {
                Ok(Column::Index(i64::try_from(v).unwrap_or(i64::MAX)))
            }
        }
        d.deserialize_any(ColumnVisitor)
    }
}

/// Number of steps of a profile at time step `dt`, or why it is unusable
/// (the message names the parameter and the bound it breaks).
pub fn steps(p: &ProfileSpec, dt: f64) -> Result<u64, String> {
    let duration = checked_duration(p, dt)?;
    let n = (duration / dt).round();
    if !(1.0..1e18).contains(&n) {
        return Err(format!("duration {duration} s gives {n} steps"));
    }
    Ok(n as u64)
}

/// Duration in s of a profile, after checking its parameters.
fn checked_duration(p: &ProfileSpec, dt: f64) -> Result<f64, String> {
    match *p {
        ProfileSpec::Sine {
            amplitude,
            frequency_hz,
            cycles,
            preload,
        } => {
            finite_positive("amplitude", amplitude)?;
            finite_positive("frequency_hz", frequency_hz)?;
            finite_positive("cycles", cycles)?;
            finite("preload", preload)?;
            Ok(cycles / frequency_hz)
        }
        ProfileSpec::Triangle {
            amplitude,
            speed,
            cycles,
            preload,
        } => {
            finite_positive("amplitude", amplitude)?;
            finite_positive("speed", speed)?;
            finite_positive("cycles", cycles)?;
            finite("preload", preload)?;
            Ok(cycles * 4.0 * amplitude / speed)
        }
        ProfileSpec::MultiStep {
            ref levels,
            ramp_s,
            hold_s,
            preload,
        } => {
            list_len("levels", levels.len())?;
            for (i, &v) in levels.iter().enumerate() {
                finite(&format!("levels[{i}]"), v)?;
            }
            finite_positive("ramp_s", ramp_s)?;
            finite_non_negative("hold_s", hold_s)?;
            finite("preload", preload)?;
            Ok(levels.len() as f64 * (ramp_s + hold_s))
        }
        ProfileSpec::SteppedSine {
            preload,
            ref preloads,
            ref frequencies_hz,
            ref amplitudes,
            cycles,
            settle_s,
            settle_cycles,
            ramp_s,
            hold_s,
        } => {
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
            Ok(stepped(p).map_or(0.0, |s| s.duration()))
        }
        ProfileSpec::Sweep {
            amplitude,
            f_start_hz,
            f_end_hz,
            duration_s,
            preload,
            ..
        } => {
            finite_positive("amplitude", amplitude)?;
            finite_positive("f_start_hz", f_start_hz)?;
            below_nyquist("f_start_hz", f_start_hz, dt)?;
            finite_positive("f_end_hz", f_end_hz)?;
            below_nyquist("f_end_hz", f_end_hz, dt)?;
            finite_positive("duration_s", duration_s)?;
            finite("preload", preload)?;
            Ok(duration_s)
        }
        ProfileSpec::StopStart {
            frequency_hz,
            damping,
            rise_s,
            duration_s,
            ref events,
            preload,
        } => {
            finite_positive("frequency_hz", frequency_hz)?;
            below_nyquist("frequency_hz", frequency_hz, dt)?;
            if !(damping.is_finite() && (0.0..1.0).contains(&damping)) {
                return Err(format!(
                    "damping (ratio) must be in [0, 1) (an oscillating mode), got {damping}"
                ));
            }
            finite_non_negative("rise_s", rise_s)?;
            finite_positive("duration_s", duration_s)?;
            finite("preload", preload)?;
            if events.is_empty() || events.len() > MAX_EVENTS {
                return Err(format!(
                    "events: 1 to {MAX_EVENTS} events expected, got {}",
                    events.len()
                ));
            }
            let mut previous = 0.0;
            for (i, e) in events.iter().enumerate() {
                if !(e.at_s.is_finite() && e.at_s >= previous && e.at_s < duration_s) {
                    return Err(format!(
                        "events[{i}].at_s must be in [{previous}, duration_s = {duration_s}) s (events in time order), got {}",
                        e.at_s
                    ));
                }
                finite(&format!("events[{i}].size"), e.size)?;
                previous = e.at_s;
            }
            Ok(duration_s)
        }
        ProfileSpec::Hold {
            duration_s,
            preload,
        } => {
            finite_positive("duration_s", duration_s)?;
            finite("preload", preload)?;
            Ok(duration_s)
        }
        ProfileSpec::Replay { ref samples, .. } => match (samples.first(), samples.last()) {
            (Some(_), Some(&(end, _))) if samples.len() >= 2 && end.is_finite() && end > 0.0 => {
                Ok(end)
            }
            _ => Err(format!(
                "replay: {} samples; at least 2, read from the file when the scene is parsed",
                samples.len()
            )),
        },
    }
}

fn finite(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} must be finite, got {v}"))
    }
}

fn finite_positive(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{name} must be finite and > 0, got {v}"))
    }
}

fn finite_non_negative(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("{name} must be finite and >= 0, got {v}"))
    }
}

fn list_len(name: &str, n: usize) -> Result<(), String> {
    if n == 0 || n > MAX_LIST {
        Err(format!("{name}: 1 to {MAX_LIST} values expected, got {n}"))
    } else {
        Ok(())
    }
}

/// A sampled sine must stay below half the rate.
fn below_nyquist(name: &str, f: f64, dt: f64) -> Result<(), String> {
    if f * dt < 0.5 {
        Ok(())
    } else {
        Err(format!(
            "{name} = {f} Hz must be below half the rate ({} Hz)",
            0.5 / dt
        ))
    }
}

/// Displacement at time `t` (s).
pub fn displacement(p: &ProfileSpec, t: f64) -> f64 {
    match *p {
        ProfileSpec::Sine {
            amplitude,
            frequency_hz,
            preload,
            ..
        } => preload + amplitude * libm::sin(TAU * frequency_hz * t),
        ProfileSpec::Triangle {
            amplitude,
            speed,
            preload,
            ..
        } => {
            // Period 4A/v; phase 0 at the preload going up.
            let period = 4.0 * amplitude / speed;
            let u = (t / period + 0.25).rem_euclid(1.0); // 0 at the bottom
            let tri = if u < 0.5 {
                4.0 * u - 1.0
            } else {
                3.0 - 4.0 * u
            };
            preload + amplitude * tri
        }
        ProfileSpec::MultiStep {
            ref levels,
            ramp_s,
            hold_s,
            preload,
        } => multi_step(levels, ramp_s, hold_s, preload, t),
        ProfileSpec::SteppedSine { .. } => match stepped(p).map(|s| s.locate(t)) {
            Some(Where::Sine {
                preload,
                amplitude,
                frequency_hz,
                tau,
            }) => preload + amplitude * sin_cycles(frequency_hz * tau),
            Some(Where::At(x)) => x,
            None => 0.0,
        },
        ProfileSpec::Sweep {
            amplitude,
            f_start_hz,
            f_end_hz,
            duration_s,
            spacing,
            preload,
        } => {
            // NaN for a law that fails the checks: the model refuses it.
            sweep_law(f_start_hz, f_end_hz, duration_s, spacing)
                .map_or(f64::NAN, |s| preload + amplitude * s.unit(t))
        }
        ProfileSpec::StopStart {
            frequency_hz,
            damping,
            rise_s,
            ref events,
            preload,
            ..
        } => {
            let mut x = preload;
            for e in events.iter().take_while(|e| e.at_s < t) {
                x += e.size * stop_start_response(t - e.at_s, frequency_hz, damping, rise_s);
            }
            x
        }
        ProfileSpec::Hold { preload, .. } => preload,
        ProfileSpec::Replay { ref samples, .. } => interpolate(samples, t),
    }
}

/// Frequency in Hz of the sine the profile imposes at time `t` (s), or
/// `None` where it is not a sine (the instantaneous-modulus plot tracks the
/// force and displacement at this frequency). Stepped sines give the
/// frequency of the step under way (`None` during rests, ramps and holds);
/// a sweep gives its instantaneous frequency f(t) for t in [0, duration_s].
pub fn frequency_at(p: &ProfileSpec, t: f64) -> Option<f64> {
    match *p {
        ProfileSpec::Sine { frequency_hz, .. } => Some(frequency_hz),
        ProfileSpec::SteppedSine { .. } => match stepped(p)?.locate(t) {
            Where::Sine { frequency_hz, .. } => Some(frequency_hz),
            Where::At(_) => None,
        },
        ProfileSpec::Sweep {
            f_start_hz,
            f_end_hz,
            duration_s,
            spacing,
            ..
        } => (0.0..=duration_s)
            .contains(&t)
            .then(|| sweep_law(f_start_hz, f_end_hz, duration_s, spacing))
            .flatten()
            .map(|s| s.frequency(t)),
        ProfileSpec::Triangle { .. }
        | ProfileSpec::MultiStep { .. }
        | ProfileSpec::StopStart { .. }
        | ProfileSpec::Hold { .. }
        | ProfileSpec::Replay { .. } => None,
    }
}

/// Amplitude in mm of the sine the profile imposes at time `t` (s), or
/// `None` where it is not a sine; defined exactly where [`frequency_at`]
/// is.
pub fn amplitude_at(p: &ProfileSpec, t: f64) -> Option<f64> {
    match *p {
        ProfileSpec::Sine { amplitude, .. } => Some(amplitude),
        ProfileSpec::SteppedSine { .. } => match stepped(p)?.locate(t) {
            Where::Sine { amplitude, .. } => Some(amplitude),
            Where::At(_) => None,
        },
        ProfileSpec::Sweep {
            amplitude,
            duration_s,
            ..
        } => (0.0..=duration_s).contains(&t).then_some(amplitude),
        ProfileSpec::Triangle { .. }
        | ProfileSpec::MultiStep { .. }
        | ProfileSpec::StopStart { .. }
        | ProfileSpec::Hold { .. }
        | ProfileSpec::Replay { .. } => None,
    }
}

fn multi_step(levels: &[f64], ramp: f64, hold: f64, preload: f64, t: f64) -> f64 {
    let last = levels.last().copied().unwrap_or(preload);
    if t.is_nan() || t <= 0.0 {
        return preload;
    }
    let unit = ramp + hold;
    let k = (t / unit).floor();
    if k >= levels.len() as f64 {
        return last;
    }
    let k = k as usize;
    let w = t - k as f64 * unit;
    let from = match k.checked_sub(1) {
        Some(j) => levels.get(j).copied().unwrap_or(preload),
        None => preload,
    };
    let to = levels.get(k).copied().unwrap_or(last);
    if w < ramp {
        from + (to - from) * (w / ramp)
    } else {
        to
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

fn stepped(p: &ProfileSpec) -> Option<Stepped<'_>> {
    match p {
        ProfileSpec::SteppedSine {
            preload,
            preloads,
            frequencies_hz,
            amplitudes,
            cycles,
            settle_s,
            settle_cycles,
            ramp_s,
            hold_s,
        } => {
            let preloads: &[f64] = match (preloads, preload) {
                (Some(list), _) => list,
                (None, Some(v)) => std::slice::from_ref(v),
                (None, None) => &[0.0],
            };
            Some(Stepped {
                preloads,
                frequencies: frequencies_hz,
                amplitudes,
                cycles: *cycles,
                settle_s: settle_s.unwrap_or(0.0),
                settle_cycles: settle_cycles.unwrap_or(0.0),
                ramp: ramp_s.unwrap_or(0.0),
                hold: hold_s.unwrap_or(0.0),
            })
        }
        _ => None,
    }
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

/// The core's sweep law ([`bushing::excitation::Sweep`]) of a sweep
/// profile, or `None` when its parameters fail the core's checks (a
/// profile built by hand and never passed through [`steps`]).
fn sweep_law(f0: f64, f1: f64, duration: f64, spacing: Spacing) -> Option<Sweep> {
    Sweep::new(f0, f1, duration, spacing.into()).ok()
}

/// Unit response of the stop/start proxy, `tau` s after an event.
///
/// One mode of undamped frequency f (ω = 2π f, ζ < 1, ω_d = ω √(1-ζ²))
/// driven by a load whose static displacement ramps linearly from 0 to 1
/// over the rise time T_r; x and ẋ start at 0. With the unit-ramp
/// response of the mode
///
/// r(τ) = τ - a + e^{-ζωτ} (a cos ω_d τ + b sin ω_d τ),
/// a = 2ζ/ω, b = (2ζ² - 1)/ω_d,
///
/// the response is r(τ)/T_r while the load rises and
/// 1 + (g(τ) - g(τ - T_r))/T_r after it (g the decaying part of r): a
/// smooth step of size 1 that overshoots and rings down at ω_d with the
/// envelope e^{-ζωτ}. For T_r = 0 it is the step response
/// 1 - e^{-ζωτ}(cos ω_d τ + ζ/√(1-ζ²) sin ω_d τ).
pub fn stop_start_response(tau: f64, frequency_hz: f64, damping: f64, rise_s: f64) -> f64 {
    if tau.is_nan() || tau <= 0.0 {
        return 0.0;
    }
    let w = TAU * frequency_hz;
    let root = libm::sqrt(1.0 - damping * damping);
    let wd = w * root;
    let decay = damping * w;
    if rise_s <= 0.0 {
        return 1.0
            - libm::exp(-decay * tau)
                * (libm::cos(wd * tau) + damping / root * libm::sin(wd * tau));
    }
    let a = 2.0 * damping / w;
    let b = (2.0 * damping * damping - 1.0) / wd;
    let g = |s: f64| libm::exp(-decay * s) * (a * libm::cos(wd * s) + b * libm::sin(wd * s));
    if tau < rise_s {
        (tau - a + g(tau)) / rise_s
    } else {
        1.0 + (g(tau) - g(tau - rise_s)) / rise_s
    }
}

/// Linear interpolation in samples (t, x) with increasing t, constant
/// beyond the ends.
fn interpolate(samples: &[(f64, f64)], t: f64) -> f64 {
    let i = samples.partition_point(|s| s.0 <= t);
    match (
        i.checked_sub(1).and_then(|j| samples.get(j)),
        samples.get(i),
    ) {
        (Some(&(t0, x0)), Some(&(t1, x1))) => x0 + (x1 - x0) * ((t - t0) / (t1 - t0)),
        (Some(&(_, x)), None) | (None, Some(&(_, x))) => x,
        (None, None) => 0.0,
    }
}

/// Completes a profile as parsed: a replay reads its CSV file, `dir`
/// being the directory relative file names start from; with `confine`,
/// the file must be inside `dir` once links and `..` are resolved. Other
/// profiles are returned unchanged.
pub fn resolve(p: ProfileSpec, dir: &Path, confine: bool) -> Result<ProfileSpec, String> {
    let ProfileSpec::Replay {
        file,
        column,
        time_column,
        rate_hz,
        ..
    } = p
    else {
        return Ok(p);
    };
    let time = match (&time_column, rate_hz) {
        (Some(_), Some(_)) => return Err("give time_column or rate_hz, not both".into()),
        (None, None) => {
            return Err("give time_column (a time column in s) or rate_hz (Hz)".into());
        }
        (Some(c), None) => Time::Column(index_check("time_column", c)?),
        (None, Some(r)) => {
            finite_positive("rate_hz", r)?;
            Time::Rate(r)
        }
    };
    index_check("column", &column)?;
    if file.trim().is_empty() {
        return Err("file must name a CSV file".into());
    }
    let path = dir.join(&file);
    let name = path.display().to_string();
    let cannot = |e: std::io::Error| format!("cannot read replay file {name}: {e}");
    if confine {
        let base = dir
            .canonicalize()
            .or_else(|_| Path::new(".").canonicalize())
            .map_err(cannot)?;
        let real = path.canonicalize().map_err(cannot)?;
        if !real.starts_with(&base) {
            return Err(format!(
                "replay file {}: outside the scene's folder, which --confine forbids",
                shown(&file)
            ));
        }
    }
    // Only regular files, checked before opening: a device or a pipe could
    // block or never end.
    let meta = std::fs::metadata(&path).map_err(cannot)?;
    if !meta.is_file() {
        return Err(format!("replay file {name} is not a regular file"));
    }
    if meta.len() > MAX_CSV_BYTES {
        return Err(format!(
            "replay file {name}: {} bytes, more than the limit of {MAX_CSV_BYTES}",
            meta.len()
        ));
    }
    let mut text = String::new();
    std::fs::File::open(&path)
        .map_err(cannot)?
        .take(MAX_CSV_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(cannot)?;
    if text.len() as u64 > MAX_CSV_BYTES {
        return Err(format!(
            "replay file {name}: more than the limit of {MAX_CSV_BYTES} bytes"
        ));
    }
    let samples = read_csv(&name, &text, &column, time)?;
    Ok(ProfileSpec::Replay {
        file,
        column,
        time_column,
        rate_hz,
        samples,
    })
}

fn index_check<'a>(name: &str, c: &'a Column) -> Result<&'a Column, String> {
    match c {
        Column::Index(i) if !(1..=MAX_COLUMN).contains(i) => Err(format!(
            "{name} = {i}: column indices count from 1 to {MAX_COLUMN}"
        )),
        Column::Name(n) if n.trim().is_empty() => Err(format!("{name}: empty column name")),
        _ => Ok(c),
    }
}

/// Where a replay's times come from.
#[derive(Debug, Clone, Copy)]
enum Time<'a> {
    Column(&'a Column),
    Rate(f64),
}

/// A field without surrounding blanks and double quotes.
fn clean(field: &str) -> &str {
    let f = field.trim();
    f.strip_prefix('"')
        .and_then(|g| g.strip_suffix('"'))
        .unwrap_or(f)
        .trim()
}

/// At most 40 characters of a field, for messages, with control and
/// other invisible characters escaped (`\u{1b}`), so that a hostile file
/// cannot write to the terminal through an error.
fn shown(field: &str) -> String {
    let mut s: String = field
        .chars()
        .take(40)
        .flat_map(char::escape_debug)
        .collect();
    if field.chars().nth(40).is_some() {
        s.push('…');
    }
    s
}

/// A number for messages: plain, or in exponent form when very large or
/// very small.
fn num(v: f64) -> String {
    if v == 0.0 || (1e-6..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Reads (time, displacement) samples from CSV text; `name` names the file
/// in errors, whose rows are the file's lines counted from 1.
///
/// Fields are separated by commas, or by semicolons or tabs when the first
/// row has no comma; blank lines and lines starting with `#` are skipped;
/// the first row is a header when one of its fields is not a number. Times
/// must increase strictly and are shifted to start at 0.
fn read_csv(
    name: &str,
    text: &str,
    column: &Column,
    time: Time<'_>,
) -> Result<Vec<(f64, f64)>, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut rows = text.lines().enumerate().filter_map(|(i, l)| {
        let t = l.trim();
        (!t.is_empty() && !t.starts_with('#')).then_some((i + 1, l))
    });
    let Some((first_line, first)) = rows.next() else {
        return Err(format!("{name}: no rows"));
    };
    let delimiter = [',', ';', '\t']
        .into_iter()
        .find(|&d| first.contains(d))
        .unwrap_or(',');
    let header: Option<Vec<&str>> = {
        let fields: Vec<&str> = first.split(delimiter).map(clean).collect();
        fields
            .iter()
            .any(|f| f.parse::<f64>().is_err())
            .then_some(fields)
    };
    let find = |label: &str, c: &Column| -> Result<usize, String> {
        match c {
            Column::Index(i) => Ok(usize::try_from(*i).unwrap_or(1).saturating_sub(1)),
            Column::Name(n) => {
                let Some(h) = &header else {
                    return Err(format!(
                        "{name}: {label} '{n}' needs a header row, but row {first_line} is all numbers"
                    ));
                };
                h.iter().position(|f| *f == n.trim()).ok_or_else(|| {
                    format!(
                        "{name}: row {first_line}: no column named '{n}' for {label} (the header has {})",
                        h.iter().map(|f| format!("'{}'", shown(f))).collect::<Vec<_>>().join(", ")
                    )
                })
            }
        }
    };
    let x_col = find("column", column)?;
    let t_col = match time {
        Time::Column(c) => Some(find("time_column", c)?),
        Time::Rate(_) => None,
    };
    let number = |line: usize, fields: &[&str], c: usize| -> Result<f64, String> {
        let Some(raw) = fields.get(c) else {
            return Err(format!(
                "{name}: row {line}, column {}: missing (the row has {} columns)",
                c + 1,
                fields.len()
            ));
        };
        let f = clean(raw);
        match f.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(format!(
                "{name}: row {line}, column {}: expected a finite number, got '{}'",
                c + 1,
                shown(f)
            )),
            Err(_) => Err(format!(
                "{name}: row {line}, column {}: expected a number, got '{}'",
                c + 1,
                shown(f)
            )),
        }
    };
    let data = header
        .is_none()
        .then_some((first_line, first))
        .into_iter()
        .chain(rows);
    let mut samples: Vec<(f64, f64)> = Vec::new();
    let mut start = 0.0;
    let mut previous = (0usize, 0.0f64);
    for (line, row) in data {
        let fields: Vec<&str> = row.split(delimiter).collect();
        let x = number(line, &fields, x_col)?;
        let t = match (t_col, time) {
            (Some(c), _) => {
                let raw = number(line, &fields, c)?;
                if samples.is_empty() {
                    start = raw;
                }
                let t = raw - start;
                if !samples.is_empty() && t <= previous.1 {
                    return Err(format!(
                        "{name}: row {line}, column {}: time {} s is not after the {} s of row {}",
                        c + 1,
                        num(raw),
                        num(previous.1 + start),
                        previous.0
                    ));
                }
                if !t.is_finite() {
                    return Err(format!(
                        "{name}: row {line}, column {}: time {} s is too far from the first row's {} s",
                        c + 1,
                        num(raw),
                        num(start)
                    ));
                }
                t
            }
            (None, Time::Rate(r)) => samples.len() as f64 / r,
            (None, Time::Column(_)) => samples.len() as f64,
        };
        if samples.len() >= MAX_SAMPLES {
            return Err(format!(
                "{name}: row {line}: more than the limit of {MAX_SAMPLES} samples"
            ));
        }
        samples.push((t, x));
        previous = (line, t);
    }
    if samples.len() < 2 {
        return Err(format!(
            "{name}: {} data rows, at least 2 needed",
            samples.len()
        ));
    }
    Ok(samples)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1e-3;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn triangle_starts_at_preload_going_up_at_the_given_speed() {
        let p = ProfileSpec::Triangle {
            amplitude: 2.0,
            speed: 4.0,
            cycles: 1.0,
            preload: 1.0,
        };
        assert!((displacement(&p, 0.0) - 1.0).abs() < 1e-12);
        assert!((displacement(&p, 0.1) - 1.4).abs() < 1e-12);
        assert!((displacement(&p, 0.5) - 3.0).abs() < 1e-12);
        assert!((displacement(&p, 1.5) + 1.0).abs() < 1e-12);
        assert_eq!(steps(&p, 1e-3), Ok(2000));
        assert_eq!(frequency_at(&p, 0.3), None);
        assert_eq!(amplitude_at(&p, 0.3), None);
    }

    #[test]
    fn sine_profile_and_its_errors() {
        let p = ProfileSpec::Sine {
            amplitude: 1.0,
            frequency_hz: 2.0,
            cycles: 3.0,
            preload: 0.5,
        };
        assert!((displacement(&p, 0.125) - 1.5).abs() < 1e-12);
        assert_eq!(steps(&p, 1e-3), Ok(1500));
        assert_eq!(frequency_at(&p, 0.4), Some(2.0));
        assert_eq!(amplitude_at(&p, 0.4), Some(1.0));
        let bad = ProfileSpec::Sine {
            amplitude: 1.0,
            frequency_hz: 0.0,
            cycles: 3.0,
            preload: 0.0,
        };
        assert!(steps(&bad, 1e-3).unwrap_err().contains("frequency_hz"));
    }

    fn multi() -> ProfileSpec {
        ProfileSpec::MultiStep {
            levels: vec![0.5, 1.5, 1.0],
            ramp_s: 20.0,
            hold_s: 360.0,
            preload: 0.25,
        }
    }

    #[test]
    fn multi_step_ramps_then_holds_each_level() {
        let p = multi();
        assert_eq!(steps(&p, 0.01), Ok(3 * 38_000));
        assert_eq!(displacement(&p, 0.0), 0.25);
        assert_eq!(displacement(&p, -1.0), 0.25);
        // Halfway up the first ramp, then held.
        assert!(close(displacement(&p, 10.0), 0.375, 1e-15));
        assert_eq!(displacement(&p, 20.0), 0.5);
        assert_eq!(displacement(&p, 379.9), 0.5);
        // Second ramp 0.5 -> 1.5 over 380..400 s, third 1.5 -> 1.0.
        assert!(close(displacement(&p, 385.0), 0.75, 1e-12));
        assert_eq!(displacement(&p, 500.0), 1.5);
        assert!(close(displacement(&p, 770.0), 1.25, 1e-12));
        assert_eq!(displacement(&p, 1000.0), 1.0);
        assert_eq!(displacement(&p, 1140.0), 1.0);
        assert_eq!(displacement(&p, 1e9), 1.0);
        // Continuous at every ramp start and end.
        for k in 0..3 {
            for edge in [0.0, 20.0] {
                let t = k as f64 * 380.0 + edge;
                let jump = (displacement(&p, t + 1e-9) - displacement(&p, t - 1e-9)).abs();
                assert!(jump < 1e-9, "jump {jump} at {t} s");
            }
        }
        assert_eq!(frequency_at(&p, 10.0), None);
        assert_eq!(amplitude_at(&p, 10.0), None);
    }

    #[test]
    fn multi_step_errors_name_the_field_and_bound() {
        let with = |f: &dyn Fn(&mut ProfileSpec)| {
            let mut p = multi();
            f(&mut p);
            steps(&p, DT).unwrap_err()
        };
        let e = with(&|p| {
            if let ProfileSpec::MultiStep { levels, .. } = p {
                levels.clear();
            }
        });
        assert_eq!(e, "levels: 1 to 10000 values expected, got 0");
        let e = with(&|p| {
            if let ProfileSpec::MultiStep { levels, .. } = p {
                levels[1] = f64::NAN;
            }
        });
        assert_eq!(e, "levels[1] must be finite, got NaN");
        let e = with(&|p| {
            if let ProfileSpec::MultiStep { ramp_s, .. } = p {
                *ramp_s = 0.0;
            }
        });
        assert_eq!(e, "ramp_s must be finite and > 0, got 0");
        let e = with(&|p| {
            if let ProfileSpec::MultiStep { hold_s, .. } = p {
                *hold_s = -1.0;
            }
        });
        assert_eq!(e, "hold_s must be finite and >= 0, got -1");
        let e = with(&|p| {
            if let ProfileSpec::MultiStep { preload, .. } = p {
                *preload = f64::INFINITY;
            }
        });
        assert_eq!(e, "preload must be finite, got inf");
        let e = with(&|p| {
            if let ProfileSpec::MultiStep { hold_s, .. } = p {
                *hold_s = 1e300;
            }
        });
        assert!(e.starts_with("duration ") && e.ends_with(" steps"), "{e}");
    }

    fn stepped_sine() -> ProfileSpec {
        ProfileSpec::SteppedSine {
            preload: None,
            preloads: Some(vec![1.0, 2.0]),
            frequencies_hz: vec![1.0, 10.0],
            amplitudes: vec![0.1, 0.25],
            cycles: 2.0,
            settle_s: Some(0.5),
            settle_cycles: None,
            ramp_s: Some(4.0),
            hold_s: Some(6.0),
        }
    }

    #[test]
    fn stepped_sine_schedule_values_and_continuity() {
        let p = stepped_sine();
        // One preload: 2 steps of 2 s at 1 Hz, 2 of 0.2 s at 10 Hz, each
        // followed by 0.5 s: a block of 2 x 2.5 + 2 x 0.7 = 6.4 s. Then a
        // 4 s ramp, a 6 s hold, the second block without its last rest.
        assert!(close(
            checked_duration(&p, DT).unwrap(),
            6.4 + 10.0 + 6.4 - 0.5,
            1e-12
        ));
        assert_eq!(steps(&p, DT), Ok(22_300));
        // First step: 0.1 mm at 1 Hz about 1 mm.
        assert!(close(displacement(&p, 0.25), 1.1, 1e-12));
        assert!(close(displacement(&p, 0.75), 0.9, 1e-12));
        assert_eq!(frequency_at(&p, 0.25), Some(1.0));
        assert_eq!(amplitude_at(&p, 0.25), Some(0.1));
        // Rest after it, then the second amplitude from 2.5 s.
        assert_eq!(displacement(&p, 2.2), 1.0);
        assert_eq!(frequency_at(&p, 2.2), None);
        assert_eq!(amplitude_at(&p, 2.2), None);
        assert!(close(displacement(&p, 2.75), 1.25, 1e-12));
        assert_eq!(amplitude_at(&p, 2.75), Some(0.25));
        // Then 10 Hz from 5 s: 0.1 mm, a quarter period in.
        assert!(close(displacement(&p, 5.025), 1.1, 1e-12));
        assert_eq!(frequency_at(&p, 5.025), Some(10.0));
        assert!(close(displacement(&p, 5.725), 1.25, 1e-12));
        assert_eq!(amplitude_at(&p, 5.725), Some(0.25));
        // Ramp 1 -> 2 mm over 6.4..10.4 s, hold to 16.4 s.
        assert!(close(displacement(&p, 8.4), 1.5, 1e-12));
        assert_eq!(frequency_at(&p, 8.4), None);
        assert_eq!(displacement(&p, 12.0), 2.0);
        // Second block at 2 mm.
        assert!(close(displacement(&p, 16.65), 2.1, 1e-12));
        assert_eq!(frequency_at(&p, 16.65), Some(1.0));
        assert!(close(displacement(&p, 16.4 + 5.7 + 0.025), 2.25, 1e-12));
        assert_eq!(displacement(&p, 100.0), 2.0);
        assert_eq!(frequency_at(&p, 100.0), None);
        assert_eq!(displacement(&p, -1.0), 1.0);
        // Continuous everywhere: no jump larger than the slope allows.
        let dt = 1e-4;
        let mut prev = displacement(&p, 0.0);
        let mut n = 1;
        while n as f64 * dt <= 22.3 {
            let x = displacement(&p, n as f64 * dt);
            // Fastest slope: 2π 10 Hz x 0.25 mm = 15.7 mm/s.
            assert!((x - prev).abs() <= 15.8 * dt, "jump at {} s", n as f64 * dt);
            prev = x;
            n += 1;
        }
        // Each step starts and ends at the preload.
        for t in [0.0, 2.0, 2.5, 4.5, 5.0, 5.2, 5.7, 5.9, 16.4, 21.9] {
            let x = displacement(&p, t);
            assert!(close(x, 1.0, 1e-12) || close(x, 2.0, 1e-12), "{x} at {t} s");
        }
    }

    #[test]
    fn stepped_sine_single_preload_and_settle_in_cycles() {
        let p = ProfileSpec::SteppedSine {
            preload: Some(0.5),
            preloads: None,
            frequencies_hz: vec![2.0, 4.0],
            amplitudes: vec![0.05, 0.1, 0.2],
            cycles: 3.0,
            settle_s: None,
            settle_cycles: Some(1.0),
            ramp_s: None,
            hold_s: None,
        };
        // Steps of 1.5 s + 0.5 s rest at 2 Hz, 0.75 + 0.25 s at 4 Hz; no
        // rest after the last step.
        assert_eq!(steps(&p, DT), Ok(8_750));
        assert!(close(displacement(&p, 4.125), 0.7, 1e-12));
        assert_eq!(amplitude_at(&p, 4.125), Some(0.2));
        assert_eq!(frequency_at(&p, 6.0 + 2.0 + 0.0625), Some(4.0));
        assert!(close(displacement(&p, 6.0 + 2.0 + 0.0625), 0.7, 1e-12));
        // No preload at all means 0.
        let q = ProfileSpec::SteppedSine {
            preload: None,
            preloads: None,
            frequencies_hz: vec![1.0],
            amplitudes: vec![1.0],
            cycles: 1.0,
            settle_s: None,
            settle_cycles: None,
            ramp_s: None,
            hold_s: None,
        };
        assert_eq!(steps(&q, DT), Ok(1000));
        assert!(close(displacement(&q, 0.25), 1.0, 1e-12));
        assert_eq!(displacement(&q, 1.0), 0.0);
    }

    #[test]
    fn stepped_sine_errors_name_the_field_and_bound() {
        let with = |f: &dyn Fn(&mut ProfileSpec)| {
            let mut p = stepped_sine();
            f(&mut p);
            steps(&p, DT).unwrap_err()
        };
        macro_rules! set {
            ($field:ident, $v:expr) => {
                &|p: &mut ProfileSpec| {
                    if let ProfileSpec::SteppedSine { $field, .. } = p {
                        *$field = $v;
                    }
                }
            };
        }
        assert_eq!(
            with(set!(preload, Some(0.0))),
            "give preload or preloads, not both"
        );
        assert_eq!(
            with(set!(preloads, Some(vec![0.0, f64::NAN]))),
            "preloads[1] must be finite, got NaN"
        );
        assert_eq!(
            with(set!(frequencies_hz, vec![1.0, -2.0])),
            "frequencies_hz[1] must be finite and > 0, got -2"
        );
        assert_eq!(
            with(set!(frequencies_hz, vec![500.0])),
            "frequencies_hz[0] = 500 Hz must be below half the rate (500 Hz)"
        );
        assert_eq!(
            with(set!(amplitudes, vec![])),
            "amplitudes: 1 to 10000 values expected, got 0"
        );
        assert_eq!(
            with(set!(amplitudes, vec![0.0])),
            "amplitudes[0] must be finite and > 0, got 0"
        );
        assert_eq!(
            with(set!(cycles, 2.5)),
            "cycles must be a whole number >= 1 (each step ends at the preload), got 2.5"
        );
        assert!(with(set!(cycles, 0.0)).starts_with("cycles must be a whole number >= 1"));
        assert_eq!(
            with(set!(settle_cycles, Some(1.0))),
            "give settle_s or settle_cycles, not both"
        );
        assert_eq!(
            with(set!(settle_s, Some(-0.5))),
            "settle_s must be finite and >= 0, got -0.5"
        );
        assert_eq!(
            with(set!(ramp_s, None)),
            "ramp_s (s) is needed to go from one preload to the next (2 preloads)"
        );
        assert_eq!(
            with(set!(ramp_s, Some(0.0))),
            "ramp_s must be finite and > 0, got 0"
        );
        assert_eq!(
            with(set!(hold_s, Some(f64::NAN))),
            "hold_s must be finite and >= 0, got NaN"
        );
        assert_eq!(
            with(set!(preloads, Some(vec![1.0]))),
            "ramp_s and hold_s apply between preloads: give two or more preloads, or remove them"
        );
        assert_eq!(
            with(&|p| {
                if let ProfileSpec::SteppedSine {
                    frequencies_hz,
                    amplitudes,
                    ..
                } = p
                {
                    *frequencies_hz = (1..=10).map(f64::from).collect();
                    *amplitudes = vec![0.1; 10_000];
                }
            }),
            "200000 sine steps (preloads x frequencies_hz x amplitudes), more than the limit of 100000"
        );
        let mut single = stepped_sine();
        if let ProfileSpec::SteppedSine {
            preload,
            preloads,
            settle_cycles,
            settle_s,
            ramp_s,
            hold_s,
            ..
        } = &mut single
        {
            (*preload, *preloads) = (Some(f64::NEG_INFINITY), None);
            (*settle_s, *settle_cycles) = (None, Some(-1.0));
            (*ramp_s, *hold_s) = (None, None);
        }
        assert_eq!(
            steps(&single, DT).unwrap_err(),
            "preload must be finite, got -inf"
        );
        if let ProfileSpec::SteppedSine { preload, .. } = &mut single {
            *preload = Some(0.0);
        }
        assert_eq!(
            steps(&single, DT).unwrap_err(),
            "settle_cycles must be finite and >= 0, got -1"
        );
    }

    fn sweep(spacing: Spacing) -> ProfileSpec {
        ProfileSpec::Sweep {
            amplitude: 0.5,
            f_start_hz: 1.0,
            f_end_hz: 16.0,
            duration_s: 8.0,
            spacing,
            preload: 1.0,
        }
    }

    #[test]
    fn log_sweep_frequency_and_phase() {
        let p = sweep(Spacing::Log);
        assert_eq!(steps(&p, DT), Ok(8000));
        // One octave every 2 s.
        assert!(close(frequency_at(&p, 0.0).unwrap(), 1.0, 1e-12));
        assert!(close(frequency_at(&p, 2.0).unwrap(), 2.0, 1e-12));
        assert!(close(frequency_at(&p, 8.0).unwrap(), 16.0, 1e-12));
        assert_eq!(frequency_at(&p, 8.1), None);
        assert_eq!(frequency_at(&p, -0.1), None);
        assert_eq!(amplitude_at(&p, 4.0), Some(0.5));
        assert_eq!(amplitude_at(&p, 9.0), None);
        // Phase: f0 T / ln r (r^(t/T) - 1) cycles, 2/ln 2 cycles after 2 s.
        let c = 2.0 / 2f64.ln();
        let expected = 1.0 + 0.5 * (TAU * c).sin();
        assert!(close(displacement(&p, 2.0), expected, 1e-12));
        assert_eq!(displacement(&p, 0.0), 1.0);
        // The phase is the integral of the frequency: the numerical slope
        // of x matches 2π f A cos φ.
        for t in [0.3, 1.7, 5.2, 7.9] {
            let h = 1e-6;
            let slope = (displacement(&p, t + h) - displacement(&p, t - h)) / (2.0 * h);
            let f = frequency_at(&p, t).unwrap();
            let l = 16f64.ln();
            let phase = TAU * 8.0 / l * ((l * t / 8.0).exp() - 1.0);
            assert!(
                close(slope, TAU * f * 0.5 * phase.cos(), 1e-5 * TAU * f),
                "t = {t}"
            );
        }
        // Held after the end.
        assert_eq!(displacement(&p, 9.0), displacement(&p, 8.0));
    }

    #[test]
    fn linear_sweep_frequency_and_phase() {
        let p = sweep(Spacing::Linear);
        assert!(close(frequency_at(&p, 4.0).unwrap(), 8.5, 1e-12));
        // Phase f0 t + (f1 - f0) t² / 2T: 1 + 15/16 cycles at 1 s.
        let expected = 1.0 + 0.5 * (TAU * (1.0 + 15.0 / 16.0)).sin();
        assert!(close(displacement(&p, 1.0), expected, 1e-12));
        // 8 + 60 = 68 whole cycles at the end: back at the preload.
        assert!(close(displacement(&p, 8.0), 1.0, 1e-12));
        // A "sweep" from f to f is a sine.
        let flat = ProfileSpec::Sweep {
            amplitude: 1.0,
            f_start_hz: 2.0,
            f_end_hz: 2.0,
            duration_s: 1.0,
            spacing: Spacing::Log,
            preload: 0.0,
        };
        assert!(close(displacement(&flat, 0.125), 1.0, 1e-12));
        assert_eq!(frequency_at(&flat, 0.5), Some(2.0));
    }

    #[test]
    fn sweep_errors_name_the_field_and_bound() {
        let set = |f: &dyn Fn(&mut f64, &mut f64, &mut f64, &mut f64, &mut f64)| {
            let mut p = sweep(Spacing::Log);
            if let ProfileSpec::Sweep {
                amplitude,
                f_start_hz,
                f_end_hz,
                duration_s,
                preload,
                ..
            } = &mut p
            {
                f(amplitude, f_start_hz, f_end_hz, duration_s, preload);
            }
            steps(&p, DT).unwrap_err()
        };
        assert_eq!(
            set(&|a, _, _, _, _| *a = 0.0),
            "amplitude must be finite and > 0, got 0"
        );
        assert_eq!(
            set(&|_, f, _, _, _| *f = -1.0),
            "f_start_hz must be finite and > 0, got -1"
        );
        assert_eq!(
            set(&|_, _, f, _, _| *f = 600.0),
            "f_end_hz = 600 Hz must be below half the rate (500 Hz)"
        );
        assert_eq!(
            set(&|_, f, _, _, _| *f = 500.0),
            "f_start_hz = 500 Hz must be below half the rate (500 Hz)"
        );
        assert_eq!(
            set(&|_, _, _, d, _| *d = f64::INFINITY),
            "duration_s must be finite and > 0, got inf"
        );
        assert_eq!(
            set(&|_, _, _, _, x| *x = f64::NAN),
            "preload must be finite, got NaN"
        );
    }

    fn stop_start(rise_s: f64) -> ProfileSpec {
        ProfileSpec::StopStart {
            frequency_hz: 10.0,
            damping: 0.1,
            rise_s,
            duration_s: 3.0,
            events: vec![
                StopStartEvent {
                    at_s: 0.5,
                    size: 2.0,
                },
                StopStartEvent {
                    at_s: 2.0,
                    size: -2.0,
                },
            ],
            preload: 0.5,
        }
    }

    #[test]
    fn stop_start_is_a_ringing_smooth_step() {
        let p = stop_start(0.05);
        assert_eq!(steps(&p, DT), Ok(3000));
        assert_eq!(displacement(&p, 0.0), 0.5);
        assert_eq!(displacement(&p, 0.5), 0.5);
        assert_eq!(frequency_at(&p, 1.0), None);
        assert_eq!(amplitude_at(&p, 1.0), None);
        // Starts with zero slope, and the unit response is continuous
        // with a continuous slope at the end of the rise.
        let h = 1e-8;
        assert!(displacement(&p, 0.5 + h) - 0.5 < 1e-9);
        for (f, z, r) in [(10.0, 0.1, 0.05), (4.0, 0.0, 0.3), (13.4, 0.7, 0.01)] {
            let y = |t: f64| stop_start_response(t, f, z, r);
            assert!((y(r + h) - y(r - h)).abs() < 1e-5, "{f} {z} {r}");
            let left = (y(r) - y(r - h)) / h;
            let right = (y(r + h) - y(r)) / h;
            assert!((left - right).abs() < 1e-3, "{left} {right}");
            // Zero slope at the start.
            assert!(y(h) < 1e-6);
        }
        // Overshoot then ring-down to the new level 2.5 mm; the first peak
        // of the step response is 1 + exp(-πζ/√(1-ζ²)).
        let step = |t: f64| stop_start_response(t, 10.0, 0.1, 0.0);
        let zeta: f64 = 0.1;
        let wd = TAU * 10.0 * (1.0 - zeta * zeta).sqrt();
        let peak = 1.0 + (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        assert!(close(step(std::f64::consts::PI / wd), peak, 1e-12));
        assert!(close(displacement(&p, 1.99), 2.5, 2e-3));
        // Back to the preload after the stop event.
        assert!(close(displacement(&p, 3.0), 0.5, 2e-3));
        // A slow rise (many periods) barely overshoots.
        let slow_peak = (0..2000)
            .map(|k| stop_start_response(k as f64 * 1e-3, 10.0, 0.1, 1.0))
            .fold(0.0, f64::max);
        assert!(slow_peak < 1.02 && slow_peak > 0.999, "{slow_peak}");
        // The ramp response formula against a direct integration of
        // ÿ + 2ζω ẏ + ω² y = ω² u(t), u the unit ramp over rise_s.
        let (w, z, r) = (TAU * 10.0, 0.1, 0.05);
        let (mut y, mut v) = (0.0f64, 0.0f64);
        let hh = 1e-6;
        let acc = |t: f64, y: f64, v: f64| w * w * ((t / r).min(1.0) - y) - 2.0 * z * w * v;
        let mut t = 0.0;
        for _ in 0..300_000 {
            // Classic RK4.
            let (k1y, k1v) = (v, acc(t, y, v));
            let (k2y, k2v) = (
                v + 0.5 * hh * k1v,
                acc(t + 0.5 * hh, y + 0.5 * hh * k1y, v + 0.5 * hh * k1v),
            );
            let (k3y, k3v) = (
                v + 0.5 * hh * k2v,
                acc(t + 0.5 * hh, y + 0.5 * hh * k2y, v + 0.5 * hh * k2v),
            );
            let (k4y, k4v) = (v + hh * k3v, acc(t + hh, y + hh * k3y, v + hh * k3v));
            y += hh / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y);
            v += hh / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            t += hh;
        }
        assert!(close(y, stop_start_response(t, 10.0, z, r), 1e-6), "{y}");
    }

    #[test]
    fn stop_start_errors_name_the_field_and_bound() {
        let set = |f: &dyn Fn(&mut ProfileSpec)| {
            let mut p = stop_start(0.05);
            f(&mut p);
            steps(&p, DT).unwrap_err()
        };
        macro_rules! field {
            ($field:ident, $v:expr) => {
                &|p: &mut ProfileSpec| {
                    if let ProfileSpec::StopStart { $field, .. } = p {
                        *$field = $v;
                    }
                }
            };
        }
        assert_eq!(
            set(field!(frequency_hz, 0.0)),
            "frequency_hz must be finite and > 0, got 0"
        );
        assert_eq!(
            set(field!(frequency_hz, 800.0)),
            "frequency_hz = 800 Hz must be below half the rate (500 Hz)"
        );
        assert_eq!(
            set(field!(damping, 1.0)),
            "damping (ratio) must be in [0, 1) (an oscillating mode), got 1"
        );
        assert_eq!(
            set(field!(rise_s, -0.1)),
            "rise_s must be finite and >= 0, got -0.1"
        );
        assert_eq!(
            set(field!(duration_s, 0.0)),
            "duration_s must be finite and > 0, got 0"
        );
        assert_eq!(
            set(field!(preload, f64::NAN)),
            "preload must be finite, got NaN"
        );
        assert_eq!(
            set(field!(events, vec![])),
            "events: 1 to 64 events expected, got 0"
        );
        assert_eq!(
            set(field!(
                events,
                vec![
                    StopStartEvent {
                        at_s: 1.0,
                        size: 1.0
                    },
                    StopStartEvent {
                        at_s: 0.5,
                        size: 1.0
                    }
                ]
            )),
            "events[1].at_s must be in [1, duration_s = 3) s (events in time order), got 0.5"
        );
        assert_eq!(
            set(field!(
                events,
                vec![StopStartEvent {
                    at_s: 3.0,
                    size: 1.0
                }]
            )),
            "events[0].at_s must be in [0, duration_s = 3) s (events in time order), got 3"
        );
        assert_eq!(
            set(field!(
                events,
                vec![StopStartEvent {
                    at_s: 0.0,
                    size: f64::INFINITY
                }]
            )),
            "events[0].size must be finite, got inf"
        );
    }

    fn csv(text: &str, column: Column, time: Time<'_>) -> Result<Vec<(f64, f64)>, String> {
        read_csv("m.csv", text, &column, time)
    }

    #[test]
    fn csv_with_header_and_time_column() {
        let text = "# measured on the rig\ntime_s, \"x_mm\",force_N\n\n10.0,0.0,1\n10.5,1.0,2\n11.0,-1.0,3\n";
        let t = Column::Name("time_s".into());
        let s = csv(text, Column::Name("x_mm".into()), Time::Column(&t)).unwrap();
        assert_eq!(s, vec![(0.0, 0.0), (0.5, 1.0), (1.0, -1.0)]);
        // By index, semicolons, a rate instead of times.
        let s = csv("0;2.5\n0;3.5\n", Column::Index(2), Time::Rate(4.0)).unwrap();
        assert_eq!(s, vec![(0.0, 2.5), (0.25, 3.5)]);
        // Interpolation and the replayed profile.
        let p = ProfileSpec::Replay {
            file: "m.csv".into(),
            column: Column::Index(2),
            time_column: Some(Column::Index(1)),
            rate_hz: None,
            samples: vec![(0.0, 0.0), (0.5, 1.0), (1.0, -1.0)],
        };
        assert_eq!(steps(&p, DT), Ok(1000));
        assert_eq!(displacement(&p, 0.5), 1.0);
        assert_eq!(displacement(&p, 0.25), 0.5);
        assert_eq!(displacement(&p, 0.75), 0.0);
        assert_eq!(displacement(&p, -1.0), 0.0);
        assert_eq!(displacement(&p, 2.0), -1.0);
        assert_eq!(frequency_at(&p, 0.5), None);
        assert_eq!(amplitude_at(&p, 0.5), None);
    }

    #[test]
    fn csv_errors_name_file_row_and_column() {
        let t = Column::Index(1);
        let x = || Column::Index(2);
        let e = csv("t,x\n0,1\n0.1,abc\n", x(), Time::Column(&t)).unwrap_err();
        assert_eq!(e, "m.csv: row 3, column 2: expected a number, got 'abc'");
        let e = csv("t,x\n0,1\n0.1,inf\n", x(), Time::Column(&t)).unwrap_err();
        assert_eq!(
            e,
            "m.csv: row 3, column 2: expected a finite number, got 'inf'"
        );
        let e = csv("t,x\n0,1\n0.1\n", x(), Time::Column(&t)).unwrap_err();
        assert_eq!(e, "m.csv: row 3, column 2: missing (the row has 1 columns)");
        let e = csv("t,x\n0,1\n0.2,1\n0.2,3\n", x(), Time::Column(&t)).unwrap_err();
        assert_eq!(
            e,
            "m.csv: row 4, column 1: time 0.2 s is not after the 0.2 s of row 3"
        );
        let e = csv("t,x\n0,1\n", x(), Time::Column(&t)).unwrap_err();
        assert_eq!(e, "m.csv: 1 data rows, at least 2 needed");
        let e = csv("# nothing\n\n", x(), Time::Rate(10.0)).unwrap_err();
        assert_eq!(e, "m.csv: no rows");
        let e = csv("t,x\n0,1\n1,2\n", Column::Name("y".into()), Time::Rate(1.0)).unwrap_err();
        assert_eq!(
            e,
            "m.csv: row 1: no column named 'y' for column (the header has 't', 'x')"
        );
        let e = csv("0,1\n1,2\n", Column::Name("x".into()), Time::Rate(1.0)).unwrap_err();
        assert_eq!(
            e,
            "m.csv: column 'x' needs a header row, but row 1 is all numbers"
        );
        let e = csv(
            "t,x\n-1e308,1\n1e308,2\n",
            x(),
            Time::Column(&Column::Index(1)),
        )
        .unwrap_err();
        assert!(
            e.starts_with("m.csv: row 3, column 1: time 1e308 s is too far"),
            "{e}"
        );
    }

    #[test]
    fn resolve_reads_the_file_and_checks_the_fields() {
        let dir = std::env::temp_dir().join(format!("bushing-profile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("d.csv"), "t,x\n0,0\n0.5,2\n").unwrap();
        let replay = |column: Column, time_column: Option<Column>, rate_hz: Option<f64>| {
            ProfileSpec::Replay {
                file: "d.csv".into(),
                column,
                time_column,
                rate_hz,
                samples: Vec::new(),
            }
        };
        let p = resolve(
            replay(Column::Name("x".into()), None, Some(2.0)),
            &dir,
            false,
        )
        .unwrap();
        assert_eq!(steps(&p, DT), Ok(500));
        assert_eq!(displacement(&p, 0.25), 1.0);
        // Without the file: no samples.
        let unread = replay(Column::Index(2), None, Some(2.0));
        assert_eq!(
            steps(&unread, DT).unwrap_err(),
            "replay: 0 samples; at least 2, read from the file when the scene is parsed"
        );
        let e = resolve(
            replay(Column::Index(2), Some(Column::Index(1)), Some(2.0)),
            &dir,
            false,
        )
        .unwrap_err();
        assert_eq!(e, "give time_column or rate_hz, not both");
        let e = resolve(replay(Column::Index(2), None, None), &dir, false).unwrap_err();
        assert_eq!(e, "give time_column (a time column in s) or rate_hz (Hz)");
        let e = resolve(replay(Column::Index(0), None, Some(2.0)), &dir, false).unwrap_err();
        assert_eq!(e, "column = 0: column indices count from 1 to 10000");
        let e = resolve(
            replay(Column::Index(2), Some(Column::Name(" ".into())), None),
            &dir,
            false,
        )
        .unwrap_err();
        assert_eq!(e, "time_column: empty column name");
        let e = resolve(replay(Column::Index(2), None, Some(-1.0)), &dir, false).unwrap_err();
        assert_eq!(e, "rate_hz must be finite and > 0, got -1");
        let e = resolve(
            replay(Column::Index(2), None, Some(2.0)),
            &dir.join("no"),
            false,
        )
        .unwrap_err();
        assert!(
            e.starts_with("cannot read replay file ") && e.contains("d.csv"),
            "{e}"
        );
        let mut directory = replay(Column::Index(2), None, Some(2.0));
        if let ProfileSpec::Replay { file, .. } = &mut directory {
            *file = ".".into();
        }
        let e = resolve(directory, &dir, false).unwrap_err();
        assert!(e.ends_with(" is not a regular file"), "{e}");
        let mut empty_name = replay(Column::Index(2), None, Some(2.0));
        if let ProfileSpec::Replay { file, .. } = &mut empty_name {
            file.clear();
        }
        assert_eq!(
            resolve(empty_name, &dir, false).unwrap_err(),
            "file must name a CSV file"
        );
        // Other profiles pass through.
        assert_eq!(resolve(multi(), &dir, false).unwrap(), multi());
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn column_deserializes_from_names_and_indices() {
        #[derive(Deserialize)]
        struct C {
            c: Column,
        }
        let c: C = toml::from_str("c = \"x_mm\"").unwrap();
        assert_eq!(c.c, Column::Name("x_mm".into()));
        let c: C = toml::from_str("c = 3").unwrap();
        assert_eq!(c.c, Column::Index(3));
        let e = toml::from_str::<C>("c = 1.5").err().unwrap();
        assert!(
            e.message()
                .contains("a column name (string) or a 1-based column index (integer)"),
            "{e}"
        );
    }
}
