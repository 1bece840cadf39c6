//! Estimated Cortex-M cycles of each measured kernel, from the instructions
//! QEMU executed.
//!
//! QEMU counts instructions; a Cortex-M4 does not spend one cycle on each.
//! The `bushing-qemu-mix` plugin records, for each measured window of the
//! kernel-cost firmware, the translation blocks that ran, how often, and
//! how often each left by a taken branch ([`Mix`]). Each block is mapped
//! onto the firmware's disassembly (`llvm-objdump -d`, [`Disassembly`])
//! and each instruction weighed by the instruction timing tables of the
//! Cortex-M4 and Cortex-M3 Technical Reference Manuals ([`Core`]):
//!
//! - ALU, moves, compares, shifts, IT, `vadd`/`vsub`/`vmul`/`vabs`/`vneg`/
//!   `vcmp`/`vcvt`/`vmov`/`vmrs`: 1 cycle. Moves of two words between core
//!   and FPU registers: 2.
//! - Single loads and stores (`ldr`, `str`, `vldr`, `vstr`, byte and
//!   halfword forms): 2; an integer load or store right after an integer
//!   load pipelines and takes 1. `ldrd`/`strd`: 3. `ldm`, `stm`, `push`,
//!   `pop`, `vldm`, `vstm`, `vpush`, `vpop`: 1 + N (N words).
//! - Multiplies: 1 on the Cortex-M4 (`mla`, long multiplies and MACs too);
//!   on the Cortex-M3 `mla`/`mls` 2, `umull`/`smull` 5 and `umlal`/`smlal`
//!   7 (the upper ends of 3-5 and 4-7). `sdiv`/`udiv`: 12 (the upper end of
//!   2-12).
//! - FPU multiply-accumulate (`vmla`, `vmls`, `vnmla`, `vnmls`, `vfma`,
//!   `vfms`, `vfnma`, `vfnms`): 3. `vdiv`, `vsqrt`: 14.
//! - An FPU arithmetic result read by the next instruction: 1 more; a
//!   multiply-accumulate whose accumulator the previous instruction wrote:
//!   1 more.
//! - A branch not taken: 1. A taken branch, call, return, or any write to
//!   the PC: 1 + P more than the instruction's own cost less one, with the
//!   pipeline refill P = [`REFILL`] (the TRM gives 1 to 3, by the target's
//!   alignment and width). `tbb`/`tbh`: 2 + P.
//!
//! Assumed: zero-wait-state memory (no flash wait states, no bus
//! contention), no interrupts, and no overlap of `vdiv`/`vsqrt` with later
//! integer instructions (the estimate is then an upper one for them). An
//! instruction skipped by its IT condition is charged as if it ran.

use std::collections::BTreeMap;

use super::firmware::{KernelLine, PeerLine, Split};

/// The pipeline refill of a taken branch, in cycles (the middle of the
/// TRM's 1 to 3).
pub const REFILL: u64 = 2;

/// Which timing table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Core {
    /// Cortex-M4 (with or without its single-precision FPU).
    M4,
    /// Cortex-M3: no FPU, slower multiply-accumulate and long multiplies.
    M3,
}

impl Core {
    /// The core of a report target (`m4f` → M4, `m3` → M3).
    pub fn of_target(target: &str) -> Option<Self> {
        match target {
            "m4f" | "m4" => Some(Self::M4),
            "m3" => Some(Self::M3),
            _ => None,
        }
    }
}

/// Why a mix or a disassembly cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A line of the plugin's output that cannot be read.
    #[error("{source_name}:{line}: {problem}")]
    Mix {
        /// The file.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        problem: String,
    },
    /// The plugin's output has no `end` line: the run failed or was cut.
    #[error("{0}: no 'end' line (the run did not finish, or the plugin failed)")]
    Unfinished(String),
    /// A block that does not fall on the disassembly's instructions.
    #[error(
        "block {start:#x}..{end:#x} of {insns} instructions is not in the disassembly ({found} found there)"
    )]
    Block {
        /// Block start.
        start: u64,
        /// Block end.
        end: u64,
        /// Instructions QEMU translated.
        insns: u64,
        /// Instructions the disassembly has in that range.
        found: u64,
    },
    /// A window number the mix does not have.
    #[error("no window {window} in the mix {source_name}")]
    NoWindow {
        /// The window asked for.
        window: u32,
        /// The mix, as named to [`Mix::parse`].
        source_name: String,
    },
}

/// One translation block's counts in a window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlockCount {
    /// First instruction's address.
    pub start: u64,
    /// One past the last instruction.
    pub end: u64,
    /// Instructions in the block.
    pub insns: u64,
    /// Executions.
    pub execs: u64,
    /// Executions that left by a taken branch.
    pub taken: u64,
}

/// One measured window.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Window {
    /// Instructions executed, as the plugin counted them.
    pub insns: u64,
    /// The blocks that ran.
    pub blocks: Vec<BlockCount>,
}

/// The plugin's output: every window in order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Mix {
    /// Windows by number.
    pub windows: Vec<Window>,
    /// The mix's name, for errors.
    pub source_name: String,
}

fn hex(word: &str) -> Option<u64> {
    u64::from_str_radix(word.strip_prefix("0x")?, 16).ok()
}

impl Mix {
    /// Reads the plugin's output; `source_name` names it in errors.
    pub fn parse(source_name: &str, text: &str) -> Result<Self, Error> {
        let bad = |line: usize, problem: String| Error::Mix {
            source_name: source_name.into(),
            line,
            problem,
        };
        let mut windows: Vec<Window> = Vec::new();
        let mut ended = false;
        for (i, raw) in text.lines().enumerate() {
            let no = i + 1;
            let words: Vec<&str> = raw.split_whitespace().collect();
            match words.as_slice() {
                ["qemu-mix", "1", ..] if no == 1 => {}
                _ if no == 1 => return Err(bad(no, format!("not a qemu-mix 1 header: '{raw}'"))),
                _ if ended => return Err(bad(no, "text after the end line".into())),
                ["window", n, insns, _blocks] => {
                    let n: usize = n.parse().map_err(|_| bad(no, format!("window '{n}'")))?;
                    if n != windows.len() {
                        return Err(bad(no, format!("window {n} after {}", windows.len())));
                    }
                    let insns = insns
                        .strip_prefix("insns=")
                        .and_then(|v| v.parse().ok())
                        .ok_or_else(|| bad(no, format!("'{insns}' is not insns=N")))?;
                    windows.push(Window {
                        insns,
                        blocks: Vec::new(),
                    });
                }
                ["tb", start, end, insns, execs, taken] => {
                    let (Some(start), Some(end)) = (hex(start), hex(end)) else {
                        return Err(bad(no, format!("addresses '{start} {end}'")));
                    };
                    let counts: Vec<u64> = [insns, execs, taken]
                        .iter()
                        .map(|w| w.parse())
                        .collect::<Result<_, _>>()
                        .map_err(|_| bad(no, format!("counts in '{raw}'")))?;
                    let [insns, execs, taken] = counts[..] else {
                        return Err(bad(no, format!("counts in '{raw}'")));
                    };
                    if end < start || taken > execs {
                        return Err(bad(no, format!("inconsistent block '{raw}'")));
                    }
                    let Some(w) = windows.last_mut() else {
                        return Err(bad(no, "a block before any window".into()));
                    };
                    w.blocks.push(BlockCount {
                        start,
                        end,
                        insns,
                        execs,
                        taken,
                    });
                }
                ["end", count] => {
                    let count: Option<usize> =
                        count.strip_prefix("windows=").and_then(|v| v.parse().ok());
                    if count != Some(windows.len()) {
                        return Err(bad(no, format!("'{raw}' after {} windows", windows.len())));
                    }
                    ended = true;
                }
                ["error", ..] => return Err(bad(no, format!("the plugin failed: {raw}"))),
                _ => return Err(bad(no, format!("unknown line '{raw}'"))),
            }
        }
        if !ended {
            return Err(Error::Unfinished(source_name.into()));
        }
        Ok(Self {
            windows,
            source_name: source_name.into(),
        })
    }

    /// Window `n`.
    pub fn window(&self, n: u32) -> Result<&Window, Error> {
        self.windows.get(n as usize).ok_or_else(|| Error::NoWindow {
            window: n,
            source_name: self.source_name.clone(),
        })
    }
}

/// FPU registers as a bit set of single-precision registers (d_n covers
/// s_2n and s_2n+1).
type FpRegs = u32;

/// How an instruction is timed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Fixed cost.
    Plain,
    /// A single integer load (pipelines with a following load or store).
    Load,
    /// A single integer store (pipelines after a load).
    Store,
    /// A branch: `Plain` cost when not taken, plus `REFILL` when taken.
    Branch,
    /// FPU arithmetic: its result read next costs one more.
    FpArith,
    /// FPU multiply-accumulate: as `FpArith`, and its accumulator written
    /// by the previous instruction costs one more.
    FpMac,
}

/// One decoded instruction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Op {
    kind: Kind,
    /// Cycles on the Cortex-M4 and the Cortex-M3, not taken.
    cycles: [u64; 2],
    /// FPU registers written (the first operand).
    writes: FpRegs,
    /// FPU registers read.
    reads: FpRegs,
    /// What it does, for [`Split`].
    class: Class,
}

/// What an instruction does: the four parts of a [`Split`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Class {
    /// FPU add, subtract, multiply (and accumulate), divide, square root,
    /// absolute value, negate.
    Arithmetic,
    /// A load or store (a `pop` into the PC too).
    Transfer,
    /// A compare or test, the move of the FPU's flags, IT, a branch.
    Control,
    /// Moves, integer arithmetic, conversions.
    Other,
}

/// The condition suffixes of ARM mnemonics.
const CONDITIONS: [&str; 15] = [
    "eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt",
];

/// `vmla.f32` → `vmla`, `movne.w` → `mov` (and whether it sets flags is
/// dropped): the base mnemonic the tables know, or `None`.
fn base(mnemonic: &str) -> Option<&'static str> {
    let head = mnemonic.split('.').next().unwrap_or(mnemonic);
    let known = |m: &str| KNOWN.iter().find(|k| **k == m).copied();
    if let Some(k) = known(head) {
        return Some(k);
    }
    if head.starts_with("it") && head.len() <= 5 && head[2..].chars().all(|c| c == 't' || c == 'e')
    {
        return Some("it");
    }
    let mut candidates = vec![head];
    for c in CONDITIONS.iter().chain(["le", "al"].iter()) {
        if let Some(h) = head.strip_suffix(c) {
            candidates.push(h);
        }
    }
    // A condition first (`bls` is `b` if lower or same), then the
    // flag-setting `s` (`muls`), which no branch has.
    if let Some(k) = candidates.iter().find_map(|h| known(h)) {
        return Some(k);
    }
    candidates
        .iter()
        .filter_map(|h| h.strip_suffix('s').and_then(known))
        .find(|k| !k.starts_with('b') && !k.starts_with("cb"))
}

/// Every base mnemonic the tables name; anything else is a 1-cycle
/// data-processing instruction.
const KNOWN: [&str; 73] = [
    "b", "bl", "bx", "blx", "cbz", "cbnz", "tbb", "tbh", "ldr", "ldrb", "ldrh", "ldrsb", "ldrsh",
    "ldrex", "str", "strb", "strh", "strex", "ldrd", "strd", "ldm", "ldmia", "ldmdb", "stm",
    "stmia", "stmdb", "push", "pop", "mul", "mla", "mls", "umull", "smull", "umlal", "smlal",
    "umaal", "sdiv", "udiv", "vldr", "vstr", "vldm", "vldmia", "vldmdb", "vstm", "vstmia",
    "vstmdb", "vpush", "vpop", "vmla", "vmls", "vnmla", "vnmls", "vfma", "vfms", "vfnma", "vfnms",
    "vdiv", "vsqrt", "vadd", "vsub", "vmul", "vnmul", "vcvt", "vmov", "vabs", "vneg", "cmp", "cmn",
    "tst", "teq", "vcmp", "vcmpe", "vmrs",
];

/// The FPU registers named in `text` (`s3`, `d1`, `{s0-s7}`, `{d8-d9}`).
fn fp_regs(text: &str) -> FpRegs {
    let mut set = 0u32;
    let mut add = |kind: char, a: u32, b: u32| {
        for r in a..=b.min(31) {
            let bits = match kind {
                's' => 1u32.checked_shl(r).unwrap_or(0),
                _ => 3u32.checked_shl(2 * r).unwrap_or(0),
            };
            set |= bits;
        }
    };
    for word in text.split(|c: char| c == ',' || c == '{' || c == '}' || c.is_whitespace()) {
        let reg = |w: &str| -> Option<(char, u32)> {
            let mut chars = w.chars();
            let kind = chars.next().filter(|c| *c == 's' || *c == 'd')?;
            let n: u32 = chars.as_str().parse().ok()?;
            Some((kind, n))
        };
        if let Some((a, b)) = word.split_once('-') {
            if let (Some((k, x)), Some((_, y))) = (reg(a), reg(b)) {
                add(k, x, y);
            }
        } else if let Some((k, x)) = reg(word) {
            add(k, x, x);
        }
    }
    set
}

/// Words moved by a register list `{r4, r5, lr}` or `{s0-s3}`, `{d8-d9}`.
fn list_words(operands: &str) -> u64 {
    let Some(list) = operands
        .split_once('{')
        .and_then(|(_, l)| l.split_once('}'))
        .map(|(l, _)| l)
    else {
        return 1;
    };
    let mut words = 0u64;
    for item in list.split(',').map(str::trim) {
        let span = |w: &str| -> Option<(char, u64)> {
            let mut chars = w.chars();
            let kind = chars.next()?;
            Some((kind, chars.as_str().parse().ok()?))
        };
        let (kind, count) = match item.split_once('-') {
            Some((a, b)) => match (span(a), span(b)) {
                (Some((k, x)), Some((_, y))) => (k, y.saturating_sub(x) + 1),
                _ => ('r', 1),
            },
            None => (item.chars().next().unwrap_or('r'), 1),
        };
        words += if kind == 'd' { 2 * count } else { count };
    }
    words.max(1)
}

/// Whether the instruction writes the PC (a return or computed jump).
fn writes_pc(base: &str, operands: &str) -> bool {
    let first = operands.split(',').next().unwrap_or("").trim();
    match base {
        "pop" | "ldm" | "ldmia" | "ldmdb" => operands.contains("pc"),
        "ldr" | "mov" | "add" => first == "pc",
        _ => false,
    }
}

/// Decodes one instruction (`mnemonic`, `operands` as llvm-objdump prints
/// them).
fn decode(mnemonic: &str, operands: &str) -> Op {
    let base = base(mnemonic).unwrap_or("alu");
    let regs = fp_regs(operands);
    let first = fp_regs(operands.split(',').next().unwrap_or(""));
    let plain = |c: u64| Op {
        kind: Kind::Plain,
        cycles: [c, c],
        writes: 0,
        reads: regs,
        class: Class::Other,
    };
    let words = list_words(operands);
    let mut op = match base {
        "b" | "bl" | "bx" | "blx" | "cbz" | "cbnz" => Op {
            kind: Kind::Branch,
            ..plain(1)
        },
        "tbb" | "tbh" => Op {
            kind: Kind::Branch,
            ..plain(2)
        },
        "ldr" | "ldrb" | "ldrh" | "ldrsb" | "ldrsh" | "ldrex" => Op {
            kind: Kind::Load,
            ..plain(2)
        },
        "str" | "strb" | "strh" | "strex" => Op {
            kind: Kind::Store,
            ..plain(2)
        },
        "ldrd" | "strd" => plain(3),
        "ldm" | "ldmia" | "ldmdb" | "stm" | "stmia" | "stmdb" | "push" | "pop" => plain(1 + words),
        "mul" => plain(1),
        "mla" | "mls" => Op {
            cycles: [1, 2],
            ..plain(1)
        },
        "umull" | "smull" => Op {
            cycles: [1, 5],
            ..plain(1)
        },
        "umlal" | "smlal" | "umaal" => Op {
            cycles: [1, 7],
            ..plain(1)
        },
        "sdiv" | "udiv" => plain(12),
        "vldr" => Op {
            writes: first,
            reads: regs & !first,
            ..plain(2)
        },
        "vstr" => plain(2),
        "vldm" | "vldmia" | "vldmdb" | "vpop" => Op {
            writes: regs,
            reads: 0,
            ..plain(1 + words)
        },
        "vstm" | "vstmia" | "vstmdb" | "vpush" => plain(1 + words),
        "vmla" | "vmls" | "vnmla" | "vnmls" | "vfma" | "vfms" | "vfnma" | "vfnms" => Op {
            kind: Kind::FpMac,
            writes: first,
            ..plain(3)
        },
        "vdiv" | "vsqrt" => Op {
            kind: Kind::FpArith,
            writes: first,
            reads: regs & !first,
            ..plain(14)
        },
        "vadd" | "vsub" | "vmul" | "vnmul" | "vcvt" => Op {
            kind: Kind::FpArith,
            writes: first,
            reads: regs & !first,
            ..plain(1)
        },
        "vmov" => {
            // Two core registers with a double or two singles: 2 cycles.
            let core = operands
                .split(',')
                .filter(|w| w.trim().starts_with('r') || w.trim() == "lr")
                .count();
            let cost = if core >= 2 { 2 } else { 1 };
            Op {
                writes: first,
                reads: regs & !first,
                ..plain(cost)
            }
        }
        _ => plain(1),
    };
    if writes_pc(base, operands) {
        op.kind = Kind::Branch;
    }
    op.class = match base {
        "vadd" | "vsub" | "vmul" | "vnmul" | "vdiv" | "vsqrt" | "vabs" | "vneg" => {
            Class::Arithmetic
        }
        _ if op.kind == Kind::FpMac => Class::Arithmetic,
        "ldr" | "ldrb" | "ldrh" | "ldrsb" | "ldrsh" | "ldrex" | "str" | "strb" | "strh"
        | "strex" | "ldrd" | "strd" | "ldm" | "ldmia" | "ldmdb" | "stm" | "stmia" | "stmdb"
        | "push" | "pop" | "vldr" | "vstr" | "vldm" | "vldmia" | "vldmdb" | "vstm" | "vstmia"
        | "vstmdb" | "vpush" | "vpop" => Class::Transfer,
        "cmp" | "cmn" | "tst" | "teq" | "vcmp" | "vcmpe" | "vmrs" | "it" => Class::Control,
        _ if op.kind == Kind::Branch => Class::Control,
        _ => Class::Other,
    };
    // One cycle, and no result stall after them (the TRM's list leaves
    // them out), but they write their first operand.
    if matches!(base, "vabs" | "vneg") {
        op.writes = first;
        op.reads = regs & !first;
    }
    op
}

/// Cycles of one pass of `ops` on `core`: each instruction's cost, with
/// the pipelined loads and the FPU stalls between neighbours (no branch
/// refill).
fn pass(core: Core, ops: &[&Op]) -> u64 {
    let column = match core {
        Core::M4 => 0,
        Core::M3 => 1,
    };
    let mut once = 0u64;
    let mut previous: Option<&Op> = None;
    for op in ops {
        let mut c = op.cycles[column];
        if let Some(p) = previous {
            let pipelined = p.kind == Kind::Load && matches!(op.kind, Kind::Load | Kind::Store);
            if pipelined {
                c = 1;
            }
            let reads_result = matches!(p.kind, Kind::FpArith | Kind::FpMac)
                && (op.reads | if op.kind == Kind::FpMac { op.writes } else { 0 }) & p.writes != 0;
            let accumulator = op.kind == Kind::FpMac && p.writes & op.writes != 0;
            if reads_result || accumulator {
                c += 1;
            }
        }
        once += c;
        previous = Some(op);
    }
    once
}

/// The block of `window` that ran the most instructions.
pub fn hottest(window: &Window) -> Option<&BlockCount> {
    window.blocks.iter().max_by_key(|b| b.insns * b.execs)
}

/// The firmware's instructions by address, decoded for timing.
#[derive(Debug, Clone, Default)]
pub struct Disassembly {
    ops: BTreeMap<u64, Op>,
    /// Each instruction as printed (`vmla.f32\ts0, s2, s4`).
    texts: BTreeMap<u64, String>,
}

impl Disassembly {
    /// Reads `llvm-objdump -d --no-show-raw-insn` output: lines
    /// `ADDR: <tab>MNEMONIC<tab>OPERANDS`; data (`.word`, `.short`,
    /// `<unknown>`) and other lines are skipped.
    pub fn parse(text: &str) -> Self {
        let mut ops = BTreeMap::new();
        let mut texts = BTreeMap::new();
        for line in text.lines() {
            let Some((addr, rest)) = line.split_once(':') else {
                continue;
            };
            let Ok(addr) = u64::from_str_radix(addr.trim(), 16) else {
                continue;
            };
            let rest = rest.split('@').next().unwrap_or("");
            let mut fields = rest.split('\t').map(str::trim).filter(|f| !f.is_empty());
            let Some(mnemonic) = fields.next() else {
                continue;
            };
            if mnemonic.starts_with('.') || mnemonic.starts_with('<') || mnemonic.contains(' ') {
                continue;
            }
            let operands = fields.next().unwrap_or("");
            ops.insert(addr, decode(mnemonic, operands));
            texts.insert(addr, format!("{mnemonic}\t{operands}"));
        }
        Self { ops, texts }
    }

    /// Instructions known.
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Whether nothing was read.
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// The addresses and decoded instructions of block `b`.
    fn block_ops(&self, b: &BlockCount) -> Result<Vec<(u64, &Op)>, Error> {
        // The block's first `insns` instructions. QEMU 7.2 can report a
        // block's end two bytes late: at a page end its Thumb translator
        // reads the next halfword (to see whether the next instruction
        // crosses the page) into the last instruction's bytes.
        let in_range = self.ops.range(b.start..b.end);
        let starts_at = self.ops.contains_key(&b.start);
        let ops: Vec<(u64, &Op)> = in_range
            .take(b.insns as usize)
            .map(|(a, op)| (*a, op))
            .collect();
        if !starts_at || ops.len() as u64 != b.insns {
            return Err(Error::Block {
                start: b.start,
                end: b.end,
                insns: b.insns,
                found: ops.len() as u64,
            });
        }
        Ok(ops)
    }

    /// The instructions of block `b` as printed, without its last one
    /// when that is a branch, and the model's cycles for one pass of them
    /// on `core` (for comparing with a straight-line model such as
    /// llvm-mca's).
    pub fn straight_line(&self, core: Core, b: &BlockCount) -> Result<(Vec<String>, u64), Error> {
        let mut ops = self.block_ops(b)?;
        if ops.last().is_some_and(|(_, op)| op.kind == Kind::Branch) {
            ops.pop();
        }
        let only: Vec<&Op> = ops.iter().map(|(_, op)| *op).collect();
        let texts = ops
            .iter()
            .map(|(a, _)| self.texts.get(a).cloned().unwrap_or_default())
            .collect();
        Ok((texts, pass(core, &only)))
    }

    /// Cycles of one block on `core`, over its executions.
    fn block(&self, core: Core, b: &BlockCount) -> Result<u64, Error> {
        let ops: Vec<&Op> = self.block_ops(b)?.into_iter().map(|(_, op)| op).collect();
        let once = pass(core, &ops);
        let last_is_branch = ops.last().is_some_and(|op| op.kind == Kind::Branch);
        let refills = if last_is_branch { b.taken } else { 0 };
        Ok(once * b.execs + refills * REFILL)
    }

    /// Estimated cycles of a window on `core`.
    ///
    /// QEMU also ends a block where no branch is (at a page end, or at its
    /// size limit); the code runs on into the block at the next address.
    /// The pair across such a split (a load after a load, an FPU result
    /// read by the next instruction) is timed as in one block, so that a
    /// kernel's cycles do not depend on where it sits in memory.
    pub fn window_cycles(&self, core: Core, window: &Window) -> Result<u64, Error> {
        let mut total = 0u64;
        for b in &window.blocks {
            total += self.block(core, b)?;
            let ops = self.block_ops(b)?;
            let Some(&(last_at, last)) = ops.last() else {
                continue;
            };
            if last.kind == Kind::Branch {
                continue;
            }
            let Some((&next_at, first)) = self.ops.range(last_at + 1..).next() else {
                continue;
            };
            let Some(next) = window.blocks.iter().find(|n| n.start == next_at) else {
                continue;
            };
            let joined = pass(core, &[last, first]);
            let apart = pass(core, &[last]) + pass(core, &[first]);
            let runs_on = b.execs.min(next.execs);
            total = (total + joined * runs_on).saturating_sub(apart * runs_on);
        }
        Ok(total)
    }

    /// Instructions executed in a window by what they do: arithmetic,
    /// transfers, control, other (see [`Split`]).
    pub fn window_split(&self, window: &Window) -> Result<[u64; 4], Error> {
        let mut total = [0u64; 4];
        for b in &window.blocks {
            for (_, op) in self.block_ops(b)? {
                let part = match op.class {
                    Class::Arithmetic => 0,
                    Class::Transfer => 1,
                    Class::Control => 2,
                    Class::Other => 3,
                };
                if let Some(t) = total.get_mut(part) {
                    *t += b.execs;
                }
            }
        }
        Ok(total)
    }
}

/// Joins a target's mix into its kernel lines: each line with windows and
/// a call count gets estimated cycles per call ([`KernelLine::cycles`],
/// [`KernelLine::cycles_call`]) and, on the Cortex-M4F, its instructions by
/// what they do ([`KernelLine::split`]); its instruction counts become the
/// plugin's exact ones (the SysTick figures are rounded to 40
/// instructions over the run), all to a tenth per call.
pub fn attach(
    lines: &mut [KernelLine],
    target: &str,
    mix: &Mix,
    disassembly: &Disassembly,
) -> Result<(), Error> {
    let Some(core) = Core::of_target(target) else {
        return Ok(());
    };
    let mut windows = Windows::new(core, mix, disassembly);
    for line in lines.iter_mut().filter(|l| l.target == target) {
        let (Some([t, e, b]), Some(calls)) = (line.windows, line.calls) else {
            continue;
        };
        if t.is_none() || calls == 0 {
            continue;
        }
        let (t, e, b) = (windows.get(t)?, windows.get(e)?, windows.get(b)?);
        line.cycles = Some(per_call(t.0, e.0, calls));
        line.cycles_call = Some(per_call(t.0, b.0, calls));
        line.net = Some(per_call(t.1, e.1, calls));
        line.per_call = per_call(t.1, b.1, calls);
        if core == Core::M4 {
            let part = |i: usize| {
                let at = |w: &[f64; 4]| w.get(i).copied().unwrap_or(0.0);
                difference_per_call(at(&t.2), at(&e.2), calls)
            };
            line.split = Some(Split {
                arithmetic: part(0),
                transfers: part(1),
                control: part(2),
                other: part(3),
            });
        }
    }
    Ok(())
}

/// Joins the mix of the Cortex-M4F `kalman-peers` run into its lines: each
/// line with windows and a call count gets its exact instructions
/// ([`PeerLine::cost`], [`PeerLine::model`]) and estimated cycles per
/// update ([`PeerLine::cycles`], [`PeerLine::model_cycles`]), each net of
/// its stand-in.
pub fn attach_peers<'l>(
    lines: impl Iterator<Item = &'l mut PeerLine>,
    mix: &Mix,
    disassembly: &Disassembly,
) -> Result<(), Error> {
    let mut windows = Windows::new(Core::M4, mix, disassembly);
    for line in lines {
        let Some(calls) = line.calls.filter(|&c| c > 0) else {
            continue;
        };
        if let Some([b, i]) = line.windows {
            let (b, i) = (windows.get(Some(b))?, windows.get(Some(i))?);
            line.cycles = Some(per_call(b.0, i.0, calls));
            line.cost = per_call(b.1, i.1, calls);
        }
        if let Some([b, i]) = line.model_windows {
            let (b, i) = (windows.get(Some(b))?, windows.get(Some(i))?);
            line.model_cycles = Some(per_call(b.0, i.0, calls));
            line.model = Some(per_call(b.1, i.1, calls));
        }
    }
    Ok(())
}

/// Per call to a tenth, as the firmware prints its SysTick figures: below
/// that is the windows' one-time difference (the set-up around a kernel
/// and around its stand-in differ by a few instructions over thousands of
/// calls).
fn per_call(x: f64, y: f64, calls: u64) -> f64 {
    difference_per_call(x, y, calls).max(0.0)
}

/// [`per_call`] without the floor at zero: the parts of a [`Split`] add up
/// to the net instructions, so a part is negative where the stand-in runs
/// an instruction of its kind that the kernel's code folds away.
fn difference_per_call(x: f64, y: f64, calls: u64) -> f64 {
    ((x - y) / calls as f64 * 10.0).round() / 10.0
}

/// (estimated cycles, instructions, instructions by what they do) of a
/// mix's windows, each computed once.
struct Windows<'a> {
    core: Core,
    mix: &'a Mix,
    disassembly: &'a Disassembly,
    memo: BTreeMap<u32, (f64, f64, [f64; 4])>,
}

impl<'a> Windows<'a> {
    fn new(core: Core, mix: &'a Mix, disassembly: &'a Disassembly) -> Self {
        Self {
            core,
            mix,
            disassembly,
            memo: BTreeMap::new(),
        }
    }

    /// Window `w`'s totals; none: zero.
    fn get(&mut self, w: Option<u32>) -> Result<(f64, f64, [f64; 4]), Error> {
        let Some(w) = w else {
            return Ok((0.0, 0.0, [0.0; 4]));
        };
        if let Some(v) = self.memo.get(&w) {
            return Ok(*v);
        }
        let window = self.mix.window(w)?;
        let v = (
            self.disassembly.window_cycles(self.core, window)? as f64,
            window.insns as f64,
            self.disassembly.window_split(window)?.map(|n| n as f64),
        );
        self.memo.insert(w, v);
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accuracy_cost::firmware::parse_kernels;

    fn dis(lines: &[(u64, &str, &str)]) -> Disassembly {
        let text: String = lines
            .iter()
            .map(|(a, m, o)| format!("{a:8x}:      \t{m}\t{o}\n"))
            .collect();
        Disassembly::parse(&text)
    }

    fn cycles(d: &Disassembly, core: Core, start: u64, end: u64, n: u64) -> u64 {
        let b = BlockCount {
            start,
            end,
            insns: n,
            execs: 1,
            taken: 0,
        };
        d.block(core, &b).unwrap_or(u64::MAX)
    }

    #[test]
    fn mnemonics_reduce_to_their_base() {
        assert_eq!(base("vmla.f32"), Some("vmla"));
        assert_eq!(base("vmls.f32"), Some("vmls"));
        assert_eq!(base("vmovne.f32"), Some("vmov"));
        assert_eq!(base("movs"), None);
        assert_eq!(base("bls"), Some("b"));
        assert_eq!(base("bl"), Some("bl"));
        assert_eq!(base("ldrls.w"), Some("ldr"));
        assert_eq!(base("pophi"), Some("pop"));
        assert_eq!(base("itte"), Some("it"));
        assert_eq!(base("mls"), Some("mls"));
        assert_eq!(base("vldmia"), Some("vldmia"));
        assert_eq!(base("umlal"), Some("umlal"));
        assert_eq!(base("vnegmi.f32"), Some("vneg"));
    }

    #[test]
    fn chained_multiply_accumulates_cost_three_and_a_stall() {
        // vmul then a vmla on its result: 1 + (3 + 1); then a vmla
        // accumulating into the same register: 3 + 1.
        let d = dis(&[
            (0x10, "vmul.f32", "s0, s1, s2"),
            (0x14, "vmla.f32", "s0, s3, s4"),
            (0x18, "vmla.f32", "s0, s5, s6"),
            (0x1c, "vadd.f32", "s8, s9, s10"),
        ]);
        assert_eq!(cycles(&d, Core::M4, 0x10, 0x20, 4), 1 + 4 + 4 + 1);
        // Independent operations: no stall.
        let d = dis(&[
            (0x10, "vmul.f32", "s0, s1, s2"),
            (0x14, "vmul.f32", "s3, s1, s2"),
            (0x18, "vadd.f32", "s0, s0, s3"),
        ]);
        assert_eq!(cycles(&d, Core::M4, 0x10, 0x1c, 3), 1 + 1 + 2);
        // A negation overwriting the result it follows reads nothing of it.
        let d = dis(&[
            (0x10, "vmul.f32", "s0, s1, s2"),
            (0x14, "vneg.f32", "s0, s3"),
        ]);
        assert_eq!(cycles(&d, Core::M4, 0x10, 0x18, 2), 1 + 1);
    }

    #[test]
    fn neighbouring_loads_pipeline_and_lists_cost_per_word() {
        let d = dis(&[
            (0x00, "ldr", "r0, [r1]"),
            (0x02, "ldr", "r2, [r1, #0x4]"),
            (0x04, "str", "r2, [r3]"),
            (0x06, "str", "r0, [r3, #0x4]"),
            (0x08, "push", "{r4, r5, r7, lr}"),
            (0x0a, "vpush", "{d8, d9}"),
            (0x0e, "vldmia", "r0, {s0-s3}"),
        ]);
        // 2 + 1 + 1 (after a load) + 2 (after a store) + 5 + 5 + 5.
        assert_eq!(cycles(&d, Core::M4, 0, 0x12, 7), 2 + 1 + 1 + 2 + 5 + 5 + 5);
    }

    #[test]
    fn taken_branches_pay_the_refill_and_the_m3_its_slow_multiplies() {
        let d = dis(&[
            (0x00, "umull", "r0, r1, r2, r3"),
            (0x04, "mla", "r0, r1, r2, r3"),
            (0x08, "subs", "r4, #0x1"),
            (0x0a, "bne", "0x0"),
        ]);
        let b = BlockCount {
            start: 0,
            end: 0x0c,
            insns: 4,
            execs: 10,
            taken: 9,
        };
        assert_eq!(d.block(Core::M4, &b), Ok(4 * 10 + 9 * REFILL));
        assert_eq!(d.block(Core::M3, &b), Ok((5 + 2 + 1 + 1) * 10 + 9 * REFILL));
        // A return by pop is a branch too.
        let d = dis(&[(0x00, "pop", "{r4, pc}")]);
        let b = BlockCount {
            start: 0,
            end: 2,
            insns: 1,
            execs: 3,
            taken: 3,
        };
        assert_eq!(d.block(Core::M4, &b), Ok(3 * 3 + 3 * REFILL));
    }

    #[test]
    fn a_block_split_without_a_branch_is_timed_as_one() {
        // Two loads, split by QEMU between them: the second pipelines
        // behind the first as in one block (2 + 1, not 2 + 2), on every
        // one of the 10 passes.
        let d = dis(&[
            (0x100, "vldr", "s0, [r0]"),
            (0x104, "vldr", "s1, [r0, #4]"),
            (0x108, "bx", "lr"),
        ]);
        let split = Window {
            insns: 30,
            blocks: vec![
                BlockCount {
                    start: 0x100,
                    end: 0x104,
                    insns: 1,
                    execs: 10,
                    taken: 0,
                },
                BlockCount {
                    start: 0x104,
                    end: 0x10a,
                    insns: 2,
                    execs: 10,
                    taken: 10,
                },
            ],
        };
        let whole = Window {
            insns: 30,
            blocks: vec![BlockCount {
                start: 0x100,
                end: 0x10a,
                insns: 3,
                execs: 10,
                taken: 10,
            }],
        };
        let (a, b) = (
            d.window_cycles(Core::M4, &split),
            d.window_cycles(Core::M4, &whole),
        );
        assert_eq!(a, b);
        assert!(a.is_ok_and(|c| c > 0));
    }

    #[test]
    fn a_block_end_read_past_its_last_instruction_is_tolerated() {
        // Seven 4-byte instructions, an eighth across the end: the block
        // holds the first seven.
        let lines: Vec<(u64, &str, &str)> = (0..8)
            .map(|i| (0x3e2 + 4 * i, "vldr", "s0, [r0]"))
            .collect();
        let d = dis(&lines);
        assert_eq!(cycles(&d, Core::M4, 0x3e2, 0x400, 7), 7 * 2);
        assert_eq!(cycles(&d, Core::M4, 0x3e4, 0x400, 7), u64::MAX);
    }

    #[test]
    fn a_block_off_the_disassembly_is_an_error() {
        let d = dis(&[(0x00, "nop", ""), (0x02, "nop", "")]);
        let b = BlockCount {
            start: 0,
            end: 4,
            insns: 3,
            execs: 1,
            taken: 0,
        };
        assert!(matches!(
            d.block(Core::M4, &b),
            Err(Error::Block { found: 2, .. })
        ));
    }

    #[test]
    fn mixes_are_read_and_broken_ones_named() {
        let good = "qemu-mix 1 open=0x10 close=0x20\nwindow 0 insns=3 blocks=1\n\
                    tb 0x00000030 0x00000036 3 1 1\nend windows=1\n";
        let mix = Mix::parse("m", good).unwrap_or_default();
        assert_eq!(mix.windows.len(), 1);
        assert_eq!(mix.window(0).map(|w| w.insns), Ok(3));
        assert!(matches!(
            mix.window(1),
            Err(Error::NoWindow { window: 1, ref source_name }) if source_name == "m"
        ));
        let cut = good.replace("end windows=1\n", "");
        assert_eq!(Mix::parse("m", &cut), Err(Error::Unfinished("m".into())));
        let bad = good.replace("3 1 1", "3 1 2");
        assert!(matches!(
            Mix::parse("m", &bad),
            Err(Error::Mix { line: 3, .. })
        ));
        let failed = good.replace("end windows=1", "error window 1 never closed");
        assert!(matches!(
            Mix::parse("m", &failed),
            Err(Error::Mix { line: 4, .. })
        ));
    }

    #[test]
    fn instructions_are_split_per_execution_net_of_the_stand_in() {
        // The kernel: a multiply, a multiply-accumulate, an absolute value
        // (arithmetic); a load, a push, a store of two words (transfers); a
        // compare, the move of its flags, an IT, a conditional branch
        // (control); a conversion, two moves and an integer add (other);
        // the return. The stand-in: a negation and the return.
        let d = dis(&[
            (0x100, "vmul.f32", "s0, s1, s2"),
            (0x104, "vmla.f32", "s0, s3, s4"),
            (0x108, "vabs.f32", "s5, s0"),
            (0x10c, "vldr", "s8, [r0]"),
            (0x110, "push", "{r4, lr}"),
            (0x112, "strd", "r1, r2, [sp]"),
            (0x116, "vcmp.f32", "s5, s6"),
            (0x11a, "vmrs", "APSR_nzcv, fpscr"),
            (0x11e, "it", "gt"),
            (0x120, "movgt", "r0, #1"),
            (0x122, "cmp", "r0, #2"),
            (0x124, "bne", "0x100"),
            (0x126, "vcvt.s32.f32", "s7, s5"),
            (0x12a, "vmov", "r1, s8"),
            (0x12e, "adds", "r1, #4"),
            (0x130, "bx", "lr"),
            (0x200, "vneg.f32", "s0, s0"),
            (0x204, "bx", "lr"),
        ]);
        let run = |start, end, insns| Window {
            insns: 4 * insns,
            blocks: vec![BlockCount {
                start,
                end,
                insns,
                execs: 4,
                taken: 4,
            }],
        };
        let mix = Mix {
            windows: vec![run(0x100, 0x132, 16), run(0x200, 0x206, 2)],
            source_name: "m".into(),
        };
        assert_eq!(d.window_split(&mix.windows[0]), Ok([12, 12, 24, 16]));
        assert_eq!(d.window_split(&mix.windows[1]), Ok([4, 0, 4, 0]));
        let text = "kernel target=m4f type=f32 family=f name=k n=1 per_call=9 calls=4 \
                    windows=0,1,-1";
        let mut m4f = parse_kernels("t", text).unwrap_or_default();
        assert!(attach(&mut m4f, "m4f", &mix, &d).is_ok());
        // Per call, less the stand-in's: (12 - 4) / 4, 12 / 4, (24 - 4) / 4,
        // 16 / 4; together the net instructions, (64 - 8) / 4.
        let split = Split {
            arithmetic: 2.0,
            transfers: 3.0,
            control: 5.0,
            other: 4.0,
        };
        assert_eq!(m4f.first().and_then(|l| l.split), Some(split));
        assert_eq!(m4f.first().and_then(|l| l.net), Some(14.0));
        // A part below the stand-in's stays negative, so that the parts
        // still add up; the instruction count does not go below zero.
        assert_eq!(difference_per_call(4.0, 8.0, 4), -1.0);
        assert_eq!(per_call(4.0, 8.0, 4), 0.0);
        // Counted on the Cortex-M4F only.
        let mut m3 = parse_kernels("t", &text.replace("m4f", "m3")).unwrap_or_default();
        assert!(attach(&mut m3, "m3", &mix, &d).is_ok());
        assert_eq!(m3.first().map(|l| l.split), Some(None));
    }

    #[test]
    fn objdump_lines_are_read_and_data_skipped() {
        let text = "\n00000400 <__stext>:\n     400:      \tbl\t0x8deac <__pre_init>    @ imm = #0x8daa8\n\
                    \x20    404:      \tvmla.f32\ts0, s2, s4\n     440: 00 00 00 20  \t.word\t0x20000000\n";
        let d = Disassembly::parse(text);
        assert_eq!(d.len(), 2);
        assert_eq!(d.ops.get(&0x404).map(|o| o.kind), Some(Kind::FpMac));
    }
}
