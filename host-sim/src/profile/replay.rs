//! `replay`: a measured displacement read from a CSV file, linearly
//! interpolated onto the scene's step.

use std::fmt;
use std::io::Read;
use std::path::Path;

use serde::Deserialize;
use serde::de::{self, Visitor};

use super::check::finite_positive;
use super::{MAX_COLUMN, MAX_CSV_BYTES, MAX_SAMPLES, Profile, ProfileSpec};

/// Replay of a measured displacement from a CSV file, linearly
/// interpolated onto the scene's step.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Replay {
    /// CSV file, relative to the scene file's directory.
    pub file: String,
    /// Displacement column: a header name or a 1-based index.
    pub column: Column,
    /// Time column in s (name or 1-based index); not with `rate_hz`.
    #[serde(default)]
    pub time_column: Option<Column>,
    /// Sampling rate of the file in Hz; not with `time_column`.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// The samples (time from the first sample in s, displacement in
    /// mm), read from `file` when the scene is loaded.
    #[serde(skip)]
    pub samples: Vec<(f64, f64)>,
}

impl Profile for Replay {
    fn duration(&self, _dt: f64) -> Result<f64, String> {
        let samples = &self.samples;
        match (samples.first(), samples.last()) {
            (Some(_), Some(&(end, _))) if samples.len() >= 2 && end.is_finite() && end > 0.0 => {
                Ok(end)
            }
            _ => Err(format!(
                "replay: {} samples; at least 2, read from the file when the scene is parsed",
                samples.len()
            )),
        }
    }

    fn displacement(&self, t: f64) -> f64 {
        interpolate(&self.samples, t)
    }
}

/// A CSV column, by header name or 1-based index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Column {
    /// Header name (surrounding blanks and double quotes ignored).
    Name(String),
    /// Index from 1, as written (checked when the file is read).
    Index(i64),
}

impl fmt::Display for Column {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Name(n) => write!(f, "'{n}'"),
            Self::Index(i) => write!(f, "{i}"),
        }
    }
}

impl<'de> Deserialize<'de> for Column {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct ColumnVisitor;
        impl Visitor<'_> for ColumnVisitor {
            type Value = Column;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a column name (string) or a 1-based column index (integer)")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Column, E> {
                Ok(Column::Name(v.to_string()))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Column, E> {
                Ok(Column::Index(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Column, E> {
                Ok(Column::Index(i64::try_from(v).unwrap_or(i64::MAX)))
            }
        }
        d.deserialize_any(ColumnVisitor)
    }
}

/// Linear interpolation in samples (t, x) with increasing t, constant
/// beyond the ends.
fn interpolate(samples: &[(f64, f64)], t: f64) -> f64 {
    let i = samples.partition_point(|s| s.0 <= t);
    match (
        i.checked_sub(1).and_then(|j| samples.get(j)),
        samples.get(i),
    ) {
        (Some(&(t0, x0)), Some(&(t1, x1))) => x0 + (x1 - x0) * ((t - t0) / (t1 - t0)),
        (Some(&(_, x)), None) | (None, Some(&(_, x))) => x,
        (None, None) => 0.0,
    }
}

/// Completes a profile as parsed: a replay reads its CSV file, `dir`
/// being the directory relative file names start from; with `confine`,
/// the file must be inside `dir` once links and `..` are resolved. Other
/// profiles are returned unchanged.
pub fn resolve(p: ProfileSpec, dir: &Path, confine: bool) -> Result<ProfileSpec, String> {
    let ProfileSpec::Replay(Replay {
        file,
        column,
        time_column,
        rate_hz,
        ..
    }) = p
    else {
        return Ok(p);
    };
    let time = match (&time_column, rate_hz) {
        (Some(_), Some(_)) => return Err("give time_column or rate_hz, not both".into()),
        (None, None) => {
            return Err("give time_column (a time column in s) or rate_hz (Hz)".into());
        }
        (Some(c), None) => Time::Column(index_check("time_column", c)?),
        (None, Some(r)) => {
            finite_positive("rate_hz", r)?;
            Time::Rate(r)
        }
    };
    index_check("column", &column)?;
    if file.trim().is_empty() {
        return Err("file must name a CSV file".into());
    }
    let path = dir.join(&file);
    let name = path.display().to_string();
    let cannot = |e: std::io::Error| format!("cannot read replay file {name}: {e}");
    if confine {
        let base = dir
            .canonicalize()
            .or_else(|_| Path::new(".").canonicalize())
            .map_err(cannot)?;
        let real = path.canonicalize().map_err(cannot)?;
        if !real.starts_with(&base) {
            return Err(format!(
                "replay file {}: outside the scene's folder, which --confine forbids",
                shown(&file)
            ));
        }
    }
    // Only regular files, checked before opening: a device or a pipe could
    // block or never end.
    let meta = std::fs::metadata(&path).map_err(cannot)?;
    if !meta.is_file() {
        return Err(format!("replay file {name} is not a regular file"));
    }
    if meta.len() > MAX_CSV_BYTES {
        return Err(format!(
            "replay file {name}: {} bytes, more than the limit of {MAX_CSV_BYTES}",
            meta.len()
        ));
    }
    let mut text = String::new();
    std::fs::File::open(&path)
        .map_err(cannot)?
        .take(MAX_CSV_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(cannot)?;
    if text.len() as u64 > MAX_CSV_BYTES {
        return Err(format!(
            "replay file {name}: more than the limit of {MAX_CSV_BYTES} bytes"
        ));
    }
    let samples = read_csv(&name, &text, &column, time)?;
    Ok(ProfileSpec::Replay(Replay {
        file,
        column,
        time_column,
        rate_hz,
        samples,
    }))
}

fn index_check<'a>(name: &str, c: &'a Column) -> Result<&'a Column, String> {
    match c {
        Column::Index(i) if !(1..=MAX_COLUMN).contains(i) => Err(format!(
            "{name} = {i}: column indices count from 1 to {MAX_COLUMN}"
        )),
        Column::Name(n) if n.trim().is_empty() => Err(format!("{name}: empty column name")),
        _ => Ok(c),
    }
}

/// Where a replay's times come from.
#[derive(Debug, Clone, Copy)]
pub(super) enum Time<'a> {
    Column(&'a Column),
    Rate(f64),
}

/// A field without the double quotes the `csv` reader leaves when blanks
/// come before them (`a, "b"`).
fn clean(field: &str) -> &str {
    field
        .strip_prefix('"')
        .and_then(|g| g.strip_suffix('"'))
        .unwrap_or(field)
        .trim()
}

/// At most 40 characters of a field, for messages, with control and
/// other invisible characters escaped (`\u{1b}`), so that a hostile file
/// cannot write to the terminal through an error.
fn shown(field: &str) -> String {
    let mut s: String = field
        .chars()
        .take(40)
        .flat_map(char::escape_debug)
        .collect();
    if field.chars().nth(40).is_some() {
        s.push('…');
    }
    s
}

/// A number for messages: plain, or in exponent form when very large or
/// very small.
fn num(v: f64) -> String {
    if v == 0.0 || (1e-6..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Reads (time, displacement) samples from CSV text with the `csv` crate;
/// `name` names the file in errors, whose rows are the file's lines counted
/// from 1.
///
/// Fields are separated by commas, or by semicolons or tabs when the first
/// row has no comma, and may be quoted; blank lines and lines starting with
/// `#` are skipped; the first row is a header when one of its fields is not
/// a number. Times must increase strictly and are shifted to start at 0.
pub(super) fn read_csv(
    name: &str,
    text: &str,
    column: &Column,
    time: Time<'_>,
) -> Result<Vec<(f64, f64)>, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let first_text = text
        .lines()
        .map(str::trim)
        .find(|t| !t.is_empty() && !t.starts_with('#'));
    let delimiter = [b',', b';', b'\t']
        .into_iter()
        .find(|&d| first_text.is_some_and(|f| f.as_bytes().contains(&d)))
        .unwrap_or(b',');
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut rows = reader.records().filter_map(|r| match r {
        Ok(record) => {
            let line = record.position().map_or(0, |p| p.line() as usize);
            let blank = record.iter().all(|f| clean(f).is_empty());
            let comment = record.get(0).is_some_and(|f| f.starts_with('#'));
            (!blank && !comment).then_some(Ok((line, record)))
        }
        Err(e) => Some(Err(format!("{name}: {e}"))),
    });
    let Some((first_line, first)) = rows.next().transpose()? else {
        return Err(format!("{name}: no rows"));
    };
    let header: Option<Vec<String>> = first
        .iter()
        .any(|f| clean(f).parse::<f64>().is_err())
        .then(|| first.iter().map(|f| clean(f).to_string()).collect());
    let find = |label: &str, c: &Column| -> Result<usize, String> {
        match c {
            Column::Index(i) => Ok(usize::try_from(*i).unwrap_or(1).saturating_sub(1)),
            Column::Name(n) => {
                let Some(h) = &header else {
                    return Err(format!(
                        "{name}: {label} '{n}' needs a header row, but row {first_line} is all numbers"
                    ));
                };
                h.iter().position(|f| f == n.trim()).ok_or_else(|| {
                    format!(
                        "{name}: row {first_line}: no column named '{n}' for {label} (the header has {})",
                        h.iter().map(|f| format!("'{}'", shown(f))).collect::<Vec<_>>().join(", ")
                    )
                })
            }
        }
    };
    let x_col = find("column", column)?;
    let t_col = match time {
        Time::Column(c) => Some(find("time_column", c)?),
        Time::Rate(_) => None,
    };
    let number = |line: usize, fields: &csv::StringRecord, c: usize| -> Result<f64, String> {
        let Some(f) = fields.get(c).map(clean) else {
            return Err(format!(
                "{name}: row {line}, column {}: missing (the row has {} columns)",
                c + 1,
                fields.len()
            ));
        };
        match f.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(format!(
                "{name}: row {line}, column {}: expected a finite number, got '{}'",
                c + 1,
                shown(f)
            )),
            Err(_) => Err(format!(
                "{name}: row {line}, column {}: expected a number, got '{}'",
                c + 1,
                shown(f)
            )),
        }
    };
    let data = header
        .is_none()
        .then_some(Ok((first_line, first)))
        .into_iter()
        .chain(rows);
    let mut samples: Vec<(f64, f64)> = Vec::new();
    let mut start = 0.0;
    let mut previous = (0usize, 0.0f64);
    for row in data {
        let (line, fields) = row?;
        let x = number(line, &fields, x_col)?;
        let t = match (t_col, time) {
            (Some(c), _) => {
                let raw = number(line, &fields, c)?;
                if samples.is_empty() {
                    start = raw;
                }
                let t = raw - start;
                if !samples.is_empty() && t <= previous.1 {
                    return Err(format!(
                        "{name}: row {line}, column {}: time {} s is not after the {} s of row {}",
                        c + 1,
                        num(raw),
                        num(previous.1 + start),
                        previous.0
                    ));
                }
                if !t.is_finite() {
                    return Err(format!(
                        "{name}: row {line}, column {}: time {} s is too far from the first row's {} s",
                        c + 1,
                        num(raw),
                        num(start)
                    ));
                }
                t
            }
            (None, Time::Rate(r)) => samples.len() as f64 / r,
            (None, Time::Column(_)) => samples.len() as f64,
        };
        if samples.len() >= MAX_SAMPLES {
            return Err(format!(
                "{name}: row {line}: more than the limit of {MAX_SAMPLES} samples"
            ));
        }
        samples.push((t, x));
        previous = (line, t);
    }
    if samples.len() < 2 {
        return Err(format!(
            "{name}: {} data rows, at least 2 needed",
            samples.len()
        ));
    }
    Ok(samples)
}
