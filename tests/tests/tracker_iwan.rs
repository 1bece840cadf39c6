//! Modal tracker on the free decay of the seed 004 §4.1 Iwan oscillator:
//! tracked frequency and damping against the harmonic-balance reference,
//! and the Iwan relevance check of eq 7.17 on the tracked curve.
//!
//! The oscillator: unit mass, ω_∞² = 5 N/m in parallel with 20 Jenkins
//! cells of stiffness 0.05 N/m slipping at φ_i = 0.2 + 1.8 (i - 1)/19 m.
//! It is struck at rest (initial velocity) so that its first peak is the
//! end of a virgin loading to p_0 = 5 m; the record starts at that peak,
//! which is exactly "released at rest from a virgin loading to 5 m" (seed
//! 004 §4.9) without a quasi-static ramp to simulate.
//!
//! `cargo test -p bushing-tests --test tracker_iwan -- --nocapture` prints
//! the tables of docs/iwan-tracking.md and the figures quoted there.

use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

use bushing::tracker::{
    Filter, Measured, ModalTracker, SensorFit, SensorSpec, Tuning, UtParams,
    damping_from_frequency, fit_first_period,
};
use bushing::{Bushing, IwanBank, IwanCellSpec, Oscillator, Polynomial, Real};
use bushing_tests::Noise;

/// Parallel linear stiffness ω_∞² (N/m, unit mass).
const K_INF: f64 = 5.0;
/// Stiffness of one Jenkins cell (N/m).
const K_CELL: f64 = 0.05;
/// First peak of the decay (m).
const P0: f64 = 5.0;
/// Integration step (s): period error (ω h)²/12 = 2e-8.
const H: f64 = 2e-4;
/// Sampling rate (Hz): 51 to 56 samples per period.
const FS: f64 = 20.0;
/// Record length (s): the envelope ends near 0.26 m.
const DURATION: f64 = 250.0;
/// Signal-to-noise ratio on the first peak (dB).
const SNR_DB: f64 = 50.0;
/// Samples of the start-value fit: one pseudo-period at 5 m (2.76 s).
const FIT_SAMPLES: usize = 56;
/// Convergence time before the comparison (s): two periods.
const T_CONV: f64 = 5.0;
/// Excluded amplitude band around full slip (m), `lo <= p_m <= hi`: the
/// measured errors exceed 0.3 points from 1.3 to 2.6 m; 0.1 m margin.
const BAND: (f64, f64) = (1.2, 2.7);
/// Acceptance bounds outside the band: relative frequency error and
/// absolute damping error (ratio, i.e. 0.3 percentage points).
const F_BOUND: f64 = 0.01;
const XI_BOUND: f64 = 0.003;
/// Bins of the eq 7.17 check and of the table: consecutive samples over
/// which the envelope drops by 10 % and that span at least one period.
const BIN_RATIO: f64 = 1.1;
const BIN_SAMPLES: usize = 56;

/// The tuning, in physical units (see docs/iwan-tracking.md).
fn tuning() -> Tuning {
    Tuning {
        frequency_walk: 5e-4,
        damping_walk: 1e-3,
        amplitude_walk: 5e-4,
        initial_frequency_error: 0.01,
        initial_damping_error: 0.005,
        initial_amplitude_error: 0.05,
        ..Tuning::default()
    }
}

fn phis() -> impl Iterator<Item = f64> + Clone {
    (0..20).map(|i| 0.2 + 1.8 * i as f64 / 19.0)
}

/// Virgin backbone f_r(p).
fn backbone(p: f64) -> f64 {
    K_INF * p + phis().map(|f| K_CELL * p.min(f)).sum::<f64>()
}

/// Its tangent just below p (cells with φ_i >= p still stick).
fn tangent(p: f64) -> f64 {
    K_INF + K_CELL * phis().filter(|&f| f >= p).count() as f64
}

/// Exact Masing dissipation per cycle of amplitude p: Σ 4 f_i (p - φ_i).
fn dissipation(p: f64) -> f64 {
    phis()
        .filter(|&f| f < p)
        .map(|f| 4.0 * K_CELL * f * (p - f))
        .sum()
}

/// First-harmonic (harmonic-balance) stiffness of a steady cycle of
/// amplitude p: ω_∞² plus, per cell, its in-phase Fourier coefficient over
/// p. A cell sticks over the first 2φ of each half cycle: with
/// cos β = 1 - 2φ/p, `k = K_CELL (β - sin 2β / 2) / π` (seed 004 eq 2.11).
fn harmonic_stiffness(p: f64) -> f64 {
    K_INF
        + phis()
            .map(|f| {
                if p <= f {
                    K_CELL
                } else {
                    let beta = (1.0 - 2.0 * f / p).acos();
                    K_CELL * (beta - 0.5 * (2.0 * beta).sin()) / PI
                }
            })
            .sum::<f64>()
}

/// The harmonic-balance reference (ω_HB, ξ_HB) at amplitude p, seed 004
/// eqs 2.11 and 7.9: ξ = D / (2π k_eq p²).
fn harmonic_balance(p: f64) -> (f64, f64) {
    let k = harmonic_stiffness(p);
    (k.sqrt(), dissipation(p) / (TAU * k * p * p))
}

/// The same stiffness by quadrature of the Masing loop built from the
/// backbone (descending branch f_r(p) - 2 f_r((p - x)/2)), midpoint rule
/// on `n` points of the half cycle.
fn harmonic_stiffness_by_quadrature(p: f64, n: usize) -> f64 {
    let mut sum = 0.0;
    for j in 0..n {
        let theta = PI * (j as f64 + 0.5) / n as f64;
        let x = p * theta.cos();
        sum += (backbone(p) - 2.0 * backbone(0.5 * (p - x))) * theta.cos();
    }
    2.0 * sum / n as f64 / p
}

/// Damping a free decay shows at amplitude p. Between two turning points
/// the energy stored in the cells that slip is the same, so the envelope
/// decays as D per cycle over the growth of the turning-point energy,
/// `dE/dp = p f_r'(p)`, not over `k_eq p²`: ξ = D / (2π p² f_r'(p)).
fn free_decay_damping(p: f64) -> f64 {
    dissipation(p) / (TAU * p * p * tangent(p))
}

/// The simulated decay, shared by every test.
struct Decay {
    /// Sample step (s).
    dt: f64,
    /// Noisy displacement samples, the first at the first peak.
    z: Vec<f64>,
    /// Noise standard deviation (m).
    noise: f64,
    /// Time and |p| of every turning point of the integration (noise
    /// free).
    peaks: Vec<(f64, f64)>,
}

fn decay() -> &'static Decay {
    static DECAY: OnceLock<Decay> = OnceLock::new();
    DECAY.get_or_init(|| {
        let cells: [IwanCellSpec; 20] = core::array::from_fn(|i| {
            IwanCellSpec::from_slip_distance(K_CELL / 6.0, 6.0, 0.2 + 1.8 * i as f64 / 19.0)
        });
        let restoring = Bushing::new(
            Polynomial::<f64, 2>::linear(K_INF + 20.0 * K_CELL).unwrap(),
            (IwanBank::<f64, 20>::new(&cells).unwrap(),),
        )
        .unwrap();
        let osc = Oscillator::new(restoring, H).unwrap();
        // Work of the virgin loading to P0: the kinetic energy to give.
        let work = 0.5 * K_INF * P0 * P0
            + phis()
                .map(|f| K_CELL * (0.5 * f * f + f * (P0 - f)))
                .sum::<f64>();
        let mut s = osc.state_at(0.0, (2.0 * work).sqrt(), 0.0);
        while osc.step(&mut s, 0.0).v > 0.0 {}
        let every = (1.0 / (FS * H)).round() as usize;
        let n = (DURATION * FS) as usize;
        let mut truth = Vec::with_capacity(n);
        let mut peaks = vec![(0.0, s.p().abs())];
        truth.push(s.p());
        let (mut p_prev, mut v_prev) = (s.p(), s.v());
        let mut steps = 0usize;
        for _ in 1..n {
            for _ in 0..every {
                let out = osc.step(&mut s, 0.0);
                assert!(out.converged);
                if (v_prev > 0.0) != (out.v > 0.0) && out.v != 0.0 {
                    let f = v_prev / (v_prev - out.v);
                    let t = (steps as f64 + f) * H;
                    peaks.push((t, (p_prev + f * (out.p - p_prev)).abs()));
                }
                steps += 1;
                (p_prev, v_prev) = (out.p, out.v);
            }
            truth.push(s.p());
        }
        let noise = truth[0] / 2f64.sqrt() * 10f64.powf(-SNR_DB / 20.0);
        let mut rng = Noise::new(4);
        let z = truth.iter().map(|p| p + noise * rng.gauss()).collect();
        Decay {
            dt: every as f64 * H,
            z,
            noise,
            peaks,
        }
    })
}

/// One tracked sample: envelope (m), natural frequency ω_0 (rad/s),
/// damping ratio, time (s).
#[derive(Debug, Clone, Copy)]
struct Sample {
    p: f64,
    omega: f64,
    xi: f64,
    t: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Case {
    EkfF32,
    UkfF32,
    EkfF64,
    UkfF64,
}

impl Case {
    fn filter(self) -> Filter {
        match self {
            Case::EkfF32 | Case::EkfF64 => Filter::Ekf,
            Case::UkfF32 | Case::UkfF64 => Filter::Ukf(UtParams::default()),
        }
    }
}

/// Tracks the decay: start values by least squares on the first
/// pseudo-period (seed 004 §3.3.1), then one update per sample.
fn run<T: Real>(filter: Filter, tuning: &Tuning) -> Vec<Sample> {
    let d = decay();
    let mut fit = [SensorFit::default()];
    let start = fit_first_period(d.dt, &[&d.z[..FIT_SAMPLES]], &mut fit).unwrap();
    let tracker = ModalTracker::<T, 4>::new(
        d.dt,
        &[SensorSpec {
            measured: Measured::Displacement,
            noise: d.noise,
        }],
        &[start.mode],
        &[fit[0].amplitude],
        tuning,
        filter,
    )
    .unwrap();
    let mut state = tracker.start();
    let mut out = Vec::with_capacity(d.z.len());
    for (k, &z) in d.z.iter().enumerate() {
        if k > 0 {
            let report = tracker.step(&mut state, &[T::from_f64(z)]);
            assert!(!report.repaired && report.accepted == 1, "{report:?}");
        }
        let m = tracker.mode(&state, 0);
        let (a, b) = tracker.displacement(&state, 0, 0);
        out.push(Sample {
            p: a.to_f64().hypot(b.to_f64()),
            omega: TAU * m.frequency.to_f64(),
            xi: m.damping.to_f64(),
            t: k as f64 * d.dt,
        });
    }
    out
}

fn tracked(case: Case) -> &'static [Sample] {
    static TRACKS: [OnceLock<Vec<Sample>>; 4] = [const { OnceLock::new() }; 4];
    TRACKS[case as usize].get_or_init(|| match case {
        Case::EkfF32 | Case::UkfF32 => run::<f32>(case.filter(), &tuning()),
        Case::EkfF64 | Case::UkfF64 => run::<f64>(case.filter(), &tuning()),
    })
}

fn in_band(p: f64) -> bool {
    p >= BAND.0 && p <= BAND.1
}

/// Worst errors against the harmonic-balance reference at the tracked
/// envelope, after the convergence time.
#[derive(Debug, Default, Clone, Copy)]
struct Worst {
    /// Outside the band: |Δω/ω|, |Δξ|.
    f_out: f64,
    xi_out: f64,
    /// Inside the band.
    f_in: f64,
    xi_in: f64,
    /// Amplitude of the worst damping error inside the band.
    xi_in_at: f64,
}

fn worst_against_reference(samples: &[Sample]) -> Worst {
    let mut w = Worst::default();
    for s in samples.iter().filter(|s| s.t >= T_CONV) {
        let (omega, xi) = harmonic_balance(s.p);
        let (ef, ez) = ((s.omega / omega - 1.0).abs(), (s.xi - xi).abs());
        if in_band(s.p) {
            w.f_in = w.f_in.max(ef);
            if ez > w.xi_in {
                w.xi_in = ez;
                w.xi_in_at = s.p;
            }
        } else {
            w.f_out = w.f_out.max(ef);
            w.xi_out = w.xi_out.max(ez);
        }
    }
    w
}

/// Tracked curve averaged over a bin of consecutive samples (at least one
/// period, and a 10 % drop of the envelope): means of the envelope, of
/// ω_0 and ξ, and of the references at each sample's envelope.
#[derive(Debug, Clone, Copy, Default)]
struct Bin {
    p: f64,
    omega: f64,
    xi: f64,
    omega_hb: f64,
    xi_hb: f64,
    xi_fd: f64,
    n: usize,
}

fn bins(samples: &[Sample]) -> Vec<Bin> {
    let mut out = Vec::new();
    let mut acc = Bin::default();
    let mut top = 0.0;
    for s in samples.iter().filter(|s| s.t >= T_CONV) {
        if acc.n == 0 {
            top = s.p;
        }
        let (omega, xi) = harmonic_balance(s.p);
        acc.p += s.p;
        acc.omega += s.omega;
        acc.xi += s.xi;
        acc.omega_hb += omega;
        acc.xi_hb += xi;
        acc.xi_fd += free_decay_damping(s.p);
        acc.n += 1;
        if acc.n >= BIN_SAMPLES && s.p * BIN_RATIO <= top {
            let n = acc.n as f64;
            out.push(Bin {
                p: acc.p / n,
                omega: acc.omega / n,
                xi: acc.xi / n,
                omega_hb: acc.omega_hb / n,
                xi_hb: acc.xi_hb / n,
                xi_fd: acc.xi_fd / n,
                n: acc.n,
            });
            acc = Bin::default();
        }
    }
    out.reverse();
    out
}

/// Eq 7.17 (continuous form) on the binned tracked curve.
fn relevance(bins: &[Bin]) -> Vec<f64> {
    let p: Vec<f64> = bins.iter().map(|b| b.p).collect();
    let w: Vec<f64> = bins.iter().map(|b| b.omega).collect();
    let mut xi = vec![0.0; bins.len()];
    damping_from_frequency(&p, &w, &mut xi).unwrap();
    xi
}

/// Worst |ξ_7.17 - ξ_tracked| over the bins outside and inside the band.
fn relevance_gap(samples: &[Sample]) -> (f64, f64) {
    let b = bins(samples);
    let predicted = relevance(&b);
    let (mut out, mut inside) = (0.0f64, 0.0f64);
    for (bin, x) in b.iter().zip(&predicted) {
        let gap = (x - bin.xi).abs();
        if in_band(bin.p) {
            inside = inside.max(gap);
        } else {
            out = out.max(gap);
        }
    }
    (out, inside)
}

/// The delay j (samples) that best matches `value(sample k)` with
/// `reference(envelope at sample k - j)` over the samples after the
/// convergence time whose envelope lies in `range`: the lag of a tracked
/// parameter behind the envelope.
fn lag(
    samples: &[Sample],
    range: (f64, f64),
    value: impl Fn(&Sample) -> f64,
    reference: impl Fn(f64) -> f64,
) -> usize {
    let fit: Vec<usize> = (0..samples.len())
        .filter(|&k| samples[k].t >= T_CONV && samples[k].p > range.0 && samples[k].p < range.1)
        .collect();
    let cost = |j: usize| -> f64 {
        fit.iter()
            .map(|&k| value(&samples[k]) - reference(samples[k.saturating_sub(j)].p))
            .map(|e| e * e)
            .sum()
    };
    (0..400)
        .min_by(|&a, &b| cost(a).total_cmp(&cost(b)))
        .unwrap_or(0)
}

/// Lag of the damping over its fall after full slip (2 m > p_m > 1 m),
/// against the free-decay damping.
fn damping_lag(samples: &[Sample]) -> usize {
    lag(samples, (1.0, 2.0), |s| s.xi, free_decay_damping)
}

/// Lag of the frequency where it changes fastest (1 m < p_m < 3.6 m),
/// against the HB frequency (which the decay follows, cycle by cycle).
fn frequency_lag(samples: &[Sample]) -> usize {
    lag(samples, (1.0, 3.6), |s| s.omega, |p| harmonic_balance(p).0)
}

/// Worst |ξ - ξ_fd(p_m(t - τ))| in the band: what is left of the in-band
/// error once the two causes (free-decay damping, lag τ) are accounted for.
fn residual_in_band(samples: &[Sample], lag: usize) -> f64 {
    (0..samples.len())
        .filter(|&k| samples[k].t >= T_CONV && in_band(samples[k].p))
        .map(|k| (samples[k].xi - free_decay_damping(samples[k.saturating_sub(lag)].p)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn harmonic_balance_reference_matches_the_seed_table() {
    // Seed 004 §4.1: p_m, ω_HB (rad/s), f_HB (Hz), ξ_HB (%), D (J).
    let table: [(f64, f64, f64, f64, f64); 10] = [
        (0.1, 2.44949, 0.38985, 0.0, 0.0),
        (0.3, 2.44647, 0.38937, 0.1274, 0.0043102),
        (0.5, 2.43735, 0.38792, 0.3669, 0.034238),
        (0.75, 2.42447, 0.38587, 0.6390, 0.13275),
        (1.0, 2.41115, 0.38375, 0.9064, 0.33108),
        (1.5, 2.38392, 0.37941, 1.4370, 1.1545),
        (2.0, 2.35621, 0.37500, 1.9826, 2.7663),
        (3.0, 2.31192, 0.36795, 2.3710, 7.1663),
        (5.0, 2.27463, 0.36202, 1.9645, 15.966),
        (10.0, 2.25051, 0.35818, 1.1930, 37.966),
    ];
    for (p, omega, f, xi, d) in table {
        let (w, x) = harmonic_balance(p);
        assert!((w - omega).abs() <= 0.5e-5, "ω_HB({p}) = {w}");
        assert!((w / TAU - f).abs() <= 0.5e-5, "f_HB({p}) = {}", w / TAU);
        assert!(
            (100.0 * x - xi).abs() <= 0.5e-4,
            "ξ_HB({p}) = {}",
            100.0 * x
        );
        let digits = if d > 0.0 {
            10f64.powf(d.log10().floor() - 4.0)
        } else {
            1e-12
        };
        assert!((dissipation(p) - d).abs() <= 0.5 * digits, "D({p})");
        // The closed form against a quadrature of the Masing loop.
        let q = harmonic_stiffness_by_quadrature(p, 20_000);
        assert!((q - w * w).abs() < 1e-8, "{q} vs {}", w * w);
    }
}

#[test]
fn free_decay_damping_differs_from_harmonic_balance_near_full_slip() {
    // Log decrement between peaks of the same sign (noise free), at their
    // geometric mean: it follows D / (2π p² f_r'), which exceeds ξ_HB by up
    // to 0.21 points around full slip, where f_r' has dropped to ω_∞² and
    // k_eq has not.
    let d = decay();
    assert!(d.peaks.len() > 150, "{} turning points", d.peaks.len());
    let (mut worst_fd, mut largest_hb, mut worst_f): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for w in d.peaks.windows(3) {
        let p = (w[0].1 * w[2].1).sqrt();
        let xi = (w[0].1 / w[2].1).ln() / TAU;
        worst_fd = worst_fd.max((xi - free_decay_damping(p)).abs());
        largest_hb = largest_hb.max(xi - harmonic_balance(p).1);
        // The cycle's frequency, at the amplitude of its middle turning
        // point: the free decay oscillates at the HB frequency.
        let omega = TAU / (w[2].0 - w[0].0);
        worst_f = worst_f.max((omega / harmonic_balance(w[1].1).0 - 1.0).abs());
    }
    eprintln!(
        "log decrement: within {:.4} points of D/(2π p² f_r'); up to {:.3} points above ξ_HB; \
         cycle frequency within {:.3} % of ω_HB",
        100.0 * worst_fd,
        100.0 * largest_hb,
        100.0 * worst_f
    );
    assert!(worst_fd < 1e-4, "free-decay damping off by {worst_fd}");
    assert!(largest_hb > 0.0018 && largest_hb < 0.0023, "{largest_hb}");
    assert!(worst_f < 5e-4, "cycle frequency off by {worst_f}");
    // The decay reaches the bottom of the slip range.
    assert!(d.peaks.last().unwrap().1 < 0.26);
}

/// The figures of one case.
#[derive(Debug, Clone, Copy)]
struct Figures {
    worst: Worst,
    /// Worst eq 7.17 gap over the bins outside and inside the band.
    gap_out: f64,
    gap_in: f64,
    /// Lag of the damping (s).
    lag: f64,
    /// In-band residual once the lag and the free-decay damping are
    /// accounted for.
    residual: f64,
    /// Lag of the frequency (s), and the worst relative frequency error
    /// once it is accounted for.
    f_lag: f64,
    f_residual: f64,
}

fn figures(samples: &[Sample]) -> Figures {
    let (gap_out, gap_in) = relevance_gap(samples);
    let lag = damping_lag(samples);
    let f_lag = frequency_lag(samples);
    let f_residual = (0..samples.len())
        .filter(|&k| samples[k].t >= T_CONV)
        .map(|k| {
            let reference = harmonic_balance(samples[k.saturating_sub(f_lag)].p).0;
            (samples[k].omega / reference - 1.0).abs()
        })
        .fold(0.0, f64::max);
    Figures {
        worst: worst_against_reference(samples),
        gap_out,
        gap_in,
        lag: lag as f64 * decay().dt,
        residual: residual_in_band(samples, lag),
        f_lag: f_lag as f64 * decay().dt,
        f_residual,
    }
}

/// The acceptance checks of one case.
fn check(case: Case) {
    let f = figures(tracked(case));
    let w = f.worst;
    eprintln!("{case:?}: {f:?}");
    // The acceptance bounds away from full slip.
    assert!(w.f_out < F_BOUND, "{case:?}: frequency {}", w.f_out);
    assert!(w.xi_out < XI_BOUND, "{case:?}: damping {}", w.xi_out);
    assert!(f.gap_out < XI_BOUND, "{case:?}: eq 7.17 {}", f.gap_out);
    // Near full slip: the frequency still holds, and so does the eq 7.17
    // check on the bin averages; the damping error measured there (0.48
    // points) is documented, and what is left of it once the free-decay
    // damping and the lag are accounted for is within the bound.
    assert!(w.f_in < F_BOUND, "{case:?}: frequency in band {}", w.f_in);
    assert!(w.xi_in < 0.005, "{case:?}: damping in band {}", w.xi_in);
    assert!(
        f.gap_in < XI_BOUND,
        "{case:?}: eq 7.17 in band {}",
        f.gap_in
    );
    assert!(
        f.residual < XI_BOUND,
        "{case:?}: unexplained {}",
        f.residual
    );
    // The lag: a fraction of a period (measured 0.65).
    let periods = f.lag / period_at_full_slip();
    assert!(
        periods > 0.4 && periods < 0.9,
        "{case:?}: lag {periods} periods"
    );
}

/// Period of the harmonic-balance frequency at 1.5 m, the middle of the
/// fall of ξ after full slip (s).
fn period_at_full_slip() -> f64 {
    TAU / harmonic_balance(1.5).0
}

#[test]
fn ekf_f32_follows_the_harmonic_balance_curve() {
    check(Case::EkfF32);
}

#[test]
fn ukf_f32_follows_the_harmonic_balance_curve() {
    check(Case::UkfF32);
}

#[test]
fn ekf_f64_follows_the_harmonic_balance_curve() {
    check(Case::EkfF64);
}

#[test]
fn ukf_f64_follows_the_harmonic_balance_curve() {
    check(Case::UkfF64);
}

/// A named change of the tuning.
type Variant = (&'static str, fn(&mut Tuning));

/// Each walk halved and doubled, EKF in f64: (name, worst errors).
fn neighbours() -> Vec<(&'static str, Worst)> {
    let base = tuning();
    let variants: [Variant; 6] = [
        ("frequency_walk / 2", |t| t.frequency_walk *= 0.5),
        ("frequency_walk * 2", |t| t.frequency_walk *= 2.0),
        ("damping_walk / 2", |t| t.damping_walk *= 0.5),
        ("damping_walk * 2", |t| t.damping_walk *= 2.0),
        ("amplitude_walk / 2", |t| t.amplitude_walk *= 0.5),
        ("amplitude_walk * 2", |t| t.amplitude_walk *= 2.0),
    ];
    variants
        .iter()
        .map(|(name, change)| {
            let mut t = base;
            change(&mut t);
            (*name, worst_against_reference(&run::<f64>(Filter::Ekf, &t)))
        })
        .collect()
}

#[test]
fn tuning_is_a_local_optimum_of_the_damping_error() {
    // Halving or doubling any walk keeps the frequency within its bound and
    // does not lower the worst damping error outside the band: the tuning
    // sits at the bottom of the lag / noise trade-off (seed 004 §3.2.6).
    let base = worst_against_reference(tracked(Case::EkfF64));
    for (name, w) in neighbours() {
        eprintln!("{name}: {w:?}");
        assert!(w.f_out < F_BOUND, "{name}: frequency {}", w.f_out);
        assert!(
            w.xi_out >= base.xi_out,
            "{name}: {} < {}",
            w.xi_out,
            base.xi_out
        );
    }
}

/// The tables of docs/iwan-tracking.md.
fn report() -> String {
    let mut out = String::new();
    let ekf = bins(tracked(Case::EkfF32));
    let ukf = bins(tracked(Case::UkfF32));
    assert_eq!(ekf.len(), ukf.len());
    let (x_ekf, x_ukf) = (relevance(&ekf), relevance(&ukf));
    out.push_str(
        "| p_m [m] | samples | f_HB [Hz] | f EKF | f UKF | ξ_HB [%] | ξ EKF | ξ UKF | \
         ξ free decay | eq 7.17 EKF | eq 7.17 UKF |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (((e, u), xe), xu) in ekf.iter().zip(&ukf).zip(&x_ekf).zip(&x_ukf).rev() {
        assert!((e.p / u.p - 1.0).abs() < 1e-3);
        out.push_str(&format!(
            "| {:.3} | {} | {:.5} | {:.5} | {:.5} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |\n",
            e.p,
            e.n,
            e.omega_hb / TAU,
            e.omega / TAU,
            u.omega / TAU,
            100.0 * e.xi_hb,
            100.0 * e.xi,
            100.0 * u.xi,
            100.0 * e.xi_fd,
            100.0 * xe,
            100.0 * xu,
        ));
    }
    out.push_str(
        "\n| case | out: Δf/f [%] | out: Δξ [pts] | in: Δf/f [%] | in: Δξ [pts] | at p_m [m] | \
         eq 7.17 out [pts] | eq 7.17 in [pts] | ξ lag [periods] | ξ residual [pts] | \
         f lag [periods] | f residual [%] |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (name, case) in [
        ("EKF f32", Case::EkfF32),
        ("UKF f32", Case::UkfF32),
        ("EKF f64", Case::EkfF64),
        ("UKF f64", Case::UkfF64),
    ] {
        let f = figures(tracked(case));
        let w = f.worst;
        out.push_str(&format!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {:.3} | {:.3} | {:.2} | {:.3} | {:.2} | {:.3} |\n",
            100.0 * w.f_out,
            100.0 * w.xi_out,
            100.0 * w.f_in,
            100.0 * w.xi_in,
            w.xi_in_at,
            100.0 * f.gap_out,
            100.0 * f.gap_in,
            f.lag / period_at_full_slip(),
            100.0 * f.residual,
            f.f_lag / period_at_full_slip(),
            100.0 * f.f_residual,
        ));
    }
    out.push_str(&slices());
    out.push_str(
        "| EKF f64, tuning | out: Δf/f [%] | out: Δξ [pts] | in: Δf/f [%] | in: Δξ [pts] |\n\
         |---|---|---|---|---|\n",
    );
    let base = worst_against_reference(tracked(Case::EkfF64));
    for (name, w) in [("as chosen", base)].into_iter().chain(neighbours()) {
        out.push_str(&format!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.3} |\n",
            100.0 * w.f_out,
            100.0 * w.xi_out,
            100.0 * w.f_in,
            100.0 * w.xi_in,
        ));
    }
    out
}

/// Worst errors per 0.1 m slice of the envelope around full slip, EKF
/// f32, after the convergence time.
fn slices() -> String {
    let mut out = String::from(
        "\n| p_m slice [m] | EKF f32: worst Δf/f [%] | worst Δξ [pts] |\n|---|---|---|\n",
    );
    for i in 10..29 {
        let (lo, hi) = (0.1 * i as f64, 0.1 * (i + 1) as f64);
        let (mut f, mut xi) = (0.0f64, 0.0f64);
        for s in tracked(Case::EkfF32)
            .iter()
            .filter(|s| s.t >= T_CONV && s.p >= lo && s.p < hi)
        {
            let (omega, x) = harmonic_balance(s.p);
            f = f.max((s.omega / omega - 1.0).abs());
            xi = xi.max((s.xi - x).abs());
        }
        out.push_str(&format!(
            "| {lo:.1}-{hi:.1} | {:.3} | {:.3} |\n",
            100.0 * f,
            100.0 * xi
        ));
    }
    out.push('\n');
    out
}

/// Cells of a markdown table block: numbers parsed, words kept.
fn cells(text: &str) -> Vec<&str> {
    text.split(['|', '\n'])
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .collect()
}

#[test]
fn documented_figures_are_current() {
    let fresh = report();
    println!("{fresh}");
    let doc = include_str!("../../docs/iwan-tracking.md");
    let (start, end) = ("<!-- generated: start -->", "<!-- generated: end -->");
    let block = doc
        .split_once(start)
        .and_then(|(_, rest)| rest.split_once(end))
        .map(|(block, _)| block)
        .expect("docs/iwan-tracking.md has no generated block");
    let (want, got) = (cells(&fresh), cells(block));
    assert_eq!(want.len(), got.len(), "regenerate the tables (--nocapture)");
    for (w, g) in want.iter().zip(&got) {
        match (w.parse::<f64>(), g.parse::<f64>()) {
            (Ok(a), Ok(b)) => {
                // One unit of the last printed digit: rounding of the same
                // value on either side of a boundary.
                let decimals = g.split_once('.').map_or(0, |(_, d)| d.len());
                let unit = 10f64.powi(-(decimals as i32));
                assert!((a - b).abs() <= 1.01 * unit, "doc {g}, measured {w}");
            }
            _ => assert_eq!(w, g, "regenerate the tables (--nocapture)"),
        }
    }
}
