//! Displacement profiles x(t) in mm.
//!
//! Each profile kind has its own module and implements [`Profile`]: the
//! displacement at any time ([`displacement`]), its duration after checking
//! every parameter (and so its length in steps, [`steps`]), and, where a
//! sine is being imposed, its frequency and amplitude ([`frequency_at`],
//! [`amplitude_at`]). The bushing starts
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

mod check;
mod hold;
mod multi_step;
mod replay;
mod sine;
mod stepped_sine;
mod stop_start;
mod sweep;
#[cfg(test)]
mod tests;
mod triangle;

use serde::Deserialize;

pub use hold::Hold;
pub use multi_step::MultiStep;
pub use replay::{Column, Replay, resolve};
pub use sine::Sine;
pub use stepped_sine::SteppedSine;
pub use stop_start::{StopStart, StopStartEvent, stop_start_response};
pub use sweep::{Spacing, Sweep};

tagged_table! {
    /// `[profile]`: the imposed displacement x(t) in mm. The formulas, the
    /// defaults and the bounds of each profile are in its module and
    /// `docs/scenes.md`.
    #[derive(Debug, Clone, PartialEq, Deserialize)]
    pub enum ProfileSpec, read by tag as ProfileByTag("ProfileSpec") {
        /// x = preload + amplitude sin(2π f t).
        Sine(Sine),
        /// Triangle between preload ± amplitude at constant speed.
        Triangle(triangle::Triangle),
        /// Multi-step relaxation (seed 000 §3.2.3, Table B.2).
        MultiStep(MultiStep),
        /// Stepped sines (seed 000 Fig. 3.3, Table B.2).
        SteppedSine(SteppedSine),
        /// Phase-continuous sine sweep.
        Sweep(Sweep),
        /// Stop/start transient (seed 000 §5.2.4).
        StopStart(StopStart),
        /// A constant input.
        Hold(Hold),
        /// Replay of a measured displacement from a CSV file.
        Replay(Replay),
    }
}

pub use triangle::Triangle;

/// The sine a profile imposes at some time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SineAt {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Amplitude, mm.
    pub amplitude: f64,
}

/// What every profile kind gives.
pub trait Profile {
    /// Checks every parameter (the message names the parameter and the
    /// bound it breaks) and gives the duration in s at time step `dt`.
    fn duration(&self, dt: f64) -> Result<f64, String>;
    /// Displacement at time `t` (s), mm.
    fn displacement(&self, t: f64) -> f64;
    /// The sine imposed at time `t`, if any (the instantaneous-modulus
    /// probe tracks the force and displacement at its frequency).
    fn sine_at(&self, _t: f64) -> Option<SineAt> {
        None
    }
}

impl ProfileSpec {
    /// The profile behind the table.
    pub fn profile(&self) -> &dyn Profile {
        match self {
            Self::Sine(p) => p,
            Self::Triangle(p) => p,
            Self::MultiStep(p) => p,
            Self::SteppedSine(p) => p,
            Self::Sweep(p) => p,
            Self::StopStart(p) => p,
            Self::Hold(p) => p,
            Self::Replay(p) => p,
        }
    }
}

/// Most entries of a list (levels, preloads, frequencies, amplitudes).
pub const MAX_LIST: usize = 10_000;
/// Most sine steps of a stepped-sine profile (preloads x frequencies x
/// amplitudes).
pub const MAX_SINE_STEPS: usize = 100_000;
/// Most events of a stop/start profile.
pub const MAX_EVENTS: usize = 64;
pub use crate::records::{MAX_COLUMN, MAX_CSV_BYTES, MAX_SAMPLES};

/// Number of steps of a profile at time step `dt`, or why it is unusable
/// (the message names the parameter and the bound it breaks).
pub fn steps(p: &ProfileSpec, dt: f64) -> Result<u64, String> {
    let duration = p.profile().duration(dt)?;
    let n = (duration / dt).round();
    if !(1.0..1e18).contains(&n) {
        return Err(format!("duration {duration} s gives {n} steps"));
    }
    Ok(n as u64)
}

/// Displacement at time `t` (s).
pub fn displacement(p: &ProfileSpec, t: f64) -> f64 {
    p.profile().displacement(t)
}

/// The measured force at time `t` (s), N, for a replay with a force
/// column; `None` for every other profile.
pub fn measured_force(p: &ProfileSpec, t: f64) -> Option<f64> {
    match p {
        ProfileSpec::Replay(r) => r.measured_force(t),
        _ => None,
    }
}

/// Frequency in Hz of the sine the profile imposes at time `t` (s), or
/// `None` where it is not a sine. Stepped sines give the frequency of the
/// step under way (`None` during rests, ramps and holds); a sweep gives its
/// instantaneous frequency f(t) for t in [0, duration_s].
pub fn frequency_at(p: &ProfileSpec, t: f64) -> Option<f64> {
    p.profile().sine_at(t).map(|s| s.frequency_hz)
}

/// Amplitude in mm of the sine the profile imposes at time `t` (s), or
/// `None` where it is not a sine; defined exactly where [`frequency_at`]
/// is.
pub fn amplitude_at(p: &ProfileSpec, t: f64) -> Option<f64> {
    p.profile().sine_at(t).map(|s| s.amplitude)
}
