//! Scalar unscented transform and first-order linearisation (seed 004
//! §3.2.4, eqs 3.34-3.40): the two ways the tracker's filters propagate a
//! mean and a variance through a nonlinear function, in one dimension.
//!
//! For `x = x̄ + ε` (eq 3.34) with `Var ε = P`, both estimate the mean and
//! the variance of `g(x)`:
//!
//! - **Linearisation** (the EKF's way): `E[g] ≈ g(x̄)`,
//!   `Var g ≈ g'(x̄)² P`, from the first term of the Taylor series (eq 3.37).
//! - **Unscented transform** (the UKF's way, eqs 3.35-3.36): three sigma
//!   points `x̄`, `x̄ ± γ √P` with the scaled weights of [`UtParams`] for
//!   n = 1 (`γ² = α² (1 + κ)`), `ḡ = Σ W_i^m g(x_i)` and
//!   `Σ = Σ W_i^c (g(x_i) - ḡ)²`. The points match the moments of ε up to
//!   the third (mean 0, variance P, skewness 0) and have the fourth moment
//!   `γ² P²`, so (eq 3.40) the mean is exact for any cubic g, and with
//!   `γ² = 3` (the Gaussian kurtosis; α = 1, κ = 2) and β = 0 the variance
//!   is exact for any quadratic g.
//!
//! The two sigma sets of Table 1 of seed 004 §3.2.4, for n = 1 and β = 0:
//! set 1 (two points ±√P, weights 1/2, centre weight 0) is α = 1, κ = 0;
//! set 2 (centre 2/3, ±√(3P) with weights 1/6) is α = 1, κ = 2. β adds
//! itself to the centre's covariance weight only, which changes the variance
//! as soon as `g(x̄) ≠ ḡ`: the moment-matching sets of the table have β = 0
//! (the tracker's default β = 2 does not give them). The thesis describes
//! set 2 as matching the normal kurtosis "4"; that is a misprint for 3, and
//! κ = 3 (points ±2√P) is a different set. The reproduction of the table,
//! the cubic used and which of its figures can be reproduced are in
//! `docs/unscented-table.md`.

use super::modal::UtParams;
use crate::error::{Param, ParamError};
use crate::real::Real;

/// Checks a mean and a variance given at run time: both finite, the
/// variance not negative.
fn check_moments<T: Real>(mean: T, variance: T) -> Result<(), ParamError> {
    if !mean.is_finite() {
        return Err(ParamError::NotFinite {
            param: Param::scalar("mean"),
        });
    }
    if !variance.is_finite() {
        return Err(ParamError::NotFinite {
            param: Param::scalar("variance"),
        });
    }
    if variance < T::ZERO {
        return Err(ParamError::OutOfRange {
            param: Param::scalar("variance"),
            value: variance.to_f64(),
            min: 0.0,
            min_open: false,
            max: f64::MAX,
        });
    }
    Ok(())
}

/// The unscented transform of one scalar random variable, weights
/// precomputed (seed 004 eqs 3.35-3.36, scaled weights of [`UtParams`] with
/// n = 1):
///
/// ```text
/// x_0 = x̄,  x_± = x̄ ± γ √P,          γ² = α² (1 + κ)
/// ḡ = W_0^m g(x_0) + W_1 (g(x_+) + g(x_-))
/// Σ = W_0^c (g(x_0) - ḡ)² + W_1 ((g(x_+) - ḡ)² + (g(x_-) - ḡ)²)
/// ```
///
/// with `W_0^m = 1 - 1/γ²`, `W_1 = 1/(2 γ²)`, `W_0^c = W_0^m + 1 - α² + β`.
///
/// - **States**: none; the weights are fixed at construction (in `f64`,
///   rounded to `T`).
/// - **Accuracy**: the sigma set has the first three moments of any
///   symmetric ε and the fourth moment `γ² P²`; the mean is exact for a
///   cubic g, the variance exact for a quadratic g when `γ² = 3` and β = 0
///   (Gaussian ε). No stability limit: a direct formula.
/// - **Cost** per call: three evaluations of g, one square root, about ten
///   multiply-adds; no division, no f64.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalarUt<T> {
    gamma: T,
    w0m: T,
    w0c: T,
    wi: T,
}

impl<T: Real> ScalarUt<T> {
    /// Weights of `ut` for one dimension, from [`UtParams::weights`]; bad
    /// parameters give its typed error.
    pub fn new(ut: &UtParams) -> Result<Self, ParamError> {
        let (gamma, w0m, w0c, wi) = ut.weights(1)?;
        Ok(Self {
            gamma: T::from_f64(gamma),
            w0m: T::from_f64(w0m),
            w0c: T::from_f64(w0c),
            wi: T::from_f64(wi),
        })
    }

    /// Spread γ: the outer sigma points sit at `x̄ ± γ √P`.
    pub fn spread(&self) -> T {
        self.gamma
    }

    /// Mean weights `(W_0^m, W_1)`: the centre's and each outer point's.
    /// `W_0^m + 2 W_1 = 1`.
    pub fn mean_weights(&self) -> (T, T) {
        (self.w0m, self.wi)
    }

    /// Covariance weights `(W_0^c, W_1)`.
    pub fn covariance_weights(&self) -> (T, T) {
        (self.w0c, self.wi)
    }

    /// The three sigma points `[x̄, x̄ + γ √P, x̄ - γ √P]`. A non-finite
    /// mean or variance, or a negative variance, is refused.
    pub fn sigma_points(&self, mean: T, variance: T) -> Result<[T; 3], ParamError> {
        check_moments(mean, variance)?;
        let d = self.gamma * variance.sqrt();
        Ok([mean, mean + d, mean - d])
    }

    /// `(ḡ, Σ)`: the unscented estimates of the mean and the variance of
    /// `g(x)` for x of mean `mean` and variance `variance` (eqs 3.35-3.36).
    /// A non-finite mean or variance, or a negative variance, is refused
    /// with a typed error; non-finite values of g are passed through.
    pub fn transform(
        &self,
        mean: T,
        variance: T,
        g: impl Fn(T) -> T,
    ) -> Result<(T, T), ParamError> {
        let [x0, xp, xm] = self.sigma_points(mean, variance)?;
        let (g0, gp, gm) = (g(x0), g(xp), g(xm));
        let gbar = self.w0m * g0 + self.wi * (gp + gm);
        let (e0, ep, em) = (g0 - gbar, gp - gbar, gm - gbar);
        let var = self.w0c * e0 * e0 + self.wi * (ep * ep + em * em);
        Ok((gbar, var))
    }
}

/// Unscented estimate `(ḡ, Σ)` of the mean and variance of `g(x)`, x of
/// mean `mean` and variance `variance` (seed 004 eqs 3.35-3.36), with the
/// weights of `ut` for one dimension: a one-off [`ScalarUt::new`] followed
/// by [`ScalarUt::transform`]. The weights are computed in `f64` on every
/// call; build a [`ScalarUt`] once for repeated use.
///
/// With β = 0, α = 1 and κ = 0 this is set 1 of Table 1 of seed 004
/// §3.2.4, with κ = 2 set 2. Cost: that of [`ScalarUt::transform`] plus one
/// `f64` square root.
pub fn unscented_scalar<T: Real>(
    ut: &UtParams,
    mean: T,
    variance: T,
    g: impl Fn(T) -> T,
) -> Result<(T, T), ParamError> {
    ScalarUt::new(ut)?.transform(mean, variance, g)
}

/// First-order linearisation (the EKF's propagation, seed 004 §3.2.4, the
/// first term of eq 3.37): `(g(x̄), g'(x̄)² P)` for x of mean `mean` and
/// variance `variance`, with the derivative `dg` supplied by the caller, as
/// the tracker's EKF does with its analytic Jacobians.
///
/// The derivative is not formed by a difference on purpose: a central
/// difference of step h adds `g''' h² / 6` to g' (for a cubic,
/// `d3 h²`), and with `h = √P` the result is exactly the variance of
/// unscented set 1, not the linearisation.
///
/// The mean misses `E[g] - g(x̄) = g''(x̄) P / 2 + …`; the variance misses
/// every term beyond the first (for a cubic with Gaussian x, see
/// `docs/unscented-table.md`). A non-finite mean or variance, or a negative
/// variance, is refused with a typed error. Cost: one evaluation of g and of
/// g', two multiplications.
pub fn linearised_scalar<T: Real>(
    mean: T,
    variance: T,
    g: impl Fn(T) -> T,
    dg: impl Fn(T) -> T,
) -> Result<(T, T), ParamError> {
    check_moments(mean, variance)?;
    let slope = dg(mean);
    Ok((g(mean), slope * slope * variance))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `g(x) = d0 + d1 e + d2 e² + d3 e³`, `e = x - c`.
    fn cubic(d: [f64; 4], c: f64) -> impl Fn(f64) -> f64 {
        move |x| {
            let e = x - c;
            d[0] + e * (d[1] + e * (d[2] + e * d[3]))
        }
    }

    /// Exact mean and variance of the cubic above for x ~ N(c, s²):
    /// E[ε²] = s², E[ε⁴] = 3 s⁴, E[ε⁶] = 15 s⁶, odd moments 0.
    fn gaussian_moments(d: [f64; 4], s: f64) -> (f64, f64) {
        let (a1, a2, a3) = (d[1] * s, d[2] * s * s, d[3] * s * s * s);
        (
            d[0] + a2,
            a1 * a1 + 6.0 * a1 * a3 + 2.0 * a2 * a2 + 15.0 * a3 * a3,
        )
    }

    fn set(kappa: f64, beta: f64) -> UtParams {
        UtParams::new(1.0, beta, kappa).unwrap()
    }

    const CUBICS: [[f64; 4]; 4] = [
        [1.0, 2.0, 3.0, 4.0],
        [-7.5, 0.3, -2.25, 0.125],
        [173.57, 100.0, 30.63, 0.5485],
        [0.0, -1.0, 0.0, 5.0],
    ];

    #[test]
    fn mean_weights_sum_to_one_and_sets_1_and_2_are_as_in_table_1() {
        for (alpha, beta, kappa) in [
            (1.0, 0.0, 0.0),
            (1.0, 2.0, 0.0),
            (1.0, 0.0, 2.0),
            (1.0, 0.0, 3.0),
            (0.5, 2.0, 1.0),
            (0.8, 2.0, 0.0),
        ] {
            let ut = ScalarUt::<f64>::new(&UtParams::new(alpha, beta, kappa).unwrap()).unwrap();
            let (w0, wi) = ut.mean_weights();
            assert!((w0 + 2.0 * wi - 1.0).abs() < 1e-9, "{alpha} {beta} {kappa}");
            let (c0, ci) = ut.covariance_weights();
            assert_eq!(ci, wi);
            assert!((c0 - (w0 + 1.0 - alpha * alpha + beta)).abs() < 1e-12);
            // The outer points carry the variance: 2 W_1 γ² = 1.
            assert!((2.0 * wi * ut.spread() * ut.spread() - 1.0).abs() < 1e-12);
        }
        let s1 = ScalarUt::<f64>::new(&set(0.0, 0.0)).unwrap();
        assert_eq!(s1.spread(), 1.0);
        assert_eq!(s1.mean_weights(), (0.0, 0.5));
        assert_eq!(s1.covariance_weights(), (0.0, 0.5));
        let s2 = ScalarUt::<f64>::new(&set(2.0, 0.0)).unwrap();
        assert!((s2.spread() - 3f64.sqrt()).abs() < 1e-15);
        let (w0, wi) = s2.mean_weights();
        assert!((w0 - 2.0 / 3.0).abs() < 1e-15 && (wi - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(
            s2.sigma_points(4.0, 4.0).unwrap(),
            [4.0, 4.0 + 2.0 * 3f64.sqrt(), 4.0 - 2.0 * 3f64.sqrt()]
        );
    }

    #[test]
    fn both_sets_give_the_exact_mean_of_any_cubic() {
        for d in CUBICS {
            for (m, s) in [(4.0, 1.0), (-2.0, 0.3), (0.0, 2.5)] {
                let (mean, _) = gaussian_moments(d, s);
                for kappa in [0.0, 2.0, 3.0] {
                    for beta in [0.0, 2.0] {
                        let (gbar, _) =
                            unscented_scalar(&set(kappa, beta), m, s * s, cubic(d, m)).unwrap();
                        let scale = d.iter().map(|c| c.abs()).sum::<f64>() * (1.0 + s).powi(3);
                        assert!(
                            (gbar - mean).abs() <= 1e-14 * scale,
                            "d {d:?} s {s} kappa {kappa}: {gbar} vs {mean}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn set_2_with_beta_0_gives_the_exact_variance_of_any_quadratic() {
        let ut = ScalarUt::<f64>::new(&set(2.0, 0.0)).unwrap();
        for d in CUBICS {
            let q = [d[0], d[1], d[2], 0.0];
            for (m, s) in [(4.0, 1.0), (-2.0, 0.3), (0.0, 2.5)] {
                let (_, var) = gaussian_moments(q, s);
                let (_, v) = ut.transform(m, s * s, cubic(q, m)).unwrap();
                assert!((v - var).abs() <= 1e-13 * var, "{q:?} {s}: {v} vs {var}");
            }
        }
        // Not so for a cubic: set 2 misses 6 d3² s⁶ (the ε⁶ moment is 9 s⁶
        // on the sigma points and 15 s⁶ for the Gaussian)...
        let d = [0.0, 1.0, 0.5, 0.25];
        let (_, var) = gaussian_moments(d, 1.0);
        let (_, v) = ut.transform(0.0, 1.0, cubic(d, 0.0)).unwrap();
        assert!((var - v - 6.0 * 0.25 * 0.25).abs() < 1e-14);
        // ...and set 1 (fourth moment 1 instead of 3) misses the quadratic
        // term: (d1 + d3)² instead of d1² + 6 d1 d3 + 2 d2² + 15 d3².
        let (_, v1) = unscented_scalar(&set(0.0, 0.0), 0.0, 1.0, cubic(d, 0.0)).unwrap();
        assert!((v1 - 1.25 * 1.25).abs() < 1e-14);
        // β only moves the centre's covariance weight: + β (g(x̄) - ḡ)².
        let (gbar, v1b) = unscented_scalar(&set(0.0, 2.0), 0.0, 1.0, cubic(d, 0.0)).unwrap();
        assert!((v1b - v1 - 2.0 * gbar * gbar).abs() < 1e-14);
    }

    #[test]
    fn linearisation_is_exact_for_affine_maps_only() {
        let (m, v) = linearised_scalar(4.0, 2.0, |x| 3.0 * x - 1.0, |_| 3.0).unwrap();
        assert_eq!((m, v), (11.0, 18.0));
        let d = [1.0, 2.0, 3.0, 4.0];
        let (m, v) = linearised_scalar(4.0, 1.0, cubic(d, 4.0), |_| 2.0).unwrap();
        let (mean, var) = gaussian_moments(d, 1.0);
        assert_eq!((m, v), (1.0, 4.0));
        assert!(mean - m == 3.0 && var > v);
    }

    #[test]
    fn bad_moments_and_parameters_are_typed_errors() {
        let ut = ScalarUt::<f32>::new(&UtParams::default()).unwrap();
        let id = |x: f32| x;
        assert_eq!(
            ut.transform(0.0, -1.0, id),
            Err(ParamError::OutOfRange {
                param: Param::scalar("variance"),
                value: -1.0,
                min: 0.0,
                min_open: false,
                max: f64::MAX,
            })
        );
        assert_eq!(
            ut.transform(f32::NAN, 1.0, id),
            Err(ParamError::NotFinite {
                param: Param::scalar("mean")
            })
        );
        assert_eq!(
            unscented_scalar(&UtParams::default(), 0.0, f64::INFINITY, |x| x),
            Err(ParamError::NotFinite {
                param: Param::scalar("variance")
            })
        );
        assert!(matches!(
            linearised_scalar(0.0f64, -1e-300, |x| x, |_| 1.0),
            Err(ParamError::OutOfRange { .. })
        ));
        // Parameters refused by UtParams::weights: α outside (0, 1], κ < 0.
        let bad = UtParams {
            alpha: 0.0,
            beta: 2.0,
            kappa: 0.0,
        };
        assert!(matches!(
            unscented_scalar(&bad, 0.0, 1.0, |x: f64| x),
            Err(ParamError::OutOfRange { param, .. }) if param.name == "alpha"
        ));
        let bad = UtParams {
            alpha: 1.0,
            beta: 0.0,
            kappa: -0.5,
        };
        assert!(matches!(
            ScalarUt::<f64>::new(&bad),
            Err(ParamError::OutOfRange { param, .. }) if param.name == "kappa"
        ));
        // The usual small-α set has W_0^c = 1 - 1/α² + 1 - α² + β < 0 in one
        // dimension: refused.
        assert!(ScalarUt::<f64>::new(&UtParams::new(1e-3, 2.0, 0.0).unwrap()).is_err());
        // A zero variance is valid: every point at the mean.
        assert_eq!(ut.transform(2.0, 0.0, |x| x * x), Ok((4.0, 0.0)));
    }
}
