//! `accuracy-cost`: one report of error against cost for every scheme,
//! order and number type (`docs/accuracy-cost.{md,csv,svg}`), regenerated
//! by `scripts/accuracy-cost.sh`.
//!
//! - **Errors** are computed here, on the host, against references that
//!   are not the code under test: closed forms (eq 1.8 for Maxwell banks,
//!   eq 1.21 for the fractional law, the continuous STS and Segalman laws,
//!   the free decay's f0 and damping), or the same model in f64 at a 64
//!   times finer step ([`families`]).
//! - **Host cost**: ns per call by a timing loop (median of several runs)
//!   and, in full mode with valgrind on the path, host instructions per
//!   call under callgrind ([`host`]).
//! - **Target cost**: the `kernel ...` lines of the `kernel-cost` firmware
//!   run in QEMU on Cortex-M4F and Cortex-M3 (guest instructions per
//!   call, state and parameter bytes), the code size of each measured
//!   function from the firmware's ELF symbol table, and flash and static
//!   RAM from its section headers ([`firmware`]).
//!
//! Rows are joined to the firmware by `family`, `name`, `n` and `type`;
//! firmware lines no row asks for go to an "other kernels" table, so a new
//! family printed by the firmware shows up without a change here.
//!
//! The command's entry point is [`run`] with a [`Command`]; [`generate`]
//! computes the report from inputs already in memory.

pub mod builds;
pub mod cycles;
pub mod families;
pub mod firmware;
pub mod host;
pub mod mca;
pub mod plot;
mod report;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use bushing::ParamError;
use firmware::{Elf, KernelLine, PeerLine, Split};

use crate::cost::callgrind;
use crate::fit::FitError;

/// Why the report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An input file could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// An output could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file or directory.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A firmware output or ELF file that cannot be read.
    #[error(transparent)]
    Firmware(#[from] firmware::Error),
    /// An executed-instruction mix that cannot be used.
    #[error(transparent)]
    Cycles(#[from] cycles::Error),
    /// Two firmware lines for the same kernel.
    #[error("{origin}: the same kernel as {previous} (target, family, name, n and type)")]
    Duplicate {
        /// `file:line` of the second line.
        origin: String,
        /// `file:line` of the first.
        previous: String,
    },
    /// A kernel or reference refused its parameters.
    #[error("{what}: {source}")]
    Param {
        /// Which kernel or reference.
        what: String,
        /// What it refused.
        source: ParamError,
    },
    /// A Maxwell fit failed.
    #[error("{what}: {source}")]
    Fit {
        /// Which fit.
        what: String,
        /// Why.
        source: FitError,
    },
    /// A fit returned another number of cells than asked.
    #[error("the fit returned {got} cells, not {asked}")]
    FitCells {
        /// Cells asked for.
        asked: usize,
        /// Cells returned.
        got: usize,
    },
    /// A fitted bank of an order the report does not build.
    #[error("no fitted bank of {0} cells")]
    FitOrder(usize),
    /// Counting host instructions failed.
    #[error(transparent)]
    Callgrind(#[from] callgrind::Error),
    /// Callgrind wrote fewer dumps than the kernels it was given.
    #[error("callgrind wrote {dumps} dumps for {kernels} kernels")]
    MissingDumps {
        /// Kernels printed by the part command.
        kernels: usize,
        /// Dumps written.
        dumps: usize,
    },
    /// A `--mix` without a `--disassembly` of the same triple.
    #[error("--mix {0}=... needs --disassembly {0}=...")]
    NoDisassembly(String),
    /// An `--elf` value that is not `TRIPLE=PATH`.
    #[error("--elf takes TRIPLE=PATH, not {0}")]
    ElfArgument(String),
}

/// An [`Error::Param`] naming `what`.
pub(crate) fn refused(what: impl Into<String>) -> impl FnOnce(ParamError) -> Error {
    move |source| Error::Param {
        what: what.into(),
        source,
    }
}

/// The kernels the report singles out (M4F, f32): family, name, n. The
/// build comparison and the llvm-mca cross-check table them.
pub const HEADLINE: [(&str, &str, usize); 6] = [
    ("maxwell-force", "rate-exact-ramp/plain", 8),
    ("maxwell", "rate-exact-ramp/plain", 8),
    ("iwan", "clamp/log", 16),
    ("bushing", "default/spline+4maxwell+3jenkins", 7),
    ("tracker", "ekf/1-mode-1-acc", 4),
    ("six-dof", "mount/invariant", 6),
];

/// What identifies a kernel: the firmware's `family`, `name`, `n` and
/// `type`.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Key {
    /// `family=`.
    pub family: String,
    /// `name=`.
    pub name: String,
    /// `n=`.
    pub n: usize,
    /// `type=`.
    pub number: String,
}

impl Key {
    /// A key.
    pub fn new(family: &str, name: &str, n: usize, number: &str) -> Self {
        Self {
            family: family.into(),
            name: name.into(),
            n,
            number: number.into(),
        }
    }

    /// One word for the callgrind child's output.
    pub fn to_word(&self) -> String {
        format!(
            "key\t{}\t{}\t{}\t{}",
            self.family, self.name, self.n, self.number
        )
    }

    /// Reads [`Key::to_word`].
    pub fn from_word(line: &str) -> Option<Self> {
        let mut w = line.strip_prefix("key\t")?.split('\t');
        let (family, name, n, number) = (w.next()?, w.next()?, w.next()?, w.next()?);
        Some(Self::new(family, name, n.parse().ok()?, number))
    }
}

/// Where a row's cost comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Cost {
    /// One measured kernel.
    One(Key),
    /// The sum of measured kernels (a configuration the firmware measures
    /// in parts: a fitted bank is a backbone plus a Maxwell bank).
    Sum(Vec<Key>),
}

/// One configuration of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Family, name, order and number type of the configuration.
    pub key: Key,
    /// Error (a fraction), when there is a reference.
    pub error: Option<f64>,
    /// What the error measures, against what.
    pub measure: String,
    /// Where the cost comes from.
    pub cost: Cost,
    /// Extra figures for the family table.
    pub detail: String,
    /// Host ns per call.
    pub host_ns: Option<f64>,
    /// Host instructions per call (callgrind).
    pub host_instr: Option<f64>,
    /// Cortex-M4F guest instructions per call (`net`, else `per_call`).
    pub m4f: Option<f64>,
    /// Cortex-M4F guest instructions per call, call included.
    pub m4f_call: Option<f64>,
    /// Cortex-M3 guest instructions per call.
    pub m3: Option<f64>,
    /// Cortex-M7 guest instructions per call (the M4F target built for the
    /// Cortex-M7: f64 in hardware).
    pub m7: Option<f64>,
    /// Cortex-M4F estimated cycles per call, net of the call (from the
    /// executed-instruction mix, [`cycles`]).
    pub m4f_cycles: Option<f64>,
    /// Cortex-M3 estimated cycles per call, net of the call.
    pub m3_cycles: Option<f64>,
    /// Cortex-M4F instructions per call, net of the call, by what they do
    /// ([`KernelLine::split`]).
    pub m4f_split: Option<Split>,
    /// The M4F input the cost is taken on (the worst of those measured),
    /// one name per part.
    pub m4f_input: Option<String>,
    /// Code bytes of the measured function (Cortex-M4F build).
    pub code_bytes: Option<u64>,
    /// State bytes.
    pub state_bytes: Option<u64>,
    /// Parameter bytes.
    pub params_bytes: Option<u64>,
    /// On its family's Pareto front (error against M4F instructions).
    pub front: bool,
}

impl Row {
    /// A row with no cost joined yet.
    pub fn new(key: Key, error: Option<f64>, measure: &str, cost: Cost) -> Self {
        Self {
            key,
            error,
            measure: measure.into(),
            cost,
            detail: String::new(),
            host_ns: None,
            host_instr: None,
            m4f: None,
            m4f_call: None,
            m3: None,
            m7: None,
            m4f_cycles: None,
            m3_cycles: None,
            m4f_split: None,
            m4f_input: None,
            code_bytes: None,
            state_bytes: None,
            params_bytes: None,
            front: false,
        }
    }
}

/// How much to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// Fewer frequencies, steps, seeds and repeats; no callgrind. Every
    /// family and code path still runs.
    pub quick: bool,
    /// Count host instructions under callgrind (when valgrind is there).
    pub callgrind: bool,
    /// Host timing.
    pub timing: host::Timing,
}

impl Options {
    /// The full report.
    pub fn full() -> Self {
        Self {
            quick: false,
            callgrind: true,
            timing: host::Timing {
                calls: 4 * host::CALLS,
                runs: 9,
            },
        }
    }

    /// The quick mode of CI.
    pub fn quick() -> Self {
        Self {
            quick: true,
            callgrind: false,
            timing: host::Timing {
                calls: host::CALLS / 10,
                runs: 3,
            },
        }
    }
}

/// What the firmware printed and where its ELF files are.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Inputs {
    /// `(source name, text)` of `kernel-cost` outputs.
    pub kernels: Vec<(String, String)>,
    /// `(triple or target, ELF bytes)` of the firmware builds.
    pub elfs: Vec<(String, Vec<u8>)>,
    /// `(source name, text)` of `kalman-peers` outputs.
    pub peers: Vec<(String, String)>,
    /// The instruction mix and disassembly of the Cortex-M4F
    /// `kalman-peers` run: exact counts and estimated cycles for its lines
    /// (those in instructions, with windows).
    pub peers_mix: Option<MixInput>,
    /// The executed-instruction mixes of the `kernel-cost` runs.
    pub mixes: Vec<MixInput>,
    /// `llvm-mca`, for the cross-check of the cycle model ([`mca`]); none:
    /// not run.
    pub llvm_mca: Option<PathBuf>,
    /// Another M4F build of the kernel-cost firmware (other flags), for
    /// the "Build flags" comparison ([`builds`]).
    pub other_build: Option<OtherBuild>,
    /// The headline kernels alone in a binary of their own (same flags),
    /// for the "Harness" section ([`builds::spread`]).
    pub headline_build: Option<OtherBuild>,
}

/// Another build's kernel-cost output and instruction mix.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OtherBuild {
    /// What differs (its flags).
    pub name: String,
    /// `(source name, text)` of its `kernel-cost` output.
    pub kernels: (String, String),
    /// Its mix and disassembly (M4F).
    pub mix: MixInput,
}

/// One target's executed-instruction mix and the disassembly of the ELF
/// that ran (see [`cycles`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MixInput {
    /// Triple (or target) of the run.
    pub triple: String,
    /// Name of the mix file, for messages.
    pub source: String,
    /// The `bushing-qemu-mix` plugin's output.
    pub mix: String,
    /// `llvm-objdump -d --no-show-raw-insn` of the ELF.
    pub disassembly: String,
}

/// The firmware's footprint.
#[derive(Debug, Clone, PartialEq)]
pub struct Footprint {
    /// Triple (or target) as given.
    pub triple: String,
    /// Report target (`m4f`, `m3`).
    pub target: String,
    /// `.text` bytes.
    pub text: u64,
    /// `.rodata` bytes.
    pub rodata: u64,
    /// `.data` bytes.
    pub data: u64,
    /// `.bss` bytes.
    pub bss: u64,
    /// Flash: every loaded section.
    pub flash: u64,
    /// Static RAM: .data + .bss + .uninit.
    pub ram: u64,
}

/// A target of the issue, its measured figure and verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Goal {
    /// What is measured.
    pub what: String,
    /// The bound (at most).
    pub limit: f64,
    /// The measured figure.
    pub measured: Option<f64>,
    /// The same in estimated Cortex-M4 cycles, where the report has them.
    pub cycles: Option<f64>,
    /// How it was measured.
    pub note: String,
}

impl Goal {
    /// Measured and within the bound.
    pub fn met(&self) -> bool {
        self.measured.is_some_and(|m| m <= self.limit)
    }
}

/// The generated report.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// Every configuration, with its joined costs.
    pub rows: Vec<Row>,
    /// What the report could not check (an ELF that is not the build
    /// that printed the lines).
    pub warnings: Vec<String>,
    /// Firmware lines no row asked for (the "other kernels" table).
    pub other: Vec<KernelLine>,
    /// The targets.
    pub goals: Vec<Goal>,
    /// Firmware footprints.
    pub footprints: Vec<Footprint>,
    /// Peer-crate lines.
    pub peers: Vec<PeerLine>,
    /// `accuracy-cost.md`.
    pub markdown: String,
    /// `accuracy-cost.csv`.
    pub csv: String,
    /// `accuracy-cost.svg`.
    pub svg: String,
}

/// Columns of the CSV.
pub const CSV_COLUMNS: [&str; 21] = [
    "family",
    "name",
    "n",
    "type",
    "error",
    "error_measure",
    "host_ns",
    "host_instr",
    "m4f_instr",
    "m3_instr",
    "m7_instr",
    "m4f_cycles",
    "m3_cycles",
    "m4f_fpu_arith",
    "m4f_load_store",
    "m4f_compare_branch",
    "m4f_other",
    "worst_input",
    "code_bytes",
    "state_bytes",
    "params_bytes",
];

/// The firmware lines, indexed by target and key.
struct Lines {
    by: BTreeMap<(String, Key), KernelLine>,
    used: BTreeSet<(String, Key)>,
}

impl Lines {
    /// Indexes `lines`; the lines of one kernel on several inputs become
    /// one, the costliest (by estimated cycles when both have them, else
    /// by instructions), with every input's cost in
    /// [`KernelLine::by_input`].
    fn new(lines: Vec<KernelLine>) -> Result<Self, Error> {
        let mut by: BTreeMap<(String, Key), KernelLine> = BTreeMap::new();
        for mut l in lines {
            let key = (
                l.target.clone(),
                Key::new(&l.family, &l.name, l.n, &l.number),
            );
            l.by_input = vec![l.input_cost()];
            let Some(old) = by.get_mut(&key) else {
                by.insert(key, l);
                continue;
            };
            let repeated = l.input.is_none()
                || old.input.is_none()
                || old
                    .by_input
                    .iter()
                    .any(|c| Some(&c.input) == l.input.as_ref());
            if repeated {
                return Err(Error::Duplicate {
                    origin: l.origin,
                    previous: old.origin.clone(),
                });
            }
            let mut inputs = std::mem::take(&mut old.by_input);
            inputs.push(l.input_cost());
            let costlier = match (l.cycles, old.cycles) {
                (Some(new), Some(was)) => new > was,
                _ => l.instructions() > old.instructions(),
            };
            if costlier {
                *old = l;
            }
            old.by_input = inputs;
        }
        Ok(Self {
            by,
            used: BTreeSet::new(),
        })
    }

    fn get(&mut self, target: &str, key: &Key) -> Option<&KernelLine> {
        let k = (target.to_string(), key.clone());
        let line = self.by.get(&k)?;
        self.used.insert(k);
        Some(line)
    }
}

/// Sum over parts, `None` when any part is missing.
fn sum_all(mut parts: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    parts.try_fold(0.0, |acc, v| Some(acc + v?))
}

fn sum_bytes(mut parts: impl Iterator<Item = Option<u64>>) -> Option<u64> {
    parts.try_fold(0u64, |acc, v| acc.checked_add(v?))
}

/// Joins the measured costs into `row`.
fn join(
    row: &mut Row,
    lines: &mut Lines,
    elfs: &BTreeMap<String, Elf>,
    ns: &BTreeMap<Key, f64>,
    instr: &BTreeMap<Key, f64>,
) {
    let keys: Vec<Key> = match &row.cost {
        Cost::One(k) => vec![k.clone()],
        Cost::Sum(ks) => ks.clone(),
    };
    row.host_ns = sum_all(keys.iter().map(|k| ns.get(k).copied()));
    row.host_instr = sum_all(keys.iter().map(|k| instr.get(k).copied()));
    let m4f: Vec<Option<KernelLine>> = keys.iter().map(|k| lines.get("m4f", k).cloned()).collect();
    let m3: Vec<Option<KernelLine>> = keys.iter().map(|k| lines.get("m3", k).cloned()).collect();
    row.m7 = sum_all(
        keys.iter()
            .map(|k| lines.get("m7", k).map(KernelLine::instructions)),
    );
    row.m4f = sum_all(m4f.iter().map(|l| l.as_ref().map(KernelLine::instructions)));
    row.m4f_call = sum_all(m4f.iter().map(|l| l.as_ref().map(|l| l.per_call)));
    row.m3 = sum_all(m3.iter().map(|l| l.as_ref().map(KernelLine::instructions)));
    row.m4f_cycles = sum_all(m4f.iter().map(|l| l.as_ref().and_then(|l| l.cycles)));
    row.m3_cycles = sum_all(m3.iter().map(|l| l.as_ref().and_then(|l| l.cycles)));
    row.m4f_split = m4f.iter().try_fold(Split::default(), |acc, l| {
        Some(acc.plus(l.as_ref()?.split?))
    });
    let mut inputs: Vec<&str> = m4f
        .iter()
        .filter_map(|l| l.as_ref()?.input.as_deref())
        .collect();
    inputs.dedup();
    row.m4f_input = (!inputs.is_empty()).then(|| inputs.join("+"));
    let elf = elfs.get("m4f");
    row.code_bytes = sum_bytes(m4f.iter().map(|l| {
        let f = l.as_ref()?.function?;
        elf?.code_size(f)
    }));
    let either = |i: usize| {
        m4f.get(i)
            .cloned()
            .flatten()
            .or(m3.get(i).cloned().flatten())
    };
    row.state_bytes = sum_bytes((0..keys.len()).map(|i| either(i)?.state_bytes));
    row.params_bytes = sum_bytes((0..keys.len()).map(|i| either(i)?.params_bytes));
}

/// Whether rows are ranked by estimated M4F cycles: every row with an M4F
/// figure has a cycle estimate (else they are ranked by instructions, so
/// that one ranking never mixes the two).
pub fn ranked_by_cycles<'a>(mut rows: impl Iterator<Item = &'a Row>) -> bool {
    rows.all(|r| r.m4f.is_none() || r.m4f_cycles.is_some())
}

/// The cost a row is ranked by: estimated M4F cycles, or M4F
/// instructions ([`ranked_by_cycles`]).
pub fn rank_cost(r: &Row, cycles: bool) -> Option<f64> {
    if cycles { r.m4f_cycles } else { r.m4f }
}

/// Marks each family's Pareto front over error and M4F cost
/// ([`rank_cost`]): a row is on it when its error is lower than that of
/// every row of the family that costs less (or as much, listed before it).
pub fn mark_fronts(rows: &mut [Row]) {
    let families: BTreeSet<String> = rows.iter().map(|r| r.key.family.clone()).collect();
    for family in families {
        let cycles = ranked_by_cycles(rows.iter().filter(|r| r.key.family == family));
        let mut idx: Vec<usize> = (0..rows.len())
            .filter(|&i| {
                let r = &rows[i];
                r.key.family == family
                    && r.error.is_some_and(f64::is_finite)
                    && rank_cost(r, cycles).is_some_and(|c| c > 0.0)
            })
            .collect();
        let cost = |i: usize| rank_cost(&rows[i], cycles).unwrap_or(f64::INFINITY);
        let err = |i: usize| rows[i].error.unwrap_or(f64::INFINITY);
        idx.sort_by(|&a, &b| cost(a).total_cmp(&cost(b)).then(err(a).total_cmp(&err(b))));
        let mut best = f64::INFINITY;
        let mut front = Vec::new();
        for i in idx {
            let e = err(i);
            if e < best {
                best = e;
                front.push(i);
            }
        }
        for i in front {
            if let Some(r) = rows.get_mut(i) {
                r.front = true;
            }
        }
    }
}

fn read_footprints(elfs: &BTreeMap<String, (String, Elf)>) -> Vec<Footprint> {
    elfs.iter()
        .map(|(target, (triple, elf))| Footprint {
            triple: triple.clone(),
            target: target.clone(),
            text: elf.section_size(".text"),
            rodata: elf.section_size(".rodata"),
            data: elf.section_size(".data"),
            bss: elf.section_size(".bss"),
            flash: elf.flash(),
            ram: elf.ram(),
        })
        .collect()
}

/// Computes the report from the firmware's outputs.
pub fn generate(inputs: &Inputs, options: &Options) -> Result<Report, Error> {
    let mut all = Vec::new();
    for (source, text) in &inputs.kernels {
        all.extend(firmware::parse_kernels(source, text)?);
    }
    let mut m4f_mix = None;
    for m in &inputs.mixes {
        let mix = cycles::Mix::parse(&m.source, &m.mix)?;
        let dis = cycles::Disassembly::parse(&m.disassembly);
        let target = firmware::target_of_triple(&m.triple);
        cycles::attach(&mut all, &target, &mix, &dis)?;
        if target == "m4f" {
            m4f_mix = Some((mix, dis));
        }
    }
    let mut lines = Lines::new(all)?;
    let mut elfs = BTreeMap::new();
    for (triple, bytes) in &inputs.elfs {
        let elf = Elf::parse(bytes, triple)?;
        elfs.insert(firmware::target_of_triple(triple), (triple.clone(), elf));
    }
    let mut peers = Vec::new();
    for (source, text) in &inputs.peers {
        peers.extend(firmware::parse_peers(source, text)?);
    }
    if let Some(m) = &inputs.peers_mix {
        let mix = cycles::Mix::parse(&m.source, &m.mix)?;
        let dis = cycles::Disassembly::parse(&m.disassembly);
        let on_target = peers.iter_mut().filter(|p| p.unit == "instructions");
        cycles::attach_peers(on_target, &mix, &dis)?;
    }

    let warnings = elf_mismatches(&lines, &elfs);
    let mut rows = families::rows(options)?;
    let mut kernels = host::kernels()?;
    kernels.extend(host::by_input()?);
    let (ns, reference_ns) = host::time_with_reference(&mut kernels, options.timing);
    drop(kernels);
    let instr = if options.callgrind && !options.quick && callgrind::available() {
        host::instructions(host::CALLS)?
    } else {
        BTreeMap::new()
    };
    let elf_only: BTreeMap<String, Elf> = elfs
        .iter()
        .map(|(t, (_, e))| (t.clone(), e.clone()))
        .collect();
    for row in &mut rows {
        join(row, &mut lines, &elf_only, &ns, &instr);
    }
    mark_fronts(&mut rows);
    let other: Vec<KernelLine> = lines
        .by
        .iter()
        .filter(|(k, _)| !lines.used.contains(*k))
        .map(|(_, l)| l.clone())
        .collect();
    let mut goals = report::goals(&mut lines, &peers);
    goals.push(report::host_goal(&ns, reference_ns));
    let footprints = read_footprints(&elfs);
    let builds = match &inputs.other_build {
        Some(o) => {
            let other = other_lines(o)?;
            builds::compare(&o.name, lines.by.values(), other.by.values())
        }
        None => None,
    };
    let spread = match &inputs.headline_build {
        Some(o) => {
            let other = other_lines(o)?;
            builds::spread(&o.name, lines.by.values(), other.by.values())
        }
        None => None,
    };
    let mca = match (&inputs.llvm_mca, &m4f_mix) {
        (Some(program), Some((mix, dis))) => {
            let m4f: Vec<&KernelLine> = lines.by.values().filter(|l| l.target == "m4f").collect();
            Some(mca::compare(program, &m4f, mix, dis))
        }
        _ => None,
    };
    let context = report::Context {
        builds,
        spread,
        mca,
        options: *options,
        inputs: inputs_summary(inputs),
        callgrind: !instr.is_empty(),
        warnings: warnings.clone(),
    };
    let by_input: Vec<KernelLine> = lines
        .by
        .values()
        .filter(|l| l.by_input.len() > 1)
        .cloned()
        .collect();
    let markdown = report::markdown(
        &rows,
        &other,
        &by_input,
        &goals,
        &footprints,
        &peers,
        &context,
    );
    let csv = report::csv(&rows, &other, &elf_only);
    let svg = report::svg(&rows);
    Ok(Report {
        rows,
        warnings,
        other,
        goals,
        footprints,
        peers,
        markdown,
        csv,
        svg,
    })
}

/// Another build's kernel lines, with their estimated cycles, merged by
/// input.
fn other_lines(o: &OtherBuild) -> Result<Lines, Error> {
    let mut other = firmware::parse_kernels(&o.kernels.0, &o.kernels.1)?;
    let mix = cycles::Mix::parse(&o.mix.source, &o.mix.mix)?;
    let dis = cycles::Disassembly::parse(&o.mix.disassembly);
    cycles::attach(
        &mut other,
        &firmware::target_of_triple(&o.mix.triple),
        &mix,
        &dis,
    )?;
    Lines::new(other)
}

/// Lines whose `fn=` address is no function of their target's ELF: the
/// ELF is not the build that printed them, and their code size is left
/// out.
fn elf_mismatches(lines: &Lines, elfs: &BTreeMap<String, (String, Elf)>) -> Vec<String> {
    let mut out = Vec::new();
    for line in lines.by.values() {
        let (Some(f), Some((triple, elf))) = (line.function, elfs.get(&line.target)) else {
            continue;
        };
        if f != 0 && elf.function_size(f).is_none() {
            out.push(format!(
                "{}: fn={f:#x} is no function of the {triple} ELF (not the build that printed it?)",
                line.origin
            ));
        }
    }
    out
}

fn inputs_summary(inputs: &Inputs) -> Vec<String> {
    let mut out: Vec<String> = inputs
        .kernels
        .iter()
        .map(|(s, _)| format!("kernel lines: `{s}`"))
        .collect();
    out.extend(inputs.elfs.iter().map(|(t, _)| format!("ELF: {t}")));
    out.extend(
        inputs
            .mixes
            .iter()
            .map(|m| format!("instruction mix: `{}` ({})", m.source, m.triple)),
    );
    out.extend(
        inputs
            .peers
            .iter()
            .map(|(s, _)| format!("peer lines: `{s}`")),
    );
    if let Some(m) = &inputs.peers_mix {
        out.push(format!("peers' instruction mix: `{}`", m.source));
    }
    for (what, build) in [
        ("other build", &inputs.other_build),
        ("headline build", &inputs.headline_build),
    ] {
        if let Some(b) = build {
            out.push(format!(
                "{what} `{}`: `{}`, `{}`",
                b.name, b.kernels.0, b.mix.source
            ));
        }
    }
    out
}

/// Writes `accuracy-cost.{md,csv,svg}` into `dir`.
pub fn write(report: &Report, dir: &Path) -> Result<Vec<PathBuf>, Error> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Write {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut out = Vec::new();
    for (name, text) in [
        ("accuracy-cost.md", &report.markdown),
        ("accuracy-cost.csv", &report.csv),
        ("accuracy-cost.svg", &report.svg),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|source| Error::Write {
            path: path.clone(),
            source,
        })?;
        out.push(path);
    }
    Ok(out)
}

/// What the `accuracy-cost` command is given.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Command {
    /// `--quick`: [`Options::quick`] (fewer frequencies, steps, seeds and
    /// repeats, no callgrind) instead of [`Options::full`].
    pub quick: bool,
    /// `--no-callgrind`: no host instruction counts in the full report.
    pub no_callgrind: bool,
    /// `--kernels FILE...`: outputs of the `kernel-cost` firmware.
    pub kernels: Vec<PathBuf>,
    /// `--elf TRIPLE=PATH...`: the firmware builds that printed them
    /// ([`parse_elf_argument`] reads one).
    pub elf: Vec<(String, PathBuf)>,
    /// `--peers FILE...`: outputs of `kalman-peers`.
    pub peers: Vec<PathBuf>,
    /// `--peers-mix FILE --peers-disassembly FILE`: the instruction mix of
    /// the Cortex-M4F `kalman-peers` run and the disassembly of its ELF.
    pub peers_mix: Option<(PathBuf, PathBuf)>,
    /// `--mix TRIPLE=PATH...`: executed-instruction mixes.
    pub mix: Vec<(String, PathBuf)>,
    /// `--disassembly TRIPLE=PATH...`: the disassembly of each ELF with a
    /// mix.
    pub disassembly: Vec<(String, PathBuf)>,
    /// `--llvm-mca PROGRAM`: the cross-check of the cycle model.
    pub llvm_mca: Option<PathBuf>,
    /// `--other-build NAME --other-kernels FILE --other-mix FILE
    /// --other-disassembly FILE`: another M4F build to compare with.
    pub other_build: Option<(String, PathBuf, PathBuf, PathBuf)>,
    /// `--headline-kernels FILE --headline-mix FILE --headline-disassembly
    /// FILE`: the headline kernels alone in an M4F binary of their own.
    pub headline_build: Option<(PathBuf, PathBuf, PathBuf)>,
    /// `--out DIR`: where `accuracy-cost.{md,csv,svg}` go.
    pub out: PathBuf,
}

impl Command {
    /// The computation's [`Options`].
    pub fn options(&self) -> Options {
        let mut options = if self.quick {
            Options::quick()
        } else {
            Options::full()
        };
        if self.no_callgrind {
            options.callgrind = false;
        }
        options
    }

    /// Reads the files it names.
    pub fn inputs(&self) -> Result<Inputs, Error> {
        let text = |path: &PathBuf| {
            std::fs::read_to_string(path)
                .map(|text| (path.display().to_string(), text))
                .map_err(|source| Error::Read {
                    path: path.clone(),
                    source,
                })
        };
        let mut elfs = Vec::with_capacity(self.elf.len());
        for (triple, path) in &self.elf {
            let bytes = std::fs::read(path).map_err(|source| Error::Read {
                path: path.clone(),
                source,
            })?;
            elfs.push((triple.clone(), bytes));
        }
        let m4f = |name: &str, kernels: &PathBuf, mix: &PathBuf, dis: &PathBuf| {
            Ok::<_, Error>(OtherBuild {
                name: name.into(),
                kernels: text(kernels)?,
                mix: MixInput {
                    triple: "thumbv7em-none-eabihf".into(),
                    source: mix.display().to_string(),
                    mix: text(mix)?.1,
                    disassembly: text(dis)?.1,
                },
            })
        };
        let mut mixes = Vec::with_capacity(self.mix.len());
        for (triple, path) in &self.mix {
            let Some((_, dis)) = self.disassembly.iter().find(|(t, _)| t == triple) else {
                return Err(Error::NoDisassembly(triple.clone()));
            };
            let (source, mix) = text(path)?;
            mixes.push(MixInput {
                triple: triple.clone(),
                source,
                mix,
                disassembly: text(dis)?.1,
            });
        }
        Ok(Inputs {
            kernels: self.kernels.iter().map(text).collect::<Result<_, _>>()?,
            elfs,
            peers: self.peers.iter().map(text).collect::<Result<_, _>>()?,
            peers_mix: match &self.peers_mix {
                Some((mix, dis)) => Some(MixInput {
                    triple: "thumbv7em-none-eabihf".into(),
                    source: mix.display().to_string(),
                    mix: text(mix)?.1,
                    disassembly: text(dis)?.1,
                }),
                None => None,
            },
            mixes,
            llvm_mca: self.llvm_mca.clone(),
            other_build: match &self.other_build {
                Some((name, kernels, mix, dis)) => Some(m4f(name, kernels, mix, dis)?),
                None => None,
            },
            headline_build: match &self.headline_build {
                Some((kernels, mix, dis)) => Some(m4f("headline-only", kernels, mix, dis)?),
                None => None,
            },
        })
    }
}

/// One `--elf` value, `TRIPLE=PATH`.
pub fn parse_elf_argument(value: &str) -> Result<(String, PathBuf), Error> {
    let (triple, path) = value
        .split_once('=')
        .ok_or_else(|| Error::ElfArgument(value.into()))?;
    Ok((triple.to_string(), PathBuf::from(path)))
}

/// The `accuracy-cost` command: reads the inputs, generates, writes, and
/// returns what it wrote and the verdict of each target.
pub fn run(command: &Command) -> Result<String, Error> {
    let report = generate(&command.inputs()?, &command.options())?;
    let written = write(&report, &command.out)?;
    let mut msg = String::new();
    for p in written {
        msg.push_str(&format!("wrote {}\n", p.display()));
    }
    for g in &report.goals {
        msg.push_str(&format!(
            "target {:<58} {}\n",
            g.what,
            if g.met() { "met" } else { "NOT met" }
        ));
    }
    Ok(msg)
}
