//! The command line of `bushing-sim`, on `clap`.
//!
//! Exit codes, the same for every command:
//!
//! | code | meaning |
//! |---|---|
//! | 0 | success |
//! | 1 | the run failed (an input or output error, a failed measurement) |
//! | 2 | usage error (an `--out` that is a link, a file or a folder of other files among them), or a scene that cannot be read, checked or built, or whose output would pass `--max-output` |
//! | 3 | a check failed: `validate` beyond its tolerance, a run with refused steps (without `--allow-refused`), `compare-trace` finding a difference |
//!
//! Errors go to stderr; a scene error shows the scene's line with a caret
//! under the place at fault. With `--json`, `run` and `validate` print
//! one JSON object on stdout whatever happens: their summary with
//! `exit_code` (and `error` when a check failed), or only the error and
//! the exit code when the command could not run.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use bytesize::ByteSize;
use clap::{Args, Parser, Subcommand};

use crate::output::{OutputError, Staged};
use crate::run::{self, RunError};
use crate::scene::{LoadOptions, NumberType, Scene, SceneError};
use crate::{
    accuracy_cost, compare, cost, fractional_report, iwan_report, modulus, powertrain, validate,
    xf_report,
};

/// Real-time bushing models on the host: run scenes, check them against
/// closed forms, measure their cost, regenerate the reports.
#[derive(Debug, Parser)]
#[command(name = "bushing-sim", version, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate a scene: OUT/trace.csv, OUT/modulus.csv and the plots.
    Run(RunArgs),
    /// Compare a scene with its closed-form references.
    Validate(ValidateArgs),
    /// Cost per step of a scene against the sum of its parts.
    Cost(CostArgs),
    /// Complex-modulus error of every Maxwell form.
    MaxwellTable(TableArgs),
    /// Saturation of the x_f cell forms against the step.
    XfTable(TableArgs),
    /// Iwan discretisations of the STS and Segalman laws.
    IwanTable(TableArgs),
    /// Grünwald accuracy, Maxwell fits and their cost.
    FractionalTable(TableArgs),
    /// A test campaign generated from a scene's model (seed 000 Appendix
    /// B part grids): OUT/campaign.toml and one CSV per test.
    Campaign(CampaignArgs),
    /// A campaign's tests reduced for identification (seed 000 §3.2-3.4):
    /// OUT/report.md and its figures; each test left out is named with
    /// its reason.
    Preprocess(PreprocessArgs),
    /// A model identified from a campaign (seed 000 chapter 3): OUT/model.toml,
    /// OUT/model.rs, OUT/model.h and OUT/report.md with its figures.
    Identify(IdentifyArgs),
    /// The engine on three 6-DOF mounts (seed 000 §5.2): modes against
    /// Table 5.2, stop/start transient, plots.
    Powertrain {
        /// Output folder (written whole or not at all).
        #[arg(long)]
        out: PathBuf,
    },
    /// A firmware's logged forces against a host trace written with
    /// trace_every = 1: bit-identical, or within N newtons.
    CompareTrace {
        /// The host's trace.csv.
        host_trace: PathBuf,
        /// The firmware's log.
        firmware_log: PathBuf,
        /// Largest difference accepted, N (bit-identical when absent).
        #[arg(long, value_name = "N")]
        within: Option<f64>,
    },
    /// Error against cost of every kernel (docs/accuracy-cost.md).
    AccuracyCost(Box<AccuracyCostArgs>),
    /// An FMI 2.0 co-simulation FMU of a scene's bushing, or of an
    /// identified model.toml (docs/fmu.md).
    Fmu(FmuArgs),
    /// One part of a scene stepped alone (for `cost --instructions`).
    #[command(hide = true)]
    CostPart {
        /// The scene.
        scene: PathBuf,
        /// Part index.
        part: usize,
        /// Steps.
        steps: usize,
    },
    /// The host kernels stepped alone (for `accuracy-cost`).
    #[command(hide = true)]
    AccuracyCostPart {
        /// Calls per kernel.
        calls: usize,
    },
}

/// How a scene file is read.
#[derive(Debug, Args)]
pub struct SceneArgs {
    /// The scene (TOML, see docs/scenes.md).
    pub scene: PathBuf,
    /// Files the scene names (a replayed CSV) must lie inside the scene's
    /// folder: for scenes from untrusted sources.
    #[arg(long)]
    pub confine: bool,
    /// Working type instead of the scene's own run.number.
    #[arg(long, value_enum)]
    pub number: Option<NumberType>,
}

impl SceneArgs {
    fn load(&self) -> Result<Scene, CliError> {
        let options = LoadOptions {
            number: self.number,
            confine: self.confine,
        };
        Ok(Scene::load_with(&self.scene, options)?)
    }
}

/// `fmu`.
#[derive(Debug, Args)]
pub struct FmuArgs {
    /// The scene or identified model.toml whose bushing the FMU carries
    /// (its profile, ADC and output settings are not used: the master
    /// drives the displacement).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The FMU file to write (`.fmu`; written whole or not at all).
    #[arg(long)]
    pub out: PathBuf,
    /// The FMU library (default: libbushing_fmu.so beside bushing-sim,
    /// from `cargo build --release -p bushing-fmu`).
    #[arg(long)]
    pub library: Option<PathBuf>,
    /// The model's name in the FMU (default: the file's stem).
    #[arg(long)]
    pub name: Option<String>,
}

/// `preprocess`.
#[derive(Debug, Args)]
pub struct PreprocessArgs {
    /// The campaign's folder (its campaign.toml and the tests' CSV files).
    pub campaign: PathBuf,
    /// Output folder (written whole or not at all).
    #[arg(long)]
    pub out: PathBuf,
    /// The tests' files must lie inside the campaign's folder.
    #[arg(long)]
    pub confine: bool,
}

/// `identify`.
#[derive(Debug, Args)]
pub struct IdentifyArgs {
    /// The campaign's folder (its campaign.toml and the tests' CSV files).
    pub campaign: PathBuf,
    /// Output folder (written whole or not at all).
    #[arg(long)]
    pub out: PathBuf,
    /// The backbone's form.
    #[arg(long, value_enum, default_value = "spline")]
    pub backbone: crate::identify::class::BackboneForm,
    /// Spline knots, or the polynomial's degree.
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u16).range(1..=64))]
    pub backbone_size: u16,
    /// Maxwell cells (0: none).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u16).range(0..=12))]
    pub maxwell: u16,
    /// The hysteresis: an Iwan bank, the STS law, or none.
    #[arg(long, value_enum, default_value = "iwan")]
    pub hysteresis: crate::identify::class::HysteresisForm,
    /// Jenkins cells of the Iwan bank.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u16).range(1..=12))]
    pub jenkins: u16,
    /// x_f cells (eq 1.36); `--xf` alone adds one.
    #[arg(
        long,
        num_args = 0..=1,
        default_value_t = 0,
        default_missing_value = "1",
        value_parser = clap::value_parser!(u16).range(0..=8)
    )]
    pub xf: u16,
    /// Tests kept out of the fit and predicted instead.
    #[arg(long, num_args = 1.., value_name = "NAME")]
    pub hold_out: Vec<String>,
    /// The tests' files must lie inside the campaign's folder.
    #[arg(long)]
    pub confine: bool,
}

/// `campaign`.
#[derive(Debug, Args)]
pub struct CampaignArgs {
    /// The scene whose backbone and effects play the part (its profile
    /// and rate are not used).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output folder (written whole or not at all).
    #[arg(long)]
    pub out: PathBuf,
    /// Gaussian noise on the force: standard deviation as a share of each
    /// test's force range.
    #[arg(long, default_value_t = 0.005)]
    pub noise: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Hold of each multi-step level, s (Table B.2: 3600).
    #[arg(long, default_value_t = 3600.0)]
    pub hold_s: f64,
    /// Hold at each preload before a preloaded test starts, s (§3.2.3:
    /// 1200); written in `campaign.toml` for the replays.
    #[arg(long, default_value_t = crate::identify::campaign::DEFAULT_PRELOAD_HOLD_S)]
    pub preload_hold_s: f64,
    /// Preloads of the sines, mm (Table B.2: 0,1,2,3; part grid only).
    #[arg(long, value_delimiter = ',', default_value = "0,1,2,3")]
    pub preloads: Vec<f64>,
    /// The grid: the part tests of Table B.2, or the shear- or
    /// traction-specimen tests of Table B.1 in strain (with --hold-s 360
    /// as in the table).
    #[arg(long, value_enum, default_value = "part")]
    pub grid: Grid,
}

/// The test grids of seed 000 Appendix B.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Grid {
    /// Table B.2: individual part tests, mm.
    Part,
    /// Table B.1: shear specimen tests, strain (1.0 = 100 %).
    SpecimenShear,
    /// Table B.1: traction specimen tests, strain (1.0 = 100 %).
    SpecimenTraction,
}

/// `run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output folder: written beside it, then put in its place whole.
    #[arg(long)]
    out: PathBuf,
    /// Succeed even if some steps were refused.
    #[arg(long)]
    allow_refused: bool,
    /// Refuse a run whose output would be larger (e.g. 500MB, 4GiB).
    #[arg(long, default_value = "1GiB", value_name = "SIZE")]
    max_output: ByteSize,
    /// Write each plot as a PNG too.
    #[arg(long)]
    png: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

/// `validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Largest relative error accepted.
    #[arg(long, default_value_t = validate::TOLERANCE)]
    tolerance: f64,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

/// `cost`.
#[derive(Debug, Args)]
pub struct CostArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Count host instructions with valgrind's callgrind instead of timing.
    #[arg(long)]
    instructions: bool,
}

/// `accuracy-cost`.
#[derive(Debug, Args)]
pub struct AccuracyCostArgs {
    /// Fewer frequencies, steps, seeds and repeats, no callgrind (CI).
    #[arg(long)]
    quick: bool,
    /// No host instruction counts in the full report.
    #[arg(long)]
    no_callgrind: bool,
    /// Outputs of the `kernel-cost` firmware.
    #[arg(long, num_args = 1.., required = true, value_name = "FILE")]
    kernels: Vec<PathBuf>,
    /// The firmware builds that printed them, as TRIPLE=PATH.
    #[arg(long, num_args = 1.., value_name = "TRIPLE=PATH", value_parser = elf_argument)]
    elf: Vec<(String, PathBuf)>,
    /// Outputs of `kalman-peers`.
    #[arg(long, num_args = 1.., value_name = "FILE")]
    peers: Vec<PathBuf>,
    /// The instruction mix of the Cortex-M4F `kalman-peers` run (the
    /// plugin's output): exact counts and estimated cycles for the peers.
    #[arg(long, value_name = "FILE", requires = "peers_disassembly")]
    peers_mix: Option<PathBuf>,
    /// The disassembly of that run's ELF.
    #[arg(long, value_name = "FILE", requires = "peers_mix")]
    peers_disassembly: Option<PathBuf>,
    /// Executed-instruction mixes of the `kernel-cost` runs (the
    /// `bushing-qemu-mix` plugin's output), as TRIPLE=PATH: estimated
    /// cycles.
    #[arg(long, num_args = 1.., value_name = "TRIPLE=PATH", value_parser = elf_argument)]
    mix: Vec<(String, PathBuf)>,
    /// `llvm-objdump -d --no-show-raw-insn` of each ELF with a mix, as
    /// TRIPLE=PATH.
    #[arg(long, num_args = 1.., value_name = "TRIPLE=PATH", value_parser = elf_argument)]
    disassembly: Vec<(String, PathBuf)>,
    /// `llvm-mca`, for the cross-check of the cycle model on a few kernels.
    #[arg(long, value_name = "PROGRAM")]
    llvm_mca: Option<PathBuf>,
    /// Another M4F build to compare with (what differs, e.g. its flags);
    /// needs the three --other-* files.
    #[arg(long, value_name = "NAME", requires_all = ["other_kernels", "other_mix", "other_disassembly"])]
    other_build: Option<String>,
    /// The other build's kernel-cost output.
    #[arg(long, value_name = "FILE", requires = "other_build")]
    other_kernels: Option<PathBuf>,
    /// The other build's instruction mix.
    #[arg(long, value_name = "FILE", requires = "other_build")]
    other_mix: Option<PathBuf>,
    /// The other build's disassembly.
    #[arg(long, value_name = "FILE", requires = "other_build")]
    other_disassembly: Option<PathBuf>,
    /// The kernel-cost output of the headline kernels alone in an M4F
    /// binary of their own (feature `headline-only`): the harness's spread
    /// between binaries. Needs the two other --headline-* files.
    #[arg(long, value_name = "FILE", requires_all = ["headline_mix", "headline_disassembly"])]
    headline_kernels: Option<PathBuf>,
    /// That binary's instruction mix.
    #[arg(long, value_name = "FILE", requires = "headline_kernels")]
    headline_mix: Option<PathBuf>,
    /// That binary's disassembly.
    #[arg(long, value_name = "FILE", requires = "headline_kernels")]
    headline_disassembly: Option<PathBuf>,
    /// Where accuracy-cost.{md,csv,svg} go.
    #[arg(long)]
    out: PathBuf,
}

fn elf_argument(s: &str) -> Result<(String, PathBuf), String> {
    accuracy_cost::parse_elf_argument(s).map_err(|e| e.to_string())
}

/// `maxwell-table` and the other reports.
#[derive(Debug, Args)]
pub struct TableArgs {
    /// Write the report to this file instead of stdout.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Steps per part for `cost --instructions`.
const INSTRUCTION_STEPS: usize = 200_000;

/// Why a command did not succeed, with its exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The scene cannot be read or checked.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A bad argument.
    #[error("{0}")]
    Usage(String),
    /// The run did not complete.
    #[error(transparent)]
    Run(#[from] RunError),
    /// An output file or folder.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Any other failure of the work itself.
    #[error("{0}")]
    Failed(String),
    /// The work completed and a check failed.
    #[error("{0}")]
    Check(String),
    /// A failure already printed in the command's JSON object.
    #[error(transparent)]
    Reported(Box<CliError>),
}

impl CliError {
    /// The process exit code.
    pub fn code(&self) -> u8 {
        match self {
            Self::Scene(_) | Self::Usage(_) => 2,
            Self::Run(RunError::Build(_) | RunError::TooLarge { .. }) => 2,
            Self::Run(RunError::Plot(_)) => 1,
            Self::Run(RunError::Output(e)) | Self::Output(e) => match e {
                OutputError::Io { .. } => 1,
                // A link, a file or a folder of other files as --out.
                _ => 2,
            },
            Self::Failed(_) => 1,
            Self::Check(_) => 3,
            Self::Reported(e) => e.code(),
        }
    }
}

/// Parses the arguments, runs the command and returns its exit code.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let json = match &cli.command {
        Command::Run(a) => a.json,
        Command::Validate(a) => a.json,
        _ => false,
    };
    match dispatch(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            report(&e);
            if json && !matches!(e, CliError::Reported(_)) {
                let value = serde_json::json!({
                    "error": e.to_string(),
                    "exit_code": e.code(),
                });
                println!("{value}");
            }
            ExitCode::from(e.code())
        }
    }
}

/// Prints an error on stderr: a scene error with its line and a caret.
fn report(e: &CliError) {
    if let CliError::Scene(scene) = e
        && scene.source.is_some()
    {
        let theme = if std::io::stderr().is_terminal() {
            miette::GraphicalTheme::unicode()
        } else {
            miette::GraphicalTheme {
                characters: miette::ThemeCharacters::ascii(),
                styles: miette::ThemeStyles::none(),
            }
        };
        let mut text = String::new();
        let handler = miette::GraphicalReportHandler::new_themed(theme);
        if handler.render_report(&mut text, scene).is_ok() {
            // miette's report starts with its own error mark.
            eprint!("{text}");
            return;
        }
    }
    eprintln!("error: {e}");
}

/// Runs one command.
pub fn dispatch(command: Command) -> Result<(), CliError> {
    match command {
        Command::Run(args) => run_command(&args),
        Command::Validate(args) => validate_command(&args),
        Command::Cost(args) => {
            let scene = args.scene.load()?;
            let text = if args.instructions {
                cost::cost_instructions(&args.scene.scene, &scene, INSTRUCTION_STEPS)
                    .map_err(|e| CliError::Failed(e.to_string()))?
                    .to_string()
            } else {
                cost::cost(&scene)
                    .map_err(|e| CliError::Failed(e.to_string()))?
                    .to_string()
            };
            print!("{text}");
            Ok(())
        }
        Command::MaxwellTable(a) => table(modulus::table, a.out.as_deref()),
        Command::XfTable(a) => table(xf_report::table, a.out.as_deref()),
        Command::IwanTable(a) => table(iwan_report::table, a.out.as_deref()),
        Command::FractionalTable(a) => table(fractional_report::table, a.out.as_deref()),
        Command::Campaign(a) => campaign(&a),
        Command::Preprocess(a) => preprocess(&a),
        Command::Identify(a) => identify(&a),
        Command::Powertrain { out } => {
            let mut staged = Staged::begin(&out)?;
            let text = powertrain::report(&mut staged).map_err(|e| match e {
                powertrain::ReportError::Output(o) => CliError::Output(o),
                other => CliError::Failed(other.to_string()),
            })?;
            staged.commit()?;
            print!("{text}");
            Ok(())
        }
        Command::CompareTrace {
            host_trace,
            firmware_log,
            within,
        } => {
            let c = compare::compare_files(&host_trace, &firmware_log, within).map_err(
                |e| match e {
                    compare::CompareError::Bound(_) => CliError::Usage(e.to_string()),
                    _ => CliError::Failed(e.to_string()),
                },
            )?;
            print!("{c}");
            match c.first_mismatch {
                None => Ok(()),
                Some(m) => Err(CliError::Check(format!("firmware and host differ at {m}"))),
            }
        }
        Command::AccuracyCost(a) => {
            let command = accuracy_cost::Command {
                quick: a.quick,
                no_callgrind: a.no_callgrind,
                kernels: a.kernels,
                elf: a.elf,
                peers: a.peers,
                peers_mix: a.peers_mix.zip(a.peers_disassembly),
                mix: a.mix,
                disassembly: a.disassembly,
                llvm_mca: a.llvm_mca,
                other_build: match (
                    a.other_build,
                    a.other_kernels,
                    a.other_mix,
                    a.other_disassembly,
                ) {
                    (Some(n), Some(k), Some(m), Some(d)) => Some((n, k, m, d)),
                    _ => None,
                },
                headline_build: match (a.headline_kernels, a.headline_mix, a.headline_disassembly) {
                    (Some(k), Some(m), Some(d)) => Some((k, m, d)),
                    _ => None,
                },
                out: a.out,
            };
            let text = accuracy_cost::run(&command).map_err(|e| CliError::Failed(e.to_string()))?;
            print!("{text}");
            Ok(())
        }
        Command::Fmu(a) => fmu_command(&a),
        Command::CostPart { scene, part, steps } => {
            cost::run_part_of(&scene, part, steps).map_err(|e| CliError::Failed(e.to_string()))
        }
        Command::AccuracyCostPart { calls } => {
            accuracy_cost::host::run_part(calls).map_err(|e| CliError::Failed(e.to_string()))
        }
    }
}

fn fmu_command(args: &FmuArgs) -> Result<(), CliError> {
    use crate::fmu::{self, FmuError};
    let options = LoadOptions {
        number: args.scene.number,
        confine: args.scene.confine,
    };
    let failed = |e: FmuError| match e {
        FmuError::Scene(s) => CliError::Scene(*s),
        FmuError::Usage(m) | FmuError::Unsupported(m) => CliError::Usage(m),
        other => CliError::Failed(other.to_string()),
    };
    fmu::check_out(&args.out).map_err(failed)?;
    let model = fmu::FmuModel::from_scene(&args.scene.scene, options).map_err(failed)?;
    let name = args.name.clone().unwrap_or_else(|| {
        args.scene
            .scene
            .file_stem()
            .map_or_else(|| "bushing".into(), |s| s.to_string_lossy().into_owned())
    });
    let library = fmu::find_library(args.library.as_deref()).map_err(failed)?;
    fmu::write_fmu(&model, &name, &library, &args.out).map_err(failed)?;
    let inputs: Vec<&str> = fmu::variables(&model)
        .iter()
        .filter(|v| v.input)
        .map(|v| v.name)
        .collect();
    println!(
        "{}: FMI 2.0 co-simulation FMU of {name} ({}, dt = {} s, inputs {}, GUID {})",
        args.out.display(),
        model.scene.number.name(),
        model.scene.dt,
        inputs.join(", "),
        model.guid
    );
    Ok(())
}

fn run_command(args: &RunArgs) -> Result<(), CliError> {
    let scene = args.scene.load()?;
    let options = run::Options {
        progress: !args.json,
        max_output: args.max_output.as_u64(),
        png: args.png,
    };
    let summary = run::run_with(&scene, &args.out, options)?;
    let failure = (summary.refused > 0 && !args.allow_refused).then(|| {
        CliError::Check(format!(
            "{} of {} steps were refused (their effect columns in {} are nan); \
             --allow-refused accepts such a run",
            summary.refused,
            summary.steps,
            args.out.join("trace.csv").display()
        ))
    });
    if !args.json {
        print!("{summary}");
        return failure.map_or(Ok(()), Err);
    }
    let mut value = serde_json::to_value(&summary).map_err(|e| CliError::Failed(e.to_string()))?;
    json_outcome(&mut value, failure)
}

/// Adds the outcome to a command's JSON object and prints it: one object
/// on stdout whatever happens (a failure is then not printed again).
fn json_outcome(value: &mut serde_json::Value, failure: Option<CliError>) -> Result<(), CliError> {
    let code = failure.as_ref().map_or(0, CliError::code);
    if let Some(object) = value.as_object_mut() {
        object.insert("exit_code".into(), code.into());
        if let Some(e) = &failure {
            object.insert("error".into(), e.to_string().into());
        }
    }
    println!("{value:#}");
    match failure {
        None => Ok(()),
        Some(e) => Err(CliError::Reported(Box::new(e))),
    }
}

fn validate_command(args: &ValidateArgs) -> Result<(), CliError> {
    if !(args.tolerance.is_finite() && args.tolerance >= 0.0) {
        return Err(CliError::Usage(format!(
            "--tolerance must be a finite relative error >= 0, got {}",
            args.tolerance
        )));
    }
    let scene = args.scene.load()?;
    let report = validate::validate(&scene)?;
    let beyond = report.beyond(args.tolerance);
    let failure = if report.refused > 0 {
        Some(CliError::Check(format!(
            "{} steps were refused: the run is no comparison with the references",
            report.refused
        )))
    } else if beyond.is_empty() {
        None
    } else {
        Some(CliError::Check(format!(
            "{} of {} checks beyond the tolerance of {:e}: {}",
            beyond.len(),
            report.checks.len(),
            args.tolerance,
            beyond
                .iter()
                .map(|c| format!("{}: {}", c.effect, c.what))
                .collect::<Vec<_>>()
                .join("; ")
        )))
    };
    if !args.json {
        print!("{report}");
        return failure.map_or(Ok(()), Err);
    }
    let mut value = serde_json::json!({
        "report": report,
        "tolerance": args.tolerance,
        "passed": failure.is_none(),
    });
    json_outcome(&mut value, failure)
}

/// Prints a report, or writes it whole into `out` (a temporary file
/// beside it, renamed into place).
/// `preprocess`: the campaign read, reduced and reported.
fn preprocess(a: &PreprocessArgs) -> Result<(), CliError> {
    use crate::identify::campaign::{Campaign, CampaignError};
    use crate::identify::report;
    let campaign = Campaign::load(&a.campaign, a.confine).map_err(|e| match e {
        CampaignError::NothingUsable { .. } => CliError::Failed(e.to_string()),
        other => CliError::Usage(other.to_string()),
    })?;
    let p = report::preprocess(&campaign);
    let mut staged = Staged::begin(&a.out)?;
    p.write(&mut staged)?;
    let path = staged.commit()?;
    println!(
        "preprocess: {} tests used ({} sines, {} multi-step, {} triangle, {} other), {} left out; report in {}",
        p.used(),
        p.sines.len(),
        p.holds.len(),
        p.triangles.len(),
        p.others.len(),
        p.excluded.len(),
        path.join("report.md").display()
    );
    for e in &p.excluded {
        println!("left out: {}: {}", e.name, e.reason);
    }
    Ok(())
}

/// `identify`: the campaign read, the model identified and written.
fn identify(a: &IdentifyArgs) -> Result<(), CliError> {
    use crate::identify::campaign::{Campaign, CampaignError};
    use crate::identify::class::ModelClass;
    use crate::identify::outcome::{IdentifyError, identify};
    let campaign = Campaign::load(&a.campaign, a.confine).map_err(|e| match e {
        CampaignError::NothingUsable { .. } => CliError::Failed(e.to_string()),
        other => CliError::Usage(other.to_string()),
    })?;
    let class = ModelClass {
        backbone: a.backbone,
        backbone_size: usize::from(a.backbone_size),
        maxwell_cells: usize::from(a.maxwell),
        hysteresis: a.hysteresis,
        jenkins_cells: usize::from(a.jenkins),
        xf_cells: usize::from(a.xf),
    };
    let started = std::time::Instant::now();
    let id = identify(&campaign, &class, &a.hold_out).map_err(|e| match e {
        IdentifyError::UnknownHoldOut(_) => CliError::Usage(e.to_string()),
        other => CliError::Failed(other.to_string()),
    })?;
    let seconds = started.elapsed().as_secs_f64();
    let mut staged = Staged::begin(&a.out)?;
    crate::identify::summary::write(&id, seconds, &mut staged)?;
    let path = staged.commit()?;
    print!("{}", crate::identify::summary::console(&id, seconds));
    println!("identify: model and report in {}", path.display());
    Ok(())
}

/// `campaign`: the grid generated into a staged folder.
fn campaign(a: &CampaignArgs) -> Result<(), CliError> {
    use crate::identify::synth::{self, SynthError};
    let scene = a.scene.load()?;
    if !(a.hold_s.is_finite() && a.hold_s >= 1.0 && a.hold_s <= 86_400.0) {
        return Err(CliError::Usage(format!(
            "--hold-s {} must be from 1 to 86400 s",
            a.hold_s
        )));
    }
    if let Some(p) = a
        .preloads
        .iter()
        .find(|p| !(p.is_finite() && p.abs() <= 100.0))
    {
        return Err(CliError::Usage(format!(
            "--preloads: {p} mm must be finite and within 100 mm"
        )));
    }
    let grid = match a.grid {
        Grid::Part => synth::part_grid(a.hold_s, &a.preloads),
        Grid::SpecimenShear => synth::specimen_grid(synth::Specimen::Shear, a.hold_s),
        Grid::SpecimenTraction => synth::specimen_grid(synth::Specimen::Traction, a.hold_s),
    };
    let mut staged = Staged::begin(&a.out)?;
    let samples = synth::write(
        &scene,
        &grid,
        a.noise,
        a.seed,
        a.preload_hold_s,
        &mut staged,
    )
    .map_err(|e| match e {
        SynthError::Output(o) => CliError::Output(o),
        SynthError::Noise(_) | SynthError::Hold(_) => CliError::Usage(e.to_string()),
        other => CliError::Failed(other.to_string()),
    })?;
    let path = staged.commit()?;
    println!(
        "campaign: {} tests, {samples} samples, force noise {} of each range (seed {}) in {}",
        grid.len(),
        a.noise,
        a.seed,
        path.display()
    );
    Ok(())
}

fn table(make: fn() -> String, out: Option<&Path>) -> Result<(), CliError> {
    let text = make();
    let Some(out) = out else {
        print!("{text}");
        return Ok(());
    };
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let write = || -> std::io::Result<()> {
        let mut file = tempfile::NamedTempFile::new_in(dir)?;
        std::io::Write::write_all(&mut file, text.as_bytes())?;
        file.as_file().sync_all()?;
        file.persist(out).map_err(|e| e.error)?;
        Ok(())
    };
    write().map_err(OutputError::io(out))?;
    println!("wrote {}", out.display());
    Ok(())
}
