//! The modal tracker in free decay and through a signal gap, and the
//! instantaneous modulus of a Maxwell bank.

use bushing::tracker::{
    Channel, Filter, Measured, ModalTracker, ModeInit, ModulusSpec, ModulusTracker, SensorFit,
    SensorSpec, SineSpec, Tuning, fit_first_period,
};
use bushing::{Bushing, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};

use crate::check::{CaseResult, Failure, at_most, holds, param};
use bushing_kernels::Noise;

pub(crate) fn modal_tracker_free_decay_f32(filter: Filter) -> CaseResult {
    // A 100 Hz mode with 1 % damping seen by an accelerometer at 50 samples
    // per period, 40 dB of white noise (xorshift and Box-Muller), start
    // values off by 0.5 % and 0.2 points: after 10 periods the natural
    // frequency within 0.05 % and the damping within 0.02 points.
    let (f0, zeta, per) = (100.0f64, 0.01f64, 50.0f64);
    let w0 = core::f64::consts::TAU * f0;
    let wd = w0 * libm::sqrt(1.0 - zeta * zeta);
    let dt = core::f64::consts::TAU / (wd * per);
    let sigma = -zeta * w0;
    let accel = |t: f64| {
        let e = libm::exp(sigma * t);
        let (re, im) = (e * libm::cos(wd * t + 0.7), e * libm::sin(wd * t + 0.7));
        let (r1, i1) = (sigma * re - wd * im, sigma * im + wd * re);
        (sigma * r1 - wd * i1, sigma * i1 + wd * r1)
    };
    let (a0, b0) = accel(0.0);
    let noise = libm::sqrt((a0 * a0 + b0 * b0) / 2.0) * 1e-2;
    let tracker = bushing_kernels::offset_tracker::<f32>(dt, f0, zeta, (a0, b0), noise, filter)
        .map_err(param)?;
    let mut state = tracker.start();
    let mut rng = Noise::new(5);
    for step in 1..=(10.0 * per) as usize {
        let z = accel(step as f64 * dt).0 + noise * rng.gauss();
        let report = tracker.step(&mut state, &[z as f32]);
        if report.repaired || report.refused {
            return Err(Failure {
                what: "covariance repaired or sample refused at step",
                got: step as f64,
                bound: 0.0,
                bits: None,
            });
        }
    }
    let mode = tracker.mode(&state, 0);
    at_most(
        "natural frequency, relative error",
        libm::fabs(mode.frequency as f64 / f0 - 1.0),
        5e-4,
    )?;
    at_most(
        "damping ratio, absolute error",
        libm::fabs(mode.damping as f64 - zeta),
        2e-4,
    )
}

pub(crate) fn modal_tracker_fit_gap_reacquire_f32(filter: Filter) -> CaseResult {
    // A sustained 50 Hz vibration at 1 kHz, 40 dB of noise. The tracker
    // starts from the least-squares fit of the first period (f64, once),
    // tracks 2 s, then the sensor reads noise only for 1 s, then the signal
    // comes back 1 % higher in frequency with 80 % of the amplitude: 20
    // periods later the frequency is within 0.05 % and the amplitude within
    // 2 %, and the mode was faded during the gap.
    let (f0, dt) = (50.0f64, 1e-3f64);
    let noise = libm::sqrt(0.5) * 1e-2;
    let mut gauss = Noise::new(11);
    let w = core::f64::consts::TAU * f0;
    let signal = |k: usize| {
        let t = k as f64 * dt;
        if k < 2000 {
            libm::cos(w * t + 0.3)
        } else if k < 3000 {
            0.0
        } else {
            0.8 * libm::cos(1.01 * w * t)
        }
    };
    let mut first = [0.0f64; 21];
    for (k, x) in first.iter_mut().enumerate() {
        *x = signal(k) + noise * gauss.gauss();
    }
    let mut fitted = [SensorFit::default()];
    let fit = fit_first_period(dt, &[&first], &mut fitted).map_err(|_| Failure {
        what: "first-period fit refused",
        got: 0.0,
        bound: 0.0,
        bits: None,
    })?;
    at_most(
        "first-period fit, relative frequency error",
        libm::fabs(fit.mode.frequency / f0 - 1.0),
        0.01,
    )?;
    let tuning = Tuning {
        frequency_walk: 0.02,
        damping_walk: 1e-4,
        amplitude_walk: 0.02,
        ..Tuning::default()
    };
    let tracker = ModalTracker::<f32, 4>::new(
        dt,
        &[SensorSpec {
            measured: Measured::Displacement,
            noise,
        }],
        &[fit.mode],
        &[fitted[0].amplitude],
        &tuning,
        filter,
    )
    .map_err(param)?;
    let mut state = tracker.start();
    let mut faded = false;
    // Samples 1..21 were drawn for the fit; the rest come fresh.
    for &x in first.iter().skip(1) {
        tracker.step(&mut state, &[x as f32]);
    }
    let back = 3000 + (20.0 / (1.01 * f0 * dt)) as usize;
    for k in first.len()..=back {
        let x = signal(k) + noise * gauss.gauss();
        let report = tracker.step(&mut state, &[x as f32]);
        holds("no covariance repair", !report.repaired)?;
        faded |= tracker.mode(&state, 0).faded;
    }
    holds("the mode faded during the gap", faded)?;
    let mode = tracker.mode(&state, 0);
    holds("the mode is back", !mode.faded)?;
    let (re, im) = tracker.displacement(&state, 0, 0);
    at_most(
        "frequency 20 periods after the return, relative error",
        libm::fabs(mode.frequency as f64 / (1.01 * f0) - 1.0),
        5e-4,
    )?;
    at_most(
        "amplitude 20 periods after the return, relative error",
        libm::fabs(libm::hypot(re as f64, im as f64) / 0.8 - 1.0),
        0.02,
    )
}

pub(crate) fn instantaneous_modulus_maxwell_bank_f32() -> CaseResult {
    // A linear backbone with four exact-ramp Maxwell cells (corners 3, 30,
    // 300 and 3000 Hz, fraction 0.15 each), in f32, driven by a 100 Hz sine
    // at 100 samples per period after 20 time constants of its slowest cell
    // (the transient is then below 1e-8). The modulus tracker, started from
    // zero, must give storage and loss within 0.5 % of the discrete bank's
    // exact complex stiffness from 2 periods on.
    let (f, per) = (100.0f64, 100usize);
    let dt = 1.0 / (f * per as f64);
    let omega = core::f64::consts::TAU * f;
    let k_inf = 2.0e5;
    let specs = [3.0, 30.0, 300.0, 3000.0].map(|c| MaxwellSpec::hz(c, 0.15));
    let bank = MaxwellBank::<f32, 4>::new(MaxwellForm::RateExactRamp, &specs, dt).map_err(param)?;
    let (bs, bl) = bank.branch_response(omega);
    let k_ref = (k_inf * (0.4 + bs), k_inf * bl);
    let bushing = Bushing::new(Polynomial::<f32, 2>::linear(k_inf).map_err(param)?, (bank,))
        .map_err(param)?;
    let mut state = bushing.state_at(0.0);
    let x0 = 1.0e-3;
    let f0 = x0 * libm::hypot(k_ref.0, k_ref.1);
    let tracker = ModulusTracker::<f32>::new(
        dt,
        &ModulusSpec {
            sine: SineSpec {
                frequency: f,
                bandwidth: f / 20.0,
            },
            displacement: Channel {
                noise: 1e-4 * x0,
                amplitude: x0,
            },
            force: Channel {
                noise: 1e-4 * f0,
                amplitude: f0,
            },
            min_snr: 10.0,
        },
    )
    .map_err(param)?;
    let mut ts = tracker.start();
    let warm_up = (20.0 / (core::f64::consts::TAU * 3.0 * dt)) as usize + per / 3;
    let (mut storage, mut loss) = (0.0f64, 0.0f64);
    for n in 1..=warm_up + 12 * per {
        let x = x0 * libm::sin(omega * dt * n as f64);
        let force = bushing.step(&mut state, x as f32).force;
        if n <= warm_up {
            continue;
        }
        holds(
            "modulus tracker step accepted",
            tracker.step(&mut ts, x as f32, force).is_ok(),
        )?;
        if n >= warm_up + 2 * per {
            let Some(m) = tracker.modulus(&ts) else {
                return holds("modulus available after 2 periods", false);
            };
            storage = storage.max(libm::fabs(m.storage as f64 / k_ref.0 - 1.0));
            loss = loss.max(libm::fabs(m.loss as f64 / k_ref.1 - 1.0));
        }
    }
    at_most("storage modulus, relative error", storage, 5e-3)?;
    at_most("loss modulus, relative error", loss, 5e-3)
}

/// A two-mode tracker on three accelerometers (16 states) with its mode
/// count fixed at compile time against the same tracker with it given at
/// run time: bit for bit the same estimate and covariance after every
/// step of two close modes in noise, on the host and on every target.
pub(crate) fn modal_tracker_modes_fixed_same_bits_f32(filter: Filter) -> CaseResult {
    let dt = 1e-3;
    let sensors = [SensorSpec {
        measured: Measured::Acceleration,
        noise: 0.5,
    }; 3];
    let modes = [
        ModeInit {
            frequency: 20.0,
            damping: 0.01,
        },
        ModeInit {
            frequency: 31.0,
            damping: 0.01,
        },
    ];
    let amplitudes = [
        (1.0, 0.0),
        (0.6, 0.2),
        (-0.8, 0.1),
        (0.5, 0.0),
        (-1.0, 0.3),
        (0.9, 0.0),
    ];
    let tuning = Tuning::default();
    let fixed = ModalTracker::<f32, 16, 2>::new(dt, &sensors, &modes, &amplitudes, &tuning, filter)
        .map_err(param)?;
    let free = ModalTracker::<f32, 16>::new(dt, &sensors, &modes, &amplitudes, &tuning, filter)
        .map_err(param)?;
    let (mut a, mut b) = (fixed.start(), free.start());
    let mut rng = Noise::new(17);
    let w = [20.2, 30.7].map(|f: f64| core::f64::consts::TAU * f);
    for k in 1..=300 {
        let t = k as f64 * dt;
        let y: [f32; 3] = core::array::from_fn(|c| {
            let shape = [[1.0, 0.5], [0.6, -1.0], [-0.8, 0.9]][c];
            let z = shape[0] * libm::cos(w[0] * t) + shape[1] * libm::sin(w[1] * t);
            (z + 0.5 * rng.gauss()) as f32
        });
        let (ra, rb) = (fixed.step(&mut a, &y), free.step(&mut b, &y));
        let same = ra == rb
            && a.x()
                .iter()
                .zip(b.x())
                .all(|(p, q)| p.to_bits() == q.to_bits())
            && a.covariance()
                .iter()
                .flatten()
                .zip(b.covariance().iter().flatten())
                .all(|(p, q)| p.to_bits() == q.to_bits());
        if !same {
            return Err(Failure {
                what: "the two forms differ at step",
                got: k as f64,
                bound: 0.0,
                bits: None,
            });
        }
    }
    holds("a finite estimate", a.x().iter().all(|v| v.is_finite()))
}
