//! Running a scene: step the bushing over the profile, write the trace,
//! the modulus points and the plots, and measure the cost of the steps
//! alone.
//!
//! Plots (SVG, axes labelled with units):
//!
//! - `force-displacement.svg`: total force and long-term elastic branch
//!   against displacement;
//! - `force-time.svg`: total force, elastic branch and each effect's force
//!   against time;
//! - `dissipated-power.svg`: two panels against time, the power each step
//!   dissipates (its energy over dt, in mW = N·mm/s) and the cumulative
//!   energy (mJ), total and per effect;
//! - `modulus-amplitude.svg` (profiles with sine portions only): the
//!   instantaneous complex modulus against the imposed amplitude, in the
//!   style of seed 000 Fig 1.24, also written as `modulus.csv`.
//!
//! Long runs are decimated for the time plots by keeping the smallest and
//! the largest value of each of a few thousand buckets, so that an
//! oscillation too fast to draw shows as its envelope instead of aliasing.

use std::fs;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use bushing::Real;

use crate::model::{self, StepRow};
use crate::plot::{self, Plot, Series};
use crate::probe::{self, ModulusPoint, ModulusProbe};
use crate::profile;
use crate::scene::{NumberType, Scene};

/// What a run measured.
#[derive(Debug, Clone)]
pub struct Summary {
    /// Steps taken.
    pub steps: u64,
    /// Effects built, by name.
    pub effects: Vec<String>,
    /// Working type.
    pub number: NumberType,
    /// Wall-clock nanoseconds per step, stepping only (no I/O).
    pub ns_per_step: f64,
    /// Energy dissipated over the run, in mJ (N·mm).
    pub dissipated_mj: f64,
    /// Largest |force| in N.
    pub peak_force: f64,
    /// Steps refused for non-finite or out-of-range input.
    pub refused: u32,
    /// Instantaneous-modulus points (empty without sine portions).
    pub modulus: Vec<ModulusPoint>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "steps          {}", self.steps)?;
        let effects = if self.effects.is_empty() {
            "none (backbone only)".to_string()
        } else {
            self.effects.join(", ")
        };
        writeln!(f, "effects        {effects}")?;
        writeln!(f, "number type    {}", self.number.name())?;
        writeln!(
            f,
            "cost           {:.1} ns/step (host wall clock, stepping only)",
            self.ns_per_step
        )?;
        writeln!(f, "dissipated     {:.6e} mJ", self.dissipated_mj)?;
        writeln!(f, "peak |force|   {:.6e} N", self.peak_force)?;
        writeln!(f, "refused steps  {}", self.refused)?;
        if !self.modulus.is_empty() {
            writeln!(f, "modulus points {}", self.modulus.len())?;
        }
        for file in &self.files {
            writeln!(f, "wrote          {}", file.display())?;
        }
        Ok(())
    }
}

/// How to run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Options {
    /// Show a progress bar on stderr for long runs (more than a million
    /// steps, or more than about a second expected), at most ten updates a
    /// second, when stderr is a terminal. Off by default: the command line
    /// turns it on, library callers and tests do not.
    pub progress: bool,
}

/// Runs `scene`, writing the trace, the modulus points and the plots into
/// `out`, without a progress bar.
pub fn run(scene: &Scene, out: &Path) -> Result<Summary, String> {
    run_with(scene, out, Options::default())
}

/// Runs `scene` with `options`.
pub fn run_with(scene: &Scene, out: &Path, options: Options) -> Result<Summary, String> {
    match scene.number {
        NumberType::F32 => run_typed::<f32>(scene, out, options),
        NumberType::F64 => run_typed::<f64>(scene, out, options),
    }
}

/// Points kept for the force-displacement plot.
const PLOT_POINTS: u64 = 20_000;
/// Buckets of the time plots (two points each).
const TIME_BUCKETS: u64 = 4_000;
/// Steps per timed chunk.
const CHUNK: usize = 4096;

/// The name of an effect's trace column, without the `_N` suffix.
pub fn column_name(effect: &str) -> String {
    effect.replace([' ', ','], "_")
}

fn run_typed<T: Real + 'static>(
    scene: &Scene,
    out: &Path,
    options: Options,
) -> Result<Summary, String> {
    let mut bushing = model::compile::<T>(scene).map_err(|e| e.to_string())?;
    fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let trace_path = out.join("trace.csv");
    let file =
        fs::File::create(&trace_path).map_err(|e| format!("{}: {e}", trace_path.display()))?;
    let mut csv = BufWriter::new(file);
    let names = model::effect_names(scene);
    let mut header = String::from("time_s,x_mm,force_N,elastic_N");
    for n in &names {
        header.push_str(&format!(",{}_N", column_name(n)));
    }
    header.push_str(",dissipated_mJ");
    // In an oscillator scene the profile is the applied force.
    let oscillator = scene.oscillator.is_some();
    if oscillator {
        header.push_str(",applied_N");
    }
    writeln!(csv, "{header}").map_err(|e| e.to_string())?;

    let steps = scene.steps();
    let stride = steps.div_ceil(PLOT_POINTS).max(1);
    let mut loop_points = Vec::new();
    let mut elastic_points = Vec::new();
    let bucket = steps.div_ceil(TIME_BUCKETS).max(1);
    let mut force_t = Envelopes::new(names.len() + 2, bucket);
    let mut power_t = Envelopes::new(names.len() + 1, bucket);
    let mut energy_t = Envelopes::new(names.len() + 1, bucket);
    let mut effect_energy = vec![0.0f64; names.len()];
    let x0 = match scene.oscillator {
        Some(o) => o.p0,
        None => scene.input(0.0),
    };
    let (_, k0) = bushing::Backbone::eval(bushing.backbone(), T::from_f64(x0));
    let mut probe = ModulusProbe::new(scene.dt, k0.to_f64());
    let mut inputs = Vec::with_capacity(CHUNK);
    let mut outputs: Vec<StepRow<T>> = Vec::with_capacity(CHUNK);
    let mut parts = Vec::with_capacity(CHUNK * names.len());
    let mut busy = 0.0f64;
    let mut energy = 0.0f64;
    let mut peak = 0.0f64;
    let mut progress = Progress::new(options.progress && std::io::stderr().is_terminal(), steps);
    let mut n = 0u64;
    while n < steps {
        let len = (steps - n).min(CHUNK as u64) as usize;
        inputs.clear();
        for k in 0..len as u64 {
            let t = (n + 1 + k) as f64 * scene.dt;
            // The profile as the model reads it (through the scene's ADC).
            inputs.push(T::from_f64(scene.input(t)));
        }
        outputs.clear();
        parts.clear();
        let start = Instant::now();
        bushing.step_into(&inputs, &mut outputs, &mut parts);
        busy += start.elapsed().as_secs_f64();
        let mut line = String::new();
        for (k, (input, o)) in inputs.iter().zip(&outputs).enumerate() {
            let i = n + 1 + k as u64;
            let t = i as f64 * scene.dt;
            let step_energy = o.dissipated.to_f64();
            energy += step_energy;
            let f = o.force.to_f64();
            let xf = o.x.to_f64();
            let elastic = o.elastic.to_f64();
            peak = peak.max(f.abs());
            let write_row = i.is_multiple_of(scene.trace_every) || i == steps;
            line.clear();
            if write_row {
                line.push_str(&format!("{t:.9},{xf:e},{f:e},{elastic:e}"));
            }
            force_t.push(0, t, f);
            force_t.push(1, t, elastic);
            power_t.push(0, t, step_energy / scene.dt);
            energy_t.push(0, t, energy);
            // Steps without a trace row still feed the plots and energies.
            if o.refused {
                if write_row {
                    names.iter().for_each(|_| line.push_str(",nan"));
                }
            } else {
                let count = names.len();
                let this_step = parts.get(k * count..(k + 1) * count).unwrap_or_default();
                for (j, e) in this_step.iter().enumerate() {
                    let (ef, ed) = (e.force.to_f64(), e.dissipated.to_f64());
                    if write_row {
                        line.push_str(&format!(",{ef:e}"));
                    }
                    force_t.push(j + 2, t, ef);
                    power_t.push(j + 1, t, ed / scene.dt);
                    if let Some(total) = effect_energy.get_mut(j) {
                        *total += ed;
                        energy_t.push(j + 1, t, *total);
                    }
                }
            }
            if write_row {
                line.push_str(&format!(",{energy:e}"));
                if oscillator {
                    line.push_str(&format!(",{:e}", input.to_f64()));
                }
                writeln!(csv, "{line}").map_err(|e| e.to_string())?;
            }
            if i.is_multiple_of(stride) {
                loop_points.push((xf, f));
                elastic_points.push((xf, elastic));
            }
            // An oscillator's profile is a force: no imposed displacement.
            let sine = profile::frequency_at(&scene.profile, t)
                .filter(|_| !oscillator)
                .map(|fr| (fr, profile::amplitude_at(&scene.profile, t)));
            probe.push(sine, t, xf, f);
        }
        n += len as u64;
        progress.update(n);
    }
    progress.finish();
    csv.flush().map_err(|e| e.to_string())?;

    let effects = if names.is_empty() {
        "backbone only".to_string()
    } else {
        names.join(" + ")
    };
    let title = |what: &str| {
        if scene.title.is_empty() {
            format!("{what} ({effects})")
        } else {
            format!("{what}: {}", scene.title)
        }
    };
    let mut files = vec![trace_path];
    let write = |files: &mut Vec<PathBuf>, name: &str, text: String| {
        let path = out.join(name);
        fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        files.push(path);
        Ok::<(), String>(())
    };

    let loop_plot = Plot {
        title: if scene.title.is_empty() {
            format!("Force-displacement ({effects})")
        } else {
            scene.title.clone()
        },
        x_label: "displacement x [mm]".into(),
        y_label: "force F [N]".into(),
        x_log: false,
        series: vec![
            Series::line(
                format!("total force, {effects}, {}", scene.number.name()),
                loop_points,
            ),
            Series::line("long-term elastic branch g0 F_inf(x)", elastic_points),
        ],
        ..Plot::default()
    };
    write(&mut files, "force-displacement.svg", loop_plot.render())?;

    let mut force_series = force_t.finish().into_iter();
    let mut series = vec![
        Series::line("total force", force_series.next().unwrap_or_default()),
        Series::line(
            "long-term elastic branch g0 F_inf(x)",
            force_series.next().unwrap_or_default(),
        ),
    ];
    for (name, points) in names.iter().zip(force_series) {
        series.push(Series::line(name.clone(), points));
    }
    let force_plot = Plot {
        title: title("Force against time"),
        x_label: "time t [s]".into(),
        y_label: "force F [N]".into(),
        x_log: false,
        series,
        ..Plot::default()
    };
    write(&mut files, "force-time.svg", force_plot.render())?;

    let per_effect = |all: Vec<Vec<(f64, f64)>>, total: &str| {
        let mut it = all.into_iter();
        let mut series = vec![Series::line(total, it.next().unwrap_or_default())];
        // With one effect its curve is the total's.
        if names.len() > 1 {
            for (name, points) in names.iter().zip(it) {
                series.push(Series::line(name.clone(), points));
            }
        }
        series
    };
    let power = Plot {
        title: title("Dissipated power"),
        x_label: "time t [s]".into(),
        y_label: "dissipated power P [mW = N·mm/s]".into(),
        x_log: false,
        series: per_effect(power_t.finish(), "total, energy of each step / dt"),
        ..Plot::default()
    };
    let cumulative = Plot {
        title: title("Cumulative dissipated energy"),
        x_label: "time t [s]".into(),
        y_label: "dissipated energy E [mJ = N·mm]".into(),
        x_log: false,
        series: per_effect(energy_t.finish(), "total"),
        ..Plot::default()
    };
    write(
        &mut files,
        "dissipated-power.svg",
        plot::render_panels(&[power, cumulative]),
    )?;

    let modulus = probe.finish();
    if probe.saw_sine {
        write(&mut files, "modulus.csv", probe::modulus_csv(&modulus))?;
        write(
            &mut files,
            "modulus-amplitude.svg",
            plot::render_panels(&probe::modulus_plots(
                &modulus,
                &title("Instantaneous complex modulus"),
            )),
        )?;
    }

    Ok(Summary {
        steps,
        effects: names,
        number: scene.number,
        ns_per_step: busy * 1e9 / steps.max(1) as f64,
        dissipated_mj: energy,
        peak_force: peak,
        refused: bushing.refused(),
        modulus,
        files,
    })
}

/// Time-plot decimation: the smallest and the largest value of each bucket
/// of `bucket` samples, in time order.
struct Envelopes {
    bucket: u64,
    series: Vec<Envelope>,
}

#[derive(Default)]
struct Envelope {
    count: u64,
    lo: (f64, f64),
    hi: (f64, f64),
    points: Vec<(f64, f64)>,
}

impl Envelope {
    fn flush(&mut self) {
        if self.count == 0 {
            return;
        }
        let (a, b) = if self.lo.0 <= self.hi.0 {
            (self.lo, self.hi)
        } else {
            (self.hi, self.lo)
        };
        self.points.push(a);
        if b != a {
            self.points.push(b);
        }
        self.count = 0;
    }
}

impl Envelopes {
    fn new(n: usize, bucket: u64) -> Self {
        Self {
            bucket,
            series: (0..n).map(|_| Envelope::default()).collect(),
        }
    }

    fn push(&mut self, series: usize, t: f64, v: f64) {
        let Some(e) = self.series.get_mut(series) else {
            return;
        };
        if e.count == 0 {
            (e.lo, e.hi) = ((t, v), (t, v));
        } else if v < e.lo.1 {
            e.lo = (t, v);
        } else if v > e.hi.1 {
            e.hi = (t, v);
        }
        e.count += 1;
        if e.count >= self.bucket {
            e.flush();
        }
    }

    fn finish(mut self) -> Vec<Vec<(f64, f64)>> {
        self.series
            .iter_mut()
            .map(|e| {
                e.flush();
                std::mem::take(&mut e.points)
            })
            .collect()
    }
}

/// A progress bar on stderr.
struct Progress {
    enabled: bool,
    shown: bool,
    total: u64,
    start: Instant,
    last: Instant,
}

/// Runs above this many steps show the bar from the start.
const LONG_RUN: u64 = 1_000_000;
const REFRESH: Duration = Duration::from_millis(100);

impl Progress {
    fn new(enabled: bool, total: u64) -> Self {
        let now = Instant::now();
        Self {
            enabled,
            shown: false,
            total,
            start: now,
            last: now,
        }
    }

    fn update(&mut self, done: u64) {
        if !self.enabled || done >= self.total {
            return;
        }
        let now = Instant::now();
        if now.duration_since(self.last) < REFRESH {
            return;
        }
        let elapsed = now.duration_since(self.start).as_secs_f64();
        let expected = elapsed * self.total as f64 / done.max(1) as f64;
        if !self.shown && self.total <= LONG_RUN && expected < 1.0 {
            return;
        }
        self.shown = true;
        self.last = now;
        let fraction = done as f64 / self.total.max(1) as f64;
        let filled = (fraction * 30.0) as usize;
        let bar: String = (0..30)
            .map(|i| if i < filled { '#' } else { '-' })
            .collect();
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r[{bar}] {:5.1} % {done}/{} steps, {:.0} s left   ",
            100.0 * fraction,
            self.total,
            (expected - elapsed).max(0.0)
        );
        let _ = err.flush();
    }

    fn finish(&mut self) {
        if self.shown {
            let mut err = std::io::stderr().lock();
            let _ = write!(err, "\r{:79}\r", "");
            let _ = err.flush();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelopes_keep_extremes_in_time_order() {
        let mut e = Envelopes::new(1, 4);
        for (i, v) in [0.0, 3.0, -2.0, 1.0, 5.0, 5.0].into_iter().enumerate() {
            e.push(0, i as f64, v);
        }
        let [points] = e.finish().try_into().unwrap();
        assert_eq!(points, vec![(1.0, 3.0), (2.0, -2.0), (4.0, 5.0)]);
        let mut one = Envelopes::new(1, 1);
        one.push(0, 0.0, 1.0);
        one.push(0, 1.0, 2.0);
        assert_eq!(one.finish()[0], vec![(0.0, 1.0), (1.0, 2.0)]);
    }

    /// With an `[adc]`, the trace's x_mm is the code the ADC reads times
    /// its step, exactly, in both number types (a power-of-two step and
    /// 12-bit codes are exact in f32).
    #[test]
    fn an_adc_scene_traces_the_quantized_displacement() {
        let text = |number: &str| {
            format!(
                "[run]\nrate_hz = 1000\nnumber = \"{number}\"\n\
                 [backbone]\ntype = \"polynomial\"\ncoefficients = [0.0, 100.0]\nrange = [-2.0, 2.0]\n\
                 [[effects]]\ntype = \"maxwell\"\nform = \"rate-exact-ramp\"\ncells = [{{ f_hz = 3.0, g = 0.2 }}]\n\
                 [profile]\ntype = \"sweep\"\namplitude = 1.3\nf_start_hz = 2.0\nf_end_hz = 20.0\nduration_s = 0.5\npreload = 0.2\n\
                 [adc]\nlsb_mm = 0.0009765625\nbits = 12\n"
            )
        };
        let dir = std::env::temp_dir().join(format!("bushing-run-adc-{}", std::process::id()));
        for number in ["f32", "f64"] {
            let scene = Scene::parse("adc.toml", &text(number)).unwrap();
            let adc = scene.adc.unwrap();
            let summary = run(&scene, &dir).unwrap();
            assert_eq!(summary.steps, 500);
            let trace = fs::read_to_string(dir.join("trace.csv")).unwrap();
            let mut rows = 0;
            for (i, line) in trace.lines().skip(1).enumerate() {
                let t = (i + 1) as f64 * scene.dt;
                let x_mm: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
                let code = adc.code(profile::displacement(&scene.profile, t));
                assert_eq!(x_mm, f64::from(code) * adc.lsb_mm, "{number} row {i}");
                rows += 1;
            }
            assert_eq!(rows, 500);
        }
        fs::remove_dir_all(dir).ok();
    }

    /// A linear spring with a viscous term and an offset on a drifting
    /// preload: K' = k, K'' = c ω exactly, whatever the drift.
    #[test]
    fn probe_removes_offsets_and_drifts() {
        let (dt, f, k, c) = (1e-3, 7.0, 120.0, 0.8);
        let w = std::f64::consts::TAU * f;
        let mut probe = ModulusProbe::new(dt, k);
        for i in 1..=5000 {
            let t = i as f64 * dt;
            let drift = 3.0 + 0.5 * t;
            let x = drift + 0.2 * (w * t).sin();
            let force = 40.0 + k * x + c * 0.2 * w * (w * t).cos() + 9.0 * t;
            probe.push(Some((f, None)), t, x, force);
        }
        let points = probe.finish();
        // 35 periods, 2 skipped and one to fill the window.
        assert!(points.len() >= 30, "{}", points.len());
        for p in &points {
            assert!((p.amplitude_mm / 0.2 - 1.0).abs() < 1e-3, "{p:?}");
            assert!((p.storage / k - 1.0).abs() < 1e-3, "{p:?}");
            assert!((p.loss / (c * w) - 1.0).abs() < 1e-2, "{p:?}");
        }
        // The imposed amplitude, when given, is the point's.
        let mut probe = ModulusProbe::new(dt, k);
        for i in 1..=1000 {
            let t = i as f64 * dt;
            let x = 0.2 * (w * t).sin();
            probe.push(Some((f, Some(0.25))), t, x, k * x);
        }
        let points = probe.finish();
        assert!(!points.is_empty() && points.iter().all(|p| p.amplitude_mm == 0.25));
        // No sine, no point; a new frequency restarts.
        let mut probe = ModulusProbe::new(dt, k);
        probe.push(None, 0.0, 0.0, 0.0);
        assert!(!probe.saw_sine && probe.finish().is_empty());
    }
}
