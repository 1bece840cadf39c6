//! An output folder that appears whole or not at all.
//!
//! A run writes into a fresh, unpredictably named folder beside `--out`
//! ([`tempfile`]), and only when every file is written and flushed does
//! [`Staged::commit`] put it in place of `--out`: on Linux by exchanging the
//! two folders in one `renameat2(RENAME_EXCHANGE)`, elsewhere by moving the
//! old folder aside first. The earlier run's folder is then deleted, so no
//! file of it is left beside the new ones. A run that fails, is killed or
//! runs out of disk leaves the previous result as it was, and at most a
//! hidden `.NAME.partial-*` folder that no one would take for a result (it
//! is removed on every error path the process survives).
//!
//! Safety rules, checked before anything is written:
//!
//! - `--out` must not be a symbolic link, nor a file;
//! - an existing `--out` is replaced only if it is empty or holds an earlier
//!   run (it has the [`MARKER`] file that every commit writes last); any
//!   other folder is refused rather than deleted;
//! - files are created with `create_new` in the fresh folder, so no link
//!   planted there can be followed.
//!
//! Every I/O error names the file it happened on.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use tempfile::TempDir;

/// The file every committed output folder holds: the list of the files
/// written, one per line. Its presence marks a folder as a run's output.
pub const MARKER: &str = ".bushing-sim-output";

/// What can go wrong with an output folder.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output path is a symbolic link.
    #[error("{}: the output folder is a symbolic link; give the real folder", .0.display())]
    Symlink(PathBuf),
    /// The output path is not a folder.
    #[error("{}: exists and is not a folder", .0.display())]
    NotAFolder(PathBuf),
    /// The output folder holds files that no run wrote.
    #[error(
        "{}: exists, is not empty and is not an earlier output of bushing-sim \
         (no {MARKER} in it); choose a new folder or empty this one",
        .0.display()
    )]
    Foreign(PathBuf),
    /// An I/O error on a named file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The error.
        source: io::Error,
    },
}

impl OutputError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>) -> impl FnOnce(io::Error) -> Self {
        let path = path.into();
        move |source| Self::Io { path, source }
    }
}

/// A folder being written, to be put in place of the output on commit.
#[derive(Debug)]
pub struct Staged {
    target: PathBuf,
    dir: TempDir,
}

impl Staged {
    /// Checks `target` and creates the staging folder beside it (creating
    /// the parent folders if needed).
    pub fn begin(target: &Path) -> Result<Self, OutputError> {
        check_target(target)?;
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        fs::create_dir_all(&parent).map_err(OutputError::io(&parent))?;
        let dir = tempfile::Builder::new()
            .prefix(&format!(".{name}.partial-"))
            .tempdir_in(&parent)
            .map_err(OutputError::io(&parent))?;
        Ok(Self {
            target: target.to_path_buf(),
            dir,
        })
    }

    /// Where `name` will be once committed (for messages and summaries).
    pub fn final_path(&self, name: &str) -> PathBuf {
        self.target.join(name)
    }

    /// Creates `name` in the staging folder, buffered.
    pub fn create(&mut self, name: &str) -> Result<OutputFile, OutputError> {
        let path = self.dir.path().join(name);
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(OutputError::io(self.final_path(name)))?;
        Ok(OutputFile {
            shown: self.final_path(name),
            inner: BufWriter::new(file),
        })
    }

    /// Writes `bytes` as file `name`.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let mut sink = self.create(name)?;
        sink.write_all(bytes)?;
        sink.finish()?;
        Ok(self.final_path(name))
    }

    /// Writes the marker and puts the folder in place of the output; the
    /// earlier output, if any, is deleted.
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        let staging = self.dir.path().to_path_buf();
        let mut names = Vec::new();
        for entry in fs::read_dir(&staging).map_err(OutputError::io(&staging))? {
            let entry = entry.map_err(OutputError::io(&staging))?;
            names.push(entry.file_name().to_string_lossy().into_owned());
        }
        names.sort();
        let mut list = names.join("\n");
        list.push('\n');
        self.write(MARKER, list.as_bytes())?;
        // The whole folder is on disk before it takes the output's name.
        File::open(self.dir.path())
            .and_then(|d| d.sync_all())
            .map_err(OutputError::io(self.dir.path()))?;
        check_target(&self.target)?;
        let staged = self.dir.keep();
        let result = swap_into_place(&staged, &self.target);
        if result.is_err() {
            // Nothing was moved: the staged folder is not a result.
            let _ = fs::remove_dir_all(&staged);
        }
        result.map(|()| self.target.clone())
    }
}

/// A buffered output file that names itself in its errors.
#[derive(Debug)]
pub struct OutputFile {
    shown: PathBuf,
    inner: BufWriter<File>,
}

impl OutputFile {
    /// Writes all of `bytes`.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<(), OutputError> {
        self.inner
            .write_all(bytes)
            .map_err(OutputError::io(&self.shown))
    }

    /// Flushes and syncs the file.
    pub fn finish(self) -> Result<(), OutputError> {
        let shown = self.shown;
        let file = self
            .inner
            .into_inner()
            .map_err(|e| OutputError::io(&shown)(e.into_error()))?;
        file.sync_all().map_err(OutputError::io(&shown))
    }

    /// The file's final path.
    pub fn path(&self) -> &Path {
        &self.shown
    }
}

/// For writers that take `io::Write` (their errors are then named with
/// [`OutputFile::path`]).
impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.inner.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// Refuses a symbolic link, a file, or a non-empty folder that is not an
/// earlier output.
fn check_target(target: &Path) -> Result<(), OutputError> {
    let meta = match fs::symlink_metadata(target) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(OutputError::io(target)(e)),
    };
    if meta.file_type().is_symlink() {
        return Err(OutputError::Symlink(target.to_path_buf()));
    }
    if !meta.is_dir() {
        return Err(OutputError::NotAFolder(target.to_path_buf()));
    }
    let marked = fs::symlink_metadata(target.join(MARKER)).is_ok_and(|m| m.is_file());
    let empty = fs::read_dir(target)
        .map_err(OutputError::io(target))?
        .next()
        .is_none();
    if marked || empty {
        Ok(())
    } else {
        Err(OutputError::Foreign(target.to_path_buf()))
    }
}

/// Puts `staged` at `target` and deletes what was there.
fn swap_into_place(staged: &Path, target: &Path) -> Result<(), OutputError> {
    if fs::symlink_metadata(target).is_err() {
        return fs::rename(staged, target).map_err(OutputError::io(target));
    }
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        if renameat_with(CWD, staged, CWD, target, RenameFlags::EXCHANGE).is_ok() {
            // `staged` now names the earlier output.
            return fs::remove_dir_all(staged).map_err(OutputError::io(staged));
        }
    }
    // Without an atomic exchange: the earlier output is moved aside first,
    // so that it is whole under its hidden name if the process dies here.
    let mut aside = staged.as_os_str().to_owned();
    aside.push(".old");
    let aside = PathBuf::from(aside);
    fs::rename(target, &aside).map_err(OutputError::io(target))?;
    if let Err(e) = fs::rename(staged, target) {
        let _ = fs::rename(&aside, target);
        return Err(OutputError::io(target)(e));
    }
    fs::remove_dir_all(&aside).map_err(OutputError::io(&aside))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_commit_replaces_an_earlier_output_and_drops_its_other_files() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        let mut first = Staged::begin(&out).unwrap();
        first.write("a.csv", b"first").unwrap();
        first.write("old.svg", b"only in the first run").unwrap();
        first.commit().unwrap();
        let mut second = Staged::begin(&out).unwrap();
        second.write("a.csv", b"second").unwrap();
        second.commit().unwrap();
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"second");
        assert!(!out.join("old.svg").exists());
        let names: Vec<_> = fs::read_dir(root.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no staging or aside folder is left");
    }

    #[test]
    fn an_uncommitted_run_leaves_the_earlier_output_whole() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        let mut first = Staged::begin(&out).unwrap();
        first.write("a.csv", b"first").unwrap();
        first.commit().unwrap();
        let mut second = Staged::begin(&out).unwrap();
        second.write("a.csv", b"cut").unwrap();
        drop(second);
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"first");
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_foreign_folder_a_file_and_a_link_are_refused() {
        let root = tempfile::tempdir().unwrap();
        let foreign = root.path().join("home");
        fs::create_dir(&foreign).unwrap();
        fs::write(foreign.join("thesis.tex"), b"keep me").unwrap();
        assert!(matches!(
            Staged::begin(&foreign),
            Err(OutputError::Foreign(_))
        ));
        let file = root.path().join("file");
        fs::write(&file, b"x").unwrap();
        assert!(matches!(
            Staged::begin(&file),
            Err(OutputError::NotAFolder(_))
        ));
        #[cfg(unix)]
        {
            let link = root.path().join("link");
            std::os::unix::fs::symlink(&foreign, &link).unwrap();
            assert!(matches!(Staged::begin(&link), Err(OutputError::Symlink(_))));
        }
        assert_eq!(
            fs::read(foreign.join("thesis.tex")).unwrap(),
            b"keep me",
            "nothing of a refused folder is touched"
        );
    }
}
