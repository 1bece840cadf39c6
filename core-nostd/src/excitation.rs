//! Excitation laws a rig generates: the sine sweep.
//!
//! A test rig drives its actuator with a displacement demand that it
//! computes on board, and a host simulation replays the same demand. Both
//! call the functions here, in `f64` through libm only (IEEE basic
//! operations plus libm give the same bits on the host and on a Cortex-M,
//! so a firmware's simulated sensor and `bushing-sim` see the same
//! displacement). They run once per sample in the demand generator, not in
//! a model step: on a Cortex-M4F the f64 sine is soft-float (a few thousand
//! instructions), which a rig pays outside its force computation.
//!
//! The sweep x = x₀ + A sin φ(t), φ(t) = 2π ∫₀ᵗ f, keeps its phase
//! continuous: f rises linearly or geometrically (equal time per octave)
//! from f₀ to f₁ over the duration T and stays at f₁ beyond.

use core::f64::consts::TAU;

use crate::error::{Param, ParamError, positive};

/// sin(2π c) for a phase `c` in cycles, reduced to one cycle first so that
/// whole cycles give exactly zero and long runs keep their precision.
pub fn sin_cycles(c: f64) -> f64 {
    libm::sin(TAU * (c - libm::floor(c)))
}

/// Frequency law of a sweep.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Spacing {
    /// f(t) = f₀ (f₁/f₀)^(t/T): equal time per octave.
    #[default]
    Log,
    /// f(t) = f₀ + (f₁ - f₀) t/T.
    Linear,
}

/// A sine sweep from `f0` to `f1` Hz over `duration` s.
///
/// ```
/// use bushing::ParamError;
/// use bushing::excitation::{Spacing, Sweep};
///
/// // A log sweep from 5 to 40 Hz over 2 s.
/// let sweep = Sweep::new(5.0, 40.0, 2.0, Spacing::Log)?;
/// assert_eq!(sweep.frequency(0.0), 5.0);
/// assert!((sweep.frequency(2.0) - 40.0).abs() < 1e-9);
/// assert_eq!(sweep.unit(0.0), 0.0); // starts at rest, amplitude 1
/// // A sweep needs a positive duration.
/// assert!(Sweep::new(5.0, 40.0, 0.0, Spacing::Log).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sweep {
    f0: f64,
    f1: f64,
    duration: f64,
    spacing: Spacing,
    /// ln(f1/f0), computed once.
    log_ratio: f64,
}

impl Sweep {
    /// Checks the law: both frequencies and the duration positive and
    /// finite ([`ParamError::NotPositive`], [`ParamError::NotFinite`] naming
    /// `f_start_hz`, `f_end_hz` or `duration_s`).
    pub fn new(f0: f64, f1: f64, duration: f64, spacing: Spacing) -> Result<Self, ParamError> {
        let f0 = positive(Param::scalar("f_start_hz"), f0)?;
        let f1 = positive(Param::scalar("f_end_hz"), f1)?;
        Ok(Self {
            f0,
            f1,
            duration: positive(Param::scalar("duration_s"), duration)?,
            spacing,
            log_ratio: libm::log(f1 / f0),
        })
    }

    /// Duration of the sweep in s.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Instantaneous frequency at `t` in [0, T], Hz.
    pub fn frequency(&self, t: f64) -> f64 {
        let r = t / self.duration;
        match self.spacing {
            Spacing::Linear => self.f0 + (self.f1 - self.f0) * r,
            Spacing::Log => self.f0 * libm::exp(self.log_ratio * r),
        }
    }

    /// Phase at `t` in [0, T], in cycles: the integral of the frequency
    /// from 0.
    pub fn cycles(&self, t: f64) -> f64 {
        match self.spacing {
            Spacing::Linear => self.f0 * t + 0.5 * (self.f1 - self.f0) * t * t / self.duration,
            Spacing::Log => {
                let l = self.log_ratio;
                if l == 0.0 {
                    self.f0 * t
                } else {
                    self.f0 * self.duration / l * libm::expm1(l * t / self.duration)
                }
            }
        }
    }

    /// sin φ(t), with t clamped to [0, T].
    pub fn unit(&self, t: f64) -> f64 {
        // max/min rather than clamp: no panicking branch.
        sin_cycles(self.cycles(t.max(0.0).min(self.duration)))
    }
}

/// The code an ideal `bits`-bit two's-complement ADC of step `lsb` gives
/// for `x`: `x / lsb` rounded to nearest (ties away from zero) and clamped
/// to [-2^(bits-1), 2^(bits-1) - 1]; NaN reads 0. `bits` is clamped to
/// [2, 31]. With a power-of-two `lsb` the division and `code * lsb` are
/// exact, so a firmware that scales the code in `f32` sees the same
/// displacement as a host that quantizes in `f64`.
pub fn adc_code(x: f64, lsb: f64, bits: u32) -> i32 {
    let half = libm::ldexp(1.0, bits.clamp(2, 31) as i32 - 1);
    let q = libm::round(x / lsb);
    if q.is_nan() {
        0
    } else {
        // In range after the clamp, so the cast is exact.
        q.max(-half).min(half - 1.0) as i32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_cycles_give_zero_and_quarters_give_one() {
        assert_eq!(sin_cycles(3.0), 0.0);
        assert_eq!(sin_cycles(-2.0), 0.0);
        assert_eq!(sin_cycles(1e6 + 0.25), 1.0);
    }

    #[test]
    fn phase_is_the_integral_of_the_frequency() {
        for spacing in [Spacing::Log, Spacing::Linear] {
            let s = Sweep::new(5.0, 40.0, 2.0, spacing).unwrap();
            assert_eq!(s.cycles(0.0), 0.0);
            // Central difference of the phase against the frequency.
            for &t in &[0.1, 0.9, 1.7] {
                let h = 1e-5;
                let slope = (s.cycles(t + h) - s.cycles(t - h)) / (2.0 * h);
                assert!((slope - s.frequency(t)).abs() < 1e-6 * s.frequency(t));
            }
            assert!((s.frequency(2.0) - 40.0).abs() < 1e-12);
        }
        // Log: equal time per octave, 3 octaves in 2 s.
        let s = Sweep::new(5.0, 40.0, 2.0, Spacing::Log).unwrap();
        assert!((s.frequency(2.0 / 3.0) - 10.0).abs() < 1e-12);
    }

    #[test]
    fn adc_codes_round_to_nearest_and_saturate() {
        let lsb = 1.0 / 4096.0;
        assert_eq!(adc_code(1.0, lsb, 16), 4096);
        assert_eq!(adc_code(-1.5 / 4096.0, lsb, 16), -2);
        assert_eq!(adc_code(0.49 / 4096.0, lsb, 16), 0);
        assert_eq!(adc_code(100.0, lsb, 16), 32767);
        assert_eq!(adc_code(-100.0, lsb, 16), -32768);
        assert_eq!(adc_code(f64::NAN, lsb, 16), 0);
        assert_eq!(adc_code(f64::INFINITY, lsb, 12), 2047);
    }

    #[test]
    fn bad_laws_are_refused_by_name() {
        assert_eq!(
            Sweep::new(0.0, 1.0, 1.0, Spacing::Log),
            Err(ParamError::NotPositive {
                param: Param::scalar("f_start_hz"),
                value: 0.0
            })
        );
        assert_eq!(
            Sweep::new(1.0, 1.0, f64::NAN, Spacing::Linear),
            Err(ParamError::NotFinite {
                param: Param::scalar("duration_s")
            })
        );
    }
}
