//! `compare-trace`: a firmware's logged force trace against a host trace.
//!
//! A rig (or a firmware with a simulated sensor) reads its displacement
//! through an ADC and steps the bushing in its own number type; it logs
//!
//! ```text
//! rig-loop number=f32 lsb_mm=0.000244140625 rate_hz=2000 [key=value ...]
//! step 1 12 3f800000
//! step 2 25 40000000
//! ```
//!
//! one header, then one line per control step: the step index from 1, the
//! signed ADC code and the force as 8 lowercase hex digits, the bits of an
//! `f32` (`number=f32`) or the two's-complement bits of a Q16.16 value
//! (`number=q16`, force = bits / 65536). Other lines are ignored. Step i
//! is the i-th data row of a `trace.csv` that `bushing-sim run` wrote with
//! `trace_every = 1` (time i / rate_hz).
//!
//! Every step's `code * lsb_mm` must equal the trace's `x_mm` exactly (the
//! two read the same displacement), and the force must be bit-identical
//! (the `f32` widened to `f64` against the trace's `force_N`, which
//! `{:e}` writes so that it reads back exactly) or, with a bound, within
//! that many newtons.

use std::fmt;

/// The number type of a firmware's force.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirmwareNumber {
    /// `f32`: the hex digits are its bits.
    F32,
    /// Q16.16 fixed point: the hex digits are the raw `i32` bits.
    Q16,
}

impl FirmwareNumber {
    /// Name as in the log header.
    pub fn name(self) -> &'static str {
        match self {
            Self::F32 => "f32",
            Self::Q16 => "q16",
        }
    }

    /// The force, in N, that the 32 bits of a step line stand for.
    pub fn decode(self, bits: u32) -> f64 {
        match self {
            Self::F32 => f64::from(f32::from_bits(bits)),
            Self::Q16 => f64::from(bits.cast_signed()) / 65536.0,
        }
    }
}

/// The `rig-loop` header of a firmware log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogHeader {
    /// Number type of the logged forces.
    pub number: FirmwareNumber,
    /// Step of one ADC code, mm.
    pub lsb_mm: f64,
    /// Control rate, Hz.
    pub rate_hz: f64,
}

/// One `step` line of a firmware log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LogStep {
    /// Line of the log, from 1.
    pub line: usize,
    /// Step index as logged (from 1).
    pub index: u64,
    /// ADC code.
    pub code: i64,
    /// The force's 32 bits.
    pub bits: u32,
}

/// A firmware log: its header and its step lines, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct FirmwareLog {
    /// The header.
    pub header: LogHeader,
    /// The steps.
    pub steps: Vec<LogStep>,
}

/// Why a firmware log and a host trace cannot be compared.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A mistake in a file.
    #[error("{at}: {what}")]
    Format {
        /// `file:line`, or the file.
        at: String,
        /// What is wrong.
        what: String,
    },
    /// The two files do not describe the same run.
    #[error("{0}")]
    Mismatch(String),
    /// A bound that is not a finite number of newtons >= 0.
    #[error("--within must be a finite number >= 0 N, got {0}")]
    Bound(f64),
}

fn format_error(at: impl Into<String>, what: impl Into<String>) -> CompareError {
    CompareError::Format {
        at: at.into(),
        what: what.into(),
    }
}

/// Reads a firmware log; `name` names it in errors. Lines that are neither
/// the header nor a step line are ignored.
pub fn parse_log(name: &str, text: &str) -> Result<FirmwareLog, CompareError> {
    let mut header: Option<(usize, LogHeader)> = None;
    let mut steps = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("rig-loop") => {
                if let Some((first, _)) = header {
                    return Err(format_error(
                        format!("{name}:{line}"),
                        format!("a second rig-loop header (the first is on line {first})"),
                    ));
                }
                let h = parse_header(words).map_err(|m| {
                    format_error(format!("{name}:{line}"), format!("rig-loop: {m}"))
                })?;
                header = Some((line, h));
            }
            Some("step") => {
                if let Some(step) = parse_step(line, words) {
                    steps.push(step);
                }
            }
            _ => {}
        }
    }
    let Some((_, header)) = header else {
        return Err(format_error(
            name,
            "no header line `rig-loop number=<f32|q16> lsb_mm=<float> rate_hz=<float>`",
        ));
    };
    Ok(FirmwareLog { header, steps })
}

fn parse_header<'a>(words: impl Iterator<Item = &'a str>) -> Result<LogHeader, String> {
    let (mut number, mut lsb, mut rate) = (None, None, None);
    for word in words {
        let Some((key, value)) = word.split_once('=') else {
            return Err(format!("field '{word}' is not key=value"));
        };
        let positive = |v: &str| match v.parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
            _ => Err(format!("{key} must be a finite number > 0, got '{v}'")),
        };
        match key {
            "number" => {
                number = Some(match value {
                    "f32" => FirmwareNumber::F32,
                    "q16" => FirmwareNumber::Q16,
                    other => return Err(format!("number '{other}' is not one of f32, q16")),
                });
            }
            "lsb_mm" => lsb = Some(positive(value)?),
            "rate_hz" => rate = Some(positive(value)?),
            _ => {}
        }
    }
    match (number, lsb, rate) {
        (Some(number), Some(lsb_mm), Some(rate_hz)) => Ok(LogHeader {
            number,
            lsb_mm,
            rate_hz,
        }),
        _ => Err("needs number=<f32|q16>, lsb_mm=<float> and rate_hz=<float>".into()),
    }
}

/// A step line `step <i> <x_code> <force_hex>`, or `None` if the line does
/// not have that form.
fn parse_step<'a>(line: usize, mut words: impl Iterator<Item = &'a str>) -> Option<LogStep> {
    let index = words.next()?.parse::<u64>().ok()?;
    let code = words.next()?.parse::<i64>().ok()?;
    let hex = words.next()?;
    if words.next().is_some()
        || hex.len() != 8
        || !hex.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
    {
        return None;
    }
    let bits = u32::from_str_radix(hex, 16).ok()?;
    Some(LogStep {
        line,
        index,
        code,
        bits,
    })
}

/// One data row of a host trace.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceRow {
    /// Line of the file, from 1.
    pub line: usize,
    /// `time_s`.
    pub time_s: f64,
    /// `x_mm`.
    pub x_mm: f64,
    /// `force_N`.
    pub force_n: f64,
}

/// Reads the `time_s`, `x_mm` and `force_N` columns of a `trace.csv`
/// with the `csv` crate; `name` names it in errors (with the file's line).
pub fn parse_trace(name: &str, text: &str) -> Result<Vec<TraceRow>, CompareError> {
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let header = reader
        .headers()
        .map_err(|e| format_error(name, e.to_string()))?
        .clone();
    if header.is_empty() {
        return Err(format_error(name, "empty file (no header row)"));
    }
    let find = |c: &str| {
        header.iter().position(|h| h == c).ok_or_else(|| {
            let shown: Vec<&str> = header.iter().collect();
            format_error(
                format!("{name}:1"),
                format!(
                    "no column '{c}' (the header has {}): not a bushing-sim trace",
                    shown.join(",")
                ),
            )
        })
    };
    let (t, x, f) = (find("time_s")?, find("x_mm")?, find("force_N")?);
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| format_error(name, e.to_string()))?;
        let line = record.position().map_or(0, |p| p.line() as usize);
        if record.iter().all(str::is_empty) {
            continue;
        }
        let cell = |i: usize, c: &str| {
            let at = format!("{name}:{line}");
            let v = record.get(i).ok_or_else(|| {
                format_error(&at, format!("no {c} (the row has {} cells)", record.len()))
            })?;
            v.parse::<f64>().map_err(|_| {
                let v: String = v.chars().take(40).flat_map(char::escape_debug).collect();
                format_error(&at, format!("{c}: expected a number, got '{v}'"))
            })
        };
        rows.push(TraceRow {
            line,
            time_s: cell(t, "time_s")?,
            x_mm: cell(x, "x_mm")?,
            force_n: cell(f, "force_N")?,
        });
    }
    Ok(rows)
}

/// The first step where the firmware and the host disagree.
#[derive(Debug, Clone, PartialEq)]
pub struct Mismatch {
    /// Step index, from 1.
    pub step: u64,
    /// Time of the step, s.
    pub time_s: f64,
    /// What differs.
    pub what: String,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "step {} (t = {} s): {}",
            self.step, self.time_s, self.what
        )
    }
}

/// What a comparison found.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The log's header.
    pub header: LogHeader,
    /// The bound on |error| in N, or `None` for bit-identical forces.
    pub within: Option<f64>,
    /// Steps compared.
    pub steps: u64,
    /// Steps whose forces are identical (as f64; two NaN count as equal).
    pub identical: u64,
    /// Largest |firmware - host| force in N (NaN if one side is NaN where
    /// the other is not), with its step; step 0 when there are no steps.
    pub max_error: (f64, u64),
    /// RMS of the force error over the steps, N (over the finite errors).
    pub rms_error: f64,
    /// Largest |host force|, N.
    pub peak_host: f64,
    /// The first step that fails a check.
    pub first_mismatch: Option<Mismatch>,
}

impl Comparison {
    /// Whether every step passed.
    pub fn passed(&self) -> bool {
        self.first_mismatch.is_none()
    }
}

impl fmt::Display for Comparison {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let h = &self.header;
        writeln!(
            f,
            "firmware       number={} lsb_mm={} rate_hz={}",
            h.number.name(),
            h.lsb_mm,
            h.rate_hz
        )?;
        writeln!(f, "steps compared {}", self.steps)?;
        let identical = if self.identical == self.steps {
            "yes, every force".to_string()
        } else {
            format!("no: {} of {} forces", self.identical, self.steps)
        };
        writeln!(f, "identical      {identical}")?;
        let (e, step) = self.max_error;
        writeln!(
            f,
            "max |error|    {e:.6e} N at step {step} (t = {} s)",
            step as f64 / h.rate_hz
        )?;
        writeln!(f, "rms error      {:.6e} N", self.rms_error)?;
        writeln!(f, "peak |host|    {:.6e} N", self.peak_host)?;
        let check = match self.within {
            None => "bit-identical forces".to_string(),
            Some(n) => format!("|error| <= {n} N"),
        };
        match &self.first_mismatch {
            None => writeln!(
                f,
                "result         pass ({check}, x = code * lsb_mm exactly)"
            ),
            Some(m) => writeln!(f, "result         FAIL ({check}): first at {m}"),
        }
    }
}

/// Compares a firmware log with a host trace, step by step. `within` is
/// the bound on |error| in N, `None` for bit-identical forces. An `Err`
/// is a file that cannot be compared (unreadable, a step missing or out of
/// order, step and row counts that differ); a failed check is the
/// [`Comparison`]'s `first_mismatch`.
pub fn compare(
    trace: &[TraceRow],
    log: &FirmwareLog,
    within: Option<f64>,
) -> Result<Comparison, CompareError> {
    if let Some(n) = within
        && !(n.is_finite() && n >= 0.0)
    {
        return Err(CompareError::Bound(n));
    }
    let h = log.header;
    for (k, s) in log.steps.iter().enumerate() {
        let expected = k as u64 + 1;
        if s.index != expected {
            let what = if s.index < expected {
                format!("step {} again or out of order", s.index)
            } else {
                format!("step {expected} missing")
            };
            return Err(format_error(
                format!("firmware log line {}", s.line),
                format!(
                    "step {} where step {expected} is expected ({what}): steps must be consecutive from 1",
                    s.index
                ),
            ));
        }
    }
    if log.steps.len() != trace.len() {
        return Err(CompareError::Mismatch(format!(
            "the firmware log has {} steps and the trace {} rows: they must be equal \
             (a trace written with trace_every = 1 over the same profile)",
            log.steps.len(),
            trace.len()
        )));
    }
    let mut c = Comparison {
        header: h,
        within,
        steps: 0,
        identical: 0,
        max_error: (f64::NEG_INFINITY, 0),
        rms_error: 0.0,
        peak_host: 0.0,
        first_mismatch: None,
    };
    let mut squares = 0.0f64;
    let mut finite = 0u64;
    for (s, row) in log.steps.iter().zip(trace) {
        let i = s.index;
        let t = i as f64 / h.rate_hz;
        let mut fail = |what: String| {
            if c.first_mismatch.is_none() {
                c.first_mismatch = Some(Mismatch {
                    step: i,
                    time_s: t,
                    what,
                });
            }
        };
        // The row is the step's: trace_every = 1 at the same rate.
        if (row.time_s - t).abs() > 1e-9 + 1e-12 * t.abs() {
            fail(format!(
                "trace line {} is at time_s = {} s, the step at i / rate_hz = {t} s \
                 (a trace written with trace_every = 1 at rate_hz = {}?)",
                row.line, row.time_s, h.rate_hz
            ));
        }
        let x = s.code as f64 * h.lsb_mm;
        if x != row.x_mm {
            fail(format!(
                "x_code {} * lsb_mm {} = {x:e} mm, the trace's x_mm = {:e} mm (line {})",
                s.code, h.lsb_mm, row.x_mm, row.line
            ));
        }
        let fw = h.number.decode(s.bits);
        let host = row.force_n;
        c.peak_host = c.peak_host.max(host.abs());
        let both_nan = fw.is_nan() && host.is_nan();
        let same = both_nan || fw.to_bits() == host.to_bits();
        if same {
            c.identical += 1;
        }
        let error = if both_nan { 0.0 } else { (fw - host).abs() };
        if error.is_finite() {
            squares += error * error;
            finite += 1;
        }
        // The first largest; a NaN error (one side NaN) is the largest.
        if !c.max_error.0.is_nan() && (error.is_nan() || error > c.max_error.0) {
            c.max_error = (error, i);
        }
        let ok = match within {
            None => same,
            Some(n) => error <= n,
        };
        if !ok {
            let hex = format!("{:08x}", s.bits);
            fail(match within {
                None => format!(
                    "force {fw:e} N (0x{hex}, {}) differs from the host's {host:e} N by {error:e} N (log line {}, trace line {})",
                    h.number.name(),
                    s.line,
                    row.line
                ),
                Some(n) => format!(
                    "|force error| {error:e} N exceeds {n} N: firmware {fw:e} N (0x{hex}, {}), host {host:e} N (log line {}, trace line {})",
                    h.number.name(),
                    s.line,
                    row.line
                ),
            });
        }
        c.steps += 1;
    }
    if c.steps == 0 {
        c.max_error = (0.0, 0);
    }
    c.rms_error = if finite == 0 {
        0.0
    } else {
        (squares / finite as f64).sqrt()
    };
    Ok(c)
}

/// `compare-trace HOST_TRACE.csv FIRMWARE.log [--within N]`: reads both
/// files and compares them. The caller prints the comparison and fails if
/// it did not pass.
pub fn compare_files(
    trace_file: &std::path::Path,
    log_file: &std::path::Path,
    within: Option<f64>,
) -> Result<Comparison, CompareError> {
    if let Some(n) = within
        && !(n.is_finite() && n >= 0.0)
    {
        return Err(CompareError::Bound(n));
    }
    let read = |f: &std::path::Path| {
        std::fs::read_to_string(f).map_err(|source| CompareError::Read {
            path: f.to_path_buf(),
            source,
        })
    };
    let trace = parse_trace(&trace_file.display().to_string(), &read(trace_file)?)?;
    let log = parse_log(&log_file.display().to_string(), &read(log_file)?)?;
    compare(&trace, &log, within)
}

#[cfg(test)]
mod tests {
    use super::*;

    const LSB: f64 = 1.0 / 4096.0;

    /// A host trace and the f32 firmware log that matches it bit for bit.
    fn pair(forces: &[f32], codes: &[i64]) -> (String, String) {
        let mut trace = String::from("time_s,x_mm,force_N,elastic_N,dissipated_mJ\n");
        let mut log = String::from(
            "boot ok\nrig-loop number=f32 lsb_mm=0.000244140625 rate_hz=1000 build=abc\n",
        );
        for (k, (&f, &c)) in forces.iter().zip(codes).enumerate() {
            let i = k + 1;
            let t = i as f64 * (1.0 / 1000.0);
            let x = c as f64 * LSB;
            let fh = f64::from(f);
            trace.push_str(&format!("{t:.9},{x:e},{fh:e},{fh:e},0e0\n"));
            log.push_str(&format!("step {i} {c} {:08x}\n", f.to_bits()));
        }
        log.push_str("done\n");
        (trace, log)
    }

    fn run(trace: &str, log: &str, within: Option<f64>) -> Result<Comparison, CompareError> {
        let t = parse_trace("trace.csv", trace)?;
        let l = parse_log("fw.log", log)?;
        compare(&t, &l, within)
    }

    const FORCES: [f32; 4] = [0.1, -2.5e3, 1.0e-7, 17.25];
    const CODES: [i64; 4] = [1, -409, 0, 32767];

    #[test]
    fn an_identical_trace_passes() {
        let (trace, log) = pair(&FORCES, &CODES);
        let c = run(&trace, &log, None).unwrap();
        assert!(c.passed(), "{c}");
        assert_eq!((c.steps, c.identical), (4, 4));
        assert_eq!(c.max_error, (0.0, 1));
        assert_eq!(c.rms_error, 0.0);
        assert_eq!(c.peak_host, 2500.0);
        assert_eq!(c.header.number, FirmwareNumber::F32);
        assert!(c.to_string().contains("identical      yes"), "{c}");
    }

    #[test]
    fn one_ulp_fails_exactly_and_passes_within_a_bound() {
        let (trace, _) = pair(&FORCES, &CODES);
        let mut off = FORCES;
        off[2] = f32::from_bits(off[2].to_bits() + 1);
        let (_, log) = pair(&off, &CODES);
        let c = run(&trace, &log, None).unwrap();
        let m = c.first_mismatch.clone().unwrap();
        assert_eq!(m.step, 3);
        assert!((m.time_s - 0.003).abs() < 1e-15);
        assert!(m.what.contains("differs from the host's"), "{m}");
        assert_eq!(c.identical, 3);
        let ulp = f64::from(off[2]) - f64::from(FORCES[2]);
        assert_eq!(c.max_error, (ulp, 3));
        assert!(c.rms_error > 0.0 && c.rms_error < ulp);
        let c = run(&trace, &log, Some(1e-9)).unwrap();
        assert!(c.passed(), "{c}");
        assert_eq!(c.identical, 3);
        let c = run(&trace, &log, Some(ulp / 2.0)).unwrap();
        assert!(c.first_mismatch.unwrap().what.contains("exceeds"));
    }

    #[test]
    fn a_missing_step_fails() {
        let (trace, log) = pair(&FORCES, &CODES);
        let gap: String = log
            .lines()
            .filter(|l| !l.starts_with("step 2 "))
            .map(|l| format!("{l}\n"))
            .collect();
        let e = run(&trace, &gap, None).unwrap_err().to_string();
        assert!(
            e.contains("line 4: step 3 where step 2 is expected (step 2 missing)"),
            "{e}"
        );
        // The last step missing: the counts differ.
        let short: String = log
            .lines()
            .filter(|l| !l.starts_with("step 4 "))
            .map(|l| format!("{l}\n"))
            .collect();
        let e = run(&trace, &short, None).unwrap_err().to_string();
        assert!(e.contains("3 steps and the trace 4 rows"), "{e}");
        // A duplicated step.
        let twice = log.replace("step 2 ", "step 1 ");
        let e = run(&trace, &twice, None).unwrap_err().to_string();
        assert!(e.contains("step 1 again or out of order"), "{e}");
    }

    #[test]
    fn an_x_mismatch_fails() {
        let (trace, _) = pair(&FORCES, &CODES);
        let mut codes = CODES;
        codes[1] += 1;
        let (_, log) = pair(&FORCES, &codes);
        for within in [None, Some(1.0)] {
            let c = run(&trace, &log, within).unwrap();
            let m = c.first_mismatch.unwrap();
            assert_eq!(m.step, 2);
            assert!(m.what.starts_with("x_code -408 * lsb_mm"), "{m}");
        }
    }

    #[test]
    fn q16_decodes_twos_complement() {
        assert_eq!(FirmwareNumber::Q16.decode(0xfffe_8000), -1.5);
        assert_eq!(FirmwareNumber::Q16.decode(0x0001_0000), 1.0);
        assert_eq!(FirmwareNumber::Q16.decode(0x8000_0000), -32768.0);
        assert_eq!(FirmwareNumber::F32.decode(0xbfc0_0000), -1.5);
        let log = "rig-loop rate_hz=1000 number=q16 lsb_mm=0.5\nstep 1 -3 fffe8000\n";
        let trace = "time_s,x_mm,force_N\n0.001000000,-1.5e0,-1.5e0\n";
        let c = run(trace, log, None).unwrap();
        assert!(c.passed(), "{c}");
        assert_eq!(c.header.number, FirmwareNumber::Q16);
    }

    #[test]
    fn other_lines_are_ignored_and_bad_headers_refused() {
        let l = parse_log(
            "fw.log",
            "hello\nstep x 1 00000000\nstep 1 2 0000000G\nstep 1 2 3 4\nrig-loop number=f32 lsb_mm=1 rate_hz=10\nstep 1 2 00000000\n",
        )
        .unwrap();
        assert_eq!(l.steps.len(), 1);
        assert_eq!(l.steps[0].line, 6);
        let e = parse_log("fw.log", "step 1 0 00000000\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("fw.log: no header line"), "{e}");
        let e = parse_log("fw.log", "rig-loop number=f16 lsb_mm=1 rate_hz=1\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "fw.log:1: rig-loop: number 'f16' is not one of f32, q16");
        let e = parse_log("fw.log", "rig-loop number=f32 lsb_mm=0 rate_hz=1\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("lsb_mm must be a finite number > 0, got '0'"),
            "{e}"
        );
        let e = parse_log("fw.log", "rig-loop number=f32 rate_hz=1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("needs number"), "{e}");
        let e = parse_trace("t.csv", "time_s,x_mm\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no column 'force_N'"), "{e}");
    }

    #[test]
    fn a_trace_of_another_rate_or_stride_is_refused() {
        let (trace, log) = pair(&FORCES, &CODES);
        let other = log.replace("rate_hz=1000", "rate_hz=500");
        let c = run(&trace, &other, None).unwrap();
        assert!(
            c.first_mismatch.unwrap().what.contains("trace_every = 1"),
            "{trace}"
        );
    }
}
