//! `cost`: what a scene costs per step against the sum of its parts.
//!
//! The scene is stepped as `run` steps it (its profile, its number type,
//! stepping only: the inputs are computed beforehand), reading what a
//! control loop reads (force, tangent and dissipated energy). Each part is
//! timed the same way on its own:
//!
//! - the backbone alone: the scene compiled without its effects
//!   (`Bushing<_, _, ()>`);
//! - each effect: the scene compiled with that effect only
//!   (`Bushing<_, _, (E,)>`), minus the backbone alone, so that the effect
//!   sees exactly the drive it sees in the scene;
//! - for comparison (not in the sum): a scene of one effect also as the
//!   general effect list of `model::build`, and a Maxwell effect of at
//!   most 8 cells as the const-size [`bushing::MaxwellBank`] firmware would use.
//!
//! Profiles shorter than [`CostOptions::min_steps`] are repeated to that
//! length; each figure is the best of [`CostOptions::repetitions`]
//! interleaved passes.
//!
//! **How a scene is held.** `model::compile` picks the shape once, at
//! build time: a scene of one effect runs as that effect's own bushing
//! type, its loop monomorphised, so it costs what its parts cost; two or
//! more effects run as a list, one match per effect and step. The drivers
//! (`run`, `validate`, `cost`) dispatch once per chunk of steps, never per
//! step. The run-time sized banks (`family::maxwell::DynMaxwell`) loop over a slice
//! of unknown length, which the compiler does not unroll; the const-size
//! line shows what firmware pays for the same cells (about half).
//!
//! `cost --instructions` counts host instructions instead, with the
//! [`callgrind`] harness that the accuracy-cost report uses too.

pub mod callgrind;
pub mod timer;

use std::fmt;
use std::hint::black_box;
use std::path::Path;

use bushing::{ParamError, Real};

use crate::family::Effect as EffectDesc;
use crate::model::{self, SceneBushing, Shape};
use crate::scene::{BackboneSpec, NumberType, Scene, SceneError};
use timer::{STEPPING, Timer, per_step, timer};

/// Why a scene could not be costed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene file could not be read.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene, or one of the parts made from it, refused its
    /// parameters.
    #[error("{what}: {source}")]
    Param {
        /// Which model was being built.
        what: String,
        /// What it refused.
        source: ParamError,
    },
    /// A part index past the scene's plan (the hidden `cost-part`
    /// command).
    #[error("no part {part} (the scene has {len})")]
    NoPart {
        /// The part asked for.
        part: usize,
        /// How many parts the plan has.
        len: usize,
    },
    /// Counting under callgrind failed.
    #[error(transparent)]
    Callgrind(#[from] callgrind::Error),
    /// Callgrind wrote no dump for a part.
    #[error("part {part}: callgrind wrote no dump")]
    NoDump {
        /// The part.
        part: usize,
    },
    /// Callgrind counted nothing in the stepping function.
    #[error("part {part}: no instruction counted in {STEPPING}")]
    NothingCounted {
        /// The part.
        part: usize,
    },
}

/// An [`Error::Param`] naming `what`.
fn refused(what: impl Into<String>) -> impl FnOnce(ParamError) -> Error {
    move |source| Error::Param {
        what: what.into(),
        source,
    }
}

/// How long to time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CostOptions {
    /// Fewest steps per timed pass (shorter profiles are repeated).
    pub min_steps: usize,
    /// Most steps per timed pass (longer profiles are cut).
    pub max_steps: usize,
    /// Passes per figure, the best kept.
    pub repetitions: usize,
}

impl Default for CostOptions {
    /// A million steps per pass, best of 11.
    fn default() -> Self {
        Self {
            min_steps: 1_000_000,
            max_steps: 4_000_000,
            repetitions: 11,
        }
    }
}

/// What a figure counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// Host wall clock, best of several passes: ns per step.
    WallClock,
    /// Host instructions counted by valgrind's callgrind in the stepping
    /// function only: instructions per step, the same on every run of the
    /// same binary.
    Instructions,
}

impl Measure {
    /// Unit of the figures.
    pub fn unit(self) -> &'static str {
        match self {
            Self::WallClock => "ns/step",
            Self::Instructions => "instr/step",
        }
    }
}

/// One measured part.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// What it is.
    pub name: String,
    /// Cost per step, in the report's [`Measure`].
    pub ns_per_step: f64,
}

/// What `cost` measured.
#[derive(Debug, Clone, PartialEq)]
pub struct CostReport {
    /// What the figures count.
    pub measure: Measure,
    /// Working type.
    pub number: NumberType,
    /// Steps per timed pass.
    pub steps: usize,
    /// Passes per figure.
    pub repetitions: usize,
    /// The backbone alone, then each effect (with the backbone subtracted).
    pub parts: Vec<Part>,
    /// The whole scene.
    pub scene_ns: f64,
    /// How the scene's effects are held ([`model::SceneModel::shape`]).
    pub shape: Shape,
    /// Other ways to hold the same effects, for comparison (not in the
    /// sum): the whole scene as an effect list, and const-size Maxwell
    /// banks (effect only, the backbone subtracted).
    pub comparisons: Vec<Part>,
}

impl CostReport {
    /// Sum of the parts, ns per step.
    pub fn sum(&self) -> f64 {
        self.parts.iter().map(|p| p.ns_per_step).sum()
    }
    /// Scene over the sum of its parts.
    pub fn ratio(&self) -> f64 {
        self.scene_ns / self.sum()
    }
}

impl fmt::Display for CostReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let number = self.number.name();
        match self.measure {
            Measure::WallClock => writeln!(
                f,
                "cost per step, {number}, {} steps per pass, best of {} passes (host wall clock, stepping only)",
                self.steps, self.repetitions
            )?,
            Measure::Instructions => writeln!(
                f,
                "cost per step, {number}, {} steps (host instructions counted by callgrind, stepping only)",
                self.steps
            )?,
        }
        let unit = self.measure.unit();
        for p in &self.parts {
            writeln!(f, "part  {:<48} {:>9.2} {unit}", p.name, p.ns_per_step)?;
        }
        writeln!(f, "sum of parts {:<41} {:>9.2} {unit}", "", self.sum())?;
        let scene = format!("scene ({})", self.shape.name());
        writeln!(f, "{scene:<54} {:>9.2} {unit}", self.scene_ns)?;
        writeln!(f, "ratio scene / sum of parts {:>36.3}", self.ratio())?;
        for p in &self.comparisons {
            writeln!(f, "for comparison: {}", p.name)?;
            writeln!(f, "{:<54} {:>9.2} {unit}", "", p.ns_per_step)?;
        }
        Ok(())
    }
}

/// Times `scene` and its parts with the default [`CostOptions`].
pub fn cost(scene: &Scene) -> Result<CostReport, Error> {
    cost_with(scene, CostOptions::default())
}

/// Times `scene` and its parts.
pub fn cost_with(scene: &Scene, options: CostOptions) -> Result<CostReport, Error> {
    match scene.number {
        NumberType::F32 => cost_typed::<f32>(scene, options),
        NumberType::F64 => cost_typed::<f64>(scene, options),
    }
}

/// The hidden command that steps one part under callgrind:
/// `PART_COMMAND SCENE.toml PART STEPS` ([`run_part_of`]).
pub const PART_COMMAND: &str = "cost-part";

/// Measures `scene` and its parts by host instructions: each part is
/// stepped `steps` times in a child process (this program's hidden
/// [`PART_COMMAND`], reading `scene_file`) under valgrind's callgrind,
/// counting only the stepping function. Needs `valgrind` on the path.
pub fn cost_instructions(
    scene_file: &Path,
    scene: &Scene,
    steps: usize,
) -> Result<CostReport, Error> {
    let plan = match scene.number {
        NumberType::F32 => plan::<f32>(scene)?.layout,
        NumberType::F64 => plan::<f64>(scene)?.layout,
    };
    let mut counts = Vec::with_capacity(plan.len);
    for part in 0..plan.len {
        let args = [
            PART_COMMAND.into(),
            scene_file.as_os_str().to_owned(),
            part.to_string().into(),
            steps.to_string().into(),
        ];
        let counted = callgrind::count(&args, STEPPING, None)?;
        let total = *counted.totals.first().ok_or(Error::NoDump { part })?;
        if total == 0 {
            return Err(Error::NothingCounted { part });
        }
        counts.push(total as f64 / steps.max(1) as f64);
    }
    Ok(plan.report(scene, Measure::Instructions, steps, 1, &counts))
}

/// The hidden [`PART_COMMAND`]: steps part `part` of `scene`'s plan over
/// `steps` steps of its profile (the child process of
/// [`cost_instructions`]).
pub fn run_part(scene: &Scene, part: usize, steps: usize) -> Result<(), Error> {
    fn go<T: Real + 'static>(scene: &Scene, part: usize, steps: usize) -> Result<(), Error> {
        let plan = plan::<T>(scene)?;
        let (inputs, x0) = inputs::<T>(scene, steps, steps);
        let timer = plan.timers.get(part).ok_or(Error::NoPart {
            part,
            len: plan.layout.len,
        })?;
        black_box(timer(&inputs, x0));
        Ok(())
    }
    match scene.number {
        NumberType::F32 => go::<f32>(scene, part, steps),
        NumberType::F64 => go::<f64>(scene, part, steps),
    }
}

/// [`run_part`] on the scene read from `scene_file`: the whole
/// [`PART_COMMAND`].
pub fn run_part_of(scene_file: &Path, part: usize, steps: usize) -> Result<(), Error> {
    run_part(&Scene::load(scene_file)?, part, steps)
}

/// The scene `scene` with the effects at `keep` only, compiled as `run`
/// compiles it (from the models the scene built).
fn compiled<T: Real + 'static>(scene: &Scene, keep: &[usize]) -> Result<Timer<T>, Error> {
    let sub = scene.only(keep);
    let what = match sub.effects() {
        [] => "the scene's backbone alone".to_string(),
        [one] if scene.effects().len() > 1 => format!("the scene with {} only", one.name()),
        _ => "the scene".to_string(),
    };
    let model = model::compile::<T>(&sub).map_err(refused(what))?;
    Ok(Box::new(move |inputs, x0| {
        per_step(model.time_steps(inputs, x0), inputs)
    }))
}

/// The profile's inputs, `min_steps` to `max_steps` of them (a short
/// profile repeated), and the start displacement.
fn inputs<T: Real>(scene: &Scene, min_steps: usize, max_steps: usize) -> (Vec<T>, T) {
    let steps = (scene.steps() as usize).clamp(1, max_steps.max(1));
    let profile: Vec<T> = (1..=steps)
        .map(|i| T::from_f64(scene.input(i as f64 * scene.dt)))
        .collect();
    let inputs = profile
        .iter()
        .copied()
        .cycle()
        .take(steps.max(min_steps))
        .collect();
    (inputs, T::from_f64(scene.input(0.0)))
}

/// What is measured, in order: the scene, the backbone alone, each effect
/// alone, then the comparisons.
struct Layout {
    len: usize,
    backbone: String,
    effects: Vec<String>,
    shape: Shape,
    /// (name, whether the backbone alone is subtracted)
    comparisons: Vec<(String, bool)>,
}

struct Plan<T> {
    timers: Vec<Timer<T>>,
    layout: Layout,
}

fn plan<T: Real + 'static>(scene: &Scene) -> Result<Plan<T>, Error> {
    let shape = model::compile::<T>(scene)
        .map_err(refused("the scene"))?
        .shape();
    let all: Vec<usize> = (0..scene.effects().len()).collect();
    let mut timers: Vec<Timer<T>> = vec![compiled(scene, &all)?, compiled(scene, &[])?];
    for j in &all {
        timers.push(compiled(scene, std::slice::from_ref(j))?);
    }
    let mut comparisons = Vec::new();
    if shape == Shape::One {
        let list: SceneBushing<T> =
            model::build(scene).map_err(refused("the scene as an effect list"))?;
        comparisons.push((
            "the whole scene as an effect list (model::build)".to_string(),
            false,
        ));
        timers.push(timer(list));
    }
    let built = scene.built::<T>().map_err(refused("the scene"))?;
    for effect in scene.effects() {
        if let EffectDesc::Maxwell(bank) = effect
            && let Some((name, t)) = bank.firmware(&built.backbone, scene.dt, scene.number.name())
        {
            comparisons.push((name, true));
            timers.push(t);
        }
    }
    let kind = if let BackboneSpec::Spline { .. } = scene.backbone {
        "spline"
    } else {
        "polynomial"
    };
    Ok(Plan {
        layout: Layout {
            len: timers.len(),
            backbone: format!("backbone alone ({kind})"),
            effects: model::effect_names(scene),
            shape,
            comparisons,
        },
        timers,
    })
}

impl Layout {
    /// The report from one figure per measured item, in plan order.
    fn report(
        self,
        scene: &Scene,
        measure: Measure,
        steps: usize,
        repetitions: usize,
        figures: &[f64],
    ) -> CostReport {
        let get = |i: usize| figures.get(i).copied().unwrap_or(f64::NAN);
        let backbone = get(1);
        let n = self.effects.len();
        let mut parts = vec![Part {
            name: self.backbone,
            ns_per_step: backbone,
        }];
        for (j, name) in self.effects.into_iter().enumerate() {
            parts.push(Part {
                name,
                ns_per_step: get(2 + j) - backbone,
            });
        }
        let comparisons = self
            .comparisons
            .into_iter()
            .enumerate()
            .map(|(j, (name, effect_only))| Part {
                name,
                ns_per_step: get(2 + n + j) - if effect_only { backbone } else { 0.0 },
            })
            .collect();
        CostReport {
            measure,
            number: scene.number,
            steps,
            repetitions,
            parts,
            scene_ns: get(0),
            shape: self.shape,
            comparisons,
        }
    }
}

fn cost_typed<T: Real + 'static>(scene: &Scene, options: CostOptions) -> Result<CostReport, Error> {
    let plan = plan::<T>(scene)?;
    let (inputs, x0) = inputs::<T>(scene, options.min_steps, options.max_steps);
    let mut best = vec![f64::INFINITY; plan.timers.len()];
    for _ in 0..options.repetitions.max(1) {
        for (b, t) in best.iter_mut().zip(&plan.timers) {
            *b = b.min(t(&inputs, x0));
        }
    }
    Ok(plan.layout.report(
        scene,
        Measure::WallClock,
        inputs.len(),
        options.repetitions.max(1),
        &best,
    ))
}
