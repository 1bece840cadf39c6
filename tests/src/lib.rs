//! Cases shared by the host and the Cortex-M suites.
//!
//! Every case is a plain function returning `Result<(), Failure>`, run by
//! the `cortex_m` test binary on the host (as a normal program) and on
//! Cortex-M4F / Cortex-M3 under QEMU (through semihosting). The golden trace
//! case demands bit-identical results on both.
#![no_std]
#![forbid(unsafe_code)]

use core::fmt;

use bushing::{
    Backbone, Bushing, Compensated, Faults, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline,
    ParamError, Polynomial, Real,
};

/// A failed check: what was measured, the value and the bound it broke.
#[derive(Debug, Clone, Copy)]
pub struct Failure {
    /// What was checked.
    pub what: &'static str,
    /// Value measured.
    pub got: f64,
    /// Bound it had to meet.
    pub bound: f64,
    /// For bit-exact checks: the pattern found and the one required.
    pub bits: Option<(u64, u64)>,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.bits {
            Some((got, want)) => write!(f, "{}: got {got:#018x}, want {want:#018x}", self.what),
            None => write!(
                f,
                "{}: got {:e}, bound {:e}",
                self.what, self.got, self.bound
            ),
        }
    }
}

/// Result of one case.
pub type CaseResult = Result<(), Failure>;

/// Fails with `what` unless `got <= bound` (NaN fails).
pub fn at_most(what: &'static str, got: f64, bound: f64) -> CaseResult {
    if got <= bound {
        Ok(())
    } else {
        Err(Failure {
            what,
            got,
            bound,
            bits: None,
        })
    }
}

/// Fails with `what` unless `cond`.
pub fn holds(what: &'static str, cond: bool) -> CaseResult {
    if cond {
        Ok(())
    } else {
        Err(Failure {
            what,
            got: 0.0,
            bound: 1.0,
            bits: None,
        })
    }
}

/// A named case.
pub type Case = (&'static str, fn() -> CaseResult);

/// Every case, by name.
pub const CASES: &[Case] = &[
    ("polynomial_f32_matches_f64", polynomial_f32_matches_f64),
    (
        "spline_f32_monotone_positive_tangent",
        spline_f32_monotone_positive_tangent,
    ),
    (
        "explicit_forms_refused_at_unit_omega_dt",
        explicit_forms_refused_at_unit_omega_dt,
    ),
    (
        "exponential_forms_bounded_1e-7_to_1e4_f32",
        exponential_forms_bounded_f32,
    ),
    (
        "exponential_forms_bounded_1e-7_to_1e4_f64",
        exponential_forms_bounded_f64,
    ),
    ("slow_cell_f32_decay_rate", slow_cell_f32_decay_rate),
    (
        "tangent_matches_central_difference_f64",
        tangent_matches_central_difference_f64,
    ),
    ("non_finite_input_keeps_state", non_finite_input_keeps_state),
    ("huge_input_refused", huge_input_refused),
    ("golden_trace_f32", golden_trace_f32),
];

/// Runs every case, printing one line each and the closing
/// `N passed, N failed`; returns the number of failures.
pub fn run_all(mut out: impl FnMut(fmt::Arguments<'_>)) -> u32 {
    let (mut passed, mut failed) = (0u32, 0u32);
    for (name, case) in CASES {
        match case() {
            Ok(()) => {
                passed += 1;
                out(format_args!("test {name} ... ok"));
            }
            Err(e) => {
                failed += 1;
                out(format_args!("test {name} ... FAILED: {e}"));
            }
        }
    }
    out(format_args!("{passed} passed, {failed} failed"));
    failed
}

fn polynomial_f32_matches_f64() -> CaseResult {
    let c = [0.0, 200.0, 0.0, 8.0];
    let p32 = Polynomial::<f32, 4>::new(&c, (-5.0, 5.0)).map_err(param)?;
    let p64 = Polynomial::<f64, 4>::new(&c, (-5.0, 5.0)).map_err(param)?;
    let mut worst = 0.0f64;
    for i in -700..=700 {
        let x = i as f64 * 0.01;
        let (f32v, k32) = p32.eval(x as f32);
        let (f64v, k64) = p64.eval(x);
        worst = worst.max((f32v as f64 - f64v).abs() / (1.0 + f64v.abs()));
        worst = worst.max((k32 as f64 - k64).abs() / k64);
    }
    at_most("relative f32 error of force and tangent", worst, 1e-6)
}

fn spline_f32_monotone_positive_tangent() -> CaseResult {
    let xs = [-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0];
    let fs = [-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0];
    let s = MonotoneSpline::<f32, 8>::new(&xs, &fs).map_err(param)?;
    let mut prev = f32::NEG_INFINITY;
    let mut min_k = f32::INFINITY;
    for i in 0..=4000 {
        let x = -5.0 + 10.0 * i as f32 / 4000.0;
        let (f, k) = s.eval(x);
        holds("spline force increases", f >= prev)?;
        prev = f;
        min_k = min_k.min(k);
    }
    holds("spline tangent positive", min_k > 0.0)
}

fn explicit_forms_refused_at_unit_omega_dt() -> CaseResult {
    for form in [MaxwellForm::LoadExplicit, MaxwellForm::RateExplicit] {
        let r = MaxwellBank::<f32, 1>::new(form, &[MaxwellSpec::new(2000.0, 0.2)], 5e-4);
        holds(
            "explicit form refused with ExplicitUnstable",
            matches!(r, Err(ParamError::ExplicitUnstable { cell: 0, .. })),
        )?;
    }
    Ok(())
}

fn exponential_forms_bounded_f32() -> CaseResult {
    exponential_forms_bounded::<f32>()
}

fn exponential_forms_bounded_f64() -> CaseResult {
    exponential_forms_bounded::<f64>()
}

/// Every exponential form, ω·dt from 1e-7 to 1e4 by decades, under a square
/// wave: finite, and within the bound of a high-pass cell,
/// |F| <= (g0 + 2 g) max|F^inf|.
fn exponential_forms_bounded<T: Real>() -> CaseResult {
    let dt = 1e-3;
    for form in [
        MaxwellForm::LoadExponential,
        MaxwellForm::RateMidpoint,
        MaxwellForm::RateExactRamp,
    ] {
        for decade in -7..=4 {
            let h = libm::pow(10.0, decade as f64);
            let spec = [MaxwellSpec::new(h / dt, 0.6)];
            let bank = MaxwellBank::<T, 1>::new(form, &spec, dt).map_err(param)?;
            let b = Bushing::new(Polynomial::<T, 2>::linear(100.0).map_err(param)?, (bank,))
                .map_err(param)?;
            let mut s = b.state_at(T::ZERO);
            let mut worst = 0.0f64;
            for n in 0..2000 {
                let x = if (n / 7) % 2 == 0 { T::ONE } else { -T::ONE };
                let out = b.step(&mut s, x);
                holds(
                    "finite output",
                    out.force.is_finite() && out.dissipated.is_finite(),
                )?;
                worst = worst.max(out.force.to_f64().abs());
            }
            at_most(
                "|F| / (g0 + 2 g) max|F^inf|",
                worst / (100.0 * (0.4 + 1.2)),
                1.0 + 1e-6,
            )?;
        }
    }
    Ok(())
}

fn slow_cell_f32_decay_rate() -> CaseResult {
    // omega dt = 1e-6, relaxing after a step: decay rate within 0.1 %.
    let h = 1e-6;
    let dt = 1e-3;
    let bank = MaxwellBank::<f32, 1, Compensated<f32>>::new(
        MaxwellForm::RateExactRamp,
        &[MaxwellSpec::new(h / dt, 0.5)],
        dt,
    )
    .map_err(param)?;
    let b =
        Bushing::new(Polynomial::<f32, 2>::linear(1.0).map_err(param)?, (bank,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let first = b.step(&mut s, 1.0).force as f64 - 0.5;
    let n = 50_000;
    let mut last = 0.0;
    for _ in 0..n {
        last = b.step(&mut s, 1.0).force as f64 - 0.5;
    }
    let rate = -libm::log(last / first) / n as f64;
    at_most("relative decay-rate error", (rate / h - 1.0).abs(), 1e-3)
}

fn tangent_matches_central_difference_f64() -> CaseResult {
    let specs = [
        MaxwellSpec::hz(0.05, 0.1),
        MaxwellSpec::hz(2.0, 0.15),
        MaxwellSpec::hz(40.0, 0.2),
        MaxwellSpec::hz(400.0, 0.05),
    ];
    let dt = 2e-4;
    let mut worst = 0.0f64;
    for form in MaxwellForm::ALL {
        let bank = MaxwellBank::<f64, 4>::new(form, &specs, dt).map_err(param)?;
        let bb = Polynomial::<f64, 4>::new(&[0.0, 200.0, 3.0, 8.0], (-5.0, 5.0)).map_err(param)?;
        let b = Bushing::new(bb, (bank,)).map_err(param)?;
        let mut s = b.state_at(0.0);
        for n in 0..400 {
            let x = 2.0 * libm::sin(n as f64 * 0.05) + 0.3;
            let (out, _) = b.trial(&s, x);
            let e = 1e-5;
            let (fp, _) = b.trial(&s, x + e);
            let (fm, _) = b.trial(&s, x - e);
            let fd = (fp.force - fm.force) / (2.0 * e);
            worst = worst.max((out.tangent - fd).abs() / out.tangent.abs());
            b.step(&mut s, x);
        }
    }
    at_most("relative tangent error, all forms", worst, 1e-6)
}

type Demo32 = Bushing<f32, Polynomial<f32, 4>, (MaxwellBank<f32, 3>,)>;

fn demo32() -> Result<Demo32, Failure> {
    let specs = [
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(5.0, 0.1),
        MaxwellSpec::hz(50.0, 0.1),
    ];
    let bank = MaxwellBank::new(MaxwellForm::RateExactRamp, &specs, 1e-3).map_err(param)?;
    let bb = Polynomial::new(&[0.0, 200.0, 0.0, 8.0], (-5.0, 5.0)).map_err(param)?;
    Bushing::new(bb, (bank,)).map_err(param)
}

fn non_finite_input_keeps_state() -> CaseResult {
    let b = demo32()?;
    let mut s = b.state_at(0.0);
    for n in 0..100 {
        b.step(&mut s, n as f32 * 0.01);
    }
    let before = s.clone();
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let out = b.step(&mut s, bad);
        holds(
            "refused step returns the last force",
            out.force == before.force(),
        )?;
        holds("refused step dissipates nothing", out.dissipated == 0.0)?;
    }
    holds(
        "fault flag raised",
        s.faults().contains(Faults::NON_FINITE_INPUT),
    )?;
    holds("three steps counted as refused", s.rejected() == 3)?;
    holds("effects' state untouched", s.effects() == before.effects())?;
    s.clear_faults();
    let out = b.step(&mut s, 1.01);
    holds(
        "next finite step runs",
        out.force.is_finite() && out.effects.is_some() && s.faults().is_empty(),
    )
}

fn huge_input_refused() -> CaseResult {
    let b = demo32()?;
    let mut s = b.state_at(0.5);
    let f = s.force();
    // 1e30 mm on a linear extension of slope ~800 N/mm: above the guard.
    let out = b.step(&mut s, 1e30);
    holds(
        "out-of-range flag",
        s.faults().contains(Faults::OUT_OF_RANGE),
    )?;
    holds("force kept", out.force == f)?;
    // Large but representable: accepted and finite.
    let out = b.step(&mut s, 1e12);
    holds(
        "1e12 accepted, finite",
        out.effects.is_some() && out.force.is_finite() && out.dissipated.is_finite(),
    )
}

/// FNV-1a over the bit patterns of a trace.
#[derive(Debug, Clone, Copy)]
pub struct TraceHash(u64);

impl TraceHash {
    /// Empty hash.
    pub const fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    /// Mixes one value.
    pub fn push<T: Real>(&mut self, v: T) {
        for byte in v.bits().to_le_bytes() {
            self.0 ^= byte as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    /// The hash.
    pub const fn value(self) -> u64 {
        self.0
    }
}

impl Default for TraceHash {
    fn default() -> Self {
        Self::new()
    }
}

/// Steps of the golden trace.
pub const GOLDEN_STEPS: usize = 12_000;
/// Hash of the golden trace, as computed on the host and required on every
/// target. Regenerate with `cargo test -p bushing-tests --test golden -- --nocapture`
/// after a deliberate change of a kernel, and say why in the commit.
pub const GOLDEN_HASH: u64 = 0x45d3_8d76_7be4_a98a;

/// The golden trace: two f32 bushings (polynomial + 4 compensated exact-ramp
/// cells; spline + 3 midpoint cells) under a two-tone input with a NaN and
/// an out-of-range sample inside; hashes force, tangent and energy.
pub fn golden_trace() -> Result<u64, Failure> {
    let specs4 = [
        MaxwellSpec::hz(0.02, 0.08),
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(5.0, 0.12),
        MaxwellSpec::hz(80.0, 0.1),
    ];
    let dt = 2e-4;
    let bank4 =
        MaxwellBank::<f32, 4, Compensated<f32>>::new(MaxwellForm::RateExactRamp, &specs4, dt)
            .map_err(param)?;
    let poly = Polynomial::<f32, 4>::new(&[0.0, 200.0, 5.0, 8.0], (-5.0, 5.0)).map_err(param)?;
    let a = Bushing::new(poly, (bank4,)).map_err(param)?;
    let specs3 = [
        MaxwellSpec::hz(1.0, 0.1),
        MaxwellSpec::hz(10.0, 0.1),
        MaxwellSpec::hz(900.0, 0.1),
    ];
    let bank3 =
        MaxwellBank::<f32, 3>::new(MaxwellForm::RateMidpoint, &specs3, dt).map_err(param)?;
    let xs = [-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0];
    let fs = [-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0];
    let spline = MonotoneSpline::<f32, 8>::new(&xs, &fs).map_err(param)?;
    let b = Bushing::new(spline, (bank3,)).map_err(param)?;
    let (mut sa, mut sb) = (a.state_at(0.0), b.state_at(0.0));
    let mut hash = TraceHash::new();
    let w1 = (core::f64::consts::TAU * 3.0 * dt) as f32;
    let w2 = (core::f64::consts::TAU * 47.0 * dt) as f32;
    for n in 0..GOLDEN_STEPS {
        let t = n as f32;
        let mut x = 3.0 * libm::sinf(w1 * t) + 0.2 * libm::sinf(w2 * t);
        if n == 5000 {
            x = f32::NAN;
        }
        if n == 7000 {
            x = 1e25;
        }
        for out in
            [a.step(&mut sa, x), b.step(&mut sb, x)].map(|o| (o.force, o.tangent, o.dissipated))
        {
            hash.push(out.0);
            hash.push(out.1);
            hash.push(out.2);
        }
    }
    holds(
        "golden trace saw its two faults",
        sa.rejected() == 2 && sb.rejected() == 2,
    )?;
    Ok(hash.value())
}

fn golden_trace_f32() -> CaseResult {
    let h = golden_trace()?;
    if h == GOLDEN_HASH {
        Ok(())
    } else {
        Err(Failure {
            what: "golden trace hash differs from the host's",
            got: 0.0,
            bound: 0.0,
            bits: Some((h, GOLDEN_HASH)),
        })
    }
}

fn param(_: ParamError) -> Failure {
    Failure {
        what: "parameters refused",
        got: 1.0,
        bound: 0.0,
        bits: None,
    }
}
