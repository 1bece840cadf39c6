//! The rotation `e^λ (cos θ, sin θ)` that turns a mode's pairs: by the
//! polynomials, from a per-mode anchor, and for a pair of sigma points
//! from the centre's by a series.

use crate::real::Real;
use crate::tracker::fast::{exp_small, is_f32};
use crate::tracker::trig::{sin_cos, sin_cos_in_range};

/// `(e^λ cos θ, e^λ sin θ)`: one sin/cos polynomial and one exponential.
#[inline(always)]
pub(super) fn rotation<T: Real>(theta: T, lambda: T) -> (T, T) {
    let (s, c) = sin_cos(theta);
    let e = exp_small(lambda);
    (e * c, e * s)
}

/// Rotations `e^(λ ± δλ) (cos(θ ± δθ), sin(θ ± δθ))` of a pair of sigma
/// points from the centre's `(ec, es)`: `e^(±d)`, `d = δλ + iδθ`, from the
/// even and odd parts of its series, `1 + d²/2 + d⁴/24` and `d + d³/6`, when
/// `f32` and |δθ| + |δλ| <= 1/32 (truncation below |d|⁵/120 = 2.6e-10,
/// under the rounding) and θ - δθ >= 0 (θ + δθ stays below π, as θ <=
/// 0.99 π); else by the polynomials, which clamp θ into [0, π].
#[inline(always)]
pub(super) fn rotation_pair<T: Real>(
    theta: T,
    lambda: T,
    dt: T,
    dl: T,
    (ec, es): (T, T),
) -> [(T, T); 2] {
    let adt = dt.abs();
    if is_f32::<T>() && adt + dl.abs() <= T::from_f64(1.0 / 32.0) && adt <= theta {
        let (d2r, d2i) = (dl * dl - dt * dt, (dl + dl) * dt);
        let (d4r, d4i) = (d2r * d2r - d2i * d2i, (d2r + d2r) * d2i);
        let c = |k: f64| T::from_f64(1.0 / k);
        let (er, ei) = (
            T::ONE + (T::HALF * d2r + c(24.0) * d4r),
            T::HALF * d2i + c(24.0) * d4i,
        );
        let (qr, qi) = (T::ONE + c(6.0) * d2r, c(6.0) * d2i);
        let (or, oi) = (dl * qr - dt * qi, dl * qi + dt * qr);
        let turn = |(ar, ai): (T, T)| (ec * ar - es * ai, ec * ai + es * ar);
        [turn((er + or, ei + oi)), turn((er - or, ei - oi))]
    } else {
        rotation_pair_far(theta, lambda, dt, dl)
    }
}

/// [`rotation_pair`] by the polynomials (out of line: rare once the filter
/// has converged, and it keeps the callers' loops small enough to unroll).
#[cold]
#[inline(never)]
fn rotation_pair_far<T: Real>(theta: T, lambda: T, dt: T, dl: T) -> [(T, T); 2] {
    [
        rotation(theta + dt, lambda + dl),
        rotation(theta - dt, lambda - dl),
    ]
}

/// Radius in |Δθ| + |Δλ| within which a rotation is taken from an anchor.
const ANCHOR_RADIUS: f64 = 1.0 / 1024.0;

/// The anchor `[θa, λa, e^λa cos θa, e^λa sin θa]` at an estimate's (θ, λ);
/// θa is NaN (no point is near it) below twice the radius, where a sigma
/// point near it could have a negative θ, which [`rotation`] clamps.
#[inline(always)]
pub(super) fn anchor_at<T: Real>(theta: T, lambda: T) -> [T; 4] {
    let (c, s) = rotation_in_range(theta, lambda);
    let ta = if theta >= T::from_f64(2.0 * ANCHOR_RADIUS) {
        theta
    } else {
        T::from_f64(f64::NAN)
    };
    [ta, lambda, c, s]
}

/// [`anchor_at`] out of line, for the rare refresh.
#[cold]
#[inline(never)]
fn anchor_far<T: Real>(theta: T, lambda: T) -> [T; 4] {
    anchor_at(theta, lambda)
}

/// `(e^λ cos θ, e^λ sin θ)` in `f32` from an anchor when (θ, λ) is within
/// `ANCHOR_RADIUS` of it: `e^(λ + iθ) = e^(λa + iθa) e^d` with
/// `d = Δλ + iΔθ` and `e^d = 1 + d + d²/2` (the next term, below
/// |d|³/6 = 1.6e-10, is under the rounding of `f32`). About 12
/// instructions instead of about 50 for the polynomials. `None` farther
/// away and for other types.
#[inline(always)]
pub(super) fn rotation_near<T: Real>(anchor: &[T; 4], theta: T, lambda: T) -> Option<(T, T)> {
    if !is_f32::<T>() {
        return None;
    }
    let [ta, la, ca, sa] = *anchor;
    let (dt, dl) = (theta - ta, lambda - la);
    let near = dt.abs() + dl.abs() <= T::from_f64(ANCHOR_RADIUS);
    if !near {
        return None;
    }
    let er = dl + T::HALF * (dl * dl - dt * dt);
    let ei = dt + dl * dt;
    Some((ca + (ca * er - sa * ei), sa + (ca * ei + sa * er)))
}

/// A pair `(a, b)` turned by the scaled rotation `(ec, es)` (eq 3.28).
#[inline(always)]
pub(super) fn rotate<T: Real>((ec, es): (T, T), a: T, b: T) -> (T, T) {
    (ec * a - es * b, es * a + ec * b)
}

/// The rotation of an estimate's (θ, λ): from the mode's anchor when near
/// it, else by the polynomials, which become the new anchor.
#[inline(always)]
pub(super) fn rotation_cached<T: Real>(anchor: &mut [T; 4], theta: T, lambda: T) -> (T, T) {
    if let Some(r) = rotation_near(anchor, theta, lambda) {
        return r;
    }
    let a = anchor_far(theta, lambda);
    *anchor = a;
    let [_, _, c, s] = a;
    (c, s)
}

/// The same for an estimate's θ, which [`ModalTracker::step`] keeps in
/// (0, θ_max] ⊂ (0, π).
///
/// [`ModalTracker::step`]: super::ModalTracker::step
#[inline(always)]
fn rotation_in_range<T: Real>(theta: T, lambda: T) -> (T, T) {
    let (s, c) = sin_cos_in_range(theta);
    let e = exp_small(lambda);
    (e * c, e * s)
}
