//! The extended Kalman filter: prediction with the Jacobian of the process
//! (eqs 3.27-3.28) and the innovation of one sensor with the Jacobian of
//! eqs 3.26, 3.32 and 3.33.

use super::matrix::{entry, get, mirror_upper, put, set, set_row, sym_row};
use super::rotation::rotation_cached;
use super::{Core, Measured, ModalTracker};
use crate::real::Real;

impl<T: Real, const N: usize, const M: usize> ModalTracker<T, N, M> {
    /// EKF prediction: x = f(x), P = F P Fᵀ + Q. F is the identity on the
    /// θ and λ rows; on a pair's rows it holds the rotation `(ec, es)` and
    /// the derivatives `(-b', a')`, `(a', b')` by θ and λ. Below 8 states
    /// (one mode, in registers): the pair rows of F P (whole rows), then
    /// their columns on and above the diagonal; `P'[θ or λ][pair] =
    /// (F P)[pair][θ or λ]` needs no second pass. From 8 on, in place and
    /// by mode blocks (the layout is `[θ, λ, a₀, b₀, a₁, b₁, …]` per mode):
    /// the pair rows of F P, then the pair columns of (F P) Fᵀ on and above
    /// the diagonal on the pair rows, then the θ and λ rows' entries above
    /// it from the pair rows below; the transforms read the θ and λ rows or columns, which
    /// they leave alone. The result is mirrored, so exactly symmetric.
    #[inline(always)]
    pub(super) fn predict_ekf(&self, state: &mut Core<T, N>, anchor: &mut [[T; 4]; N]) {
        if N >= 8 {
            self.predict_ekf_blocks(state, anchor);
            self.add_process_noise(state);
            return;
        }
        let c_n = self.c_n();
        let Core { x, p, .. } = state;
        let (ti, li) = self.theta_lambda(0);
        let Some(a) = anchor.first_mut() else { return };
        let (ec, es) = rotation_cached(a, get(x, ti), get(x, li));
        self.rotate_mode(x, 0, (ec, es));
        // Copies of the rows, read from on and above the diagonal.
        let (row_t, row_l) = (sym_row(p, ti), sym_row(p, li));
        for c in 0..c_n {
            let (ai, bi) = self.pair(0, c);
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
                (*na, *nb) = transition((ec, es), a1, b1, pa, pb, pt, pl);
            }
            set_row(p, ai, na);
            set_row(p, bi, nb);
        }
        // Pair columns on and above the diagonal.
        for c in 0..c_n {
            let (ai, bi) = self.pair(0, c);
            for i in [ai, bi] {
                let Some(r) = p.get_mut(i) else { continue };
                let (vt, vl) = (get(r, ti), get(r, li));
                for c2 in 0..c_n {
                    let (aj, bj) = self.pair(0, c2);
                    if bj < i {
                        continue;
                    }
                    let (a1, b1) = (get(x, aj), get(x, bj));
                    let (va, vb) = (get(r, aj), get(r, bj));
                    let (na, nb) = transition((ec, es), a1, b1, va, vb, vt, vl);
                    if aj >= i {
                        put(r, aj, na);
                    }
                    put(r, bj, nb);
                }
            }
        }
        // Mirror: a pair row holds its final entries on and above the
        // diagonal; a θ or λ row finds its pair columns below it.
        for i in 0..N {
            for j in i + 1..N {
                if self.is_amplitude(i) {
                    let v = entry(p, i, j);
                    set(p, j, i, v);
                } else if self.is_amplitude(j) {
                    let v = entry(p, j, i);
                    set(p, i, j, v);
                }
            }
        }
        self.add_process_noise(state);
    }

    /// [`Self::predict_ekf`] from 8 states on: x and P by mode blocks.
    #[inline(always)]
    fn predict_ekf_blocks(&self, state: &mut Core<T, N>, anchor: &mut [[T; 4]; N]) {
        let block = self.block();
        let Core { x, p, .. } = state;
        let rot = self.rotate_blocks(x, anchor);
        // Rows: a pair's rows of F P from its own rows and its mode's θ and
        // λ rows, on the columns read below: the θ and λ columns of its
        // mode and the modes before, and the columns from its own on (the
        // other entries lie below the diagonal and are replaced by the
        // mirror).
        for (m, ((rows, xm), &r)) in p
            .chunks_exact_mut(block)
            .zip(x.chunks_exact(block))
            .zip(&rot)
            .enumerate()
        {
            let first = m * block;
            let Some(([rt, rl], pairs)) = rows.split_first_chunk_mut::<2>() else {
                continue;
            };
            for (q, (pair, xp)) in pairs
                .chunks_exact_mut(2)
                .zip(xm.get(2..).unwrap_or(&[]).chunks_exact(2))
                .enumerate()
            {
                let ([ra, rb], &[a1, b1]) = (pair, xp) else {
                    continue;
                };
                for m2 in 0..=m {
                    let (t2, _) = self.theta_lambda(m2);
                    let cols = t2..t2 + 2;
                    let (Some(ca), Some(cb), Some(ct), Some(cl)) = (
                        ra.get_mut(cols.clone()),
                        rb.get_mut(cols.clone()),
                        rt.get(cols.clone()),
                        rl.get(cols),
                    ) else {
                        continue;
                    };
                    for (((pa, pb), &pt), &pl) in ca.iter_mut().zip(cb.iter_mut()).zip(ct).zip(cl) {
                        (*pa, *pb) = transition(r, a1, b1, *pa, *pb, pt, pl);
                    }
                }
                let own = first + 2 + 2 * q;
                let (Some(ra), Some(rb), Some(rt), Some(rl)) = (
                    ra.get_mut(own..),
                    rb.get_mut(own..),
                    rt.get(own..),
                    rl.get(own..),
                ) else {
                    continue;
                };
                for (((pa, pb), &pt), &pl) in ra.iter_mut().zip(rb.iter_mut()).zip(rt).zip(rl) {
                    (*pa, *pb) = transition(r, a1, b1, *pa, *pb, pt, pl);
                }
            }
        }
        // Columns of (F P) Fᵀ, a pair of columns at a time, on and above
        // the diagonal, on the pair rows only: the θ and λ rows' entries
        // are set below.
        for (m2, &r) in rot.iter().enumerate().take(self.m_n()) {
            let (tj, _) = self.theta_lambda(m2);
            for c2 in 0..self.c_n() {
                let (aj, bj) = self.pair(m2, c2);
                let (a1, b1) = (get(x, aj), get(x, bj));
                let turn = |row: &mut [T; N]| {
                    // The mode's columns from θ to this pair: θ, λ first,
                    // the pair last.
                    let seg = row.get_mut(tj..=bj).unwrap_or(&mut []);
                    let Some((&mut [vt, vl], rest)) = seg.split_first_chunk_mut::<2>() else {
                        return;
                    };
                    let Some((_, [va, vb])) = rest.split_last_chunk_mut::<2>() else {
                        return;
                    };
                    (*va, *vb) = transition(r, a1, b1, *va, *vb, vt, vl);
                };
                // Two rows a time, a pair's, down to this pair; a mode's
                // first two rows are its θ and λ (`block` is at least 2).
                let rows = p.get_mut(..=bj).unwrap_or(&mut []);
                for (k, pair) in rows.chunks_exact_mut(2).enumerate() {
                    if (2 * k) % block != 0 {
                        pair.iter_mut().for_each(turn);
                    }
                }
            }
        }
        // A θ or λ row's entries above the diagonal: F leaves its columns
        // alone, so they are the pair rows' θ and λ entries below it.
        for m in 0..self.m_n() {
            let (ti, li) = self.theta_lambda(m);
            for i in [ti, li] {
                let Some((top, bottom)) = p.split_at_mut_checked(i + 1) else {
                    continue;
                };
                let Some(ri) = top.last_mut() else { continue };
                for (rj, j) in bottom.iter().zip(i + 1..) {
                    put(ri, j, get(rj, i));
                }
            }
        }
        mirror_upper(p);
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
        } else if M > 0 {
            // The observed states known at compile time: each v_i a
            // register, summed over its column's observed entries in the
            // order of the whole-row sums below (from zero), so the same
            // numbers. The observed rows are looked up once, not per entry
            // (P is symmetric: row j holds column j), through indices the
            // optimiser does not see as constants: with the θ and λ rows'
            // addresses known, it loads their entries ahead of the sums and
            // spills them to the stack (about 450 instructions a step with
            // 2 modes on 3 sensors on a Cortex-M4F).
            let Some(first) = state.p.first() else {
                return (zhat, T::ZERO);
            };
            let mut rows = [first; N];
            let idx = core::hint::black_box(idx);
            for (r, &j) in rows.iter_mut().zip(&idx).take(used) {
                if let Some(rj) = state.p.get(j) {
                    *r = rj;
                }
            }
            for (i, vi) in v.iter_mut().enumerate() {
                let mut acc = T::ZERO;
                for (r, &hj) in rows.iter().zip(&h).take(used) {
                    acc += get(*r, i) * hj;
                }
                *vi = acc;
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

/// The two entries of a pair's rows (or columns) of F times a column (or
/// row): the rotation of `(pa, pb)` and the θ and λ derivatives of the
/// rotated pair `(a1, b1)` times `(pt, pl)`.
#[inline(always)]
fn transition<T: Real>((ec, es): (T, T), a1: T, b1: T, pa: T, pb: T, pt: T, pl: T) -> (T, T) {
    (
        ec * pa - es * pb - b1 * pt + a1 * pl,
        es * pa + ec * pb + a1 * pt + b1 * pl,
    )
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
