//! Broken scene files: each one is refused with its expected message at its
//! expected place (issue 6, "a scene file with a mistake gets the file,
//! line, column and what was expected; a bad parameter gets the effect's
//! name and the bound it breaks").
//!
//! Every file in `tests/scenes/broken/` starts with comment lines that say
//! what its error must be:
//!
//! ```toml
//! # expect: <text the message must contain>   (one or more lines)
//! # at: LINE:COL                               (or `# at: none`)
//! # pending: <what is still wrong with the message or location>
//! ```
//!
//! A `# pending:` file describes the error the scene should give but does
//! not yet: it must still be refused, and the test fails as soon as it gives
//! the expected error, so that the line is dropped and the case kept.

use std::path::{Path, PathBuf};

use bushing_sim::Scene;
use bushing_sim::scene::Location;

fn broken_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/broken")
}

/// What a broken file says about its own error.
#[derive(Debug)]
struct Expectation {
    texts: Vec<String>,
    at: Option<Location>,
    pending: Option<String>,
}

fn expectation(path: &Path, text: &str) -> Expectation {
    let mut texts = Vec::new();
    let mut at = None;
    let mut pending = None;
    for line in text.lines().take_while(|l| l.starts_with('#')) {
        if let Some(t) = line.strip_prefix("# expect: ") {
            texts.push(t.to_string());
        } else if let Some(a) = line.strip_prefix("# at: ") {
            at = Some(if a == "none" {
                None
            } else {
                let (l, c) = a
                    .split_once(':')
                    .unwrap_or_else(|| panic!("{}: `# at: {a}` is not LINE:COL", path.display()));
                Some(Location {
                    line: l.parse().unwrap(),
                    column: c.parse().unwrap(),
                })
            });
        } else if let Some(p) = line.strip_prefix("# pending: ") {
            pending = Some(p.to_string());
        }
    }
    assert!(!texts.is_empty(), "{}: no `# expect:` line", path.display());
    let at = at.unwrap_or_else(|| panic!("{}: no `# at:` line", path.display()));
    Expectation { texts, at, pending }
}

fn broken_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(broken_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_broken_scene_gives_its_expected_error_and_place() {
    let files = broken_files();
    let mut checked = 0;
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap();
        let want = expectation(path, &text);
        let e = match Scene::load(path) {
            Ok(_) => {
                failures.push(format!("{}: loaded without an error", path.display()));
                continue;
            }
            Err(e) => e,
        };
        let shown = e.to_string();
        let file = path.display().to_string();
        assert_eq!(e.file, file);
        let prefix = match want.at {
            Some(l) => format!("{file}:{}:{}: ", l.line, l.column),
            None => format!("{file}: "),
        };
        let matches = shown.starts_with(&prefix)
            && e.at == want.at
            && want.texts.iter().all(|t| e.message.contains(t.as_str()));
        match (&want.pending, matches) {
            (None, true) => checked += 1,
            (None, false) => failures.push(format!(
                "{shown}\n    expected `{prefix}` and a message containing {:?}",
                want.texts
            )),
            (Some(_), false) => {
                // Still refused, with a message that names the file.
                assert!(shown.starts_with(&format!("{file}:")), "{shown}");
            }
            (Some(p), true) => failures.push(format!(
                "{shown}\n    now gives the expected error: drop its `# pending: {p}` line"
            )),
        }
        // A location, when given, lies inside the file.
        if let Some(l) = e.at {
            let lines = text.lines().count().max(1);
            assert!(l.line <= lines && l.column >= 1, "{shown}");
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
    assert!(
        checked >= 20,
        "{checked} broken scenes with a checked message, at least 20 expected"
    );
}

#[test]
fn broken_scenes_are_all_different() {
    let files = broken_files();
    let texts: Vec<String> = files
        .iter()
        .map(|p| {
            let t = std::fs::read_to_string(p).unwrap();
            // The scene without its header comments and title.
            t.lines()
                .skip_while(|l| l.starts_with('#'))
                .filter(|l| !l.starts_with("title"))
                .collect::<Vec<_>>()
                .join("\n")
        })
        .collect();
    for (i, a) in texts.iter().enumerate() {
        for (j, b) in texts.iter().enumerate().skip(i + 1) {
            assert_ne!(
                a,
                b,
                "{} and {} are the same scene",
                files[i].display(),
                files[j].display()
            );
        }
    }
    assert!(files.len() >= 24, "{} broken scenes", files.len());
}

#[test]
fn a_file_that_cannot_be_read_gives_a_clean_error() {
    let dir = std::env::temp_dir().join(format!("bushing-unreadable-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    let missing = dir.join("no-such-scene.toml");
    let e = Scene::load(&missing).unwrap_err();
    let name = missing.display().to_string();
    assert_eq!(e.at, None);
    assert_eq!(e.file, name);
    assert!(
        e.to_string().starts_with(&format!("{name}: cannot read: ")),
        "{e}"
    );

    // A directory in place of a file: refused before it is opened.
    let e = Scene::load(&dir).unwrap_err();
    assert_eq!(e.at, None);
    assert!(e.message.starts_with("not a regular file"), "{e}");

    // Not UTF-8 text (a scene saved in Latin-1, say).
    let latin1 = dir.join("latin1.toml");
    std::fs::write(&latin1, b"title = \"Fr\xe9quence\"\n").unwrap();
    let e = Scene::load(&latin1).unwrap_err();
    assert_eq!(e.at, None);
    assert!(e.message.starts_with("cannot read: "), "{e}");
    assert!(e.message.contains("UTF-8"), "{e}");

    // An empty file is read, then refused for what it lacks.
    let empty = dir.join("empty.toml");
    std::fs::write(&empty, "").unwrap();
    let e = Scene::load(&empty).unwrap_err();
    assert!(e.message.contains("missing field"), "{e}");

    std::fs::remove_dir_all(&dir).ok();
}
