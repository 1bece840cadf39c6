//! Iwan equivalents of the order-independent laws: the error falls with the
//! order, and the committed report is current.

use bushing_sim::iwan_report::{
    self, ORDERS, PLACEMENTS, SEGALMAN_PLACEMENTS, segalman_error, sts_error,
};

#[test]
fn sts_iwan_error_falls_with_n_for_both_placements() {
    for (name, placement) in PLACEMENTS {
        let errors: Vec<f64> = ORDERS
            .iter()
            .map(|&n| sts_error(n, placement).unwrap())
            .collect();
        for pair in errors.windows(2) {
            assert!(pair[1] < pair[0], "{name}: {errors:?}");
        }
        println!("{name}: {errors:?}");
    }
    // Logarithmic placement wins from N = 8 on, and reaches 0.1 % at N = 64.
    for &n in &ORDERS[1..] {
        assert!(sts_error(n, PLACEMENTS[1].1).unwrap() < sts_error(n, PLACEMENTS[0].1).unwrap());
    }
    assert!(sts_error(64, PLACEMENTS[1].1).unwrap() < 1e-3);
}

#[test]
fn segalman_log_placement_resolves_micro_slip_where_uniform_cannot() {
    let (f_s, k_t, chi, beta) = iwan_report::SEGALMAN;
    let phi_max = bushing::discretize::Segalman::new(f_s, k_t, chi, beta)
        .unwrap()
        .phi_max();
    for frac in iwan_report::AMPLITUDES {
        let log = segalman_error(64, SEGALMAN_PLACEMENTS[1].1, frac * phi_max).unwrap();
        assert!(log.abs() < 1e-2, "log, a = {frac} phi_max: {log}");
    }
    // At a = 1e-3 phi_max no uniform slider slides: no dissipation at all.
    let uniform = segalman_error(64, SEGALMAN_PLACEMENTS[0].1, 1e-3 * phi_max).unwrap();
    assert_eq!(uniform, -1.0);
}

#[test]
fn committed_iwan_table_is_current() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/iwan-discretization.md"
    );
    let committed = std::fs::read_to_string(path).expect("docs/iwan-discretization.md");
    assert!(
        committed == iwan_report::table(),
        "docs/iwan-discretization.md is stale: run `cargo run --release -p bushing-sim -- iwan-table --out docs/iwan-discretization.md`"
    );
}
