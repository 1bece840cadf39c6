//! What `bushing-sim identify` writes: the model three ways
//! ([`super::export`]), `report.md` (stages, refinement, parameters with
//! their identifiability, per-test errors beside the thesis's objectives,
//! held-out predictions, the pre-processing) and its figures.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::export;
use super::outcome::{Identification, TestFit};
use super::sine::SinePoint;
use crate::markdown::Table;
use crate::output::{OutputError, Staged};
use crate::plot::{Legend, Plot, Series, render_panels};

/// Percent with two decimals.
fn pct(v: f64) -> String {
    format!("{:.2}", 100.0 * v)
}

fn opt_pct(v: Option<f64>) -> String {
    v.map_or_else(|| "".into(), pct)
}

/// The lines printed by the command.
pub fn console(id: &Identification, seconds: f64) -> String {
    let mut s = String::new();
    let samples: usize = id.fitted.iter().map(|t| t.time.len()).sum();
    let _ = writeln!(
        s,
        "identify: {} tests fitted ({samples} samples), {} held out, {} left out; {} parameters; {:.1} s",
        id.fitted.len(),
        id.held_out.len(),
        id.pre.excluded.len(),
        id.refined.spreads.len(),
        seconds
    );
    let worst = |v: &[TestFit]| v.iter().map(|t| t.rms).fold(0.0, f64::max);
    let _ = writeln!(
        s,
        "refinement: cost {:.3e} -> {:.3e} ({} Jacobians, {} replays, {}); worst RMS error {} % of a test's force range",
        id.refined.cost.0,
        id.refined.cost.1,
        id.refined.jacobians,
        id.refined.replays,
        id.refined.termination,
        pct(worst(&id.fitted))
    );
    if !id.held_out.is_empty() {
        let _ = writeln!(
            s,
            "held out: worst RMS error {} % of a test's force range",
            pct(worst(&id.held_out))
        );
    }
    for e in &id.pre.excluded {
        let _ = writeln!(s, "left out: {}: {}", e.name, e.reason);
    }
    for (name, why) in &id.unreplayed {
        let _ = writeln!(s, "not replayed: {name}: {why}");
    }
    for (p, sp) in id.model().params().iter().zip(&id.refined.spreads) {
        if let Some(why) = &sp.undetermined {
            let _ = writeln!(s, "not determined: {}: {why}", p.name);
        }
    }
    s
}

/// The per-test table.
fn tests_table(tests: &[TestFit]) -> String {
    let mut t = Table::new([
        "test",
        "kind",
        "RMS error, % of force range",
        "W_d error %",
        "K_s error %",
        "K′ error %",
        "K″ error %",
        "hold end error, % of range (3.1)",
    ]);
    for f in tests {
        t.row([
            f.name.clone(),
            f.kind.name().into(),
            pct(f.rms),
            opt_pct(f.sine_error(|p| p.energy_per_cycle)),
            opt_pct(f.sine_error(|p| p.secant)),
            opt_pct(f.sine_error(|p| p.storage)),
            opt_pct(f.sine_error(|p| p.loss)),
            opt_pct(f.hold_ends),
        ]);
    }
    t.finish()
}

/// The sines at zero preload, by a rounded key.
fn sine_groups<K: Ord>(
    tests: &[TestFit],
    key: impl Fn(&SinePoint) -> K,
) -> BTreeMap<K, Vec<(SinePoint, SinePoint)>> {
    let mut g: BTreeMap<K, Vec<(SinePoint, SinePoint)>> = BTreeMap::new();
    for (m, p) in tests.iter().filter_map(|t| t.sine) {
        if m.preload_mm.abs() <= 0.05 * m.amplitude_mm.max(1e-3) {
            g.entry(key(&m)).or_default().push((m, p));
        }
    }
    g
}

/// The thesis's objectives on the fitted tests: (3.1) hold ends, (3.3)
/// and (3.7) normalised energy per cycle, (3.6) and (3.8) secant drop
/// with amplitude (zero-preload sines, each frequency).
fn objectives(tests: &[TestFit]) -> Vec<(String, String, f64)> {
    let holds: f64 = tests
        .iter()
        .filter_map(|t| t.hold_ends)
        .map(|e| e * e)
        .sum();
    let by_f = sine_groups(tests, |p| (p.frequency_hz * 1e3).round() as i64);
    let energy: f64 = by_f
        .values()
        .flatten()
        .map(|(m, p)| (p.normalised_energy - m.normalised_energy).powi(2))
        .sum();
    let mut drop = 0.0;
    for v in by_f.values() {
        let mut v = v.clone();
        v.sort_by(|a, b| a.0.amplitude_mm.total_cmp(&b.0.amplitude_mm));
        for w in v.windows(2) {
            let model = w[0].1.secant - w[1].1.secant;
            let test = w[0].0.secant - w[1].0.secant;
            let scale = w[0].0.secant.abs().max(1e-12);
            drop += ((model - test) / scale).powi(2);
        }
    }
    vec![
        (
            "3.1".into(),
            "Σ over holds of (end force error / force range)²".into(),
            holds,
        ),
        (
            "3.3, 3.7".into(),
            "Σ over zero-preload sines of (W_d/(A_F A_x) model − test)²".into(),
            energy,
        ),
        (
            "3.6, 3.8".into(),
            "Σ over frequencies and amplitude steps of (secant drop model − test)², over K_s"
                .into(),
            drop,
        ),
    ]
}

/// `report.md`.
pub fn markdown(id: &Identification, seconds: f64) -> String {
    let mut s = String::new();
    let c = &id.class;
    let _ = writeln!(s, "# Identification of the campaign \"{}\"\n", id.pre.name);
    let _ = writeln!(
        s,
        "Model class: {:?} backbone ({}), {} Maxwell cells, hysteresis {:?}{}, {} x_f cells. \
         {} tests fitted, {} held out, {} left out. Identified in {seconds:.1} s.\n",
        c.backbone,
        c.backbone_size,
        c.maxwell_cells,
        c.hysteresis,
        if matches!(c.hysteresis, super::class::HysteresisForm::Iwan) {
            format!(" ({} Jenkins cells)", c.jenkins_cells)
        } else {
            String::new()
        },
        c.xf_cells,
        id.fitted.len(),
        id.held_out.len(),
        id.pre.excluded.len()
    );
    s.push_str("The model is in `model.toml` (a scene), `model.rs` (Rust constructors) and `model.h` (C constants), all from the same printed numbers.\n\n");
    s.push_str("## Stages (seed 000 §3.4)\n\n");
    let xs = &id.stages.long_term.0;
    let _ = writeln!(
        s,
        "1. Long-term backbone g⁰F^∞ from the triangles' midlines and the hold ends: {} knots from {} to {} mm.",
        xs.len(),
        xs.first().copied().unwrap_or(0.0),
        xs.last().copied().unwrap_or(0.0)
    );
    if !id.stages.jenkins.is_empty() {
        let cells: Vec<String> = id
            .stages
            .jenkins
            .iter()
            .map(|p| format!("{:.3} mm (drop {:.3})", p.distance_mm, p.drop))
            .collect();
        let _ = writeln!(
            s,
            "2. Jenkins cells placed on the normalised instantaneous modulus (`normalised-modulus.svg`), slipping at {} from a turning point.",
            cells.join(", ")
        );
    }
    if let Some((c, k1)) = id.stages.sts {
        let _ = writeln!(
            s,
            "2. The STS law fitted to the instantaneous modulus: C = {c:.4e} N²/mm, K_1 = {k1:.4e} N/mm."
        );
    }
    if !id.stages.maxwell.is_empty() {
        let cells: Vec<String> = id
            .stages
            .maxwell
            .iter()
            .map(|(f, r)| format!("{f:.3} Hz (g/g⁰ {r:.3})"))
            .collect();
        let _ = writeln!(
            s,
            "3. Maxwell cells from {} sines' rate-dependent storage and loss: {}.",
            id.stages.rate_points.len(),
            cells.join(", ")
        );
    }
    if !id.stages.xf.is_empty() {
        let cells: Vec<String> = id
            .stages
            .xf
            .iter()
            .map(|(f, r, x_f)| format!("{f:.4} Hz (g/g⁰ {r:.3}, x_f {x_f:.4} mm)"))
            .collect();
        let _ = writeln!(
            s,
            "3. x_f cells from {} sines' first harmonics: {}.",
            id.stages.rate_sines.len(),
            cells.join(", ")
        );
    }
    let (lo, hi) = id.stages.backbone_span;
    if id.stages.rate_sines.len() < id.pre.sines.len() {
        let _ = writeln!(
            s,
            "\nStage 3 read the {} of {} sines whose preload ± amplitude stays within {lo:.4} to {hi:.4} mm, where stage 1 saw the backbone.",
            id.stages.rate_sines.len(),
            id.pre.sines.len()
        );
    }
    let r = &id.refined;
    let _ = writeln!(
        s,
        "\n## Joint refinement\n\nAll parameters together, minimising the sum over tests of (RMS force error / force range)², \
         the force from the core's `step` in f64: cost {:.4e} at the stages' model, {:.4e} refined \
         ({} Jacobians, {} replays of the campaign; {}).\n",
        r.cost.0, r.cost.1, r.jacobians, r.replays, r.termination
    );
    s.push_str("### Parameters and identifiability\n\n95 % intervals from `s² (JᵀJ)⁻¹` at the final Jacobian.\n\n");
    let mut t = Table::new(["parameter", "value", "unit", "95 % interval", "determined"]);
    for (p, sp) in id.model().params().iter().zip(&r.spreads) {
        t.row([
            p.name.clone(),
            format!("{:.6e}", p.value),
            p.unit.into(),
            if sp.relative {
                format!("±{} %", pct(sp.half_width))
            } else {
                format!("±{:.3e} {}", sp.half_width, p.unit)
            },
            sp.undetermined
                .as_ref()
                .map_or_else(|| "yes".to_string(), |w| format!("**no**: {w}")),
        ]);
    }
    s.push_str(&t.finish());
    s.push_str("\n### The thesis's objectives (fitted tests)\n\n");
    let mut t = Table::new(["eq", "objective", "value"]);
    for (eq, what, v) in objectives(&id.fitted) {
        t.row([eq, what, format!("{v:.4e}")]);
    }
    s.push_str(&t.finish());
    s.push_str("\n## Fitted tests\n\n");
    s.push_str(&tests_table(&id.fitted));
    if !id.held_out.is_empty() {
        s.push_str("\n## Held-out tests, predicted\n\n");
        s.push_str(&tests_table(&id.held_out));
    }
    if !id.unreplayed.is_empty() {
        s.push_str("\n## Tests not replayed\n\n");
        for (name, why) in &id.unreplayed {
            let _ = writeln!(s, "- {name}: {why}");
        }
    }
    s.push_str("\n## Figures\n\n- `loop-<test>.svg`: measured and identified force against displacement, each test;\n\
                - `identified-modulus-frequency.svg`: K′, K″ and the loss factor against frequency (markers measured, lines identified);\n\
                - `identified-modulus-amplitude.svg`: secant modulus and loss factor against amplitude;\n\
                - `residual.svg`: force residual against time, each test;\n\
                - `normalised-modulus.svg`: the instantaneous-modulus curve with the placed cells.\n");
    s.push_str("\n---\n\n");
    for line in id.pre.markdown().lines() {
        if line.starts_with('#') {
            let _ = writeln!(s, "#{line}");
        } else {
            let _ = writeln!(s, "{line}");
        }
    }
    s
}

/// A file-name-safe form of a test's name.
fn file_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The figures, by file name.
pub fn figures(id: &Identification) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for t in id.fitted.iter().chain(&id.held_out) {
        let mut p = Plot::new(
            format!("{} ({}): force against displacement", t.name, t.kind.name()),
            "displacement x [mm]",
            "force F [N]",
        );
        let pairs = |f: &[f64]| t.x.iter().copied().zip(f.iter().copied()).collect();
        p.series
            .push(Series::markers("measured", pairs(&t.measured)));
        p.series.push(Series::line("identified", pairs(&t.model)));
        out.push((
            format!("loop-{}.svg", file_name(&t.name)),
            render_panels(&[p]),
        ));
    }
    let mut residual = Plot::new(
        "Force residual, identified − measured",
        "time in the test [s]",
        "residual [N]",
    );
    residual.legend = Legend::Hidden;
    for t in id.fitted.iter().chain(&id.held_out) {
        residual.series.push(Series::line(
            t.name.clone(),
            t.time
                .iter()
                .zip(t.model.iter().zip(&t.measured))
                .map(|(&time, (m, f))| (time, m - f))
                .collect(),
        ));
    }
    out.push(("residual.svg".into(), render_panels(&[residual])));
    let all: Vec<TestFit> = id.fitted.iter().chain(&id.held_out).cloned().collect();
    if all.iter().any(|t| t.sine.is_some()) {
        out.push((
            "identified-modulus-frequency.svg".into(),
            render_panels(&sine_panels(
                &all,
                true,
                &[
                    ("Storage modulus K′", "K′ [N/mm]", |p| p.storage),
                    ("Loss modulus K″", "K″ [N/mm]", |p| p.loss),
                    ("Loss factor", "K″ / K′", |p| p.loss_factor),
                ],
            )),
        ));
        out.push((
            "identified-modulus-amplitude.svg".into(),
            render_panels(&sine_panels(
                &all,
                false,
                &[
                    ("Secant modulus (eq 3.5)", "K_s [N/mm]", |p| p.secant),
                    ("Loss factor", "K″ / K′", |p| p.loss_factor),
                ],
            )),
        ));
    }
    out
}

/// A quantity read from a sine's first harmonic.
type Quantity = fn(&SinePoint) -> f64;
/// A panel: title, y label and the quantity.
type Panel<'a> = (&'a str, &'a str, Quantity);

/// A sine quantity of the zero-preload sines against frequency, one
/// series per amplitude (`against_frequency`), or against amplitude, one
/// per frequency: measured markers and identified lines, a panel per
/// `(title, y label, value)`.
fn sine_panels(all: &[TestFit], against_frequency: bool, panels: &[Panel<'_>]) -> Vec<Plot> {
    let (x_of, group_of, x_label, unit): (Quantity, Quantity, _, _) = if against_frequency {
        (
            |p| p.frequency_hz,
            |p| p.amplitude_mm,
            "frequency f [Hz]",
            "mm",
        )
    } else {
        (
            |p| p.amplitude_mm,
            |p| p.frequency_hz,
            "amplitude X [mm]",
            "Hz",
        )
    };
    let groups = sine_groups(all, |p| (group_of(p) * 1e3).round() as i64);
    panels
        .iter()
        .map(|&(title, y, value)| {
            let mut plot = Plot::new(title, x_label, y);
            plot.x_log = true;
            for (key, v) in &groups {
                let mut v = v.clone();
                v.sort_by(|a, b| x_of(&a.0).total_cmp(&x_of(&b.0)));
                let label = format!("{} {unit}", *key as f64 / 1e3);
                plot.series.push(Series::markers(
                    format!("{label} measured"),
                    v.iter().map(|(m, _)| (x_of(m), value(m))).collect(),
                ));
                plot.series.push(Series::line(
                    format!("{label} identified"),
                    v.iter().map(|(m, p)| (x_of(m), value(p))).collect(),
                ));
            }
            plot
        })
        .collect()
}

/// Writes the model files, `report.md` and the figures into `out`.
pub fn write(id: &Identification, seconds: f64, out: &mut Staged) -> Result<(), OutputError> {
    let name = &id.pre.name;
    out.write("model.toml", id.model_toml.as_bytes())?;
    out.write("model.rs", export::rust(id.model(), name).as_bytes())?;
    out.write("model.h", export::c_header(id.model(), name).as_bytes())?;
    out.write("report.md", markdown(id, seconds).as_bytes())?;
    for (file, svg) in figures(id) {
        out.write(&file, svg.as_bytes())?;
    }
    for (file, svg) in id.pre.figures() {
        out.write(file, svg.as_bytes())?;
    }
    Ok(())
}
