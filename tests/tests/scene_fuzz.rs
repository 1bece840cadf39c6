//! Fuzzing the scene parser (issue 6: "no input file can make the program
//! panic; the parser is fuzzed").
//!
//! A deterministic mutator starts from every scene in `scenes/`, every
//! broken scene in `tests/scenes/broken/` and the first scene with each
//! example of `docs/scenes.md` in place of its tables. It applies one to
//! four random mutations (bit flips, deletions, insertions of TOML
//! punctuation, table headers, key names, effect kinds, forms and profile
//! types, extreme numbers such as `1e308`, `-0`, `nan`, `inf`, very long
//! strings and deep nesting, duplicated, swapped and dropped lines, lines
//! spliced from another scene, truncation) and hands the text to
//! `Scene::parse_in` under `catch_unwind`. One execution in [`CSV_EVERY`]
//! mutates a replayed CSV file instead (from the CSV files of the tests)
//! and parses a scene that replays it. Mutants that parse are kept, one
//! pool per kind of scene, as bases for further mutation; each is built in
//! its number type and stepped over its first [`STEPPED`] steps, and some
//! of those with at most [`RUN_STEPS`] steps are also run end to end (trace
//! and plot files), all under `catch_unwind`.
//!
//! The normal test runs [`QUICK_EXECUTIONS`] executions; the long run is
//!
//! ```sh
//! SCENE_FUZZ_EXECUTIONS=1000000 cargo test --release -p bushing-tests \
//!     --test scene_fuzz -- --ignored --nocapture
//! ```
//!
//! (`SCENE_FUZZ_SEED` picks another stream). Both print how many inputs
//! parsed and what was stepped. A panic fails the test with the input
//! reduced to a minimal one that still panics at the same place; such
//! inputs are kept in [`REGRESSIONS`].

use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::Once;

use bushing::Real;
use bushing_sim::scene::NumberType;
use bushing_sim::{Scene, model, profile, run};
use bushing_tests::Noise;

/// Executions of the normal test run.
const QUICK_EXECUTIONS: u64 = 20_000;
/// Default length of the long run.
const LONG_EXECUTIONS: u64 = 1_000_000;
/// Parsed mutants with at most this many steps may be run end to end.
const RUN_STEPS: u64 = 5_000;
/// Steps taken on the model of each mutant that parses.
const STEPPED: u64 = 400;
/// One stepped mutant in this many is also run end to end into files
/// (when it has at most [`RUN_STEPS`] steps).
const END_TO_END_EVERY: u64 = 16;
/// Parsed mutants kept as bases for further mutation, per kind of scene.
const POOL: usize = 32;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn toml_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| (p.display().to_string(), std::fs::read(&p).unwrap()))
        .collect()
}

/// The ```toml blocks of `docs/scenes.md`, one example per feature.
fn doc_blocks() -> Vec<String> {
    let doc = std::fs::read_to_string(root().join("docs/scenes.md")).unwrap();
    let mut blocks = Vec::new();
    let mut open: Option<String> = None;
    for line in doc.lines() {
        match open.as_mut() {
            None if line.trim() == "```toml" => open = Some(String::new()),
            Some(_) if line.trim() == "```" => blocks.extend(open.take()),
            Some(b) => {
                b.push_str(line);
                b.push('\n');
            }
            None => {}
        }
    }
    blocks
}

/// The tables of a scene, each with its header line ("" for the keys
/// before the first header).
fn tables(text: &str) -> Vec<(String, String)> {
    let mut out = vec![(String::new(), String::new())];
    for line in text.split_inclusive('\n') {
        if line.trim_start().starts_with('[') {
            out.push((line.trim().to_string(), String::new()));
        }
        if let Some((_, body)) = out.last_mut() {
            body.push_str(line);
        }
    }
    out
}

/// `base` with its tables replaced by the tables of `block` of the same
/// name (all its `[[effects]]` when the block has some), or `None` when
/// the block has no table.
fn with_block(base: &str, block: &str) -> Option<String> {
    let new = tables(block);
    let headers: Vec<&str> = new.iter().skip(1).map(|(h, _)| h.as_str()).collect();
    if headers.is_empty() {
        return None;
    }
    let mut text: String = tables(base)
        .iter()
        .filter(|(h, _)| !headers.contains(&h.as_str()))
        .map(|(_, b)| b.as_str())
        .collect();
    if !text.ends_with('\n') {
        text.push('\n');
    }
    new.iter().skip(1).for_each(|(_, b)| text.push_str(b));
    Some(text)
}

/// The starting inputs: every scene, every broken scene, and the first
/// scene with each example of `docs/scenes.md` in place of its tables.
fn seeds() -> Vec<Vec<u8>> {
    let good = toml_files(&root().join("scenes"));
    let broken = toml_files(&root().join("tests/scenes/broken"));
    assert!(good.len() >= 4, "{} scenes in scenes/", good.len());
    assert!(broken.len() >= 20, "{} broken scenes", broken.len());
    let base = String::from_utf8(good[0].1.clone()).unwrap();
    let documented: Vec<Vec<u8>> = doc_blocks()
        .iter()
        .filter_map(|b| with_block(&base, b))
        .map(String::into_bytes)
        .collect();
    assert!(
        documented.len() >= 8,
        "{} documented examples",
        documented.len()
    );
    good.into_iter()
        .chain(broken)
        .map(|(_, t)| t)
        .chain(documented)
        .collect()
}

/// Key names and short string values of the seeds, added to [`WORDS`] so
/// that the mutator knows the names of new kinds and parameters.
fn harvested_words(seeds: &[Vec<u8>]) -> Vec<String> {
    let mut words: Vec<String> = WORDS.iter().map(|w| w.to_string()).collect();
    for seed in seeds {
        let text = String::from_utf8_lossy(seed);
        for line in text.lines().filter(|l| !l.trim_start().starts_with('#')) {
            let key = line.split('=').next().unwrap_or("").trim();
            let key = key.trim_start_matches(['{', ',', ' ']);
            let mut found = vec![key];
            found.extend(line.split('"').skip(1).step_by(2));
            for w in found {
                let ok = !w.is_empty()
                    && w.len() <= 32
                    && w.bytes()
                        .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-');
                if ok && !words.iter().any(|x| x == w) {
                    words.push(w.to_string());
                }
            }
        }
    }
    words
}

/// TOML punctuation and fragments.
const TOKENS: &[&str] = &[
    "]",
    "[",
    "]]",
    "[[",
    "=",
    "\"",
    "'",
    "\"\"\"",
    "'''",
    ",",
    "{",
    "}",
    "{}",
    "[]",
    ".",
    "#",
    "\n",
    "\r\n",
    "\r",
    "\t",
    " ",
    "\\",
    "\\u00e9",
    "\\UFFFFFFFF",
    "\u{0}",
    "\u{feff}",
    "é",
    "\u{10ffff}",
    "[[effects]]\n",
    "[effects]\n",
    "[run]\n",
    "[backbone]\n",
    "[profile]\n",
    "[run.rate_hz]\n",
    "[[profile]]\n",
    "type = ",
    "cells = []\n",
    "cells = [{}]\n",
    "cells = [{ f_hz = 1.0, g = 0.1 }]\n",
    "cells = [{ g = 0.1, x_f = 0.05 }]\n",
    "cells = [{ f_hz = 0.0, g = 0.1, x_f = 0.02 }]\n",
    "a.b.c = 1\n",
    "effects = 1\n",
    "true",
    "false",
    "1979-05-27T07:32:00Z",
    "07:32:00",
    "1979-05-27",
];

/// Numbers at the edges of what a parameter can take.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-0.0",
    "+0.0",
    "1",
    "-1",
    "0.5",
    "1.0000000000000002",
    "0.9999999999999999",
    "2",
    "64",
    "65",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e-308",
    "5e-324",
    "-5e-324",
    "1e9",
    "1e10",
    "2e9",
    "1e18",
    "1e-9",
    "nan",
    "+nan",
    "-nan",
    "inf",
    "+inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551616",
    "4294967296",
    "0x7fffffff",
    "0o777",
    "0b101",
    "1_000",
    "1__0",
    "1e",
    "1.",
    ".5",
    "00",
    "3.4028235e38",
    "3.5e38",
    "1.1754944e-38",
    "1e-45",
];

/// Words a scene uses: table and key names, kinds, forms and laws.
const WORDS: &[&str] = &[
    "title",
    "run",
    "rate_hz",
    "number",
    "f32",
    "f64",
    "backbone",
    "type",
    "polynomial",
    "coefficients",
    "range",
    "spline",
    "x",
    "force",
    "effects",
    "maxwell",
    "form",
    "state",
    "plain",
    "multiplied",
    "compensated",
    "load-explicit",
    "load-exponential",
    "rate-explicit",
    "rate-midpoint",
    "rate-exact-ramp",
    "cells",
    "f_hz",
    "g",
    "iwan",
    "clamp",
    "slider",
    "k_ref",
    "slip_force",
    "x_f",
    "xf",
    "midpoint",
    "exact-ramp",
    "turning-points",
    "law",
    "sts",
    "table",
    "c",
    "k1",
    "d",
    "k",
    "first_loading",
    "masing",
    "ignored",
    "dahl",
    "k_d",
    "f_f",
    "alpha",
    "bouc-wen",
    "a",
    "beta",
    "gamma",
    "n",
    "berg",
    "f_max",
    "x2",
    "dashpot",
    "profile",
    "sine",
    "triangle",
    "amplitude",
    "frequency_hz",
    "cycles",
    "preload",
    "speed",
];

/// Random choices for the mutator, drawn from the shared seeded generator.
struct Rng(Noise);

impl Rng {
    /// Uniform in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        ((self.0.uniform() * n as f64) as usize).min(n - 1)
    }

    fn chance(&mut self, p: f64) -> bool {
        self.0.uniform() < p
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

fn line_starts(text: &[u8]) -> Vec<usize> {
    std::iter::once(0)
        .chain(
            text.iter()
                .enumerate()
                .filter(|(_, b)| **b == b'\n')
                .map(|(i, _)| i + 1),
        )
        .collect()
}

/// Byte range of line `i` including its newline.
fn line_range(text: &[u8], starts: &[usize], i: usize) -> (usize, usize) {
    let end = starts.get(i + 1).copied().unwrap_or(text.len());
    (starts[i], end)
}

/// Ranges of the number-like runs of `text` (digits with signs, dots and
/// exponents, or the words nan and inf).
fn number_runs(text: &[u8]) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts_number = text[i].is_ascii_digit()
            || text[i..].starts_with(b"nan")
            || text[i..].starts_with(b"inf");
        if starts_number {
            let mut j = i;
            while j < text.len()
                && (text[j].is_ascii_alphanumeric() || matches!(text[j], b'.' | b'+' | b'-' | b'_'))
            {
                j += 1;
            }
            let start = if i > 0 && matches!(text[i - 1], b'-' | b'+') {
                i - 1
            } else {
                i
            };
            runs.push((start, j));
            i = j;
        } else {
            i += 1;
        }
    }
    runs
}

/// Ranges of the contents of the basic strings of `text`.
fn string_runs(text: &[u8]) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut open = None;
    for (i, b) in text.iter().enumerate() {
        match (*b, open) {
            (b'"', None) => open = Some(i + 1),
            (b'"', Some(s)) => {
                runs.push((s, i));
                open = None;
            }
            (b'\n', Some(_)) => open = None,
            _ => {}
        }
    }
    runs
}

fn mutate_once(rng: &mut Rng, text: &mut Vec<u8>, seeds: &[Vec<u8>], words: &[String]) {
    let at = rng.below(text.len() + 1);
    match rng.below(15) {
        0 if !text.is_empty() => {
            let i = rng.below(text.len());
            text[i] ^= 1 << rng.below(8);
        }
        1 if !text.is_empty() => {
            let i = rng.below(text.len());
            text[i] = if rng.chance(0.5) {
                *rng.pick(b"[]{}=\"',.#\n\\ 0123456789-+einf_")
            } else {
                rng.below(256) as u8
            };
        }
        2 if !text.is_empty() => {
            let at = at.min(text.len() - 1);
            let len = if rng.chance(0.8) {
                1 + rng.below(16)
            } else {
                1 + rng.below(text.len() / 4 + 1)
            };
            text.drain(at..(at + len).min(text.len()));
        }
        3 => {
            let t = rng.pick(TOKENS).as_bytes();
            text.splice(at..at, t.iter().copied());
        }
        4 => {
            let w = rng.pick(words);
            let w = match rng.below(3) {
                0 => format!("\"{w}\""),
                1 => format!("\n{w} = "),
                _ => w.clone(),
            };
            text.splice(at..at, w.bytes());
        }
        5 | 6 => {
            // Most targeted: a number of the scene becomes an extreme one.
            let runs = number_runs(text);
            let n = rng.pick(NUMBERS).as_bytes();
            if runs.is_empty() {
                text.splice(at..at, n.iter().copied());
            } else {
                let (s, e) = *rng.pick(&runs);
                text.splice(s..e, n.iter().copied());
            }
        }
        7 => {
            let runs = string_runs(text);
            if let Some(&(s, e)) = (!runs.is_empty()).then(|| rng.pick(&runs)) {
                let w = rng.pick(words).as_bytes();
                text.splice(s..e, w.iter().copied());
            }
        }
        8 | 9 => {
            let starts = line_starts(text);
            let i = rng.below(starts.len());
            let (s, e) = line_range(text, &starts, i);
            let line = text[s..e].to_vec();
            match rng.below(3) {
                0 => {
                    // Duplicate the line.
                    text.splice(e..e, line);
                }
                1 => {
                    text.drain(s..e);
                }
                _ => {
                    // Swap with another line.
                    let j = rng.below(starts.len());
                    let (s2, e2) = line_range(text, &starts, j);
                    if e <= s2 {
                        let other = text[s2..e2].to_vec();
                        text.splice(s2..e2, line);
                        text.splice(s..e, other);
                    }
                }
            }
        }
        10 => text.truncate(at),
        11 => {
            // A line from another scene, at a line start.
            let donor = rng.pick(seeds);
            let ds = line_starts(donor);
            let (s, e) = line_range(donor, &ds, rng.below(ds.len()));
            let mut line = donor[s..e].to_vec();
            if line.last() != Some(&b'\n') {
                line.push(b'\n');
            }
            let starts = line_starts(text);
            let at = *rng.pick(&starts);
            text.splice(at..at, line);
        }
        12 => {
            // Something very long.
            let len = [10, 1_000, 10_000, 100_000][rng.below(4)];
            let long: Vec<u8> = match rng.below(5) {
                0 => std::iter::once(b'"')
                    .chain(std::iter::repeat_n(b'a', len))
                    .chain(std::iter::once(b'"'))
                    .collect(),
                1 => std::iter::repeat_n(b'9', len.min(10_000)).collect(),
                2 => std::iter::repeat_n(b'[', len.min(10_000)).collect(),
                3 => {
                    let mut v = b"x = ".to_vec();
                    v.extend(std::iter::repeat_n(b'[', len.min(1_000)));
                    v.extend(std::iter::repeat_n(b']', len.min(1_000)));
                    v.push(b'\n');
                    v
                }
                _ => std::iter::repeat_n(&b"1.0, "[..], len.min(10_000) / 5)
                    .flatten()
                    .copied()
                    .collect(),
            };
            text.splice(at..at, long);
        }
        _ => {
            // The value after an `=` becomes a number, a word or a token.
            let starts = line_starts(text);
            let i = rng.below(starts.len());
            let (s, e) = line_range(text, &starts, i);
            if let Some(eq) = text[s..e].iter().position(|b| *b == b'=') {
                let v = match rng.below(3) {
                    0 => rng.pick(NUMBERS).to_string(),
                    1 => format!("\"{}\"", rng.pick(words)),
                    _ => rng.pick(TOKENS).to_string(),
                };
                let end = if text[e - 1] == b'\n' { e - 1 } else { e };
                text.splice(s + eq + 1..end, format!(" {v}").bytes());
            }
        }
    }
}

thread_local! {
    /// Set while this thread fuzzes: panics are recorded, not printed.
    static QUIET: Cell<bool> = const { Cell::new(false) };
    /// The last panic of this thread while quiet: message and place.
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

fn quiet_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if QUIET.with(Cell::get) {
                LAST_PANIC.with(|p| *p.borrow_mut() = Some(info.to_string()));
            } else {
                previous(info);
            }
        }));
    });
}

/// What happened to one input.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Outcome {
    /// Refused with an error.
    Refused,
    /// Parsed, built and stepped: the profile type and the effect kinds,
    /// and whether the scene was also run end to end.
    Stepped(Vec<String>, bool),
    /// Parsed but the model builder refused it.
    BuildRefused,
}

/// Where an input panicked, and the panic.
#[derive(Debug, Clone)]
struct Panic {
    stage: &'static str,
    message: String,
}

impl Panic {
    /// The source place of the panic (the first line of the hook's report).
    fn place(&self) -> &str {
        self.message.lines().next().unwrap_or("")
    }
}

fn step_model<T: Real + 'static>(scene: &Scene) -> Result<(), String> {
    let mut bushing = model::compile::<T>(scene).map_err(|e| e.to_string())?;
    let names = model::effect_names(scene);
    let inputs: Vec<T> = (1..=scene.steps().min(STEPPED))
        .map(|n| T::from_f64(profile::displacement(&scene.profile, n as f64 * scene.dt)))
        .collect();
    let (mut rows, mut parts) = (Vec::new(), Vec::new());
    // As a run steps it: re-tuned on the scene's temperature history.
    model::step_scene(scene, bushing.as_mut(), 0, &inputs, &mut rows, &mut parts)
        .map_err(|e| e.to_string())?;
    assert_eq!(rows.len(), inputs.len(), "one row per step");
    assert_eq!(
        parts.len(),
        inputs.len() * names.len(),
        "one output per effect"
    );
    Ok(())
}

/// The panic of a `catch_unwind` that failed, with the message the quiet
/// hook recorded (or the payload).
fn caught<R>(stage: &'static str, r: std::thread::Result<R>) -> Result<R, Panic> {
    r.map_err(|payload| {
        let message = LAST_PANIC
            .with(|p| p.borrow_mut().take())
            .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Panic { stage, message }
    })
}

/// Parses `text` (a replayed CSV file being named relative to `dir`),
/// builds the scene's model and steps it, and runs it end to end into `out`
/// when given and the scene is short; all under `catch_unwind`.
fn execute(text: &str, dir: &Path, out: Option<&Path>) -> Result<Outcome, Panic> {
    let parsed = caught(
        "Scene::parse",
        panic::catch_unwind(|| {
            let r = Scene::parse_in("fuzz.toml", text, dir);
            if let Err(e) = &r {
                // The error names the file and lies inside it.
                assert_eq!(e.file, "fuzz.toml");
                assert!(!e.message.is_empty(), "empty message");
                let shown = e.to_string();
                assert!(shown.starts_with("fuzz.toml:"), "{shown}");
                if let Some(l) = e.at {
                    let lines = text.split('\n').count();
                    assert!(l.line >= 1 && l.line <= lines && l.column >= 1, "{shown}");
                }
            }
            r
        }),
    )?;
    let Ok(scene) = parsed else {
        return Ok(Outcome::Refused);
    };
    let steps = caught("Scene::steps", panic::catch_unwind(|| scene.steps()))?;
    let built = caught(
        "model::build and step",
        panic::catch_unwind(|| match scene.number {
            NumberType::F32 => step_model::<f32>(&scene),
            NumberType::F64 => step_model::<f64>(&scene),
        }),
    )?;
    if built.is_err() {
        return Ok(Outcome::BuildRefused);
    }
    let out = out.filter(|_| steps <= RUN_STEPS);
    if let Some(out) = out {
        let summary = caught(
            "run::run",
            panic::catch_unwind(AssertUnwindSafe(|| run::run(&scene, out))),
        )?;
        if let Ok(s) = summary {
            let shown = caught(
                "Summary display",
                panic::catch_unwind(AssertUnwindSafe(|| s.to_string())),
            )?;
            assert!(shown.contains("steps"));
        }
    }
    let profile: String = format!("{:?}", scene.profile)
        .chars()
        .take_while(char::is_ascii_alphanumeric)
        .collect();
    let mut features = vec![format!("profile {profile}")];
    for e in scene.effects() {
        let name = e.name();
        features.push(format!("effect {}", name.split(' ').next().unwrap_or("")));
    }
    if scene.temperature.is_some() {
        features.push("temperature".into());
    }
    Ok(Outcome::Stepped(features, out.is_some()))
}

/// Reduces `input` to a shorter one for which `panics` still holds.
fn minimise(input: &str, panics: impl Fn(&str) -> bool) -> String {
    let mut best = input.to_string();
    // Whole lines first, then ever smaller chunks.
    let mut i = 0;
    while i < best.split_inclusive('\n').count() {
        let candidate: String = best
            .split_inclusive('\n')
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, l)| l)
            .collect();
        if panics(&candidate) {
            best = candidate;
        } else {
            i += 1;
        }
    }
    let mut chunk = best.len() / 2;
    while chunk >= 1 {
        let mut at = 0;
        while at < best.len() {
            let (s, e) = (at, (at + chunk).min(best.len()));
            if best.is_char_boundary(s) && best.is_char_boundary(e) {
                let candidate = format!("{}{}", &best[..s], &best[e..]);
                if panics(&candidate) {
                    best = candidate;
                    continue;
                }
            }
            at += chunk;
        }
        chunk /= 2;
    }
    best
}

/// The replay profiles a mutated CSV file is read with: by column name
/// against a time column, by index at a rate, by indices.
const REPLAY_PROFILES: &[&str] = &[
    "[profile]\ntype = \"replay\"\nfile = \"fuzz.csv\"\ncolumn = \"x_mm\"\ntime_column = \"time_s\"\n",
    "[profile]\ntype = \"replay\"\nfile = \"fuzz.csv\"\ncolumn = 2\nrate_hz = 200\n",
    "[profile]\ntype = \"replay\"\nfile = \"fuzz.csv\"\ncolumn = 2\ntime_column = 1\n",
];

/// A scene replaying `fuzz.csv` with profile `i` of [`REPLAY_PROFILES`].
fn replay_scene(i: usize) -> String {
    format!(
        "[run]\nrate_hz = 1000\nnumber = \"f64\"\n\n[backbone]\ntype = \"polynomial\"\n\
         coefficients = [0.0, 150.0, 0.0, 4.0]\nrange = [-6.0, 6.0]\n\n[[effects]]\n\
         type = \"iwan\"\nform = \"clamp\"\ncells = [{{ g = 0.1, x_f = 0.05 }}]\n\n{}",
        REPLAY_PROFILES[i]
    )
}

/// What a fuzz run saw.
#[derive(Debug, Default)]
struct Tally {
    /// Scene texts tried (mutated scenes and replays of mutated CSV files).
    executions: u64,
    /// Of which replays of a mutated CSV file.
    csv_executions: u64,
    refused: u64,
    parsed: u64,
    /// Replays of a mutated CSV file that parsed.
    csv_parsed: u64,
    stepped: u64,
    end_to_end: u64,
    build_refused: Vec<String>,
    /// Stepped mutants by profile type and by effect kind.
    features: BTreeMap<String, u64>,
    /// Inputs that panicked.
    panicked: u64,
    /// A minimised input for each place that panicked.
    panics: Vec<(String, Panic)>,
}

/// Inputs that parsed, bases for further mutation, in one pool per kind
/// of scene (profile type and effect kinds) so that the kinds that survive
/// mutation most easily do not crowd out the others.
#[derive(Default)]
struct Corpus(BTreeMap<String, Vec<Vec<u8>>>);

impl Corpus {
    fn keep(&mut self, rng: &mut Rng, kind: String, input: Vec<u8>) {
        let pool = self.0.entry(kind).or_default();
        if pool.len() < POOL {
            pool.push(input);
        } else {
            let i = rng.below(POOL);
            pool[i] = input;
        }
    }

    /// An input of a kind drawn uniformly over the kinds.
    fn pick(&self, rng: &mut Rng) -> Option<&Vec<u8>> {
        if self.0.is_empty() {
            return None;
        }
        let i = rng.below(self.0.len());
        self.0.values().nth(i).map(|pool| rng.pick(pool))
    }
}

/// One CSV execution in this many.
const CSV_EVERY: u64 = 8;

fn fuzz(executions: u64, seed: u64) -> Tally {
    quiet_panics();
    QUIET.with(|q| q.set(true));
    let seeds = seeds();
    let words = harvested_words(&seeds);
    // Replayed files: the CSV files of the tests.
    let mut csv_files: Vec<PathBuf> = ["tests/data", "tests/scenes/broken"]
        .iter()
        .filter_map(|d| std::fs::read_dir(root().join(d)).ok())
        .flat_map(|d| d.map(|e| e.unwrap().path()))
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    csv_files.sort();
    let csv_seeds: Vec<Vec<u8>> = csv_files
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    let scenes_dir = root().join("scenes");
    let out =
        std::env::temp_dir().join(format!("bushing-scene-fuzz-{}-{seed}", std::process::id()));
    let replay_dir = out.join("replay");
    std::fs::create_dir_all(&replay_dir).unwrap();
    let csv_path = replay_dir.join("fuzz.csv");
    let mut rng = Rng(Noise::new(seed));
    let (mut corpus, mut csv_corpus) = (Corpus::default(), Corpus::default());
    let mut tally = Tally::default();
    while tally.executions < executions {
        tally.executions += 1;
        let csv = !csv_seeds.is_empty() && tally.executions % CSV_EVERY == 0;
        let (pool, bases) = if csv {
            (&csv_corpus, &csv_seeds)
        } else {
            (&corpus, &seeds)
        };
        let base = if rng.chance(0.5) {
            pool.pick(&mut rng)
        } else {
            None
        };
        let mut bytes = base.unwrap_or_else(|| rng.pick(bases)).clone();
        for _ in 0..1 + rng.below(4) {
            mutate_once(&mut rng, &mut bytes, bases, &words);
        }
        let (text, dir) = if csv {
            tally.csv_executions += 1;
            std::fs::write(&csv_path, &bytes).unwrap();
            (replay_scene(rng.below(REPLAY_PROFILES.len())), &replay_dir)
        } else {
            (String::from_utf8_lossy(&bytes).into_owned(), &scenes_dir)
        };
        let end_to_end =
            (tally.stepped % END_TO_END_EVERY == END_TO_END_EVERY - 1).then_some(out.as_path());
        match execute(&text, dir, end_to_end) {
            Ok(Outcome::Refused) => tally.refused += 1,
            Ok(outcome) => {
                tally.parsed += 1;
                let mut kind = String::new();
                match outcome {
                    Outcome::Stepped(features, ran) => {
                        kind = features.join(", ");
                        for f in features {
                            *tally.features.entry(f).or_default() += 1;
                        }
                        tally.stepped += 1;
                        tally.end_to_end += u64::from(ran);
                    }
                    _ if tally.build_refused.len() < 8 => tally.build_refused.push(text.clone()),
                    _ => {}
                }
                if csv {
                    tally.csv_parsed += 1;
                    csv_corpus.keep(&mut rng, kind, bytes);
                } else {
                    corpus.keep(&mut rng, kind, text.into_bytes());
                }
            }
            Err(p) => {
                tally.panicked += 1;
                // One minimised input per place that panics.
                let place = p.place().to_string();
                let seen = tally.panics.iter().any(|(_, q)| q.place() == place);
                if tally.panics.len() < 8 && !seen {
                    let same =
                        |r: Result<Outcome, Panic>| matches!(r, Err(q) if q.place() == place);
                    let input = if csv {
                        let csv_text = String::from_utf8_lossy(&bytes).into_owned();
                        let small = minimise(&csv_text, |c| {
                            std::fs::write(&csv_path, c).unwrap();
                            same(execute(&text, dir, Some(&out)))
                        });
                        format!("{text}\nwith fuzz.csv:\n{small}")
                    } else {
                        minimise(&text, |t| same(execute(t, dir, Some(&out))))
                    };
                    tally.panics.push((input, p));
                }
            }
        }
    }
    QUIET.with(|q| q.set(false));
    std::fs::remove_dir_all(&out).ok();
    println!(
        "scene fuzz (seed {seed}): {} executions ({} of them replays of a mutated CSV file), \
         {} refused, {} parsed ({} CSV), {} built and stepped ({STEPPED} steps at most), {} run \
         end to end, {} parsed but refused by the model builder, {} panicked ({} places)",
        tally.executions,
        tally.csv_executions,
        tally.refused,
        tally.parsed,
        tally.csv_parsed,
        tally.stepped,
        tally.end_to_end,
        tally.build_refused.len(),
        tally.panicked,
        tally.panics.len()
    );
    let features: Vec<String> = tally
        .features
        .iter()
        .map(|(f, n)| format!("{f}: {n}"))
        .collect();
    println!("stepped mutants by feature: {}", features.join(", "));
    tally
}

fn check(tally: &Tally) {
    let panics: Vec<String> = tally
        .panics
        .iter()
        .map(|(input, p)| format!("in {}: {}\ninput: {input:?}", p.stage, p.message))
        .collect();
    assert!(panics.is_empty(), "\n{}", panics.join("\n\n"));
    assert!(
        tally.build_refused.is_empty(),
        "scenes the parser accepts but the model builder refuses:\n{:?}",
        tally.build_refused
    );
    assert_eq!(
        tally.refused + tally.parsed + tally.panicked,
        tally.executions
    );
    // The mutator reaches both sides of the parser and the models.
    assert!(tally.refused >= tally.executions / 10, "{tally:?}");
    assert!(tally.parsed >= tally.executions / 20, "{tally:?}");
    assert!(tally.stepped >= tally.parsed / 4, "{tally:?}");
    assert!(tally.end_to_end >= 1, "{tally:?}");
    assert!(
        tally.csv_executions >= tally.executions / CSV_EVERY,
        "{tally:?}"
    );
    assert!(tally.csv_parsed >= tally.csv_executions / 20, "{tally:?}");
    // Every effect kind and the basic profiles were built and stepped.
    for kind in [
        "effect maxwell",
        "effect iwan",
        "effect xf",
        "effect turning-points",
        "effect dahl",
        "effect bouc-wen",
        "effect berg",
        "effect fractional",
        "effect dashpot",
        "temperature",
        "profile Sine",
        "profile Triangle",
    ] {
        assert!(
            tally.features.get(kind).is_some_and(|n| *n >= 10),
            "{kind}: {:?}",
            tally.features
        );
    }
}

#[test]
fn parser_fuzz_finds_no_panic() {
    let tally = fuzz(QUICK_EXECUTIONS, 6);
    check(&tally);
}

/// The long run; see the module documentation for the command.
#[test]
#[ignore = "long: set SCENE_FUZZ_EXECUTIONS and run with --ignored --release"]
fn parser_fuzz_long_run() {
    let executions = std::env::var("SCENE_FUZZ_EXECUTIONS")
        .ok()
        .map_or(LONG_EXECUTIONS, |s| s.parse().unwrap());
    let seed = std::env::var("SCENE_FUZZ_SEED")
        .ok()
        .map_or(2_000_006, |s| s.parse().unwrap());
    let tally = fuzz(executions, seed);
    check(&tally);
}

/// Inputs the fuzz run found to panic, minimised, with where they panicked
/// and the replayed `fuzz.csv` when there is one: each must now give an
/// error or run to the end.
const REGRESSIONS: &[(&str, &str, Option<&str>)] = &[
    (
        // Found by the long run (seed 2000006). A sine of 5e-324 mm in f64
        // gives forces of a few 1e-322 N: the tick step of the force axis
        // underflowed to 0 in the former `svg::ticks`, `(lo / step).ceil() as i64`
        // saturated and collecting i64::MIN..=i64::MAX ticks panicked
        // ("capacity overflow").
        "run::run, in the former svg::ticks (capacity overflow), subnormal sine",
        "[run]\nrate_hz = 1000\nnumber = \"f64\"\n[backbone]\ntype = \"polynomial\"\n\
         coefficients = [0.0, 100.0]\nrange = [-2.0, 2.0]\n[profile]\ntype = \"sine\"\n\
         amplitude = 5e-324\nfrequency_hz = 5.0\ncycles = 2\n",
        None,
    ),
    (
        // Found by a second long run (seed 2000006), the same underflow
        // reached through a replayed displacement of 5e-324 mm.
        "run::run, capacity overflow, subnormal replayed displacement",
        "[run]\nrate_hz = 1000\nnumber = \"f64\"\n[backbone]\ntype = \"polynomial\"\n\
         coefficients = [0.0, 150.0, 0.0, 4.0]\nrange = [-6.0, 6.0]\n[[effects]]\n\
         type = \"iwan\"\nform = \"clamp\"\ncells = [{ g = 0.1, x_f = 0.05 }]\n[profile]\n\
         type = \"replay\"\nfile = \"fuzz.csv\"\ncolumn = 2\nrate_hz = 200\n",
        Some("1,5e-324,5\n,0"),
    ),
];

#[test]
fn inputs_that_panicked_give_errors_or_run() {
    quiet_panics();
    let out = std::env::temp_dir().join(format!("bushing-fuzz-regressions-{}", std::process::id()));
    let dir = out.join("replay");
    std::fs::create_dir_all(&dir).unwrap();
    let mut failures = Vec::new();
    for (what, text, csv) in REGRESSIONS {
        std::fs::write(dir.join("fuzz.csv"), csv.unwrap_or("")).unwrap();
        QUIET.with(|q| q.set(true));
        let outcome = execute(text, &dir, Some(&out));
        QUIET.with(|q| q.set(false));
        match outcome {
            Ok(o) => assert!(
                matches!(o, Outcome::Refused | Outcome::Stepped(_, true)),
                "{what}: {o:?}"
            ),
            Err(p) => failures.push(format!(
                "{what}: still panics in {}: {}",
                p.stage, p.message
            )),
        }
    }
    std::fs::remove_dir_all(&out).ok();
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// Inputs at the edges of the format, each refused with an error.
const REFUSED: &[&str] = &[
    "",
    "\u{feff}",
    "\n\n\n",
    "# only a comment",
    "[run]\nrate_hz = 1e308\n",
    "title = \"\"\"\n",
    "[[effects]]\ntype = \"maxwell\"\n",
    "[run]\nrate_hz = 1000\n[backbone]\ntype = \"polynomial\"\ncoefficients = []\nrange = [-1.0, 1.0]\n[profile]\ntype = \"sine\"\namplitude = 1.0\nfrequency_hz = 1.0\ncycles = 1\n",
    "[run]\nrate_hz = 1000\n[backbone]\ntype = \"spline\"\nx = []\nforce = []\n[profile]\ntype = \"sine\"\namplitude = 1.0\nfrequency_hz = 1.0\ncycles = 1\n",
    "[run]\nrate_hz = 5e-324\n[backbone]\ntype = \"polynomial\"\ncoefficients = [0.0, 1.0]\nrange = [-1.0, 1.0]\n[profile]\ntype = \"sine\"\namplitude = 1.0\nfrequency_hz = 1.0\ncycles = 1\n",
    "[run]\nrate_hz = 1000\n[backbone]\ntype = \"polynomial\"\ncoefficients = [0.0, 1.0]\nrange = [-1e308, 1e308]\n[profile]\ntype = \"sine\"\namplitude = 1e308\nfrequency_hz = 1e-308\ncycles = 1e308\n",
    "[run]\nrate_hz = 1000\n[backbone]\ntype = \"polynomial\"\ncoefficients = [0.0, 1.0]\nrange = [-1.0, 1.0]\n[profile]\ntype = \"sine\"\namplitude = 1.0\nfrequency_hz = 1.0\ncycles = 5e-324\n",
];

#[test]
fn inputs_at_the_edges_are_refused_without_panic() {
    quiet_panics();
    let deep = format!("x = {}{}\n", "[".repeat(5_000), "]".repeat(5_000));
    let long_key = format!("{} = 1\n", "k".repeat(100_000));
    let long_string = format!("title = \"{}\"\n", "a".repeat(1_000_000));
    let long_number = format!("[run]\nrate_hz = {}\n", "9".repeat(100_000));
    let extra = [deep, long_key, long_string, long_number];
    for text in REFUSED
        .iter()
        .copied()
        .chain(extra.iter().map(String::as_str))
    {
        QUIET.with(|q| q.set(true));
        let outcome = execute(text, &root().join("scenes"), None);
        QUIET.with(|q| q.set(false));
        let short: String = text.chars().take(80).collect();
        match outcome {
            Ok(o) => assert_eq!(o, Outcome::Refused, "{short:?}"),
            Err(p) => panic!("{short:?} panics in {}: {}", p.stage, p.message),
        }
    }
}

/// Replayed CSV files at the edges, and whether each of the
/// [`REPLAY_PROFILES`] accepts them (by name against a time column, by index
/// at 200 Hz, by indices).
const EDGE_CSV: &[(&str, [bool; 3])] = &[
    ("", [false; 3]),
    ("\u{feff}", [false; 3]),
    ("# only a comment\n", [false; 3]),
    ("time_s,x_mm\n", [false; 3]),
    ("time_s,x_mm\n0.0,0.0\n", [false; 3]),
    ("time_s,x_mm\n0.0,nan\n0.01,0.0\n", [false; 3]),
    ("time_s,x_mm\n0.0,0.0\n0.01\n", [false; 3]),
    ("time_s,x_mm\n0.0,0.0\n0.01,1e309\n", [false; 3]),
    // Times that do not increase, or span too much or too little.
    ("time_s,x_mm\n0.0,0.0\n0.0,0.1\n", [false, true, false]),
    ("time_s,x_mm\n0.0,0.0\n-0.01,0.1\n", [false, true, false]),
    ("time_s,x_mm\n0.0,0.0\n1e308,0.1\n", [false, true, false]),
    ("time_s,x_mm\n0.0,0.0\n5e-324,0.1\n", [false, true, false]),
    // No header, a repeated name, an unbalanced quote (read as CSV reads
    // it: one quoted field to the end of the file, so no data rows).
    ("0.0,0.0\n0.01,0.1\n", [false, true, true]),
    ("time_s,time_s\n0.0,0.0\n0.01,0.1\n", [false, true, true]),
    ("\"time_s,x_mm\n0.0,0.0\n0.01,0.1\n", [false; 3]),
    ("time_s;x_mm\r\n0.0;0.0\r\n0.01;0.1\r\n", [true; 3]),
];

#[test]
fn replayed_files_at_the_edges_give_errors_not_panics() {
    quiet_panics();
    let dir = std::env::temp_dir().join(format!("bushing-csv-edges-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (csv, accepted) in EDGE_CSV {
        std::fs::write(dir.join("fuzz.csv"), csv).unwrap();
        for (i, accepted) in accepted.iter().enumerate() {
            QUIET.with(|q| q.set(true));
            let outcome = execute(&replay_scene(i), &dir, None);
            QUIET.with(|q| q.set(false));
            match outcome {
                Ok(o) => assert_eq!(o != Outcome::Refused, *accepted, "{csv:?} profile {i}"),
                Err(p) => panic!("{csv:?} profile {i} panics in {}: {}", p.stage, p.message),
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
