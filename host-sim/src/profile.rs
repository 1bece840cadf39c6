//! Displacement profiles x(t) in mm.

use crate::scene::ProfileSpec;

/// Number of steps of a profile at time step `dt`, or why it is unusable.
pub fn steps(p: &ProfileSpec, dt: f64) -> Result<u64, String> {
    let duration = match *p {
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
            cycles / frequency_hz
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
            cycles * 4.0 * amplitude / speed
        }
    };
    let n = (duration / dt).round();
    if !(1.0..1e18).contains(&n) {
        return Err(format!("duration {duration} s gives {n} steps"));
    }
    Ok(n as u64)
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

/// Displacement at time `t` (s).
pub fn displacement(p: &ProfileSpec, t: f64) -> f64 {
    match *p {
        ProfileSpec::Sine {
            amplitude,
            frequency_hz,
            preload,
            ..
        } => preload + amplitude * (std::f64::consts::TAU * frequency_hz * t).sin(),
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
    }
}

/// Frequency in Hz of the sine the profile imposes at time `t` (s), or
/// `None` where it is not a sine (the instantaneous-modulus plot tracks the
/// force and displacement at this frequency).
pub fn frequency_at(p: &ProfileSpec, _t: f64) -> Option<f64> {
    match *p {
        ProfileSpec::Sine { frequency_hz, .. } => Some(frequency_hz),
        ProfileSpec::Triangle { .. } => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let bad = ProfileSpec::Sine {
            amplitude: 1.0,
            frequency_hz: 0.0,
            cycles: 3.0,
            preload: 0.0,
        };
        assert!(steps(&bad, 1e-3).unwrap_err().contains("frequency_hz"));
    }
}
