//! The `.fmu` archive: `modelDescription.xml`, the library in
//! `binaries/linux64/` and the model in `resources/`, written to a
//! temporary file beside `--out` and renamed onto it only when complete.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use zip::write::SimpleFileOptions;

use super::FmuError;
use super::description::{MODEL_IDENTIFIER, model_description};
use super::resource::{FmuModel, RESOURCE_FILE};

/// File name of the FMU library cargo builds (`cargo build --release -p
/// bushing-fmu`).
pub const LIBRARY_FILE: &str = "libbushing_fmu.so";

/// Functions the library must export: the ones a co-simulation master
/// calls first and on every step.
pub const REQUIRED_SYMBOLS: [&str; 6] = [
    "fmi2GetVersion",
    "fmi2Instantiate",
    "fmi2DoStep",
    "fmi2GetReal",
    "fmi2GetFMUstate",
    "fmi2SerializeFMUstate",
];

/// Largest library accepted, bytes.
const MAX_LIBRARY_BYTES: u64 = 256 << 20;

/// The FMU library beside the running `bushing-sim` (cargo puts both in
/// `target/<profile>/`), or `explicit` when given.
pub fn find_library(explicit: Option<&Path>) -> Result<PathBuf, FmuError> {
    if let Some(path) = explicit {
        return Ok(path.to_path_buf());
    }
    let exe = std::env::current_exe().map_err(|e| FmuError::Io(e.to_string()))?;
    let beside = exe.parent().map(|d| d.join(LIBRARY_FILE));
    match beside {
        Some(path) if path.is_file() => Ok(path),
        _ => Err(FmuError::Library(format!(
            "{LIBRARY_FILE} is not beside {}: build it with `cargo build --release -p \
             bushing-fmu` (the same profile as bushing-sim) or give --library",
            exe.display()
        ))),
    }
}

/// Reads the library at `path` and checks it is an x86-64 ELF shared
/// object exporting the FMI functions.
fn read_library(path: &Path) -> Result<Vec<u8>, FmuError> {
    use object::{Object, ObjectSymbol};
    let bad = |what: String| FmuError::Library(format!("{}: {what}", path.display()));
    let meta = std::fs::metadata(path).map_err(|e| bad(e.to_string()))?;
    if !meta.is_file() || meta.len() > MAX_LIBRARY_BYTES {
        return Err(bad(format!(
            "not a regular file of at most {MAX_LIBRARY_BYTES} bytes"
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| bad(e.to_string()))?;
    let file = object::File::parse(&*bytes).map_err(|e| bad(format!("not an object file: {e}")))?;
    if file.architecture() != object::Architecture::X86_64
        || file.kind() != object::ObjectKind::Dynamic
        || file.format() != object::BinaryFormat::Elf
    {
        return Err(bad(
            "not an x86-64 ELF shared library (binaries/linux64)".into()
        ));
    }
    let exported: Vec<&str> = file
        .dynamic_symbols()
        .filter(|s| s.is_definition())
        .filter_map(|s| s.name().ok())
        .collect();
    for name in REQUIRED_SYMBOLS {
        if !exported.contains(&name) {
            return Err(bad(format!("it does not export {name}")));
        }
    }
    Ok(bytes)
}

/// Refuses an output path that is not a `.fmu` name, or that is a
/// symbolic link or anything but a file.
pub fn check_out(out: &Path) -> Result<(), FmuError> {
    let usage = |what: &str| FmuError::Usage(format!("{}: {what}", out.display()));
    if out.extension().and_then(|e| e.to_str()) != Some("fmu") {
        return Err(usage("the output must be a .fmu file"));
    }
    match std::fs::symlink_metadata(out) {
        Ok(m) if m.file_type().is_symlink() => Err(usage("is a symbolic link; give the real file")),
        Ok(m) if !m.is_file() => Err(usage("exists and is not a file")),
        _ => Ok(()),
    }
}

/// Writes the FMU of `model`, named `name`, with the library at
/// `library`, to `out` (a `.fmu` file; an existing file is replaced only
/// when the new one is complete).
pub fn write_fmu(model: &FmuModel, name: &str, library: &Path, out: &Path) -> Result<(), FmuError> {
    check_out(out)?;
    let library = read_library(library)?;
    let description = model_description(model, name);
    let dir = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let io = |e: std::io::Error| FmuError::Io(format!("{}: {e}", out.display()));
    let mut temp = tempfile::Builder::new()
        .prefix(".bushing-fmu-")
        .suffix(".partial")
        .tempfile_in(dir)
        .map_err(io)?;
    {
        let mut zip = zip::ZipWriter::new(temp.as_file_mut());
        let options =
            SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
        let zerr = |e: zip::result::ZipError| FmuError::Io(format!("{}: {e}", out.display()));
        let files: [(String, &[u8]); 3] = [
            ("modelDescription.xml".into(), description.as_bytes()),
            (format!("binaries/linux64/{MODEL_IDENTIFIER}.so"), &library),
            (format!("resources/{RESOURCE_FILE}"), model.text.as_bytes()),
        ];
        for (path, bytes) in files {
            zip.start_file(path, options).map_err(zerr)?;
            zip.write_all(bytes).map_err(io)?;
        }
        zip.finish().map_err(zerr)?;
    }
    temp.as_file().sync_all().map_err(io)?;
    temp.persist(out).map_err(|e| io(e.error))?;
    Ok(())
}
