//! The built `bushing-sim` binary as a new user and a careless one would
//! use it: every case of the command line's contract, with its exit code
//! (0 success, 1 run failure, 2 usage or scene error, 3 a failed check)
//! and its message.

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Duration;

use assert_cmd::Command;
use predicates::prelude::*;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scene(name: &str) -> PathBuf {
    root().join("scenes").join(name)
}

/// The built binary, run from the workspace root (scene paths are
/// relative to it), with a timeout so that a hang fails.
fn sim() -> Command {
    let mut c = Command::cargo_bin("bushing-sim").unwrap();
    c.timeout(Duration::from_secs(120)).current_dir(root());
    c
}

/// Runs `cmd`, which writes into `out`: a usage error (exit 2) whose
/// message holds `says`, and nothing at `out`.
fn refused_usage(cmd: &mut Command, out: &Path, says: &str) {
    cmd.assert().code(2).stderr(predicate::str::contains(says));
    assert!(!out.exists(), "{} was written", out.display());
}

/// `scenes/NAME` with `from` replaced by `to`, written into `dir`.
fn edited(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let text = fs::read_to_string(scene(name)).unwrap();
    assert!(text.contains(from), "{name} has {from}");
    let path = dir.join(name.replace('/', "-"));
    fs::write(&path, text.replacen(from, to, 1)).unwrap();
    path
}

#[test]
fn help_and_version_succeed_for_every_command() {
    sim()
        .arg("--version")
        .assert()
        .code(0)
        .stdout(predicate::str::starts_with("bushing-sim "));
    for command in [
        "run",
        "validate",
        "cost",
        "campaign",
        "compare-trace",
        "maxwell-table",
    ] {
        sim()
            .args([command, "--help"])
            .assert()
            .code(0)
            .stdout(predicate::str::contains(format!(
                "Usage: bushing-sim {command}"
            )));
    }
}

#[test]
fn usage_errors_exit_2() {
    sim()
        .arg("frobnicate")
        .assert()
        .code(2)
        .stderr(predicate::str::contains("unrecognized subcommand"));
    sim()
        .args(["run", "scenes/quickstart.toml"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--out <OUT>"));
    sim()
        .args([
            "run",
            "scenes/quickstart.toml",
            "--out",
            "x",
            "--number",
            "f16",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("invalid value 'f16'"));
    sim()
        .args(["validate", "scenes/maxwell4.toml", "--tolerance", "nan"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--tolerance must be a finite"));
}

#[test]
fn a_scene_error_shows_its_line_with_a_caret_and_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let bad = edited(
        dir.path(),
        "maxwell4.toml",
        "form = \"rate-exact-ramp\"",
        "form = \"rate-exact-rump\"",
    );
    sim()
        .arg("run")
        .arg(&bad)
        .arg("--out")
        .arg(dir.path().join("out"))
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("form: unknown variant `rate-exact-rump`, expected one of")
                .and(predicate::str::contains("form = \"rate-exact-rump\""))
                .and(predicate::str::contains("^^^")),
        );
    assert!(
        !dir.path().join("out").exists(),
        "no output for a bad scene"
    );
}

#[test]
fn scene_files_that_are_not_regular_or_too_large_are_refused_without_reading() {
    let dir = tempfile::tempdir().unwrap();
    #[cfg(unix)]
    {
        let fifo = dir.path().join("fifo.toml");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        for args in [&["run", "--out", "unused"][..], &["validate"]] {
            sim()
                .args(args)
                .arg(&fifo)
                .timeout(Duration::from_secs(10))
                .assert()
                .code(2)
                .stderr(predicate::str::contains("not a regular file"));
        }
        sim()
            .args(["validate", "/dev/zero"])
            .timeout(Duration::from_secs(10))
            .assert()
            .code(2)
            .stderr(predicate::str::contains("not a regular file"));
    }
    let big = dir.path().join("big.toml");
    fs::write(&big, vec![b'#'; 30_000_000]).unwrap();
    sim()
        .arg("validate")
        .arg(&big)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "30000000 bytes, more than the limit of 1048576",
        ));
}

#[test]
fn a_run_whose_steps_are_refused_exits_3_unless_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = edited(
        dir.path(),
        "profile-sweep.toml",
        "f_start_hz = 0.5",
        "f_start_hz = 5e-324",
    );
    let huge = edited(
        dir.path(),
        "profile-sweep.toml",
        "amplitude = 0.5 ",
        "amplitude = 1e308 ",
    );
    for s in [&sweep, &huge] {
        sim()
            .arg("run")
            .arg(s)
            .arg("--out")
            .arg(dir.path().join("out"))
            .assert()
            .code(3)
            .stderr(predicate::str::contains("steps were refused"));
    }
    sim()
        .arg("run")
        .arg(&huge)
        .arg("--out")
        .arg(dir.path().join("out"))
        .arg("--allow-refused")
        .assert()
        .code(0)
        .stdout(predicate::str::contains("refused steps  40000"));
}

#[test]
fn validate_exits_3_beyond_its_tolerance_or_with_refused_steps() {
    sim()
        .args(["validate", "scenes/maxwell4.toml"])
        .assert()
        .code(0);
    sim()
        .args(["validate", "scenes/maxwell4.toml", "--tolerance", "1e-6"])
        .assert()
        .code(3)
        .stderr(predicate::str::contains(
            "3 of 5 checks beyond the tolerance of 1e-6",
        ));
    let dir = tempfile::tempdir().unwrap();
    let inf = edited(
        dir.path(),
        "maxwell4.toml",
        "amplitude = 1.0",
        "amplitude = 1e308",
    );
    sim()
        .arg("validate")
        .arg(&inf)
        .assert()
        .code(3)
        .stderr(predicate::str::contains("8000 steps were refused"));
}

#[test]
fn json_summaries_parse() {
    let dir = tempfile::tempdir().unwrap();
    let out = sim()
        .args(["run", "scenes/maxwell4.toml", "--json", "--out"])
        .arg(dir.path().join("out"))
        .assert()
        .code(0)
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["steps"], 8000);
    assert_eq!(v["refused"], 0);
    assert_eq!(v["number"], "f32");
    let out = sim()
        .args(["validate", "scenes/maxwell4.toml", "--json"])
        .assert()
        .code(0)
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["passed"], true);
    assert_eq!(v["exit_code"], 0);
    assert_eq!(v["report"]["checks"].as_array().unwrap().len(), 5);
    let out = sim()
        .args(["validate", "no-such-scene.toml", "--json"])
        .assert()
        .code(2)
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["exit_code"], 2);
}

#[test]
fn an_output_estimated_beyond_the_limit_is_refused_before_stepping() {
    let dir = tempfile::tempdir().unwrap();
    // 5 Hz at 1e8 Hz over 20 periods: 4e8 steps, about 50 GB of trace.
    let fast = edited(
        dir.path(),
        "quickstart.toml",
        "rate_hz = 2000",
        "rate_hz = 1e8",
    );
    let fast_text = fs::read_to_string(&fast)
        .unwrap()
        .replacen("cycles = 10", "cycles = 20", 1);
    fs::write(&fast, fast_text).unwrap();
    let out = dir.path().join("out");
    refused_usage(
        sim()
            .arg("run")
            .arg(&fast)
            .arg("--out")
            .arg(&out)
            .timeout(Duration::from_secs(20)),
        &out,
        "more than the limit of 1.0 GiB",
    );
    // The limit is the user's: a tiny one refuses the quickstart too.
    sim()
        .args([
            "run",
            "scenes/quickstart.toml",
            "--max-output",
            "1KB",
            "--out",
        ])
        .arg(dir.path().join("out"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--max-output"));
}

/// The files of a folder, without the hidden ones.
fn visible(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.'))
        .collect();
    names.sort();
    names
}

#[test]
fn a_new_run_replaces_the_old_output_whole_and_follows_no_link() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    sim()
        .args(["run", "scenes/maxwell4.toml", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    assert!(visible(&out).contains(&"modulus.csv".to_string()));
    // A planted link where the trace goes: never written through.
    let victim = dir.path().join("victim.txt");
    fs::write(&victim, "precious").unwrap();
    fs::remove_file(out.join("trace.csv")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&victim, out.join("trace.csv")).unwrap();
    // A scene without a sine writes no modulus files: the old ones go.
    sim()
        .args(["run", "scenes/sts-triangles.toml", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    assert_eq!(fs::read_to_string(&victim).unwrap(), "precious");
    assert!(!out.join("trace.csv").is_symlink());
    let names = visible(&out);
    assert!(!names.contains(&"modulus.csv".to_string()), "{names:?}");
    assert_eq!(visible(dir.path()), ["out", "victim.txt"]);
    // The output folder itself as a link, or a folder of other files.
    #[cfg(unix)]
    {
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&out, &link).unwrap();
        sim()
            .args(["run", "scenes/quickstart.toml", "--out"])
            .arg(&link)
            .current_dir(root())
            .assert()
            .code(2)
            .stderr(predicate::str::contains("is a symbolic link"));
    }
    let home = dir.path().join("home");
    fs::create_dir(&home).unwrap();
    fs::write(home.join("notes.txt"), "mine").unwrap();
    sim()
        .args(["run", "scenes/quickstart.toml", "--out"])
        .arg(&home)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("is not an earlier output"));
    assert_eq!(visible(&home), ["notes.txt"]);
}

#[test]
fn a_killed_run_leaves_the_previous_output_whole() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    sim()
        .args(["run", "scenes/quickstart.toml", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    let before = fs::read(out.join("trace.csv")).unwrap();
    // A long run (f64, 4e7 steps, 1 kHz sine... written whole or not at
    // all), killed by the timeout after a second of stepping.
    let long = edited(
        dir.path(),
        "quickstart.toml",
        "cycles = 10",
        "cycles = 100000",
    );
    sim()
        .arg("run")
        .arg(&long)
        .args(["--max-output", "100GB", "--out"])
        .arg(&out)
        .timeout(Duration::from_secs(1))
        .assert()
        .interrupted();
    assert_eq!(fs::read(out.join("trace.csv")).unwrap(), before);
    assert_eq!(visible(dir.path()), ["out", "quickstart.toml"]);
}

#[test]
fn an_io_error_names_its_file_and_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain-file");
    fs::write(&file, "x").unwrap();
    sim()
        .args(["run", "scenes/quickstart.toml", "--out"])
        .arg(file.join("out"))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("plain-file"));
    sim()
        .args(["maxwell-table", "--out"])
        .arg(file.join("table.md"))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("table.md"));
}

#[test]
fn a_replay_may_not_leave_the_scene_folder_when_confined() {
    // scenes/profile-replay.toml reads ../tests/data/replay-displacement.csv.
    sim()
        .args(["validate", "scenes/profile-replay.toml"])
        .assert()
        .code(0);
    sim()
        .args(["validate", "--confine", "scenes/profile-replay.toml"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("outside the scene's folder"));
}

#[test]
fn an_error_quotes_a_bad_cell_short_and_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let cell = format!("\u{1b}[31m{}", "9".repeat(200));
    fs::write(
        dir.path().join("data.csv"),
        format!("time_s,x_mm\n0,0\n0.01,{cell}\n"),
    )
    .unwrap();
    let text = fs::read_to_string(scene("profile-replay.toml"))
        .unwrap()
        .replace("../tests/data/replay-displacement.csv", "data.csv");
    let path = dir.path().join("replay.toml");
    fs::write(&path, text).unwrap();
    let assert = sim().arg("validate").arg(&path).assert().code(2);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(!stderr.contains('\u{1b}'), "no raw escape: {stderr:?}");
    assert!(stderr.contains("\\u{1b}[31m"), "{stderr}");
    assert!(!stderr.contains(&"9".repeat(60)), "short excerpt: {stderr}");
}

#[test]
fn modulus_points_are_thinned_like_the_trace() {
    let dir = tempfile::tempdir().unwrap();
    // 200 Hz at 2 kHz: a point per 10-step period, unless thinned.
    let fast = edited(
        dir.path(),
        "quickstart.toml",
        "frequency_hz = 5.0",
        "frequency_hz = 200.0",
    );
    let text = fs::read_to_string(&fast)
        .unwrap()
        .replacen("cycles = 10", "cycles = 400", 1)
        + "\n[output]\ntrace_every = 100\n";
    fs::write(&fast, text).unwrap();
    let out = dir.path().join("out");
    sim()
        .arg("run")
        .arg(&fast)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(0);
    let trace_rows = fs::read_to_string(out.join("trace.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    let points = fs::read_to_string(out.join("modulus.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(trace_rows, 40);
    assert!(
        (30..=40).contains(&points),
        "{points} modulus points for {trace_rows} trace rows"
    );
}

#[test]
fn the_scripts_find_the_build_where_cargo_puts_it() {
    let elsewhere = tempfile::tempdir().unwrap();
    let out = std::process::Command::new("bash")
        .args(["-c", ". scripts/target-dir.sh && printf %s \"$target\""])
        .current_dir(root())
        .env("CARGO_TARGET_DIR", elsewhere.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        Path::new(&String::from_utf8(out.stdout).unwrap()),
        elsewhere.path()
    );
}

#[test]
fn a_test_over_frequency_is_plotted_against_frequency_and_png_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    sim()
        .args(["run", "scenes/profile-stepped-sine.toml", "--png", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    let svg = fs::read_to_string(out.join("modulus-frequency.svg")).unwrap();
    assert!(svg.contains("[Hz]"), "a frequency axis");
    for stem in ["force-displacement", "force-time", "modulus-frequency"] {
        let png = fs::read(out.join(format!("{stem}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{stem}.png is a PNG");
    }
    // One frequency: no frequency plot, and no PNG unless asked.
    sim()
        .args(["run", "scenes/quickstart.toml", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    assert_eq!(
        visible(&out),
        [
            "dissipated-power.svg",
            "force-displacement.svg",
            "force-time.svg",
            "modulus-amplitude.svg",
            "modulus.csv",
            "trace.csv"
        ]
    );
}

#[cfg(unix)]
#[test]
fn a_write_that_fails_midway_names_its_file_and_leaves_the_previous_output() {
    // A file-size limit (with its signal ignored) makes every write past
    // 200 KiB fail, as a full disk does.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    sim()
        .args(["run", "scenes/maxwell4.toml", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    let before = fs::read(out.join("trace.csv")).unwrap();
    let binary = assert_cmd::cargo::cargo_bin("bushing-sim");
    let script = format!(
        "trap '' XFSZ; ulimit -f 200; exec '{}' run scenes/seed000/fig-1-24-payne.toml --out '{}'",
        binary.display(),
        out.display()
    );
    let result = std::process::Command::new("bash")
        .args(["-c", &script])
        .current_dir(root())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("trace.csv"), "{stderr}");
    assert_eq!(fs::read(out.join("trace.csv")).unwrap(), before);
    assert_eq!(visible(dir.path()), ["out"], "no partial result beside it");
    assert_eq!(
        fs::read_dir(dir.path()).unwrap().count(),
        1,
        "staging removed"
    );
}

#[test]
fn compare_trace_refuses_a_bad_bound_and_names_a_missing_file() {
    sim()
        .args([
            "compare-trace",
            "no-trace.csv",
            "no-firmware.log",
            "--within=-1",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--within must be a finite number"));
    sim()
        .args(["compare-trace", "no-trace.csv", "no-firmware.log"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("no-trace.csv"));
}

#[test]
fn json_is_one_object_even_when_a_check_fails() {
    let dir = tempfile::tempdir().unwrap();
    let huge = edited(
        dir.path(),
        "profile-sweep.toml",
        "amplitude = 0.5 ",
        "amplitude = 1e308 ",
    );
    let out = sim()
        .arg("run")
        .arg(&huge)
        .args(["--json", "--out"])
        .arg(dir.path().join("out"))
        .assert()
        .code(3)
        .get_output()
        .stdout
        .clone();
    // `from_slice` refuses trailing data: a second object would fail here.
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["exit_code"], 3);
    assert_eq!(v["refused"], 40000);
    assert!(v["error"].as_str().unwrap().contains("steps were refused"));
    let out = sim()
        .args([
            "validate",
            "scenes/maxwell4.toml",
            "--json",
            "--tolerance",
            "1e-6",
        ])
        .assert()
        .code(3)
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["passed"], false);
    assert_eq!(v["exit_code"], 3);
    assert!(
        v["error"]
            .as_str()
            .unwrap()
            .contains("beyond the tolerance")
    );
}

/// `bushing-sim campaign SCENE` on a small grid (30 s holds, sines about
/// 0 mm only) with `extra` arguments, into `out`.
fn small_campaign(scene: &str, out: &Path, extra: &[&str]) -> assert_cmd::assert::Assert {
    sim()
        .args(["campaign", scene, "--hold-s", "30", "--preloads", "0"])
        .args(extra)
        .arg("--out")
        .arg(out)
        .assert()
}

/// `campaign` writes a campaign the identification reads back, whole or
/// not at all; a noise that is not a share of the range is a usage error.
#[test]
fn campaign_writes_a_readable_campaign_and_refuses_a_bad_noise() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("campaign");
    small_campaign("scenes/maxwell4.toml", &out, &[])
        .code(0)
        .stdout(predicate::str::starts_with("campaign: 56 tests, "));
    let c = bushing_sim::identify::campaign::Campaign::load(&out, true).unwrap();
    assert_eq!((c.tests.len(), c.excluded.len()), (56, 0));
    let bad = dir.path().join("bad");
    sim()
        .args(["campaign", "scenes/maxwell4.toml", "--noise", "1.5"])
        .arg("--out")
        .arg(&bad)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "noise = 1.5 must be finite and in [0, 1)",
        ));
    assert!(!bad.exists(), "nothing written for a refused campaign");
}

/// `preprocess` reads a campaign, reports each step and names each test
/// it leaves out with its reason; a campaign it cannot read is a usage
/// error and writes nothing.
#[test]
fn preprocess_reports_every_test_and_each_one_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let campaign = dir.path().join("campaign");
    small_campaign("scenes/hysteresis-triangle.toml", &campaign, &[]).code(0);
    let out = dir.path().join("pre");
    sim()
        .arg("preprocess")
        .arg(&campaign)
        .arg("--out")
        .arg(&out)
        .arg("--confine")
        .assert()
        .code(0)
        .stdout(
            predicate::str::contains(
                "54 tests used (35 sines, 1 multi-step, 18 triangle, 0 other), 2 left out",
            )
            .and(predicate::str::contains(
                "left out: tri-1-0-0.05: no branch of 5 samples or more",
            )),
        );
    let report = fs::read_to_string(out.join("report.md")).unwrap();
    for section in [
        "## Tests left out",
        "## Sines",
        "## Multi-step holds",
        "## Triangles",
    ] {
        assert!(report.contains(section), "{section}");
    }
    assert_eq!(report.matches("\n| sine-").count(), 35);
    for svg in [
        "modulus-frequency.svg",
        "modulus-amplitude.svg",
        "relaxation.svg",
        "instantaneous-modulus.svg",
        "long-term-backbone.svg",
        "normalised-modulus.svg",
    ] {
        let text = fs::read_to_string(out.join(svg)).unwrap();
        bushing_sim::plot::well_formed(&text).unwrap_or_else(|e| panic!("{svg}: {e}"));
    }
    let broken = root().join("tests/campaigns/broken/04-duplicate-name");
    let nothing = dir.path().join("nothing");
    refused_usage(
        sim()
            .arg("preprocess")
            .arg(&broken)
            .arg("--out")
            .arg(&nothing),
        &nothing,
        "is named twice",
    );
}

/// A replay whose CSV also has a measured force: `run` overlays it on the
/// force plots and prints the model's RMS residual. Here the record is a
/// generated test of the same model with 0.5 % noise: the residual is that
/// noise (and the replay's start from rest), not more.
#[test]
fn a_replay_with_a_measured_force_reports_its_residual() {
    let dir = tempfile::tempdir().unwrap();
    let campaign = dir.path().join("campaign");
    small_campaign(
        "scenes/maxwell4.toml",
        &campaign,
        &["--noise", "0.005", "--seed", "3"],
    )
    .code(0);
    // The 5 Hz, 1 mm sine: 50 samples a period, replayed at the scene's rate.
    let text = fs::read_to_string(scene("maxwell4.toml")).unwrap();
    let model = &text[..text.find("[profile]").unwrap()];
    let replay = format!(
        "{model}[profile]\ntype = \"replay\"\nfile = \"campaign/sine-5-0-1.csv\"\n\
         column = \"x_mm\"\ntime_column = \"time_s\"\nforce_column = \"force_n\"\n"
    );
    let path = dir.path().join("replay.toml");
    fs::write(&path, &replay).unwrap();
    let out = dir.path().join("out");
    let run = sim()
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(0);
    let stdout = String::from_utf8(run.get_output().stdout.clone()).unwrap();
    let line = stdout
        .lines()
        .find(|l| l.starts_with("measured force RMS residual"))
        .unwrap_or_else(|| panic!("{stdout}"));
    let percent: f64 = line
        .split(", ")
        .nth(1)
        .and_then(|p| p.split(' ').next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!((0.3..2.0).contains(&percent), "{line}");
    let plot = fs::read_to_string(out.join("force-time.svg")).unwrap();
    assert!(plot.contains("measured force"));
    // A force column the file does not have.
    fs::write(&path, replay.replace("\"force_n\"", "\"F\"")).unwrap();
    sim()
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(dir.path().join("none"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "no column named 'F' for force_column",
        ));
}

/// `identify` writes the model three ways and its report; `model.toml`
/// runs as a scene as it is, and the numbers of `model.rs` and `model.h`
/// are those of `model.toml`; an unknown `--hold-out` is a usage error
/// and writes nothing.
#[test]
fn identify_writes_a_runnable_model_and_its_report() {
    let dir = tempfile::tempdir().unwrap();
    let campaign = dir.path().join("campaign");
    small_campaign("examples/identification/truth.toml", &campaign, &[]).code(0);
    let out = dir.path().join("identified");
    sim()
        .arg("identify")
        .arg(&campaign)
        .args(["--hold-out", "sine-5-0-0.5"])
        .arg("--out")
        .arg(&out)
        .assert()
        .code(0)
        .stdout(predicate::str::contains("1 held out"));
    for file in [
        "model.toml",
        "model.rs",
        "model.h",
        "report.md",
        "loop-sine-5-0-0.5.svg",
        "identified-modulus-frequency.svg",
        "residual.svg",
    ] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("## Held-out tests, predicted"));
    let toml = std::fs::read_to_string(out.join("model.toml")).unwrap();
    let scene = bushing_sim::Scene::parse("model.toml", &toml).unwrap();
    let rust = std::fs::read_to_string(out.join("model.rs")).unwrap();
    let header = std::fs::read_to_string(out.join("model.h")).unwrap();
    if let bushing_sim::family::backbone::BackboneSpec::Spline { force, .. } = &scene.backbone {
        for f in force {
            assert!(rust.contains(&format!("{f:?}")), "{f} not in model.rs");
            assert!(header.contains(&format!("{f:.16e}")), "{f} not in model.h");
        }
    } else {
        panic!("a spline backbone was asked for");
    }
    let run = dir.path().join("run");
    sim()
        .arg("run")
        .arg(out.join("model.toml"))
        .arg("--out")
        .arg(&run)
        .assert()
        .code(0);
    assert!(run.join("trace.csv").is_file());
    let refused = dir.path().join("refused");
    refused_usage(
        sim()
            .arg("identify")
            .arg(&campaign)
            .args(["--hold-out", "no-such-test", "--out"])
            .arg(&refused),
        &refused,
        "--hold-out no-such-test",
    );
}

/// `campaign --grid specimen-shear` writes the shear-specimen grid of
/// Table B.1 (a multi-step test of 10 levels, 5 triangle tests, 117
/// sines), in strain.
#[test]
fn campaign_writes_the_specimen_grid_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("specimen");
    sim()
        .args([
            "campaign",
            "scenes/seed000/m1-shear-sine-low.toml",
            "--grid",
            "specimen-shear",
            "--hold-s",
            "30",
            "--out",
        ])
        .arg(&out)
        .assert()
        .code(0)
        .stdout(predicate::str::starts_with("campaign: 123 tests, "));
    let c = bushing_sim::identify::campaign::Campaign::load(&out, true).unwrap();
    assert_eq!((c.tests.len(), c.excluded.len()), (123, 0));
    let largest = c
        .tests
        .iter()
        .flat_map(|t| t.record.x.iter())
        .fold(0.0f64, |m, &x| m.max(x.abs()));
    assert!(
        (largest - 1.0).abs() < 1e-9,
        "the largest strain is the 100 % hold: {largest}"
    );
}

/// Every option of the model class runs end to end: a polynomial backbone,
/// the STS law, two Maxwell cells and two x_f cells, written as a scene,
/// as Rust constructors and as C constants.
#[test]
fn identify_runs_every_model_class_option() {
    let dir = tempfile::tempdir().unwrap();
    let campaign = dir.path().join("campaign");
    small_campaign("examples/identification/truth.toml", &campaign, &[]).code(0);
    let out = dir.path().join("identified");
    sim()
        .arg("identify")
        .arg(&campaign)
        .args([
            "--backbone",
            "polynomial",
            "--backbone-size",
            "5",
            "--hysteresis",
            "sts",
            "--maxwell",
            "2",
            "--xf",
            "2",
            "--out",
        ])
        .arg(&out)
        .assert()
        .code(0);
    let toml = std::fs::read_to_string(out.join("model.toml")).unwrap();
    for part in [
        "type = \"polynomial\"",
        "law = \"sts\"",
        "type = \"xf\"",
        "type = \"maxwell\"",
    ] {
        assert!(toml.contains(part), "{part} not in model.toml");
    }
    let scene = bushing_sim::Scene::parse("model.toml", &toml).unwrap();
    assert_eq!(scene.effects().len(), 3);
    let rust = std::fs::read_to_string(out.join("model.rs")).unwrap();
    for part in [
        "Polynomial<T, 6>",
        "TurningPoints<Sts<T>, 32>",
        "XfBank<T, 2>",
        "MaxwellBank<T, 2>",
    ] {
        assert!(rust.contains(part), "{part} not in model.rs");
    }
    let header = std::fs::read_to_string(out.join("model.h")).unwrap();
    assert!(header.contains("#define BUSHING_MODEL_XF_CELLS 2"));
}
