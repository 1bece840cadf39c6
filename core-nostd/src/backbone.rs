//! Hyperelastic backbones: the high-frequency static gain F^∞(x) and its
//! tangent K^∞(x) = dF^∞/dx (seed 000 §1.2, eq 1.2; Ch. 3 §3.4.1).
//!
//! A backbone is stateless. The bushing evaluates it once per step and shares
//! `(F^∞, K^∞)` with every dissipative cell, which works on fractions g^i of
//! it (force-rate coupling, eq 1.12). Both backbones here guarantee K^∞ > 0
//! on the whole real line (a convex elastic potential, seed 000 §2.3.1) and
//! extrapolate linearly outside their range, so a test that drives a bushing
//! past its identified range gets a bounded, monotone force instead of the
//! wild turn of a cubic.

use crate::error::{Param, ParamError, finite, positive};
use crate::real::Real;

/// The elastic backbone F^∞(x) of a bushing.
pub trait Backbone<T: Real> {
    /// Returns `(F^∞(x), K^∞(x))`. Never panics; finite for finite `x`
    /// unless the force itself overflows the working type.
    fn eval(&self, x: T) -> (T, T);
}

/// Polynomial backbone F^∞(x) = Σ c_k x^k on a range `[lo, hi]`, extended
/// linearly (with the end tangent) outside it.
///
/// - Equation: seed 000 eq 1.2 with a polynomial interpolation of the
///   measured static points (§1.2.1).
/// - States: none.
/// - Stability: construction proves K^∞(x) > 0 on `[lo, hi]` (Bernstein
///   coefficients of the derivative, refined by subdivision) and refuses the
///   polynomial otherwise with [`ParamError::TangentNotPositive`].
/// - Cost: Horner on `N` coefficients, `2(N-1)` multiply-adds, plus two
///   compares for the range.
///
/// ```
/// use bushing::{Backbone, ParamError, Polynomial};
///
/// // F = 150 x + 4 x³ on [-6, 6] mm, in N.
/// let p = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0))?;
/// let (force, tangent) = p.eval(1.0);
/// assert_eq!((force, tangent), (154.0, 162.0));
/// // A stiffness that turns negative on the range is refused.
/// let soft = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, -4.0], (-6.0, 6.0));
/// assert!(matches!(soft, Err(ParamError::TangentNotPositive { .. })));
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polynomial<T, const N: usize> {
    coeffs: [T; N],
    lo: T,
    hi: T,
    f_lo: T,
    k_lo: T,
    f_hi: T,
    k_hi: T,
}

impl<T: Real, const N: usize> Polynomial<T, N> {
    /// Builds `F(x) = coeffs[0] + coeffs[1] x + ...` (c_k in N/mm^k, x in
    /// mm) valid on `range` (mm).
    /// Fewer than `N` coefficients are padded with zeros.
    pub fn new(coeffs: &[f64], range: (f64, f64)) -> Result<Self, ParamError> {
        let param = Param::scalar("coefficients");
        if coeffs.len() < 2 {
            return Err(ParamError::TooFew {
                param,
                min: 2,
                got: coeffs.len(),
            });
        }
        if coeffs.len() > N {
            return Err(ParamError::TooMany {
                param,
                capacity: N,
                got: coeffs.len(),
            });
        }
        let mut c = [0.0f64; N];
        for (i, (dst, &src)) in c.iter_mut().zip(coeffs).enumerate() {
            *dst = finite(Param::item("coefficients", i), src)?;
        }
        let (lo, hi) = range;
        finite(Param::scalar("range.lo"), lo)?;
        finite(Param::scalar("range.hi"), hi)?;
        if lo >= hi {
            return Err(ParamError::EmptyRange { lo, hi });
        }
        tangent_positive_on(&c, lo, hi)?;
        let (f_lo, k_lo) = horner(&c, lo);
        let (f_hi, k_hi) = horner(&c, hi);
        // Coefficients and end values valid in f64 must fit the working type.
        if let Some(i) = c.iter().position(|&v| !T::from_f64(v).is_finite()) {
            return Err(ParamError::NotFinite {
                param: Param::item("coefficients", i),
            });
        }
        if [f_lo, k_lo, f_hi, k_hi]
            .iter()
            .any(|&v| !T::from_f64(v).is_finite())
        {
            return Err(ParamError::NotFinite {
                param: Param::scalar("range"),
            });
        }
        Ok(Self {
            coeffs: c.map(T::from_f64),
            lo: T::from_f64(lo),
            hi: T::from_f64(hi),
            f_lo: T::from_f64(f_lo),
            k_lo: T::from_f64(k_lo),
            f_hi: T::from_f64(f_hi),
            k_hi: T::from_f64(k_hi),
        })
    }

    /// The linear backbone F^∞ = k x.
    pub fn linear(stiffness: f64) -> Result<Self, ParamError> {
        positive(Param::scalar("stiffness"), stiffness)?;
        Self::new(&[0.0, stiffness], (-1.0, 1.0))
    }
}

impl<T: Real, const N: usize> Backbone<T> for Polynomial<T, N> {
    #[inline]
    fn eval(&self, x: T) -> (T, T) {
        if x < self.lo {
            (self.f_lo + self.k_lo * (x - self.lo), self.k_lo)
        } else if x > self.hi {
            (self.f_hi + self.k_hi * (x - self.hi), self.k_hi)
        } else {
            horner(&self.coeffs, x)
        }
    }
}

/// Value and derivative of Σ c_k x^k by Horner's scheme.
#[inline(always)]
fn horner<T: Real, const N: usize>(c: &[T; N], x: T) -> (T, T) {
    // The leading coefficient starts both sums, which then need no
    // products by zero: the same values as starting from f = k = 0.
    let Some((&top, rest)) = c.split_last() else {
        return (T::ZERO, T::ZERO);
    };
    let mut f = top;
    let mut k = T::ZERO;
    for (i, &ck) in rest.iter().rev().enumerate() {
        k = if i == 0 { f } else { k * x + f };
        f = f * x + ck;
    }
    (f, k)
}

/// Proves that the derivative of Σ c_k x^k is positive on `[lo, hi]`.
///
/// The derivative is written in the Bernstein basis of `[lo, hi]`; all
/// coefficients positive proves positivity, a non-positive end coefficient
/// disproves it, and otherwise the interval is halved (de Casteljau) down to
/// a relative width of 2^-40.
fn tangent_positive_on<const N: usize>(c: &[f64; N], lo: f64, hi: f64) -> Result<(), ParamError> {
    // Derivative coefficients, degree m = N - 2 (at most).
    let mut d = [0.0f64; N];
    for (k, dk) in d.iter_mut().enumerate() {
        if let Some(&ck1) = c.get(k + 1) {
            *dk = (k + 1) as f64 * ck1;
        }
    }
    let m = N.saturating_sub(2);
    // Substitute x = lo + w t: q(t) = Σ d_k (lo + w t)^k, by Horner on polynomials.
    let w = hi - lo;
    let mut q = [0.0f64; N];
    for k in (0..=m).rev() {
        let mut next = [0.0f64; N];
        for j in 0..=m {
            let prev = if j > 0 {
                q.get(j - 1).copied().unwrap_or(0.0)
            } else {
                0.0
            };
            let here = q.get(j).copied().unwrap_or(0.0);
            if let Some(n) = next.get_mut(j) {
                *n = lo * here + w * prev;
            }
        }
        if let (Some(n0), Some(&dk)) = (next.get_mut(0), d.get(k)) {
            *n0 += dk;
        }
        q = next;
    }
    // Power basis in t -> Bernstein basis of degree m on [0, 1].
    let mut b = [0.0f64; N];
    for (i, bi) in b.iter_mut().enumerate().take(m + 1) {
        let mut sum = 0.0;
        for j in 0..=i {
            sum += binomial(i, j) / binomial(m, j) * q.get(j).copied().unwrap_or(0.0);
        }
        *bi = sum;
    }
    bernstein_positive(&b, m, lo, hi, 0)
}

fn bernstein_positive<const N: usize>(
    b: &[f64; N],
    m: usize,
    lo: f64,
    hi: f64,
    depth: u32,
) -> Result<(), ParamError> {
    let first = b.first().copied().unwrap_or(0.0);
    let last = b.get(m).copied().unwrap_or(0.0);
    if first <= 0.0 || !first.is_finite() {
        return Err(ParamError::TangentNotPositive { x: lo });
    }
    if last <= 0.0 || !last.is_finite() {
        return Err(ParamError::TangentNotPositive { x: hi });
    }
    if b.iter().take(m + 1).all(|&v| v > 0.0) {
        return Ok(());
    }
    let mid = 0.5 * (lo + hi);
    if depth >= 40 {
        return Err(ParamError::TangentNotPositive { x: mid });
    }
    // de Casteljau split at t = 1/2.
    let mut work = *b;
    let mut left = [0.0f64; N];
    let mut right = [0.0f64; N];
    for r in 0..=m {
        if let Some(l) = left.get_mut(r) {
            *l = work.first().copied().unwrap_or(0.0);
        }
        if let Some(rt) = right.get_mut(m - r) {
            *rt = work.get(m - r).copied().unwrap_or(0.0);
        }
        for i in 0..(m - r) {
            let a = work.get(i).copied().unwrap_or(0.0);
            let c = work.get(i + 1).copied().unwrap_or(0.0);
            if let Some(wi) = work.get_mut(i) {
                *wi = 0.5 * (a + c);
            }
        }
    }
    bernstein_positive(&left, m, lo, mid, depth + 1)?;
    bernstein_positive(&right, m, mid, hi, depth + 1)
}

fn binomial(n: usize, k: usize) -> f64 {
    let mut r = 1.0f64;
    for i in 0..k {
        r = r * (n - i) as f64 / (i + 1) as f64;
    }
    r
}

/// One cubic piece `a + b t + c t^2 + d t^3`, `t = x - x0`, with the
/// derivative coefficients pre-scaled (`c2 = 2c`, `d3 = 3d`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Piece<T> {
    x0: T,
    a: T,
    b: T,
    c: T,
    d: T,
    c2: T,
    d3: T,
}

impl<T: Real> Piece<T> {
    #[inline(always)]
    fn eval(&self, x: T) -> (T, T) {
        let t = x - self.x0;
        let f = self.a + t * (self.b + t * (self.c + t * self.d));
        let k = self.b + t * (self.c2 + t * self.d3);
        (f, k)
    }

    /// Every coefficient finite in the working type.
    fn fits(&self) -> bool {
        [self.x0, self.a, self.b, self.c, self.d, self.c2, self.d3]
            .iter()
            .all(|v| v.is_finite())
    }

    fn new(x0: f64, a: f64, b: f64, c: f64, d: f64) -> Self {
        Self {
            x0: T::from_f64(x0),
            a: T::from_f64(a),
            b: T::from_f64(b),
            c: T::from_f64(c),
            d: T::from_f64(d),
            c2: T::from_f64(2.0 * c),
            d3: T::from_f64(3.0 * d),
        }
    }
}

/// Monotone cubic spline through measured static points (x_i, F_i), with a
/// fixed capacity of `N` points, extended linearly beyond the end points.
///
/// - Equation: piecewise cubic Hermite interpolation of the backbone points
///   of seed 000 §3.4.1. The knot slopes follow Steffen (1990): at an
///   interior knot `m_i = min(2 s_{i-1}, 2 s_i, p_i)` with `s` the secant
///   slopes and `p_i` the slope of the parabola through three knots; at the
///   ends, the end secant. This keeps the interpolant monotone and its
///   tangent positive, which a C² spline does not guarantee; the price is
///   C¹ instead of C² continuity.
/// - States: none.
/// - Stability: points must increase strictly in x and in F (positive
///   stiffness), checked at construction.
/// - Cost: the search for the piece over the whole capacity (spare
///   capacity repeats the last piece, so there is no data-dependent loop
///   test) and 6 multiply-adds. The search halves: `log2 N` compares, the
///   fewest instructions, 20 guest instructions more than a cubic
///   polynomial on a Cortex-M4F for N = 8 (`scripts/accuracy-cost.sh`).
///   An in-order microcontroller takes about an instruction a cycle, so
///   every bare-metal target halves. On an out-of-order host what counts
///   is how long the step's instructions wait on each other: there, up to
///   N = 8 the compiler turns the halving into conditional moves, each
///   waiting on the one before, and the search counts the pieces that
///   start at or below x instead, `N - 1` compares that do not wait on
///   each other (the default bushing's host step 23 to 17 ns,
///   `cargo bench -p bushing-sim --bench kernels -- default_bushing`); from
///   16 pieces on the halving branches, the branches follow a slowly moving
///   input, and it stays (counting made the 256-point capacity of
///   `bushing-sim run` a third slower). Both find the same piece, so the
///   numbers are the same.
///
/// ```
/// use bushing::{Backbone, MonotoneSpline, ParamError};
///
/// // Measured static points, mm and N.
/// let s = MonotoneSpline::<f32, 8>::new(&[-2.0, 0.0, 1.0, 2.0], &[-400.0, 0.0, 160.0, 400.0])?;
/// let (force, tangent) = s.eval(1.0);
/// assert_eq!(force, 160.0);
/// assert!(tangent > 0.0);
/// // Forces must increase with x.
/// let bad = MonotoneSpline::<f32, 8>::new(&[0.0, 1.0, 2.0], &[0.0, 10.0, 5.0]);
/// assert!(matches!(bad, Err(ParamError::NotIncreasing { .. })));
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonotoneSpline<T, const N: usize> {
    /// Piece `i` covers `[x_i, x_{i+1})`; piece `n-1` is the linear
    /// extension beyond the last point.
    pieces: [Piece<T>; N],
    /// Linear extension below the first point.
    below: Piece<T>,
    len: usize,
}

impl<T: Real, const N: usize> MonotoneSpline<T, N> {
    /// Builds the spline through `(xs[i], forces[i])`: displacements in mm,
    /// forces in N.
    pub fn new(xs: &[f64], forces: &[f64]) -> Result<Self, ParamError> {
        let n = xs.len();
        if n < 2 {
            return Err(ParamError::TooFew {
                param: Param::scalar("x"),
                min: 2,
                got: n,
            });
        }
        if n > N {
            return Err(ParamError::TooMany {
                param: Param::scalar("x"),
                capacity: N,
                got: n,
            });
        }
        if forces.len() != n {
            return Err(ParamError::LengthMismatch {
                param: Param::scalar("force"),
                expected: n,
                got: forces.len(),
            });
        }
        for i in 0..n {
            let (x, f) = (at(xs, i), at(forces, i));
            finite(Param::item("x", i), x)?;
            finite(Param::item("force", i), f)?;
            if i > 0 && x <= at(xs, i - 1) {
                return Err(ParamError::NotIncreasing {
                    param: Param::item("x", i),
                });
            }
            if i > 0 && f <= at(forces, i - 1) {
                return Err(ParamError::NotIncreasing {
                    param: Param::item("force", i),
                });
            }
        }
        let h = |i: usize| at(xs, i + 1) - at(xs, i);
        let s = |i: usize| (at(forces, i + 1) - at(forces, i)) / h(i);
        let slope = |i: usize| -> f64 {
            if i == 0 {
                s(0)
            } else if i == n - 1 {
                s(n - 2)
            } else {
                let p = (s(i - 1) * h(i) + s(i) * h(i - 1)) / (h(i - 1) + h(i));
                (2.0 * s(i - 1)).min(2.0 * s(i)).min(p)
            }
        };
        let mut pieces = [Piece::default(); N];
        for (i, piece) in pieces.iter_mut().enumerate().take(n) {
            let (x0, y0, m0) = (at(xs, i), at(forces, i), slope(i));
            *piece = if i + 1 < n {
                let (hi, si, m1) = (h(i), s(i), slope(i + 1));
                let c = (3.0 * si - 2.0 * m0 - m1) / hi;
                let d = (m0 + m1 - 2.0 * si) / (hi * hi);
                Piece::new(x0, y0, m0, c, d)
            } else {
                Piece::new(x0, y0, m0, 0.0, 0.0)
            };
        }
        // Unused capacity repeats the extension piece, so that the search
        // runs over all N pieces with a fixed number of halvings.
        let last = pieces.get(n - 1).copied().unwrap_or_default();
        for piece in pieces.iter_mut().skip(n) {
            *piece = last;
        }
        let below = Piece::new(at(xs, 0), at(forces, 0), slope(0), 0.0, 0.0);
        // Points valid in f64 whose cubic coefficients overflow the working
        // type (points far apart in force and close in x).
        if let Some(i) = pieces.iter().take(n).position(|p| !p.fits()) {
            return Err(ParamError::NotFinite {
                param: Param::item("force", i),
            });
        }
        Ok(Self {
            pieces,
            below,
            len: n,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: a spline has at least two points.
    pub fn is_empty(&self) -> bool {
        false
    }
}

fn at(v: &[f64], i: usize) -> f64 {
    v.get(i).copied().unwrap_or(f64::NAN)
}

impl<T: Real, const N: usize> Backbone<T> for MonotoneSpline<T, N> {
    #[inline]
    fn eval(&self, x: T) -> (T, T) {
        let first = self.pieces.first().map_or(T::ZERO, |p| p.x0);
        if x < first {
            return self.below.eval(x);
        }
        // Which search: see the cost in the type's doc.
        let i = if cfg!(target_os = "none") || N > 8 {
            self.halving(x)
        } else {
            self.counting(x)
        };
        self.pieces.get(i).map_or((T::ZERO, T::ZERO), |p| p.eval(x))
    }
}

impl<T: Real, const N: usize> MonotoneSpline<T, N> {
    /// The largest i with x_i <= x (0 when there is none, or x is NaN),
    /// over the whole capacity (the pieces past `len` repeat the extension
    /// piece): `log2 N` halvings, each compare waiting on the last.
    #[inline(always)]
    fn halving(&self, x: T) -> usize {
        let mut base = 0usize;
        let mut size = N;
        while size > 1 {
            let half = size / 2;
            let mid = base + half;
            if self.pieces.get(mid).is_some_and(|p| p.x0 <= x) {
                base = mid;
            }
            size -= half;
        }
        base
    }

    /// The number of pieces after the first that start at or below x: `N
    /// - 1` compares independent of each other. The starts do not
    /// decrease, so the compares that hold are the first ones and their
    /// count is [`Self::halving`]'s index.
    #[inline(always)]
    fn counting(&self, x: T) -> usize {
        self.pieces.iter().skip(1).filter(|p| p.x0 <= x).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coefficients_that_overflow_the_working_type_are_refused() {
        // 1e39 is finite in f64 and infinite in f32, where Horner's scheme
        // would give inf * 0 = NaN at x = 0. Found by the step_models fuzzer.
        let c = [0.0, 1000.0, 1e39, 2.0];
        let r = Polynomial::<f32, 4>::new(&c, (0.0, 12.0));
        assert!(matches!(r, Err(ParamError::NotFinite { .. })), "{r:?}");
        assert!(Polynomial::<f64, 4>::new(&c, (0.0, 12.0)).is_ok());
        let r = MonotoneSpline::<f32, 4>::new(&[0.0, 1e-30, 1.0], &[0.0, 1e30, 2e30]);
        assert!(matches!(r, Err(ParamError::NotFinite { .. })), "{r:?}");
    }

    fn central_difference<B: Backbone<f64>>(b: &B, x: f64) -> f64 {
        let e = 1e-6 * (1.0 + x.abs());
        (b.eval(x + e).0 - b.eval(x - e).0) / (2.0 * e)
    }

    #[test]
    fn polynomial_value_tangent_and_linear_extension() {
        let p = Polynomial::<f64, 4>::new(&[1.0, 2.0, 0.0, 0.5], (-1.0, 2.0)).unwrap();
        assert_eq!(p.eval(1.0), (3.5, 3.5));
        // Beyond the range: the end value plus the end tangent times the overshoot.
        let (f_hi, k_hi) = p.eval(2.0);
        assert_eq!((f_hi, k_hi), (9.0, 8.0));
        assert_eq!(p.eval(3.0), (17.0, 8.0));
        assert_eq!(p.eval(-2.0), (-1.5 - 3.5, 3.5));
        // Inside the range (at its ends the backbone is only C1).
        for i in 1..60 {
            let x = -1.0 + 0.05 * i as f64;
            let (_, k) = p.eval(x);
            assert!((k - central_difference(&p, x)).abs() <= 1e-7 * k.abs());
        }
    }

    #[test]
    fn spare_spline_capacity_changes_nothing() {
        let xs = [-3.0, -1.0, 0.0, 0.4, 2.5];
        let fs = [-900.0, -160.0, 0.0, 70.0, 800.0];
        let exact = MonotoneSpline::<f64, 5>::new(&xs, &fs).unwrap();
        let roomy = MonotoneSpline::<f64, 16>::new(&xs, &fs).unwrap();
        let odd = MonotoneSpline::<f64, 7>::new(&xs, &fs).unwrap();
        for i in 0..=400 {
            let x = -5.0 + 0.025 * i as f64;
            assert_eq!(exact.eval(x), roomy.eval(x), "x = {x}");
            assert_eq!(exact.eval(x), odd.eval(x), "x = {x}");
        }
        for x in xs {
            assert_eq!(exact.eval(x), roomy.eval(x));
        }
    }

    #[test]
    fn polynomial_with_negative_tangent_is_refused() {
        // K = 1 - 3x^2 < 0 for |x| > 0.577.
        let e = Polynomial::<f64, 4>::new(&[0.0, 1.0, 0.0, -1.0], (-1.0, 1.0)).unwrap_err();
        assert!(matches!(e, ParamError::TangentNotPositive { .. }));
        // The same cubic on a range where it is monotone is accepted.
        assert!(Polynomial::<f64, 4>::new(&[0.0, 1.0, 0.0, -1.0], (-0.5, 0.5)).is_ok());
        // Interior minimum of the tangent just above zero: K = x^2 + 1e-3.
        assert!(Polynomial::<f64, 4>::new(&[0.0, 1e-3, 0.0, 1.0 / 3.0], (-1.0, 1.0)).is_ok());
        // ... and just below zero: K = (x - 0.3)^2 - 1e-4.
        let c = [0.0, 0.09 - 1e-4, -0.3, 1.0 / 3.0];
        assert!(matches!(
            Polynomial::<f64, 4>::new(&c, (-1.0, 1.0)),
            Err(ParamError::TangentNotPositive { .. })
        ));
    }

    #[test]
    fn polynomial_parameter_errors() {
        type P = Polynomial<f64, 3>;
        assert!(matches!(
            P::new(&[1.0], (0.0, 1.0)),
            Err(ParamError::TooFew { .. })
        ));
        assert!(matches!(
            P::new(&[0.0, 1.0, 0.0, 0.0], (0.0, 1.0)),
            Err(ParamError::TooMany {
                capacity: 3,
                got: 4,
                ..
            })
        ));
        assert_eq!(
            P::new(&[0.0, f64::NAN], (0.0, 1.0)),
            Err(ParamError::NotFinite {
                param: Param::item("coefficients", 1)
            })
        );
        assert_eq!(
            P::new(&[0.0, 1.0], (1.0, 1.0)),
            Err(ParamError::EmptyRange { lo: 1.0, hi: 1.0 })
        );
        assert!(matches!(
            P::linear(0.0),
            Err(ParamError::NotPositive { .. })
        ));
    }

    const XS: [f64; 7] = [-3.0, -2.0, -1.0, 0.0, 1.0, 1.5, 4.0];
    const FS: [f64; 7] = [-900.0, -350.0, -120.0, 0.0, 100.0, 180.0, 2000.0];

    #[test]
    fn spline_interpolates_and_is_monotone_with_positive_tangent() {
        let s = MonotoneSpline::<f64, 8>::new(&XS, &FS).unwrap();
        for (x, f) in XS.iter().zip(FS) {
            assert!((s.eval(*x).0 - f).abs() <= 1e-9 * f.abs().max(1.0));
        }
        let mut prev = f64::NEG_INFINITY;
        for i in 0..=2000 {
            let x = -4.0 + 9.0 * i as f64 / 2000.0;
            let (f, k) = s.eval(x);
            assert!(f > prev, "not increasing at {x}");
            assert!(k > 0.0, "tangent {k} at {x}");
            prev = f;
        }
    }

    #[test]
    fn spline_tangent_matches_central_difference_away_from_knots() {
        let s = MonotoneSpline::<f64, 8>::new(&XS, &FS).unwrap();
        for i in 0..400 {
            let x = -3.9 + 7.8 * (i as f64 + 0.37) / 400.0;
            if XS.iter().any(|k| (k - x).abs() < 1e-4) {
                continue;
            }
            let (_, k) = s.eval(x);
            let fd = central_difference(&s, x);
            assert!((k - fd).abs() <= 1e-6 * k, "x = {x}: {k} vs {fd}");
        }
    }

    #[test]
    fn spline_is_continuous_at_knots_and_extends_linearly() {
        let s = MonotoneSpline::<f64, 8>::new(&XS, &FS).unwrap();
        for &x in &XS[1..XS.len() - 1] {
            let (fl, kl) = s.eval(x - 1e-12);
            let (fr, kr) = s.eval(x);
            assert!((fl - fr).abs() < 1e-8);
            assert!((kl - kr).abs() < 1e-6 * kr);
        }
        let (f_end, k_end) = s.eval(4.0);
        assert_eq!(s.eval(5.0), (f_end + k_end, k_end));
        let (f_0, k_0) = s.eval(-3.0);
        assert_eq!(s.eval(-4.0), (f_0 - k_0, k_0));
    }

    /// The two searches give the same piece for every x: at, just below
    /// and just above each knot, between knots, beyond both ends, at the
    /// infinities and NaN; for every number of points a capacity holds,
    /// so with and without repeated extension pieces, and for capacities
    /// that are not powers of two.
    fn searches_agree<const N: usize>() {
        for n in 2..=N {
            let xs: [f64; N] =
                core::array::from_fn(|i| -3.0 + 1.25 * i as f64 + 0.1 * (i * i) as f64);
            let fs: [f64; N] = core::array::from_fn(|i| 100.0 * i as f64 + (i * i) as f64);
            let s = MonotoneSpline::<f32, N>::new(&xs[..n], &fs[..n]).unwrap();
            let probes = [
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                0.0,
                -0.0,
                -1e9,
                1e9,
            ];
            let check = |x: f32| {
                assert_eq!(s.halving(x), s.counting(x), "{n} points of {N}, x = {x}");
            };
            for x in probes {
                check(x);
            }
            for (i, &k) in xs.iter().take(n).enumerate() {
                let k = k as f32;
                for x in [k, k.next_down(), k.next_up()] {
                    check(x);
                }
                if let Some(&next) = xs.get(i + 1) {
                    check(0.5 * (k + next as f32));
                }
            }
        }
    }

    #[test]
    fn halving_and_counting_find_the_same_piece() {
        searches_agree::<2>();
        searches_agree::<5>();
        searches_agree::<8>();
        searches_agree::<13>();
        // The count is the largest index whose piece starts at or below x:
        // 6 points (the last at 1.5), so pieces 5 to 7 are the extension.
        let s = MonotoneSpline::<f32, 8>::new(&XS[..6], &FS[..6]).unwrap();
        assert_eq!(s.counting(-3.5), 0);
        assert_eq!(s.counting(-3.0), 0);
        assert_eq!(s.counting(0.5), 3);
        assert_eq!(s.counting(1.0), 4);
        assert_eq!(s.counting(1.5), 7);
        assert_eq!(s.halving(1.5), 7);
    }

    #[test]
    fn spline_parameter_errors() {
        type S = MonotoneSpline<f64, 4>;
        assert!(matches!(
            S::new(&[0.0], &[0.0]),
            Err(ParamError::TooFew { .. })
        ));
        assert!(matches!(
            S::new(&[0.0, 1.0, 2.0, 3.0, 4.0], &[0.0, 1.0, 2.0, 3.0, 4.0]),
            Err(ParamError::TooMany {
                capacity: 4,
                got: 5,
                ..
            })
        ));
        assert_eq!(
            S::new(&[0.0, 1.0, 1.0], &[0.0, 1.0, 2.0]),
            Err(ParamError::NotIncreasing {
                param: Param::item("x", 2)
            })
        );
        assert_eq!(
            S::new(&[0.0, 1.0, 2.0], &[0.0, 1.0, 1.0]),
            Err(ParamError::NotIncreasing {
                param: Param::item("force", 2)
            })
        );
        assert!(matches!(
            S::new(&[0.0, 1.0], &[0.0]),
            Err(ParamError::LengthMismatch { .. })
        ));
        assert_eq!(
            S::new(&[0.0, f64::INFINITY], &[0.0, 1.0]),
            Err(ParamError::NotFinite {
                param: Param::item("x", 1)
            })
        );
    }
}
