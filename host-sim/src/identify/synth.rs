//! Campaigns generated from a known model: the tests of a grid (by
//! default the part grids of seed 000 Appendix B, Table B.2) run on a
//! scene's backbone and effects in f64, sampled as the seed's machine
//! samples them (§3.2.3: 20 Hz on multi-step ramps and 1 Hz during the
//! holds, 3 Hz at 10 mm/min and 0.3 Hz at 1 mm/min on triangles, 50
//! samples per period on sines), with Gaussian noise on the force. What
//! the identification is tested on, and the worked example.
//!
//! Each test is stepped at its own model step (a whole fraction of its
//! sampling step), from rest at 0 mm. A preloaded test first has the
//! replay's lead-in ([`super::replay::preload_steps`]: a 20 s ramp to the
//! preload, then the campaign's preload hold). A sine is recorded after
//! unrecorded passes of its cycles (at least 2 s), in which the model
//! settles into its steady cycle as the machine's sweeps let it
//! (Fig. 3.3); the other tests
//! are recorded from their start. The replay of a record makes the same
//! lead-in, so the model that generated a campaign replays it to within
//! its sub-steps.

use std::f64::consts::TAU;

use bushing::ParamError;
use bushing_kernels::Noise;

use super::campaign::{Kind, MAX_PRELOAD_HOLD_S};
use super::replay;
use crate::csv_text::CsvText;
use crate::model::{self, SceneBushing};
use crate::output::{OutputError, Staged};
use crate::scene::Scene;

/// What one generated test imposes.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// 20 s ramps to each level, each held `hold_s`.
    MultiStep {
        /// Levels in mm, in order.
        levels: Vec<f64>,
        /// Hold at each level, s.
        hold_s: f64,
    },
    /// Constant-speed triangles about a preload.
    Triangle {
        /// Speed, mm/min.
        speed_mm_per_min: f64,
        /// Amplitude, mm.
        amplitude_mm: f64,
        /// Preload, mm.
        preload_mm: f64,
        /// Whole cycles.
        cycles: u32,
        /// Samples per mm of travel (the seed's machine: 18, see
        /// [`PART_SAMPLES_PER_MM`]).
        samples_per_mm: f64,
    },
    /// Band-limited random displacement (test kind `other`): 32 sines at
    /// log-spaced frequencies over the band with seeded random phases,
    /// faded in over its first 2 s from rest at 0.
    Random {
        /// Lowest frequency, Hz.
        f_lo_hz: f64,
        /// Highest frequency, Hz.
        f_hi_hz: f64,
        /// RMS displacement once faded in, mm.
        rms_mm: f64,
        /// Duration, s.
        duration_s: f64,
        /// Seed of the phases.
        seed: u64,
    },
    /// A sine about a preload.
    Sine {
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Amplitude, mm.
        amplitude_mm: f64,
        /// Preload, mm.
        preload_mm: f64,
        /// Whole cycles.
        cycles: u32,
    },
}

/// Ramp time of a multi-step level, s (§3.2.3).
pub const RAMP_S: f64 = 20.0;
/// Model steps per sample.
const SUBSTEPS: usize = 4;
/// Samples per mm of a triangle on the seed's machine: 3 Hz at 10 mm/min,
/// 0.3 Hz at 1 mm/min (§3.2.3).
pub const PART_SAMPLES_PER_MM: f64 = 18.0;
/// Tones of a random displacement.
const RANDOM_TONES: usize = 32;

impl Shape {
    /// A sine of `cycles` cycles about `preload_mm` at each frequency (Hz)
    /// and each amplitude (mm), amplitudes swept at each frequency.
    pub fn sines(
        frequencies_hz: &[f64],
        amplitudes_mm: &[f64],
        preload_mm: f64,
        cycles: u32,
    ) -> Vec<Self> {
        frequencies_hz
            .iter()
            .flat_map(|&frequency_hz| {
                amplitudes_mm.iter().map(move |&amplitude_mm| Self::Sine {
                    frequency_hz,
                    amplitude_mm,
                    preload_mm,
                    cycles,
                })
            })
            .collect()
    }

    /// The test's name in the campaign.
    pub fn name(&self) -> String {
        match self {
            Self::MultiStep { levels, hold_s } => format!("ms-{}x{hold_s}", levels.len()),
            Self::Triangle {
                speed_mm_per_min,
                amplitude_mm,
                preload_mm,
                ..
            } => format!("tri-{speed_mm_per_min}-{preload_mm}-{amplitude_mm}"),
            Self::Sine {
                frequency_hz,
                amplitude_mm,
                preload_mm,
                ..
            } => format!("sine-{frequency_hz}-{preload_mm}-{amplitude_mm}"),
            Self::Random {
                f_hi_hz,
                rms_mm,
                seed,
                ..
            } => format!("random-{f_hi_hz}-{rms_mm}-{seed}"),
        }
    }

    fn kind(&self) -> Kind {
        match self {
            Self::MultiStep { .. } => Kind::MultiStep,
            Self::Triangle { .. } => Kind::Triangle,
            Self::Sine { .. } => Kind::Sine,
            Self::Random { .. } => Kind::Other,
        }
    }

    /// Duration, s.
    pub fn duration(&self) -> f64 {
        match self {
            Self::MultiStep { levels, hold_s } => levels.len() as f64 * (RAMP_S + hold_s),
            Self::Triangle {
                speed_mm_per_min,
                amplitude_mm,
                cycles,
                ..
            } => f64::from(*cycles) * 4.0 * amplitude_mm / (speed_mm_per_min / 60.0),
            Self::Sine {
                frequency_hz,
                cycles,
                ..
            } => f64::from(*cycles) / frequency_hz + self.lead(),
            Self::Random { duration_s, .. } => *duration_s,
        }
    }

    /// Time before the record starts, after the preload's lead-in, s: a
    /// sine's unrecorded passes of its cycles
    /// ([`replay::lead_passes`]); 0 for the other tests.
    pub fn lead(&self) -> f64 {
        match self {
            Self::Sine {
                frequency_hz,
                cycles,
                ..
            } => {
                let record_s = f64::from(*cycles) / frequency_hz;
                replay::lead_passes(record_s) as f64 * record_s
            }
            _ => 0.0,
        }
    }

    /// The preload the test starts from, mm.
    pub fn preload(&self) -> f64 {
        match self {
            Self::Triangle { preload_mm, .. } | Self::Sine { preload_mm, .. } => *preload_mm,
            _ => 0.0,
        }
    }

    /// Sampling rate at time `t`, Hz.
    fn sample_hz(&self, t: f64) -> f64 {
        match self {
            Self::MultiStep { hold_s, .. } => {
                if t.rem_euclid(RAMP_S + hold_s) < RAMP_S {
                    20.0
                } else {
                    1.0
                }
            }
            Self::Triangle {
                speed_mm_per_min,
                samples_per_mm,
                ..
            } => samples_per_mm * speed_mm_per_min / 60.0,
            Self::Sine { frequency_hz, .. } => 50.0 * frequency_hz,
            Self::Random { f_hi_hz, .. } => 50.0 * f_hi_hz,
        }
    }

    /// The model's step, s: a fraction [`SUBSTEPS`] of the finest sampling
    /// step of the test.
    fn model_dt(&self) -> f64 {
        let finest = match self {
            Self::MultiStep { .. } => 20.0,
            _ => self.sample_hz(0.0),
        };
        1.0 / (finest * SUBSTEPS as f64)
    }

    /// Displacement at `t`, mm.
    pub fn displacement(&self, t: f64) -> f64 {
        match self {
            Self::MultiStep { levels, hold_s } => {
                let period = RAMP_S + hold_s;
                let k = ((t / period).floor() as usize).min(levels.len().saturating_sub(1));
                let level =
                    |i: Option<usize>| i.and_then(|i| levels.get(i)).copied().unwrap_or(0.0);
                let (from, to) = (level(k.checked_sub(1)), level(Some(k)));
                let u = ((t - k as f64 * period) / RAMP_S).clamp(0.0, 1.0);
                from + (to - from) * u
            }
            Self::Triangle {
                speed_mm_per_min,
                amplitude_mm,
                preload_mm,
                ..
            } => {
                // From the preload up first: a quarter period to the top.
                let period = 4.0 * amplitude_mm / (speed_mm_per_min / 60.0);
                let p = (t / period + 0.25).rem_euclid(1.0);
                preload_mm + amplitude_mm * (1.0 - 4.0 * (p - 0.5).abs())
            }
            Self::Sine {
                frequency_hz,
                amplitude_mm,
                preload_mm,
                ..
            } => preload_mm + amplitude_mm * (TAU * frequency_hz * t).sin(),
            Self::Random {
                f_lo_hz,
                f_hi_hz,
                rms_mm,
                seed,
                ..
            } => {
                let mut phases = Noise::new(*seed);
                let a = rms_mm * (2.0 / RANDOM_TONES as f64).sqrt();
                let ratio = f_hi_hz / f_lo_hz;
                let sum: f64 = (0..RANDOM_TONES)
                    .map(|k| {
                        let f = f_lo_hz * ratio.powf(k as f64 / (RANDOM_TONES - 1) as f64);
                        (TAU * f * t + TAU * phases.uniform()).sin()
                    })
                    .sum();
                (t / 2.0).min(1.0) * a * sum
            }
        }
    }
}

/// The part grids of Table B.2 of seed 000: the multi-step levels 0.5 to
/// 5 mm held `hold_s` (3600 s in the table); triangles at 1 and 10 mm/min,
/// 3 cycles, the amplitude sweep 0.05 to 4.5 mm at no preload and the
/// preloads 1 to 4 mm at 1 mm; sines of 5 cycles at 0.1 to 100 Hz and
/// 0.05 to 1 mm about the preloads 0 to 3 mm (`preloads`).
pub fn part_grid(hold_s: f64, preloads: &[f64]) -> Vec<Shape> {
    let mut grid = vec![Shape::MultiStep {
        levels: vec![0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0],
        hold_s,
    }];
    for speed in [1.0, 10.0] {
        for a in [0.05, 0.1, 0.25, 0.5, 1.0, 4.5] {
            grid.push(Shape::Triangle {
                speed_mm_per_min: speed,
                amplitude_mm: a,
                preload_mm: 0.0,
                cycles: 3,
                samples_per_mm: PART_SAMPLES_PER_MM,
            });
        }
        for p in [1.0, 2.0, 3.0, 4.0] {
            grid.push(Shape::Triangle {
                speed_mm_per_min: speed,
                amplitude_mm: 1.0,
                preload_mm: p,
                cycles: 3,
                samples_per_mm: PART_SAMPLES_PER_MM,
            });
        }
    }
    for &p in preloads {
        grid.extend(Shape::sines(
            &[0.1, 0.5, 1.0, 5.0, 10.0, 50.0, 100.0],
            &[0.05, 0.1, 0.25, 0.5, 1.0],
            p,
            5,
        ));
    }
    grid
}

/// A specimen of Table B.1 of seed 000, tested in strain (a unit
/// specimen: 1.0 is 100 %).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Specimen {
    /// Simple shear, a rubber layer 5 mm thick (an assumption: the
    /// thickness is not given): 10 mm/min is 2 per minute.
    Shear,
    /// Traction, a gauge length of 20 mm (an assumption): 10 mm/min is
    /// 0.5 per minute.
    Traction,
}

impl Specimen {
    /// Machine travel per unit strain, mm.
    pub const fn gauge_mm(self) -> f64 {
        match self {
            Self::Shear => 5.0,
            Self::Traction => 20.0,
        }
    }
}

/// The specimen grids of Table B.1 of seed 000, in strain, with the
/// machine's speeds (1 and 10 mm/min) and sampling (18 per mm) carried
/// through the specimen's gauge ([`Specimen::gauge_mm`]):
///
/// - multi-step: shear 0.1 to 1.0, traction -0.3 to 0.6 by 0.15, held
///   `hold_s` (360 s in the table);
/// - triangles of 3 cycles: shear 0.5 about 0 and 0.2 at both speeds and
///   0.9 about 0 at 10 mm/min; traction 0.2 about -0.1, 0 and 0.1 at both
///   speeds, 0.05 about -0.3 to 0.3 by 0.1 at 10 mm/min (the Madelung
///   loops), and 0.001 to 0.1 about 0 at 10 mm/min (the Payne sweep, its
///   0.5 left out: it leaves the tabulated law);
/// - sines of 5 cycles about the preloads (shear 0, 0.45, 0.9; traction
///   -0.3 to 0.6 by 0.15), at 0.1 to 10 Hz of 1e-4 to 0.01 and at 50 and
///   100 Hz of 1e-4 to 0.1 (the table's amplitudes, see the reference flag
///   on them).
pub fn specimen_grid(specimen: Specimen, hold_s: f64) -> Vec<Shape> {
    let gauge = specimen.gauge_mm();
    let triangle = |mm_per_min: f64, amplitude_mm, preload_mm| Shape::Triangle {
        speed_mm_per_min: mm_per_min / gauge,
        amplitude_mm,
        preload_mm,
        cycles: 3,
        samples_per_mm: gauge * PART_SAMPLES_PER_MM,
    };
    // Levels in hundredths, so that names read as the table's values.
    let steps = |from: i32, step: i32, n: i32| -> Vec<f64> {
        (0..n).map(|k| f64::from(from + step * k) / 100.0).collect()
    };
    let (levels, preloads) = match specimen {
        Specimen::Shear => (steps(10, 10, 10), vec![0.0, 0.45, 0.9]),
        Specimen::Traction => (steps(-30, 15, 7), steps(-30, 15, 7)),
    };
    let mut grid = vec![Shape::MultiStep { levels, hold_s }];
    match specimen {
        Specimen::Shear => {
            for speed in [1.0, 10.0] {
                for p in [0.0, 0.2] {
                    grid.push(triangle(speed, 0.5, p));
                }
            }
            grid.push(triangle(10.0, 0.9, 0.0));
        }
        Specimen::Traction => {
            for speed in [1.0, 10.0] {
                for p in [-0.1, 0.0, 0.1] {
                    grid.push(triangle(speed, 0.2, p));
                }
            }
            for p in steps(-30, 10, 7) {
                grid.push(triangle(10.0, 0.05, p));
            }
            for a in [0.001, 0.005, 0.01, 0.1] {
                grid.push(triangle(10.0, a, 0.0));
            }
        }
    }
    for p in preloads {
        for (frequencies, amplitudes) in [
            (
                &[0.1, 0.5, 1.0, 5.0, 10.0][..],
                &[1e-4, 5e-4, 1e-3, 5e-3, 1e-2][..],
            ),
            (
                &[50.0, 100.0][..],
                &[1e-4, 5e-4, 1e-3, 5e-3, 1e-2, 5e-2, 0.1][..],
            ),
        ] {
            grid.extend(Shape::sines(frequencies, amplitudes, p, 5));
        }
    }
    grid
}

/// Why a campaign could not be generated.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// The model refused a test's time step.
    #[error("test {test}: the model at dt = {dt} s: {source}")]
    Model {
        /// The test.
        test: String,
        /// Its model step, s.
        dt: f64,
        /// What the model refused.
        source: ParamError,
    },
    /// The model refused a step of a test (its force left the guard).
    #[error("test {test}: the model refused the step at t = {t} s")]
    Refused {
        /// The test.
        test: String,
        /// Time of the step, s.
        t: f64,
    },
    /// A preload hold a replay cannot run.
    #[error("preload hold = {0} s must be from 0 to {MAX_PRELOAD_HOLD_S} s")]
    Hold(f64),
    /// A noise level that is not a fraction.
    #[error("noise = {0} must be finite and in [0, 1) (a share of each test's force range)")]
    Noise(f64),
    /// Writing failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// One generated record: (time s, displacement mm, force N) per sample,
/// without noise; a preload held `preload_hold_s` before the test.
pub fn record(
    scene: &Scene,
    shape: &Shape,
    preload_hold_s: f64,
) -> Result<Vec<[f64; 3]>, SynthError> {
    let at = |dt: f64| {
        model::build_at::<f64>(scene, dt).map_err(|source| SynthError::Model {
            test: shape.name(),
            dt,
            source,
        })
    };
    let refused = |t: f64| SynthError::Refused {
        test: shape.name(),
        t,
    };
    let dt = shape.model_dt();
    let bushing = at(dt)?;
    let mut state = bushing.state_at(0.0);
    // The lead-in to the preload, at its own steps (built once per step).
    let lead_in = replay::preload_steps(shape.preload(), preload_hold_s);
    let mut t = -lead_in.iter().map(|s| s.0).sum::<f64>();
    let mut built: Vec<(f64, SceneBushing<f64>)> = Vec::new();
    for (h, x) in lead_in {
        let b = match built.iter().position(|b| b.0 == h) {
            Some(i) => &built[i].1,
            None => {
                built.push((h, at(h)?));
                &built[built.len() - 1].1
            }
        };
        t += h;
        if b.step(&mut state, x).effects.is_none() {
            return Err(refused(t));
        }
    }
    let steps = (shape.duration() / dt).round() as u64;
    let mut rows = Vec::new();
    let mut next_sample = 0.0;
    let lead = shape.lead();
    for n in 0..=steps {
        let t = n as f64 * dt;
        let x = shape.displacement(t);
        let force = if n == 0 {
            state.force()
        } else {
            let o = bushing.step(&mut state, x);
            if o.effects.is_none() {
                return Err(refused(t));
            }
            o.force
        };
        if t >= next_sample - 0.5 * dt {
            if t >= lead - 0.5 * dt {
                rows.push([t - lead, x, force]);
            }
            next_sample = t + 1.0 / shape.sample_hz(t);
        }
    }
    Ok(rows)
}

/// Writes `campaign.toml` and one CSV per test of `grid`, generated from
/// `scene`'s model, into `out`; the force gets Gaussian noise of standard
/// deviation `noise` times the test's force range (`seed` sets the
/// draws); every preload is held `preload_hold_s` before its test.
/// Returns the number of samples written.
pub fn write(
    scene: &Scene,
    grid: &[Shape],
    noise: f64,
    seed: u64,
    preload_hold_s: f64,
    out: &mut Staged,
) -> Result<usize, SynthError> {
    if !(noise.is_finite() && (0.0..1.0).contains(&noise)) {
        return Err(SynthError::Noise(noise));
    }
    if !(0.0..=MAX_PRELOAD_HOLD_S).contains(&preload_hold_s) {
        return Err(SynthError::Hold(preload_hold_s));
    }
    let mut draws = Noise::new(seed);
    let mut toml = format!(
        "# Generated by `bushing-sim campaign` from the model of a scene ({}),\n\
         # force noise {noise} of each test's range, seed {seed}.\n\
         [campaign]\nname = \"{}\"\npreload_hold_s = {preload_hold_s:?}\n",
        scene.title.replace(['"', '\\', '\n'], " "),
        scene.title.replace(['"', '\\', '\n'], " ")
    );
    let mut samples = 0;
    for shape in grid {
        let rows = record(scene, shape, preload_hold_s)?;
        let (lo, hi) = super::extremes(rows.iter().map(|r| &r[2]));
        let sigma = noise * (hi - lo);
        let name = shape.name();
        let mut csv = CsvText::new(["time_s", "x_mm", "force_n"]);
        for r in &rows {
            let f = r[2] + sigma * draws.gauss();
            csv.record([r[0].to_string(), r[1].to_string(), f.to_string()]);
        }
        samples += rows.len();
        out.write(&format!("{name}.csv"), csv.finish().as_bytes())?;
        toml.push_str(&format!(
            "\n[[test]]\nname = \"{name}\"\nkind = \"{}\"\nfile = \"{name}.csv\"\n",
            shape.kind().name()
        ));
        match shape {
            Shape::MultiStep { .. } | Shape::Random { .. } => {}
            Shape::Triangle {
                speed_mm_per_min,
                amplitude_mm,
                preload_mm,
                ..
            } => toml.push_str(&format!(
                "speed_mm_per_min = {speed_mm_per_min:?}\namplitude_mm = {amplitude_mm:?}\npreload_mm = {preload_mm:?}\n"
            )),
            Shape::Sine {
                frequency_hz,
                amplitude_mm,
                preload_mm,
                ..
            } => toml.push_str(&format!(
                "frequency_hz = {frequency_hz:?}\namplitude_mm = {amplitude_mm:?}\npreload_mm = {preload_mm:?}\n"
            )),
        }
    }
    out.write("campaign.toml", toml.as_bytes())?;
    Ok(samples)
}
