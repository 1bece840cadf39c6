//! Construction: the tuning checked and turned into the scaled states'
//! start values, variances, bands and unscented-transform weights.

use super::matrix::put;
use super::{Filter, Measured, ModalTracker, ModeInit, SensorSpec, Tuning, Weights};
use crate::error::{Param, ParamError, finite, in_range, positive};
use crate::real::Real;

fn sq(x: f64) -> f64 {
    x * x
}

pub(super) fn powk(x: f64, k: i32) -> f64 {
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

impl<T: Real, const N: usize, const M: usize> ModalTracker<T, N, M> {
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
        if M > 0 && m_n != M {
            return Err(ParamError::LengthMismatch {
                param: Param::scalar("modes"),
                expected: M,
                got: m_n,
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
                shift: T::ZERO,
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
                shift: T::from_f64(deviation_shift(
                    wi,
                    4 * m_n,
                    w0c + 2.0 * wi * N as f64 - 2.0,
                )),
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
}

/// The shift c of the UKF's sigma-point deviations from 8 states on (see
/// `predict_ukf_blocks`): with K deviations `D_k` of weight `W_i` and
/// `δ = W_i Σ D_k`, `W_i Σ (D_k - c δ)(D_k - c δ)ᵀ` adds
/// `(W_i K c² - 2 c) δ δᵀ` to `W_i Σ D_k D_kᵀ`, which is the
/// `(β - α²) δ δᵀ` = `q δ δᵀ` the transform needs when
/// `c = (1 - √(1 + W_i K q)) / (W_i K)`, the root nearer zero. Real, since
/// `q >= -α²` and `W_i K = K / (2 α² (n + κ)) <= 1/(2 α²)` (K = 4 modes
/// <= n).
fn deviation_shift(wi: f64, k: usize, q: f64) -> f64 {
    let a = wi * k as f64;
    if a > 0.0 {
        (1.0 - libm::sqrt(1.0 + a * q)) / a
    } else {
        0.0
    }
}
