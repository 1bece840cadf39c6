//! Prints the golden-trace hash computed on the host, and checks it against
//! the committed constant that the Cortex-M suite also requires.

#[test]
fn golden_trace_hash_is_the_committed_one() {
    let h = bushing_tests::golden_trace().expect("golden trace runs");
    println!(
        "golden trace hash over {} steps: {h:#018x}",
        bushing_tests::GOLDEN_STEPS
    );
    assert_eq!(
        h,
        bushing_tests::GOLDEN_HASH,
        "kernel output changed; if deliberate, set GOLDEN_HASH = {h:#018x}"
    );
}

#[test]
fn hysteresis_golden_trace_hash_is_the_committed_one() {
    let h = bushing_tests::golden_trace_hysteresis().expect("golden trace runs");
    println!("hysteresis golden trace hash: {h:#018x}");
    assert_eq!(
        h,
        bushing_tests::GOLDEN_HYSTERESIS_HASH,
        "kernel output changed; if deliberate, set GOLDEN_HYSTERESIS_HASH = {h:#018x}"
    );
}

#[test]
fn friction_golden_trace_hash_is_the_committed_one() {
    let h = bushing_tests::golden_trace_friction().expect("golden trace runs");
    println!("friction golden trace hash: {h:#018x}");
    assert_eq!(
        h,
        bushing_tests::GOLDEN_FRICTION_HASH,
        "kernel output changed; if deliberate, set GOLDEN_FRICTION_HASH = {h:#018x}"
    );
}
