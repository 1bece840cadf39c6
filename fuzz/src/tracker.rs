//! The trackers: `ModalTracker` (EKF and UKF with any `UtParams`, each
//! sensor kind, one or two modes and sensors, any `Tuning`) on damped sines
//! with noise, outliers and garbage; its start values from
//! `fit_first_period` or `fit_amplitudes`; `SineTracker` and
//! `ModulusTracker`; the relevance check; the scalar unscented transform
//! and linearisation.
//!
//! Contract: no panic; the trackers' states stay finite; a relevance
//! curve computed without error is finite.

use std::f64::consts::TAU;

use arbitrary::{Result, Unstructured};
use bushing::tracker::{
    Channel, Filter, Measured, ModalTracker, ModeInit, ModulusSpec, ModulusTracker, ScalarUt,
    SensorFit, SensorSpec, SineSpec, SineTracker, Tuning, UtParams, damping_from_frequency,
    damping_from_frequency_uniform, fit_amplitudes, fit_first_period,
    frequency_from_damping_uniform, linearised_scalar, unscented_scalar,
};

use crate::contract::built;
use crate::draw::{decades, param};
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    match u.int_in_range(0u8..=7)? {
        0..=2 => {
            let (modes, sensors) = (u.int_in_range(1..=2)?, u.int_in_range(1..=2)?);
            let setup = Setup::draw(u, modes, sensors)?;
            modal::<T>(u, &setup)
        }
        3 => start_values::<T>(u),
        4 => sine::<T>(u),
        5 => modulus::<T>(u),
        6 if !T::FIXED => relevance(u),
        _ => unscented::<T>(u),
    }
}

/// The set-up of a modal tracker and the modes it is shown.
struct Setup {
    dt: f64,
    sensors: Vec<SensorSpec>,
    modes: Vec<ModeInit>,
    /// Complex amplitude of mode m at sensor c, `m * sensors + c`.
    amplitudes: Vec<(f64, f64)>,
}

impl Setup {
    fn draw(u: &mut Unstructured<'_>, modes: usize, sensors: usize) -> Result<Self> {
        let dt = decades(u, 1e-4, 1e-2)?;
        let mut s = Self {
            dt,
            sensors: Vec::new(),
            modes: Vec::new(),
            amplitudes: Vec::new(),
        };
        for _ in 0..sensors {
            s.sensors.push(SensorSpec {
                measured: *u.choose(&[
                    Measured::Displacement,
                    Measured::Velocity,
                    Measured::Acceleration,
                ])?,
                noise: decades(u, 1e-4, 1.0)?,
            });
        }
        for _ in 0..modes {
            s.modes.push(ModeInit {
                frequency: decades(u, 0.5, 0.4 / dt)?,
                damping: param(u, -0.02, 0.2)?,
            });
        }
        for _ in 0..modes * sensors {
            s.amplitudes
                .push((param(u, -10.0, 10.0)?, param(u, -10.0, 10.0)?));
        }
        Ok(s)
    }

    /// The clean sample of sensor `c` at step `k`: the real part of
    /// `Σ_m A_mc s_m^order e^{s_m k dt}`, `s_m = -ξ ω_0 + i ω_0 √(1 - ξ²)`.
    fn clean(&self, c: usize, k: usize) -> f64 {
        let t = k as f64 * self.dt;
        let order = self.sensors.get(c).map_or(0, |s| s.measured.order());
        let mut sum = 0.0;
        for (m, mode) in self.modes.iter().enumerate() {
            let w0 = TAU * mode.frequency;
            let z = mode.damping;
            let (sr, si) = (-z * w0, w0 * (1.0 - z * z).abs().sqrt());
            let (mut re, mut im) = self
                .amplitudes
                .get(m * self.sensors.len() + c)
                .copied()
                .unwrap_or_default();
            for _ in 0..order {
                (re, im) = (re * sr - im * si, re * si + im * sr);
            }
            let (e, phase) = ((sr * t).exp(), si * t);
            sum += e * (re * phase.cos() - im * phase.sin());
        }
        sum
    }
}

/// A measured sample: mostly `clean` with noise of standard deviation
/// about `noise`, sometimes an outlier, a special value or any bit
/// pattern.
fn sample<T: Num>(u: &mut Unstructured<'_>, clean: f64, noise: f64) -> Result<T> {
    Ok(match u.int_in_range(0u8..=31)? {
        0 => T::any(u)?,
        1 => T::from_f64(*u.choose(&[f64::NAN, f64::INFINITY, -f64::INFINITY, 1e30, 0.0])?),
        2 => T::from_f64(clean * param(u, -100.0, 100.0)?),
        _ => T::from_f64(clean + noise * u.int_in_range(-1000i32..=1000)? as f64 * 1e-3),
    })
}

fn finite<'a, T: Num + 'a>(v: impl IntoIterator<Item = &'a T>) -> bool {
    v.into_iter().all(|x| x.is_finite())
}

fn modal<T: Num>(u: &mut Unstructured<'_>, setup: &Setup) -> Result<()> {
    if u.ratio(1u8, 32)? {
        // Whatever the set-up, a state count that may not match it.
        return modal_in::<T, 4>(u, setup);
    }
    match (setup.modes.len(), setup.sensors.len()) {
        (1, 1) => modal_in::<T, 4>(u, setup),
        (1, 2) => modal_in::<T, 6>(u, setup),
        (2, 1) => modal_in::<T, 8>(u, setup),
        _ => modal_in::<T, 12>(u, setup),
    }
}

fn tuning(u: &mut Unstructured<'_>) -> Result<Tuning> {
    if u.arbitrary()? {
        return Ok(Tuning::default());
    }
    Ok(Tuning {
        frequency_walk: param(u, 0.0, 1.0)?,
        damping_walk: param(u, 0.0, 0.1)?,
        amplitude_walk: param(u, 0.0, 1.0)?,
        initial_frequency_error: decades(u, 1e-4, 0.1)?,
        initial_damping_error: decades(u, 1e-4, 0.1)?,
        initial_amplitude_error: decades(u, 1e-3, 1.0)?,
        gate: param(u, 1.0, 10.0)?,
        outlier_run: u.int_in_range(0..=16)?,
        fade_snr: param(u, 0.0, 10.0)?,
        max_damping: param(u, 0.0, 0.99)?,
        max_frequency: param(u, 0.0, 0.99)?,
    })
}

fn ut_params(u: &mut Unstructured<'_>) -> Result<Option<UtParams>> {
    let (alpha, beta, kappa) = (
        param(u, 0.0, 1.0)?,
        param(u, 0.0, 4.0)?,
        param(u, 0.0, 3.0)?,
    );
    Ok(if u.arbitrary()? {
        built(UtParams::new(alpha, beta, kappa))
    } else {
        Some(UtParams { alpha, beta, kappa })
    })
}

fn modal_in<T: Num, const N: usize>(u: &mut Unstructured<'_>, setup: &Setup) -> Result<()> {
    let filter = match u.int_in_range(0u8..=2)? {
        0 => Filter::Ekf,
        1 => Filter::Ukf(UtParams::default()),
        _ => match ut_params(u)? {
            Some(ut) => Filter::Ukf(ut),
            None => return Ok(()),
        },
    };
    let tuning = tuning(u)?;
    let Some(t) = built(ModalTracker::<T, N>::new(
        setup.dt,
        &setup.sensors,
        &setup.modes,
        &setup.amplitudes,
        &tuning,
        filter,
    )) else {
        return Ok(());
    };
    let _ = t.dt();
    let mut s = t.start();
    let mut samples = [T::ZERO; 2];
    for k in 0..u.int_in_range(1usize..=256)? {
        for (c, (y, sensor)) in samples.iter_mut().zip(&setup.sensors).enumerate() {
            *y = sample(u, setup.clean(c, k), sensor.noise)?;
        }
        let report = t.step(&mut s, samples.get(..t.sensors()).unwrap_or(&[]));
        assert!(
            finite(s.x()) && finite(s.covariance().iter().flatten()),
            "non-finite tracker state after {report:?}"
        );
        for m in 0..t.modes() {
            let _ = t.mode(&s, m);
            for c in 0..t.sensors() {
                let _ = t.displacement(&s, m, c);
            }
        }
    }
    Ok(())
}

/// Start values fitted to a record of the set-up's modes, then tracked.
fn start_values<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let (modes, sensors) = (u.int_in_range(1..=2)?, u.int_in_range(1..=2)?);
    let mut setup = Setup::draw(u, modes, sensors)?;
    let len = u.int_in_range(0usize..=96)?;
    let mut records = vec![Vec::new(); sensors];
    for (c, (record, sensor)) in records.iter_mut().zip(&setup.sensors).enumerate() {
        for k in 0..len {
            let y: f64 = sample(u, setup.clean(c, k), sensor.noise)?;
            record.push(y);
        }
    }
    let records: Vec<&[f64]> = records.iter().map(Vec::as_slice).collect();
    let fitted = if modes == 1 && u.arbitrary()? {
        let mut out = vec![SensorFit::default(); sensors];
        fit_first_period(setup.dt, &records, &mut out).map(|fit| {
            setup.modes = vec![fit.mode];
            out
        })
    } else {
        let mut out = vec![SensorFit::default(); modes * sensors];
        fit_amplitudes(setup.dt, &setup.modes, &records, &mut out).map(|()| out)
    };
    match fitted {
        Ok(out) => {
            setup.amplitudes = out.iter().map(|f| f.amplitude).collect();
            modal::<T>(u, &setup)
        }
        Err(e) => {
            let _ = e.to_string();
            Ok(())
        }
    }
}

fn sine_spec(u: &mut Unstructured<'_>) -> Result<(f64, SineSpec)> {
    let dt = decades(u, 1e-4, 1e-2)?;
    let frequency = decades(u, 0.1, 0.45 / dt)?;
    Ok((
        dt,
        SineSpec {
            frequency,
            bandwidth: decades(u, 1e-3, 0.5 * frequency)?,
        },
    ))
}

fn channel(u: &mut Unstructured<'_>) -> Result<Channel> {
    Ok(Channel {
        noise: decades(u, 1e-4, 1.0)?,
        amplitude: decades(u, 1e-2, 10.0)?,
    })
}

fn sine<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let (dt, spec) = sine_spec(u)?;
    let channel = channel(u)?;
    let Some(t) = built(SineTracker::<T>::new(dt, &spec, channel)) else {
        return Ok(());
    };
    let _ = (t.dt(), t.frequency(), t.bandwidth(), t.envelope_pole());
    let (amplitude, phase) = (param(u, 0.0, 10.0)?, param(u, 0.0, TAU)?);
    let mut s = t.start();
    for k in 0..u.int_in_range(1usize..=512)? {
        let clean = amplitude * (TAU * spec.frequency * k as f64 * dt + phase).sin();
        let _ = t.step(&mut s, sample(u, clean, channel.noise)?);
        assert!(finite(&[s.a(), s.b()]), "non-finite sine tracker state");
        let _ = (t.predict(&s), t.gain(&s), t.covariance(&s), s.amplitude());
        let _ = (s.pair(), s.refused(), s.repairs());
    }
    Ok(())
}

fn modulus<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let (dt, sine) = sine_spec(u)?;
    let spec = ModulusSpec {
        sine,
        displacement: channel(u)?,
        force: channel(u)?,
        min_snr: param(u, 0.0, 20.0)?,
    };
    let Some(t) = built(ModulusTracker::<T>::new(dt, &spec)) else {
        return Ok(());
    };
    let _ = (t.dt(), t.frequency(), t.bandwidth());
    let (x, k, delta) = (
        param(u, 0.0, 5.0)?,
        decades(u, 1.0, 1e4)?,
        param(u, 0.0, 1.5)?,
    );
    let mut s = t.start();
    for n in 0..u.int_in_range(1usize..=512)? {
        let phase = TAU * sine.frequency * n as f64 * dt;
        let d = sample(u, x * phase.sin(), spec.displacement.noise)?;
        let f = sample(u, k * x * (phase + delta).sin(), spec.force.noise)?;
        let _ = t.step(&mut s, d, f);
        let (a, b) = (s.displacement(), s.force());
        assert!(
            finite(&[a.0, a.1, b.0, b.1]),
            "non-finite modulus tracker state"
        );
        if let Some(m) = t.modulus(&s) {
            let _ = (m.magnitude(), m.loss_factor());
        }
        let _ = (
            t.covariance(&s, 0),
            t.covariance(&s, 1),
            s.refused(),
            s.repairs(),
        );
    }
    Ok(())
}

/// The relevance check on curves of up to 8 points (sometimes an output
/// of another length).
fn relevance(u: &mut Unstructured<'_>) -> Result<()> {
    let n = u.int_in_range(0usize..=8)?;
    let m = if u.ratio(1u8, 16)? { n + 1 } else { n };
    let (mut omega, mut amplitude, mut damping) = ([0.0; 8], [0.0; 8], [0.0; 8]);
    let (mut w, mut a) = (decades(u, 1.0, 1e3)?, 0.0);
    for ((wi, ai), xi) in omega
        .iter_mut()
        .zip(&mut amplitude)
        .zip(&mut damping)
        .take(n)
    {
        *wi = w;
        w *= param(u, 0.9, 1.0)?;
        a += decades(u, 1e-3, 1.0)?;
        *ai = a;
        *xi = param(u, -0.1, 0.5)?;
    }
    let mut out = [0.0; 9];
    let r = match u.int_in_range(0u8..=2)? {
        0 => damping_from_frequency_uniform(&omega[..n], &mut out[..m]),
        1 => damping_from_frequency(&amplitude[..n], &omega[..n], &mut out[..m]),
        _ => frequency_from_damping_uniform(decades(u, 1.0, 1e3)?, &damping[..n], &mut out[..m]),
    };
    if built(r).is_some() {
        assert!(
            finite(&out[..m]),
            "a non-finite relevance curve: {:?}",
            &out[..m]
        );
    }
    Ok(())
}

fn unscented<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let Some(ut) = ut_params(u)? else {
        return Ok(());
    };
    let mut c = [T::ZERO; 4];
    for ck in &mut c {
        *ck = T::from_f64(param(u, -10.0, 10.0)?);
    }
    let g = |x: T| c[0] + x * (c[1] + x * (c[2] + x * c[3]));
    let dg = |x: T| c[1] + x * (T::from_f64(2.0) * c[2] + T::from_f64(3.0) * x * c[3]);
    let (mean, variance) = if u.ratio(1u8, 8)? {
        (T::any(u)?, T::any(u)?)
    } else {
        (
            T::from_f64(param(u, -10.0, 10.0)?),
            T::from_f64(param(u, 0.0, 10.0)?),
        )
    };
    if let Some(s) = built(ScalarUt::<T>::new(&ut)) {
        let _ = (s.spread(), s.mean_weights(), s.covariance_weights());
        let _ = built(s.sigma_points(mean, variance));
        let _ = built(s.transform(mean, variance, g));
    }
    let _ = built(unscented_scalar(&ut, mean, variance, g));
    let _ = built(linearised_scalar(mean, variance, g, dg));
    Ok(())
}
