//! The pre-processing of a campaign, each step in a report (issue item
//! "each step in the report"): which tests are used and which are left
//! out with their reason, the first harmonic of every sine, the holds of
//! every multi-step test, the branches of every triangle test, and their
//! plots. `bushing-sim preprocess CAMPAIGN --out DIR` writes it.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::backbone::{PART_THRESHOLD_MM, knots, midline};
use super::campaign::{Campaign, Excluded, Kind};
use super::hysteresis::{Placed, normalised, place};
use super::relax::{Hold, holds};
use super::sine::{SinePoint, first_harmonic};
use super::triangle::{Triangles, branches};
use crate::markdown::Table;
use crate::output::{OutputError, Staged};
use crate::plot::{Legend, Plot, Series, render_panels};

/// A campaign's tests reduced to what the identification reads.
#[derive(Debug, Clone, PartialEq)]
pub struct Preprocessed {
    /// The campaign's name.
    pub name: String,
    /// Each usable sine and its first harmonic.
    pub sines: Vec<(String, SinePoint)>,
    /// Each usable multi-step test and its holds.
    pub holds: Vec<(String, Vec<Hold>)>,
    /// Each usable triangle test and its branches.
    pub triangles: Vec<(String, Triangles)>,
    /// The tests of kind `other`, kept whole for the time-domain fit.
    pub others: Vec<String>,
    /// The triangles' midline points `(x mm, F N)` past
    /// [`PART_THRESHOLD_MM`] from the turning points: the long-term
    /// backbone g⁰ F^∞ (the first stage of the identification).
    pub midline: Vec<(f64, f64)>,
    /// Knots of the long-term backbone made from the midline, when there
    /// are enough points and the forces increase.
    pub long_term: Option<(Vec<f64>, Vec<f64>)>,
    /// The instantaneous-modulus curve over the long-term modulus (the
    /// knots' spline), binned: `(distance mm, ratio, points)`.
    pub normalised: Vec<(f64, f64, usize)>,
    /// [`JENKINS_CELLS`] Jenkins cells placed on it (the second stage).
    pub jenkins: Option<Vec<Placed>>,
    /// The lengths of the analysis, scaled to the largest triangle.
    pub scale: Scale,
    /// Every test left out, when reading or here, with its reason.
    pub excluded: Vec<Excluded>,
}

/// Reduces every test of `campaign`; a test that fails its checks joins
/// the excluded ones.
pub fn preprocess(campaign: &Campaign) -> Preprocessed {
    let mut p = Preprocessed {
        name: campaign.name.clone(),
        sines: Vec::new(),
        holds: Vec::new(),
        triangles: Vec::new(),
        others: Vec::new(),
        midline: Vec::new(),
        long_term: None,
        normalised: Vec::new(),
        jenkins: None,
        excluded: campaign.excluded.clone(),
        scale: Scale::of(PART_LARGEST_MM),
    };
    for t in &campaign.tests {
        let name = t.name.clone();
        let outcome = match t.kind {
            Kind::Sine => first_harmonic(t).map(|s| p.sines.push((name.clone(), s))),
            Kind::MultiStep => holds(t).map(|h| p.holds.push((name.clone(), h))),
            Kind::Triangle => branches(t).map(|b| p.triangles.push((name.clone(), b))),
            Kind::Other => {
                p.others.push(name.clone());
                Ok(())
            }
        };
        if let Err(reason) = outcome {
            p.excluded.push(Excluded { name, reason });
        }
    }
    let triangles: Vec<_> = p.triangles.iter().map(|(_, t)| t.clone()).collect();
    let largest = triangles.iter().map(|t| t.amplitude_mm).fold(0.0, f64::max);
    if largest > 0.0 {
        p.scale = Scale::of(largest);
    }
    let sc = p.scale;
    p.midline = midline(&triangles, sc.threshold_mm, sc.step_mm);
    p.long_term = knots(&p.midline, LONG_TERM_KNOTS);
    if let Some((xs, fs)) = &p.long_term
        && let Ok(spline) = bushing::MonotoneSpline::<f64, LONG_TERM_KNOTS>::new(xs, fs)
    {
        use bushing::Backbone;
        // Only where the knots say what the long-term modulus is.
        let known = (xs[0], xs[xs.len() - 1]);
        p.normalised = normalised(&triangles, |x| spline.eval(x).1, known, sc.bin_mm);
        p.jenkins = place(&p.normalised, JENKINS_CELLS, sc.filter_start_mm);
    }
    p
}

/// The lengths the analysis of triangles uses, in proportion to the
/// campaign's largest triangle amplitude L: on a part (L = 4.5 mm, Table
/// B.2) they are [`PART_THRESHOLD_MM`], [`MIDLINE_STEP_MM`],
/// [`FILTER_START_MM`] and [`super::hysteresis::BIN_MM`]; on a specimen
/// in strain they shrink with its amplitudes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// Distance from the turning points past which the midline is the
    /// long-term backbone (L / 3).
    pub threshold_mm: f64,
    /// Spacing of the midline points (L / 90).
    pub step_mm: f64,
    /// Distance after a turning point the filtered curve needs (L / 30).
    pub filter_start_mm: f64,
    /// Width of the distance bins of the normalised curve (L / 225).
    pub bin_mm: f64,
}

/// The largest triangle amplitude of the part grids, mm.
pub const PART_LARGEST_MM: f64 = 4.5;

impl Scale {
    /// The lengths for a largest triangle amplitude `largest_mm`.
    pub fn of(largest_mm: f64) -> Self {
        let r = largest_mm / PART_LARGEST_MM;
        Self {
            threshold_mm: PART_THRESHOLD_MM * r,
            step_mm: MIDLINE_STEP_MM * r,
            filter_start_mm: FILTER_START_MM * r,
            bin_mm: super::hysteresis::BIN_MM * r,
        }
    }
}

/// Jenkins cells placed by the second stage (the seed's graphical
/// identification kept 3).
pub const JENKINS_CELLS: usize = 3;
/// Distance after a turning point the filtered curve needs to settle, mm.
pub const FILTER_START_MM: f64 = 0.15;

/// Spacing of the midline points, mm.
pub const MIDLINE_STEP_MM: f64 = 0.05;
/// Knots of the long-term backbone.
pub const LONG_TERM_KNOTS: usize = 9;

/// Five decimals for the tables (no "-0.00000").
fn g(v: f64) -> String {
    let r = (v * 1e5).round() / 1e5;
    format!("{:.5}", if r == 0.0 { 0.0 } else { r })
}

impl Preprocessed {
    /// Tests used.
    pub fn used(&self) -> usize {
        self.sines.len() + self.holds.len() + self.triangles.len() + self.others.len()
    }

    /// The report, `report.md`.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Pre-processing of the campaign \"{}\"\n", self.name);
        let _ = writeln!(
            s,
            "{} tests used ({} sines, {} multi-step, {} triangle, {} other); {} left out.\n",
            self.used(),
            self.sines.len(),
            self.holds.len(),
            self.triangles.len(),
            self.others.len(),
            self.excluded.len()
        );
        if !self.excluded.is_empty() {
            s.push_str("## Tests left out\n\n");
            let mut t = Table::new(["test", "reason"]);
            for e in &self.excluded {
                t.row([e.name.clone(), e.reason.to_string()]);
            }
            s.push_str(&t.finish());
            s.push('\n');
        }
        if !self.sines.is_empty() {
            s.push_str(
                "## Sines: first harmonic (last half of the whole periods)\n\n\
                 K′, K″ from the least-squares first harmonic of force over displacement; \
                 K_s = A_F / A_x (eq 3.5, peak-to-peak, eq 3.4); W_d = ∮ F dx per cycle \
                 (eq 3.2, trapezoid rule); W_d / (A_F A_x) as in eqs 3.3 and 3.7. \
                 Figures: `modulus-frequency.svg`, `modulus-amplitude.svg`.\n\n",
            );
            let mut t = Table::new([
                "test",
                "f [Hz]",
                "X [mm]",
                "preload [mm]",
                "K′ [N/mm]",
                "K″ [N/mm]",
                "loss factor",
                "K_s [N/mm]",
                "W_d [mJ]",
                "W_d/(A_F A_x)",
                "periods",
                "samples/period",
            ]);
            for (name, p) in &self.sines {
                t.row([
                    name.clone(),
                    g(p.frequency_hz),
                    g(p.amplitude_mm),
                    g(p.preload_mm),
                    g(p.storage),
                    g(p.loss),
                    g(p.loss_factor),
                    g(p.secant),
                    g(p.energy_per_cycle),
                    g(p.normalised_energy),
                    p.periods.to_string(),
                    format!("{:.1}", p.samples_per_period),
                ]);
            }
            s.push_str(&t.finish());
            s.push('\n');
        }
        if !self.holds.is_empty() {
            s.push_str(
                "## Multi-step holds\n\n\
                 The force at the start and at the end (mean over the last tenth) of each \
                 hold: the end points are the long-term backbone (eq 3.1's data). \
                 Figure: `relaxation.svg`.\n\n",
            );
            let mut t = Table::new(["test", "level [mm]", "hold [s]", "F start [N]", "F end [N]"]);
            for (name, hs) in &self.holds {
                for h in hs {
                    t.row([
                        name.clone(),
                        g(h.level_mm),
                        format!("{:.1}", h.duration_s),
                        g(h.force_start),
                        g(h.force_end),
                    ]);
                }
            }
            s.push_str(&t.finish());
            s.push('\n');
        }
        if !self.triangles.is_empty() {
            s.push_str(
                "## Triangles\n\n\
                 Branches cut at the turning points, each filtered apart (second-order \
                 Butterworth forward and backward, cutoff a tenth of the sampling rate, ends \
                 extended by odd reflection); the instantaneous modulus dF/dx against the \
                 distance to the branch's turning point (§3.4). Figure: \
                 `instantaneous-modulus.svg`.\n\n",
            );
            let mut t = Table::new([
                "test",
                "amplitude [mm]",
                "preload [mm]",
                "speed [mm/min]",
                "branches",
                "dF/dx after the turning point [N/mm]",
                "dF/dx at the branch end [N/mm]",
            ]);
            for (name, tr) in &self.triangles {
                let reversal = tr.branches.get(1).or(tr.branches.first());
                let first = reversal
                    .and_then(|b| b.modulus.first())
                    .map_or(f64::NAN, |m| m.1);
                let last = reversal
                    .and_then(|b| b.modulus.last())
                    .map_or(f64::NAN, |m| m.1);
                t.row([
                    name.clone(),
                    g(tr.amplitude_mm),
                    g(tr.preload_mm),
                    g(tr.speed_mm_per_min),
                    tr.branches.len().to_string(),
                    g(first),
                    g(last),
                ]);
            }
            s.push_str(&t.finish());
            s.push('\n');
        }
        if !self.midline.is_empty() {
            let _ = writeln!(
                s,
                "## Long-term backbone (first stage)\n\n\
                 The mean of each loading and unloading branch at the same displacement, \
                 farther than {} mm from their turning points (§3.4), keeps \
                 the long-term force g⁰ F^∞(x) alone: {} points over [{:.3}, {:.3}] mm. \
                 Figure: `long-term-backbone.svg`.\n",
                g(self.scale.threshold_mm),
                self.midline.len(),
                self.midline[0].0,
                self.midline[self.midline.len() - 1].0
            );
            match &self.long_term {
                Some((xs, fs)) => {
                    let mut t = Table::new(["knot x [mm]", "g⁰ F^∞ [N]"]);
                    for (x, f) in xs.iter().zip(fs) {
                        t.row([g(*x), g(*f)]);
                    }
                    s.push_str(&t.finish());
                    s.push('\n');
                }
                None => s.push_str("No knots: too few points, or forces that do not increase.\n\n"),
            }
        }
        if let Some(cells) = &self.jenkins {
            let _ = writeln!(
                s,
                "## Jenkins cells placed (second stage)\n\n\
                 The instantaneous modulus over the long-term modulus of the knots' spline at \
                 the same x, binned every {} mm, is a staircase `1 + Σ g_j / g⁰` whose steps \
                 sit where the cells slip; {JENKINS_CELLS} steps fitted by least squares \
                 (bins within {} mm of a turning point left out). On a linear \
                 backbone a cell slips at twice its slip distance x_f. Figure: \
                 `normalised-modulus.svg`.\n",
                g(self.scale.bin_mm),
                g(self.scale.filter_start_mm)
            );
            let mut t = Table::new(["slips at [mm]", "x_f on a linear backbone [mm]", "g_j / g⁰"]);
            for c in cells {
                t.row([g(c.distance_mm), g(0.5 * c.distance_mm), g(c.drop)]);
            }
            s.push_str(&t.finish());
            s.push('\n');
        }
        if !self.others.is_empty() {
            let _ = writeln!(
                s,
                "## Other tests\n\nKept whole for the time-domain fit: {}.\n",
                self.others.join(", ")
            );
        }
        s
    }

    /// The figures, by file name.
    pub fn figures(&self) -> Vec<(&'static str, String)> {
        let mut out = Vec::new();
        if !self.sines.is_empty() {
            out.push(("modulus-frequency.svg", render_panels(&self.by_frequency())));
            out.push(("modulus-amplitude.svg", render_panels(&self.by_amplitude())));
        }
        if !self.holds.is_empty() {
            let mut p = Plot::new(
                "Multi-step holds: force relaxing at each level",
                "time in the hold [s]",
                "force F [N]",
            );
            p.legend = Legend::Hidden;
            for (name, hs) in &self.holds {
                for h in hs {
                    p.series.push(Series::line(
                        format!("{name} {} mm", h.level_mm),
                        h.curve.clone(),
                    ));
                }
            }
            let mut ends = Plot::new(
                "Hold end points: the long-term backbone",
                "displacement x [mm]",
                "force at the end of the hold [N]",
            );
            for (name, hs) in &self.holds {
                ends.series.push(Series::markers(
                    name.clone(),
                    hs.iter().map(|h| (h.level_mm, h.force_end)).collect(),
                ));
            }
            out.push(("relaxation.svg", render_panels(&[p, ends])));
        }
        if !self.triangles.is_empty() {
            let mut p = Plot::new(
                "Instantaneous modulus after each turning point (§3.4)",
                "distance to the turning point [mm]",
                "dF/dx [N/mm]",
            );
            p.legend = Legend::Hidden;
            for (name, tr) in &self.triangles {
                for (i, b) in tr.branches.iter().enumerate().skip(1) {
                    p.series
                        .push(Series::line(format!("{name} #{i}"), b.modulus.clone()));
                }
            }
            out.push(("instantaneous-modulus.svg", render_panels(&[p])));
        }
        if !self.midline.is_empty() {
            let mut p = Plot::new(
                "Long-term backbone: the triangles' midline",
                "displacement x [mm]",
                "g0 F_inf [N]",
            );
            p.series
                .push(Series::markers("midline", self.midline.clone()));
            if let Some((xs, fs)) = &self.long_term {
                p.series.push(Series::line(
                    "knots",
                    xs.iter().copied().zip(fs.iter().copied()).collect(),
                ));
            }
            for (name, hs) in &self.holds {
                p.series.push(Series::markers(
                    format!("{name}: hold ends"),
                    hs.iter().map(|h| (h.level_mm, h.force_end)).collect(),
                ));
            }
            out.push(("long-term-backbone.svg", render_panels(&[p])));
        }
        if !self.normalised.is_empty() {
            let mut p = Plot::new(
                "Instantaneous modulus over the long-term modulus (§3.4)",
                "distance to the turning point [mm]",
                "K_inst / (g0 K_inf)",
            );
            p.series.push(Series::markers(
                "binned curve",
                self.normalised.iter().map(|b| (b.0, b.1)).collect(),
            ));
            if let Some(cells) = &self.jenkins {
                // The fitted staircase: 1 + the drops still to come.
                let end = self.normalised.last().map_or(0.0, |b| b.0);
                let mut level: f64 = 1.0 + cells.iter().map(|c| c.drop).sum::<f64>();
                let mut stairs = vec![(0.0, level)];
                for c in cells {
                    stairs.push((c.distance_mm, level));
                    level -= c.drop;
                    stairs.push((c.distance_mm, level));
                }
                stairs.push((end, level));
                p.series.push(Series::line("placed cells", stairs));
            }
            out.push(("normalised-modulus.svg", render_panels(&[p])));
        }
        out
    }

    /// The sines of the lowest preload, one series per amplitude.
    fn groups<K: Ord + Copy>(&self, key: impl Fn(&SinePoint) -> K) -> BTreeMap<K, Vec<SinePoint>> {
        let lowest = self
            .sines
            .iter()
            .map(|(_, p)| p.preload_mm)
            .fold(f64::INFINITY, f64::min);
        let mut groups: BTreeMap<K, Vec<SinePoint>> = BTreeMap::new();
        for (_, p) in &self.sines {
            if (p.preload_mm - lowest).abs() <= 0.05 * p.amplitude_mm.max(1e-3) {
                groups.entry(key(p)).or_default().push(*p);
            }
        }
        groups
    }

    fn by_frequency(&self) -> Vec<Plot> {
        // Amplitudes grouped to 3 significant digits.
        let groups = self.groups(|p| (p.amplitude_mm * 1e3).round() as i64);
        let panel = |title: &str, y: &str, value: fn(&SinePoint) -> f64| {
            let mut plot = Plot::new(title, "frequency f [Hz]", y);
            plot.x_log = true;
            for (a, points) in &groups {
                let mut pts: Vec<(f64, f64)> =
                    points.iter().map(|p| (p.frequency_hz, value(p))).collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                plot.series
                    .push(Series::markers(format!("{} mm", *a as f64 / 1e3), pts));
            }
            plot
        };
        vec![
            panel(
                "Storage modulus K′ against frequency",
                "K′ [N/mm]",
                |p| p.storage,
            ),
            panel("Loss modulus K″ against frequency", "K″ [N/mm]", |p| {
                p.loss
            }),
            panel("Loss factor against frequency", "K″ / K′", |p| {
                p.loss_factor
            }),
        ]
    }

    fn by_amplitude(&self) -> Vec<Plot> {
        let groups = self.groups(|p| (p.frequency_hz * 1e3).round() as i64);
        let panel = |title: &str, y: &str, value: fn(&SinePoint) -> f64| {
            let mut plot = Plot::new(title, "amplitude X [mm]", y);
            plot.x_log = true;
            for (f, points) in &groups {
                let mut pts: Vec<(f64, f64)> =
                    points.iter().map(|p| (p.amplitude_mm, value(p))).collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                plot.series
                    .push(Series::markers(format!("{} Hz", *f as f64 / 1e3), pts));
            }
            plot
        };
        vec![
            panel(
                "Secant modulus against amplitude (eq 3.5)",
                "K_s [N/mm]",
                |p| p.secant,
            ),
            panel("Loss factor against amplitude", "K″ / K′", |p| {
                p.loss_factor
            }),
        ]
    }

    /// Writes `report.md` and the figures into `out`.
    pub fn write(&self, out: &mut Staged) -> Result<(), OutputError> {
        out.write("report.md", self.markdown().as_bytes())?;
        for (name, svg) in self.figures() {
            out.write(name, svg.as_bytes())?;
        }
        Ok(())
    }
}
