//! `trace.csv`: one row per `trace_every` steps and the last, written with
//! the `csv` crate. The numbers keep the form they have always had (time
//! with 9 decimals, the rest in shortest exponent form), so traces compare
//! byte for byte across versions.

use std::fmt::Write as _;

use bushing::Real;

use super::RunError;
use super::pipeline::{Sink, Step};
use crate::output::{OutputError, OutputFile as File};

/// Writes the trace rows.
pub struct TraceSink {
    csv: csv::Writer<File>,
    record: csv::ByteRecord,
    field: String,
    every: u64,
    last: u64,
    effects: usize,
    oscillator: bool,
    energy: f64,
}

/// The name of an effect's trace column, without the `_N` suffix.
pub fn column_name(effect: &str) -> String {
    effect.replace([' ', ','], "_")
}

/// Bytes a trace row can take at most: the time, then the other columns
/// in exponent form (sign, 17 digits, point, exponent).
pub fn row_bytes(effects: usize, oscillator: bool) -> u64 {
    let columns = 4 + effects as u64 + u64::from(oscillator);
    16 + 25 * columns
}

impl TraceSink {
    /// Writes the header into `file`.
    pub fn new(
        file: File,
        names: &[String],
        oscillator: bool,
        every: u64,
        steps: u64,
    ) -> Result<Self, RunError> {
        let csv = csv::WriterBuilder::new().from_writer(file);
        let mut header = vec![
            "time_s".to_string(),
            "x_mm".into(),
            "force_N".into(),
            "elastic_N".into(),
        ];
        header.extend(names.iter().map(|n| format!("{}_N", column_name(n))));
        header.push("dissipated_mJ".into());
        // In an oscillator scene the profile is the applied force.
        if oscillator {
            header.push("applied_N".into());
        }
        let mut sink = Self {
            csv,
            record: csv::ByteRecord::new(),
            field: String::new(),
            every: every.max(1),
            last: steps,
            effects: names.len(),
            oscillator,
            energy: 0.0,
        };
        sink.csv.write_record(&header).map_err(|e| sink.error(e))?;
        Ok(sink)
    }

    fn error(&self, e: csv::Error) -> RunError {
        let path = self.csv.get_ref().path().to_path_buf();
        let source = match e.into_kind() {
            csv::ErrorKind::Io(io) => io,
            other => std::io::Error::other(format!("{other:?}")),
        };
        RunError::Output(OutputError::Io { path, source })
    }

    fn push(&mut self, args: std::fmt::Arguments<'_>) {
        self.field.clear();
        let _ = self.field.write_fmt(args);
        self.record.push_field(self.field.as_bytes());
    }

    /// Flushes and syncs the file.
    pub fn finish(self) -> Result<(), RunError> {
        let path = self.csv.get_ref().path().to_path_buf();
        let file = self.csv.into_inner().map_err(|e| {
            RunError::Output(OutputError::Io {
                path,
                source: std::io::Error::other(e.to_string()),
            })
        })?;
        file.finish().map_err(RunError::Output)
    }
}

impl<T: Real> Sink<T> for TraceSink {
    fn step(&mut self, s: &Step<'_, T>) -> Result<(), RunError> {
        self.energy += s.row.dissipated.to_f64();
        if !(s.index.is_multiple_of(self.every) || s.index == self.last) {
            return Ok(());
        }
        self.record.clear();
        let (t, x, f, elastic) = (
            s.time,
            s.row.x.to_f64(),
            s.row.force.to_f64(),
            s.row.elastic.to_f64(),
        );
        self.push(format_args!("{t:.9}"));
        self.push(format_args!("{x:e}"));
        self.push(format_args!("{f:e}"));
        self.push(format_args!("{elastic:e}"));
        if s.row.refused {
            for _ in 0..self.effects {
                self.record.push_field(b"nan");
            }
        } else {
            for e in s.parts {
                self.push(format_args!("{:e}", e.force.to_f64()));
            }
        }
        let energy = self.energy;
        self.push(format_args!("{energy:e}"));
        if self.oscillator {
            self.push(format_args!("{:e}", s.input.to_f64()));
        }
        let record = std::mem::take(&mut self.record);
        let written = self.csv.write_byte_record(&record);
        self.record = record;
        written.map_err(|e| self.error(e))
    }
}
