//! The tracker's inputs and outputs: what a sensor measures, the tuning in
//! physical units, the filter and its unscented-transform parameters, the
//! start values of a mode, and what a step and a mode report.

use crate::error::{Param, ParamError, in_range};

/// What a sensor measures of the motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Measured {
    /// Displacement (eq 3.26).
    #[default]
    Displacement,
    /// Velocity (eq 3.33).
    Velocity,
    /// Acceleration (eq 3.32, derivatives of σ and ω neglected).
    Acceleration,
}

impl Measured {
    /// Order k of the time derivative.
    pub const fn order(self) -> i32 {
        match self {
            Self::Displacement => 0,
            Self::Velocity => 1,
            Self::Acceleration => 2,
        }
    }
}

/// One sensor: what it measures and the standard deviation of its noise,
/// in its own units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorSpec {
    /// Measured quantity.
    pub measured: Measured,
    /// Noise standard deviation (sensor units).
    pub noise: f64,
}

/// Parameters of the scaled unscented transform (Julier 2002; the thesis
/// gives none): with n states, `λ = α² (n + κ) - n`, sigma points
/// `x ± √(n + λ)` times the columns of the Cholesky factor of P, weights
/// `W_0^m = λ / (n + λ)`, `W_0^c = W_0^m + 1 - α² + β`,
/// `W_i = 1 / (2 (n + λ))`.
///
/// The default α = 1, β = 2, κ = 0 puts no weight on the centre point for
/// the mean and keeps every covariance weight positive, so the predicted
/// covariance is positive semi-definite by construction. κ = 3 - n (the
/// "classic" choice) gives a negative centre weight for n > 3 and is
/// refused here, as is any set with a negative covariance weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UtParams {
    /// Spread α, in (0, 1].
    pub alpha: f64,
    /// Prior-knowledge weight β >= 0 (2 for a Gaussian).
    pub beta: f64,
    /// Secondary scaling κ >= 0.
    pub kappa: f64,
}

impl Default for UtParams {
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 2.0,
            kappa: 0.0,
        }
    }
}

impl UtParams {
    /// Checked parameters.
    pub fn new(alpha: f64, beta: f64, kappa: f64) -> Result<Self, ParamError> {
        Ok(Self {
            alpha: in_range(Param::scalar("alpha"), alpha, 0.0, true, 1.0)?,
            beta: in_range(Param::scalar("beta"), beta, 0.0, false, f64::MAX)?,
            kappa: in_range(Param::scalar("kappa"), kappa, 0.0, false, f64::MAX)?,
        })
    }

    /// `(√(n + λ), W_0^m, W_0^c, W_i)` for `n` states.
    pub fn weights(&self, n: usize) -> Result<(f64, f64, f64, f64), ParamError> {
        let p = Self::new(self.alpha, self.beta, self.kappa)?;
        let n = n as f64;
        let spread = p.alpha * p.alpha * (n + p.kappa);
        let lambda = spread - n;
        let w0m = lambda / spread;
        let w0c = w0m + 1.0 - p.alpha * p.alpha + p.beta;
        if w0c < 0.0 {
            return Err(ParamError::OutOfRange {
                param: Param::scalar("alpha"),
                value: p.alpha,
                min: 0.0,
                min_open: true,
                max: 1.0,
            });
        }
        Ok((libm::sqrt(spread), w0m, w0c, 0.5 / spread))
    }
}

/// Extended or unscented filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Filter {
    /// Extended Kalman filter.
    Ekf,
    /// Unscented Kalman filter.
    Ukf(UtParams),
}

/// Tuning in physical units. The rules:
///
/// - `frequency_walk` (Hz/√s): how fast the frequency may wander, as a
///   random walk; over a time T it drifts by about `walk √T`. For a free
///   decay that softens by Δf over T, start at `Δf / √T`; 0 for a linear
///   structure. Too large makes ω noisy, too small biases it (seed 004
///   §3.2.6).
/// - `damping_walk` (1/√s): the same for the damping ratio.
/// - `amplitude_walk` (relative, 1/√s): unmodelled amplitude modulation.
/// - `initial_frequency_error` (relative), `initial_damping_error`
///   (absolute damping ratio), `initial_amplitude_error` (relative): the
///   standard deviations of the start values; too large diverges, too small
///   converges slowly to a biased value (seed 004 §3.2.6).
/// - `gate` (standard deviations): innovations beyond it are outliers and
///   skipped; `outlier_run` of them in a row make the tracker re-acquire.
/// - `fade_snr`: a mode whose predicted amplitude at every sensor is below
///   this many noise standard deviations is faded (ω, σ frozen); it comes
///   back above twice that.
/// - `max_damping`: the largest |damping ratio| accepted; `max_frequency`:
///   the largest phase step, as a fraction of Nyquist.
///
/// [`ModalTracker::new`] refuses (`OutOfRange`, with the largest value
/// allowed) a walk or an initial error whose variance in the scaled states,
/// per step or at the start, is not below [`Real::GUARD`] of the working
/// type (`2^60` in `f32`: an initial damping error up to about
/// `2^30 / (ω_0 dt)`), and likewise a sensor noise against the mode
/// amplitudes.
///
/// [`ModalTracker::new`]: super::ModalTracker::new
/// [`Real::GUARD`]: crate::real::Real::GUARD
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// Random walk of each mode's frequency, Hz/√s.
    pub frequency_walk: f64,
    /// Random walk of each damping ratio, 1/√s.
    pub damping_walk: f64,
    /// Random walk of the amplitudes, relative, 1/√s.
    pub amplitude_walk: f64,
    /// Standard deviation of the initial frequency, relative.
    pub initial_frequency_error: f64,
    /// Standard deviation of the initial damping ratio, absolute.
    pub initial_damping_error: f64,
    /// Standard deviation of the initial amplitudes, relative.
    pub initial_amplitude_error: f64,
    /// Innovation gate, in standard deviations.
    pub gate: f64,
    /// Consecutive outliers after which the tracker re-acquires.
    pub outlier_run: u32,
    /// Amplitude-to-noise ratio below which a mode fades.
    pub fade_snr: f64,
    /// Largest |damping ratio|.
    pub max_damping: f64,
    /// Largest frequency, as a fraction of Nyquist.
    pub max_frequency: f64,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            frequency_walk: 0.0,
            damping_walk: 0.0,
            amplitude_walk: 0.0,
            initial_frequency_error: 0.01,
            initial_damping_error: 0.01,
            initial_amplitude_error: 0.1,
            gate: 6.0,
            outlier_run: 8,
            fade_snr: 3.0,
            max_damping: 0.5,
            max_frequency: 0.9,
        }
    }
}

/// Start values of one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeInit {
    /// Natural frequency f_0, Hz.
    pub frequency: f64,
    /// Damping ratio ξ (negative for a growing mode).
    pub damping: f64,
}

/// What the tracker says of one mode (post-processing of eq 3.7).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModeStatus<T> {
    /// Natural frequency f_0 = ω_0 / 2π, Hz.
    pub frequency: T,
    /// Damping ratio ξ = -σ / ω_0.
    pub damping: T,
    /// Damped angular frequency ω, rad/s.
    pub omega: T,
    /// Log-decay rate σ, 1/s.
    pub sigma: T,
    /// Frozen because the mode sank into the noise.
    pub faded: bool,
}

/// Counters of one step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModalReport {
    /// Sensors whose sample updated the state.
    pub accepted: u8,
    /// Sensors whose sample was gated out.
    pub gated: u8,
    /// The tracker re-acquired after a run of outliers.
    pub reacquired: bool,
    /// The covariance had to be reset (non-finite or not positive).
    pub repaired: bool,
    /// A non-finite sample was refused.
    pub refused: bool,
}
