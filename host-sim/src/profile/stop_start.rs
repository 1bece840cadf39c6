//! `stop-start`: a displacement proxy of the stop/start transient of
//! seed 000 §5.2.4.

use std::f64::consts::TAU;

use serde::Deserialize;

use super::check::{below_nyquist, finite, finite_non_negative, finite_positive};
use super::{MAX_EVENTS, Profile};

/// Stop/start transient, a displacement proxy of seed 000 §5.2.4: each
/// event is the response of one mode (`frequency_hz`, `damping`) to a
/// load ramped over `rise_s` whose static displacement is the event's
/// `size`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StopStart {
    /// Frequency of the mode that rings, in Hz (undamped).
    pub frequency_hz: f64,
    /// Damping ratio ζ in [0, 1).
    pub damping: f64,
    /// Rise time of each load change in s (0 for a step).
    pub rise_s: f64,
    /// Duration in s.
    pub duration_s: f64,
    /// The events, in time order.
    pub events: Vec<StopStartEvent>,
    /// Static offset in mm before the first event.
    #[serde(default)]
    pub preload: f64,
}

impl Profile for StopStart {
    fn duration(&self, dt: f64) -> Result<f64, String> {
        let Self {
            frequency_hz,
            damping,
            rise_s,
            duration_s,
            events,
            preload,
        } = self;
        let (frequency_hz, damping, rise_s, duration_s, preload) =
            (*frequency_hz, *damping, *rise_s, *duration_s, *preload);

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

    fn displacement(&self, t: f64) -> f64 {
        let mut x = self.preload;
        for e in self.events.iter().take_while(|e| e.at_s < t) {
            x += e.size
                * stop_start_response(t - e.at_s, self.frequency_hz, self.damping, self.rise_s);
        }
        x
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
