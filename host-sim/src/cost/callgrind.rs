//! The harness of every host instruction count: this program started
//! again under valgrind's callgrind, on one of its hidden part commands
//! (`cost-part`, `accuracy-cost-part`), counting instructions only inside
//! the named stepping function.
//!
//! Callgrind writes its dumps into a fresh temporary directory (created
//! with an unpredictable name, removed when the count is read or fails);
//! nothing is left behind and no existing directory is reused.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};

/// What went wrong while counting.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// This program's own path is unknown (it is started again under
    /// valgrind).
    #[error("cannot find this program: {0}")]
    CurrentExe(#[source] std::io::Error),
    /// The temporary directory for the dumps could not be created.
    #[error("cannot create a temporary directory for callgrind's dumps: {0}")]
    TempDir(#[source] std::io::Error),
    /// `valgrind` could not be started.
    #[error("cannot start valgrind (is it installed?): {0}")]
    Start(#[source] std::io::Error),
    /// valgrind, or the program under it, failed.
    #[error("valgrind on `{command}` failed: {status}")]
    Failed {
        /// The part command given to this program.
        command: String,
        /// valgrind's exit status.
        status: ExitStatus,
    },
    /// A dump could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The dump.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A dump has no `totals:` or `summary:` line.
    #[error("{}: no instruction total", path.display())]
    NoTotal {
        /// The dump.
        path: PathBuf,
    },
}

/// What one run under callgrind gave.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Counts {
    /// The child's standard output.
    pub stdout: String,
    /// Instructions counted in each dump, in order: one per return from
    /// the `dump_after` function, else the single dump of the run.
    pub totals: Vec<u64>,
}

/// Whether `valgrind` can be started.
pub fn available() -> bool {
    Command::new("valgrind")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Runs this program with `args` under callgrind, counting instructions
/// only inside functions whose name contains `collect`
/// (`--toggle-collect`), and, with `dump_after`, writing one dump each
/// time a function whose name contains it returns (`--dump-after`).
/// Returns the child's output and each dump's instruction total.
pub fn count(args: &[OsString], collect: &str, dump_after: Option<&str>) -> Result<Counts, Error> {
    let exe = std::env::current_exe().map_err(Error::CurrentExe)?;
    let dir = tempfile::Builder::new()
        .prefix("bushing-callgrind-")
        .tempdir()
        .map_err(Error::TempDir)?;
    let base = dir.path().join("callgrind.out");
    let mut valgrind = Command::new("valgrind");
    valgrind
        .arg("--tool=callgrind")
        .arg(format!("--callgrind-out-file={}", base.display()))
        .arg(format!("--toggle-collect=*{collect}*"));
    if let Some(f) = dump_after {
        valgrind.arg(format!("--dump-after=*{f}*"));
    }
    let output = valgrind
        .arg(&exe)
        .args(args)
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .output()
        .map_err(Error::Start)?;
    if !output.status.success() {
        let words: Vec<_> = args.iter().map(|a| a.to_string_lossy()).collect();
        return Err(Error::Failed {
            command: words.join(" "),
            status: output.status,
        });
    }
    let totals = totals(&base)?;
    dir.close().map_err(Error::TempDir)?;
    Ok(Counts {
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        totals,
    })
}

/// The totals of the dumps `base.1`, `base.2`, ... in order; `base`
/// alone when there are none (callgrind writes the numbered dumps on
/// `--dump-after`, and `base` at exit).
fn totals(base: &Path) -> Result<Vec<u64>, Error> {
    let numbered = |i: usize| PathBuf::from(format!("{}.{i}", base.display()));
    let mut files: Vec<PathBuf> = (1..).map(numbered).take_while(|p| p.exists()).collect();
    if files.is_empty() {
        files.push(base.to_path_buf());
    }
    files
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).map_err(|source| Error::Read {
                path: path.clone(),
                source,
            })?;
            total(&text).ok_or(Error::NoTotal { path })
        })
        .collect()
}

/// The event total of a callgrind dump (its `totals:` or `summary:` line;
/// the first event is the instruction count).
fn total(text: &str) -> Option<u64> {
    text.lines().find_map(|line| {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("totals:" | "summary:") => words.next()?.parse().ok(),
            _ => None,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn totals_are_read_from_either_line() {
        assert_eq!(
            total("events: Ir\nsummary: 1234\ntotals: 1234\n"),
            Some(1234)
        );
        assert_eq!(total("totals: 7 3\n"), Some(7));
        assert_eq!(total("fn=main\n0 12\n"), None);
    }

    #[test]
    fn numbered_dumps_come_in_order_and_the_final_one_is_left_out() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("callgrind.out");
        for (name, total) in [("callgrind.out", 0), ("callgrind.out.1", 5)] {
            std::fs::write(dir.path().join(name), format!("totals: {total}\n")).unwrap();
        }
        std::fs::write(dir.path().join("callgrind.out.2"), "summary: 9\n").unwrap();
        assert_eq!(totals(&base).unwrap(), [5, 9]);
        std::fs::remove_file(dir.path().join("callgrind.out.1")).unwrap();
        assert_eq!(totals(&base).unwrap(), [0]);
        std::fs::remove_file(&base).unwrap();
        assert!(matches!(totals(&base), Err(Error::Read { .. })));
    }
}
