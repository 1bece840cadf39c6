//! The outputs of a scene run (issue 6, build items 2-3, acceptance 1-2):
//! every plot well-formed SVG with labelled axes and units, the trace with
//! exactly the columns of the effects present, the instantaneous modulus
//! of a Maxwell scene against the bank's exact complex modulus, the
//! `validate` lines of a Maxwell and an Iwan scene, and the `cost` report
//! (its parts and arithmetic only: no timing is asserted).

mod common;
use common::{root, scene_files};
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use bushing::{MaxwellBank, MaxwellSpec};
use bushing_sim::family::maxwell::Maxwell;
use bushing_sim::scene::Effect;
use bushing_sim::validate::{self, Outcome};
use bushing_sim::{Scene, cost, plot, run};

fn out_dir(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("bushing-outputs-{name}-{}", std::process::id()))
}

/// The text of every `<text>` element.
fn texts(svg: &str) -> Vec<&str> {
    svg.split("<text")
        .skip(1)
        .filter_map(|s| {
            let body = s.get(s.find('>')? + 1..)?;
            body.get(..body.find("</text>")?)
        })
        .collect()
}

/// Each panel of a plot has a horizontal and a vertical axis label with a
/// unit in brackets; `labels` are the expected ones (escaped as written).
fn check_plot(path: &Path, labels: &[&str]) {
    let text = std::fs::read_to_string(path).unwrap();
    plot::well_formed(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let all = texts(&text);
    for label in labels {
        assert!(
            all.contains(label),
            "{}: no axis label {label:?}",
            path.display()
        );
        assert!(label.ends_with(']') && label.contains(" ["), "{label}");
    }
    let panels = text.matches("<g transform=").count();
    let with_unit = all.iter().filter(|t| t.ends_with(']')).count();
    assert!(panels >= 1 && with_unit >= 2 * panels, "{}", path.display());
}

const TIME: &str = "time t [s]";
const FORCE: &str = "force F [N]";

fn check_all_plots(out: &Path, sine: bool) {
    check_plot(
        &out.join("force-displacement.svg"),
        &["displacement x [mm]", FORCE],
    );
    check_plot(&out.join("force-time.svg"), &[TIME, FORCE]);
    check_plot(
        &out.join("dissipated-power.svg"),
        &[
            TIME,
            "dissipated power P [mW = N·mm/s]",
            "dissipated energy E [mJ = N·mm]",
        ],
    );
    let modulus = out.join("modulus-amplitude.svg");
    assert_eq!(modulus.exists(), sine, "{}", modulus.display());
    assert_eq!(out.join("modulus.csv").exists(), sine);
    if sine {
        check_plot(
            &modulus,
            &[
                "imposed amplitude X [mm]",
                "modulus K&apos;, K&apos;&apos; [N/mm]",
            ],
        );
    }
}

/// Rows of a CSV file after its header.
fn rows(path: &Path) -> (String, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn quickstart_plots_are_well_formed_with_units() {
    let scene = Scene::load(&root().join("scenes/quickstart.toml")).unwrap();
    let out = out_dir("quickstart");
    let summary = run::run(&scene, &out).unwrap();
    check_all_plots(&out, true);
    // 10 cycles: the tracker starts after one (the running mean), skips 2
    // and ends half a period early: 6 or more points, all at 2 mm and 5 Hz.
    let (header, modulus) = rows(&out.join("modulus.csv"));
    assert_eq!(
        header,
        "frequency_hz,amplitude_mm,storage_N_per_mm,loss_N_per_mm,loss_factor"
    );
    assert!(modulus.len() >= 6, "{}", modulus.len());
    assert_eq!(modulus.len(), summary.modulus.len());
    for r in &modulus {
        assert_eq!(r[0], 5.0);
        assert!((r[1] - 2.0).abs() < 1e-6, "{r:?}");
        // Between the long-term and the instantaneous secant stiffness of
        // the cubic backbone at 2 mm (150 + 4·4 N/mm), lossy, η = K''/K'.
        assert!(r[2] > 0.65 * 150.0 && r[2] < 166.0 && r[3] > 0.0, "{r:?}");
        assert!((r[4] - r[3] / r[2]).abs() < 1e-12 * r[4].abs().max(1.0));
    }
    std::fs::remove_dir_all(out).ok();
}

/// Every scene of `scenes/` (and its subdirectories) runs without a
/// refused step and writes well-formed plots with units; the modulus plot
/// exactly when the profile imposes a sine somewhere.
#[test]
fn every_scene_writes_well_formed_plots() {
    let names = scene_files();
    assert!(names.len() >= 30, "{} scenes", names.len());
    for path in names {
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        let out = out_dir(&format!("all-{stem}"));
        let summary = run::run(&scene, &out).unwrap_or_else(|e| panic!("{stem}: {e}"));
        assert_eq!(summary.refused, 0, "{stem}");
        assert!(summary.steps > 0, "{stem}");
        let sine = (1..=scene.steps()).any(|i| {
            bushing_sim::profile::frequency_at(&scene.profile, i as f64 * scene.dt).is_some()
        });
        check_all_plots(&out, sine);
        std::fs::remove_dir_all(out).ok();
    }
}

#[test]
fn a_triangle_scene_writes_no_modulus() {
    let scene = Scene::load(&root().join("scenes/hysteresis-triangle.toml")).unwrap();
    let out = out_dir("triangle");
    let summary = run::run(&scene, &out).unwrap();
    check_all_plots(&out, false);
    assert!(summary.modulus.is_empty());
    std::fs::remove_dir_all(out).ok();
}

/// The scene's Maxwell cells and the complex modulus of its discrete bank
/// at `f` Hz on the linear backbone K^∞: `K^∞ (g^0 + Σ H_i)`.
fn exact_modulus(scene: &Scene, k_inf: f64, f: f64) -> (f64, f64) {
    let Effect::Maxwell(Maxwell { form, cells, .. }) = &scene.effects()[0] else {
        panic!("not a Maxwell scene");
    };
    let specs: [MaxwellSpec; 4] = cells.clone().try_into().unwrap();
    let bank = MaxwellBank::<f32, 4>::new(*form, &specs, scene.dt).unwrap();
    let (s, l) = bank.branch_response(TAU * f);
    let g0 = 1.0 - cells.iter().map(|c| c.g).sum::<f64>();
    (k_inf * (g0 + s), k_inf * l)
}

#[test]
fn maxwell4_trace_columns_and_modulus_against_the_exact_bank() {
    let scene = Scene::load(&root().join("scenes/maxwell4.toml")).unwrap();
    let out = out_dir("maxwell4");
    let summary = run::run(&scene, &out).unwrap();
    check_all_plots(&out, true);
    // No column for any absent effect.
    let (header, trace) = rows(&out.join("trace.csv"));
    assert_eq!(
        header,
        "time_s,x_mm,force_N,elastic_N,maxwell_rate-exact-ramp_x4_N,dissipated_mJ"
    );
    assert_eq!(trace.len() as u64, summary.steps);
    assert!(trace.iter().all(|r| r.len() == 6));

    // Every point is taken 2 tracked periods or more after the tracker's
    // start: storage and loss within 0.5 % of the discrete bank's exact
    // response (seed 000 eq 1.8 as sampled).
    let (storage, loss) = exact_modulus(&scene, 200.0, 10.0);
    let (_, modulus) = rows(&out.join("modulus.csv"));
    // 40 cycles: about 36 tracked periods after the 2 skipped.
    assert!(modulus.len() >= 35, "{}", modulus.len());
    let mut worst = (0.0f64, 0.0f64);
    for r in &modulus {
        assert_eq!(r[0], 10.0);
        assert!((r[1] - 1.0).abs() < 1e-6, "{r:?}");
        worst.0 = worst.0.max((r[2] / storage - 1.0).abs());
        worst.1 = worst.1.max((r[3] / loss - 1.0).abs());
    }
    assert!(worst.0 < 5e-3 && worst.1 < 5e-3, "{worst:?}");
    // Steady at the end: within 1e-5 of the reference.
    let last = modulus.last().unwrap();
    assert!((last[2] / storage - 1.0).abs() < 1e-5, "{last:?}");
    assert!((last[3] / loss - 1.0).abs() < 1e-5, "{last:?}");
    std::fs::remove_dir_all(out).ok();
}

#[test]
fn every_state_storage_gives_the_same_force_for_cells_that_are_not_slow() {
    // maxwell4 (1 to 100 Hz at 2 kHz: ω dt from 3e-3) in f32 with each
    // storage: the multiplied pole rounds by at most 2^-25 / ω dt = 1e-5
    // of the decay rate, the compensated state is exact; the force traces
    // agree within 1e-4 of the peak force.
    let text = std::fs::read_to_string(root().join("scenes/maxwell4.toml")).unwrap();
    let mut traces = Vec::new();
    for state in ["plain", "multiplied", "compensated"] {
        let edited = text.replace(
            "form = \"rate-exact-ramp\"",
            &format!("form = \"rate-exact-ramp\"\nstate = \"{state}\""),
        );
        assert_ne!(edited, text);
        let scene = Scene::parse("maxwell4.toml", &edited).unwrap();
        let out = out_dir(&format!("maxwell4-{state}"));
        run::run(&scene, &out).unwrap();
        let (_, trace) = rows(&out.join("trace.csv"));
        traces.push(trace.iter().map(|r| r[2]).collect::<Vec<f64>>());
        std::fs::remove_dir_all(out).ok();
    }
    let peak = traces[0].iter().fold(0.0f64, |m, f| m.max(f.abs()));
    assert!(peak > 100.0, "{peak}");
    for other in &traces[1..] {
        assert_eq!(other.len(), traces[0].len());
        let worst = traces[0]
            .iter()
            .zip(other)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-4 * peak, "{worst} of {peak}");
    }
    // The storages differ (rounding), so the test sees three kernels.
    assert_ne!(traces[0], traces[1]);
}

/// The relative error printed at the end of a validate line.
fn printed_error(line: &str) -> f64 {
    let at = line.rfind("relative error ").unwrap() + "relative error ".len();
    line[at..].trim().parse().unwrap()
}

#[test]
fn validate_a_maxwell_scene_within_half_a_percent() {
    let scene = Scene::load(&root().join("scenes/maxwell4.toml")).unwrap();
    let report = validate::validate(&scene).unwrap();
    let text = report.to_string();
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines[0].starts_with("validate: sine of 1e0 mm at 1e1 Hz"),
        "{text}"
    );
    assert_eq!(lines.len(), 6, "{text}");
    for line in &lines[1..] {
        assert!(line.starts_with("maxwell rate-exact-ramp x4: "), "{line}");
        let e = printed_error(line);
        assert!(e.abs() < 5e-3, "{line}");
    }
    // Against the discrete bank the fit is exact to rounding.
    let (storage, loss) = exact_modulus(&scene, 200.0, 10.0);
    match report.checks[0].outcome {
        Outcome::Compared {
            reference,
            measured,
        } => {
            assert!((reference / storage - 1.0).abs() < 1e-12);
            assert!((measured / storage - 1.0).abs() < 1e-5, "{measured}");
        }
        Outcome::NoReference(ref why) => panic!("{why}"),
    }
    let loss_check = &report.checks[1];
    assert!(loss_check.what.starts_with("loss K''"));
    assert!(loss_check.relative_error().unwrap().abs() < 1e-5);
    assert!(
        matches!(loss_check.outcome, Outcome::Compared { reference, .. } if (reference / loss - 1.0).abs() < 1e-12)
    );
}

const IWAN: &str = r#"
title = "Iwan clamp and Berg on a linear backbone"
[run]
rate_hz = 1000
number = "f64"
[backbone]
type = "polynomial"
coefficients = [0.0, 150.0]
range = [-5.0, 5.0]
[[effects]]
type = "iwan"
form = "clamp"
cells = [{ g = 0.1, x_f = 0.05 }, { g = 0.1, x_f = 0.3 }, { g = 0.1, x_f = 2.0 }]
[[effects]]
type = "berg"
f_max = 12.0
x2 = 0.05
[[effects]]
type = "turning-points"
law = "sts"
c = 400.0
k1 = 300.0
[profile]
type = "sine"
amplitude = 1.0
frequency_hz = 2.0
cycles = 4
"#;

#[test]
fn validate_an_iwan_scene_against_its_masing_loops() {
    let scene = Scene::parse("iwan.toml", IWAN).unwrap();
    let text = validate::validate(&scene).unwrap().to_string();
    let lines: Vec<&str> = text.lines().collect();
    // Per hysteresis effect: the steady cycle's energy and swing, and the
    // energy of an asymmetric inner loop (0.2A to 0.6A after +-A).
    assert_eq!(lines.len(), 8, "{text}");
    for effect in ["iwan clamp x3", "turning-points sts"] {
        let inner = format!("{effect}: energy of an asymmetric inner loop");
        assert!(lines.iter().any(|l| l.starts_with(&inner)), "{text}");
    }
    // Cells of slip distance 0.05 and 0.3 mm slip, the 2 mm one does not:
    // 4 F_f (A - x_f) = 4 (0.75 (0.95) + 4.5 (0.7)) = 15.45 mJ per cycle.
    let energy = lines
        .iter()
        .find(|l| l.starts_with("iwan clamp x3: energy per steady cycle"))
        .unwrap();
    assert!(energy.contains("reference 1.545000e1 mJ"), "{energy}");
    // Tip: 0.75 + 4.5 + 0.1·150·1 = 20.25 N.
    let tip = lines
        .iter()
        .find(|l| l.starts_with("iwan clamp x3: half peak-to-peak force"))
        .unwrap();
    assert!(tip.contains("reference 2.025000e1 N"), "{tip}");
    for line in &lines[1..] {
        let e = printed_error(line);
        // The clamp form and the stack are exact, force and energy, on
        // every loop (the stack's energy is the closed-form work along each
        // branch travelled); Berg's loop has converged to within 1e-3 after
        // 3 cycles.
        let bound = if line.starts_with("berg") { 1e-3 } else { 1e-9 };
        assert!(e.abs() < bound, "{line}");
    }
    // A nonlinear backbone has no closed form for the clamp form.
    let cubic = IWAN.replace("[0.0, 150.0]", "[0.0, 150.0, 0.0, 4.0]");
    let text = validate::validate(&Scene::parse("c.toml", &cubic).unwrap())
        .unwrap()
        .to_string();
    assert!(
        text.contains("iwan clamp x3: no closed-form reference (the clamp form's Masing loop needs a linear backbone)"),
        "{text}"
    );
}

#[test]
fn cost_lists_every_part_and_adds_them_up() {
    let scene = Scene::load(&root().join("scenes/hysteresis-triangle.toml")).unwrap();
    let options = cost::CostOptions {
        min_steps: 20_000,
        max_steps: 20_000,
        repetitions: 2,
    };
    let report = cost::cost_with(&scene, options).unwrap();
    let text = report.to_string();
    let value = |line: &str| -> f64 {
        let v = line.trim_end().strip_suffix("ns/step").unwrap();
        v.split_whitespace().last().unwrap().parse().unwrap()
    };
    let mut parts = Vec::new();
    for name in [
        "backbone alone (polynomial)",
        "maxwell rate-exact-ramp x3",
        "iwan clamp x3",
        "xf exact-ramp x1",
    ] {
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("part  {name} ")))
            .unwrap_or_else(|| panic!("no part {name}:\n{text}"));
        parts.push(value(line));
    }
    let sum = value(
        text.lines()
            .find(|l| l.starts_with("sum of parts"))
            .unwrap(),
    );
    let whole = value(text.lines().find(|l| l.starts_with("scene ")).unwrap());
    let ratio: f64 = text
        .lines()
        .find(|l| l.starts_with("ratio scene / sum of parts"))
        .and_then(|l| l.split_whitespace().last())
        .unwrap()
        .parse()
        .unwrap();
    assert!(parts.iter().chain([&sum, &whole]).all(|v| v.is_finite()));
    assert!(whole > 0.0 && parts[0] > 0.0, "{text}");
    // The printed figures are rounded to 0.01 ns and the ratio to 0.001.
    assert!((parts.iter().sum::<f64>() - sum).abs() < 0.03, "{text}");
    assert!(
        (whole / sum - ratio).abs() < 1e-3 + 0.02 / sum.abs(),
        "{text}"
    );
    assert_eq!(report.parts.len(), 4);
    assert_eq!(report.shape, bushing_sim::model::Shape::List);
    assert!(text.contains("scene (effect list)"), "{text}");
    assert!(
        text.lines().any(|l| l
            == "for comparison: maxwell rate-exact-ramp x3 as a const-size MaxwellBank<f32, 3>, effect only"),
        "{text}"
    );
}

#[test]
fn a_one_effect_scene_is_costed_as_its_own_bushing_type_and_as_a_list() {
    let scene = Scene::load(&root().join("scenes/maxwell4.toml")).unwrap();
    let options = cost::CostOptions {
        min_steps: 10_000,
        max_steps: 10_000,
        repetitions: 1,
    };
    let report = cost::cost_with(&scene, options).unwrap();
    assert_eq!(report.shape, bushing_sim::model::Shape::One);
    assert_eq!(report.measure, cost::Measure::WallClock);
    let names: Vec<_> = report.comparisons.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "the whole scene as an effect list (model::build)",
            "maxwell rate-exact-ramp x4 as a const-size MaxwellBank<f32, 4>, effect only"
        ]
    );
    assert!(report.comparisons.iter().all(|p| p.ns_per_step.is_finite()));
    // The hidden child command of `cost --instructions` refuses a part
    // the plan does not have.
    let err = cost::run_part(&scene, 5, 10).unwrap_err();
    assert_eq!(err.to_string(), "no part 5 (the scene has 5)");
    assert!(cost::run_part(&scene, 4, 10).is_ok());
}

/// The trace of `scene`: header and rows.
fn trace(scene: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let scene = Scene::load(&root().join(scene)).unwrap();
    let out = out_dir(&format!("columns-{}", scene.effects().len()));
    run::run(&scene, &out).unwrap();
    let text = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    std::fs::remove_dir_all(&out).ok();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn every_trace_row_has_that_steps_effect_forces() {
    // The bushing's force is g0 F_inf + (((0 + F_1) + F_2) + ...) in the
    // scene's type; each column is printed exactly (f32 through f64), so
    // the row must add up bit for bit. Each effect column changes on at
    // least a tenth of the rows (a saturated friction cell holds its force
    // while it slides; a column repeated over a chunk of steps would change
    // once in thousands of rows).
    for (file, effects) in [
        ("scenes/maxwell4.toml", 1),
        ("scenes/hysteresis-triangle.toml", 3),
        ("scenes/friction-cells.toml", 3),
    ] {
        let (header, rows) = trace(file);
        assert_eq!(header.len(), 5 + effects, "{file}: {header:?}");
        assert!(rows.len() > 4096, "{file}: {} rows", rows.len());
        for (i, row) in rows.iter().enumerate() {
            let sum = row[4..4 + effects]
                .iter()
                .fold(0.0f32, |acc, &f| acc + f as f32);
            assert_eq!(
                row[3] as f32 + sum,
                row[2] as f32,
                "{file}, row {i}: {row:?}"
            );
        }
        for j in 4..4 + effects {
            let changes = rows.windows(2).filter(|w| w[0][j] != w[1][j]).count();
            assert!(
                changes * 10 >= rows.len(),
                "{file}: column {} changes on {changes} of {} rows",
                header[j],
                rows.len()
            );
        }
    }
}

#[test]
fn trace_every_keeps_every_nth_row_and_the_last() {
    let text = std::fs::read_to_string(root().join("scenes/maxwell4.toml")).unwrap();
    let full = Scene::parse("maxwell4.toml", &text).unwrap();
    let sparse = Scene::parse(
        "maxwell4.toml",
        &format!("{text}\n[output]\ntrace_every = 7\n"),
    )
    .unwrap();
    assert_eq!((full.trace_every, sparse.trace_every), (1, 7));
    let read = |scene: &Scene, name: &str| {
        let out = out_dir(name);
        let summary = run::run(scene, &out).unwrap();
        let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
        std::fs::remove_dir_all(&out).ok();
        let rows: Vec<String> = csv.lines().skip(1).map(String::from).collect();
        (summary, rows)
    };
    let (a, all) = read(&full, "every-1");
    let (b, kept) = read(&sparse, "every-7");
    let steps = full.steps() as usize;
    assert_eq!(all.len(), steps);
    // Rows 7, 14, ... and the last step (8000 is not a multiple of 7).
    assert_eq!(steps % 7, 6);
    assert_eq!(kept.len(), steps / 7 + 1);
    for (j, row) in kept.iter().enumerate() {
        let i = if j < steps / 7 { 7 * (j + 1) } else { steps };
        assert_eq!(row, &all[i - 1], "kept row {j} is step {i}");
    }
    // The energies and plots still see every step.
    assert_eq!(a.dissipated_mj, b.dissipated_mj);
    assert_eq!(a.modulus, b.modulus);
}
