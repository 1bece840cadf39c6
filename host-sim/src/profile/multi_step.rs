//! `multi-step`: relaxation steps (seed 000 §3.2.3, Table B.2).

use serde::Deserialize;

use super::Profile;
use super::check::{finite, finite_non_negative, finite_positive, list_len};

/// Multi-step relaxation (seed 000 §3.2.3, Table B.2): from `preload`,
/// a linear ramp of `ramp_s` to each level in turn, each held `hold_s`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiStep {
    /// Levels in mm, in the order they are reached.
    pub levels: Vec<f64>,
    /// Duration of each ramp in s (> 0; the thesis uses 20 s).
    pub ramp_s: f64,
    /// Hold at each level in s (>= 0; the thesis uses 360 s or 3600 s).
    pub hold_s: f64,
    /// Starting level in mm (the bushing starts relaxed there).
    #[serde(default)]
    pub preload: f64,
}

impl Profile for MultiStep {
    fn duration(&self, _dt: f64) -> Result<f64, String> {
        list_len("levels", self.levels.len())?;
        for (i, &v) in self.levels.iter().enumerate() {
            finite(&format!("levels[{i}]"), v)?;
        }
        finite_positive("ramp_s", self.ramp_s)?;
        finite_non_negative("hold_s", self.hold_s)?;
        finite("preload", self.preload)?;
        Ok(self.levels.len() as f64 * (self.ramp_s + self.hold_s))
    }

    fn displacement(&self, t: f64) -> f64 {
        multi_step(&self.levels, self.ramp_s, self.hold_s, self.preload, t)
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
