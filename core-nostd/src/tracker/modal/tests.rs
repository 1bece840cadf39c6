use bushing_kernels::Noise;

use super::rotation::{anchor_at, rotation, rotation_near, rotation_pair};
use super::*;
use crate::error::{Param, ParamError};

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

/// The set-up of fuzz input `crash-3dab1a41`: one mode, one
/// displacement sensor, the default UKF, and a tuning with an initial
/// damping error of 3.6e88 and a damping walk of 1e308.
struct Crash {
    dt: f64,
    sensors: [SensorSpec; 1],
    modes: [ModeInit; 1],
    amplitudes: [(f64, f64); 1],
    tuning: Tuning,
}

fn crash_setup() -> Crash {
    let sensors = [SensorSpec {
        measured: Measured::Displacement,
        noise: 0.000_380_398_102_815_358_2,
    }];
    let modes = [ModeInit {
        frequency: 0.567_662_700_022_572_9,
        damping: 0.103_909_034_729_003_9,
    }];
    let tuning = Tuning {
        frequency_walk: 0.156_304_359_436_035_16,
        damping_walk: 1e308,
        amplitude_walk: 0.949_062_347_412_109_4,
        initial_frequency_error: 1e-4,
        initial_damping_error: 3.606_372_053_036_077e88,
        initial_amplitude_error: 0.746_309_693_702_413_5,
        gate: 6.137_052_536_010_742,
        outlier_run: 13,
        fade_snr: 9.294_834_136_962_89,
        max_damping: 0.920_384_960_174_560_5,
        max_frequency: 0.989_984_893_798_828_1,
    };
    Crash {
        dt: 2.053_479_933_262_200_4e-4,
        sensors,
        modes,
        amplitudes: [(0.0, -8.749_370_574_951_172)],
        tuning,
    }
}

fn crash_tracker(tuning: &Tuning) -> Result<ModalTracker<f32, 4>, ParamError> {
    let Crash {
        dt,
        sensors,
        modes,
        amplitudes,
        ..
    } = crash_setup();
    ModalTracker::new(
        dt,
        &sensors,
        &modes,
        &amplitudes,
        tuning,
        Filter::Ukf(UtParams::default()),
    )
}

fn finite_state<const N: usize>(s: &ModalState<f32, N>) -> bool {
    s.x()
        .iter()
        .chain(s.covariance().iter().flatten())
        .all(|v| v.is_finite())
}

#[test]
fn start_and_process_variances_beyond_the_guard_are_refused() {
    // The λ start variance (3.6e88 × ω_0 dt = 7.3e-4)² overflowed f32,
    // so the start covariance, and every repair, held an infinity: the
    // first step (its prediction refused, hence `repaired`) left a
    // non-finite covariance. Now a typed error at construction.
    let tuning = crash_setup().tuning;
    // The fuzz target's check: whatever `new` accepts keeps a finite
    // state.
    if let Ok(t) = crash_tracker(&tuning) {
        let mut s = t.start();
        let r = t.step(&mut s, &[4.184_379_2e-5]);
        assert!(finite_state(&s), "non-finite tracker state after {r:?}");
    }
    let e = crash_tracker(&tuning).map(|_| ());
    assert!(
        matches!(e, Err(ParamError::OutOfRange { param, .. })
            if param == Param::scalar("initial_damping_error")),
        "{e:?}"
    );
    // With that error sane, the damping walk's per-step variance
    // (1e308 ω_0 dt)² dt is refused in turn.
    let sane = Tuning {
        initial_damping_error: 0.01,
        ..tuning
    };
    let e = crash_tracker(&sane).map(|_| ());
    assert!(
        matches!(e, Err(ParamError::OutOfRange { param, .. })
            if param == Param::scalar("damping_walk")),
        "{e:?}"
    );
    // Both sane: the fuzz input's one sample updates a finite state.
    let t = crash_tracker(&Tuning {
        damping_walk: 0.01,
        ..sane
    })
    .unwrap();
    let mut s = t.start();
    assert!(finite_state(&s));
    let r = t.step(&mut s, &[4.184_379_2e-5]);
    assert!(finite_state(&s), "{r:?} {:?} {:?}", s.x(), s.covariance());
    assert!(!r.repaired && r.accepted == 1, "{r:?}");
}

#[test]
fn variances_just_below_the_guard_keep_a_finite_state() {
    // Each walk and initial error of the crash set-up in turn: 1e300 is
    // refused with the largest value allowed; 0.99 of it builds, and
    // EKF and UKF stay finite over wild samples.
    type Field = fn(&mut Tuning) -> &mut f64;
    let fields: [(&str, Field); 6] = [
        ("frequency_walk", |t| &mut t.frequency_walk),
        ("damping_walk", |t| &mut t.damping_walk),
        ("amplitude_walk", |t| &mut t.amplitude_walk),
        ("initial_frequency_error", |t| {
            &mut t.initial_frequency_error
        }),
        ("initial_damping_error", |t| &mut t.initial_damping_error),
        ("initial_amplitude_error", |t| {
            &mut t.initial_amplitude_error
        }),
    ];
    let Crash {
        dt,
        sensors,
        modes,
        amplitudes,
        ..
    } = crash_setup();
    let samples = [4.184_379_2e-5, f32::NAN, 1e30, -1e30, 0.0, f32::MAX, 1e-3];
    for (name, field) in fields {
        let mut t = Tuning::default();
        *field(&mut t) = 1e300;
        let max = match crash_tracker(&t) {
            Err(ParamError::OutOfRange {
                param, value, max, ..
            }) if param == Param::scalar(name) && value == 1e300 => max,
            e => panic!("{name}: {:?}", e.map(|_| ())),
        };
        *field(&mut t) = 0.99 * max;
        for filter in [Filter::Ekf, Filter::Ukf(UtParams::default())] {
            let tr =
                ModalTracker::<f32, 4>::new(dt, &sensors, &modes, &amplitudes, &t, filter).unwrap();
            let mut s = tr.start();
            assert!(finite_state(&s), "{name} start");
            for k in 0..64 {
                let r = tr.step(&mut s, &[samples[k % samples.len()]]);
                assert!(finite_state(&s), "{name} {filter:?} step {k}: {r:?}");
            }
        }
    }
    // The noise of a sensor against the amplitudes: its variance in
    // the scaled states is bounded the same way.
    let loud = [SensorSpec {
        noise: 1e30,
        ..sensors[0]
    }];
    let e = ModalTracker::<f32, 4>::new(
        dt,
        &loud,
        &modes,
        &amplitudes,
        &Tuning::default(),
        Filter::Ekf,
    );
    assert!(matches!(e, Err(ParamError::OutOfRange { param, .. })
            if param == Param::item("noise", 0)));
    // In f64 the guard is 2^500: the same noise is accepted.
    assert!(
        ModalTracker::<f64, 4>::new(
            dt,
            &loud,
            &modes,
            &amplitudes,
            &Tuning::default(),
            Filter::Ekf
        )
        .is_ok()
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

// The structured filters against plain dense references, in f64, for
// one and two modes and one and two sensors: the EKF prediction against
// F P Fᵀ + Q with F written out, the UKF prediction and innovation
// against all 2n + 1 sigma points of the same square root of P, the
// update against the Joseph form written out.

fn tracker<const N: usize>(modes: usize, sensors: usize, filter: Filter) -> ModalTracker<f64, N> {
    tracker_as::<f64, N, 0>(modes, sensors, filter)
}

/// [`tracker`] in `T`, with `M` modes fixed at compile time (0: at run
/// time).
fn tracker_as<T: Real, const N: usize, const M: usize>(
    modes: usize,
    sensors: usize,
    filter: Filter,
) -> ModalTracker<T, N, M> {
    let kinds = [
        Measured::Acceleration,
        Measured::Velocity,
        Measured::Displacement,
    ];
    let spec = kinds.map(|measured| SensorSpec {
        measured,
        noise: 1e-2,
    });
    let ms = [
        ModeInit {
            frequency: 20.0,
            damping: 0.01,
        },
        ModeInit {
            frequency: 57.0,
            damping: 0.03,
        },
    ];
    let amps = [
        (1.0, 0.3),
        (-0.4, 0.8),
        (0.7, -0.2),
        (0.5, 0.5),
        (0.9, 0.1),
        (0.2, -0.6),
    ];
    let tuning = Tuning {
        frequency_walk: 0.5,
        damping_walk: 0.02,
        amplitude_walk: 0.1,
        ..Tuning::default()
    };
    ModalTracker::new(
        1e-3,
        &spec[..sensors],
        &ms[..modes],
        &amps[..modes * sensors],
        &tuning,
        filter,
    )
    .unwrap()
}

/// A perturbed start estimate and a dense positive definite covariance
/// (entries of the order of the start variances, θ and λ correlated
/// with the amplitudes).
#[allow(clippy::needless_range_loop)]
fn random_core<const N: usize>(tr: &ModalTracker<f64, N>, rng: &mut Noise) -> Core<f64, N> {
    let mut x = tr.x0;
    let mut scale = [0.0; N];
    for (i, (xi, si)) in x.iter_mut().zip(scale.iter_mut()).enumerate() {
        *si = tr.p0[i].sqrt();
        *xi += 0.3 * *si * rng.symmetric();
    }
    let mut a = [[0.0; N]; N];
    for row in a.iter_mut() {
        for v in row.iter_mut() {
            *v = rng.symmetric();
        }
    }
    let mut p = [[0.0; N]; N];
    for i in 0..N {
        for j in 0..N {
            let dot: f64 = (0..N).map(|k| a[i][k] * a[j][k]).sum();
            p[i][j] = scale[i] * scale[j] * (dot / N as f64 + if i == j { 0.5 } else { 0.0 });
        }
    }
    Core {
        x,
        p,
        faded: [false; N],
        run: 0,
    }
}

fn process_ref<const N: usize>(tr: &ModalTracker<f64, N>, x: &mut [f64; N]) {
    for m in 0..tr.modes {
        let (ti, li) = tr.theta_lambda(m);
        let r = rotation(x[ti], x[li]);
        tr.rotate_mode(x, m, r);
    }
}

fn add_q_ref<const N: usize>(tr: &ModalTracker<f64, N>, c: &Core<f64, N>, p: &mut [[f64; N]; N]) {
    for m in 0..tr.modes {
        let (ti, li) = tr.theta_lambda(m);
        if !c.faded[m] {
            p[ti][ti] += tr.q_theta;
            p[li][li] += tr.q_lambda[m];
        }
        for k in 0..tr.sensors {
            let (ai, bi) = tr.pair(m, k);
            p[ai][ai] += tr.q_amp;
            p[bi][bi] += tr.q_amp;
        }
    }
}

/// Lower Cholesky factor in the tracker's pivot order, columns indexed
/// by pivot, rows by state.
#[allow(clippy::needless_range_loop)]
fn cholesky_ref<const N: usize>(tr: &ModalTracker<f64, N>, p: &[[f64; N]; N]) -> [[f64; N]; N] {
    let piv: [usize; N] = core::array::from_fn(|t| tr.pivot(t));
    let mut l = [[0.0; N]; N];
    for j in 0..N {
        let d = p[piv[j]][piv[j]] - (0..j).map(|k| l[j][k] * l[j][k]).sum::<f64>();
        l[j][j] = d.sqrt();
        for i in j + 1..N {
            let v = p[piv[i]][piv[j]] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            l[i][j] = v / l[j][j];
        }
    }
    let mut out = [[0.0; N]; N];
    for i in 0..N {
        for t in 0..N {
            out[piv[i]][t] = l[i][t];
        }
    }
    out
}

fn close<const N: usize>(a: &[[f64; N]; N], b: &[[f64; N]; N], what: &str) {
    let big = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..N {
        for j in 0..N {
            assert!(
                (a[i][j] - b[i][j]).abs() <= 1e-12 * big,
                "{what} [{i}][{j}]: {} against {}",
                a[i][j],
                b[i][j]
            );
        }
    }
    assert!(
        (0..N).all(|i| (0..N).all(|j| a[i][j] == a[j][i])),
        "{what} not symmetric"
    );
}

// Dense references read best with indices.
#[allow(clippy::needless_range_loop)]
fn check_filters<const N: usize>(modes: usize, sensors: usize) {
    let mut rng = Noise::new(N as u64 * 7919 + modes as u64);
    for round in 0..4 {
        // EKF prediction.
        let tr = tracker::<N>(modes, sensors, Filter::Ekf);
        let mut core = random_core(&tr, &mut rng);
        core.faded[0] = round == 3;
        let mut x = core.x;
        process_ref(&tr, &mut x);
        let mut f = [[0.0; N]; N];
        for (i, row) in f.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        for m in 0..modes {
            let (ti, li) = tr.theta_lambda(m);
            let (ec, es) = rotation(core.x[ti], core.x[li]);
            for k in 0..sensors {
                let (ai, bi) = tr.pair(m, k);
                let (a1, b1) = (x[ai], x[bi]);
                f[ai][ai] = ec;
                f[ai][bi] = -es;
                f[bi][ai] = es;
                f[bi][bi] = ec;
                f[ai][ti] = -b1;
                f[ai][li] = a1;
                f[bi][ti] = a1;
                f[bi][li] = b1;
            }
        }
        let mut fp = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                fp[i][j] = (0..N).map(|k| f[i][k] * core.p[k][j]).sum();
            }
        }
        let mut want = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                want[i][j] = (0..N).map(|k| fp[i][k] * f[j][k]).sum();
            }
        }
        add_q_ref(&tr, &core, &mut want);
        let mut got = core.clone();
        let mut anchor = [[f64::NAN; 4]; N];
        tr.predict_ekf(&mut got, &mut anchor);
        assert_eq!(got.x, x, "EKF x, {modes} modes {sensors} sensors");
        close(&got.p, &want, "EKF P");

        // Joseph update, with a frozen mode in the last round.
        let (mut v, s, y) = ([0.0; N], 0.7, 0.3);
        for vi in v.iter_mut() {
            *vi = 0.1 * rng.symmetric();
        }
        let mut k = v.map(|vi| vi / s);
        if core.faded[0] {
            k[0] = 0.0;
            k[1] = 0.0;
        }
        let mut want = got.p;
        for i in 0..N {
            for j in 0..N {
                want[i][j] += -k[i] * v[j] - v[i] * k[j] + s * k[i] * k[j];
            }
        }
        let before = got.x;
        let mut upd = got.clone();
        tr.update(&mut upd, &v, s, y);
        close(&upd.p, &want, "Joseph update");
        for i in 0..N {
            assert!((upd.x[i] - (before[i] + k[i] * y)).abs() <= 1e-15 * (1.0 + before[i].abs()));
        }

        // UKF prediction against the full sigma set.
        let tr = tracker::<N>(modes, sensors, Filter::Ukf(UtParams::default()));
        let (g, w0m, w0c, wi) = UtParams::default().weights(N).unwrap();
        let l = cholesky_ref(&tr, &core.p);
        let mut points = [[0.0; N]; 2];
        let mut y0 = core.x;
        process_ref(&tr, &mut y0);
        let mut mean = y0.map(|v| w0m * v);
        let mut ys = [[[0.0; N]; 2]; N];
        for t in 0..N {
            for (sgn, pt) in [1.0, -1.0].into_iter().zip(points.iter_mut()) {
                for i in 0..N {
                    pt[i] = core.x[i] + sgn * g * l[i][t];
                }
                process_ref(&tr, pt);
            }
            ys[t] = points;
            for i in 0..N {
                mean[i] += wi * (points[0][i] + points[1][i]);
            }
        }
        let mut want = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                let mut acc = w0c * (y0[i] - mean[i]) * (y0[j] - mean[j]);
                for pts in &ys {
                    for pt in pts {
                        acc += wi * (pt[i] - mean[i]) * (pt[j] - mean[j]);
                    }
                }
                want[i][j] = acc;
            }
        }
        add_q_ref(&tr, &core, &mut want);
        let mut got = core.clone();
        let mut anchor = [[f64::NAN; 4]; N];
        assert!(tr.predict_ukf(&mut got, &mut anchor, &mut ukf::Scratch::new()));
        for i in 0..N {
            assert!(
                (got.x[i] - mean[i]).abs() <= 1e-13 * (1.0 + mean[i].abs()),
                "UKF mean {i}: {} against {}",
                got.x[i],
                mean[i]
            );
        }
        close(&got.p, &want, "UKF P");

        // UKF innovation of every sensor against the full sigma set.
        for c in 0..sensors {
            let observe = |x: &[f64; N]| {
                (0..modes)
                    .map(|m| {
                        let (ti, li) = tr.theta_lambda(m);
                        let (ai, bi) = tr.pair(m, c);
                        let (hp, hq) = tr.coefficients(c, x[ti], x[li]);
                        hp * x[ai] + hq * x[bi]
                    })
                    .sum::<f64>()
            };
            let z0 = observe(&core.x);
            let mut zs = [[0.0; 2]; N];
            let mut zhat = w0m * z0;
            for t in 0..N {
                for (sgn, z) in [1.0, -1.0].into_iter().zip(zs[t].iter_mut()) {
                    let pt: [f64; N] = core::array::from_fn(|i| core.x[i] + sgn * g * l[i][t]);
                    *z = observe(&pt);
                    zhat += wi * *z;
                }
            }
            let mut szz = w0c * (z0 - zhat) * (z0 - zhat) + tr.r[c];
            let mut pxz = [0.0; N];
            for t in 0..N {
                for (sgn, &z) in [1.0, -1.0].into_iter().zip(&zs[t]) {
                    szz += wi * (z - zhat) * (z - zhat);
                    for i in 0..N {
                        pxz[i] += wi * sgn * g * l[i][t] * (z - zhat);
                    }
                }
            }
            let mut v = [0.0; N];
            let (zh, sz) = tr
                .innovation_ukf(&core, c, &mut v, &mut ukf::Scratch::new())
                .unwrap();
            assert!(
                (zh - zhat).abs() <= 1e-13 * (1.0 + zhat.abs()),
                "zhat {zh} {zhat}"
            );
            assert!((sz - szz).abs() <= 1e-12 * szz, "Pzz {sz} {szz}");
            let big = pxz.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..N {
                assert!(
                    (v[i] - pxz[i]).abs() <= 1e-12 * big,
                    "Pxz {i}: {} {}",
                    v[i],
                    pxz[i]
                );
            }
        }

        // Not positive definite: refused, whether the amplitude block
        // fails within the last pair, within the first or only through
        // the coupling of the first pair to the last.
        let (first, last) = (tr.pair(0, 0), tr.pair(modes - 1, sensors - 1));
        for (i, j) in [(last.0, last.1), (first.0, first.1), (first.1, last.0)] {
            let mut bad = core.clone();
            bad.p[i][j] = 2.0 * (bad.p[i][i] * bad.p[j][j]).sqrt();
            bad.p[j][i] = bad.p[i][j];
            let mut anchor = [[f64::NAN; 4]; N];
            let refused = !tr.predict_ukf(&mut bad, &mut anchor, &mut ukf::Scratch::new());
            assert!(refused, "{N} states, entry ({i}, {j})");
        }
    }
}

/// Bit for bit the same state (an anchor's θ may be NaN).
fn same_bits<const N: usize>(a: &ModalState<f32, N>, b: &ModalState<f32, N>) -> bool {
    let bits = |s: &ModalState<f32, N>| {
        let (x, p, anchor) = (s.core.x, s.core.p, s.anchor);
        x.into_iter()
            .chain(p.into_iter().flatten())
            .chain(anchor.into_iter().flatten())
            .map(f32::to_bits)
    };
    bits(a).eq(bits(b))
        && (a.core.faded, a.core.run) == (b.core.faded, b.core.run)
        && (a.outliers, a.repairs, a.reacquisitions) == (b.outliers, b.repairs, b.reacquisitions)
}

/// A two-mode tracker with its mode count fixed at compile time against
/// the same tracker with it given at run time, in f32: the same numbers
/// at every step, through gated outliers, a refused sample, a
/// re-acquisition and the fade of the second mode.
fn same_with_modes_at_compile_time<const N: usize>(sensors: usize, filter: Filter) {
    let fixed = tracker_as::<f32, N, 2>(2, sensors, filter);
    let free = tracker_as::<f32, N, 0>(2, sensors, filter);
    let (mut a, mut b) = (fixed.start(), free.start());
    let mut rng = Noise::new(0x5eed + N as u64);
    let (mut faded, mut gated, mut reacquired) = (false, 0u32, false);
    for k in 0..4000 {
        let t = k as f64 * 1e-3;
        // The second mode dies out after the first second.
        let second = if k < 1000 { 0.8 } else { 0.0 };
        let y: [f32; 3] = core::array::from_fn(|c| {
            let shape = [1.0, -0.7, 0.4][c];
            let z = (core::f64::consts::TAU * 20.0 * t).sin()
                + second * shape * (core::f64::consts::TAU * 57.0 * t).cos()
                + 1e-2 * rng.gauss();
            match k {
                // Outliers, one alone and then a run that re-acquires.
                500 | 1500..=1520 => 1e3,
                700 if c == 0 => f32::NAN,
                _ => z as f32,
            }
        });
        let (ra, rb) = (fixed.step(&mut a, &y), free.step(&mut b, &y));
        assert_eq!(ra, rb, "step {k}");
        assert!(same_bits(&a, &b), "step {k}: {a:?} against {b:?}");
        gated += u32::from(ra.gated);
        reacquired |= ra.reacquired;
        faded |= fixed.mode(&a, 1).faded;
    }
    assert!(
        gated > 0 && reacquired && faded,
        "{gated} {reacquired} {faded}"
    );
}

#[test]
fn modes_fixed_at_compile_time_step_the_same_numbers() {
    for filter in [Filter::Ekf, Filter::Ukf(UtParams::default())] {
        same_with_modes_at_compile_time::<8>(1, filter);
        same_with_modes_at_compile_time::<12>(2, filter);
        same_with_modes_at_compile_time::<16>(3, filter);
    }
    // A count other than M is refused.
    let r = ModalTracker::<f32, 8, 2>::new(
        1e-3,
        &sensor(),
        &[ModeInit {
            frequency: 20.0,
            damping: 0.0,
        }],
        &[(1.0, 0.0)],
        &Tuning::default(),
        Filter::Ekf,
    );
    assert_eq!(
        r,
        Err(ParamError::LengthMismatch {
            param: Param::scalar("modes"),
            expected: 2,
            got: 1,
        })
    );
}

#[test]
fn structured_filters_match_dense_references() {
    check_filters::<4>(1, 1);
    check_filters::<6>(1, 2);
    check_filters::<8>(2, 1);
    check_filters::<12>(2, 2);
    check_filters::<16>(2, 3);
}

#[test]
fn sigma_point_and_anchor_rotations_are_accurate_in_f32() {
    // Against the f64 polynomials (themselves within 6e-8 of sin, cos).
    let mut rng = Noise::new(3);
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..20_000 {
        let theta = 0.05 + 2.8 * (rng.symmetric() + 1.0) / 2.0;
        let lambda = 0.05 * rng.symmetric();
        let (dt, dl) = (
            theta.min(1.0 / 32.0) * rng.symmetric() * 0.5,
            rng.symmetric() / 64.0,
        );
        let exact = |t: f64, l: f64| rotation(t, l);
        let c = rotation(theta as f32, lambda as f32);
        let [p, m] = rotation_pair(theta as f32, lambda as f32, dt as f32, dl as f32, c);
        // The f32 rounding of the arguments moves the exact values by
        // up to an ulp of θ times the rotation.
        let (tp, lp) = (
            f64::from(theta as f32) + f64::from(dt as f32),
            f64::from(lambda as f32) + f64::from(dl as f32),
        );
        let (tm, lm) = (
            f64::from(theta as f32) - f64::from(dt as f32),
            f64::from(lambda as f32) - f64::from(dl as f32),
        );
        for (r, e) in [(p, exact(tp, lp)), (m, exact(tm, lm))] {
            let err = (f64::from(r.0) - e.0).hypot(f64::from(r.1) - e.1) / e.0.hypot(e.1);
            worst.0 = worst.0.max(err);
        }
        // Anchor within its radius.
        let anchor = anchor_at(theta as f32, lambda as f32);
        let (t2, l2) = (
            theta as f32 + (dt / 32.0) as f32,
            lambda as f32 - (dl / 32.0) as f32,
        );
        let r = rotation_near(&anchor, t2, l2).unwrap();
        let e = exact(f64::from(t2), f64::from(l2));
        let err = (f64::from(r.0) - e.0).hypot(f64::from(r.1) - e.1) / e.0.hypot(e.1);
        worst.1 = worst.1.max(err);
    }
    assert!(worst.0 < 5e-7, "sigma pairs {}", worst.0);
    assert!(worst.1 < 5e-7, "anchor {}", worst.1);
    // Outside the radius, or for f64, no anchor.
    let anchor = anchor_at(0.5f32, 0.0);
    assert!(rotation_near(&anchor, 0.502f32, 0.0).is_none());
    assert!(rotation_near(&anchor_at(0.5f64, 0.0), 0.5, 0.0).is_none());
    // Below twice the radius θ has no anchor (sigma points could cross 0).
    assert!(rotation_near(&anchor_at(1e-3f32, 0.0), 1e-3, 0.0).is_none());
}
