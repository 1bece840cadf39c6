use super::*;
use crate::family::fractional::{FRACTIONAL_TAPS, Fractional};
use crate::family::iwan::{Iwan, IwanForm};
use bushing::IwanCellSpec;

const GOOD: &str = r#"
title = "t"
[run]
rate_hz = 1000
number = "f64"
[backbone]
type = "polynomial"
coefficients = [0.0, 100.0]
range = [-1.0, 1.0]
[[effects]]
type = "maxwell"
form = "rate-exact-ramp"
cells = [{ f_hz = 1.0, g = 0.2 }]
[profile]
type = "sine"
amplitude = 1.0
frequency_hz = 2.0
cycles = 3
"#;

#[test]
fn a_good_scene_parses() {
    let s = Scene::parse("good.toml", GOOD).unwrap();
    assert_eq!(s.dt, 1e-3);
    assert_eq!(s.number, NumberType::F64);
    assert_eq!(s.steps(), 1500);
    assert_eq!(s.effects().len(), 1);
}

/// The models are built once, when the scene is read, in its working
/// type: reading them back in that type borrows them, another type builds
/// a copy from the same checked parameters; `only` keeps the built models
/// of the effects it keeps, and `with_effects` builds the new ones.
#[test]
fn a_scene_builds_its_models_once_in_its_working_type() {
    let two = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"dahl\"\nk_d = 200.0\nf_f = 10.0\n[profile]",
    );
    let s = Scene::parse("s.toml", &two).unwrap();
    assert!(matches!(s.built::<f64>().unwrap(), Cow::Borrowed(_)));
    let other = s.built::<f32>().unwrap();
    assert!(matches!(other, Cow::Owned(_)));
    assert_eq!(other.effects.len(), 2);

    let dahl = s.only(&[1]);
    assert_eq!(dahl.effects(), &s.effects()[1..]);
    let built = dahl.built::<f64>().unwrap();
    assert!(matches!(built, Cow::Borrowed(_)));
    assert!(matches!(
        built.effects[..],
        [crate::family::AnyEffect::Dahl(_)]
    ));
    assert!(s.only(&[]).built::<f64>().unwrap().effects.is_empty());

    // A changed cell is built again, and a bad one is refused.
    let mut effects = s.effects().to_vec();
    let Effect::Maxwell(bank) = &mut effects[0] else {
        panic!("{:?}", effects[0]);
    };
    bank.cells[0].omega *= 2.0;
    let changed = s.with_effects(effects.clone()).unwrap();
    assert_eq!(changed.effects(), &effects[..]);
    let response = |scene: &Scene| match &scene.built::<f64>().unwrap().effects[0] {
        crate::family::AnyEffect::Maxwell(b) => b.branch_response(10.0),
        other => panic!("{other:?}"),
    };
    assert_ne!(response(&changed), response(&s));
    let Effect::Maxwell(bank) = &mut effects[0] else {
        unreachable!()
    };
    bank.cells[0].g = -1.0;
    assert!(matches!(
        s.with_effects(effects),
        Err(ParamError::NotPositive { .. })
    ));
}

#[test]
fn syntax_errors_carry_line_and_column() {
    let bad = GOOD.replace("rate_hz = 1000", "rate_hz = = 1000");
    let e = Scene::parse("bad.toml", &bad).unwrap_err();
    assert_eq!(e.at.map(|l| l.line), Some(4), "{e}");
    assert!(e.to_string().starts_with("bad.toml:4:"), "{e}");
}

#[test]
fn unknown_fields_and_kinds_are_located() {
    let bad = GOOD.replace("amplitude = 1.0", "amplitud = 1.0");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(e.message.contains("amplitud"), "{e}");
    assert!(e.at.is_some());
    let bad = GOOD.replace("type = \"maxwell\"", "type = \"maxwel\"");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(e.message.contains("maxwel"), "{e}");
    assert_eq!(e.at.map(|l| l.line), Some(11), "{e}");
}

#[test]
fn bad_parameters_name_effect_parameter_and_bound() {
    let bad = GOOD.replace("f_hz = 1.0", "f_hz = -1.0");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(
        e.message.contains("effects[0] (maxwell)")
            && e.message.contains("cells[0]: f_hz must be > 0 (got -1)"),
        "{e}"
    );
    // The cell itself, on the `cells` line.
    assert_eq!(e.at.map(|l| (l.line, l.column)), Some((13, 10)), "{e}");
    let bad = GOOD
        .replace("rate-exact-ramp", "rate-explicit")
        .replace("f_hz = 1.0", "f_hz = 200.0");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(e.message.contains("omega*dt = 1.25"), "{e}");
    let bad = GOOD.replace("g = 0.2", "g = 1.5");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(
        e.message
            .contains("effects[0] (maxwell): cells[0]: g = 1.5 must be in (0, 1]"),
        "{e}"
    );
    assert_eq!(e.at.map(|l| l.line), Some(13), "{e}");
    let bad = GOOD.replace(
        "coefficients = [0.0, 100.0]",
        "coefficients = [0.0, -100.0]",
    );
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(e.message.starts_with("backbone: backbone tangent"), "{e}");
    assert_eq!(e.at.map(|l| l.line), Some(6), "{e}");
}

#[test]
fn iwan_cells_take_a_slip_force_or_a_distance_on_k_ref() {
    let iwan = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"iwan\"\nform = \"clamp\"\ncells = [{ g = 0.1, x_f = 0.5 }, { g = 0.2, slip_force = 7.0 }]\n[profile]",
    );
    let s = Scene::parse("s.toml", &iwan).unwrap();
    match &s.effects()[1] {
        Effect::Iwan(Iwan { form, k_ref, cells }) => {
            assert_eq!(*form, IwanForm::Clamp);
            assert_eq!(*k_ref, 100.0); // backbone tangent at 0
            assert_eq!(cells[0], IwanCellSpec::new(0.1, 0.1 * 100.0 * 0.5));
            assert_eq!(cells[1], IwanCellSpec::new(0.2, 7.0));
        }
        other => panic!("{other:?}"),
    }
    let both = iwan.replace(
        "{ g = 0.1, x_f = 0.5 }",
        "{ g = 0.1, x_f = 0.5, slip_force = 1.0 }",
    );
    let e = Scene::parse("s.toml", &both).unwrap_err();
    assert!(
        e.message
            .contains("cells[0]: give exactly one of slip_force"),
        "{e}"
    );
    let bad_form = iwan.replace("form = \"clamp\"", "form = \"stick\"");
    assert!(
        Scene::parse("s.toml", &bad_form)
            .unwrap_err()
            .message
            .contains("form: unknown variant `stick`, expected `clamp` or `slider`")
    );
    let too_much = iwan.replace("g = 0.2, slip_force", "g = 0.75, slip_force");
    assert!(
        Scene::parse("s.toml", &too_much)
            .unwrap_err()
            .message
            .contains("above 1")
    );
}

#[test]
fn xf_cells_are_checked() {
    let xf = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"xf\"\nform = \"exact-ramp\"\ncells = [{ f_hz = 0.0, g = 0.1, x_f = 0.02 }]\n[profile]",
    );
    let s = Scene::parse("s.toml", &xf).unwrap();
    assert_eq!(s.effects()[1].name(), "xf exact-ramp x1");
    let bad = xf.replace("x_f = 0.02", "x_f = -0.02");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(
        e.message
            .contains("effects[1] (xf): cells[0]: x_f must be > 0"),
        "{e}"
    );
    let twice = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"maxwell\"\nform = \"rate-midpoint\"\ncells = [{ f_hz = 3.0, g = 0.1 }]\n[profile]",
    );
    let e = Scene::parse("s.toml", &twice).unwrap_err();
    assert!(
        e.message.contains("effects[1]: a second 'maxwell' effect"),
        "{e}"
    );
}

#[test]
fn friction_cells_are_checked() {
    let cells = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"dahl\"\nk_d = 200.0\nf_f = 10.0\n\
         [[effects]]\ntype = \"bouc-wen\"\nalpha = 20.0\na = 10.0\nbeta = 60.0\ngamma = 20.0\nn = 8.0\n\
         [[effects]]\ntype = \"berg\"\nf_max = 12.0\nx2 = 0.05\n[profile]",
    );
    let s = Scene::parse("s.toml", &cells).unwrap();
    let names: Vec<_> = s.effects().iter().map(Effect::name).collect();
    assert_eq!(names[1..], ["dahl alpha=1", "bouc-wen n=8", "berg"]);
    assert_eq!(
        s.effects()
            .iter()
            .skip(1)
            .map(Effect::fraction)
            .sum::<f64>(),
        0.0
    );
    let bad = cells.replace("gamma = 20.0", "gamma = 70.0");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(
        e.message
            .contains("effects[2] (bouc-wen): beta - |gamma| must be"),
        "{e}"
    );
    let bad = cells.replace("x2 = 0.05", "x2 = 0.0");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(e.message.contains("effects[3] (berg): x2 must be"), "{e}");
    let bad = cells.replace("f_f = 10.0", "f_f = 10.0\nmu = 0.3");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(e.message.contains("mu"), "{e}");
    assert!(e.at.is_some(), "{e}");
}

#[test]
fn turning_point_laws_are_checked() {
    let sts = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"turning-points\"\nlaw = \"sts\"\nc = 400.0\nk1 = 300.0\n[profile]",
    );
    let s = Scene::parse("s.toml", &sts).unwrap();
    assert_eq!(s.effects()[1].name(), "turning-points sts");
    assert_eq!(s.effects()[1].fraction(), 0.0);
    let missing = sts.replace("k1 = 300.0\n", "");
    let e = Scene::parse("s.toml", &missing).unwrap_err();
    assert!(
        e.message
            .contains("law 'sts' takes c (N²/mm) and k1 (N/mm)"),
        "{e}"
    );
    let table = sts.replace(
        "law = \"sts\"\nc = 400.0\nk1 = 300.0",
        "law = \"table\"\nd = [0.0, 0.5]\nk = [100.0, 120.0]",
    );
    let e = Scene::parse("s.toml", &table).unwrap_err();
    assert!(
        e.message
            .contains("k[1] must not exceed the entry before it"),
        "{e}"
    );
    let first = sts.replace("k1 = 300.0", "k1 = 300.0\nfirst_loading = \"later\"");
    assert!(
        Scene::parse("s.toml", &first)
            .unwrap_err()
            .message
            .contains("first_loading: unknown variant `later`, expected `masing` or `ignored`")
    );
}

/// Line and column of an error.
fn at(e: &SceneError) -> (usize, usize) {
    e.at.map_or((0, 0), |l| (l.line, l.column))
}

#[test]
fn wrong_values_in_tagged_tables_point_at_the_value_and_name_the_key() {
    // [[effects]]: a newtype variant, a struct variant's cell, an
    // optional parameter.
    let friction = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"dahl\"\nk_d = 200.0\nf_f = \"10 N\"\n[profile]",
    );
    let e = Scene::parse("s.toml", &friction).unwrap_err();
    assert_eq!(
        e.message,
        "effects[1] (dahl): f_f: invalid type: string \"10 N\", expected f64"
    );
    assert_eq!(at(&e), (17, 7), "{e}");
    let cell = GOOD.replace("g = 0.2", "g = \"0.2\"");
    let e = Scene::parse("s.toml", &cell).unwrap_err();
    assert!(
        e.message
            .starts_with("effects[0] (maxwell): cells[0].g: invalid type: string"),
        "{e}"
    );
    assert_eq!(at(&e), (13, 28), "{e}");
    let iwan = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"iwan\"\nform = \"clamp\"\ncells = [{ g = 0.1, x_f = true }]\n[profile]",
    );
    let e = Scene::parse("s.toml", &iwan).unwrap_err();
    assert!(
        e.message.starts_with(
            "effects[1] (iwan): cells[0].x_f: invalid type: boolean `true`, expected f64"
        ),
        "{e}"
    );
    assert_eq!(at(&e), (17, 27), "{e}");
    // A missing key of a cell points at the cell.
    let e = Scene::parse("s.toml", &GOOD.replace("f_hz = 1.0, ", "")).unwrap_err();
    assert_eq!(
        e.message,
        "effects[0] (maxwell): cells[0]: missing field `f_hz`"
    );
    assert_eq!(at(&e), (13, 10), "{e}");
    // [backbone] and [profile].
    let e = Scene::parse("s.toml", &GOOD.replace("100.0]", "\"100\"]")).unwrap_err();
    assert!(
        e.message
            .starts_with("backbone: coefficients[1]: invalid type: string"),
        "{e}"
    );
    assert_eq!(at(&e), (8, 22), "{e}");
    let e = Scene::parse("s.toml", &GOOD.replace("cycles = 3", "cycles = [3]")).unwrap_err();
    assert!(
        e.message
            .starts_with("profile: cycles: invalid type: sequence, expected f64"),
        "{e}"
    );
    assert_eq!(at(&e), (18, 10), "{e}");
    // Outside the tagged tables the key is named too.
    let e = Scene::parse("s.toml", &GOOD.replace("1000", "\"1 kHz\"")).unwrap_err();
    assert!(
        e.message.starts_with("run.rate_hz: invalid type: string"),
        "{e}"
    );
    assert_eq!(at(&e), (4, 11), "{e}");
}

#[test]
fn unknown_keys_in_tagged_tables_stay_at_their_table() {
    // In the second [[effects]] table (serde points at the first).
    let bad = GOOD.replace(
        "[profile]",
        "[[effects]]\ntype = \"berg\"\nf_max = 12.0\nx2 = 0.05\nmu = 0.3\n[profile]",
    );
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert_eq!(
        e.message,
        "effects[1] (berg): unknown field `mu`, expected `f_max` or `x2`"
    );
    assert_eq!(at(&e), (14, 1), "{e}");
    let bad = GOOD.replace("cycles = 3", "cycles = 3\nphase = 0.5");
    let e = Scene::parse("s.toml", &bad).unwrap_err();
    assert!(
        e.message.starts_with("profile: unknown field `phase`"),
        "{e}"
    );
    assert_eq!(at(&e), (14, 1), "{e}");
}

#[test]
fn tables_and_arrays_of_tables_written_for_each_other_are_named() {
    let e = Scene::parse("s.toml", &GOOD.replace("[[effects]]", "[effects]")).unwrap_err();
    assert!(
        e.message.starts_with(
            "effects: a single table `[effects]` where an array of tables is expected: \
             write `[[effects]]`"
        ),
        "{e}"
    );
    assert_eq!(at(&e), (10, 1), "{e}");
    let e = Scene::parse("s.toml", &GOOD.replace("[run]", "[[run]]")).unwrap_err();
    assert_eq!(
        e.message,
        "run: `[[run]]` starts an array of tables where a single table is expected: \
         write `[run]`"
    );
    assert_eq!(at(&e), (3, 1), "{e}");
    let inline = GOOD.replace(
        "cells = [{ f_hz = 1.0, g = 0.2 }]",
        "cells = { f_hz = 1.0, g = 0.2 }",
    );
    let e = Scene::parse("s.toml", &inline).unwrap_err();
    assert!(
        e.message
            .starts_with("effects[0] (maxwell): cells: a table where an array is expected"),
        "{e}"
    );
    assert_eq!(at(&e), (13, 9), "{e}");
}

#[test]
fn shape_errors_of_odd_documents_do_not_panic() {
    for text in [
        "",
        "effects = 3",
        "effects = [1, \"x\"]\n[run]\nrate_hz = 1",
        "[[effects]]\ntype = 3",
        "[[effects]]\n[[effects]]\ntype = \"dahl\"\nk_d = \"\"",
        "backbone = \"spline\"",
        "[[backbone]]\n[[backbone]]",
        "[profile]\ntype = \"stop-start\"\n[[profile.events]]\nat_s = \"0\"",
        "a.b.c.d.e.f = [[[[[[1]]]]]]",
    ] {
        let e = Scene::parse("s.toml", text).unwrap_err();
        assert!(!e.message.is_empty(), "{text:?}");
    }
}

#[test]
fn an_adc_table_parses_with_its_default_width() {
    let s = Scene::parse("s.toml", &format!("{GOOD}[adc]\nlsb_mm = 0.000244140625\n")).unwrap();
    assert_eq!(
        s.adc,
        Some(Adc {
            lsb_mm: 1.0 / 4096.0,
            bits: 16
        })
    );
    // The model reads code * lsb: 1 mm sine at 2 Hz, t = 0.125 s is
    // its crest (1 mm = 4096 codes).
    assert_eq!(s.input(0.125), 1.0);
    let x = crate::profile::displacement(&s.profile, 0.01);
    let code = bushing::excitation::adc_code(x, 1.0 / 4096.0, 16);
    assert_eq!(s.input(0.01), f64::from(code) / 4096.0);
    assert_ne!(s.input(0.01), x);
    let s = Scene::parse("s.toml", &format!("{GOOD}[adc]\nlsb_mm = 0.5\nbits = 2\n")).unwrap();
    assert_eq!(s.adc.map(|a| a.bits), Some(2));
    // Two bits saturate at codes -2..=1: 0.5 mm at most.
    assert_eq!(s.input(0.125), 0.5);
    assert!(Scene::parse("s.toml", GOOD).unwrap().adc.is_none());
}

#[test]
fn bad_adc_values_are_refused_at_the_table() {
    let adc = |body: &str| Scene::parse("s.toml", &format!("{GOOD}[adc]\n{body}\n")).unwrap_err();
    // [adc] is on line 19, after GOOD.
    for (lsb, shown) in [
        ("0.0", "0"),
        ("-0.001", "-0.001"),
        ("nan", "NaN"),
        ("inf", "inf"),
    ] {
        let e = adc(&format!("lsb_mm = {lsb}"));
        assert_eq!(
            e.message,
            format!("adc.lsb_mm must be finite and > 0 mm, got {shown}")
        );
        assert_eq!(at(&e), (19, 1), "{e}");
    }
    for bits in ["1", "25", "-3", "0"] {
        let e = adc(&format!("lsb_mm = 0.001\nbits = {bits}"));
        assert_eq!(
            e.message,
            format!("adc.bits must be a whole number from 2 to 24, got {bits}")
        );
        assert_eq!(at(&e), (19, 1), "{e}");
    }
    for bits in ["24", "2"] {
        Scene::parse(
            "s.toml",
            &format!("{GOOD}[adc]\nlsb_mm = 0.001\nbits = {bits}\n"),
        )
        .unwrap();
    }
    let e = adc("lsb_mm = 0.001\nbits = 12.5");
    assert!(
        e.message
            .starts_with("adc.bits: invalid type: floating point"),
        "{e}"
    );
    assert_eq!(at(&e), (21, 8), "{e}");
    let e = adc("lsb = 0.001");
    assert!(e.message.contains("unknown field `lsb`"), "{e}");
    assert!(e.at.is_some(), "{e}");
    let e = adc("bits = 12");
    assert!(e.message.contains("missing field `lsb_mm`"), "{e}");
    assert!(e.at.is_some(), "{e}");
    // Not with an oscillator, whose profile is a force.
    let e = Scene::parse(
        "s.toml",
        &format!("{GOOD}[oscillator]\np0 = 0.0\n[adc]\nlsb_mm = 0.001\n"),
    )
    .unwrap_err();
    assert!(
        e.message
            .starts_with("adc: an [oscillator] scene's profile is a force"),
        "{e}"
    );
    assert_eq!(at(&e), (21, 1), "{e}");
}

#[test]
fn the_number_type_can_be_overridden() {
    let s = Scene::parse_as("s.toml", GOOD, Path::new(""), Some(NumberType::F32)).unwrap();
    assert_eq!(s.number, NumberType::F32);
    let s = Scene::parse_as("s.toml", GOOD, Path::new(""), None).unwrap();
    assert_eq!(s.number, NumberType::F64);
    // The checks run in the overriding type.
    let big = GOOD.replace("[0.0, 100.0]", "[0.0, 1e39]");
    Scene::parse("s.toml", &big).unwrap();
    let e = Scene::parse_as("s.toml", &big, Path::new(""), Some(NumberType::F32)).unwrap_err();
    assert!(e.message.starts_with("backbone (f32)"), "{e}");
}

#[test]
fn location_counts_characters() {
    assert_eq!(
        Location::of("ab\ncé\nx", 6),
        Location { line: 2, column: 3 }
    );
    assert_eq!(Location::of("", 10), Location { line: 1, column: 1 });
}

/// GOOD with a `[temperature]` table of `body`.
fn with_temperature(body: &str) -> String {
    format!("{GOOD}[temperature]\n{body}\n")
}

#[test]
fn a_temperature_history_is_linear_between_its_points_and_constant_outside() {
    let s = Scene::parse(
        "t.toml",
        &with_temperature(
            "law = \"wlf\"\nc1 = 8.86\nc2 = 101.6\nt_ref = 20.0\n\
             points = [[1.0, 20.0], [3.0, 40.0], [4.0, 0.0]]",
        ),
    )
    .unwrap();
    let t = s.temperature.unwrap();
    assert_eq!(t.every, 1, "default: before every step");
    for (time, want) in [
        (-1.0, 20.0),
        (0.0, 20.0),
        (1.0, 20.0),
        (2.0, 30.0),
        (3.0, 40.0),
        (3.5, 20.0),
        (4.0, 0.0),
        (1e9, 0.0),
    ] {
        assert_eq!(t.at(time), want, "T({time})");
    }
    assert_eq!(t.shift_at(0.0), Ok(1.0));
    // Colder is slower: a_T > 1 below t_ref.
    assert!(t.shift_at(5.0).unwrap() > 1.0 && t.shift_at(2.0).unwrap() < 1.0);
    // Arrhenius in kelvin, re-tuned every 50 steps.
    let s = Scene::parse(
        "t.toml",
        &with_temperature(
            "law = \"arrhenius\"\nactivation = 12000.0\nt_ref = 293.15\n\
             points = [[0.0, 273.15]]\nevery = 50",
        ),
    )
    .unwrap();
    let t = s.temperature.unwrap();
    assert_eq!(t.every, 50);
    let want = (12000.0f64 * (1.0 / 273.15 - 1.0 / 293.15)).exp();
    assert!((t.shift_at(7.0).unwrap() / want - 1.0).abs() < 1e-12);
}

#[test]
fn temperature_mistakes_name_the_field_at_the_table() {
    let line = GOOD.lines().count() + 1;
    for (body, message) in [
        (
            "law = \"wlf\"\nc1 = 8.86\nt_ref = 20.0\npoints = [[0.0, 20.0]]",
            "temperature: law 'wlf' takes c1 and c2",
        ),
        (
            "law = \"wlf\"\nc1 = 8.86\nc2 = -1.0\nt_ref = 20.0\npoints = [[0.0, 20.0]]",
            "temperature: c2 must be > 0",
        ),
        (
            "law = \"arrhenius\"\nactivation = 1e4\nt_ref = 293.15\npoints = [[0.0, -3.0]]",
            "temperature.points[0]: temperature -3 is outside the domain of the Arrhenius law",
        ),
        (
            "law = \"wlf\"\nc1 = 8.86\nc2 = 101.6\nt_ref = 20.0\npoints = []",
            "temperature.points: at least one",
        ),
        (
            "law = \"wlf\"\nc1 = 8.86\nc2 = 101.6\nt_ref = 20.0\npoints = [[0.0, 20.0], [0.0, 30.0]]",
            "temperature.points[1]: time 0 s is not after",
        ),
        (
            "law = \"wlf\"\nc1 = 8.86\nc2 = 101.6\nt_ref = 20.0\npoints = [[0.0, nan]]",
            "temperature.points[0]: time and temperature must be finite",
        ),
        (
            "law = \"wlf\"\nc1 = 8.86\nc2 = 101.6\nt_ref = 20.0\npoints = [[0.0, 20.0]]\nevery = 0",
            "temperature.every must be a whole number >= 1",
        ),
        (
            // a_T = e^967 overflows f64.
            "law = \"arrhenius\"\nactivation = 1e4\nt_ref = 300.0\npoints = [[0.0, 10.0]]",
            "temperature.points[0]: temperature 10 gives a shift factor a_T that is not finite",
        ),
    ] {
        let e = Scene::parse("t.toml", &with_temperature(body)).unwrap_err();
        assert!(e.message.starts_with(message), "{e}");
        assert_eq!(e.at.map(|l| l.line), Some(line), "{e}");
    }
}

#[test]
fn a_fractional_effect_parses_with_its_menu_of_memory_lengths() {
    let frac = |taps: &str, alpha: &str| {
        GOOD.replace(
            "form = \"rate-exact-ramp\"\ncells = [{ f_hz = 1.0, g = 0.2 }]",
            &format!("f_c_hz = 2.0\nalpha = {alpha}\ng = 0.4\ntaps = {taps}"),
        )
        .replace("\"maxwell\"", "\"fractional\"")
    };
    for taps in FRACTIONAL_TAPS {
        let s = Scene::parse("f.toml", &frac(&taps.to_string(), "0.5")).unwrap();
        let Effect::Fractional(Fractional { spec, taps: n }) = &s.effects()[0] else {
            panic!("{:?}", s.effects()[0]);
        };
        assert_eq!((spec.alpha, spec.g, *n), (0.5, 0.4, taps));
        assert!((spec.omega_c - std::f64::consts::TAU * 2.0).abs() < 1e-12);
        assert_eq!(
            s.effects()[0].name(),
            format!("fractional alpha 0.5 x{taps}")
        );
        assert_eq!(s.effects()[0].fraction(), 0.4);
    }
    for (taps, alpha, message) in [
        ("0", "0.5", "taps = 0 is not one of 16, 64, 256, 1024, 4096"),
        ("-16", "0.5", "taps = -16 is not one of"),
        ("4097", "0.5", "taps = 4097 is not one of"),
        ("64", "0.0", "alpha must be > 0"),
        ("64", "1.0000001", "alpha = 1.0000001 is outside (0, 1]"),
    ] {
        let e = Scene::parse("f.toml", &frac(taps, alpha)).unwrap_err();
        assert!(
            e.message
                .starts_with(&format!("effects[0] (fractional): {message}")),
            "{e}"
        );
        assert_eq!(e.at.map(|l| l.line), Some(10), "{e}");
    }
    // Order 1 is a Maxwell cell, and allowed.
    assert!(Scene::parse("f.toml", &frac("16", "1.0")).is_ok());
}
