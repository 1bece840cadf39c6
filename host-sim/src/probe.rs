//! The instantaneous complex modulus of a run (seed 000 Fig 1.24): the
//! probe that tracks it on line, its points, their CSV and their plots.

use std::collections::VecDeque;

use bushing::tracker::{Channel, ModulusSpec, ModulusState, ModulusTracker, SineSpec};

use crate::plot::{Marker, Plot, Series, Shape, palette};

/// One point of the instantaneous-modulus plot: the tracked complex
/// modulus at the end of one tracked period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModulusPoint {
    /// Time of the tracked sample, s.
    pub time_s: f64,
    /// Frequency of the imposed sine, Hz.
    pub frequency_hz: f64,
    /// Imposed amplitude, mm.
    pub amplitude_mm: f64,
    /// Mean displacement over the last period (the preload), mm.
    pub mean_mm: f64,
    /// Storage modulus K', N/mm.
    pub storage: f64,
    /// Loss modulus K'', N/mm.
    pub loss: f64,
}

impl ModulusPoint {
    /// Loss factor K''/K' (NaN when K' is zero).
    pub fn loss_factor(&self) -> f64 {
        if self.storage == 0.0 {
            f64::NAN
        } else {
            self.loss / self.storage
        }
    }
}

/// Tracking bandwidth of the modulus tracker as a fraction of the test
/// frequency: its memory is about 1/(2π · 0.2) = 0.8 period, short enough
/// to follow a stepped amplitude within a few periods.
pub const TRACK_BANDWIDTH: f64 = 0.2;
/// Tracked periods skipped before the first modulus point.
pub const SKIPPED_PERIODS: u64 = 2;
/// Longest period tracked, in samples (the running mean keeps one period).
pub const MAX_PERIOD_SAMPLES: f64 = 2_097_152.0;

/// The on-line instantaneous modulus of the run (seed 000 Fig 1.24), with
/// the library's [`ModulusTracker`] on x and F at the frequency the profile
/// imposes.
///
/// The tracker has no mean state, and a constant or slowly moving offset
/// (a preload, the relaxation of slow cells after a start from rest) would
/// leak into the complex amplitudes. So both signals go through a running
/// mean over exactly one period (fractional end weight), and the tracker
/// is fed the sample at the middle of that window minus the mean: a
/// constant or a linear drift cancels exactly, a steady sine passes
/// unchanged. The delay of half a period is the same on both channels, so
/// it cancels in F/X. The tracker starts when the first window is full (one
/// period into the sine) and is restarted whenever the frequency changes;
/// one point is taken at the end of every tracked period after the first
/// [`SKIPPED_PERIODS`]. Sines of fewer than 2 or more than
/// [`MAX_PERIOD_SAMPLES`] samples per period are not tracked.
pub struct ModulusProbe {
    dt: f64,
    /// Backbone tangent where the run starts, N/mm: scale of the force.
    stiffness: f64,
    frequency: Option<f64>,
    /// Samples per period.
    period: f64,
    /// (t, x, F, imposed amplitude or NaN).
    window: VecDeque<(f64, f64, f64, f64)>,
    sums: (f64, f64),
    tracker: Option<(ModulusTracker<f64>, ModulusState<f64>)>,
    /// The tracker could not be built for this frequency.
    dead: bool,
    fed: u64,
    next_point: u64,
    points: Vec<ModulusPoint>,
    /// Least time between two kept points, s.
    gap: f64,
    /// Points were dropped to stay under [`MAX_MODULUS_POINTS`].
    capped: bool,
    /// Some sample had a sine frequency.
    pub saw_sine: bool,
}

/// Most modulus points a run keeps (about 21 MB of `modulus.csv`). When a
/// run reaches it, every other point is dropped and the least time between
/// points doubles, so the points still cover the whole run evenly.
pub const MAX_MODULUS_POINTS: usize = 100_000;

impl ModulusProbe {
    /// A probe for time step `dt` on a bushing of tangent `stiffness`.
    pub fn new(dt: f64, stiffness: f64) -> Self {
        Self {
            dt,
            stiffness: if stiffness.is_finite() && stiffness > 0.0 {
                stiffness
            } else {
                1.0
            },
            frequency: None,
            period: 0.0,
            window: VecDeque::new(),
            sums: (0.0, 0.0),
            tracker: None,
            dead: false,
            fed: 0,
            next_point: SKIPPED_PERIODS,
            points: Vec::new(),
            gap: 0.0,
            capped: false,
            saw_sine: false,
        }
    }

    /// Keeps no more points than the trace has rows: two points at least
    /// `every` steps apart (a point per period otherwise).
    pub fn thinned(mut self, every: u64) -> Self {
        self.gap = (every.max(1) as f64 - 0.5) * self.dt;
        self
    }

    /// Points were dropped to stay under [`MAX_MODULUS_POINTS`].
    pub fn capped(&self) -> bool {
        self.capped
    }

    fn keep(&mut self, point: ModulusPoint) {
        if let Some(last) = self.points.last()
            && point.time_s - last.time_s < self.gap
        {
            return;
        }
        if self.points.len() >= MAX_MODULUS_POINTS {
            let mut k = 0;
            self.points.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.gap = 2.0 * self.gap.max(self.dt);
            self.capped = true;
            if let Some(last) = self.points.last()
                && point.time_s - last.time_s < self.gap
            {
                return;
            }
        }
        self.points.push(point);
    }

    /// One sample at time `t`: displacement `x` (mm) and force `f` (N), with
    /// the frequency and the amplitude of the sine imposed then, if any
    /// (without an amplitude, the tracked displacement amplitude is used).
    pub fn push(&mut self, sine: Option<(f64, Option<f64>)>, t: f64, x: f64, f: f64) {
        let (frequency, amplitude) = match sine {
            Some((f, a)) => (Some(f), a),
            None => (None, None),
        };
        let changed = match (frequency, self.frequency) {
            (Some(a), Some(b)) => (a - b).abs() > 1e-12 * b.abs(),
            (None, None) => false,
            _ => true,
        };
        if changed {
            self.restart(frequency);
        }
        if self.frequency.is_none() || self.dead {
            return;
        }
        self.saw_sine = true;
        if !(x.is_finite() && f.is_finite()) {
            return;
        }
        let whole = self.period.floor();
        let frac = self.period - whole;
        let len = whole as usize + 1;
        self.window
            .push_back((t, x, f, amplitude.unwrap_or(f64::NAN)));
        self.sums.0 += x;
        self.sums.1 += f;
        if self.window.len() > len
            && let Some((_, ox, of, _)) = self.window.pop_front()
        {
            self.sums.0 -= ox;
            self.sums.1 -= of;
        }
        if self.window.len() < len {
            return;
        }
        let Some(&(_, ox, of, _)) = self.window.front() else {
            return;
        };
        let mean = (
            (self.sums.0 - (1.0 - frac) * ox) / self.period,
            (self.sums.1 - (1.0 - frac) * of) / self.period,
        );
        if self.tracker.is_none() && !self.start(mean) {
            self.dead = true;
            return;
        }
        let Some(&(tc, xc, fc, ac)) = self.window.get(len / 2) else {
            return;
        };
        let Some((tracker, state)) = &mut self.tracker else {
            return;
        };
        if tracker.step(state, xc - mean.0, fc - mean.1).is_err() {
            return;
        }
        self.fed += 1;
        // One sample early at most: a step of whole periods that ends on a
        // rest still gets its last point.
        if self.fed as f64 + 1.0 >= self.next_point as f64 * self.period {
            self.next_point += 1;
            if let Some(m) = tracker.modulus(state) {
                let (ax, bx) = state.displacement();
                let point = ModulusPoint {
                    time_s: tc,
                    frequency_hz: tracker.frequency(),
                    amplitude_mm: if ac.is_finite() { ac } else { ax.hypot(bx) },
                    mean_mm: mean.0,
                    storage: m.storage,
                    loss: m.loss,
                };
                self.keep(point);
            }
        }
    }

    fn restart(&mut self, frequency: Option<f64>) {
        self.frequency = frequency.filter(|f| f.is_finite() && *f > 0.0);
        self.period = self.frequency.map_or(0.0, |f| 1.0 / (f * self.dt));
        self.dead =
            !(self.period.is_finite() && self.period >= 2.0 && self.period <= MAX_PERIOD_SAMPLES);
        self.window.clear();
        self.sums = (0.0, 0.0);
        self.tracker = None;
        self.fed = 0;
        self.next_point = SKIPPED_PERIODS;
    }

    /// Builds the tracker once the first window is full, with the
    /// amplitudes seen in it; false if it cannot be built.
    fn start(&mut self, mean: (f64, f64)) -> bool {
        let Some(frequency) = self.frequency else {
            return false;
        };
        let (ax, af) = self.window.iter().fold((0.0f64, 0.0f64), |(a, b), s| {
            (a.max((s.1 - mean.0).abs()), b.max((s.2 - mean.1).abs()))
        });
        if !(ax > 0.0 && ax.is_finite()) {
            return false;
        }
        let af = if af > 0.0 && af.is_finite() {
            af
        } else {
            self.stiffness * ax
        };
        let spec = ModulusSpec {
            sine: SineSpec {
                frequency,
                bandwidth: TRACK_BANDWIDTH * frequency,
            },
            displacement: Channel {
                noise: 1e-4 * ax,
                amplitude: ax,
            },
            force: Channel {
                noise: 1e-4 * af,
                amplitude: af,
            },
            min_snr: 10.0,
        };
        match ModulusTracker::<f64>::new(self.dt, &spec) {
            Ok(t) => {
                let s = t.start();
                self.tracker = Some((t, s));
                true
            }
            Err(_) => false,
        }
    }

    /// The points taken.
    pub fn finish(&self) -> Vec<ModulusPoint> {
        self.points.clone()
    }
}

/// `modulus.csv`: one row per point.
pub fn modulus_csv(points: &[ModulusPoint]) -> String {
    let mut text = crate::csv_text::CsvText::new([
        "frequency_hz",
        "amplitude_mm",
        "storage_N_per_mm",
        "loss_N_per_mm",
        "loss_factor",
    ]);
    for p in points {
        text.record(
            [
                p.frequency_hz,
                p.amplitude_mm,
                p.storage,
                p.loss,
                p.loss_factor(),
            ]
            .map(|v| format!("{v:e}")),
        );
    }
    text.finish()
}

/// The modulus plot: storage K′ and loss K″ against the imposed amplitude,
/// one series per frequency; one panel per preload when there are several
/// (so that each legend stays short).
pub fn modulus_plots(points: &[ModulusPoint], title: &str) -> Vec<Plot> {
    let mean = preload_of;
    let mut preloads: Vec<f64> = points.iter().map(mean).collect();
    preloads.sort_by(f64::total_cmp);
    preloads.dedup();
    let (lo, hi) = points
        .iter()
        .map(|p| p.amplitude_mm)
        .filter(|a| *a > 0.0 && a.is_finite())
        .fold((f64::INFINITY, 0.0f64), |(l, h), a| (l.min(a), h.max(a)));
    let panel = |title: String, at: &dyn Fn(&ModulusPoint) -> bool| {
        let mut frequencies: Vec<f64> = Vec::new();
        for p in points.iter().filter(|p| at(p)) {
            if !frequencies.contains(&p.frequency_hz) {
                frequencies.push(p.frequency_hz);
            }
        }
        let mut series = Vec::new();
        for f in frequencies {
            let of = || points.iter().filter(move |p| at(p) && p.frequency_hz == f);
            series.push(Series::markers(
                format!("storage K' at {f} Hz"),
                of().map(|p| (p.amplitude_mm, p.storage)).collect(),
            ));
            series.push(Series::markers(
                format!("loss K'' at {f} Hz"),
                of().map(|p| (p.amplitude_mm, p.loss)).collect(),
            ));
        }
        Plot {
            title,
            x_label: "imposed amplitude X [mm]".into(),
            y_label: "modulus K', K'' [N/mm]".into(),
            x_log: hi > 3.0 * lo,
            series,
            ..Plot::default()
        }
    };
    if points.is_empty() {
        let title = format!("{title} (no sine held at one frequency for 3 periods)");
        return vec![panel(title, &|_| true)];
    }
    if preloads.len() <= 1 {
        return vec![panel(title.to_string(), &|_| true)];
    }
    preloads
        .iter()
        .map(|&m| panel(format!("{title}, mean x {m} mm"), &move |p| mean(p) == m))
        .collect()
}

/// Means within 1 µm are one preload (+ 0.0 turns -0 into 0).
fn preload_of(p: &ModulusPoint) -> f64 {
    (p.mean_mm * 1e3).round() / 1e3 + 0.0
}

/// Amplitudes within 4 significant digits are one: the key and the value.
fn amplitude_of(p: &ModulusPoint) -> (String, f64) {
    let key = format!("{:.3e}", p.amplitude_mm);
    let value = key.parse().unwrap_or(p.amplitude_mm);
    (key, value)
}

/// The distinct amplitudes of `points`, in order of appearance.
fn amplitudes<'a>(points: impl Iterator<Item = &'a ModulusPoint>) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for p in points {
        let a = amplitude_of(p);
        if !out.iter().any(|(k, _)| *k == a.0) {
            out.push(a);
        }
    }
    out
}

/// Whether `points` sweep the frequency: two distinct frequencies or more
/// at one amplitude. Such a run reads against frequency
/// ([`frequency_plots`]); one at a single frequency per amplitude, against
/// amplitude ([`modulus_plots`]).
pub fn sweeps_frequency(points: &[ModulusPoint]) -> bool {
    amplitudes(points.iter()).iter().any(|(key, _)| {
        let mut frequencies: Vec<f64> = Vec::new();
        for p in points.iter().filter(|p| amplitude_of(p).0 == *key) {
            if !frequencies
                .iter()
                .any(|f| (f - p.frequency_hz).abs() <= 1e-9 * f.abs())
            {
                frequencies.push(p.frequency_hz);
            }
        }
        frequencies.len() >= 2
    })
}

/// More amplitudes than this share one series (a run whose amplitude is
/// measured rather than imposed).
const MAX_AMPLITUDE_SERIES: usize = 10;

/// The modulus against frequency on a logarithmic axis, for a sweep in
/// frequency (a stepped sine): three panels, storage K′, loss K″ (N/mm)
/// and loss factor K″/K′, one series per imposed amplitude: every point as
/// a marker and a line through the last (settled) point at each
/// frequency. With several preloads, three panels per preload.
pub fn frequency_plots(points: &[ModulusPoint], title: &str) -> Vec<Plot> {
    type Quantity = (&'static str, &'static str, fn(&ModulusPoint) -> f64);
    const QUANTITIES: [Quantity; 3] = [
        ("storage modulus", "storage modulus K' [N/mm]", |p| {
            p.storage
        }),
        ("loss modulus", "loss modulus K'' [N/mm]", |p| p.loss),
        (
            "loss factor",
            "loss factor K''/K' [-]",
            ModulusPoint::loss_factor,
        ),
    ];
    let mut preloads: Vec<f64> = points.iter().map(preload_of).collect();
    preloads.sort_by(f64::total_cmp);
    preloads.dedup();
    let several = preloads.len() > 1;
    if preloads.is_empty() {
        preloads.push(0.0);
    }
    let mut plots = Vec::new();
    for &preload in &preloads {
        let here: Vec<&ModulusPoint> = points
            .iter()
            .filter(|p| !several || preload_of(p) == preload)
            .collect();
        let mut groups = amplitudes(here.iter().copied());
        let merged = groups.len() > MAX_AMPLITUDE_SERIES;
        if merged {
            groups = vec![(String::new(), f64::NAN)];
        }
        for (what, y_label, value) in QUANTITIES {
            let mut plot = Plot {
                title: match (points.is_empty(), several) {
                    (true, _) => {
                        format!("{title}: {what} (no sine held at one frequency for 3 periods)")
                    }
                    (false, true) => format!("{title}, mean x {preload} mm: {what}"),
                    (false, false) => format!("{title}: {what}"),
                },
                x_label: "frequency f [Hz]".into(),
                y_label: y_label.into(),
                x_log: true,
                ..Plot::default()
            };
            for (i, (key, amplitude)) in groups.iter().enumerate() {
                let of = || {
                    here.iter()
                        .copied()
                        .filter(|p| merged || amplitude_of(p).0 == *key)
                };
                let name = if merged {
                    format!("all {} amplitudes", here.len())
                } else {
                    format!("X = {amplitude} mm")
                };
                // The last point at each frequency, by frequency.
                let mut settled: Vec<(f64, f64)> = Vec::new();
                for p in of() {
                    match settled.iter_mut().find(|s| s.0 == p.frequency_hz) {
                        Some(s) => s.1 = value(p),
                        None => settled.push((p.frequency_hz, value(p))),
                    }
                }
                settled.sort_by(|a, b| a.0.total_cmp(&b.0));
                let color = palette(i);
                plot.series
                    .push(Series::line("", settled).with_color(color));
                plot.series.push(
                    Series::markers(name, of().map(|p| (p.frequency_hz, value(p))).collect())
                        .with_color(color)
                        .with_marker(Marker {
                            shape: Shape::nth(i),
                            radius: 4,
                            filled: true,
                        }),
                );
            }
            plots.push(plot);
        }
    }
    plots
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(time_s: f64) -> ModulusPoint {
        ModulusPoint {
            time_s,
            frequency_hz: 1.0,
            amplitude_mm: 1.0,
            mean_mm: 0.0,
            storage: 1.0,
            loss: 0.1,
        }
    }

    #[test]
    fn points_are_capped_by_halving_their_density_over_the_whole_run() {
        let dt = 1e-3;
        let mut probe = ModulusProbe::new(dt, 1.0).thinned(1);
        let n = 4 * MAX_MODULUS_POINTS;
        for k in 0..n {
            probe.keep(point(k as f64 * 2.0 * dt));
        }
        let points = probe.finish();
        assert!(probe.capped());
        assert!(points.len() <= MAX_MODULUS_POINTS, "{}", points.len());
        assert!(points.len() >= MAX_MODULUS_POINTS / 2, "{}", points.len());
        // Still the whole run, evenly: first and last quarter both present.
        let end = (n - 1) as f64 * 2.0 * dt;
        assert_eq!(points[0].time_s, 0.0);
        assert!(points.last().unwrap().time_s > 0.99 * end);
        let spacing: Vec<f64> = points
            .windows(2)
            .map(|w| w[1].time_s - w[0].time_s)
            .collect();
        let (lo, hi) = spacing
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), s| (l.min(*s), h.max(*s)));
        assert!(hi <= 2.0 * lo + 1e-12, "spacing {lo} to {hi}");
    }

    #[test]
    fn thinning_keeps_points_at_least_trace_every_steps_apart() {
        let dt = 1e-3;
        let mut probe = ModulusProbe::new(dt, 1.0).thinned(10);
        for k in 0..1000 {
            probe.keep(point(k as f64 * 4.0 * dt));
        }
        let points = probe.finish();
        assert!(!probe.capped());
        assert_eq!(points.len(), 334);
        assert!(
            points
                .windows(2)
                .all(|w| w[1].time_s - w[0].time_s >= 9.5 * dt)
        );
    }
}
