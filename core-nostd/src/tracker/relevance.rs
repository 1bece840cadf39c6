//! The Iwan relevance check of seed 004 §7.4.2: the damping an Iwan joint
//! must show, given how much its frequency drops with the amplitude, and
//! the inverse.
//!
//! For a mode whose restoring force is `f_r(p) = ω²(p) p` (unit modal mass,
//! secant stiffness ω², seed 004 eq 7.10) and that obeys Masing's rules, the
//! energy dissipated per cycle of amplitude `p_m` follows from the backbone
//! alone (seed 004 eq 7.13, `D = 8 ∫_0^{p_m} f_r dp - 4 p_m f_r(p_m)`), and
//! with `ξ = D / (2π ω²(p_m) p_m²)` (eq 7.9) the damping ratio is
//!
//! ```text
//! ξ(p_m) = 4 ∫_0^{p_m} p ω²(p) dp / (π p_m² ω²(p_m)) - 2/π
//! ```
//!
//! Only the ratios ω²(p)/ω²(p_m) enter: the damping of an Iwan joint is set
//! by its relative softening, whatever the units of ω and p. A measured
//! damping curve that disagrees with the one predicted from the measured
//! frequency curve says the joint is not an Iwan (Masing) system, or that a
//! parasitic damping ξ_0 (seed 004 §7.5.3) must be removed first.
//!
//! - [`damping_from_frequency_uniform`]: eq 7.17, the trapezoid rule on the
//!   uniform grid `p_m^n = n p_max / N` (eq 7.14).
//! - [`damping_from_frequency`]: the continuous form on any increasing grid,
//!   for the non-uniform amplitudes of a tracked free decay.
//! - [`frequency_from_damping_uniform`]: eq 7.18 as a forward recursion.
//!
//! All three are exact when `f_r` is piecewise linear with its kinks on the
//! grid (a discrete Iwan bank), and second order in the grid step otherwise.
//! They are post-processing: f64, no allocation (the caller owns the
//! slices), no panics; bad input is a typed [`ParamError`].
//!
//! Only ratios enter, and they are formed before anything is squared: each
//! running sum is kept in units of the current ω (and amplitude), rescaled
//! by exact powers of two as these change (`frexp`, `scalbn`). So no
//! square over- or underflows and every `Ok` result is finite; scaling
//! every ω (or amplitude) by a power of two changes no bit of it and by any
//! other factor changes it only by rounding; and where the direct f64
//! formulas stay in the normal range (every ordinary input) the results
//! are theirs bit for bit. What is refused for its size is what has no
//! answer in f64, or nearly: an ω more than 2^400 times below an ω at a
//! smaller amplitude (ξ of 1e240 and beyond), and in the inverse an ω_n
//! above the largest f64, each a [`ParamError::OutOfRange`] naming the
//! input and its bound.

use core::f64::consts::PI;

use crate::error::{Param, ParamError, positive};

/// Largest factor by which a frequency may fall below one at a smaller
/// amplitude, as a divisor: 2^-400 (3.9e-121). A larger drop would give a
/// damping ratio above 1e240, a number no joint has, and the bound keeps
/// every sum of the recursions far from overflow for any slice length.
const DROP_MIN: f64 = f64::from_bits((1023 - 400) << 52);

/// Checks a list of strictly positive finite values.
fn positive_list(name: &'static str, values: &[f64]) -> Result<(), ParamError> {
    for (i, &v) in values.iter().enumerate() {
        positive(Param::item(name, i), v)?;
    }
    Ok(())
}

/// Checks that no ω falls below [`DROP_MIN`] times the largest ω before it.
fn bounded_drop(omega: &[f64]) -> Result<(), ParamError> {
    let mut largest: f64 = 0.0;
    for (i, &w) in omega.iter().enumerate() {
        let min = largest * DROP_MIN;
        if w < min {
            return Err(ParamError::OutOfRange {
                param: Param::item("omega", i),
                value: w,
                min,
                min_open: false,
                max: f64::MAX,
            });
        }
        largest = largest.max(w);
    }
    Ok(())
}

/// Checks that `input` is not empty and that `output` has its length.
fn lengths(input: usize, output: &'static str, got: usize) -> Result<(), ParamError> {
    if input == 0 {
        return Err(ParamError::TooFew {
            param: Param::scalar(output),
            min: 1,
            got: 0,
        });
    }
    if got != input {
        return Err(ParamError::LengthMismatch {
            param: Param::scalar(output),
            expected: input,
            got,
        });
    }
    Ok(())
}

/// Damping predicted from the frequency curve on a uniform amplitude grid,
/// seed 004 eq 7.17.
///
/// `omega[k - 1]` is the frequency at `p_m^k = k p_max / N`, k = 1..N (any
/// unit: only ratios enter); `damping[n - 1]` receives
///
/// ```text
/// ξ_n = 2 (1 - n) / (π n) + 4 / (π n² ω_n²) Σ_{k=1}^{n-1} k ω_k²      (eq 7.17)
/// ```
///
/// the trapezoid rule applied to eq 7.13 with `f_r(0) = 0` (eqs 7.15-7.16).
/// `ξ_1 = 0` by construction and a constant ω gives ξ ≡ 0. Equal to
/// [`damping_from_frequency`] on the grid `n p_max / N`.
///
/// The sum is kept in units of the current ω_n (see the module docs), so
/// every accepted ω gives a finite ξ: frequencies near 1e±300 give the
/// damping of ordinary ones.
///
/// - Errors: `omega` empty ([`ParamError::TooFew`]), `damping` of another
///   length ([`ParamError::LengthMismatch`]), an ω not finite or not
///   positive ([`ParamError::NotFinite`], [`ParamError::NotPositive`], with
///   its index), an ω more than 2^400 (2.6e120) times below the largest ω
///   before it ([`ParamError::OutOfRange`] with its index and that bound:
///   ξ would exceed 1e240). `damping` is left untouched on error.
/// - Cost: N multiply-adds, N divisions and N exact power-of-two rescalings.
pub fn damping_from_frequency_uniform(
    omega: &[f64],
    damping: &mut [f64],
) -> Result<(), ParamError> {
    lengths(omega.len(), "damping", damping.len())?;
    positive_list("omega", omega)?;
    bounded_drop(omega)?;
    // Σ_{k < n} k ω_k² in units of 4^e, where ω_n = m 2^e.
    let (mut sum, mut e_sum) = (0.0, 0);
    for (i, (&w, xi)) in omega.iter().zip(damping.iter_mut()).enumerate() {
        let n = (i + 1) as f64;
        let (m, e) = libm::frexp(w);
        sum = libm::scalbn(sum, 2 * (e_sum - e));
        e_sum = e;
        let w2 = m * m;
        *xi = 2.0 * (1.0 - n) / (PI * n) + 4.0 * sum / (PI * n * n * w2);
        sum += n * w2;
    }
    Ok(())
}

/// Damping predicted from the frequency curve on any increasing amplitude
/// grid: the continuous form of seed 004 eq 7.17,
///
/// ```text
/// ξ(p_m) = 4 ∫_0^{p_m} p ω²(p) dp / (π p_m² ω²(p_m)) - 2/π
/// ```
///
/// with the integral by the trapezoid rule on `0, amplitude[0],
/// amplitude[1], ...`. Below the smallest amplitude ω is taken equal to
/// `omega[0]` (the low-amplitude plateau of a joint that sticks): the
/// first panel is then `amplitude[0]² ω_0² / 2`, exact, and
/// `damping[0] = 0`. The trapezoid rule integrates `f_r = p ω²` exactly
/// where it is linear, so the result is exact for a discrete Iwan bank
/// whose slip amplitudes are grid points.
///
/// For a tracked free decay, pass the envelope `p_m` (displacement
/// amplitude) in increasing order with the tracked natural frequency at
/// each; the prediction is as noisy as `ω(p_m)` relative to the lower
/// amplitudes: a relative error ε on `ω(p_m)` moves ξ by about
/// `-2 (ξ + 2/π) ε ≈ -1.3 ε`.
///
/// The integral is kept in units of the current amplitude and ω (see the
/// module docs), so every accepted amplitude and ω gives a finite ξ.
///
/// - Errors: empty or mismatched lists ([`ParamError::TooFew`],
///   [`ParamError::LengthMismatch`]), a non-finite or non-positive amplitude
///   or ω (with its index), an amplitude not above the one before it
///   ([`ParamError::NotIncreasing`]), an ω more than 2^400 (2.6e120) times
///   below the largest ω before it ([`ParamError::OutOfRange`] with its
///   index and that bound). `damping` is left untouched on error.
/// - Cost: about 6 N multiply-adds, N divisions and 3 N exact power-of-two
///   rescalings.
pub fn damping_from_frequency(
    amplitude: &[f64],
    omega: &[f64],
    damping: &mut [f64],
) -> Result<(), ParamError> {
    lengths(amplitude.len(), "omega", omega.len())?;
    lengths(amplitude.len(), "damping", damping.len())?;
    positive_list("amplitude", amplitude)?;
    positive_list("omega", omega)?;
    let mut previous = 0.0;
    for (i, &p) in amplitude.iter().enumerate() {
        if p <= previous {
            return Err(ParamError::NotIncreasing {
                param: Param::item("amplitude", i),
            });
        }
        previous = p;
    }
    bounded_drop(omega)?;
    // ∫_0^p f_r dp with f_r = p ω², trapezoid from (0, 0), in units of the
    // current amplitude p = m_p 2^e_p and ω = m_w 2^e_w: p0 in 2^e_p, f0 in
    // 2^(e_p + 2 e_w), the integral in 4^(e_p + e_w).
    let (mut integral, mut p0, mut f0) = (0.0, 0.0, 0.0);
    let (mut e_p0, mut e_w0) = (0, 0);
    for ((&p, &w), xi) in amplitude.iter().zip(omega).zip(damping.iter_mut()) {
        let ((p, e_p), (w, e_w)) = (libm::frexp(p), libm::frexp(w));
        let (dp, dw) = (e_p0 - e_p, e_w0 - e_w);
        (e_p0, e_w0) = (e_p, e_w);
        p0 = libm::scalbn(p0, dp);
        f0 = libm::scalbn(f0, dp + 2 * dw);
        integral = libm::scalbn(integral, 2 * (dp + dw));
        let f = p * w * w;
        integral += 0.5 * (p - p0) * (f0 + f);
        *xi = 4.0 * integral / (PI * p * f) - 2.0 / PI;
        (p0, f0) = (p, f);
    }
    Ok(())
}

/// Frequency curve from the damping curve on a uniform amplitude grid:
/// seed 004 eq 7.18, solved as the forward recursion of its lower
/// triangular system,
///
/// ```text
/// ω_n² = 4 Σ_{k=1}^{n-1} k ω_k² / (π n² ξ_n + 2 n (n - 1)),   n = 2..N,   ω_1 = ω_0
/// ```
///
/// (eq 7.17 multiplied by π n² ω_n²). `damping[n - 1]` is ξ at
/// `p_m^n = n p_max / N`; `damping[0]` is not used (eq 7.17 makes ξ_1 = 0)
/// and `omega[0] = omega0`, the frequency at the first grid amplitude. The
/// output has the unit of `omega0`. Remove any parasitic damping ξ_0 from
/// the curve first (seed 004 §7.5.3): the recursion ascribes all damping to
/// slip.
///
/// Noise on ξ propagates forward: each ω_n carries the errors of all the
/// damping values below it, weighted by the amplitudes.
///
/// The sum is kept as a mantissa and a power of four (see the module docs),
/// so the ratios `ω_n / ω_0` do not depend on `omega0` and every ω_n within
/// the range of f64 is returned; an ω_n below the smallest positive f64,
/// or whose ξ_n is so large (about 1e305 / n²) that the diagonal
/// overflows, is returned as 0.
///
/// - Errors: empty or mismatched lists, `omega0` not finite or not positive,
///   a non-finite ξ, and a ξ_n at or below `-2 (n - 1) / (π n)`, where the
///   diagonal `π n² ξ_n + 2 n (n - 1)` of eq 7.18 is no longer positive
///   ([`ParamError::OutOfRange`] with its index; a ξ_n a few ulps above
///   that bound whose rounded diagonal is not positive is refused too, with
///   itself as the reported bound). An ω_n beyond the largest f64:
///   [`ParamError::OutOfRange`] on `omega0`, with the largest `omega0` for
///   which every ω_n is finite as its upper bound. `omega` is left untouched
///   on error.
/// - Cost: 2 N multiply-adds, 2 N divisions and 2 N square roots (the
///   recursion runs once to check that every ω_n is finite, once to write).
pub fn frequency_from_damping_uniform(
    omega0: f64,
    damping: &[f64],
    omega: &mut [f64],
) -> Result<(), ParamError> {
    lengths(damping.len(), "omega", omega.len())?;
    positive(Param::scalar("omega0"), omega0)?;
    for (i, &xi) in damping.iter().enumerate().skip(1) {
        let n = (i + 1) as f64;
        let min = -2.0 * (n - 1.0) / (PI * n);
        if !xi.is_finite() {
            return Err(ParamError::NotFinite {
                param: Param::item("damping", i),
            });
        }
        // The diagonal exactly as the recursion rounds it (never NaN).
        let diagonal = PI * n * n * xi + 2.0 * n * (n - 1.0);
        if xi <= min || diagonal <= 0.0 {
            return Err(ParamError::OutOfRange {
                param: Param::item("damping", i),
                value: xi,
                min: min.max(xi),
                min_open: true,
                max: f64::MAX,
            });
        }
    }
    // Largest omega0 for which every ω_n is finite: omega0 f64::MAX / ω_n,
    // formed from ω_n = r 2^e and omega0 = m0 2^e0 without overflow.
    let (m0, e0) = libm::frexp(omega0);
    let max_mantissa = 2.0 - f64::EPSILON; // f64::MAX / 2^1023
    let (mut finite, mut limit) = (true, f64::MAX);
    inverse_recursion(omega0, damping, |_, r, e| {
        finite &= libm::scalbn(r, e).is_finite();
        if r > 0.0 {
            let room = libm::scalbn(m0 * max_mantissa / r, (e0 + 1023).saturating_sub(e));
            limit = limit.min(room);
        }
    });
    if !finite {
        return Err(ParamError::OutOfRange {
            param: Param::scalar("omega0"),
            value: omega0,
            min: 0.0,
            min_open: true,
            max: limit.min(omega0.next_down()),
        });
    }
    inverse_recursion(omega0, damping, |i, r, e| {
        if let Some(w) = omega.get_mut(i) {
            *w = libm::scalbn(r, e);
        }
    });
    Ok(())
}

/// The recursion of [`frequency_from_damping_uniform`] on checked input:
/// calls `emit(n - 1, r, e)` with `ω_n = r 2^e`, n = 1..N.
///
/// `Σ_{k<n} k ω_k² = s 4^e` with `s` kept in [1/2, 2) by exact power-of-four
/// rescaling, so nothing over- or underflows whatever `omega0`, and where
/// the direct f64 recursion stays in the normal range both round alike:
/// `ω_n = r 2^e` bit for bit.
fn inverse_recursion(omega0: f64, damping: &[f64], mut emit: impl FnMut(usize, f64, i32)) {
    let (m0, e0) = libm::frexp(omega0);
    emit(0, m0, e0);
    let (mut s, mut e) = (m0 * m0, e0);
    for (i, &xi) in damping.iter().enumerate().skip(1) {
        let n = (i + 1) as f64;
        // The diagonal is positive (checked) and at least an ulp of
        // 2 n (n - 1) when not infinite: w2 < 2^53 n².
        let w2 = 4.0 * s / (PI * n * n * xi + 2.0 * n * (n - 1.0));
        emit(i, libm::sqrt(w2), e);
        s += n * w2;
        let (_, k) = libm::frexp(s);
        let j = k >> 1; // s >= 1/2, so k >= 0
        s = libm::scalbn(s, -2 * j);
        e = e.saturating_add(j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;
    use alloc::vec::Vec;

    /// Slip amplitudes of the seed 004 §4.1 oscillator: 20 cells of
    /// stiffness 0.05 slipping from 0.2 to 2 m, beside ω_∞² = 5.
    fn phis() -> impl Iterator<Item = f64> + Clone {
        (0..20).map(|i| 0.2 + 1.8 * i as f64 / 19.0)
    }

    /// Virgin backbone f_r(p) of that oscillator.
    fn backbone(p: f64) -> f64 {
        5.0 * p + phis().map(|f| 0.05 * p.min(f)).sum::<f64>()
    }

    /// Exact secant damping: Masing dissipation Σ 4 f_i (p - φ_i) over
    /// 2π f_r(p) p (seed 004 eqs 7.9-7.10).
    fn secant_damping(p: f64) -> f64 {
        let d: f64 = phis()
            .filter(|&f| f < p)
            .map(|f| 4.0 * 0.05 * f * (p - f))
            .sum();
        d / (2.0 * PI * backbone(p) * p)
    }

    #[test]
    fn constant_frequency_gives_no_damping() {
        let omega = [2.5; 50];
        let mut xi = [1.0; 50];
        damping_from_frequency_uniform(&omega, &mut xi).unwrap();
        assert!(xi.iter().all(|x| x.abs() < 1e-14), "{xi:?}");
        let amps: Vec<f64> = (0..50).map(|i| 0.01 * 1.1f64.powi(i)).collect();
        let mut xi = [1.0; 50];
        damping_from_frequency(&amps, &omega, &mut xi).unwrap();
        assert!(xi.iter().all(|x| x.abs() < 1e-14), "{xi:?}");
    }

    #[test]
    fn uniform_and_continuous_forms_agree_on_the_uniform_grid() {
        let n = 200;
        let amps: Vec<f64> = (1..=n).map(|k| 0.3 * k as f64 / n as f64).collect();
        let omega: Vec<f64> = amps.iter().map(|p| 3.0 - p * p).collect();
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        damping_from_frequency_uniform(&omega, &mut a).unwrap();
        damping_from_frequency(&amps, &omega, &mut b).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-13, "{x} vs {y}");
        }
        assert_eq!(a[0], 0.0);
    }

    #[test]
    fn linear_loss_in_stiffness_matches_its_closed_form() {
        // Seed 004 §3.2: ω² = ω_0² (1 - c p) gives ξ = 2 c p / (3π (1 - c p)).
        // f_r = ω_0² (p - c p²) is quadratic, so the trapezoid error is known
        // exactly: on the uniform grid eq 7.17 returns ξ (1 - 1/n²).
        let (w0, c, n) = (2.0 * PI * 40.0, 0.19, 400);
        let omega: Vec<f64> = (1..=n)
            .map(|k| w0 * libm::sqrt(1.0 - c * k as f64 / n as f64))
            .collect();
        let mut xi = vec![0.0; n];
        damping_from_frequency_uniform(&omega, &mut xi).unwrap();
        for (k, &x) in xi.iter().enumerate() {
            let (nk, p) = ((k + 1) as f64, (k + 1) as f64 / n as f64);
            let exact = 2.0 * c * p / (3.0 * PI * (1.0 - c * p));
            assert!((x - exact * (1.0 - 1.0 / (nk * nk))).abs() < 1e-14);
        }
        // A 10 % frequency drop at p = 1: ξ = 4.98 %.
        let last = xi[n - 1];
        assert!((last - 0.049_78).abs() < 1e-5, "{last}");
        // Non-uniform (geometric) grid: second order in the largest step.
        let m = 2000;
        let amps: Vec<f64> = (0..m)
            .map(|i| 1e-3 * libm::pow(1e3, i as f64 / (m - 1) as f64))
            .collect();
        let omega: Vec<f64> = amps.iter().map(|p| w0 * libm::sqrt(1.0 - c * p)).collect();
        let mut xi = vec![0.0; m];
        damping_from_frequency(&amps, &omega, &mut xi).unwrap();
        let exact = 2.0 * c / (3.0 * PI * (1.0 - c));
        // Successive amplitudes 3.46e-3 apart in relative terms: measured
        // relative error -3.98e-6, a third of that step squared.
        let rel = xi[m - 1] / exact - 1.0;
        assert!(rel.abs() < 5e-6, "{rel:e}");
    }

    #[test]
    fn power_law_micro_slip_matches_its_closed_form() {
        // Seed 004 §3.2: ω² = ω_0² (1 - c p^(1+χ)) gives
        // ξ = 2 c (1+χ) p^(1+χ) / (π (3+χ) (1 - c p^(1+χ))).
        for chi in [-0.5, 0.0, 0.5, 1.0] {
            let (c, n) = (0.1, 4000);
            let amps: Vec<f64> = (1..=n).map(|k| k as f64 / n as f64).collect();
            let omega: Vec<f64> = amps
                .iter()
                .map(|&p| libm::sqrt(6.0 * (1.0 - c * libm::pow(p, 1.0 + chi))))
                .collect();
            let mut xi = vec![0.0; n];
            damping_from_frequency(&amps, &omega, &mut xi).unwrap();
            for &k in &[n / 10, n / 2, n] {
                let p = amps[k - 1];
                let s = c * libm::pow(p, 1.0 + chi);
                let exact = 2.0 * (1.0 + chi) * s / (PI * (3.0 + chi) * (1.0 - s));
                // Trapezoid error: relative (h / p)² = 1/k² times a
                // constant of order one (exactly 1 for χ = 0, 0.97 for
                // χ = 0.5, 1.25 for χ = -0.5).
                let bound = 1.3 / (k * k) as f64;
                assert!((xi[k - 1] / exact - 1.0).abs() < bound, "chi {chi} p {p}");
            }
        }
    }

    #[test]
    fn reference_oscillator_secant_damping_is_exact_on_its_kinks() {
        // Grid step 0.05/19 m puts every slip amplitude φ_i and every
        // amplitude of the seed 004 §4.1 table on a node: the trapezoid
        // rule is then exact for the piecewise-linear backbone.
        let n = 3800;
        let p_max = 10.0;
        let amps: Vec<f64> = (1..=n).map(|k| p_max * k as f64 / n as f64).collect();
        let omega: Vec<f64> = amps.iter().map(|&p| libm::sqrt(backbone(p) / p)).collect();
        let mut xi = vec![0.0; n];
        damping_from_frequency_uniform(&omega, &mut xi).unwrap();
        for (&p, &x) in amps.iter().zip(&xi) {
            assert!((x - secant_damping(p)).abs() < 1e-12, "p {p}");
        }
        // The table's secant column, to its printed digits (%).
        let table = [
            (0.2, 0.0),
            (0.3, 0.1274),
            (0.5, 0.3671),
            (0.75, 0.6393),
            (1.0, 0.9069),
            (1.5, 1.4376),
            (2.0, 1.9832),
            (3.0, 2.3614),
            (5.0, 1.9472),
            (10.0, 1.1825),
        ];
        for (p, printed) in table {
            let k = libm::round(p / p_max * n as f64) as usize;
            assert!(
                (100.0 * xi[k - 1] - printed).abs() <= 0.5e-4,
                "p {p}: {} vs {printed}",
                100.0 * xi[k - 1]
            );
        }
        // And the inverse recursion returns the secant frequency curve.
        let mut back = vec![0.0; n];
        frequency_from_damping_uniform(omega[0], &xi, &mut back).unwrap();
        for (a, b) in omega.iter().zip(&back) {
            assert!((a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn inverse_recursion_round_trips() {
        let n = 500;
        let omega: Vec<f64> = (1..=n)
            .map(|k| {
                let p = k as f64 / n as f64;
                10.0 * (1.0 - 0.08 * p * p) + 0.3 * libm::sin(7.0 * p) * p
            })
            .collect();
        let mut xi = vec![0.0; n];
        damping_from_frequency_uniform(&omega, &mut xi).unwrap();
        let mut back = vec![0.0; n];
        frequency_from_damping_uniform(omega[0], &xi, &mut back).unwrap();
        for (a, b) in omega.iter().zip(&back) {
            assert!((a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
        }
        // The frequency depends on the relative softening only: another
        // ω_0 scales the whole curve.
        frequency_from_damping_uniform(2.0 * omega[0], &xi, &mut back).unwrap();
        for (a, b) in omega.iter().zip(&back) {
            assert!((2.0 * a / b - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let mut out = [0.0; 3];
        assert_eq!(
            damping_from_frequency_uniform(&[], &mut []),
            Err(ParamError::TooFew {
                param: Param::scalar("damping"),
                min: 1,
                got: 0
            })
        );
        assert_eq!(
            damping_from_frequency_uniform(&[1.0, 1.0], &mut out),
            Err(ParamError::LengthMismatch {
                param: Param::scalar("damping"),
                expected: 2,
                got: 3
            })
        );
        assert_eq!(
            damping_from_frequency_uniform(&[1.0, f64::NAN, 1.0], &mut out),
            Err(ParamError::NotFinite {
                param: Param::item("omega", 1)
            })
        );
        assert_eq!(
            damping_from_frequency_uniform(&[1.0, 1.0, 0.0], &mut out),
            Err(ParamError::NotPositive {
                param: Param::item("omega", 2),
                value: 0.0
            })
        );
        assert_eq!(out, [0.0; 3], "left untouched");
        let w = [1.0; 3];
        assert_eq!(
            damping_from_frequency(&[0.1, 0.2], &w, &mut out),
            Err(ParamError::LengthMismatch {
                param: Param::scalar("omega"),
                expected: 2,
                got: 3
            })
        );
        assert_eq!(
            damping_from_frequency(&[0.1, 0.3, 0.3], &w, &mut out),
            Err(ParamError::NotIncreasing {
                param: Param::item("amplitude", 2)
            })
        );
        assert_eq!(
            damping_from_frequency(&[-0.1, 0.3, 0.4], &w, &mut out),
            Err(ParamError::NotPositive {
                param: Param::item("amplitude", 0),
                value: -0.1
            })
        );
        assert_eq!(
            damping_from_frequency(&[0.1, f64::INFINITY, 0.4], &w, &mut out),
            Err(ParamError::NotFinite {
                param: Param::item("amplitude", 1)
            })
        );
        assert_eq!(
            damping_from_frequency(&[0.1, 0.2, 0.4], &[1.0, -1.0, 1.0], &mut out),
            Err(ParamError::NotPositive {
                param: Param::item("omega", 1),
                value: -1.0
            })
        );
        assert_eq!(
            frequency_from_damping_uniform(0.0, &[0.0; 3], &mut out),
            Err(ParamError::NotPositive {
                param: Param::scalar("omega0"),
                value: 0.0
            })
        );
        assert_eq!(
            frequency_from_damping_uniform(f64::NAN, &[0.0; 3], &mut out),
            Err(ParamError::NotFinite {
                param: Param::scalar("omega0")
            })
        );
        assert_eq!(
            frequency_from_damping_uniform(1.0, &[0.0; 2], &mut out),
            Err(ParamError::LengthMismatch {
                param: Param::scalar("omega"),
                expected: 2,
                got: 3
            })
        );
        // n = 2: the diagonal 4π ξ_2 + 4 vanishes at ξ_2 = -1/π.
        let bad = -1.0 / PI;
        assert_eq!(
            frequency_from_damping_uniform(1.0, &[0.0, bad, 0.0], &mut out),
            Err(ParamError::OutOfRange {
                param: Param::item("damping", 1),
                value: bad,
                min: bad,
                min_open: true,
                max: f64::MAX
            })
        );
        assert_eq!(
            frequency_from_damping_uniform(1.0, &[0.0, 0.0, f64::NAN], &mut out),
            Err(ParamError::NotFinite {
                param: Param::item("damping", 2)
            })
        );
        // damping[0] is not read.
        frequency_from_damping_uniform(1.0, &[f64::NAN, 0.0, 0.0], &mut out).unwrap();
        assert_eq!(out, [1.0; 3]);
    }

    /// Eq 7.17 formed directly in f64 (the form before the rescaling): the
    /// reference for inputs whose squares stay in the normal range.
    fn direct_uniform(omega: &[f64]) -> Vec<f64> {
        let mut sum = 0.0;
        let mut out = Vec::new();
        for (i, &w) in omega.iter().enumerate() {
            let n = (i + 1) as f64;
            let w2 = w * w;
            out.push(2.0 * (1.0 - n) / (PI * n) + 4.0 * sum / (PI * n * n * w2));
            sum += n * w2;
        }
        out
    }

    /// The continuous form formed directly in f64.
    fn direct_continuous(amplitude: &[f64], omega: &[f64]) -> Vec<f64> {
        let (mut integral, mut p0, mut f0) = (0.0, 0.0, 0.0);
        let mut out = Vec::new();
        for (&p, &w) in amplitude.iter().zip(omega) {
            let f = p * w * w;
            integral += 0.5 * (p - p0) * (f0 + f);
            out.push(4.0 * integral / (PI * p * f) - 2.0 / PI);
            (p0, f0) = (p, f);
        }
        out
    }

    /// Eq 7.18 formed directly in f64.
    fn direct_inverse(omega0: f64, damping: &[f64]) -> Vec<f64> {
        let mut sum = omega0 * omega0;
        let mut out = vec![omega0];
        for (i, &xi) in damping.iter().enumerate().skip(1) {
            let n = (i + 1) as f64;
            let w2 = 4.0 * sum / (PI * n * n * xi + 2.0 * n * (n - 1.0));
            out.push(libm::sqrt(w2));
            sum += n * w2;
        }
        out
    }

    /// A softening curve with a wiggle, on n uniform amplitudes in (0, 1].
    fn wiggly(n: usize) -> Vec<f64> {
        (1..=n)
            .map(|k| {
                let p = k as f64 / n as f64;
                10.0 * (1.0 - 0.08 * p * p) + 0.3 * libm::sin(7.0 * p) * p
            })
            .collect()
    }

    #[test]
    fn ordinary_inputs_give_the_direct_formulas_bit_for_bit() {
        // The rescaling is by exact powers of two: where the direct form
        // neither over- nor underflows, every rounding is the same.
        let n = 3800;
        let amps: Vec<f64> = (1..=n).map(|k| 10.0 * k as f64 / n as f64).collect();
        let reference: Vec<f64> = amps.iter().map(|&p| libm::sqrt(backbone(p) / p)).collect();
        let geometric: Vec<f64> = (0..500)
            .map(|i| 1e-3 * libm::pow(1e3, i as f64 / 499.0))
            .collect();
        let falling: Vec<f64> = geometric
            .iter()
            .map(|p| 2.0 * PI * 40.0 * libm::sqrt(1.0 - 0.19 * p / 1e3))
            .collect();
        for omega in [reference.clone(), wiggly(500), falling.clone()] {
            let mut xi = vec![0.0; omega.len()];
            damping_from_frequency_uniform(&omega, &mut xi).unwrap();
            let direct = direct_uniform(&omega);
            assert!(
                xi.iter()
                    .zip(&direct)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
            let mut back = vec![0.0; omega.len()];
            frequency_from_damping_uniform(omega[0], &xi, &mut back).unwrap();
            let direct = direct_inverse(omega[0], &xi);
            assert!(
                back.iter()
                    .zip(&direct)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
        }
        for (a, w) in [(&amps, &reference), (&geometric, &falling)] {
            let mut xi = vec![0.0; a.len()];
            damping_from_frequency(a, w, &mut xi).unwrap();
            let direct = direct_continuous(a, w);
            assert!(
                xi.iter()
                    .zip(&direct)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
        }
    }

    #[test]
    fn scaled_inputs_give_the_same_ratios() {
        // Only ratios enter: frequencies (and amplitudes) scaled by 1e±200,
        // where the direct squares overflow or underflow, give the same
        // damping to 1e-12, and the inverse scales with omega0. A power of
        // two changes no bit.
        let n = 400;
        let omega = wiggly(n);
        let amps: Vec<f64> = (0..n)
            .map(|i| 1e-2 * libm::pow(1e2, i as f64 / (n - 1) as f64))
            .collect();
        let mut xi_u = vec![0.0; n];
        damping_from_frequency_uniform(&omega, &mut xi_u).unwrap();
        let mut xi_c = vec![0.0; n];
        damping_from_frequency(&amps, &omega, &mut xi_c).unwrap();
        let mut w_i = vec![0.0; n];
        frequency_from_damping_uniform(omega[0], &xi_u, &mut w_i).unwrap();
        let close = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| x.is_finite() && (x - y).abs() <= 1e-12)
        };
        let pow2 = libm::scalbn(1.0, 900);
        for scale in [1e200, 1e-200, 1e300, 1e-300, pow2, 1.0 / pow2] {
            let scaled: Vec<f64> = omega.iter().map(|w| w * scale).collect();
            let mut xi = vec![0.0; n];
            damping_from_frequency_uniform(&scaled, &mut xi).unwrap();
            assert!(close(&xi, &xi_u), "uniform, scale {scale:e}");
            for amp_scale in [1.0, 1e200, 1e-200, pow2] {
                let a: Vec<f64> = amps.iter().map(|p| p * amp_scale).collect();
                damping_from_frequency(&a, &scaled, &mut xi).unwrap();
                assert!(close(&xi, &xi_c), "scales {scale:e} {amp_scale:e}");
                if scale == pow2 && amp_scale == pow2 {
                    assert_eq!(xi, xi_c);
                }
            }
            let mut w = vec![0.0; n];
            frequency_from_damping_uniform(omega[0] * scale, &xi_u, &mut w).unwrap();
            for (a, b) in w.iter().zip(&w_i) {
                assert!((a / (b * scale) - 1.0).abs() < 1e-12, "inverse, {scale:e}");
            }
            if scale == pow2 {
                assert!(w.iter().zip(&w_i).all(|(a, b)| *a == b * scale));
            }
        }
        // The same curve 1e200 times smaller gave NaN in the direct form.
        let tiny: Vec<f64> = omega.iter().map(|w| w * 1e-200).collect();
        assert!(direct_uniform(&tiny)[1].is_nan());
    }

    #[test]
    fn extreme_magnitudes_give_finite_ratios() {
        let mut out = [f64::NAN; 2];
        for w in [1e-200, 1e200, 1e-308, 5e-324, f64::MAX] {
            damping_from_frequency_uniform(&[w, w], &mut out).unwrap();
            assert_eq!(out[0], 0.0, "{w:e}");
            assert!(out[1].abs() < 1e-16, "{w:e}: {out:?}");
            // (ξ_1 = 0 to the rounding of 2 p f / (π p f) - 2/π.)
            damping_from_frequency(&[1.0, 2.0], &[w, w], &mut out).unwrap();
            assert!(out.iter().all(|x| x.abs() < 1e-15), "{w:e}: {out:?}");
        }
        for p in [1e-300, 1e300, 5e-324] {
            damping_from_frequency(&[p, 2.0 * p], &[1.0, 1.0], &mut out).unwrap();
            assert!(out.iter().all(|x| x.abs() < 1e-15), "{p:e}: {out:?}");
        }
        // A constant ω is no damping however large (was [1e200, inf]):
        // ω_2 = ω_0 / √(1 + π ξ_2).
        for w0 in [1e200, 1e-200, 1e-320, f64::MAX / 2.0] {
            frequency_from_damping_uniform(w0, &[0.0, 0.1], &mut out).unwrap();
            assert_eq!(out[0], w0);
            let expected = w0 / libm::sqrt(1.0 + 0.1 * PI);
            let tol = if w0 < 1e-300 { 1e-8 } else { 1e-15 };
            assert!((out[1] / expected - 1.0).abs() < tol, "{w0:e}: {out:?}");
        }
        // Frequencies rising by 1e400: the lower ones weigh nothing at the
        // top, where ξ is the leading term alone.
        let mut out = [f64::NAN; 3];
        damping_from_frequency_uniform(&[1e-200, 1e-200, 1e200], &mut out).unwrap();
        assert_eq!(out[2], 2.0 * (1.0 - 3.0) / (PI * 3.0));
        damping_from_frequency(&[1.0, 2.0, 3.0], &[1e-200, 1e-200, 1e200], &mut out).unwrap();
        // Only the last panel counts: 4 (3 ω_3² / 2) / (9 π ω_3²) - 2/π.
        assert!((out[2] + 4.0 / (3.0 * PI)).abs() < 1e-15, "{out:?}");
        // At the largest accepted drop, 2^-400: ξ_2 = (2^800 - 1) / π.
        let edge = libm::scalbn(1.0, -400);
        let mut out = [f64::NAN; 2];
        damping_from_frequency_uniform(&[1.0, edge], &mut out).unwrap();
        let expected = libm::scalbn(1.0, 800) / PI;
        assert!((out[1] / expected - 1.0).abs() < 1e-15, "{out:?}");
        damping_from_frequency(&[1.0, 2.0], &[1.0, edge], &mut out).unwrap();
        // (4 ∫ / (π p² ω²) with ∫ = 2^-1 + (1 + 2^-799)/2 ... ≈ 1 / (2^-800))
        assert!(
            out[1].is_finite() && (out[1] / expected - 1.0).abs() < 1e-15,
            "{out:?}"
        );
    }

    #[test]
    fn answers_beyond_f64_are_typed_errors() {
        let mut out = [7.0; 2];
        // A drop of more than 2^400 below an earlier ω (ξ above 1e240).
        let below = libm::scalbn(1.0, -400).next_down();
        let drop = |value, min| {
            Err(ParamError::OutOfRange {
                param: Param::item("omega", 1),
                value,
                min,
                min_open: false,
                max: f64::MAX,
            })
        };
        assert_eq!(
            damping_from_frequency_uniform(&[1.0, below], &mut out),
            drop(below, libm::scalbn(1.0, -400))
        );
        assert_eq!(
            damping_from_frequency_uniform(&[1e200, 1e-200], &mut out),
            drop(1e-200, 1e200 * libm::scalbn(1.0, -400))
        );
        assert_eq!(
            damping_from_frequency(&[1.0, 2.0], &[1e200, 1e-200], &mut out),
            drop(1e-200, 1e200 * libm::scalbn(1.0, -400))
        );
        assert_eq!(out, [7.0; 2], "left untouched");

        // An ω_n beyond f64::MAX: ω_2 = 100 ω_0 with ω_0 = 1e307.
        let xi = (4e-4 - 4.0) / (4.0 * PI);
        let Err(ParamError::OutOfRange {
            param,
            value,
            min,
            min_open,
            max,
        }) = frequency_from_damping_uniform(1e307, &[0.0, xi], &mut out)
        else {
            panic!("not refused");
        };
        assert_eq!(
            (param, value, min, min_open),
            (Param::scalar("omega0"), 1e307, 0.0, true)
        );
        assert_eq!(out, [7.0; 2], "left untouched");
        let ratio = libm::sqrt(4.0 / (4.0 * PI * xi + 4.0));
        assert!((max * ratio / f64::MAX - 1.0).abs() < 1e-12, "{max:e}");
        // The bound itself is accepted and gives an ω_2 near f64::MAX.
        frequency_from_damping_uniform(max, &[0.0, xi], &mut out).unwrap();
        assert!(
            out[1].is_finite() && out[1] > 0.999_999 * f64::MAX,
            "{out:?}"
        );

        // ξ_n one ulp above its bound, where the rounded diagonal vanishes
        // (n = 15): the direct recursion returned inf with Ok.
        let n = 15.0;
        let bound = -2.0 * (n - 1.0) / (PI * n);
        let above = bound.next_up();
        assert_eq!(PI * n * n * above + 2.0 * n * (n - 1.0), 0.0);
        let mut damping = [0.0; 15];
        damping[14] = above;
        let mut out = [7.0; 15];
        assert_eq!(
            frequency_from_damping_uniform(1.0, &damping, &mut out),
            Err(ParamError::OutOfRange {
                param: Param::item("damping", 14),
                value: above,
                min: above,
                min_open: true,
                max: f64::MAX
            })
        );
        assert_eq!(out, [7.0; 15], "left untouched");
        // Two ulps above, the diagonal is positive: a large but finite ω.
        damping[14] = above.next_up();
        frequency_from_damping_uniform(1.0, &damping, &mut out).unwrap();
        assert!(out.iter().all(|w| w.is_finite() && *w > 0.0), "{out:?}");
    }
}
