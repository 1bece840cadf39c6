//! Time to identify a campaign of 40 tests and about 10⁶ samples, on one
//! core: the in-class truth of `examples/identification/truth.toml` on a
//! multi-step test with holds of 3600 s, three triangles and 36 sines
//! (0.1 to 50 Hz, 0.05 to 1 mm) of 533 cycles each at 50 samples per
//! period, 0.5 % force noise. Generating the campaign is not timed.
//!
//! `cargo bench -p bushing-sim --bench identify`. Printed, never asserted.

use std::path::Path;

use bushing_sim::Scene;
use bushing_sim::identify::campaign::{Campaign, DEFAULT_PRELOAD_HOLD_S};
use bushing_sim::identify::class::ModelClass;
use bushing_sim::identify::outcome::identify;
use bushing_sim::identify::synth::{self, Shape};
use bushing_sim::output::Staged;
use divan::Bencher;

fn main() {
    divan::main();
}

/// The 40 tests.
fn grid() -> Vec<Shape> {
    let mut grid = vec![Shape::MultiStep {
        levels: vec![0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0],
        hold_s: 3600.0,
    }];
    for (speed, a) in [(10.0, 1.0), (10.0, 4.5), (1.0, 1.0)] {
        grid.push(Shape::Triangle {
            speed_mm_per_min: speed,
            amplitude_mm: a,
            preload_mm: 0.0,
            cycles: 3,
            samples_per_mm: bushing_sim::identify::synth::PART_SAMPLES_PER_MM,
        });
    }
    grid.extend(Shape::sines(
        &[0.1, 0.5, 1.0, 5.0, 10.0, 50.0],
        &[0.05, 0.1, 0.25, 0.5, 0.75, 1.0],
        0.0,
        533,
    ));
    grid
}

#[divan::bench(sample_count = 1, sample_size = 1)]
fn forty_tests_a_million_samples(bencher: Bencher<'_, '_>) {
    let truth = Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/identification/truth.toml"),
    )
    .expect("the truth scene reads");
    let dir = tempfile::tempdir().expect("a temporary folder");
    let out = dir.path().join("campaign");
    let mut staged = Staged::begin(&out).expect("a staged folder");
    let samples = synth::write(
        &truth,
        &grid(),
        0.005,
        1,
        DEFAULT_PRELOAD_HOLD_S,
        &mut staged,
    )
    .expect("the campaign");
    staged.commit().expect("the campaign written");
    let campaign = Campaign::load(&out, true).expect("the campaign reads back");
    println!("{} tests, {samples} samples", campaign.tests.len());
    bencher.bench(|| {
        let id = identify(&campaign, &ModelClass::default(), &[]).expect("identified");
        println!(
            "{} Jacobians, {} replays; worst RMS {:.3} % of a test's force range",
            id.refined.jacobians,
            id.refined.replays,
            100.0 * id.fitted.iter().map(|t| t.rms).fold(0.0, f64::max)
        );
    });
}
