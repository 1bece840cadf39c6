//! sin and cos of a phase step θ in [0, π] without libm trig.
//!
//! Taylor polynomials on [0, π/2] (sin to θ^11, cos to θ^12), reflected
//! about π/2 above it. Truncation: below 5.7e-8 for sin and 6.4e-9 for cos
//! at θ = π/2, relatively below 1e-7 for sin near 0; in `f32` the rounding
//! of the Horner sums dominates: within 2.4e-7 of libm's `sin`/`cos` over
//! [0, π], and sin within 1e-6 relative on (0, π/2] (tested).
//! Cost: 12 multiply-adds and one comparison (two more to clamp the
//! argument, which [`sin_cos_in_range`] leaves to its caller).

use super::fast::clamp;
use crate::real::Real;

/// `(sin θ, cos θ)` for θ in [0, π]; arguments outside are clamped to it.
#[inline]
pub fn sin_cos<T: Real>(theta: T) -> (T, T) {
    let pi = T::from_f64(core::f64::consts::PI);
    sin_cos_in_range(clamp(theta, T::ZERO, pi))
}

/// `(sin θ, cos θ)` for θ already in [0, π] (unspecified outside).
#[inline(always)]
pub fn sin_cos_in_range<T: Real>(theta: T) -> (T, T) {
    let pi = T::from_f64(core::f64::consts::PI);
    let half_pi = T::from_f64(core::f64::consts::FRAC_PI_2);
    let (x, flip) = if theta > half_pi {
        (pi - theta, true)
    } else {
        (theta, false)
    };
    let x2 = x * x;
    // Horner in x², with the Taylor coefficients (-1)^k/(2k+1)! and
    // (-1)^k/(2k)!.
    let c = |k: f64| T::from_f64(k);
    let s = c(-1.0 / 6.0)
        + x2 * (c(1.0 / 120.0)
            + x2 * (c(-1.0 / 5040.0) + x2 * (c(1.0 / 362_880.0) + x2 * c(-1.0 / 39_916_800.0))));
    let sin = x + x * x2 * s;
    let k = c(1.0 / 24.0)
        + x2 * (c(-1.0 / 720.0)
            + x2 * (c(1.0 / 40_320.0)
                + x2 * (c(-1.0 / 3_628_800.0) + x2 * c(1.0 / 479_001_600.0))));
    let cos = T::ONE - T::HALF * x2 + x2 * x2 * k;
    (sin, if flip { -cos } else { cos })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomial_sin_cos_match_libm_over_zero_to_pi() {
        let mut worst = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..=100_000 {
            let t = core::f64::consts::PI * k as f64 / 100_000.0;
            let (s, c) = sin_cos(t);
            worst.0 = worst.0.max((s - t.sin()).abs()).max((c - t.cos()).abs());
            let tf = t as f32;
            let (s, c) = sin_cos(tf);
            let (se, ce) = ((tf as f64).sin(), (tf as f64).cos());
            worst.1 = worst
                .1
                .max((s as f64 - se).abs())
                .max((c as f64 - ce).abs());
            if k > 0 && k <= 50_000 {
                // Relative accuracy of sin near 0 (the rotation's small
                // angle; near π the f32 rounding of π itself dominates).
                worst.2 = worst.2.max((s as f64 / se - 1.0).abs());
            }
        }
        assert!(worst.0 < 6e-8, "f64 truncation {}", worst.0);
        assert!(worst.1 < 2.4e-7, "f32 {}", worst.1);
        assert!(worst.2 < 1e-6, "f32 relative sin {}", worst.2);
    }
}
