//! `hold`: a constant input.

use serde::Deserialize;

use super::Profile;
use super::check::{finite, finite_positive};

/// A constant input: x held at `preload` (in an oscillator scene, a
/// constant force: 0 gives a free decay).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hold {
    /// Duration in s.
    pub duration_s: f64,
    /// The held value, mm (N in an oscillator scene).
    #[serde(default)]
    pub preload: f64,
}

impl Profile for Hold {
    fn duration(&self, _dt: f64) -> Result<f64, String> {
        finite_positive("duration_s", self.duration_s)?;
        finite("preload", self.preload)?;
        Ok(self.duration_s)
    }

    fn displacement(&self, _t: f64) -> f64 {
        self.preload
    }
}
