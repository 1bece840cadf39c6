//! Fixed-point working types for cores without an FPU (feature `fixed`):
//! [`Q16`] (`I16F16` of the `fixed` crate, 32 bits) and [`Q32`] (`I32F32`,
//! 64 bits).
//!
//! They implement [`Real`], so the *same* generic model code (one scheme,
//! one implementation) runs in fixed point: `Bushing<Q16, MonotoneSpline<Q16,
//! 8>, (MaxwellBank<Q16, 4>, IwanBank<Q16, 3>)>` is the default bushing of
//! the firmware examples on a Cortex-M3 (`thumbv7m-none-eabi`), with no
//! soft-float call in its step.
//!
//! # Arithmetic
//!
//! Every operator saturates: `fixed`'s plain operators panic on overflow in
//! a debug build and wrap in a release build, and both are forbidden on the
//! hot path. A saturated value is the largest (or most negative) number of
//! the type, so a runaway force shows as a force pinned at the limit, and a
//! backbone force that saturated is refused by the bushing (it exceeds
//! [`Real::GUARD`], see below).
//!
//! | operation | result |
//! |---|---|
//! | `+`, `-`, unary `-`, [`Real::abs`] | exact, or saturated (`-MIN` and `abs(MIN)` give `MAX`) |
//! | `*` | rounded to nearest (ties toward +∞), saturated |
//! | `/` | rounded to nearest (ties away from zero), saturated; `x / 0` is `MAX` for x > 0, `MIN` for x < 0 and `0` for `0 / 0`; never panics |
//! | [`Real::from_f64`] | rounded to nearest (ties to even), saturated; NaN gives 0 |
//! | [`Real::is_finite`] | always true: there is no NaN or infinity |
//! | [`Real::bits`] | the raw two's-complement bits, zero-extended (as `f32::to_bits`) |
//! | [`Real::exp`], [`Real::exp_m1`], [`Real::powf`], [`Real::sqrt`], [`Real::atan2`] | through libm in `f32` ([`Q16`]) or `f64` ([`Q32`]) and back, saturated; NaN (`sqrt` of a negative) gives 0. Soft-float on a Cortex-M3: construction and re-tune only, never in the step of a supported model |
//!
//! The multiplication rounds to nearest rather than truncating (as `fixed`
//! does): a truncated product is biased by half a unit, and a relaxation
//! `F ← F - d F` with truncated `d F` stops decaying for positive F (the
//! floor of a small positive decrement is 0) but not for negative F. With
//! rounding to nearest the dead band is symmetric, `|F| < ε / (2 d)`.
//!
//! # GUARD and units
//!
//! [`Real::GUARD`] is the largest backbone force and tangent a bushing step
//! accepts: 2^14 = 16 384 in [`Q16`] and 2^30 in [`Q32`], half the range.
//! The forces formed in a step are sums of at most two guarded values: the
//! increment `F^∞_n - F^∞_{n-1}`, and the total force `g^0 F^∞ + Σ F^i`
//! (a rate-form Maxwell branch is bounded by `2 g_i max|F^∞|`, so the total
//! stays below `(1 + Σ g_i) GUARD <= 2 GUARD`), so none of them saturates
//! (the extreme `2 GUARD` itself is one unit above `MAX` and loses that
//! unit). GUARD is also below `MAX`, so a backbone force that saturated in
//! the evaluation is refused and flagged
//! ([`Faults::OUT_OF_RANGE`](crate::Faults::OUT_OF_RANGE)) rather than used.
//!
//! What GUARD cannot protect in [`Q16`] is the *dissipated energy* of a
//! Maxwell bank, which forms
//! `Σ (ω_i dt / g_i) (F^i_{n-1}² + F^i_n²)` before dividing by K^∞: the sum
//! of squares saturates once a branch force passes 128 N (less for a fast
//! cell with `ω_i dt / g_i > 1`), and the reported energy is then too small
//! (the default bushing at 3.5 mm loses 6 % of it, a 50 Hz cell of g = 0.3
//! at 3.9 mm and 100 Hz 84 %; see `tests/tests/fixed_point.rs`). The force
//! and tangent are not affected. A GUARD small enough to prevent it (2^7)
//! would make the natural units unusable (see below); the cure is in the
//! bank (forming `(ω dt / (g K^∞)) F` before the second factor). In [`Q32`]
//! the squares saturate only above 32 000 N.
//!
//! Choose units so that the backbone force stays below GUARD and the force
//! resolution is small against the error budget: in [`Q16`], **mm and N**
//! (forces up to 16 384 N, resolution 2^-16 N = 15 µN, displacement
//! resolution 15 nm). Do *not* move to kN to gain range: the rounding error
//! of a slow Maxwell cell is about `ε / (1 - e^{-ω dt})` force units (next
//! section), 0.1 N in N but 100 N in kN for a 0.05 Hz cell at 2 kHz. A
//! bushing stiffer than 16 kN at its largest deflection needs [`Q32`]
//! (2^30 N, resolution 2.3e-10 N), or daN with the error budget scaled by 10.
//!
//! # Accuracy against f64
//!
//! The coefficients are computed in f64 at construction and rounded once
//! (absolute error `ε/2`, `ε` = [`Real::EPSILON`] = 2^-16 in [`Q16`]). For a
//! rate-form Maxwell cell `F_n = F_{n-1} - d F_{n-1} + p ΔF^∞_n` the error
//! `e_n` of the branch force against the exact-coefficient recursion obeys
//! `e_n = (1 - d̃) e_{n-1} - δd F_{n-1} + δp ΔF^∞_n + p̃ Δ(δF^∞)_n + r_n`
//! (`r_n`: two rounded products, `|r_n| <= ε`). The terms carried by an
//! increment telescope (summation by parts: `|Σ a^k Δu_{n-k}| <= 2 max|u|`),
//! the others are amplified by the recursion gain `1/d̃`:
//!
//! ```text
//! |e| <= (|δd| max|F^i| + ε) / d̃  +  2 |δp| max|F^∞|  +  2 p̃ max|δF^∞|
//! ```
//!
//! with `d = 1 - e^{-ω dt}` and `|δd|, |δp| <= ε/2`. The first term
//! dominates, and it is the `ε / (1 - e^{-ω dt})` of slow cells: the
//! rounding of each step (ε) and the error of the stored pole (ε/2 per unit
//! of branch force) both build up over the cell's memory of `1/d̃` steps.
//! It is a worst case: under a sine the pole error averages out over each
//! period, and the measured error is about `ε/d̃` of the slowest cell (0.1 N
//! for a 0.05 Hz cell at 2 kHz, d = 1.57e-4). The stored pole itself is off
//! by up to `ε / (2 d)` relative (5 % there), which moves the corner
//! frequency of the slowest cells; a cell with `ω dt < 2^-17` (0.0024 Hz at
//! 2 kHz) has `d̃ = 0` and does not relax at all. A held cell stops
//! relaxing where its decrement `d̃ F` rounds to zero, `|F| < ε / (2 d̃)`
//! (0.05 N for the 0.05 Hz cell).
//!
//! The load forms (1.13, 1.15) add `|δq| max|F^∞| / d̃`, with `q = -ω dt g
//! e^{-ω dt/2}` only a few units of ε for a slow cell: the static gain of
//! its relaxation, `q̃/d̃` instead of `q/d`, is off by up to
//! `ε / (2 ω dt g) + ε / (2 ω dt)` relative (53 % for a 0.05 Hz cell of
//! g = 0.1 at 2 kHz; measured 33 % at g = 0.15 and 100 % at g = 0.05). It
//! shows under a preload: the load forms need [`Q32`] for slow cells.
//!
//! The Iwan clamp form has no recursion gain: a slipping cell is reset to
//! its stored slip force (error ε/2), and between slips it accumulates the
//! rounding of `g̃ ΔF^∞`, at most ε/2 per step. A cell that never slips
//! integrates that rounding for as long as it sticks (in f32 as well, with
//! a relative rounding instead).

//! Measured against f64 (N and mm, 2 kHz, 20 s sines; `cargo test -p
//! bushing-tests --test fixed_point -- --nocapture`), largest force error,
//! and its share of the largest force:
//!
//! | model, drive | [`Q16`] | [`Q32`] | f32 |
//! |---|---|---|---|
//! | 4 Maxwell cells 0.05-50 Hz, exact ramp, 3 mm 1 Hz | 0.11 N (2.7e-4) | 7.5e-7 N | 1.5e-4 N |
//! | 8 Maxwell cells 0.01-100 Hz, exact ramp, 3 mm 1 Hz | 0.23 N (5.5e-4) | 3.4e-6 N | 3.3e-4 N |
//! | 4 cells, load exponential, 2 mm 1 Hz on 1 mm preload | 1.25 N (3.2e-3) | 2.3e-5 N | 1.2e-4 N |
//! | 8 cells, load exponential, same | 3.0 N (7.8e-3) | 2.1e-4 N | 1.2e-4 N |
//! | 16 Jenkins cells (clamp), 3 mm 1 Hz | 6.8 mN (1.9e-5) | 1.0e-7 N | |
//! | default bushing (spline, 4 Maxwell, 3 Jenkins), 2 mm 1 Hz | 0.12 N (3.3e-4) | | |
//!
//! Every figure is within the bound above (2 % to 24 % of it): the error is
//! the slowest cell's `ε / d̃` order, and the dissipated energy is within
//! 2e-4 relative for the rate forms (when its squares do not saturate,
//! see above).
//!
//! # Models
//!
//! Supported (the step uses only `+ - * /`, comparisons and `abs`, and is
//! tested against f64): [`Polynomial`](crate::Polynomial) and
//! [`MonotoneSpline`](crate::MonotoneSpline) backbones, [`MaxwellBank`]
//! in every form with [`Plain`](crate::Plain) or
//! [`Multiplied`](crate::Multiplied) states, [`IwanBank`](crate::IwanBank)
//! (clamp) and [`IwanSliders`](crate::IwanSliders), and the
//! [`Bushing`](crate::Bushing) with force, tangent and dissipated energy.
//! [`Compensated`](crate::Compensated) states work but gain nothing (fixed
//! point addition is exact: the compensation word stays 0).
//!
//! Not supported: the x_f cells ([`crate::xf`]: `exp_m1` of the state every
//! step), the continuous STS law ([`crate::stack::Sts`]: `sqrt` every
//! step), the Dahl and Bouc-Wen cells (`exp_m1`, `powf`), the modal
//! tracker (`sqrt` and variances spanning many decades). They compile, but
//! their step would run soft-float libm through a conversion and lose
//! precision. The Berg cell, the K_f(d) table on the turning-point stack,
//! the fractional cell and the [`Oscillator`](crate::Oscillator) (whose
//! chord iteration stops at `64 EPSILON`, 1e-3 in [`Q16`]) use arithmetic
//! only but are not verified in fixed point.
//!
//! # Cost (Cortex-M3)
//!
//! [`Q16`]: an addition is `adds` and a conditional `eor` on the overflow
//! flag (v7-M has no `qadd`); a multiplication is one `smlal` (the 32x32 ->
//! 64 product plus the rounding constant), a two-instruction shift and
//! about ten instructions of saturation checks on the high word, against a
//! soft-float `__aeabi_fmul` call; a division is a 64-bit
//! `__aeabi_ldivmod` call (one per bank per step, for the energy, dropped
//! when the caller does not read it). [`Q32`]: a multiplication is a
//! 64x64 -> 128 product (about 55 instructions), a division a 128-bit
//! library call.
//!
//! Guest instructions per step under QEMU (`mps2-an385`, `-icount`, 2 000
//! steps of a ±2 mm triangle), the same generic kernels in each type:
//!
//! | kernel | [`Q16`] | [`Q32`] | f32 (soft float) |
//! |---|---|---|---|
//! | polynomial + 4 Maxwell cells (exact ramp), force only | 371 | 1 133 | 2 398 |
//! | the same, with tangent and dissipated energy | 775 | 3 968 | 3 985 |
//! | default bushing (spline, 4 Maxwell, 3 Jenkins), force only | 513 | 1 436 | 3 006 |
//! | the same, with tangent and dissipated energy | 1 170 | 6 756 | 4 605 |
//!
//! [`MaxwellBank`]: crate::MaxwellBank

use core::fmt;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

use ::fixed::types::{I16F16, I32F32};

use crate::real::Real;

macro_rules! fixed_real {
    (
        $(#[$doc:meta])*
        $name:ident, $fx:ty, $bits:ty, $wide:ty, $frac:expr,
        $float:ty, $exp:path, $expm1:path, $pow:path, $sqrt:path, $atan2:path
    ) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Default, PartialEq, Eq, PartialOrd, Hash)]
        pub struct $name(pub $fx);

        impl $name {
            /// Number of fractional bits.
            pub const FRAC_BITS: u32 = $frac;
            /// Largest value.
            pub const MAX: Self = Self(<$fx>::MAX);
            /// Most negative value.
            pub const MIN: Self = Self(<$fx>::MIN);
            /// Resolution: the distance between two neighbouring values.
            pub const RESOLUTION: Self = Self(<$fx>::DELTA);

            /// The number whose raw two's-complement bits are `bits`
            /// (value `bits / 2^FRAC_BITS`).
            #[inline(always)]
            pub const fn from_bits(bits: $bits) -> Self {
                Self(<$fx>::from_bits(bits))
            }

            /// The raw two's-complement bits.
            #[inline(always)]
            pub const fn to_bits(self) -> $bits {
                self.0.to_bits()
            }

            /// Saturating product, rounded to nearest (ties toward +∞).
            #[inline(always)]
            pub const fn mul_round(self, rhs: Self) -> Self {
                let p = (self.to_bits() as $wide) * (rhs.to_bits() as $wide);
                let r = (p + (1 << ($frac - 1))) >> $frac;
                Self::from_bits(saturate!(r, $bits, $wide))
            }

            /// Saturating quotient, rounded to nearest (ties away from
            /// zero); `x / 0` saturates by the sign of x and `0 / 0` is 0.
            #[inline(always)]
            pub const fn div_round(self, rhs: Self) -> Self {
                let (a, b) = (self.to_bits(), rhs.to_bits());
                if b == 0 {
                    return if a > 0 {
                        Self::MAX
                    } else if a < 0 {
                        Self::MIN
                    } else {
                        Self::from_bits(0)
                    };
                }
                let n = (a as $wide) << $frac;
                let d = b as $wide;
                // |n| < 2^(2 bits - 1) and d != 0: neither call fails.
                let (q, r) = match (n.checked_div(d), n.checked_rem(d)) {
                    (Some(q), Some(r)) => (q, r),
                    _ => (0, 0),
                };
                let q = if r.unsigned_abs() >= d.unsigned_abs() - r.unsigned_abs() {
                    if (n < 0) == (d < 0) { q + 1 } else { q - 1 }
                } else {
                    q
                };
                Self::from_bits(saturate!(q, $bits, $wide))
            }

            #[inline(always)]
            fn from_float(v: $float) -> Self {
                Self::from_f64_rounded(v as f64)
            }

            /// `v` rounded to the nearest value (ties to even) and
            /// saturated, NaN giving 0: what `fixed`'s
            /// `saturating_from_num` gives, without the panicking branch it
            /// keeps for NaN (on a core without an FPU, LLVM cannot see
            /// that a soft-float NaN test has already excluded it).
            #[inline(always)]
            fn from_f64_rounded(v: f64) -> Self {
                // Scaling by a power of two is exact; `as` saturates and
                // maps NaN to 0.
                let scaled = libm::rint(v * (1u64 << $frac) as f64);
                Self::from_bits(scaled as $bits)
            }

            #[inline(always)]
            fn to_float(self) -> $float {
                self.0.to_num::<$float>()
            }
        }

        impl From<$fx> for $name {
            #[inline(always)]
            fn from(v: $fx) -> Self {
                Self(v)
            }
        }

        impl From<$name> for $fx {
            #[inline(always)]
            fn from(v: $name) -> Self {
                v.0
            }
        }

        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                fmt::Display::fmt(&self.0, f)
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                fmt::Display::fmt(&self.0, f)
            }
        }

        /// The value as the nearest `f64` (exact for `Q16`), formatted on
        /// the host.
        #[cfg(feature = "defmt")]
        impl defmt::Format for $name {
            fn format(&self, f: defmt::Formatter<'_>) {
                defmt::write!(f, "{=f64}", self.0.to_num::<f64>());
            }
        }

        impl Add for $name {
            type Output = Self;
            #[inline(always)]
            fn add(self, rhs: Self) -> Self {
                Self(self.0.saturating_add(rhs.0))
            }
        }

        impl Sub for $name {
            type Output = Self;
            #[inline(always)]
            fn sub(self, rhs: Self) -> Self {
                Self(self.0.saturating_sub(rhs.0))
            }
        }

        impl Mul for $name {
            type Output = Self;
            #[inline(always)]
            fn mul(self, rhs: Self) -> Self {
                self.mul_round(rhs)
            }
        }

        impl Div for $name {
            type Output = Self;
            #[inline(always)]
            fn div(self, rhs: Self) -> Self {
                self.div_round(rhs)
            }
        }

        impl Neg for $name {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                Self(self.0.saturating_neg())
            }
        }

        impl AddAssign for $name {
            #[inline(always)]
            fn add_assign(&mut self, rhs: Self) {
                *self = *self + rhs;
            }
        }

        impl SubAssign for $name {
            #[inline(always)]
            fn sub_assign(&mut self, rhs: Self) {
                *self = *self - rhs;
            }
        }

        impl MulAssign for $name {
            #[inline(always)]
            fn mul_assign(&mut self, rhs: Self) {
                *self = *self * rhs;
            }
        }

        impl Real for $name {
            const ZERO: Self = Self::from_bits(0);
            const ONE: Self = Self::from_bits(1 << $frac);
            const HALF: Self = Self::from_bits(1 << ($frac - 1));
            /// Half the range (2^14 in `Q16`, 2^30 in `Q32`): see the
            /// module docs.
            const GUARD: Self = Self::from_bits(1 << (<$bits>::BITS - 2));
            const NAME: &'static str = stringify!($fx);
            /// The resolution, 2^-FRAC_BITS.
            const EPSILON: Self = Self::from_bits(1);

            #[inline(always)]
            fn from_f64(v: f64) -> Self {
                Self::from_f64_rounded(v)
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self.0.to_num::<f64>()
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                true
            }
            #[inline(always)]
            fn abs(self) -> Self {
                Self(self.0.saturating_abs())
            }
            #[inline(always)]
            fn bits(self) -> u64 {
                self.to_bits().cast_unsigned() as u64
            }
            #[inline(always)]
            fn min(self, other: Self) -> Self {
                if other < self { other } else { self }
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                if other > self { other } else { self }
            }
            #[inline]
            fn exp(self) -> Self {
                Self::from_float($exp(self.to_float()))
            }
            #[inline]
            fn exp_m1(self) -> Self {
                Self::from_float($expm1(self.to_float()))
            }
            #[inline]
            fn powf(self, e: Self) -> Self {
                Self::from_float($pow(self.to_float(), e.to_float()))
            }
            #[inline]
            fn sqrt(self) -> Self {
                Self::from_float($sqrt(self.to_float()))
            }
            #[inline(always)]
            fn atan2(self, other: Self) -> Self {
                Self::from_float($atan2(self.to_float(), other.to_float()))
            }
        }
    };
}

/// `r` (a wide integer) limited to the range of `$bits`.
macro_rules! saturate {
    ($r:expr, $bits:ty, $wide:ty) => {{
        let r = $r;
        if r > <$bits>::MAX as $wide {
            <$bits>::MAX
        } else if r < <$bits>::MIN as $wide {
            <$bits>::MIN
        } else {
            r as $bits
        }
    }};
}

fixed_real!(
    /// Signed fixed point with 16 integer and 16 fractional bits
    /// (`fixed::types::I16F16`, Q15.16 with the sign): the natural working
    /// type of a Cortex-M3, whose `smull` forms the 32x32 -> 64 product in
    /// one instruction.
    ///
    /// - **Range**: -32 768 to 32 767.999 985; [`Real::GUARD`] = 16 384.
    /// - **Resolution**: 2^-16 = 1.53e-5 ([`Real::EPSILON`]).
    /// - **Arithmetic**: saturating, products and quotients rounded to
    ///   nearest, no panic (division by zero saturates by the sign, 0/0 is
    ///   0), no NaN or infinity; `exp`/`exp_m1`/`powf`/`sqrt` through `f32`
    ///   libm (construction and re-tune only).
    /// - **Models**: backbones (polynomial, spline), Maxwell banks (every
    ///   form; slow cells in the load forms lose their static gain, use
    ///   [`Q32`]), Iwan banks (clamp, slider) and the bushing with force,
    ///   tangent and energy. Not the x_f, STS, Dahl or Bouc-Wen cells, which
    ///   call `exp`/`sqrt`/`powf` every step. See the [module docs](self).
    /// - **Units**: mm and N (forces below 16 384 N, 15 µN and 15 nm
    ///   resolution). A slow Maxwell cell's error is about
    ///   `2^-16 / (1 - e^{-ω dt})` N, 0.1 N for 0.05 Hz at 2 kHz: do not
    ///   trade resolution for range with kN.
    /// - **Cost** on a Cortex-M3: a saturating multiply is `smlal` (product
    ///   and rounding constant), a shift and the saturation checks (about 14
    ///   instructions, no call); a saturating add is `adds` and a
    ///   conditional `eor` on overflow; a division is an `__aeabi_ldivmod`
    ///   call (once per bank per step, for the energy). The default bushing
    ///   steps in 513 guest instructions (force only; 1 170 with tangent
    ///   and energy) against 3 006 (4 605) in soft-float f32.
    ///
    /// ```
    /// use bushing::{Bushing, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial, Q16, Real};
    ///
    /// let dt = 5e-4; // 2 kHz
    /// let backbone = Polynomial::<Q16, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0))?; // N, mm
    /// let cells = [MaxwellSpec::hz(0.5, 0.1), MaxwellSpec::hz(5.0, 0.2)];
    /// let bank = MaxwellBank::<Q16, 2>::new(MaxwellForm::RateExactRamp, &cells, dt)?;
    /// let bushing = Bushing::new(backbone, (bank,))?;
    /// let mut state = bushing.state_at(Q16::ZERO);
    /// let out = bushing.step(&mut state, Q16::from_f64(0.12));
    /// assert!(out.force > Q16::ZERO && out.dissipated >= Q16::ZERO);
    /// // F^∞(0.12 mm) = 18.007 N, less what the cells relax in the step.
    /// assert!((out.force.to_f64() - 18.0).abs() < 0.05);
    /// # Ok::<(), bushing::ParamError>(())
    /// ```
    Q16, I16F16, i32, i64, 16,
    f32, libm::expf, libm::expm1f, libm::powf, libm::sqrtf, libm::atan2f
);

fixed_real!(
    /// Signed fixed point with 32 integer and 32 fractional bits
    /// (`fixed::types::I32F32`): the precise fixed-point type, when
    /// [`Q16`]'s resolution is too coarse for slow cells (the load-form
    /// Maxwell cells) or its range too small.
    ///
    /// - **Range**: about ±2.1e9; [`Real::GUARD`] = 2^30.
    /// - **Resolution**: 2^-32 = 2.3e-10 ([`Real::EPSILON`]).
    /// - **Arithmetic**: as [`Q16`], with `exp`/`exp_m1`/`powf`/`sqrt`
    ///   through `f64` libm.
    /// - **Models**: as [`Q16`]; the slow-cell error is 65 536 times smaller.
    /// - **Units**: mm and N.
    /// - **Cost** on a Cortex-M3: a saturating multiply is a 64x64 -> 128
    ///   product and a shift with the saturation checks (about 55
    ///   instructions, 4 times a [`Q16`] multiply); a division is a 128-bit
    ///   library call. The default bushing steps in 1 436 guest
    ///   instructions (force only), still half of soft-float f32, but
    ///   6 756 with the energy's two 128-bit divisions.
    Q32, I32F32, i64, i128, 32,
    f64, libm::exp, libm::expm1, libm::pow, libm::sqrt, libm::atan2
);

#[cfg(test)]
mod tests {
    #[test]
    fn conversions_round_as_the_fixed_crate_does() {
        let mut values = alloc::vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1e-9,
            -1e-9,
            3.0e4,
            -3.3e4,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            2.5e9,
            -2.5e9,
        ];
        // Ties in both types, and values either side of them.
        for k in -40i32..40 {
            for frac in [16, 32] {
                let tie = (f64::from(k) + 0.5) / (1u64 << frac) as f64;
                values.extend([tie, tie * (1.0 + 1e-15), tie * (1.0 - 1e-15)]);
            }
        }
        let mut x = 0.1234f64;
        for _ in 0..2000 {
            x = (x * 7919.0 + 0.377).fract();
            values.push((x - 0.5) * 7.0e4);
            values.push((x - 0.5) * 1.0e-3);
        }
        for &v in &values {
            assert_eq!(Q16::from_f64(v).0, I16F16::saturating_from_num(v), "{v}");
            assert_eq!(Q32::from_f64(v).0, I32F32::saturating_from_num(v), "{v}");
            let f = v as f32;
            assert_eq!(Q16::from_float(f).0, I16F16::saturating_from_num(f), "{f}");
        }
        assert_eq!(Q16::from_f64(f64::NAN), Q16::ZERO);
        assert_eq!(Q32::from_f64(f64::NAN), Q32::ZERO);
    }

    use super::*;
    use crate::backbone::{Backbone, MonotoneSpline, Polynomial};
    use crate::bushing::Bushing;
    use crate::iwan::{IwanBank, IwanCellSpec, IwanSliders};
    use crate::maxwell::{MaxwellBank, MaxwellForm, MaxwellSpec};

    fn q(v: f64) -> Q16 {
        Q16::from_f64(v)
    }

    #[test]
    fn constants() {
        assert_eq!(Q16::ONE.to_f64(), 1.0);
        assert_eq!(Q16::HALF.to_f64(), 0.5);
        assert_eq!(Q16::GUARD.to_f64(), 16_384.0);
        assert_eq!(Q16::EPSILON.to_f64(), 2f64.powi(-16));
        assert_eq!(Q16::EPSILON, Q16::RESOLUTION);
        assert_eq!(Q32::GUARD.to_f64(), 2f64.powi(30));
        assert_eq!(Q32::EPSILON.to_f64(), 2f64.powi(-32));
        assert_eq!(Q32::ONE.to_f64(), 1.0);
        assert_eq!(<Q16 as Real>::NAME, "I16F16");
        assert_eq!(<Q32 as Real>::NAME, "I32F32");
        // Two guarded values add to MAX, one unit short of 2 GUARD.
        assert_eq!(Q16::GUARD + Q16::GUARD, Q16::MAX);
        assert_eq!(Q16::MAX.to_f64(), 32_768.0 - 2f64.powi(-16));
        assert_eq!(Q32::GUARD + Q32::GUARD, Q32::MAX);
        assert_eq!((Q16::GUARD - Q16::GUARD) - Q16::GUARD, -Q16::GUARD);
        assert!(Q16::GUARD.is_finite() && Q16::MAX.is_finite());
    }

    #[test]
    fn from_f64_rounds_to_nearest_and_saturates() {
        let e = 2f64.powi(-16);
        assert_eq!(q(0.3 * e).to_bits(), 0);
        assert_eq!(q(0.7 * e).to_bits(), 1);
        assert_eq!(q(-0.7 * e).to_bits(), -1);
        assert_eq!(q(1.5 * e).to_bits(), 2); // ties to even
        assert_eq!(q(2.5 * e).to_bits(), 2);
        assert_eq!(q(1e9), Q16::MAX);
        assert_eq!(q(-1e9), Q16::MIN);
        assert_eq!(q(f64::INFINITY), Q16::MAX);
        assert_eq!(q(f64::NEG_INFINITY), Q16::MIN);
        assert_eq!(q(f64::NAN), Q16::ZERO);
        assert_eq!(Q32::from_f64(f64::NAN), Q32::ZERO);
        assert_eq!(Q32::from_f64(1e300), Q32::MAX);
        for v in [0.0, 1.0, -1.0, 123.456, -0.001, 32_767.0] {
            assert!((q(v).to_f64() - v).abs() <= 0.5 * e, "{v}");
            assert!(
                (Q32::from_f64(v).to_f64() - v).abs() <= 2f64.powi(-33),
                "{v}"
            );
        }
    }

    #[test]
    fn bits_are_the_raw_word_zero_extended() {
        assert_eq!(Q16::ONE.bits(), 0x1_0000);
        assert_eq!((-Q16::EPSILON).bits(), 0xffff_ffff);
        assert_eq!((-Q32::EPSILON).bits(), u64::MAX);
        assert_eq!(Q32::ONE.bits(), 1 << 32);
    }

    #[test]
    fn arithmetic_saturates_and_never_panics() {
        // Debug build: overflow checks are on, so any wrapping path would
        // panic here.
        let extremes = [
            Q16::MIN,
            Q16::MIN + Q16::EPSILON,
            -Q16::ONE,
            -Q16::EPSILON,
            Q16::ZERO,
            Q16::EPSILON,
            Q16::HALF,
            Q16::ONE,
            Q16::GUARD,
            Q16::MAX - Q16::EPSILON,
            Q16::MAX,
        ];
        for &a in &extremes {
            for &b in &extremes {
                let (x, y) = (a.to_f64(), b.to_f64());
                let clamp = |v: f64| v.clamp(Q16::MIN.to_f64(), Q16::MAX.to_f64());
                let half = 0.5 * Q16::EPSILON.to_f64();
                assert_eq!((a + b).to_f64(), clamp(x + y));
                assert_eq!((a - b).to_f64(), clamp(x - y));
                assert!(((a * b).to_f64() - clamp(x * y)).abs() <= half, "{a} * {b}");
                let d = (a / b).to_f64();
                if y == 0.0 {
                    let expect = if x > 0.0 {
                        Q16::MAX
                    } else if x < 0.0 {
                        Q16::MIN
                    } else {
                        Q16::ZERO
                    };
                    assert_eq!(a / b, expect, "{a} / 0");
                } else {
                    assert!((d - clamp(x / y)).abs() <= half, "{a} / {b}");
                }
                let mut c = a;
                c += b;
                c -= b;
                c *= b;
                let _ = (
                    a.abs(),
                    -a,
                    a.min(b),
                    a.max(b),
                    a.exp(),
                    a.sqrt(),
                    a.powf(b),
                );
                let _ = a.exp_m1();
            }
        }
        assert_eq!(-Q16::MIN, Q16::MAX);
        assert_eq!(Q16::MIN.abs(), Q16::MAX);
        assert_eq!(Q16::MIN / -Q16::EPSILON, Q16::MAX);
        assert_eq!(Q16::MAX * Q16::MAX, Q16::MAX);
        assert_eq!(Q16::MIN * Q16::MAX, Q16::MIN);
        assert_eq!(Q16::MIN * Q16::MIN, Q16::MAX);
        assert_eq!(Q32::MIN * Q32::MIN, Q32::MAX);
        assert_eq!(Q32::MIN / -Q32::EPSILON, Q32::MAX);
        assert_eq!(Q32::ONE / Q32::ZERO, Q32::MAX);
        assert_eq!(-Q32::ONE / Q32::ZERO, Q32::MIN);
        assert_eq!(Q32::ZERO / Q32::ZERO, Q32::ZERO);
        assert_eq!(Q32::MIN.abs(), Q32::MAX);
        assert_eq!((-Q16::ONE).sqrt(), Q16::ZERO); // NaN -> 0
        assert_eq!(q(20.0).exp(), Q16::MAX);
    }

    #[test]
    fn products_and_quotients_round_to_nearest() {
        let e = Q16::EPSILON;
        // 1.5 ulp * 0.5 = 0.75 ulp -> 1 ulp (truncation would give 0).
        assert_eq!((Q16::from_bits(3) * Q16::HALF).to_bits(), 2);
        assert_eq!((Q16::from_bits(-3) * Q16::HALF).to_bits(), -1); // tie -1.5 -> -1
        assert_eq!((Q16::from_bits(1) * Q16::HALF).to_bits(), 1); // tie 0.5 -> 1
        assert_eq!((e * e).to_bits(), 0);
        assert_eq!((Q16::ONE / q(3.0)).to_bits(), 21_845); // 21845.33
        assert_eq!((q(2.0) / q(3.0)).to_bits(), 43_691); // 43690.67
        assert_eq!((-q(2.0) / q(3.0)).to_bits(), -43_691);
        assert_eq!((Q16::from_bits(1) / q(2.0)).to_bits(), 1); // tie away
        assert_eq!((Q16::from_bits(-1) / q(2.0)).to_bits(), -1);
        // Random operands against exact rational arithmetic in i128.
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..20_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let (a, b) = (
                (s as i32) >> (s % 17),
                ((s >> 32) as i32) >> ((s >> 8) % 23),
            );
            let p = i128::from(a) * i128::from(b);
            let exact = p as f64 / 2f64.powi(32);
            let m = (Q16::from_bits(a) * Q16::from_bits(b)).to_f64();
            let clamp = exact.clamp(Q16::MIN.to_f64(), Q16::MAX.to_f64());
            assert!((m - clamp).abs() <= 0.5 / 65_536.0, "{a} * {b}");
            if b != 0 {
                let exact = a as f64 / b as f64;
                let d = (Q16::from_bits(a) / Q16::from_bits(b)).to_f64();
                let clamp = exact.clamp(Q16::MIN.to_f64(), Q16::MAX.to_f64());
                assert!((d - clamp).abs() <= 0.5 / 65_536.0 + 1e-12, "{a} / {b}");
            }
            let (a, b) = (s as i64 >> (s % 40), (s.rotate_left(29) as i64) >> (s % 37));
            let m = Q32::from_bits(a) * Q32::from_bits(b);
            let exact = (i128::from(a) * i128::from(b) + (1 << 31)) >> 32;
            let exact = exact.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64;
            assert_eq!(m.to_bits(), exact, "{a} * {b}");
        }
    }

    #[test]
    fn libm_functions_go_through_the_float_type() {
        assert!((q(1.0).exp().to_f64() - core::f64::consts::E).abs() < 1e-4);
        assert!((q(-1e-3).exp_m1().to_f64() + 9.995e-4).abs() < 2e-5);
        assert!((q(2.0).sqrt().to_f64() - core::f64::consts::SQRT_2).abs() < 1e-4);
        assert!((q(2.0).powf(q(0.5)).to_f64() - core::f64::consts::SQRT_2).abs() < 1e-4);
        let e = Q32::from_f64(1.0).exp().to_f64();
        assert!((e - core::f64::consts::E).abs() < 1e-9);
    }

    /// Every model the module docs list as supported builds and steps in
    /// both types; extreme and saturating inputs are refused or pinned,
    /// never a panic.
    #[test]
    fn supported_models_step_and_survive_extreme_inputs() {
        fn run<T: Real>() {
            let p = Polynomial::<T, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).unwrap();
            let s = MonotoneSpline::<T, 8>::new(
                &[-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0],
                &[-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0],
            )
            .unwrap();
            let cells = [MaxwellSpec::hz(0.05, 0.1), MaxwellSpec::hz(50.0, 0.1)];
            let jenkins = [IwanCellSpec::new(0.1, 1.5), IwanCellSpec::new(0.1, 6.0)];
            for form in MaxwellForm::ALL {
                let b = Bushing::new(
                    s,
                    (
                        MaxwellBank::<T, 2>::new(form, &cells, 5e-4).unwrap(),
                        IwanBank::<T, 2>::new(&jenkins).unwrap(),
                        IwanSliders::<T, 2>::new(&jenkins, 150.0).unwrap(),
                    ),
                )
                .unwrap();
                let mut st = b.state_at(T::ZERO);
                let inputs = [
                    0.5, 1.0, -2.0, 1e6, -1e6, 3.9, -3.9, 12.0, -12.0, 0.0, 1e-9, 1e30,
                ];
                for (i, &x) in inputs.iter().enumerate() {
                    let out = b.step(&mut st, T::from_f64(x));
                    assert!(out.dissipated >= T::ZERO, "{form:?} {i}");
                    assert!(out.force.abs() <= T::from_f64(2.0) * T::GUARD);
                    assert!(out.tangent >= T::ZERO);
                }
                // 1e6 mm and 1e30 saturate the backbone: refused and flagged.
                assert!(st.rejected() > 0 || T::NAME == "I32F32");
                let b = Bushing::new(p, (MaxwellBank::<T, 2>::new(form, &cells, 5e-4).unwrap(),))
                    .unwrap();
                let mut st = b.state_at(T::from_f64(1e9));
                for x in [T::from_f64(1e9), T::from_f64(-1e9), T::ZERO] {
                    let _ = b.step(&mut st, x);
                }
                let _ = p.eval(T::from_f64(-1e12));
            }
        }
        run::<Q16>();
        run::<Q32>();
    }
}
