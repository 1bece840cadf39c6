//! The slave against `bushing-sim run`'s stepping, its rollback, and
//! every misuse with the status the standard gives it.

use std::path::{Path, PathBuf};

use bushing::{Faults, Real};

use super::description::{ENERGY, FAULTS, FORCE, REFUSED, TANGENT, TEMPERATURE, X};
use super::resource::FmuModel;
use super::slave::{Phase, Slave, Status};
use crate::model::{StepRow, compile, step_scene};
use crate::scene::{LoadOptions, NumberType, Scene};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(name)
}

/// Read in `number`.
fn options(number: NumberType) -> LoadOptions {
    LoadOptions {
        number: Some(number),
        confine: false,
    }
}

fn model(name: &str, number: NumberType) -> FmuModel {
    let options = options(number);
    FmuModel::from_scene(&scene_path(name), options).unwrap()
}

fn slave(model: FmuModel) -> Slave {
    let guid = model.guid.clone();
    Slave::new(model, &guid).unwrap()
}

/// A slave initialised at rest at `x0`.
fn started(model: FmuModel, x0: f64) -> Slave {
    let mut s = slave(model);
    s.setup_experiment(0.0).unwrap();
    s.enter_initialization().unwrap();
    s.set_real(X, x0).unwrap();
    s.exit_initialization().unwrap();
    s
}

/// Force, tangent and energy of `bushing-sim run`'s stepping of the scene
/// (its first `steps` steps), and of the slave given the same inputs one
/// model step per communication step, the temperature set as the scene's
/// history re-tunes it: bit for bit.
fn same_as_run<T: Real + 'static>(name: &str, number: NumberType, steps: u64) {
    let options = options(number);
    let scene = Scene::load_with(&scene_path(name), options).unwrap();
    let mut model = compile::<T>(&scene).unwrap();
    let inputs: Vec<T> = (1..=steps)
        .map(|n| T::from_f64(scene.input(n as f64 * scene.dt)))
        .collect();
    let (mut rows, mut parts): (Vec<StepRow<T>>, _) = (Vec::new(), Vec::new());
    step_scene(&scene, model.as_mut(), 0, &inputs, &mut rows, &mut parts).unwrap();

    let mut s = started(self::model(name, number), scene.input(0.0));
    let mut energy = 0.0;
    for (n, row) in rows.iter().enumerate() {
        let t = n as f64 * scene.dt;
        if let Some(h) = &scene.temperature
            && (n as u64).is_multiple_of(h.every)
        {
            s.set_real(TEMPERATURE, h.at(t)).unwrap();
        }
        s.set_real(X, scene.input((n + 1) as f64 * scene.dt))
            .unwrap();
        assert_eq!(s.do_step(t, scene.dt), Ok(None), "{name} step {n}");
        energy += row.dissipated.to_f64();
        let got = [FORCE, TANGENT, ENERGY].map(|vr| s.get_real(vr).unwrap().to_bits());
        let want = [row.force.to_f64(), row.tangent.to_f64(), energy].map(f64::to_bits);
        assert_eq!(got, want, "{name} ({}) step {}", number.name(), n + 1);
    }
}

#[test]
fn maxwell_bit_for_bit() {
    same_as_run::<f64>("maxwell4.toml", NumberType::F64, 4000);
    same_as_run::<f32>("maxwell4.toml", NumberType::F32, 4000);
}

#[test]
fn composite_bit_for_bit() {
    same_as_run::<f64>("hysteresis-triangle.toml", NumberType::F64, 6000);
    same_as_run::<f32>("hysteresis-triangle.toml", NumberType::F32, 6000);
}

#[test]
fn sts_bit_for_bit() {
    same_as_run::<f64>("sts-triangles.toml", NumberType::F64, 4000);
}

#[test]
fn temperature_bit_for_bit() {
    same_as_run::<f64>("temperature-ramp.toml", NumberType::F64, 12_000);
    same_as_run::<f32>("temperature-ramp.toml", NumberType::F32, 12_000);
}

/// Outputs after each of `steps` communication steps of 3 model steps
/// under a sine.
fn outputs(s: &mut Slave, from: u64, steps: u64) -> Vec<[u64; 5]> {
    let h = 3.0 * s.dt();
    (from..from + steps)
        .map(|k| {
            let t = s.time();
            s.set_real(X, 1.5 * (k as f64 * 0.05).sin()).unwrap();
            s.do_step(t, h).unwrap();
            let reals = [FORCE, TANGENT, ENERGY].map(|vr| s.get_real(vr).unwrap().to_bits());
            let ints = [FAULTS, REFUSED].map(|vr| s.get_integer(vr).unwrap() as u64);
            [reals[0], reals[1], reals[2], ints[0], ints[1]]
        })
        .collect()
}

#[test]
fn rollback_and_serialised_state_reproduce_the_outputs() {
    for number in [NumberType::F64, NumberType::F32] {
        let mut s = started(model("hysteresis-triangle.toml", number), 0.0);
        outputs(&mut s, 0, 500);
        let saved = s.get_state().unwrap();
        let first = outputs(&mut s, 500, 300);
        s.set_state(&saved).unwrap();
        assert_eq!(
            outputs(&mut s, 500, 300),
            first,
            "set state, {}",
            number.name()
        );

        // Through bytes, into another instance of the same FMU.
        let bytes = s.serialize(&saved);
        let mut other = started(model("hysteresis-triangle.toml", number), 0.0);
        let restored = other.deserialize(&bytes).unwrap();
        assert_eq!(restored, saved);
        other.set_state(&restored).unwrap();
        assert_eq!(
            outputs(&mut other, 500, 300),
            first,
            "serialised, {}",
            number.name()
        );
    }
}

#[test]
fn rollback_restores_the_temperature_tuning() {
    let mut s = started(model("temperature-ramp.toml", NumberType::F64), 0.0);
    outputs(&mut s, 0, 100);
    let saved = s.get_state().unwrap();
    let first = outputs(&mut s, 100, 200);
    s.set_real(TEMPERATURE, 40.0).unwrap();
    outputs(&mut s, 300, 50);
    s.set_state(&saved).unwrap();
    assert_eq!(s.get_real(TEMPERATURE).unwrap(), 0.0);
    assert_eq!(outputs(&mut s, 100, 200), first);
}

fn refused(r: Result<impl std::fmt::Debug, super::slave::Report>, what: &str) -> String {
    let e = r.expect_err(what);
    assert_eq!(e.status, Status::Error, "{what}");
    e.message
}

#[test]
fn calls_out_of_order_are_errors() {
    let m = model("maxwell4.toml", NumberType::F64);
    let mut s = slave(m.clone());
    let msg = refused(s.do_step(0.0, s.dt()), "step before initialisation");
    assert!(
        msg.contains("fmi2DoStep called in phase instantiated"),
        "{msg}"
    );
    assert_eq!(s.phase(), Phase::Error);
    // Only a reset (or a saved state) brings it back.
    refused(s.enter_initialization(), "enter in error");
    s.reset().unwrap();
    assert_eq!(s.phase(), Phase::Instantiated);
    refused(s.get_real(FORCE), "get before initialisation");
    s.reset().unwrap();
    refused(s.exit_initialization(), "exit before enter");
    s.reset().unwrap();
    s.enter_initialization().unwrap();
    refused(s.setup_experiment(0.0), "setup in initialization mode");

    let mut s = started(m.clone(), 0.0);
    refused(s.enter_initialization(), "enter twice");
    let mut s = started(m, 0.0);
    s.terminate().unwrap();
    refused(s.do_step(0.0, s.dt()), "step after terminate");
}

#[test]
fn steps_that_are_not_whole_model_steps_are_errors() {
    let m = model("maxwell4.toml", NumberType::F64);
    let dt = m.scene.dt;
    for h in [0.5 * dt, 2.5 * dt, 0.0, -dt, f64::NAN, f64::INFINITY] {
        let mut s = started(m.clone(), 0.0);
        let msg = refused(s.do_step(0.0, h), "bad step");
        assert!(msg.contains("not a whole number"), "{h}: {msg}");
        assert_eq!(s.time(), 0.0);
    }
    let mut s = started(m.clone(), 0.0);
    let msg = refused(s.do_step(0.0, 2e8 * dt), "too many steps");
    assert!(msg.contains("more than the limit"), "{msg}");
    // A communication point that is not the slave's time.
    let mut s = started(m.clone(), 0.0);
    s.do_step(0.0, 4.0 * dt).unwrap();
    let msg = refused(s.do_step(0.0, dt), "repeated point");
    assert!(msg.contains("is not the FMU's time"), "{msg}");
    // A master's sum of h is off by roundings only: accepted.
    let mut s = started(m, 0.0);
    let mut t = 0.0;
    for _ in 0..1000 {
        s.do_step(t, 3.0 * dt).unwrap();
        t += 3.0 * dt;
    }
    assert_eq!(s.time(), 3000.0 * dt);
}

#[test]
fn bad_values_and_references_are_errors() {
    let m = model("maxwell4.toml", NumberType::F64);
    for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut s = started(m.clone(), 0.0);
        let msg = refused(s.set_real(X, x), "non-finite x");
        assert!(msg.contains("must be finite"), "{msg}");
        // The value was not taken.
        assert_eq!(s.get_real(X).unwrap(), 0.0);
    }
    let mut s = started(m.clone(), 0.0);
    refused(s.set_real(FORCE, 1.0), "set an output");
    let mut s = started(m.clone(), 0.0);
    refused(s.set_real(TEMPERATURE, 20.0), "no temperature input");
    let mut s = started(m.clone(), 0.0);
    refused(s.get_real(99), "unknown Real");
    let mut s = started(m.clone(), 0.0);
    refused(s.get_integer(FORCE), "a Real as Integer");
    let mut s = started(m, 0.0);
    refused(s.set_integer(FAULTS), "set an Integer output");

    // A temperature whose shifted cells the model refuses.
    let m = model("temperature-ramp.toml", NumberType::F32);
    let mut s = started(m, 0.0);
    let before = s.get_real(TEMPERATURE).unwrap();
    let msg = refused(s.set_real(TEMPERATURE, -200.0), "WLF pole");
    assert!(msg.contains("temperature = -200"), "{msg}");
    assert_eq!(s.get_real(TEMPERATURE).unwrap(), before);
}

#[test]
fn an_error_is_left_through_a_saved_state() {
    let mut s = started(model("maxwell4.toml", NumberType::F64), 0.0);
    outputs(&mut s, 0, 10);
    let saved = s.get_state().unwrap();
    let next = outputs(&mut s, 10, 5);
    refused(s.do_step(-1.0, s.dt()), "bad point");
    refused(s.get_state(), "save in error");
    s.set_state(&saved).unwrap();
    assert_eq!(s.phase(), Phase::StepComplete);
    assert_eq!(outputs(&mut s, 10, 5), next);
}

#[test]
fn refused_model_steps_are_warnings() {
    let mut s = started(model("maxwell4.toml", NumberType::F64), 0.0);
    s.set_real(X, 1.0).unwrap();
    s.do_step(0.0, s.dt()).unwrap();
    let force = s.get_real(FORCE).unwrap();
    // Beyond the working type's guard.
    s.set_real(X, 1e200).unwrap();
    let t = s.time();
    let w = s.do_step(t, 4.0 * s.dt()).unwrap().expect("a warning");
    assert_eq!(w.status, Status::Warning);
    assert!(
        w.message.contains("4 of the 4 model steps"),
        "{}",
        w.message
    );
    assert!(w.message.contains("OUT_OF_RANGE"), "{}", w.message);
    assert_eq!(s.get_real(FORCE).unwrap(), force);
    assert_eq!(
        s.get_integer(FAULTS).unwrap(),
        i32::from(Faults::OUT_OF_RANGE.bits())
    );
    assert_eq!(s.get_integer(REFUSED).unwrap(), 4);
    assert_eq!(s.phase(), Phase::StepComplete);
}

#[test]
fn foreign_or_damaged_states_are_errors() {
    let m = model("maxwell4.toml", NumberType::F64);
    let mut s = started(m.clone(), 0.0);
    outputs(&mut s, 0, 10);
    let saved = s.get_state().unwrap();
    let bytes = s.serialize(&saved);
    let mut flipped = bytes.clone();
    if let Some(b) = flipped.last_mut() {
        *b ^= 1;
    }
    for (bad, what) in [
        (&flipped[..], "damaged (CRC-32 differs)"),
        (&bytes[..bytes.len() - 3], "damaged (CRC-32 differs)"),
        (&bytes[..20], "another model"),
        (&b"not a state"[..], "no header"),
    ] {
        let mut s = started(m.clone(), 0.0);
        let msg = refused(s.deserialize(bad), what);
        assert!(msg.contains(what), "{what}: {msg}");
    }
    // A state of the same scene in the other number type is another model.
    let mut other = started(model("maxwell4.toml", NumberType::F32), 0.0);
    let foreign = other.get_state().unwrap();
    let msg = refused(other.deserialize(&bytes), "f64 state into f32");
    assert!(msg.contains("another model"), "{msg}");
    let msg = refused(s.set_state(&foreign), "set a foreign state");
    assert!(msg.contains("another model"), "{msg}");
}

#[test]
fn a_changed_or_bad_resource_is_refused() {
    let m = model("maxwell4.toml", NumberType::F64);
    let e = Slave::new(m.clone(), "{00000000-0000-0000-0000-000000000000}").unwrap_err();
    assert_eq!(e.status, Status::Error);
    assert!(e.message.contains("is not the GUID"), "{}", e.message);

    let dir = tempfile::tempdir().unwrap();
    let missing = FmuModel::load(dir.path()).unwrap_err().to_string();
    assert!(missing.contains("model.toml"), "{missing}");
    let broken = m.text.replace("[backbone]", "[backbone\n");
    std::fs::write(dir.path().join("model.toml"), broken).unwrap();
    let malformed = FmuModel::load(dir.path()).unwrap_err().to_string();
    assert!(malformed.contains("model.toml"), "{malformed}");
    let bad_value = m.text.replace("g = 0.1", "g = 1.5");
    std::fs::write(dir.path().join("model.toml"), bad_value).unwrap();
    let refused = FmuModel::load(dir.path()).unwrap_err();
    assert!(matches!(refused, super::FmuError::Scene(_)), "{refused}");
}

#[test]
fn oscillator_scenes_are_refused() {
    let options = LoadOptions::default();
    let e = FmuModel::from_scene(&scene_path("seed004/iwan-oscillator.toml"), options).unwrap_err();
    assert!(e.to_string().contains("[oscillator]"), "{e}");
}

/// Scene files under `dir`, recursively.
fn scene_files(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            scene_files(&path, found);
        } else if path.extension().is_some_and(|e| e == "toml") {
            found.push(path);
        }
    }
}

/// The effects no scene of `scenes/` uses: slider-form Iwan cells, a
/// measured K_f table, Maxwell cells with multiplied states.
const OTHER_FORMS: &str = r#"
[run]
rate_hz = 1000
[backbone]
type = "polynomial"
coefficients = [0.0, 150.0]
range = [-5.0, 5.0]
[[effects]]
type = "maxwell"
form = "rate-exact-ramp"
state = "multiplied"
cells = [{ f_hz = 2.0, g = 0.2 }]
[[effects]]
type = "iwan"
form = "slider"
cells = [{ g = 0.1, x_f = 0.05 }, { g = 0.1, x_f = 0.3 }]
[[effects]]
type = "turning-points"
law = "table"
d = [0.0, 0.1, 0.5, 2.0]
k = [300.0, 120.0, 30.0, 0.0]
[profile]
type = "sine"
amplitude = 1.0
frequency_hz = 2.0
cycles = 1
"#;

#[test]
fn every_effect_state_round_trips_through_bytes() {
    let mut paths = Vec::new();
    scene_files(&scene_path(""), &mut paths);
    let dir = tempfile::tempdir().unwrap();
    let other = dir.path().join("other-forms.toml");
    std::fs::write(&other, OTHER_FORMS).unwrap();
    paths.push(other);
    paths.sort();
    let mut kinds = std::collections::BTreeSet::new();
    for path in &paths {
        let name = path.display();
        for number in [NumberType::F32, NumberType::F64] {
            let options = options(number);
            let m = match FmuModel::from_scene(path, options) {
                Ok(m) => m,
                Err(super::FmuError::Unsupported(_)) => continue,
                Err(e) => panic!("{name}: {e}"),
            };
            kinds.extend(m.scene.effects().iter().map(|e| e.name()));
            let mut s = started(m, 0.0);
            outputs(&mut s, 0, 200);
            let saved = s.get_state().unwrap();
            let bytes = s.serialize(&saved);
            assert_eq!(s.deserialize(&bytes).unwrap(), saved, "{name}");
            let next = outputs(&mut s, 200, 50);
            let restored = s.deserialize(&bytes).unwrap();
            s.set_state(&restored).unwrap();
            assert_eq!(outputs(&mut s, 200, 50), next, "{name}");
        }
    }
    // Every family's state, in every form, is among them.
    for family in [
        "maxwell rate-exact-ramp",
        "iwan clamp",
        "iwan slider",
        "xf exact-ramp",
        "turning-points sts",
        "turning-points table",
        "dahl",
        "bouc-wen",
        "berg",
        "fractional",
        "dashpot",
    ] {
        assert!(
            kinds.iter().any(|k| k.starts_with(family)),
            "{family} not in {kinds:?}"
        );
    }
}

#[test]
fn model_description_names_every_variable() {
    use super::description::model_description;
    let m = model("temperature-ramp.toml", NumberType::F64);
    let xml = model_description(&m, "ramp <&> \"test\"");
    crate::plot::well_formed(&xml).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let root = doc.root_element();
    assert_eq!(root.attribute("fmiVersion"), Some("2.0"));
    assert_eq!(root.attribute("guid"), Some(m.guid.as_str()));
    assert_eq!(root.attribute("modelName"), Some("ramp <&> \"test\""));
    let cs = root
        .children()
        .find(|n| n.has_tag_name("CoSimulation"))
        .unwrap();
    assert_eq!(cs.attribute("canGetAndSetFMUstate"), Some("true"));
    assert_eq!(cs.attribute("canSerializeFMUstate"), Some("true"));
    let experiment = root
        .children()
        .find(|n| n.has_tag_name("DefaultExperiment"))
        .unwrap();
    assert_eq!(experiment.attribute("stepSize"), Some("0.001"));
    assert_eq!(experiment.attribute("stopTime"), Some("30.0"));
    let variables: Vec<(&str, &str, &str)> = root
        .descendants()
        .filter(|n| n.has_tag_name("ScalarVariable"))
        .map(|n| {
            (
                n.attribute("name").unwrap(),
                n.attribute("valueReference").unwrap(),
                n.attribute("causality").unwrap(),
            )
        })
        .collect();
    assert_eq!(
        variables,
        [
            ("x", "0", "input"),
            ("temperature", "4", "input"),
            ("force", "1", "output"),
            ("tangent", "2", "output"),
            ("energy", "3", "output"),
            ("faults", "5", "output"),
            ("refused", "6", "output"),
        ]
    );
    // The temperature starts where the scene's history does (0 °C).
    let start = root
        .descendants()
        .find(|n| n.attribute("name") == Some("temperature"))
        .and_then(|n| n.first_element_child())
        .and_then(|n| n.attribute("start"));
    assert_eq!(start, Some("0.0"));
    // Outputs, in ModelStructure, by their 1-based index.
    let outputs: Vec<&str> = root
        .descendants()
        .find(|n| n.has_tag_name("Outputs"))
        .unwrap()
        .children()
        .filter_map(|n| n.attribute("index"))
        .collect();
    assert_eq!(outputs, ["3", "4", "5", "6", "7"]);

    // Without a temperature history there is no temperature input.
    let plain = model_description(&model("maxwell4.toml", NumberType::F64), "m");
    assert!(!plain.contains("temperature"));
}

#[test]
fn the_resource_keeps_the_model_and_drops_the_drive() {
    let m = model("rig-loop.toml", NumberType::F32);
    for table in ["[profile]", "[backbone]", "[run]"] {
        assert!(m.text.contains(table), "{table}");
    }
    assert!(!m.text.contains("[adc]"));
    assert!(!m.text.contains("[output]"));
    assert!(m.text.contains("type = \"hold\""));
    // Read back, the same model: the same GUID and the same steps.
    let again = FmuModel::parse(&m.text, "model.toml").unwrap();
    assert_eq!(again.guid, m.guid);
    assert_eq!(again.scene.dt, m.scene.dt);
}
