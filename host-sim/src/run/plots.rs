//! The plots of a run, fed step by step: the force-displacement loop
//! (every few steps, at most [`PLOT_POINTS`]), the time plots decimated to
//! the smallest and largest value of each of [`TIME_BUCKETS`] buckets (so
//! that an oscillation too fast to draw shows as its envelope instead of
//! aliasing), the dissipated power and energy per effect, and the modulus
//! probe's points.

use std::path::PathBuf;

use bushing::Real;

use super::RunError;
use super::pipeline::{Sink, Step};
use crate::output::Staged;
use crate::plot::{self, Plot, Series};
use crate::probe::{self, ModulusPoint, ModulusProbe};
use crate::profile;
use crate::scene::Scene;

/// Points kept for the force-displacement plot.
pub const PLOT_POINTS: u64 = 20_000;
/// Buckets of the time plots (two points each).
pub const TIME_BUCKETS: u64 = 4_000;

/// Collects what the plots draw.
pub struct PlotSink<'a> {
    scene: &'a Scene,
    names: &'a [String],
    oscillator: bool,
    stride: u64,
    loop_points: Vec<(f64, f64)>,
    elastic_points: Vec<(f64, f64)>,
    force_t: Envelopes,
    power_t: Envelopes,
    energy_t: Envelopes,
    effect_energy: Vec<f64>,
    energy: f64,
    peak: f64,
    probe: ModulusProbe,
    /// The replay's measured force: its time envelope, its loop points,
    /// and the residual so far.
    measured_t: Envelopes,
    measured_loop: Vec<(f64, f64)>,
    residual: Residual,
}

/// The model's force against a replay's measured force, accumulated.
#[derive(Debug, Clone, Copy)]
struct Residual {
    sum_sq: f64,
    n: u64,
    lo: f64,
    hi: f64,
}

/// The model's force against the force measured with a replayed record.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MeasuredFit {
    /// Steps compared.
    pub steps: u64,
    /// RMS of model force minus measured force, N.
    pub rms_n: f64,
    /// Range of the measured force (largest minus smallest), N.
    pub range_n: f64,
    /// The RMS residual as a percentage of that range.
    pub rms_percent: f64,
}

impl<'a> PlotSink<'a> {
    /// A sink for `scene`, whose effects are `names`; `stiffness` is the
    /// backbone tangent at the start, N/mm (the modulus probe's scale).
    pub fn new(scene: &'a Scene, names: &'a [String], stiffness: f64) -> Self {
        let steps = scene.steps();
        let bucket = steps.div_ceil(TIME_BUCKETS).max(1);
        Self {
            scene,
            names,
            oscillator: scene.oscillator.is_some(),
            stride: steps.div_ceil(PLOT_POINTS).max(1),
            loop_points: Vec::new(),
            elastic_points: Vec::new(),
            force_t: Envelopes::new(names.len() + 2, bucket),
            power_t: Envelopes::new(names.len() + 1, bucket),
            energy_t: Envelopes::new(names.len() + 1, bucket),
            effect_energy: vec![0.0; names.len()],
            energy: 0.0,
            peak: 0.0,
            probe: ModulusProbe::new(scene.dt, stiffness).thinned(scene.trace_every),
            measured_t: Envelopes::new(1, bucket),
            measured_loop: Vec::new(),
            residual: Residual {
                sum_sq: 0.0,
                n: 0,
                lo: f64::INFINITY,
                hi: f64::NEG_INFINITY,
            },
        }
    }

    /// The model's force against the replay's measured force, when the
    /// replay has a force column.
    pub fn measured(&self) -> Option<MeasuredFit> {
        let r = self.residual;
        (r.n > 0).then(|| {
            let rms = (r.sum_sq / r.n as f64).sqrt();
            let range = r.hi - r.lo;
            MeasuredFit {
                steps: r.n,
                rms_n: rms,
                range_n: range,
                rms_percent: 100.0 * rms / range,
            }
        })
    }

    /// Energy dissipated so far, mJ.
    pub fn energy(&self) -> f64 {
        self.energy
    }

    /// Largest |force| so far, N.
    pub fn peak(&self) -> f64 {
        self.peak
    }

    /// Writes the plots and the modulus points into `out`, returning the
    /// files written and the modulus points. With `png`, each figure is
    /// also written as a PNG beside its SVG.
    pub fn write(
        self,
        out: &mut Staged,
        png: bool,
    ) -> Result<(Vec<PathBuf>, Vec<ModulusPoint>, bool), RunError> {
        let Self {
            scene,
            names,
            loop_points,
            elastic_points,
            force_t,
            power_t,
            energy_t,
            probe,
            measured_t,
            measured_loop,
            residual,
            ..
        } = self;
        let measured = residual.n > 0;
        let mut w = Figures {
            out,
            png,
            files: Vec::new(),
        };
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

        let loop_plot = Plot {
            title: if scene.title.is_empty() {
                format!("Force-displacement ({effects})")
            } else {
                scene.title.clone()
            },
            x_label: "displacement x [mm]".into(),
            y_label: "force F [N]".into(),
            series: vec![
                Series::line(
                    format!("total force, {effects}, {}", scene.number.name()),
                    loop_points,
                ),
                Series::line("long-term elastic branch g0 F_inf(x)", elastic_points),
            ]
            .into_iter()
            .chain(measured.then(|| Series::dashed("measured force", measured_loop)))
            .collect(),
            ..Plot::default()
        };
        w.figure("force-displacement", &[loop_plot])?;

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
        if measured {
            let points = measured_t.finish().into_iter().next().unwrap_or_default();
            series.push(Series::dashed("measured force", points));
        }
        let force_plot = Plot {
            title: title("Force against time"),
            x_label: "time t [s]".into(),
            y_label: "force F [N]".into(),
            series,
            ..Plot::default()
        };
        w.figure("force-time", &[force_plot])?;

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
            series: per_effect(power_t.finish(), "total, energy of each step / dt"),
            ..Plot::default()
        };
        let cumulative = Plot {
            title: title("Cumulative dissipated energy"),
            x_label: "time t [s]".into(),
            y_label: "dissipated energy E [mJ = N·mm]".into(),
            series: per_effect(energy_t.finish(), "total"),
            ..Plot::default()
        };
        w.figure("dissipated-power", &[power, cumulative])?;

        let modulus = probe.finish();
        let capped = probe.capped();
        if probe.saw_sine {
            let title = title("Instantaneous complex modulus");
            let csv = probe::modulus_csv(&modulus);
            w.files.push(w.out.write("modulus.csv", csv.as_bytes())?);
            w.figure("modulus-amplitude", &probe::modulus_plots(&modulus, &title))?;
            // A test over frequency reads against frequency.
            if probe::sweeps_frequency(&modulus) {
                w.figure(
                    "modulus-frequency",
                    &probe::frequency_plots(&modulus, &title),
                )?;
            }
        }
        Ok((w.files, modulus, capped))
    }
}

/// Writes figures, as SVG and on request as PNG too.
struct Figures<'o> {
    out: &'o mut Staged,
    png: bool,
    files: Vec<PathBuf>,
}

impl Figures<'_> {
    fn figure(&mut self, stem: &str, panels: &[Plot]) -> Result<(), RunError> {
        let svg = plot::render_panels(panels);
        self.files
            .push(self.out.write(&format!("{stem}.svg"), svg.as_bytes())?);
        if self.png {
            let png = plot::png_panels(panels)?;
            self.files
                .push(self.out.write(&format!("{stem}.png"), &png)?);
        }
        Ok(())
    }
}

impl<T: Real> Sink<T> for PlotSink<'_> {
    fn step(&mut self, s: &Step<'_, T>) -> Result<(), RunError> {
        let t = s.time;
        let step_energy = s.row.dissipated.to_f64();
        self.energy += step_energy;
        let (xf, f, elastic) = (
            s.row.x.to_f64(),
            s.row.force.to_f64(),
            s.row.elastic.to_f64(),
        );
        self.peak = self.peak.max(f.abs());
        self.force_t.push(0, t, f);
        self.force_t.push(1, t, elastic);
        self.power_t.push(0, t, step_energy / self.scene.dt);
        self.energy_t.push(0, t, self.energy);
        for (j, e) in s.parts.iter().enumerate() {
            let (ef, ed) = (e.force.to_f64(), e.dissipated.to_f64());
            self.force_t.push(j + 2, t, ef);
            self.power_t.push(j + 1, t, ed / self.scene.dt);
            if let Some(total) = self.effect_energy.get_mut(j) {
                *total += ed;
                self.energy_t.push(j + 1, t, *total);
            }
        }
        let measured = profile::measured_force(&self.scene.profile, t);
        if let Some(m) = measured {
            let r = &mut self.residual;
            r.sum_sq += (f - m) * (f - m);
            r.n += 1;
            r.lo = r.lo.min(m);
            r.hi = r.hi.max(m);
            self.measured_t.push(0, t, m);
        }
        if s.index.is_multiple_of(self.stride) {
            self.loop_points.push((xf, f));
            self.elastic_points.push((xf, elastic));
            if let Some(m) = measured {
                self.measured_loop.push((xf, m));
            }
        }
        // An oscillator's profile is a force: no imposed displacement.
        let sine = profile::frequency_at(&self.scene.profile, t)
            .filter(|_| !self.oscillator)
            .map(|fr| (fr, profile::amplitude_at(&self.scene.profile, t)));
        self.probe.push(sine, t, xf, f);
        Ok(())
    }
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
