//! The scene profiles of docs/scenes.md (multi-step relaxation, stepped
//! sines, sweep, stop/start, CSV replay): parsed from scene text, run end to
//! end, and their errors located at the `[profile]` table.

use std::path::{Path, PathBuf};

use bushing_sim::profile::{self, stop_start_response};
use bushing_sim::{Scene, run};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn data() -> PathBuf {
    root().join("tests/data")
}

/// A scene with a linear backbone and two Maxwell cells; `[profile]` is
/// on line 13.
fn scene_text(rate_hz: f64, profile: &str) -> String {
    format!(
        r#"title = "profile test"
[run]
rate_hz = {rate_hz}
number = "f64"
[backbone]
type = "polynomial"
coefficients = [0.0, 100.0]
range = [-5.0, 5.0]
[[effects]]
type = "maxwell"
form = "rate-exact-ramp"
cells = [{{ f_hz = 0.5, g = 0.2 }}, {{ f_hz = 5.0, g = 0.1 }}]
[profile]
{profile}
"#
    )
}

/// Runs a scene into a fresh directory and returns the trace rows.
fn run_rows(scene: &Scene, name: &str) -> (run::Summary, Vec<Vec<f64>>) {
    let out = std::env::temp_dir().join(format!("bushing-{name}-{}", std::process::id()));
    let summary = run::run(scene, &out).unwrap();
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    std::fs::remove_dir_all(out).ok();
    assert_eq!(rows.len() as u64, summary.steps);
    (summary, rows)
}

/// Trace row of step `i` (time i dt), steps counting from 1.
fn row(rows: &[Vec<f64>], i: usize) -> &[f64] {
    &rows[i - 1]
}

#[test]
fn multi_step_holds_each_level_while_the_force_relaxes() {
    let text = scene_text(
        100.0,
        "type = \"multi-step\"\nlevels = [0.5, 1.0, 0.5]\nramp_s = 2.0\nhold_s = 20.0",
    );
    let scene = Scene::parse("m.toml", &text).unwrap();
    assert_eq!(scene.steps(), 6600);
    let (summary, rows) = run_rows(&scene, "multi-step");
    assert_eq!(summary.refused, 0);
    for (k, level) in [0.5, 1.0, 0.5].into_iter().enumerate() {
        let first = k * 2200 + 200; // end of the ramp, step index
        let last = (k + 1) * 2200;
        let mut previous: Option<f64> = None;
        for i in first..=last {
            let r = row(&rows, i);
            assert_eq!(r[1], level, "x at t = {}", r[0]);
            // The force relaxes monotonically towards g0 F^inf(x): down
            // after a step up, up after a step down.
            if let Some(p) = previous {
                if k < 2 {
                    assert!(r[2] <= p + 1e-9, "t = {}", r[0]);
                } else {
                    assert!(r[2] >= p - 1e-9, "t = {}", r[0]);
                }
            }
            previous = Some(r[2]);
        }
        let start = row(&rows, first);
        let end = row(&rows, last);
        // The ramp at 0.25 mm/s leaves about g v K / ω = 1.6 N in the
        // 0.5 Hz cell; 20 s later (63 time constants) nothing is left.
        assert!((start[2] - start[3]).abs() > 1.0, "{start:?}");
        assert!((end[2] - end[3]).abs() < 1e-6, "{end:?}");
        assert!((end[3] - 0.7 * 100.0 * level).abs() < 1e-9);
    }
    // The ramps are linear: halfway up the second one.
    assert!((row(&rows, 2300)[1] - 0.75).abs() < 1e-12);
}

#[test]
fn stepped_sine_steps_start_at_the_preload_and_reach_each_amplitude() {
    let text = scene_text(
        1000.0,
        "type = \"stepped-sine\"\npreloads = [0.5, 1.5]\nfrequencies_hz = [2.0, 5.0]\n\
         amplitudes = [0.1, 0.3]\ncycles = 2\nsettle_s = 0.1\nramp_s = 1.0\nhold_s = 0.5",
    );
    let scene = Scene::parse("s.toml", &text).unwrap();
    // Per preload: 2 x (1 s + 0.1 s) at 2 Hz, 2 x (0.4 s + 0.1 s) at 5 Hz;
    // a 1 s ramp and a 0.5 s hold between; no rest after the last step.
    assert_eq!(scene.steps(), 7800);
    let (_, rows) = run_rows(&scene, "stepped-sine");
    // (preload, frequency, amplitude, start in ms, length in ms)
    let mut steps = Vec::new();
    for (block, preload) in [(0usize, 0.5), (4700usize, 1.5)] {
        let mut start = block;
        for (f, len) in [(2.0, 1000usize), (5.0, 400usize)] {
            for a in [0.1, 0.3] {
                steps.push((preload, f, a, start, len));
                start += len + 100;
            }
        }
    }
    assert_eq!(steps.len(), 8);
    for &(preload, f, a, start, len) in &steps {
        let x = |i: usize| if i == 0 { 0.5 } else { row(&rows, i)[1] };
        assert!((x(start) - preload).abs() < 1e-12, "start {start}");
        assert!((x(start + len) - preload).abs() < 1e-12, "end {start}");
        let peak = (start..=start + len)
            .map(|i| (x(i) - preload).abs())
            .fold(0.0, f64::max);
        assert!((peak - a).abs() < 1e-12, "{peak} at {start} ms");
        // What the modulus plot reads at mid-step.
        let t = (start + len / 3) as f64 * 1e-3;
        assert_eq!(profile::frequency_at(&scene.profile, t), Some(f));
        assert_eq!(profile::amplitude_at(&scene.profile, t), Some(a));
        // Resting afterwards (but for the very last step).
        if start + len < 7800 {
            let t = (start + len + 50) as f64 * 1e-3;
            assert_eq!(profile::frequency_at(&scene.profile, t), None);
            assert_eq!(x(start + len + 50), preload);
        }
    }
    // Halfway up the ramp between the preloads, then the hold.
    assert!((row(&rows, 3700)[1] - 1.0).abs() < 1e-12);
    assert_eq!(row(&rows, 4500)[1], 1.5);
    // Continuous: no step moves x by more than the fastest slope allows
    // (2π 5 Hz x 0.3 mm = 9.4 mm/s).
    for w in rows.windows(2) {
        assert!((w[1][1] - w[0][1]).abs() <= 9.5e-3, "t = {}", w[1][0]);
    }
}

#[test]
fn sweep_crosses_the_preload_once_per_cycle_at_the_instantaneous_frequency() {
    let text = scene_text(
        2000.0,
        "type = \"sweep\"\nspacing = \"log\"\nf_start_hz = 1.0\nf_end_hz = 16.0\n\
         duration_s = 8.0\namplitude = 0.5\npreload = 1.0",
    );
    let scene = Scene::parse("w.toml", &text).unwrap();
    assert_eq!(scene.steps(), 16_000);
    let (summary, rows) = run_rows(&scene, "sweep");
    assert!(summary.dissipated_mj > 0.0);
    // Upward crossings of the preload, linearly interpolated in time.
    let mut crossings = Vec::new();
    let mut prev = (0.0, 1.0);
    for r in &rows {
        let (t, x) = (r[0], r[1]);
        if prev.1 < 1.0 && x >= 1.0 {
            crossings.push(prev.0 + (t - prev.0) * (1.0 - prev.1) / (x - prev.1));
        }
        prev = (t, x);
    }
    // 8 s x 15 Hz / ln 16 = 43.28 cycles.
    assert_eq!(crossings.len(), 43);
    for w in crossings.windows(2) {
        let mid = 0.5 * (w[0] + w[1]);
        let f = profile::frequency_at(&scene.profile, mid).unwrap();
        let measured = 1.0 / (w[1] - w[0]);
        assert!((measured / f - 1.0).abs() < 5e-3, "{measured} vs {f} Hz");
    }
    assert!((profile::frequency_at(&scene.profile, 6.0).unwrap() - 8.0).abs() < 1e-12);
    assert_eq!(profile::amplitude_at(&scene.profile, 6.0), Some(0.5));
}

#[test]
fn stop_start_rings_down_at_the_mode_and_settles_at_each_level() {
    let text = scene_text(
        2000.0,
        "type = \"stop-start\"\nfrequency_hz = 10.0\ndamping = 0.2\nrise_s = 0.05\n\
         duration_s = 3.0\npreload = 0.2\n\
         events = [{ at_s = 0.2, size = 1.0 }, { at_s = 1.5, size = -1.0 }]",
    );
    let scene = Scene::parse("t.toml", &text).unwrap();
    assert_eq!(scene.steps(), 6000);
    let (summary, rows) = run_rows(&scene, "stop-start");
    assert!(summary.dissipated_mj > 0.0);
    let x = |t: f64| row(&rows, (t * 2000.0).round() as usize)[1];
    assert_eq!(x(0.2), 0.2);
    assert!((x(1.45) - 1.2).abs() < 1e-5);
    assert!((x(3.0) - 0.2).abs() < 1e-5);
    // Local maxima of x after the rise: a damped sine about the new level,
    // successive overshoots in the ratio exp(-2π ζ / √(1 - ζ²)).
    let peaks: Vec<f64> = rows
        .windows(3)
        .filter(|w| w[1][0] > 0.25 && w[1][0] < 1.4 && w[1][1] > w[0][1] && w[1][1] >= w[2][1])
        .map(|w| w[1][1] - 1.2)
        .collect();
    assert!(peaks.len() >= 3, "{peaks:?}");
    let zeta: f64 = 0.2;
    let ratio = (-std::f64::consts::TAU * zeta / (1.0 - zeta * zeta).sqrt()).exp();
    assert!(
        (peaks[1] / peaks[0] / ratio - 1.0).abs() < 0.01,
        "{peaks:?}"
    );
    // The first overshoot is below the one of an instantaneous step.
    let step_overshoot =
        stop_start_response(0.5 / (10.0 * (1.0 - zeta * zeta).sqrt()), 10.0, zeta, 0.0) - 1.0;
    assert!(peaks[0] > 0.0 && peaks[0] < step_overshoot, "{peaks:?}");
    assert_eq!(profile::frequency_at(&scene.profile, 0.5), None);
}

/// Samples of the replay fixture: (time in s, x in mm).
fn fixture() -> Vec<(f64, f64)> {
    std::fs::read_to_string(data().join("replay-displacement.csv"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (f[0], f[1])
        })
        .collect()
}

#[test]
fn replay_reproduces_the_samples_at_their_times_and_interpolates_between() {
    let samples = fixture();
    assert_eq!(samples.len(), 401);
    let text = scene_text(
        1000.0,
        "type = \"replay\"\nfile = \"replay-displacement.csv\"\ncolumn = \"x_mm\"\ntime_column = 1",
    );
    let scene = Scene::parse_in("r.toml", &text, &data()).unwrap();
    assert_eq!(scene.steps(), 2000);
    let (_, rows) = run_rows(&scene, "replay");
    for (k, &(t, x)) in samples.iter().enumerate().skip(1) {
        let r = row(&rows, 5 * k);
        assert!((r[0] - t).abs() < 1e-9);
        assert!((r[1] - x).abs() <= 1e-12 * x.abs().max(1.0), "t = {t}");
        // Two fifths of the way to the next sample.
        if let Some(&(_, next)) = samples.get(k + 1) {
            let between = row(&rows, 5 * k + 2)[1];
            assert!((between - (x + 0.4 * (next - x))).abs() < 1e-12, "t = {t}");
        }
    }
    // The same column by index, timed by a rate instead of the times.
    let by_rate = scene_text(
        1000.0,
        "type = \"replay\"\nfile = \"replay-displacement.csv\"\ncolumn = 2\nrate_hz = 200",
    );
    let other = Scene::parse_in("r.toml", &by_rate, &data()).unwrap();
    assert_eq!(other.steps(), 2000);
    for t in [0.0, 0.0123, 0.5, 1.2345, 2.0] {
        let (a, b) = (
            profile::displacement(&scene.profile, t),
            profile::displacement(&other.profile, t),
        );
        assert!((a - b).abs() < 1e-12, "{t}: {a} {b}");
    }
    // In-memory text: relative names start from the current directory, an
    // absolute name is used as it is.
    let absolute = text.replace(
        "\"replay-displacement.csv\"",
        &format!(
            "{:?}",
            data().join("replay-displacement.csv").display().to_string()
        ),
    );
    assert_eq!(Scene::parse("r.toml", &absolute).unwrap().steps(), 2000);
}

#[test]
fn example_scenes_of_each_profile_load_with_their_step_counts() {
    for (name, steps) in [
        ("profile-multi-step", 228_000),
        ("profile-stepped-sine", 174_000),
        ("profile-sweep", 40_000),
        ("profile-stop-start", 10_000),
        ("profile-replay", 2_000),
    ] {
        let scene = Scene::load(&root().join(format!("scenes/{name}.toml"))).unwrap();
        assert_eq!(scene.steps(), steps, "{name}");
    }
    // The replay scene finds its CSV relative to its own directory.
    let scene = Scene::load(&root().join("scenes/profile-replay.toml")).unwrap();
    let (summary, rows) = run_rows(&scene, "replay-scene");
    assert_eq!(summary.refused, 0);
    let last = fixture().last().copied().unwrap();
    assert!((rows.last().unwrap()[1] - last.1).abs() < 1e-6);
}

/// Parses `profile` in the test scene, expecting an error located at the
/// `[profile]` table, and returns its message.
fn profile_error(profile: &str, dir: &Path) -> String {
    let e = Scene::parse_in("bad.toml", &scene_text(1000.0, profile), dir).unwrap_err();
    assert_eq!(e.at.map(|l| l.line), Some(13), "{e}");
    assert!(e.to_string().starts_with("bad.toml:13:"), "{e}");
    e.message
}

#[test]
fn profile_errors_name_the_field_the_bound_and_the_csv_row() {
    let here = Path::new("");
    let cases: [(&str, &str); 10] = [
        (
            "type = \"multi-step\"\nlevels = []\nramp_s = 20\nhold_s = 360",
            "profile: levels: 1 to 10000 values expected, got 0",
        ),
        (
            "type = \"multi-step\"\nlevels = [1.0]\nramp_s = 0\nhold_s = 360",
            "profile: ramp_s must be finite and > 0, got 0",
        ),
        (
            "type = \"stepped-sine\"\nfrequencies_hz = [1.0]\namplitudes = [0.1]\ncycles = 2.5",
            "profile: cycles must be a whole number >= 1 (each step ends at the preload), got 2.5",
        ),
        (
            "type = \"stepped-sine\"\nfrequencies_hz = [1.0, 600.0]\namplitudes = [0.1]\ncycles = 2",
            "profile: frequencies_hz[1] = 600 Hz must be below half the rate (500 Hz)",
        ),
        (
            "type = \"stepped-sine\"\npreloads = [0.0, 1.0]\nfrequencies_hz = [1.0]\namplitudes = [0.1]\ncycles = 2",
            "profile: ramp_s (s) is needed to go from one preload to the next (2 preloads)",
        ),
        (
            "type = \"sweep\"\nf_start_hz = 1\nf_end_hz = 10\nduration_s = 0\namplitude = 1",
            "profile: duration_s must be finite and > 0, got 0",
        ),
        (
            "type = \"stop-start\"\nfrequency_hz = 10\ndamping = 1.2\nrise_s = 0.1\nduration_s = 2\nevents = [{ at_s = 0.5, size = 1 }]",
            "profile: damping (ratio) must be in [0, 1) (an oscillating mode), got 1.2",
        ),
        (
            "type = \"stop-start\"\nfrequency_hz = 10\ndamping = 0.1\nrise_s = 0.1\nduration_s = 2\nevents = [{ at_s = 2.5, size = 1 }]",
            "profile: events[0].at_s must be in [0, duration_s = 2) s (events in time order), got 2.5",
        ),
        (
            "type = \"replay\"\nfile = \"x.csv\"\ncolumn = 0\nrate_hz = 100",
            "profile: column = 0: column indices count from 1 to 10000",
        ),
        (
            "type = \"replay\"\nfile = \"x.csv\"\ncolumn = 1",
            "profile: give time_column (a time column in s) or rate_hz (Hz)",
        ),
    ];
    for (profile, expected) in cases {
        assert_eq!(profile_error(profile, here), expected);
    }

    // Syntax and shape errors from the parser, located in the table.
    // An unknown name in a value: at the value.
    let sweep = "type = \"sweep\"\nspacing = \"cubic\"\nf_start_hz = 1\nf_end_hz = 10\nduration_s = 1\namplitude = 1";
    let e = Scene::parse_in("bad.toml", &scene_text(1000.0, sweep), here).unwrap_err();
    assert!(
        e.to_string().starts_with(
            "bad.toml:15:11: profile: spacing: unknown variant `cubic`, expected `log` or `linear`"
        ),
        "{e}"
    );
    let e = profile_error(
        "type = \"multi-step\"\nlevels = [1.0]\nramp_s = 20\nhold = 360",
        here,
    );
    assert!(e.contains("hold"), "{e}");
    // A wrong type is located at the value itself (line 16, `column`).
    let text = scene_text(
        1000.0,
        "type = \"replay\"\nfile = \"x.csv\"\ncolumn = 1.5\nrate_hz = 100",
    );
    let e = Scene::parse_in("bad.toml", &text, here).unwrap_err();
    assert_eq!(e.at.map(|l| (l.line, l.column)), Some((16, 10)), "{e}");
    assert!(
        e.message
            .starts_with("profile: column: invalid type: floating point `1.5`")
            && e.message
                .contains("a column name (string) or a 1-based column index"),
        "{e}"
    );
    // Samples come from the file only.
    let e = profile_error(
        "type = \"replay\"\nfile = \"x.csv\"\ncolumn = 1\nrate_hz = 100\nsamples = [[0.0, 1.0]]",
        here,
    );
    assert!(e.contains("samples"), "{e}");

    // The CSV file: missing, a bad number, times going backwards, an
    // unknown column; each named with its row and column.
    let dir = data();
    let name = |f: &str| dir.join(f).display().to_string();
    let e = profile_error(
        "type = \"replay\"\nfile = \"missing.csv\"\ncolumn = 2\nrate_hz = 100",
        &dir,
    );
    assert!(
        e.starts_with(&format!(
            "profile: replay file {}: cannot read: ",
            name("missing.csv")
        )),
        "{e}"
    );
    let e = profile_error(
        "type = \"replay\"\nfile = \"replay-bad-number.csv\"\ncolumn = \"x_mm\"\ntime_column = \"time_s\"",
        &dir,
    );
    assert_eq!(
        e,
        format!(
            "profile: {}: row 4, column 2: expected a number, got 'O.2'",
            name("replay-bad-number.csv")
        )
    );
    let e = profile_error(
        "type = \"replay\"\nfile = \"replay-time-backwards.csv\"\ncolumn = 2\ntime_column = 1",
        &dir,
    );
    assert_eq!(
        e,
        format!(
            "profile: {}: row 5, column 1: time 0.015 s is not after the 0.02 s of row 4",
            name("replay-time-backwards.csv")
        )
    );
    let e = profile_error(
        "type = \"replay\"\nfile = \"replay-displacement.csv\"\ncolumn = \"x\"\nrate_hz = 200",
        &dir,
    );
    assert_eq!(
        e,
        format!(
            "profile: {}: row 4: no column named 'x' for column (the header has 'time_s', 'x_mm', 'force_N')",
            name("replay-displacement.csv")
        )
    );
}

#[test]
fn sine_and_triangle_are_unchanged() {
    let text = scene_text(
        1000.0,
        "type = \"triangle\"\namplitude = 2.0\nspeed = 4.0\ncycles = 1\npreload = 1.0",
    );
    let scene = Scene::parse("tri.toml", &text).unwrap();
    assert_eq!(scene.steps(), 2000);
    assert_eq!(profile::displacement(&scene.profile, 0.5), 3.0);
    assert_eq!(profile::frequency_at(&scene.profile, 0.5), None);
    let text = scene_text(
        1000.0,
        "type = \"sine\"\namplitude = 2.0\nfrequency_hz = 5.0\ncycles = 3",
    );
    let scene = Scene::parse("sine.toml", &text).unwrap();
    assert_eq!(scene.steps(), 600);
    for n in 0..600 {
        let t = n as f64 * 1e-3;
        assert_eq!(
            profile::displacement(&scene.profile, t),
            // libm, as the profile: the same bits on every platform.
            2.0 * libm::sin(std::f64::consts::TAU * 5.0 * t)
        );
    }
    assert_eq!(profile::amplitude_at(&scene.profile, 0.1), Some(2.0));
}
