//! How a cell stores its force: plainly, or with a compensation term.

use crate::real::Real;
use core::fmt::Debug;

/// Storage of one recursive state that is updated by small increments.
///
/// A slow Maxwell cell (ω·dt = 1e-6) decays by a millionth of its value per
/// step. In `f32` that decrement is only 8 to 17 units in the last place of
/// the state, so rounding it to whole units biases the decay rate by up to
/// ~0.1 % at ω·dt = 1e-6 and by 20 % at ω·dt = 1e-7. [`Compensated`] keeps
/// the rounding error of every update in a second word (Fast2Sum) and feeds
/// it back into the next one, which makes the decay rate exact to the
/// precision of the coefficients (4e-8 relative at ω·dt = 1e-6 in `f32`) for
/// three more additions per cell.
pub trait Accumulator<T: Real>: Copy + Default + Debug + PartialEq {
    /// Current value.
    fn value(self) -> T;
    /// Adds `inc` to the value.
    fn add(&mut self, inc: T);
    /// One relaxation step `F ← F - d F + inc`, where `keep = 1 - d` is
    /// the same pole given as a product: each storage uses the one it
    /// needs (the decrement `d F` by default, which keeps a slow cell's
    /// decay rate in `f32`).
    #[inline(always)]
    fn relax(&mut self, keep: T, decay: T, inc: T) {
        let _ = keep;
        let old = self.value();
        self.add(inc - decay * old);
    }
}

/// One word updated as `F ← e^{-h} F + inc`: the textbook recurrence, one
/// subtraction cheaper than [`Plain`], for cells that are not slow.
///
/// In `f32` the pole `e^{-h}` rounds to a multiple of 2^-24 below 1, so a
/// slow cell loses its decay rate: 6 % at ω·dt = 1e-6, and a cell with
/// ω·dt below 3e-8 stops relaxing altogether (the pole rounds to 1). Use it
/// when every ω·dt of the bank is above about 1e-3 (0.2 % rate error
/// bound from the pole's rounding: 2^-25 / h).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Multiplied<T>(pub T);

impl<T: Real> Accumulator<T> for Multiplied<T> {
    #[inline(always)]
    fn value(self) -> T {
        self.0
    }
    #[inline(always)]
    fn add(&mut self, inc: T) {
        self.0 += inc;
    }
    #[inline(always)]
    fn relax(&mut self, keep: T, _decay: T, inc: T) {
        self.0 = keep * self.0 + inc;
    }
}

/// One word; the sum is rounded at every update.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Plain<T>(pub T);

impl<T: Real> Accumulator<T> for Plain<T> {
    #[inline(always)]
    fn value(self) -> T {
        self.0
    }
    #[inline(always)]
    fn add(&mut self, inc: T) {
        self.0 += inc;
    }
}

/// Two words: the value is `hi + lo`, `lo` holding what rounding `hi` lost.
///
/// The update is Fast2Sum (Dekker 1971), exact when `|hi| >= |lo + inc|`,
/// which is the case that matters (small increments on a large state); when
/// it does not hold, the error kept in `lo` is still within one rounding of
/// `hi`, as with [`Plain`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Compensated<T> {
    hi: T,
    lo: T,
}

impl<T: Real> Accumulator<T> for Compensated<T> {
    #[inline(always)]
    fn value(self) -> T {
        self.hi + self.lo
    }
    #[inline(always)]
    fn add(&mut self, inc: T) {
        let y = self.lo + inc;
        let t = self.hi + y;
        self.lo = y - (t - self.hi);
        self.hi = t;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decay rate error of F <- F - d F over `n` steps, relative.
    fn decay_rate_error<A: Accumulator<f32>>(h: f64, n: usize) -> f64 {
        let d = -libm::expm1(-h) as f32;
        let mut acc = A::default();
        acc.add(1.0);
        for _ in 0..n {
            let v = acc.value();
            acc.add(-d * v);
        }
        -(acc.value() as f64).ln() / (n as f64 * h) - 1.0
    }

    #[test]
    fn compensated_f32_decay_is_exact_where_plain_drifts() {
        for h in [1e-6, 1e-7] {
            let e = decay_rate_error::<Compensated<f32>>(h, 200_000);
            assert!(e.abs() < 1e-6, "compensated, h = {h}: {e}");
        }
        // The plain state is measurably biased at 1e-7 (this is why the
        // compensated form exists).
        let e = decay_rate_error::<Plain<f32>>(1e-7, 200_000);
        assert!(e.abs() > 1e-2, "plain, h = 1e-7: {e}");
    }
}
