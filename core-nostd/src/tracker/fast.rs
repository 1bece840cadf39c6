//! Cheap elementary functions for the tracker's per-sample path: `e^x` of a
//! small log-decay and `1/√x`, without libm calls and without a division.
//!
//! - [`exp_small`]: in `f32`, `e^x` for |x| < 1/16 by its Taylor polynomial
//!   to x⁵ (truncation below 8.3e-11 relative, so the `f32` rounding of the
//!   Horner sum dominates: within 1.2e-7 of the exact value, tested); libm's
//!   `expf`/`exp` elsewhere and in `f64`. About 12 guest instructions on a
//!   Cortex-M4F instead of about 40.
//! - [`rsqrt`]: `1/√x` for positive normal x from the classic bit-pattern
//!   guess (relative error below 3.5e-3) and Newton steps
//!   `y ← y (3/2 - x/2 y²)`, three in `f32` and four in `f64`, which square
//!   the error each time: within 2.4e-7 (`f32`) and 4.5e-16 (`f64`) of the
//!   exact value (tested). About 15 guest instructions on a Cortex-M4F; libm's
//!   `sqrtf` alone is about 77, and a division more.
//! - `clamp` (within the crate): `v.max(lo).min(hi)` by comparisons, for the
//!   phase argument of the sin/cos polynomials and the tracker's bands
//!   (`f32::max` is a libm call on a Cortex-M4F).
//!
//! The `f32` and `f64` paths are chosen by the size and the epsilon of the
//! type, known at compile time; another [`Real`] type (fixed point) takes its
//! own `exp` and `sqrt`.

pub use crate::real::{is_f32, is_f64, min_positive, rsqrt};

use crate::real::Real;

/// `e^x`; the polynomial below |x| = 1/16 in `f32`, libm elsewhere. NaN
/// gives NaN.
#[inline(always)]
pub fn exp_small<T: Real>(x: T) -> T {
    if is_f32::<T>() && x.abs() < T::from_f64(0.0625) {
        let c = |k: f64| T::from_f64(1.0 / k);
        T::ONE + x * (T::ONE + x * (c(2.0) + x * (c(6.0) + x * (c(24.0) + x * c(120.0)))))
    } else {
        x.exp()
    }
}

/// `v.max(lo).min(hi)` for `lo <= hi` (NaN gives `lo`) by comparisons:
/// `f32::max` is a libm call on a Cortex-M4F.
#[inline(always)]
pub(crate) fn clamp<T: Real>(v: T, lo: T, hi: T) -> T {
    if v >= lo {
        if v > hi { hi } else { v }
    } else {
        lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Log-spaced positive normal numbers over the whole f32 range, and a
    /// dense sweep of one binade pair (where the guess's error peaks).
    fn samples() -> impl Iterator<Item = f64> {
        let wide = (0..20_000).map(|k| 10f64.powf(-37.9 + 76.4 * k as f64 / 20_000.0));
        let dense = (0..100_000).map(|k| 1.0 + 3.0 * k as f64 / 100_000.0);
        wide.chain(dense)
    }

    #[test]
    fn rsqrt_to_full_precision() {
        let (mut worst32, mut worst64) = (0.0f64, 0.0f64);
        for v in samples() {
            let exact = 1.0 / v.sqrt();
            let x32 = v as f32;
            let exact32 = 1.0 / f64::from(x32).sqrt();
            worst32 = worst32.max((f64::from(rsqrt(x32)) / exact32 - 1.0).abs());
            worst64 = worst64.max((rsqrt(v) / exact - 1.0).abs());
        }
        // A few units in the last place: 2^-23 = 1.19e-7, 2^-52 = 2.2e-16.
        assert!(worst32 < 2.4e-7, "f32 {worst32:e}");
        assert!(worst64 < 4.5e-16, "f64 {worst64:e}");
        // sqrt as x · rsqrt(x), the way the factorisation forms it.
        let mut worst = 0.0f64;
        for v in samples() {
            let x = v as f32;
            let s = x * rsqrt(x);
            worst = worst.max((f64::from(s) / f64::from(x).sqrt() - 1.0).abs());
        }
        assert!(worst < 3e-7, "sqrt {worst:e}");
    }

    #[test]
    fn exp_small_matches_libm() {
        let mut worst = 0.0f64;
        for k in -100_000..=100_000 {
            let x = k as f32 * 1e-6; // ±0.1: both branches
            let e = f64::from(x).exp();
            worst = worst.max((f64::from(exp_small(x)) / e - 1.0).abs());
            assert_eq!(exp_small(f64::from(x)), libm::exp(f64::from(x)));
        }
        assert!(worst < 1.2e-7, "{worst:e}");
        assert!(exp_small(f32::NAN).is_nan());
        assert_eq!(exp_small(0.0f32), 1.0);
    }
}
