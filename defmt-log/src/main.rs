//! `bushing-defmt-log ELF LOG`: prints the decoded defmt log of a firmware
//! run, one line per frame; exits with failure on any decoding error (see
//! the library's docs).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;

/// Decodes a firmware's defmt log with the table of its ELF.
#[derive(Parser)]
#[command(version)]
struct Args {
    /// The firmware's ELF (its defmt table).
    elf: PathBuf,
    /// The raw log: the bytes the firmware's logger wrote.
    log: PathBuf,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let read = |p: &PathBuf| std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()));
    let result = read(&args.elf).and_then(|elf| {
        let raw = read(&args.log)?;
        // The whole text first: a log that fails to decode prints nothing
        // that could pass for a complete one.
        let mut text = Vec::new();
        let frames = bushing_defmt_log::decode(&elf, &raw, &mut text).map_err(|e| e.to_string())?;
        std::io::stdout()
            .lock()
            .write_all(&text)
            .map_err(|e| format!("writing the decoded log: {e}"))?;
        Ok(frames)
    });
    match result {
        Ok(frames) => {
            eprintln!("{frames} frames decoded");
            ExitCode::SUCCESS
        }
        Err(why) => {
            eprintln!("error: {why}");
            ExitCode::FAILURE
        }
    }
}
