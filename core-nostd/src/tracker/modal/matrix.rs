//! Reads and writes of the fixed-size state vector and covariance by index
//! (an index out of range reads zero and writes nothing), rows, and the
//! symmetric helpers.

use crate::real::Real;

#[inline(always)]
pub(super) fn get<T: Real>(v: &[T], i: usize) -> T {
    v.get(i).copied().unwrap_or(T::ZERO)
}

#[inline(always)]
pub(super) fn put<T>(v: &mut [T], i: usize, value: T) {
    if let Some(e) = v.get_mut(i) {
        *e = value;
    }
}

#[inline(always)]
pub(super) fn entry<T: Real, const N: usize>(p: &[[T; N]; N], i: usize, j: usize) -> T {
    p.get(i).map_or(T::ZERO, |r| get(r, j))
}

/// Row i of a matrix.
#[inline(always)]
pub(super) fn row<T: Real, const N: usize>(p: &[[T; N]; N], i: usize) -> [T; N] {
    p.get(i).copied().unwrap_or([T::ZERO; N])
}

/// Row i of a symmetric matrix; below 8 states read from the entries on
/// and above the diagonal (fewer loads once the step is inlined).
#[inline(always)]
pub(super) fn sym_row<T: Real, const N: usize>(p: &[[T; N]; N], i: usize) -> [T; N] {
    if N < 8 {
        let mut r = [T::ZERO; N];
        for (j, v) in r.iter_mut().enumerate() {
            *v = entry(p, i.min(j), i.max(j));
        }
        r
    } else {
        p.get(i).copied().unwrap_or([T::ZERO; N])
    }
}

#[inline(always)]
pub(super) fn set_row<T, const N: usize>(p: &mut [[T; N]; N], i: usize, r: [T; N]) {
    if let Some(dst) = p.get_mut(i) {
        *dst = r;
    }
}

/// Copies the entries above the diagonal to those below it. From 8 states
/// on out of line: the call is small against the copy, and the copy's
/// code (its registers) then does not depend on the step around it.
#[inline(always)]
pub(super) fn mirror_upper<T: Copy, const N: usize>(p: &mut [[T; N]; N]) {
    if N >= 8 {
        mirror_out_of_line(p);
    } else {
        mirror(p);
    }
}

#[inline(never)]
fn mirror_out_of_line<T: Copy, const N: usize>(p: &mut [[T; N]; N]) {
    mirror(p);
}

#[inline(always)]
fn mirror<T: Copy, const N: usize>(p: &mut [[T; N]; N]) {
    for i in 1..N {
        let Some((top, bottom)) = p.split_at_mut_checked(i) else {
            continue;
        };
        let Some(ri) = bottom.first_mut() else {
            continue;
        };
        for (dst, rj) in ri.iter_mut().zip(top.iter()) {
            if let Some(&v) = rj.get(i) {
                *dst = v;
            }
        }
    }
}

#[inline(always)]
pub(super) fn set<T, const N: usize>(p: &mut [[T; N]; N], i: usize, j: usize, value: T) {
    if let Some(v) = p.get_mut(i).and_then(|r| r.get_mut(j)) {
        *v = value;
    }
}

/// A zero the optimiser does not see as a constant. Stores of it stay
/// inline; a run of stores of a constant zero becomes a call of `memset`,
/// which stores a word per few instructions on a Cortex-M.
#[inline(always)]
pub(super) fn opaque_zero<T: Real>() -> T {
    core::hint::black_box(T::ZERO)
}

#[inline(always)]
pub(super) fn add_diag<T: Real, const N: usize>(p: &mut [[T; N]; N], i: usize, q: T) {
    if let Some(v) = p.get_mut(i).and_then(|r| r.get_mut(i)) {
        *v += q;
    }
}
