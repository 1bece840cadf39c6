//! The working types the models are fuzzed in, and what the fuzzer needs
//! of each beyond [`Real`].

use arbitrary::{Result, Unstructured};
use bushing::{
    Accumulator, LibmExp, MaxwellBank, MicromathExp, ParamError, Q16, Q32, Real, ShiftFactor,
};

/// A working type: `f32`, `f64`, `Q16` or `Q32`.
pub trait Num: Real {
    /// A fixed-point type: the families skip what does not run in the
    /// working type (the f64 post-processing).
    const FIXED: bool = false;

    /// Any value of the type from any bit pattern: NaN, infinities and
    /// subnormals in floating point, the whole range in fixed point.
    fn any(u: &mut Unstructured<'_>) -> Result<Self>;

    /// [`MaxwellBank::retune`] with libm's exponentials, or with
    /// micromath's where the type has them and `alt` is set.
    fn retune<const N: usize, A: Accumulator<Self>>(
        bank: &mut MaxwellBank<Self, N, A>,
        a_t: Self,
        alt: bool,
    ) -> core::result::Result<(), ParamError> {
        let _ = alt;
        bank.retune::<LibmExp>(a_t)
    }

    /// [`ShiftFactor::at_in`], with the exponentials chosen as in
    /// [`Num::retune`].
    fn shift_at(law: &ShiftFactor, t: Self, alt: bool) -> core::result::Result<Self, ParamError> {
        let _ = alt;
        law.at_in::<Self, LibmExp>(t)
    }
}

impl Num for f32 {
    fn any(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(f32::from_bits(u.arbitrary()?))
    }
    fn retune<const N: usize, A: Accumulator<Self>>(
        bank: &mut MaxwellBank<Self, N, A>,
        a_t: Self,
        alt: bool,
    ) -> core::result::Result<(), ParamError> {
        if alt {
            bank.retune::<MicromathExp>(a_t)
        } else {
            bank.retune::<LibmExp>(a_t)
        }
    }
    fn shift_at(law: &ShiftFactor, t: Self, alt: bool) -> core::result::Result<Self, ParamError> {
        if alt {
            law.at_in::<Self, MicromathExp>(t)
        } else {
            law.at_in::<Self, LibmExp>(t)
        }
    }
}

impl Num for f64 {
    fn any(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(f64::from_bits(u.arbitrary()?))
    }
}

impl Num for Q16 {
    const FIXED: bool = true;
    fn any(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(Q16::from_bits(u.arbitrary()?))
    }
}

impl Num for Q32 {
    const FIXED: bool = true;
    fn any(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(Q32::from_bits(u.arbitrary()?))
    }
}
