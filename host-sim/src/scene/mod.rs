//! Scene files: what to simulate, at which rate and in which number type,
//! under which displacement profile. See `docs/scenes.md`.
//!
//! Parsing is two-staged: TOML into plain structs (syntax and shape errors
//! carry the line and column), then validation into model parameters
//! (parameter errors name the effect, the parameter and the bound, at the
//! line of the effect's table).

mod errors;
mod spec;
mod temperature;
#[cfg(test)]
mod tests;

use std::borrow::Cow;
use std::ops::Range;
use std::path::Path;

use bushing::{Backbone, ParamError, Real, ShiftFactor};

pub use crate::family::backbone::BackboneSpec;
pub use crate::family::{Built, Effect, EffectSpec, MAX_CELLS, Models, Setting};
pub use crate::profile::ProfileSpec;
pub use errors::{Location, SceneError};
pub use spec::*;

use crate::records::{ReadError, read_limited};
use errors::shape_error;
use temperature::validate_temperature;

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

/// A scene read and checked: every value is in range, and every model is
/// built, once, in the working type (a run clones the built models).
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
    /// Effects, checked (read them with [`Scene::effects`]; the built
    /// models follow them).
    effects: Vec<Effect>,
    /// The backbone and effects built in `number`.
    models: Models,
    /// Profile.
    pub profile: ProfileSpec,
    /// Steps between two rows of `trace.csv` (1: every step).
    pub trace_every: u64,
    /// A unit mass on the bushing, driven by the profile as a force.
    pub oscillator: Option<OscillatorSpec>,
    /// The ADC the model reads the imposed displacement through (never in
    /// an oscillator scene).
    pub adc: Option<Adc>,
    /// The temperature history the Maxwell banks follow, if any.
    pub temperature: Option<Temperature>,
}

/// A validated `[temperature]`: the Maxwell corners follow a temperature
/// history, `ω_i(t) = ω_i / a_T(T(t))` (seed 000 eqs 1.46-1.48, with the
/// usual a_T > 1 on the cold, slow side; see [`bushing::temperature`]).
/// At every point of the history the law is defined, a_T is finite and
/// positive, and every shifted Maxwell cell is valid in the working type.
#[derive(Debug, Clone, PartialEq)]
pub struct Temperature {
    /// The shift-factor law.
    pub law: ShiftFactor,
    /// (time in s, temperature), times increasing: piecewise linear
    /// between them, constant before the first and after the last.
    pub points: Vec<(f64, f64)>,
    /// Steps between two re-tunes (1: before every step).
    pub every: u64,
}

impl Temperature {
    /// The temperature at time `t` (s): linear between the points,
    /// constant outside them, and never outside the two points around `t`
    /// (so never outside the range checked when the scene was read).
    pub fn at(&self, t: f64) -> f64 {
        let i = self.points.partition_point(|&(ti, _)| ti <= t);
        match (
            i.checked_sub(1).and_then(|j| self.points.get(j)),
            self.points.get(i),
        ) {
            (Some(&(t0, v0)), Some(&(t1, v1))) => {
                let v = v0 + (v1 - v0) * ((t - t0) / (t1 - t0));
                v.clamp(v0.min(v1), v0.max(v1))
            }
            (Some(&(_, v)), None) | (None, Some(&(_, v))) => v,
            (None, None) => f64::NAN,
        }
    }

    /// The shift factor a_T at time `t` (s), in f64
    /// ([`ShiftFactor::at`] of [`Temperature::at`]).
    pub fn shift_at(&self, t: f64) -> Result<f64, ParamError> {
        self.law.at(self.at(t))
    }
}

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
        let file = path.display().to_string();
        let fail = |message: String| SceneError {
            file: file.clone(),
            at: None,
            message,
            source: None,
        };
        let text = read_limited(path, MAX_SCENE_BYTES).map_err(|e| {
            fail(match e {
                ReadError::NotRegular => "not a regular file; a scene is a TOML file".into(),
                ReadError::TooLarge { size, limit } => {
                    format!("{size} bytes, more than the limit of {limit} for a scene")
                }
                other => other.to_string(),
            })
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
        let in_f64 = crate::family::backbone::backbone::<f64>(&backbone)
            .map_err(|e| err(Some(bb_span.clone()), format!("backbone: {e}")))?;
        let setting = Setting {
            dt,
            // The reference stiffness of Iwan cells given by slip distance.
            k_at_rest: in_f64.eval(0.0).1,
        };
        let (raw_effects, raw_temperature) = (raw.effects, raw.temperature);
        let (effects, models, temperature) = match run.number {
            NumberType::F32 => {
                // The backbone's checks in the working type, where a value
                // valid in f64 may overflow or vanish.
                let backbone = crate::family::backbone::backbone::<f32>(&backbone)
                    .map_err(|e| err(Some(bb_span.clone()), format!("backbone (f32): {e}")))?;
                let (e, b, t) = checked(backbone, raw_effects, raw_temperature, &setting, &err)?;
                (e, Models::F32(b), t)
            }
            NumberType::F64 => {
                let (e, b, t) = checked(in_f64, raw_effects, raw_temperature, &setting, &err)?;
                (e, Models::F64(b), t)
            }
        };

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
            models,
            profile,
            trace_every,
            oscillator,
            adc,
            temperature,
        })
    }

    /// The effects, checked, in the scene's order.
    pub fn effects(&self) -> &[Effect] {
        &self.effects
    }

    /// The backbone and effects as built in `T`: the scene's own models
    /// when `T` is its working type, else built now from the same checked
    /// parameters.
    pub fn built<T: Real + 'static>(&self) -> Result<Cow<'_, Built<T>>, ParamError> {
        if let Some(built) = self.models.get::<T>() {
            return Ok(Cow::Borrowed(built));
        }
        Ok(Cow::Owned(Built {
            backbone: crate::family::backbone::backbone::<T>(&self.backbone)?,
            effects: self
                .effects
                .iter()
                .map(|e| e.build::<T>(self.dt))
                .collect::<Result<_, _>>()?,
        }))
    }

    /// The same scene with only the effects at `keep` (indices into
    /// [`Scene::effects`], in that order), their models as built.
    pub fn only(&self, keep: &[usize]) -> Self {
        Self {
            effects: keep
                .iter()
                .filter_map(|&i| self.effects.get(i).cloned())
                .collect(),
            models: self.models.only(keep),
            ..self.clone()
        }
    }

    /// The same scene with `effects` instead of its own, built in its
    /// working type (the scene's checks of a table are not run again: the
    /// core's constructors are).
    pub fn with_effects(&self, effects: Vec<Effect>) -> Result<Self, ParamError> {
        fn build<T: Real>(
            effects: &[Effect],
            backbone: &crate::family::backbone::AnyBackbone<T>,
            dt: f64,
        ) -> Result<Built<T>, ParamError> {
            Ok(Built {
                backbone: backbone.clone(),
                effects: effects
                    .iter()
                    .map(|e| e.build::<T>(dt))
                    .collect::<Result<_, _>>()?,
            })
        }
        let models = match &self.models {
            Models::F32(b) => Models::F32(build(&effects, &b.backbone, self.dt)?),
            Models::F64(b) => Models::F64(build(&effects, &b.backbone, self.dt)?),
        };
        Ok(Self {
            effects,
            models,
            ..self.clone()
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

/// The effects (and the temperature history that re-tunes them) checked
/// and built in `T` on `backbone`; `err` places a message at a span.
#[allow(clippy::type_complexity)]
fn checked<T: Real>(
    backbone: crate::family::backbone::AnyBackbone<T>,
    raw: Vec<toml::Spanned<EffectSpec>>,
    temperature: Option<toml::Spanned<TemperatureSpec>>,
    setting: &Setting,
    err: &dyn Fn(Option<Range<usize>>, String) -> SceneError,
) -> Result<(Vec<Effect>, Built<T>, Option<Temperature>), SceneError> {
    let mut effects = Vec::with_capacity(raw.len());
    let mut built = Vec::with_capacity(raw.len());
    let mut seen = Vec::new();
    for (i, spanned) in raw.into_iter().enumerate() {
        let span = spanned.span();
        let spec = spanned.into_inner();
        let kind = spec.kind();
        if seen.contains(&kind) {
            return Err(err(
                Some(span),
                format!("effects[{i}]: a second '{kind}' effect; put all its cells in one table"),
            ));
        }
        seen.push(kind);
        let (effect, model) = spec
            .check::<T>(setting)
            .map_err(|m| err(Some(span.clone()), format!("effects[{i}] ({kind}): {m}")))?;
        effects.push(effect);
        built.push(model);
    }
    let sum: f64 = effects.iter().map(Effect::fraction).sum();
    if sum > 1.0 + 1e-12 {
        return Err(err(None, ParamError::FractionsAboveOne { sum }.to_string()));
    }
    let temperature = match temperature {
        None => None,
        Some(t) => {
            let span = t.span();
            let checked = validate_temperature::<T>(t.into_inner(), &built);
            Some(checked.map_err(|m| err(Some(span), format!("temperature{m}")))?)
        }
    };
    let built = Built {
        backbone,
        effects: built,
    };
    Ok((effects, built, temperature))
}
