//! `triangle`: between preload ± amplitude at constant speed.

use serde::Deserialize;

use super::Profile;
use super::check::{finite, finite_positive};

/// Triangle between preload ± amplitude at constant speed, starting
/// upward from the preload.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Triangle {
    /// Amplitude in mm.
    pub amplitude: f64,
    /// Speed in mm/s.
    pub speed: f64,
    /// Number of cycles.
    pub cycles: f64,
    /// Static offset in mm.
    #[serde(default)]
    pub preload: f64,
}

impl Profile for Triangle {
    fn duration(&self, _dt: f64) -> Result<f64, String> {
        finite_positive("amplitude", self.amplitude)?;
        finite_positive("speed", self.speed)?;
        finite_positive("cycles", self.cycles)?;
        finite("preload", self.preload)?;
        Ok(self.cycles * 4.0 * self.amplitude / self.speed)
    }

    fn displacement(&self, t: f64) -> f64 {
        // Period 4A/v; phase 0 at the preload going up.
        let period = 4.0 * self.amplitude / self.speed;
        let u = (t / period + 0.25).rem_euclid(1.0); // 0 at the bottom
        let tri = if u < 0.5 {
            4.0 * u - 1.0
        } else {
            3.0 - 4.0 * u
        };
        self.preload + self.amplitude * tri
    }
}
