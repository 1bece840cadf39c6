//! A scene run end to end: the trace and plot files, and the trace equal,
//! bit for bit, to the const-generic firmware kernel stepped directly.

mod common;
use common::{root, scene_files};

use bushing::{Bushing, Compensated, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};
use bushing_sim::{Scene, run};

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
        let effect = o.effects.unwrap().0.force;
        assert_eq!(effect, row[4] as f32, "effect column at t = {}", row[0]);
        assert_eq!(o.elastic + effect, row[2] as f32);
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
    assert!(scene.effects().is_empty());
    let b = bushing_sim::model::build::<f64>(&scene).unwrap();
    assert!(b.effects().effects().is_empty());
    assert_eq!(b.g0(), 1.0);
    let out = std::env::temp_dir().join(format!("bushing-bare-{}", std::process::id()));
    let summary = run::run(&scene, &out).unwrap();
    assert_eq!(summary.dissipated_mj, 0.0);
    assert!(summary.effects.is_empty());
    std::fs::remove_dir_all(out).ok();
}

#[test]
fn composite_scene_equals_the_const_generic_kernels() {
    use bushing::{IwanBank, IwanCellSpec, XfBank, XfForm, XfSpec};
    let scene = Scene::load(&root().join("scenes/hysteresis-triangle.toml")).unwrap();
    assert_eq!(scene.effects().len(), 3);
    let dyn_bushing = bushing_sim::model::build::<f32>(&scene).unwrap();
    let maxwell = MaxwellBank::<f32, 3>::new(
        MaxwellForm::RateExactRamp,
        &[
            MaxwellSpec::hz(0.5, 0.08),
            MaxwellSpec::hz(5.0, 0.10),
            MaxwellSpec::hz(50.0, 0.04),
        ],
        1e-3,
    )
    .unwrap();
    let iwan = IwanBank::<f32, 3>::new(&[
        IwanCellSpec::from_slip_distance(0.08, 150.0, 0.05),
        IwanCellSpec::from_slip_distance(0.08, 150.0, 0.2),
        IwanCellSpec::from_slip_distance(0.08, 150.0, 0.8),
    ])
    .unwrap();
    let xf =
        XfBank::<f32, 1>::new(XfForm::ExactRamp, &[XfSpec::hz(0.005, 0.2, 0.02)], 1e-3).unwrap();
    let backbone = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).unwrap();
    let fixed = Bushing::new(backbone, (maxwell, iwan, xf)).unwrap();
    assert_eq!(fixed.g0(), dyn_bushing.g0());
    let (mut sd, mut sf) = (dyn_bushing.state_at(0.0), fixed.state_at(0.0));
    let mut energy = 0.0f64;
    for n in 1..=scene.steps() {
        let x = bushing_sim::profile::displacement(&scene.profile, n as f64 * scene.dt) as f32;
        let (a, b) = (dyn_bushing.step(&mut sd, x), fixed.step(&mut sf, x));
        assert_eq!(
            (a.force, a.tangent, a.dissipated),
            (b.force, b.tangent, b.dissipated),
            "step {n}"
        );
        let (m, i, f) = b.effects.unwrap();
        for e in [m, i, f] {
            assert!(e.dissipated >= 0.0);
        }
        energy += b.dissipated as f64;
    }
    // Two closed triangles dissipate.
    assert!(energy > 0.0);
}

#[test]
fn friction_scene_equals_the_const_generic_cells_and_stays_bounded() {
    use bushing::{Berg, BoucWen, Dahl};
    let scene = Scene::load(&root().join("scenes/friction-cells.toml")).unwrap();
    assert_eq!(scene.effects().len(), 3);
    let dyn_bushing = bushing_sim::model::build::<f32>(&scene).unwrap();
    let dahl = Dahl::<f32>::new(200.0, 10.0, 1.0).unwrap();
    let bouc_wen = BoucWen::<f32>::new(20.0, 10.0, 60.0, 20.0, 8.0).unwrap();
    let berg = Berg::<f32>::new(12.0, 0.05).unwrap();
    let ultimate = bouc_wen.ultimate_force();
    assert!((ultimate - 20.0 * (1.0f32 / 8.0).powf(1.0 / 8.0)).abs() < 1e-4);
    let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0)).unwrap();
    let fixed = Bushing::new(backbone, (dahl, bouc_wen, berg)).unwrap();
    assert_eq!(fixed.g0(), 1.0);
    let (mut sd, mut sf) = (dyn_bushing.state_at(0.0), fixed.state_at(0.0));
    let mut energy = [0.0f64; 3];
    let mut peak = [0.0f32; 3];
    for n in 1..=scene.steps() {
        let x = bushing_sim::profile::displacement(&scene.profile, n as f64 * scene.dt) as f32;
        let (a, b) = (dyn_bushing.step(&mut sd, x), fixed.step(&mut sf, x));
        assert_eq!(
            (a.force, a.tangent, a.dissipated),
            (b.force, b.tangent, b.dissipated),
            "step {n}"
        );
        let (d, w, g) = b.effects.unwrap();
        for (i, e) in [d, w, g].into_iter().enumerate() {
            assert!(e.dissipated >= 0.0, "cell {i} at step {n}");
            energy[i] += e.dissipated as f64;
            peak[i] = peak[i].max(e.force.abs());
        }
        assert!(d.force.abs() <= 10.0 && g.force.abs() < 12.0);
        assert!(w.force.abs() <= ultimate * (1.0 + 1e-6));
    }
    // Triangles of 1 mm drive every cell to within 1 % of its saturation.
    assert!(peak[0] > 0.99 * 10.0 && peak[1] > 0.99 * ultimate && peak[2] > 0.9 * 12.0);
    // Three closed loops, each about 4 F_sat x 1 mm of area per cycle.
    for (i, e) in energy.iter().enumerate() {
        assert!(*e > 3.0 * 2.0 * peak[i] as f64, "cell {i}: {e} mJ");
    }
}

#[test]
fn committed_xf_table_is_current() {
    let path = root().join("docs/xf-saturation.md");
    let committed = std::fs::read_to_string(path).expect("docs/xf-saturation.md");
    assert!(
        committed == bushing_sim::xf_report::table(),
        "docs/xf-saturation.md is stale: run `cargo run --release -p bushing-sim -- xf-table --out docs/xf-saturation.md`"
    );
}

/// Every scene in `scenes/` loads and runs as the README runs it (`run
/// SCENE --out DIR`), refuses no step, and every plot it writes is
/// well-formed SVG whose axes carry a unit in brackets.
/// Steps `scene` both ways: compiled (as `run` does) and as the general
/// effect list, and demands the same rows and per-effect outputs, bit for
/// bit.
fn compiled_equals_list<T: bushing::Real + 'static>(scene: &Scene) {
    use bushing_sim::model::{self, Shape};
    let mut compiled = model::compile::<T>(scene).unwrap();
    if let Some(spec) = scene.oscillator {
        return oscillator_equals_core::<T>(scene, spec, compiled.as_mut());
    }
    let expected = match scene.effects().len() {
        0 => Shape::BackboneOnly,
        1 => Shape::One,
        _ => Shape::List,
    };
    assert_eq!(compiled.shape(), expected, "{}", scene.title);
    assert_eq!(compiled.effect_count(), scene.effects().len());
    let list = model::build::<T>(scene).unwrap();
    assert_eq!(compiled.g0(), list.g0());
    let x0 = bushing_sim::profile::displacement(&scene.profile, 0.0);
    let mut state = list.state_at(T::from_f64(x0));
    let steps = scene.steps().min(50_000);
    let inputs: Vec<T> = (1..=steps)
        .map(|n| {
            T::from_f64(bushing_sim::profile::displacement(
                &scene.profile,
                n as f64 * scene.dt,
            ))
        })
        .collect();
    let (mut rows, mut parts) = (Vec::new(), Vec::new());
    for chunk in inputs.chunks(1000) {
        compiled.step_into(chunk, &mut rows, &mut parts);
    }
    assert_eq!(rows.len(), inputs.len());
    assert_eq!(parts.len(), inputs.len() * scene.effects().len());
    let count = scene.effects().len();
    for (n, (&x, row)) in inputs.iter().zip(&rows).enumerate() {
        let o = list.step(&mut state, x);
        let bits = |v: T| v.bits();
        assert_eq!(
            [row.force, row.tangent, row.dissipated, row.elastic].map(bits),
            [o.force, o.tangent, o.dissipated, o.elastic].map(bits),
            "{}: step {n}",
            scene.title
        );
        assert_eq!(row.refused, o.effects.is_none());
        let mine = &parts[n * count..(n + 1) * count];
        let theirs = model::effect_outputs(&state);
        for (a, b) in mine.iter().zip(&theirs) {
            assert_eq!(
                [a.force, a.tangent, a.dissipated].map(bits),
                [b.force, b.tangent, b.dissipated].map(bits),
                "{}: step {n}",
                scene.title
            );
        }
    }
    assert_eq!(compiled.refused(), state.rejected());
}

/// An oscillator scene steps as the core's `Oscillator` on the effect
/// list, the profile giving the force.
fn oscillator_equals_core<T: bushing::Real + 'static>(
    scene: &Scene,
    spec: bushing_sim::scene::OscillatorSpec,
    compiled: &mut dyn bushing_sim::model::SceneModel<T>,
) {
    use bushing_sim::model::{self, Shape};
    assert_eq!(compiled.shape(), Shape::Oscillator);
    let force = |n: u64| {
        T::from_f64(bushing_sim::profile::displacement(
            &scene.profile,
            n as f64 * scene.dt,
        ))
    };
    let core = bushing::Oscillator::new(model::build::<T>(scene).unwrap(), scene.dt).unwrap();
    let mut state = core.state_at(T::from_f64(spec.p0), T::from_f64(spec.v0), force(0));
    let inputs: Vec<T> = (1..=scene.steps().min(20_000)).map(force).collect();
    let (mut rows, mut parts) = (Vec::new(), Vec::new());
    compiled.step_into(&inputs, &mut rows, &mut parts);
    assert_eq!(parts.len(), inputs.len() * scene.effects().len());
    for (n, (&f, row)) in inputs.iter().zip(&rows).enumerate() {
        let o = core.step(&mut state, f);
        assert_eq!(
            [row.x, row.force, row.dissipated].map(|v| v.bits()),
            [o.p, o.force, o.dissipated].map(|v| v.bits()),
            "{}: step {n}",
            scene.title
        );
        assert_eq!(row.refused, !o.converged);
    }
}

#[test]
fn every_scene_compiled_steps_bit_for_bit_as_the_effect_list() {
    let mut seen = 0;
    for path in scene_files() {
        let scene = Scene::load(&path).unwrap();
        compiled_equals_list::<f32>(&scene);
        compiled_equals_list::<f64>(&scene);
        // The same scene with its first effect only, and with none.
        for keep in [1, 0] {
            let first: Vec<usize> = (0..keep.min(scene.effects().len())).collect();
            let sub = scene.only(&first);
            compiled_equals_list::<f32>(&sub);
        }
        seen += 1;
    }
    assert!(seen >= 30, "{seen} scenes");
}
