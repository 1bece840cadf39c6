//! A scene run end to end: the trace and plot files, and the trace equal,
//! bit for bit, to the const-generic firmware kernel stepped directly.

use std::path::PathBuf;

use bushing::{Bushing, Compensated, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};
use bushing_sim::{Scene, run};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn quickstart_scene_writes_trace_and_plot_equal_to_the_firmware_kernel() {
    let scene = Scene::load(&root().join("scenes/quickstart.toml")).unwrap();
    let out = std::env::temp_dir().join(format!("bushing-quickstart-{}", std::process::id()));
    let summary = run::run(&scene, &out).unwrap();
    assert_eq!(summary.steps, 4000);
    assert_eq!(summary.refused, 0);

    let svg = std::fs::read_to_string(out.join("force-displacement.svg")).unwrap();
    assert!(svg.contains("displacement x [mm]") && svg.contains("force F [N]"));

    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,x_mm,force_N,elastic_N,maxwell_rate-exact-ramp_x3_N,dissipated_mJ"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 4000);

    // The same bushing as firmware would build it.
    let specs = [
        MaxwellSpec::hz(0.5, 0.10),
        MaxwellSpec::hz(5.0, 0.20),
        MaxwellSpec::hz(50.0, 0.05),
    ];
    let bank = MaxwellBank::<f32, 3, Compensated<f32>>::new(
        MaxwellForm::RateExactRamp,
        &specs,
        1.0 / 2000.0,
    )
    .unwrap();
    let backbone = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).unwrap();
    let b = Bushing::new(backbone, (bank,)).unwrap();
    let mut s = b.state_at(0.0);
    let mut energy = 0.0f64;
    for row in &rows {
        let x = row[1] as f32;
        let o = b.step(&mut s, x);
        assert_eq!(o.force, row[2] as f32, "force at t = {}", row[0]);
        assert_eq!(o.elastic + o.effects.unwrap().0.force, row[2] as f32);
        energy += o.dissipated as f64;
    }
    let last = rows.last().unwrap();
    assert!((energy - last[5]).abs() <= 1e-9 * energy);
    // A steady loop dissipates: positive energy, about equal per cycle.
    assert!(energy > 0.0 && (summary.dissipated_mj - energy).abs() <= 1e-9 * energy);
    std::fs::remove_dir_all(out).ok();
}

#[test]
fn a_scene_with_no_effects_builds_none_and_dissipates_nothing() {
    let text = std::fs::read_to_string(root().join("scenes/quickstart.toml")).unwrap();
    let start = text.find("[[effects]]").unwrap();
    let end = text.find("[profile]").unwrap();
    let bare = format!("{}{}", &text[..start], &text[end..]);
    let scene = Scene::parse("bare.toml", &bare).unwrap();
    assert!(scene.effects.is_empty());
    let b = bushing_sim::model::build::<f64>(&scene).unwrap();
    assert!(b.effects().0.is_none());
    assert_eq!(b.g0(), 1.0);
    let out = std::env::temp_dir().join(format!("bushing-bare-{}", std::process::id()));
    let summary = run::run(&scene, &out).unwrap();
    assert_eq!(summary.dissipated_mj, 0.0);
    assert!(summary.effects.is_empty());
    std::fs::remove_dir_all(out).ok();
}
