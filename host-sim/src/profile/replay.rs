//! `replay`: a measured displacement read from a CSV file, linearly
//! interpolated onto the scene's step.

use std::path::Path;

use serde::Deserialize;

use super::check::finite_positive;
use super::{Profile, ProfileSpec};
pub use crate::records::Column;
use crate::records::{Time, check_column, read_file, read_table};

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
    /// A measured force column in N (name or 1-based index): `run`
    /// overlays it on its force plots and reports the model's RMS
    /// residual against it.
    #[serde(default)]
    pub force_column: Option<Column>,
    /// The samples (time from the first sample in s, displacement in
    /// mm), read from `file` when the scene is loaded.
    #[serde(skip)]
    pub samples: Vec<(f64, f64)>,
    /// The measured force at the same times (N), when `force_column` is
    /// given.
    #[serde(skip)]
    pub measured: Vec<(f64, f64)>,
}

impl Replay {
    /// The measured force at `t` (s), linearly interpolated, when the
    /// replay has a force column.
    pub fn measured_force(&self, t: f64) -> Option<f64> {
        (!self.measured.is_empty()).then(|| interpolate(&self.measured, t))
    }
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
        force_column,
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
        (Some(c), None) => Time::Column(check_column("time_column", c)?),
        (None, Some(r)) => {
            finite_positive("rate_hz", r)?;
            Time::Rate(r)
        }
    };
    check_column("column", &column)?;
    if file.trim().is_empty() {
        return Err("file must name a CSV file".into());
    }
    let replay_file = |e: crate::records::RecordError| format!("replay file {e}");
    let (name, text) = read_file(dir, &file, confine, "the scene's folder").map_err(replay_file)?;
    let (samples, measured) = match &force_column {
        None => (
            read_csv(&name, &text, &column, time).map_err(|e| e.to_string())?,
            Vec::new(),
        ),
        Some(f) => {
            check_column("force_column", f)?;
            let rows = read_table(
                &name,
                &text,
                [("column", &column), ("force_column", f)],
                time,
            )
            .map_err(|e| e.to_string())?;
            rows.into_iter()
                .map(|(t, [x, force])| ((t, x), (t, force)))
                .unzip()
        }
    };
    Ok(ProfileSpec::Replay(Replay {
        file,
        column,
        time_column,
        rate_hz,
        force_column,
        samples,
        measured,
    }))
}

/// (time, displacement) samples of `column` ([`read_table`]).
pub(super) fn read_csv(
    name: &str,
    text: &str,
    column: &Column,
    time: Time<'_>,
) -> Result<Vec<(f64, f64)>, crate::records::RecordError> {
    let rows = read_table(name, text, [("column", column)], time)?;
    Ok(rows.into_iter().map(|(t, [x])| (t, x)).collect())
}
