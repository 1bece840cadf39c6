//! Run-time composition of a bushing from a scene: only the effects the
//! scene lists are built; an absent effect is a `None` that is skipped.

use bushing::maxwell::{self, MaxwellCell};
use bushing::{
    Accumulator, Backbone, Bushing, BushingState, Compensated, Drive, Effect, EffectOutput,
    MaxwellForm, MaxwellSpec, MonotoneSpline, ParamError, Plain, Polynomial, Real,
};

use crate::scene::{BackboneSpec, Effect as EffectDesc, Scene};

/// Most polynomial coefficients a scene may give.
pub const MAX_COEFFICIENTS: usize = 8;
/// Most spline points a scene may give.
pub const MAX_POINTS: usize = 256;

/// A backbone chosen at run time.
#[derive(Debug, Clone)]
pub enum AnyBackbone<T> {
    /// Polynomial.
    Polynomial(Polynomial<T, MAX_COEFFICIENTS>),
    /// Monotone spline.
    Spline(Box<MonotoneSpline<T, MAX_POINTS>>),
}

impl<T: Real> Backbone<T> for AnyBackbone<T> {
    #[inline]
    fn eval(&self, x: T) -> (T, T) {
        match self {
            Self::Polynomial(p) => p.eval(x),
            Self::Spline(s) => s.eval(x),
        }
    }
}

/// Builds the backbone of a scene.
pub fn backbone<T: Real>(spec: &BackboneSpec) -> Result<AnyBackbone<T>, ParamError> {
    Ok(match spec {
        BackboneSpec::Polynomial {
            coefficients,
            range,
        } => AnyBackbone::Polynomial(Polynomial::new(coefficients, (range[0], range[1]))?),
        BackboneSpec::Spline { x, force } => {
            AnyBackbone::Spline(Box::new(MonotoneSpline::new(x, force)?))
        }
    })
}

/// Checks a backbone spec by building it in `f64`.
pub fn check_backbone(spec: &BackboneSpec) -> Result<(), ParamError> {
    backbone::<f64>(spec).map(|_| ())
}

/// A Maxwell bank sized at run time; the scheme is the core's
/// [`maxwell::step_cells`], the same code the const-size bank runs.
#[derive(Debug, Clone)]
pub struct DynMaxwell<T> {
    form: MaxwellForm,
    cells: Vec<MaxwellCell<T>>,
    tangent_gain: T,
    fraction: f64,
    dt: f64,
    compensated: bool,
}

/// State of a [`DynMaxwell`].
#[derive(Debug, Clone, PartialEq)]
pub enum DynMaxwellState<T> {
    /// One word per cell.
    Plain(Vec<Plain<T>>),
    /// Two words per cell.
    Compensated(Vec<Compensated<T>>),
}

impl<T: Real> DynMaxwell<T> {
    /// Builds the bank.
    pub fn new(
        form: MaxwellForm,
        specs: &[MaxwellSpec],
        dt: f64,
        compensated: bool,
    ) -> Result<Self, ParamError> {
        let cells = specs
            .iter()
            .enumerate()
            .map(|(i, s)| MaxwellCell::new(form, *s, dt, i))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            form,
            tangent_gain: maxwell::tangent_gain(&cells),
            cells,
            fraction: specs.iter().map(|s| s.g).sum(),
            dt,
            compensated,
        })
    }
}

fn zeros<A: Accumulator<T>, T: Real>(n: usize) -> Vec<A> {
    vec![A::default(); n]
}

impl<T: Real> Effect<T> for DynMaxwell<T> {
    type State = DynMaxwellState<T>;
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        Some(self.dt)
    }
    fn rest(&self) -> Self::State {
        if self.compensated {
            DynMaxwellState::Compensated(zeros(self.cells.len()))
        } else {
            DynMaxwellState::Plain(zeros(self.cells.len()))
        }
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        match state {
            DynMaxwellState::Plain(s) => {
                maxwell::step_cells(self.form, &self.cells, s, self.tangent_gain, drive)
            }
            DynMaxwellState::Compensated(s) => {
                maxwell::step_cells(self.form, &self.cells, s, self.tangent_gain, drive)
            }
        }
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// The effects a scene can name, each present or not.
pub type SceneEffects<T> = (Option<DynMaxwell<T>>,);

/// A bushing built from a scene.
pub type SceneBushing<T> = Bushing<T, AnyBackbone<T>, SceneEffects<T>>;

/// State of a [`SceneBushing`].
pub type SceneState<T> = BushingState<T, <SceneEffects<T> as Effect<T>>::State>;

/// Builds the bushing a scene describes, with only its effects.
pub fn build<T: Real>(scene: &Scene) -> Result<SceneBushing<T>, ParamError> {
    let mut maxwell = None;
    for e in &scene.effects {
        match e {
            EffectDesc::Maxwell {
                form,
                compensated,
                cells,
            } => maxwell = Some(DynMaxwell::new(*form, cells, scene.dt, *compensated)?),
        }
    }
    Bushing::new(backbone(&scene.backbone)?, (maxwell,))
}

/// Names of the effects present, in trace-column order.
pub fn effect_names(scene: &Scene) -> Vec<String> {
    scene.effects.iter().map(EffectDesc::name).collect()
}

/// Per-effect forces and energies of one step, in trace-column order.
pub fn effect_outputs<T: Real>(
    report: &<SceneEffects<T> as Effect<T>>::Report,
) -> Vec<EffectOutput<T>> {
    let (maxwell,) = report;
    maxwell.iter().copied().collect()
}
