//! A test campaign as the elastomer machine recorded it: `campaign.toml`
//! and one CSV per test (seed 000 §3.2, Appendix B).
//!
//! ```toml
//! [campaign]
//! name = "rear twist-beam bushing, x"
//! # columns = { time = "time_s", x = "x_mm", force = "force_n" }   # the default names
//!
//! [[test]]
//! name = "sine-5-0.25"
//! kind = "sine"              # multi-step, triangle, sine or other
//! file = "sine-5-0.25.csv"
//! frequency_hz = 5.0         # nominal values: optional, checked against the record
//! amplitude_mm = 0.25
//! preload_mm = 0.0
//! # preload_hold_s = 1200.0 # how long the preload was held before the record
//! ```
//!
//! A preloaded record is replayed from rest through a 20 s ramp and a hold
//! at its preload of `preload_hold_s` (seconds): a test's own value, else
//! `[campaign] preload_hold_s`, else the seed machine's 20 minutes
//! (§3.2.3).
//!
//! A mistake in `campaign.toml` itself (its syntax, an unknown key, two
//! tests of one name) stops the reading, with the line. A mistake in one
//! test (an unknown kind, a missing or unreadable file, a NaN, times that
//! do not increase, too few samples) excludes that test with the reason,
//! and the others are read; only a campaign with no usable test is an
//! error.

use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::records::{Column, RecordError, Time, read_file, read_limited, read_table, shown};

/// Most bytes of `campaign.toml`.
pub const MAX_CAMPAIGN_BYTES: u64 = 1 << 20;
/// Fewest samples a usable record has.
pub const MIN_SAMPLES: usize = 8;
/// The hold at a preload before a record when the campaign does not say:
/// the seed machine's 20 minutes (§3.2.3), s.
pub const DEFAULT_PRELOAD_HOLD_S: f64 = 1200.0;
/// Longest hold at a preload a campaign may state (a day), s.
pub const MAX_PRELOAD_HOLD_S: f64 = 86_400.0;

/// `campaign.toml`, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct CampaignFile {
    campaign: Header,
    #[serde(default, rename = "test")]
    tests: Vec<Spanned<TestSpec>>,
}

/// `[campaign]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Header {
    name: String,
    #[serde(default)]
    columns: Columns,
    #[serde(default)]
    preload_hold_s: Option<Spanned<f64>>,
}

/// The names of the three columns every test's CSV has.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Columns {
    /// Time in s.
    #[serde(default = "time_name")]
    pub time: String,
    /// Imposed displacement in mm.
    #[serde(default = "x_name")]
    pub x: String,
    /// Measured force in N.
    #[serde(default = "force_name")]
    pub force: String,
}

fn time_name() -> String {
    "time_s".into()
}
fn x_name() -> String {
    "x_mm".into()
}
fn force_name() -> String {
    "force_n".into()
}

impl Default for Columns {
    fn default() -> Self {
        Self {
            time: time_name(),
            x: x_name(),
            force: force_name(),
        }
    }
}

/// One `[[test]]`, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct TestSpec {
    name: String,
    kind: String,
    file: String,
    #[serde(default)]
    frequency_hz: Option<f64>,
    #[serde(default)]
    amplitude_mm: Option<f64>,
    #[serde(default)]
    preload_mm: Option<f64>,
    #[serde(default)]
    speed_mm_per_min: Option<f64>,
    #[serde(default)]
    preload_hold_s: Option<f64>,
}

/// What a test imposes (seed 000 §3.2.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Steps of displacement, each held while the force relaxes
    /// (hyperelasticity).
    MultiStep,
    /// Constant-speed triangles (rate-independent hysteresis).
    Triangle,
    /// A sine (viscoelasticity).
    Sine,
    /// Anything else (a road profile): used by the time-domain fit only.
    Other,
}

impl Kind {
    /// The kinds, as written in `campaign.toml`.
    pub const ALL: [Self; 4] = [Self::MultiStep, Self::Triangle, Self::Sine, Self::Other];

    /// Name in `campaign.toml`.
    pub fn name(self) -> &'static str {
        match self {
            Self::MultiStep => "multi-step",
            Self::Triangle => "triangle",
            Self::Sine => "sine",
            Self::Other => "other",
        }
    }
}

/// The nominal values a test may state; each one given is checked against
/// the record.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Nominal {
    /// Sine frequency, Hz.
    pub frequency_hz: Option<f64>,
    /// Amplitude, mm.
    pub amplitude_mm: Option<f64>,
    /// Preload (mean displacement), mm.
    pub preload_mm: Option<f64>,
    /// Triangle speed, mm/min.
    pub speed_mm_per_min: Option<f64>,
}

/// A record: time (s, from 0), displacement (mm) and force (N), in time
/// order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Record {
    /// Times, s, strictly increasing from 0.
    pub time: Vec<f64>,
    /// Displacement, mm.
    pub x: Vec<f64>,
    /// Force, N.
    pub force: Vec<f64>,
}

impl Record {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether the record has no sample.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }
}

/// A usable test.
#[derive(Debug, Clone, PartialEq)]
pub struct Test {
    /// Name, unique in the campaign.
    pub name: String,
    /// What it imposes.
    pub kind: Kind,
    /// Its CSV file.
    pub file: PathBuf,
    /// The values it states.
    pub nominal: Nominal,
    /// The samples.
    pub record: Record,
    /// How long the machine held the record's preload before it started,
    /// s (the replay's lead-in, [`super::replay::preload_steps`]).
    pub preload_hold_s: f64,
}

/// A test left out, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Excluded {
    /// The test's name.
    pub name: String,
    /// Why it is not used.
    pub reason: TestError,
}

/// Why a test is left out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TestError {
    /// `kind` is not a known kind.
    #[error("kind '{0}' is not one of multi-step, triangle, sine, other")]
    UnknownKind(String),
    /// A nominal value that cannot be one.
    #[error("{name} = {value} must be finite{}", if *.positive { " and > 0" } else { "" })]
    BadNominal {
        /// The key.
        name: &'static str,
        /// The value given.
        value: f64,
        /// Whether it must also be positive.
        positive: bool,
    },
    /// The CSV file could not be read as samples.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// Too few samples to use.
    #[error("{file}: {samples} samples, at least {MIN_SAMPLES} needed")]
    TooFew {
        /// The file.
        file: String,
        /// Samples read.
        samples: usize,
    },
    /// A preload hold that is not a duration a replay can run.
    #[error("preload_hold_s = {0} must be from 0 to {MAX_PRELOAD_HOLD_S} s")]
    BadHold(f64),
    /// A check of pre-processing failed (the record does not match its
    /// nominal values, the force is clipped, too few samples per period).
    #[error("{0}")]
    Check(String),
}

/// Why a campaign could not be read at all.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CampaignError {
    /// `campaign.toml` could not be read.
    #[error("{file}: {what}")]
    File {
        /// The file.
        file: String,
        /// What went wrong.
        what: String,
    },
    /// `campaign.toml` is not a campaign: its syntax or its shape.
    #[error("{file}:{line}:{column}: {what}")]
    Toml {
        /// The file.
        file: String,
        /// Line, from 1.
        line: usize,
        /// Column, from 1.
        column: usize,
        /// What was expected.
        what: String,
    },
    /// Two tests have one name.
    #[error("{file}:{line}: test '{name}' is named twice (first at line {first})")]
    DuplicateName {
        /// The file.
        file: String,
        /// The name.
        name: String,
        /// Line of the second.
        line: usize,
        /// Line of the first.
        first: usize,
    },
    /// `[campaign] preload_hold_s` is not a duration a replay can run.
    #[error("{file}:{line}: preload_hold_s = {value} must be from 0 to {MAX_PRELOAD_HOLD_S} s")]
    BadHold {
        /// The file.
        file: String,
        /// Line, from 1.
        line: usize,
        /// The value given.
        value: f64,
    },
    /// No test is listed.
    #[error("{file}: no [[test]]: a campaign lists its tests")]
    NoTests {
        /// The file.
        file: String,
    },
    /// Every test was left out.
    #[error("{file}: no usable test; {}", list(.excluded))]
    NothingUsable {
        /// The file.
        file: String,
        /// Every test, with its reason.
        excluded: Vec<Excluded>,
    },
}

fn list(excluded: &[Excluded]) -> String {
    excluded
        .iter()
        .map(|e| format!("{}: {}", e.name, e.reason))
        .collect::<Vec<_>>()
        .join("; ")
}

/// A campaign read: its usable tests, in the order listed, and the tests
/// left out with their reasons.
#[derive(Debug, Clone, PartialEq)]
pub struct Campaign {
    /// `[campaign] name`.
    pub name: String,
    /// The folder.
    pub dir: PathBuf,
    /// The usable tests.
    pub tests: Vec<Test>,
    /// The tests left out.
    pub excluded: Vec<Excluded>,
}

impl Campaign {
    /// Reads `DIR/campaign.toml` and every test's CSV. With `confine`,
    /// each test's file must be inside `dir`.
    pub fn load(dir: &Path, confine: bool) -> Result<Self, CampaignError> {
        let path = dir.join("campaign.toml");
        let file = path.display().to_string();
        let fail = |what: String| CampaignError::File {
            file: file.clone(),
            what,
        };
        let text = read_limited(&path, MAX_CAMPAIGN_BYTES).map_err(|e| fail(e.to_string()))?;
        Self::parse(&file, &text, dir, confine)
    }

    /// Reads campaign text; `file` names it in errors and the tests' files
    /// are found in `dir`.
    pub fn parse(file: &str, text: &str, dir: &Path, confine: bool) -> Result<Self, CampaignError> {
        let raw: CampaignFile = toml::from_str(text).map_err(|e| {
            let at = e.span().map_or(0, |s| s.start);
            let before = &text[..at.min(text.len())];
            CampaignError::Toml {
                file: file.to_string(),
                line: before.matches('\n').count() + 1,
                column: before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1,
                what: e.message().trim().to_string(),
            }
        })?;
        if raw.tests.is_empty() {
            return Err(CampaignError::NoTests {
                file: file.to_string(),
            });
        }
        let line_of = |at: usize| text[..at.min(text.len())].matches('\n').count() + 1;
        let mut seen: Vec<(String, usize)> = Vec::new();
        for t in &raw.tests {
            let line = line_of(t.span().start);
            if let Some((_, first)) = seen.iter().find(|(n, _)| *n == t.get_ref().name) {
                return Err(CampaignError::DuplicateName {
                    file: file.to_string(),
                    name: t.get_ref().name.clone(),
                    line,
                    first: *first,
                });
            }
            seen.push((t.get_ref().name.clone(), line));
        }
        let columns = raw.campaign.columns;
        let hold = match raw.campaign.preload_hold_s {
            Some(h) if !valid_hold(*h.get_ref()) => {
                return Err(CampaignError::BadHold {
                    file: file.to_string(),
                    line: line_of(h.span().start),
                    value: *h.get_ref(),
                });
            }
            Some(h) => h.into_inner(),
            None => DEFAULT_PRELOAD_HOLD_S,
        };
        let mut tests = Vec::new();
        let mut excluded = Vec::new();
        for spec in raw.tests {
            let spec = spec.into_inner();
            let name = spec.name.clone();
            match read_test(spec, dir, confine, &columns, hold) {
                Ok(test) => tests.push(test),
                Err(reason) => excluded.push(Excluded { name, reason }),
            }
        }
        if tests.is_empty() {
            return Err(CampaignError::NothingUsable {
                file: file.to_string(),
                excluded,
            });
        }
        Ok(Self {
            name: raw.campaign.name,
            dir: dir.to_path_buf(),
            tests,
            excluded,
        })
    }
}

/// One test's checks and record.
fn read_test(
    spec: TestSpec,
    dir: &Path,
    confine: bool,
    columns: &Columns,
    hold: f64,
) -> Result<Test, TestError> {
    let preload_hold_s = match spec.preload_hold_s {
        Some(h) if !valid_hold(h) => return Err(TestError::BadHold(h)),
        Some(h) => h,
        None => hold,
    };
    let kind = Kind::ALL
        .into_iter()
        .find(|k| k.name() == spec.kind)
        .ok_or_else(|| TestError::UnknownKind(shown(&spec.kind)))?;
    let nominal = Nominal {
        frequency_hz: nominal("frequency_hz", spec.frequency_hz, true)?,
        amplitude_mm: nominal("amplitude_mm", spec.amplitude_mm, true)?,
        preload_mm: nominal("preload_mm", spec.preload_mm, false)?,
        speed_mm_per_min: nominal("speed_mm_per_min", spec.speed_mm_per_min, true)?,
    };
    let (name, text) = read_file(dir, &spec.file, confine, "the campaign's folder")?;
    let (time, x, force) = (
        Column::Name(columns.time.clone()),
        Column::Name(columns.x.clone()),
        Column::Name(columns.force.clone()),
    );
    let rows = read_table(
        &name,
        &text,
        [("x", &x), ("force", &force)],
        Time::Column(&time),
    )?;
    if rows.len() < MIN_SAMPLES {
        return Err(TestError::TooFew {
            file: name,
            samples: rows.len(),
        });
    }
    let mut record = Record::default();
    for (t, [xv, f]) in rows {
        record.time.push(t);
        record.x.push(xv);
        record.force.push(f);
    }
    Ok(Test {
        name: spec.name,
        kind,
        file: dir.join(&spec.file),
        nominal,
        record,
        preload_hold_s,
    })
}

fn valid_hold(h: f64) -> bool {
    (0.0..=MAX_PRELOAD_HOLD_S).contains(&h)
}

fn nominal(name: &'static str, v: Option<f64>, positive: bool) -> Result<Option<f64>, TestError> {
    match v {
        Some(value) if !value.is_finite() || (positive && value <= 0.0) => {
            Err(TestError::BadNominal {
                name,
                value,
                positive,
            })
        }
        other => Ok(other),
    }
}
