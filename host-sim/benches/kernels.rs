//! Host benchmarks (divan) of the kernels of the accuracy-cost report:
//! Maxwell forms × orders × f32/f64 (and the three state storages at 8
//! cells), Iwan banks, x_f forms, Grünwald taps, the default bushing and
//! the trackers. Each iteration is one pass of the `kernel-cost`
//! firmware's 2000-sample sine (or its drives), counted as 2000 items, so
//! divan's throughput is calls per second.
//!
//! `cargo bench -p bushing-sim --bench kernels` (add `-- maxwell` to run
//! one group). Timings are printed, never asserted.

use bushing::tracker::{Filter, UtParams};
use bushing::{
    Accumulator, Backbone, Bushing, Compensated, Effect, MaxwellBank, MaxwellForm, Multiplied,
    Plain, Real, XfBank, XfForm, XfSpec,
};
use bushing_kernels::DT;
use bushing_sim::accuracy_cost::families::{XF_CELL, maxwell_specs};
use bushing_sim::accuracy_cost::host::{CALLS, drives};
use divan::counter::ItemsCount;
use divan::{Bencher, black_box};

fn main() {
    divan::main();
}

const FORMS: [&str; 5] = [
    "load-explicit",
    "load-exponential",
    "rate-explicit",
    "rate-midpoint",
    "rate-exact-ramp",
];

/// One pass of `effect` over the firmware's drives from rest.
fn effect_pass<T: Real, E: Effect<T>>(bencher: Bencher<'_, '_>, effect: &E) {
    let drives = drives::<T>().expect("the firmware's drives");
    bencher
        .counter(ItemsCount::new(drives.len()))
        .bench_local(|| {
            let mut state = effect.rest(T::ZERO);
            for d in &drives {
                black_box(effect.step(&mut state, black_box(d)));
            }
        });
}

/// One pass of `b` over the firmware's sine (force, tangent, energy).
fn bushing_pass<B: Backbone<f32>, E: Effect<f32>>(
    bencher: Bencher<'_, '_>,
    b: &Bushing<f32, B, E>,
) {
    let (amplitude, period) = bushing_sim::accuracy_cost::families::SINE;
    let xs = bushing_kernels::sine::<f32, CALLS>(amplitude, period);
    bencher.counter(ItemsCount::new(xs.len())).bench_local(|| {
        let mut state = b.state_at(0.0);
        for &x in &xs {
            let o = b.step(&mut state, black_box(x));
            black_box([o.force, o.tangent, o.dissipated]);
        }
    });
}

fn form(name: &str) -> MaxwellForm {
    MaxwellForm::from_name(name).expect("a form name")
}

/// Every form, order and number type, plain states.
#[divan::bench(types = [f32, f64], consts = [1, 2, 4, 8, 16], args = FORMS)]
fn maxwell<T: Real, const N: usize>(bencher: Bencher<'_, '_>, name: &str) {
    let specs = maxwell_specs::<N>().expect("the firmware's cells");
    let bank = MaxwellBank::<T, N>::new(form(name), &specs, DT).expect("a bank");
    effect_pass::<T, _>(bencher, &bank);
}

fn maxwell8_state<A: Accumulator<f32>>(bencher: Bencher<'_, '_>) {
    let specs = maxwell_specs::<8>().expect("the firmware's cells");
    let bank =
        MaxwellBank::<f32, 8, A>::new(MaxwellForm::RateExactRamp, &specs, DT).expect("a bank");
    effect_pass::<f32, _>(bencher, &bank);
}

/// Eight exact-ramp cells in f32 with each state storage.
#[divan::bench]
fn maxwell8_plain(bencher: Bencher<'_, '_>) {
    maxwell8_state::<Plain<f32>>(bencher);
}

/// See [`maxwell8_plain`].
#[divan::bench]
fn maxwell8_multiplied(bencher: Bencher<'_, '_>) {
    maxwell8_state::<Multiplied<f32>>(bencher);
}

/// See [`maxwell8_plain`].
#[divan::bench]
fn maxwell8_compensated(bencher: Bencher<'_, '_>) {
    maxwell8_state::<Compensated<f32>>(bencher);
}

/// The firmware's clamp Iwan banks.
#[divan::bench(consts = [1, 2, 4, 8, 16, 32, 64])]
fn iwan<const N: usize>(bencher: Bencher<'_, '_>) {
    let bank = bushing_kernels::iwan_bank::<f32, N>().expect("the firmware's bank");
    effect_pass::<f32, _>(bencher, &bank);
}

/// The firmware's x_f cell in both forms.
#[divan::bench(types = [f32, f64], args = ["midpoint", "exact-ramp"])]
fn xf<T: Real>(bencher: Bencher<'_, '_>, name: &str) {
    let (f, g, x_f) = XF_CELL;
    let form = if name == "midpoint" {
        XfForm::Midpoint
    } else {
        XfForm::ExactRamp
    };
    let bank = XfBank::<T, 1>::new(form, &[XfSpec::hz(f, g, x_f)], DT).expect("a cell");
    effect_pass::<T, _>(bencher, &bank);
}

/// The firmware's Grünwald cell (whole bushing step).
#[divan::bench(consts = [16, 64, 256, 1024])]
fn grunwald<const N: usize>(bencher: Bencher<'_, '_>) {
    let b = bushing_kernels::grunwald::<N>().expect("the firmware's cell");
    bushing_pass(bencher, &b);
}

/// Spline backbone + 4 Maxwell + 3 Jenkins.
#[divan::bench]
fn default_bushing(bencher: Bencher<'_, '_>) {
    let b = bushing_kernels::default_bushing::<f32>().expect("the default bushing");
    bushing_pass(bencher, &b);
}

/// The firmware's tracker update (one mode, one accelerometer, 1 kHz).
#[divan::bench(types = [f32, f64], args = ["ekf", "ukf"])]
fn tracker<T: Real>(bencher: Bencher<'_, '_>, filter: &str) {
    let filter = if filter == "ekf" {
        Filter::Ekf
    } else {
        Filter::Ukf(UtParams::default())
    };
    let tracker = bushing_kernels::modal_tracker::<T>(filter).expect("a tracker");
    let samples: Vec<T> = (0..CALLS)
        .map(|k| T::from_f64((std::f64::consts::TAU * 0.02 * k as f64).cos()))
        .collect();
    bencher
        .counter(ItemsCount::new(samples.len()))
        .bench_local(|| {
            let mut state = tracker.start();
            for y in &samples {
                black_box(tracker.step(&mut state, &[black_box(*y)]));
            }
        });
}
