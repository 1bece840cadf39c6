//! `sine`: x = preload + amplitude sin(2π f t).

use std::f64::consts::TAU;

use serde::Deserialize;

use super::check::{finite, finite_positive};
use super::{Profile, SineAt};

/// x = preload + amplitude sin(2π f t).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sine {
    /// Amplitude in mm.
    pub amplitude: f64,
    /// Frequency in Hz.
    pub frequency_hz: f64,
    /// Number of cycles.
    pub cycles: f64,
    /// Static offset in mm.
    #[serde(default)]
    pub preload: f64,
}

impl Profile for Sine {
    fn duration(&self, _dt: f64) -> Result<f64, String> {
        finite_positive("amplitude", self.amplitude)?;
        finite_positive("frequency_hz", self.frequency_hz)?;
        finite_positive("cycles", self.cycles)?;
        finite("preload", self.preload)?;
        Ok(self.cycles / self.frequency_hz)
    }

    fn displacement(&self, t: f64) -> f64 {
        self.preload + self.amplitude * libm::sin(TAU * self.frequency_hz * t)
    }

    fn sine_at(&self, _t: f64) -> Option<SineAt> {
        Some(SineAt {
            frequency_hz: self.frequency_hz,
            amplitude: self.amplitude,
        })
    }
}
