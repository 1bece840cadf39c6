use bushing_kernels::Noise;

use super::*;
use core::f64::consts::TAU;

fn spec(frequency: f64, bandwidth: f64) -> SineSpec {
    SineSpec {
        frequency,
        bandwidth,
    }
}

const CH: Channel = Channel {
    noise: 1e-3,
    amplitude: 1.0,
};

#[test]
fn bad_parameters_are_typed_errors() {
    let new = |dt, f, b, n, a| {
        SineTracker::<f32>::new(
            dt,
            &spec(f, b),
            Channel {
                noise: n,
                amplitude: a,
            },
        )
    };
    assert!(new(1e-3, 10.0, 0.5, 1e-3, 1.0).is_ok());
    let not_positive = |r: Result<SineTracker<f32>, ParamError>, name| matches!(r, Err(ParamError::NotPositive { param, .. }) if param == Param::scalar(name));
    let not_finite = |r: Result<SineTracker<f32>, ParamError>, name| matches!(r, Err(ParamError::NotFinite { param }) if param == Param::scalar(name));
    let out_of_range = |r: Result<SineTracker<f32>, ParamError>, name| matches!(r, Err(ParamError::OutOfRange { param, .. }) if param == Param::scalar(name));
    assert!(not_positive(new(0.0, 10.0, 0.5, 1e-3, 1.0), "dt"));
    assert!(not_positive(new(-1e-3, 10.0, 0.5, 1e-3, 1.0), "dt"));
    assert!(not_finite(new(f64::NAN, 10.0, 0.5, 1e-3, 1.0), "dt"));
    assert!(not_positive(new(1e-3, 0.0, 0.5, 1e-3, 1.0), "frequency"));
    assert!(not_finite(
        new(1e-3, f64::INFINITY, 0.5, 1e-3, 1.0),
        "frequency"
    ));
    // Nyquist is 500 Hz at 1 kHz: refused at and above it.
    assert!(out_of_range(new(1e-3, 500.0, 0.5, 1e-3, 1.0), "frequency"));
    assert!(new(1e-3, 499.0, 0.5, 1e-3, 1.0).is_ok());
    assert!(not_positive(new(1e-3, 10.0, 0.0, 1e-3, 1.0), "bandwidth"));
    assert!(not_finite(
        new(1e-3, 10.0, f64::NAN, 1e-3, 1.0),
        "bandwidth"
    ));
    // Above f/2, or so wide that K > 1/4.
    assert!(out_of_range(new(1e-3, 10.0, 5.1, 1e-3, 1.0), "bandwidth"));
    assert!(new(1e-3, 10.0, 5.0, 1e-3, 1.0).is_ok());
    assert!(out_of_range(new(1e-3, 400.0, 50.0, 1e-3, 1.0), "bandwidth"));
    // So narrow that the rounding of the update would matter in f32
    // (K < 1024 ε) but not in f64.
    let narrow = 1e-4 / (TAU * 1e-3);
    assert!(out_of_range(
        new(1e-3, 10.0, narrow, 1e-3, 1.0),
        "bandwidth"
    ));
    assert!(
        SineTracker::<f64>::new(
            1e-3,
            &spec(10.0, narrow),
            Channel {
                noise: 1e-3,
                amplitude: 1.0
            }
        )
        .is_ok()
    );
    assert!(not_positive(new(1e-3, 10.0, 0.5, 0.0, 1.0), "noise"));
    assert!(not_finite(new(1e-3, 10.0, 0.5, f64::NAN, 1.0), "noise"));
    assert!(not_positive(new(1e-3, 10.0, 0.5, 1e-3, -1.0), "amplitude"));
    assert!(not_finite(new(1e-3, 10.0, 0.5, 1e-300, 1e300), "amplitude"));

    let m = |x: Channel, f: Channel, snr| {
        ModulusTracker::<f32>::new(
            1e-3,
            &ModulusSpec {
                sine: spec(10.0, 0.5),
                displacement: x,
                force: f,
                min_snr: snr,
            },
        )
    };
    assert!(m(CH, CH, 10.0).is_ok());
    let bad = Channel {
        noise: -1.0,
        amplitude: 1.0,
    };
    assert!(matches!(
        m(bad, CH, 10.0),
        Err(ParamError::NotPositive { param, .. }) if param == Param::scalar("displacement_noise")
    ));
    assert!(matches!(
        m(CH, bad, 10.0),
        Err(ParamError::NotPositive { param, .. }) if param == Param::scalar("force_noise")
    ));
    assert!(matches!(
        m(CH, CH, 0.0),
        Err(ParamError::NotPositive { param, .. }) if param == Param::scalar("min_snr")
    ));
}

/// Runs a tracker on `x_n = Re[u e^{iθn}] (+ noise)` and returns the
/// largest error `|a + ib - u e^{iθn}| / |u|` from sample `from` on.
fn clean_error<T: Real>(samples: usize, periods: usize, from: usize) -> f64 {
    let f = 10.0;
    let dt = 1.0 / (f * samples as f64);
    let tr = SineTracker::<T>::new(dt, &spec(f, f / 20.0), CH).unwrap();
    let mut s = tr.start();
    let (ur, ui) = (0.6, -0.8);
    let mut worst: f64 = 0.0;
    for n in 0..samples * periods {
        let ph = TAU * (n % samples) as f64 / samples as f64;
        let (c, sn) = (libm::cos(ph), libm::sin(ph));
        let (re, im) = (ur * c - ui * sn, ur * sn + ui * c);
        assert_eq!(tr.predict(&s), tr.kernel.rotate(s.pair()).0);
        tr.step(&mut s, T::from_f64(re)).unwrap();
        if n >= from {
            let (a, b) = s.pair();
            let e = libm::hypot(a.to_f64() - re, b.to_f64() - im);
            worst = worst.max(e);
        }
    }
    assert_eq!(s.repairs(), 0);
    worst
}

#[test]
fn clean_sine_is_fitted_exactly_after_one_period() {
    // The model holds, so the filter is exact once the prior is
    // outweighed: the prior's pull is about 2 / (N p0) with N samples and
    // p0 = (amplitude / noise)² = 1e6 (f64) or 1 / (64 ε) = 1.3e5 (f32).
    for samples in [4, 10, 50, 200] {
        let e64 = clean_error::<f64>(samples, 6, samples);
        assert!(e64 < 1e-6, "f64, {samples} samples/period: {e64:e}");
        let e32 = clean_error::<f32>(samples, 6, samples);
        assert!(e32 < 2e-5, "f32, {samples} samples/period: {e32:e}");
    }
}

#[test]
fn steady_state_corner_is_the_bandwidth() {
    // The steady-state error dynamics (I - k H) F have the pole pair
    // ρ e^{±iθ} with ρ² = det = 1 - k_a: compare ρ with e^{-2π B Δt}.
    // The design averages the measurement over a period, so it holds
    // to O(B/f) and O(1/samples).
    for (samples, ratios, tol) in [
        (50usize, [0.01, 0.05, 0.2], 0.01),
        (200, [0.01, 0.05, 0.2], 0.01),
        (1000, [0.01, 0.05, 0.2], 0.01),
        (4, [0.01, 0.02, 0.05], 0.05),
        (10, [0.01, 0.02, 0.05], 0.05),
    ] {
        for r in ratios {
            let f = 1.0;
            let dt = 1.0 / (f * samples as f64);
            let tr = SineTracker::<f64>::new(dt, &spec(f, r * f), CH).unwrap();
            let mut s = tr.start();
            // The covariance does not depend on the data; 12 time
            // constants of the envelope.
            let n = (12.0 / (TAU * r * f * dt)) as usize;
            for _ in 0..n {
                tr.step(&mut s, 0.0).unwrap();
            }
            let (k0, _) = tr.gain(&s);
            let rho = libm::sqrt(1.0 - k0);
            let corner = libm::log(rho) / libm::log(tr.envelope_pole());
            assert!(
                (corner - 1.0).abs() < tol,
                "{samples} samples/period, B = {r} f: corner {corner}"
            );
        }
    }
}

#[test]
fn steady_noise_on_the_estimate_is_sigma_root_k() {
    // The envelope low-pass of pole 1 - K fed by the measurement noise
    // leaves σ² K on each of a and b; the filter's covariance, which
    // also allows for the amplitude wander, says 2K. 2e6 samples are
    // about 3000 correlation times: 1.3 % statistical spread on the
    // standard deviation.
    let (f, samples, sigma) = (10.0, 200usize, 0.01);
    let dt = 1.0 / (f * samples as f64);
    let ch = Channel {
        noise: sigma,
        amplitude: 1.0,
    };
    let tr = SineTracker::<f64>::new(dt, &spec(f, 0.05 * f), ch).unwrap();
    let k = 1.0 - tr.envelope_pole();
    let mut s = tr.start();
    let mut g = Noise::from_state(0x2545_f491_4f6c_dd1d);
    let first = (20.0 / k) as usize;
    let (mut sa, mut sb, mut count) = (0.0, 0.0, 0.0);
    for n in 0..first + 2_000_000 {
        let ph = TAU * f * dt * n as f64;
        let (c, sn) = (libm::cos(ph), libm::sin(ph));
        tr.step(&mut s, c + sigma * g.gauss()).unwrap();
        if n >= first {
            let (a, b) = s.pair();
            sa += (a - c) * (a - c);
            sb += (b - sn) * (b - sn);
            count += 1.0;
        }
    }
    let expected = sigma * libm::sqrt(k);
    for (name, v) in [("a", sa), ("b", sb)] {
        let std = libm::sqrt(v / count);
        assert!(
            (std / expected - 1.0).abs() < 0.05,
            "{name}: {std:e} vs σ√K = {expected:e}"
        );
    }
    let p = tr.covariance(&s);
    let said = sigma * sigma * 2.0 * k;
    assert!((p[0][0] / said - 1.0).abs() < 0.05 && (p[1][1] / said - 1.0).abs() < 0.05);
}

#[test]
fn a_constant_offset_leaks_as_two_b_over_f() {
    // In the frame turning with the sine, an offset D sits at -f, where
    // the envelope low-pass of corner B passes about 2 (B/f) D.
    for ratio in [0.01, 0.05] {
        let (f, samples, offset) = (10.0, 200usize, 0.3);
        let dt = 1.0 / (f * samples as f64);
        let tr = SineTracker::<f64>::new(dt, &spec(f, ratio * f), CH).unwrap();
        let k = 1.0 - tr.envelope_pole();
        let mut s = tr.start();
        let first = (30.0 / k) as usize;
        let mut worst: f64 = 0.0;
        for n in 0..first + 20 * samples {
            let ph = TAU * f * dt * n as f64;
            let (c, sn) = (libm::cos(ph), libm::sin(ph));
            tr.step(&mut s, c + offset).unwrap();
            if n >= first {
                let (a, b) = s.pair();
                worst = worst.max(libm::hypot(a - c, b - sn));
            }
        }
        let expected = 2.0 * ratio * offset;
        assert!(
            (worst / expected - 1.0).abs() < 0.05,
            "B = {ratio} f: {worst:e} vs {expected:e}"
        );
    }
}

#[test]
fn non_finite_samples_are_refused_and_the_phase_kept() {
    let dt = 1e-3;
    let tr = SineTracker::<f32>::new(dt, &spec(10.0, 0.5), CH).unwrap();
    let mut s = tr.start();
    let x = |n: usize| libm::sin(TAU * 10.0 * dt * n as f64) as f32;
    for n in 0..300 {
        tr.step(&mut s, x(n)).unwrap();
    }
    for (n, bad) in [
        (300, f32::NAN),
        (301, f32::INFINITY),
        (302, f32::NEG_INFINITY),
    ] {
        let before = s.clone();
        assert_eq!(tr.step(&mut s, bad), Err(Refused::NonFiniteSample));
        // The prediction only: rotated estimate, grown covariance.
        assert_eq!(s.pair(), tr.kernel.rotate(before.pair()));
        assert!(tr.covariance(&s)[0][0] + tr.covariance(&s)[1][1] > 0.0);
        let _ = n;
    }
    assert_eq!(s.refused(), 3);
    // The next sample fits the phase carried through the gap.
    let y = tr.step(&mut s, x(303)).unwrap();
    assert!(y.abs() < 1e-3, "innovation after the gap {y}");
    assert!((s.amplitude() - 1.0).abs() < 1e-3);

    // A sample whose update would take the state beyond GUARD (2^60) is
    // refused too, with the same prediction; 2^59 is taken.
    let mut big = tr.start();
    assert_eq!(tr.step(&mut big, f32::MAX), Err(Refused::Overflow));
    assert_eq!(big.pair(), (0.0, 0.0));
    tr.step(&mut big, 2f32.powi(59)).unwrap();
    assert!(big.a() > 0.99 * 2f32.powi(59) && big.a() <= f32::GUARD);
    let kept = big.clone();
    assert_eq!(tr.step(&mut big, -f32::MAX), Err(Refused::Overflow));
    assert_eq!(big.pair(), tr.kernel.rotate(kept.pair()));
    assert_eq!(big.refused(), 2);

    // The modulus tracker refuses the pair if either sample is bad.
    let m = ModulusTracker::<f32>::new(
        dt,
        &ModulusSpec {
            sine: spec(10.0, 0.5),
            displacement: CH,
            force: CH,
            min_snr: 10.0,
        },
    )
    .unwrap();
    let mut ms = m.start();
    assert_eq!(
        m.step(&mut ms, 1.0, f32::NAN),
        Err(Refused::NonFiniteSample)
    );
    assert_eq!(ms.displacement(), (0.0, 0.0));
    assert_eq!(ms.refused(), 1);
}

/// Runs f32 and f64 trackers side by side on a noisy sine and checks
/// the f32 covariance at every step.
fn covariance_run(samples: usize, ratio: f64, snr: f64, steps: usize) {
    let f = 50.0;
    let dt = 1.0 / (f * samples as f64);
    let ch = Channel {
        noise: 1.0 / snr,
        amplitude: 1.0,
    };
    let t32 = SineTracker::<f32>::new(dt, &spec(f, ratio * f), ch).unwrap();
    let t64 = SineTracker::<f64>::new(dt, &spec(f, ratio * f), ch).unwrap();
    let (mut s32, mut s64) = (t32.start(), t64.start());
    let mut g = Noise::from_state(0x9e37_79b9_7f4a_7c15);
    for n in 0..steps {
        let z = libm::sin(TAU * f * dt * n as f64 + 0.4) + g.gauss() / snr;
        t32.step(&mut s32, z as f32).unwrap();
        t64.step(&mut s64, z).unwrap();
        let p = t32.covariance(&s32);
        assert_eq!(p[0][1], p[1][0]);
        let det = p[0][0] as f64 * p[1][1] as f64 - p[0][1] as f64 * p[0][1] as f64;
        assert!(
            p[0][0] > 0.0 && p[1][1] > 0.0 && det >= 0.0,
            "{samples} samples/period, step {n}: {p:?}"
        );
    }
    assert_eq!(s32.repairs(), 0);
    assert_eq!(s64.repairs(), 0);
    // Steady state: the f32 covariance and estimate follow f64's.
    let (p32, p64) = (t32.covariance(&s32), t64.covariance(&s64));
    let scale = p64[0][0] + p64[1][1];
    for i in 0..2 {
        for j in 0..2 {
            let d = (p32[i][j] as f64 - p64[i][j]).abs() / scale;
            assert!(
                d < 1e-3,
                "{samples}: P[{i}][{j}] {} vs {}",
                p32[i][j],
                p64[i][j]
            );
        }
    }
    let (a32, b32) = s32.pair();
    let (a64, b64) = s64.pair();
    let d = libm::hypot(a32 as f64 - a64, b32 as f64 - b64);
    assert!(d < 1e-4, "{samples}: estimate differs by {d:e}");
}

#[test]
fn f32_covariance_stays_symmetric_positive_over_long_runs() {
    // From 4 to 2000 samples per period, narrow and wide bandwidths,
    // noisy and near-clean signals (the cap on the initial variance
    // matters for the latter), 200 000 steps each.
    for (samples, ratio, snr) in [
        (4, 0.01, 100.0),
        (10, 0.05, 1e6),
        (200, 0.01, 100.0),
        (200, 0.2, 1e9),
        (2000, 0.05, 1e4),
    ] {
        covariance_run(samples, ratio, snr, 200_000);
    }
}

#[test]
fn f32_clean_sine_at_the_narrowest_bandwidth_stays_within_the_dead_band() {
    // K = 1024 ε, the smallest accepted: a correction below half an ulp
    // is lost, so the error may wander up to about ε / (8K) = 1.2e-4 of
    // the amplitude; the rotation must not add a drift of its own (with
    // cos θ rounded next to 1 it would bias the amplitude by up to
    // ε/(4K) = 2.4e-4). Slow sines at fast sampling are the hard case.
    for (fs, f) in [(1e4, 1.0), (1e5, 50.0), (1e3, 10.0)] {
        let dt = 1.0 / fs;
        let k_min = 1024.0 * f32::EPSILON as f64;
        let b = -libm::log1p(-k_min) / (TAU * dt) * (1.0 + 1e-9);
        let tr = SineTracker::<f32>::new(dt, &spec(f, b), CH).unwrap();
        let k = 1.0 - tr.envelope_pole();
        let mut s = tr.start();
        // 40 envelope time constants, the second half checked.
        let total = (40.0 / k) as usize;
        let mut worst: f64 = 0.0;
        for n in 0..total {
            let ph = TAU * f * dt * n as f64;
            tr.step(&mut s, libm::cos(ph) as f32).unwrap();
            if n > total / 2 {
                let (a, b) = s.pair();
                let e = libm::hypot(a as f64 - libm::cos(ph), b as f64 - libm::sin(ph));
                worst = worst.max(e);
            }
        }
        let band = f32::EPSILON as f64 / (8.0 * k);
        assert!(
            worst < band,
            "{fs} Hz sampling, {f} Hz: {worst:e} vs {band:e}"
        );
    }
}

fn modulus_tracker(f: f64, samples: usize, ratio: f64) -> ModulusTracker<f64> {
    ModulusTracker::new(
        1.0 / (f * samples as f64),
        &ModulusSpec {
            sine: spec(f, ratio * f),
            displacement: CH,
            force: CH,
            min_snr: 10.0,
        },
    )
    .unwrap()
}

#[test]
fn modulus_of_a_clean_linear_pair_is_exact_and_waits_for_the_displacement() {
    let (f, samples) = (10.0, 100);
    let m = modulus_tracker(f, samples, 0.05);
    let (k1, k2) = (3.0, 0.7);
    let mut s = m.start();
    assert_eq!(m.modulus(&s), None);
    let mut first = None;
    for n in 0..samples * 3 {
        let ph = TAU * n as f64 / samples as f64 + 1.0;
        let x = 0.2 * libm::cos(ph);
        let force = 0.2 * (k1 * libm::cos(ph) - k2 * libm::sin(ph));
        m.step(&mut s, x, force).unwrap();
        if let Some(k) = m.modulus(&s) {
            first.get_or_insert(n);
            if n >= samples {
                assert!((k.storage - k1).abs() < 1e-6 && (k.loss - k2).abs() < 1e-6);
            }
        }
    }
    // Available within the first tenth of a period.
    assert!(first.is_some_and(|n| n < samples / 10), "{first:?}");
    let k = m.modulus(&s).unwrap();
    assert!((k.loss_factor().unwrap() - k2 / k1).abs() < 1e-6);
    assert!((k.magnitude() - libm::hypot(k1, k2)).abs() < 1e-6);

    // No displacement: never a modulus, however large the force.
    let mut s = m.start();
    for n in 0..samples * 3 {
        let ph = TAU * n as f64 / samples as f64;
        m.step(&mut s, 0.0, 1e3 * libm::sin(ph)).unwrap();
        assert_eq!(m.modulus(&s), None);
    }
}

#[test]
fn a_mistuned_frequency_biases_each_amplitude_but_not_the_modulus() {
    // The sine is 1 % above the tuned 10 Hz: 0.1 Hz off against a
    // 0.5 Hz corner, so each amplitude is seen through the low-pass at
    // the offset, |1/(1 + 0.2 i)| = 0.98 with a 0.2 rad lag (an error of
    // about 0.2 of the amplitude), identical on both channels.
    let (f, samples) = (10.0, 100);
    let m = modulus_tracker(f, samples, 0.05);
    let kstar = (3.0, 0.7);
    let mut s = m.start();
    let (mut amp_err, mut mod_err): (f64, f64) = (0.0, 0.0);
    let true_f = 1.01 * f;
    let dt = m.dt();
    for n in 0..samples * 40 {
        let ph = TAU * true_f * dt * n as f64;
        let (c, sn) = (libm::cos(ph), libm::sin(ph));
        let x = c;
        let force = kstar.0 * c - kstar.1 * sn;
        m.step(&mut s, x, force).unwrap();
        if n >= samples * 20 {
            let (a, b) = s.displacement();
            amp_err = amp_err.max(libm::hypot(a - c, b - sn));
            let k = m.modulus(&s).unwrap();
            let e =
                libm::hypot(k.storage - kstar.0, k.loss - kstar.1) / libm::hypot(kstar.0, kstar.1);
            mod_err = mod_err.max(e);
        }
    }
    assert!(amp_err > 0.1, "displacement error {amp_err}");
    assert!(mod_err < 5e-3, "modulus error {mod_err}");
}

#[test]
fn ordinary_tracking_is_unchanged_by_the_guard() {
    // Bit patterns of every a, b and innovation of a noisy f32 run
    // (FNV-style hash) and the end values, recorded before the state
    // guard was added: the guard only compares.
    let dt = 1e-3;
    let tr = SineTracker::<f32>::new(dt, &spec(10.0, 0.5), CH).unwrap();
    let mut s = tr.start();
    let mut g = Noise::from_state(0x1234_5678_9abc_def1);
    let mut h: u64 = 0;
    for n in 0..5000 {
        let z = 2.0 * libm::sin(TAU * 10.3 * dt * n as f64 + 0.3) + 0.05 * g.gauss();
        let y = tr.step(&mut s, z as f32).unwrap();
        for v in [s.a(), s.b(), y] {
            h = (h ^ v.bits()).wrapping_mul(0x0100_0000_01b3);
        }
    }
    assert_eq!(h, 0x603c_8e0a_08c4_6e53);
    assert_eq!(s.pair(), (0.521_148_9, 1.612_143_2));
    let p = tr.covariance(&s);
    assert_eq!(
        (p[0][0], p[0][1], p[1][1]),
        (6.271_389e-9, -1.566_794_3e-10, 6.306_885_2e-9)
    );
    let m = ModulusTracker::<f32>::new(
        dt,
        &ModulusSpec {
            sine: spec(10.0, 0.5),
            displacement: CH,
            force: Channel {
                noise: 1e-2,
                amplitude: 5.0,
            },
            min_snr: 10.0,
        },
    )
    .unwrap();
    let mut ms = m.start();
    let mut h: u64 = 0;
    for n in 0..5000 {
        let ph = TAU * 10.0 * dt * n as f64;
        let x = libm::cos(ph) + 1e-3 * g.gauss();
        let f = 3.0 * libm::cos(ph) - 0.7 * libm::sin(ph) + 1e-2 * g.gauss();
        let (yx, yf) = m.step(&mut ms, x as f32, f as f32).unwrap();
        let ((ax, bx), (af, bf)) = (ms.displacement(), ms.force());
        for v in [ax, bx, af, bf, yx, yf] {
            h = (h ^ v.bits()).wrapping_mul(0x0100_0000_01b3);
        }
    }
    assert_eq!(h, 0x8f95_bba6_51f0_fc90);
    assert_eq!(ms.displacement(), (0.998_081_15, -0.062_783_33));
    assert_eq!(ms.force(), (3.037_794_6, 0.510_287_94));
    let k = m.modulus(&ms).unwrap();
    assert_eq!((k.storage, k.loss), (2.999_604_7, 0.699_956_2));
}

#[test]
fn samples_near_f32_max_leave_the_state_within_the_guard() {
    // Accepted, they used to put a and b near f32::MAX, where the next
    // rotation overflowed (a = -inf, then NaN). Each would now take the
    // state beyond 2^60: all refused, the state stays zero, and the
    // tracker then follows a sine as from the start.
    let ys = [
        -3.4e38f32, -3.4e38, 3.4e38, 3.4e38, -1e38, 3.4e38, 1e38, -3.4e38, -3.4e38, -2e38,
    ];
    let ch = Channel {
        noise: 1.0,
        amplitude: 1.0,
    };
    let dt = 1e-3;
    let sine = SineSpec {
        frequency: 100.0,
        bandwidth: 1.0,
    };
    let t = SineTracker::<f32>::new(dt, &sine, ch).unwrap();
    let mut s = t.start();
    for y in ys {
        assert_eq!(t.step(&mut s, y), Err(Refused::Overflow));
        assert_eq!(s.pair(), (0.0, 0.0));
    }
    assert_eq!(s.refused(), 10);
    let m = ModulusTracker::<f32>::new(
        dt,
        &ModulusSpec {
            sine,
            displacement: ch,
            force: ch,
            min_snr: 1.0,
        },
    )
    .unwrap();
    let mut ms = m.start();
    // Either channel too large refuses the pair; a small one alone is
    // fine.
    for (i, y) in ys.into_iter().enumerate() {
        let (x, f) = if i % 2 == 0 { (y, 0.5) } else { (0.5, y) };
        assert_eq!(m.step(&mut ms, x, f), Err(Refused::Overflow));
        assert_eq!(ms.displacement(), (0.0, 0.0));
        assert_eq!(ms.force(), (0.0, 0.0));
    }
    assert_eq!(ms.refused(), 10);
    for n in 0..2000 {
        let ph = TAU * 100.0 * dt * n as f64;
        let (c, sn) = (libm::cos(ph), libm::sin(ph));
        t.step(&mut s, c as f32).unwrap();
        m.step(&mut ms, c as f32, (2.0 * c - 0.5 * sn) as f32)
            .unwrap();
    }
    assert!((s.amplitude() - 1.0).abs() < 1e-4, "{}", s.amplitude());
    let k = m.modulus(&ms).unwrap();
    assert!((k.storage - 2.0).abs() < 1e-4 && (k.loss - 0.5).abs() < 1e-4);
}

/// Drives a tracker of `C` channels with samples of the order of GUARD,
/// the largest finite value, NaN and infinities, and checks the
/// documented outcome of every step. Returns how often each path was
/// taken: accepted, refused with the rotation stored, refused with the
/// rotation halved.
fn hostile<T: Real, const C: usize>(
    kernel: &Kernel<T>,
    mut step: impl FnMut([T; C]) -> (Result<[T; C], Refused>, [(T, T); C], u32),
    seed: u64,
) -> [u32; 3] {
    let g = T::GUARD.to_f64();
    let big = T::from_f64(f64::MAX).to_f64(); // the largest finite value
    let levels = [
        0.0,
        0.3,
        0.7,
        0.99,
        1.0,
        1.5,
        3.0,
        1e-20,
        1e20,
        big,
        f64::NAN,
        f64::INFINITY,
    ];
    let mut u = Noise::from_state(seed);
    let mut pick = || {
        let v = levels[(u.uniform() * levels.len() as f64) as usize];
        let v = if v.is_finite() && v != big && v > 1e-10 && v < 1e10 {
            v * g
        } else {
            v
        };
        T::from_f64(if u.uniform() < 0.5 { -v } else { v })
    };
    let mut before = [(T::ZERO, T::ZERO); C];
    let mut counts = [0u32; 3];
    for n in 1..=20_000u32 {
        let z: [T; C] = core::array::from_fn(|_| pick());
        let rotated = before.map(|p| kernel.rotate(p));
        let (r, after, refused) = step(z);
        assert!(guarded(&after), "step {n}: {after:?}");
        match r {
            Ok(y) => {
                assert!(y.iter().all(|v| v.is_finite()));
                counts[0] += 1;
            }
            Err(e) => {
                let expected = if z.iter().all(|v| v.is_finite()) {
                    Refused::Overflow
                } else {
                    Refused::NonFiniteSample
                };
                assert_eq!(e, expected, "step {n}: {z:?}");
                if guarded(&rotated) {
                    assert_eq!(after, rotated);
                    counts[1] += 1;
                } else {
                    assert_eq!(after, rotated.map(|(a, b)| (a * T::HALF, b * T::HALF)));
                    counts[2] += 1;
                }
            }
        }
        assert_eq!(refused, counts[1] + counts[2]);
        before = after;
    }
    counts
}

fn hostile_runs<T: Real>() {
    // θ = π/4 turns a state at the guard's corner past it.
    let (dt, sine) = (1e-3, spec(125.0, 10.0));
    let ch = Channel {
        noise: 1.0,
        amplitude: 1.0,
    };
    let t = SineTracker::<T>::new(dt, &sine, ch).unwrap();
    let mut s = t.start();
    let counts = hostile(
        &t.kernel,
        |[z]| {
            let r = t.step(&mut s, z).map(|y| [y]);
            assert!(s.amplitude().is_finite());
            (r, [s.pair()], s.refused())
        },
        0x2545_f491_4f6c_dd1d,
    );
    assert!(
        counts.iter().all(|&c| c > 0),
        "{} sine: {counts:?}",
        T::NAME
    );
    let m = ModulusTracker::<T>::new(
        dt,
        &ModulusSpec {
            sine,
            displacement: ch,
            force: ch,
            min_snr: 1.0,
        },
    )
    .unwrap();
    let mut ms = m.start();
    let counts = hostile(
        &m.kernel,
        |[x, f]| {
            let r = m.step(&mut ms, x, f).map(|(x, f)| [x, f]);
            if let Some(k) = m.modulus(&ms) {
                assert!(k.storage.is_finite() && k.loss.is_finite());
            }
            (r, ms.pairs, ms.refused())
        },
        0x9e37_79b9_7f4a_7c15,
    );
    assert!(
        counts.iter().all(|&c| c > 0),
        "{} modulus: {counts:?}",
        T::NAME
    );
}

#[test]
fn hostile_samples_never_take_the_state_past_the_guard() {
    hostile_runs::<f32>();
    hostile_runs::<f64>();
}

#[test]
fn a_subnormal_time_step_gives_finite_coefficients() {
    // 2π f overflowed before f Δt was formed: θ was inf and the first
    // step gave a = b = NaN. With θ = 2π (f Δt) this is the tracker of
    // 360 Hz at 1 kHz, 36 Hz wide.
    let ch = Channel {
        noise: 1.0,
        amplitude: 1.0,
    };
    let tiny = SineTracker::<f64>::new(1e-308, &spec(3.6e307, 3.6e306), ch).unwrap();
    let plain = SineTracker::<f64>::new(1e-3, &spec(360.0, 36.0), ch).unwrap();
    let (vt, vp) = (&tiny.kernel, &plain.kernel);
    for (a, b) in [
        (vt.vers, vp.vers),
        (vt.sin, vp.sin),
        (vt.vers2, vp.vers2),
        (vt.sin2, vp.sin2),
        (vt.q, vp.q),
    ] {
        assert!((a / b - 1.0).abs() < 1e-14, "{a} vs {b}");
    }
    let (mut st, mut sp) = (tiny.start(), plain.start());
    for n in 0..100 {
        let z = libm::cos(TAU * 0.36 * n as f64 + 0.2);
        tiny.step(&mut st, z).unwrap();
        plain.step(&mut sp, z).unwrap();
        let (a, b) = st.pair();
        assert!(libm::hypot(a - sp.a(), b - sp.b()) < 1e-12, "step {n}");
    }
    assert!((st.amplitude() - 1.0).abs() < 1e-9);
    let modulus = |dt, f, b| {
        ModulusTracker::<f64>::new(
            dt,
            &ModulusSpec {
                sine: spec(f, b),
                displacement: ch,
                force: ch,
                min_snr: 10.0,
            },
        )
        .unwrap()
    };
    let (mt, mp) = (
        modulus(1e-308, 3.6e307, 3.6e306),
        modulus(1e-3, 360.0, 36.0),
    );
    let (mut st, mut sp) = (mt.start(), mp.start());
    for n in 0..100 {
        let ph = TAU * 0.36 * n as f64;
        let (x, f) = (libm::cos(ph), 2.0 * libm::cos(ph + 0.3));
        mt.step(&mut st, x, f).unwrap();
        mp.step(&mut sp, x, f).unwrap();
        for (a, b) in [
            (st.displacement(), sp.displacement()),
            (st.force(), sp.force()),
        ] {
            assert!(libm::hypot(a.0 - b.0, a.1 - b.1) < 1e-12, "step {n}");
        }
    }

    // Across time steps from the smallest subnormal to 1e300 and
    // frequencies up to Nyquist or f64::MAX: either a typed refusal or
    // finite coefficients and steps (f32: 48 of 216 built, f64: 85,
    // among them f = f64::MAX at Δt = 1e-310, where 2π f overflows).
    let mut built = [0; 2];
    for dt in [5e-324, 1e-320, 1e-310, 1e-308, 1e-300, 1e-3, 1.0, 1e300] {
        let near_nyquist = [1e-6, 0.01, 0.2, 0.49, 0.499_999_999_999].map(|r| r / dt);
        for f in near_nyquist
            .into_iter()
            .chain([1.0, 1e300, 0.5 * f64::MAX, f64::MAX])
        {
            for ratio in [1e-3, 0.05, 0.5] {
                let sine = spec(f, ratio * f);
                built[0] += check_built::<f32>(SineTracker::new(dt, &sine, ch), dt * f);
                built[1] += check_built::<f64>(SineTracker::new(dt, &sine, ch), dt * f);
            }
        }
    }
    assert_eq!(built, [48, 85]);
}

/// Checks the coefficients and 20 steps of a built tracker; 1 if built.
fn check_built<T: Real>(t: Result<SineTracker<T>, ParamError>, f_dt: f64) -> u32 {
    let Ok(t) = t else {
        return 0;
    };
    let k = &t.kernel;
    let coefficients = [k.vers, k.sin, k.vers2, k.sin2, k.q, k.p0];
    assert!(
        coefficients.iter().all(|c| c.is_finite()) && k.sin > T::ZERO,
        "{} f dt {f_dt:e}: {coefficients:?}",
        T::NAME
    );
    let mut s = t.start();
    for n in 0..20 {
        let z = libm::cos(TAU * f_dt * n as f64);
        t.step(&mut s, T::from_f64(z)).unwrap();
        assert!(s.a().is_finite() && s.b().is_finite());
    }
    1
}

#[test]
fn squares_that_overflow_the_working_type_are_refused() {
    // The covariance is reported times noise²: 1e40 is infinite in f32.
    let ch = Channel {
        noise: 1e20,
        amplitude: 1e21,
    };
    assert_eq!(
        SineTracker::<f32>::new(1e-3, &spec(10.0, 0.5), ch),
        Err(ParamError::NotFinite {
            param: Param::scalar("noise")
        })
    );
    let t = SineTracker::<f64>::new(1e-3, &spec(10.0, 0.5), ch).unwrap();
    assert!(t.covariance(&t.start())[0][0].is_finite());
    let m = |displacement, force, min_snr| {
        ModulusTracker::<f32>::new(
            1e-3,
            &ModulusSpec {
                sine: spec(10.0, 0.5),
                displacement,
                force,
                min_snr,
            },
        )
    };
    let not_finite = |name| {
        Err(ParamError::NotFinite {
            param: Param::scalar(name),
        })
    };
    assert_eq!(m(ch, CH, 10.0), not_finite("displacement_noise"));
    assert_eq!(m(CH, ch, 10.0), not_finite("force_noise"));
    // (min_snr σ_X)² = (1e20 · 1e-3)² = 1e34 fits; (1e25 · 1e-3)² not.
    assert!(m(CH, CH, 1e20).is_ok());
    assert_eq!(m(CH, CH, 1e25), not_finite("min_snr"));
}

#[test]
fn a_state_at_the_guards_corner_does_not_lock_the_tracker() {
    // (0.9, 0.9) GUARD turned by θ = π/4 has b = 1.27 GUARD, and no
    // ordinary sample moves b by that much in one update: each sample
    // is refused. Kept as it was, the state would stay there for good;
    // halved, it is back inside and the tracker follows the sine.
    let dt = 1e-3;
    let t = SineTracker::<f32>::new(dt, &spec(125.0, 10.0), CH).unwrap();
    let mut s = t.start();
    let g = 0.9 * f32::GUARD;
    s.pair = (g, g);
    let rotated = t.kernel.rotate(s.pair);
    assert!(rotated.1 > f32::GUARD);
    assert_eq!(t.step(&mut s, 0.0), Err(Refused::Overflow));
    assert_eq!(s.pair(), (0.5 * rotated.0, 0.5 * rotated.1));
    let mut refused = 1;
    for n in 1..5000 {
        let z = libm::cos(TAU * 0.125 * n as f64) as f32;
        refused += t.step(&mut s, z).is_err() as u32;
        assert!(guarded(&[s.pair()]));
    }
    assert_eq!(s.refused(), refused);
    assert!(refused < 10, "{refused}");
    assert!((s.amplitude() - 1.0).abs() < 1e-3, "{}", s.amplitude());
}
