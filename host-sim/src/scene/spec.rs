//! The scene file as written: the TOML tables, read by serde.

use serde::Deserialize;
use toml::Spanned;

use crate::family::EffectSpec;
use crate::family::backbone::BackboneSpec;
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
