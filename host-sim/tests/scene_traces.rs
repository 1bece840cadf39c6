//! Every scene of `scenes/` run through the built binary, with the
//! README's command form, writes the `trace.csv` whose SHA-256 is listed in
//! `scenes/trace-hashes.sha256`: one line per scene, the SHA-256 of the
//! trace it writes, two spaces, the scene.
//!
//! The list was taken before the command line and the scene reader were
//! rebuilt; a change of a single byte of any trace fails here. A deliberate
//! change of a trace updates the list, with the reason in its commit.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use sha2::{Digest, Sha256};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// (scene path relative to the root, expected hex digest).
fn listed() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(root().join("scenes/trace-hashes.sha256")).unwrap();
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let (hash, path) = l.split_once("  ").expect("sha256sum line");
            (path.to_string(), hash.to_string())
        })
        .collect()
}

fn scene_files(dir: &Path, found: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            scene_files(&path, found);
        } else if path.extension().is_some_and(|e| e == "toml") {
            let rel = path.strip_prefix(root()).unwrap();
            found.push(rel.to_string_lossy().replace('\\', "/"));
        }
    }
}

#[test]
fn every_scene_is_listed() {
    let mut found = Vec::new();
    scene_files(&root().join("scenes"), &mut found);
    found.sort();
    let mut listed: Vec<String> = listed().into_iter().map(|(p, _)| p).collect();
    listed.sort();
    assert_eq!(
        found, listed,
        "scenes/trace-hashes.sha256 lists every scene"
    );
}

#[test]
fn every_scene_writes_its_listed_trace_bytes() {
    let out = tempfile::tempdir().unwrap();
    let mut changed = Vec::new();
    for (i, (scene, expected)) in listed().iter().enumerate() {
        let dir = out.path().join(format!("scene-{i}"));
        Command::cargo_bin("bushing-sim")
            .unwrap()
            .current_dir(root())
            .args(["run", scene, "--out"])
            .arg(&dir)
            .assert()
            .success();
        let bytes = std::fs::read(dir.join("trace.csv")).unwrap();
        let hash = format!("{:x}", Sha256::digest(&bytes));
        if &hash != expected {
            changed.push(format!("{hash}  {scene}"));
        }
    }
    assert!(
        changed.is_empty(),
        "traces changed (new digests):\n{}",
        changed.join("\n")
    );
}
