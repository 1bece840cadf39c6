//! Regularised single hysteresis cells: Dahl (eq 1.43), Bouc-Wen (eq 1.44)
//! and Berg (eq 1.45), seed 000 §1.4.4 and seed 004 §2.5-2.7.
//!
//! The thesis fits them as comparators and does not retain them: after a
//! turning point they still switch on sign(ẋ), and Dahl and Berg do not
//! superpose loading and unloading curves (no Masing). They act in
//! displacement space and add their force to the bushing (no fraction of the
//! backbone). Each update here is exact or implicit in the travel
//! ξ = |x - x_{n-1}| of the step, so that a step much larger than the
//! cell's characteristic displacement saturates instead of overshooting.
//!
//! Dissipation is reported per step as a trapezoid of a density that is
//! never negative: for Dahl and Bouc-Wen, the power left after the elastic
//! storage F²/(2 k_0) of the initial stiffness k_0; for Berg, the density of
//! the Iwan model whose branch is Berg's hyperbola. Over a closed steady
//! loop the Dahl and Bouc-Wen energies equal the loop area.

use crate::bushing::{Drive, Effect, EffectOutput};
use crate::error::{Param, ParamError, positive, scaled};
use crate::real::{Real, clamp, rsqrt};

/// State shared by the single cells: last x and force (and, for Berg, the
/// last turning point and direction).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CellState<T> {
    x: T,
    force: T,
    slope: T,
    x_turn: T,
    f_turn: T,
    dir: i8,
}

impl<T: Real> CellState<T> {
    /// Cell force.
    pub fn force(&self) -> T {
        self.force
    }

    /// Commits a step that reached `x` with `force` and `slope`, and
    /// reports it.
    #[inline(always)]
    fn commit(&mut self, x: T, force: T, slope: T, dissipated: T) -> EffectOutput<T> {
        self.x = x;
        self.force = force;
        self.slope = slope;
        EffectOutput {
            force,
            tangent: slope,
            dissipated,
        }
    }
}

/// Dahl's friction cell (eq 1.43): `dF/dx = k_d (1 - s F / F_f)^α`,
/// s = sign(ẋ).
///
/// - **Update**: exact for a monotone step, in u = 1 - s F/F_f ∈ [0, 2]:
///   `u_n = u_{n-1} e^{-k_d ξ / F_f}` for α = 1, and
///   `u_n^{1-α} = u_{n-1}^{1-α} - (1-α) k_d ξ / F_f` (floored at 0: the cell
///   saturates in a finite travel) for α < 1, `+ (α-1) k_d ξ / F_f` for
///   α > 1. |F| <= F_f for any step, any α: no step limit.
/// - **States**: F and x_{n-1}.
/// - **Stiff regime**: k_d ξ / F_f ≫ 1 gives u_n → 0, the saturation s F_f.
/// - **Limits**: with α = 1 this is the x_f cell with ω = 0 on a linear
///   backbone (k_d = g K, F_f = g K x_f); it does not obey Masing (the slope
///   after a reversal from saturation is 2^α k_d).
/// - **Cost**: one `expm1` (α = 1) or two `powf` per step.
///
/// ```
/// use bushing::{Bushing, Dahl, ParamError, Polynomial};
///
/// // Initial stiffness 60 N/mm, friction force 8 N, exponent 1.
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (Dahl::new(60.0, 8.0, 1.0)?,))?;
/// let mut state = bushing.state_at(0.0);
/// let out = bushing.step(&mut state, 2.0);
/// // Far along one way the cell nears its friction force.
/// assert!(out.force > 207.0 && out.force <= 208.0);
/// assert!(Dahl::<f32>::new(60.0, -8.0, 1.0).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dahl<T> {
    k_d: T,
    f_f: T,
    inv_f_f: T,
    alpha: T,
    one_minus_alpha: T,
    inv_one_minus_alpha: T,
    unit: bool,
}

impl<T: Real> Dahl<T> {
    /// `k_d`: initial stiffness (N/mm); `f_f`: friction force (N); `alpha` > 0.
    pub fn new(k_d: f64, f_f: f64, alpha: f64) -> Result<Self, ParamError> {
        let k_d = scaled::<T>(Param::scalar("k_d"), k_d)?;
        let f_f = scaled::<T>(Param::scalar("f_f"), f_f)?;
        let alpha = positive(Param::scalar("alpha"), alpha)?;
        let unit = alpha == 1.0;
        Ok(Self {
            k_d: T::from_f64(k_d),
            f_f: T::from_f64(f_f),
            inv_f_f: T::from_f64(1.0 / f_f),
            alpha: T::from_f64(alpha),
            one_minus_alpha: T::from_f64(1.0 - alpha),
            inv_one_minus_alpha: T::from_f64(if unit { 0.0 } else { 1.0 / (1.0 - alpha) }),
            unit,
        })
    }

    /// u^α, with 0^α = 0.
    fn pow_alpha(&self, u: T) -> T {
        if self.unit {
            u
        } else if u > T::ZERO {
            u.powf(self.alpha)
        } else {
            T::ZERO
        }
    }
}

impl<T: Real> Dahl<T> {
    fn rest_slope(&self) -> T {
        self.k_d
    }
    /// One step of travel `xi` in direction `s`.
    #[inline(always)]
    fn advance(&self, st: &mut CellState<T>, drive: &Drive<T>, s: T, xi: T) -> EffectOutput<T> {
        let two = T::ONE + T::ONE;
        let u0 = (T::ONE - s * st.force * self.inv_f_f).max(T::ZERO).min(two);
        let c = self.k_d * self.inv_f_f * xi;
        let u1 = if self.unit {
            u0 + u0 * (-c).exp_m1()
        } else if u0 > T::ZERO {
            let v = u0.powf(self.one_minus_alpha) - self.one_minus_alpha * c;
            if v > T::ZERO {
                v.powf(self.inv_one_minus_alpha)
            } else {
                T::ZERO
            }
        } else {
            T::ZERO
        };
        let u1 = u1.max(T::ZERO).min(two);
        let force = s * self.f_f * (T::ONE - u1);
        let (p0, p1) = (
            (T::ONE - u0) * (T::ONE - self.pow_alpha(u0)),
            (T::ONE - u1) * (T::ONE - self.pow_alpha(u1)),
        );
        let slope = self.k_d * self.pow_alpha(u1);
        let dissipated = T::HALF * xi * self.f_f * (p0 + p1);
        st.commit(drive.x, force, slope, dissipated)
    }
}

/// Most iterations of the Bouc-Wen solver per step.
const MAX_ITERATIONS: u32 = 60;
/// Largest whole `n - 1` of a Bouc-Wen cell computed as products.
const MAX_WHOLE_POWER: u8 = 8;

/// `e` as a whole number up to [`MAX_WHOLE_POWER`], if it is one.
fn whole_power(e: f64) -> Option<u8> {
    let k = libm::round(e);
    (k == e && (0.0..=f64::from(MAX_WHOLE_POWER)).contains(&k)).then_some(k as u8)
}

/// How a Bouc-Wen cell forms |w|^(n-1) and finds its root.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Exponent {
    /// n = 1: the root in closed form.
    One,
    /// n = 2: the root in closed form.
    Two,
    /// n - 1 a whole number from 2 to [`MAX_WHOLE_POWER`]: that many
    /// products, Newton steps.
    Whole(u8),
    /// Any other n: `powf`, Newton steps.
    Real,
}

impl Exponent {
    fn of(n: f64) -> Self {
        match whole_power(n - 1.0) {
            Some(0) => Self::One,
            Some(1) => Self::Two,
            Some(k) => Self::Whole(k),
            None => Self::Real,
        }
    }
}

/// The Bouc-Wen cell (eq 1.44, the thesis's naming):
/// `Ḟ = α ẋ (A - (γ + β sign(ẋ) sign(F)) |F/α|^n)`, i.e. F = α z with
/// `dz/dx = A - (γ + β s sign(z)) |z|^n`.
///
/// - **Update**: backward Euler in the travel ξ on w = s z (z seen in the
///   direction of motion), `w_n = w_{n-1} + ξ f(w_n)` with
///   `f(w) = A - (γ + β sign(w)) |w|^n` decreasing in w. The root lies
///   between w_{n-1} and the ultimate value w_u = (A / (β + γ))^(1/n). For
///   n = 1 and n = 2 it is found in closed form (a division, or a square
///   root and a division); otherwise by Newton steps kept inside that
///   bracket, its ends included (bisection when a step leaves it), at most
///   60 iterations, done when a Newton correction is within 1e-12 (1 + |w|)
///   (4 ε (1 + |w|) in f32). Unconditionally stable:
///   w never leaves [min(w_{n-1}, w_u), max(w_{n-1}, w_u)], whatever ξ
///   and n.
/// - **States**: F and x_{n-1}.
/// - **Limits**: n > 0, A > 0, β > 0, -β < γ < β (the thesis's
///   constraints). First order in ξ: accuracy needs ξ ≪ w_u / A.
/// - **Cost**: n = 1: no iteration, one evaluation of f and two
///   divisions. n = 2: no iteration, one division and one `rsqrt` (Newton
///   steps, no libm), the slope from the same root; about 188 guest
///   instructions a step for a whole bushing on a Cortex-M4F
///   (`docs/accuracy-cost.md`, `friction`, `bouc-wen/n-2`). The step
///   dispatches once on the exponent, so each closed form runs its own
///   straight-line code. Other n: one `powf` per Newton
///   iteration, none when n is a whole number up to 9 (n - 1 products
///   instead); 2.6 iterations a step on average for n = 1.5 and 3, 1.95
///   for n = 8, under a sine in f64 (the test
///   `bouc_wen_takes_newton_steps_not_bisections`).
///
/// ```
/// use bushing::{BoucWen, Bushing, ParamError, Polynomial};
///
/// // α = 40 N/mm, A = 1, β = 0.75, γ = 0.25, n = 1.
/// let cell = BoucWen::new(40.0, 1.0, 0.75, 0.25, 1.0)?;
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (cell,))?;
/// let mut state = bushing.state_at(0.0);
/// let out = bushing.step(&mut state, 0.5);
/// assert!(out.force > 50.0 && out.tangent > 0.0);
/// // β must exceed |γ| for the loop to stay bounded.
/// assert!(BoucWen::<f32>::new(40.0, 1.0, 0.25, 0.75, 1.0).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoucWen<T> {
    alpha: T,
    a: T,
    /// γ + β and γ - β, the coefficient c of f for w >= 0 and w < 0,
    /// formed in the working type from its β and γ.
    c_pos: T,
    c_neg: T,
    n: T,
    n_minus_1: T,
    /// How the power and the root are formed.
    exponent: Exponent,
    /// Relative size of a Newton correction taken as converged: 1e-12, or
    /// 4 ε of the working type if that is larger (f32).
    tol: T,
    w_u: T,
    k0: T,
    inv_alpha: T,
    /// α / (2 A): halving is exact, so the energy is the same as with
    /// ½ and α / A as separate factors.
    half_alpha_over_a: T,
}

impl<T: Real> BoucWen<T> {
    /// Parameters as in eq 1.44: `alpha` (N/mm), `a`, `beta`, `gamma`, `n`.
    pub fn new(alpha: f64, a: f64, beta: f64, gamma: f64, n: f64) -> Result<Self, ParamError> {
        let alpha = scaled::<T>(Param::scalar("alpha"), alpha)?;
        let a = scaled::<T>(Param::scalar("a"), a)?;
        let beta = scaled::<T>(Param::scalar("beta"), beta)?;
        let n = scaled::<T>(Param::scalar("n"), n)?;
        if !(gamma.is_finite() && gamma.abs() < beta) {
            return Err(ParamError::NotPositive {
                param: Param::scalar("beta - |gamma|"),
                value: beta - gamma.abs(),
            });
        }
        // The ultimate displacement (a / (beta + gamma))^(1/n) must fit the
        // working type (a small n raises it to a large power).
        let w_u = scaled::<T>(
            Param::scalar("(a / (beta + gamma))^(1/n)"),
            libm::pow(a / (beta + gamma), 1.0 / n),
        )?;
        Ok(Self {
            alpha: T::from_f64(alpha),
            a: T::from_f64(a),
            c_pos: T::from_f64(gamma) + T::from_f64(beta),
            c_neg: T::from_f64(gamma) - T::from_f64(beta),
            n: T::from_f64(n),
            n_minus_1: T::from_f64(n - 1.0),
            exponent: Exponent::of(n),
            tol: T::from_f64(1e-12).max(T::EPSILON * T::from_f64(4.0)),
            w_u: T::from_f64(w_u),
            k0: T::from_f64(alpha * a),
            inv_alpha: T::from_f64(1.0 / alpha),
            half_alpha_over_a: T::from_f64(0.5 * alpha / a),
        })
    }

    /// Ultimate force α w_u.
    pub fn ultimate_force(&self) -> T {
        self.alpha * self.w_u
    }

    /// [`Self::rate_as`] with the cell's own exponent.
    #[cfg(test)]
    fn rate(&self, w: T) -> (T, T, T, T) {
        self.rate_as(w, self.exponent)
    }

    /// (f(w), f'(w), c = γ + β sign(w), |w|^n), with
    /// f(w) = A - c |w|^n and f'(w) = -n c |w|^(n-1) sign(w) <= 0, for
    /// `power` the cell's exponent (a constant where the step has
    /// dispatched on it, so that each exponent gets its own code).
    #[inline(always)]
    fn rate_as(&self, w: T, power: Exponent) -> (T, T, T, T) {
        let aw = w.abs();
        let (c, c_sign) = if w < T::ZERO {
            (self.c_neg, -self.c_neg)
        } else {
            (self.c_pos, self.c_pos)
        };
        if aw == T::ZERO {
            return (self.a, T::ZERO, c, T::ZERO);
        }
        let pow_n1 = match power {
            Exponent::One => T::ONE,
            Exponent::Two => aw,
            Exponent::Whole(k) => (0..k).fold(T::ONE, |p, _| p * aw),
            Exponent::Real => aw.powf(self.n_minus_1),
        };
        let pow_n = pow_n1 * aw;
        (self.a - c * pow_n, -self.n * c_sign * pow_n1, c, pow_n)
    }
}

impl<T: Real> BoucWen<T> {
    fn rest_slope(&self) -> T {
        self.k0
    }
    /// The root's bracket from `w0`: between it and w_u, ends included.
    #[inline(always)]
    fn bracket(&self, w0: T) -> (T, T) {
        if w0 < self.w_u {
            (w0, self.w_u)
        } else {
            (self.w_u, w0)
        }
    }

    /// [`Self::solve_as`] with the cell's own exponent.
    #[cfg(test)]
    fn solve(&self, w0: T, xi: T, f0: T) -> (T, T, u32) {
        self.solve_as(w0, xi, f0, self.exponent)
    }

    /// The backward-Euler root `w` of `g(w) = w - w0 - ξ f(w)` from `w0`
    /// (where `f(w0) = f0`), the slope `f(w) / g'(w)`, and the iterations
    /// taken, for `power` as in [`Self::rate_as`]. Newton steps inside the
    /// bracket between w0 and w_u (its ends included), bisection when a
    /// step leaves it; done when a Newton correction is within
    /// `tol (1 + |w|)` or the bracket is that narrow.
    #[inline(always)]
    fn solve_as(&self, w0: T, xi: T, f0: T, power: Exponent) -> (T, T, u32) {
        let (mut lo, mut hi) = self.bracket(w0);
        if let Exponent::One | Exponent::Two = power {
            let (w, slope_w, _, _) = self.solve_exact(w0, xi, (lo, hi), power == Exponent::Two);
            return (w, slope_w, 1);
        }
        let mut w = clamp(w0 + xi * f0, lo, hi);
        let mut slope_w = T::ZERO;
        let mut iterations = 0;
        while iterations < MAX_ITERATIONS {
            iterations += 1;
            let (f, df, _, _) = self.rate_as(w, power);
            let g = w - w0 - xi * f;
            let dg = T::ONE - xi * df; // >= 1
            slope_w = f / dg;
            if g > T::ZERO {
                hi = w;
            } else if g < T::ZERO {
                lo = w;
            } else {
                break;
            }
            let step = g / dg;
            let next = w - step;
            let tol = self.tol * (T::ONE + w.abs());
            if step.abs() <= tol {
                // Newton's own correction is below the tolerance: take it
                // (kept in the bracket) without another evaluation.
                w = clamp(next, lo, hi);
                break;
            }
            w = if next >= lo && next <= hi {
                next
            } else {
                T::HALF * (lo + hi)
            };
            if hi - lo <= tol {
                break;
            }
        }
        (w, slope_w, iterations)
    }

    /// [`Self::solve_as`] for n = 1 (`squared` false) and n = 2, in closed
    /// form, also returning c and |w|^n at the root (as [`Self::rate_as`]).
    /// With b = w0 + ξ A, g(0) = -b and g increasing: the root has the sign
    /// of b, and on that side f(w) = A - k w for n = 1, A - k w|w| for
    /// n = 2, with k = β + γ (b >= 0) or β - γ (b < 0), both positive.
    /// - n = 1: `w = b / (1 + ξ k)`, and the slope f(w) / g'(w) by
    ///   [`Self::rate_as`].
    /// - n = 2: `w = 2 b / (1 + r)` with `r = sqrt(u)`, `u = 1 + 4 ξ k |b|`,
    ///   the root of `ξ k w|w| + w - b = 0` written without cancellation.
    ///   There g'(w) = 1 + 2 ξ k |w| = r exactly, so the slope is
    ///   f(w) / r = f(w) · rsqrt(u), with r = u · rsqrt(u) (within 3e-7 in
    ///   `f32`, no libm call, no second division). The root is clamped to
    ///   the bracket against rounding (it then moves by a rounding error,
    ///   and g'(w) = r still holds to that). Beyond the guard, where the
    ///   Newton steps of `rsqrt` would overflow, r is libm's square root
    ///   and the slope f(w) / g'(w), as for other n.
    #[inline(always)]
    fn solve_exact(&self, w0: T, xi: T, (lo, hi): (T, T), squared: bool) -> (T, T, T, T) {
        let b = w0 + xi * self.a;
        // c of f on the root's side (the root, clamped or not, has the
        // sign of b: the bracket reaches past zero only towards w_u > 0),
        // and k = |c|.
        let c = if b < T::ZERO { self.c_neg } else { self.c_pos };
        let k = c.abs();
        if squared {
            let q = xi * k * b.abs();
            let u = T::ONE + ((q + q) + (q + q));
            if u < T::GUARD {
                let inverse = rsqrt(u);
                let w = clamp((b + b) / (T::ONE + u * inverse), lo, hi);
                // f(w) = A - c |w|²: what `rate` gives, without its
                // branches.
                let p = w * w;
                return (w, (self.a - c * p) * inverse, c, p);
            }
            let w = (b + b) / (T::ONE + u.sqrt());
            self.slope_at(clamp(w, lo, hi), xi, Exponent::Two)
        } else {
            self.slope_at(clamp(b / (T::ONE + xi * k), lo, hi), xi, Exponent::One)
        }
    }

    /// `(w, f(w) / g'(w), c, |w|^n)` at a root w.
    #[inline(always)]
    fn slope_at(&self, w: T, xi: T, power: Exponent) -> (T, T, T, T) {
        let (f, df, c, p) = self.rate_as(w, power);
        (w, f / (T::ONE - xi * df), c, p)
    }

    /// The root from `w0` (where `f(w0) = f0`), its slope, and c and
    /// |w|^n there.
    #[inline(always)]
    fn root(&self, w0: T, xi: T, f0: T, power: Exponent) -> (T, T, T, T) {
        if let Exponent::One | Exponent::Two = power {
            return self.solve_exact(w0, xi, self.bracket(w0), power == Exponent::Two);
        }
        let (w, slope_w, _) = self.solve_as(w0, xi, f0, power);
        let (_, _, c, p) = self.rate_as(w, power);
        (w, slope_w, c, p)
    }

    /// One step of travel `xi` in direction `s`.
    #[inline(always)]
    fn advance(&self, st: &mut CellState<T>, drive: &Drive<T>, s: T, xi: T) -> EffectOutput<T> {
        // One dispatch on the exponent; each closed form gets its own code.
        match self.exponent {
            Exponent::Two => self.advance_as(st, drive, s, xi, Exponent::Two),
            Exponent::One => self.advance_as(st, drive, s, xi, Exponent::One),
            power => self.advance_as(st, drive, s, xi, power),
        }
    }

    /// [`Self::advance`] with the exponent given.
    #[inline(always)]
    fn advance_as(
        &self,
        st: &mut CellState<T>,
        drive: &Drive<T>,
        s: T,
        xi: T,
        power: Exponent,
    ) -> EffectOutput<T> {
        let w0 = s * st.force * self.inv_alpha;
        let (f0, _, c0, p0) = self.rate_as(w0, power);
        let (w, slope_w, c1, p1) = self.root(w0, xi, f0, power);
        let force = s * self.alpha * w;
        let slope = self.alpha * slope_w;
        // P = (α / A) |ẋ| w c |w|^n >= 0 (w and c have the same sign).
        let density = |w: T, c: T, p: T| w * c * p;
        let dissipated = xi * self.half_alpha_over_a * (density(w0, c0, p0) + density(w, c1, p1));
        st.commit(drive.x, force, slope, dissipated)
    }
}

/// Berg's friction cell (eq 1.45, read as in Berg's paper: the denominator
/// carries the turning-point ratio α_T = s F_T / F_fmax, where the print
/// shows F - F_T):
///
/// ```text
/// F = F_T + (x - x_T) (F_fmax - s F_T) / (x_2 (1 - s F_T / F_fmax) + |x - x_T|)
/// ```
///
/// - **Update**: explicit and exact: each branch is a hyperbola from the last
///   turning point (x_T, F_T) towards s F_fmax, with initial slope
///   F_fmax / x_2 after every reversal. |F| < F_fmax for any step.
/// - **States**: F, x_{n-1}, the last turning point and the direction.
/// - **Limits**: one turning point only: inner loops do not close where they
///   started (no Madelung), and loading and unloading curves differ.
/// - **Dissipation**: the branch is H(d) = M d / (c + d), M = F_fmax - s F_T,
///   c = x_2 M / F_fmax, whose equivalent Iwan dissipates
///   `|ẋ| M d² / (2 (c + d)²)`.
/// - **Cost**: two divisions per step (by denominators >= max(x_2 (1 -
///   |F_T| / F_fmax), 2^-24 x_2) > 0: the floor keeps a branch that starts
///   saturated flat instead of 0/0), a few multiply-adds.
///
/// ```
/// use bushing::{Berg, Bushing, ParamError, Polynomial};
///
/// // Largest friction force 8 N, reached half way after x2 = 0.1 mm.
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (Berg::new(8.0, 0.1)?,))?;
/// let mut state = bushing.state_at(0.0);
/// let out = bushing.step(&mut state, 0.1);
/// assert!((out.force - 14.0).abs() < 0.01);
/// assert!(Berg::<f32>::new(8.0, 0.0).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Berg<T> {
    f_max: T,
    x2: T,
    inv_x2: T,
    inv_f_max: T,
    /// Floor of c, 2^-24 x_2: rounding can bring |F_T| to F_fmax, where c
    /// would vanish and a branch starting at its turning point divide 0/0.
    c_min: T,
}

impl<T: Real> Berg<T> {
    /// `f_max`: the largest friction force (N); `x2`: the displacement at
    /// which half of it is reached from rest (mm).
    pub fn new(f_max: f64, x2: f64) -> Result<Self, ParamError> {
        let f_max = scaled::<T>(Param::scalar("f_max"), f_max)?;
        let x2 = scaled::<T>(Param::scalar("x2"), x2)?;
        Ok(Self {
            f_max: T::from_f64(f_max),
            x2: T::from_f64(x2),
            inv_x2: T::from_f64(1.0 / x2),
            inv_f_max: T::from_f64(1.0 / f_max),
            c_min: T::from_f64(x2 * libm::ldexp(1.0, -24)),
        })
    }
}

impl<T: Real> Berg<T> {
    fn rest_slope(&self) -> T {
        self.f_max * self.inv_x2
    }
    /// One step of travel `xi` in direction `s`.
    #[inline(always)]
    fn advance(&self, st: &mut CellState<T>, drive: &Drive<T>, s: T, xi: T) -> EffectOutput<T> {
        let x = drive.x;
        let dir: i8 = if s > T::ZERO { 1 } else { -1 };
        if st.dir != 0 && dir != st.dir {
            st.x_turn = st.x;
            st.f_turn = st.force;
        }
        let m = self.f_max - s * st.f_turn;
        let c = (self.x2 * m * self.inv_f_max).max(self.c_min);
        let d0 = (st.x - st.x_turn).abs();
        let d1 = (x - st.x_turn).abs();
        // The only divisions of the three cells' explicit updates, by
        // c + d >= c = max(x_2 (1 - |F_T| / F_fmax), 2^-24 x_2) > 0.
        let q0 = d0 / (c + d0);
        let inv_den = T::ONE / (c + d1);
        let q1 = d1 * inv_den;
        let force = st.f_turn + s * m * q1;
        let slope = m * c * inv_den * inv_den;
        let dissipated = T::HALF * xi * T::HALF * m * (q0 * q0 + q1 * q1);
        st.dir = dir;
        st.commit(x, force, slope, dissipated)
    }
}

/// The [`Effect`] impl the three cells share: no fraction, no time step, a
/// relaxed state at x0 with the slope at rest, and a step that holds the
/// force when x does not move and otherwise advances by the travel.
macro_rules! single_cell_effect {
    ($($cell:ident),*) => {$(
        impl<T: Real> Effect<T> for $cell<T> {
            type State = CellState<T>;
            type Report = EffectOutput<T>;
            fn fraction(&self) -> f64 {
                0.0
            }
            fn dt(&self) -> Option<f64> {
                None
            }
            fn rest(&self, x0: T) -> CellState<T> {
                CellState {
                    x: x0,
                    x_turn: x0,
                    slope: self.rest_slope(),
                    ..CellState::default()
                }
            }
            #[inline]
            fn step(&self, st: &mut CellState<T>, drive: &Drive<T>) -> EffectOutput<T> {
                // x is within the guard and so is the last x: dx is a
                // number, zero or of a sign.
                let dx = drive.x - st.x;
                if dx == T::ZERO {
                    return EffectOutput {
                        force: st.force,
                        tangent: st.slope,
                        dissipated: T::ZERO,
                    };
                }
                let s = if dx > T::ZERO { T::ONE } else { -T::ONE };
                self.advance(st, drive, s, dx.abs())
            }
            #[inline(always)]
            fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
                *report
            }
        }
    )*};
}

single_cell_effect!(Dahl, BoucWen, Berg);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backbone::Polynomial;
    use crate::bushing::Bushing;
    use crate::xf::{XfBank, XfForm, XfSpec};

    #[test]
    fn berg_reversal_from_a_saturated_force_stays_finite() {
        // Far travel rounds |F| to F_fmax; a tiny step up and back then
        // reverses at a turning force of F_fmax, where c = 0 made the
        // branch 0/0. Found by the step_models fuzzer.
        let b = Bushing::new(
            Polynomial::<f32, 2>::linear(150.0).unwrap(),
            (Berg::<f32>::new(17.058468, 0.6624918).unwrap(),),
        )
        .unwrap();
        let mut s = b.state_at(0.0);
        for x in [-1e7f32, 0.0, 3.5e-44, 0.0, -1.0] {
            let out = b.step(&mut s, x);
            assert!(
                out.force.is_finite() && out.tangent.is_finite(),
                "at {x}: {out:?}"
            );
            assert!(out.dissipated.is_finite() && out.dissipated >= 0.0);
        }
    }

    #[test]
    fn parameters_whose_reciprocal_leaves_the_working_type_are_refused() {
        // x2 = 1e-40 is positive in f64 and zero in f32, where 1/x2 would
        // be infinite. Found by the step_models fuzzer.
        let r = Berg::<f32>::new(40.0, 1e-40);
        assert!(matches!(r, Err(ParamError::OutOfRange { .. })), "{r:?}");
        assert!(Berg::<f64>::new(40.0, 1e-40).is_ok());
        assert!(matches!(
            Dahl::<f32>::new(1e30, 1.0, 1.0),
            Err(ParamError::OutOfRange { .. })
        ));
        assert!(matches!(
            XfBank::<f32, 1>::new(XfForm::ExactRamp, &[XfSpec::hz(1.0, 0.1, 1e-30)], 1e-3),
            Err(ParamError::OutOfRange { .. })
        ));
    }

    fn run<E: Effect<f64, Report = EffectOutput<f64>>>(
        e: E,
        xs: impl Iterator<Item = f64>,
        mut visit: impl FnMut(f64, EffectOutput<f64>),
    ) {
        let b = Bushing::new(Polynomial::<f64, 2>::linear(1.0).unwrap(), (e,)).unwrap();
        let mut s = b.state_at(0.0);
        for x in xs {
            let o = b.step(&mut s, x);
            visit(x, o.effects.unwrap().0);
        }
    }

    /// Steps of `h` times the characteristic displacement, alternating.
    fn jumps(h: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..n).map(move |k| if k % 3 == 2 { -h } else { h * (k % 3) as f64 })
    }

    #[test]
    fn dahl_alpha_one_is_the_rate_independent_x_f_cell() {
        // k_d = g K = 5, F_f = g K x_f = 1 on K = 10, g = 0.5, x_f = 0.2.
        let xf = XfBank::<f64, 1>::new(
            XfForm::ExactRamp,
            &[XfSpec {
                omega: 0.0,
                g: 0.5,
                x_f: 0.2,
            }],
            1e-3,
        )
        .unwrap();
        let a = Bushing::new(Polynomial::<f64, 2>::linear(10.0).unwrap(), (xf,)).unwrap();
        let b = Bushing::new(
            Polynomial::<f64, 2>::linear(5.0).unwrap(),
            (Dahl::new(5.0, 1.0, 1.0).unwrap(),),
        )
        .unwrap();
        let (mut sa, mut sb) = (a.state_at(0.0), b.state_at(0.0));
        for k in 0..3000 {
            let x = 0.7 * libm::sin(0.01 * k as f64) + 0.2 * libm::sin(0.13 * k as f64);
            let fa = a.step(&mut sa, x).effects.unwrap().0;
            let fb = b.step(&mut sb, x).effects.unwrap().0;
            assert!(
                (fa.force - fb.force).abs() < 1e-12,
                "{k}: {} vs {}",
                fa.force,
                fb.force
            );
            assert!((fa.dissipated - fb.dissipated).abs() < 1e-3 * fa.dissipated.max(1e-9) + 1e-12);
        }
    }

    #[test]
    fn dahl_and_bouc_wen_stay_bounded_for_huge_steps_and_large_exponents() {
        for alpha in [0.3, 1.0, 2.0, 5.0] {
            let d = Dahl::<f64>::new(100.0, 2.0, alpha).unwrap();
            let x_c = 2.0 / 100.0;
            for h in [0.01, 1.0, 100.0] {
                run(d, jumps(h * x_c, 300), |_, o| {
                    assert!(
                        o.force.is_finite() && o.force.abs() <= 2.0 * (1.0 + 1e-12),
                        "dahl {alpha} {h}: {o:?}"
                    );
                    assert!(o.dissipated >= 0.0 && o.dissipated.is_finite());
                });
            }
        }
        for n in [0.5, 1.0, 2.0, 5.0, 20.0] {
            let bw = BoucWen::<f64>::new(100.0, 1.0, 30.0, 10.0, n).unwrap();
            let f_u = bw.ultimate_force();
            let x_c = f_u / 100.0;
            for h in [0.01, 1.0, 100.0] {
                run(bw, jumps(h * x_c, 300), |_, o| {
                    assert!(
                        o.force.is_finite() && o.force.abs() <= f_u * (1.0 + 1e-9),
                        "bw n={n} h={h}: {o:?} > {f_u}"
                    );
                    assert!(o.dissipated >= 0.0 && o.dissipated.is_finite());
                });
            }
        }
    }

    #[test]
    fn bouc_wen_converges_to_the_continuous_loop_and_energy_is_the_loop_area() {
        // n = 1, gamma = 0 (the x_f cell again): over the third, steady
        // cycle, closed at the same x and force, the reported energy tends to
        // the loop area (the stored energy returns to its value) at the
        // first order of the implicit update.
        let bw = BoucWen::<f64>::new(50.0, 1.0, 5.0, 0.0, 1.0).unwrap();
        let gap = |n: usize| {
            let (mut area, mut diss) = (0.0, 0.0);
            let mut last = (0.0, 0.0);
            let xs = (0..=3 * n)
                .map(move |k| 0.6 * libm::sin(core::f64::consts::TAU * k as f64 / n as f64));
            let mut k = 0;
            run(bw, xs, |x, o| {
                if k > 2 * n {
                    area += 0.5 * (o.force + last.1) * (x - last.0);
                    diss += o.dissipated;
                }
                last = (x, o.force);
                k += 1;
            });
            (diss - area).abs() / area
        };
        let (coarse, fine) = (gap(5_000), gap(20_000));
        assert!(fine < 1e-4, "{fine}");
        assert!(
            coarse / fine > 3.0,
            "first order expected: {coarse} -> {fine}"
        );
        // Saturation: alpha A / beta = 10 N.
        assert!((bw.ultimate_force() - 10.0).abs() < 1e-12);
    }

    /// The iterations of the Bouc-Wen solver on every step of a sine of
    /// 0.6 mm (600 steps a cycle, 3 cycles): the mean and the largest, and
    /// the largest residual |g(w)| / (1 + |w|) of the root taken.
    fn bouc_wen_iterations<T: Real>(n: f64) -> (f64, u32, f64) {
        let bw = BoucWen::<T>::new(50.0, 1.0, 5.0, 2.0, n).unwrap();
        let mut st = bw.rest(T::ZERO);
        let (mut sum, mut worst, mut residual) = (0u32, 0u32, 0.0f64);
        let steps = 1800;
        for k in 1..=steps {
            let x = T::from_f64(0.6 * libm::sin(core::f64::consts::TAU * k as f64 / 600.0));
            let dx = x - st.x;
            let s = if dx < T::ZERO { -T::ONE } else { T::ONE };
            let (w0, xi) = (s * st.force * bw.inv_alpha, dx.abs());
            let (f0, ..) = bw.rate(w0);
            let (w, _, it) = bw.solve(w0, xi, f0);
            let g = w - w0 - xi * bw.rate(w).0;
            residual = residual.max((g.abs() / (T::ONE + w.abs())).to_f64());
            sum += it;
            worst = worst.max(it);
            let drive = Drive {
                x,
                dx,
                f_inf: T::ZERO,
                df_inf: T::ZERO,
                k_inf: T::ONE,
            };
            bw.step(&mut st, &drive);
        }
        (f64::from(sum) / steps as f64, worst, residual)
    }

    #[test]
    fn bouc_wen_takes_newton_steps_not_bisections() {
        // n = 1 and 2 are solved in closed form: one evaluation, and the
        // residual of the backward-Euler equation at rounding level.
        for n in [1.0, 2.0] {
            let (mean, worst, residual) = bouc_wen_iterations::<f64>(n);
            assert!(mean == 1.0 && worst == 1, "n = {n}: {mean} mean");
            assert!(residual < 1e-15, "n = {n}: {residual}");
            let (mean, worst, residual) = bouc_wen_iterations::<f32>(n);
            assert!(mean == 1.0 && worst == 1, "f32, n = {n}: {mean} mean");
            assert!(residual < 1e-7, "f32, n = {n}: {residual}");
        }
        // Other exponents by Newton. Measured: 2.54 (n = 3), 2.59
        // (n = 1.5), 1.95 (n = 8) a step in f64; at most 1.90 in f32.
        for n in [3.0, 1.5, 8.0] {
            let (mean, worst, residual) = bouc_wen_iterations::<f64>(n);
            assert!(
                mean <= 3.0 && worst <= 4,
                "n = {n}: {mean} mean, {worst} worst"
            );
            assert!(residual < 1e-15, "n = {n}: {residual}");
        }
        for n in [3.0, 1.5, 8.0] {
            let (mean, worst, residual) = bouc_wen_iterations::<f32>(n);
            assert!(
                mean <= 2.5 && worst <= 3,
                "f32, n = {n}: {mean} mean, {worst} worst"
            );
            assert!(residual < 1e-7, "f32, n = {n}: {residual}");
        }
        assert_eq!(whole_power(2.0), Some(2));
        assert_eq!(whole_power(0.5), None);
        assert_eq!(whole_power(9.0), None);
    }

    #[test]
    fn bouc_wen_closed_forms_find_newtons_root() {
        // The same cell solved by Newton (the power through powf): the
        // roots agree to the solver's tolerance, on both sides of 0 and
        // for steps far beyond the cell's characteristic travel.
        for n in [1.0, 2.0] {
            let exact = BoucWen::<f64>::new(50.0, 1.0, 5.0, 2.0, n).unwrap();
            let mut newton = exact;
            newton.exponent = Exponent::Real;
            for w0 in [-0.6, -0.1, 0.0, 0.05, 0.4] {
                for xi in [1e-6, 1e-3, 0.1, 10.0] {
                    let (f0, ..) = exact.rate(w0);
                    let (w, slope, _) = exact.solve(w0, xi, f0);
                    let (w_n, slope_n, _) = newton.solve(w0, xi, f0);
                    let tol = 1e-11 * (1.0 + w.abs());
                    assert!((w - w_n).abs() <= tol, "n = {n}, {w0} {xi}: {w} {w_n}");
                    // At w = 0 (here b = 0 exactly) f' has a kink for
                    // n = 1: each solver reports a one-sided slope.
                    if w.abs() > 1e-9 {
                        assert!(
                            (slope - slope_n).abs() <= 1e-9 * (1.0 + slope.abs()),
                            "n = {n}, {w0} {xi}: {slope} {slope_n}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn berg_starts_every_branch_at_f_max_over_x2_and_tends_to_f_max() {
        let b = Berg::<f64>::new(3.0, 0.1).unwrap();
        let path = [0.05, 0.1, 50.0, 49.95, -50.0];
        run(b, path.into_iter(), |x, o| {
            if x == 0.05 {
                assert!((o.force - 1.0).abs() < 1e-12); // 3 * 0.05 / (0.1 + 0.05)
            }
            if x == 50.0 {
                assert!(o.force < 3.0 && o.force > 2.99);
            }
            if x == -50.0 {
                // From the turning point at 50 (F_T ~ 2.99), d = 100: the
                // hyperbola is 0.2 % short of -F_max.
                assert!(o.force > -3.0 && o.force < -2.98, "{}", o.force);
            }
            assert!(o.dissipated >= 0.0);
        });
        // Right after the reversal at 50 the slope is back to F_max / x2 = 30.
        let bushing = Bushing::new(Polynomial::<f64, 2>::linear(1.0).unwrap(), (b,)).unwrap();
        let mut st = bushing.state_at(0.0);
        bushing.step(&mut st, 50.0);
        let t = bushing
            .step(&mut st, 50.0 - 1e-7)
            .effects
            .unwrap()
            .0
            .tangent;
        assert!((t - 30.0).abs() < 1e-3, "{t}");
    }

    #[test]
    fn parameter_errors() {
        assert!(matches!(
            Dahl::<f64>::new(1.0, 1.0, 0.0),
            Err(ParamError::NotPositive { .. })
        ));
        assert!(matches!(
            BoucWen::<f64>::new(1.0, 1.0, 1.0, 1.0, 2.0),
            Err(ParamError::NotPositive { .. })
        ));
        assert!(matches!(
            BoucWen::<f64>::new(1.0, 1.0, 1.0, 0.0, -2.0),
            Err(ParamError::NotPositive { .. })
        ));
        assert!(matches!(
            Berg::<f64>::new(1.0, 0.0),
            Err(ParamError::NotPositive { .. })
        ));
    }
}
