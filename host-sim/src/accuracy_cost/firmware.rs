//! What the firmware printed: `kernel ...` lines of `kernel-cost`,
//! `kalman ...` lines of `kalman-peers`, and the firmware ELF files (code
//! size of each measured function, flash and static RAM, read with the
//! `object` crate).
//!
//! Lines are `key=value` words separated by spaces after the leading word.
//! Unknown keys are kept; a line that starts with the leading word but
//! cannot be read is an error naming its file, line number and text. Other
//! lines (comments, QEMU or cargo chatter) are skipped.

use std::collections::{BTreeMap, BTreeSet};

use object::elf;
use object::read::elf::{ElfFile32, SectionHeader, Sym};
use object::{Object, ObjectSection};

/// A firmware output or ELF file that cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A `kernel` or `kalman` line that cannot be read.
    #[error("{origin}: malformed {word} line '{line}': {problem}")]
    Line {
        /// `file:line`.
        origin: String,
        /// The leading word: `kernel` or `kalman`.
        word: &'static str,
        /// The line as printed (trimmed).
        line: String,
        /// What is wrong with it.
        problem: LineProblem,
    },
    /// A `kernel` line with nothing after the word.
    #[error("{origin}: empty kernel line")]
    EmptyKernelLine {
        /// `file:line`.
        origin: String,
    },
    /// An ELF file that cannot be read.
    #[error("{what}: not a readable 32-bit ELF file ({reason})")]
    Elf {
        /// The file as given (`--elf TRIPLE=PATH`: the triple).
        what: String,
        /// What the reader found.
        reason: String,
    },
}

/// What is wrong with a line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LineProblem {
    /// A word without `=`.
    #[error("'{0}' is not key=value")]
    NotKeyValue(String),
    /// `=value` or `key=`.
    #[error("'{0}' has an empty key or value")]
    Empty(String),
    /// The same key twice.
    #[error("key '{0}' given twice")]
    Twice(String),
    /// A required key is missing.
    #[error("no {0}=")]
    Missing(&'static str),
    /// A value that is not a number.
    #[error("{key}={text} is not a number")]
    NotNumber {
        /// The key.
        key: &'static str,
        /// Its value.
        text: String,
    },
    /// A number that is negative, infinite or NaN.
    #[error("{key}={text} is not a finite number >= 0")]
    NotFinite {
        /// The key.
        key: &'static str,
        /// Its value.
        text: String,
    },
    /// A value that is not an unsigned integer.
    #[error("{key}={text} is not an unsigned integer")]
    NotInteger {
        /// The key.
        key: &'static str,
        /// Its value.
        text: String,
    },
    /// `n=` beyond `usize`.
    #[error("n too large")]
    TooLarge,
}

/// Where a kernel runs: `m4f`, `m3`, or whatever the line says.
pub type Target = String;

/// One `kernel ...` line.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelLine {
    /// `target=`: `m4f` or `m3`.
    pub target: Target,
    /// `type=`: number type (`f32`, `f64`, `fixed`, ...).
    pub number: String,
    /// `family=`.
    pub family: String,
    /// `name=`.
    pub name: String,
    /// `n=`: order (cells, taps, states).
    pub n: usize,
    /// `input=`: the input the kernel ran on (`sine`, `small-sine`,
    /// `noise`, or `own` for a kernel that takes no signal). Lines of
    /// the same kernel on several inputs are merged into the costliest,
    /// which keeps this name.
    pub input: Option<String>,
    /// Every input the kernel was measured on, with its instructions and
    /// estimated cycles per call (filled when lines are merged).
    pub by_input: Vec<InputCost>,
    /// `per_call=`: guest instructions per call, call included.
    pub per_call: f64,
    /// `net=`: the same without the call (what the kernel costs inlined),
    /// when printed.
    pub net: Option<f64>,
    /// `state_bytes=`.
    pub state_bytes: Option<u64>,
    /// `params_bytes=`.
    pub params_bytes: Option<u64>,
    /// `fn=`: address of the measured function (0: none).
    pub function: Option<u64>,
    /// `calls=`: calls measured.
    pub calls: Option<u64>,
    /// `windows=T,E,B`: the numbers of the probe windows of the kernel,
    /// its empty stand-in and the harness baseline (`-1`: none), for the
    /// executed-instruction mix.
    pub windows: Option<[Option<u32>; 3]>,
    /// Estimated cycles per call, net of the call (from the mix), when a
    /// mix was given for the line's target.
    pub cycles: Option<f64>,
    /// Estimated cycles per call, call included.
    pub cycles_call: Option<f64>,
    /// The instructions per call, net of the call, by what they do, from
    /// the Cortex-M4F mix.
    pub split: Option<Split>,
    /// Every key of the line, as printed.
    pub fields: BTreeMap<String, String>,
    /// `file:line`, for messages.
    pub origin: String,
}

/// A kernel's Cortex-M4F instructions per call, net of the call, by what
/// they do: what computes, what moves data between registers and memory,
/// and what decides. Arithmetic and transfers together are a floor the
/// kernel's code cannot go below without computing less or keeping more
/// in registers.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Split {
    /// FPU arithmetic: add, subtract, multiply and its accumulating forms,
    /// divide, square root, absolute value, negate.
    pub arithmetic: f64,
    /// Loads and stores, of one register or several (pushes and pops too).
    pub transfers: f64,
    /// Compares and tests (the FPU's with the move of its flags), IT and
    /// branches (calls and returns too).
    pub control: f64,
    /// The rest: register moves, integer arithmetic, conversions.
    pub other: f64,
}

impl Split {
    /// The entry-wise sum.
    pub fn plus(self, o: Self) -> Self {
        Self {
            arithmetic: self.arithmetic + o.arithmetic,
            transfers: self.transfers + o.transfers,
            control: self.control + o.control,
            other: self.other + o.other,
        }
    }
}

/// A kernel's cost on one input.
#[derive(Debug, Clone, PartialEq)]
pub struct InputCost {
    /// The input's name.
    pub input: String,
    /// Instructions per call, net of the call.
    pub instructions: f64,
    /// Estimated cycles per call, net of the call.
    pub cycles: Option<f64>,
}

impl KernelLine {
    /// This line's cost as an [`InputCost`] (unnamed input: `-`).
    pub fn input_cost(&self) -> InputCost {
        InputCost {
            input: self.input.clone().unwrap_or_else(|| "-".into()),
            instructions: self.instructions(),
            cycles: self.cycles,
        }
    }

    /// Instructions per call as the report counts them: `net` when the
    /// firmware printed it, else `per_call`.
    pub fn instructions(&self) -> f64 {
        self.net.unwrap_or(self.per_call)
    }
}

/// One `kalman ...` line of `kalman-peers`.
#[derive(Debug, Clone, PartialEq)]
pub struct PeerLine {
    /// `name=`.
    pub name: String,
    /// `crate=`: `crate@version`, or `bushing` for ours.
    pub krate: String,
    /// `filter=`: `ekf`, `ukf`, `kf`.
    pub filter: String,
    /// `cost=`.
    pub cost: f64,
    /// `unit=`: `instructions` or `ns`.
    pub unit: String,
    /// `model=`: the cost of the harness's model functions (f(x), F,
    /// h(x), H) inside a peer's update, in the same unit; none for ours.
    pub model: Option<f64>,
    /// `freq_err_pct=`.
    pub freq_err_pct: Option<f64>,
    /// `damp_err_pts=`.
    pub damp_err_pts: Option<f64>,
    /// `amp_rms=`.
    pub amp_rms: Option<f64>,
    /// Which input it came from (file name).
    pub source: String,
    /// `calls=`: updates measured (on the target).
    pub calls: Option<u64>,
    /// `windows=B,I`: the probe windows of the filter's pass and of its
    /// stand-in's (on the target).
    pub windows: Option<[u32; 2]>,
    /// `model_windows=B,I`: the same for the model functions alone.
    pub model_windows: Option<[u32; 2]>,
    /// Estimated Cortex-M4 cycles per update, from the run's instruction
    /// mix when one was given.
    pub cycles: Option<f64>,
    /// The same for the model functions alone.
    pub model_cycles: Option<f64>,
}

impl PeerLine {
    /// Estimated cycles of the filter alone, without the model functions
    /// the harness gives it.
    pub fn filter_only_cycles(&self) -> Option<f64> {
        Some(self.cycles? - self.model_cycles.unwrap_or(0.0))
    }

    /// The filter's own cost: [`PeerLine::cost`] less the model functions
    /// the harness gives it.
    pub fn filter_only(&self) -> f64 {
        self.cost - self.model.unwrap_or(0.0)
    }

    /// True for our own tracker.
    pub fn is_ours(&self) -> bool {
        self.krate == "bushing" || self.krate.starts_with("bushing@")
    }
}

/// Splits `key=value` words.
fn fields(words: &str) -> Result<BTreeMap<String, String>, LineProblem> {
    let mut out = BTreeMap::new();
    for word in words.split_whitespace() {
        let (k, v) = word
            .split_once('=')
            .ok_or_else(|| LineProblem::NotKeyValue(word.into()))?;
        if k.is_empty() || v.is_empty() {
            return Err(LineProblem::Empty(word.into()));
        }
        if out.insert(k.to_string(), v.to_string()).is_some() {
            return Err(LineProblem::Twice(k.into()));
        }
    }
    Ok(out)
}

/// A required key.
fn required<'a>(
    f: &'a BTreeMap<String, String>,
    key: &'static str,
) -> Result<&'a str, LineProblem> {
    f.get(key)
        .map(String::as_str)
        .ok_or(LineProblem::Missing(key))
}

/// A number (finite, >= 0).
fn number(text: &str, key: &'static str) -> Result<f64, LineProblem> {
    let v: f64 = text.parse().map_err(|_| LineProblem::NotNumber {
        key,
        text: text.into(),
    })?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(LineProblem::NotFinite {
            key,
            text: text.into(),
        })
    }
}

fn optional_number(
    f: &BTreeMap<String, String>,
    key: &'static str,
) -> Result<Option<f64>, LineProblem> {
    f.get(key).map(|t| number(t, key)).transpose()
}

/// An unsigned integer, decimal or `0x` hexadecimal.
fn integer(text: &str, key: &'static str) -> Result<u64, LineProblem> {
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => text.parse(),
    };
    parsed.map_err(|_| LineProblem::NotInteger {
        key,
        text: text.into(),
    })
}

fn optional_integer(
    f: &BTreeMap<String, String>,
    key: &'static str,
) -> Result<Option<u64>, LineProblem> {
    f.get(key).map(|t| integer(t, key)).transpose()
}

/// `windows=T,E,B`: three window numbers, `-1` for none.
fn windows(f: &BTreeMap<String, String>) -> Result<Option<[Option<u32>; 3]>, LineProblem> {
    let Some(text) = f.get("windows") else {
        return Ok(None);
    };
    let bad = || LineProblem::NotInteger {
        key: "windows",
        text: text.clone(),
    };
    let parts: Vec<Option<u32>> = text
        .split(',')
        .map(|w| match w {
            "-1" => Ok(None),
            _ => w.parse().map(Some).map_err(|_| bad()),
        })
        .collect::<Result<_, _>>()?;
    let [t, e, b] = parts[..] else {
        return Err(bad());
    };
    Ok(Some([t, e, b]))
}

/// One `kernel ...` line's words (after the leading word).
fn kernel_line(rest: &str, origin: String) -> Result<KernelLine, LineProblem> {
    let f = fields(rest)?;
    let n = integer(required(&f, "n")?, "n")?;
    let n = usize::try_from(n).map_err(|_| LineProblem::TooLarge)?;
    Ok(KernelLine {
        target: required(&f, "target")?.to_string(),
        number: required(&f, "type")?.to_string(),
        family: required(&f, "family")?.to_string(),
        name: required(&f, "name")?.to_string(),
        n,
        input: f.get("input").cloned(),
        by_input: Vec::new(),
        per_call: number(required(&f, "per_call")?, "per_call")?,
        net: optional_number(&f, "net")?,
        state_bytes: optional_integer(&f, "state_bytes")?,
        params_bytes: optional_integer(&f, "params_bytes")?,
        function: optional_integer(&f, "fn")?,
        calls: optional_integer(&f, "calls")?,
        windows: windows(&f)?,
        cycles: None,
        cycles_call: None,
        split: None,
        fields: f,
        origin,
    })
}

/// Reads every `kernel ...` line of `text` (from `source`, for messages).
pub fn parse_kernels(source: &str, text: &str) -> Result<Vec<KernelLine>, Error> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        let origin = format!("{source}:{}", i + 1);
        let Some(rest) = line.strip_prefix("kernel ") else {
            if line == "kernel" {
                return Err(Error::EmptyKernelLine { origin });
            }
            continue;
        };
        let parsed = kernel_line(rest, origin.clone()).map_err(|problem| Error::Line {
            origin,
            word: "kernel",
            line: line.into(),
            problem,
        })?;
        out.push(parsed);
    }
    Ok(out)
}

/// One `kalman ...` line's words (after the leading word).
fn peer_line(rest: &str, source: &str) -> Result<PeerLine, LineProblem> {
    let f = fields(rest)?;
    // Errors may be signed or missing ("nan" when a filter diverged).
    let error = |key: &'static str| -> Result<Option<f64>, LineProblem> {
        match f.get(key) {
            None => Ok(None),
            Some(t) => {
                let v: f64 = t.parse().map_err(|_| LineProblem::NotNumber {
                    key,
                    text: t.clone(),
                })?;
                Ok(v.is_finite().then_some(v.abs()))
            }
        }
    };
    Ok(PeerLine {
        name: required(&f, "name")?.to_string(),
        krate: required(&f, "crate")?.to_string(),
        filter: required(&f, "filter")?.to_string(),
        cost: number(required(&f, "cost")?, "cost")?,
        unit: required(&f, "unit")?.to_string(),
        model: optional_number(&f, "model")?,
        freq_err_pct: error("freq_err_pct")?,
        damp_err_pts: error("damp_err_pts")?,
        amp_rms: error("amp_rms")?,
        source: source.to_string(),
        calls: optional_integer(&f, "calls")?,
        windows: window_pair(&f, "windows")?,
        model_windows: window_pair(&f, "model_windows")?,
        cycles: None,
        model_cycles: None,
    })
}

/// `KEY=B,I`: two window numbers.
fn window_pair(
    f: &BTreeMap<String, String>,
    key: &'static str,
) -> Result<Option<[u32; 2]>, LineProblem> {
    let Some(text) = f.get(key) else {
        return Ok(None);
    };
    let bad = || LineProblem::NotInteger {
        key,
        text: text.clone(),
    };
    let (b, i) = text.split_once(',').ok_or_else(bad)?;
    match (b.parse(), i.parse()) {
        (Ok(b), Ok(i)) => Ok(Some([b, i])),
        _ => Err(bad()),
    }
}

/// Reads every `kalman ...` line of `text`.
pub fn parse_peers(source: &str, text: &str) -> Result<Vec<PeerLine>, Error> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        let Some(rest) = line.strip_prefix("kalman ") else {
            continue;
        };
        out.push(peer_line(rest, source).map_err(|problem| Error::Line {
            origin: format!("{source}:{}", i + 1),
            word: "kalman",
            line: line.into(),
            problem,
        })?);
    }
    Ok(out)
}

/// Which report target an ELF given as `--elf TRIPLE=PATH` belongs to.
pub fn target_of_triple(triple: &str) -> Target {
    match triple {
        "thumbv7em-none-eabihf" | "m4f" => "m4f".into(),
        "thumbv7m-none-eabi" | "m3" => "m3".into(),
        other => other.into(),
    }
}

/// A section header of an ELF32 file.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Name from the section-name string table.
    pub name: String,
    /// `sh_type`.
    pub kind: u32,
    /// `sh_flags`.
    pub flags: u64,
    /// `sh_addr`.
    pub addr: u64,
    /// `sh_size`.
    pub size: u64,
}

/// A function symbol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Function {
    /// Address, Thumb bit cleared.
    pub addr: u64,
    /// Size in bytes.
    pub size: u64,
}

/// The parts of an ELF32 file the report uses.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Elf {
    /// Every section.
    pub sections: Vec<Section>,
    /// Every `STT_FUNC` symbol of `.symtab`.
    pub functions: Vec<Function>,
    /// The bytes of each executable section, with its address.
    pub code: Vec<(u64, Vec<u8>)>,
}

impl Elf {
    /// Reads the section headers and the function symbols of an ELF32
    /// file; `what` names it in errors.
    pub fn parse(bytes: &[u8], what: &str) -> Result<Self, Error> {
        let bad = |reason: object::read::Error| Error::Elf {
            what: what.into(),
            reason: reason.to_string(),
        };
        let file = ElfFile32::<object::Endianness>::parse(bytes).map_err(bad)?;
        let endian = file.endian();
        let mut sections = Vec::new();
        let mut code = Vec::new();
        for s in file.sections() {
            let header = s.elf_section_header();
            if header.sh_flags(endian).0 & elf::SHF_EXECINSTR.0 != 0
                && header.sh_type(endian) != elf::SHT_NOBITS
            {
                code.push((s.address(), s.data().map_err(bad)?.to_vec()));
            }
            sections.push(Section {
                name: String::from_utf8_lossy(s.name_bytes().map_err(bad)?).into_owned(),
                kind: header.sh_type(endian).0,
                flags: header.sh_flags(endian).0,
                addr: u64::from(header.sh_addr(endian)),
                size: u64::from(header.sh_size(endian)),
            });
        }
        let functions = file
            .symbols()
            .map(|s| s.elf_symbol())
            .filter(|s| s.st_type() == elf::STT_FUNC)
            .map(|s| Function {
                addr: u64::from(s.st_value(endian)) & !1,
                size: u64::from(s.st_size(endian)),
            })
            .collect();
        Ok(Self {
            sections,
            functions,
            code,
        })
    }

    /// Code size of the function at `addr` with every function it reaches
    /// by calls (`BL`) and tail calls (`B.W` to a function's start),
    /// followed to the end and each counted once: what a firmware links
    /// for that call. Calls through a register are not followed.
    pub fn code_size(&self, addr: u64) -> Option<u64> {
        let start = addr & !1;
        self.function_size(start)?;
        let mut seen = BTreeSet::new();
        let mut todo = vec![start];
        let mut total = 0;
        while let Some(f) = todo.pop() {
            if !seen.insert(f) {
                continue;
            }
            let Some(size) = self.function_size(f) else {
                continue;
            };
            total += size;
            todo.extend(self.callees(f, size).filter(|t| !seen.contains(t)));
        }
        Some(total)
    }

    /// The function starts that the `BL` and `B.W` instructions of
    /// `[addr, addr + size)` jump to, decoded as Thumb-2 from the start.
    fn callees(&self, addr: u64, size: u64) -> impl Iterator<Item = u64> + '_ {
        let bytes = self
            .code
            .iter()
            .find_map(|(at, bytes)| {
                let from = usize::try_from(addr.checked_sub(*at)?).ok()?;
                let to = from.checked_add(usize::try_from(size).ok()?)?;
                bytes.get(from..to)
            })
            .unwrap_or(&[]);
        let half = |o: usize| {
            bytes
                .get(o..o + 2)
                .map(|h| u16::from_le_bytes([h[0], h[1]]))
        };
        let mut targets = Vec::new();
        let mut o = 0;
        while let Some(first) = half(o) {
            // 32-bit encodings start with 0b11101, 0b11110 or 0b11111.
            if first >> 11 < 0b11101 {
                o += 2;
                continue;
            }
            if let Some(t) = half(o + 2).and_then(|second| thumb_branch(first, second)) {
                let at = addr.wrapping_add(o as u64 + 4);
                targets.push(at.wrapping_add_signed(t));
            }
            o += 4;
        }
        targets
            .into_iter()
            .filter(|&t| self.function_size(t).is_some())
    }

    /// Code size of the function at `addr` (Thumb bit ignored): the
    /// largest size of the symbols there (aliases share an address).
    pub fn function_size(&self, addr: u64) -> Option<u64> {
        let addr = addr & !1;
        if addr == 0 {
            return None;
        }
        self.functions
            .iter()
            .filter(|f| f.addr == addr)
            .map(|f| f.size)
            .max()
    }

    /// Size of the section called `name` (0 when absent).
    pub fn section_size(&self, name: &str) -> u64 {
        self.sections
            .iter()
            .filter(|s| s.name == name)
            .map(|s| s.size)
            .sum()
    }

    /// Flash: every section loaded from the image (allocated and not
    /// NOBITS: vector table, .text, .rodata, .data's initial values).
    pub fn flash(&self) -> u64 {
        self.sections
            .iter()
            .filter(|s| s.flags & elf::SHF_ALLOC.0 != 0 && s.kind != elf::SHT_NOBITS.0)
            .map(|s| s.size)
            .sum()
    }

    /// Static RAM: .data, .bss and .uninit.
    pub fn ram(&self) -> u64 {
        [".data", ".bss", ".uninit"]
            .iter()
            .map(|n| self.section_size(n))
            .sum()
    }
}

/// The offset of a Thumb-2 `BL` (T1) or `B.W` (T4) from the instruction's
/// address plus 4; `None` for any other instruction.
fn thumb_branch(first: u16, second: u16) -> Option<i64> {
    let link_or_wide = second & 0xd000;
    if first & 0xf800 != 0xf000 || (link_or_wide != 0xd000 && link_or_wide != 0x9000) {
        return None;
    }
    let bit = |v: u16, n: u32| i64::from((v >> n) & 1);
    let s = bit(first, 10);
    let (i1, i2) = (1 - (bit(second, 13) ^ s), 1 - (bit(second, 11) ^ s));
    let imm = (s << 24)
        | (i1 << 23)
        | (i2 << 22)
        | (i64::from(first & 0x3ff) << 12)
        | (i64::from(second & 0x7ff) << 1);
    // Sign-extended from 25 bits.
    Some((imm << 39) >> 39)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal ELF32: sections NULL, .text (0x40 bytes at 0x400),
    /// .bss (0x10, NOBITS), .symtab (two functions, one object), .strtab
    /// and .shstrtab.
    pub(crate) fn tiny_elf() -> Vec<u8> {
        tiny_elf_with(vec![0u8; 0x40])
    }

    /// [`tiny_elf`] with these 0x40 bytes of `.text`.
    fn tiny_elf_with(text: Vec<u8>) -> Vec<u8> {
        let shstr = b"\0.text\0.bss\0.symtab\0.strtab\0.shstrtab\0";
        let name = |s: &str| {
            let hay = std::str::from_utf8(shstr).unwrap_or("");
            hay.find(s).unwrap_or(0) as u32
        };
        let mut sym = Vec::new();
        sym.extend_from_slice(&[0u8; 16]);
        for (value, size, info) in [(0x401u32, 0x20u32, 0x12u8), (0x421, 0x1c, 0x02), (0, 4, 1)] {
            sym.extend_from_slice(&1u32.to_le_bytes());
            sym.extend_from_slice(&value.to_le_bytes());
            sym.extend_from_slice(&size.to_le_bytes());
            sym.extend_from_slice(&[info, 0, 1, 0]);
        }
        let strtab = b"\0f\0".to_vec();
        let mut body = Vec::new();
        let mut place = |bytes: &[u8]| {
            let at = 52 + body.len() as u32;
            body.extend_from_slice(bytes);
            at
        };
        let text_off = place(&text);
        let sym_off = place(&sym);
        let str_off = place(&strtab);
        let shstr_off = place(shstr);
        let shoff = 52 + body.len() as u32;
        let mut out = vec![0x7f, b'E', b'L', b'F', 1, 1, 1, 0];
        out.resize(16, 0);
        out.extend_from_slice(&2u16.to_le_bytes()); // e_type
        out.extend_from_slice(&40u16.to_le_bytes()); // EM_ARM
        out.extend_from_slice(&1u32.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes()); // entry
        out.extend_from_slice(&0u32.to_le_bytes()); // phoff
        out.extend_from_slice(&shoff.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes()); // flags
        out.extend_from_slice(&52u16.to_le_bytes());
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(&40u16.to_le_bytes());
        out.extend_from_slice(&6u16.to_le_bytes());
        out.extend_from_slice(&5u16.to_le_bytes());
        out.extend_from_slice(&body);
        let headers: [[u32; 10]; 6] = [
            [0; 10],
            [name(".text"), 1, 6, 0x400, text_off, 0x40, 0, 0, 8, 0],
            [name(".bss"), 8, 3, 0x2000_0000, 0, 0x10, 0, 0, 4, 0],
            [
                name(".symtab"),
                2,
                0,
                0,
                sym_off,
                sym.len() as u32,
                4,
                1,
                4,
                16,
            ],
            [
                name(".strtab"),
                3,
                0,
                0,
                str_off,
                strtab.len() as u32,
                0,
                0,
                1,
                0,
            ],
            [
                name(".shstrtab"),
                3,
                0,
                0,
                shstr_off,
                shstr.len() as u32,
                0,
                0,
                1,
                0,
            ],
        ];
        for h in headers {
            for w in h {
                out.extend_from_slice(&w.to_le_bytes());
            }
        }
        out
    }

    #[test]
    fn elf_sections_and_function_sizes() {
        let elf = Elf::parse(&tiny_elf(), "tiny").unwrap();
        assert_eq!(elf.section_size(".text"), 0x40);
        assert_eq!(elf.flash(), 0x40);
        assert_eq!(elf.ram(), 0x10);
        assert_eq!(elf.function_size(0x401), Some(0x20));
        assert_eq!(elf.function_size(0x400), Some(0x20));
        assert_eq!(elf.function_size(0x420), Some(0x1c));
        assert_eq!(elf.function_size(0), None);
        assert_eq!(elf.function_size(0x999), None);
    }

    /// A Thumb-2 `BL` (or, `link` false, `B.W`) at `from` to `to`.
    fn branch(from: u64, to: u64, link: bool) -> [u8; 4] {
        let offset = to.wrapping_sub(from + 4) as i64;
        let bit = |n: u32| ((offset >> n) & 1) as u16;
        let s = bit(24);
        let (j1, j2) = ((1 - bit(23)) ^ s, (1 - bit(22)) ^ s);
        let first = 0xf000 | (s << 10) | ((offset >> 12) as u16 & 0x3ff);
        let second = if link { 0xd000 } else { 0x9000 }
            | (j1 << 13)
            | (j2 << 11)
            | ((offset >> 1) as u16 & 0x7ff);
        let [a, b] = first.to_le_bytes();
        let [c, d] = second.to_le_bytes();
        [a, b, c, d]
    }

    #[test]
    fn thumb_branches_decode() {
        for (from, to) in [
            (0x7fc, 0xb330),
            (0xb330, 0x7fc),
            (0x1000, 0x1000),
            (0, 0xff_fffe),
        ] {
            for link in [true, false] {
                let [a, b, c, d] = branch(from, to, link);
                let got = thumb_branch(u16::from_le_bytes([a, b]), u16::from_le_bytes([c, d]));
                assert_eq!(
                    got,
                    Some(to as i64 - from as i64 - 4),
                    "{from:#x} -> {to:#x}"
                );
            }
        }
        // A conditional branch (T3), a 16-bit and a data-processing
        // instruction are no calls.
        assert_eq!(thumb_branch(0xf000, 0x8000), None);
        assert_eq!(thumb_branch(0xbf00, 0xd000), None);
        assert_eq!(thumb_branch(0xeb00, 0xd000), None);
    }

    #[test]
    fn code_size_follows_calls_and_tail_calls_once() {
        // f (0x400, 0x20 bytes) calls g (0x420, 0x1c bytes) after a 16-bit
        // instruction; g jumps back to f's start (a cycle) and to the
        // middle of f (no function start, not followed).
        let mut text = vec![0u8; 0x40];
        text[2..6].copy_from_slice(&branch(0x402, 0x420, true));
        text[0x20..0x24].copy_from_slice(&branch(0x420, 0x400, false));
        text[0x24..0x28].copy_from_slice(&branch(0x424, 0x410, true));
        let elf = Elf::parse(&tiny_elf_with(text), "calls").unwrap();
        assert_eq!(elf.function_size(0x401), Some(0x20));
        assert_eq!(elf.code_size(0x401), Some(0x20 + 0x1c));
        assert_eq!(elf.code_size(0x420), Some(0x20 + 0x1c));
        assert_eq!(elf.code_size(0x999), None);
        // Without the calls, each function alone.
        let elf = Elf::parse(&tiny_elf(), "tiny").unwrap();
        assert_eq!(elf.code_size(0x400), Some(0x20));
    }

    #[test]
    fn truncated_or_foreign_files_are_errors_not_panics() {
        let elf = tiny_elf();
        for cut in [0, 3, 20, 51, 100, elf.len() - 1] {
            let _ = Elf::parse(elf.get(..cut).unwrap_or(&[]), "cut");
        }
        assert!(Elf::parse(b"\x7fELF\x02\x01", "x").is_err());
        assert!(
            Elf::parse(b"MZ", "x")
                .unwrap_err()
                .to_string()
                .contains("x:")
        );
    }

    #[test]
    fn kernel_lines_are_read_and_bad_ones_named() {
        let text = "# comment\nqemu noise\n\
            kernel target=m4f type=f32 family=maxwell name=rate-exact-ramp/plain n=8 per_call=126.0 state_bytes=32 params_bytes=448 fn=0x0000061c\n\
            kernel target=m3 type=fixed family=mount6 name=x n=1 per_call=3 extra=yes\n";
        let lines = parse_kernels("k.txt", text).unwrap();
        assert_eq!(lines.len(), 2);
        assert_eq!(lines[0].function, Some(0x61c));
        assert_eq!(lines[0].instructions(), 126.0);
        assert_eq!(lines[0].origin, "k.txt:3");
        assert_eq!(
            lines[1].fields.get("extra").map(String::as_str),
            Some("yes")
        );
        for bad in [
            "kernel target=m4f type=f32 family=a name=b n=1",
            "kernel target=m4f type=f32 family=a name=b n=x per_call=1",
            "kernel target=m4f type=f32 family=a name=b n=1 per_call=nan",
            "kernel target=m4f type=f32 family=a name=b n=1 per_call=1 per_call=2",
            "kernel target=m4f oops family=a name=b n=1 per_call=1",
            "kernel target=m4f type=f32 family=a name=b n=1 per_call=1 fn=0xzz",
            "kernel",
        ] {
            let e = parse_kernels("f", bad).unwrap_err().to_string();
            assert!(e.starts_with("f:1"), "{e}");
        }
    }

    #[test]
    fn peer_lines() {
        let text = "kalman name=a crate=kalman-x@0.1 filter=ekf cost=900 unit=instructions model=250 freq_err_pct=0.02 damp_err_pts=-0.01 amp_rms=nan\n";
        let p = parse_peers("p", text).unwrap();
        assert_eq!(p[0].damp_err_pts, Some(0.01));
        assert_eq!((p[0].model, p[0].filter_only()), (Some(250.0), 650.0));
        assert_eq!(p[0].amp_rms, None);
        assert!(!p[0].is_ours());
        assert!(parse_peers("p", "kalman name=a crate=b filter=ekf unit=ns").is_err());
        let target = "kalman name=a crate=b filter=ekf cost=9 unit=instructions calls=40 windows=2,3 model_windows=0,1\n";
        let p = parse_peers("p", target).unwrap();
        assert_eq!(
            (p[0].calls, p[0].windows, p[0].model_windows),
            (Some(40), Some([2, 3]), Some([0, 1]))
        );
        for bad in ["windows=2", "windows=2,x", "model_windows=-1,1"] {
            let line = format!("kalman name=a crate=b filter=ekf cost=9 unit=instructions {bad}");
            assert!(parse_peers("p", &line).is_err(), "{bad}");
        }
    }
}
