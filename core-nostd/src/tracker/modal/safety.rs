//! What keeps the state usable after an update: θ and λ in their bands,
//! the covariance floor, fading, loosening, and the finiteness check
//! behind the undo.

use super::matrix::{entry, get, opaque_zero, put, set};
use super::{Core, Measured, ModalTracker};
use crate::real::Real;
use crate::tracker::fast::clamp;

impl<T: Real, const N: usize, const M: usize> ModalTracker<T, N, M> {
    /// θ and λ into their bands, the diagonal above its floor.
    #[inline(always)]
    pub(super) fn constrain(&self, state: &mut Core<T, N>) {
        for m in 0..self.m_n() {
            let (ti, li) = self.theta_lambda(m);
            // One comparison each when well inside the band (NaN fails it).
            let t = get(&state.x, ti);
            let inside = (t - self.theta_mid).abs() <= self.theta_half;
            if !inside {
                cold();
                put(&mut state.x, ti, clamp(t, self.theta_min, self.theta_max));
            }
            let l = get(&state.x, li);
            let inside = l.abs() <= self.lambda_half;
            if !inside {
                cold();
                put(&mut state.x, li, clamp(l, self.lambda_min, self.lambda_max));
            }
        }
        for (i, (row, &floor)) in state.p.iter_mut().zip(&self.floor).enumerate() {
            if let Some(v) = row.get_mut(i)
                && *v < floor
            {
                cold();
                *v = floor;
            }
        }
    }

    /// Marks modes faded or back, keeps a faded mode's amplitudes loose and
    /// gives a returning mode's ω and σ their start uncertainty.
    #[inline(always)]
    pub(super) fn fade(&self, state: &mut Core<T, N>) {
        for m in 0..self.m_n() {
            let (ti, li) = self.theta_lambda(m);
            let (t, l) = (get(&state.x, ti), get(&state.x, li));
            let rate2 = t * t + l * l;
            let was = state.faded.get(m).copied().unwrap_or(false);
            // Faded: stays so unless above the upper threshold at a sensor;
            // not faded: fades when below the lower one at every sensor.
            let mut now = true;
            for c in 0..self.c_n() {
                if !was && !now {
                    break;
                }
                let (ai, bi) = self.pair(m, c);
                let (a, b) = (get(&state.x, ai), get(&state.x, bi));
                let mut amp2 = a * a + b * b;
                match self.measured.get(c).copied().unwrap_or_default() {
                    Measured::Displacement => {}
                    Measured::Velocity => amp2 *= rate2,
                    Measured::Acceleration => {
                        amp2 *= rate2;
                        amp2 *= rate2;
                    }
                }
                let still = if was {
                    let above = amp2 > get(&self.fade_above, c);
                    !above
                } else {
                    amp2 < get(&self.fade_below, c)
                };
                now &= still;
            }
            if !now && !was {
                continue;
            }
            cold();
            put(&mut state.faded, m, now);
            if now {
                self.loosen_amplitudes(state, Some(m));
            } else if was {
                // Back: the frequency and damping may have moved while the
                // mode was gone, so they are as uncertain as at the start.
                self.loosen(state, ti);
                self.loosen(state, li);
            }
        }
    }

    /// Raises the amplitude variances of mode `m` (or of every mode) to their
    /// start values and drops their correlations.
    #[inline(always)]
    pub(super) fn loosen_amplitudes(&self, state: &mut Core<T, N>, mode: Option<usize>) {
        for m in 0..self.m_n() {
            if mode.is_some_and(|x| x != m) {
                continue;
            }
            for c in 0..self.c_n() {
                let (ai, bi) = self.pair(m, c);
                self.loosen(state, ai);
                self.loosen(state, bi);
            }
        }
    }

    /// Raises the variance of state `i` to its start value, if below, and
    /// drops its correlations.
    #[inline(always)]
    fn loosen(&self, state: &mut Core<T, N>, i: usize) {
        let p0 = get(&self.p0, i);
        if entry(&state.p, i, i) < p0 {
            // The whole row and column, the diagonal set last. From 8
            // states on the row's stores stay inline with an opaque zero
            // (below, the loop is unrolled with the plain one).
            let zero = if N >= 8 { opaque_zero() } else { T::ZERO };
            if let Some(row) = state.p.get_mut(i) {
                for v in row.iter_mut() {
                    *v = zero;
                }
            }
            for row in state.p.iter_mut() {
                put(row, i, zero);
            }
            set(&mut state.p, i, i, p0);
        }
    }
}

/// True when the estimate and the covariance are finite: their sum is,
/// unless a huge finite entry overflowed it, which the entry-wise check
/// then tells apart.
#[inline(always)]
pub(super) fn all_finite<T: Real, const N: usize>(state: &Core<T, N>) -> bool {
    let mut acc = state.x.first().copied().unwrap_or(T::ZERO);
    for v in state.x.iter().skip(1) {
        acc += *v;
    }
    for (i, row) in state.p.iter().enumerate() {
        if N < 8 {
            for v in row.iter().skip(i) {
                acc += *v;
            }
        } else {
            for v in row.get(i..).unwrap_or(&[]) {
                acc += *v;
            }
        }
    }
    acc.is_finite()
        || (state.x.iter().all(|v| v.is_finite())
            && state.p.iter().all(|r| r.iter().all(|v| v.is_finite())))
}

/// Marks the path that calls it as rare, so that the optimiser branches
/// around it rather than computing it into selects.
#[cold]
#[inline(never)]
pub(super) fn cold() {}
