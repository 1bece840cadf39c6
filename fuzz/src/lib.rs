//! The model families of the core, each built from arbitrary parameters
//! (mostly plausible, sometimes any bit pattern) and stepped over arbitrary
//! inputs under the contract of [`contract`].
//!
//! One module per family, each with one `fuzz` function generic over the
//! working type. The targets in `fuzz_targets/` run one family each, so
//! that a family can be fuzzed on its own for as long as it needs;
//! `step_models` runs any of them. The floating-point families step in
//! `f32` (and in `f64` for one input in eight); `fixed_point` steps the
//! same families in `Q16` and `Q32`.

pub mod contract;
pub mod draw;
pub mod num;

mod backbone;
mod fractional;
mod friction;
mod iwan;
mod maxwell;
mod oscillator;
mod six_dof;
mod stack;
mod tracker;
mod viscous;
mod xf;

use arbitrary::{Result, Unstructured};
use bushing::{Q16, Q32};
use num::Num;

/// A family of models: the constructors and steps one target drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// `Polynomial` (`new`, `linear`) and `MonotoneSpline` backbones alone.
    Backbone,
    /// `MaxwellCell`, `MaxwellBank` in every form with each accumulator,
    /// `shifted` and `retune` (libm and micromath) with a `ShiftFactor`
    /// (WLF, Arrhenius) in f64 and in the working type.
    Maxwell,
    /// `FractionalSpec` and `Grunwald` with 0 to 64 taps.
    Fractional,
    /// `IwanCellSpec`, `ClampCell`, `SliderCell`, `IwanBank`,
    /// `IwanSliders`, and the banks of `discretize` (STS or K_f table to
    /// Iwan, Segalman's four-parameter Iwan, uniform or logarithmic).
    Iwan,
    /// `XfCell` and `XfBank` in both forms.
    Xf,
    /// `Sts` and `KfTable` on `TurningPoints` of several capacities, with
    /// both `FirstLoading` variants.
    Stack,
    /// `Dahl`, `BoucWen` and `Berg`.
    Friction,
    /// `Dashpot`, alone and beside a Maxwell or an Iwan bank.
    Viscous,
    /// `Oscillator` on Iwan, Maxwell and friction restoring forces, driven
    /// by arbitrary forces or a `Sweep`.
    Oscillator,
    /// `SixDof` of non-linear laws in both connectivities, its step and
    /// its 12x12 `tangent`.
    SixDof,
    /// `ModalTracker` (EKF and UKF, each sensor kind, one or two modes and
    /// sensors), `SineTracker`, `ModulusTracker`, `fit_first_period`,
    /// `fit_amplitudes`, the relevance check and the unscented transform.
    Tracker,
    /// Every family above in `Q16` and `Q32`.
    FixedPoint,
}

impl Family {
    /// Every family; `FixedPoint`, which runs the others, comes last.
    pub const ALL: [Self; 12] = [
        Self::Backbone,
        Self::Maxwell,
        Self::Fractional,
        Self::Iwan,
        Self::Xf,
        Self::Stack,
        Self::Friction,
        Self::Viscous,
        Self::Oscillator,
        Self::SixDof,
        Self::Tracker,
        Self::FixedPoint,
    ];

    fn fuzz(self, u: &mut Unstructured<'_>) -> Result<()> {
        match self {
            Self::FixedPoint => {
                let (_, typed) = Self::ALL.split_last().expect("families");
                let family = *u.choose(typed)?;
                if u.arbitrary()? {
                    family.fuzz_in::<Q16>(u)
                } else {
                    family.fuzz_in::<Q32>(u)
                }
            }
            _ if u.ratio(1u8, 8)? => self.fuzz_in::<f64>(u),
            _ => self.fuzz_in::<f32>(u),
        }
    }

    fn fuzz_in<T: Num>(self, u: &mut Unstructured<'_>) -> Result<()> {
        match self {
            Self::Backbone => backbone::fuzz::<T>(u),
            Self::Maxwell => maxwell::fuzz::<T>(u),
            Self::Fractional => fractional::fuzz::<T>(u),
            Self::Iwan => iwan::fuzz::<T>(u),
            Self::Xf => xf::fuzz::<T>(u),
            Self::Stack => stack::fuzz::<T>(u),
            Self::Friction => friction::fuzz::<T>(u),
            Self::Viscous => viscous::fuzz::<T>(u),
            Self::Oscillator => oscillator::fuzz::<T>(u),
            Self::SixDof => six_dof::fuzz::<T>(u),
            Self::Tracker => tracker::fuzz::<T>(u),
            Self::FixedPoint => Ok(()),
        }
    }
}

/// One input of `family`'s target. Running out of input bytes ends the
/// input early; every other outcome is checked inside.
pub fn run(family: Family, data: &[u8]) {
    let _ = family.fuzz(&mut Unstructured::new(data));
}

/// One input of any family, picked by the first byte.
pub fn run_any(data: &[u8]) {
    let mut u = Unstructured::new(data);
    if let Ok(&family) = u.choose(&Family::ALL) {
        let _ = family.fuzz(&mut u);
    }
}
