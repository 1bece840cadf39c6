//! Run-time composition of a bushing from a scene: only the effects the
//! scene lists are built, kept in a list in the scene's order, and a step
//! visits only those.

mod oscillator;
mod tuned;

use bushing::{Bushing, BushingState, Drive, Effect, EffectOutput, ParamError, Real};

use crate::family::backbone::BackboneSpec;
pub use crate::family::backbone::{AnyBackbone, MAX_COEFFICIENTS, MAX_POINTS, backbone};
use crate::family::{AnyEffect, AnyState, Tuned, each_effect};
use crate::scene::Scene;

use oscillator::OscillatorModel;
pub use tuned::shifted_bushing;

/// The effects a scene lists, in its order, and only those: one step
/// visits each present effect once (no slot for an absent one).
#[derive(Debug, Clone)]
pub struct EffectList<T> {
    effects: Vec<AnyEffect<T>>,
}

impl<T> EffectList<T> {
    /// The effects, in the scene's order.
    pub fn effects(&self) -> &[AnyEffect<T>] {
        &self.effects
    }
}

impl<T: Real> EffectList<T> {
    /// Steps every slot in place (keeping its state aside first when
    /// `keep`): the total, and whether every effect's own output is
    /// within the guard.
    #[inline(always)]
    fn advance(
        &self,
        state: &mut [Slot<T>],
        drive: &Drive<T>,
        keep: bool,
    ) -> (EffectOutput<T>, bool) {
        let mut total = EffectOutput::zero();
        let mut magnitude = T::ZERO;
        for (e, slot) in self.effects.iter().zip(state.iter_mut()) {
            if keep {
                slot.before.0.copy_from(&slot.state);
                slot.before.1 = slot.last;
            }
            let out = e.step(&mut slot.state, drive);
            slot.last = out;
            magnitude += out.force.abs() + out.tangent.abs();
            total.force += out.force;
            total.tangent += out.tangent;
            total.dissipated += out.dissipated;
        }
        (total, magnitude <= T::GUARD)
    }
}

/// State of one effect of an [`EffectList`], with what its last step gave.
/// Saved and restored as plain data (`serde`): the state and the last
/// output; the copy kept for a refused step is scratch and not saved.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(
    from = "SavedSlot<T>",
    into = "SavedSlot<T>",
    bound(
        serialize = "T: serde::Serialize",
        deserialize = "T: serde::Deserialize<'de>"
    )
)]
pub struct Slot<T: Real> {
    /// The effect's state.
    pub state: AnyState<T>,
    /// Output of the effect's last step.
    pub last: EffectOutput<T>,
    /// The state and output before the step in progress, kept so that a
    /// refused step can be undone without allocating (not part of the
    /// state's value: equality ignores it).
    before: (AnyState<T>, EffectOutput<T>),
}

/// What a [`Slot`] saves.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "T: serde::Serialize",
    deserialize = "T: serde::Deserialize<'de>"
))]
struct SavedSlot<T: Real> {
    state: AnyState<T>,
    last: EffectOutput<T>,
}

impl<T: Real> From<SavedSlot<T>> for Slot<T> {
    fn from(saved: SavedSlot<T>) -> Self {
        Self {
            before: (saved.state.clone(), saved.last),
            state: saved.state,
            last: saved.last,
        }
    }
}

impl<T: Real> From<Slot<T>> for SavedSlot<T> {
    fn from(slot: Slot<T>) -> Self {
        Self {
            state: slot.state,
            last: slot.last,
        }
    }
}

impl<T: Real> PartialEq for Slot<T> {
    fn eq(&self, other: &Self) -> bool {
        self.state == other.state && self.last == other.last
    }
}

impl<T: Real> Effect<T> for EffectList<T> {
    type State = Vec<Slot<T>>;
    /// The sum over the effects; each effect's own output is kept in its
    /// [`Slot`] (see [`effect_outputs`]).
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.effects.iter().map(AnyEffect::fraction).sum()
    }
    fn dt(&self) -> Option<f64> {
        self.check_dt(None).ok().flatten()
    }
    fn check_dt(&self, dt: Option<f64>) -> Result<Option<f64>, ParamError> {
        self.effects.iter().try_fold(dt, |dt, e| e.check_dt(dt))
    }
    fn rest(&self, x0: T) -> Self::State {
        self.effects
            .iter()
            .map(|e| {
                let state = e.rest(x0);
                Slot {
                    before: (state.clone(), EffectOutput::zero()),
                    state,
                    last: EffectOutput::zero(),
                }
            })
            .collect()
    }
    #[inline(always)]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        self.advance(state, drive, false).0
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
    /// Steps every slot in place after keeping its state aside, and
    /// undoes every slot when one effect's output leaves the guard or
    /// `accept` refuses the total: the default's copy of the whole list
    /// would allocate on every step.
    fn step_if(
        &self,
        state: &mut Self::State,
        drive: &Drive<T>,
        accept: impl FnOnce(&EffectOutput<T>) -> bool,
    ) -> Option<EffectOutput<T>> {
        let (total, guarded) = self.advance(state, drive, true);
        if guarded && accept(&total) {
            return Some(total);
        }
        for slot in state.iter_mut() {
            std::mem::swap(&mut slot.state, &mut slot.before.0);
            slot.last = slot.before.1;
        }
        None
    }
}

/// The effects a scene can name, as built for it.
pub type SceneEffects<T> = EffectList<T>;

/// A bushing built from a scene.
pub type SceneBushing<T> = Bushing<T, AnyBackbone<T>, SceneEffects<T>>;

/// State of a [`SceneBushing`].
pub type SceneState<T> = BushingState<T, <SceneEffects<T> as Effect<T>>::State>;

/// The bushing a scene describes, with only its effects: the models the
/// scene built when it was read (built now when `T` is not the scene's
/// working type).
pub fn build<T: Real + 'static>(scene: &Scene) -> Result<SceneBushing<T>, ParamError> {
    let built = scene.built::<T>()?.into_owned();
    Bushing::new(
        built.backbone,
        EffectList {
            effects: built.effects,
        },
    )
}

/// The bushing of a scene's backbone and effects built for another time
/// step `dt` (s) than the scene's own: each family's constructor again, at
/// `dt` (a campaign generated from a model samples each test at its own
/// rate).
pub fn build_at<T: Real>(scene: &Scene, dt: f64) -> Result<SceneBushing<T>, ParamError> {
    build_parts(&scene.backbone, scene.effects(), dt)
}

/// The bushing of a backbone and checked effects built in `T` at time
/// step `dt` (s): a scene's parts, or a model being identified.
pub fn build_parts<T: Real>(
    spec: &BackboneSpec,
    effects: &[crate::family::Effect],
    dt: f64,
) -> Result<SceneBushing<T>, ParamError> {
    let effects = effects
        .iter()
        .map(|e| e.build::<T>(dt))
        .collect::<Result<_, _>>()?;
    Bushing::new(backbone::<T>(spec)?, EffectList { effects })
}

/// Names of the effects present, in trace-column order.
pub fn effect_names(scene: &Scene) -> Vec<String> {
    scene
        .effects()
        .iter()
        .map(crate::family::Effect::name)
        .collect()
}

/// Per-effect forces and energies of the last step, in trace-column order
/// (the scene's order).
pub fn effect_outputs<T: Real>(state: &SceneState<T>) -> Vec<EffectOutput<T>> {
    state.effects().iter().map(|slot| slot.last).collect()
}

/// What the drivers read from one step of a [`SceneModel`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRow<T> {
    /// Displacement x_n: the input, or in an oscillator scene the mass's
    /// displacement.
    pub x: T,
    /// Total force F_n.
    pub force: T,
    /// Algorithmic tangent dF_n/dx_n.
    pub tangent: T,
    /// Energy dissipated in the step, all effects.
    pub dissipated: T,
    /// Long-term elastic branch g^0 F^∞(x_n).
    pub elastic: T,
    /// The step was refused (non-finite or out-of-range input): the state
    /// was kept and the effects' outputs of this row are zero.
    pub refused: bool,
}

/// Effects whose per-effect outputs a driver can read after a step.
pub trait Parts<T: Real>: Effect<T> + Tuned {
    /// Appends each effect's output of the step that gave `report` (and
    /// left `state`), in the scene's order.
    fn parts(state: &Self::State, report: &Self::Report, out: &mut Vec<EffectOutput<T>>);
}

impl<T: Real> Parts<T> for () {
    fn parts(_: &(), _: &(), _: &mut Vec<EffectOutput<T>>) {}
}

impl<T: Real, E: Effect<T> + Tuned> Parts<T> for (E,) {
    #[inline(always)]
    fn parts(_: &Self::State, report: &Self::Report, out: &mut Vec<EffectOutput<T>>) {
        out.push(E::total(&report.0));
    }
}

impl<T: Real> Parts<T> for EffectList<T> {
    #[inline(always)]
    fn parts(state: &Vec<Slot<T>>, _: &EffectOutput<T>, out: &mut Vec<EffectOutput<T>>) {
        out.extend(state.iter().map(|slot| slot.last));
    }
}

/// How a compiled scene holds its effects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// No effect: `Bushing<T, AnyBackbone<T>, ()>`.
    BackboneOnly,
    /// One effect `E`: `Bushing<T, AnyBackbone<T>, (E,)>`, the loop
    /// monomorphised for it.
    One,
    /// Two or more: an [`EffectList`], one match per effect and step.
    List,
    /// A unit mass on the bushing (its effects in an [`EffectList`]),
    /// driven by a force.
    Oscillator,
}

impl Shape {
    /// A short description.
    pub fn name(self) -> &'static str {
        match self {
            Self::BackboneOnly => "backbone only",
            Self::One => "one effect, monomorphised",
            Self::List => "effect list",
            Self::Oscillator => "oscillator, effect list",
        }
    }
}

/// A scene's bushing with its state, behind one object-safe interface, so
/// that a driver dispatches once per chunk of steps while the steps
/// themselves run in a loop monomorphised for the scene's shape (see
/// [`compile`]).
pub trait SceneModel<T: Real> {
    /// How the effects are held.
    fn shape(&self) -> Shape;
    /// The backbone.
    fn backbone(&self) -> &AnyBackbone<T>;
    /// Long-term fraction g^0.
    fn g0(&self) -> f64;
    /// Number of effects (per-effect outputs per step).
    fn effect_count(&self) -> usize;
    /// Steps refused so far.
    fn refused(&self) -> u32;
    /// Steps through `inputs` (displacements, or forces in an oscillator
    /// scene), appending one row per step to `rows` and
    /// [`SceneModel::effect_count`] outputs per step to `parts`.
    fn step_into(
        &mut self,
        inputs: &[T],
        rows: &mut Vec<StepRow<T>>,
        parts: &mut Vec<EffectOutput<T>>,
    );
    /// Steps a fresh copy of the model from rest at `x0` through `inputs`,
    /// reading force, tangent and dissipated energy as a control loop
    /// does, and returns the wall-clock time of the steps alone (the
    /// model's own state is left untouched).
    fn time_steps(&self, inputs: &[T], x0: T) -> std::time::Duration;
    /// Re-tunes the Maxwell banks, between two steps, to the shift factor
    /// `a_t` (absolute: corners ω_i / a_t of the scene's ω_i; 1 as built);
    /// the state carries over. Nothing is rebuilt when the model is tuned
    /// to `a_t` already. On error the model is left as it was.
    fn retune(&mut self, a_t: f64) -> Result<(), ParamError>;
}

/// A [`Bushing`] of the scene's backbone and effects `E`, with its state.
struct Compiled<T: Real, E: Effect<T>> {
    bushing: Bushing<T, AnyBackbone<T>, E>,
    state: BushingState<T, E::State>,
    shape: Shape,
    count: usize,
    /// The shift factor the Maxwell banks are tuned to.
    shift: f64,
}

impl<T: Real, E: Parts<T>> SceneModel<T> for Compiled<T, E> {
    fn shape(&self) -> Shape {
        self.shape
    }
    fn backbone(&self) -> &AnyBackbone<T> {
        self.bushing.backbone()
    }
    fn g0(&self) -> f64 {
        self.bushing.g0()
    }
    fn effect_count(&self) -> usize {
        self.count
    }
    fn refused(&self) -> u32 {
        self.state.rejected()
    }
    fn step_into(
        &mut self,
        inputs: &[T],
        rows: &mut Vec<StepRow<T>>,
        parts: &mut Vec<EffectOutput<T>>,
    ) {
        for &x in inputs {
            let o = self.bushing.step(&mut self.state, x);
            rows.push(StepRow {
                x,
                force: o.force,
                tangent: o.tangent,
                dissipated: o.dissipated,
                elastic: o.elastic,
                refused: o.effects.is_none(),
            });
            match &o.effects {
                Some(report) => E::parts(self.state.effects(), report, parts),
                None => parts.extend((0..self.count).map(|_| EffectOutput::zero())),
            }
        }
    }
    fn time_steps(&self, inputs: &[T], x0: T) -> std::time::Duration {
        crate::cost::timer::stepping_pass(&self.bushing, inputs, x0)
    }
    fn retune(&mut self, a_t: f64) -> Result<(), ParamError> {
        if a_t != self.shift {
            self.bushing = shifted_bushing(&self.bushing, a_t)?;
            self.shift = a_t;
        }
        Ok(())
    }
}

fn compiled<T: Real + 'static, E: Parts<T> + 'static>(
    backbone: AnyBackbone<T>,
    effects: E,
    x0: T,
    shape: Shape,
    count: usize,
) -> Result<Box<dyn SceneModel<T>>, ParamError> {
    let bushing = Bushing::new(backbone, effects)?;
    let state = bushing.state_at(x0);
    Ok(Box::new(Compiled {
        bushing,
        state,
        shape,
        count,
        shift: 1.0,
    }))
}

/// Builds the bushing a scene describes, with only its effects, at rest
/// at the profile's start, in the cheapest shape for it: no effect is the
/// bare backbone (`Bushing<_, _, ()>`), one effect is the bushing of that
/// effect alone (`Bushing<_, _, (E,)>`, as firmware would declare it), and
/// two or more are an [`EffectList`]. The steps are bit-identical to
/// [`build`]'s in every shape.
pub fn compile<T: Real + 'static>(scene: &Scene) -> Result<Box<dyn SceneModel<T>>, ParamError> {
    // The profile as the model reads it (through the scene's ADC).
    let x0 = T::from_f64(scene.input(0.0));
    let list = build::<T>(scene)?;
    if let Some(spec) = scene.oscillator {
        return OscillatorModel::boxed(list, scene.dt, spec, x0);
    }
    let backbone = list.backbone().clone();
    let mut effects = list.effects().effects().to_vec();
    match (effects.pop(), effects.is_empty()) {
        (None, _) => compiled(backbone, (), x0, Shape::BackboneOnly, 0),
        (Some(last), true) => each_effect!(last, |e| compiled(backbone, (e,), x0, Shape::One, 1)),
        (Some(last), false) => {
            effects.push(last);
            let count = effects.len();
            compiled(backbone, EffectList { effects }, x0, Shape::List, count)
        }
    }
}

/// Steps `model` through `inputs` as [`SceneModel::step_into`] does, the
/// first input being step `done + 1` of `scene`, and follows the scene's
/// temperature history: before the step that starts at `t = n dt`, for
/// every `n` (steps done) that is a multiple of `every`, the Maxwell banks
/// are re-tuned to a_T(T(t)) ([`SceneModel::retune`]). A scene without a
/// history is stepped by `step_into` alone, in one call.
pub fn step_scene<T: Real>(
    scene: &Scene,
    model: &mut dyn SceneModel<T>,
    done: u64,
    inputs: &[T],
    rows: &mut Vec<StepRow<T>>,
    parts: &mut Vec<EffectOutput<T>>,
) -> Result<(), ParamError> {
    let Some(history) = &scene.temperature else {
        model.step_into(inputs, rows, parts);
        return Ok(());
    };
    let every = history.every.max(1);
    let (mut n, mut rest) = (done, inputs);
    while !rest.is_empty() {
        if n.is_multiple_of(every) {
            model.retune(history.shift_at(n as f64 * scene.dt)?)?;
        }
        let until = usize::try_from(every - n % every).unwrap_or(usize::MAX);
        let (now, later) = rest.split_at(rest.len().min(until));
        model.step_into(now, rows, parts);
        n += now.len() as u64;
        rest = later;
    }
    Ok(())
}
