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
//! - **Safety**: θ kept in (0, θ_max] below Nyquist and λ in a band given by
//!   the largest damping ratio; covariance diagonal floored; an innovation
//!   gate (outliers skipped, a run of them re-acquires); a mode whose
//!   amplitude sinks below `fade_snr` times the noise is *faded*: its ω and
//!   σ are frozen and its amplitudes kept loose until it comes back above
//!   twice that, when ω and σ get their start uncertainty again (they may
//!   have moved while the mode was gone) and are tracked again. A step
//!   that would leave a non-finite state is undone and the covariance reset.
//! - **States**: `N = modes (2 sensors + 2)` values and an N×N covariance.
//! - **Cost** per sample, n = N states, C sensors: EKF about 8n² (covariance
//!   prediction) + C (6n + 2n²/2) multiply-adds, one `expf` and one sin/cos
//!   polynomial per mode, one division per sensor; UKF one n×n Cholesky
//!   per sensor and per prediction and 2n + 1 process or observation
//!   evaluations each. No f64 and no libm trig per sample.

use super::trig::sin_cos;
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
    x: [T; N],
    p: [[T; N]; N],
    faded: [bool; N],
    run: u32,
    /// Samples gated out since the start.
    pub outliers: u32,
    /// Covariance resets since the start.
    pub repairs: u32,
    /// Re-acquisitions since the start.
    pub reacquisitions: u32,
}

impl<T: Real, const N: usize> ModalState<T, N> {
    /// The state vector (per mode: θ, λ, then a, b per sensor).
    pub fn x(&self) -> &[T; N] {
        &self.x
    }
    /// The covariance.
    pub fn covariance(&self) -> &[[T; N]; N] {
        &self.p
    }
}

fn sq(x: f64) -> f64 {
    x * x
}

fn powk(x: f64, k: i32) -> f64 {
    (0..k).fold(1.0, |acc, _| acc * x)
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
    gate2: T,
    outlier_run: u32,
    fade2: T,
    ut: (T, T, T, T),
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

        let mut me = Self {
            modes: m_n,
            sensors: c_n,
            dt,
            filter,
            measured: [Measured::Displacement; N],
            meas_gain: [T::ZERO; N],
            scale: [T::ZERO; N],
            r: [T::ZERO; N],
            q_theta: T::from_f64(sq(core::f64::consts::TAU * f_walk * dt) * dt),
            q_lambda: [T::ZERO; N],
            q_amp: T::from_f64(a_walk * a_walk * dt),
            p0: [T::ZERO; N],
            floor: [T::ZERO; N],
            x0: [T::ZERO; N],
            theta_max: T::from_f64(theta_max),
            theta_min: T::from_f64(theta_max * 1e-6),
            lambda_min: T::ZERO,
            lambda_max: T::ZERO,
            gate2: T::from_f64(gate * gate),
            outlier_run: t.outlier_run.max(1),
            fade2: T::from_f64(fade * fade),
            ut: (T::ZERO, T::ZERO, T::ZERO, T::ZERO),
        };
        if let Filter::Ukf(ut) = filter {
            let (g, w0m, w0c, wi) = ut.weights(N)?;
            me.ut = (
                T::from_f64(g),
                T::from_f64(w0m),
                T::from_f64(w0c),
                T::from_f64(wi),
            );
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
            put(&mut me.p0, ti, T::from_f64(sq(e_f * theta)));
            put(&mut me.p0, li, T::from_f64(sq(e_z * w0dt)));
            put(&mut me.q_lambda, m, T::from_f64(sq(z_walk * w0dt) * dt));
            let eps = 64.0 * T::EPSILON.to_f64();
            put(&mut me.floor, ti, T::from_f64(sq(eps * theta)));
            put(&mut me.floor, li, T::from_f64(sq(eps * w0dt)));
        }
        let lam = max_z * largest_omega0_dt;
        me.lambda_min = T::from_f64(-lam);
        me.lambda_max = T::from_f64(lam);
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
            put(&mut me.r, c, T::from_f64(sq(noise * powk(dt, k) / total)));
            for (m, &(dr, di)) in disp.iter().take(m_n).enumerate() {
                let (ai, bi) = me.pair(m, c);
                put(&mut me.x0, ai, T::from_f64(dr / total));
                put(&mut me.x0, bi, T::from_f64(di / total));
                put(&mut me.p0, ai, T::from_f64(e_a * e_a));
                put(&mut me.p0, bi, T::from_f64(e_a * e_a));
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

    /// The start state: the initial estimate and its diagonal covariance.
    pub fn start(&self) -> ModalState<T, N> {
        let mut p = [[T::ZERO; N]; N];
        for (i, row) in p.iter_mut().enumerate() {
            put(row, i, get(&self.p0, i));
        }
        ModalState {
            x: self.x0,
            p,
            faded: [false; N],
            run: 0,
            outliers: 0,
            repairs: 0,
            reacquisitions: 0,
        }
    }

    fn theta_lambda(&self, m: usize) -> (usize, usize) {
        let base = m * (2 * self.sensors + 2);
        (base, base + 1)
    }

    fn pair(&self, m: usize, c: usize) -> (usize, usize) {
        let base = m * (2 * self.sensors + 2) + 2 + 2 * c;
        (base, base + 1)
    }

    /// Frequency, damping and frozen flag of mode `m` (eq 3.7 closed form).
    pub fn mode(&self, state: &ModalState<T, N>, m: usize) -> ModeStatus<T> {
        let (ti, li) = self.theta_lambda(m);
        let (theta, lambda) = (get(&state.x, ti), get(&state.x, li));
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
            faded: state.faded.get(m).copied().unwrap_or(false),
        }
    }

    /// Complex amplitude `(re, im)` of mode `m` in the displacement at
    /// sensor `c` (for velocity and acceleration sensors, the displacement
    /// whose derivative they measure), sensor units times s^k.
    pub fn displacement(&self, state: &ModalState<T, N>, m: usize, c: usize) -> (T, T) {
        let (ai, bi) = self.pair(m, c);
        let s = get(&self.scale, c) * T::from_f64(1.0 / powk(self.dt, self.measured_order(c)));
        (get(&state.x, ai) * s, get(&state.x, bi) * s)
    }

    fn measured_order(&self, c: usize) -> i32 {
        self.measured.get(c).copied().unwrap_or_default().order()
    }

    /// `(e^λ cos θ, e^λ sin θ)` of mode `m`: its one sin/cos polynomial and
    /// `exp` per step.
    #[inline(always)]
    fn rotation(&self, x: &[T; N], m: usize) -> (T, T) {
        let (ti, li) = self.theta_lambda(m);
        let (s, c) = sin_cos(get(x, ti));
        let e = get(x, li).exp();
        (e * c, e * s)
    }

    /// Rotates mode `m`'s analytic-signal pairs by `(ec, es)` (eq 3.28).
    #[inline(always)]
    fn rotate_mode(&self, x: &mut [T; N], m: usize, (ec, es): (T, T)) {
        for k in 0..self.sensors {
            let (ai, bi) = self.pair(m, k);
            let (a, b) = (get(x, ai), get(x, bi));
            put(x, ai, ec * a - es * b);
            put(x, bi, es * a + ec * b);
        }
    }

    /// Applies the process (eq 3.28) to a state vector.
    fn process(&self, x: &mut [T; N]) {
        for m in 0..self.modes {
            let r = self.rotation(x, m);
            self.rotate_mode(x, m, r);
        }
    }

    /// Predicted sample of sensor `c` (scaled) and its gradient entries at
    /// (θ, λ, a, b) for mode `m`.
    fn observe_mode(&self, x: &[T; N], m: usize, c: usize) -> (T, [T; 4]) {
        let (ti, li) = self.theta_lambda(m);
        let (ai, bi) = self.pair(m, c);
        let (t, l, a, b) = (get(x, ti), get(x, li), get(x, ai), get(x, bi));
        let two = T::ONE + T::ONE;
        match self.measured.get(c).copied().unwrap_or_default() {
            Measured::Displacement => (a, [T::ZERO, T::ZERO, T::ONE, T::ZERO]),
            Measured::Velocity => (l * a - t * b, [-b, a, l, -t]),
            Measured::Acceleration => {
                let (ca, cb) = (l * l - t * t, -two * l * t);
                (
                    ca * a + cb * b,
                    [-two * (t * a + l * b), two * (l * a - t * b), ca, cb],
                )
            }
        }
    }

    fn observe(&self, x: &[T; N], c: usize) -> T {
        let mut z = T::ZERO;
        for m in 0..self.modes {
            z += self.observe_mode(x, m, c).0;
        }
        z
    }

    /// One sample per sensor, in sensor units (`samples[c]`): predict, then
    /// update sensor by sensor. A non-finite sample is refused for that
    /// sensor only.
    pub fn step(&self, state: &mut ModalState<T, N>, samples: &[T]) -> ModalReport {
        let mut report = ModalReport::default();
        let saved = state.clone();
        let ok = match self.filter {
            Filter::Ekf => self.predict_ekf(state),
            Filter::Ukf(_) => self.predict_ukf(state),
        };
        if !ok {
            self.repair(state, &saved, &mut report);
            return report;
        }
        for c in 0..self.sensors {
            let z = samples.get(c).copied().unwrap_or(T::ZERO);
            if !z.is_finite() {
                report.refused = true;
                continue;
            }
            let z = z * get(&self.meas_gain, c);
            let mut v = [T::ZERO; N];
            let Some((zhat, s)) = self.innovation(state, c, &mut v) else {
                self.repair(state, &saved, &mut report);
                return report;
            };
            let y = z - zhat;
            let run_over = state.run + 1 >= self.outlier_run;
            if y * y > self.gate2 * s && !run_over {
                state.run += 1;
                state.outliers = state.outliers.saturating_add(1);
                report.gated += 1;
                continue;
            }
            if y * y > self.gate2 * s {
                // A run of outliers: the model lost the signal. Loosen the
                // amplitudes and take the sample.
                self.loosen_amplitudes(state, None);
                state.reacquisitions = state.reacquisitions.saturating_add(1);
                report.reacquired = true;
                state.run = 0;
                let Some((zhat, s)) = self.innovation(state, c, &mut v) else {
                    self.repair(state, &saved, &mut report);
                    return report;
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
        let finite = state.x.iter().all(|v| v.is_finite())
            && state.p.iter().all(|r| r.iter().all(|v| v.is_finite()));
        if !finite {
            self.repair(state, &saved, &mut report);
        }
        report
    }

    /// Predicted sample of sensor `c`, cross-covariance into `v` and
    /// innovation variance; `None` when the covariance is not usable.
    fn innovation(&self, state: &ModalState<T, N>, c: usize, v: &mut [T; N]) -> Option<(T, T)> {
        let (zhat, s) = match self.filter {
            Filter::Ekf => self.innovation_ekf(state, c, v),
            Filter::Ukf(_) => self.innovation_ukf(state, c, v)?,
        };
        (s.is_finite() && s > T::ZERO).then_some((zhat, s))
    }

    fn repair(
        &self,
        state: &mut ModalState<T, N>,
        saved: &ModalState<T, N>,
        report: &mut ModalReport,
    ) {
        let counters = (state.outliers, state.repairs, state.reacquisitions);
        *state = saved.clone();
        state.outliers = counters.0;
        state.repairs = counters.1.saturating_add(1);
        state.reacquisitions = counters.2;
        let fresh = self.start();
        state.p = fresh.p;
        report.repaired = true;
    }

    /// EKF prediction: x = f(x), P = F P Fᵀ + Q with F applied as row and
    /// vector operations (F is the identity but for the pair rows).
    fn predict_ekf(&self, state: &mut ModalState<T, N>) -> bool {
        let mut rot = [(T::ZERO, T::ZERO); N];
        for (m, r) in rot.iter_mut().enumerate().take(self.modes) {
            *r = self.rotation(&state.x, m);
            self.rotate_mode(&mut state.x, m, *r);
        }
        let x = &state.x;
        let p = &mut state.p;
        for (m, &(ec, es)) in rot.iter().enumerate().take(self.modes) {
            let (ti, li) = self.theta_lambda(m);
            let (row_t, row_l) = (
                p.get(ti).copied().unwrap_or([T::ZERO; N]),
                p.get(li).copied().unwrap_or([T::ZERO; N]),
            );
            for k in 0..self.sensors {
                let (ai, bi) = self.pair(m, k);
                let (a1, b1) = (get(x, ai), get(x, bi));
                // Rows: (F P)[a] = ec P[a] - es P[b] - b' P[θ] + a' P[λ].
                let (ra, rb) = (
                    p.get(ai).copied().unwrap_or([T::ZERO; N]),
                    p.get(bi).copied().unwrap_or([T::ZERO; N]),
                );
                let mut na = [T::ZERO; N];
                let mut nb = [T::ZERO; N];
                for j in 0..N {
                    let (pa, pb, pt, pl) =
                        (get(&ra, j), get(&rb, j), get(&row_t, j), get(&row_l, j));
                    put(&mut na, j, ec * pa - es * pb - b1 * pt + a1 * pl);
                    put(&mut nb, j, es * pa + ec * pb + a1 * pt + b1 * pl);
                }
                if let Some(r) = p.get_mut(ai) {
                    *r = na;
                }
                if let Some(r) = p.get_mut(bi) {
                    *r = nb;
                }
            }
        }
        // Columns: row i of F P Fᵀ is F applied to row i of F P.
        for row in p.iter_mut() {
            for (m, &(ec, es)) in rot.iter().enumerate().take(self.modes) {
                let (ti, li) = self.theta_lambda(m);
                let (vt, vl) = (get(row, ti), get(row, li));
                for k in 0..self.sensors {
                    let (ai, bi) = self.pair(m, k);
                    let (a1, b1) = (get(x, ai), get(x, bi));
                    let (va, vb) = (get(row, ai), get(row, bi));
                    put(row, ai, ec * va - es * vb - b1 * vt + a1 * vl);
                    put(row, bi, es * va + ec * vb + a1 * vt + b1 * vl);
                }
            }
        }
        self.add_process_noise(state);
        true
    }

    fn add_process_noise(&self, state: &mut ModalState<T, N>) {
        for m in 0..self.modes {
            let frozen = state.faded.get(m).copied().unwrap_or(false);
            let (ti, li) = self.theta_lambda(m);
            if !frozen {
                self.add_diag(&mut state.p, ti, self.q_theta);
                self.add_diag(&mut state.p, li, get(&self.q_lambda, m));
            }
            for c in 0..self.sensors {
                let (ai, bi) = self.pair(m, c);
                self.add_diag(&mut state.p, ai, self.q_amp);
                self.add_diag(&mut state.p, bi, self.q_amp);
            }
        }
        // Exact symmetry.
        for i in 0..N {
            for j in i + 1..N {
                let v = T::HALF * (entry(&state.p, i, j) + entry(&state.p, j, i));
                self.set(&mut state.p, i, j, v);
                self.set(&mut state.p, j, i, v);
            }
        }
    }

    fn add_diag(&self, p: &mut [[T; N]; N], i: usize, q: T) {
        if let Some(v) = p.get_mut(i).and_then(|r| r.get_mut(i)) {
            *v += q;
        }
    }

    fn set(&self, p: &mut [[T; N]; N], i: usize, j: usize, value: T) {
        if let Some(v) = p.get_mut(i).and_then(|r| r.get_mut(j)) {
            *v = value;
        }
    }

    /// EKF innovation of sensor `c`: predicted sample, `v = P hᵀ`, and
    /// `s = h P hᵀ + r`.
    fn innovation_ekf(&self, state: &ModalState<T, N>, c: usize, v: &mut [T; N]) -> (T, T) {
        let mut h = [T::ZERO; N];
        let mut zhat = T::ZERO;
        for m in 0..self.modes {
            let (z, g) = self.observe_mode(&state.x, m, c);
            zhat += z;
            let (ti, li) = self.theta_lambda(m);
            let (ai, bi) = self.pair(m, c);
            for (i, gi) in [ti, li, ai, bi].into_iter().zip(g) {
                put(&mut h, i, gi);
            }
        }
        let mut s = get(&self.r, c);
        for (vi, row) in v.iter_mut().zip(&state.p) {
            *vi = row
                .iter()
                .zip(&h)
                .fold(T::ZERO, |acc, (&pij, &hj)| acc + pij * hj);
        }
        for (vi, hi) in v.iter().zip(&h) {
            s += *vi * *hi;
        }
        (zhat, s)
    }

    /// Lower Cholesky factor of the covariance, times the sigma spread;
    /// `None` if it is not positive definite.
    fn sigma_factor(&self, p: &[[T; N]; N]) -> Option<[[T; N]; N]> {
        let mut l = [[T::ZERO; N]; N];
        for j in 0..N {
            let mut d = entry(p, j, j);
            for k in 0..j {
                let ljk = entry(&l, j, k);
                d -= ljk * ljk;
            }
            if !d.is_finite() || d <= T::ZERO {
                return None;
            }
            let ljj = d.sqrt();
            let inv = T::ONE / ljj;
            self.set(&mut l, j, j, ljj);
            for i in j + 1..N {
                let mut v = entry(p, i, j);
                for k in 0..j {
                    v -= entry(&l, i, k) * entry(&l, j, k);
                }
                self.set(&mut l, i, j, v * inv);
            }
        }
        let g = self.ut.0;
        for row in l.iter_mut() {
            for v in row.iter_mut() {
                *v *= g;
            }
        }
        Some(l)
    }

    /// Sigma point `x ± column j of L`.
    fn sigma(&self, x: &[T; N], l: &[[T; N]; N], j: usize, sign: T) -> [T; N] {
        let mut out = *x;
        for (i, o) in out.iter_mut().enumerate() {
            *o += sign * entry(l, i, j);
        }
        out
    }

    fn predict_ukf(&self, state: &mut ModalState<T, N>) -> bool {
        let Some(l) = self.sigma_factor(&state.p) else {
            return false;
        };
        let (_, w0m, w0c, wi) = self.ut;
        let mut x0 = state.x;
        self.process(&mut x0);
        let mut plus = [[T::ZERO; N]; N];
        let mut minus = [[T::ZERO; N]; N];
        let mut mean = [T::ZERO; N];
        for (i, m) in mean.iter_mut().enumerate() {
            *m = w0m * get(&x0, i);
        }
        for j in 0..N {
            let mut xp = self.sigma(&state.x, &l, j, T::ONE);
            let mut xm = self.sigma(&state.x, &l, j, -T::ONE);
            self.process(&mut xp);
            self.process(&mut xm);
            for ((m, a), b) in mean.iter_mut().zip(&xp).zip(&xm) {
                *m += wi * (*a + *b);
            }
            if let Some(r) = plus.get_mut(j) {
                *r = xp;
            }
            if let Some(r) = minus.get_mut(j) {
                *r = xm;
            }
        }
        let mut p = [[T::ZERO; N]; N];
        for i in 0..N {
            for k in i..N {
                let d0 = (get(&x0, i) - get(&mean, i)) * (get(&x0, k) - get(&mean, k));
                let mut acc = T::ZERO;
                for (xp, xm) in plus.iter().zip(&minus) {
                    acc += (get(xp, i) - get(&mean, i)) * (get(xp, k) - get(&mean, k))
                        + (get(xm, i) - get(&mean, i)) * (get(xm, k) - get(&mean, k));
                }
                let v = w0c * d0 + wi * acc;
                self.set(&mut p, i, k, v);
                self.set(&mut p, k, i, v);
            }
        }
        state.x = mean;
        state.p = p;
        self.add_process_noise(state);
        true
    }

    /// UKF innovation of sensor `c` with sigma points redrawn from the
    /// current estimate: predicted sample, `v = Pxz`, `s = Pzz + r`.
    fn innovation_ukf(&self, state: &ModalState<T, N>, c: usize, v: &mut [T; N]) -> Option<(T, T)> {
        let l = self.sigma_factor(&state.p)?;
        let (_, w0m, w0c, wi) = self.ut;
        let z0 = self.observe(&state.x, c);
        let mut zp = [T::ZERO; N];
        let mut zm = [T::ZERO; N];
        let mut zhat = w0m * z0;
        for j in 0..N {
            let a = self.observe(&self.sigma(&state.x, &l, j, T::ONE), c);
            let b = self.observe(&self.sigma(&state.x, &l, j, -T::ONE), c);
            zhat += wi * (a + b);
            put(&mut zp, j, a);
            put(&mut zm, j, b);
        }
        let mut s = w0c * (z0 - zhat) * (z0 - zhat) + get(&self.r, c);
        for (a, b) in zp.iter().zip(&zm) {
            s += wi * ((*a - zhat) * (*a - zhat) + (*b - zhat) * (*b - zhat));
        }
        // Pxz = Σ W_i (±L_j)(Z_j^± - ẑ) = W_i Σ L_j (Z_j^+ - Z_j^-).
        for (i, vi) in v.iter_mut().enumerate() {
            let mut acc = T::ZERO;
            for (j, (a, b)) in zp.iter().zip(&zm).enumerate() {
                acc += entry(&l, i, j) * (*a - *b);
            }
            *vi = wi * acc;
        }
        Some((zhat, s))
    }

    /// Scalar update with cross-covariance `v`, innovation variance `s` and
    /// innovation `y`, in the Joseph form (valid for the frozen rows' zero
    /// gain).
    fn update(&self, state: &mut ModalState<T, N>, v: &[T; N], s: T, y: T) {
        let inv = T::ONE / s;
        let mut k = [T::ZERO; N];
        for (ki, vi) in k.iter_mut().zip(v) {
            *ki = *vi * inv;
        }
        for m in 0..self.modes {
            if state.faded.get(m).copied().unwrap_or(false) {
                let (ti, li) = self.theta_lambda(m);
                put(&mut k, ti, T::ZERO);
                put(&mut k, li, T::ZERO);
            }
        }
        for (xi, ki) in state.x.iter_mut().zip(&k) {
            *xi += *ki * y;
        }
        for i in 0..N {
            let (ki, vi) = (get(&k, i), get(v, i));
            for j in i..N {
                let (kj, vj) = (get(&k, j), get(v, j));
                let val = entry(&state.p, i, j) - ki * vj - vi * kj + s * ki * kj;
                self.set(&mut state.p, i, j, val);
                self.set(&mut state.p, j, i, val);
            }
        }
    }

    /// θ and λ into their bands, the diagonal above its floor.
    fn constrain(&self, state: &mut ModalState<T, N>) {
        for m in 0..self.modes {
            let (ti, li) = self.theta_lambda(m);
            let t = get(&state.x, ti).max(self.theta_min).min(self.theta_max);
            put(&mut state.x, ti, t);
            let l = get(&state.x, li).max(self.lambda_min).min(self.lambda_max);
            put(&mut state.x, li, l);
        }
        for i in 0..N {
            let floor = get(&self.floor, i);
            if let Some(v) = state.p.get_mut(i).and_then(|r| r.get_mut(i))
                && *v < floor
            {
                *v = floor;
            }
        }
    }

    /// Marks modes faded or back, keeps a faded mode's amplitudes loose and
    /// gives a returning mode's ω and σ their start uncertainty.
    fn fade(&self, state: &mut ModalState<T, N>) {
        for m in 0..self.modes {
            let (ti, li) = self.theta_lambda(m);
            let (t, l) = (get(&state.x, ti), get(&state.x, li));
            let rate2 = t * t + l * l;
            let (mut below, mut above) = (true, false);
            for c in 0..self.sensors {
                let (ai, bi) = self.pair(m, c);
                let (a, b) = (get(&state.x, ai), get(&state.x, bi));
                let mut amp2 = a * a + b * b;
                for _ in 0..self.measured_order(c) {
                    amp2 *= rate2;
                }
                let noise2 = self.fade2 * get(&self.r, c);
                below &= amp2 < noise2;
                above |= amp2 > (T::ONE + T::ONE + T::ONE + T::ONE) * noise2;
            }
            let was = state.faded.get(m).copied().unwrap_or(false);
            let now = if was { !above } else { below };
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
    fn loosen_amplitudes(&self, state: &mut ModalState<T, N>, mode: Option<usize>) {
        for m in 0..self.modes {
            if mode.is_some_and(|x| x != m) {
                continue;
            }
            for c in 0..self.sensors {
                let (ai, bi) = self.pair(m, c);
                self.loosen(state, ai);
                self.loosen(state, bi);
            }
        }
    }

    /// Raises the variance of state `i` to its start value, if below, and
    /// drops its correlations.
    fn loosen(&self, state: &mut ModalState<T, N>, i: usize) {
        let p0 = get(&self.p0, i);
        if entry(&state.p, i, i) < p0 {
            for j in 0..N {
                if j != i {
                    self.set(&mut state.p, i, j, T::ZERO);
                    self.set(&mut state.p, j, i, T::ZERO);
                }
            }
            self.set(&mut state.p, i, i, p0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sensor() -> [SensorSpec; 1] {
        [SensorSpec {
            measured: Measured::Displacement,
            noise: 1e-3,
        }]
    }

    fn mode(frequency: f64, damping: f64) -> [ModeInit; 1] {
        [ModeInit { frequency, damping }]
    }

    #[test]
    fn bad_parameters_are_typed_errors() {
        let t = Tuning::default();
        fn build<const N: usize>(dt: f64, f: f64, z: f64, t: &Tuning) -> Result<(), ParamError> {
            ModalTracker::<f32, N>::new(dt, &sensor(), &mode(f, z), &[(1.0, 0.0)], t, Filter::Ekf)
                .map(|_| ())
        }
        let new = |dt, f, z, n: usize| match n {
            4 => build::<4>(dt, f, z, &t),
            _ => build::<6>(dt, f, z, &t),
        };
        assert!(new(1e-3, 10.0, 0.01, 4).is_ok());
        assert!(matches!(
            new(0.0, 10.0, 0.01, 4),
            Err(ParamError::NotPositive { .. })
        ));
        // Above 0.9 Nyquist (500 Hz at 1 kHz).
        assert!(matches!(
            new(1e-3, 460.0, 0.01, 4),
            Err(ParamError::OutOfRange { param, .. }) if param == Param::item("frequency", 0)
        ));
        assert!(matches!(
            new(1e-3, 10.0, 0.7, 4),
            Err(ParamError::OutOfRange { param, .. }) if param == Param::item("damping", 0)
        ));
        assert!(matches!(
            new(1e-3, 10.0, 0.01, 6),
            Err(ParamError::LengthMismatch {
                expected: 4,
                got: 6,
                ..
            })
        ));
        let zero = ModalTracker::<f32, 4>::new(
            1e-3,
            &sensor(),
            &mode(10.0, 0.01),
            &[(0.0, 0.0)],
            &t,
            Filter::Ekf,
        );
        assert!(matches!(zero, Err(ParamError::NotPositive { .. })));
        assert!(UtParams::new(0.0, 2.0, 0.0).is_err());
        assert!(UtParams::new(1.0, -1.0, 0.0).is_err());
        assert!(UtParams::new(1.0, 2.0, -1.0).is_err());
        assert!(UtParams::new(0.5, 2.0, 1.0).is_ok());
        let bad = Tuning {
            gate: 0.0,
            ..Tuning::default()
        };
        assert!(
            ModalTracker::<f32, 4>::new(
                1e-3,
                &sensor(),
                &mode(10.0, 0.01),
                &[(1.0, 0.0)],
                &bad,
                Filter::Ekf
            )
            .is_err()
        );
    }

    #[test]
    fn scaled_ut_weights_sum_to_one() {
        for (a, b, k) in [(1.0, 2.0, 0.0), (0.5, 2.0, 1.0), (1.0, 0.0, 3.0)] {
            let (g, w0m, w0c, wi) = UtParams::new(a, b, k).unwrap().weights(4).unwrap();
            assert!((w0m + 8.0 * wi - 1.0).abs() < 1e-12);
            assert!(w0c >= 0.0 && wi > 0.0);
            assert!((g * g * 2.0 * wi - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn non_finite_samples_are_refused_and_the_state_kept() {
        for filter in [Filter::Ekf, Filter::Ukf(UtParams::default())] {
            let tr = ModalTracker::<f32, 4>::new(
                1e-3,
                &sensor(),
                &mode(10.0, 0.01),
                &[(1.0, 0.0)],
                &Tuning::default(),
                filter,
            )
            .unwrap();
            let mut s = tr.start();
            let r = tr.step(&mut s, &[f32::NAN]);
            assert!(r.refused && r.accepted == 0);
            assert!(s.x().iter().all(|v| v.is_finite()));
            // A sample far outside the gate is skipped, not absorbed.
            let before = tr.mode(&s, 0);
            let r = tr.step(&mut s, &[1e6]);
            assert_eq!(r.gated, 1);
            assert_eq!(tr.mode(&s, 0).frequency, before.frequency);
        }
    }
}
