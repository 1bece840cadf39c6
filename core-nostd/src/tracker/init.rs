//! Start values for the modal tracker: a least-squares fit of the first
//! pseudo-period (seed 004 §3.2.6 and §3.3.1).
//!
//! The thesis starts its tracker from "modal parameters identified on the
//! first cycles": a least-squares fit of `A e^{σt} cos(ωt + φ)` on the first
//! pseudo-period, with the time origin where the excitation stops. The
//! initial covariance and the process noise then only have to cover the
//! error of that fit, which is what keeps the first periods of a free decay
//! (where the amplitudes are largest) usable.
//!
//! [`fit_first_period`] does that fit for one mode seen by any number of
//! sensors (they share ω and σ, as in the tracker's formulation B, seed 004
//! eqs 3.43-3.45); [`fit_amplitudes`] fits only the complex amplitudes of
//! several modes whose frequency and damping are known (from a previous
//! test, a model or a spectrum peak). Both run once, before the first
//! update, in f64 with libm (one `acos` and one `log` in all); they are not
//! part of the per-sample path.
//!
//! # The fit of one mode
//!
//! With `z = e^{λ + iθ}` per sample (`λ = σ dt`, `θ = ω dt`) every sensor
//! reads `x_k = Re[c z^k] = e^{λk} (α cos θk - β sin θk)`, `c = α + iβ`.
//!
//! 1. **Linear prediction.** A damped sinusoid obeys
//!    `x_k = c_1 x_{k-d} + c_2 x_{k-2d}` with `c_1 = 2 e^{λd} cos θd`,
//!    `c_2 = -e^{2λd}`, for any lag d. The two coefficients are found by
//!    least squares over all sensors at once (they share the pole). A first
//!    pass at d = 1 locates θ; the second uses the lag closest to a quarter
//!    period, where `θd ≈ π/2` and the estimate is least sensitive to noise
//!    (at d = 1 and 200 samples per period, `c_1 ≈ 2` and `c_2 ≈ -1`, and a
//!    1e-4 noise bias on `c_2` moves the damping ratio by 0.2 points).
//! 2. **Gauss-Newton on the full model** (separable least squares): for the
//!    current (θ, λ) the amplitudes of each sensor are a 2 x 2 linear least
//!    squares; the step on (θ, λ) solves the normal equations with the
//!    amplitudes eliminated (a 2 x 2 Schur complement per sensor), so the
//!    cost is linear in the number of sensors and the memory is constant.
//!    It stops when the step is below 1e-12 of θ (a few iterations from the
//!    linear-prediction start) or after 32 iterations.
//!
//! The result is the least-squares (maximum-likelihood under white noise)
//! estimate of the record: on a clean damped sine it is exact to rounding,
//! and with noise its scatter is the Cramér-Rao bound of one period, which
//! the tracker's `initial_*_error` tuning should cover (about 1 % in
//! frequency and 0.5 points of damping at 40 dB over one period of 20
//! samples; the tracker tests use the fit at 20 to 200 samples per period).
//!
//! Cost: about 30 flops per sample and sensor per iteration (two passes,
//! with `cos`, `sin` and `exp` evaluated by a complex recurrence, not libm).
//!
//! The residual RMS of each sensor is returned: it estimates that sensor's
//! noise, the value the thesis recommends over-estimating for R (§3.2.6).

use core::fmt;

use super::modal::ModeInit;
use crate::error::{Param, ParamError, positive};

/// Why a record could not be fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FitError {
    /// A parameter is out of range (dt, the mode list, the output lengths).
    Param(ParamError),
    /// A record is shorter than the fit needs.
    TooShort {
        /// Sensor index.
        sensor: usize,
        /// Samples needed.
        need: usize,
        /// Samples given.
        got: usize,
    },
    /// A sample is NaN or infinite.
    NotFinite {
        /// Sensor index.
        sensor: usize,
        /// Sample index.
        index: usize,
    },
    /// Every record is zero.
    NoSignal,
    /// The records hold no decaying or growing oscillation: the linear
    /// prediction gives real poles (a trend or noise only).
    NotOscillating,
    /// The Gauss-Newton iteration left the range 0 < θ < π or did not
    /// settle: the record holds more than one mode, or much noise.
    NotConverged,
}

impl From<ParamError> for FitError {
    fn from(e: ParamError) -> Self {
        Self::Param(e)
    }
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Param(e) => write!(f, "{e}"),
            Self::TooShort { sensor, need, got } => write!(
                f,
                "record of sensor {sensor}: {got} samples, the fit needs at least {need}"
            ),
            Self::NotFinite { sensor, index } => {
                write!(f, "record of sensor {sensor}: sample {index} is not finite")
            }
            Self::NoSignal => write!(f, "every record is zero"),
            Self::NotOscillating => write!(f, "the records hold no oscillation"),
            Self::NotConverged => write!(
                f,
                "the fit did not settle on one damped sine (several modes or much noise?)"
            ),
        }
    }
}

/// Least-squares start values of one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstPeriodFit {
    /// Natural frequency and damping ratio, ready for the tracker.
    pub mode: ModeInit,
    /// Gauss-Newton iterations taken.
    pub iterations: u32,
}

/// What the fit found for one sensor.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SensorFit {
    /// Complex amplitude `(re, im)` at the first sample, in the sensor's
    /// units: the tracker's `amplitudes` argument.
    pub amplitude: (f64, f64),
    /// RMS of the fit residual, in the sensor's units: an estimate of the
    /// sensor's noise.
    pub residual: f64,
}

/// Fewest samples per record.
pub const MIN_SAMPLES: usize = 8;

/// The largest number of modes [`fit_amplitudes`] takes.
pub const MAX_FIT_MODES: usize = 4;

/// Least-squares fit of one damped sine common to all `records` (one per
/// sensor, sample 0 at the time origin, at step `dt`), over about its first
/// pseudo-period. Fills `out[c]` with sensor c's amplitude at sample 0 and
/// its residual RMS. A record should span between half a period and
/// somewhat more than one; any length works if the linear prediction can
/// see the oscillation.
pub fn fit_first_period(
    dt: f64,
    records: &[&[f64]],
    out: &mut [SensorFit],
) -> Result<FirstPeriodFit, FitError> {
    let dt = positive(Param::scalar("dt"), dt)?;
    check_records(records, out.len())?;
    // 1. Linear prediction at the shortest lag that sees the oscillation
    //    (noise can make the lag-1 poles real when θ is small), then near a
    //    quarter period.
    let shortest = records.iter().map(|r| r.len()).min().unwrap_or(0);
    let longest_lag = (shortest - 1) / 3;
    let mut d = 1;
    let z1 = loop {
        match predict(records, d) {
            Ok((z, _)) => break (z.0 / d as f64, z.1 / d as f64),
            Err(FitError::NotOscillating) if 2 * d <= longest_lag => d *= 2,
            Err(e) => return Err(e),
        }
    };
    let quarter = libm::round(core::f64::consts::FRAC_PI_2 / z1.1) as usize;
    let lag = quarter.clamp(1, longest_lag.max(1));
    let (mut lambda, mut theta) = if lag > 1 {
        let (zd, _) = predict(records, lag)?;
        (zd.0 / lag as f64, zd.1 / lag as f64)
    } else {
        z1
    };
    // 2. Separable Gauss-Newton on (θ, λ).
    let mut iterations = 0;
    loop {
        let (step, converged) = gauss_newton_step(records, theta, lambda);
        let (dth, dla) = step.ok_or(FitError::NotConverged)?;
        theta += dth;
        lambda += dla;
        iterations += 1;
        if !(theta > 0.0 && theta < core::f64::consts::PI && lambda.is_finite()) {
            return Err(FitError::NotConverged);
        }
        if converged || libm::fabs(dth) < 1e-12 * theta {
            break;
        }
        if iterations >= 32 {
            return Err(FitError::NotConverged);
        }
    }
    for (rec, o) in records.iter().zip(out.iter_mut()) {
        *o = amplitudes_one(rec, theta, lambda);
    }
    let w0dt = libm::hypot(theta, lambda);
    Ok(FirstPeriodFit {
        mode: ModeInit {
            frequency: w0dt / (core::f64::consts::TAU * dt),
            damping: -lambda / w0dt,
        },
        iterations,
    })
}

/// Least-squares complex amplitudes of known modes: `out[m * C + c]` gets
/// mode m's amplitude in sensor c at sample 0 (the tracker's `amplitudes`
/// layout), with its residual RMS (the same for every mode of a sensor).
/// Up to [`MAX_FIT_MODES`] modes; the records should span at least the
/// beat period of the closest pair, or the modes cannot be told apart (the
/// normal equations then become singular and the fit is refused).
pub fn fit_amplitudes(
    dt: f64,
    modes: &[ModeInit],
    records: &[&[f64]],
    out: &mut [SensorFit],
) -> Result<(), FitError> {
    let dt = positive(Param::scalar("dt"), dt)?;
    let m_n = modes.len();
    if m_n == 0 || m_n > MAX_FIT_MODES {
        return Err(FitError::Param(if m_n == 0 {
            ParamError::TooFew {
                param: Param::scalar("modes"),
                min: 1,
                got: 0,
            }
        } else {
            ParamError::TooMany {
                param: Param::scalar("modes"),
                capacity: MAX_FIT_MODES,
                got: m_n,
            }
        }));
    }
    if out.len() != m_n * records.len() {
        return Err(FitError::Param(ParamError::LengthMismatch {
            param: Param::scalar("out"),
            expected: m_n * records.len(),
            got: out.len(),
        }));
    }
    check_records(records, records.len())?;
    let mut poles = [(0.0f64, 0.0f64); MAX_FIT_MODES];
    for (i, (mode, p)) in modes.iter().zip(poles.iter_mut()).enumerate() {
        let f = positive(Param::item("frequency", i), mode.frequency)?;
        let w0dt = core::f64::consts::TAU * f * dt;
        let z = mode.damping;
        if z.is_nan() || z.abs() >= 1.0 || w0dt >= core::f64::consts::PI {
            return Err(FitError::Param(ParamError::OutOfRange {
                param: Param::item("damping", i),
                value: z,
                min: -1.0,
                min_open: true,
                max: 1.0,
            }));
        }
        *p = (-z * w0dt, w0dt * libm::sqrt(1.0 - z * z));
    }
    const K: usize = 2 * MAX_FIT_MODES;
    let n = 2 * m_n;
    let c_n = records.len();
    for (c, rec) in records.iter().enumerate() {
        // Normal equations of x_k = Σ_m α_m u_mk + β_m v_mk.
        let mut a = [[0.0f64; K]; K];
        let mut g = [0.0f64; K];
        let mut basis = [0.0f64; K];
        let mut z = [(1.0f64, 0.0f64); MAX_FIT_MODES];
        let mut rot = [(0.0f64, 0.0f64); MAX_FIT_MODES];
        for (r, &(la, th)) in rot.iter_mut().zip(poles.iter()).take(m_n) {
            let e = libm::exp(la);
            *r = (e * libm::cos(th), e * libm::sin(th));
        }
        for &x in rec.iter() {
            for (m, zm) in z.iter_mut().enumerate().take(m_n) {
                if let Some([u, v]) = basis.get_mut(2 * m..2 * m + 2) {
                    *u = zm.0;
                    *v = -zm.1;
                }
                let r = rot.get(m).copied().unwrap_or((0.0, 0.0));
                *zm = (zm.0 * r.0 - zm.1 * r.1, zm.0 * r.1 + zm.1 * r.0);
            }
            for i in 0..n {
                let bi = basis.get(i).copied().unwrap_or(0.0);
                if let Some(gi) = g.get_mut(i) {
                    *gi += bi * x;
                }
                if let Some(row) = a.get_mut(i) {
                    for (aij, &bj) in row.iter_mut().zip(basis.iter()).take(n) {
                        *aij += bi * bj;
                    }
                }
            }
        }
        let sol = solve_spd(&mut a, &mut g, n).ok_or(FitError::NotConverged)?;
        // Residual.
        let mut sum = 0.0;
        let mut z = [(1.0f64, 0.0f64); MAX_FIT_MODES];
        for &x in rec.iter() {
            let mut model = 0.0;
            for (m, zm) in z.iter_mut().enumerate().take(m_n) {
                let (al, be) = (
                    sol.get(2 * m).copied().unwrap_or(0.0),
                    sol.get(2 * m + 1).copied().unwrap_or(0.0),
                );
                model += al * zm.0 - be * zm.1;
                let r = rot.get(m).copied().unwrap_or((0.0, 0.0));
                *zm = (zm.0 * r.0 - zm.1 * r.1, zm.0 * r.1 + zm.1 * r.0);
            }
            sum += (x - model) * (x - model);
        }
        let residual = libm::sqrt(sum / rec.len() as f64);
        for m in 0..m_n {
            if let Some(o) = out.get_mut(m * c_n + c) {
                *o = SensorFit {
                    amplitude: (
                        sol.get(2 * m).copied().unwrap_or(0.0),
                        sol.get(2 * m + 1).copied().unwrap_or(0.0),
                    ),
                    residual,
                };
            }
        }
    }
    Ok(())
}

fn check_records(records: &[&[f64]], outputs: usize) -> Result<(), FitError> {
    if records.is_empty() {
        return Err(FitError::Param(ParamError::TooFew {
            param: Param::scalar("records"),
            min: 1,
            got: 0,
        }));
    }
    if outputs != records.len() {
        return Err(FitError::Param(ParamError::LengthMismatch {
            param: Param::scalar("out"),
            expected: records.len(),
            got: outputs,
        }));
    }
    let mut energy = 0.0;
    for (sensor, rec) in records.iter().enumerate() {
        if rec.len() < MIN_SAMPLES {
            return Err(FitError::TooShort {
                sensor,
                need: MIN_SAMPLES,
                got: rec.len(),
            });
        }
        for (index, &x) in rec.iter().enumerate() {
            if !x.is_finite() {
                return Err(FitError::NotFinite { sensor, index });
            }
            energy += x * x;
        }
    }
    if energy > 0.0 {
        Ok(())
    } else {
        Err(FitError::NoSignal)
    }
}

/// Linear prediction at lag `d`, pooled over the records: `((λd, θd), rss)`.
fn predict(records: &[&[f64]], d: usize) -> Result<((f64, f64), f64), FitError> {
    let (mut s11, mut s12, mut s22, mut g1, mut g2, mut s00) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for rec in records {
        for ((&x2, &x1), &x0) in rec
            .iter()
            .zip(rec.iter().skip(d))
            .zip(rec.iter().skip(2 * d))
        {
            s11 += x1 * x1;
            s12 += x1 * x2;
            s22 += x2 * x2;
            g1 += x1 * x0;
            g2 += x2 * x0;
            s00 += x0 * x0;
        }
    }
    let det = s11 * s22 - s12 * s12;
    if det.is_nan() || det <= 1e-300 {
        return Err(FitError::NotOscillating);
    }
    let c1 = (g1 * s22 - g2 * s12) / det;
    let c2 = (s11 * g2 - s12 * g1) / det;
    let rss = s00 - c1 * g1 - c2 * g2;
    // Complex poles need c2 < 0 and c1² < -4 c2.
    if c2.is_nan() || c2 >= 0.0 || c1 * c1 >= -4.0 * c2 {
        return Err(FitError::NotOscillating);
    }
    let r = libm::sqrt(-c2);
    Ok(((libm::log(r), libm::acos(0.5 * c1 / r)), rss))
}

/// The best amplitude of one record for the pole (θ, λ), and the residual.
fn amplitudes_one(rec: &[f64], theta: f64, lambda: f64) -> SensorFit {
    let (a, g) = basis_sums(rec, theta, lambda);
    let (al, be) = solve2(a, g).unwrap_or((0.0, 0.0));
    let mut sum = 0.0;
    for_each_basis(rec, theta, lambda, |_, x, u, v| {
        let r = x - al * u - be * v;
        sum += r * r;
    });
    SensorFit {
        amplitude: (al, be),
        residual: libm::sqrt(sum / rec.len() as f64),
    }
}

/// Calls `f(k, x_k, u_k, v_k)` with `u_k + i (-v_k) = z^k`,
/// `z = e^{λ + iθ}`, by a complex recurrence renormalised every 64 steps.
fn for_each_basis(rec: &[f64], theta: f64, lambda: f64, mut f: impl FnMut(f64, f64, f64, f64)) {
    let e = libm::exp(lambda);
    let (rc, rs) = (e * libm::cos(theta), e * libm::sin(theta));
    let (mut zr, mut zi) = (1.0f64, 0.0f64);
    for (k, &x) in rec.iter().enumerate() {
        if k % 64 == 0 && k > 0 {
            let kf = k as f64;
            let m = libm::exp(lambda * kf);
            zr = m * libm::cos(theta * kf);
            zi = m * libm::sin(theta * kf);
        }
        f(k as f64, x, zr, -zi);
        let nr = zr * rc - zi * rs;
        zi = zr * rs + zi * rc;
        zr = nr;
    }
}

fn basis_sums(rec: &[f64], theta: f64, lambda: f64) -> ([[f64; 2]; 2], [f64; 2]) {
    let mut a = [[0.0; 2]; 2];
    let mut g = [0.0; 2];
    for_each_basis(rec, theta, lambda, |_, x, u, v| {
        a[0][0] += u * u;
        a[0][1] += u * v;
        a[1][1] += v * v;
        g[0] += u * x;
        g[1] += v * x;
    });
    a[1][0] = a[0][1];
    (a, g)
}

fn solve2(a: [[f64; 2]; 2], g: [f64; 2]) -> Option<(f64, f64)> {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    let scale = a[0][0] * a[1][1];
    if det.is_nan() || det <= 1e-14 * scale {
        return None;
    }
    Some((
        (g[0] * a[1][1] - g[1] * a[0][1]) / det,
        (a[0][0] * g[1] - a[1][0] * g[0]) / det,
    ))
}

/// One separable Gauss-Newton step on (θ, λ): the step, and whether the
/// residual is already at rounding level.
fn gauss_newton_step(records: &[&[f64]], theta: f64, lambda: f64) -> (Option<(f64, f64)>, bool) {
    // Reduced normal equations S δ = r over the sensors.
    let mut s = [[0.0f64; 2]; 2];
    let mut r = [0.0f64; 2];
    let (mut rss, mut total) = (0.0, 0.0);
    for rec in records {
        let (a, g) = basis_sums(rec, theta, lambda);
        let Some((al, be)) = solve2(a, g) else {
            return (None, false);
        };
        // Jacobian columns: ∂x/∂θ = -k e^{λk}(α sin θk + β cos θk),
        // ∂x/∂λ = k x_model; with u = e^{λk} cos θk, v = -e^{λk} sin θk.
        let mut b = [[0.0f64; 2]; 2]; // [u; v] x [θ, λ]
        let mut d = [[0.0f64; 2]; 2];
        let mut gp = [0.0f64; 2];
        for_each_basis(rec, theta, lambda, |k, x, u, v| {
            let model = al * u + be * v;
            let res = x - model;
            let jt = k * (al * v - be * u);
            let jl = k * model;
            b[0][0] += u * jt;
            b[0][1] += u * jl;
            b[1][0] += v * jt;
            b[1][1] += v * jl;
            d[0][0] += jt * jt;
            d[0][1] += jt * jl;
            d[1][1] += jl * jl;
            gp[0] += jt * res;
            gp[1] += jl * res;
            rss += res * res;
            total += x * x;
        });
        d[1][0] = d[0][1];
        // S += D - Bᵀ A⁻¹ B (the amplitudes are at their optimum, so their
        // gradient is zero and r gets Jᵀ res only).
        // M = A⁻¹ B, then S += D - Bᵀ M.
        let det = a[0][0] * a[1][1] - a[0][1] * a[0][1];
        let m = [
            [
                (a[1][1] * b[0][0] - a[0][1] * b[1][0]) / det,
                (a[1][1] * b[0][1] - a[0][1] * b[1][1]) / det,
            ],
            [
                (a[0][0] * b[1][0] - a[0][1] * b[0][0]) / det,
                (a[0][0] * b[1][1] - a[0][1] * b[0][1]) / det,
            ],
        ];
        s[0][0] += d[0][0] - (b[0][0] * m[0][0] + b[1][0] * m[1][0]);
        s[0][1] += d[0][1] - (b[0][0] * m[0][1] + b[1][0] * m[1][1]);
        s[1][0] += d[1][0] - (b[0][1] * m[0][0] + b[1][1] * m[1][0]);
        s[1][1] += d[1][1] - (b[0][1] * m[0][1] + b[1][1] * m[1][1]);
        r[0] += gp[0];
        r[1] += gp[1];
    }
    let tiny = rss <= 1e-28 * total;
    (solve2(s, r), tiny)
}

/// Solves the symmetric positive definite `n x n` system in place by
/// Cholesky; `None` when it is not positive definite.
fn solve_spd<const K: usize>(
    a: &mut [[f64; K]; K],
    g: &mut [f64; K],
    n: usize,
) -> Option<[f64; K]> {
    let n = n.min(K);
    let mut diag_max = 0.0f64;
    for (i, row) in a.iter().enumerate().take(n) {
        diag_max = diag_max.max(row.get(i).copied().unwrap_or(0.0));
    }
    for j in 0..n {
        let mut d = a.get(j)?.get(j).copied()?;
        for k in 0..j {
            let l = a.get(j)?.get(k).copied()?;
            d -= l * l;
        }
        if d.is_nan() || d <= 1e-13 * diag_max {
            return None;
        }
        let d = libm::sqrt(d);
        *a.get_mut(j)?.get_mut(j)? = d;
        for i in j + 1..n {
            let mut v = a.get(i)?.get(j).copied()?;
            for k in 0..j {
                v -= a.get(i)?.get(k).copied()? * a.get(j)?.get(k).copied()?;
            }
            *a.get_mut(i)?.get_mut(j)? = v / d;
        }
    }
    // Forward then back substitution.
    for i in 0..n {
        let mut v = g.get(i).copied()?;
        for k in 0..i {
            v -= a.get(i)?.get(k).copied()? * g.get(k).copied()?;
        }
        *g.get_mut(i)? = v / a.get(i)?.get(i).copied()?;
    }
    for i in (0..n).rev() {
        let mut v = g.get(i).copied()?;
        for k in i + 1..n {
            v -= a.get(k)?.get(i).copied()? * g.get(k).copied()?;
        }
        *g.get_mut(i)? = v / a.get(i)?.get(i).copied()?;
    }
    Some(*g)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples of `Re[c e^{(σ + iω) t}]` times `(σ + iω)^order`.
    fn decay(f0: f64, zeta: f64, dt: f64, c: (f64, f64), n: usize, out: &mut [f64]) -> (f64, f64) {
        let w0 = core::f64::consts::TAU * f0;
        let (s, w) = (-zeta * w0, w0 * libm::sqrt(1.0 - zeta * zeta));
        for (k, o) in out.iter_mut().enumerate().take(n) {
            let t = k as f64 * dt;
            let e = libm::exp(s * t);
            let (co, si) = (libm::cos(w * t), libm::sin(w * t));
            *o = e * (c.0 * co - c.1 * si);
        }
        (s, w)
    }

    #[test]
    fn clean_decay_is_fitted_to_rounding() {
        for (f0, zeta, per) in [
            (10.0, 0.001, 20.0),
            (100.0, 0.05, 200.0),
            (1000.0, 0.01, 50.0),
        ] {
            let dt = 1.0 / (f0 * per);
            let n = per as usize;
            let mut buf = [0.0f64; 256];
            decay(f0, zeta, dt, (0.3, -1.2), n, &mut buf);
            let mut out = [SensorFit::default(); 1];
            let fit = fit_first_period(dt, &[&buf[..n]], &mut out).unwrap();
            assert!((fit.mode.frequency / f0 - 1.0).abs() < 1e-10, "{fit:?}");
            assert!((fit.mode.damping - zeta).abs() < 1e-10, "{fit:?}");
            assert!((out[0].amplitude.0 - 0.3).abs() < 1e-9, "{out:?}");
            assert!((out[0].amplitude.1 + 1.2).abs() < 1e-9, "{out:?}");
            assert!(out[0].residual < 1e-10);
        }
    }

    #[test]
    fn sensors_share_the_pole() {
        let (f0, zeta, dt) = (50.0, 0.02, 1e-3);
        let mut a = [0.0f64; 20];
        let mut b = [0.0f64; 20];
        decay(f0, zeta, dt, (1.0, 0.0), 20, &mut a);
        decay(f0, zeta, dt, (-0.2, 0.5), 20, &mut b);
        let mut out = [SensorFit::default(); 2];
        let fit = fit_first_period(dt, &[&a, &b], &mut out).unwrap();
        assert!((fit.mode.frequency / f0 - 1.0).abs() < 1e-10);
        assert!((out[1].amplitude.0 + 0.2).abs() < 1e-9);
        assert!((out[1].amplitude.1 - 0.5).abs() < 1e-9);
    }

    #[test]
    fn amplitudes_of_two_known_modes() {
        let dt = 1e-3;
        let (mut a, mut b) = ([0.0f64; 200], [0.0f64; 200]);
        decay(10.0, 0.01, dt, (1.0, 0.5), 200, &mut a);
        decay(23.0, 0.02, dt, (-0.3, 0.2), 200, &mut b);
        let sum: [f64; 200] = core::array::from_fn(|k| a[k] + b[k]);
        let modes = [
            ModeInit {
                frequency: 10.0,
                damping: 0.01,
            },
            ModeInit {
                frequency: 23.0,
                damping: 0.02,
            },
        ];
        let mut out = [SensorFit::default(); 2];
        fit_amplitudes(dt, &modes, &[&sum], &mut out).unwrap();
        assert!((out[0].amplitude.0 - 1.0).abs() < 1e-9, "{out:?}");
        assert!((out[0].amplitude.1 - 0.5).abs() < 1e-9);
        assert!((out[1].amplitude.0 + 0.3).abs() < 1e-9);
        assert!((out[1].amplitude.1 - 0.2).abs() < 1e-9);
        assert!(out[0].residual < 1e-10);
    }

    #[test]
    fn bad_records_are_refused_with_their_reason() {
        let mut out = [SensorFit::default(); 1];
        let zeros = [0.0f64; 20];
        assert_eq!(
            fit_first_period(1e-3, &[&zeros], &mut out),
            Err(FitError::NoSignal)
        );
        let short = [1.0f64; 4];
        assert!(matches!(
            fit_first_period(1e-3, &[&short], &mut out),
            Err(FitError::TooShort {
                sensor: 0,
                got: 4,
                ..
            })
        ));
        let mut nan = [1.0f64; 20];
        nan[7] = f64::NAN;
        assert_eq!(
            fit_first_period(1e-3, &[&nan], &mut out),
            Err(FitError::NotFinite {
                sensor: 0,
                index: 7
            })
        );
        // A pure exponential has a real pole.
        let trend: [f64; 20] = core::array::from_fn(|k| libm::exp(-0.1 * k as f64));
        assert_eq!(
            fit_first_period(1e-3, &[&trend], &mut out),
            Err(FitError::NotOscillating)
        );
        assert!(matches!(
            fit_first_period(-1.0, &[&trend], &mut out),
            Err(FitError::Param(ParamError::NotPositive { .. }))
        ));
        let mut two = [SensorFit::default(); 2];
        assert!(matches!(
            fit_first_period(1e-3, &[&trend], &mut two),
            Err(FitError::Param(ParamError::LengthMismatch { .. }))
        ));
    }
}
