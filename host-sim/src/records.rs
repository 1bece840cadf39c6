//! Measured records: samples read from a CSV file by column, for a
//! replayed profile and for the tests of an identification campaign. One
//! reader, with the `csv` crate: regular files under a size limit, a
//! header row or none, columns by name or 1-based index, every number
//! finite, times strictly increasing, and every error naming the file, the
//! row (its line in the file) and the column.

use std::fmt;
use std::io::Read;
use std::path::Path;

use serde::Deserialize;
use serde::de::{self, Visitor};

/// Most samples a CSV file may hold.
pub const MAX_SAMPLES: usize = 10_000_000;
/// Largest CSV file, in bytes.
pub const MAX_CSV_BYTES: u64 = 1 << 30;
/// Highest 1-based column index accepted.
pub const MAX_COLUMN: i64 = 10_000;

/// A CSV file that could not be read as samples: the file, the row (line
/// in the file) and the column where known, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct RecordError {
    /// The file, as named.
    pub file: String,
    /// Line of the file, from 1.
    pub row: Option<usize>,
    /// Column, from 1.
    pub column: Option<usize>,
    /// What is wrong.
    pub what: String,
}

impl fmt::Display for RecordError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.file)?;
        if let Some(r) = self.row {
            write!(f, ": row {r}")?;
        }
        if let Some(c) = self.column {
            write!(f, ", column {c}")?;
        }
        write!(f, ": {}", self.what)
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

/// Why a file could not be read whole.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// Opening or reading failed.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// Not a regular file (a directory, a pipe, a device).
    #[error("not a regular file")]
    NotRegular,
    /// Larger than the limit.
    #[error("{size} bytes, more than the limit of {limit}")]
    TooLarge {
        /// Size in bytes (the limit plus one when the file grew while
        /// being read).
        size: u64,
        /// The limit.
        limit: u64,
    },
    /// Not UTF-8 text.
    #[error("cannot read: not UTF-8 text (byte {0} is not valid)")]
    NotUtf8(usize),
}

/// The text of the file at `path`: only a regular file (a pipe or a
/// device could block or never end) of at most `limit` bytes, checked
/// before it is opened and again while it is read; UTF-8. The one way a
/// scene, a campaign and a CSV record are read.
pub fn read_limited(path: &Path, limit: u64) -> Result<String, ReadError> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular);
    }
    if meta.len() > limit {
        return Err(ReadError::TooLarge {
            size: meta.len(),
            limit,
        });
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge {
            size: bytes.len() as u64,
            limit,
        });
    }
    String::from_utf8(bytes).map_err(|e| ReadError::NotUtf8(e.utf8_error().valid_up_to()))
}

/// Reads a CSV file named `file` relative to `dir`: only a regular file of
/// at most [`MAX_CSV_BYTES`] (a device or a pipe could block or never
/// end); with `confine`, the file must be inside `dir` once links and `..`
/// are resolved (`folder` says whose folder `dir` is, for the message).
/// Returns the path as shown in messages and the text.
pub fn read_file(
    dir: &Path,
    file: &str,
    confine: bool,
    folder: &str,
) -> Result<(String, String), RecordError> {
    let path = dir.join(file);
    let name = path.display().to_string();
    let fail = |what: String| RecordError {
        file: name.clone(),
        row: None,
        column: None,
        what,
    };
    let cannot = |e: std::io::Error| fail(format!("cannot read: {e}"));
    if file.trim().is_empty() {
        return Err(fail("no file named".into()));
    }
    if confine {
        let base = dir
            .canonicalize()
            .or_else(|_| Path::new(".").canonicalize())
            .map_err(cannot)?;
        let real = path.canonicalize().map_err(cannot)?;
        if !real.starts_with(&base) {
            return Err(RecordError {
                file: shown(file),
                ..fail(format!("outside {folder}, which --confine forbids"))
            });
        }
    }
    let text = read_limited(&path, MAX_CSV_BYTES).map_err(|e| fail(e.to_string()))?;
    Ok((name, text))
}

/// Checks a column as written: an index from 1 to [`MAX_COLUMN`], or a
/// name that is not empty; `name` is the key it was given under.
pub fn check_column<'a>(name: &str, c: &'a Column) -> Result<&'a Column, String> {
    match c {
        Column::Index(i) if !(1..=MAX_COLUMN).contains(i) => Err(format!(
            "{name} = {i}: column indices count from 1 to {MAX_COLUMN}"
        )),
        Column::Name(n) if n.trim().is_empty() => Err(format!("{name}: empty column name")),
        _ => Ok(c),
    }
}

/// Where the times of a record come from.
#[derive(Debug, Clone, Copy)]
pub enum Time<'a> {
    /// A time column in s.
    Column(&'a Column),
    /// A sampling rate in Hz (the first row at 0).
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
pub fn shown(field: &str) -> String {
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

/// Reads samples from CSV text with the `csv` crate: for each data row,
/// the time and the value of each of `columns` (`(key, column)`, the key
/// naming the column in messages); `name` names the file in errors, whose
/// rows are the file's lines counted from 1.
///
/// Fields are separated by commas, or by semicolons or tabs when the first
/// row has no comma, and may be quoted; blank lines and lines starting with
/// `#` are skipped; the first row is a header when one of its fields is not
/// a number. Times must increase strictly and are shifted to start at 0.
/// At least 2 and at most [`MAX_SAMPLES`] rows.
pub fn read_table<const N: usize>(
    name: &str,
    text: &str,
    columns: [(&str, &Column); N],
    time: Time<'_>,
) -> Result<Vec<(f64, [f64; N])>, RecordError> {
    let at = |row: Option<usize>, column: Option<usize>, what: String| RecordError {
        file: name.to_string(),
        row,
        column,
        what,
    };
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
        Err(e) => Some(Err(at(None, None, e.to_string()))),
    });
    let Some((first_line, first)) = rows.next().transpose()? else {
        return Err(at(None, None, "no rows".into()));
    };
    let header: Option<Vec<String>> = first
        .iter()
        .any(|f| clean(f).parse::<f64>().is_err())
        .then(|| first.iter().map(|f| clean(f).to_string()).collect());
    let find = |label: &str, c: &Column| -> Result<usize, RecordError> {
        match c {
            Column::Index(i) => Ok(usize::try_from(*i).unwrap_or(1).saturating_sub(1)),
            Column::Name(n) => {
                let Some(h) = &header else {
                    return Err(at(
                        None,
                        None,
                        format!(
                            "{label} '{n}' needs a header row, but row {first_line} is all numbers"
                        ),
                    ));
                };
                h.iter().position(|f| f == n.trim()).ok_or_else(|| {
                    at(
                        Some(first_line),
                        None,
                        format!(
                            "no column named '{n}' for {label} (the header has {})",
                            h.iter()
                                .map(|f| format!("'{}'", shown(f)))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                })
            }
        }
    };
    let mut value_cols = [0usize; N];
    for (slot, (label, c)) in value_cols.iter_mut().zip(columns) {
        *slot = find(label, c)?;
    }
    let t_col = match time {
        Time::Column(c) => Some(find("time_column", c)?),
        Time::Rate(_) => None,
    };
    let number = |line: usize, fields: &csv::StringRecord, c: usize| -> Result<f64, RecordError> {
        let Some(f) = fields.get(c).map(clean) else {
            return Err(at(
                Some(line),
                Some(c + 1),
                format!("missing (the row has {} columns)", fields.len()),
            ));
        };
        match f.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(at(
                Some(line),
                Some(c + 1),
                format!("expected a finite number, got '{}'", shown(f)),
            )),
            Err(_) => Err(at(
                Some(line),
                Some(c + 1),
                format!("expected a number, got '{}'", shown(f)),
            )),
        }
    };
    let data = header
        .is_none()
        .then_some(Ok((first_line, first)))
        .into_iter()
        .chain(rows);
    let mut samples: Vec<(f64, [f64; N])> = Vec::new();
    let mut start = 0.0;
    let mut previous = (0usize, 0.0f64);
    for row in data {
        let (line, fields) = row?;
        let mut values = [0.0; N];
        for (v, &c) in values.iter_mut().zip(&value_cols) {
            *v = number(line, &fields, c)?;
        }
        let t = match (t_col, time) {
            (Some(c), _) => {
                let raw = number(line, &fields, c)?;
                if samples.is_empty() {
                    start = raw;
                }
                let t = raw - start;
                if !samples.is_empty() && t <= previous.1 {
                    return Err(at(
                        Some(line),
                        Some(c + 1),
                        format!(
                            "time {} s is not after the {} s of row {}",
                            num(raw),
                            num(previous.1 + start),
                            previous.0
                        ),
                    ));
                }
                if !t.is_finite() {
                    return Err(at(
                        Some(line),
                        Some(c + 1),
                        format!(
                            "time {} s is too far from the first row's {} s",
                            num(raw),
                            num(start)
                        ),
                    ));
                }
                t
            }
            (None, Time::Rate(r)) => samples.len() as f64 / r,
            (None, Time::Column(_)) => samples.len() as f64,
        };
        if samples.len() >= MAX_SAMPLES {
            return Err(at(
                Some(line),
                None,
                format!("more than the limit of {MAX_SAMPLES} samples"),
            ));
        }
        samples.push((t, values));
        previous = (line, t);
    }
    if samples.len() < 2 {
        return Err(at(
            None,
            None,
            format!("{} data rows, at least 2 needed", samples.len()),
        ));
    }
    Ok(samples)
}
