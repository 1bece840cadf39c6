//! A QEMU TCG plugin that records, for each measured window of the
//! kernel-cost firmware, which translation blocks ran, how often, and how
//! often each left by a taken branch. `bushing-sim accuracy-cost` maps the
//! blocks onto the ELF's disassembly and weighs every executed instruction
//! by the Cortex-M4 timing tables: estimated cycles beside the instruction
//! counts.
//!
//! The firmware brackets each measurement with two marker functions,
//! `window_open` and `window_close` (`bushing_boards::probe`); the plugin
//! finds their addresses in the ELF given as `elf=` and writes to `out=`:
//!
//! ```text
//! qemu-mix 1 open=0x00001234 close=0x00001240
//! window 0 insns=5120 blocks=3
//! tb 0x00002000 0x0000200c 5 1024 1023
//! ...
//! end windows=1
//! ```
//!
//! A `tb` line is one translation: start and end address (one past its
//! last instruction), its instruction count, its executions in the window,
//! and how many of those left it for an address other than its end (a
//! taken branch, a call, a return). The `end` line is written only when
//! every window closed and every write succeeded, so a run that failed
//! leaves a file the reader refuses.
//!
//! Run with
//! `qemu-system-arm ... -plugin libbushing_qemu_mix.so,elf=FW.elf,out=MIX.txt -kernel FW.elf`.

mod ffi;

use std::io::{self, Write};

/// Format version of the output's first line.
pub const FORMAT: u32 = 1;

/// Addresses of the two marker functions (Thumb bit cleared).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Marks {
    /// Start of `window_open`.
    pub open: u64,
    /// Start of `window_close`.
    pub close: u64,
}

/// Why the markers could not be found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MarkError {
    /// Not an ELF file the reader understands.
    Elf(String),
    /// No symbol, or more than one, for a marker.
    Symbol {
        /// The marker's name.
        name: &'static str,
        /// How many symbols matched.
        found: usize,
    },
}

impl std::fmt::Display for MarkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Elf(why) => write!(f, "not a readable ELF file: {why}"),
            Self::Symbol { name, found } => {
                write!(f, "{found} symbols named like '{name}' (want exactly 1)")
            }
        }
    }
}

impl Marks {
    /// The marker addresses from an ELF's symbol table: the one function
    /// whose (mangled) name contains `window_open`, and `window_close`.
    pub fn from_elf(bytes: &[u8]) -> Result<Self, MarkError> {
        use object::{Object, ObjectSymbol, SymbolKind};
        let file = object::File::parse(bytes).map_err(|e| MarkError::Elf(e.to_string()))?;
        let find = |name: &'static str| {
            let found: Vec<u64> = file
                .symbols()
                .filter(|s| s.kind() == SymbolKind::Text)
                .filter(|s| s.name().is_ok_and(|n| n.contains(name)))
                .map(|s| s.address() & !1)
                .collect();
            match found.as_slice() {
                [one] => Ok(*one),
                _ => Err(MarkError::Symbol {
                    name,
                    found: found.len(),
                }),
            }
        };
        Ok(Self {
            open: find("window_open")?,
            close: find("window_close")?,
        })
    }
}

/// One translation block and its counts in the open window.
#[derive(Debug, Clone, Copy)]
struct Block {
    start: u64,
    end: u64,
    insns: u64,
    execs: u64,
    taken: u64,
}

/// The plugin's state: every translation, the open window's counts and
/// the output.
#[derive(Debug)]
pub struct Recorder<W: Write> {
    marks: Marks,
    blocks: Vec<Block>,
    touched: Vec<usize>,
    previous: Option<usize>,
    open: bool,
    windows: u64,
    insns: u64,
    out: W,
    failure: Option<String>,
}

impl<W: Write> Recorder<W> {
    /// A recorder writing to `out`; writes the header line.
    pub fn new(marks: Marks, mut out: W) -> io::Result<Self> {
        writeln!(
            out,
            "qemu-mix {FORMAT} open={:#010x} close={:#010x}",
            marks.open, marks.close
        )?;
        Ok(Self {
            marks,
            blocks: Vec::new(),
            touched: Vec::new(),
            previous: None,
            open: false,
            windows: 0,
            insns: 0,
            out,
            failure: None,
        })
    }

    /// Records a new translation of `insns` instructions from `start` to
    /// `end`; returns the id its executions are reported with.
    pub fn translated(&mut self, start: u64, end: u64, insns: u64) -> usize {
        self.blocks.push(Block {
            start,
            end,
            insns,
            execs: 0,
            taken: 0,
        });
        self.blocks.len() - 1
    }

    /// Block `id` is about to run.
    pub fn executed(&mut self, id: usize) {
        let Some(&Block { start, .. }) = self.blocks.get(id) else {
            self.fail(format!("execution of unknown block {id}"));
            return;
        };
        if self.open
            && let Some(p) = self.previous.and_then(|p| self.blocks.get_mut(p))
            && p.end != start
        {
            p.taken += 1;
        }
        if start == self.marks.open {
            if self.open {
                self.fail(format!("window {} opened twice", self.windows));
            }
            self.open = true;
            self.previous = None;
            self.insns = 0;
            return;
        }
        if start == self.marks.close && self.open {
            self.close();
            return;
        }
        if !self.open {
            return;
        }
        if let Some(b) = self.blocks.get_mut(id) {
            if b.execs == 0 {
                self.touched.push(id);
            }
            b.execs += 1;
            self.insns += b.insns;
        }
        self.previous = Some(id);
    }

    fn close(&mut self) {
        self.open = false;
        self.previous = None;
        let mut touched = std::mem::take(&mut self.touched);
        touched.sort_by_key(|&id| self.blocks.get(id).map(|b| (b.start, b.end)));
        let result = (|| {
            writeln!(
                self.out,
                "window {} insns={} blocks={}",
                self.windows,
                self.insns,
                touched.len()
            )?;
            for &id in &touched {
                if let Some(b) = self.blocks.get_mut(id) {
                    writeln!(
                        self.out,
                        "tb {:#010x} {:#010x} {} {} {}",
                        b.start, b.end, b.insns, b.execs, b.taken
                    )?;
                    b.execs = 0;
                    b.taken = 0;
                }
            }
            Ok::<(), io::Error>(())
        })();
        if let Err(e) = result {
            self.fail(format!("writing window {}: {e}", self.windows));
        }
        touched.clear();
        self.touched = touched;
        self.windows += 1;
    }

    fn fail(&mut self, why: String) {
        if self.failure.is_none() {
            self.failure = Some(why);
        }
    }

    /// Ends the output: the `end` line when every window closed and every
    /// write succeeded, else an `error` line; the error is returned too.
    pub fn finish(&mut self) -> Result<(), String> {
        if self.open {
            self.fail(format!("window {} never closed", self.windows));
        }
        let line = match &self.failure {
            None => format!("end windows={}", self.windows),
            Some(why) => format!("error {why}"),
        };
        let written = writeln!(self.out, "{line}").and_then(|()| self.out.flush());
        match (self.failure.clone(), written) {
            (Some(why), _) => Err(why),
            (None, Err(e)) => Err(format!("writing the end line: {e}")),
            (None, Ok(())) => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MARKS: Marks = Marks {
        open: 0x100,
        close: 0x200,
    };

    fn text(r: Recorder<Vec<u8>>) -> String {
        String::from_utf8(r.out).unwrap_or_default()
    }

    #[test]
    fn a_window_counts_blocks_and_taken_exits() {
        let mut r = Recorder::new(MARKS, Vec::new()).unwrap();
        let open = r.translated(0x100, 0x104, 2);
        let close = r.translated(0x200, 0x206, 3);
        let head = r.translated(0x300, 0x308, 3);
        let body = r.translated(0x308, 0x310, 4);
        let outside = r.translated(0x400, 0x404, 1);
        r.executed(outside);
        r.executed(open);
        // Three passes of a loop: head falls into body, body branches back
        // to head twice, then leaves for the close marker.
        for _ in 0..3 {
            r.executed(head);
            r.executed(body);
        }
        r.executed(close);
        r.executed(outside);
        assert_eq!(r.finish(), Ok(()));
        let out = text(r);
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(
            lines,
            [
                "qemu-mix 1 open=0x00000100 close=0x00000200",
                "window 0 insns=21 blocks=2",
                "tb 0x00000300 0x00000308 3 3 0",
                "tb 0x00000308 0x00000310 4 3 3",
                "end windows=1",
            ]
        );
    }

    #[test]
    fn an_unclosed_window_ends_in_an_error_line() {
        let mut r = Recorder::new(MARKS, Vec::new()).unwrap();
        let open = r.translated(0x100, 0x104, 2);
        r.executed(open);
        assert!(r.finish().is_err());
        assert!(text(r).ends_with("error window 0 never closed\n"));
    }

    #[test]
    fn an_unknown_block_is_an_error_not_a_panic() {
        let mut r = Recorder::new(MARKS, Vec::new()).unwrap();
        r.executed(7);
        assert_eq!(r.finish(), Err("execution of unknown block 7".into()));
    }

    #[test]
    fn a_file_that_is_not_elf_has_no_marks() {
        assert!(matches!(
            Marks::from_elf(b"not elf"),
            Err(MarkError::Elf(_))
        ));
    }
}
