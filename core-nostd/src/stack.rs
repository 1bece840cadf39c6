//! Hysteretic relaxation with a turning-point stack: the non-parametric
//! model K_f(d) of seed 000 §1.4.1 and the continuous standard triboelastic
//! solid (STS) of §1.4.3.
//!
//! After a turning point T, the force grows with the distance d = |x - x_T|
//! only (eqs 1.27-1.28, with the sign factor the print omits):
//!
//! ```text
//! F(x) = F_T + s H(d),    H(d) = ∫_0^d K_f(r) dr,    s = sign(x - x_T)
//! ```
//!
//! which obeys Madelung's rules when the turning points are remembered: a
//! branch that comes back to the turning point it started from wipes the
//! inner loop and continues the branch that led there (eq 1.29). First
//! loading follows Masing: from the virgin state the curve is
//! `F_v(x) = sign(x) H(2|x|) / 2`, the reversal curves scaled by one half.
//!
//! The [`Relaxation`] gives `(H(d), K_f(d))`: [`KfTable`], a piecewise-linear
//! K_f(d) through measured points, or [`Sts`], the continuous STS law
//! (eq 1.41 read with K̂_0 = K̂_1 = K_1, which makes F - F_T vanish at d = 0;
//! N = 2 on reversal branches, N = 1 on the virgin curve):
//!
//! ```text
//! H(d) = sqrt(2 C d + (C/K_1)²) - C/K_1,    K_f(d) = C / sqrt(2 C d + (C/K_1)²)   (1.42)
//! ```
//!
//! This force is added to the bushing in displacement space: it takes no
//! fraction of the backbone (its K_f is the stiffness it adds).
//!
//! - **States**: `M` turning points (x_T, F_T), their count, the direction,
//!   the last x and force, the virgin flag; 2M + 6 words.
//! - **Overflow**: when a reversal finds the stack full, the two oldest
//!   turning points are dropped and the span between them is recorded
//!   ([`StackState::dropped_span`]). Only paths that later leave every kept
//!   loop are affected: they continue the current branch instead of the
//!   forgotten outer one, and for a non-increasing K_f the force differs from
//!   the unbounded model by at most H(dropped span) (tested). Nothing panics.
//! - **Dissipation**: the model is a continuous Iwan model (cells of reversal
//!   span r and stiffness -dK_f), whose sliding cells dissipate
//!   `|ẋ| (H(D) - D K_f(D)) / 2` at distance D from the turning point (D =
//!   2|x| on the virgin curve); trapezoid over the step, never negative
//!   because K_f must not increase.
//! - **Stability**: no time step, no division by the state; exact for any
//!   step size and rate independent.
//! - **Cost**: a compare per stored level passed, one `Relaxation`
//!   evaluation (binary search for [`KfTable`]; a `sqrt` and a division for
//!   [`Sts`]).

use crate::bushing::{Drive, Effect, EffectOutput};
use crate::error::{Param, ParamError, finite, scaled};
use crate::real::Real;

/// A hysteretic relaxation law: the force gained along a branch.
pub trait Relaxation<T: Real> {
    /// `(H(d), K_f(d))` for `d >= 0`: the force gained at distance `d` from
    /// a turning point and its slope. H(0) = 0, K_f >= 0 and non-increasing.
    fn branch(&self, d: T) -> (T, T);
}

/// The continuous STS law (eq 1.42): stiffness K_1 at the turning point,
/// relaxing as `(1/2) sqrt(C / d)` far from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sts<T> {
    two_c: T,
    c: T,
    a: T,
    a2: T,
}

impl<T: Real> Sts<T> {
    /// `c` = C (N²/mm: the product of the infinitesimal slip force and
    /// stiffness), `k1` = K_1 (N/mm), the hysteretic stiffness at a
    /// turning point.
    pub fn new(c: f64, k1: f64) -> Result<Self, ParamError> {
        // C, K_1 and the distance C/K_1 (squared in the law) must fit the
        // working type.
        let c = scaled::<T>(Param::scalar("c"), c)?;
        let k1 = scaled::<T>(Param::scalar("k1"), k1)?;
        let a = scaled::<T>(Param::scalar("c / k1"), c / k1)?;
        Ok(Self {
            two_c: T::from_f64(2.0 * c),
            c: T::from_f64(c),
            a: T::from_f64(a),
            a2: T::from_f64(a * a),
        })
    }
}

impl<T: Real> Relaxation<T> for Sts<T> {
    #[inline]
    fn branch(&self, d: T) -> (T, T) {
        // r >= C/K_1 > 0: the division is by a value bounded away from 0.
        let r = (self.two_c * d + self.a2).sqrt();
        (r - self.a, self.c / r)
    }
}

/// One linear piece of K_f: from `d0`, value `k0`, slope `s`, integral `h0`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct KfPiece<T> {
    d0: T,
    h0: T,
    k0: T,
    s: T,
    half_s: T,
}

/// A measured hysteretic relaxation stiffness K_f(d): piecewise linear
/// through up to `M` points (d_i, K_i), constant K_0 below d_0 and constant
/// beyond the last point (give a last point with K = 0 for a force that
/// saturates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KfTable<T, const M: usize> {
    pieces: [KfPiece<T>; M],
    len: usize,
}

impl<T: Real, const M: usize> KfTable<T, M> {
    /// Builds the table: `d` increasing from >= 0, `k` >= 0 and
    /// non-increasing.
    pub fn new(d: &[f64], k: &[f64]) -> Result<Self, ParamError> {
        let n = d.len();
        if n == 0 {
            return Err(ParamError::TooFew {
                param: Param::scalar("d"),
                min: 1,
                got: 0,
            });
        }
        if n > M {
            return Err(ParamError::TooMany {
                param: Param::scalar("d"),
                capacity: M,
                got: n,
            });
        }
        if k.len() != n {
            return Err(ParamError::LengthMismatch {
                param: Param::scalar("k"),
                expected: n,
                got: k.len(),
            });
        }
        let mut pieces = [KfPiece::default(); M];
        let mut h = 0.0;
        let mut prev: Option<(f64, f64)> = None;
        for (i, (&di, &ki)) in d.iter().zip(k).enumerate() {
            finite(Param::item("d", i), di)?;
            finite(Param::item("k", i), ki)?;
            if ki < 0.0 {
                return Err(ParamError::NotPositive {
                    param: Param::item("k", i),
                    value: ki,
                });
            }
            match prev {
                None if di < 0.0 => {
                    return Err(ParamError::NotPositive {
                        param: Param::item("d", i),
                        value: di,
                    });
                }
                None => h = ki * di,
                Some((dp, kp)) => {
                    if di <= dp {
                        return Err(ParamError::NotIncreasing {
                            param: Param::item("d", i),
                        });
                    }
                    if ki > kp {
                        return Err(ParamError::Increasing {
                            param: Param::item("k", i),
                        });
                    }
                    h += 0.5 * (ki + kp) * (di - dp);
                }
            }
            let s = match (d.get(i + 1), k.get(i + 1)) {
                (Some(&dn), Some(&kn)) if dn > di => (kn - ki) / (dn - di),
                _ => 0.0,
            };
            if let Some(p) = pieces.get_mut(i) {
                *p = KfPiece {
                    d0: T::from_f64(di),
                    h0: T::from_f64(h),
                    k0: T::from_f64(ki),
                    s: T::from_f64(s),
                    half_s: T::from_f64(0.5 * s),
                };
            }
            prev = Some((di, ki));
        }
        Ok(Self { pieces, len: n })
    }
}

impl<T: Real, const M: usize> Relaxation<T> for KfTable<T, M> {
    #[inline]
    fn branch(&self, d: T) -> (T, T) {
        let first = self.pieces.first().copied().unwrap_or_default();
        if d < first.d0 {
            return (first.k0 * d, first.k0);
        }
        let (mut lo, mut hi) = (0usize, self.len);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            match self.pieces.get(mid) {
                Some(p) if p.d0 <= d => lo = mid,
                _ => hi = mid,
            }
        }
        let p = self.pieces.get(lo).copied().unwrap_or_default();
        let t = d - p.d0;
        (p.h0 + t * (p.k0 + p.half_s * t), p.k0 + p.s * t)
    }
}

/// How the model treats the first loading from the initial state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstLoading {
    /// Masing's rule: the virgin curve H(2|x - x0|)/2, and a path that
    /// leaves every loop returns to it.
    Masing,
    /// As eq 1.42: the initial point is a turning point and every branch is
    /// a reversal curve.
    Ignored,
}

/// State of a [`TurningPoints`] model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StackState<T, const M: usize> {
    points: [(T, T); M],
    len: usize,
    dir: i8,
    x: T,
    force: T,
    slope: T,
    density: T,
    origin: T,
    /// The oldest kept turning point was reached from the virgin curve.
    virgin_bottom: bool,
    dropped_span: T,
    overflows: u32,
}

impl<T: Real, const M: usize> StackState<T, M> {
    /// Turning points held.
    pub fn depth(&self) -> usize {
        self.len
    }
    /// True on the virgin (first loading) curve.
    pub fn on_virgin_curve(&self) -> bool {
        self.len == 0
    }
    /// Largest span between two turning points dropped on overflow (0 if
    /// none): the force error after an overflow is at most H of it.
    pub fn dropped_span(&self) -> T {
        self.dropped_span
    }
    /// Number of overflows (saturating).
    pub fn overflows(&self) -> u32 {
        self.overflows
    }
    /// Hysteretic force.
    pub fn force(&self) -> T {
        self.force
    }
}

/// The hysteretic relaxation model with a turning-point stack of capacity
/// `M` (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurningPoints<R, const M: usize> {
    law: R,
    first_loading: FirstLoading,
}

impl<R, const M: usize> TurningPoints<R, M> {
    /// A model with relaxation law `law`. `M >= 2` is checked at compile
    /// time.
    pub const fn new(law: R, first_loading: FirstLoading) -> Self {
        const { assert!(M >= 2, "a turning-point stack needs room for two points") };
        Self { law, first_loading }
    }

    /// The relaxation law.
    pub fn law(&self) -> &R {
        &self.law
    }
}

/// Force, slope and dissipation density at `x` for the current stack,
/// moving in direction `s`.
#[inline(always)]
fn on_branch<T: Real, R: Relaxation<T>, const M: usize>(
    law: &R,
    st: &StackState<T, M>,
    x: T,
    s: i8,
) -> (T, T, T) {
    {
        let top = if st.len == 0 {
            None
        } else {
            st.points.get(st.len - 1)
        };
        let (f, k, d, h) = match top {
            None => {
                let u = x - st.origin;
                let d = u.abs() + u.abs();
                let (h, k) = law.branch(d);
                let f = if u < T::ZERO {
                    -T::HALF * h
                } else {
                    T::HALF * h
                };
                (f, k, d, h)
            }
            Some(&(xt, ft)) => {
                let d = (x - xt).abs();
                let (h, k) = law.branch(d);
                (if s < 0 { ft - h } else { ft + h }, k, d, h)
            }
        };
        let density = T::HALF * (h - d * k);
        (f, k, if density > T::ZERO { density } else { T::ZERO })
    }
}

impl<T: Real, R: Relaxation<T>, const M: usize> Effect<T> for TurningPoints<R, M> {
    type State = StackState<T, M>;
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        0.0
    }
    fn dt(&self) -> Option<f64> {
        None
    }
    fn rest(&self, x0: T) -> StackState<T, M> {
        let mut st = StackState {
            points: [(T::ZERO, T::ZERO); M],
            len: 0,
            dir: 0,
            x: x0,
            force: T::ZERO,
            slope: T::ZERO,
            density: T::ZERO,
            origin: x0,
            virgin_bottom: true,
            dropped_span: T::ZERO,
            overflows: 0,
        };
        if self.first_loading == FirstLoading::Ignored {
            if let Some(p) = st.points.first_mut() {
                *p = (x0, T::ZERO);
            }
            st.len = 1;
            st.virgin_bottom = false;
        }
        st.slope = self.law.branch(T::ZERO).1;
        st
    }

    #[inline]
    fn step(&self, st: &mut StackState<T, M>, drive: &Drive<T>) -> EffectOutput<T> {
        let x = drive.x;
        let s: i8 = if x > st.x {
            1
        } else if x < st.x {
            -1
        } else {
            return EffectOutput {
                force: st.force,
                tangent: st.slope,
                dissipated: T::ZERO,
            };
        };
        let mut density_start = st.density;
        if st.dir != 0 && s != st.dir {
            push(st, st.x, st.force);
            density_start = T::ZERO;
        }
        // Madelung: passing the turning point below the top closes the inner
        // loop; the oldest kept point can only be passed back onto the
        // virgin curve (after an overflow, or with first loading ignored, the
        // current branch continues).
        loop {
            let passed = |xa: T| if s > 0 { x >= xa } else { x <= xa };
            if st.len >= 3 || (st.len == 2 && st.virgin_bottom) {
                let xa = st.points.get(st.len - 2).map_or(x, |p| p.0);
                if passed(xa) {
                    st.len -= 2;
                    continue;
                }
            } else if st.len == 1 && st.virgin_bottom {
                // The virgin curve is odd about the origin: the branch from
                // the first turning point meets it at the mirror point.
                let xt = st.points.first().map_or(x, |p| p.0);
                if passed(st.origin + st.origin - xt) {
                    st.len = 0;
                    continue;
                }
            }
            break;
        }
        let (f, k, density) = on_branch(&self.law, st, x, s);
        let dissipated = (x - st.x).abs() * T::HALF * (density_start + density);
        st.x = x;
        st.force = f;
        st.slope = k;
        st.density = density;
        st.dir = s;
        EffectOutput {
            force: f,
            tangent: k,
            dissipated,
        }
    }

    #[inline(always)]
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// Pushes a turning point, dropping the two oldest when full.
fn push<T: Real, const M: usize>(st: &mut StackState<T, M>, x: T, f: T) {
    if st.len >= M {
        let span = match (st.points.first(), st.points.get(1)) {
            (Some(a), Some(b)) => (a.0 - b.0).abs(),
            _ => T::ZERO,
        };
        if span > st.dropped_span {
            st.dropped_span = span;
        }
        st.points.copy_within(2.., 0);
        st.len = M - 2;
        st.virgin_bottom = false;
        st.overflows = st.overflows.saturating_add(1);
    }
    if let Some(p) = st.points.get_mut(st.len) {
        *p = (x, f);
        st.len += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backbone::Polynomial;
    use crate::bushing::Bushing;
    use alloc::vec;
    use alloc::vec::Vec;
    use proptest::prelude::*;

    const C: f64 = 400.0;
    const K1: f64 = 300.0;

    fn sts<const M: usize>(
        first: FirstLoading,
    ) -> Bushing<f64, Polynomial<f64, 2>, (TurningPoints<Sts<f64>, M>,)> {
        Bushing::new(
            Polynomial::linear(100.0).unwrap(),
            (TurningPoints::new(Sts::new(C, K1).unwrap(), first),),
        )
        .unwrap()
    }

    /// Eq 1.41 (K̂ = K_1) written out independently: N = 1 virgin, N = 2 reversal.
    fn sts_closed_form(n: f64, d: f64) -> f64 {
        ((n * C * d.abs() + (n * C / (2.0 * K1)).powi(2)).sqrt() - n * C / (2.0 * K1)).copysign(d)
    }

    fn hysteretic(out: &crate::bushing::Output<f64, (EffectOutput<f64>,)>) -> f64 {
        out.effects.unwrap().0.force
    }

    #[test]
    fn masing_virgin_and_reversal_curves_follow_eq_1_41() {
        let b = sts::<8>(FirstLoading::Masing);
        let mut s = b.state_at(0.0);
        let x1 = 2.0;
        let n = 2000;
        for k in 1..=n {
            let x = x1 * k as f64 / n as f64;
            let f = hysteretic(&b.step(&mut s, x));
            let want = sts_closed_form(1.0, x);
            assert!(
                (f - want).abs() <= 1e-9 * want.abs().max(1.0),
                "virgin at {x}: {f} vs {want}"
            );
        }
        let ft = sts_closed_form(1.0, x1);
        for k in 1..=n {
            let d = 2.0 * x1 * k as f64 / n as f64;
            let f = hysteretic(&b.step(&mut s, x1 - d));
            let want = ft - sts_closed_form(2.0, d);
            assert!(
                (f - want).abs() <= 1e-9 * want.abs().max(1.0),
                "reversal at d = {d}: {f} vs {want}"
            );
            // Factor 2: the reversal curve is twice the virgin curve at d/2.
            assert!(
                ((ft - f) - 2.0 * sts_closed_form(1.0, 0.5 * d)).abs()
                    <= 1e-9 * (ft - f).abs().max(1.0)
            );
        }
        // Past -x1 the path is back on the virgin curve (N = 1 again).
        let f = hysteretic(&b.step(&mut s, -3.0));
        assert!(s.effects().0.on_virgin_curve());
        assert!((f - sts_closed_form(1.0, -3.0)).abs() <= 1e-9 * f.abs());
    }

    #[test]
    fn ignored_first_loading_starts_on_a_reversal_curve() {
        let b = sts::<8>(FirstLoading::Ignored);
        let mut s = b.state_at(0.5);
        let f = hysteretic(&b.step(&mut s, 1.5));
        assert!((f - sts_closed_form(2.0, 1.0)).abs() < 1e-12);
    }

    #[test]
    fn steady_cycle_energy_matches_the_masing_integral() {
        // D(p) = 8 ∫_0^p F_v - 4 p F_v(p) with F_v(p) = sqrt(C p + b²) - b, b = C / (2 K1).
        let b = sts::<8>(FirstLoading::Masing);
        let bb = C / (2.0 * K1);
        for p in [0.05, 0.5, 2.0] {
            let integral = 2.0 / (3.0 * C) * ((C * p + bb * bb).powf(1.5) - bb.powi(3)) - bb * p;
            let exact = 8.0 * integral - 4.0 * p * sts_closed_form(1.0, p);
            let mut s = b.state_at(0.0);
            let n = 4000;
            let mut cycle = 0.0;
            for k in 0..3 * n {
                let x = p * libm::sin(
                    core::f64::consts::TAU * k as f64 / n as f64 + 0.5 * core::f64::consts::PI,
                );
                let out = b.step(&mut s, x);
                assert!(out.dissipated >= 0.0);
                if k >= 2 * n {
                    cycle += out.dissipated;
                }
            }
            assert!(
                (cycle / exact - 1.0).abs() < 1e-3,
                "p = {p}: {cycle} vs {exact}"
            );
        }
    }

    #[test]
    fn kf_table_integrates_and_validates() {
        let t = KfTable::<f64, 4>::new(&[0.1, 0.5, 1.0], &[100.0, 20.0, 0.0]).unwrap();
        assert_eq!(t.branch(0.05), (5.0, 100.0));
        let (h, k) = t.branch(0.3);
        assert!((k - 60.0).abs() < 1e-12);
        assert!((h - (10.0 + 0.2 * (100.0 + 60.0) / 2.0)).abs() < 1e-12);
        let (h_end, k_end) = t.branch(5.0);
        assert_eq!(k_end, 0.0);
        assert!((h_end - (10.0 + 24.0 + 5.0)).abs() < 1e-12);
        assert_eq!(
            KfTable::<f64, 4>::new(&[0.0, 1.0], &[1.0, 2.0]),
            Err(ParamError::Increasing {
                param: Param::item("k", 1)
            })
        );
        assert_eq!(
            KfTable::<f64, 4>::new(&[0.0, 0.0], &[2.0, 1.0]),
            Err(ParamError::NotIncreasing {
                param: Param::item("d", 1)
            })
        );
        assert!(matches!(
            KfTable::<f64, 1>::new(&[0.0, 1.0], &[2.0, 1.0]),
            Err(ParamError::TooMany { .. })
        ));
        assert!(matches!(
            Sts::<f64>::new(0.0, 1.0),
            Err(ParamError::NotPositive { .. })
        ));
    }

    fn walk(points: &[f64], h: f64, mut visit: impl FnMut(f64, bool)) {
        let mut x = 0.0;
        for &p in points {
            let n = ((p - x).abs() / h).ceil().max(1.0) as usize;
            for k in 1..=n {
                visit(
                    if k == n {
                        p
                    } else {
                        x + (p - x) * k as f64 / n as f64
                    },
                    k == n,
                );
            }
            x = p;
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Madelung: turning point A, then B inside the current loop, inner
        /// loops between them, back to A: the force at A is found again.
        #[test]
        fn madelung_return_point_memory_stack(
            a in -3.0f64..3.0,
            reach in 0.01f64..0.99,
            down in any::<bool>(),
            inner in prop::collection::vec(0.01f64..0.99, 0..10),
            h in 0.002f64..0.2,
        ) {
            let b = sts::<16>(FirstLoading::Masing);
            let mut s = b.state_at(0.0);
            let previous = if down { -4.0 } else { 4.5 };
            let b_pt = a + (previous - a) * reach;
            let mut path = if down { vec![4.5, -4.0, a, b_pt] } else { vec![-4.0, 4.5, a, b_pt] };
            path.extend(inner.iter().map(|u| a + (b_pt - a) * u));
            path.push(a);
            let mut at_a = Vec::new();
            let mut turns = 0;
            walk(&path, h, |x, at_turn| {
                let f = b.step(&mut s, x).effects.unwrap().0.force;
                if at_turn {
                    turns += 1;
                    if turns == 3 || turns == path.len() {
                        at_a.push(f);
                    }
                }
            });
            prop_assert!((at_a[0] - at_a[1]).abs() <= 1e-9 * at_a[0].abs().max(1.0), "{} vs {}", at_a[0], at_a[1]);
        }

        /// Overflow: a 4-deep stack against a 64-deep one on random turning
        /// points; the force never differs by more than H(dropped span).
        #[test]
        fn overflow_error_is_bounded_by_h_of_the_dropped_span(
            turns in prop::collection::vec(-3.0f64..3.0, 2..40),
        ) {
            let small = sts::<4>(FirstLoading::Masing);
            let big = sts::<64>(FirstLoading::Masing);
            let (mut ss, mut sb) = (small.state_at(0.0), big.state_at(0.0));
            let law = Sts::<f64>::new(C, K1).unwrap();
            walk(&turns, 0.05, |x, _| {
                let fs = small.step(&mut ss, x).effects.unwrap().0.force;
                let fb = big.step(&mut sb, x).effects.unwrap().0.force;
                let bound = law.branch(ss.effects().0.dropped_span()).0;
                assert!((fs - fb).abs() <= bound + 1e-9 * fb.abs().max(1.0), "{fs} vs {fb}, bound {bound}");
            });
            prop_assert!(sb.effects().0.overflows() == 0);
        }
    }
}
