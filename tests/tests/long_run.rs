//! Long runs without drift: every model in f32 under an exactly periodic
//! input (a 2 mm sine of 200 samples, the phase taken modulo the period),
//! for `LONG_RUN_STEPS` steps (10^6 by default, as in CI). The force over
//! the last period must match the first steady period (the 50th) within
//! 1e-4 of its amplitude: rounding may not accumulate into a drift.
//!
//! The 10^8-step run of the hard-case suite:
//!
//! ```text
//! LONG_RUN_STEPS=100000000 cargo test --release -p bushing-tests --test long_run -- --nocapture
//! ```

use bushing::{
    Berg, BoucWen, Bushing, Dahl, Effect, FirstLoading, FractionalSpec, Grunwald, IwanBank,
    IwanCellSpec, IwanSliders, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial, Sts,
    TurningPoints, XfBank, XfForm, XfSpec,
    accumulator::{Compensated, Multiplied},
};

/// Samples per period of the input.
const PERIOD: usize = 200;
/// The first steady period (the slowest cell's time constant is 0.3 s, 1.5
/// periods).
const STEADY: usize = 50;
const DT: f64 = 1e-3;

fn steps() -> usize {
    std::env::var("LONG_RUN_STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000)
}

/// The input at step `n`: exactly periodic in f32.
fn input(n: usize) -> f32 {
    let phase = std::f64::consts::TAU * (n % PERIOD) as f64 / PERIOD as f64;
    (2.0 * phase.sin()) as f32
}

/// Largest difference between the last period's force and the first steady
/// period's, over the latter's amplitude.
fn drift<B: bushing::Backbone<f32>, E: Effect<f32>>(b: &Bushing<f32, B, E>) -> f64 {
    let total = steps().max((STEADY + 2) * PERIOD);
    let periods = total / PERIOD;
    let mut s = b.state_at(0.0);
    let mut first = [0.0f32; PERIOD];
    let mut worst = 0.0f64;
    let mut amplitude = 0.0f64;
    for p in 0..periods {
        for (k, slot) in first.iter_mut().enumerate() {
            let out = b.step(&mut s, input(p * PERIOD + k));
            assert!(out.force.is_finite(), "non-finite force at period {p}");
            if p == STEADY {
                *slot = out.force;
                amplitude = amplitude.max(out.force.abs() as f64);
            } else if p + 1 == periods {
                worst = worst.max((out.force - *slot).abs() as f64);
            }
        }
    }
    worst / amplitude
}

fn backbone() -> Polynomial<f32, 4> {
    Polynomial::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).expect("a hardening cubic")
}

fn maxwell_specs() -> [MaxwellSpec; 4] {
    [
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(2.0, 0.15),
        MaxwellSpec::hz(8.0, 0.15),
        MaxwellSpec::hz(40.0, 0.1),
    ]
}

fn jenkins() -> [IwanCellSpec; 4] {
    [0.05, 0.2, 0.5, 1.2].map(|x_f| IwanCellSpec::from_slip_distance(0.1, 150.0, x_f))
}

fn check(name: &str, drift: f64) {
    println!("{name}: last period against period {STEADY}, relative: {drift:e}");
    assert!(drift <= 1e-4, "{name} drifts: {drift:e}");
}

#[test]
fn maxwell_banks_do_not_drift() {
    for form in MaxwellForm::ALL {
        let bank = MaxwellBank::<f32, 4>::new(form, &maxwell_specs(), DT);
        // The explicit forms accept the 40 Hz cell at 1 kHz: ω·dt = 0.25.
        let b = Bushing::new(backbone(), (bank.expect("four cells"),)).expect("a bushing");
        check(form.name(), drift(&b));
    }
    let bank = MaxwellBank::<f32, 4, Compensated<f32>>::new(
        MaxwellForm::RateExactRamp,
        &maxwell_specs(),
        DT,
    )
    .expect("four cells");
    check(
        "compensated",
        drift(&Bushing::new(backbone(), (bank,)).expect("a bushing")),
    );
    let bank = MaxwellBank::<f32, 4, Multiplied<f32>>::new(
        MaxwellForm::RateExactRamp,
        &maxwell_specs(),
        DT,
    )
    .expect("four cells");
    check(
        "multiplied",
        drift(&Bushing::new(backbone(), (bank,)).expect("a bushing")),
    );
}

#[test]
fn iwan_banks_do_not_drift() {
    let clamp = IwanBank::<f32, 4>::new(&jenkins()).expect("four cells");
    check(
        "iwan clamp",
        drift(&Bushing::new(backbone(), (clamp,)).expect("a bushing")),
    );
    let sliders = IwanSliders::<f32, 4>::new(&jenkins(), 150.0).expect("four cells");
    check(
        "iwan sliders",
        drift(&Bushing::new(backbone(), (sliders,)).expect("a bushing")),
    );
}

#[test]
fn xf_cells_do_not_drift() {
    for form in XfForm::ALL {
        let bank = XfBank::<f32, 2>::new(
            form,
            &[XfSpec::hz(5.0, 0.1, 0.02), XfSpec::hz(0.5, 0.1, 0.2)],
            DT,
        )
        .expect("two cells");
        check(
            "x_f",
            drift(&Bushing::new(backbone(), (bank,)).expect("a bushing")),
        );
    }
}

#[test]
fn stack_friction_and_fractional_cells_do_not_drift() {
    let sts = TurningPoints::<Sts<f32>, 16>::new(
        Sts::new(400.0, 300.0).expect("an STS law"),
        FirstLoading::Masing,
    );
    check(
        "sts stack",
        drift(&Bushing::new(backbone(), (sts,)).expect("a bushing")),
    );
    let dahl = Dahl::<f32>::new(100.0, 20.0, 1.0).expect("a Dahl cell");
    check(
        "dahl",
        drift(&Bushing::new(backbone(), (dahl,)).expect("a bushing")),
    );
    let bw = BoucWen::<f32>::new(100.0, 1.0, 3.0, 1.0, 8.0).expect("a Bouc-Wen cell");
    check(
        "bouc-wen",
        drift(&Bushing::new(backbone(), (bw,)).expect("a bushing")),
    );
    let berg = Berg::<f32>::new(20.0, 0.1).expect("a Berg cell");
    check(
        "berg",
        drift(&Bushing::new(backbone(), (berg,)).expect("a bushing")),
    );
    let g = Grunwald::<f32, 64>::new(FractionalSpec::hz(2.0, 0.5, 0.3), DT).expect("a cell");
    check(
        "grunwald",
        drift(&Bushing::new(backbone(), (g,)).expect("a bushing")),
    );
}

#[test]
fn composite_bushing_does_not_drift() {
    let maxwell =
        MaxwellBank::<f32, 4>::new(MaxwellForm::RateExactRamp, &maxwell_specs(), DT).expect("4");
    let iwan = IwanBank::<f32, 4>::new(&jenkins()).expect("four cells");
    let xf = XfBank::<f32, 1>::new(XfForm::ExactRamp, &[XfSpec::hz(5.0, 0.05, 0.02)], DT)
        .expect("one cell");
    let b = Bushing::new(backbone(), (maxwell, iwan, xf)).expect("a bushing");
    check("maxwell + iwan + x_f", drift(&b));
}
