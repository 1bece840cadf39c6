//! Re-tuning a scene's Maxwell banks to a temperature (the core's shift of
//! the corners, eq 1.48 of seed 000); every other effect is left as it is.

use bushing::{Berg, BoucWen, Bushing, Dahl, Effect, ParamError, Real};

pub use crate::backbone::AnyBackbone;

use super::*;

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

impl<T: Real> Tuned for DynMaxwell<T> {
    /// Every cell rebuilt by the core's constructor at ω_i / a_t, as
    /// [`bushing::MaxwellBank::shifted`] does; the state carries over (it
    /// holds branch forces or relaxations, not coefficients).
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Self::tuned(self.form, &self.specs, self.dt, self.storage, a_t)
    }
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
    DynIwanClamp<T>,
    DynIwanSliders<T>,
    DynXf<T>,
    StsStack<T>,
    TableStack<T>,
    Dahl<T>,
    BoucWen<T>,
    Berg<T>,
    DynGrunwald<T>,
);

impl Tuned for () {
    fn shifted(&self, _: f64) -> Result<Self, ParamError> {
        Ok(())
    }
}

impl<E: Tuned> Tuned for (E,) {
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Ok((self.0.shifted(a_t)?,))
    }
}

impl<T: Real> Tuned for AnyEffect<T> {
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Ok(match self {
            Self::Maxwell(e) => Self::Maxwell(e.shifted(a_t)?),
            other => other.clone(),
        })
    }
}

impl<T: Real> Tuned for EffectList<T> {
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Ok(Self {
            effects: self
                .effects
                .iter()
                .map(|e| e.shifted(a_t))
                .collect::<Result<_, _>>()?,
        })
    }
}

/// `bushing` with its effects at the shift factor `a_t` (same backbone).
pub(super) fn shifted_bushing<T: Real, E: Effect<T> + Tuned>(
    bushing: &Bushing<T, AnyBackbone<T>, E>,
    a_t: f64,
) -> Result<Bushing<T, AnyBackbone<T>, E>, ParamError> {
    Bushing::new(bushing.backbone().clone(), bushing.effects().shifted(a_t)?)
}
