//! The scalar trait shared by every model.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// `v` limited to `[lo, hi]` with plain compares, for finite inputs (the
/// models refuse others): the NaN rules of `f32::max`/`min`, a library call
/// on cores without `vmaxnm`, are not needed.
#[inline(always)]
pub(crate) fn clamp<T: PartialOrd>(v: T, lo: T, hi: T) -> T {
    if v > hi {
        hi
    } else if v < lo {
        lo
    } else {
        v
    }
}

/// Every magnitude (values known not to be negative: no sign to strip) and
/// every value within `bound` in magnitude (a NaN fails). In floating
/// point, one comparison of the sum of them all, which is at least each of
/// them (rounding is monotone), and each one only when it fails (beyond the
/// bound, overflowed or NaN): the same answer in fewer compares. A
/// fixed-point type compares them one by one, where a saturating add costs
/// more than a compare.
#[inline(always)]
pub(crate) fn all_within<T: Real>(magnitudes: &[T], values: &[T], bound: T) -> bool {
    let each = || magnitudes.iter().all(|m| *m <= bound) && values.iter().all(|x| x.abs() <= bound);
    if !(is_f32::<T>() || is_f64::<T>()) {
        return each();
    }
    let sum = magnitudes.iter().fold(T::ZERO, |acc, m| acc + *m);
    values.iter().fold(sum, |acc, x| acc + x.abs()) <= bound || each()
}

/// True when `T` is `f32` (by size and epsilon, known at compile time).
#[inline(always)]
pub fn is_f32<T: Real>() -> bool {
    core::mem::size_of::<T>() == 4 && T::EPSILON.to_f64() == f64::from(f32::EPSILON)
}

/// True when `T` is `f64`.
#[inline(always)]
pub fn is_f64<T: Real>() -> bool {
    core::mem::size_of::<T>() == 8 && T::EPSILON.to_f64() == f64::EPSILON
}

/// Smallest positive normal number of the type (`f32` or `f64`; the `f32`
/// one, which rounds to zero in a fixed-point type, for any other).
/// [`rsqrt`] expects its argument above it.
#[inline(always)]
pub fn min_positive<T: Real>() -> T {
    if is_f64::<T>() {
        T::from_f64(f64::MIN_POSITIVE)
    } else {
        T::from_f64(f64::from(f32::MIN_POSITIVE))
    }
}

/// `1/√x` for a positive, normal, finite x, without libm and without a
/// division: the classic bit-pattern guess (relative error below 3.5e-3)
/// and Newton steps `y ← y (3/2 - x/2 y²)`, three in `f32` and four in
/// `f64`, which square the error each time: within 2.4e-7 (`f32`) and
/// 4.5e-16 (`f64`) of the exact value (tested in `tracker::fast`). About
/// 15 guest instructions on a Cortex-M4F, where libm's `sqrtf` is a
/// software routine of about 77. Another [`Real`] type (fixed point) takes
/// `1 / sqrt(x)`. Other arguments give an unspecified value.
#[inline(always)]
pub fn rsqrt<T: Real>(x: T) -> T {
    if is_f32::<T>() {
        {
            // For f32 these conversions are the identity and vanish.
            let x = x.to_f64() as f32;
            let half = 0.5 * x;
            let mut y = f32::from_bits(0x5f37_5a86_u32.wrapping_sub(x.to_bits() >> 1));
            y *= 1.5 - half * y * y;
            y *= 1.5 - half * y * y;
            y *= 1.5 - half * y * y;
            T::from_f64(f64::from(y))
        }
    } else if is_f64::<T>() {
        {
            let x = x.to_f64();
            let half = 0.5 * x;
            let mut y = f64::from_bits(0x5fe6_eb50_c7b5_37a9_u64.wrapping_sub(x.to_bits() >> 1));
            y *= 1.5 - half * y * y;
            y *= 1.5 - half * y * y;
            y *= 1.5 - half * y * y;
            y *= 1.5 - half * y * y;
            T::from_f64(y)
        }
    } else {
        T::ONE / x.sqrt()
    }
}

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
    /// The angle of the point (x, y) = (`other`, `self`) in (-π, π],
    /// through libm (`atan2f` works in single precision). Only the 6-DOF
    /// bushing calls it per step, once, for the relative rotation angle.
    fn atan2(self, other: Self) -> Self;
}

macro_rules! impl_real {
    ($t:ty, $guard:expr, $bits:expr, $exp:path, $expm1:path, $pow:path, $sqrt:path, $atan2:path) => {
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
            #[inline(always)]
            fn atan2(self, other: Self) -> Self {
                $atan2(self, other)
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
    libm::sqrtf,
    libm::atan2f
);
impl_real!(
    f64,
    3.273_390_607_896_142e150, // 2^500
    |v| v.to_bits(),
    libm::exp,
    libm::expm1,
    libm::pow,
    libm::sqrt,
    libm::atan2
);

/// Where a run-time re-tune forms its exponentials in the working type
/// (see [`MaxwellBank::retune`](crate::MaxwellBank::retune) and
/// [`ShiftFactor::at_in`](crate::ShiftFactor::at_in)).
///
/// Construction computes every exponential in `f64` with libm, which is
/// soft-float on a Cortex-M4F; a firmware that re-tunes on line picks one of
/// these providers instead and stays on the single-precision FPU.
pub trait Exponentials<T> {
    /// Name for reports.
    const NAME: &'static str;
    /// e^x.
    fn exp(x: T) -> T;
    /// 1 - e^-h for h >= 0, with its relative accuracy kept as h -> 0 (a
    /// slow cell's decay per step).
    fn one_minus_exp_neg(h: T) -> T;
}

/// libm's `expf`/`expm1f` (or `exp`/`expm1` in `f64`): correctly rounded
/// within an ulp or so; `expf` is about 38 guest instructions on a Cortex-M4F.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LibmExp;

impl<T: Real> Exponentials<T> for LibmExp {
    const NAME: &'static str = "libm";
    #[inline(always)]
    fn exp(x: T) -> T {
        x.exp()
    }
    #[inline(always)]
    fn one_minus_exp_neg(h: T) -> T {
        -(-h).exp_m1()
    }
}

/// micromath's `exp` (`f32` only, feature `micromath`): a 4-term series on
/// the fractional part of x log2 e, relative error up to 2.4e-3 for x <= 0
/// (7.5e-4 for x > 0; measured over [-20, 20] against libm's `exp`).
/// micromath has no `expm1`, so `1 - e^-h` is summed as
/// `h (1 - h/2 (1 - h/3 (1 - h/4)))` below h = 1/16 (truncation below
/// 1.3e-7 relative) and formed as `1 - exp(-h)` above.
#[cfg(feature = "micromath")]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MicromathExp;

#[cfg(feature = "micromath")]
impl MicromathExp {
    /// Below this h, `1 - e^-h` is taken from its series.
    pub const SERIES_BELOW: f32 = 0.0625;
    /// ln of the largest f32: `exp` is infinite from here on.
    pub const LN_MAX: f32 = 88.722_84;
}

#[cfg(feature = "micromath")]
impl Exponentials<f32> for MicromathExp {
    const NAME: &'static str = "micromath";
    #[inline(always)]
    fn exp(x: f32) -> f32 {
        // micromath 2.1 lets the exponent 128 through for x in [88.72,
        // 89.42) (a debug assertion there, NaN in release): above ln of the
        // largest f32 the answer is infinite anyway, and a NaN stays NaN.
        if x.is_nan() {
            return x;
        }
        if x >= Self::LN_MAX {
            return f32::INFINITY;
        }
        // By path: on a host with std, `x.exp()` would be std's inherent
        // method, not micromath's.
        micromath::F32Ext::exp(x)
    }
    #[inline(always)]
    fn one_minus_exp_neg(h: f32) -> f32 {
        if h < Self::SERIES_BELOW {
            const THIRD: f32 = 1.0 / 3.0;
            h * (1.0 - 0.5 * h * (1.0 - THIRD * h * (1.0 - 0.25 * h)))
        } else {
            1.0 - micromath::F32Ext::exp(-h)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `all_within` against the comparisons one by one, over every triple of
    /// `values` (0, -0, at and beyond the bound, sums beyond it or
    /// overflowing, the largest finite value, infinities, NaN).
    fn all_within_as_one_by_one<T: Real>(values: &[T], bound: T) {
        for &a in values {
            for &b in values {
                for &c in values {
                    let v = [a, b, c];
                    let plain = v.iter().all(|x| x.abs() <= bound);
                    assert_eq!(all_within(&[], &v, bound), plain, "{v:?} against {bound:?}");
                    // The first as a magnitude, when it is one.
                    if a.partial_cmp(&T::ZERO) != Some(core::cmp::Ordering::Less) {
                        let got = all_within(&[a], &[b, c], bound);
                        assert_eq!(got, plain, "{v:?} against {bound:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_sum_of_magnitudes_decides_as_the_values_one_by_one() {
        let f = [
            0.0,
            -0.0,
            0.5,
            -0.6,
            1.0,
            -1.0,
            1.000_001,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        all_within_as_one_by_one::<f32>(&f, 1.0);
        all_within_as_one_by_one::<f32>(&f, f32::MAX);
        all_within_as_one_by_one::<f32>(&f, <f32 as Real>::GUARD);
        let d = f.map(f64::from);
        all_within_as_one_by_one::<f64>(&d, 1.0);
        all_within_as_one_by_one::<f64>(&d, f64::MAX);
        #[cfg(feature = "fixed")]
        {
            use crate::fixed::Q16;
            let q = [
                0.0, 0.5, -0.6, 1.0, -1.0, 1.001, 16_384.0, 32_767.0, -32_768.0,
            ];
            let q = q.map(Q16::from_f64);
            all_within_as_one_by_one::<Q16>(&q, Q16::ONE);
            all_within_as_one_by_one::<Q16>(&q, Q16::GUARD);
        }
    }

    #[cfg(feature = "micromath")]
    #[test]
    fn micromath_exp_is_total_over_f32() {
        // Every argument from -200 to 200 in steps of 1/64, the edges and
        // NaN: no panic (micromath's exponent check fires in debug builds
        // between 88.72 and 89.42), infinite past ln(f32::MAX), finite and
        // within micromath's 2.4e-3 below it.
        for k in -12_800..=12_800 {
            let x = k as f32 / 64.0;
            let e = MicromathExp::exp(x);
            if x >= MicromathExp::LN_MAX {
                assert_eq!(e, f32::INFINITY, "{x}");
            } else if x > -80.0 {
                let exact = libm::exp(x as f64);
                assert!(
                    (e as f64 / exact - 1.0).abs() < 2.5e-3,
                    "{x}: {e} vs {exact}"
                );
            } else {
                assert!(e.is_finite() && e >= 0.0, "{x}: {e}");
            }
        }
        assert!(MicromathExp::exp(f32::NAN).is_nan());
        assert_eq!(MicromathExp::exp(f32::INFINITY), f32::INFINITY);
        assert!(MicromathExp::exp(f32::NEG_INFINITY).abs() < 1e-30);
    }

    #[test]
    fn exponential_providers_keep_slow_decays() {
        for h in [1e-7f64, 1e-5, 1e-3, 0.05, 0.07, 0.5, 0.69, 1.0, 3.0, 20.0] {
            let exact = -libm::expm1(-h);
            let hf = h as f32;
            let exact_f = -libm::expm1(-(hf as f64)); // same argument as f32
            let libm_f = <LibmExp as Exponentials<f32>>::one_minus_exp_neg(hf) as f64;
            assert!(
                (libm_f / exact_f - 1.0).abs() < 2.0 * f32::EPSILON as f64,
                "libm h={h}"
            );
            let libm_d = <LibmExp as Exponentials<f64>>::one_minus_exp_neg(h);
            assert_eq!(libm_d, exact);
            #[cfg(feature = "micromath")]
            {
                let mm = MicromathExp::one_minus_exp_neg(hf) as f64;
                // Series region: truncation and rounding; above it, micromath's
                // 2.4e-3 on e^-h, amplified by e^-h / (1 - e^-h).
                let bound = if hf < MicromathExp::SERIES_BELOW {
                    4.0 * f32::EPSILON as f64
                } else {
                    2.4e-3 * (-h).exp() / exact + 4.0 * f32::EPSILON as f64
                };
                assert!(
                    (mm / exact_f - 1.0).abs() < bound,
                    "micromath h={h}: {mm} vs {exact_f}"
                );
                let e = MicromathExp::exp(-hf) as f64;
                assert!(
                    (e / libm::exp(-(hf as f64)) - 1.0).abs() < 2.4e-3,
                    "exp(-{h})"
                );
            }
        }
        // The effective corner of a cell, ln(1 / (1 - d)) / dt, moves by at
        // most 0.34 % with micromath (largest at h = ln 2). Above h = 5 the
        // f32 rounding of d next to 1 dominates whatever the exponential
        // (and such a cell relaxes within a step).
        #[cfg(feature = "micromath")]
        for k in 0..5_000 {
            let h = 0.01 + k as f32 * 1e-3;
            let d = MicromathExp::one_minus_exp_neg(h) as f64;
            let corner = -libm::log1p(-d) / h as f64;
            assert!((corner - 1.0).abs() < 3.5e-3, "h = {h}: corner {corner}");
        }
    }

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
