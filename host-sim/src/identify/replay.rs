//! A test replayed on a candidate model, as the time-domain refinement
//! and the predictions of held-out tests need it: the record's
//! displacement imposed sample by sample on the core's own `step` in f64,
//! from rest at 0 mm.
//!
//! - **Irregular sampling.** The core's models are fixed-step: a model is
//!   built for each distinct interval of the record (intervals equal to
//!   0.1 % share one model), and a step uses the model of its interval.
//!   Every state is plain data that does not depend on the step, so the
//!   models hand it on. Between two samples the displacement is a ramp,
//!   which the exact-ramp forms integrate exactly.
//! - **Lead-in.** Every replay starts from rest at 0 mm. A record that
//!   starts elsewhere (a preload) is reached as the machine reaches it
//!   (seed 000 §3.2.3): a 20 s ramp, then the test's preload hold
//!   (`preload_hold_s` in `campaign.toml`, the seed's 20 minutes by
//!   default), see [`preload_steps`]. A sine was recorded in its steady
//!   cycle after sweeps the record does not hold: its replay runs the
//!   record's whole periods for at least 2 s ([`lead_passes`]) and is
//!   scored on the pass after. The first
//!   sample is reached in one step of the first interval. Generated
//!   campaigns (`synth`) are made with the same lead-in, so the model that
//!   made a campaign replays it exactly.

use bushing::ParamError;

use super::campaign::{Kind, MAX_PRELOAD_HOLD_S, Test, TestError};
use crate::family::Effect;
use crate::family::backbone::BackboneSpec;
use crate::model::{SceneBushing, build_parts};

/// Most distinct intervals a record may have (to 0.1 %).
pub const MAX_INTERVALS: usize = 64;
/// A step list's entry that does not step: the force is read as it is.
const READ: u8 = u8::MAX;
/// Shortest unrecorded lead-in of a sine before its record, s: the
/// machine's sweep at one frequency (Fig. 3.3) runs for seconds before a
/// step is recorded.
pub const SINE_LEAD_S: f64 = 2.0;
/// Most passes of a sine record in its lead-in.
const MAX_LEAD_PASSES: usize = 1000;

/// Unrecorded passes of a sine record of `record_s` seconds before it is
/// recorded: enough whole passes for [`SINE_LEAD_S`], at least one. The
/// one rule of replays and of generated campaigns.
pub fn lead_passes(record_s: f64) -> usize {
    let n = (SINE_LEAD_S / record_s).ceil();
    if n.is_finite() && n >= 1.0 {
        (n as usize).min(MAX_LEAD_PASSES)
    } else {
        1
    }
}
/// Ramp from rest to a record's preload, s (the multi-step ramp of
/// §3.2.3).
pub const PRELOAD_RAMP_S: f64 = 20.0;
/// Step of the ramp to the preload, s.
const PRELOAD_DT: f64 = 0.05;
/// Longest step of the hold at the preload, s: the displacement is
/// constant, and every cell's decay over a hold is exact at any step.
const HOLD_DT: f64 = 1.0;

/// The steps `(dt s, x mm)` that take a model from rest at 0 mm to a
/// record's first displacement `x0` and hold it there `hold_s` before the
/// record (none when `x0` is 0): a ramp of [`PRELOAD_RAMP_S`] in steps of
/// 0.05 s, then the hold in equal steps of at most 1 s. The one lead-in of
/// replays and of generated campaigns. `hold_s` is clamped to
/// [0, [`MAX_PRELOAD_HOLD_S`]].
pub fn preload_steps(x0: f64, hold_s: f64) -> Vec<(f64, f64)> {
    if x0 == 0.0 {
        return Vec::new();
    }
    let n = (PRELOAD_RAMP_S / PRELOAD_DT).round() as usize;
    let hold_s = if hold_s.is_finite() {
        hold_s.clamp(0.0, MAX_PRELOAD_HOLD_S)
    } else {
        0.0
    };
    let holds = (hold_s / HOLD_DT).ceil() as usize;
    let mut steps: Vec<(f64, f64)> = (1..=n)
        .map(|k| (PRELOAD_DT, x0 * k as f64 / n as f64))
        .collect();
    if holds > 0 {
        let dt = hold_s / holds as f64;
        steps.extend((0..holds).map(|_| (dt, x0)));
    }
    steps
}

/// A test ready to replay.
#[derive(Debug, Clone, PartialEq)]
pub struct Drive {
    /// The test's name.
    pub name: String,
    /// Its kind.
    pub kind: Kind,
    /// The distinct intervals, s.
    dts: Vec<f64>,
    /// Each step: the index of its interval ([`READ`]: no step), the
    /// displacement it reaches (mm), and whether that is a sample of the
    /// record.
    steps: Vec<(u8, f64, bool)>,
    /// The step that reaches the record's first sample on the scored pass.
    scored_from: usize,
    /// The record's samples.
    pub samples: usize,
}

/// Why a record cannot be replayed.
fn irregular(n: usize) -> TestError {
    TestError::Check(format!(
        "more than {MAX_INTERVALS} distinct sampling intervals (to 0.1 %) ({n} or more): \
         resample the record onto fewer steps"
    ))
}

impl Drive {
    /// The replay of `test`.
    pub fn new(test: &Test) -> Result<Self, TestError> {
        let r = &test.record;
        if r.len() < 2 {
            return Err(TestError::Check(format!(
                "{} samples: nothing to replay",
                r.len()
            )));
        }
        let mut d = Self {
            name: test.name.clone(),
            kind: test.kind,
            dts: Vec::new(),
            steps: Vec::with_capacity(2 * r.len()),
            scored_from: 0,
            samples: r.len(),
        };
        let peaks = if test.kind == Kind::Triangle {
            turning_points(&r.time, &r.x)
        } else {
            Vec::new()
        };
        // Samples 1 on, each reached from the one before.
        let mut pass = Vec::with_capacity(r.len() + peaks.len());
        for (i, (w, &x)) in r.time.windows(2).zip(&r.x[1..]).enumerate() {
            let dt = w[1] - w[0];
            match peaks.iter().find(|p| p.before == i + 1) {
                Some(p) => {
                    pass.push((d.interval(dt * p.share)?, p.x, false));
                    pass.push((d.interval(dt * (1.0 - p.share))?, x, true));
                }
                None => pass.push((d.interval(dt)?, x, true)),
            }
        }
        for (dt, x) in preload_steps(r.x[0], test.preload_hold_s) {
            let i = d.interval(dt)?;
            d.steps.push((i, x, false));
        }
        // The lead-in ends at sample 0 (rest at 0 mm, or the preload).
        let read_first = (READ, r.x[0], true);
        if test.kind == Kind::Sine {
            // A record of whole periods that ends where it began: its last
            // sample is its first of the next period. Otherwise sample 0
            // is reached in one step of the first interval.
            let (lo, hi) = super::extremes(&r.x);
            let closes = (r.x[r.len() - 1] - r.x[0]).abs() <= 1e-9 * (hi - lo);
            let wrap = if closes {
                READ
            } else {
                d.interval(r.time[1] - r.time[0])?
            };
            let record_s = r.time[r.len() - 1] - r.time[0];
            for _ in 0..lead_passes(record_s) {
                d.steps.extend_from_slice(&pass);
                d.steps.push((wrap, r.x[0], false));
            }
            d.scored_from = d.steps.len() - 1;
            if let Some(last) = d.steps.last_mut() {
                last.2 = true;
            }
        } else {
            d.scored_from = d.steps.len();
            d.steps.push(read_first);
        }
        d.steps.extend_from_slice(&pass);
        Ok(d)
    }

    /// The index of the model for interval `dt`, added if new.
    fn interval(&mut self, dt: f64) -> Result<u8, TestError> {
        let key = |v: f64| (v.ln() * 1e3).round();
        let i = match self.dts.iter().position(|&v| key(v) == key(dt)) {
            Some(i) => i,
            None => {
                if self.dts.len() >= MAX_INTERVALS {
                    return Err(irregular(self.dts.len() + 1));
                }
                self.dts.push(dt);
                self.dts.len() - 1
            }
        };
        u8::try_from(i).map_err(|_| irregular(i))
    }

    /// Model steps per replay (lead-in included).
    pub fn steps(&self) -> usize {
        self.steps.len()
    }

    /// The model's force at each of the record's samples, or `None` when
    /// the model refuses a step (its force left the guard).
    pub fn run(&self, model: &Model) -> Result<Option<Vec<f64>>, ParamError> {
        let bushings: Vec<SceneBushing<f64>> = self
            .dts
            .iter()
            .map(|&dt| model.build(dt))
            .collect::<Result<_, _>>()?;
        let Some(first) = bushings.first() else {
            return Ok(None);
        };
        let mut state = first.state_at(0.0);
        let mut forces = Vec::with_capacity(self.samples);
        for (n, &(i, x, sample)) in self.steps.iter().enumerate() {
            let force = if i == READ {
                state.force()
            } else {
                let Some(b) = bushings.get(usize::from(i)) else {
                    return Ok(None);
                };
                let out = b.step(&mut state, x);
                if out.effects.is_none() {
                    return Ok(None);
                }
                out.force
            };
            if n >= self.scored_from && sample {
                forces.push(force);
            }
        }
        Ok(Some(forces))
    }
}

/// A turning point of a triangle record between two samples.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Peak {
    /// The sample it comes before.
    before: usize,
    /// Where it falls in the interval, in sixteenths (1 to 15).
    share: f64,
    /// Its displacement, mm.
    x: f64,
}

/// The turning points of a constant-speed record that fall between
/// samples: where the line through the two samples before a reversal
/// meets the line through the two after it, placed on the nearest
/// sixteenth of its interval (so a record has at most 30 more intervals).
/// A record at a few samples per millimetre misses most of its turning
/// points, and a replay through the samples alone would cut every corner
/// of every hysteresis loop.
fn turning_points(t: &[f64], x: &[f64]) -> Vec<Peak> {
    let mut out = Vec::new();
    for i in 2..x.len().saturating_sub(2) {
        let (a, b) = (x[i] - x[i - 1], x[i + 1] - x[i]);
        if a * b >= 0.0 || (a * b).is_nan() {
            continue;
        }
        let s1 = (x[i - 1] - x[i - 2]) / (t[i - 1] - t[i - 2]);
        let s2 = (x[i + 2] - x[i + 1]) / (t[i + 2] - t[i + 1]);
        if s1 * s2 >= 0.0 || (s1 * s2).is_nan() {
            continue;
        }
        let tp = (x[i + 1] - x[i - 1] + s1 * t[i - 1] - s2 * t[i + 1]) / (s1 - s2);
        // In the interval before sample i or in the one after it.
        let (before, t0) = if tp < t[i] {
            (i, t[i - 1])
        } else {
            (i + 1, t[i])
        };
        let dt = t[before] - t0;
        let k = ((tp - t0) / dt * 16.0).round();
        if !(1.0..=15.0).contains(&k) {
            continue;
        }
        let share = k / 16.0;
        let tq = t0 + share * dt;
        let xp = if tp < t[i] {
            x[i - 1] + s1 * (tq - t[i - 1])
        } else {
            x[i + 1] + s2 * (tq - t[i + 1])
        };
        out.push(Peak {
            before,
            share,
            x: xp,
        });
    }
    out
}

/// A model to replay: a backbone and effects, built at any step.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// F^∞(x).
    pub backbone: BackboneSpec,
    /// The effects, checked.
    pub effects: Vec<Effect>,
}

impl Model {
    /// The bushing in f64 at time step `dt` (s).
    pub fn build(&self, dt: f64) -> Result<SceneBushing<f64>, ParamError> {
        build_parts(&self.backbone, &self.effects, dt)
    }
}
