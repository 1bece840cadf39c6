//! The modal Kalman tracker of seed 004 chapter 3.
//!
//! Each mode m carries a phase step and a log-decay per sample,
//! `θ_m = ω_m dt` and `λ_m = σ_m dt`, shared by all sensors (formulation B,
//! eqs 3.43-3.45), and one analytic-signal pair `(a, b)` per sensor: the
//! sensor's displacement divided by a scale fixed at construction, so that
//! every state is of order one in `f32`. The process is the exact
//! discretisation of `ż = (σ + iω) z` (eqs 3.27-3.28):
//!
//! ```text
//! a' = e^λ (cos θ a - sin θ b),   b' = e^λ (sin θ a + cos θ b),   θ' = θ,   λ' = λ
//! ```
//!
//! and a sensor sees the sum over modes of `Re[(λ + iθ)^k (a + ib)]`: k = 0
//! displacement (eq 3.26), k = 1 velocity (eq 3.33, `λ a - θ b`), k = 2
//! acceleration (eq 3.32, `(λ² - θ²) a - 2 λ θ b`), in units of the sensor
//! times dt^k over its scale. The reported natural frequency and damping
//! ratio are the closed form of eq 3.7 for this model: `ω_0 = √(ω² + σ²)`,
//! `ξ = -σ / ω_0`.
//!
//! - **Filters**: an extended Kalman filter (Jacobians of the process and of
//!   eqs 3.26/3.32/3.33) or an unscented one (scaled unscented transform,
//!   [`UtParams`]). Both apply the sensors one by one (diagonal R, eq 3.8)
//!   and update the covariance in the Joseph form for a scalar observation,
//!   `P - K Pxzᵀ - Pxz Kᵀ + Pzz K Kᵀ`, which stays valid when a gain row is
//!   zeroed (frozen parameters), computed on one triangle and mirrored.
//! - **Structure**: F is the identity on the θ and λ rows and a scaled
//!   rotation plus two columns on each pair's rows, so the EKF prediction
//!   transforms only the pair rows and then their columns on one triangle.
//!   The UKF factors P with θ and λ first: the sigma points of the amplitude
//!   columns then share the centre's θ and λ, move linearly under the
//!   process and the sensors, and add exactly `R S Rᵀ` (S the amplitude
//!   covariance given θ and λ) to the predicted covariance, `H S Hᵀ` to Pzz
//!   and `S Hᵀ` to Pxz; only the 4 modes sigma points of the θ and λ
//!   columns are propagated one by one. This is the scaled transform for
//!   that square root of P, not an approximation (tested against all
//!   2n + 1 points).
//! - **Safety**: θ kept in (0, θ_max] below Nyquist and λ in a band given by
//!   the largest damping ratio; covariance diagonal floored; an innovation
//!   gate (outliers skipped, a run of them re-acquires); a mode whose
//!   amplitude sinks below `fade_snr` times the noise is *faded*: its ω and
//!   σ are frozen and its amplitudes kept loose until it comes back above
//!   twice that, when ω and σ get their start uncertainty again (they may
//!   have moved while the mode was gone) and are tracked again. A step
//!   that would leave a non-finite state (or meets a covariance that is not
//!   positive definite, or an innovation variance that is not positive and
//!   below [`Real::GUARD`]) is undone and the covariance reset to its start
//!   value. That value, the process noise and the sensor noise variances
//!   are checked below [`Real::GUARD`] in the working type at construction
//!   (a tuning beyond is a typed error), so the reset restores a finite
//!   covariance a step can use, and the state stays finite whatever the
//!   samples.
//! - **States**: `N = modes (2 sensors + 2)` values and an N×N covariance.
//! - **Cost** per sample, n = N states, M modes, C sensors: EKF about 6n²
//!   (prediction) + C (n² + 4Mn) multiply-adds and one division per sensor;
//!   UKF one factorisation (n³/6 multiply-adds, n - 1 Newton `1/√d`) per
//!   prediction and per sensor, (4M + 1) n²/2 for the predicted covariance
//!   and 4M observations per sensor. The rotation `e^λ (cos θ, sin θ)` is
//!   taken in `f32` from a per-mode anchor when (θ, λ) is within 2^-10 of
//!   it (a second-order series, [`ModalState`] keeps the anchor) and the
//!   sigma points' from the centre's by a fourth-order series; the sin/cos
//!   polynomial and `e^λ` run only when an anchor moves. Below 8 states
//!   (one mode) the whole step is unrolled on a copy of the state held in
//!   registers. No f64, no libm trig and no square root per sample.
//!   Guest instructions per call of `step` through a non-inlined function
//!   on Cortex-M4F (QEMU, f32; `cargo run -q -p bushing-boards --release
//!   --target thumbv7em-none-eabihf --bin kernel-cost`, family `tracker`):
//!   one mode and one accelerometer (4 states) EKF 346, UKF 1002; two modes
//!   and three accelerometers (16 states) EKF 15 283, UKF 107 020.

use super::fast::{exp_small, is_f32, min_positive, rsqrt};
use super::trig::{sin_cos, sin_cos_in_range};
use crate::error::{Param, ParamError, finite, in_range, positive};
use crate::real::Real;

/// What a sensor measures of the motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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

/// Running state: estimate, covariance and counters.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalState<T, const N: usize> {
    core: Core<T, N>,
    /// Per mode, a cached rotation `[θa, λa, e^λa cos θa, e^λa sin θa]`
    /// (see `rotation_near`).
    anchor: [[T; 4]; N],
    /// Samples gated out since the start.
    pub outliers: u32,
    /// Covariance resets since the start.
    pub repairs: u32,
    /// Re-acquisitions since the start.
    pub reacquisitions: u32,
}

/// What a step works on and an undo restores: estimate, covariance,
/// faded flags, outlier run.
#[derive(Debug, Clone, PartialEq)]
struct Core<T, const N: usize> {
    x: [T; N],
    p: [[T; N]; N],
    faded: [bool; N],
    run: u32,
}

impl<T: Real, const N: usize> ModalState<T, N> {
    /// The state vector (per mode: θ, λ, then a, b per sensor).
    pub fn x(&self) -> &[T; N] {
        &self.core.x
    }
    /// The covariance.
    pub fn covariance(&self) -> &[[T; N]; N] {
        &self.core.p
    }
}

fn sq(x: f64) -> f64 {
    x * x
}

fn powk(x: f64, k: i32) -> f64 {
    (0..k).fold(1.0, |acc, _| acc * x)
}

/// A variance the covariance starts from (and is reset to) or gains at
/// every step, formed from the tuning value `value` in units of `unit`
/// (`variance = (value unit)²`), in the working type: refused unless below
/// [`Real::GUARD`], as no step can use a covariance entry at or beyond it
/// (the pivot and innovation checks refuse it), and a start covariance that
/// overflows the type would leave a repair nothing finite to restore. The
/// error gives the largest value, `√GUARD / unit`.
fn variance<T: Real>(
    param: Param,
    value: f64,
    min_open: bool,
    variance: f64,
    unit: f64,
) -> Result<T, ParamError> {
    let guard = T::GUARD.to_f64();
    // NaN fails too.
    if variance < guard {
        Ok(T::from_f64(variance))
    } else {
        Err(ParamError::OutOfRange {
            param,
            value,
            min: 0.0,
            min_open,
            max: libm::sqrt(guard) / unit,
        })
    }
}

#[inline(always)]
fn get<T: Real>(v: &[T], i: usize) -> T {
    v.get(i).copied().unwrap_or(T::ZERO)
}

#[inline(always)]
fn put<T>(v: &mut [T], i: usize, value: T) {
    if let Some(e) = v.get_mut(i) {
        *e = value;
    }
}

#[inline(always)]
fn entry<T: Real, const N: usize>(p: &[[T; N]; N], i: usize, j: usize) -> T {
    p.get(i).map_or(T::ZERO, |r| get(r, j))
}

/// The tracker's parameters (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ModalTracker<T, const N: usize> {
    modes: usize,
    sensors: usize,
    dt: f64,
    filter: Filter,
    measured: [Measured; N],
    /// Per sensor: dt^k / scale, from a sample to the scaled state units.
    meas_gain: [T; N],
    /// Per sensor: the displacement scale (sensor units times s^k).
    scale: [T; N],
    r: [T; N],
    q_theta: T,
    q_lambda: [T; N],
    q_amp: T,
    p0: [T; N],
    floor: [T; N],
    x0: [T; N],
    theta_max: T,
    theta_min: T,
    lambda_min: T,
    lambda_max: T,
    /// Centre and half-width of the θ band, and half-width of the λ band
    /// (centred on 0), shrunk by a few ulps: inside them no clamp is needed.
    theta_mid: T,
    theta_half: T,
    lambda_half: T,
    gate2: T,
    outlier_run: u32,
    /// Per sensor: `fade_snr² r`, below which a mode fades, and four times
    /// that, above which it is back.
    fade_below: [T; N],
    fade_above: [T; N],
    ut: Weights<T>,
    /// Elimination order of the UKF's factorisation: θ and λ of every mode,
    /// then the amplitudes.
    pivots: [usize; N],
    /// True for the amplitude states.
    amplitude: [bool; N],
}

/// Scaled-UT constants in the working type, the 2(n - 2 modes) sigma points
/// of the amplitude columns folded into the centre weights (see
/// `predict_ukf`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Weights<T> {
    /// √(n + λ).
    spread: T,
    /// W_i.
    wi: T,
    /// W_i √(n + λ).
    wi_spread: T,
    /// W_0^m + 2 W_i (n - 2 modes).
    centre_mean: T,
    /// W_0^c + 2 W_i (n - 2 modes).
    centre_cov: T,
}

impl<T: Real, const N: usize> ModalTracker<T, N> {
    /// A tracker for `modes.len()` modes seen by `sensors.len()` sensors at
    /// time step `dt`. `amplitudes[m * C + c]` is the complex amplitude
    /// `(re, im)` of mode m in the signal of sensor c at the first sample,
    /// in the sensor's units (its analytic signal: the sample is the real
    /// part). N must equal `modes (2 sensors + 2)`.
    pub fn new(
        dt: f64,
        sensors: &[SensorSpec],
        modes: &[ModeInit],
        amplitudes: &[(f64, f64)],
        tuning: &Tuning,
        filter: Filter,
    ) -> Result<Self, ParamError> {
        let dt = positive(Param::scalar("dt"), dt)?;
        let (c_n, m_n) = (sensors.len(), modes.len());
        if c_n == 0 || m_n == 0 {
            return Err(ParamError::TooFew {
                param: Param::scalar(if c_n == 0 { "sensors" } else { "modes" }),
                min: 1,
                got: 0,
            });
        }
        let block = 2 * c_n + 2;
        if m_n * block != N {
            return Err(ParamError::LengthMismatch {
                param: Param::scalar("states"),
                expected: m_n * block,
                got: N,
            });
        }
        if amplitudes.len() != m_n * c_n {
            return Err(ParamError::LengthMismatch {
                param: Param::scalar("amplitudes"),
                expected: m_n * c_n,
                got: amplitudes.len(),
            });
        }
        let t = tuning;
        let walk = |name, v| in_range(Param::scalar(name), v, 0.0, false, f64::MAX);
        let f_walk = walk("frequency_walk", t.frequency_walk)?;
        let z_walk = walk("damping_walk", t.damping_walk)?;
        let a_walk = walk("amplitude_walk", t.amplitude_walk)?;
        let e_f = positive(
            Param::scalar("initial_frequency_error"),
            t.initial_frequency_error,
        )?;
        let e_z = positive(
            Param::scalar("initial_damping_error"),
            t.initial_damping_error,
        )?;
        let e_a = positive(
            Param::scalar("initial_amplitude_error"),
            t.initial_amplitude_error,
        )?;
        let gate = positive(Param::scalar("gate"), t.gate)?;
        let fade = in_range(Param::scalar("fade_snr"), t.fade_snr, 0.0, false, f64::MAX)?;
        let max_z = in_range(Param::scalar("max_damping"), t.max_damping, 0.0, true, 0.99)?;
        let max_f = in_range(
            Param::scalar("max_frequency"),
            t.max_frequency,
            0.0,
            true,
            0.99,
        )?;
        let nyquist = 0.5 / dt;
        let theta_max = core::f64::consts::PI * max_f;
        let root_dt = libm::sqrt(dt);
        let q_theta = variance(
            Param::scalar("frequency_walk"),
            f_walk,
            false,
            sq(core::f64::consts::TAU * f_walk * dt) * dt,
            core::f64::consts::TAU * dt * root_dt,
        )?;
        let q_amp = variance(
            Param::scalar("amplitude_walk"),
            a_walk,
            false,
            a_walk * a_walk * dt,
            root_dt,
        )?;
        let p0_amp = variance(
            Param::scalar("initial_amplitude_error"),
            e_a,
            true,
            e_a * e_a,
            1.0,
        )?;

        let mut me = Self {
            modes: m_n,
            sensors: c_n,
            dt,
            filter,
            measured: [Measured::Displacement; N],
            meas_gain: [T::ZERO; N],
            scale: [T::ZERO; N],
            r: [T::ZERO; N],
            q_theta,
            q_lambda: [T::ZERO; N],
            q_amp,
            p0: [T::ZERO; N],
            floor: [T::ZERO; N],
            x0: [T::ZERO; N],
            theta_max: T::from_f64(theta_max),
            theta_min: T::from_f64(theta_max * 1e-6),
            lambda_min: T::ZERO,
            lambda_max: T::ZERO,
            theta_mid: T::ZERO,
            theta_half: T::ZERO,
            lambda_half: T::ZERO,
            gate2: T::from_f64(gate * gate),
            outlier_run: t.outlier_run.max(1),
            fade_below: [T::ZERO; N],
            fade_above: [T::ZERO; N],
            ut: Weights {
                spread: T::ZERO,
                wi: T::ZERO,
                wi_spread: T::ZERO,
                centre_mean: T::ZERO,
                centre_cov: T::ZERO,
            },
            pivots: [0; N],
            amplitude: [false; N],
        };
        if let Filter::Ukf(ut) = filter {
            let (g, w0m, w0c, wi) = ut.weights(N)?;
            let folded = 2.0 * wi * (N - 2 * m_n) as f64;
            me.ut = Weights {
                spread: T::from_f64(g),
                wi: T::from_f64(wi),
                wi_spread: T::from_f64(wi * g),
                centre_mean: T::from_f64(w0m + folded),
                centre_cov: T::from_f64(w0c + folded),
            };
        }
        // Factorisation order: θ and λ of every mode first, so that the
        // square-root columns of the amplitudes leave θ and λ alone.
        let mut next = 0;
        for m in 0..m_n {
            let (ti, li) = me.theta_lambda(m);
            put(&mut me.pivots, next, ti);
            put(&mut me.pivots, next + 1, li);
            next += 2;
        }
        for m in 0..m_n {
            for c in 0..c_n {
                let (ai, bi) = me.pair(m, c);
                put(&mut me.pivots, next, ai);
                put(&mut me.pivots, next + 1, bi);
                put(&mut me.amplitude, ai, true);
                put(&mut me.amplitude, bi, true);
                next += 2;
            }
        }
        // Modes: phase step and log-decay per sample.
        let mut steps = [(0.0f64, 0.0f64); N];
        let mut largest_omega0_dt = 0.0f64;
        for (m, (mode, st)) in modes.iter().zip(steps.iter_mut()).enumerate() {
            let f = in_range(
                Param::item("frequency", m),
                mode.frequency,
                0.0,
                true,
                nyquist * max_f,
            )?;
            let z = in_range(
                Param::item("damping", m),
                mode.damping,
                -max_z,
                false,
                max_z,
            )?;
            let w0dt = core::f64::consts::TAU * f * dt;
            let theta = w0dt * libm::sqrt(1.0 - z * z);
            if theta > theta_max {
                return Err(ParamError::OutOfRange {
                    param: Param::item("frequency", m),
                    value: f,
                    min: 0.0,
                    min_open: true,
                    max: nyquist * max_f,
                });
            }
            *st = (theta, -z * w0dt);
            largest_omega0_dt = largest_omega0_dt.max(w0dt);
            let (ti, li) = me.theta_lambda(m);
            put(&mut me.x0, ti, T::from_f64(theta));
            put(&mut me.x0, li, T::from_f64(-z * w0dt));
            let e_theta = Param::scalar("initial_frequency_error");
            put(
                &mut me.p0,
                ti,
                variance(e_theta, e_f, true, sq(e_f * theta), theta)?,
            );
            let e_lambda = Param::scalar("initial_damping_error");
            put(
                &mut me.p0,
                li,
                variance(e_lambda, e_z, true, sq(e_z * w0dt), w0dt)?,
            );
            let walk = Param::scalar("damping_walk");
            let q = variance(walk, z_walk, false, sq(z_walk * w0dt) * dt, w0dt * root_dt)?;
            put(&mut me.q_lambda, m, q);
            let eps = 64.0 * T::EPSILON.to_f64();
            put(&mut me.floor, ti, T::from_f64(sq(eps * theta)));
            put(&mut me.floor, li, T::from_f64(sq(eps * w0dt)));
        }
        let lam = max_z * largest_omega0_dt;
        me.lambda_min = T::from_f64(-lam);
        me.lambda_max = T::from_f64(lam);
        let shrink = 1.0 - 8.0 * T::EPSILON.to_f64();
        let (t_lo, t_hi) = (me.theta_min.to_f64(), me.theta_max.to_f64());
        me.theta_mid = T::from_f64(0.5 * (t_lo + t_hi));
        me.theta_half =
            T::from_f64(0.5 * (t_hi - t_lo) * shrink - 4.0 * T::EPSILON.to_f64() * t_hi);
        me.lambda_half = T::from_f64(me.lambda_max.to_f64() * shrink);
        // Sensors: scale the displacement-equivalent amplitudes to one.
        for (c, s) in sensors.iter().enumerate() {
            let noise = positive(Param::item("noise", c), s.noise)?;
            let k = s.measured.order();
            let mut total = 0.0;
            let mut disp = [(0.0f64, 0.0f64); N];
            for (m, (&(theta, lambda), d)) in
                steps.iter().zip(disp.iter_mut()).take(m_n).enumerate()
            {
                let (re, im) = *amplitudes.get(m * c_n + c).unwrap_or(&(0.0, 0.0));
                let re = finite(Param::item("amplitudes", m * c_n + c), re)?;
                let im = finite(Param::item("amplitudes", m * c_n + c), im)?;
                // w dt^k / (λ + iθ)^k
                let (mut dr, mut di) = (re * powk(dt, k), im * powk(dt, k));
                for _ in 0..k {
                    let den = lambda * lambda + theta * theta;
                    let (nr, ni) = (
                        (dr * lambda + di * theta) / den,
                        (di * lambda - dr * theta) / den,
                    );
                    dr = nr;
                    di = ni;
                }
                *d = (dr, di);
                total += libm::hypot(dr, di);
            }
            if total <= 0.0 || !total.is_finite() {
                return Err(ParamError::NotPositive {
                    param: Param::item("amplitudes", c),
                    value: total,
                });
            }
            put(&mut me.measured, c, s.measured);
            put(&mut me.scale, c, T::from_f64(total));
            put(&mut me.meas_gain, c, T::from_f64(powk(dt, k) / total));
            let r = sq(noise * powk(dt, k) / total);
            let r = variance(Param::item("noise", c), noise, true, r, powk(dt, k) / total)?;
            put(&mut me.r, c, r);
            let fade2 = T::from_f64(fade * fade);
            put(&mut me.fade_below, c, fade2 * r);
            put(&mut me.fade_above, c, T::from_f64(4.0) * (fade2 * r));
            for (m, &(dr, di)) in disp.iter().take(m_n).enumerate() {
                let (ai, bi) = me.pair(m, c);
                put(&mut me.x0, ai, T::from_f64(dr / total));
                put(&mut me.x0, bi, T::from_f64(di / total));
                put(&mut me.p0, ai, p0_amp);
                put(&mut me.p0, bi, p0_amp);
                let eps = 64.0 * T::EPSILON.to_f64();
                put(&mut me.floor, ai, T::from_f64(eps * eps));
                put(&mut me.floor, bi, T::from_f64(eps * eps));
            }
        }
        Ok(me)
    }

    /// Number of modes.
    pub fn modes(&self) -> usize {
        self.modes
    }
    /// Number of sensors.
    pub fn sensors(&self) -> usize {
        self.sensors
    }
    /// Time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Number of modes for the per-sample code: a mode takes at least four
    /// states, so below eight there is one, known at compile time.
    #[inline(always)]
    fn m_n(&self) -> usize {
        if N < 8 { 1 } else { self.modes }
    }

    /// Number of sensors for the per-sample code: with one mode, `(N - 2)/2`.
    #[inline(always)]
    fn c_n(&self) -> usize {
        if N < 8 {
            N.saturating_sub(2) / 2
        } else {
            self.sensors
        }
    }

    /// State index of the t-th pivot of the UKF's factorisation.
    #[inline(always)]
    fn pivot(&self, t: usize) -> usize {
        if N < 8 {
            t
        } else {
            self.pivots.get(t).copied().unwrap_or(0)
        }
    }

    /// True for an amplitude state.
    #[inline(always)]
    fn is_amplitude(&self, i: usize) -> bool {
        if N < 8 {
            i >= 2
        } else {
            self.amplitude.get(i).copied().unwrap_or(false)
        }
    }

    /// The start state: the initial estimate and its diagonal covariance.
    pub fn start(&self) -> ModalState<T, N> {
        let mut anchor = [[T::ZERO; 4]; N];
        for (m, a) in anchor.iter_mut().enumerate().take(self.m_n()) {
            let (ti, li) = self.theta_lambda(m);
            *a = anchor_at(get(&self.x0, ti), get(&self.x0, li));
        }
        ModalState {
            core: Core {
                x: self.x0,
                p: self.start_covariance(),
                faded: [false; N],
                run: 0,
            },
            anchor,
            outliers: 0,
            repairs: 0,
            reacquisitions: 0,
        }
    }

    fn start_covariance(&self) -> [[T; N]; N] {
        let mut p = [[T::ZERO; N]; N];
        for (i, row) in p.iter_mut().enumerate() {
            put(row, i, get(&self.p0, i));
        }
        p
    }

    #[inline(always)]
    fn theta_lambda(&self, m: usize) -> (usize, usize) {
        let base = m * (2 * self.c_n() + 2);
        (base, base + 1)
    }

    #[inline(always)]
    fn pair(&self, m: usize, c: usize) -> (usize, usize) {
        let base = m * (2 * self.c_n() + 2) + 2 + 2 * c;
        (base, base + 1)
    }

    /// Frequency, damping and frozen flag of mode `m` (eq 3.7 closed form).
    pub fn mode(&self, state: &ModalState<T, N>, m: usize) -> ModeStatus<T> {
        let (ti, li) = self.theta_lambda(m);
        let (theta, lambda) = (get(&state.core.x, ti), get(&state.core.x, li));
        let inv_dt = T::from_f64(1.0 / self.dt);
        let w0dt = (theta * theta + lambda * lambda).sqrt();
        ModeStatus {
            frequency: w0dt * inv_dt * T::from_f64(1.0 / core::f64::consts::TAU),
            damping: if w0dt > T::ZERO {
                -lambda / w0dt
            } else {
                T::ZERO
            },
            omega: theta * inv_dt,
            sigma: lambda * inv_dt,
            faded: state.core.faded.get(m).copied().unwrap_or(false),
        }
    }

    /// Complex amplitude `(re, im)` of mode `m` in the displacement at
    /// sensor `c` (for velocity and acceleration sensors, the displacement
    /// whose derivative they measure), sensor units times s^k.
    pub fn displacement(&self, state: &ModalState<T, N>, m: usize, c: usize) -> (T, T) {
        let (ai, bi) = self.pair(m, c);
        let s = get(&self.scale, c) * T::from_f64(1.0 / powk(self.dt, self.measured_order(c)));
        (get(&state.core.x, ai) * s, get(&state.core.x, bi) * s)
    }

    fn measured_order(&self, c: usize) -> i32 {
        self.measured.get(c).copied().unwrap_or_default().order()
    }

    /// Rotates mode `m`'s analytic-signal pairs by `(ec, es)` (eq 3.28).
    #[inline(always)]
    fn rotate_mode(&self, x: &mut [T; N], m: usize, (ec, es): (T, T)) {
        for k in 0..self.c_n() {
            let (ai, bi) = self.pair(m, k);
            let (a, b) = (get(x, ai), get(x, bi));
            put(x, ai, ec * a - es * b);
            put(x, bi, es * a + ec * b);
        }
    }

    /// `(α, β)` such that sensor `c` reads `α a + β b` of a pair whose mode
    /// has phase step `t` and log-decay `l`: the real part of `(l + i t)^k`
    /// times `a + i b`.
    #[inline(always)]
    fn coefficients(&self, c: usize, t: T, l: T) -> (T, T) {
        match self.measured.get(c).copied().unwrap_or_default() {
            Measured::Displacement => (T::ONE, T::ZERO),
            Measured::Velocity => (l, -t),
            Measured::Acceleration => (l * l - t * t, -(T::ONE + T::ONE) * l * t),
        }
    }

    /// One sample per sensor, in sensor units (`samples[c]`): predict, then
    /// update sensor by sensor. A non-finite sample is refused for that
    /// sensor only.
    pub fn step(&self, state: &mut ModalState<T, N>, samples: &[T]) -> ModalReport {
        match self.filter {
            Filter::Ekf => self.step_as::<false>(state, samples),
            Filter::Ukf(_) => self.step_as::<true>(state, samples),
        }
    }

    /// The step of one filter, with the undo: a step that fails leaves the
    /// estimate, the flags and the outlier run as they were and the
    /// covariance at its start value.
    #[inline(always)]
    fn step_as<const UKF: bool>(&self, state: &mut ModalState<T, N>, samples: &[T]) -> ModalReport {
        let ModalState {
            core,
            anchor,
            outliers,
            reacquisitions,
            ..
        } = state;
        let (mut report, ok) = if N < 8 {
            // One mode: the step runs on a copy that the optimiser keeps in
            // registers, and the copy is the undo.
            let mut work = core.clone();
            let (report, ok) =
                self.run::<UKF>(&mut work, anchor, outliers, reacquisitions, samples);
            if ok {
                *core = work;
            }
            (report, ok)
        } else {
            // The covariance is reset on undo, so not saved.
            let (x, faded, run) = (core.x, core.faded, core.run);
            let (report, ok) = self.run::<UKF>(core, anchor, outliers, reacquisitions, samples);
            if !ok {
                core.x = x;
                core.faded = faded;
                core.run = run;
            }
            (report, ok)
        };
        if !ok {
            self.reset(state, &mut report);
        }
        report
    }

    /// Counts a repair and resets the covariance.
    #[cold]
    fn reset(&self, state: &mut ModalState<T, N>, report: &mut ModalReport) {
        state.repairs = state.repairs.saturating_add(1);
        state.core.p = self.start_covariance();
        report.repaired = true;
    }

    /// Predict and update; false when the step must be undone (covariance
    /// not positive definite, innovation variance not positive, or a
    /// non-finite result).
    #[inline(always)]
    fn run<const UKF: bool>(
        &self,
        state: &mut Core<T, N>,
        anchor: &mut [[T; 4]; N],
        outliers: &mut u32,
        reacquisitions: &mut u32,
        samples: &[T],
    ) -> (ModalReport, bool) {
        let mut report = ModalReport::default();
        if UKF {
            if !self.predict_ukf(state, anchor) {
                return (report, false);
            }
        } else {
            self.predict_ekf(state, anchor);
        }
        for c in 0..self.c_n() {
            let z = samples.get(c).copied().unwrap_or(T::ZERO);
            if !z.is_finite() {
                cold();
                report.refused = true;
                continue;
            }
            let z = z * get(&self.meas_gain, c);
            let mut v = [T::ZERO; N];
            let Some((zhat, s)) = self.innovation::<UKF>(state, c, &mut v) else {
                return (report, false);
            };
            let y = z - zhat;
            if y * y > self.gate2 * s {
                cold();
                if state.run.saturating_add(1) < self.outlier_run {
                    state.run = state.run.saturating_add(1);
                    *outliers = outliers.saturating_add(1);
                    report.gated += 1;
                    continue;
                }
                // A run of outliers: the model lost the signal. Loosen the
                // amplitudes and take the sample.
                self.loosen_amplitudes(state, None);
                *reacquisitions = reacquisitions.saturating_add(1);
                report.reacquired = true;
                state.run = 0;
                let Some((zhat, s)) = self.innovation::<UKF>(state, c, &mut v) else {
                    return (report, false);
                };
                self.update(state, &v, s, z - zhat);
            } else {
                state.run = 0;
                self.update(state, &v, s, y);
            }
            report.accepted += 1;
        }
        self.constrain(state);
        self.fade(state);
        let ok = all_finite(state);
        (report, ok)
    }

    /// Predicted sample of sensor `c`, cross-covariance into `v` and
    /// innovation variance; `None` when the covariance is not usable.
    #[inline(always)]
    fn innovation<const UKF: bool>(
        &self,
        state: &Core<T, N>,
        c: usize,
        v: &mut [T; N],
    ) -> Option<(T, T)> {
        let (zhat, s) = if UKF {
            self.innovation_ukf(state, c, v)?
        } else {
            self.innovation_ekf(state, c, v)
        };
        // Positive and finite (GUARD: a comparison rather than a test of
        // the bit pattern).
        if s > T::ZERO && s < T::GUARD {
            Some((zhat, s))
        } else {
            cold();
            None
        }
    }

    /// EKF prediction: x = f(x), P = F P Fᵀ + Q. F is the identity on the
    /// θ and λ rows; on a pair's rows it holds the rotation `(ec, es)` and
    /// the derivatives `(-b', a')`, `(a', b')` by θ and λ. First the pair
    /// rows of F P (whole rows), then their columns on and above the
    /// diagonal; `P'[θ or λ][pair] = (F P)[pair][θ or λ]` needs no second
    /// pass. The result is mirrored, so exactly symmetric.
    #[inline(always)]
    fn predict_ekf(&self, state: &mut Core<T, N>, anchor: &mut [[T; 4]; N]) {
        let (m_n, c_n) = (self.m_n(), self.c_n());
        let Core { x, p, .. } = state;
        let mut rot = [(T::ZERO, T::ZERO); N];
        for (m, (r, a)) in rot.iter_mut().zip(anchor.iter_mut()).enumerate().take(m_n) {
            let (ti, li) = self.theta_lambda(m);
            *r = rotation_cached(a, get(x, ti), get(x, li));
            self.rotate_mode(x, m, *r);
            let (ec, es) = *r;
            if N < 8 {
                // Copies of the rows, read from on and above the diagonal.
                let (row_t, row_l) = (sym_row(p, ti), sym_row(p, li));
                for c in 0..c_n {
                    let (ai, bi) = self.pair(m, c);
                    let (a1, b1) = (get(x, ai), get(x, bi));
                    let (ra, rb) = (sym_row(p, ai), sym_row(p, bi));
                    let (mut na, mut nb) = ([T::ZERO; N], [T::ZERO; N]);
                    for ((((na, nb), (&pa, &pb)), &pt), &pl) in na
                        .iter_mut()
                        .zip(nb.iter_mut())
                        .zip(ra.iter().zip(&rb))
                        .zip(&row_t)
                        .zip(&row_l)
                    {
                        *na = ec * pa - es * pb - b1 * pt + a1 * pl;
                        *nb = es * pa + ec * pb + a1 * pt + b1 * pl;
                    }
                    set_row(p, ai, na);
                    set_row(p, bi, nb);
                }
                continue;
            }
            // In place: the θ and λ rows come before the pair rows.
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                let (a1, b1) = (get(x, ai), get(x, bi));
                let Some((head, tail)) = p.split_at_mut_checked(ai) else {
                    continue;
                };
                let (Some(rt), Some(rl), [ra, rb, ..]) = (head.get(ti), head.get(li), tail) else {
                    continue;
                };
                for (((pa, pb), &pt), &pl) in ra.iter_mut().zip(rb.iter_mut()).zip(rt).zip(rl) {
                    let (va, vb) = (*pa, *pb);
                    *pa = ec * va - es * vb - b1 * pt + a1 * pl;
                    *pb = es * va + ec * vb + a1 * pt + b1 * pl;
                }
            }
        }
        // Columns of the pair rows, on and above the diagonal.
        for m in 0..m_n {
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                for i in [ai, bi] {
                    let Some(r) = p.get_mut(i) else { continue };
                    for (m2, &(ec, es)) in rot.iter().enumerate().take(m_n) {
                        let (ti, li) = self.theta_lambda(m2);
                        let (vt, vl) = (get(r, ti), get(r, li));
                        for c2 in 0..c_n {
                            let (aj, bj) = self.pair(m2, c2);
                            if bj < i {
                                continue;
                            }
                            let (a1, b1) = (get(x, aj), get(x, bj));
                            let (va, vb) = (get(r, aj), get(r, bj));
                            if aj >= i {
                                put(r, aj, ec * va - es * vb - b1 * vt + a1 * vl);
                            }
                            put(r, bj, es * va + ec * vb + a1 * vt + b1 * vl);
                        }
                    }
                }
            }
        }
        // Mirror: a pair row holds its final entries on and above the
        // diagonal; a θ or λ row finds its pair columns below it.
        for i in 0..N {
            if N < 8 {
                for j in i + 1..N {
                    if self.is_amplitude(i) {
                        let v = entry(p, i, j);
                        set(p, j, i, v);
                    } else if self.is_amplitude(j) {
                        let v = entry(p, j, i);
                        set(p, i, j, v);
                    }
                }
                continue;
            }
            let Some((top, bottom)) = p.split_at_mut_checked(i + 1) else {
                continue;
            };
            let Some(ri) = top.last_mut() else { continue };
            let pair_row = self.is_amplitude(i);
            for (rj, j) in bottom.iter_mut().zip(i + 1..) {
                if pair_row {
                    put(rj, i, get(ri, j));
                } else if self.is_amplitude(j) {
                    put(ri, j, get(rj, i));
                }
            }
        }
        self.add_process_noise(state);
    }

    #[inline(always)]
    fn add_process_noise(&self, state: &mut Core<T, N>) {
        for m in 0..self.m_n() {
            let frozen = state.faded.get(m).copied().unwrap_or(false);
            let (ti, li) = self.theta_lambda(m);
            if !frozen {
                add_diag(&mut state.p, ti, self.q_theta);
                add_diag(&mut state.p, li, get(&self.q_lambda, m));
            }
            for c in 0..self.c_n() {
                let (ai, bi) = self.pair(m, c);
                add_diag(&mut state.p, ai, self.q_amp);
                add_diag(&mut state.p, bi, self.q_amp);
            }
        }
    }

    /// EKF innovation of sensor `c`: predicted sample, `v = P hᵀ`, and
    /// `s = h P hᵀ + r`; h has four entries per mode.
    #[inline(always)]
    fn innovation_ekf(&self, state: &Core<T, N>, c: usize, v: &mut [T; N]) -> (T, T) {
        match self.measured.get(c).copied().unwrap_or_default() {
            Measured::Displacement => self.innovation_ekf_k::<0>(state, c, v),
            Measured::Velocity => self.innovation_ekf_k::<1>(state, c, v),
            Measured::Acceleration => self.innovation_ekf_k::<2>(state, c, v),
        }
    }

    /// [`Self::innovation_ekf`] for a sensor of derivative order K.
    #[inline(always)]
    fn innovation_ekf_k<const K: u8>(
        &self,
        state: &Core<T, N>,
        c: usize,
        v: &mut [T; N],
    ) -> (T, T) {
        let m_n = self.m_n();
        let mut idx = [0usize; N];
        let mut h = [T::ZERO; N];
        let mut zhat = T::ZERO;
        for m in 0..m_n {
            let (ti, li) = self.theta_lambda(m);
            let (ai, bi) = self.pair(m, c);
            let x = &state.x;
            let (z, g) = observe::<T, K>(get(x, ti), get(x, li), get(x, ai), get(x, bi));
            zhat += z;
            for (k, (i, gi)) in [ti, li, ai, bi].into_iter().zip(g).enumerate() {
                put(&mut idx, 4 * m + k, i);
                put(&mut h, 4 * m + k, gi);
            }
        }
        let used = 4 * m_n;
        if N < 8 {
            for (i, vi) in v.iter_mut().enumerate() {
                // A copy read from on and above the diagonal.
                let row = sym_row(&state.p, i);
                // From the first product, not from zero (0 + x is not folded).
                let first = get(&row, idx.first().copied().unwrap_or(0)) * get(&h, 0);
                *vi = idx
                    .iter()
                    .zip(&h)
                    .take(used)
                    .skip(1)
                    .fold(first, |acc, (&j, &hj)| acc + get(&row, j) * hj);
            }
        } else {
            // P is symmetric: v is the sum of h_j times row j, whole rows.
            *v = [T::ZERO; N];
            for (&j, &hj) in idx.iter().zip(&h).take(used) {
                if let Some(rj) = state.p.get(j) {
                    for (vi, &pj) in v.iter_mut().zip(rj) {
                        *vi += pj * hj;
                    }
                }
            }
        }
        let mut s = get(&self.r, c);
        for (&j, &hj) in idx.iter().zip(&h).take(used) {
            s += get(v, j) * hj;
        }
        (zhat, s)
    }

    /// Factorisation for the sigma points, in the order θ, λ of every mode,
    /// then the amplitudes: `cols[t]` gets column t of the lower Cholesky
    /// factor for the 2 modes θ and λ pivots (zero on the states eliminated
    /// before), `schur` the covariance of the amplitudes given θ and λ,
    /// `P - Σ_t cols[t] cols[t]ᵀ` (its amplitude block; the rest is
    /// meaningless), which is all the amplitude columns contribute (see
    /// `predict_ukf`). The amplitude pivots are still eliminated to check
    /// that P is positive definite; false if not. `1/√d` per pivot by
    /// Newton's method, no division.
    #[inline(always)]
    fn factor(&self, p: &[[T; N]; N], cols: &mut [[T; N]; N], schur: &mut [[T; N]; N]) -> bool {
        if N < 8 {
            return factor_natural(p, cols, schur);
        }
        // Permuted to the pivot order and factored right-looking: after
        // pivot t the rows below hold the Schur complement on and below the
        // diagonal (what lies elsewhere is never read). Whole-row updates
        // (the column's zeros leave the eliminated part alone) unroll and
        // need no bounds per entry.
        let k_n = 2 * self.m_n();
        let mut w = [[T::ZERO; N]; N];
        for (i, row) in w.iter_mut().enumerate() {
            let pi = self.pivot(i);
            for (j, v) in row.iter_mut().enumerate().take(i + 1) {
                *v = entry(p, pi, self.pivot(j));
            }
        }
        for t in 0..N {
            let d = entry(&w, t, t);
            if !pivot_ok(d) {
                return false;
            }
            if t + 1 == N {
                break;
            }
            let r = rsqrt(d);
            let mut l = [T::ZERO; N];
            for (li, row) in l.iter_mut().zip(&w).skip(t + 1) {
                *li = get(row, t) * r;
            }
            for (row, &li) in w.iter_mut().zip(&l).skip(t + 1) {
                for (v, &lj) in row.iter_mut().zip(&l) {
                    *v -= li * lj;
                }
            }
            if t < k_n {
                if let Some(col) = cols.get_mut(t) {
                    *col = [T::ZERO; N];
                    put(col, self.pivot(t), d * r);
                    for (i, &li) in l.iter().enumerate().skip(t + 1) {
                        put(col, self.pivot(i), li);
                    }
                }
                if t + 1 == k_n {
                    for (i, row) in w.iter().enumerate().skip(k_n) {
                        let pi = self.pivot(i);
                        for (j, &v) in row.iter().enumerate().take(i + 1).skip(k_n) {
                            let pj = self.pivot(j);
                            set(schur, pi, pj, v);
                            set(schur, pj, pi, v);
                        }
                    }
                }
            }
        }
        true
    }

    /// UKF prediction. With θ and λ factored first, the sigma points of the
    /// amplitude columns `x ± γ l_t` share the centre's θ and λ, so the
    /// process moves them linearly: `f(x) ± γ R l_t`, R the centre's
    /// rotations. Their 2(n - 2 modes) points then add `2 W_i` times the
    /// centre's deviation each (folded into the centre weights) and, as
    /// `2 W_i γ² = 1`, exactly `R S Rᵀ` to the covariance, S the amplitude
    /// covariance given θ and λ. Only the 4 modes points of the θ and λ
    /// columns go through the rotation polynomials. The result is the scaled
    /// unscented transform with this square root of P, not an approximation.
    #[inline(always)]
    fn predict_ukf(&self, state: &mut Core<T, N>, anchor: &mut [[T; 4]; N]) -> bool {
        let mut cols = [[T::ZERO; N]; N];
        let mut schur = [[T::ZERO; N]; N];
        if !self.factor(&state.p, &mut cols, &mut schur) {
            return false;
        }
        let (m_n, k_n) = (self.m_n(), 2 * self.m_n());
        let w = self.ut;
        let x = state.x;
        let mut rot = [(T::ZERO, T::ZERO); N];
        let mut f0 = x;
        for (m, (r, a)) in rot.iter_mut().zip(anchor.iter_mut()).enumerate().take(m_n) {
            let (ti, li) = self.theta_lambda(m);
            *r = rotation_cached(a, get(&x, ti), get(&x, li));
            self.rotate_mode(&mut f0, m, *r);
        }
        // The θ and λ columns: column t is zero on the θ and λ of the
        // modes before mode t/2, whose rotation is then the centre's.
        let mut plus = [[T::ZERO; N]; N];
        let mut minus = [[T::ZERO; N]; N];
        for (t, ((l, xp), xm)) in cols
            .iter()
            .zip(plus.iter_mut())
            .zip(minus.iter_mut())
            .take(k_n)
            .enumerate()
        {
            for (((p, n), &xi), &li) in xp.iter_mut().zip(xm.iter_mut()).zip(&x).zip(l) {
                let d = w.spread * li;
                *p = xi + d;
                *n = xi - d;
            }
            for (m, &r) in rot.iter().enumerate().take(m_n) {
                let (rp, rn) = if 2 * m + 1 >= t {
                    let (ti, li) = self.theta_lambda(m);
                    let g = w.spread;
                    let [rp, rn] =
                        rotation_pair(get(&x, ti), get(&x, li), g * get(l, ti), g * get(l, li), r);
                    (rp, rn)
                } else {
                    (r, r)
                };
                self.rotate_mode(xp, m, rp);
                self.rotate_mode(xm, m, rn);
            }
        }
        let mut mean = [T::ZERO; N];
        for (i, m) in mean.iter_mut().enumerate() {
            let mut acc = T::ZERO;
            for (xp, xm) in plus.iter().zip(&minus).take(k_n) {
                acc += get(xp, i) + get(xm, i);
            }
            *m = w.centre_mean * get(&f0, i) + w.wi * acc;
        }
        let mut d0 = f0;
        for (d, m) in d0.iter_mut().zip(&mean) {
            *d -= *m;
        }
        for (xp, xm) in plus.iter_mut().zip(minus.iter_mut()).take(k_n) {
            for ((p, n), m) in xp.iter_mut().zip(xm.iter_mut()).zip(&mean) {
                *p -= *m;
                *n -= *m;
            }
        }
        let p = &mut state.p;
        for i in 0..N {
            let di = get(&d0, i);
            for j in 0..N {
                if j < i {
                    continue;
                }
                let mut acc = T::ZERO;
                for (xp, xm) in plus.iter().zip(&minus).take(k_n) {
                    acc += get(xp, i) * get(xp, j) + get(xm, i) * get(xm, j);
                }
                let v = w.centre_cov * di * get(&d0, j) + w.wi * acc;
                set(p, i, j, v);
                set(p, j, i, v);
            }
        }
        self.add_rotated(p, &schur, &rot);
        state.x = mean;
        self.add_process_noise(state);
        true
    }

    /// `p += R S Rᵀ` on the amplitude block, R the rotation of each mode's
    /// pairs: first the rows, then the columns on and above the diagonal,
    /// mirrored.
    #[inline(always)]
    fn add_rotated(&self, p: &mut [[T; N]; N], s: &[[T; N]; N], rot: &[(T, T); N]) {
        let (m_n, c_n) = (self.m_n(), self.c_n());
        let mut rs = [[T::ZERO; N]; N];
        for (m, &(ec, es)) in rot.iter().enumerate().take(m_n) {
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                let (sa, sb) = (sym_row(s, ai), sym_row(s, bi));
                let (mut na, mut nb) = ([T::ZERO; N], [T::ZERO; N]);
                for (j, (na, nb)) in na.iter_mut().zip(nb.iter_mut()).enumerate() {
                    if self.is_amplitude(j) {
                        let (va, vb) = (get(&sa, j), get(&sb, j));
                        *na = ec * va - es * vb;
                        *nb = es * va + ec * vb;
                    }
                }
                set_row(&mut rs, ai, na);
                set_row(&mut rs, bi, nb);
            }
        }
        for m in 0..m_n {
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                for i in [ai, bi] {
                    let r = row(&rs, i);
                    for (m2, &(ec, es)) in rot.iter().enumerate().take(m_n) {
                        for c2 in 0..c_n {
                            let (aj, bj) = self.pair(m2, c2);
                            if bj < i {
                                continue;
                            }
                            let (va, vb) = (get(&r, aj), get(&r, bj));
                            if aj >= i {
                                let v = entry(p, i, aj) + (ec * va - es * vb);
                                set(p, i, aj, v);
                                set(p, aj, i, v);
                            }
                            let v = entry(p, i, bj) + (es * va + ec * vb);
                            set(p, i, bj, v);
                            set(p, bj, i, v);
                        }
                    }
                }
            }
        }
    }

    /// UKF innovation of sensor `c` with sigma points redrawn from the
    /// current estimate: predicted sample, `v = Pxz`, `s = Pzz + r`. As in
    /// the prediction, the amplitude columns see the sensor's linear
    /// coefficients H at the centre (`z = H x` for fixed θ, λ) and add
    /// exactly `H S Hᵀ` to Pzz and `S Hᵀ` to Pxz; only the θ and λ columns
    /// are observed point by point.
    #[inline(always)]
    fn innovation_ukf(&self, state: &Core<T, N>, c: usize, v: &mut [T; N]) -> Option<(T, T)> {
        let mut cols = [[T::ZERO; N]; N];
        let mut schur = [[T::ZERO; N]; N];
        if !self.factor(&state.p, &mut cols, &mut schur) {
            return None;
        }
        let (m_n, k_n) = (self.m_n(), 2 * self.m_n());
        let w = self.ut;
        let x = &state.x;
        let mut h = [(T::ZERO, T::ZERO); N];
        let mut z0 = T::ZERO;
        for (m, hm) in h.iter_mut().enumerate().take(m_n) {
            let (ti, li) = self.theta_lambda(m);
            let (ai, bi) = self.pair(m, c);
            *hm = self.coefficients(c, get(x, ti), get(x, li));
            z0 += hm.0 * get(x, ai) + hm.1 * get(x, bi);
        }
        let mut zp = [T::ZERO; N];
        let mut zm = [T::ZERO; N];
        let mut sum = T::ZERO;
        for ((l, zp), zm) in cols.iter().zip(zp.iter_mut()).zip(zm.iter_mut()).take(k_n) {
            let (mut a, mut b) = (T::ZERO, T::ZERO);
            for m in 0..m_n {
                let (ti, li) = self.theta_lambda(m);
                let (ai, bi) = self.pair(m, c);
                let g = w.spread;
                let (dt, dl) = (g * get(l, ti), g * get(l, li));
                let (da, db) = (g * get(l, ai), g * get(l, bi));
                let (t0, l0, a0, b0) = (get(x, ti), get(x, li), get(x, ai), get(x, bi));
                let (hp, hq) = self.coefficients(c, t0 + dt, l0 + dl);
                a += hp * (a0 + da) + hq * (b0 + db);
                let (hp, hq) = self.coefficients(c, t0 - dt, l0 - dl);
                b += hp * (a0 - da) + hq * (b0 - db);
            }
            *zp = a;
            *zm = b;
            sum += a + b;
        }
        let zhat = w.centre_mean * z0 + w.wi * sum;
        // u = S Hᵀ (amplitude rows), then H S Hᵀ.
        let mut u = [T::ZERO; N];
        for (i, ui) in u.iter_mut().enumerate() {
            if !self.is_amplitude(i) {
                continue;
            }
            let r = sym_row(&schur, i);
            let mut acc = T::ZERO;
            for (m, &(hp, hq)) in h.iter().enumerate().take(m_n) {
                let (ai, bi) = self.pair(m, c);
                acc += hp * get(&r, ai) + hq * get(&r, bi);
            }
            *ui = acc;
        }
        let dz = z0 - zhat;
        let mut s = w.centre_cov * dz * dz + get(&self.r, c);
        for (m, &(hp, hq)) in h.iter().enumerate().take(m_n) {
            let (ai, bi) = self.pair(m, c);
            s += hp * get(&u, ai) + hq * get(&u, bi);
        }
        let mut spread = T::ZERO;
        for (a, b) in zp.iter().zip(&zm).take(k_n) {
            let (da, db) = (*a - zhat, *b - zhat);
            spread += da * da + db * db;
        }
        s += w.wi * spread;
        // Pxz = W_i γ Σ_t l_t (Z_t^+ - Z_t^-) over θ and λ columns, + S Hᵀ.
        for (i, (vi, ui)) in v.iter_mut().zip(&u).enumerate() {
            let mut acc = T::ZERO;
            for ((l, a), b) in cols.iter().zip(&zp).zip(&zm).take(k_n) {
                acc += get(l, i) * (*a - *b);
            }
            *vi = w.wi_spread * acc + *ui;
        }
        Some((zhat, s))
    }

    /// Scalar update with cross-covariance `v`, innovation variance `s` and
    /// innovation `y`, in the Joseph form `P - K vᵀ - v Kᵀ + s K Kᵀ`
    /// (valid for the frozen rows' zero gain), as `P + K uᵀ - v Kᵀ` with
    /// `u = s K - v` (zero but for rounding where the gain is not frozen),
    /// on and above the diagonal, mirrored.
    #[inline(always)]
    fn update(&self, state: &mut Core<T, N>, v: &[T; N], s: T, y: T) {
        let inv = T::ONE / s;
        let mut k = [T::ZERO; N];
        for (ki, vi) in k.iter_mut().zip(v) {
            *ki = *vi * inv;
        }
        for m in 0..self.m_n() {
            if state.faded.get(m).copied().unwrap_or(false) {
                let (ti, li) = self.theta_lambda(m);
                put(&mut k, ti, T::ZERO);
                put(&mut k, li, T::ZERO);
            }
        }
        for (xi, ki) in state.x.iter_mut().zip(&k) {
            *xi += *ki * y;
        }
        let mut u = [T::ZERO; N];
        for ((ui, ki), vi) in u.iter_mut().zip(&k).zip(v) {
            *ui = s * *ki - *vi;
        }
        let p = &mut state.p;
        if N < 8 {
            // Fully unrolled: every entry a register.
            for i in 0..N {
                let (ki, vi) = (get(&k, i), get(v, i));
                for j in i..N {
                    let (kj, uj) = (get(&k, j), get(&u, j));
                    let val = entry(p, i, j) + ki * uj - vi * kj;
                    set(p, i, j, val);
                    set(p, j, i, val);
                }
            }
            return;
        }
        for (i, (row, (&ki, &vi))) in p.iter_mut().zip(k.iter().zip(v)).enumerate() {
            let (Some(r), Some(kt), Some(ut)) = (row.get_mut(i..), k.get(i..), u.get(i..)) else {
                continue;
            };
            for ((pij, &kj), &uj) in r.iter_mut().zip(kt).zip(ut) {
                *pij = *pij + ki * uj - vi * kj;
            }
        }
        mirror_upper(p);
    }

    /// θ and λ into their bands, the diagonal above its floor.
    #[inline(always)]
    fn constrain(&self, state: &mut Core<T, N>) {
        for m in 0..self.m_n() {
            let (ti, li) = self.theta_lambda(m);
            // One comparison each when well inside the band (NaN fails it).
            let t = get(&state.x, ti);
            let inside = (t - self.theta_mid).abs() <= self.theta_half;
            if !inside {
                cold();
                put(&mut state.x, ti, clamp(t, self.theta_min, self.theta_max));
            }
            let l = get(&state.x, li);
            let inside = l.abs() <= self.lambda_half;
            if !inside {
                cold();
                put(&mut state.x, li, clamp(l, self.lambda_min, self.lambda_max));
            }
        }
        for (i, (row, &floor)) in state.p.iter_mut().zip(&self.floor).enumerate() {
            if let Some(v) = row.get_mut(i)
                && *v < floor
            {
                cold();
                *v = floor;
            }
        }
    }

    /// Marks modes faded or back, keeps a faded mode's amplitudes loose and
    /// gives a returning mode's ω and σ their start uncertainty.
    #[inline(always)]
    fn fade(&self, state: &mut Core<T, N>) {
        for m in 0..self.m_n() {
            let (ti, li) = self.theta_lambda(m);
            let (t, l) = (get(&state.x, ti), get(&state.x, li));
            let rate2 = t * t + l * l;
            let was = state.faded.get(m).copied().unwrap_or(false);
            // Faded: stays so unless above the upper threshold at a sensor;
            // not faded: fades when below the lower one at every sensor.
            let mut now = true;
            for c in 0..self.c_n() {
                if !was && !now {
                    break;
                }
                let (ai, bi) = self.pair(m, c);
                let (a, b) = (get(&state.x, ai), get(&state.x, bi));
                let mut amp2 = a * a + b * b;
                match self.measured.get(c).copied().unwrap_or_default() {
                    Measured::Displacement => {}
                    Measured::Velocity => amp2 *= rate2,
                    Measured::Acceleration => {
                        amp2 *= rate2;
                        amp2 *= rate2;
                    }
                }
                let still = if was {
                    let above = amp2 > get(&self.fade_above, c);
                    !above
                } else {
                    amp2 < get(&self.fade_below, c)
                };
                now &= still;
            }
            if !now && !was {
                continue;
            }
            cold();
            put(&mut state.faded, m, now);
            if now {
                self.loosen_amplitudes(state, Some(m));
            } else if was {
                // Back: the frequency and damping may have moved while the
                // mode was gone, so they are as uncertain as at the start.
                self.loosen(state, ti);
                self.loosen(state, li);
            }
        }
    }

    /// Raises the amplitude variances of mode `m` (or of every mode) to their
    /// start values and drops their correlations.
    #[inline(always)]
    fn loosen_amplitudes(&self, state: &mut Core<T, N>, mode: Option<usize>) {
        for m in 0..self.m_n() {
            if mode.is_some_and(|x| x != m) {
                continue;
            }
            for c in 0..self.c_n() {
                let (ai, bi) = self.pair(m, c);
                self.loosen(state, ai);
                self.loosen(state, bi);
            }
        }
    }

    /// Raises the variance of state `i` to its start value, if below, and
    /// drops its correlations.
    #[inline(always)]
    fn loosen(&self, state: &mut Core<T, N>, i: usize) {
        let p0 = get(&self.p0, i);
        if entry(&state.p, i, i) < p0 {
            for j in 0..N {
                if j != i {
                    set(&mut state.p, i, j, T::ZERO);
                    set(&mut state.p, j, i, T::ZERO);
                }
            }
            set(&mut state.p, i, i, p0);
        }
    }
}

/// Predicted sample of a sensor of derivative order K (scaled) from one
/// mode with phase step `t`, log-decay `l` and pair `(a, b)`, and its
/// gradient by (θ, λ, a, b): the real part of `(l + i t)^K (a + i b)`.
#[inline(always)]
fn observe<T: Real, const K: u8>(t: T, l: T, a: T, b: T) -> (T, [T; 4]) {
    let two = T::ONE + T::ONE;
    match K {
        0 => (a, [T::ZERO, T::ZERO, T::ONE, T::ZERO]),
        1 => (l * a - t * b, [-b, a, l, -t]),
        _ => {
            let (ca, cb) = (l * l - t * t, -two * l * t);
            (
                ca * a + cb * b,
                [-two * (t * a + l * b), two * (l * a - t * b), ca, cb],
            )
        }
    }
}

/// `(e^λ cos θ, e^λ sin θ)`: one sin/cos polynomial and one exponential.
#[inline(always)]
fn rotation<T: Real>(theta: T, lambda: T) -> (T, T) {
    let (s, c) = sin_cos(theta);
    let e = exp_small(lambda);
    (e * c, e * s)
}

/// [`ModalTracker::factor`] for one mode, whose θ and λ come first: the
/// plain right-looking Cholesky order, with loops the optimiser unrolls.
#[inline(always)]
fn factor_natural<T: Real, const N: usize>(
    p: &[[T; N]; N],
    cols: &mut [[T; N]; N],
    schur: &mut [[T; N]; N],
) -> bool {
    let mut w = *p;
    for t in 0..N {
        let d = entry(&w, t, t);
        if !pivot_ok(d) {
            return false;
        }
        if t + 1 == N {
            break;
        }
        let r = rsqrt(d);
        // Constant trip counts and masks, so that the loops unroll.
        let mut l = [T::ZERO; N];
        for (i, li) in l.iter_mut().enumerate() {
            if i > t {
                *li = entry(&w, i, t) * r;
            }
        }
        for i in 0..N {
            let li = get(&l, i);
            for j in 0..N {
                if i > t && j >= i {
                    let v = entry(&w, i, j) - li * get(&l, j);
                    set(&mut w, i, j, v);
                    set(&mut w, j, i, v);
                }
            }
        }
        if t < 2 {
            put(&mut l, t, d * r);
            if let Some(col) = cols.get_mut(t) {
                *col = l;
            }
            if t == 1 {
                *schur = w;
            }
        }
    }
    true
}

/// A usable pivot: positive (and normal, for [`rsqrt`]) and below GUARD
/// (finite; a larger variance of these scaled states is a diverged filter).
#[inline(always)]
fn pivot_ok<T: Real>(d: T) -> bool {
    d > min_positive::<T>() && d < T::GUARD
}

/// Rotations `e^(λ ± δλ) (cos(θ ± δθ), sin(θ ± δθ))` of a pair of sigma
/// points from the centre's `(ec, es)`: `e^(±d)`, `d = δλ + iδθ`, from the
/// even and odd parts of its series, `1 + d²/2 + d⁴/24` and `d + d³/6`, when
/// `f32` and |δθ| + |δλ| <= 1/32 (truncation below |d|⁵/120 = 2.6e-10,
/// under the rounding) and θ - δθ >= 0 (θ + δθ stays below π, as θ <=
/// 0.99 π); else by the polynomials, which clamp θ into [0, π].
#[inline(always)]
fn rotation_pair<T: Real>(theta: T, lambda: T, dt: T, dl: T, (ec, es): (T, T)) -> [(T, T); 2] {
    let adt = dt.abs();
    if is_f32::<T>() && adt + dl.abs() <= T::from_f64(1.0 / 32.0) && adt <= theta {
        let (d2r, d2i) = (dl * dl - dt * dt, (dl + dl) * dt);
        let (d4r, d4i) = (d2r * d2r - d2i * d2i, (d2r + d2r) * d2i);
        let c = |k: f64| T::from_f64(1.0 / k);
        let (er, ei) = (
            T::ONE + (T::HALF * d2r + c(24.0) * d4r),
            T::HALF * d2i + c(24.0) * d4i,
        );
        let (qr, qi) = (T::ONE + c(6.0) * d2r, c(6.0) * d2i);
        let (or, oi) = (dl * qr - dt * qi, dl * qi + dt * qr);
        let turn = |(ar, ai): (T, T)| (ec * ar - es * ai, ec * ai + es * ar);
        [turn((er + or, ei + oi)), turn((er - or, ei - oi))]
    } else {
        rotation_pair_far(theta, lambda, dt, dl)
    }
}

/// [`rotation_pair`] by the polynomials (out of line: rare once the filter
/// has converged, and it keeps the callers' loops small enough to unroll).
#[cold]
#[inline(never)]
fn rotation_pair_far<T: Real>(theta: T, lambda: T, dt: T, dl: T) -> [(T, T); 2] {
    [
        rotation(theta + dt, lambda + dl),
        rotation(theta - dt, lambda - dl),
    ]
}

/// Radius in |Δθ| + |Δλ| within which a rotation is taken from an anchor.
const ANCHOR_RADIUS: f64 = 1.0 / 1024.0;

/// The anchor `[θa, λa, e^λa cos θa, e^λa sin θa]` at an estimate's (θ, λ);
/// θa is NaN (no point is near it) below twice the radius, where a sigma
/// point near it could have a negative θ, which [`rotation`] clamps.
#[inline(always)]
fn anchor_at<T: Real>(theta: T, lambda: T) -> [T; 4] {
    let (c, s) = rotation_in_range(theta, lambda);
    let ta = if theta >= T::from_f64(2.0 * ANCHOR_RADIUS) {
        theta
    } else {
        T::from_f64(f64::NAN)
    };
    [ta, lambda, c, s]
}

/// [`anchor_at`] out of line, for the rare refresh.
#[cold]
#[inline(never)]
fn anchor_far<T: Real>(theta: T, lambda: T) -> [T; 4] {
    anchor_at(theta, lambda)
}

/// `(e^λ cos θ, e^λ sin θ)` in `f32` from an anchor when (θ, λ) is within
/// `ANCHOR_RADIUS` of it: `e^(λ + iθ) = e^(λa + iθa) e^d` with
/// `d = Δλ + iΔθ` and `e^d = 1 + d + d²/2` (the next term, below
/// |d|³/6 = 1.6e-10, is under the rounding of `f32`). About 12
/// instructions instead of about 50 for the polynomials. `None` farther
/// away and for other types.
#[inline(always)]
fn rotation_near<T: Real>(anchor: &[T; 4], theta: T, lambda: T) -> Option<(T, T)> {
    if !is_f32::<T>() {
        return None;
    }
    let [ta, la, ca, sa] = *anchor;
    let (dt, dl) = (theta - ta, lambda - la);
    let near = dt.abs() + dl.abs() <= T::from_f64(ANCHOR_RADIUS);
    if !near {
        return None;
    }
    let er = dl + T::HALF * (dl * dl - dt * dt);
    let ei = dt + dl * dt;
    Some((ca + (ca * er - sa * ei), sa + (ca * ei + sa * er)))
}

/// The rotation of an estimate's (θ, λ): from the mode's anchor when near
/// it, else by the polynomials, which become the new anchor.
#[inline(always)]
fn rotation_cached<T: Real>(anchor: &mut [T; 4], theta: T, lambda: T) -> (T, T) {
    if let Some(r) = rotation_near(anchor, theta, lambda) {
        return r;
    }
    let a = anchor_far(theta, lambda);
    *anchor = a;
    let [_, _, c, s] = a;
    (c, s)
}

/// The same for an estimate's θ, which [`ModalTracker::step`] keeps in
/// (0, θ_max] ⊂ (0, π).
#[inline(always)]
fn rotation_in_range<T: Real>(theta: T, lambda: T) -> (T, T) {
    let (s, c) = sin_cos_in_range(theta);
    let e = exp_small(lambda);
    (e * c, e * s)
}

/// True when the estimate and the covariance are finite: their sum is,
/// unless a huge finite entry overflowed it, which the entry-wise check
/// then tells apart.
#[inline(always)]
fn all_finite<T: Real, const N: usize>(state: &Core<T, N>) -> bool {
    let mut acc = state.x.first().copied().unwrap_or(T::ZERO);
    for v in state.x.iter().skip(1) {
        acc += *v;
    }
    for (i, row) in state.p.iter().enumerate() {
        if N < 8 {
            for v in row.iter().skip(i) {
                acc += *v;
            }
        } else {
            for v in row.get(i..).unwrap_or(&[]) {
                acc += *v;
            }
        }
    }
    acc.is_finite()
        || (state.x.iter().all(|v| v.is_finite())
            && state.p.iter().all(|r| r.iter().all(|v| v.is_finite())))
}

/// Marks the path that calls it as rare, so that the optimiser branches
/// around it rather than computing it into selects.
#[cold]
#[inline(never)]
fn cold() {}

/// `v.max(lo).min(hi)` for `lo <= hi` (NaN gives `lo`) by comparisons:
/// `f32::max` is a libm call on a Cortex-M4F.
#[inline(always)]
pub(crate) fn clamp<T: Real>(v: T, lo: T, hi: T) -> T {
    if v >= lo {
        if v > hi { hi } else { v }
    } else {
        lo
    }
}

/// Row i of a matrix.
#[inline(always)]
fn row<T: Real, const N: usize>(p: &[[T; N]; N], i: usize) -> [T; N] {
    p.get(i).copied().unwrap_or([T::ZERO; N])
}

/// Row i of a symmetric matrix; below 8 states read from the entries on
/// and above the diagonal (fewer loads once the step is inlined).
#[inline(always)]
fn sym_row<T: Real, const N: usize>(p: &[[T; N]; N], i: usize) -> [T; N] {
    if N < 8 {
        let mut r = [T::ZERO; N];
        for (j, v) in r.iter_mut().enumerate() {
            *v = entry(p, i.min(j), i.max(j));
        }
        r
    } else {
        p.get(i).copied().unwrap_or([T::ZERO; N])
    }
}

#[inline(always)]
fn set_row<T, const N: usize>(p: &mut [[T; N]; N], i: usize, r: [T; N]) {
    if let Some(dst) = p.get_mut(i) {
        *dst = r;
    }
}

/// Copies the entries above the diagonal to those below it.
#[inline(always)]
fn mirror_upper<T: Copy, const N: usize>(p: &mut [[T; N]; N]) {
    for i in 1..N {
        let Some((top, bottom)) = p.split_at_mut_checked(i) else {
            continue;
        };
        let Some(ri) = bottom.first_mut() else {
            continue;
        };
        for (dst, rj) in ri.iter_mut().zip(top.iter()) {
            if let Some(&v) = rj.get(i) {
                *dst = v;
            }
        }
    }
}

#[inline(always)]
fn set<T, const N: usize>(p: &mut [[T; N]; N], i: usize, j: usize, value: T) {
    if let Some(v) = p.get_mut(i).and_then(|r| r.get_mut(j)) {
        *v = value;
    }
}

#[inline(always)]
fn add_diag<T: Real, const N: usize>(p: &mut [[T; N]; N], i: usize, q: T) {
    if let Some(v) = p.get_mut(i).and_then(|r| r.get_mut(i)) {
        *v += q;
    }
}

#[cfg(test)]
mod tests;
