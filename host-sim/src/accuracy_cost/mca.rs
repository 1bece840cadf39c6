//! The cycle model of [`super::cycles`] against LLVM's Cortex-M4
//! scheduling model: the hottest straight-line block of a few kernels,
//! timed by both.
//!
//! `llvm-mca -mcpu=cortex-m4` issues one instruction a cycle and charges
//! only the latency of a result to the instruction that reads it; the
//! Technical Reference Manual's tables, which the report's estimates use,
//! also occupy the pipeline for 2 cycles per single load and store, 3 per
//! multiply-accumulate and 14 per divide or square root. The two agree on
//! blocks of single-cycle instructions and part where loads and
//! multiply-accumulates are many; the table shows by how much.

use std::path::Path;
use std::process::Command;

use super::HEADLINE;
use super::cycles::{self, Core, Disassembly, Mix};
use super::firmware::KernelLine;

/// Iterations llvm-mca runs the block for (its figure is per iteration).
const ITERATIONS: u32 = 100;

/// One kernel's hottest block, timed both ways.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// `family: name n=N`.
    pub kernel: String,
    /// The block's first address.
    pub start: u64,
    /// Instructions compared (the block without a final branch).
    pub instructions: usize,
    /// Share of the kernel window's instructions the block ran.
    pub share: f64,
    /// The report's model, one pass.
    pub model: u64,
    /// llvm-mca's cycles per iteration, or why there is none.
    pub mca: Result<f64, String>,
}

/// Compares the model with llvm-mca (the program at `mca`) on [`HEADLINE`]
/// of the M4F `lines`, whose windows are in `mix` over `disassembly`.
pub fn compare(
    mca: &Path,
    lines: &[&KernelLine],
    mix: &Mix,
    disassembly: &Disassembly,
) -> Vec<Check> {
    let mut out = Vec::new();
    for (family, name, n) in HEADLINE {
        let Some(line) = lines
            .iter()
            .find(|l| l.family == family && l.name == name && l.n == n && l.number == "f32")
        else {
            continue;
        };
        let Some(Some(w)) = line.windows.map(|w| w[0]) else {
            continue;
        };
        let Ok(window) = mix.window(w) else {
            continue;
        };
        let Some(block) = cycles::hottest(window) else {
            continue;
        };
        let kernel = format!("{family}: {name} n={n}");
        let share = (block.insns * block.execs) as f64 / window.insns.max(1) as f64;
        match disassembly.straight_line(Core::M4, block) {
            Ok((texts, model)) => out.push(Check {
                kernel,
                start: block.start,
                instructions: texts.len(),
                share,
                model,
                mca: run(mca, &texts),
            }),
            Err(e) => out.push(Check {
                kernel,
                start: block.start,
                instructions: 0,
                share,
                model: 0,
                mca: Err(e.to_string()),
            }),
        }
    }
    out
}

/// llvm-mca's cycles per iteration of `instructions` on the Cortex-M4.
fn run(mca: &Path, instructions: &[String]) -> Result<f64, String> {
    let mut source = String::from(".syntax unified\n.thumb\n");
    for i in instructions {
        source.push_str(i);
        source.push('\n');
    }
    let file = tempfile::Builder::new()
        .suffix(".s")
        .tempfile()
        .map_err(|e| format!("temporary file: {e}"))?;
    std::fs::write(file.path(), source).map_err(|e| format!("temporary file: {e}"))?;
    let output = Command::new(mca)
        .args([
            "-mtriple=thumbv7em-none-eabihf",
            "-mcpu=cortex-m4",
            &format!("-iterations={ITERATIONS}"),
        ])
        .arg(file.path())
        .output()
        .map_err(|e| format!("{}: {e}", mca.display()))?;
    let text = String::from_utf8_lossy(&output.stdout);
    if !output.status.success() {
        let why = String::from_utf8_lossy(&output.stderr);
        return Err(why.lines().next().unwrap_or("failed").to_string());
    }
    total_cycles(&text)
        .map(|total| total / f64::from(ITERATIONS))
        .ok_or_else(|| "no 'Total Cycles' in its output".into())
}

/// The `Total Cycles:` figure of llvm-mca's summary.
fn total_cycles(text: &str) -> Option<f64> {
    text.lines()
        .find_map(|l| l.trim().strip_prefix("Total Cycles:"))
        .and_then(|v| v.trim().parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_is_read() {
        let text = "Iterations:        100\nInstructions:      10500\nTotal Cycles:      12501\n";
        assert_eq!(total_cycles(text), Some(12501.0));
        assert_eq!(total_cycles("Iterations: 100\n"), None);
    }

    #[test]
    fn a_missing_program_is_an_error_not_a_panic() {
        let e = run(Path::new("/nonexistent/llvm-mca"), &["nop".into()]);
        assert!(e.is_err_and(|e| e.contains("/nonexistent/llvm-mca")));
    }
}
