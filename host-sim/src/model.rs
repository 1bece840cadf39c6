//! Run-time composition of a bushing from a scene: only the effects the
//! scene lists are built; an absent effect is a `None` that is skipped.

use bushing::iwan::{self, ClampCell, SliderCell};
use bushing::maxwell::{self, MaxwellCell};
use bushing::xf::{self, XfCell};
use bushing::{
    Accumulator, Backbone, Berg, BoucWen, Bushing, BushingState, Compensated, Dahl, Drive, Effect,
    EffectOutput, IwanCellSpec, KfTable, MaxwellForm, MaxwellSpec, MonotoneSpline, ParamError,
    Plain, Polynomial, Real, Sts, TurningPoints, XfForm, XfSpec,
};

use crate::scene::{
    BackboneSpec, Effect as EffectDesc, Friction, Law, STACK_DEPTH, Scene, TABLE_POINTS,
};

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
    fn rest(&self, _: T) -> Self::State {
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

/// A core slice kernel: advances cells `C` with one state word each.
pub type Kernel<T, C> = fn(&[C], &mut [T], &Drive<T>) -> EffectOutput<T>;

/// A bank of cells with one force-like state word each, sized at run
/// time; the scheme is the core's slice kernel for that cell type.
#[derive(Debug, Clone)]
pub struct DynBank<T, C> {
    cells: Vec<C>,
    kernel: Kernel<T, C>,
    /// The state word at rest is x0 (slider positions) rather than 0.
    rest_at_x0: bool,
    fraction: f64,
    dt: Option<f64>,
}

impl<T: Real, C> Effect<T> for DynBank<T, C> {
    type State = Vec<T>;
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        self.dt
    }
    fn rest(&self, x0: T) -> Vec<T> {
        vec![if self.rest_at_x0 { x0 } else { T::ZERO }; self.cells.len()]
    }
    #[inline]
    fn step(&self, state: &mut Vec<T>, drive: &Drive<T>) -> EffectOutput<T> {
        (self.kernel)(&self.cells, state, drive)
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// Iwan bank, clamp form.
pub type DynIwanClamp<T> = DynBank<T, ClampCell<T>>;
/// Iwan bank, slider form.
pub type DynIwanSliders<T> = DynBank<T, SliderCell<T>>;
/// x_f bank.
pub type DynXf<T> = DynBank<T, XfCell<T>>;

fn iwan_clamp<T: Real>(specs: &[IwanCellSpec]) -> Result<DynIwanClamp<T>, ParamError> {
    Ok(DynBank {
        cells: specs
            .iter()
            .enumerate()
            .map(|(i, s)| ClampCell::new(*s, i))
            .collect::<Result<_, _>>()?,
        kernel: iwan::step_clamp::<T>,
        rest_at_x0: false,
        fraction: specs.iter().map(|s| s.g).sum(),
        dt: None,
    })
}

/// A run-time sized slider-form Iwan bank.
pub fn iwan_sliders<T: Real>(
    specs: &[IwanCellSpec],
    k_ref: f64,
) -> Result<DynIwanSliders<T>, ParamError> {
    Ok(DynBank {
        cells: specs
            .iter()
            .enumerate()
            .map(|(i, s)| SliderCell::new(*s, k_ref, i))
            .collect::<Result<_, _>>()?,
        kernel: iwan::step_sliders::<T>,
        rest_at_x0: true,
        fraction: specs.iter().map(|s| s.g).sum(),
        dt: None,
    })
}

fn xf_bank<T: Real>(form: XfForm, specs: &[XfSpec], dt: f64) -> Result<DynXf<T>, ParamError> {
    Ok(DynBank {
        cells: specs
            .iter()
            .enumerate()
            .map(|(i, s)| XfCell::new(*s, dt, i))
            .collect::<Result<_, _>>()?,
        kernel: match form {
            XfForm::Midpoint => |c, s, d| xf::step_xf(XfForm::Midpoint, c, s, d),
            XfForm::ExactRamp => |c, s, d| xf::step_xf(XfForm::ExactRamp, c, s, d),
        },
        rest_at_x0: false,
        fraction: specs.iter().map(|s| s.g).sum(),
        dt: Some(dt),
    })
}

/// Turning-point model with the STS law.
pub type StsStack<T> = TurningPoints<Sts<T>, STACK_DEPTH>;
/// Turning-point model with a measured K_f table.
pub type TableStack<T> = TurningPoints<KfTable<T, TABLE_POINTS>, STACK_DEPTH>;

/// The stack models a scene can name.
pub type SceneStacks<T> = (Option<StsStack<T>>, Option<TableStack<T>>);
/// The single friction cells a scene can name.
pub type SceneFriction<T> = (Option<Dahl<T>>, Option<BoucWen<T>>, Option<Berg<T>>);

/// The effects a scene can name, each present or not.
pub type SceneEffects<T> = (
    Option<DynMaxwell<T>>,
    Option<DynIwanClamp<T>>,
    Option<DynIwanSliders<T>>,
    Option<DynXf<T>>,
    SceneStacks<T>,
    SceneFriction<T>,
);

/// A bushing built from a scene.
pub type SceneBushing<T> = Bushing<T, AnyBackbone<T>, SceneEffects<T>>;

/// State of a [`SceneBushing`].
pub type SceneState<T> = BushingState<T, <SceneEffects<T> as Effect<T>>::State>;

/// Builds the bushing a scene describes, with only its effects.
pub fn build<T: Real>(scene: &Scene) -> Result<SceneBushing<T>, ParamError> {
    let (mut maxwell, mut clamp, mut sliders, mut xf) = (None, None, None, None);
    let (mut sts, mut table) = (None, None);
    let (mut dahl, mut bouc_wen, mut berg) = (None, None, None);
    for e in &scene.effects {
        match e {
            EffectDesc::Maxwell {
                form,
                compensated,
                cells,
            } => maxwell = Some(DynMaxwell::new(*form, cells, scene.dt, *compensated)?),
            EffectDesc::Iwan {
                slider: false,
                cells,
                ..
            } => clamp = Some(iwan_clamp(cells)?),
            EffectDesc::Iwan {
                slider: true,
                k_ref,
                cells,
            } => sliders = Some(iwan_sliders(cells, *k_ref)?),
            EffectDesc::Xf { form, cells } => xf = Some(xf_bank(*form, cells, scene.dt)?),
            EffectDesc::TurningPoints { law, first_loading } => match law {
                Law::Sts { c, k1 } => {
                    sts = Some(TurningPoints::new(Sts::new(*c, *k1)?, *first_loading))
                }
                Law::Table { d, k } => {
                    table = Some(TurningPoints::new(KfTable::new(d, k)?, *first_loading));
                }
            },
            EffectDesc::Friction(Friction::Dahl(p)) => {
                dahl = Some(Dahl::new(p.k_d, p.f_f, p.alpha)?);
            }
            EffectDesc::Friction(Friction::BoucWen(p)) => {
                bouc_wen = Some(BoucWen::new(p.alpha, p.a, p.beta, p.gamma, p.n)?);
            }
            EffectDesc::Friction(Friction::Berg(p)) => berg = Some(Berg::new(p.f_max, p.x2)?),
        }
    }
    Bushing::new(
        backbone(&scene.backbone)?,
        (
            maxwell,
            clamp,
            sliders,
            xf,
            (sts, table),
            (dahl, bouc_wen, berg),
        ),
    )
}

/// Names of the effects present, in trace-column order.
pub fn effect_names(scene: &Scene) -> Vec<String> {
    scene.effects.iter().map(EffectDesc::name).collect()
}

/// Per-effect forces and energies of one step, in trace-column order.
///
/// A scene lists at most one effect of each kind and the trace columns
/// follow the scene's order, so outputs are matched by kind.
pub fn effect_outputs<T: Real>(
    scene: &Scene,
    report: &<SceneEffects<T> as Effect<T>>::Report,
) -> Vec<EffectOutput<T>> {
    let (maxwell, clamp, sliders, xf, (sts, table), (dahl, bouc_wen, berg)) = report;
    scene
        .effects
        .iter()
        .filter_map(|e| match e {
            EffectDesc::Maxwell { .. } => *maxwell,
            EffectDesc::Iwan { slider: false, .. } => *clamp,
            EffectDesc::Iwan { slider: true, .. } => *sliders,
            EffectDesc::Xf { .. } => *xf,
            EffectDesc::TurningPoints {
                law: Law::Sts { .. },
                ..
            } => *sts,
            EffectDesc::TurningPoints {
                law: Law::Table { .. },
                ..
            } => *table,
            EffectDesc::Friction(Friction::Dahl(_)) => *dahl,
            EffectDesc::Friction(Friction::BoucWen(_)) => *bouc_wen,
            EffectDesc::Friction(Friction::Berg(_)) => *berg,
        })
        .collect()
}
