//! Steady-state complex modulus of a linear backbone plus a 4-cell Maxwell
//! bank against the closed form of seed 000 eq 1.8.

use bushing::MaxwellForm;
use bushing_sim::modulus::{self, POLE_SETS, measure};

/// Exact ramp, 50 samples per period: storage and loss within 0.5 % for
/// every placement of the poles from 1e-3 to 1e3 times the test frequency
/// (a decade-wide set of four cells slid by quarter decades, plus the
/// named slow/central/fast sets).
#[test]
fn exact_ramp_within_half_percent_at_50_samples_per_period_anywhere() {
    let mut sets: Vec<[f64; 4]> = POLE_SETS.iter().map(|s| s.ratios).collect();
    for k in 0..=20 {
        let r = 1e-3 * 10f64.powf(k as f64 / 4.0);
        sets.push([
            r,
            r * 2.154_434_690_031_884,
            r * 4.641_588_833_612_779,
            r * 10.0,
        ]);
    }
    let mut worst: (f64, f64) = (0.0, 0.0);
    for ratios in &sets {
        let m = measure::<f64>(MaxwellForm::RateExactRamp, ratios, 50).unwrap();
        let (s, l, _) = m.errors(ratios);
        assert!(s.abs() <= 5e-3, "storage error {s:e} for poles {ratios:?}");
        assert!(l.abs() <= 5e-3, "loss error {l:e} for poles {ratios:?}");
        worst = (worst.0.max(s.abs()), worst.1.max(l.abs()));
    }
    println!(
        "worst storage error {:.3e}, worst loss error {:.3e}",
        worst.0, worst.1
    );
}

/// The same in f32: the working type of the firmware does not spoil it.
#[test]
fn exact_ramp_f32_within_half_percent_at_50_samples_per_period() {
    for set in POLE_SETS {
        let m = measure::<f32>(MaxwellForm::RateExactRamp, &set.ratios, 50).unwrap();
        let (s, l, _) = m.errors(&set.ratios);
        assert!(
            s.abs() <= 5e-3 && l.abs() <= 5e-3,
            "{}: {s:e} / {l:e}",
            set.name
        );
    }
}

/// The energy each step reports adds up to π X² K'' per steady cycle.
#[test]
fn exact_ramp_dissipated_energy_matches_loss_modulus() {
    for set in POLE_SETS {
        let m = measure::<f64>(MaxwellForm::RateExactRamp, &set.ratios, 50).unwrap();
        let (_, _, e) = m.errors(&set.ratios);
        assert!(e.abs() <= 1e-3, "{}: energy error {e:e}", set.name);
    }
}

/// The thesis's midpoint form (1.17) loses the loss modulus of cells with
/// ω dt ≫ 1: with the fast set at 50 samples per period more than 15 % of
/// K'' is gone (the exact-ramp form keeps it within 0.5 %).
#[test]
fn midpoint_form_loses_loss_modulus_of_fast_cells() {
    let fast = POLE_SETS[2].ratios;
    let m = measure::<f64>(MaxwellForm::RateMidpoint, &fast, 50).unwrap();
    let (_, l, _) = m.errors(&fast);
    assert!(l < -0.15, "midpoint loss error {l:e}");
}

/// Eq 1.15 keeps a static-gain error of h²/24 per cell, which explodes for
/// fast cells: the storage modulus of the fast set is more than doubled.
#[test]
fn load_exponential_form_overshoots_storage_with_fast_cells() {
    let fast = POLE_SETS[2].ratios;
    let m = measure::<f64>(MaxwellForm::LoadExponential, &fast, 50).unwrap();
    let (s, _, _) = m.errors(&fast);
    assert!(s > 0.9, "load-exponential storage error {s:e}");
}

#[test]
fn committed_accuracy_table_is_current() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/maxwell-accuracy.md");
    let committed = std::fs::read_to_string(path).expect("docs/maxwell-accuracy.md");
    assert!(
        committed == modulus::table(),
        "docs/maxwell-accuracy.md is stale: run `cargo run --release -p bushing-sim -- maxwell-table --out docs/maxwell-accuracy.md`"
    );
}
