//! The models in fixed point (`Q16` = I16F16, `Q32` = I32F32, feature
//! `fixed`) against the same models in f64, within a bound derived from the
//! schemes (see `core-nostd/src/fixed.rs`, "Accuracy against f64").
//!
//! Units are the firmware's: mm and N, 2 kHz. The inputs are sines sampled
//! on the `Q16` grid, so both models see the same displacements; the f64
//! model has the exact coefficients, so the difference is the fixed-point
//! error: rounding of every product, and the one rounding of every
//! coefficient.
//!
//! The bound, per branch, with ε the resolution, `~` the stored value and
//! `δ` its rounding error (|δ| <= ε/2), `F_m = max|F^∞|` over the run and
//! `e_b = max|F̃^∞ - F^∞|` (the backbone's own error, measured):
//!
//! - rate-form Maxwell cell (`F ← F - d F + p ΔF^∞`, two rounded products):
//!   `(|δd| 2 p F_m + ε) / d̃ + 2 |δp| F_m + 2 p̃ e_b`;
//! - load-form Maxwell cell (state `s ← s - d s + p ΔF^∞ + q F^∞`, branch
//!   `s + g F^∞`): `(|δd| s_m + |δq| F_m + 1.5 ε + |q̃| e_b) / d̃ + 2 |δp| F_m
//!   + 2 p̃ e_b + |δg| F_m + g̃ e_b + ε/2`, with `s_m = 2 p F_m + |q| F_m / d`;
//! - clamp-form Jenkins cell slipping every half cycle (the clamp resets
//!   the error to |δF_f|): `|δF_f| + 2 |δg| F_m + 2 g̃ e_b + ε/2 · n`, n the
//!   steps of a period;
//! - elastic branch: `|δg^0| F_m + g̃^0 e_b + ε/2`.
//!
//! The increments telescope (summation by parts), the rest is amplified by
//! the recursion gain 1/d̃: the `ε / (1 - e^{-ω dt})` of slow cells.

use std::f64::consts::PI;

use bushing::{
    Backbone, Bushing, Effect, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec,
    MonotoneSpline, Polynomial, Q16, Q32, Real,
};

/// Control period: 2 kHz.
const DT: f64 = 5e-4;

/// Four cells from 0.05 Hz to 50 Hz, one per decade (the firmware
/// examples' `CELLS`).
const CELLS4: [MaxwellSpec; 4] = [
    MaxwellSpec::new(0.1 * PI, 0.1),
    MaxwellSpec::new(PI, 0.1),
    MaxwellSpec::new(10.0 * PI, 0.15),
    MaxwellSpec::new(100.0 * PI, 0.1),
];

/// Eight cells, two per decade from 0.01 Hz to 100 Hz, g = 0.07 each (the
/// firmware examples' `maxwell8`).
fn cells8() -> [MaxwellSpec; 8] {
    let ratio = 10f64.powf(4.0 / 7.0);
    let mut f = 0.01;
    core::array::from_fn(|_| {
        let c = MaxwellSpec::hz(f, 0.07);
        f *= ratio;
        c
    })
}

/// Sixteen Jenkins cells on 150 N/mm, slip distances 0.02 to 1.5 mm in
/// logarithmic steps, total fraction 0.4 (the firmware examples' `jenkins`).
fn jenkins<const N: usize>() -> [IwanCellSpec; N] {
    let ratio = 75f64.powf(1.0 / (N - 1) as f64);
    let mut x_f = 0.02;
    core::array::from_fn(|_| {
        let c = IwanCellSpec::from_slip_distance(0.4 / N as f64, 150.0, x_f);
        x_f *= ratio;
        c
    })
}

/// The three Jenkins cells of the default bushing: 0.05, 0.2 and 0.5 mm on
/// 150 N/mm, g = 0.08.
const JENKINS3: [IwanCellSpec; 3] = [
    IwanCellSpec::new(0.08, 0.08 * 150.0 * 0.05),
    IwanCellSpec::new(0.08, 0.08 * 150.0 * 0.2),
    IwanCellSpec::new(0.08, 0.08 * 150.0 * 0.5),
];

/// Cubic hardening backbone 150 x + 4 x³ on ±6 mm (N, mm).
fn polynomial<T: Real>() -> Polynomial<T, 4> {
    Polynomial::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).unwrap()
}

/// Eight measured points, N and mm (the default bushing's backbone).
fn spline<T: Real>() -> MonotoneSpline<T, 8> {
    MonotoneSpline::new(
        &[-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0],
        &[-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0],
    )
    .unwrap()
}

type Default3<T> = Bushing<T, MonotoneSpline<T, 8>, (MaxwellBank<T, 4>, IwanBank<T, 3>)>;

/// The default bushing: spline backbone, 4 Maxwell cells (exact ramp, plain
/// states), 3 Jenkins cells (clamp form).
fn default_bushing<T: Real>() -> Default3<T> {
    Bushing::new(
        spline(),
        (
            MaxwellBank::new(MaxwellForm::RateExactRamp, &CELLS4, DT).unwrap(),
            IwanBank::new(&JENKINS3).unwrap(),
        ),
    )
    .unwrap()
}

/// A sine of `amplitude` mm at `hz` over `periods` periods, on the Q16 grid
/// (so exactly the same input for every type).
fn sine(amplitude: f64, hz: f64, periods: f64) -> Vec<f64> {
    let n = (periods / (hz * DT)).round() as usize;
    (0..=n)
        .map(|i| Q16::from_f64(amplitude * (2.0 * PI * hz * i as f64 * DT).sin()).to_f64())
        .collect()
}

/// One run: every output of every step, widened to f64.
struct Trace {
    force: Vec<f64>,
    tangent: Vec<f64>,
    dissipated: f64,
    bits: Vec<u64>,
}

fn run<T: Real, B: Backbone<T>, E: Effect<T>>(b: &Bushing<T, B, E>, xs: &[f64]) -> Trace {
    let mut st = b.state_at(T::ZERO);
    let mut t = Trace {
        force: Vec::with_capacity(xs.len()),
        tangent: Vec::with_capacity(xs.len()),
        dissipated: 0.0,
        bits: Vec::with_capacity(xs.len()),
    };
    for &x in xs {
        let o = b.step(&mut st, T::from_f64(x));
        assert!(o.effects.is_some(), "step refused at x = {x}");
        t.force.push(o.force.to_f64());
        t.tangent.push(o.tangent.to_f64());
        t.dissipated += o.dissipated.to_f64();
        t.bits.push(o.force.bits());
    }
    t
}

/// Largest |a - b| over two traces.
fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// `(F_m, e_b)`: the largest backbone force over the inputs, and the
/// largest error of the backbone in `T` against f64.
fn backbone_error<T: Real, B: Backbone<T>, R: Backbone<f64>>(
    b: &B,
    reference: &R,
    xs: &[f64],
) -> (f64, f64) {
    xs.iter().fold((0.0f64, 0.0f64), |(fm, eb), &x| {
        let f = reference.eval(x).0;
        let ft = b.eval(T::from_f64(x)).0.to_f64();
        (fm.max(f.abs()), eb.max((ft - f).abs()))
    })
}

/// The stored value of `v` in `T`, and its rounding error.
fn stored<T: Real>(v: f64) -> (f64, f64) {
    let s = T::from_f64(v).to_f64();
    (s, (s - v).abs())
}

/// The bound of the module docs for one Maxwell cell in `T`.
fn maxwell_cell_bound<T: Real>(form: MaxwellForm, spec: MaxwellSpec, fm: f64, eb: f64) -> f64 {
    let eps = T::EPSILON.to_f64();
    let h = spec.omega * DT;
    let g = spec.g;
    let d = -(-h).exp_m1();
    let (dt_, dd) = stored::<T>(d);
    assert!(dt_ > 0.0, "cell {spec:?} frozen in {}", T::NAME);
    match form {
        MaxwellForm::RateExactRamp => {
            let p = g * d / h;
            let (pt, dp) = stored::<T>(p);
            (dd * 2.0 * p * fm + eps) / dt_ + 2.0 * dp * fm + 2.0 * pt * eb
        }
        MaxwellForm::LoadExponential => {
            let m = (-0.5 * h).exp();
            let (p, q) = (0.5 * h * g * m, -h * g * m);
            let ((pt, dp), (qt, dq), (gt, dg)) = (stored::<T>(p), stored::<T>(q), stored::<T>(g));
            let s_m = 2.0 * p * fm + q.abs() * fm / d;
            (dd * s_m + dq * fm + 1.5 * eps + qt.abs() * eb) / dt_
                + 2.0 * dp * fm
                + 2.0 * pt * eb
                + dg * fm
                + gt * eb
                + 0.5 * eps
        }
        other => panic!("no bound for {other:?}"),
    }
}

/// The bound for one clamp-form Jenkins cell that slips every half cycle,
/// `period` steps per cycle.
fn iwan_cell_bound<T: Real>(spec: IwanCellSpec, fm: f64, eb: f64, period: usize) -> f64 {
    let eps = T::EPSILON.to_f64();
    let (gt, dg) = stored::<T>(spec.g);
    let (_, dl) = stored::<T>(spec.slip_force);
    dl + 2.0 * dg * fm + 2.0 * gt * eb + 0.5 * eps * period as f64
}

/// The elastic branch's bound for a bushing of total fraction `sum_g`.
fn elastic_bound<T: Real>(sum_g: f64, fm: f64, eb: f64) -> f64 {
    let (g0t, dg0) = stored::<T>(1.0 - sum_g);
    dg0 * fm + g0t * eb + 0.5 * T::EPSILON.to_f64()
}

struct Figures {
    error: f64,
    bound: f64,
    scale: f64,
    energy: f64,
    tangent: f64,
}

impl Figures {
    fn print(&self, what: &str) {
        println!(
            "{what}: max |F - F_f64| = {:.3e} N (bound {:.3e} N, {:.1} % of it; {:.2e} of max|F| = {:.0} N); \
             energy {:+.2e} relative; max tangent error {:.2e} N/mm",
            self.error,
            self.bound,
            100.0 * self.error / self.bound,
            self.error / self.scale,
            self.scale,
            self.energy,
            self.tangent,
        );
    }
}

/// A polynomial backbone with an `N`-cell Maxwell bank in `T` against f64,
/// under a sine.
fn maxwell_vs_f64<T: Real, const N: usize>(
    form: MaxwellForm,
    specs: &[MaxwellSpec; N],
    xs: &[f64],
) -> Figures {
    let fixed = Bushing::new(
        polynomial::<T>(),
        (MaxwellBank::<T, N>::new(form, specs, DT).unwrap(),),
    )
    .unwrap();
    let reference = Bushing::new(
        polynomial::<f64>(),
        (MaxwellBank::<f64, N>::new(form, specs, DT).unwrap(),),
    )
    .unwrap();
    let (fm, eb) = backbone_error(&polynomial::<T>(), &polynomial::<f64>(), xs);
    let sum_g: f64 = specs.iter().map(|s| s.g).sum();
    let bound = elastic_bound::<T>(sum_g, fm, eb)
        + specs
            .iter()
            .map(|&s| maxwell_cell_bound::<T>(form, s, fm, eb))
            .sum::<f64>();
    let (a, b) = (run(&fixed, xs), run(&reference, xs));
    Figures {
        error: max_diff(&a.force, &b.force),
        bound,
        scale: b.force.iter().fold(0.0, |m, f| m.max(f.abs())),
        energy: a.dissipated / b.dissipated - 1.0,
        tangent: max_diff(&a.tangent, &b.tangent),
    }
}

/// Sines used for every bank: 3 mm at 1 Hz over 20 s (40 000 steps: the
/// 0.05 Hz cell's transient and the steady state), 1 mm at 20 Hz, and 2 mm
/// at 1 Hz about a 1 mm preload (where the load forms' static-gain error
/// shows).
fn drives() -> [(&'static str, Vec<f64>); 3] {
    let preloaded = sine(2.0, 1.0, 20.0).into_iter().map(|x| x + 1.0).collect();
    [
        ("3 mm 1 Hz", sine(3.0, 1.0, 20.0)),
        ("1 mm 20 Hz", sine(1.0, 20.0, 100.0)),
        ("1 mm + 2 mm 1 Hz", preloaded),
    ]
}

#[test]
fn maxwell_banks_in_q16_track_f64_within_the_bound() {
    let c8 = cells8();
    for (name, xs) in drives() {
        for form in [MaxwellForm::RateExactRamp, MaxwellForm::LoadExponential] {
            let f4 = maxwell_vs_f64::<Q16, 4>(form, &CELLS4, &xs);
            f4.print(&format!("Q16, 4 cells, {}, {name}", form.name()));
            let f8 = maxwell_vs_f64::<Q16, 8>(form, &c8, &xs);
            f8.print(&format!("Q16, 8 cells, {}, {name}", form.name()));
            // For scale: f32 on the same runs (its bound is relative, not
            // this one).
            for (n, f) in [
                (4, maxwell_vs_f64::<f32, 4>(form, &CELLS4, &xs)),
                (8, maxwell_vs_f64::<f32, 8>(form, &c8, &xs)),
            ] {
                println!(
                    "  f32, {n} cells: max |F - F_f64| = {:.3e} N, energy {:+.2e} relative",
                    f.error, f.energy
                );
            }
            for f in [&f4, &f8] {
                assert!(f.error <= f.bound, "{} {name}", form.name());
                assert!(f.tangent < 0.01, "{} {name}", form.name());
                if form == MaxwellForm::RateExactRamp {
                    // The rate form: within 1e-3 of the force (measured:
                    // up to 5.5e-4, about ε/d̃ of the slowest cell).
                    assert!(f.error < 1e-3 * f.scale, "{name}");
                    assert!(f.energy.abs() < 1e-3, "{name}");
                }
            }
        }
    }
}

#[test]
fn maxwell_banks_in_q32_track_f64_within_the_bound() {
    let c8 = cells8();
    for (name, xs) in drives() {
        for form in [MaxwellForm::RateExactRamp, MaxwellForm::LoadExponential] {
            let f4 = maxwell_vs_f64::<Q32, 4>(form, &CELLS4, &xs);
            f4.print(&format!("Q32, 4 cells, {}, {name}", form.name()));
            let f8 = maxwell_vs_f64::<Q32, 8>(form, &c8, &xs);
            f8.print(&format!("Q32, 8 cells, {}, {name}", form.name()));
            for f in [&f4, &f8] {
                assert!(f.error <= f.bound, "{} {name}", form.name());
                assert!(f.error < 1e-6 * f.scale, "{} {name}", form.name());
                assert!(f.energy.abs() < 1e-6, "{} {name}", form.name());
            }
        }
    }
}

/// A 16-cell Iwan bank (clamp form) on the polynomial backbone; at 3 mm
/// every cell slips every half cycle (g F^∞(3 mm) = 14.6 N > F_f <= 9 N).
fn iwan16_vs_f64<T: Real>(xs: &[f64], period: usize) -> Figures {
    let cells = jenkins::<16>();
    let fixed = Bushing::new(
        polynomial::<T>(),
        (IwanBank::<T, 16>::new(&cells).unwrap(),),
    )
    .unwrap();
    let reference = Bushing::new(
        polynomial::<f64>(),
        (IwanBank::<f64, 16>::new(&cells).unwrap(),),
    )
    .unwrap();
    let (fm, eb) = backbone_error(&polynomial::<T>(), &polynomial::<f64>(), xs);
    for c in &cells {
        assert!(c.g * fm > c.slip_force, "{c:?} does not slip");
    }
    let bound = elastic_bound::<T>(0.4, fm, eb)
        + cells
            .iter()
            .map(|&c| iwan_cell_bound::<T>(c, fm, eb, period))
            .sum::<f64>();
    let (a, b) = (run(&fixed, xs), run(&reference, xs));
    Figures {
        error: max_diff(&a.force, &b.force),
        bound,
        scale: b.force.iter().fold(0.0, |m, f| m.max(f.abs())),
        energy: a.dissipated / b.dissipated - 1.0,
        tangent: max_diff(&a.tangent, &b.tangent),
    }
}

#[test]
fn iwan16_clamp_bank_in_q16_tracks_f64_within_the_bound() {
    for (hz, name) in [(1.0, "3 mm 1 Hz"), (20.0, "3 mm 20 Hz")] {
        let xs = sine(3.0, hz, 20.0);
        let period = (1.0 / (hz * DT)).round() as usize;
        for (t, f) in [
            ("Q16", iwan16_vs_f64::<Q16>(&xs, period)),
            ("Q32", iwan16_vs_f64::<Q32>(&xs, period)),
        ] {
            f.print(&format!("{t}, 16 Jenkins cells, {name}"));
            assert!(f.error <= f.bound, "{t} {name}");
            assert!(f.energy.abs() < 1e-4, "{t} {name}");
        }
    }
}

#[test]
fn default_bushing_in_q16_tracks_f64_within_the_bound() {
    for (amplitude, hz) in [(2.0, 1.0), (3.5, 1.0), (1.0, 10.0)] {
        let xs = sine(amplitude, hz, 20.0);
        let period = (1.0 / (hz * DT)).round() as usize;
        let (fm, eb) = backbone_error(&spline::<Q16>(), &spline::<f64>(), &xs);
        let sum_g =
            CELLS4.iter().map(|c| c.g).sum::<f64>() + JENKINS3.iter().map(|c| c.g).sum::<f64>();
        for c in &JENKINS3 {
            assert!(c.g * fm > c.slip_force);
        }
        let bound = elastic_bound::<Q16>(sum_g, fm, eb)
            + CELLS4
                .iter()
                .map(|&s| maxwell_cell_bound::<Q16>(MaxwellForm::RateExactRamp, s, fm, eb))
                .sum::<f64>()
            + JENKINS3
                .iter()
                .map(|&c| iwan_cell_bound::<Q16>(c, fm, eb, period))
                .sum::<f64>();
        let (a, b) = (
            run(&default_bushing::<Q16>(), &xs),
            run(&default_bushing::<f64>(), &xs),
        );
        let f = Figures {
            error: max_diff(&a.force, &b.force),
            bound,
            scale: b.force.iter().fold(0.0, |m, f| m.max(f.abs())),
            energy: a.dissipated / b.dissipated - 1.0,
            tangent: max_diff(&a.tangent, &b.tangent),
        };
        f.print(&format!(
            "Q16, default bushing, {amplitude} mm {hz} Hz (backbone error {eb:.2e} N)"
        ));
        assert!(f.error <= f.bound);
        assert!(f.error < 1e-3 * f.scale);
        // The Maxwell energy forms F_i² + F_i² of each branch; in Q16 that
        // saturates once a branch force passes 128 N (0.15 F^∞ beyond 850
        // N: the 3.5 mm case reaches -2050 N), and energy is lost.
        if 0.15 * fm < 128.0 {
            assert!(f.energy.abs() < 1e-3);
        } else {
            assert!(f.energy < 0.0 && f.energy > -0.5, "{}", f.energy);
        }
        // The tangent differs only at the steps where a Jenkins cell clamps
        // in one type and not yet in the other (a jump of g K^∞).
        let jumps = a
            .tangent
            .iter()
            .zip(&b.tangent)
            .filter(|(x, y)| (*x - *y).abs() > 1e-2)
            .count();
        println!(
            "  tangent steps off by more than 0.01 N/mm: {jumps} of {}",
            xs.len()
        );
        assert!(jumps <= 4 * 3 * 20 + 10, "{jumps}");
    }
}

/// The ε/(1 - e^{-ω dt}) of slow cells, shown: a rate-form cell held after
/// a ramp relaxes in f64 to 0, in Q16 it stops where its decrement d̃ F
/// rounds to zero, within one unit below ε / (2 d̃).
#[test]
fn a_held_slow_cell_stops_in_a_dead_band_of_half_resolution_over_d() {
    let eps = Q16::EPSILON.to_f64();
    for hz in [0.05, 0.5, 5.0] {
        let spec = [MaxwellSpec::hz(hz, 0.1)];
        let b = Bushing::new(
            Polynomial::<Q16, 2>::linear(150.0).unwrap(),
            (MaxwellBank::<Q16, 1>::new(MaxwellForm::RateExactRamp, &spec, DT).unwrap(),),
        )
        .unwrap();
        let d = stored::<Q16>(-(-spec[0].omega * DT).exp_m1()).0;
        let mut st = b.state_at(Q16::ZERO);
        for i in 0..=100 {
            b.step(&mut st, Q16::from_f64(0.02 * i as f64));
        }
        let hold = (20.0 / d) as usize;
        for _ in 0..hold {
            b.step(&mut st, Q16::from_f64(2.0));
        }
        let residual = st.effects().0[0].0.to_f64();
        let edge = eps / (2.0 * d);
        println!(
            "{hz} Hz: d = {d:.3e}, residual branch force after {hold} steps {residual:.4e} N, \
             eps/(2d) = {edge:.4e} N"
        );
        assert!(residual < edge && residual >= edge - eps, "{hz} Hz");
    }
}

/// The load forms' static gain in Q16: a held cell settles on q̃/d̃ F^∞
/// instead of q/d F^∞, with q = -ω dt g e^{-ω dt/2} a few units of
/// resolution for a slow cell: a relative error up to ε / (2 ω dt g) +
/// ε / (2 ω dt), 33 % for a 0.05 Hz cell of g = 0.15 at 2 kHz and 100 % at
/// g = 0.05. Q32 removes it.
#[test]
fn load_form_static_gain_of_slow_cells_needs_q32() {
    fn held<T: Real>(spec: &[MaxwellSpec; 1]) -> f64 {
        let b = Bushing::new(
            Polynomial::<T, 2>::linear(150.0).unwrap(),
            (MaxwellBank::<T, 1>::new(MaxwellForm::LoadExponential, spec, DT).unwrap(),),
        )
        .unwrap();
        let mut st = b.state_at(T::from_f64(2.0));
        for _ in 0..200_000 {
            b.step(&mut st, T::from_f64(2.0));
        }
        st.effects().0[0].0.to_f64()
    }
    let eps = Q16::EPSILON.to_f64();
    for g in [0.15, 0.05] {
        let spec = [MaxwellSpec::hz(0.05, g)];
        let h = spec[0].omega * DT;
        let (d, q) = (-(-h).exp_m1(), -h * g * (-0.5 * h).exp());
        let predicted = (stored::<Q16>(q).0 / stored::<Q16>(d).0) / (q / d) - 1.0;
        let bound = eps / (2.0 * h * g) + eps / (2.0 * h);
        // The relaxation settles on q/d F^∞ with F^∞ = 300 N.
        let settle = |relaxation: f64| relaxation / (q / d * 300.0) - 1.0;
        let (e16, e32) = (settle(held::<Q16>(&spec)), settle(held::<Q32>(&spec)));
        println!(
            "0.05 Hz load-exponential cell, g = {g}: static gain error Q16 {e16:+.3e} \
             (predicted from the stored q and d {predicted:+.3e}, bound {bound:.3e}), Q32 {e32:+.3e}"
        );
        assert!((e16 - predicted).abs() < 1e-2, "{e16} vs {predicted}");
        assert!(e16.abs() > 0.2 && e16.abs() <= bound + 1e-2, "{e16}");
        assert!(e32.abs() < 1e-5, "{e32}");
    }
}

/// Maxwell's dissipated energy forms Σ (ω dt / g) (F_old² + F_new²) before
/// the division by K^∞: in Q16 the sum of squares saturates once a branch
/// force passes 128 N (or 128 / sqrt(ω dt / g) N when ω dt / g > 1, a fast
/// cell), which loses energy (never adds any); the force is not affected.
#[test]
fn maxwell_energy_square_saturates_in_q16_but_not_the_force() {
    let spec = [MaxwellSpec::hz(50.0, 0.3)];
    let form = MaxwellForm::RateExactRamp;
    let fixed = Bushing::new(
        spline::<Q16>(),
        (MaxwellBank::<Q16, 1>::new(form, &spec, DT).unwrap(),),
    )
    .unwrap();
    let reference = Bushing::new(
        spline::<f64>(),
        (MaxwellBank::<f64, 1>::new(form, &spec, DT).unwrap(),),
    )
    .unwrap();
    let xs = sine(3.9, 100.0, 20.0);
    let (fm, eb) = backbone_error(&spline::<Q16>(), &spline::<f64>(), &xs);
    let bound =
        elastic_bound::<Q16>(0.3, fm, eb) + maxwell_cell_bound::<Q16>(form, spec[0], fm, eb);
    let (a, b) = (run(&fixed, &xs), run(&reference, &xs));
    let error = max_diff(&a.force, &b.force);
    let deficit = a.dissipated / b.dissipated - 1.0;
    println!(
        "one 50 Hz cell, g = 0.3, 3.9 mm at 100 Hz: force error {error:.3e} N (bound {bound:.3e} N), \
         energy {deficit:+.3e} relative"
    );
    assert!(error <= bound);
    // The squares saturate: most of the energy is lost, none is invented.
    assert!(deficit < -0.5, "{deficit}");
}

#[test]
fn fixed_point_runs_are_deterministic_and_trial_matches_step() {
    let xs = sine(2.5, 3.0, 4.0);
    let b = default_bushing::<Q16>();
    let (a, c) = (run(&b, &xs), run(&b, &xs));
    assert_eq!(a.bits, c.bits);
    let mut st = b.state_at(Q16::ZERO);
    for &x in &xs {
        let x = Q16::from_f64(x);
        let (out, next) = b.trial(&st, x);
        let stepped = b.step(&mut st, x);
        assert_eq!(out.force.bits(), stepped.force.bits());
        assert_eq!(next, st);
    }
    // A digest of the force trace, printed: integer arithmetic is the same
    // on every target, so a Cortex-M3 run must print the same.
    let digest = a.bits.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &v| {
        (h ^ v).wrapping_mul(0x100_0000_01b3)
    });
    println!("default bushing Q16 trace digest {digest:#018x}");
}

/// Random, extreme and saturating inputs through every supported model in
/// both types (a debug build: any overflow would panic): no panic, refused
/// steps flagged, forces within range.
#[test]
fn no_panic_for_extreme_inputs() {
    fn all<T: Real>() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let b = default_bushing::<T>();
        let m = Bushing::new(
            polynomial::<T>(),
            (
                MaxwellBank::<T, 4>::new(MaxwellForm::LoadExponential, &CELLS4, DT).unwrap(),
                IwanBank::<T, 16>::new(&jenkins::<16>()).unwrap(),
            ),
        )
        .unwrap();
        let (mut sb, mut sm) = (b.state_at(T::ZERO), m.state_at(T::ZERO));
        let mut refused = 0;
        for i in 0..20_000 {
            let r = next();
            let x = match i % 5 {
                0 => (r as i64 as f64) * 2f64.powi(-40), // ±8e6
                1 => f64::from_bits(r),                  // any f64, NaN included
                2 => [1e300, -1e300, 0.0, 4.0, -4.0][(r % 5) as usize],
                _ => ((r >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 12.0,
            };
            let o1 = b.step(&mut sb, T::from_f64(x));
            let o2 = m.step(&mut sm, T::from_f64(x));
            refused += usize::from(o1.effects.is_none()) + usize::from(o2.effects.is_none());
            assert!(o1.dissipated >= T::ZERO && o2.dissipated >= T::ZERO);
            assert!(o1.force.abs() <= T::from_f64(2.0) * T::GUARD);
        }
        println!("{}: {refused} steps refused", T::NAME);
        assert!(refused > 0 && sb.faults() != bushing::Faults::NONE);
    }
    all::<Q16>();
    all::<Q32>();
}
