//! The identification as one call ([`identify`]): the campaign
//! pre-processed, the stages, the joint refinement, the identifiability of
//! each parameter, and every test replayed on the result, fitted or held
//! out ([`predict`]), with the thesis's objectives beside the time-domain
//! error: the energy dissipated per cycle and the secant modulus of each
//! sine (eqs 3.2-3.8), and the end force of each relaxation hold (eq 3.1).

use super::campaign::{Campaign, Kind, Test, TestError};
use super::class::{Candidate, ModelClass};
use super::export;
use super::joint::{Bounds, Refined, Scored, refine};
use super::relax::holds;
use super::replay::{Drive, Model};
use super::report::{Preprocessed, preprocess};
use super::sine::{SinePoint, first_harmonic, model_harmonic};
use super::stages::{StageError, Stages, stages};

/// A test replayed on the identified model.
#[derive(Debug, Clone, PartialEq)]
pub struct TestFit {
    /// The test's name.
    pub name: String,
    /// Its kind.
    pub kind: Kind,
    /// Its record: times (s), displacements (mm) and forces (N).
    pub time: Vec<f64>,
    /// Displacements, mm.
    pub x: Vec<f64>,
    /// Measured forces, N.
    pub measured: Vec<f64>,
    /// The model's forces, N.
    pub model: Vec<f64>,
    /// RMS force error over the test's force range.
    pub rms: f64,
    /// For a sine: its first harmonic measured and on the model.
    pub sine: Option<(SinePoint, SinePoint)>,
    /// For a multi-step test: the largest error of a hold's end force over
    /// the test's force range (eq 3.1).
    pub hold_ends: Option<f64>,
}

impl TestFit {
    /// Relative error of a sine quantity, model against measured.
    pub fn sine_error(&self, value: fn(&SinePoint) -> f64) -> Option<f64> {
        self.sine
            .as_ref()
            .map(|(m, p)| (value(p) - value(m)) / value(m))
    }
}

/// The result of an identification.
#[derive(Debug, Clone)]
pub struct Identification {
    /// The class identified.
    pub class: ModelClass,
    /// The fitted tests pre-processed.
    pub pre: Preprocessed,
    /// The stages' findings and starting model.
    pub stages: Stages,
    /// The refinement and the parameters' spreads.
    pub refined: Refined,
    /// The fitted tests replayed on the refined model.
    pub fitted: Vec<TestFit>,
    /// The held-out tests predicted by it.
    pub held_out: Vec<TestFit>,
    /// Tests that could not be replayed, with the reason.
    pub unreplayed: Vec<(String, String)>,
    /// `model.toml`: the refined model as written, which every replay
    /// reads back.
    pub model_toml: String,
}

impl Identification {
    /// The identified model.
    pub fn model(&self) -> &Candidate {
        &self.refined.model
    }
}

/// Why no model was identified.
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    /// `--hold-out` names a test the campaign does not have.
    #[error("--hold-out {0}: the campaign has no usable test of that name")]
    UnknownHoldOut(String),
    /// No test left to fit.
    #[error("no test is left to fit ({0} held out, {1} left out by the checks)")]
    NothingToFit(usize, usize),
    /// A stage could not start.
    #[error(transparent)]
    Stage(#[from] StageError),
    /// The written model does not read back (a bug, reported rather than
    /// written).
    #[error("the identified model does not read back as a scene: {0}")]
    Written(String),
}

/// Identifies a model of `class` from `campaign`, keeping the tests named
/// in `hold_out` out of the fit and predicting them.
pub fn identify(
    campaign: &Campaign,
    class: &ModelClass,
    hold_out: &[String],
) -> Result<Identification, IdentifyError> {
    for name in hold_out {
        if !campaign.tests.iter().any(|t| &t.name == name) {
            return Err(IdentifyError::UnknownHoldOut(name.clone()));
        }
    }
    let (kept, held): (Vec<Test>, Vec<Test>) = campaign
        .tests
        .iter()
        .cloned()
        .partition(|t| !hold_out.contains(&t.name));
    let fit_campaign = Campaign {
        tests: kept,
        ..campaign.clone()
    };
    let pre = preprocess(&fit_campaign);
    let used: Vec<&Test> = fit_campaign
        .tests
        .iter()
        .filter(|t| !pre.excluded.iter().any(|e| e.name == t.name))
        .collect();
    if used.is_empty() {
        return Err(IdentifyError::NothingToFit(held.len(), pre.excluded.len()));
    }
    let stages = stages(&fit_campaign, &pre, class)?;
    let mut unreplayed = Vec::new();
    let mut scored = Vec::new();
    for t in &used {
        match Scored::of(t) {
            Ok(s) => scored.push(s),
            Err(e) => unreplayed.push((t.name.clone(), e.to_string())),
        }
    }
    let (f_lo, f_hi) = pre
        .sines
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), (_, s)| {
            (lo.min(s.frequency_hz), hi.max(s.frequency_hz))
        });
    let bounds = if f_lo <= f_hi {
        Bounds::tested(f_lo, f_hi)
    } else {
        // No sine: the holds and ramps see 0.001 to 10 Hz.
        Bounds::tested(0.1, 1.0)
    };
    let refined = refine(&stages.initial, &scored, bounds);
    let model_toml = export::toml(&refined.model, &campaign.name, export::demo(&pre));
    let scene = crate::scene::Scene::parse("model.toml", &model_toml)
        .map_err(|e| IdentifyError::Written(e.to_string()))?;
    let model = Model {
        backbone: scene.backbone.clone(),
        effects: scene.effects().to_vec(),
    };
    let mut replay = |tests: &[&Test]| {
        let mut out = Vec::new();
        for t in tests {
            match predict(&model, t) {
                Ok(f) => out.push(f),
                Err(e) => unreplayed.push((t.name.clone(), e.to_string())),
            }
        }
        out
    };
    let fitted = replay(&used);
    let held_refs: Vec<&Test> = held.iter().collect();
    let held_out = replay(&held_refs);
    let mut refined = refined;
    rules(&mut refined, &pre);
    Ok(Identification {
        class: *class,
        pre,
        stages,
        refined,
        fitted,
        held_out,
        unreplayed,
        model_toml,
    })
}

/// What the campaign cannot determine by construction, named whatever the
/// Jacobian says: a Maxwell cell above the highest tested frequency (or
/// below the lowest with no relaxation test), a Jenkins cell whose slip
/// distance is below the smallest tested amplitude.
fn rules(refined: &mut Refined, pre: &Preprocessed) {
    let model = &refined.model;
    let (f_lo, f_hi) = pre
        .sines
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), (_, s)| {
            (lo.min(s.frequency_hz), hi.max(s.frequency_hz))
        });
    let smallest = pre
        .sines
        .iter()
        .map(|(_, s)| s.amplitude_mm)
        .chain(pre.triangles.iter().map(|(_, t)| t.amplitude_mm))
        .fold(f64::INFINITY, f64::min);
    let relaxation = !pre.holds.is_empty();
    let k0 = model.k_at_rest();
    let params = model.params();
    for (p, s) in params.iter().zip(refined.spreads.iter_mut()) {
        let index = |prefix: &str| {
            p.name
                .strip_prefix(prefix)
                .and_then(|r| r.split(']').next())
                .and_then(|i| i.parse::<usize>().ok())
        };
        let why = if let Some(i) = index("maxwell[") {
            let f = model.maxwell[i].omega / std::f64::consts::TAU;
            if f > f_hi {
                Some(format!(
                    "the cell's corner {f:.3} Hz is above the highest tested frequency ({f_hi} Hz)"
                ))
            } else if f < f_lo && !relaxation {
                Some(format!(
                    "the cell's corner {f:.3} Hz is below the lowest tested frequency ({f_lo} Hz) \
                     and no relaxation test was fitted"
                ))
            } else {
                None
            }
        } else if let Some(j) = index("iwan[") {
            let c = model.jenkins[j];
            let slip = c.slip_force / (c.g * k0);
            (slip < smallest).then(|| {
                format!(
                    "the cell's slip distance {slip:.4} mm is below the smallest tested \
                     amplitude ({smallest} mm)"
                )
            })
        } else {
            None
        };
        if why.is_some() {
            s.undetermined = why;
        }
    }
}

/// `test` replayed on `model`, with its errors.
pub fn predict(model: &Model, test: &Test) -> Result<TestFit, TestError> {
    let forces = Drive::new(test)?
        .run(model)
        .map_err(|e| TestError::Check(format!("the model cannot be built: {e}")))?
        .ok_or_else(|| TestError::Check("the model refused a step of the record".into()))?;
    let r = &test.record;
    let (lo, hi) = super::extremes(&r.force);
    let range = (hi - lo).max(1e-12);
    let n = forces.len().max(1) as f64;
    let rms = (forces
        .iter()
        .zip(&r.force)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / n)
        .sqrt()
        / range;
    let mut on_model = test.clone();
    on_model.record.force = forces.clone();
    let sine = (test.kind == Kind::Sine)
        .then(|| {
            first_harmonic(test)
                .ok()
                .zip(model_harmonic(&on_model).ok())
        })
        .flatten();
    let hold_ends = (test.kind == Kind::MultiStep)
        .then(|| {
            let (m, p) = (holds(test).ok()?, holds(&on_model).ok()?);
            Some(
                m.iter()
                    .zip(&p)
                    .map(|(a, b)| (a.force_end - b.force_end).abs() / range)
                    .fold(0.0, f64::max),
            )
        })
        .flatten();
    Ok(TestFit {
        name: test.name.clone(),
        kind: test.kind,
        time: r.time.clone(),
        x: r.x.clone(),
        measured: r.force.clone(),
        model: forces,
        rms,
        sine,
        hold_ends,
    })
}
