//! `cost`: what a scene costs per step against the sum of its parts.
//!
//! The scene is stepped as `run` steps it (its profile, its number type,
//! stepping only: the inputs are computed beforehand), reading what a
//! control loop reads (force, tangent and dissipated energy). Each part is
//! timed the same way on its own:
//!
//! - the backbone alone: a bushing of the scene's backbone and no effect
//!   (the type `()`, no run-time slot);
//! - each effect: a bushing of the backbone and that effect only, as the
//!   scene builds it, minus the backbone alone, so that the effect sees
//!   exactly the drive it sees in the scene;
//! - for a Maxwell effect of at most 8 cells, also the const-size
//!   [`MaxwellBank`] the firmware would use, for comparison.
//!
//! Profiles shorter than [`CostOptions::min_steps`] are repeated to that
//! length; each figure is the best of [`CostOptions::repetitions`]
//! interleaved passes.
//!
//! **Where a run-time composed scene loses time.** The scene's bushing is
//! one type for every scene (`model::SceneBushing`): the effects the scene
//! lists, in a list, each behind a match on its kind; an absent effect has
//! no slot and costs nothing. Each step walks the list and dispatches, and
//! on a small scene that is a visible share of the step: `cost
//! scenes/maxwell4.toml` measured the scene 1.26 to 1.28 times the sum of
//! its parts (the earlier design, nine optional slots tested every step,
//! measured 1.25 to 1.31). Separately, the run-time sized banks
//! (`model::DynMaxwell`) loop over a slice of unknown length behind a match
//! on the state storage, which the compiler neither unrolls nor inlines;
//! the const-size line shows what the firmware pays for the same cells
//! (about half).

use std::fmt;
use std::hint::black_box;
use std::time::Instant;

use bushing::{
    Accumulator, Backbone, Bushing, Compensated, Effect, MaxwellBank, MaxwellForm, MaxwellSpec,
    Plain, Real,
};

use crate::model::{self, AnyBackbone, AnyEffect, SceneBushing, SceneEffects};
use crate::profile;
use crate::scene::{BackboneSpec, Effect as EffectDesc, NumberType, Scene};

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

/// One timed part.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// What it is.
    pub name: String,
    /// Best ns per step.
    pub ns_per_step: f64,
}

/// What `cost` measured.
#[derive(Debug, Clone, PartialEq)]
pub struct CostReport {
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
    /// Const-size banks for comparison (not in the sum).
    pub firmware: Vec<Part>,
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
        writeln!(
            f,
            "cost per step, {}, {} steps per pass, best of {} passes (host wall clock, stepping only)",
            self.number.name(),
            self.steps,
            self.repetitions
        )?;
        for p in &self.parts {
            writeln!(f, "part  {:<48} {:>9.2} ns/step", p.name, p.ns_per_step)?;
        }
        writeln!(f, "sum of parts {:<41} {:>9.2} ns/step", "", self.sum())?;
        writeln!(f, "scene {:<48} {:>9.2} ns/step", "", self.scene_ns)?;
        writeln!(f, "ratio scene / sum of parts {:>36.3}", self.ratio())?;
        for p in &self.firmware {
            writeln!(
                f,
                "for comparison, {:<38} {:>9.2} ns/step",
                p.name, p.ns_per_step
            )?;
        }
        Ok(())
    }
}

/// Times `scene` and its parts with the default [`CostOptions`].
pub fn cost(scene: &Scene) -> Result<CostReport, String> {
    cost_with(scene, CostOptions::default())
}

/// Times `scene` and its parts.
pub fn cost_with(scene: &Scene, options: CostOptions) -> Result<CostReport, String> {
    match scene.number {
        NumberType::F32 => cost_typed::<f32>(scene, options),
        NumberType::F64 => cost_typed::<f64>(scene, options),
    }
}

/// One timed pass: ns per step of `b` over `inputs`, from rest at `x0`.
fn pass<T: Real, B: Backbone<T>, E: Effect<T>>(b: &Bushing<T, B, E>, inputs: &[T], x0: T) -> f64 {
    let mut state = b.state_at(x0);
    let start = Instant::now();
    for &x in inputs {
        let o = b.step(&mut state, x);
        black_box((o.force, o.tangent, o.dissipated));
    }
    start.elapsed().as_secs_f64() * 1e9 / inputs.len().max(1) as f64
}

type Timer<T> = Box<dyn Fn(&[T], T) -> f64>;

fn timer<T: Real + 'static, B: Backbone<T> + 'static, E: Effect<T> + 'static>(
    b: Bushing<T, B, E>,
) -> Timer<T> {
    Box::new(move |inputs, x0| pass(&b, inputs, x0))
}

/// A bushing of `backbone` and the first effect of `effects`, as its own
/// concrete type (no list around it).
fn alone<T: Real + 'static>(
    backbone: &AnyBackbone<T>,
    effects: &SceneEffects<T>,
) -> Result<Timer<T>, String> {
    fn one<T: Real + 'static, E: Effect<T> + Clone + 'static>(
        backbone: &AnyBackbone<T>,
        e: &E,
    ) -> Result<Timer<T>, String> {
        Bushing::new(backbone.clone(), (e.clone(),))
            .map(timer)
            .map_err(|e| e.to_string())
    }
    match effects.effects().first() {
        Some(AnyEffect::Maxwell(e)) => one(backbone, e),
        Some(AnyEffect::Clamp(e)) => one(backbone, e),
        Some(AnyEffect::Sliders(e)) => one(backbone, e),
        Some(AnyEffect::Xf(e)) => one(backbone, e),
        Some(AnyEffect::Sts(e)) => one(backbone, e),
        Some(AnyEffect::Table(e)) => one(backbone, e),
        Some(AnyEffect::Dahl(e)) => one(backbone, e),
        Some(AnyEffect::BoucWen(e)) => one(backbone, e),
        Some(AnyEffect::Berg(e)) => one(backbone, e),
        None => Err("no effect to time".into()),
    }
}

/// The const-size Maxwell bank of `cells` (1 to 8), as firmware builds it.
fn firmware_maxwell<T: Real + 'static>(
    backbone: &AnyBackbone<T>,
    form: MaxwellForm,
    cells: &[MaxwellSpec],
    dt: f64,
    compensated: bool,
) -> Option<Timer<T>> {
    fn bank<T: Real + 'static, A: Accumulator<T> + 'static, const N: usize>(
        backbone: &AnyBackbone<T>,
        form: MaxwellForm,
        cells: &[MaxwellSpec],
        dt: f64,
    ) -> Option<Timer<T>> {
        let specs: &[MaxwellSpec; N] = cells.try_into().ok()?;
        let bank = MaxwellBank::<T, N, A>::new(form, specs, dt).ok()?;
        Bushing::new(backbone.clone(), (bank,)).ok().map(timer)
    }
    macro_rules! sizes {
        ($acc:ty) => {
            match cells.len() {
                1 => bank::<T, $acc, 1>(backbone, form, cells, dt),
                2 => bank::<T, $acc, 2>(backbone, form, cells, dt),
                3 => bank::<T, $acc, 3>(backbone, form, cells, dt),
                4 => bank::<T, $acc, 4>(backbone, form, cells, dt),
                5 => bank::<T, $acc, 5>(backbone, form, cells, dt),
                6 => bank::<T, $acc, 6>(backbone, form, cells, dt),
                7 => bank::<T, $acc, 7>(backbone, form, cells, dt),
                8 => bank::<T, $acc, 8>(backbone, form, cells, dt),
                _ => None,
            }
        };
    }
    if compensated {
        sizes!(Compensated<T>)
    } else {
        sizes!(Plain<T>)
    }
}

fn cost_typed<T: Real + 'static>(
    scene: &Scene,
    options: CostOptions,
) -> Result<CostReport, String> {
    let built: SceneBushing<T> = model::build(scene).map_err(|e| e.to_string())?;
    let backbone = model::backbone::<T>(&scene.backbone).map_err(|e| e.to_string())?;
    let names = model::effect_names(scene);

    // The profile, repeated to at least min_steps.
    let steps = (scene.steps() as usize).clamp(1, options.max_steps.max(1));
    let profile: Vec<T> = (1..=steps)
        .map(|i| T::from_f64(profile::displacement(&scene.profile, i as f64 * scene.dt)))
        .collect();
    let inputs: Vec<T> = profile
        .iter()
        .copied()
        .cycle()
        .take(steps.max(options.min_steps))
        .collect();
    let x0 = T::from_f64(profile::displacement(&scene.profile, 0.0));

    let mut timers: Vec<Timer<T>> = vec![
        timer(built),
        timer(Bushing::new(backbone.clone(), ()).map_err(|e| e.to_string())?),
    ];
    for effect in &scene.effects {
        let sub = Scene {
            effects: vec![effect.clone()],
            ..scene.clone()
        };
        let b: SceneBushing<T> = model::build(&sub).map_err(|e| e.to_string())?;
        timers.push(alone(&backbone, b.effects())?);
    }
    let mut firmware_names = Vec::new();
    for effect in &scene.effects {
        if let EffectDesc::Maxwell {
            form,
            compensated,
            cells,
        } = effect
            && let Some(t) = firmware_maxwell(&backbone, *form, cells, scene.dt, *compensated)
        {
            firmware_names.push(format!(
                "MaxwellBank<{}, {}{}> (const size)",
                scene.number.name(),
                cells.len(),
                if *compensated { ", Compensated" } else { "" }
            ));
            timers.push(t);
        }
    }

    let mut best = vec![f64::INFINITY; timers.len()];
    for _ in 0..options.repetitions.max(1) {
        for (b, t) in best.iter_mut().zip(&timers) {
            *b = b.min(t(&inputs, x0));
        }
    }
    let get = |i: usize| best.get(i).copied().unwrap_or(f64::NAN);
    let scene_ns = get(0);
    let backbone_ns = get(1);
    let kind = if let BackboneSpec::Spline { .. } = scene.backbone {
        "spline"
    } else {
        "polynomial"
    };
    let mut parts = vec![Part {
        name: format!("backbone alone ({kind})"),
        ns_per_step: backbone_ns,
    }];
    for (j, name) in names.iter().enumerate() {
        parts.push(Part {
            name: name.clone(),
            ns_per_step: get(2 + j) - backbone_ns,
        });
    }
    let firmware = firmware_names
        .into_iter()
        .enumerate()
        .map(|(j, name)| Part {
            name,
            ns_per_step: get(2 + names.len() + j) - backbone_ns,
        })
        .collect();
    Ok(CostReport {
        number: scene.number,
        steps: inputs.len(),
        repetitions: options.repetitions.max(1),
        parts,
        scene_ns,
        firmware,
    })
}
