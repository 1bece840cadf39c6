//! `validate`: a scene against its closed-form references, where one
//! exists.
//!
//! The scene is stepped as `run` steps it, in its own number type, and each
//! effect's force and dissipated energy are taken over the last whole
//! cycles of a periodic profile (a sine or a triangle, symmetric about the
//! preload). The first cycle is never used: it holds the first loading.
//!
//! | effect | check | reference |
//! |---|---|---|
//! | Maxwell (sine, linear backbone K^∞) | first-harmonic K', K'' of `g^0 K^∞ x` + the bank's force, least squares over the last whole periods | `K^∞ (g^0 + Σ H_i(e^{iωΔt}))`, the discrete bank's exact steady state, and eq 1.8 of seed 000, `K^∞ (g^0 + Σ g_i iω / (iω + ω_i))` |
//! | Maxwell | energy per steady cycle | `π X² K''` of the bank |
//! | Iwan (clamp on a linear backbone, or slider) | energy per steady cycle | Masing loop of each Jenkins cell: `Σ 4 F_f,i (A - x_f,i)` over the cells that slip, `x_f,i = F_f,i / (g_i k)` with k the backbone slope (clamp) or k_ref (slider) |
//! | Iwan | half the peak-to-peak force of the steady loop | `Σ min(F_f,i, g_i k A)` |
//! | turning points | half peak-to-peak force, energy per cycle | Masing loop of the law: `H(2A)/2` and `2 ∫_0^{2A} H - 2A H(2A)` |
//! | Iwan, turning points | energy of an asymmetric inner loop: from rest at the profile's start x0 to x0 ± A, then twice between x0 + 0.2A and x0 + 0.6A at 10 steps per branch | Masing loop of span 0.4A (as above) |
//! | x_f (linear backbone; triangle, or sine with ω_i = 0) | half peak-to-peak force | each cell is Dahl's law of exponent 1 in x with `λ = ω/v + 1/x_f`, saturation `g K^∞ / λ` (`g K^∞ x_f` at ω = 0): tip `g K^∞ tanh(λ A) / λ` |
//! | Dahl | half peak-to-peak force | saturation `f_f`; loop tip `f_f tanh(k_d A / f_f)` (α = 1), else the root of the closed-form travel |
//! | Bouc-Wen | half peak-to-peak force | ultimate force `α w_u`; loop tip from the travel `∫ dw / (A - (γ + β sgn w) \|w\|^n) = 2A` |
//! | Berg | half peak-to-peak force | `f_max`; loop tip, root of `(x_2 / f_max) r² + (x_2 + A) r - A f_max = 0` |
//!
//! A is the amplitude of the profile and v the speed of a triangle. The
//! friction laws never reach their saturation force in a finite travel
//! (Dahl with α < 1 does), so the reference is the tip of the steady loop
//! of the continuous law at the profile's amplitude; the saturation force
//! is printed with it.

use std::f64::consts::TAU;
use std::fmt;

use bushing::Real;

use crate::harmonic::Harmonic;
use crate::model;
use crate::profile::{Sine, Triangle};
pub use crate::reference::Outcome;
use crate::reference::{Drive as Kind, INNER_SPAN, INNER_STEPS, Measured};
use crate::run::{self, RunError, Sink, Step};
use crate::scene::{BackboneSpec, NumberType, ProfileSpec, Scene};

/// One line of the report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Check {
    /// Effect name, as in the trace.
    pub effect: String,
    /// What is compared, with the reference's equation.
    pub what: String,
    /// Unit of the values.
    pub unit: &'static str,
    /// Reference and measured value, or why there is no reference.
    pub outcome: Outcome,
}

impl Check {
    /// `measured / reference - 1`, if compared.
    pub fn relative_error(&self) -> Option<f64> {
        match self.outcome {
            Outcome::Compared {
                reference,
                measured,
            } => Some(if reference == 0.0 {
                measured
            } else {
                measured / reference - 1.0
            }),
            Outcome::NoReference(_) => None,
        }
    }
}

impl fmt::Display for Check {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.outcome {
            Outcome::Compared {
                reference,
                measured,
            } => write!(
                f,
                "{}: {}: reference {reference:.6e} {u}, measured {measured:.6e} {u}, relative error {:+.2e}",
                self.effect,
                self.what,
                self.relative_error().unwrap_or(f64::NAN),
                u = self.unit
            ),
            Outcome::NoReference(why) => {
                write!(f, "{}: no closed-form reference ({why})", self.effect)
            }
        }
    }
}

/// What `validate` found.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// The profile and the window used.
    pub context: String,
    /// One entry per check.
    pub checks: Vec<Check>,
    /// Steps the model refused: a run with any is no comparison.
    pub refused: u32,
}

/// The relative error `validate` accepts by default: 0.1 %.
pub const TOLERANCE: f64 = 1e-3;

impl Report {
    /// The checks whose relative error is beyond `tolerance` in magnitude,
    /// or not a finite number (a NaN or an infinity never passes).
    pub fn beyond(&self, tolerance: f64) -> Vec<&Check> {
        self.checks
            .iter()
            .filter(|c| {
                c.relative_error()
                    .is_some_and(|e| !(e.is_finite() && e.abs() <= tolerance))
            })
            .collect()
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", self.context)?;
        for c in &self.checks {
            writeln!(f, "{c}")?;
        }
        Ok(())
    }
}

/// Compares `scene` with its closed-form references. Errors only when the
/// scene's model cannot be built or stepped ([`RunError`]); a missing reference is a line of the
/// report.
pub fn validate(scene: &Scene) -> Result<Report, RunError> {
    match scene.number {
        NumberType::F32 => validate_typed::<f32>(scene),
        NumberType::F64 => validate_typed::<f64>(scene),
    }
}

/// A periodic profile symmetric about its preload.
#[derive(Debug, Clone, Copy)]
struct Periodic {
    /// Amplitude A, mm.
    amplitude: f64,
    /// Period, s.
    period: f64,
    /// Sine frequency in Hz, or the speed of a triangle in mm/s.
    kind: Kind,
}

fn periodic(p: &ProfileSpec) -> Option<Periodic> {
    if let ProfileSpec::Sine(Sine {
        amplitude,
        frequency_hz,
        ..
    }) = p
    {
        return Some(Periodic {
            amplitude: *amplitude,
            period: 1.0 / *frequency_hz,
            kind: Kind::Sine(*frequency_hz),
        });
    }
    if let ProfileSpec::Triangle(Triangle {
        amplitude, speed, ..
    }) = p
    {
        return Some(Periodic {
            amplitude: *amplitude,
            period: 4.0 * *amplitude / *speed,
            kind: Kind::Triangle(*speed),
        });
    }
    None
}

/// Slope of a backbone that is linear everywhere.
fn linear_stiffness(b: &BackboneSpec) -> Option<f64> {
    if let BackboneSpec::Polynomial { coefficients, .. } = b
        && coefficients.iter().skip(2).all(|c| *c == 0.0)
    {
        return coefficients.get(1).copied();
    }
    None
}

/// Most whole cycles in the least-squares window.
const WINDOW_CYCLES: u64 = 5;

/// What the window gathered, streamed (no sample is stored).
struct Window {
    /// First harmonics of x (signal 0) and of `elastic + force` of each
    /// effect (signal 1 + j), over the whole window.
    harmonic: Harmonic,
    /// Per effect over the last cycle: energy, smallest and largest force.
    energy: Vec<f64>,
    low: Vec<f64>,
    high: Vec<f64>,
}

impl Window {
    /// Half the peak-to-peak force of effect `j` over the last cycle.
    fn swing(&self, j: usize) -> f64 {
        match (self.low.get(j), self.high.get(j)) {
            (Some(lo), Some(hi)) => 0.5 * (hi - lo),
            _ => f64::NAN,
        }
    }
}

/// The steady-cycle window as a sink of the stepping pipeline: steps after
/// `start` feed the first harmonics, steps after `last` (the last cycle)
/// the energies and force extremes.
struct WindowSink<'w> {
    window: &'w mut Window,
    forces: Vec<f64>,
    start: u64,
    last: u64,
}

impl<T: Real> Sink<T> for WindowSink<'_> {
    fn step(&mut self, s: &Step<'_, T>) -> Result<(), RunError> {
        if s.index <= self.start {
            return Ok(());
        }
        let w = &mut *self.window;
        let elastic = s.row.elastic.to_f64();
        for (j, f) in self.forces.iter_mut().enumerate() {
            let e = s.parts.get(j);
            *f = e.map_or(f64::NAN, |e| e.force.to_f64());
            if s.index > self.last {
                let d = e.map_or(f64::NAN, |e| e.dissipated.to_f64());
                if let (Some(en), Some(lo), Some(hi)) =
                    (w.energy.get_mut(j), w.low.get_mut(j), w.high.get_mut(j))
                {
                    *en += d;
                    *lo = lo.min(*f);
                    *hi = hi.max(*f);
                }
            }
        }
        w.harmonic.push(
            s.time,
            std::iter::once(s.demand).chain(self.forces.iter().map(|f| elastic + f)),
        );
        Ok(())
    }
}

fn validate_typed<T: Real + 'static>(scene: &Scene) -> Result<Report, RunError> {
    let mut bushing = model::compile::<T>(scene)?;
    let names = model::effect_names(scene);
    let none = |why: &str| Report {
        refused: 0,
        context: format!("validate: {why}"),
        checks: names
            .iter()
            .map(|n| Check {
                effect: n.clone(),
                what: String::new(),
                unit: "",
                outcome: Outcome::NoReference(why.to_string()),
            })
            .collect(),
    };
    if scene.oscillator.is_some() {
        return Ok(none(
            "an oscillator scene: the displacement is not imposed (the free decay of the Iwan oscillator is checked by the tracker suites)",
        ));
    }
    let Some(p) = periodic(&scene.profile) else {
        return Ok(none("the profile is not a periodic sine or triangle"));
    };
    let steps = scene.steps();
    let spp = p.period / scene.dt;
    let whole = (steps as f64 / spp + 1e-9).floor() as u64;
    if whole < 2 || spp < 4.0 {
        return Ok(none(
            "fewer than 2 whole cycles or 4 steps per cycle: no steady cycle",
        ));
    }
    let cycles = WINDOW_CYCLES.min(whole - 1);
    let end = (whole as f64 * spp).round() as u64;
    let start = ((whole - cycles) as f64 * spp).round() as u64;
    let last = ((whole - 1) as f64 * spp).round() as u64;
    let n = names.len();
    let omega = match p.kind {
        Kind::Sine(f) => TAU * f,
        Kind::Triangle(_) => TAU / p.period,
    };
    let mut w = Window {
        harmonic: Harmonic::new(omega, n + 1),
        energy: vec![0.0; n],
        low: vec![f64::INFINITY; n],
        high: vec![f64::NEG_INFINITY; n],
    };
    let mut sink = WindowSink {
        window: &mut w,
        forces: vec![f64::NAN; n],
        start,
        last,
    };
    run::drive_steps(scene, bushing.as_mut(), end, &mut [&mut sink])?;
    let t0 = start as f64 * scene.dt;
    let kind = match p.kind {
        Kind::Sine(f) => format!("sine of {:e} mm at {f:e} Hz", p.amplitude),
        Kind::Triangle(v) => format!("triangle of {:e} mm at {v:e} mm/s", p.amplitude),
    };
    let context = format!(
        "validate: {kind}, {} Hz, {}; steady window: cycles {} to {whole} (t = {t0:.6} s to {:.6} s); {} refused steps",
        1.0 / scene.dt,
        scene.number.name(),
        whole - cycles + 1,
        end as f64 * scene.dt,
        bushing.refused()
    );
    let k_lin = linear_stiffness(&scene.backbone);
    let inner = inner_loop_energies::<T>(scene, p.amplitude)?;
    let built = scene.built::<T>()?;
    let xp = w.harmonic.fit(0);
    let x2 = xp.map_or(f64::NAN, |(a, b)| a * a + b * b);
    let mut checks = Vec::new();
    for (j, ((effect, model), name)) in scene
        .effects()
        .iter()
        .zip(&built.effects)
        .zip(&names)
        .enumerate()
    {
        let modulus = crate::harmonic::ratio(&w.harmonic, 0, j + 1);
        let measured = Measured {
            amplitude: p.amplitude,
            drive: p.kind,
            k_lin,
            g0: bushing.g0(),
            dt: scene.dt,
            t0,
            retuned: scene.temperature.is_some(),
            swing: w.swing(j),
            per_cycle: w.energy.get(j).copied().unwrap_or(f64::NAN),
            modulus,
            x_amplitude: x2.sqrt(),
            inner: inner.get(j).copied().unwrap_or(f64::NAN),
        };
        for (what, unit, outcome) in effect.references(model, &measured) {
            checks.push(Check {
                effect: name.clone(),
                what,
                unit,
                outcome,
            });
        }
    }
    Ok(Report {
        context,
        checks,
        refused: bushing.refused(),
    })
}

/// Each effect's energy over an asymmetric inner loop: from rest at the
/// profile's start x0 to x0 + A and x0 - A (50 steps per half amplitude),
/// then twice between x0 + 0.2 A and x0 + 0.6 A at [`INNER_STEPS`] per
/// branch, the second loop measured (NaN for an effect if a step was
/// refused). The symmetric loops of the profile return onto the first
/// loading curve; this loop closes on a turning point inside an outer loop,
/// where a law has to split the closing step between the two branches.
fn inner_loop_energies<T: Real + 'static>(scene: &Scene, a: f64) -> Result<Vec<f64>, RunError> {
    let mut bushing = model::compile::<T>(scene)?;
    let x0 = scene.input(0.0);
    let (lo, hi) = (x0 + 0.2 * a, x0 + (0.2 + INNER_SPAN) * a);
    let mut path = Vec::new();
    let mut x = x0;
    for (target, steps) in [(x0 + a, 50), (x0 - a, 100), (hi, 80)] {
        path.extend((1..=steps).map(|k| (x + (target - x) * k as f64 / steps as f64, false)));
        x = target;
    }
    let n = INNER_STEPS;
    for measured in [false, true] {
        path.extend((1..=2 * n).map(|k| {
            let u = if k <= n { k } else { 2 * n - k } as f64 / n as f64;
            (hi - (hi - lo) * u, measured)
        }));
    }
    let mut energy = vec![0.0; model::effect_names(scene).len()];
    let (mut rows, mut outputs) = (Vec::with_capacity(1), Vec::with_capacity(energy.len()));
    for (x, measured) in path {
        rows.clear();
        outputs.clear();
        bushing.step_into(&[T::from_f64(x)], &mut rows, &mut outputs);
        let refused = rows.first().is_none_or(|r| r.refused);
        for (j, e) in energy.iter_mut().enumerate() {
            match outputs.get(j) {
                _ if refused => *e = f64::NAN,
                Some(o) if measured => *e += o.dissipated.to_f64(),
                _ => {}
            }
        }
    }
    Ok(energy)
}
