//! `sweep`: a phase-continuous sine sweep, linear or logarithmic.

use bushing::excitation::Sweep as SweepLaw;
use serde::Deserialize;

use super::check::{below_nyquist, finite, finite_positive};
use super::{Profile, SineAt};

/// Sine sweep, phase-continuous: x = preload + amplitude sin(φ(t)) with
/// φ the integral of 2π f(t), f linear or logarithmic in time from
/// `f_start_hz` to `f_end_hz` over `duration_s`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// Amplitude in mm.
    pub amplitude: f64,
    /// Frequency at t = 0 in Hz.
    pub f_start_hz: f64,
    /// Frequency at t = duration_s in Hz.
    pub f_end_hz: f64,
    /// Duration in s.
    pub duration_s: f64,
    /// Frequency law: "log" (default) or "linear".
    #[serde(default)]
    pub spacing: Spacing,
    /// Static offset in mm.
    #[serde(default)]
    pub preload: f64,
}

impl Profile for Sweep {
    fn duration(&self, dt: f64) -> Result<f64, String> {
        finite_positive("amplitude", self.amplitude)?;
        finite_positive("f_start_hz", self.f_start_hz)?;
        below_nyquist("f_start_hz", self.f_start_hz, dt)?;
        finite_positive("f_end_hz", self.f_end_hz)?;
        below_nyquist("f_end_hz", self.f_end_hz, dt)?;
        finite_positive("duration_s", self.duration_s)?;
        finite("preload", self.preload)?;
        Ok(self.duration_s)
    }

    fn displacement(&self, t: f64) -> f64 {
        // NaN for a law that fails the checks: the model refuses it.
        self.law()
            .map_or(f64::NAN, |s| self.preload + self.amplitude * s.unit(t))
    }

    fn sine_at(&self, t: f64) -> Option<SineAt> {
        let law = (0.0..=self.duration_s).contains(&t).then(|| self.law())??;
        Some(SineAt {
            frequency_hz: law.frequency(t),
            amplitude: self.amplitude,
        })
    }
}

impl Sweep {
    /// The core's sweep law ([`bushing::excitation::Sweep`]), or `None`
    /// when the parameters fail the core's checks (a profile built by hand
    /// and never passed through [`super::steps`]).
    fn law(&self) -> Option<SweepLaw> {
        SweepLaw::new(
            self.f_start_hz,
            self.f_end_hz,
            self.duration_s,
            self.spacing.into(),
        )
        .ok()
    }
}

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
