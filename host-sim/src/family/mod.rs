//! The model families a scene can name, one module each, with everything
//! the host knows about it in one place: its `[[effects]]` table (read by
//! serde, straight into the core's parameter types where the table writes
//! them as they are), its checks and its build (the only place a family's
//! model is constructed), its closed-form references for `validate`, and
//! for the Maxwell bank the const-size comparison of `cost`.
//!
//! | module | `type` | built as |
//! |---|---|---|
//! | [`maxwell`] | `maxwell` | [`maxwell::DynMaxwell`] |
//! | [`iwan`] | `iwan` | [`iwan::DynIwanClamp`], [`iwan::DynIwanSliders`] |
//! | [`turning_points`] | `turning-points` | [`turning_points::StsStack`], [`turning_points::TableStack`] |
//! | [`xf`] | `xf` | [`xf::DynXf`] |
//! | [`friction`] | `dahl`, `bouc-wen`, `berg` | the core's cells |
//! | [`dashpot`] | `dashpot` | the core's `Dashpot` |
//! | [`fractional`] | `fractional` | [`fractional::DynGrunwald`] |
//! | [`backbone`] | `[backbone]` | [`backbone::AnyBackbone`] |
//!
//! A scene checks each table into an [`Effect`] and builds it once, in its
//! working type ([`Built`]); a run clones the built models.

pub mod backbone;
mod bank;
pub mod dashpot;
pub mod fractional;
pub mod friction;
pub mod iwan;
pub mod maxwell;
pub mod turning_points;
pub mod xf;

use std::any::Any;

use bushing::{Berg, BoucWen, Dahl, Dashpot, Drive, Effect as _, EffectOutput, ParamError, Real};
use serde::Deserialize;

use crate::reference::{Line, Measured, no};

pub use bank::{DynBank, Kernel};

/// Largest bank a scene may ask for.
pub const MAX_CELLS: usize = 64;

/// Checks the number of cells of a bank: 1 to [`MAX_CELLS`].
fn check_count(n: usize) -> Result<(), String> {
    if n == 0 || n > MAX_CELLS {
        Err(format!("1 to {MAX_CELLS} cells expected, got {n}"))
    } else {
        Ok(())
    }
}

/// What an effect's table is checked against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setting {
    /// Time step, s.
    pub dt: f64,
    /// Tangent of the backbone at 0, N/mm (the default reference stiffness
    /// of Iwan cells given by slip distance).
    pub k_at_rest: f64,
}

tagged_table! {
    /// One `[[effects]]` table, as written.
    #[derive(Debug, Clone, Deserialize)]
    pub enum EffectSpec, read by tag as EffectByTag("EffectSpec") {
        /// A bank of Maxwell cells.
        Maxwell(maxwell::Maxwell),
        /// A bank of Jenkins cells (Iwan).
        Iwan(iwan::IwanTable),
        /// Hysteretic relaxation with a turning-point stack.
        TurningPoints(turning_points::StackTable),
        /// A bank of nonlinear viscous x_f cells.
        Xf(xf::Xf),
        /// Dahl's friction cell (eq 1.43).
        Dahl(friction::DahlParams),
        /// The Bouc-Wen cell (eq 1.44, the thesis's naming).
        BoucWen(friction::BoucWenParams),
        /// Berg's friction cell (eq 1.45).
        Berg(friction::BergParams),
        /// A fractional-derivative cell, the truncated Grünwald sum.
        Fractional(fractional::FractionalTable),
        /// A viscous dashpot.
        Dashpot(dashpot::DashpotTable),
    }
}

impl EffectSpec {
    /// Name of the effect kind, as in scene files.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Maxwell(_) => "maxwell",
            Self::Iwan(_) => "iwan",
            Self::TurningPoints(_) => "turning-points",
            Self::Xf(_) => "xf",
            Self::Dahl(_) => "dahl",
            Self::BoucWen(_) => "bouc-wen",
            Self::Berg(_) => "berg",
            Self::Fractional(_) => "fractional",
            Self::Dashpot(_) => "dashpot",
        }
    }

    /// The table checked and its model built in the working type `T`
    /// (every parameter check of the core, including the values that leave
    /// `T`).
    pub fn check<T: Real>(self, setting: &Setting) -> Result<(Effect, AnyEffect<T>), String> {
        let effect = match self {
            Self::Maxwell(m) => Effect::Maxwell(m.check()?),
            Self::Iwan(t) => Effect::Iwan(t.check(setting)?),
            Self::TurningPoints(t) => Effect::TurningPoints(t.check()?),
            Self::Xf(x) => Effect::Xf(x.check()?),
            Self::Dahl(p) => Effect::Friction(friction::Friction::Dahl(p)),
            Self::BoucWen(p) => Effect::Friction(friction::Friction::BoucWen(p)),
            Self::Berg(p) => Effect::Friction(friction::Friction::Berg(p)),
            Self::Fractional(t) => Effect::Fractional(t.check()?),
            Self::Dashpot(d) => Effect::Dashpot(d),
        };
        let built = effect.build(setting.dt).map_err(|e| e.to_string())?;
        Ok((effect, built))
    }
}

/// A checked effect: its parameters in the core's types.
#[derive(Debug, Clone, PartialEq)]
pub enum Effect {
    /// A Maxwell bank.
    Maxwell(maxwell::Maxwell),
    /// An Iwan bank.
    Iwan(iwan::Iwan),
    /// A turning-point stack model.
    TurningPoints(turning_points::Stack),
    /// An x_f bank.
    Xf(xf::Xf),
    /// A single friction cell.
    Friction(friction::Friction),
    /// A Grünwald fractional cell.
    Fractional(fractional::Fractional),
    /// A viscous dashpot.
    Dashpot(dashpot::DashpotTable),
}

impl Effect {
    /// Builds the model in `T` for time step `dt`: the one constructor of
    /// each family.
    pub fn build<T: Real>(&self, dt: f64) -> Result<AnyEffect<T>, ParamError> {
        match self {
            Self::Maxwell(m) => m.build(dt).map(AnyEffect::Maxwell),
            Self::Iwan(i) => i.build(),
            Self::TurningPoints(s) => s.build(),
            Self::Xf(x) => x.build(dt).map(AnyEffect::Xf),
            Self::Friction(f) => f.build(),
            Self::Fractional(f) => f.build(dt).map(AnyEffect::Fractional),
            Self::Dashpot(d) => d.build(dt).map(AnyEffect::Dashpot),
        }
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        match self {
            Self::Maxwell(m) => m.name(),
            Self::Iwan(i) => i.name(),
            Self::TurningPoints(s) => s.name(),
            Self::Xf(x) => x.name(),
            Self::Friction(f) => f.name(),
            Self::Fractional(f) => f.name(),
            Self::Dashpot(d) => d.name(),
        }
    }

    /// Sum of the load fractions of the effect's cells.
    pub fn fraction(&self) -> f64 {
        match self {
            Self::Maxwell(m) => m.cells.iter().map(|c| c.g).sum(),
            Self::Iwan(i) => i.cells.iter().map(|c| c.g).sum(),
            Self::Xf(x) => x.cells.iter().map(|c| c.g).sum(),
            Self::Fractional(f) => f.spec.g,
            Self::TurningPoints(_) | Self::Friction(_) | Self::Dashpot(_) => 0.0,
        }
    }

    /// The closed-form references of the effect `built` from `self`,
    /// against its steady cycle `m`.
    pub fn references<T: Real>(&self, built: &AnyEffect<T>, m: &Measured) -> Vec<Line> {
        match (self, built) {
            (Self::Maxwell(e), AnyEffect::Maxwell(bank)) => e.references(bank, m),
            (Self::Iwan(e), _) => e.references(m),
            (Self::TurningPoints(e), _) => e.references(m),
            (Self::Xf(e), _) => e.references(m),
            (Self::Friction(e), _) => e.references(m),
            (Self::Fractional(_), AnyEffect::Fractional(cell)) => fractional::references(cell, m),
            (Self::Dashpot(d), _) => d.references(m),
            _ => no("the model built is not of this effect's family"),
        }
    }
}

/// The backbone and effects of a scene built in `T`.
#[derive(Debug, Clone)]
pub struct Built<T> {
    /// The backbone.
    pub backbone: backbone::AnyBackbone<T>,
    /// The effects, in the scene's order.
    pub effects: Vec<AnyEffect<T>>,
}

/// A scene's models, built once in its working type.
#[derive(Debug, Clone)]
pub enum Models {
    /// Built in f32.
    F32(Built<f32>),
    /// Built in f64.
    F64(Built<f64>),
}

impl Models {
    /// The models if they are built in `T`.
    pub fn get<T: 'static>(&self) -> Option<&Built<T>> {
        match self {
            Self::F32(b) => (b as &dyn Any).downcast_ref(),
            Self::F64(b) => (b as &dyn Any).downcast_ref(),
        }
    }

    /// The same models with only the effects at `keep` (in that order).
    pub fn only(&self, keep: &[usize]) -> Self {
        fn pick<T: Clone>(b: &Built<T>, keep: &[usize]) -> Built<T> {
            Built {
                backbone: b.backbone.clone(),
                effects: keep
                    .iter()
                    .filter_map(|&i| b.effects.get(i).cloned())
                    .collect(),
            }
        }
        match self {
            Self::F32(b) => Self::F32(pick(b, keep)),
            Self::F64(b) => Self::F64(pick(b, keep)),
        }
    }
}

/// One effect a scene can name, built.
#[derive(Debug, Clone)]
pub enum AnyEffect<T> {
    /// Maxwell bank.
    Maxwell(maxwell::DynMaxwell<T>),
    /// Iwan bank, clamp form.
    Clamp(iwan::DynIwanClamp<T>),
    /// Iwan bank, slider form.
    Sliders(iwan::DynIwanSliders<T>),
    /// x_f bank.
    Xf(xf::DynXf<T>),
    /// Turning-point stack, STS law.
    Sts(turning_points::StsStack<T>),
    /// Turning-point stack, measured table.
    Table(turning_points::TableStack<T>),
    /// Dahl cell.
    Dahl(Dahl<T>),
    /// Bouc-Wen cell.
    BoucWen(BoucWen<T>),
    /// Berg cell.
    Berg(Berg<T>),
    /// Grünwald fractional cell.
    Fractional(fractional::DynGrunwald<T>),
    /// Viscous dashpot.
    Dashpot(Dashpot<T>),
}

/// Calls `$f` with the effect inside an [`AnyEffect`] (one arm per kind).
macro_rules! each_effect {
    ($e:expr, |$x:ident| $f:expr) => {
        match $e {
            $crate::family::AnyEffect::Maxwell($x) => $f,
            $crate::family::AnyEffect::Clamp($x) => $f,
            $crate::family::AnyEffect::Sliders($x) => $f,
            $crate::family::AnyEffect::Xf($x) => $f,
            $crate::family::AnyEffect::Sts($x) => $f,
            $crate::family::AnyEffect::Table($x) => $f,
            $crate::family::AnyEffect::Dahl($x) => $f,
            $crate::family::AnyEffect::BoucWen($x) => $f,
            $crate::family::AnyEffect::Berg($x) => $f,
            $crate::family::AnyEffect::Fractional($x) => $f,
            $crate::family::AnyEffect::Dashpot($x) => $f,
        }
    };
}
pub(crate) use each_effect;

/// State of one [`AnyEffect`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "T: serde::Serialize",
    deserialize = "T: serde::Deserialize<'de>"
))]
pub enum AnyState<T: Real> {
    /// Maxwell bank.
    Maxwell(<maxwell::DynMaxwell<T> as bushing::Effect<T>>::State),
    /// Iwan bank, clamp form.
    Clamp(<iwan::DynIwanClamp<T> as bushing::Effect<T>>::State),
    /// Iwan bank, slider form.
    Sliders(<iwan::DynIwanSliders<T> as bushing::Effect<T>>::State),
    /// x_f bank.
    Xf(<xf::DynXf<T> as bushing::Effect<T>>::State),
    /// Turning-point stack, STS law.
    Sts(<turning_points::StsStack<T> as bushing::Effect<T>>::State),
    /// Turning-point stack, measured table.
    Table(<turning_points::TableStack<T> as bushing::Effect<T>>::State),
    /// Dahl cell.
    Dahl(<Dahl<T> as bushing::Effect<T>>::State),
    /// Bouc-Wen cell.
    BoucWen(<BoucWen<T> as bushing::Effect<T>>::State),
    /// Berg cell.
    Berg(<Berg<T> as bushing::Effect<T>>::State),
    /// Grünwald fractional cell.
    Fractional(<fractional::DynGrunwald<T> as bushing::Effect<T>>::State),
    /// Viscous dashpot (no state).
    Dashpot(<Dashpot<T> as bushing::Effect<T>>::State),
}

impl<T: Real> AnyEffect<T> {
    /// Load fraction of the effect.
    pub fn fraction(&self) -> f64 {
        each_effect!(self, |e| e.fraction())
    }

    /// The effect's time-step check ([`bushing::Effect::check_dt`]).
    pub fn check_dt(&self, dt: Option<f64>) -> Result<Option<f64>, ParamError> {
        each_effect!(self, |e| e.check_dt(dt))
    }

    /// State at rest at `x0`.
    pub fn rest(&self, x0: T) -> AnyState<T> {
        match self {
            Self::Maxwell(e) => AnyState::Maxwell(e.rest(x0)),
            Self::Clamp(e) => AnyState::Clamp(e.rest(x0)),
            Self::Sliders(e) => AnyState::Sliders(e.rest(x0)),
            Self::Xf(e) => AnyState::Xf(e.rest(x0)),
            Self::Sts(e) => AnyState::Sts(e.rest(x0)),
            Self::Table(e) => AnyState::Table(e.rest(x0)),
            Self::Dahl(e) => AnyState::Dahl(e.rest(x0)),
            Self::BoucWen(e) => AnyState::BoucWen(e.rest(x0)),
            Self::Berg(e) => AnyState::Berg(e.rest(x0)),
            Self::Fractional(e) => AnyState::Fractional(e.rest(x0)),
            Self::Dashpot(_) => AnyState::Dashpot(()),
        }
    }

    /// One step of the effect in `state` (which came from its `rest`).
    #[inline(always)]
    pub fn step(&self, state: &mut AnyState<T>, drive: &Drive<T>) -> EffectOutput<T> {
        fn go<T: Real, E: bushing::Effect<T>>(
            e: &E,
            s: &mut E::State,
            d: &Drive<T>,
        ) -> EffectOutput<T> {
            E::total(&e.step(s, d))
        }
        match (self, state) {
            (Self::Maxwell(e), AnyState::Maxwell(s)) => go(e, s, drive),
            (Self::Clamp(e), AnyState::Clamp(s)) => go(e, s, drive),
            (Self::Sliders(e), AnyState::Sliders(s)) => go(e, s, drive),
            (Self::Xf(e), AnyState::Xf(s)) => go(e, s, drive),
            (Self::Sts(e), AnyState::Sts(s)) => go(e, s, drive),
            (Self::Table(e), AnyState::Table(s)) => go(e, s, drive),
            (Self::Dahl(e), AnyState::Dahl(s)) => go(e, s, drive),
            (Self::BoucWen(e), AnyState::BoucWen(s)) => go(e, s, drive),
            (Self::Berg(e), AnyState::Berg(s)) => go(e, s, drive),
            (Self::Fractional(e), AnyState::Fractional(s)) => go(e, s, drive),
            (Self::Dashpot(e), AnyState::Dashpot(s)) => go(e, s, drive),
            // A state always comes from its own effect's `rest`.
            _ => EffectOutput::zero(),
        }
    }
}

impl<T: Real> AnyState<T> {
    /// Makes `self` equal to `src`, reusing `self`'s storage when both are
    /// of the same kind (no allocation in a running list).
    pub fn copy_from(&mut self, src: &Self) {
        match (self, src) {
            (Self::Maxwell(d), Self::Maxwell(s)) => d.copy_from(s),
            (Self::Clamp(d), Self::Clamp(s)) => {
                d.0.clone_from(&s.0);
                d.1 = s.1;
            }
            (Self::Sliders(d), Self::Sliders(s)) | (Self::Xf(d), Self::Xf(s)) => d.clone_from(s),
            (Self::Fractional(d), Self::Fractional(s)) => d.clone_from(s),
            (d, s) => d.clone_from(s),
        }
    }
}

/// Effects as a temperature history re-tunes them: only the Maxwell banks
/// move, their corners ω_i / a_T (seed 000 eqs 1.46-1.48; see
/// [`bushing::temperature`] for the direction of a_T); every other effect
/// is kept as it is.
pub trait Tuned: Sized {
    /// The same effect with its Maxwell corners at the shift factor `a_t`,
    /// absolute (from the corners as given, whatever the effect is tuned to
    /// now, so repeated re-tunes do not drift).
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError>;
}

/// Effects a temperature leaves as they are.
macro_rules! untuned {
    ($($ty:ty),+ $(,)?) => {
        $(
            impl<T: Real> Tuned for $ty {
                fn shifted(&self, _: f64) -> Result<Self, ParamError> {
                    Ok(self.clone())
                }
            }
        )+
    };
}

untuned!(
    iwan::DynIwanClamp<T>,
    iwan::DynIwanSliders<T>,
    xf::DynXf<T>,
    turning_points::StsStack<T>,
    turning_points::TableStack<T>,
    Dahl<T>,
    BoucWen<T>,
    Berg<T>,
    fractional::DynGrunwald<T>,
    Dashpot<T>,
);

impl<T: Real> Tuned for AnyEffect<T> {
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Ok(match self {
            Self::Maxwell(e) => Self::Maxwell(e.shifted(a_t)?),
            other => other.clone(),
        })
    }
}
