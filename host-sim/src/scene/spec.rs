//! The scene file as written: the TOML tables, read by serde.

use serde::Deserialize;
use toml::Spanned;

use crate::backbone::BackboneSpec;
use crate::profile::ProfileSpec;

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
    /// A temperature history the Maxwell banks follow during the run;
    /// optional.
    #[serde(default)]
    pub temperature: Option<Spanned<TemperatureSpec>>,
}

/// `[temperature]`, as written: a temperature history, piecewise linear in
/// time, and the shift-factor law that turns it into a_T (seed 000 eqs
/// 1.46-1.48; [`bushing::temperature`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TemperatureSpec {
    /// "wlf" (needs `c1` and `c2`) or "arrhenius" (needs `activation`).
    pub law: String,
    /// WLF C_1 (dimensionless).
    #[serde(default)]
    pub c1: Option<f64>,
    /// WLF C_2 in kelvin.
    #[serde(default)]
    pub c2: Option<f64>,
    /// Reference temperature T_0 (WLF: the unit of the points; Arrhenius:
    /// kelvin): the temperature at which the cells are as written.
    pub t_ref: f64,
    /// Arrhenius E_a / R in kelvin.
    #[serde(default)]
    pub activation: Option<f64>,
    /// (time in s, temperature) pairs, times increasing.
    pub points: Vec<[f64; 2]>,
    /// Re-tune every this many steps (default 1).
    #[serde(default = "default_every")]
    pub every: i64,
}

fn default_every() -> i64 {
    1
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
        /// A fractional-derivative cell, the truncated Grünwald sum of
        /// eqs 1.23-1.25.
        Fractional {
            /// Transition frequency f_c in Hz (ω_c = 2π f_c).
            f_c_hz: f64,
            /// Order α of the derivative, 0 < α <= 1.
            alpha: f64,
            /// Load fraction g.
            g: f64,
            /// Memory length N in steps: one of [`super::FRACTIONAL_TAPS`].
            taps: i64,
        },
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
            Self::Fractional { .. } => "fractional",
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
