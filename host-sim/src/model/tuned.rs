//! The other half of re-tuning (see [`crate::family::Tuned`]): the bushing
//! shapes a compiled scene takes, and a whole bushing swapped for its shift.

use bushing::{Bushing, Effect, ParamError, Real};

use super::{AnyBackbone, EffectList};
use crate::family::Tuned;

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

/// `bushing` with its effects at the shift factor `a_t`, absolute (same
/// backbone; see [`Tuned::shifted`]).
pub fn shifted_bushing<T: Real, E: Effect<T> + Tuned>(
    bushing: &Bushing<T, AnyBackbone<T>, E>,
    a_t: f64,
) -> Result<Bushing<T, AnyBackbone<T>, E>, ParamError> {
    Bushing::new(bushing.backbone().clone(), bushing.effects().shifted(a_t)?)
}
