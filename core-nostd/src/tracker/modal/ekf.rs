//! The extended Kalman filter: prediction with the Jacobian of the process
//! (eqs 3.27-3.28) and the innovation of one sensor with the Jacobian of
//! eqs 3.26, 3.32 and 3.33.

use super::matrix::{entry, get, put, set, set_row, sym_row};
use super::rotation::rotation_cached;
use super::{Core, Measured, ModalTracker};
use crate::real::Real;

impl<T: Real, const N: usize> ModalTracker<T, N> {
    /// EKF prediction: x = f(x), P = F P Fᵀ + Q. F is the identity on the
    /// θ and λ rows; on a pair's rows it holds the rotation `(ec, es)` and
    /// the derivatives `(-b', a')`, `(a', b')` by θ and λ. First the pair
    /// rows of F P (whole rows), then their columns on and above the
    /// diagonal; `P'[θ or λ][pair] = (F P)[pair][θ or λ]` needs no second
    /// pass. The result is mirrored, so exactly symmetric.
    #[inline(always)]
    pub(super) fn predict_ekf(&self, state: &mut Core<T, N>, anchor: &mut [[T; 4]; N]) {
        let (m_n, c_n) = (self.m_n(), self.c_n());
        let Core { x, p, .. } = state;
        let mut rot = [(T::ZERO, T::ZERO); N];
        for (m, (r, a)) in rot.iter_mut().zip(anchor.iter_mut()).enumerate().take(m_n) {
            let (ti, li) = self.theta_lambda(m);
            *r = rotation_cached(a, get(x, ti), get(x, li));
            self.rotate_mode(x, m, *r);
            let (ec, es) = *r;
            if N < 8 {
                // Copies of the rows, read from on and above the diagonal.
                let (row_t, row_l) = (sym_row(p, ti), sym_row(p, li));
                for c in 0..c_n {
                    let (ai, bi) = self.pair(m, c);
                    let (a1, b1) = (get(x, ai), get(x, bi));
                    let (ra, rb) = (sym_row(p, ai), sym_row(p, bi));
                    let (mut na, mut nb) = ([T::ZERO; N], [T::ZERO; N]);
                    for ((((na, nb), (&pa, &pb)), &pt), &pl) in na
                        .iter_mut()
                        .zip(nb.iter_mut())
                        .zip(ra.iter().zip(&rb))
                        .zip(&row_t)
                        .zip(&row_l)
                    {
                        *na = ec * pa - es * pb - b1 * pt + a1 * pl;
                        *nb = es * pa + ec * pb + a1 * pt + b1 * pl;
                    }
                    set_row(p, ai, na);
                    set_row(p, bi, nb);
                }
                continue;
            }
            // In place: the θ and λ rows come before the pair rows.
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                let (a1, b1) = (get(x, ai), get(x, bi));
                let Some((head, tail)) = p.split_at_mut_checked(ai) else {
                    continue;
                };
                let (Some(rt), Some(rl), [ra, rb, ..]) = (head.get(ti), head.get(li), tail) else {
                    continue;
                };
                for (((pa, pb), &pt), &pl) in ra.iter_mut().zip(rb.iter_mut()).zip(rt).zip(rl) {
                    let (va, vb) = (*pa, *pb);
                    *pa = ec * va - es * vb - b1 * pt + a1 * pl;
                    *pb = es * va + ec * vb + a1 * pt + b1 * pl;
                }
            }
        }
        // Columns of the pair rows, on and above the diagonal.
        for m in 0..m_n {
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                for i in [ai, bi] {
                    let Some(r) = p.get_mut(i) else { continue };
                    for (m2, &(ec, es)) in rot.iter().enumerate().take(m_n) {
                        let (ti, li) = self.theta_lambda(m2);
                        let (vt, vl) = (get(r, ti), get(r, li));
                        for c2 in 0..c_n {
                            let (aj, bj) = self.pair(m2, c2);
                            if bj < i {
                                continue;
                            }
                            let (a1, b1) = (get(x, aj), get(x, bj));
                            let (va, vb) = (get(r, aj), get(r, bj));
                            if aj >= i {
                                put(r, aj, ec * va - es * vb - b1 * vt + a1 * vl);
                            }
                            put(r, bj, es * va + ec * vb + a1 * vt + b1 * vl);
                        }
                    }
                }
            }
        }
        // Mirror: a pair row holds its final entries on and above the
        // diagonal; a θ or λ row finds its pair columns below it.
        for i in 0..N {
            if N < 8 {
                for j in i + 1..N {
                    if self.is_amplitude(i) {
                        let v = entry(p, i, j);
                        set(p, j, i, v);
                    } else if self.is_amplitude(j) {
                        let v = entry(p, j, i);
                        set(p, i, j, v);
                    }
                }
                continue;
            }
            let Some((top, bottom)) = p.split_at_mut_checked(i + 1) else {
                continue;
            };
            let Some(ri) = top.last_mut() else { continue };
            let pair_row = self.is_amplitude(i);
            for (rj, j) in bottom.iter_mut().zip(i + 1..) {
                if pair_row {
                    put(rj, i, get(ri, j));
                } else if self.is_amplitude(j) {
                    put(ri, j, get(rj, i));
                }
            }
        }
        self.add_process_noise(state);
    }

    /// EKF innovation of sensor `c`: predicted sample, `v = P hᵀ`, and
    /// `s = h P hᵀ + r`; h has four entries per mode.
    #[inline(always)]
    pub(super) fn innovation_ekf(&self, state: &Core<T, N>, c: usize, v: &mut [T; N]) -> (T, T) {
        match self.measured.get(c).copied().unwrap_or_default() {
            Measured::Displacement => self.innovation_ekf_k::<0>(state, c, v),
            Measured::Velocity => self.innovation_ekf_k::<1>(state, c, v),
            Measured::Acceleration => self.innovation_ekf_k::<2>(state, c, v),
        }
    }

    /// [`Self::innovation_ekf`] for a sensor of derivative order K.
    #[inline(always)]
    fn innovation_ekf_k<const K: u8>(
        &self,
        state: &Core<T, N>,
        c: usize,
        v: &mut [T; N],
    ) -> (T, T) {
        let m_n = self.m_n();
        let mut idx = [0usize; N];
        let mut h = [T::ZERO; N];
        let mut zhat = T::ZERO;
        for m in 0..m_n {
            let (ti, li) = self.theta_lambda(m);
            let (ai, bi) = self.pair(m, c);
            let x = &state.x;
            let (z, g) = observe::<T, K>(get(x, ti), get(x, li), get(x, ai), get(x, bi));
            zhat += z;
            for (k, (i, gi)) in [ti, li, ai, bi].into_iter().zip(g).enumerate() {
                put(&mut idx, 4 * m + k, i);
                put(&mut h, 4 * m + k, gi);
            }
        }
        let used = 4 * m_n;
        if N < 8 {
            for (i, vi) in v.iter_mut().enumerate() {
                // A copy read from on and above the diagonal.
                let row = sym_row(&state.p, i);
                // From the first product, not from zero (0 + x is not folded).
                let first = get(&row, idx.first().copied().unwrap_or(0)) * get(&h, 0);
                *vi = idx
                    .iter()
                    .zip(&h)
                    .take(used)
                    .skip(1)
                    .fold(first, |acc, (&j, &hj)| acc + get(&row, j) * hj);
            }
        } else {
            // P is symmetric: v is the sum of h_j times row j, whole rows.
            *v = [T::ZERO; N];
            for (&j, &hj) in idx.iter().zip(&h).take(used) {
                if let Some(rj) = state.p.get(j) {
                    for (vi, &pj) in v.iter_mut().zip(rj) {
                        *vi += pj * hj;
                    }
                }
            }
        }
        let mut s = get(&self.r, c);
        for (&j, &hj) in idx.iter().zip(&h).take(used) {
            s += get(v, j) * hj;
        }
        (zhat, s)
    }
}

/// Predicted sample of a sensor of derivative order K (scaled) from one
/// mode with phase step `t`, log-decay `l` and pair `(a, b)`, and its
/// gradient by (θ, λ, a, b): the real part of `(l + i t)^K (a + i b)`.
#[inline(always)]
fn observe<T: Real, const K: u8>(t: T, l: T, a: T, b: T) -> (T, [T; 4]) {
    let two = T::ONE + T::ONE;
    match K {
        0 => (a, [T::ZERO, T::ZERO, T::ONE, T::ZERO]),
        1 => (l * a - t * b, [-b, a, l, -t]),
        _ => {
            let (ca, cb) = (l * l - t * t, -two * l * t);
            (
                ca * a + cb * b,
                [-two * (t * a + l * b), two * (l * a - t * b), ca, cb],
            )
        }
    }
}
