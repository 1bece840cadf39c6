//! `bushing-sim fmu`: what it refuses, with which exit code and message,
//! and that a refused FMU leaves no file behind. (`scripts/fmu.sh` packs
//! real FMUs with the release library and runs them under fmpy.)

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use predicates::str::contains;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn fmu(args: &[&str]) -> assert_cmd::assert::Assert {
    Command::cargo_bin("bushing-sim")
        .unwrap()
        .current_dir(root())
        .arg("fmu")
        .args(args)
        .assert()
}

/// The names in `dir`.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn refusals_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bushing.fmu");
    let out = out.to_str().unwrap();
    let not_elf = dir.path().join("libfake.so");
    std::fs::write(&not_elf, b"not a library").unwrap();
    let not_elf = not_elf.to_str().unwrap();

    fmu(&["scenes/maxwell4.toml", "--out", out, "--library", not_elf])
        .code(1)
        .stderr(contains("not an object file"));
    fmu(&[
        "scenes/maxwell4.toml",
        "--out",
        out,
        "--library",
        "no/such/lib.so",
    ])
    .code(1)
    .stderr(contains("no/such/lib.so"));
    let txt = dir.path().join("bushing.txt");
    fmu(&["scenes/maxwell4.toml", "--out", txt.to_str().unwrap()])
        .code(2)
        .stderr(contains("must be a .fmu file"));
    fmu(&["scenes/seed004/iwan-oscillator.toml", "--out", out])
        .code(2)
        .stderr(contains("[oscillator]"));
    // A folder where the FMU would go.
    let folder = dir.path().join("folder.fmu");
    std::fs::create_dir(&folder).unwrap();
    fmu(&[
        "scenes/maxwell4.toml",
        "--out",
        folder.to_str().unwrap(),
        "--library",
        not_elf,
    ])
    .code(2)
    .stderr(contains("is not a file"));
    assert_eq!(listing(dir.path()), ["folder.fmu", "libfake.so"]);
}

#[test]
fn a_bad_scene_points_at_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bad.toml");
    let text = std::fs::read_to_string(root().join("scenes/maxwell4.toml")).unwrap();
    std::fs::write(&scene, text.replace("g = 0.15", "g = 1.15")).unwrap();
    let out = dir.path().join("bad.fmu");
    fmu(&[scene.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .code(2)
        .stderr(contains("bad.toml"));
    assert!(!out.exists());
}
