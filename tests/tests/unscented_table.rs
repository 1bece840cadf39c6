//! Table 1 of seed 004 §3.2.4: errors on the mean and the variance of
//! g(x), x ~ N(4, 1), g a cubic, for the linearisation and the two sigma
//! sets, computed with the library's scalar transforms (eqs 3.34-3.40).
//! The thesis does not give its cubic; `docs/unscented-table.md` explains
//! the one used here, why the printed set-2 variance error (2.2 %) cannot
//! come out against the exact Gaussian moments of any cubic that matches
//! the other printed figures, and the reading under which all six do.
//!
//! Errors are relative, |approximation - reference| / reference, in %. A
//! printed figure is reproduced when the computed one is within half a unit
//! of its last printed digit.

use bushing::Real;
use bushing::tracker::{ScalarUt, UtParams, linearised_scalar, unscented_scalar};

/// Input mean and variance (std 1).
const MEAN: f64 = 4.0;
const VAR: f64 = 1.0;

/// The cubic of the reproduction: `g(x) = d0 + d1 e + d2 e² + d3 e³`,
/// `e = x - 4`.
const CUBIC: [f64; 4] = [173.57, 100.0, 30.63, 0.5485];

/// Printed figures, in %: (mean, variance) for linearisation, set 1, set 2.
const PRINTED: [[f64; 2]; 3] = [[15.0, 18.1], [0.0, 17.2], [0.0, 2.2]];
/// Half a unit of the last printed digit of each figure.
const HALF_UNIT: [[f64; 2]; 3] = [[0.5, 0.05], [0.5, 0.05], [0.5, 0.05]];

fn g<T: Real>(d: [f64; 4]) -> impl Fn(T) -> T {
    let [d0, d1, d2, d3] = d.map(T::from_f64);
    let c = T::from_f64(MEAN);
    move |x| {
        let e = x - c;
        d0 + e * (d1 + e * (d2 + e * d3))
    }
}

fn dg<T: Real>(d: [f64; 4]) -> impl Fn(T) -> T {
    let [_, d1, d2, d3] = d.map(T::from_f64);
    let (two, three) = (T::from_f64(2.0), T::from_f64(3.0));
    let c = T::from_f64(MEAN);
    move |x| {
        let e = x - c;
        d1 + e * (two * d2 + e * three * d3)
    }
}

/// Exact mean and variance of g(x) for x ~ N(4, 1): odd moments of e
/// vanish, E[e²] = 1, E[e⁴] = 3, E[e⁶] = 15.
fn exact(d: [f64; 4]) -> (f64, f64) {
    let [d0, d1, d2, d3] = d;
    (
        d0 + d2,
        d1 * d1 + 6.0 * d1 * d3 + 2.0 * d2 * d2 + 15.0 * d3 * d3,
    )
}

/// The same moments by the 4-point Gauss-Hermite rule of N(0, 1) (exact
/// up to degree 7, so for g² of degree 6): nodes ±√(3 ∓ √6), weights
/// (3 ± √6) / 12. An independent check of the closed form.
fn gauss_hermite(d: [f64; 4]) -> (f64, f64) {
    let s6 = 6f64.sqrt();
    let rule = [
        ((3.0 - s6).sqrt(), (3.0 + s6) / 12.0),
        ((3.0 + s6).sqrt(), (3.0 - s6) / 12.0),
    ];
    let f = g::<f64>(d);
    let nodes = rule
        .iter()
        .flat_map(|&(x, w)| [(MEAN + x, w), (MEAN - x, w)]);
    let mean: f64 = nodes.clone().map(|(x, w)| w * f(x)).sum();
    let var = nodes.map(|(x, w)| w * (f(x) - mean).powi(2)).sum();
    (mean, var)
}

/// UT parameters of a set: α = 1, the given κ and β; the fourth moment of
/// the sigma set is 1 + κ.
fn set(kappa: f64, beta: f64) -> UtParams {
    UtParams::new(1.0, beta, kappa).unwrap()
}

/// Signed relative errors in % of (linearisation, set 1, set 2 with the
/// given κ), computed in `T`, against the exact moments with the variance
/// scaled by `reference_scale`.
fn rows<T: Real>(d: [f64; 4], kappa_2: f64, reference_scale: f64) -> [[f64; 2]; 3] {
    let (mean, var) = exact(d);
    let var = var * reference_scale;
    let (m, v) = (T::from_f64(MEAN), T::from_f64(VAR));
    let lin = linearised_scalar(m, v, g::<T>(d), dg::<T>(d)).unwrap();
    let s1 = unscented_scalar(&set(0.0, 0.0), m, v, g::<T>(d)).unwrap();
    let s2 = ScalarUt::<T>::new(&set(kappa_2, 0.0))
        .unwrap()
        .transform(m, v, g::<T>(d))
        .unwrap();
    [lin, s1, s2].map(|(gm, gv)| {
        [
            100.0 * (gm.to_f64() - mean) / mean,
            100.0 * (gv.to_f64() - var) / var,
        ]
    })
}

fn assert_reproduced(name: &str, got: [[f64; 2]; 3]) {
    let labels = ["linearisation", "set 1", "set 2"];
    for (i, label) in labels.iter().enumerate() {
        for (j, what) in ["mean", "variance"].iter().enumerate() {
            let e = got[i][j].abs();
            assert!(
                (e - PRINTED[i][j]).abs() < HALF_UNIT[i][j],
                "{name}: {label} {what} error {e:.4} % does not round to {} %",
                PRINTED[i][j]
            );
        }
    }
}

#[test]
fn closed_form_moments_agree_with_gauss_hermite() {
    for d in [CUBIC, CUBIC_B, [1.0, -2.0, 3.0, -4.0]] {
        let (m, v) = exact(d);
        let (mq, vq) = gauss_hermite(d);
        assert!((m - mq).abs() <= 1e-13 * m.abs().max(1.0), "{d:?}");
        assert!((v - vq).abs() <= 1e-12 * v, "{d:?}: {v} vs {vq}");
    }
}

/// Linearisation row and set 1 row, and the set-2 mean, against the exact
/// Gaussian moments (κ = 2: kurtosis 3).
#[test]
fn linearisation_and_set_1_rows_and_set_2_mean_round_to_the_printed_figures() {
    let r64 = rows::<f64>(CUBIC, 2.0, 1.0);
    let r32 = rows::<f32>(CUBIC, 2.0, 1.0);
    for (name, r) in [("f64", r64), ("f32", r32)] {
        println!(
            "{name}: linearisation {:+.4} % / {:+.4} %, set 1 {:+.2e} % / {:+.4} %, set 2 {:+.2e} % / {:+.4} %",
            r[0][0], r[0][1], r[1][0], r[1][1], r[2][0], r[2][1]
        );
        // Five of the six printed figures (the sixth is the next test's).
        for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1), (2, 0)] {
            let e = r[i][j];
            assert!(
                (e.abs() - PRINTED[i][j]).abs() < HALF_UNIT[i][j],
                "{name}: row {i} column {j}: {e} vs {}",
                PRINTED[i][j]
            );
        }
        // Every approximation is below the exact value.
        assert!(r[0][0] < 0.0 && r[0][1] < 0.0 && r[1][1] < 0.0 && r[2][1] < 0.0);
    }
    // The means of both sets are exact for a cubic: zero up to rounding.
    // f64: below 1e-12 relative. f32: the sigma points are rounded to f32
    // (|x| <= 6, error <= 6 · 2⁻²⁴) and g is evaluated by Horner on terms
    // of about twice the result, so the mean carries a few ulp of f32:
    // bound 16 ε_f32 ≈ 1.9e-6 relative.
    for r in [r64[1][0], r64[2][0]] {
        assert!(r.abs() < 1e-10, "f64 set mean error {r} %");
    }
    for r in [r32[1][0], r32[2][0]] {
        assert!(
            r.abs() < 100.0 * 16.0 * f64::from(f32::EPSILON),
            "f32 set mean error {r} %"
        );
    }
    // f32 against f64: the variances (about 1.2e4, from values about 2e2)
    // keep a few ulp of f32, far below the 0.05 % rounding margin: bound
    // 1e-3 percentage point.
    for i in 0..3 {
        for j in 0..2 {
            assert!((r32[i][j] - r64[i][j]).abs() < 1e-3, "{i} {j}");
        }
    }
}

/// The set-2 variance error is the closed form `6 d3² / V` for kurtosis 3
/// (κ = 2) and `(2 d1 d3 + d2² + d3²) / V` for kurtosis 4 (κ = 3): 0.015 %
/// and 8.6 % for the cubic, neither the printed 2.2 %.
#[test]
fn set_2_variance_error_is_not_the_printed_one_for_either_kurtosis() {
    let [_, d1, d2, d3] = CUBIC;
    let (_, v) = exact(CUBIC);
    let k3 = rows::<f64>(CUBIC, 2.0, 1.0)[2][1];
    let k4 = rows::<f64>(CUBIC, 3.0, 1.0)[2][1];
    println!("set 2 variance error: kurtosis 3 {k3:+.4} %, kurtosis 4 {k4:+.4} %");
    assert!((k3 + 100.0 * 6.0 * d3 * d3 / v).abs() < 1e-9);
    assert!((k4 - 100.0 * (2.0 * d1 * d3 + d2 * d2 + d3 * d3) / v).abs() < 1e-9);
    assert!(k3.abs() < 0.05, "kurtosis 3 rounds to 0.0 %: {k3}");
    assert!((k4 - 8.6).abs() < 0.05, "kurtosis 4 rounds to 8.6 %: {k4}");
    for e in [k3, k4] {
        assert!((e.abs() - PRINTED[2][1]).abs() > 2.0, "{e}");
    }
}

/// Every cubic whose linearisation and set-1 variance errors round to the
/// printed 18.1 % and 17.2 % (all sign cases) has a set-2 variance error at
/// least 2 percentage points away from the printed 2.2 %, with either
/// kurtosis. Variance errors depend only on `d2/d1` and `d3/d1`; with
/// `d1 = 1` the two printed figures give V (from the linearisation,
/// `|1 - V| / V`), then `(1 + d3)²` (set 1), then `d2²` (from V).
#[test]
fn no_cubic_reproduces_all_three_printed_variance_errors() {
    let n = 20;
    let mut admissible = 0;
    let mut worst = f64::INFINITY;
    // Range of the set-2 variance error, in %, per branch (linearisation
    // under or over the exact variance) and kurtosis (3, 4).
    let mut range = [[(f64::INFINITY, 0.0f64); 2]; 2];
    for i in 0..=n {
        let e_lin = 0.1805 + 0.001 * i as f64 / n as f64;
        for j in 0..=n {
            let e_1 = 0.1715 + 0.001 * j as f64 / n as f64;
            for v in [1.0 / (1.0 - e_lin), 1.0 / (1.0 + e_lin)] {
                for s1 in [v * (1.0 - e_1), v * (1.0 + e_1)] {
                    for d3 in [s1.sqrt() - 1.0, -s1.sqrt() - 1.0] {
                        let d2_sq = (v - 1.0 - 6.0 * d3 - 15.0 * d3 * d3) / 2.0;
                        if d2_sq < 0.0 {
                            continue;
                        }
                        let d = [1.0, 1.0, d2_sq.sqrt(), d3];
                        let r3 = rows::<f64>(d, 2.0, 1.0);
                        let r4 = rows::<f64>(d, 3.0, 1.0);
                        // The construction does give the two printed figures.
                        assert!((r3[0][1].abs() - 18.1).abs() < 0.05 + 1e-9);
                        assert!((r3[1][1].abs() - 17.2).abs() < 0.05 + 1e-9);
                        let branch = usize::from(v < 1.0);
                        for (k, e) in [r3[2][1], r4[2][1]].into_iter().enumerate() {
                            worst = worst.min((e.abs() - PRINTED[2][1]).abs());
                            let r = &mut range[branch][k];
                            *r = (r.0.min(e.abs()), r.1.max(e.abs()));
                        }
                        admissible += 1;
                    }
                }
            }
        }
    }
    println!(
        "{admissible} admissible cubics; closest set-2 variance error is {worst:.3} pp from 2.2 %"
    );
    for (b, name) in ["under", "over"].iter().enumerate() {
        for (k, kurtosis) in [3, 4].iter().enumerate() {
            let (lo, hi) = range[b][k];
            println!("linearisation {name}, kurtosis {kurtosis}: set 2 {lo:.3} % .. {hi:.3} %");
        }
    }
    // One admissible cubic per point of the box in each branch.
    assert_eq!(admissible, 2 * (n + 1) * (n + 1));
    assert!(worst > 2.0, "a cubic comes within {worst} pp of 2.2 %");
}

/// A second cubic, for the biased-reference reading.
const CUBIC_B: [f64; 4] = [160.65, 100.0, 28.35, 0.55];
/// Reference variance 2.25 % above the exact one.
const REFERENCE_SCALE: f64 = 1.0225;

/// If the reference variance of the thesis was 2.25 % above the exact
/// Gaussian value (as a sample estimate easily is), all six printed figures
/// come out with kurtosis 3 (κ = 2) and the second cubic, in f64 and f32;
/// with kurtosis 4 (κ = 3) the set-2 figure is 5.3 %, not 2.2 %.
#[test]
fn all_six_figures_round_to_the_printed_ones_against_a_reference_2_25_percent_high() {
    let r64 = rows::<f64>(CUBIC_B, 2.0, REFERENCE_SCALE);
    let r32 = rows::<f32>(CUBIC_B, 2.0, REFERENCE_SCALE);
    for (name, r) in [("f64", r64), ("f32", r32)] {
        println!(
            "{name} (reference x {REFERENCE_SCALE}): linearisation {:+.4} % / {:+.4} %, set 1 {:+.2e} % / {:+.4} %, set 2 {:+.2e} % / {:+.4} %",
            r[0][0], r[0][1], r[1][0], r[1][1], r[2][0], r[2][1]
        );
        assert_reproduced(name, r);
    }
    for i in 0..3 {
        for j in 0..2 {
            assert!((r32[i][j] - r64[i][j]).abs() < 1e-3, "{i} {j}");
        }
    }
    let k4 = rows::<f64>(CUBIC_B, 3.0, REFERENCE_SCALE)[2][1];
    println!("kurtosis 4, same reference: set 2 variance error {k4:+.4} %");
    assert!((k4.abs() - PRINTED[2][1]).abs() > 2.0, "{k4}");
}
