use std::f64::consts::TAU;

use super::replay::read_csv;
use super::*;
use crate::records::Time;

const DT: f64 = 1e-3;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn triangle_starts_at_preload_going_up_at_the_given_speed() {
    let p = ProfileSpec::Triangle(Triangle {
        amplitude: 2.0,
        speed: 4.0,
        cycles: 1.0,
        preload: 1.0,
    });
    assert!((displacement(&p, 0.0) - 1.0).abs() < 1e-12);
    assert!((displacement(&p, 0.1) - 1.4).abs() < 1e-12);
    assert!((displacement(&p, 0.5) - 3.0).abs() < 1e-12);
    assert!((displacement(&p, 1.5) + 1.0).abs() < 1e-12);
    assert_eq!(steps(&p, 1e-3), Ok(2000));
    assert_eq!(frequency_at(&p, 0.3), None);
    assert_eq!(amplitude_at(&p, 0.3), None);
}

#[test]
fn sine_profile_and_its_errors() {
    let p = ProfileSpec::Sine(Sine {
        amplitude: 1.0,
        frequency_hz: 2.0,
        cycles: 3.0,
        preload: 0.5,
    });
    assert!((displacement(&p, 0.125) - 1.5).abs() < 1e-12);
    assert_eq!(steps(&p, 1e-3), Ok(1500));
    assert_eq!(frequency_at(&p, 0.4), Some(2.0));
    assert_eq!(amplitude_at(&p, 0.4), Some(1.0));
    let bad = ProfileSpec::Sine(Sine {
        amplitude: 1.0,
        frequency_hz: 0.0,
        cycles: 3.0,
        preload: 0.0,
    });
    assert!(steps(&bad, 1e-3).unwrap_err().contains("frequency_hz"));
}

fn multi() -> ProfileSpec {
    ProfileSpec::MultiStep(MultiStep {
        levels: vec![0.5, 1.5, 1.0],
        ramp_s: 20.0,
        hold_s: 360.0,
        preload: 0.25,
    })
}

#[test]
fn multi_step_ramps_then_holds_each_level() {
    let p = multi();
    assert_eq!(steps(&p, 0.01), Ok(3 * 38_000));
    assert_eq!(displacement(&p, 0.0), 0.25);
    assert_eq!(displacement(&p, -1.0), 0.25);
    // Halfway up the first ramp, then held.
    assert!(close(displacement(&p, 10.0), 0.375, 1e-15));
    assert_eq!(displacement(&p, 20.0), 0.5);
    assert_eq!(displacement(&p, 379.9), 0.5);
    // Second ramp 0.5 -> 1.5 over 380..400 s, third 1.5 -> 1.0.
    assert!(close(displacement(&p, 385.0), 0.75, 1e-12));
    assert_eq!(displacement(&p, 500.0), 1.5);
    assert!(close(displacement(&p, 770.0), 1.25, 1e-12));
    assert_eq!(displacement(&p, 1000.0), 1.0);
    assert_eq!(displacement(&p, 1140.0), 1.0);
    assert_eq!(displacement(&p, 1e9), 1.0);
    // Continuous at every ramp start and end.
    for k in 0..3 {
        for edge in [0.0, 20.0] {
            let t = k as f64 * 380.0 + edge;
            let jump = (displacement(&p, t + 1e-9) - displacement(&p, t - 1e-9)).abs();
            assert!(jump < 1e-9, "jump {jump} at {t} s");
        }
    }
    assert_eq!(frequency_at(&p, 10.0), None);
    assert_eq!(amplitude_at(&p, 10.0), None);
}

#[test]
fn multi_step_errors_name_the_field_and_bound() {
    let with = |f: &dyn Fn(&mut ProfileSpec)| {
        let mut p = multi();
        f(&mut p);
        steps(&p, DT).unwrap_err()
    };
    let e = with(&|p| {
        if let ProfileSpec::MultiStep(MultiStep { levels, .. }) = p {
            levels.clear();
        }
    });
    assert_eq!(e, "levels: 1 to 10000 values expected, got 0");
    let e = with(&|p| {
        if let ProfileSpec::MultiStep(MultiStep { levels, .. }) = p {
            levels[1] = f64::NAN;
        }
    });
    assert_eq!(e, "levels[1] must be finite, got NaN");
    let e = with(&|p| {
        if let ProfileSpec::MultiStep(MultiStep { ramp_s, .. }) = p {
            *ramp_s = 0.0;
        }
    });
    assert_eq!(e, "ramp_s must be finite and > 0, got 0");
    let e = with(&|p| {
        if let ProfileSpec::MultiStep(MultiStep { hold_s, .. }) = p {
            *hold_s = -1.0;
        }
    });
    assert_eq!(e, "hold_s must be finite and >= 0, got -1");
    let e = with(&|p| {
        if let ProfileSpec::MultiStep(MultiStep { preload, .. }) = p {
            *preload = f64::INFINITY;
        }
    });
    assert_eq!(e, "preload must be finite, got inf");
    let e = with(&|p| {
        if let ProfileSpec::MultiStep(MultiStep { hold_s, .. }) = p {
            *hold_s = 1e300;
        }
    });
    assert!(e.starts_with("duration ") && e.ends_with(" steps"), "{e}");
}

fn stepped_sine() -> ProfileSpec {
    ProfileSpec::SteppedSine(SteppedSine {
        preload: None,
        preloads: Some(vec![1.0, 2.0]),
        frequencies_hz: vec![1.0, 10.0],
        amplitudes: vec![0.1, 0.25],
        cycles: 2.0,
        settle_s: Some(0.5),
        settle_cycles: None,
        ramp_s: Some(4.0),
        hold_s: Some(6.0),
    })
}

#[test]
fn stepped_sine_schedule_values_and_continuity() {
    let p = stepped_sine();
    // One preload: 2 steps of 2 s at 1 Hz, 2 of 0.2 s at 10 Hz, each
    // followed by 0.5 s: a block of 2 x 2.5 + 2 x 0.7 = 6.4 s. Then a
    // 4 s ramp, a 6 s hold, the second block without its last rest.
    assert!(close(
        p.profile().duration(DT).unwrap(),
        6.4 + 10.0 + 6.4 - 0.5,
        1e-12
    ));
    assert_eq!(steps(&p, DT), Ok(22_300));
    // First step: 0.1 mm at 1 Hz about 1 mm.
    assert!(close(displacement(&p, 0.25), 1.1, 1e-12));
    assert!(close(displacement(&p, 0.75), 0.9, 1e-12));
    assert_eq!(frequency_at(&p, 0.25), Some(1.0));
    assert_eq!(amplitude_at(&p, 0.25), Some(0.1));
    // Rest after it, then the second amplitude from 2.5 s.
    assert_eq!(displacement(&p, 2.2), 1.0);
    assert_eq!(frequency_at(&p, 2.2), None);
    assert_eq!(amplitude_at(&p, 2.2), None);
    assert!(close(displacement(&p, 2.75), 1.25, 1e-12));
    assert_eq!(amplitude_at(&p, 2.75), Some(0.25));
    // Then 10 Hz from 5 s: 0.1 mm, a quarter period in.
    assert!(close(displacement(&p, 5.025), 1.1, 1e-12));
    assert_eq!(frequency_at(&p, 5.025), Some(10.0));
    assert!(close(displacement(&p, 5.725), 1.25, 1e-12));
    assert_eq!(amplitude_at(&p, 5.725), Some(0.25));
    // Ramp 1 -> 2 mm over 6.4..10.4 s, hold to 16.4 s.
    assert!(close(displacement(&p, 8.4), 1.5, 1e-12));
    assert_eq!(frequency_at(&p, 8.4), None);
    assert_eq!(displacement(&p, 12.0), 2.0);
    // Second block at 2 mm.
    assert!(close(displacement(&p, 16.65), 2.1, 1e-12));
    assert_eq!(frequency_at(&p, 16.65), Some(1.0));
    assert!(close(displacement(&p, 16.4 + 5.7 + 0.025), 2.25, 1e-12));
    assert_eq!(displacement(&p, 100.0), 2.0);
    assert_eq!(frequency_at(&p, 100.0), None);
    assert_eq!(displacement(&p, -1.0), 1.0);
    // Continuous everywhere: no jump larger than the slope allows.
    let dt = 1e-4;
    let mut prev = displacement(&p, 0.0);
    let mut n = 1;
    while n as f64 * dt <= 22.3 {
        let x = displacement(&p, n as f64 * dt);
        // Fastest slope: 2π 10 Hz x 0.25 mm = 15.7 mm/s.
        assert!((x - prev).abs() <= 15.8 * dt, "jump at {} s", n as f64 * dt);
        prev = x;
        n += 1;
    }
    // Each step starts and ends at the preload.
    for t in [0.0, 2.0, 2.5, 4.5, 5.0, 5.2, 5.7, 5.9, 16.4, 21.9] {
        let x = displacement(&p, t);
        assert!(close(x, 1.0, 1e-12) || close(x, 2.0, 1e-12), "{x} at {t} s");
    }
}

#[test]
fn stepped_sine_single_preload_and_settle_in_cycles() {
    let p = ProfileSpec::SteppedSine(SteppedSine {
        preload: Some(0.5),
        preloads: None,
        frequencies_hz: vec![2.0, 4.0],
        amplitudes: vec![0.05, 0.1, 0.2],
        cycles: 3.0,
        settle_s: None,
        settle_cycles: Some(1.0),
        ramp_s: None,
        hold_s: None,
    });
    // Steps of 1.5 s + 0.5 s rest at 2 Hz, 0.75 + 0.25 s at 4 Hz; no
    // rest after the last step.
    assert_eq!(steps(&p, DT), Ok(8_750));
    assert!(close(displacement(&p, 4.125), 0.7, 1e-12));
    assert_eq!(amplitude_at(&p, 4.125), Some(0.2));
    assert_eq!(frequency_at(&p, 6.0 + 2.0 + 0.0625), Some(4.0));
    assert!(close(displacement(&p, 6.0 + 2.0 + 0.0625), 0.7, 1e-12));
    // No preload at all means 0.
    let q = ProfileSpec::SteppedSine(SteppedSine {
        preload: None,
        preloads: None,
        frequencies_hz: vec![1.0],
        amplitudes: vec![1.0],
        cycles: 1.0,
        settle_s: None,
        settle_cycles: None,
        ramp_s: None,
        hold_s: None,
    });
    assert_eq!(steps(&q, DT), Ok(1000));
    assert!(close(displacement(&q, 0.25), 1.0, 1e-12));
    assert_eq!(displacement(&q, 1.0), 0.0);
}

#[test]
fn stepped_sine_errors_name_the_field_and_bound() {
    let with = |f: &dyn Fn(&mut ProfileSpec)| {
        let mut p = stepped_sine();
        f(&mut p);
        steps(&p, DT).unwrap_err()
    };
    macro_rules! set {
        ($field:ident, $v:expr) => {
            &|p: &mut ProfileSpec| {
                if let ProfileSpec::SteppedSine(SteppedSine { $field, .. }) = p {
                    *$field = $v;
                }
            }
        };
    }
    assert_eq!(
        with(set!(preload, Some(0.0))),
        "give preload or preloads, not both"
    );
    assert_eq!(
        with(set!(preloads, Some(vec![0.0, f64::NAN]))),
        "preloads[1] must be finite, got NaN"
    );
    assert_eq!(
        with(set!(frequencies_hz, vec![1.0, -2.0])),
        "frequencies_hz[1] must be finite and > 0, got -2"
    );
    assert_eq!(
        with(set!(frequencies_hz, vec![500.0])),
        "frequencies_hz[0] = 500 Hz must be below half the rate (500 Hz)"
    );
    assert_eq!(
        with(set!(amplitudes, vec![])),
        "amplitudes: 1 to 10000 values expected, got 0"
    );
    assert_eq!(
        with(set!(amplitudes, vec![0.0])),
        "amplitudes[0] must be finite and > 0, got 0"
    );
    assert_eq!(
        with(set!(cycles, 2.5)),
        "cycles must be a whole number >= 1 (each step ends at the preload), got 2.5"
    );
    assert!(with(set!(cycles, 0.0)).starts_with("cycles must be a whole number >= 1"));
    assert_eq!(
        with(set!(settle_cycles, Some(1.0))),
        "give settle_s or settle_cycles, not both"
    );
    assert_eq!(
        with(set!(settle_s, Some(-0.5))),
        "settle_s must be finite and >= 0, got -0.5"
    );
    assert_eq!(
        with(set!(ramp_s, None)),
        "ramp_s (s) is needed to go from one preload to the next (2 preloads)"
    );
    assert_eq!(
        with(set!(ramp_s, Some(0.0))),
        "ramp_s must be finite and > 0, got 0"
    );
    assert_eq!(
        with(set!(hold_s, Some(f64::NAN))),
        "hold_s must be finite and >= 0, got NaN"
    );
    assert_eq!(
        with(set!(preloads, Some(vec![1.0]))),
        "ramp_s and hold_s apply between preloads: give two or more preloads, or remove them"
    );
    assert_eq!(
        with(&|p| {
            if let ProfileSpec::SteppedSine(SteppedSine {
                frequencies_hz,
                amplitudes,
                ..
            }) = p
            {
                *frequencies_hz = (1..=10).map(f64::from).collect();
                *amplitudes = vec![0.1; 10_000];
            }
        }),
        "200000 sine steps (preloads x frequencies_hz x amplitudes), more than the limit of 100000"
    );
    let mut single = stepped_sine();
    if let ProfileSpec::SteppedSine(SteppedSine {
        preload,
        preloads,
        settle_cycles,
        settle_s,
        ramp_s,
        hold_s,
        ..
    }) = &mut single
    {
        (*preload, *preloads) = (Some(f64::NEG_INFINITY), None);
        (*settle_s, *settle_cycles) = (None, Some(-1.0));
        (*ramp_s, *hold_s) = (None, None);
    }
    assert_eq!(
        steps(&single, DT).unwrap_err(),
        "preload must be finite, got -inf"
    );
    if let ProfileSpec::SteppedSine(SteppedSine { preload, .. }) = &mut single {
        *preload = Some(0.0);
    }
    assert_eq!(
        steps(&single, DT).unwrap_err(),
        "settle_cycles must be finite and >= 0, got -1"
    );
}

fn sweep(spacing: Spacing) -> ProfileSpec {
    ProfileSpec::Sweep(Sweep {
        amplitude: 0.5,
        f_start_hz: 1.0,
        f_end_hz: 16.0,
        duration_s: 8.0,
        spacing,
        preload: 1.0,
    })
}

#[test]
fn log_sweep_frequency_and_phase() {
    let p = sweep(Spacing::Log);
    assert_eq!(steps(&p, DT), Ok(8000));
    // One octave every 2 s.
    assert!(close(frequency_at(&p, 0.0).unwrap(), 1.0, 1e-12));
    assert!(close(frequency_at(&p, 2.0).unwrap(), 2.0, 1e-12));
    assert!(close(frequency_at(&p, 8.0).unwrap(), 16.0, 1e-12));
    assert_eq!(frequency_at(&p, 8.1), None);
    assert_eq!(frequency_at(&p, -0.1), None);
    assert_eq!(amplitude_at(&p, 4.0), Some(0.5));
    assert_eq!(amplitude_at(&p, 9.0), None);
    // Phase: f0 T / ln r (r^(t/T) - 1) cycles, 2/ln 2 cycles after 2 s.
    let c = 2.0 / 2f64.ln();
    let expected = 1.0 + 0.5 * (TAU * c).sin();
    assert!(close(displacement(&p, 2.0), expected, 1e-12));
    assert_eq!(displacement(&p, 0.0), 1.0);
    // The phase is the integral of the frequency: the numerical slope
    // of x matches 2π f A cos φ.
    for t in [0.3, 1.7, 5.2, 7.9] {
        let h = 1e-6;
        let slope = (displacement(&p, t + h) - displacement(&p, t - h)) / (2.0 * h);
        let f = frequency_at(&p, t).unwrap();
        let l = 16f64.ln();
        let phase = TAU * 8.0 / l * ((l * t / 8.0).exp() - 1.0);
        assert!(
            close(slope, TAU * f * 0.5 * phase.cos(), 1e-5 * TAU * f),
            "t = {t}"
        );
    }
    // Held after the end.
    assert_eq!(displacement(&p, 9.0), displacement(&p, 8.0));
}

#[test]
fn linear_sweep_frequency_and_phase() {
    let p = sweep(Spacing::Linear);
    assert!(close(frequency_at(&p, 4.0).unwrap(), 8.5, 1e-12));
    // Phase f0 t + (f1 - f0) t² / 2T: 1 + 15/16 cycles at 1 s.
    let expected = 1.0 + 0.5 * (TAU * (1.0 + 15.0 / 16.0)).sin();
    assert!(close(displacement(&p, 1.0), expected, 1e-12));
    // 8 + 60 = 68 whole cycles at the end: back at the preload.
    assert!(close(displacement(&p, 8.0), 1.0, 1e-12));
    // A "sweep" from f to f is a sine.
    let flat = ProfileSpec::Sweep(Sweep {
        amplitude: 1.0,
        f_start_hz: 2.0,
        f_end_hz: 2.0,
        duration_s: 1.0,
        spacing: Spacing::Log,
        preload: 0.0,
    });
    assert!(close(displacement(&flat, 0.125), 1.0, 1e-12));
    assert_eq!(frequency_at(&flat, 0.5), Some(2.0));
}

#[test]
fn sweep_errors_name_the_field_and_bound() {
    let set = |f: &dyn Fn(&mut f64, &mut f64, &mut f64, &mut f64, &mut f64)| {
        let mut p = sweep(Spacing::Log);
        if let ProfileSpec::Sweep(Sweep {
            amplitude,
            f_start_hz,
            f_end_hz,
            duration_s,
            preload,
            ..
        }) = &mut p
        {
            f(amplitude, f_start_hz, f_end_hz, duration_s, preload);
        }
        steps(&p, DT).unwrap_err()
    };
    assert_eq!(
        set(&|a, _, _, _, _| *a = 0.0),
        "amplitude must be finite and > 0, got 0"
    );
    assert_eq!(
        set(&|_, f, _, _, _| *f = -1.0),
        "f_start_hz must be finite and > 0, got -1"
    );
    assert_eq!(
        set(&|_, _, f, _, _| *f = 600.0),
        "f_end_hz = 600 Hz must be below half the rate (500 Hz)"
    );
    assert_eq!(
        set(&|_, f, _, _, _| *f = 500.0),
        "f_start_hz = 500 Hz must be below half the rate (500 Hz)"
    );
    assert_eq!(
        set(&|_, _, _, d, _| *d = f64::INFINITY),
        "duration_s must be finite and > 0, got inf"
    );
    assert_eq!(
        set(&|_, _, _, _, x| *x = f64::NAN),
        "preload must be finite, got NaN"
    );
}

fn stop_start(rise_s: f64) -> ProfileSpec {
    ProfileSpec::StopStart(StopStart {
        frequency_hz: 10.0,
        damping: 0.1,
        rise_s,
        duration_s: 3.0,
        events: vec![
            StopStartEvent {
                at_s: 0.5,
                size: 2.0,
            },
            StopStartEvent {
                at_s: 2.0,
                size: -2.0,
            },
        ],
        preload: 0.5,
    })
}

#[test]
fn stop_start_is_a_ringing_smooth_step() {
    let p = stop_start(0.05);
    assert_eq!(steps(&p, DT), Ok(3000));
    assert_eq!(displacement(&p, 0.0), 0.5);
    assert_eq!(displacement(&p, 0.5), 0.5);
    assert_eq!(frequency_at(&p, 1.0), None);
    assert_eq!(amplitude_at(&p, 1.0), None);
    // Starts with zero slope, and the unit response is continuous
    // with a continuous slope at the end of the rise.
    let h = 1e-8;
    assert!(displacement(&p, 0.5 + h) - 0.5 < 1e-9);
    for (f, z, r) in [(10.0, 0.1, 0.05), (4.0, 0.0, 0.3), (13.4, 0.7, 0.01)] {
        let y = |t: f64| stop_start_response(t, f, z, r);
        assert!((y(r + h) - y(r - h)).abs() < 1e-5, "{f} {z} {r}");
        let left = (y(r) - y(r - h)) / h;
        let right = (y(r + h) - y(r)) / h;
        assert!((left - right).abs() < 1e-3, "{left} {right}");
        // Zero slope at the start.
        assert!(y(h) < 1e-6);
    }
    // Overshoot then ring-down to the new level 2.5 mm; the first peak
    // of the step response is 1 + exp(-πζ/√(1-ζ²)).
    let step = |t: f64| stop_start_response(t, 10.0, 0.1, 0.0);
    let zeta: f64 = 0.1;
    let wd = TAU * 10.0 * (1.0 - zeta * zeta).sqrt();
    let peak = 1.0 + (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
    assert!(close(step(std::f64::consts::PI / wd), peak, 1e-12));
    assert!(close(displacement(&p, 1.99), 2.5, 2e-3));
    // Back to the preload after the stop event.
    assert!(close(displacement(&p, 3.0), 0.5, 2e-3));
    // A slow rise (many periods) barely overshoots.
    let slow_peak = (0..2000)
        .map(|k| stop_start_response(k as f64 * 1e-3, 10.0, 0.1, 1.0))
        .fold(0.0, f64::max);
    assert!(slow_peak < 1.02 && slow_peak > 0.999, "{slow_peak}");
    // The ramp response formula against a direct integration of
    // ÿ + 2ζω ẏ + ω² y = ω² u(t), u the unit ramp over rise_s.
    let (w, z, r) = (TAU * 10.0, 0.1, 0.05);
    let (mut y, mut v) = (0.0f64, 0.0f64);
    let hh = 1e-6;
    let acc = |t: f64, y: f64, v: f64| w * w * ((t / r).min(1.0) - y) - 2.0 * z * w * v;
    let mut t = 0.0;
    for _ in 0..300_000 {
        // Classic RK4.
        let (k1y, k1v) = (v, acc(t, y, v));
        let (k2y, k2v) = (
            v + 0.5 * hh * k1v,
            acc(t + 0.5 * hh, y + 0.5 * hh * k1y, v + 0.5 * hh * k1v),
        );
        let (k3y, k3v) = (
            v + 0.5 * hh * k2v,
            acc(t + 0.5 * hh, y + 0.5 * hh * k2y, v + 0.5 * hh * k2v),
        );
        let (k4y, k4v) = (v + hh * k3v, acc(t + hh, y + hh * k3y, v + hh * k3v));
        y += hh / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y);
        v += hh / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        t += hh;
    }
    assert!(close(y, stop_start_response(t, 10.0, z, r), 1e-6), "{y}");
}

#[test]
fn stop_start_errors_name_the_field_and_bound() {
    let set = |f: &dyn Fn(&mut ProfileSpec)| {
        let mut p = stop_start(0.05);
        f(&mut p);
        steps(&p, DT).unwrap_err()
    };
    macro_rules! field {
        ($field:ident, $v:expr) => {
            &|p: &mut ProfileSpec| {
                if let ProfileSpec::StopStart(StopStart { $field, .. }) = p {
                    *$field = $v;
                }
            }
        };
    }
    assert_eq!(
        set(field!(frequency_hz, 0.0)),
        "frequency_hz must be finite and > 0, got 0"
    );
    assert_eq!(
        set(field!(frequency_hz, 800.0)),
        "frequency_hz = 800 Hz must be below half the rate (500 Hz)"
    );
    assert_eq!(
        set(field!(damping, 1.0)),
        "damping (ratio) must be in [0, 1) (an oscillating mode), got 1"
    );
    assert_eq!(
        set(field!(rise_s, -0.1)),
        "rise_s must be finite and >= 0, got -0.1"
    );
    assert_eq!(
        set(field!(duration_s, 0.0)),
        "duration_s must be finite and > 0, got 0"
    );
    assert_eq!(
        set(field!(preload, f64::NAN)),
        "preload must be finite, got NaN"
    );
    assert_eq!(
        set(field!(events, vec![])),
        "events: 1 to 64 events expected, got 0"
    );
    assert_eq!(
        set(field!(
            events,
            vec![
                StopStartEvent {
                    at_s: 1.0,
                    size: 1.0
                },
                StopStartEvent {
                    at_s: 0.5,
                    size: 1.0
                }
            ]
        )),
        "events[1].at_s must be in [1, duration_s = 3) s (events in time order), got 0.5"
    );
    assert_eq!(
        set(field!(
            events,
            vec![StopStartEvent {
                at_s: 3.0,
                size: 1.0
            }]
        )),
        "events[0].at_s must be in [0, duration_s = 3) s (events in time order), got 3"
    );
    assert_eq!(
        set(field!(
            events,
            vec![StopStartEvent {
                at_s: 0.0,
                size: f64::INFINITY
            }]
        )),
        "events[0].size must be finite, got inf"
    );
}

fn csv(text: &str, column: Column, time: Time<'_>) -> Result<Vec<(f64, f64)>, String> {
    read_csv("m.csv", text, &column, time).map_err(|e| e.to_string())
}

#[test]
fn csv_with_header_and_time_column() {
    let text =
        "# measured on the rig\ntime_s, \"x_mm\",force_N\n\n10.0,0.0,1\n10.5,1.0,2\n11.0,-1.0,3\n";
    let t = Column::Name("time_s".into());
    let s = csv(text, Column::Name("x_mm".into()), Time::Column(&t)).unwrap();
    assert_eq!(s, vec![(0.0, 0.0), (0.5, 1.0), (1.0, -1.0)]);
    // By index, semicolons, a rate instead of times.
    let s = csv("0;2.5\n0;3.5\n", Column::Index(2), Time::Rate(4.0)).unwrap();
    assert_eq!(s, vec![(0.0, 2.5), (0.25, 3.5)]);
    // Interpolation and the replayed profile.
    let p = ProfileSpec::Replay(Replay {
        file: "m.csv".into(),
        column: Column::Index(2),
        time_column: Some(Column::Index(1)),
        rate_hz: None,
        force_column: None,
        samples: vec![(0.0, 0.0), (0.5, 1.0), (1.0, -1.0)],
        measured: Vec::new(),
    });
    assert_eq!(steps(&p, DT), Ok(1000));
    assert_eq!(displacement(&p, 0.5), 1.0);
    assert_eq!(displacement(&p, 0.25), 0.5);
    assert_eq!(displacement(&p, 0.75), 0.0);
    assert_eq!(displacement(&p, -1.0), 0.0);
    assert_eq!(displacement(&p, 2.0), -1.0);
    assert_eq!(frequency_at(&p, 0.5), None);
    assert_eq!(amplitude_at(&p, 0.5), None);
}

#[test]
fn csv_errors_name_file_row_and_column() {
    let t = Column::Index(1);
    let x = || Column::Index(2);
    let e = csv("t,x\n0,1\n0.1,abc\n", x(), Time::Column(&t)).unwrap_err();
    assert_eq!(e, "m.csv: row 3, column 2: expected a number, got 'abc'");
    let e = csv("t,x\n0,1\n0.1,inf\n", x(), Time::Column(&t)).unwrap_err();
    assert_eq!(
        e,
        "m.csv: row 3, column 2: expected a finite number, got 'inf'"
    );
    let e = csv("t,x\n0,1\n0.1\n", x(), Time::Column(&t)).unwrap_err();
    assert_eq!(e, "m.csv: row 3, column 2: missing (the row has 1 columns)");
    let e = csv("t,x\n0,1\n0.2,1\n0.2,3\n", x(), Time::Column(&t)).unwrap_err();
    assert_eq!(
        e,
        "m.csv: row 4, column 1: time 0.2 s is not after the 0.2 s of row 3"
    );
    let e = csv("t,x\n0,1\n", x(), Time::Column(&t)).unwrap_err();
    assert_eq!(e, "m.csv: 1 data rows, at least 2 needed");
    let e = csv("# nothing\n\n", x(), Time::Rate(10.0)).unwrap_err();
    assert_eq!(e, "m.csv: no rows");
    let e = csv("t,x\n0,1\n1,2\n", Column::Name("y".into()), Time::Rate(1.0)).unwrap_err();
    assert_eq!(
        e,
        "m.csv: row 1: no column named 'y' for column (the header has 't', 'x')"
    );
    let e = csv("0,1\n1,2\n", Column::Name("x".into()), Time::Rate(1.0)).unwrap_err();
    assert_eq!(
        e,
        "m.csv: column 'x' needs a header row, but row 1 is all numbers"
    );
    let e = csv(
        "t,x\n-1e308,1\n1e308,2\n",
        x(),
        Time::Column(&Column::Index(1)),
    )
    .unwrap_err();
    assert!(
        e.starts_with("m.csv: row 3, column 1: time 1e308 s is too far"),
        "{e}"
    );
}

#[test]
fn resolve_reads_the_file_and_checks_the_fields() {
    let dir = std::env::temp_dir().join(format!("bushing-profile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("d.csv"), "t,x\n0,0\n0.5,2\n").unwrap();
    let replay = |column: Column, time_column: Option<Column>, rate_hz: Option<f64>| {
        ProfileSpec::Replay(Replay {
            file: "d.csv".into(),
            column,
            time_column,
            rate_hz,
            force_column: None,
            samples: Vec::new(),
            measured: Vec::new(),
        })
    };
    let p = resolve(
        replay(Column::Name("x".into()), None, Some(2.0)),
        &dir,
        false,
    )
    .unwrap();
    assert_eq!(steps(&p, DT), Ok(500));
    assert_eq!(displacement(&p, 0.25), 1.0);
    // Without the file: no samples.
    let unread = replay(Column::Index(2), None, Some(2.0));
    assert_eq!(
        steps(&unread, DT).unwrap_err(),
        "replay: 0 samples; at least 2, read from the file when the scene is parsed"
    );
    let e = resolve(
        replay(Column::Index(2), Some(Column::Index(1)), Some(2.0)),
        &dir,
        false,
    )
    .unwrap_err();
    assert_eq!(e, "give time_column or rate_hz, not both");
    let e = resolve(replay(Column::Index(2), None, None), &dir, false).unwrap_err();
    assert_eq!(e, "give time_column (a time column in s) or rate_hz (Hz)");
    let e = resolve(replay(Column::Index(0), None, Some(2.0)), &dir, false).unwrap_err();
    assert_eq!(e, "column = 0: column indices count from 1 to 10000");
    let e = resolve(
        replay(Column::Index(2), Some(Column::Name(" ".into())), None),
        &dir,
        false,
    )
    .unwrap_err();
    assert_eq!(e, "time_column: empty column name");
    let e = resolve(replay(Column::Index(2), None, Some(-1.0)), &dir, false).unwrap_err();
    assert_eq!(e, "rate_hz must be finite and > 0, got -1");
    let e = resolve(
        replay(Column::Index(2), None, Some(2.0)),
        &dir.join("no"),
        false,
    )
    .unwrap_err();
    assert!(
        e.starts_with("replay file ") && e.contains("d.csv: cannot read: "),
        "{e}"
    );
    let mut directory = replay(Column::Index(2), None, Some(2.0));
    if let ProfileSpec::Replay(Replay { file, .. }) = &mut directory {
        *file = ".".into();
    }
    let e = resolve(directory, &dir, false).unwrap_err();
    assert!(e.ends_with(": not a regular file"), "{e}");
    let mut empty_name = replay(Column::Index(2), None, Some(2.0));
    if let ProfileSpec::Replay(Replay { file, .. }) = &mut empty_name {
        file.clear();
    }
    assert_eq!(
        resolve(empty_name, &dir, false).unwrap_err(),
        "file must name a CSV file"
    );
    // Other profiles pass through.
    assert_eq!(resolve(multi(), &dir, false).unwrap(), multi());
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn column_deserializes_from_names_and_indices() {
    #[derive(Deserialize)]
    struct C {
        c: Column,
    }
    let c: C = toml::from_str("c = \"x_mm\"").unwrap();
    assert_eq!(c.c, Column::Name("x_mm".into()));
    let c: C = toml::from_str("c = 3").unwrap();
    assert_eq!(c.c, Column::Index(3));
    let e = toml::from_str::<C>("c = 1.5").err().unwrap();
    assert!(
        e.message()
            .contains("a column name (string) or a 1-based column index (integer)"),
        "{e}"
    );
}
