//! The scalar trait shared by every model.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A floating-point working type for the hot path: `f32` or `f64`.
///
/// Models are generic over `Real`; every coefficient is computed in `f64` at
/// construction and stored as `Self` with [`Real::from_f64`]. The step itself
/// only uses the arithmetic operators, comparisons and [`Real::abs`], so an
/// `f32` model on a Cortex-M4F runs on the single-precision FPU alone and the
/// same kernel gives bit-identical results on the host and on the target.
pub trait Real:
    Copy
    + Default
    + PartialOrd
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// Additive identity.
    const ZERO: Self;
    /// Multiplicative identity.
    const ONE: Self;
    /// One half.
    const HALF: Self;
    /// Largest backbone force (and tangent) a step accepts: `2^60` in `f32`,
    /// `2^500` in `f64`. Above it the step is refused and the state kept, so
    /// that no product formed in a step (force squared times a gain, in the
    /// dissipated energy) can overflow.
    const GUARD: Self;
    /// Name of the type, for reports.
    const NAME: &'static str;
    /// Machine epsilon (distance from 1 to the next number), for stopping
    /// tests of iterations.
    const EPSILON: Self;

    /// Rounds an `f64` to the working type (construction time only).
    fn from_f64(v: f64) -> Self;
    /// Widens to `f64` (reports and tests).
    fn to_f64(self) -> f64;
    /// True unless NaN or infinite.
    fn is_finite(self) -> bool;
    /// Absolute value.
    fn abs(self) -> Self;
    /// The IEEE bit pattern, widened to 64 bits (golden traces).
    fn bits(self) -> u64;
    /// The smaller of two values (the other one if either is NaN).
    fn min(self, other: Self) -> Self;
    /// The larger of two values (the other one if either is NaN).
    fn max(self, other: Self) -> Self;
    /// e^self through libm (`expf`: about 38 guest instructions on a
    /// Cortex-M4F). Only the cells whose coefficients depend on the state
    /// (the x_f cell) call it per step.
    fn exp(self) -> Self;
    /// e^self - 1 through libm, accurate near 0 (`expm1f`), for decays
    /// formed at run time.
    fn exp_m1(self) -> Self;
    /// self^e through libm (`powf`: a few hundred guest instructions on a
    /// Cortex-M4F); only the Dahl (α ≠ 1) and Bouc-Wen cells call it.
    fn powf(self, e: Self) -> Self;
    /// Square root through libm (`sqrtf`: about 77 guest instructions on a
    /// Cortex-M4F, which has no `vsqrt` path in libm).
    fn sqrt(self) -> Self;
}

macro_rules! impl_real {
    ($t:ty, $guard:expr, $bits:expr, $exp:path, $expm1:path, $pow:path, $sqrt:path) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const HALF: Self = 0.5;
            const GUARD: Self = $guard;
            const NAME: &'static str = stringify!($t);
            const EPSILON: Self = <$t>::EPSILON;

            #[inline(always)]
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn bits(self) -> u64 {
                let to_u64: fn($t) -> u64 = $bits;
                to_u64(self)
            }
            #[inline(always)]
            fn min(self, other: Self) -> Self {
                <$t>::min(self, other)
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            #[inline(always)]
            fn exp(self) -> Self {
                $exp(self)
            }
            #[inline(always)]
            fn exp_m1(self) -> Self {
                $expm1(self)
            }
            #[inline(always)]
            fn powf(self, e: Self) -> Self {
                $pow(self, e)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $sqrt(self)
            }
        }
    };
}

impl_real!(
    f32,
    1.152_921_5e18, // 2^60
    |v| v.to_bits() as u64,
    libm::expf,
    libm::expm1f,
    libm::powf,
    libm::sqrtf
);
impl_real!(
    f64,
    3.273_390_607_896_142e150, // 2^500
    |v| v.to_bits(),
    libm::exp,
    libm::expm1,
    libm::pow,
    libm::sqrt
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guards_are_exact_powers_of_two() {
        assert_eq!(<f32 as Real>::GUARD, 2f32.powi(60));
        assert_eq!(<f64 as Real>::GUARD, 2f64.powi(500));
        // Squaring a guarded value and scaling by 2^60 stays finite.
        let g = <f32 as Real>::GUARD;
        assert!((g * g).is_finite());
        let g = <f64 as Real>::GUARD;
        assert!((g * g * 2f64.powi(20)).is_finite());
    }
}
