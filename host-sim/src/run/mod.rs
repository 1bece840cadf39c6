//! Running a scene: step the bushing over the profile through the one
//! stepping pipeline ([`drive`]) with its sinks (the trace, the plots and
//! modulus probe, the progress bar), measure the cost of the steps alone,
//! and write everything into a staged output folder that appears whole or
//! not at all ([`crate::output`]). Before stepping, the output is estimated
//! and a run above [`Options::max_output`] is refused.
//!
//! Plots (SVG, and PNG with [`Options::png`]; axes labelled with units):
//!
//! - `force-displacement.svg`: total force and long-term elastic branch
//!   against displacement;
//! - `force-time.svg`: total force, elastic branch and each effect's force
//!   against time;
//! - `dissipated-power.svg`: two panels against time, the power each step
//!   dissipates (its energy over dt, in mW = N·mm/s) and the cumulative
//!   energy (mJ), total and per effect;
//! - `modulus-amplitude.svg` (profiles with sine portions only): the
//!   instantaneous complex modulus against the imposed amplitude, in the
//!   style of seed 000 Fig 1.24, also written as `modulus.csv`;
//! - `modulus-frequency.svg` (sines at two frequencies or more): K', K''
//!   and the loss factor against frequency.
//!
//! Long runs are decimated for the time plots by keeping the smallest and
//! the largest value of each of a few thousand buckets, so that an
//! oscillation too fast to draw shows as its envelope instead of aliasing.

mod pipeline;
mod plots;
mod progress;
mod trace;

use std::path::{Path, PathBuf};

use bushing::Real;
use serde::Serialize;

pub use pipeline::{CHUNK, Sink, Step, drive, drive_steps};
pub use plots::{MeasuredFit, PLOT_POINTS, PlotSink, TIME_BUCKETS};
pub use progress::Progress;
pub use trace::{TraceSink, column_name, row_bytes};

use crate::model;
use crate::output::{OutputError, Staged};
use crate::probe::{MAX_MODULUS_POINTS, ModulusPoint};
use crate::scene::{NumberType, Scene};

/// Why a run produced no result.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene's model could not be built.
    #[error("the scene's model cannot be built: {0}")]
    Build(#[from] bushing::ParamError),
    /// The run would write more than allowed.
    #[error(
        "the run would write about {} (trace of {rows} rows), more than the limit of {}; \
         raise `trace_every` in the scene or the limit with --max-output",
        bytesize::ByteSize(*estimate), bytesize::ByteSize(*limit)
    )]
    TooLarge {
        /// Estimated bytes.
        estimate: u64,
        /// Trace rows.
        rows: u64,
        /// The limit.
        limit: u64,
    },
    /// Writing the output failed.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A plot could not be drawn.
    #[error("plot: {0}")]
    Plot(#[from] crate::plot::PlotError),
}

/// What a run measured.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Steps taken.
    pub steps: u64,
    /// Effects built, by name.
    pub effects: Vec<String>,
    /// Working type.
    pub number: NumberType,
    /// Wall-clock nanoseconds per step, stepping only (no I/O).
    pub ns_per_step: f64,
    /// Energy dissipated over the run, in mJ (N·mm).
    pub dissipated_mj: f64,
    /// Largest |force| in N.
    pub peak_force: f64,
    /// Steps refused for non-finite or out-of-range input.
    pub refused: u32,
    /// Instantaneous-modulus points (empty without sine portions).
    #[serde(skip)]
    pub modulus: Vec<ModulusPoint>,
    /// Modulus points were thinned to stay under [`MAX_MODULUS_POINTS`].
    pub modulus_capped: bool,
    /// The model's force against the measured force of a replay with a
    /// force column.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measured: Option<MeasuredFit>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "steps          {}", self.steps)?;
        let effects = if self.effects.is_empty() {
            "none (backbone only)".to_string()
        } else {
            self.effects.join(", ")
        };
        writeln!(f, "effects        {effects}")?;
        writeln!(f, "number type    {}", self.number.name())?;
        writeln!(
            f,
            "cost           {:.1} ns/step (host wall clock, stepping only)",
            self.ns_per_step
        )?;
        writeln!(f, "dissipated     {:.6e} mJ", self.dissipated_mj)?;
        writeln!(f, "peak |force|   {:.6e} N", self.peak_force)?;
        writeln!(f, "refused steps  {}", self.refused)?;
        if !self.modulus.is_empty() {
            let capped = if self.modulus_capped {
                format!(" (thinned to stay under {MAX_MODULUS_POINTS})")
            } else {
                String::new()
            };
            writeln!(f, "modulus points {}{capped}", self.modulus.len())?;
        }
        if let Some(m) = &self.measured {
            writeln!(
                f,
                "measured force RMS residual {:.6e} N, {:.3} % of the measured range {:.6e} N ({} steps)",
                m.rms_n, m.rms_percent, m.range_n, m.steps
            )?;
        }
        for file in &self.files {
            writeln!(f, "wrote          {}", file.display())?;
        }
        Ok(())
    }
}

/// How to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// Show a progress bar on stderr for long runs (more than a million
    /// steps, or more than about a second expected), at most ten updates a
    /// second, when stderr is a terminal. Off by default: the command line
    /// turns it on, library callers and tests do not.
    pub progress: bool,
    /// Most bytes the run may write ([`estimate_output`] is checked
    /// against it before stepping).
    pub max_output: u64,
    /// Write each figure as a PNG too.
    pub png: bool,
}

/// The default output limit: 1 GiB.
pub const MAX_OUTPUT: u64 = 1 << 30;

impl Default for Options {
    fn default() -> Self {
        Self {
            progress: false,
            max_output: MAX_OUTPUT,
            png: false,
        }
    }
}

/// Runs `scene`, writing the trace, the modulus points and the plots into
/// `out`, without a progress bar.
pub fn run(scene: &Scene, out: &Path) -> Result<Summary, RunError> {
    run_with(scene, out, Options::default())
}

/// Runs `scene` with `options`.
pub fn run_with(scene: &Scene, out: &Path, options: Options) -> Result<Summary, RunError> {
    match scene.number {
        NumberType::F32 => run_typed::<f32>(scene, out, options),
        NumberType::F64 => run_typed::<f64>(scene, out, options),
    }
}

/// What a run will write at most, in bytes, and its trace rows: the
/// trace, the modulus points (one per period at most, capped), and the
/// plots (bounded by their point counts).
pub fn estimate_output(scene: &Scene) -> (u64, u64) {
    let steps = scene.steps();
    let rows = 1 + steps / scene.trace_every.max(1) + 1;
    let names = model::effect_names(scene);
    let trace = rows.saturating_mul(row_bytes(names.len(), scene.oscillator.is_some()));
    let points = (steps / 2).min(MAX_MODULUS_POINTS as u64);
    let modulus = points * 5 * 25;
    let plots = (PLOT_POINTS * 2 + TIME_BUCKETS * 2 * (3 * names.len() as u64 + 4)) * 40;
    (trace.saturating_add(modulus).saturating_add(plots), rows)
}

fn run_typed<T: Real + 'static>(
    scene: &Scene,
    out: &Path,
    options: Options,
) -> Result<Summary, RunError> {
    let (estimate, rows) = estimate_output(scene);
    if estimate > options.max_output {
        return Err(RunError::TooLarge {
            estimate,
            rows,
            limit: options.max_output,
        });
    }
    let mut bushing = model::compile::<T>(scene)?;
    let mut staged = Staged::begin(out)?;
    let names = model::effect_names(scene);
    let steps = scene.steps();
    let trace_file = staged.create("trace.csv")?;
    let trace_path = trace_file.path().to_path_buf();
    let mut trace = TraceSink::new(
        trace_file,
        &names,
        scene.oscillator.is_some(),
        scene.trace_every,
        steps,
    )?;
    let x0 = match scene.oscillator {
        Some(o) => o.p0,
        None => scene.input(0.0),
    };
    let (_, k0) = bushing::Backbone::eval(bushing.backbone(), T::from_f64(x0));
    let mut plots = PlotSink::new(scene, &names, k0.to_f64());
    let mut progress = Progress::new(options.progress, steps);
    let busy = drive(
        scene,
        bushing.as_mut(),
        &mut [&mut trace, &mut plots, &mut progress],
    )?;
    progress.finish();
    trace.finish()?;
    let (energy, peak, measured) = (plots.energy(), plots.peak(), plots.measured());
    let (written, modulus, modulus_capped) = plots.write(&mut staged, options.png)?;
    let mut files = vec![trace_path];
    files.extend(written);
    staged.commit()?;
    Ok(Summary {
        steps,
        effects: names,
        number: scene.number,
        ns_per_step: busy * 1e9 / steps.max(1) as f64,
        dissipated_mj: energy,
        peak_force: peak,
        refused: bushing.refused(),
        modulus,
        modulus_capped,
        measured,
        files,
    })
}
