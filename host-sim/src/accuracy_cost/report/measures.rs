//! The report's sections on how its costs are measured: the harness (the
//! same kernels in a binary of their own), the build flags (this build
//! against another), each kernel's cost on every input, and the cycle model
//! against llvm-mca.

use std::fmt::Write;

use super::cycles_instr;
use crate::accuracy_cost::firmware::{InputCost, KernelLine};
use crate::markdown::{Table, cell};

/// The section of the measuring harness and its spread between binaries.
pub(super) fn harness_section(
    s: &mut String,
    spread: Option<&crate::accuracy_cost::builds::Spread>,
) {
    let _ = writeln!(
        s,
        "\n## Harness\n\n\
         Every kernel, whatever its shape, is measured by one harness \
         (`bushing_boards::probe::measure`): a loop compiled once that calls the kernel through a \
         trait object, in a window of its own; then a stand-in of the same signature (its result \
         made from the input, nothing computed) through the same compiled call; then the idle \
         loop. The kernel's figures are differences of windows: less the stand-in, what the kernel \
         adds to a control loop; less the idle loop, the whole call. No loop is compiled around a \
         particular kernel, so the compiler's choices there cannot move a kernel's count.\n\n\
         To show that a kernel's count does not depend on what else its binary holds, the \
         firmware is built a second time with the headline kernels alone \
         (`--features headline-only`, the same flags) and measured the same way.\n"
    );
    let Some(sp) = spread else {
        let _ = writeln!(
            s,
            "Not compared in this run (`scripts/accuracy-cost.sh` builds and measures the \
             headline-only binary)."
        );
        return;
    };
    let _ = writeln!(
        s,
        "Against the `{}` binary, over the {} M4F kernel and input pairs measured in both: the \
         largest difference is {:.1} instructions and {:.1} estimated cycles per call.\n",
        sp.other,
        sp.rows.len(),
        sp.max_instructions(),
        sp.max_cycles()
    );
    let mut table = Table::new([
        "kernel",
        "n",
        "input",
        "cycles (instr), full binary",
        "cycles (instr), headline alone",
    ]);
    for r in &sp.rows {
        table.row([
            format!("{}: {}", r.key.family, r.key.name),
            r.key.n.to_string(),
            r.input.clone(),
            cycles_instr(r.ours.1, Some(r.ours.0), 1),
            cycles_instr(r.other.1, Some(r.other.0), 1),
        ]);
    }
    s.push_str(&table.finish());
}

/// The section of the build flags, chosen on estimated cycles.
pub(super) fn builds_section(
    s: &mut String,
    builds: Option<&crate::accuracy_cost::builds::Comparison>,
) {
    let _ = writeln!(
        s,
        "\n## Build flags\n\n\
         The Cortex-M4F firmware is built with `-C target-cpu=cortex-m4` (`.cargo/config.toml`): \
         LLVM then schedules for the Cortex-M4 and splits multiply-accumulates into a multiply \
         and an add (the same rounding: `vmla` is not fused), which takes more instructions and \
         fewer cycles. The flags are chosen on estimated cycles, not on instructions, which rank \
         the two builds the other way round.\n"
    );
    let Some(c) = builds else {
        let _ = writeln!(
            s,
            "Not compared in this run (the full report builds and measures the other build)."
        );
        return;
    };
    let _ = writeln!(
        s,
        "Against `{}`, over the {} M4F f32 kernels with estimated cycles in both (each on its \
         worst input): geometric mean of the cycles {:.3} times the other build's, of the \
         instructions {:.3} times; {} kernels take fewer cycles, {} more.\n",
        c.other, c.kernels, c.cycles_ratio, c.instructions_ratio, c.fewer_cycles, c.more_cycles
    );
    let mut table = Table::new([
        "kernel",
        "n",
        "cycles (instr), this build",
        "cycles (instr), the other",
    ]);
    for (k, p) in &c.named {
        table.row([
            format!("{}: {}", k.family, k.name),
            k.n.to_string(),
            cycles_instr(Some(p.ours.1), Some(p.ours.0), 0),
            cycles_instr(Some(p.other.1), Some(p.other.0), 0),
        ]);
    }
    s.push_str(&table.finish());
}

/// The section of the cycle model against llvm-mca.
pub(super) fn mca_table(s: &mut String, checks: Option<&[crate::accuracy_cost::mca::Check]>) {
    let _ = writeln!(
        s,
        "\n## Cycle model against llvm-mca\n\n\
         The hottest straight-line block of a few kernels (its final branch left out), timed by the \
         report's model (one pass) and by `llvm-mca -mcpu=cortex-m4` (cycles per iteration over \
         100). LLVM's Cortex-M4 model issues one instruction a cycle and charges only a result's \
         latency to the instruction that reads it; the Technical Reference Manual's tables, which \
         the model follows, also hold the pipeline 2 cycles for a single load or store, 3 for a \
         multiply-accumulate and 14 for a divide. They agree on single-cycle code and part where \
         loads and multiply-accumulates are many.\n"
    );
    let Some(checks) = checks else {
        let _ = writeln!(
            s,
            "Not run: no `--llvm-mca PROGRAM` (the full report runs it when `llvm-mca` is installed)."
        );
        return;
    };
    let mut table = Table::new([
        "kernel",
        "block",
        "instructions",
        "share of the kernel's",
        "model cycles",
        "llvm-mca cycles",
        "model / llvm-mca",
    ]);
    for c in checks {
        let (mca, ratio) = match &c.mca {
            Ok(m) => (format!("{m:.1}"), format!("{:.2}", c.model as f64 / m)),
            Err(why) => (format!("failed: {}", cell(why)), "-".into()),
        };
        table.row([
            c.kernel.clone(),
            format!("{:#x}", c.start),
            c.instructions.to_string(),
            format!("{:.0} %", 100.0 * c.share),
            c.model.to_string(),
            mca,
            ratio,
        ]);
    }
    s.push_str(&table.finish());
}

/// The section of every kernel's cost on each of its inputs.
pub(super) fn input_table(s: &mut String, lines: &[KernelLine]) {
    let _ = writeln!(
        s,
        "\n## Cost by input\n\n\
         Every kernel that takes a signal runs on three inputs: `sine`, its nominal sine (2 mm \
         and 100 samples a period for a bushing or an effect; amplitude 1 at 20 Hz and 1 kHz for \
         the trackers; a force of 9 for the oscillator; the mount's cycle of up to 1 mm and \
         0.02 rad), `small-sine`, the same at 0.005 of it (0.01 mm: below the smallest slip \
         displacement of every Iwan bank, so that no held cell is skipped; below the sensors' \
         noise for the trackers), and `noise`, band-limited noise of half the sine's amplitude \
         as RMS (two poles at 2 % of the sample rate, seeded). Every table above takes a kernel's \
         worst input (by estimated M4F cycles) and names it. The kernels that take no signal \
         (re-tuning, the WLF factor, the first-period fit) have one input, `own`. Cortex-M4F, \
         f32, estimated cycles (instructions) per call, net of the call:\n"
    );
    let mut names: Vec<String> = Vec::new();
    for l in lines {
        for c in &l.by_input {
            if !names.contains(&c.input) {
                names.push(c.input.clone());
            }
        }
    }
    let mine: Vec<&KernelLine> = lines
        .iter()
        .filter(|l| l.target == "m4f" && l.number == "f32" && l.by_input.len() > 1)
        .collect();
    if mine.is_empty() {
        let _ = writeln!(s, "No kernel was measured on more than one input.");
        return;
    }
    let mut table = Table::new(
        ["kernel", "n"]
            .into_iter()
            .map(String::from)
            .chain(names.iter().cloned())
            .chain(["worst".to_string(), "worst / first".to_string()]),
    );
    for l in mine {
        let cost = |c: &InputCost| c.cycles.unwrap_or(c.instructions);
        let first = l.by_input.first().map(cost);
        let worst = l.by_input.iter().map(cost).fold(f64::NAN, f64::max);
        let cells = names.iter().map(|n| {
            l.by_input.iter().find(|c| &c.input == n).map_or_else(
                || "-".into(),
                |c| cycles_instr(c.cycles, Some(c.instructions), 0),
            )
        });
        table.row(
            [format!("{}: {}", l.family, l.name), l.n.to_string()]
                .into_iter()
                .chain(cells)
                .chain([
                    l.input.clone().unwrap_or_else(|| "-".into()),
                    first.map_or_else(|| "-".into(), |f| format!("{:.2}", worst / f)),
                ]),
        );
    }
    s.push_str(&table.finish());
}
