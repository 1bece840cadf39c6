//! The identification's input: campaigns read and checked, and the first
//! harmonic of measured sines.
//!
//! `tests/campaigns/broken/` holds one campaign per mistake; its
//! `campaign.toml` starts with the text its error must contain (`# expect:
//! …`, one or more) and, for a mistake with a place, `# at: LINE`.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use bushing::{Bushing, MaxwellForm, MaxwellSpec, Polynomial};
use bushing_sim::family::maxwell::{DynMaxwell, Storage};
use bushing_sim::identify::campaign::{Campaign, Kind, Nominal, Record, Test, TestError};
use bushing_sim::identify::sine::{SinePoint, first_harmonic};

fn broken() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/campaigns/broken")
}

#[test]
fn every_broken_campaign_gives_its_expected_error() {
    let mut seen = 0;
    let mut dirs: Vec<_> = std::fs::read_dir(broken())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    let mut wrong = Vec::new();
    for dir in dirs {
        let text = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
        let expect: Vec<&str> = text
            .lines()
            .filter_map(|l| l.strip_prefix("# expect: "))
            .collect();
        let at = text.lines().find_map(|l| l.strip_prefix("# at: "));
        assert!(!expect.is_empty(), "{}: no `# expect:` line", dir.display());
        let message = match Campaign::load(&dir, true) {
            Ok(c) => format!("read, {} tests usable", c.tests.len()),
            Err(e) => e.to_string(),
        };
        let placed = at.is_none_or(|line| message.contains(&format!("campaign.toml:{line}:")));
        if !placed || !expect.iter().all(|e| message.contains(e)) {
            wrong.push(format!(
                "{}\n  got {message}\n  expected {expect:?} at {at:?}",
                dir.display()
            ));
        }
        seen += 1;
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    assert!(seen >= 15, "{seen} broken campaigns");
}

/// One bad test is left out with its reason; the others are read.
#[test]
fn one_bad_test_does_not_stop_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(broken().join("14-negative-frequency/sine.csv")).unwrap();
    std::fs::write(dir.path().join("good.csv"), &good).unwrap();
    std::fs::write(
        dir.path().join("bad.csv"),
        "time_s,x_mm,force_n\n0,0,0\n0,1,1\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("campaign.toml"),
        r#"[campaign]
name = "part"

[[test]]
name = "good"
kind = "sine"
file = "good.csv"
frequency_hz = 5.0

[[test]]
name = "bad"
kind = "triangle"
file = "bad.csv"

[[test]]
name = "road"
kind = "cobbles"
file = "good.csv"
"#,
    )
    .unwrap();
    let c = Campaign::load(dir.path(), false).unwrap();
    assert_eq!(c.name, "part");
    assert_eq!(c.tests.len(), 1);
    assert_eq!(c.tests[0].name, "good");
    assert_eq!(c.tests[0].kind, Kind::Sine);
    assert_eq!(c.tests[0].record.len(), 60);
    let reasons: Vec<String> = c
        .excluded
        .iter()
        .map(|e| format!("{}: {}", e.name, e.reason))
        .collect();
    assert_eq!(reasons.len(), 2, "{reasons:?}");
    assert!(
        reasons[0].starts_with("bad: ")
            && reasons[0]
                .ends_with("bad.csv: row 3, column 1: time 0 s is not after the 0 s of row 2"),
        "{reasons:?}"
    );
    assert_eq!(
        reasons[1],
        "road: kind 'cobbles' is not one of multi-step, triangle, sine, other"
    );
}

/// A sine record of a linear backbone with a Maxwell bank, stepped at the
/// sampling step itself: its steady state is the discrete bank's exact
/// response, which the first harmonic must give back.
fn maxwell_sine(f: f64, a: f64, per: usize, periods: usize) -> (Test, (f64, f64), f64) {
    let k = 120.0;
    let dt = 1.0 / (f * per as f64);
    let cells = [MaxwellSpec::hz(f, 0.2), MaxwellSpec::hz(4.0 * f, 0.3)];
    let bank =
        DynMaxwell::<f64>::new(MaxwellForm::RateExactRamp, &cells, dt, Storage::Plain).unwrap();
    let (re, im) = bank.branch_response(TAU * f);
    let g0 = 0.5;
    let b = Bushing::new(
        Polynomial::<f64, 2>::new(&[0.0, k], (-10.0, 10.0)).unwrap(),
        (bank,),
    )
    .unwrap();
    let mut s = b.state_at(0.0);
    let mut record = Record::default();
    for n in 0..=per * periods {
        let t = n as f64 * dt;
        let x = a * (TAU * f * t).sin();
        let o = b.step(&mut s, x);
        record.time.push(t);
        record.x.push(x);
        record.force.push(o.force);
    }
    let test = Test {
        name: "sine".into(),
        kind: Kind::Sine,
        file: PathBuf::from("sine.csv"),
        nominal: Nominal {
            frequency_hz: Some(f),
            amplitude_mm: Some(a),
            preload_mm: Some(0.0),
            speed_mm_per_min: None,
        },
        record,
        preload_hold_s: 1200.0,
    };
    (test, (k * (g0 + re), k * im), k)
}

#[test]
fn the_first_harmonic_of_a_maxwell_sine_is_the_bank_s_exact_response() {
    // The first half is left out: the slower cell's transient has decayed
    // by e^-60π at the window's start.
    let (test, (storage, loss), _) = maxwell_sine(5.0, 0.25, 50, 60);
    let p: SinePoint = first_harmonic(&test).unwrap();
    assert_eq!(p.periods, 30);
    assert!((p.samples_per_period - 50.0).abs() < 1e-9);
    assert!(
        (p.storage / storage - 1.0).abs() < 1e-5,
        "{} {storage}",
        p.storage
    );
    assert!((p.loss / loss - 1.0).abs() < 1e-5, "{} {loss}", p.loss);
    assert!((p.amplitude_mm / 0.25 - 1.0).abs() < 1e-12);
    assert!(p.preload_mm.abs() < 1e-12);
    // The trapezoid rule over a sampled first harmonic: π X² K″ sin θ / θ,
    // θ = 2π / 50 (0.26 % below π X² K″).
    let theta = TAU / 50.0;
    let w = std::f64::consts::PI * 0.25 * 0.25 * loss * theta.sin() / theta;
    assert!(
        (p.energy_per_cycle / w - 1.0).abs() < 1e-5,
        "{} {w}",
        p.energy_per_cycle
    );
    assert!(p.secant > p.storage && p.loss_factor > 0.0);
    // W_d / (A_F A_x), with A_F = K_s A_x.
    let x = &test.record.x;
    let ax =
        x.iter().cloned().fold(f64::MIN, f64::max) - x.iter().cloned().fold(f64::MAX, f64::min);
    let w_norm = p.energy_per_cycle / (p.secant * ax * ax);
    assert!((p.normalised_energy / w_norm - 1.0).abs() < 1e-12);
}

#[test]
fn sines_that_fail_a_check_are_excluded_with_the_reason() {
    let reason = |t: &Test| match first_harmonic(t) {
        Err(TestError::Check(m)) => m,
        other => panic!("{other:?}"),
    };
    // Too few samples per period.
    let (t, ..) = maxwell_sine(5.0, 0.25, 8, 10);
    assert!(
        reason(&t).starts_with("8.0 samples per period at 5 Hz, at least 10 needed"),
        "{}",
        reason(&t)
    );
    // A sine the machine did not follow: half the nominal amplitude.
    let (mut t, ..) = maxwell_sine(50.0, 0.05, 50, 10);
    t.nominal.amplitude_mm = Some(0.1);
    assert!(
        reason(&t).starts_with("recorded amplitude 0.0500 mm, nominal 0.1 mm"),
        "{}",
        reason(&t)
    );
    // A nominal frequency the record does not have.
    let (mut t, ..) = maxwell_sine(5.0, 0.25, 50, 10);
    t.nominal.frequency_hz = Some(6.0);
    assert!(reason(&t).contains("not a sine at 6 Hz"), "{}", reason(&t));
    // A clipped force.
    let (mut t, ..) = maxwell_sine(5.0, 0.25, 50, 10);
    let top = 0.8 * t.record.force.iter().cloned().fold(f64::MIN, f64::max);
    for f in &mut t.record.force {
        *f = f.min(top);
    }
    assert!(
        reason(&t).starts_with("the force is clipped: "),
        "{}",
        reason(&t)
    );
    // A triangle written as a sine.
    let (mut t, ..) = maxwell_sine(5.0, 0.25, 50, 10);
    for (x, time) in t.record.x.iter_mut().zip(&t.record.time) {
        let phase = (time * 5.0).fract();
        *x = 0.25 * (1.0 - 4.0 * (phase - 0.5).abs());
    }
    assert!(
        reason(&t).starts_with("the displacement is not a sine at 5 Hz"),
        "{}",
        reason(&t)
    );
}

const MAXWELL_MODEL: &str = r#"
title = "linear backbone and three Maxwell cells"
[run]
rate_hz = 1000
number = "f64"
[backbone]
type = "polynomial"
coefficients = [0.0, 150.0]
range = [-8.0, 8.0]
[[effects]]
type = "maxwell"
form = "rate-exact-ramp"
cells = [{ f_hz = 0.5, g = 0.1 }, { f_hz = 5.0, g = 0.2 }, { f_hz = 50.0, g = 0.05 }]
[profile]
type = "sine"
amplitude = 1.0
frequency_hz = 1.0
cycles = 1
"#;

/// A campaign generated from a known model and read back: every test is
/// usable, every sine's first harmonic is the model's exact discrete
/// response without noise, and within five standard deviations of the
/// least-squares estimate with the default 0.5 % noise.
#[test]
fn a_generated_campaign_reads_back_with_the_model_s_moduli() {
    use bushing_sim::identify::synth;
    use bushing_sim::output::Staged;
    let scene = bushing_sim::Scene::parse("model.toml", MAXWELL_MODEL).unwrap();
    let grid = synth::part_grid(60.0, &[0.0, 2.0]);
    let (k, cells) = (
        150.0,
        [
            MaxwellSpec::hz(0.5, 0.1),
            MaxwellSpec::hz(5.0, 0.2),
            MaxwellSpec::hz(50.0, 0.05),
        ],
    );
    for noise in [0.0, 0.005] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("campaign");
        let mut staged = Staged::begin(&out).unwrap();
        let samples = synth::write(&scene, &grid, noise, 7, 1200.0, &mut staged).unwrap();
        staged.commit().unwrap();
        let c = Campaign::load(&out, true).unwrap();
        assert_eq!(c.tests.len(), grid.len(), "{:?}", c.excluded);
        assert_eq!(
            c.tests.iter().map(|t| t.record.len()).sum::<usize>(),
            samples
        );
        let mut sines = 0;
        for t in c.tests.iter().filter(|t| t.kind == Kind::Sine) {
            let p = first_harmonic(t).unwrap_or_else(|e| panic!("{}: {e}", t.name));
            let f = p.frequency_hz;
            let dt = 1.0 / (200.0 * f);
            let bank =
                DynMaxwell::<f64>::new(MaxwellForm::RateExactRamp, &cells, dt, Storage::Plain)
                    .unwrap();
            let (re, im) = bank.branch_response(TAU * f);
            let (storage, loss) = (k * (0.65 + re), k * im);
            // Without noise: exact but for the slow cell's transient. With
            // it: five standard deviations of a least-squares coefficient,
            // σ √(2/n) over X, σ the noise times the force range (2 K_s X).
            let n = p.periods as f64 * p.samples_per_period;
            let bound = if noise == 0.0 {
                1e-5 * storage
            } else {
                5.0 * noise * 2.0 * p.secant * (2.0 / n).sqrt()
            };
            assert!(
                (p.storage - storage).abs() < bound && (p.loss - loss).abs() < bound,
                "{}: K' {} against {storage}, K'' {} against {loss}, bound {bound}",
                t.name,
                p.storage,
                p.loss
            );
            sines += 1;
        }
        assert_eq!(sines, 70);
    }
}

/// A generated test as the campaign reader would give it (no noise).
fn generated(model: &str, shape: bushing_sim::identify::synth::Shape, kind: Kind) -> Test {
    let scene = bushing_sim::Scene::parse("model.toml", model).unwrap();
    let rows = bushing_sim::identify::synth::record(&scene, &shape, 1200.0).unwrap();
    let mut record = Record::default();
    for [t, x, f] in rows {
        record.time.push(t);
        record.x.push(x);
        record.force.push(f);
    }
    Test {
        name: shape.name(),
        kind,
        file: PathBuf::from("generated.csv"),
        nominal: Nominal::default(),
        record,
        preload_hold_s: 1200.0,
    }
}

/// Each multi-step hold is found, and its end force is the long-term
/// backbone g^0 K x once the Maxwell cells have relaxed.
#[test]
fn multi_step_holds_end_on_the_long_term_backbone() {
    use bushing_sim::identify::relax::holds;
    use bushing_sim::identify::synth::Shape;
    let levels = vec![0.5, 1.0, 1.5, 2.0, 3.0];
    let test = generated(
        MAXWELL_MODEL,
        Shape::MultiStep {
            levels: levels.clone(),
            hold_s: 60.0,
        },
        Kind::MultiStep,
    );
    let h = holds(&test).unwrap();
    assert_eq!(h.len(), levels.len());
    for (hold, level) in h.iter().zip(&levels) {
        assert!((hold.level_mm - level).abs() < 1e-12, "{hold:?}");
        assert!((hold.duration_s - 60.0).abs() <= 1.0, "{}", hold.duration_s);
        let long_term = 0.65 * 150.0 * level;
        assert!(
            (hold.force_end / long_term - 1.0).abs() < 1e-9,
            "{} {long_term}",
            hold.force_end
        );
        // It relaxes: the start still carries some of the cells' share.
        assert!(hold.force_start > hold.force_end);
    }
    let sine = generated(
        MAXWELL_MODEL,
        Shape::Sine {
            frequency_hz: 1.0,
            amplitude_mm: 1.0,
            preload_mm: 0.0,
            cycles: 3,
        },
        Kind::MultiStep,
    );
    assert!(matches!(holds(&sine), Err(TestError::Check(m)) if m.starts_with("no hold")));
}

const IWAN_MODEL: &str = r#"
title = "linear backbone and two Jenkins cells"
[run]
rate_hz = 1000
number = "f64"
[backbone]
type = "polynomial"
coefficients = [0.0, 100.0]
range = [-10.0, 10.0]
[[effects]]
type = "iwan"
form = "clamp"
cells = [{ g = 0.2, x_f = 0.5 }, { g = 0.3, x_f = 1.2 }]
[profile]
type = "sine"
amplitude = 1.0
frequency_hz = 1.0
cycles = 1
"#;

/// Along a branch, the instantaneous modulus of an Iwan bank on a linear
/// backbone K steps down by g_i K where cell i slips, at twice its slip
/// distance from the turning point (Masing): K, then 0.8 K past 1 mm,
/// then 0.5 K past 2.4 mm. The low-pass smooths each kink over a few
/// samples (18 a millimetre), which the checks keep clear of.
#[test]
fn triangle_branches_show_each_cell_slipping_at_twice_its_distance() {
    use bushing_sim::identify::synth::Shape;
    use bushing_sim::identify::triangle::branches;
    let test = generated(
        IWAN_MODEL,
        Shape::Triangle {
            speed_mm_per_min: 10.0,
            amplitude_mm: 4.0,
            preload_mm: 0.0,
            cycles: 3,
            samples_per_mm: bushing_sim::identify::synth::PART_SAMPLES_PER_MM,
        },
        Kind::Triangle,
    );
    let t = branches(&test).unwrap();
    assert!((t.amplitude_mm - 4.0).abs() < 1e-9 && t.preload_mm.abs() < 1e-9);
    assert!(
        (t.speed_mm_per_min - 10.0).abs() < 1e-6,
        "{}",
        t.speed_mm_per_min
    );
    // The first loading from rest, then 6 reversals (the last one cut).
    assert!(t.branches.len() >= 6, "{}", t.branches.len());
    let mut checked = 0;
    for b in &t.branches[1..] {
        assert!((b.turning_mm.abs() - 4.0).abs() < 1e-9, "{}", b.turning_mm);
        for &(d, k) in &b.modulus {
            let expect = if (0.15..0.65).contains(&d) {
                100.0
            } else if (1.35..1.95).contains(&d) {
                80.0
            } else if (2.85..7.8).contains(&d) {
                50.0
            } else {
                continue;
            };
            assert!(
                (k / expect - 1.0).abs() < 0.01,
                "d = {d}: {k} against {expect}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked}");
    // Too few samples per branch: 0.05 mm at 10 mm/min, 3 Hz.
    let tiny = generated(
        IWAN_MODEL,
        Shape::Triangle {
            speed_mm_per_min: 10.0,
            amplitude_mm: 0.05,
            preload_mm: 0.0,
            cycles: 3,
            samples_per_mm: bushing_sim::identify::synth::PART_SAMPLES_PER_MM,
        },
        Kind::Triangle,
    );
    assert!(
        matches!(branches(&tiny), Err(TestError::Check(m)) if m.starts_with("no branch of 5 samples")),
        "{:?}",
        branches(&tiny)
    );
}

/// The first stage: the triangles' midline is the long-term backbone
/// g⁰ F^∞(x) of a model with every kind of hysteresis (Maxwell, Jenkins
/// and x_f cells on a cubic backbone), within 1 %, and so are the spline
/// knots made from it.
#[test]
fn the_triangle_midline_is_the_long_term_backbone() {
    use bushing_sim::identify::backbone::{knots, midline};
    use bushing_sim::identify::synth::Shape;
    use bushing_sim::identify::triangle::branches;
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/hysteresis-triangle.toml"),
    )
    .unwrap();
    // g0 = 1 - 0.22 (Maxwell) - 0.24 (Jenkins) - 0.2 (x_f); F_inf = 150 x + 4 x^3.
    let long_term = |x: f64| 0.34 * (150.0 * x + 4.0 * x * x * x);
    let triangles: Vec<_> = [(10.0, 4.5, 0.0), (1.0, 4.5, 0.0)]
        .into_iter()
        .map(|(speed, a, p)| {
            let t = generated(
                &text,
                Shape::Triangle {
                    speed_mm_per_min: speed,
                    amplitude_mm: a,
                    preload_mm: p,
                    cycles: 2,
                    samples_per_mm: bushing_sim::identify::synth::PART_SAMPLES_PER_MM,
                },
                Kind::Triangle,
            );
            branches(&t).unwrap()
        })
        .collect();
    // The Jenkins cells slip within 2 F_f / (g K) = 1.6 mm of a turning
    // point: 2 mm keeps clear of them.
    let points = midline(&triangles, 2.0, 0.05);
    assert!(points.len() > 100, "{}", points.len());
    let (lo, hi) = (points[0].0, points[points.len() - 1].0);
    assert!(lo <= -2.4 && hi >= 2.4, "{lo} {hi}");
    let worst = points
        .iter()
        .map(|&(x, f)| (f - long_term(x)).abs())
        .fold(0.0f64, f64::max);
    println!(
        "midline: {} points over [{lo}, {hi}] mm, largest error {:.3e} of the force at {hi} mm",
        points.len(),
        worst / long_term(hi)
    );
    for &(x, f) in &points {
        let want = long_term(x);
        assert!(
            (f - want).abs() <= 0.01 * long_term(hi),
            "x = {x}: midline {f} against {want}"
        );
    }
    let (xs, fs) = knots(&points, 9).unwrap();
    for (x, f) in xs.iter().zip(&fs) {
        assert!(
            (f - long_term(*x)).abs() <= 0.01 * long_term(hi),
            "{x}: {f}"
        );
    }
}

/// The second stage: on an Iwan bank with a linear backbone (long-term
/// modulus g⁰ K = 50 N/mm), two steps fitted to the normalised curve give
/// back the two Jenkins cells: slipping at 1.0 and 2.4 mm from the
/// turning point (twice their slip distances) with drops g_j / g⁰ of 0.4
/// and 0.6.
#[test]
fn jenkins_cells_are_placed_back_on_the_normalised_curve() {
    use bushing_sim::identify::hysteresis::{normalised, place};
    use bushing_sim::identify::synth::Shape;
    use bushing_sim::identify::triangle::branches;
    let triangles: Vec<_> = [10.0, 1.0]
        .into_iter()
        .map(|speed| {
            let t = generated(
                IWAN_MODEL,
                Shape::Triangle {
                    speed_mm_per_min: speed,
                    amplitude_mm: 4.0,
                    preload_mm: 0.0,
                    cycles: 2,
                    samples_per_mm: bushing_sim::identify::synth::PART_SAMPLES_PER_MM,
                },
                Kind::Triangle,
            );
            branches(&t).unwrap()
        })
        .collect();
    let curve = normalised(
        &triangles,
        |_| 50.0,
        (-10.0, 10.0),
        bushing_sim::identify::hysteresis::BIN_MM,
    );
    let cells = place(&curve, 2, 0.15).unwrap();
    println!("placed: {cells:?}");
    assert_eq!(cells.len(), 2);
    for (cell, (distance, drop)) in cells.iter().zip([(1.0, 0.4), (2.4, 0.6)]) {
        assert!(
            (cell.distance_mm - distance).abs() < 0.06,
            "{cell:?} against {distance} mm"
        );
        assert!(
            (cell.drop / drop - 1.0).abs() < 0.03,
            "{cell:?} against {drop}"
        );
    }
    assert!(place(&curve, 0, 0.15).is_none());
}

/// Records too short for any analysis, built through the library, are
/// refused with a reason rather than a panic; an empty multi-step grid
/// stays at rest.
#[test]
fn degenerate_records_are_refused_not_panicked_on() {
    use bushing_sim::identify::relax::holds;
    use bushing_sim::identify::synth::Shape;
    use bushing_sim::identify::triangle::branches;
    for n in [0, 1, 3] {
        let record = Record {
            time: (0..n).map(|i| i as f64).collect(),
            x: vec![0.0; n],
            force: vec![0.0; n],
        };
        let test = |kind| Test {
            name: "short".into(),
            kind,
            file: PathBuf::from("short.csv"),
            nominal: Nominal::default(),
            record: record.clone(),
            preload_hold_s: 1200.0,
        };
        assert!(matches!(
            first_harmonic(&test(Kind::Sine)),
            Err(TestError::Check(_))
        ));
        assert!(matches!(
            branches(&test(Kind::Triangle)),
            Err(TestError::Check(_))
        ));
        assert!(matches!(
            holds(&test(Kind::MultiStep)),
            Err(TestError::Check(_))
        ));
    }
    let empty = Shape::MultiStep {
        levels: Vec::new(),
        hold_s: 10.0,
    };
    assert_eq!(empty.displacement(5.0), 0.0);
}
