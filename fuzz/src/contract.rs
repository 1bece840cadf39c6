//! The contract every stepped model is held to.
//!
//! - Construction ends in a model or a typed [`ParamError`] (never a
//!   panic); the error's text is formed too.
//! - A step never panics.
//! - A refused step (`effects == None`) leaves the force bit-identical to
//!   the previous one, in the output and in the state.
//! - An accepted step gives a finite force, tangent and dissipated energy,
//!   the force and tangent within [`Real::GUARD`] in magnitude, and so
//!   does each effect's own report.
//!
//! [`ParamError`]: bushing::ParamError

use arbitrary::{Result, Unstructured};
use bushing::{Backbone, Bushing, BushingState, Effect, EffectOutput, Output, Real};

use crate::draw::Path;
use crate::num::Num;

// Drawing parameters builds backbones with `built`, so it lives in `draw`;
// it is the construction half of this contract.
pub use crate::draw::built;

/// Finite and within [`Real::GUARD`] in magnitude (a NaN fails).
pub fn guarded<T: Real>(v: T) -> bool {
    v.is_finite() && v.abs() <= T::GUARD
}

/// The effects of a bushing, whose reports can be read one effect at a
/// time.
pub trait Members<T: Real>: Effect<T> {
    /// Calls `f` with the total report of each member effect.
    fn each(report: &Self::Report, f: &mut dyn FnMut(EffectOutput<T>));
}

impl<T: Real> Members<T> for () {
    fn each(_: &(), _: &mut dyn FnMut(EffectOutput<T>)) {}
}

macro_rules! members {
    ($($name:ident $idx:tt),+) => {
        impl<T: Real, $($name: Effect<T>),+> Members<T> for ($($name,)+) {
            fn each(report: &Self::Report, f: &mut dyn FnMut(EffectOutput<T>)) {
                $( f($name::total(&report.$idx)); )+
            }
        }
    };
}

members!(A 0);
members!(A 0, B 1);
members!(A 0, B 1, C 2);

/// Checks one bushing output against the contract: `before` is the
/// state's force before the step, `after` after it.
pub fn check<T: Real, E: Members<T>>(out: &Output<T, E::Report>, before: T, after: T) {
    match &out.effects {
        None => {
            assert_eq!(
                out.force.bits(),
                before.bits(),
                "a refused step changed the force: {out:?}"
            );
            assert_eq!(
                after.bits(),
                before.bits(),
                "a refused step changed the state"
            );
        }
        Some(report) => {
            assert!(
                guarded(out.force) && guarded(out.tangent) && out.dissipated.is_finite(),
                "an accepted step out of the contract: {out:?}"
            );
            E::each(report, &mut |e| {
                assert!(
                    guarded(e.force) && guarded(e.tangent),
                    "an accepted step with an effect out of the guard: {e:?}"
                );
            });
            assert_eq!(
                after.bits(),
                out.force.bits(),
                "the state does not hold the force returned"
            );
        }
    }
}

/// Builds the bushing of `backbone` and `effects` and steps it over
/// arbitrary inputs from an arbitrary start.
pub fn drive<T: Num, B: Backbone<T>, E: Members<T>>(
    u: &mut Unstructured<'_>,
    backbone: B,
    effects: E,
) -> Result<()> {
    let Some(b) = built(Bushing::new(backbone, effects)) else {
        return Ok(());
    };
    let mut path = Path::new(10.0);
    let mut s = b.state_at(path.next(u)?);
    steps(u, &b, &mut s, &mut path)
}

/// Up to 256 steps of a running bushing, by `step` or now and then by
/// `trial` and a commit, each checked.
pub fn steps<T: Num, B: Backbone<T>, E: Members<T>>(
    u: &mut Unstructured<'_>,
    b: &Bushing<T, B, E>,
    s: &mut BushingState<T, E::State>,
    path: &mut Path<T>,
) -> Result<()> {
    for _ in 0..u.int_in_range(1usize..=256)? {
        let x = path.next(u)?;
        let before = s.force();
        let out = if u.ratio(1u8, 16)? {
            let (out, next) = b.trial(s, x);
            *s = next;
            out
        } else {
            b.step(s, x)
        };
        check::<T, E>(&out, before, s.force());
    }
    Ok(())
}
