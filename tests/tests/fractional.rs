//! Fractional model and Maxwell fits: the acceptance bounds, and the
//! committed report current.

use bushing::{MaxwellBank, MaxwellForm, MaxwellSpec};
use bushing_sim::fractional_report::{FIT_ALPHAS, fit_fractional, table};

#[test]
fn fitted_banks_reach_one_percent_with_8_cells_and_a_tenth_with_12() {
    for alpha in FIT_ALPHAS {
        for (m, bound) in [(8, 0.01), (12, 0.001)] {
            let f = fit_fractional(alpha, m).unwrap();
            assert!(
                f.storage_error <= bound && f.loss_error <= bound,
                "alpha {alpha}, M {m}: storage {} loss {}",
                f.storage_error,
                f.loss_error
            );
            assert_eq!(f.cells.len(), m);
            assert!(f.cells.iter().all(|c| c.omega > 0.0 && c.g > 0.0));
            assert!(f.cells.iter().map(|c| c.g).sum::<f64>() <= 1.0 + 1e-9);
            // The thesis's design rule: more than one pole per decade.
            assert!(f.poles_per_decade(0.01, 100.0) > 1.0);
            if m == 8 {
                // What the firmware runs: the core's bank accepts the fit.
                let specs: [MaxwellSpec; 8] = f.cells.clone().try_into().unwrap();
                MaxwellBank::<f32, 8>::new(MaxwellForm::RateExactRamp, &specs, 5e-4).unwrap();
            }
        }
    }
}

#[test]
fn f32_retunes_stay_within_their_exponentials_error() {
    use bushing_sim::fractional_report::{RETUNE_SHIFTS, RetunePath, retune_bank, retune_error};
    let specs = retune_bank().unwrap();
    for a_t in RETUNE_SHIFTS {
        let worst = |path| {
            let (s, l) = retune_error(&specs, a_t, path).unwrap();
            s.max(l)
        };
        let rounded = worst(RetunePath::F64);
        // f32 rounding of the coefficients: a few ulps on the modulus.
        assert!(rounded < 2e-7, "a_t {a_t}: f64 path {rounded}");
        let libm = worst(RetunePath::Libm);
        assert!(libm < 2e-7, "a_t {a_t}: libm {libm}");
        // micromath's exp is off by up to 2.4e-3 on e^-h.
        let micromath = worst(RetunePath::Micromath);
        assert!(micromath < 2.4e-3, "a_t {a_t}: micromath {micromath}");
    }
}

#[test]
fn committed_fractional_report_is_current() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let committed =
        std::fs::read_to_string(root.join("docs/fractional.md")).expect("docs/fractional.md");
    assert!(
        committed == table(),
        "docs/fractional.md is stale: run `cargo run --release -p bushing-sim -- fractional-table --out docs/fractional.md`"
    );
}
