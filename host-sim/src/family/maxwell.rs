//! Maxwell banks (seed 000 eqs 1.13-1.17): `type = "maxwell"`.
//!
//! ```toml
//! [[effects]]
//! type = "maxwell"
//! form = "rate-exact-ramp"   # any `MaxwellForm` name
//! state = "compensated"      # plain (default), multiplied, compensated
//! cells = [{ f_hz = 0.5, g = 0.08 }, { f_hz = 5.0, g = 0.1 }]
//! ```
//!
//! The table is read straight into the core's `MaxwellForm` and
//! `MaxwellSpec` (its checked `f_hz`, `g`); [`DynMaxwell`] runs the core's
//! `maxwell::step_cells`, the code of the const-size bank.

use std::f64::consts::{PI, TAU};

use bushing::{
    Accumulator, Bushing, Compensated, Drive, Effect, EffectOutput, MaxwellBank, MaxwellCell,
    MaxwellForm, MaxwellSpec, Multiplied, Param, ParamError, Plain, Real, maxwell,
};
use serde::Deserialize;

use super::backbone::AnyBackbone;
use super::{Tuned, check_count};
use crate::cost::timer::{Timer, timer};
use crate::reference::{Drive as Profile, Line, Measured, compared, no};

/// `[[effects]] type = "maxwell"`, as written and as checked.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Maxwell {
    /// Discrete form (eqs 1.13-1.17).
    pub form: MaxwellForm,
    /// How each cell stores its state.
    #[serde(default)]
    pub state: Storage,
    /// The cells: corner frequency `f_hz` (ω = 2π f) and load fraction `g`.
    pub cells: Vec<MaxwellSpec>,
}

/// How the cells of a Maxwell bank store their state (the core's
/// accumulators).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Storage {
    /// `F - d F`, one word ([`bushing::Plain`]): slow cells keep their rate.
    #[default]
    Plain,
    /// `e^-h F`, one word ([`bushing::Multiplied`]): for cells not slow.
    Multiplied,
    /// Fast2Sum, two words ([`bushing::Compensated`]): slow cells in f32.
    Compensated,
}

impl Storage {
    /// The scene's name of the storage.
    pub fn name(self) -> &'static str {
        match self {
            Self::Plain => "plain",
            Self::Multiplied => "multiplied",
            Self::Compensated => "compensated",
        }
    }
}

impl Maxwell {
    /// What the bank's constructor does not check: the number of cells and
    /// the sum of their fractions.
    pub(super) fn check(self) -> Result<Self, String> {
        check_count(self.cells.len())?;
        let sum: f64 = self.cells.iter().map(|c| c.g).sum();
        if sum > 1.0 + 1e-12 {
            return Err(ParamError::FractionsAboveOne { sum }.to_string());
        }
        Ok(self)
    }

    /// The bank in `T` at time step `dt`.
    pub fn build<T: Real>(&self, dt: f64) -> Result<DynMaxwell<T>, ParamError> {
        DynMaxwell::new(self.form, &self.cells, dt, self.state)
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        format!("maxwell {} x{}", self.form.name(), self.cells.len())
    }

    /// Under a sine on a linear backbone K: the first harmonic against the
    /// discrete bank's exact steady state `K (g^0 + Σ H_i(e^{iωΔt}))` and
    /// against eq 1.8, `K (g^0 + Σ g_i iω / (iω + ω_i))`; the energy per
    /// cycle against `π X² K''`.
    pub(super) fn references<T: Real>(&self, bank: &DynMaxwell<T>, m: &Measured) -> Vec<Line> {
        if m.retuned {
            return no("a [temperature] history moves the corners during the run");
        }
        let (Profile::Sine(f), Some(k)) = (m.drive, m.k_lin) else {
            return no("the complex modulus needs a sine on a linear backbone");
        };
        let omega = TAU * f;
        let discrete = bank.branch_response(omega);
        let mut continuous = (0.0, 0.0);
        for c in &self.cells {
            let r = c.omega / omega;
            continuous.0 += c.g / (1.0 + r * r);
            continuous.1 += c.g * r / (1.0 + r * r);
        }
        let Some((storage, loss)) = m.modulus else {
            return no("the least-squares fit is singular");
        };
        let slowest = self
            .cells
            .iter()
            .map(|c| c.omega)
            .fold(f64::INFINITY, f64::min);
        let left = (-slowest * m.t0).exp();
        let note = if left > 1e-4 {
            format!("; transient of the slowest cell e^(-omega t) = {left:.1e} at the window")
        } else {
            String::new()
        };
        let (g0, x) = (m.g0, m.x_amplitude);
        vec![
            compared(
                format!(
                    "storage K' of g0 K x + bank force, first harmonic vs the discrete bank's exact response{note}"
                ),
                "N/mm",
                k * (g0 + discrete.0),
                storage,
            ),
            compared(
                "loss K'' vs the discrete bank's exact response",
                "N/mm",
                k * discrete.1,
                loss,
            ),
            compared(
                "storage K' vs eq 1.8 (continuous)",
                "N/mm",
                k * (g0 + continuous.0),
                storage,
            ),
            compared(
                "loss K'' vs eq 1.8 (continuous)",
                "N/mm",
                k * continuous.1,
                loss,
            ),
            compared(
                "energy per steady cycle vs pi X^2 K'' (discrete bank)",
                "mJ",
                PI * x * x * k * discrete.1,
                m.per_cycle,
            ),
        ]
    }

    /// The cost comparison: the same cells (1 to 8) as the const-size
    /// [`MaxwellBank`] firmware declares, on `backbone`, with its name.
    pub fn firmware<T: Real + 'static>(
        &self,
        backbone: &AnyBackbone<T>,
        dt: f64,
        number: &str,
    ) -> Option<(String, Timer<T>)> {
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
                match self.cells.len() {
                    1 => bank::<T, $acc, 1>(backbone, self.form, &self.cells, dt),
                    2 => bank::<T, $acc, 2>(backbone, self.form, &self.cells, dt),
                    3 => bank::<T, $acc, 3>(backbone, self.form, &self.cells, dt),
                    4 => bank::<T, $acc, 4>(backbone, self.form, &self.cells, dt),
                    5 => bank::<T, $acc, 5>(backbone, self.form, &self.cells, dt),
                    6 => bank::<T, $acc, 6>(backbone, self.form, &self.cells, dt),
                    7 => bank::<T, $acc, 7>(backbone, self.form, &self.cells, dt),
                    8 => bank::<T, $acc, 8>(backbone, self.form, &self.cells, dt),
                    _ => None,
                }
            };
        }
        let (timer, accumulator) = match self.state {
            Storage::Plain => (sizes!(Plain<T>), ""),
            Storage::Multiplied => (sizes!(Multiplied<T>), ", Multiplied"),
            Storage::Compensated => (sizes!(Compensated<T>), ", Compensated"),
        };
        let name = format!(
            "{} as a const-size MaxwellBank<{number}, {}{accumulator}>, effect only",
            self.name(),
            self.cells.len(),
        );
        timer.map(|t| (name, t))
    }
}

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
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum DynMaxwellState<T> {
    /// One word per cell, `F - d F`.
    Plain(Vec<Plain<T>>),
    /// One word per cell, `e^-h F`.
    Multiplied(Vec<Multiplied<T>>),
    /// Two words per cell.
    Compensated(Vec<Compensated<T>>),
}

impl<T: Real> DynMaxwellState<T> {
    /// Makes `self` equal to `src`, in place when both store alike.
    pub(super) fn copy_from(&mut self, src: &Self) {
        match (self, src) {
            (Self::Plain(d), Self::Plain(s)) => d.clone_from(s),
            (Self::Multiplied(d), Self::Multiplied(s)) => d.clone_from(s),
            (Self::Compensated(d), Self::Compensated(s)) => d.clone_from(s),
            (d, s) => d.clone_from(s),
        }
    }
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

    /// Branch share of the complex stiffness over K^∞ at ω (rad/s), as
    /// (storage, loss): the discrete bank's exact steady state, with its
    /// coefficients as stored in `T` ([`maxwell::branch_response`]).
    pub fn branch_response(&self, omega: f64) -> (f64, f64) {
        maxwell::branch_response(self.form, &self.cells, omega * self.dt)
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

impl<T: Real> Tuned for DynMaxwell<T> {
    /// Every cell rebuilt by the core's constructor at ω_i / a_t, as
    /// [`bushing::MaxwellBank::shifted`] does; the state carries over (it
    /// holds branch forces or relaxations, not coefficients).
    fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Self::tuned(self.form, &self.specs, self.dt, self.storage, a_t)
    }
}
