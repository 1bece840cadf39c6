//! The banks a scene sizes at run time (Maxwell, Iwan, x_f) and the
//! fractional cell behind its menu of lengths: each steps with the core's
//! own cell scheme, the same code the const-size banks run.

use std::sync::Arc;

use bushing::fractional::{FractionalSpec, Grunwald, GrunwaldState};
use bushing::iwan::{self, ClampCell, Held, SliderCell};
use bushing::maxwell::{self, MaxwellCell};
use bushing::xf::{self, XfCell};
use bushing::{
    Accumulator, Compensated, Drive, Effect, EffectOutput, IwanCellSpec, MaxwellForm, MaxwellSpec,
    Multiplied, Param, ParamError, Plain, Real, XfForm, XfSpec,
};

use crate::scene::{FRACTIONAL_TAPS, Storage};

/// A Maxwell bank sized at run time; the scheme is the core's
/// [`maxwell::step_cells`], the same code the const-size bank runs.
#[derive(Debug, Clone)]
pub struct DynMaxwell<T> {
    pub(super) form: MaxwellForm,
    /// The cells at the reference temperature, as given.
    pub(super) specs: Vec<MaxwellSpec>,
    cells: Vec<MaxwellCell<T>>,
    tangent_gain: T,
    fraction: f64,
    pub(super) dt: f64,
    pub(super) storage: Storage,
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
    pub(super) fn tuned(
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

pub(super) fn iwan_clamp<T: Real>(specs: &[IwanCellSpec]) -> Result<DynIwanClamp<T>, ParamError> {
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

pub(super) fn xf_bank<T: Real>(
    form: XfForm,
    specs: &[XfSpec],
    dt: f64,
) -> Result<DynXf<T>, ParamError> {
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
