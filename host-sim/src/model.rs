//! Run-time composition of a bushing from a scene: only the effects the
//! scene lists are built, kept in a list in the scene's order, and a step
//! visits only those.

use std::sync::Arc;

use bushing::fractional::{FractionalSpec, Grunwald, GrunwaldState};
use bushing::iwan::{self, ClampCell, Held, SliderCell};
use bushing::maxwell::{self, MaxwellCell};
use bushing::xf::{self, XfCell};
use bushing::{
    Accumulator, Backbone, Berg, BoucWen, Bushing, BushingState, Compensated, Dahl, Drive, Effect,
    EffectOutput, IwanCellSpec, KfTable, MaxwellForm, MaxwellSpec, Multiplied, Oscillator,
    OscillatorState, Param, ParamError, Plain, Real, Sts, TurningPoints, XfForm, XfSpec,
};

pub use crate::backbone::{AnyBackbone, MAX_COEFFICIENTS, MAX_POINTS, backbone};
use crate::scene::{
    Effect as EffectDesc, FRACTIONAL_TAPS, Friction, Law, STACK_DEPTH, Scene, Storage, TABLE_POINTS,
};

/// A Maxwell bank sized at run time; the scheme is the core's
/// [`maxwell::step_cells`], the same code the const-size bank runs.
#[derive(Debug, Clone)]
pub struct DynMaxwell<T> {
    form: MaxwellForm,
    /// The cells at the reference temperature, as given.
    specs: Vec<MaxwellSpec>,
    cells: Vec<MaxwellCell<T>>,
    tangent_gain: T,
    fraction: f64,
    dt: f64,
    storage: Storage,
}

/// State of a [`DynMaxwell`].
#[derive(Debug, Clone, PartialEq)]
pub enum DynMaxwellState<T> {
    /// One word per cell, `F - d F`.
    Plain(Vec<Plain<T>>),
    /// One word per cell, `e^-h F`.
    Multiplied(Vec<Multiplied<T>>),
    /// Two words per cell.
    Compensated(Vec<Compensated<T>>),
}

impl<T: Real> DynMaxwell<T> {
    /// Builds the bank.
    pub fn new(
        form: MaxwellForm,
        specs: &[MaxwellSpec],
        dt: f64,
        storage: Storage,
    ) -> Result<Self, ParamError> {
        Self::tuned(form, specs, dt, storage, 1.0)
    }

    /// The bank of `specs` (at the reference temperature) tuned to the
    /// shift factor `a_t`: each cell built by the core's constructor with
    /// its corner ω_i / a_t, as [`bushing::MaxwellBank::shifted`] builds
    /// them (a_t = 1 leaves every corner as given).
    fn tuned(
        form: MaxwellForm,
        specs: &[MaxwellSpec],
        dt: f64,
        storage: Storage,
        a_t: f64,
    ) -> Result<Self, ParamError> {
        let param = Param::scalar("a_t");
        if !a_t.is_finite() {
            return Err(ParamError::NotFinite { param });
        }
        if a_t <= 0.0 {
            return Err(ParamError::NotPositive { param, value: a_t });
        }
        let cells = specs
            .iter()
            .enumerate()
            .map(|(i, s)| MaxwellCell::new(form, MaxwellSpec::new(s.omega / a_t, s.g), dt, i))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            form,
            specs: specs.to_vec(),
            tangent_gain: maxwell::tangent_gain(&cells),
            cells,
            fraction: specs.iter().map(|s| s.g).sum(),
            dt,
            storage,
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
        let n = self.cells.len();
        match self.storage {
            Storage::Plain => DynMaxwellState::Plain(zeros(n)),
            Storage::Multiplied => DynMaxwellState::Multiplied(zeros(n)),
            Storage::Compensated => DynMaxwellState::Compensated(zeros(n)),
        }
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        match state {
            DynMaxwellState::Plain(s) => {
                maxwell::step_cells(self.form, &self.cells, s, self.tangent_gain, drive)
            }
            DynMaxwellState::Multiplied(s) => {
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

/// Iwan bank, clamp form, sized at run time (the core's clamp kernel).
#[derive(Debug, Clone)]
pub struct DynIwanClamp<T> {
    cells: Vec<ClampCell<T>>,
    fraction: f64,
}

impl<T: Real> Effect<T> for DynIwanClamp<T> {
    type State = (Vec<T>, Held<T>);
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        None
    }
    fn rest(&self, _: T) -> Self::State {
        (vec![T::ZERO; self.cells.len()], Held::default())
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        iwan::step_clamp(&self.cells, &mut state.0, &mut state.1, drive)
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// Iwan bank, slider form.
pub type DynIwanSliders<T> = DynBank<T, SliderCell<T>>;
/// x_f bank.
pub type DynXf<T> = DynBank<T, XfCell<T>>;

fn iwan_clamp<T: Real>(specs: &[IwanCellSpec]) -> Result<DynIwanClamp<T>, ParamError> {
    Ok(DynIwanClamp {
        cells: specs
            .iter()
            .enumerate()
            .map(|(i, s)| ClampCell::new(*s, i))
            .collect::<Result<_, _>>()?,
        fraction: specs.iter().map(|s| s.g).sum(),
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

/// Declares [`DynGrunwald`] and its state over a menu of memory lengths.
macro_rules! grunwald_menu {
    ($($variant:ident = $n:literal),+ $(,)?) => {
        /// A Grünwald fractional cell (the core's [`Grunwald`]) whose memory
        /// length N, a const generic of the core, is picked at run time from
        /// [`FRACTIONAL_TAPS`](crate::scene::FRACTIONAL_TAPS): one
        /// monomorphised cell per length. The parameters (N weights) are
        /// shared, so cloning a built model does not copy them.
        #[derive(Debug, Clone)]
        pub enum DynGrunwald<T> {
            $(
                #[doc = concat!("N = ", stringify!($n), ".")]
                $variant(Arc<Grunwald<T, $n>>),
            )+
        }

        /// State of a [`DynGrunwald`]: the core's ring of N values, boxed.
        #[derive(Debug, PartialEq)]
        pub enum DynGrunwaldState<T> {
            $(
                #[doc = concat!("N = ", stringify!($n), ".")]
                $variant(Box<GrunwaldState<T, $n>>),
            )+
        }

        impl<T: Real> Clone for DynGrunwaldState<T> {
            fn clone(&self) -> Self {
                match self {
                    $(Self::$variant(s) => Self::$variant(s.clone()),)+
                }
            }
            /// Copies into the same box when both are of one length: an
            /// effect list keeps a copy of every state before each step.
            fn clone_from(&mut self, source: &Self) {
                match (self, source) {
                    $((Self::$variant(d), Self::$variant(s)) => (**d).clone_from(s),)+
                    (d, s) => *d = s.clone(),
                }
            }
        }

        impl<T: Real> DynGrunwald<T> {
            /// Builds the cell with `taps` history taps (one of the menu)
            /// for time step `dt`; the core's checks of `spec` and `dt`.
            pub fn new(spec: FractionalSpec, taps: usize, dt: f64) -> Result<Self, ParamError> {
                match taps {
                    $($n => Ok(Self::$variant(Arc::new(Grunwald::new(spec, dt)?))),)+
                    // The scene reader names the menu; this is its ends.
                    _ => Err(ParamError::OutOfRange {
                        param: Param::scalar("taps"),
                        value: taps as f64,
                        min: FRACTIONAL_TAPS[0] as f64,
                        min_open: false,
                        max: FRACTIONAL_TAPS[FRACTIONAL_TAPS.len() - 1] as f64,
                    }),
                }
            }

            /// Memory length N.
            pub fn taps(&self) -> usize {
                match self {
                    $(Self::$variant(_) => $n,)+
                }
            }

            /// Branch share of the complex stiffness over K^∞ at ω (rad/s),
            /// as (storage, loss): the discrete cell's exact steady state
            /// ([`Grunwald::branch_response`]).
            pub fn branch_response(&self, omega: f64) -> (f64, f64) {
                match self {
                    $(Self::$variant(c) => c.branch_response(omega),)+
                }
            }
        }

        impl<T: Real> Effect<T> for DynGrunwald<T> {
            type State = DynGrunwaldState<T>;
            type Report = EffectOutput<T>;

            fn fraction(&self) -> f64 {
                match self {
                    $(Self::$variant(c) => c.fraction(),)+
                }
            }
            fn dt(&self) -> Option<f64> {
                match self {
                    $(Self::$variant(c) => c.dt(),)+
                }
            }
            fn rest(&self, x0: T) -> Self::State {
                match self {
                    $(Self::$variant(c) => DynGrunwaldState::$variant(Box::new(c.rest(x0))),)+
                }
            }
            #[inline]
            fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
                match (self, state) {
                    $((Self::$variant(c), DynGrunwaldState::$variant(s)) => c.step(s, drive),)+
                    // A state always comes from its own cell's `rest`.
                    _ => EffectOutput::zero(),
                }
            }
            fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
                *report
            }
            /// The core's refusal, which keeps only what a step writes.
            #[inline]
            fn step_if(
                &self,
                state: &mut Self::State,
                drive: &Drive<T>,
                accept: impl FnOnce(&EffectOutput<T>) -> bool,
            ) -> Option<EffectOutput<T>> {
                match (self, state) {
                    $((Self::$variant(c), DynGrunwaldState::$variant(s)) => {
                        c.step_if(s, drive, accept)
                    })+
                    _ => None,
                }
            }
        }
    };
}

grunwald_menu!(X16 = 16, X64 = 64, X256 = 256, X1024 = 1024, X4096 = 4096);

/// Turning-point model with the STS law.
pub type StsStack<T> = TurningPoints<Sts<T>, STACK_DEPTH>;
/// Turning-point model with a measured K_f table.
pub type TableStack<T> = TurningPoints<KfTable<T, TABLE_POINTS>, STACK_DEPTH>;

/// One effect a scene can name, built.
#[derive(Debug, Clone)]
pub enum AnyEffect<T> {
    /// Maxwell bank.
    Maxwell(DynMaxwell<T>),
    /// Iwan bank, clamp form.
    Clamp(DynIwanClamp<T>),
    /// Iwan bank, slider form.
    Sliders(DynIwanSliders<T>),
    /// x_f bank.
    Xf(DynXf<T>),
    /// Turning-point stack, STS law.
    Sts(StsStack<T>),
    /// Turning-point stack, measured table.
    Table(TableStack<T>),
    /// Dahl cell.
    Dahl(Dahl<T>),
    /// Bouc-Wen cell.
    BoucWen(BoucWen<T>),
    /// Berg cell.
    Berg(Berg<T>),
    /// Grünwald fractional cell.
    Fractional(DynGrunwald<T>),
}

/// State of one [`AnyEffect`].
#[derive(Debug, Clone, PartialEq)]
pub enum AnyState<T: Real> {
    /// Maxwell bank.
    Maxwell(<DynMaxwell<T> as Effect<T>>::State),
    /// Iwan bank, clamp form.
    Clamp(<DynIwanClamp<T> as Effect<T>>::State),
    /// Iwan bank, slider form.
    Sliders(<DynIwanSliders<T> as Effect<T>>::State),
    /// x_f bank.
    Xf(<DynXf<T> as Effect<T>>::State),
    /// Turning-point stack, STS law.
    Sts(<StsStack<T> as Effect<T>>::State),
    /// Turning-point stack, measured table.
    Table(<TableStack<T> as Effect<T>>::State),
    /// Dahl cell.
    Dahl(<Dahl<T> as Effect<T>>::State),
    /// Bouc-Wen cell.
    BoucWen(<BoucWen<T> as Effect<T>>::State),
    /// Berg cell.
    Berg(<Berg<T> as Effect<T>>::State),
    /// Grünwald fractional cell.
    Fractional(<DynGrunwald<T> as Effect<T>>::State),
}

/// Calls `$f` with the effect inside an [`AnyEffect`] (one arm per kind).
macro_rules! each_effect {
    ($e:expr, |$x:ident| $f:expr) => {
        match $e {
            AnyEffect::Maxwell($x) => $f,
            AnyEffect::Clamp($x) => $f,
            AnyEffect::Sliders($x) => $f,
            AnyEffect::Xf($x) => $f,
            AnyEffect::Sts($x) => $f,
            AnyEffect::Table($x) => $f,
            AnyEffect::Dahl($x) => $f,
            AnyEffect::BoucWen($x) => $f,
            AnyEffect::Berg($x) => $f,
            AnyEffect::Fractional($x) => $f,
        }
    };
}

impl<T: Real> AnyEffect<T> {
    fn fraction(&self) -> f64 {
        each_effect!(self, |e| e.fraction())
    }
    fn check_dt(&self, dt: Option<f64>) -> Result<Option<f64>, ParamError> {
        each_effect!(self, |e| e.check_dt(dt))
    }
    fn rest(&self, x0: T) -> AnyState<T> {
        match self {
            Self::Maxwell(e) => AnyState::Maxwell(e.rest(x0)),
            Self::Clamp(e) => AnyState::Clamp(e.rest(x0)),
            Self::Sliders(e) => AnyState::Sliders(e.rest(x0)),
            Self::Xf(e) => AnyState::Xf(e.rest(x0)),
            Self::Sts(e) => AnyState::Sts(e.rest(x0)),
            Self::Table(e) => AnyState::Table(e.rest(x0)),
            Self::Dahl(e) => AnyState::Dahl(e.rest(x0)),
            Self::BoucWen(e) => AnyState::BoucWen(e.rest(x0)),
            Self::Berg(e) => AnyState::Berg(e.rest(x0)),
            Self::Fractional(e) => AnyState::Fractional(e.rest(x0)),
        }
    }
    #[inline(always)]
    fn step(&self, state: &mut AnyState<T>, drive: &Drive<T>) -> EffectOutput<T> {
        fn go<T: Real, E: Effect<T>>(e: &E, s: &mut E::State, d: &Drive<T>) -> EffectOutput<T> {
            E::total(&e.step(s, d))
        }
        match (self, state) {
            (Self::Maxwell(e), AnyState::Maxwell(s)) => go(e, s, drive),
            (Self::Clamp(e), AnyState::Clamp(s)) => go(e, s, drive),
            (Self::Sliders(e), AnyState::Sliders(s)) => go(e, s, drive),
            (Self::Xf(e), AnyState::Xf(s)) => go(e, s, drive),
            (Self::Sts(e), AnyState::Sts(s)) => go(e, s, drive),
            (Self::Table(e), AnyState::Table(s)) => go(e, s, drive),
            (Self::Dahl(e), AnyState::Dahl(s)) => go(e, s, drive),
            (Self::BoucWen(e), AnyState::BoucWen(s)) => go(e, s, drive),
            (Self::Berg(e), AnyState::Berg(s)) => go(e, s, drive),
            (Self::Fractional(e), AnyState::Fractional(s)) => go(e, s, drive),
            // A state always comes from its own effect's `rest`.
            _ => EffectOutput::zero(),
        }
    }
}

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
#[derive(Debug, Clone)]
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

impl<T: Real> PartialEq for Slot<T> {
    fn eq(&self, other: &Self) -> bool {
        self.state == other.state && self.last == other.last
    }
}

impl<T: Real> AnyState<T> {
    /// Makes `self` equal to `src`, reusing `self`'s storage when both are
    /// of the same kind (no allocation in a running list).
    fn copy_from(&mut self, src: &Self) {
        match (self, src) {
            (Self::Maxwell(d), Self::Maxwell(s)) => match (d, s) {
                (DynMaxwellState::Plain(d), DynMaxwellState::Plain(s)) => d.clone_from(s),
                (DynMaxwellState::Multiplied(d), DynMaxwellState::Multiplied(s)) => d.clone_from(s),
                (DynMaxwellState::Compensated(d), DynMaxwellState::Compensated(s)) => {
                    d.clone_from(s)
                }
                (d, s) => d.clone_from(s),
            },
            (Self::Clamp(d), Self::Clamp(s)) => {
                d.0.clone_from(&s.0);
                d.1 = s.1;
            }
            (Self::Sliders(d), Self::Sliders(s)) | (Self::Xf(d), Self::Xf(s)) => d.clone_from(s),
            (Self::Fractional(d), Self::Fractional(s)) => d.clone_from(s),
            (d, s) => d.clone_from(s),
        }
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

/// Effects as a temperature history re-tunes them: only the Maxwell banks
/// move, their corners ω_i / a_T (seed 000 eqs 1.46-1.48; see
/// [`bushing::temperature`] for the direction of a_T); every other effect
/// is kept as it is.
pub trait Tuned: Sized {
    /// The same effect with its Maxwell corners at the shift factor `a_t`,
    /// absolute (from the corners as given, whatever the effect is tuned to
    /// now, so repeated re-tunes do not drift).
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError>;
}

impl<T: Real> Tuned for DynMaxwell<T> {
    /// Every cell rebuilt by the core's constructor at ω_i / a_t, as
    /// [`bushing::MaxwellBank::shifted`] does; the state carries over (it
    /// holds branch forces or relaxations, not coefficients).
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Self::tuned(self.form, &self.specs, self.dt, self.storage, a_t)
    }
}

/// Effects a temperature leaves as they are.
macro_rules! untuned {
    ($($ty:ty),+ $(,)?) => {
        $(
            impl<T: Real> Tuned for $ty {
                fn shifted(&self, _: f64) -> Result<Self, ParamError> {
                    Ok(self.clone())
                }
            }
        )+
    };
}

untuned!(
    DynIwanClamp<T>,
    DynIwanSliders<T>,
    DynXf<T>,
    StsStack<T>,
    TableStack<T>,
    Dahl<T>,
    BoucWen<T>,
    Berg<T>,
    DynGrunwald<T>,
);

impl Tuned for () {
    fn shifted(&self, _: f64) -> Result<Self, ParamError> {
        Ok(())
    }
}

impl<E: Tuned> Tuned for (E,) {
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Ok((self.0.shifted(a_t)?,))
    }
}

impl<T: Real> Tuned for AnyEffect<T> {
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Ok(match self {
            Self::Maxwell(e) => Self::Maxwell(e.shifted(a_t)?),
            other => other.clone(),
        })
    }
}

impl<T: Real> Tuned for EffectList<T> {
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Ok(Self {
            effects: self
                .effects
                .iter()
                .map(|e| e.shifted(a_t))
                .collect::<Result<_, _>>()?,
        })
    }
}

/// `bushing` with its effects at the shift factor `a_t` (same backbone).
fn shifted_bushing<T: Real, E: Effect<T> + Tuned>(
    bushing: &Bushing<T, AnyBackbone<T>, E>,
    a_t: f64,
) -> Result<Bushing<T, AnyBackbone<T>, E>, ParamError> {
    Bushing::new(bushing.backbone().clone(), bushing.effects().shifted(a_t)?)
}

/// The effects a scene can name, as built for it.
pub type SceneEffects<T> = EffectList<T>;

/// A bushing built from a scene.
pub type SceneBushing<T> = Bushing<T, AnyBackbone<T>, SceneEffects<T>>;

/// State of a [`SceneBushing`].
pub type SceneState<T> = BushingState<T, <SceneEffects<T> as Effect<T>>::State>;

/// Builds the bushing a scene describes, with only its effects.
pub fn build<T: Real>(scene: &Scene) -> Result<SceneBushing<T>, ParamError> {
    let mut effects = Vec::with_capacity(scene.effects.len());
    for e in &scene.effects {
        effects.push(match e {
            EffectDesc::Maxwell {
                form,
                storage,
                cells,
            } => AnyEffect::Maxwell(DynMaxwell::new(*form, cells, scene.dt, *storage)?),
            EffectDesc::Iwan {
                slider: false,
                cells,
                ..
            } => AnyEffect::Clamp(iwan_clamp(cells)?),
            EffectDesc::Iwan {
                slider: true,
                k_ref,
                cells,
            } => AnyEffect::Sliders(iwan_sliders(cells, *k_ref)?),
            EffectDesc::Xf { form, cells } => AnyEffect::Xf(xf_bank(*form, cells, scene.dt)?),
            EffectDesc::TurningPoints { law, first_loading } => match law {
                Law::Sts { c, k1 } => {
                    AnyEffect::Sts(TurningPoints::new(Sts::new(*c, *k1)?, *first_loading))
                }
                Law::Table { d, k } => {
                    AnyEffect::Table(TurningPoints::new(KfTable::new(d, k)?, *first_loading))
                }
            },
            EffectDesc::Friction(Friction::Dahl(p)) => {
                AnyEffect::Dahl(Dahl::new(p.k_d, p.f_f, p.alpha)?)
            }
            EffectDesc::Friction(Friction::BoucWen(p)) => {
                AnyEffect::BoucWen(BoucWen::new(p.alpha, p.a, p.beta, p.gamma, p.n)?)
            }
            EffectDesc::Friction(Friction::Berg(p)) => AnyEffect::Berg(Berg::new(p.f_max, p.x2)?),
            EffectDesc::Fractional { spec, taps } => {
                AnyEffect::Fractional(DynGrunwald::new(*spec, *taps, scene.dt)?)
            }
        });
    }
    Bushing::new(backbone(&scene.backbone)?, EffectList { effects })
}

/// Names of the effects present, in trace-column order.
pub fn effect_names(scene: &Scene) -> Vec<String> {
    scene.effects.iter().map(EffectDesc::name).collect()
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
        stepping_pass(&self.bushing, inputs, x0)
    }
    fn retune(&mut self, a_t: f64) -> Result<(), ParamError> {
        if a_t != self.shift {
            self.bushing = shifted_bushing(&self.bushing, a_t)?;
            self.shift = a_t;
        }
        Ok(())
    }
}

/// Steps `bushing` from rest at `x0` through `inputs`, reading force,
/// tangent and dissipated energy as a control loop does, and returns the
/// wall-clock time of the steps. Never inlined, so that an instruction
/// counter can select it by name (`cost --instructions`).
#[inline(never)]
pub fn stepping_pass<T: Real, B: Backbone<T>, E: Effect<T>>(
    bushing: &Bushing<T, B, E>,
    inputs: &[T],
    x0: T,
) -> std::time::Duration {
    let mut state = bushing.state_at(x0);
    let start = std::time::Instant::now();
    for &x in inputs {
        let o = bushing.step(&mut state, x);
        std::hint::black_box((o.force, o.tangent, o.dissipated));
    }
    start.elapsed()
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

/// A unit mass on a scene's bushing, `x'' + F(x) = f(t)`, integrated by the
/// core's [`Oscillator`] (Newmark's average acceleration with a chord
/// iteration); the inputs are the forces f.
struct OscillatorModel<T: Real> {
    oscillator: Oscillator<T, AnyBackbone<T>, EffectList<T>>,
    state: OscillatorState<T, Vec<Slot<T>>>,
    start: (T, T),
    count: usize,
    unconverged: u32,
    /// The shift factor the Maxwell banks are tuned to.
    shift: f64,
}

impl<T: Real + 'static> OscillatorModel<T> {
    fn boxed(
        bushing: SceneBushing<T>,
        dt: f64,
        spec: crate::scene::OscillatorSpec,
        f0: T,
    ) -> Result<Box<dyn SceneModel<T>>, ParamError> {
        let count = bushing.effects().effects().len();
        let oscillator = Oscillator::new(bushing, dt)?;
        let start = (T::from_f64(spec.p0), T::from_f64(spec.v0));
        let state = oscillator.state_at(start.0, start.1, f0);
        Ok(Box::new(Self {
            oscillator,
            state,
            start,
            count,
            unconverged: 0,
            shift: 1.0,
        }))
    }
}

impl<T: Real> SceneModel<T> for OscillatorModel<T> {
    fn shape(&self) -> Shape {
        Shape::Oscillator
    }
    fn backbone(&self) -> &AnyBackbone<T> {
        self.oscillator.restoring().backbone()
    }
    fn g0(&self) -> f64 {
        self.oscillator.restoring().g0()
    }
    fn effect_count(&self) -> usize {
        self.count
    }
    /// Steps refused by the restoring force, plus steps whose iteration
    /// did not converge.
    fn refused(&self) -> u32 {
        self.state
            .restoring()
            .rejected()
            .saturating_add(self.unconverged)
    }
    fn step_into(
        &mut self,
        inputs: &[T],
        rows: &mut Vec<StepRow<T>>,
        parts: &mut Vec<EffectOutput<T>>,
    ) {
        let g0 = T::from_f64(self.g0());
        for &f in inputs {
            let o = self.oscillator.step(&mut self.state, f);
            if !o.converged {
                self.unconverged = self.unconverged.saturating_add(1);
            }
            let restoring = self.state.restoring();
            let (f_inf, _) = self.oscillator.restoring().backbone().eval(o.p);
            rows.push(StepRow {
                x: o.p,
                force: o.force,
                tangent: restoring.tangent(),
                dissipated: o.dissipated,
                elastic: g0 * f_inf,
                refused: !o.converged,
            });
            EffectList::parts(restoring.effects(), &EffectOutput::zero(), parts);
        }
    }
    /// Steps from the scene's initial displacement and velocity (the
    /// start force is the first input); `x0` is not used.
    fn time_steps(&self, inputs: &[T], _x0: T) -> std::time::Duration {
        let f0 = inputs.first().copied().unwrap_or(T::ZERO);
        let mut state = self.oscillator.state_at(self.start.0, self.start.1, f0);
        let start = std::time::Instant::now();
        for &f in inputs {
            let o = self.oscillator.step(&mut state, f);
            std::hint::black_box((o.p, o.force, o.dissipated));
        }
        start.elapsed()
    }
    /// The restoring force re-tuned, and the oscillator built on it again
    /// (its chord slope follows the tangent at rest).
    fn retune(&mut self, a_t: f64) -> Result<(), ParamError> {
        if a_t != self.shift {
            let restoring = shifted_bushing(self.oscillator.restoring(), a_t)?;
            self.oscillator = Oscillator::new(restoring, self.oscillator.dt())?;
            self.shift = a_t;
        }
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fractional_menu_builds_every_listed_length_and_no_other() {
        let spec = FractionalSpec::hz(5.0, 0.5, 0.6);
        for n in 0..=2 * FRACTIONAL_TAPS[FRACTIONAL_TAPS.len() - 1] {
            match DynGrunwald::<f32>::new(spec, n, 1e-3) {
                Ok(cell) => {
                    assert!(FRACTIONAL_TAPS.contains(&n), "{n} is not listed");
                    assert_eq!(cell.taps(), n);
                    assert_eq!(cell.fraction(), 0.6);
                    assert_eq!(cell.dt(), Some(1e-3));
                }
                Err(e) => {
                    assert!(!FRACTIONAL_TAPS.contains(&n), "{n}: {e}");
                    assert!(matches!(e, ParamError::OutOfRange { .. }), "{e}");
                }
            }
        }
    }

    #[test]
    fn a_fractional_state_is_copied_into_its_own_box() {
        let cell = DynGrunwald::<f64>::new(FractionalSpec::hz(5.0, 0.5, 0.6), 256, 1e-3).unwrap();
        let drive = Drive {
            x: 1.0,
            dx: 1.0,
            f_inf: 100.0,
            df_inf: 100.0,
            k_inf: 100.0,
        };
        let mut stepped = cell.rest(0.0);
        cell.step(&mut stepped, &drive);
        let mut copy = cell.rest(0.0);
        let DynGrunwaldState::X256(boxed) = &copy else {
            panic!("256 taps");
        };
        let before = std::ptr::from_ref(&**boxed);
        copy.clone_from(&stepped);
        assert_eq!(copy, stepped);
        let DynGrunwaldState::X256(boxed) = &copy else {
            panic!("256 taps");
        };
        assert_eq!(std::ptr::from_ref(&**boxed), before, "no new allocation");
    }
}
