//! Scene files: what to simulate, at which rate and in which number type,
//! under which displacement profile. See `docs/scenes.md`.
//!
//! Parsing is two-staged: TOML into plain structs (syntax and shape errors
//! carry the line and column), then validation into model parameters
//! (parameter errors name the effect, the parameter and the bound, at the
//! line of the effect's table).

use std::fmt;
use std::ops::Range;
use std::path::Path;

use bushing::{
    Backbone, FirstLoading, IwanCellSpec, KfTable, MaxwellForm, MaxwellSpec, ParamError, Sts,
    XfForm, XfSpec,
};
use serde::Deserialize;
use serde::de::{self, DeserializeSeed, Visitor};
use toml::Spanned;
use toml::de::{DeTable, DeValue, ValueDeserializer};

/// Declares a table whose variant its `type` key names
/// (`#[serde(tag = "type")]`), and beside it the same variants read
/// externally tagged: `$by_tag::deserialize` (a serde `remote` of the enum)
/// reads a table's content, without its `type`, as the variant `type`
/// names. Serde reads a tagged table through a buffer that forgets where
/// each value was, so a wrong value inside one is reported at the table;
/// read again by [`tagged_mistake`], the same mistake points at the value.
macro_rules! tagged_table {
    (
        $(#[$meta:meta])*
        pub enum $name:ident, read by tag as $by_tag:ident($remote:literal) $body:tt
    ) => {
        $(#[$meta])*
        #[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
        pub enum $name $body

        #[derive(Deserialize)]
        #[serde(remote = $remote, rename_all = "kebab-case", deny_unknown_fields)]
        #[allow(dead_code)] // never built: its `deserialize` builds the public enum
        enum $by_tag $body
    };
}

/// A scene file, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Free text shown in reports.
    #[serde(default)]
    pub title: String,
    /// Rate and number type.
    pub run: Spanned<RunSpec>,
    /// The elastic backbone F^∞(x).
    pub backbone: Spanned<BackboneSpec>,
    /// Dissipative effects, each with its parameters; only these are built.
    #[serde(default)]
    pub effects: Vec<Spanned<EffectSpec>>,
    /// Displacement profile.
    pub profile: Spanned<ProfileSpec>,
    /// What `run` writes; optional.
    #[serde(default)]
    pub output: Option<Spanned<OutputSpec>>,
    /// A unit mass on the bushing, driven by the profile as a force;
    /// optional.
    #[serde(default)]
    pub oscillator: Option<Spanned<OscillatorSpec>>,
    /// The rig's displacement ADC the model reads the profile through;
    /// optional.
    #[serde(default)]
    pub adc: Option<Spanned<AdcSpec>>,
}

/// `[adc]`, as written: the displacement fed to the model is what an ideal
/// ADC of step `lsb_mm` and `bits` bits reads
/// ([`bushing::excitation::adc_code`]).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdcSpec {
    /// Step of one code, mm (finite, > 0).
    pub lsb_mm: f64,
    /// Width of the code, 2 to 24 bits (default 16).
    #[serde(default = "default_adc_bits")]
    pub bits: i64,
}

fn default_adc_bits() -> i64 {
    16
}

/// Widest ADC a scene may declare.
pub const MAX_ADC_BITS: u32 = 24;

/// A validated `[adc]`: an ideal two's-complement ADC of step `lsb_mm`,
/// rounding to nearest and saturating at its range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adc {
    /// Step of one code, mm.
    pub lsb_mm: f64,
    /// Width of the code in bits, 2 to [`MAX_ADC_BITS`].
    pub bits: u32,
}

impl Adc {
    /// The code the ADC gives for `x` mm.
    pub fn code(&self, x: f64) -> i32 {
        bushing::excitation::adc_code(x, self.lsb_mm, self.bits)
    }

    /// The displacement it reads for `x` mm: `code(x) * lsb_mm`, in f64.
    pub fn read(&self, x: f64) -> f64 {
        f64::from(self.code(x)) * self.lsb_mm
    }
}

/// `[oscillator]`: a unit modal mass on the bushing, `x'' + F(x) = f(t)`,
/// the profile giving the force f in N instead of the displacement (seed
/// 004 §2.8, the one-degree-of-freedom macro-model of a mode; the mass unit
/// is N·s²/mm).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OscillatorSpec {
    /// Displacement at t = 0, mm.
    #[serde(default)]
    pub p0: f64,
    /// Velocity at t = 0, mm/s.
    #[serde(default)]
    pub v0: f64,
}

/// `[output]`: what `run` writes.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Write every n-th step to `trace.csv` (and always the last); the
    /// plots, energies and modulus points still see every step.
    #[serde(default = "default_trace_every")]
    pub trace_every: i64,
}

fn default_trace_every() -> i64 {
    1
}

/// `[run]`: time step and number type.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Sampling rate in Hz (the time step is its inverse).
    pub rate_hz: f64,
    /// Working type of the models.
    #[serde(default)]
    pub number: NumberType,
}

/// Working type of the models.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum NumberType {
    /// Single precision, as on a Cortex-M4F.
    #[default]
    F32,
    /// Double precision.
    F64,
}

impl NumberType {
    /// Name as written in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Self::F32 => "f32",
            Self::F64 => "f64",
        }
    }
}

tagged_table! {
    /// `[backbone]`: F^∞(x) in N for x in mm.
    #[derive(Debug, Clone, Deserialize)]
    pub enum BackboneSpec, read by tag as BackboneByTag("BackboneSpec") {
        /// F = c0 + c1 x + c2 x^2 + ... on `range`, linear outside.
        Polynomial {
            /// Coefficients c0, c1, ... (N/mm^k), at most 8.
            coefficients: Vec<f64>,
            /// Validity range [lo, hi] in mm.
            range: [f64; 2],
        },
        /// Monotone cubic spline through measured points, linear outside.
        Spline {
            /// Displacements in mm, increasing.
            x: Vec<f64>,
            /// Forces in N, increasing.
            force: Vec<f64>,
        },
    }
}

tagged_table! {
    /// One `[[effects]]` table.
    #[derive(Debug, Clone, Deserialize)]
    pub enum EffectSpec, read by tag as EffectByTag("EffectSpec") {
        /// A bank of Maxwell cells.
        Maxwell {
            /// Discrete form: load-explicit, load-exponential, rate-explicit,
            /// rate-midpoint or rate-exact-ramp.
            form: String,
            /// State storage: "plain", "multiplied" or "compensated".
            #[serde(default = "default_state")]
            state: String,
            /// The cells.
            cells: Vec<CellSpec>,
        },
        /// A bank of Jenkins cells (Iwan).
        Iwan {
            /// "clamp" (force saturation, eq 1.32) or "slider" (eq 1.30).
            form: String,
            /// Reference stiffness in N/mm that turns slip distances into slip
            /// forces (and the slider springs); default: backbone tangent at 0.
            #[serde(default)]
            k_ref: Option<f64>,
            /// The cells.
            cells: Vec<IwanCellToml>,
        },
        /// Hysteretic relaxation with a turning-point stack (eqs 1.27-1.29,
        /// 1.41-1.42).
        TurningPoints {
            /// "sts" (continuous STS, needs `c` and `k1`) or "table" (measured
            /// K_f, needs `d` and `k`).
            law: String,
            /// STS constant C in N²/mm.
            #[serde(default)]
            c: Option<f64>,
            /// STS stiffness at a turning point K_1 in N/mm.
            #[serde(default)]
            k1: Option<f64>,
            /// Table: distances from the turning point in mm.
            #[serde(default)]
            d: Option<Vec<f64>>,
            /// Table: K_f in N/mm, non-increasing.
            #[serde(default)]
            k: Option<Vec<f64>>,
            /// "masing" (default) or "ignored".
            #[serde(default = "default_first_loading")]
            first_loading: String,
        },
        /// A bank of nonlinear viscous x_f cells (eq 1.52).
        Xf {
            /// "midpoint" (eq 2.41) or "exact-ramp".
            form: String,
            /// The cells.
            cells: Vec<XfCellToml>,
        },
        /// Dahl's friction cell (eq 1.43).
        Dahl(DahlParams),
        /// The Bouc-Wen cell (eq 1.44, the thesis's naming).
        BoucWen(BoucWenParams),
        /// Berg's friction cell (eq 1.45).
        Berg(BergParams),
    }
}

/// Parameters of a Dahl cell.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DahlParams {
    /// Initial stiffness in N/mm.
    pub k_d: f64,
    /// Friction force in N.
    pub f_f: f64,
    /// Exponent (default 1).
    #[serde(default = "default_exponent")]
    pub alpha: f64,
}

/// Parameters of a Bouc-Wen cell.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoucWenParams {
    /// Force scale in N/mm.
    pub alpha: f64,
    /// A.
    pub a: f64,
    /// β.
    pub beta: f64,
    /// γ, with |γ| < β.
    pub gamma: f64,
    /// Exponent n.
    pub n: f64,
}

/// Parameters of a Berg cell.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BergParams {
    /// Largest friction force in N.
    pub f_max: f64,
    /// Displacement in mm at which half of it is reached from rest.
    pub x2: f64,
}

fn default_exponent() -> f64 {
    1.0
}

/// One Jenkins cell: a fraction and either a slip force or a slip distance.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IwanCellToml {
    /// Load fraction g.
    pub g: f64,
    /// Slip force in N.
    #[serde(default)]
    pub slip_force: Option<f64>,
    /// Slip distance from rest in mm (slip force g k_ref x_f).
    #[serde(default)]
    pub x_f: Option<f64>,
}

/// One x_f cell.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct XfCellToml {
    /// Viscous relaxation frequency in Hz (0 for rate independence).
    pub f_hz: f64,
    /// Load fraction g.
    pub g: f64,
    /// Hysteretic relaxation distance in mm.
    pub x_f: f64,
}

fn default_first_loading() -> String {
    "masing".into()
}

fn default_state() -> String {
    "plain".into()
}

impl EffectSpec {
    /// Name of the effect kind, as in scene files.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Maxwell { .. } => "maxwell",
            Self::Iwan { .. } => "iwan",
            Self::TurningPoints { .. } => "turning-points",
            Self::Xf { .. } => "xf",
            Self::Dahl(_) => "dahl",
            Self::BoucWen(_) => "bouc-wen",
            Self::Berg(_) => "berg",
        }
    }
}

/// One Maxwell cell: corner frequency in Hz and load fraction.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellSpec {
    /// Corner frequency in Hz (ω = 2π f).
    pub f_hz: f64,
    /// Load fraction g of the high-frequency backbone.
    pub g: f64,
}

tagged_table! {
    /// `[profile]`: the imposed displacement x(t) in mm. The formulas, the
    /// defaults and the bounds of each profile are in [`crate::profile`] and
    /// `docs/scenes.md`.
    #[derive(Debug, Clone, PartialEq, Deserialize)]
    pub enum ProfileSpec, read by tag as ProfileByTag("ProfileSpec") {
        /// x = preload + amplitude sin(2π f t).
        Sine {
            /// Amplitude in mm.
            amplitude: f64,
            /// Frequency in Hz.
            frequency_hz: f64,
            /// Number of cycles.
            cycles: f64,
            /// Static offset in mm.
            #[serde(default)]
            preload: f64,
        },
        /// Triangle between preload ± amplitude at constant speed, starting
        /// upward from the preload.
        Triangle {
            /// Amplitude in mm.
            amplitude: f64,
            /// Speed in mm/s.
            speed: f64,
            /// Number of cycles.
            cycles: f64,
            /// Static offset in mm.
            #[serde(default)]
            preload: f64,
        },
        /// Multi-step relaxation (seed 000 §3.2.3, Table B.2): from `preload`,
        /// a linear ramp of `ramp_s` to each level in turn, each held `hold_s`.
        MultiStep {
            /// Levels in mm, in the order they are reached.
            levels: Vec<f64>,
            /// Duration of each ramp in s (> 0; the thesis uses 20 s).
            ramp_s: f64,
            /// Hold at each level in s (>= 0; the thesis uses 360 s or 3600 s).
            hold_s: f64,
            /// Starting level in mm (the bushing starts relaxed there).
            #[serde(default)]
            preload: f64,
        },
        /// Stepped sines (seed 000 Fig. 3.3, Table B.2): at each preload, for
        /// each frequency, a step of whole `cycles` at each amplitude in turn,
        /// each step starting and ending at the preload with zero phase.
        SteppedSine {
            /// A single preload in mm (default 0); not with `preloads`.
            #[serde(default)]
            preload: Option<f64>,
            /// Several preloads in mm, visited in order; not with `preload`.
            #[serde(default)]
            preloads: Option<Vec<f64>>,
            /// Frequencies in Hz, outer loop at each preload.
            frequencies_hz: Vec<f64>,
            /// Amplitudes in mm, inner loop.
            amplitudes: Vec<f64>,
            /// Whole number of cycles per step.
            cycles: f64,
            /// Rest at the preload after each step, in s; not with
            /// `settle_cycles`.
            #[serde(default)]
            settle_s: Option<f64>,
            /// Rest at the preload after each step, in periods of that step's
            /// frequency; not with `settle_s`.
            #[serde(default)]
            settle_cycles: Option<f64>,
            /// Ramp between preloads in s (needed with two or more preloads).
            #[serde(default)]
            ramp_s: Option<f64>,
            /// Hold after each preload change in s (default 0).
            #[serde(default)]
            hold_s: Option<f64>,
        },
        /// Sine sweep, phase-continuous: x = preload + amplitude sin(φ(t)) with
        /// φ the integral of 2π f(t), f linear or logarithmic in time from
        /// `f_start_hz` to `f_end_hz` over `duration_s`.
        Sweep {
            /// Amplitude in mm.
            amplitude: f64,
            /// Frequency at t = 0 in Hz.
            f_start_hz: f64,
            /// Frequency at t = duration_s in Hz.
            f_end_hz: f64,
            /// Duration in s.
            duration_s: f64,
            /// Frequency law: "log" (default) or "linear".
            #[serde(default)]
            spacing: crate::profile::Spacing,
            /// Static offset in mm.
            #[serde(default)]
            preload: f64,
        },
        /// Stop/start transient, a displacement proxy of seed 000 §5.2.4: each
        /// event is the response of one mode (`frequency_hz`, `damping`) to a
        /// load ramped over `rise_s` whose static displacement is the event's
        /// `size`.
        StopStart {
            /// Frequency of the mode that rings, in Hz (undamped).
            frequency_hz: f64,
            /// Damping ratio ζ in [0, 1).
            damping: f64,
            /// Rise time of each load change in s (0 for a step).
            rise_s: f64,
            /// Duration in s.
            duration_s: f64,
            /// The events, in time order.
            events: Vec<crate::profile::StopStartEvent>,
            /// Static offset in mm before the first event.
            #[serde(default)]
            preload: f64,
        },
        /// A constant input: x held at `preload` (in an oscillator scene,
        /// a constant force: 0 gives a free decay).
        Hold {
            /// Duration in s.
            duration_s: f64,
            /// The held value, mm (N in an oscillator scene).
            #[serde(default)]
            preload: f64,
        },
        /// Replay of a measured displacement from a CSV file, linearly
        /// interpolated onto the scene's step.
        Replay {
            /// CSV file, relative to the scene file's directory.
            file: String,
            /// Displacement column: a header name or a 1-based index.
            column: crate::profile::Column,
            /// Time column in s (name or 1-based index); not with `rate_hz`.
            #[serde(default)]
            time_column: Option<crate::profile::Column>,
            /// Sampling rate of the file in Hz; not with `time_column`.
            #[serde(default)]
            rate_hz: Option<f64>,
            /// The samples (time from the first sample in s, displacement in
            /// mm), read from `file` when the scene is loaded.
            #[serde(skip)]
            samples: Vec<(f64, f64)>,
        },
    }
}

/// Where in a file something went wrong: 1-based line and column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1 (in characters).
    pub column: usize,
}

impl Location {
    /// Location of byte offset `at` in `text`.
    pub fn of(text: &str, at: usize) -> Self {
        let at = at.min(text.len());
        let before = text.get(..at).unwrap_or(text);
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Self { line, column }
    }
}

/// A scene that could not be read or built.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// File name as given.
    pub file: String,
    /// Position of the mistake, when known.
    pub at: Option<Location>,
    /// What was expected.
    pub message: String,
    /// The scene's text and the byte range at fault, for a report that
    /// shows the line with a caret ([`miette::Diagnostic`]).
    pub source: Option<(std::sync::Arc<str>, Range<usize>)>,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.at {
            Some(l) => write!(f, "{}:{}:{}: {}", self.file, l.line, l.column, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for SceneError {}

impl miette::Diagnostic for SceneError {
    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        self.source
            .as_ref()
            .map(|(text, _)| text as &dyn miette::SourceCode)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        let (text, span) = self.source.as_ref()?;
        let start = span.start.min(text.len());
        // The first line of the span: a whole table would hide the caret.
        let line_end = text[start..].find('\n').map_or(text.len(), |n| start + n);
        let end = span.end.clamp(start, line_end).max(start);
        Some(Box::new(std::iter::once(miette::LabeledSpan::at(
            start..end,
            "here",
        ))))
    }
}

/// Most bytes of a scene file: scenes are a page of TOML, and a larger
/// file is refused before it is read.
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// How a scene file is read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Working type instead of the scene's own `run.number`.
    pub number: Option<NumberType>,
    /// Files the scene names (a replayed CSV) must be inside the scene's
    /// folder: for scenes from untrusted sources.
    pub confine: bool,
}

/// A scene read and checked: every value is in range and every model can
/// be built (the models themselves are built by [`crate::model`]).
#[derive(Debug, Clone)]
pub struct Scene {
    /// Title.
    pub title: String,
    /// Time step in s.
    pub dt: f64,
    /// Working type.
    pub number: NumberType,
    /// Backbone.
    pub backbone: BackboneSpec,
    /// Effects, validated.
    pub effects: Vec<Effect>,
    /// Profile.
    pub profile: ProfileSpec,
    /// Steps between two rows of `trace.csv` (1: every step).
    pub trace_every: u64,
    /// A unit mass on the bushing, driven by the profile as a force.
    pub oscillator: Option<OscillatorSpec>,
    /// The ADC the model reads the imposed displacement through (never in
    /// an oscillator scene).
    pub adc: Option<Adc>,
}

/// How the cells of a Maxwell bank store their state (the core's
/// accumulators).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    /// `F - d F`, one word ([`bushing::Plain`]): slow cells keep their rate.
    Plain,
    /// `e^-h F`, one word ([`bushing::Multiplied`]): for cells not slow.
    Multiplied,
    /// Fast2Sum, two words ([`bushing::Compensated`]): slow cells in f32.
    Compensated,
}

impl Storage {
    /// Parses the scene's `state` value.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "plain" => Some(Self::Plain),
            "multiplied" => Some(Self::Multiplied),
            "compensated" => Some(Self::Compensated),
            _ => None,
        }
    }

    /// The scene's name of the storage.
    pub fn name(self) -> &'static str {
        match self {
            Self::Plain => "plain",
            Self::Multiplied => "multiplied",
            Self::Compensated => "compensated",
        }
    }
}

/// A validated effect.
#[derive(Debug, Clone)]
pub enum Effect {
    /// A Maxwell bank.
    Maxwell {
        /// Form.
        form: MaxwellForm,
        /// How each cell stores its state.
        storage: Storage,
        /// Cells (ω in rad/s).
        cells: Vec<MaxwellSpec>,
    },
    /// An Iwan bank.
    Iwan {
        /// Slider form (else clamp form).
        slider: bool,
        /// Reference stiffness (N/mm).
        k_ref: f64,
        /// Cells.
        cells: Vec<IwanCellSpec>,
    },
    /// A turning-point stack model.
    TurningPoints {
        /// The law.
        law: Law,
        /// First loading rule.
        first_loading: FirstLoading,
    },
    /// An x_f bank.
    Xf {
        /// Form.
        form: XfForm,
        /// Cells (ω in rad/s).
        cells: Vec<XfSpec>,
    },
    /// A single friction cell.
    Friction(Friction),
}

/// A validated single friction cell (parameters in f64; the model is built
/// in the run's number type).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Friction {
    /// Dahl (eq 1.43).
    Dahl(DahlParams),
    /// Bouc-Wen (eq 1.44).
    BoucWen(BoucWenParams),
    /// Berg (eq 1.45).
    Berg(BergParams),
}

impl Effect {
    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        match self {
            Self::Maxwell { form, cells, .. } => {
                format!("maxwell {} x{}", form.name(), cells.len())
            }
            Self::Iwan { slider, cells, .. } => {
                let form = if *slider { "slider" } else { "clamp" };
                format!("iwan {form} x{}", cells.len())
            }
            Self::TurningPoints { law, .. } => match law {
                Law::Sts { .. } => "turning-points sts".into(),
                Law::Table { d, .. } => format!("turning-points table x{}", d.len()),
            },
            Self::Xf { form, cells } => format!("xf {} x{}", form.name(), cells.len()),
            Self::Friction(Friction::Dahl(p)) => format!("dahl alpha={}", p.alpha),
            Self::Friction(Friction::BoucWen(p)) => format!("bouc-wen n={}", p.n),
            Self::Friction(Friction::Berg(_)) => "berg".into(),
        }
    }

    /// Sum of the load fractions of the effect's cells.
    pub fn fraction(&self) -> f64 {
        match self {
            Self::Maxwell { cells, .. } => cells.iter().map(|c| c.g).sum(),
            Self::Iwan { cells, .. } => cells.iter().map(|c| c.g).sum(),
            Self::Xf { cells, .. } => cells.iter().map(|c| c.g).sum(),
            Self::TurningPoints { .. } | Self::Friction(_) => 0.0,
        }
    }
}

/// A hysteretic relaxation law, validated.
#[derive(Debug, Clone, PartialEq)]
pub enum Law {
    /// Continuous STS.
    Sts {
        /// C in N²/mm.
        c: f64,
        /// K_1 in N/mm.
        k1: f64,
    },
    /// Measured K_f(d).
    Table {
        /// Distances, mm.
        d: Vec<f64>,
        /// K_f, N/mm.
        k: Vec<f64>,
    },
}

/// Turning points a scene's stack model holds.
pub const STACK_DEPTH: usize = 32;
/// Points a scene's K_f table may hold.
pub const TABLE_POINTS: usize = 64;

/// Largest bank a scene may ask for.
pub const MAX_CELLS: usize = 64;
/// Largest number of steps a scene may ask for.
pub const MAX_STEPS: u64 = 2_000_000_000;

impl Scene {
    /// Reads and checks a scene file.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        Self::load_as(path, None)
    }

    /// Reads and checks a scene file, in number type `number` instead of
    /// the scene's own when given (every check then runs in that type).
    pub fn load_as(path: &Path, number: Option<NumberType>) -> Result<Self, SceneError> {
        Self::load_with(
            path,
            LoadOptions {
                number,
                confine: false,
            },
        )
    }

    /// Reads and checks a scene file. Only a regular file of at most
    /// [`MAX_SCENE_BYTES`] is read (a pipe or a device could block or never
    /// end); the checks come before it is opened.
    pub fn load_with(path: &Path, options: LoadOptions) -> Result<Self, SceneError> {
        use std::io::Read;
        let file = path.display().to_string();
        let fail = |message: String| SceneError {
            file: file.clone(),
            at: None,
            message,
            source: None,
        };
        let meta = std::fs::metadata(path).map_err(|e| fail(format!("cannot read: {e}")))?;
        if !meta.is_file() {
            return Err(fail("not a regular file; a scene is a TOML file".into()));
        }
        if meta.len() > MAX_SCENE_BYTES {
            return Err(fail(format!(
                "{} bytes, more than the limit of {MAX_SCENE_BYTES} for a scene",
                meta.len()
            )));
        }
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|e| fail(format!("cannot read: {e}")))?;
        if bytes.len() as u64 > MAX_SCENE_BYTES {
            return Err(fail(format!(
                "more than the limit of {MAX_SCENE_BYTES} bytes for a scene"
            )));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            fail(format!(
                "cannot read: not UTF-8 text (byte {} is not valid)",
                e.utf8_error().valid_up_to()
            ))
        })?;
        let dir = path.parent().unwrap_or(Path::new(""));
        Self::parse_with(&file, &text, dir, options)
    }

    /// Parses and checks scene text; `file` names it in errors. Files the
    /// scene refers to (a replayed CSV) are found relative to the current
    /// directory; see [`Scene::parse_in`].
    pub fn parse(file: &str, text: &str) -> Result<Self, SceneError> {
        Self::parse_in(file, text, Path::new(""))
    }

    /// Parses and checks scene text whose relative file names are relative
    /// to `dir` (the scene file's directory when loaded from a file).
    pub fn parse_in(file: &str, text: &str, dir: &Path) -> Result<Self, SceneError> {
        Self::parse_as(file, text, dir, None)
    }

    /// [`Scene::parse_in`], in number type `number` instead of the scene's
    /// own `run.number` when given.
    pub fn parse_as(
        file: &str,
        text: &str,
        dir: &Path,
        number: Option<NumberType>,
    ) -> Result<Self, SceneError> {
        Self::parse_with(
            file,
            text,
            dir,
            LoadOptions {
                number,
                confine: false,
            },
        )
    }

    /// [`Scene::parse_in`] with [`LoadOptions`].
    pub fn parse_with(
        file: &str,
        text: &str,
        dir: &Path,
        options: LoadOptions,
    ) -> Result<Self, SceneError> {
        let number = options.number;
        let shared: std::sync::Arc<str> = text.into();
        let err = |span: Option<Range<usize>>, message: String| SceneError {
            file: file.to_string(),
            at: span.as_ref().map(|s| Location::of(text, s.start)),
            message,
            source: span.map(|s| (shared.clone(), s)),
        };
        let raw: SceneFile = toml::from_str(text).map_err(|e| {
            let (span, message) = shape_error(text, &e);
            err(span, message)
        })?;

        let run_span = raw.run.span();
        let mut run = raw.run.into_inner();
        if let Some(number) = number {
            run.number = number;
        }
        if !(run.rate_hz.is_finite() && run.rate_hz > 0.0 && run.rate_hz <= 1e9) {
            return Err(err(
                Some(run_span),
                format!("run.rate_hz must be in (0, 1e9] Hz, got {}", run.rate_hz),
            ));
        }
        let dt = 1.0 / run.rate_hz;

        let bb_span = raw.backbone.span();
        let backbone = raw.backbone.into_inner();
        // The reference stiffness of Iwan cells given by slip distance.
        let k_at_rest = crate::model::backbone::<f64>(&backbone)
            .map_err(|e| err(Some(bb_span.clone()), format!("backbone: {e}")))?
            .eval(0.0)
            .1;
        // The same checks in the working type, where a value valid in f64
        // may overflow or vanish.
        if run.number == NumberType::F32 {
            crate::model::backbone::<f32>(&backbone)
                .map_err(|e| err(Some(bb_span.clone()), format!("backbone (f32): {e}")))?;
        }

        let mut effects = Vec::new();
        let mut seen = Vec::new();
        for (i, spanned) in raw.effects.into_iter().enumerate() {
            let span = spanned.span();
            let spec = spanned.into_inner();
            let kind = spec.kind();
            if seen.contains(&kind) {
                return Err(err(
                    Some(span),
                    format!(
                        "effects[{i}]: a second '{kind}' effect; put all its cells in one table"
                    ),
                ));
            }
            seen.push(kind);
            let checked = match run.number {
                NumberType::F32 => validate_effect::<f32>(spec, dt, k_at_rest),
                NumberType::F64 => validate_effect::<f64>(spec, dt, k_at_rest),
            };
            let effect = checked
                .map_err(|m| err(Some(span.clone()), format!("effects[{i}] ({kind}): {m}")))?;
            effects.push(effect);
        }
        let sum: f64 = effects.iter().map(Effect::fraction).sum();
        if sum > 1.0 + 1e-12 {
            return Err(err(None, ParamError::FractionsAboveOne { sum }.to_string()));
        }

        let pr_span = raw.profile.span();
        let profile = crate::profile::resolve(raw.profile.into_inner(), dir, options.confine)
            .map_err(|m| err(Some(pr_span.clone()), format!("profile: {m}")))?;
        let steps = crate::profile::steps(&profile, dt)
            .map_err(|m| err(Some(pr_span.clone()), format!("profile: {m}")))?;
        if steps > MAX_STEPS {
            return Err(err(
                Some(pr_span),
                format!("profile: {steps} steps, more than the limit of {MAX_STEPS}"),
            ));
        }
        let trace_every = match raw.output {
            None => 1,
            Some(o) => {
                let span = o.span();
                let every = o.into_inner().trace_every;
                u64::try_from(every)
                    .ok()
                    .filter(|&n| n >= 1)
                    .ok_or_else(|| {
                        err(
                            Some(span),
                            format!("output.trace_every must be a whole number >= 1, got {every}"),
                        )
                    })?
            }
        };
        let oscillator = match raw.oscillator {
            None => None,
            Some(o) => {
                let span = o.span();
                let o = o.into_inner();
                let bad = |m: String| err(Some(span.clone()), format!("oscillator.{m}"));
                for (name, v) in [("p0", o.p0), ("v0", o.v0)] {
                    if !v.is_finite() {
                        return Err(bad(format!("{name} must be finite, got {v}")));
                    }
                }
                Some(o)
            }
        };
        let adc = match raw.adc {
            None => None,
            Some(a) => {
                let span = a.span();
                let a = a.into_inner();
                let bad = |m: String| err(Some(span.clone()), format!("adc.{m}"));
                if oscillator.is_some() {
                    return Err(err(
                        Some(span),
                        "adc: an [oscillator] scene's profile is a force, not a displacement \
                         read by an ADC: remove [adc] or [oscillator]"
                            .into(),
                    ));
                }
                if !(a.lsb_mm.is_finite() && a.lsb_mm > 0.0) {
                    return Err(bad(format!(
                        "lsb_mm must be finite and > 0 mm, got {}",
                        a.lsb_mm
                    )));
                }
                let bits = u32::try_from(a.bits)
                    .ok()
                    .filter(|b| (2..=MAX_ADC_BITS).contains(b))
                    .ok_or_else(|| {
                        bad(format!(
                            "bits must be a whole number from 2 to {MAX_ADC_BITS}, got {}",
                            a.bits
                        ))
                    })?;
                Some(Adc {
                    lsb_mm: a.lsb_mm,
                    bits,
                })
            }
        };
        Ok(Self {
            title: raw.title,
            dt,
            number: run.number,
            backbone,
            effects,
            profile,
            trace_every,
            oscillator,
            adc,
        })
    }

    /// Number of steps the profile takes.
    pub fn steps(&self) -> u64 {
        crate::profile::steps(&self.profile, self.dt).unwrap_or(0)
    }

    /// The input of the model at time `t` (s): the profile's displacement
    /// in mm, as the `[adc]` reads it when there is one (`code * lsb_mm`,
    /// in f64), or in an oscillator scene the applied force in N.
    pub fn input(&self, t: f64) -> f64 {
        let x = crate::profile::displacement(&self.profile, t);
        match self.adc {
            Some(adc) => adc.read(x),
            None => x,
        }
    }
}

/// Checks an effect table by building its cells in the working type `T`
/// (every parameter check of the core, including the values that leave
/// `T`).
fn validate_effect<T: bushing::Real>(
    spec: EffectSpec,
    dt: f64,
    k_at_rest: f64,
) -> Result<Effect, String> {
    match spec {
        EffectSpec::Maxwell { form, state, cells } => {
            let form = MaxwellForm::from_name(&form).ok_or_else(|| {
                let names: Vec<_> = MaxwellForm::ALL.iter().map(|f| f.name()).collect();
                format!("form '{form}' is not one of {}", names.join(", "))
            })?;
            let storage = Storage::from_name(&state).ok_or_else(|| {
                format!("state '{state}' is not one of plain, multiplied, compensated")
            })?;
            check_count(cells.len())?;
            for (i, c) in cells.iter().enumerate() {
                if !(c.f_hz.is_finite() && c.f_hz > 0.0) {
                    return Err(format!(
                        "cells[{i}].f_hz must be finite and > 0 Hz, got {}",
                        c.f_hz
                    ));
                }
            }
            let cells: Vec<MaxwellSpec> =
                cells.iter().map(|c| MaxwellSpec::hz(c.f_hz, c.g)).collect();
            // Build each cell once to run every parameter check of the core.
            for (i, c) in cells.iter().enumerate() {
                bushing::MaxwellCell::<T>::new(form, *c, dt, i).map_err(|e| e.to_string())?;
            }
            let sum: f64 = cells.iter().map(|c| c.g).sum();
            if sum > 1.0 + 1e-12 {
                return Err(ParamError::FractionsAboveOne { sum }.to_string());
            }
            Ok(Effect::Maxwell {
                form,
                storage,
                cells,
            })
        }
        EffectSpec::Iwan { form, k_ref, cells } => {
            let slider = match form.as_str() {
                "clamp" => false,
                "slider" => true,
                other => return Err(format!("form '{other}' is not one of clamp, slider")),
            };
            let k_ref = k_ref.unwrap_or(k_at_rest);
            if !(k_ref.is_finite() && k_ref > 0.0) {
                return Err(format!("k_ref must be finite and > 0 N/mm, got {k_ref}"));
            }
            check_count(cells.len())?;
            let cells = cells
                .iter()
                .enumerate()
                .map(|(i, c)| match (c.slip_force, c.x_f) {
                    (Some(f), None) => Ok(IwanCellSpec::new(c.g, f)),
                    (None, Some(x_f)) => Ok(IwanCellSpec::from_slip_distance(c.g, k_ref, x_f)),
                    _ => Err(format!(
                        "cells[{i}]: give exactly one of slip_force (N) and x_f (mm)"
                    )),
                })
                .collect::<Result<Vec<_>, _>>()?;
            for (i, c) in cells.iter().enumerate() {
                bushing::iwan::SliderCell::<T>::new(*c, k_ref, i).map_err(|e| e.to_string())?;
            }
            Ok(Effect::Iwan {
                slider,
                k_ref,
                cells,
            })
        }
        EffectSpec::TurningPoints {
            law,
            c,
            k1,
            d,
            k,
            first_loading,
        } => {
            let first_loading = match first_loading.as_str() {
                "masing" => FirstLoading::Masing,
                "ignored" => FirstLoading::Ignored,
                other => {
                    return Err(format!(
                        "first_loading '{other}' is not one of masing, ignored"
                    ));
                }
            };
            let law = match (law.as_str(), c, k1, d, k) {
                ("sts", Some(c), Some(k1), None, None) => {
                    Sts::<T>::new(c, k1).map_err(|e| e.to_string())?;
                    Law::Sts { c, k1 }
                }
                ("sts", ..) => {
                    return Err("law 'sts' takes c (N²/mm) and k1 (N/mm), and no d or k".into());
                }
                ("table", None, None, Some(d), Some(k)) => {
                    KfTable::<T, TABLE_POINTS>::new(&d, &k).map_err(|e| e.to_string())?;
                    Law::Table { d, k }
                }
                ("table", ..) => {
                    return Err("law 'table' takes d (mm) and k (N/mm), and no c or k1".into());
                }
                (other, ..) => return Err(format!("law '{other}' is not one of sts, table")),
            };
            Ok(Effect::TurningPoints { law, first_loading })
        }
        EffectSpec::Xf { form, cells } => {
            let form = XfForm::from_name(&form)
                .ok_or_else(|| format!("form '{form}' is not one of midpoint, exact-ramp"))?;
            check_count(cells.len())?;
            let cells: Vec<XfSpec> = cells
                .iter()
                .map(|c| XfSpec::hz(c.f_hz, c.g, c.x_f))
                .collect();
            for (i, c) in cells.iter().enumerate() {
                bushing::xf::XfCell::<T>::new(*c, dt, i).map_err(|e| e.to_string())?;
            }
            Ok(Effect::Xf { form, cells })
        }
        EffectSpec::Dahl(p) => {
            bushing::Dahl::<T>::new(p.k_d, p.f_f, p.alpha).map_err(|e| e.to_string())?;
            Ok(Effect::Friction(Friction::Dahl(p)))
        }
        EffectSpec::BoucWen(p) => {
            bushing::BoucWen::<T>::new(p.alpha, p.a, p.beta, p.gamma, p.n)
                .map_err(|e| e.to_string())?;
            Ok(Effect::Friction(Friction::BoucWen(p)))
        }
        EffectSpec::Berg(p) => {
            bushing::Berg::<T>::new(p.f_max, p.x2).map_err(|e| e.to_string())?;
            Ok(Effect::Friction(Friction::Berg(p)))
        }
    }
}

fn check_count(n: usize) -> Result<(), String> {
    if n == 0 || n > MAX_CELLS {
        Err(format!("1 to {MAX_CELLS} cells expected, got {n}"))
    } else {
        Ok(())
    }
}
/// The place and the message of a TOML or shape error (a missing key, a
/// value of the wrong type), as precise as the document allows: a mistake
/// inside a tagged table (`[backbone]`, `[[effects]]`, `[profile]`) is found
/// again by reading the table as its variant ([`tagged_mistake`]), and the
/// message starts with where it is (`effects[0] (maxwell): cells[1].g: `).
fn shape_error(text: &str, e: &toml::de::Error) -> (Option<Range<usize>>, String) {
    let message = e.message().trim().to_string();
    let Some(mut span) = e.span() else {
        return (None, message);
    };
    // A syntax error: the parser's own place and message.
    let Ok(doc) = DeTable::parse(text) else {
        return (Some(span), message);
    };
    let doc = doc.into_inner();
    if let Some(at) = tagged_mistake(&doc, &span, &message) {
        span = at;
    }
    let mut path = Vec::new();
    let mut best = None;
    find_value(&doc, &span, &mut path, &mut best);
    let Some((path, value)) = best else {
        return (Some(span), message);
    };
    let Some(value) = value else {
        // A key (an unknown one): name the table it is in.
        let table = path.split_last().map_or(&[][..], |(_, t)| t);
        return (Some(span), format!("{}{message}", prefix(&doc, table)));
    };
    let opens = |s: &str| text.get(span.start..).is_some_and(|t| t.starts_with(s));
    let (path, message) = match (value, &path[..]) {
        // `[effects]` for `[[effects]]`, `cells = { … }` for `cells = [{ … }]`.
        (DeValue::Table(_), _) if message.starts_with("invalid type: map, expected a sequence") => {
            let name = dotted(&path);
            let message = if opens("[") {
                format!(
                    "a single table `[{name}]` where an array of tables is expected: \
                     write `[[{name}]]` above each entry"
                )
            } else {
                "a table where an array is expected: write `[{ … }, { … }]`".to_string()
            };
            (&path[..], message)
        }
        // `[[backbone]]` for `[backbone]`: serde reads the table's fields
        // from the array's entries, the first of which is a whole table.
        (DeValue::Table(_), [table @ Step::Key(name), Step::Index(0)])
            if opens("[[") && message.starts_with("invalid type: map") =>
        {
            let message = format!(
                "`[[{name}]]` starts an array of tables where a single table is expected: \
                 write `[{name}]`"
            );
            (std::slice::from_ref(table), message)
        }
        _ => (&path[..], message),
    };
    (Some(span), format!("{}{message}", prefix(&doc, path)))
}

/// Where the mistake is when an error points at a tagged table (or at the
/// `[[effects]]` array, as errors inside its entries do): the first such
/// table that does not read as its variant, at the value the variant names
/// (at the table itself for unknown keys and names, whose message lists
/// what the table takes). `None` to leave the error where it is.
fn tagged_mistake(doc: &DeTable<'_>, span: &Range<usize>, message: &str) -> Option<Range<usize>> {
    // Errors inside an `[[effects]]` entry point at the array, whose span
    // is that of its first entry.
    let in_effects = doc.get("effects").is_some_and(|e| e.span() == *span);
    let candidates = tagged_tables(doc)
        .into_iter()
        .filter(|(table, _, entry)| table.span() == *span || (*entry && in_effects));
    for (table, read, _) in candidates {
        let Some(tag) = tag_of(table) else {
            // No string `type` (or not a table): serde stops here too.
            return Some(table.span());
        };
        let Err(again) = read(by_tag(table, tag)) else {
            continue;
        };
        // The same mistake, found where it is; otherwise leave it.
        if again.message().trim() != message {
            return None;
        }
        let unknown =
            message.starts_with("unknown field") || message.starts_with("unknown variant");
        return Some(match again.span() {
            Some(at) if !unknown => at,
            _ => table.span(),
        });
    }
    None
}

/// Reads one tagged table's content as the variant its `type` names.
type ReadByTag = for<'i> fn(ByTag<'i>) -> Result<(), toml::de::Error>;

/// The tagged tables of a scene document in the order serde reads them,
/// each with its variant reader and whether it is an `[[effects]]` entry.
fn tagged_tables<'a, 'i>(doc: &'a DeTable<'i>) -> Vec<(&'a Spanned<DeValue<'i>>, ReadByTag, bool)> {
    let mut tables: Vec<(&Spanned<DeValue<'i>>, ReadByTag, bool)> = Vec::new();
    if let Some(t) = doc.get("backbone") {
        tables.push((t, |d| BackboneByTag::deserialize(d).map(drop), false));
    }
    if let Some(DeValue::Array(effects)) = doc.get("effects").map(Spanned::get_ref) {
        for t in effects.iter() {
            tables.push((t, |d| EffectByTag::deserialize(d).map(drop), true));
        }
    }
    if let Some(t) = doc.get("profile") {
        tables.push((t, |d| ProfileByTag::deserialize(d).map(drop), false));
    }
    tables
}

/// The `type` of a tagged table, if it is a table with a string `type`.
fn tag_of<'a>(table: &'a Spanned<DeValue<'_>>) -> Option<&'a str> {
    table.get_ref().get("type")?.get_ref().as_str()
}

/// A tagged table's content, without its `type`, as variant `tag`.
fn by_tag<'i>(table: &Spanned<DeValue<'i>>, tag: &str) -> ByTag<'i> {
    let mut content = match table.get_ref() {
        DeValue::Table(t) => t.clone(),
        _ => DeTable::new(),
    };
    content.remove("type");
    ByTag {
        tag: tag.to_string(),
        content: Spanned::new(table.span(), DeValue::Table(content)),
    }
}

/// A tagged table's content (its keys but `type`) presented as variant
/// `tag` of an externally tagged enum.
struct ByTag<'i> {
    tag: String,
    content: Spanned<DeValue<'i>>,
}

impl<'de> de::Deserializer<'de> for ByTag<'de> {
    type Error = toml::de::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        visitor.visit_enum(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf option unit unit_struct newtype_struct seq tuple
        tuple_struct map struct enum identifier ignored_any
    }
}

impl<'de> de::EnumAccess<'de> for ByTag<'de> {
    type Error = toml::de::Error;
    type Variant = VariantContent<'de>;

    fn variant_seed<V: DeserializeSeed<'de>>(
        self,
        seed: V,
    ) -> Result<(V::Value, Self::Variant), Self::Error> {
        let tag = de::value::StringDeserializer::<toml::de::Error>::new(self.tag);
        Ok((seed.deserialize(tag)?, VariantContent(self.content)))
    }
}

/// The content of a variant read by [`ByTag`].
struct VariantContent<'i>(Spanned<DeValue<'i>>);

impl<'de> de::VariantAccess<'de> for VariantContent<'de> {
    type Error = toml::de::Error;

    fn unit_variant(self) -> Result<(), Self::Error> {
        Ok(())
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(
        self,
        seed: T,
    ) -> Result<T::Value, Self::Error> {
        seed.deserialize(ValueDeserializer::from(self.0))
    }

    fn tuple_variant<V: Visitor<'de>>(
        self,
        _len: usize,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        de::Deserializer::deserialize_seq(ValueDeserializer::from(self.0), visitor)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        de::Deserializer::deserialize_struct(ValueDeserializer::from(self.0), "", fields, visitor)
    }
}

/// One step of the way to a value: a key of a table or an index of an
/// array.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// Deepest nesting [`find_value`] looks into (a scene nests four deep).
const MAX_DEPTH: usize = 32;

/// The deepest value (or key, with `None`) of a document whose span is
/// some span, and the way to it.
type Found<'a, 'i> = Option<(Vec<Step<'a>>, Option<&'a DeValue<'i>>)>;

/// Looks through `table` (at `path`) for the deepest value or key whose
/// span is `span`, into `best`.
fn find_value<'a, 'i>(
    table: &'a DeTable<'i>,
    span: &Range<usize>,
    path: &mut Vec<Step<'a>>,
    best: &mut Found<'a, 'i>,
) {
    for (key, value) in table.iter() {
        path.push(Step::Key(key.get_ref()));
        if key.span() == *span && best.as_ref().is_none_or(|(p, _)| p.len() < path.len()) {
            *best = Some((path.clone(), None));
        }
        visit_value(value, span, path, best);
        path.pop();
    }
}

fn visit_value<'a, 'i>(
    value: &'a Spanned<DeValue<'i>>,
    span: &Range<usize>,
    path: &mut Vec<Step<'a>>,
    best: &mut Found<'a, 'i>,
) {
    if value.span() == *span && best.as_ref().is_none_or(|(p, _)| p.len() < path.len()) {
        *best = Some((path.clone(), Some(value.get_ref())));
    }
    if path.len() >= MAX_DEPTH {
        return;
    }
    match value.get_ref() {
        DeValue::Table(t) => find_value(t, span, path, best),
        DeValue::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                path.push(Step::Index(i));
                visit_value(v, span, path, best);
                path.pop();
            }
        }
        _ => {}
    }
}

/// `cells[1].g` for the way `cells`, 1, `g`.
fn dotted(path: &[Step<'_>]) -> String {
    let mut s = String::new();
    for step in path {
        match step {
            Step::Key(k) if s.is_empty() => s.push_str(k),
            Step::Key(k) => {
                s.push('.');
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// What an error message at `path` starts with: the section as the
/// parameter checks name it (`backbone: `, `profile: `,
/// `effects[0] (maxwell): `), then the key inside it (`cells[1].g: `);
/// outside those sections the dotted key (`run.rate_hz: `).
fn prefix(doc: &DeTable<'_>, path: &[Step<'_>]) -> String {
    let (section, rest) = match path {
        [] => return String::new(),
        [Step::Key("effects"), Step::Index(i), rest @ ..] => {
            let kind = doc
                .get("effects")
                .and_then(|e| e.get_ref().get(*i))
                .and_then(|e| e.get_ref().get("type"))
                .and_then(|t| t.get_ref().as_str());
            match kind {
                // Not when the kind itself is the mistake.
                Some(kind) if rest != [Step::Key("type")] => {
                    (format!("effects[{i}] ({kind})"), rest)
                }
                _ => (format!("effects[{i}]"), rest),
            }
        }
        [Step::Key(k @ ("backbone" | "profile")), rest @ ..] => ((*k).to_string(), rest),
        _ => return format!("{}: ", dotted(path)),
    };
    if rest.is_empty() {
        format!("{section}: ")
    } else {
        format!("{section}: {}: ", dotted(rest))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
title = "t"
[run]
rate_hz = 1000
number = "f64"
[backbone]
type = "polynomial"
coefficients = [0.0, 100.0]
range = [-1.0, 1.0]
[[effects]]
type = "maxwell"
form = "rate-exact-ramp"
cells = [{ f_hz = 1.0, g = 0.2 }]
[profile]
type = "sine"
amplitude = 1.0
frequency_hz = 2.0
cycles = 3
"#;

    #[test]
    fn a_good_scene_parses() {
        let s = Scene::parse("good.toml", GOOD).unwrap();
        assert_eq!(s.dt, 1e-3);
        assert_eq!(s.number, NumberType::F64);
        assert_eq!(s.steps(), 1500);
        assert_eq!(s.effects.len(), 1);
    }

    #[test]
    fn syntax_errors_carry_line_and_column() {
        let bad = GOOD.replace("rate_hz = 1000", "rate_hz = = 1000");
        let e = Scene::parse("bad.toml", &bad).unwrap_err();
        assert_eq!(e.at.map(|l| l.line), Some(4), "{e}");
        assert!(e.to_string().starts_with("bad.toml:4:"), "{e}");
    }

    #[test]
    fn unknown_fields_and_kinds_are_located() {
        let bad = GOOD.replace("amplitude = 1.0", "amplitud = 1.0");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(e.message.contains("amplitud"), "{e}");
        assert!(e.at.is_some());
        let bad = GOOD.replace("type = \"maxwell\"", "type = \"maxwel\"");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(e.message.contains("maxwel"), "{e}");
        assert_eq!(e.at.map(|l| l.line), Some(11), "{e}");
    }

    #[test]
    fn bad_parameters_name_effect_parameter_and_bound() {
        let bad = GOOD.replace("f_hz = 1.0", "f_hz = -1.0");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(
            e.message.contains("effects[0] (maxwell)")
                && e.message.contains("cells[0].f_hz must be finite and > 0"),
            "{e}"
        );
        // The effect's [[effects]] header.
        assert_eq!(e.at.map(|l| l.line), Some(10), "{e}");
        let bad = GOOD
            .replace("rate-exact-ramp", "rate-explicit")
            .replace("f_hz = 1.0", "f_hz = 200.0");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(e.message.contains("omega*dt = 1.25"), "{e}");
        let bad = GOOD.replace("g = 0.2", "g = 1.5");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(
            e.message
                .contains("effects[0] (maxwell): cells[0].g = 1.5 must be in (0, 1]"),
            "{e}"
        );
        assert_eq!(e.at.map(|l| l.line), Some(10), "{e}");
        let bad = GOOD.replace(
            "coefficients = [0.0, 100.0]",
            "coefficients = [0.0, -100.0]",
        );
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(e.message.starts_with("backbone: backbone tangent"), "{e}");
        assert_eq!(e.at.map(|l| l.line), Some(6), "{e}");
    }

    #[test]
    fn iwan_cells_take_a_slip_force_or_a_distance_on_k_ref() {
        let iwan = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"iwan\"\nform = \"clamp\"\ncells = [{ g = 0.1, x_f = 0.5 }, { g = 0.2, slip_force = 7.0 }]\n[profile]",
        );
        let s = Scene::parse("s.toml", &iwan).unwrap();
        match &s.effects[1] {
            Effect::Iwan {
                slider,
                k_ref,
                cells,
            } => {
                assert!(!slider);
                assert_eq!(*k_ref, 100.0); // backbone tangent at 0
                assert_eq!(cells[0], IwanCellSpec::new(0.1, 0.1 * 100.0 * 0.5));
                assert_eq!(cells[1], IwanCellSpec::new(0.2, 7.0));
            }
            other => panic!("{other:?}"),
        }
        let both = iwan.replace(
            "{ g = 0.1, x_f = 0.5 }",
            "{ g = 0.1, x_f = 0.5, slip_force = 1.0 }",
        );
        let e = Scene::parse("s.toml", &both).unwrap_err();
        assert!(
            e.message
                .contains("cells[0]: give exactly one of slip_force"),
            "{e}"
        );
        let bad_form = iwan.replace("form = \"clamp\"", "form = \"stick\"");
        assert!(
            Scene::parse("s.toml", &bad_form)
                .unwrap_err()
                .message
                .contains("not one of clamp, slider")
        );
        let too_much = iwan.replace("g = 0.2, slip_force", "g = 0.75, slip_force");
        assert!(
            Scene::parse("s.toml", &too_much)
                .unwrap_err()
                .message
                .contains("above 1")
        );
    }

    #[test]
    fn xf_cells_are_checked() {
        let xf = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"xf\"\nform = \"exact-ramp\"\ncells = [{ f_hz = 0.0, g = 0.1, x_f = 0.02 }]\n[profile]",
        );
        let s = Scene::parse("s.toml", &xf).unwrap();
        assert_eq!(s.effects[1].name(), "xf exact-ramp x1");
        let bad = xf.replace("x_f = 0.02", "x_f = -0.02");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(
            e.message.contains("effects[1] (xf): x_f[0] must be > 0"),
            "{e}"
        );
        let twice = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"maxwell\"\nform = \"rate-midpoint\"\ncells = [{ f_hz = 3.0, g = 0.1 }]\n[profile]",
        );
        let e = Scene::parse("s.toml", &twice).unwrap_err();
        assert!(
            e.message.contains("effects[1]: a second 'maxwell' effect"),
            "{e}"
        );
    }

    #[test]
    fn friction_cells_are_checked() {
        let cells = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"dahl\"\nk_d = 200.0\nf_f = 10.0\n\
             [[effects]]\ntype = \"bouc-wen\"\nalpha = 20.0\na = 10.0\nbeta = 60.0\ngamma = 20.0\nn = 8.0\n\
             [[effects]]\ntype = \"berg\"\nf_max = 12.0\nx2 = 0.05\n[profile]",
        );
        let s = Scene::parse("s.toml", &cells).unwrap();
        let names: Vec<_> = s.effects.iter().map(Effect::name).collect();
        assert_eq!(names[1..], ["dahl alpha=1", "bouc-wen n=8", "berg"]);
        assert_eq!(
            s.effects.iter().skip(1).map(Effect::fraction).sum::<f64>(),
            0.0
        );
        let bad = cells.replace("gamma = 20.0", "gamma = 70.0");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(
            e.message
                .contains("effects[2] (bouc-wen): beta - |gamma| must be"),
            "{e}"
        );
        let bad = cells.replace("x2 = 0.05", "x2 = 0.0");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(e.message.contains("effects[3] (berg): x2 must be"), "{e}");
        let bad = cells.replace("f_f = 10.0", "f_f = 10.0\nmu = 0.3");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(e.message.contains("mu"), "{e}");
        assert!(e.at.is_some(), "{e}");
    }

    #[test]
    fn turning_point_laws_are_checked() {
        let sts = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"turning-points\"\nlaw = \"sts\"\nc = 400.0\nk1 = 300.0\n[profile]",
        );
        let s = Scene::parse("s.toml", &sts).unwrap();
        assert_eq!(s.effects[1].name(), "turning-points sts");
        assert_eq!(s.effects[1].fraction(), 0.0);
        let missing = sts.replace("k1 = 300.0\n", "");
        let e = Scene::parse("s.toml", &missing).unwrap_err();
        assert!(
            e.message
                .contains("law 'sts' takes c (N²/mm) and k1 (N/mm)"),
            "{e}"
        );
        let table = sts.replace(
            "law = \"sts\"\nc = 400.0\nk1 = 300.0",
            "law = \"table\"\nd = [0.0, 0.5]\nk = [100.0, 120.0]",
        );
        let e = Scene::parse("s.toml", &table).unwrap_err();
        assert!(
            e.message
                .contains("k[1] must not exceed the entry before it"),
            "{e}"
        );
        let first = sts.replace("k1 = 300.0", "k1 = 300.0\nfirst_loading = \"later\"");
        assert!(
            Scene::parse("s.toml", &first)
                .unwrap_err()
                .message
                .contains("not one of masing, ignored")
        );
    }

    /// Line and column of an error.
    fn at(e: &SceneError) -> (usize, usize) {
        e.at.map_or((0, 0), |l| (l.line, l.column))
    }

    #[test]
    fn wrong_values_in_tagged_tables_point_at_the_value_and_name_the_key() {
        // [[effects]]: a newtype variant, a struct variant's cell, an
        // optional parameter.
        let friction = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"dahl\"\nk_d = 200.0\nf_f = \"10 N\"\n[profile]",
        );
        let e = Scene::parse("s.toml", &friction).unwrap_err();
        assert_eq!(
            e.message,
            "effects[1] (dahl): f_f: invalid type: string \"10 N\", expected f64"
        );
        assert_eq!(at(&e), (17, 7), "{e}");
        let cell = GOOD.replace("g = 0.2", "g = \"0.2\"");
        let e = Scene::parse("s.toml", &cell).unwrap_err();
        assert!(
            e.message
                .starts_with("effects[0] (maxwell): cells[0].g: invalid type: string"),
            "{e}"
        );
        assert_eq!(at(&e), (13, 28), "{e}");
        let iwan = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"iwan\"\nform = \"clamp\"\ncells = [{ g = 0.1, x_f = true }]\n[profile]",
        );
        let e = Scene::parse("s.toml", &iwan).unwrap_err();
        assert!(
            e.message.starts_with(
                "effects[1] (iwan): cells[0].x_f: invalid type: boolean `true`, expected f64"
            ),
            "{e}"
        );
        assert_eq!(at(&e), (17, 27), "{e}");
        // A missing key of a cell points at the cell.
        let e = Scene::parse("s.toml", &GOOD.replace("f_hz = 1.0, ", "")).unwrap_err();
        assert_eq!(
            e.message,
            "effects[0] (maxwell): cells[0]: missing field `f_hz`"
        );
        assert_eq!(at(&e), (13, 10), "{e}");
        // [backbone] and [profile].
        let e = Scene::parse("s.toml", &GOOD.replace("100.0]", "\"100\"]")).unwrap_err();
        assert!(
            e.message
                .starts_with("backbone: coefficients[1]: invalid type: string"),
            "{e}"
        );
        assert_eq!(at(&e), (8, 22), "{e}");
        let e = Scene::parse("s.toml", &GOOD.replace("cycles = 3", "cycles = [3]")).unwrap_err();
        assert!(
            e.message
                .starts_with("profile: cycles: invalid type: sequence, expected f64"),
            "{e}"
        );
        assert_eq!(at(&e), (18, 10), "{e}");
        // Outside the tagged tables the key is named too.
        let e = Scene::parse("s.toml", &GOOD.replace("1000", "\"1 kHz\"")).unwrap_err();
        assert!(
            e.message.starts_with("run.rate_hz: invalid type: string"),
            "{e}"
        );
        assert_eq!(at(&e), (4, 11), "{e}");
    }

    #[test]
    fn unknown_keys_in_tagged_tables_stay_at_their_table() {
        // In the second [[effects]] table (serde points at the first).
        let bad = GOOD.replace(
            "[profile]",
            "[[effects]]\ntype = \"berg\"\nf_max = 12.0\nx2 = 0.05\nmu = 0.3\n[profile]",
        );
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert_eq!(
            e.message,
            "effects[1] (berg): unknown field `mu`, expected `f_max` or `x2`"
        );
        assert_eq!(at(&e), (14, 1), "{e}");
        let bad = GOOD.replace("cycles = 3", "cycles = 3\nphase = 0.5");
        let e = Scene::parse("s.toml", &bad).unwrap_err();
        assert!(
            e.message.starts_with("profile: unknown field `phase`"),
            "{e}"
        );
        assert_eq!(at(&e), (14, 1), "{e}");
    }

    #[test]
    fn tables_and_arrays_of_tables_written_for_each_other_are_named() {
        let e = Scene::parse("s.toml", &GOOD.replace("[[effects]]", "[effects]")).unwrap_err();
        assert!(
            e.message.starts_with(
                "effects: a single table `[effects]` where an array of tables is expected: \
                 write `[[effects]]`"
            ),
            "{e}"
        );
        assert_eq!(at(&e), (10, 1), "{e}");
        let e = Scene::parse("s.toml", &GOOD.replace("[run]", "[[run]]")).unwrap_err();
        assert_eq!(
            e.message,
            "run: `[[run]]` starts an array of tables where a single table is expected: \
             write `[run]`"
        );
        assert_eq!(at(&e), (3, 1), "{e}");
        let inline = GOOD.replace(
            "cells = [{ f_hz = 1.0, g = 0.2 }]",
            "cells = { f_hz = 1.0, g = 0.2 }",
        );
        let e = Scene::parse("s.toml", &inline).unwrap_err();
        assert!(
            e.message
                .starts_with("effects[0] (maxwell): cells: a table where an array is expected"),
            "{e}"
        );
        assert_eq!(at(&e), (13, 9), "{e}");
    }

    #[test]
    fn shape_errors_of_odd_documents_do_not_panic() {
        for text in [
            "",
            "effects = 3",
            "effects = [1, \"x\"]\n[run]\nrate_hz = 1",
            "[[effects]]\ntype = 3",
            "[[effects]]\n[[effects]]\ntype = \"dahl\"\nk_d = \"\"",
            "backbone = \"spline\"",
            "[[backbone]]\n[[backbone]]",
            "[profile]\ntype = \"stop-start\"\n[[profile.events]]\nat_s = \"0\"",
            "a.b.c.d.e.f = [[[[[[1]]]]]]",
        ] {
            let e = Scene::parse("s.toml", text).unwrap_err();
            assert!(!e.message.is_empty(), "{text:?}");
        }
    }

    #[test]
    fn an_adc_table_parses_with_its_default_width() {
        let s = Scene::parse("s.toml", &format!("{GOOD}[adc]\nlsb_mm = 0.000244140625\n")).unwrap();
        assert_eq!(
            s.adc,
            Some(Adc {
                lsb_mm: 1.0 / 4096.0,
                bits: 16
            })
        );
        // The model reads code * lsb: 1 mm sine at 2 Hz, t = 0.125 s is
        // its crest (1 mm = 4096 codes).
        assert_eq!(s.input(0.125), 1.0);
        let x = crate::profile::displacement(&s.profile, 0.01);
        let code = bushing::excitation::adc_code(x, 1.0 / 4096.0, 16);
        assert_eq!(s.input(0.01), f64::from(code) / 4096.0);
        assert_ne!(s.input(0.01), x);
        let s = Scene::parse("s.toml", &format!("{GOOD}[adc]\nlsb_mm = 0.5\nbits = 2\n")).unwrap();
        assert_eq!(s.adc.map(|a| a.bits), Some(2));
        // Two bits saturate at codes -2..=1: 0.5 mm at most.
        assert_eq!(s.input(0.125), 0.5);
        assert!(Scene::parse("s.toml", GOOD).unwrap().adc.is_none());
    }

    #[test]
    fn bad_adc_values_are_refused_at_the_table() {
        let adc =
            |body: &str| Scene::parse("s.toml", &format!("{GOOD}[adc]\n{body}\n")).unwrap_err();
        // [adc] is on line 19, after GOOD.
        for (lsb, shown) in [
            ("0.0", "0"),
            ("-0.001", "-0.001"),
            ("nan", "NaN"),
            ("inf", "inf"),
        ] {
            let e = adc(&format!("lsb_mm = {lsb}"));
            assert_eq!(
                e.message,
                format!("adc.lsb_mm must be finite and > 0 mm, got {shown}")
            );
            assert_eq!(at(&e), (19, 1), "{e}");
        }
        for bits in ["1", "25", "-3", "0"] {
            let e = adc(&format!("lsb_mm = 0.001\nbits = {bits}"));
            assert_eq!(
                e.message,
                format!("adc.bits must be a whole number from 2 to 24, got {bits}")
            );
            assert_eq!(at(&e), (19, 1), "{e}");
        }
        for bits in ["24", "2"] {
            Scene::parse(
                "s.toml",
                &format!("{GOOD}[adc]\nlsb_mm = 0.001\nbits = {bits}\n"),
            )
            .unwrap();
        }
        let e = adc("lsb_mm = 0.001\nbits = 12.5");
        assert!(
            e.message
                .starts_with("adc.bits: invalid type: floating point"),
            "{e}"
        );
        assert_eq!(at(&e), (21, 8), "{e}");
        let e = adc("lsb = 0.001");
        assert!(e.message.contains("unknown field `lsb`"), "{e}");
        assert!(e.at.is_some(), "{e}");
        let e = adc("bits = 12");
        assert!(e.message.contains("missing field `lsb_mm`"), "{e}");
        assert!(e.at.is_some(), "{e}");
        // Not with an oscillator, whose profile is a force.
        let e = Scene::parse(
            "s.toml",
            &format!("{GOOD}[oscillator]\np0 = 0.0\n[adc]\nlsb_mm = 0.001\n"),
        )
        .unwrap_err();
        assert!(
            e.message
                .starts_with("adc: an [oscillator] scene's profile is a force"),
            "{e}"
        );
        assert_eq!(at(&e), (21, 1), "{e}");
    }

    #[test]
    fn the_number_type_can_be_overridden() {
        let s = Scene::parse_as("s.toml", GOOD, Path::new(""), Some(NumberType::F32)).unwrap();
        assert_eq!(s.number, NumberType::F32);
        let s = Scene::parse_as("s.toml", GOOD, Path::new(""), None).unwrap();
        assert_eq!(s.number, NumberType::F64);
        // The checks run in the overriding type.
        let big = GOOD.replace("[0.0, 100.0]", "[0.0, 1e39]");
        Scene::parse("s.toml", &big).unwrap();
        let e = Scene::parse_as("s.toml", &big, Path::new(""), Some(NumberType::F32)).unwrap_err();
        assert!(e.message.starts_with("backbone (f32)"), "{e}");
    }

    #[test]
    fn location_counts_characters() {
        assert_eq!(
            Location::of("ab\ncé\nx", 6),
            Location { line: 2, column: 3 }
        );
        assert_eq!(Location::of("", 10), Location { line: 1, column: 1 });
    }
}
