//! The unscented Kalman filter: the factorisation with θ and λ first, the
//! prediction and the innovation of one sensor, the amplitude columns in
//! closed form (see the module docs of `modal`).

use super::matrix::{entry, get, mirror_upper, put, row, set, set_row, sym_row};
use super::rotation::{rotate, rotation_cached, rotation_pair};
use super::{Core, ModalTracker};
use crate::real::Real;
use crate::tracker::fast::{min_positive, rsqrt};

/// Working array of a UKF step from 8 states on, zeroed once per step and
/// written before it is read: the factor's θ and λ columns (one row each),
/// shared by the prediction and every innovation. Below 8 states the step
/// keeps its two columns in registers and the array is optimised away.
pub(super) struct Scratch<T, const N: usize> {
    cols: [[T; N]; N],
}

impl<T: Real, const N: usize> Scratch<T, N> {
    pub(super) fn new() -> Self {
        Self {
            cols: [[T::ZERO; N]; N],
        }
    }
}

impl<T: Real, const N: usize, const M: usize> ModalTracker<T, N, M> {
    /// UKF prediction. With θ and λ factored first, the sigma points of the
    /// amplitude columns `x ± γ l_t` share the centre's θ and λ, so the
    /// process moves them linearly: `f(x) ± γ R l_t`, R the centre's
    /// rotations. Their 2(n - 2 modes) points then add `2 W_i` times the
    /// centre's deviation each (folded into the centre weights) and, as
    /// `2 W_i γ² = 1`, exactly `R S Rᵀ` to the covariance, S the amplitude
    /// covariance given θ and λ. Only the 4 modes points of the θ and λ
    /// columns go through the rotation polynomials. The result is the scaled
    /// unscented transform with this square root of P, not an approximation.
    /// From 8 states on, [`Self::predict_ukf_blocks`]. False if P is not
    /// positive definite.
    #[inline(always)]
    pub(super) fn predict_ukf(
        &self,
        state: &mut Core<T, N>,
        anchor: &mut [[T; 4]; N],
        scratch: &mut Scratch<T, N>,
    ) -> bool {
        if N >= 8 {
            return self.predict_ukf_blocks(state, anchor, scratch);
        }
        let mut cols = [[T::ZERO; N]; 2];
        let mut schur = [[T::ZERO; N]; N];
        if !factor_natural(&state.p, &mut cols, &mut schur) {
            return false;
        }
        let (m_n, k_n) = (self.m_n(), 2 * self.m_n());
        let w = self.ut;
        let x = state.x;
        let mut rot = [(T::ZERO, T::ZERO); N];
        let mut f0 = x;
        for (m, (r, a)) in rot.iter_mut().zip(anchor.iter_mut()).enumerate().take(m_n) {
            let (ti, li) = self.theta_lambda(m);
            *r = rotation_cached(a, get(&x, ti), get(&x, li));
            self.rotate_mode(&mut f0, m, *r);
        }
        // The θ and λ columns: column t is zero on the θ and λ of the
        // modes before mode t/2, whose rotation is then the centre's.
        let mut plus = [[T::ZERO; N]; N];
        let mut minus = [[T::ZERO; N]; N];
        for (t, ((l, xp), xm)) in cols
            .iter()
            .zip(plus.iter_mut())
            .zip(minus.iter_mut())
            .take(k_n)
            .enumerate()
        {
            for (((p, n), &xi), &li) in xp.iter_mut().zip(xm.iter_mut()).zip(&x).zip(l) {
                let d = w.spread * li;
                *p = xi + d;
                *n = xi - d;
            }
            for (m, &r) in rot.iter().enumerate().take(m_n) {
                let (rp, rn) = if 2 * m + 1 >= t {
                    let (ti, li) = self.theta_lambda(m);
                    let g = w.spread;
                    let [rp, rn] =
                        rotation_pair(get(&x, ti), get(&x, li), g * get(l, ti), g * get(l, li), r);
                    (rp, rn)
                } else {
                    (r, r)
                };
                self.rotate_mode(xp, m, rp);
                self.rotate_mode(xm, m, rn);
            }
        }
        let mut mean = [T::ZERO; N];
        for (i, m) in mean.iter_mut().enumerate() {
            let mut acc = T::ZERO;
            for (xp, xm) in plus.iter().zip(&minus).take(k_n) {
                acc += get(xp, i) + get(xm, i);
            }
            *m = w.centre_mean * get(&f0, i) + w.wi * acc;
        }
        let mut d0 = f0;
        for (d, m) in d0.iter_mut().zip(&mean) {
            *d -= *m;
        }
        for (xp, xm) in plus.iter_mut().zip(minus.iter_mut()).take(k_n) {
            for ((p, n), m) in xp.iter_mut().zip(xm.iter_mut()).zip(&mean) {
                *p -= *m;
                *n -= *m;
            }
        }
        let p = &mut state.p;
        for i in 0..N {
            let di = get(&d0, i);
            for j in 0..N {
                if j < i {
                    continue;
                }
                let mut acc = T::ZERO;
                for (xp, xm) in plus.iter().zip(&minus).take(k_n) {
                    acc += get(xp, i) * get(xp, j) + get(xm, i) * get(xm, j);
                }
                let v = w.centre_cov * di * get(&d0, j) + w.wi * acc;
                set(p, i, j, v);
                set(p, j, i, v);
            }
        }
        self.add_rotated(p, &schur, &rot);
        state.x = mean;
        self.add_process_noise(state);
        true
    }

    /// [`Self::predict_ukf`] from 8 states on, by mode blocks. Only the θ
    /// and λ pivots are eliminated: their columns of the factor
    /// ([`Self::leading_columns`]) and, in a copy of P, S =
    /// `P - Σ_t l_t l_tᵀ` on the amplitude rows. With `D` the
    /// deviations of the θ and λ columns' sigma points from the propagated
    /// centre `f(x)` (for a mode whose θ and λ the column leaves alone,
    /// exactly `±γ R l_t`, so computed) and `δ = W_i Σ D`, the mean is
    /// `f(x) + δ` and the covariance
    /// `W_i Σ_t (D⁺ D⁺ᵀ + D⁻ D⁻ᵀ) + (β - α²) δ δᵀ + R S Rᵀ`: the same
    /// transform as with the deviations from the mean (tested against all
    /// 2n + 1 points), without a difference of two nearly equal sums; the
    /// δδᵀ term is folded into the deviations, as `D - c δ`.
    /// Once `R S Rᵀ` is formed, the amplitude block of S is factored in
    /// place, which checks that P is positive definite (false if not), and
    /// the copy then holds the deviations.
    #[inline(always)]
    fn predict_ukf_blocks(
        &self,
        state: &mut Core<T, N>,
        anchor: &mut [[T; 4]; N],
        scratch: &mut Scratch<T, N>,
    ) -> bool {
        let (m_n, k_n, block) = (self.m_n(), 2 * self.m_n(), self.block());
        let w = self.ut;
        let cols = &mut scratch.cols;
        // The θ and λ columns of the factor, then S on the amplitude rows:
        // `P - Σ_t l_t l_tᵀ`, subtracted in the order of t, each row from
        // the diagonal of its amplitude pair's first row (what lies before
        // is never read); then zero on the θ and λ columns of those rows.
        if !self.leading_columns(&state.p, cols) {
            return false;
        }
        let mut s = state.p;
        let leading = cols.get(..k_n).unwrap_or(&[]);
        for (i, row) in s.iter_mut().enumerate() {
            let from = i & !1;
            let (true, Some(row)) = (self.is_amplitude(i), row.get_mut(from..)) else {
                continue;
            };
            let tail = |l| from_on(l, from).iter();
            let mut quads = leading.chunks_exact(4);
            for quad in &mut quads {
                let [l0, l1, l2, l3] = quad else { continue };
                let (a0, a1, a2, a3) = (get(l0, i), get(l1, i), get(l2, i), get(l3, i));
                let ls = tail(l0).zip(tail(l1)).zip(tail(l2)).zip(tail(l3));
                for (v, (((&b0, &b1), &b2), &b3)) in row.iter_mut().zip(ls) {
                    *v = (((*v - a0 * b0) - a1 * b1) - a2 * b2) - a3 * b3;
                }
            }
            if let [l0, l1] = quads.remainder() {
                let (a0, a1) = (get(l0, i), get(l1, i));
                for (v, (&b0, &b1)) in row.iter_mut().zip(tail(l0).zip(tail(l1))) {
                    *v = (*v - a0 * b0) - a1 * b1;
                }
            }
        }
        for (i, row) in s.iter_mut().enumerate() {
            if self.is_amplitude(i) {
                for m in 0..m_n {
                    let (ti, li) = self.theta_lambda(m);
                    put(row, ti, T::ZERO);
                    put(row, li, T::ZERO);
                }
            }
        }
        let x = state.x;
        let mut f0 = x;
        let rot = self.rotate_blocks(&mut f0, anchor);
        let p = &mut state.p;
        // R S Rᵀ: the pair rows of S turned (θ and λ rows zero), both from
        // the first one's diagonal (what lies before is replaced by the
        // mirror), then the pair columns on and above the diagonal.
        for (first, ((rows, srows), &r)) in p
            .chunks_exact_mut(block)
            .zip(s.chunks_exact(block))
            .zip(&rot)
            .enumerate()
            .map(|(m, blocks)| (m * block, blocks))
        {
            let Some(([rt, rl], pairs)) = rows.split_first_chunk_mut::<2>() else {
                continue;
            };
            *rt = [T::ZERO; N];
            *rl = [T::ZERO; N];
            let spairs = srows.get(2..).unwrap_or(&[]);
            let rows = pairs.chunks_exact_mut(2).zip(spairs.chunks_exact(2));
            for ((pair, spair), from) in rows.zip((first + 2..).step_by(2)) {
                if let ([ra, rb], [sa, sb]) = (pair, spair) {
                    let dst = ra.iter_mut().skip(from).zip(rb.iter_mut().skip(from));
                    for ((pa, pb), (&va, &vb)) in
                        dst.zip(from_on(sa, from).iter().zip(from_on(sb, from)))
                    {
                        (*pa, *pb) = rotate(r, va, vb);
                    }
                }
            }
        }
        for (m2, &r) in rot.iter().enumerate().take(m_n) {
            for c2 in 0..self.c_n() {
                let (aj, bj) = self.pair(m2, c2);
                for row in p.iter_mut().take(bj + 1) {
                    if let Some([va, vb]) = row.get_mut(aj..=bj) {
                        (*va, *vb) = rotate(r, *va, *vb);
                    }
                }
            }
        }
        // S is used; its factorisation checks that P is positive definite
        // (P is reset when the step is refused), and its rows then hold the
        // deviations of the θ and λ columns' sigma points, rows 2t (plus)
        // and 2t + 1 (minus), each written whole.
        if !self.amplitudes_definite(&mut s) {
            return false;
        }
        let dev = &mut s;
        let g = w.spread;
        let mut delta = [T::ZERO; N];
        for (t, (l, pm)) in cols
            .iter()
            .zip(dev.chunks_exact_mut(2))
            .take(k_n)
            .enumerate()
        {
            let [dp, dm] = pm else { continue };
            let modes = dp
                .chunks_exact_mut(block)
                .zip(dm.chunks_exact_mut(block))
                .zip(l.chunks_exact(block))
                .zip(x.chunks_exact(block).zip(f0.chunks_exact(block)))
                .zip(&rot);
            for (m, ((((dpm, dmm), lm), (xm, fm)), &r)) in modes.enumerate() {
                let (Some(([dpt, dpl], dpp)), Some(([dmt, dml], dmp))) = (
                    dpm.split_first_chunk_mut::<2>(),
                    dmm.split_first_chunk_mut::<2>(),
                ) else {
                    continue;
                };
                let (Some((&[lt, ll], lp)), Some((&[xt, xl], xp)), Some((_, fp))) = (
                    lm.split_first_chunk::<2>(),
                    xm.split_first_chunk::<2>(),
                    fm.split_first_chunk::<2>(),
                ) else {
                    continue;
                };
                let (dt, dl) = (g * lt, g * ll);
                // θ and λ offsets as the sigma points hold them, (θ + γl) -
                // θ rather than γl: the rounding of θ ± γl belongs to the
                // points propagated, and without it the covariance drifts
                // indefinite in f32 over long runs (`tracker_endurance`).
                (*dpt, *dpl) = ((xt + dt) - xt, (xl + dl) - xl);
                (*dmt, *dml) = ((xt - dt) - xt, (xl - dl) - xl);
                let pairs = dpp
                    .chunks_exact_mut(2)
                    .zip(dmp.chunks_exact_mut(2))
                    .zip(lp.chunks_exact(2))
                    .zip(xp.chunks_exact(2).zip(fp.chunks_exact(2)));
                if 2 * m + 1 >= t {
                    let [rp, rn] = rotation_pair(xt, xl, dt, dl, r);
                    for (((dpp, dmp), lp), (xp, fp)) in pairs {
                        if let ([pa, pb], [na, nb], &[la, lb], &[a, b], &[fa, fb]) =
                            (dpp, dmp, lp, xp, fp)
                        {
                            let (da, db) = (g * la, g * lb);
                            let (ya, yb) = rotate(rp, a + da, b + db);
                            (*pa, *pb) = (ya - fa, yb - fb);
                            let (ya, yb) = rotate(rn, a - da, b - db);
                            (*na, *nb) = (ya - fa, yb - fb);
                        }
                    }
                } else {
                    for ((dpp, dmp), lp) in pairs.map(|(d, _)| d) {
                        if let ([pa, pb], [na, nb], &[la, lb]) = (dpp, dmp, lp) {
                            let (ua, ub) = rotate(r, g * la, g * lb);
                            (*pa, *pb, *na, *nb) = (ua, ub, -ua, -ub);
                        }
                    }
                }
            }
            for ((d, &a), &b) in delta.iter_mut().zip(dp.iter()).zip(dm.iter()) {
                *d += a + b;
            }
        }
        for d in delta.iter_mut() {
            *d *= w.wi;
        }
        // D - c δ: the products of these alone are the covariance (see
        // `construct::deviation_shift`).
        for d in dev.iter_mut().take(2 * k_n) {
            for (v, &dj) in d.iter_mut().zip(&delta) {
                *v -= w.shift * dj;
            }
        }
        // The sigma points' products on and above the diagonal, mirrored:
        // two rows at a time, both from the first one's diagonal (the
        // entries below it are replaced by the mirror), so that each
        // deviation entry loaded serves both.
        let quads = dev.get(..4 * m_n).unwrap_or(&[]);
        for (i, rows) in p.chunks_exact_mut(2).enumerate().map(|(h, r)| (2 * h, r)) {
            let [r0, r1] = rows else { continue };
            let (Some(r0), Some(r1)) = (r0.get_mut(i..), r1.get_mut(i..)) else {
                continue;
            };
            let f = |d: &[T; N]| (w.wi * get(d, i), w.wi * get(d, i + 1));
            let tail = |d| from_on(d, i).iter();
            // Two modes' four deviations (θ and λ, plus and minus) at a
            // time, each mode's sum added in turn; then a last odd mode.
            let mut pairs = quads.chunks_exact(8);
            for octet in &mut pairs {
                let [d0, d1, d2, d3, e0, e1, e2, e3] = octet else {
                    continue;
                };
                let ((k0, h0), (k1, h1), (k2, h2), (k3, h3)) = (f(d0), f(d1), f(d2), f(d3));
                let ((g0, j0), (g1, j1), (g2, j2), (g3, j3)) = (f(e0), f(e1), f(e2), f(e3));
                let ds = tail(d0).zip(tail(d1)).zip(tail(d2)).zip(tail(d3));
                let es = tail(e0).zip(tail(e1)).zip(tail(e2)).zip(tail(e3));
                for (((v0, v1), (((&a, &b), &c), &d)), (((&p, &q), &r), &u)) in
                    r0.iter_mut().zip(r1.iter_mut()).zip(ds).zip(es)
                {
                    *v0 = (*v0 + (k0 * a + k1 * b + k2 * c + k3 * d))
                        + (g0 * p + g1 * q + g2 * r + g3 * u);
                    *v1 = (*v1 + (h0 * a + h1 * b + h2 * c + h3 * d))
                        + (j0 * p + j1 * q + j2 * r + j3 * u);
                }
            }
            if let [d0, d1, d2, d3] = pairs.remainder() {
                let ((k0, h0), (k1, h1), (k2, h2), (k3, h3)) = (f(d0), f(d1), f(d2), f(d3));
                let ds = tail(d0).zip(tail(d1)).zip(tail(d2)).zip(tail(d3));
                for ((v0, v1), (((&a, &b), &c), &d)) in r0.iter_mut().zip(r1.iter_mut()).zip(ds) {
                    *v0 += k0 * a + k1 * b + k2 * c + k3 * d;
                    *v1 += h0 * a + h1 * b + h2 * c + h3 * d;
                }
            }
        }
        mirror_upper(p);
        for (xi, (&fi, &di)) in state.x.iter_mut().zip(f0.iter().zip(&delta)) {
            *xi = fi + di;
        }
        self.add_process_noise(state);
        true
    }

    /// True if the amplitude block of `s` (symmetric, zero on the θ and λ
    /// columns of its amplitude rows) is positive definite: its Cholesky
    /// factorisation in place, on and above the diagonal, every pivot
    /// usable. The amplitudes come in pairs (a, a + 1), and so are taken:
    /// the pair's two pivots in turn, its rows scaled into the factor's
    /// l and m, then each later pair of rows less both products at once,
    /// `(v - l_i l_j) - m_i m_j`, the numbers of one pivot after the other
    /// with half the loads and stores. The last pair needs only its
    /// pivots. Rows are updated from the multiple of 4 at or below the
    /// diagonal; what lies before it is not used.
    #[inline(always)]
    fn amplitudes_definite(&self, s: &mut [[T; N]; N]) -> bool {
        let k_n = 2 * self.m_n();
        let pairs = N.saturating_sub(k_n) / 2;
        for q in 0..pairs {
            let a = self.pivot(k_n + 2 * q);
            let Some((top, below)) = s.split_at_mut_checked(a + 2) else {
                return false;
            };
            let Some([ra, rb]) = top.last_chunk_mut::<2>() else {
                return false;
            };
            let d = get(ra, a);
            if !pivot_ok(d) {
                return false;
            }
            let r = rsqrt(d);
            let lb = get(ra, a + 1) * r;
            if q + 1 == pairs {
                return pivot_ok(get(rb, a + 1) - lb * lb);
            }
            let from = a & !3;
            let (Some(ta), Some(tb)) = (ra.get_mut(from..), rb.get_mut(from..)) else {
                return false;
            };
            for (va, vb) in ta.iter_mut().zip(tb.iter_mut()) {
                let l = *va * r;
                *va = l;
                *vb -= lb * l;
            }
            let d = get(tb, a + 1 - from);
            if !pivot_ok(d) {
                return false;
            }
            let r = rsqrt(d);
            for v in tb.iter_mut() {
                *v *= r;
            }
            let (l, m) = (&*ra, &*rb);
            for (rows, i) in below.chunks_exact_mut(2).zip((a + 2..).step_by(2)) {
                let ([ri, rj], true) = (rows, self.is_amplitude(i)) else {
                    continue;
                };
                let from = i & !3;
                let (li, lj, mi, mj) = (get(l, i), get(l, i + 1), get(m, i), get(m, i + 1));
                let cols = from_on(l, from).iter().zip(from_on(m, from));
                let (Some(ri), Some(rj)) = (ri.get_mut(from..), rj.get_mut(from..)) else {
                    continue;
                };
                for ((vi, vj), (&lc, &mc)) in ri.iter_mut().zip(rj.iter_mut()).zip(cols) {
                    *vi = (*vi - li * lc) - mi * mc;
                    *vj = (*vj - lj * lc) - mj * mc;
                }
            }
        }
        true
    }

    /// `p += R S Rᵀ` on the amplitude block, R the rotation of each mode's
    /// pairs: first the rows, then the columns on and above the diagonal,
    /// mirrored.
    #[inline(always)]
    fn add_rotated(&self, p: &mut [[T; N]; N], s: &[[T; N]; N], rot: &[(T, T); N]) {
        let (m_n, c_n) = (self.m_n(), self.c_n());
        let mut rs = [[T::ZERO; N]; N];
        for (m, &(ec, es)) in rot.iter().enumerate().take(m_n) {
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                let (sa, sb) = (sym_row(s, ai), sym_row(s, bi));
                let (mut na, mut nb) = ([T::ZERO; N], [T::ZERO; N]);
                for (j, (na, nb)) in na.iter_mut().zip(nb.iter_mut()).enumerate() {
                    if self.is_amplitude(j) {
                        let (va, vb) = (get(&sa, j), get(&sb, j));
                        (*na, *nb) = rotate((ec, es), va, vb);
                    }
                }
                set_row(&mut rs, ai, na);
                set_row(&mut rs, bi, nb);
            }
        }
        for m in 0..m_n {
            for c in 0..c_n {
                let (ai, bi) = self.pair(m, c);
                for i in [ai, bi] {
                    let r = row(&rs, i);
                    for (m2, &(ec, es)) in rot.iter().enumerate().take(m_n) {
                        for c2 in 0..c_n {
                            let (aj, bj) = self.pair(m2, c2);
                            if bj < i {
                                continue;
                            }
                            let (va, vb) = (get(&r, aj), get(&r, bj));
                            let (ra, rb) = rotate((ec, es), va, vb);
                            if aj >= i {
                                let v = entry(p, i, aj) + ra;
                                set(p, i, aj, v);
                                set(p, aj, i, v);
                            }
                            let v = entry(p, i, bj) + rb;
                            set(p, i, bj, v);
                            set(p, bj, i, v);
                        }
                    }
                }
            }
        }
    }

    /// UKF innovation of sensor `c` with sigma points redrawn from the
    /// current estimate: predicted sample, `v = Pxz`, `s = Pzz + r`. As in
    /// the prediction, the amplitude columns see the sensor's linear
    /// coefficients H at the centre (`z = H x` for fixed θ, λ) and add
    /// exactly `H S Hᵀ` to Pzz and `S Hᵀ` to Pxz; only the θ and λ columns
    /// are observed point by point.
    #[inline(always)]
    pub(super) fn innovation_ukf(
        &self,
        state: &Core<T, N>,
        c: usize,
        v: &mut [T; N],
        scratch: &mut Scratch<T, N>,
    ) -> Option<(T, T)> {
        // The θ and λ columns, and the amplitude covariance given θ and λ
        // below 8 states (where the scratch is not used).
        let mut natural = [[T::ZERO; N]; 2];
        let (schur, cols): (_, &[[T; N]]) = if N < 8 {
            let mut schur = [[T::ZERO; N]; N];
            if !factor_natural(&state.p, &mut natural, &mut schur) {
                return None;
            }
            (Some(schur), &natural)
        } else if self.leading_columns(&state.p, &mut scratch.cols) {
            (None, &scratch.cols)
        } else {
            return None;
        };
        let (m_n, k_n) = (self.m_n(), 2 * self.m_n());
        let w = self.ut;
        let x = &state.x;
        let mut h = [(T::ZERO, T::ZERO); N];
        let mut z0 = T::ZERO;
        for (m, hm) in h.iter_mut().enumerate().take(m_n) {
            let (ti, li) = self.theta_lambda(m);
            let (ai, bi) = self.pair(m, c);
            *hm = self.coefficients(c, get(x, ti), get(x, li));
            z0 += hm.0 * get(x, ai) + hm.1 * get(x, bi);
        }
        let mut zp = [T::ZERO; N];
        let mut zm = [T::ZERO; N];
        let mut sum = T::ZERO;
        for ((l, zp), zm) in cols.iter().zip(zp.iter_mut()).zip(zm.iter_mut()).take(k_n) {
            let (mut a, mut b) = (T::ZERO, T::ZERO);
            for m in 0..m_n {
                let (ti, li) = self.theta_lambda(m);
                let (ai, bi) = self.pair(m, c);
                let g = w.spread;
                let (dt, dl) = (g * get(l, ti), g * get(l, li));
                let (da, db) = (g * get(l, ai), g * get(l, bi));
                let (t0, l0, a0, b0) = (get(x, ti), get(x, li), get(x, ai), get(x, bi));
                let (hp, hq) = self.coefficients(c, t0 + dt, l0 + dl);
                a += hp * (a0 + da) + hq * (b0 + db);
                let (hp, hq) = self.coefficients(c, t0 - dt, l0 - dl);
                b += hp * (a0 - da) + hq * (b0 - db);
            }
            *zp = a;
            *zm = b;
            sum += a + b;
        }
        let zhat = w.centre_mean * z0 + w.wi * sum;
        // u = S Hᵀ (amplitude rows, zero on θ and λ), then H S Hᵀ. From 8
        // states on S is not formed: S Hᵀ = P Hᵀ - Σ_t l_t (l_t · H), as
        // whole rows (P is symmetric).
        let mut u = [T::ZERO; N];
        if let Some(schur) = &schur {
            for (i, ui) in u.iter_mut().enumerate() {
                if !self.is_amplitude(i) {
                    continue;
                }
                let r = sym_row(schur, i);
                let mut acc = T::ZERO;
                for (m, &(hp, hq)) in h.iter().enumerate().take(m_n) {
                    let (ai, bi) = self.pair(m, c);
                    acc += hp * get(&r, ai) + hq * get(&r, bi);
                }
                *ui = acc;
            }
        } else {
            for (m, &(hp, hq)) in h.iter().enumerate().take(m_n) {
                let (ai, bi) = self.pair(m, c);
                let (Some(ra), Some(rb)) = (state.p.get(ai), state.p.get(bi)) else {
                    continue;
                };
                for ((ui, &pa), &pb) in u.iter_mut().zip(ra).zip(rb) {
                    *ui += hp * pa + hq * pb;
                }
            }
            for l in cols.iter().take(k_n) {
                let mut gt = T::ZERO;
                for (m, &(hp, hq)) in h.iter().enumerate().take(m_n) {
                    let (ai, bi) = self.pair(m, c);
                    gt += hp * get(l, ai) + hq * get(l, bi);
                }
                for (ui, &li) in u.iter_mut().zip(l) {
                    *ui -= li * gt;
                }
            }
            for m in 0..m_n {
                let (ti, li) = self.theta_lambda(m);
                put(&mut u, ti, T::ZERO);
                put(&mut u, li, T::ZERO);
            }
        }
        let dz = z0 - zhat;
        let mut s = w.centre_cov * dz * dz + get(&self.r, c);
        for (m, &(hp, hq)) in h.iter().enumerate().take(m_n) {
            let (ai, bi) = self.pair(m, c);
            s += hp * get(&u, ai) + hq * get(&u, bi);
        }
        let mut spread = T::ZERO;
        for (a, b) in zp.iter().zip(&zm).take(k_n) {
            let (da, db) = (*a - zhat, *b - zhat);
            spread += da * da + db * db;
        }
        s += w.wi * spread;
        // Pxz = W_i γ Σ_t l_t (Z_t^+ - Z_t^-) over θ and λ columns, + S Hᵀ.
        let mut acc = [T::ZERO; N];
        for ((l, a), b) in cols.iter().zip(&zp).zip(&zm).take(k_n) {
            let d = *a - *b;
            for (acc, &li) in acc.iter_mut().zip(l) {
                *acc += li * d;
            }
        }
        for ((vi, &ai), &ui) in v.iter_mut().zip(&acc).zip(&u) {
            *vi = w.wi_spread * ai + ui;
        }

        Some((zhat, s))
    }
}

impl<T: Real, const N: usize, const M: usize> ModalTracker<T, N, M> {
    /// The θ and λ columns of the Cholesky factor of P in the order θ, λ of
    /// every mode, then the amplitudes (8 states or more), left-looking:
    /// column t is P's pivot column less the columns before it times their
    /// entry at the pivot, scaled by `1/√d`, and zero on the states
    /// eliminated before; written to `cols[t]`. The amplitude pivots are not
    /// eliminated: an innovation needs only `S Hᵀ`, which these columns
    /// give, and the prediction checks S once per step
    /// ([`Self::amplitudes_definite`]). Each entry is P's less the same
    /// products in the same order as in the right-looking elimination of
    /// these pivots, so the same numbers. False if a pivot is not usable.
    #[inline(always)]
    fn leading_columns(&self, p: &[[T; N]; N], cols: &mut [[T; N]; N]) -> bool {
        // A mode's θ and λ columns at once: the two pivots, and the θ
        // column's entry at λ, first (scalars), then both columns in one
        // pass, each entry P's less the columns before in turn, times
        // 1/√d (the λ column less the θ column last).
        for m in 0..self.m_n() {
            let (ti, li) = (self.pivot(2 * m), self.pivot(2 * m + 1));
            let Some((before, rest)) = cols.split_at_mut_checked(2 * m) else {
                return false;
            };
            let (Some([ct, cl]), Some(pt), Some(pl)) =
                (rest.first_chunk_mut::<2>(), p.get(ti), p.get(li))
            else {
                return false;
            };
            let (mut dt, mut e, mut dl) = (get(pt, ti), get(pt, li), get(pl, li));
            for l in before.iter() {
                let (ft, fl) = (get(l, ti), get(l, li));
                dt -= ft * ft;
                e -= fl * ft;
                dl -= fl * fl;
            }
            if !pivot_ok(dt) {
                return false;
            }
            let rt = rsqrt(dt);
            let e = e * rt;
            dl -= e * e;
            if !pivot_ok(dl) {
                return false;
            }
            let rl = rsqrt(dl);
            for (j, ((vt, vl), (&at, &al))) in ct
                .iter_mut()
                .zip(cl.iter_mut())
                .zip(pt.iter().zip(pl))
                .enumerate()
            {
                let (mut a, mut b) = (at, al);
                for l in before.iter() {
                    let v = get(l, j);
                    a -= v * get(l, ti);
                    b -= v * get(l, li);
                }
                let a = a * rt;
                *vt = a;
                *vl = (b - a * e) * rl;
            }
            put(ct, ti, dt * rt);
            put(cl, li, dl * rl);
            put(cl, ti, T::ZERO);
            for s in 0..2 * m {
                let q = self.pivot(s);
                put(ct, q, T::ZERO);
                put(cl, q, T::ZERO);
            }
        }
        true
    }
}

/// Factorisation for the sigma points below 8 states (one mode, whose θ
/// and λ come first): `cols[0]` and `cols[1]` get the θ and λ columns of
/// the lower Cholesky factor, `schur` the covariance of the amplitudes
/// given θ and λ (`P - Σ_t l_t l_tᵀ` on the amplitude block), which is all
/// the amplitude columns contribute (see `predict_ukf`). The amplitude
/// pivots are still eliminated, to check that P is positive definite
/// (false if not). The plain right-looking order, with loops the
/// optimiser unrolls; `1/√d` per pivot by Newton's method, no division.
#[inline(always)]
fn factor_natural<T: Real, const N: usize>(
    p: &[[T; N]; N],
    cols: &mut [[T; N]; 2],
    schur: &mut [[T; N]; N],
) -> bool {
    let mut w = *p;
    for t in 0..N {
        let d = entry(&w, t, t);
        if !pivot_ok(d) {
            return false;
        }
        if t + 1 == N {
            break;
        }
        let r = rsqrt(d);
        // Constant trip counts and masks, so that the loops unroll.
        let mut l = [T::ZERO; N];
        for (i, li) in l.iter_mut().enumerate() {
            if i > t {
                *li = entry(&w, i, t) * r;
            }
        }
        for i in 0..N {
            let li = get(&l, i);
            for j in 0..N {
                if i > t && j >= i {
                    let v = entry(&w, i, j) - li * get(&l, j);
                    set(&mut w, i, j, v);
                    set(&mut w, j, i, v);
                }
            }
        }
        if t < 2 {
            put(&mut l, t, d * r);
            if let Some(col) = cols.get_mut(t) {
                *col = l;
            }
            if t == 1 {
                *schur = w;
            }
        }
    }
    true
}

/// The entries of `d` from index `from` on.
#[inline(always)]
fn from_on<T>(d: &[T], from: usize) -> &[T] {
    d.get(from..).unwrap_or(&[])
}

/// A usable pivot: positive (and normal, for [`rsqrt`]) and below GUARD
/// (finite; a larger variance of these scaled states is a diverged filter).
#[inline(always)]
fn pivot_ok<T: Real>(d: T) -> bool {
    d > min_positive::<T>() && d < T::GUARD
}
