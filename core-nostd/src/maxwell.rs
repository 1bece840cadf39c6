//! Generalised Maxwell cells in the five discrete forms of seed 000 §1.3.2.
//!
//! A Maxwell branch `i` has a corner angular frequency ω_i (rad/s; the pole is
//! `-ω_i`, the corner in Hz `ω_i / 2π`) and a load fraction g_i of the
//! high-frequency backbone. Its continuous laws are the load relaxation
//! (eq 1.11) `Ḟ^i/ω_i + F^i = -g_i F^∞(x)` and the load-rate relaxation
//! (eq 1.12) `Ḟ^i + ω_i F^i = g_i Ḟ^∞(x)`; the bushing force is
//! `F = g^0 F^∞ + Σ branch forces` (eq 1.9) with the static limit
//! `g^0 = 1 - Σ g_i`, and for a linear backbone `F^∞ = K^∞ x` the complex
//! stiffness is eq 1.8, `K(iω) = K^∞ (g^0 + Σ g_i iω / (iω + ω_i))`.
//!
//! With `h = ω_i dt` every form is the one recurrence
//!
//! ```text
//! F^i_n = F^i_{n-1} - d F^i_{n-1} + p ΔF^∞_n + q F^∞_n
//! ```
//!
//! | form | eq | d | p | q |
//! |---|---|---|---|---|
//! | [`MaxwellForm::LoadExplicit`] | 1.13 | h | 0 | -h g |
//! | [`MaxwellForm::LoadExponential`] | 1.15 | 1 - e^-h | h g e^(-h/2) / 2 | -h g e^(-h/2) |
//! | [`MaxwellForm::RateExplicit`] | 1.16 | h | g | 0 |
//! | [`MaxwellForm::RateMidpoint`] | 1.17 | 1 - e^-h | g e^(-h/2) | 0 |
//! | [`MaxwellForm::RateExactRamp`] | 1.12 exact | 1 - e^-h | g (1 - e^-h)/h | 0 |
//!
//! The load forms carry the relaxation `F^i_LR = F^i - g_i F^∞` and report the
//! branch force `F^i_LR + g_i F^∞`, so every form reports the same branch
//! forces. `d = -expm1(-h)` is computed in `f64` and stored, so slow cells
//! keep their decay rate (`1 - e^-h` formed in `f32` would lose it).
//!
//! - **States**: one accumulator per cell (one word, or two with
//!   [`Compensated`](crate::Compensated)); the bushing keeps the shared
//!   `F^∞_{n-1}`.
//! - **Stability**: the exponential forms have the pole `e^-h`, stable for
//!   every h > 0 (finite and bounded from h = 1e-7 to 1e4, tested). The
//!   explicit forms have the pole `1 - h`, which is negative (oscillating)
//!   from h = 1 and unstable from h = 2; they are refused at `h >= 1`
//!   ([`ParamError::ExplicitUnstable`]).
//! - **Accuracy**: the exponential load form (1.15) settles, under a
//!   constant F^∞, on `-g (h/2)/sinh(h/2) F^∞` instead of `-g F^∞`: a
//!   static-gain error of h²/24 per cell, which vanishes only as dt → 0.
//!   The exact-ramp form is exact for a backbone force that
//!   is linear in time over the step; the midpoint form (1.17) replaces
//!   `(1 - e^-h)/h` by `e^(-h/2)`, −4 % at h = 1 and a vanishing gain
//!   (lost loss modulus) for h ≫ 1; see `docs/maxwell-accuracy.md`.
//! - **States and their cost**: the state storage `A` chooses how a cell
//!   applies its pole. [`Plain`] subtracts the stored
//!   decrement, `F - d F` (slow cells keep their decay rate in `f32`);
//!   [`Multiplied`](crate::Multiplied) multiplies by `e^-h` (one
//!   subtraction fewer, for banks whose every ω dt is above about 1e-3);
//!   [`Compensated`](crate::Compensated) adds a Fast2Sum word (exact decay
//!   down to ω dt = 1e-7, three additions more).
//! - **Dissipation**: the dashpot of cell i dissipates `ω_i F_i² / (g_i K^∞)`
//!   per unit time (its force over its damping coefficient); the step
//!   reports `Σ ω_i Δt (F_i,n-1² + F_i,n²) / (2 g_i K^∞)`, the trapezoid
//!   over the step, never negative. Over a steady cycle it tends to the loop
//!   area π X² K'' as the step shrinks (checked by `bushing-sim validate`).
//! - **Cost**: rate forms 2 multiply-adds per cell, load forms 4; the
//!   dissipated energy adds 3 per cell and one division per bank by K^∞.
//!   [`Effect::step_force`] skips the energy and the tangent. Measured on a
//!   Cortex-M4F, a bank of 8 in a rate form through the force-only call
//!   costs 8.7 guest instructions per cell with `Plain` states and 8.0
//!   with `Multiplied` ones (net of the call; `scripts/accuracy-cost.sh`
//!   regenerates the figures in `docs/accuracy-cost.md`).

use core::marker::PhantomData;

use crate::accumulator::{Accumulator, Plain};
use crate::bushing::{Drive, Effect, EffectOutput};
use crate::error::{Param, ParamError, positive, positive_in};
use crate::real::{Exponentials, LibmExp, Real};

/// The discrete form of a Maxwell cell (see the module table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Deserialize, serde::Serialize),
    serde(rename_all = "kebab-case")
)]
pub enum MaxwellForm {
    /// Load relaxation, explicit Euler (eq 1.13).
    LoadExplicit,
    /// Load relaxation, exponential with trapezoid (eq 1.15).
    LoadExponential,
    /// Load-rate relaxation, explicit (eq 1.16).
    RateExplicit,
    /// Load-rate relaxation, exponential midpoint (eq 1.17), the thesis's scheme.
    RateMidpoint,
    /// Load-rate relaxation, exponential integrator exact for a ramp input.
    RateExactRamp,
}

impl MaxwellForm {
    /// Every form, in the order of the thesis.
    pub const ALL: [Self; 5] = [
        Self::LoadExplicit,
        Self::LoadExponential,
        Self::RateExplicit,
        Self::RateMidpoint,
        Self::RateExactRamp,
    ];

    /// Name used in scene files and reports.
    pub const fn name(self) -> &'static str {
        match self {
            Self::LoadExplicit => "load-explicit",
            Self::LoadExponential => "load-exponential",
            Self::RateExplicit => "rate-explicit",
            Self::RateMidpoint => "rate-midpoint",
            Self::RateExactRamp => "rate-exact-ramp",
        }
    }

    /// Parses a name written by [`MaxwellForm::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Equation of seed 000 the form implements.
    pub const fn equation(self) -> &'static str {
        match self {
            Self::LoadExplicit => "1.13",
            Self::LoadExponential => "1.15",
            Self::RateExplicit => "1.16",
            Self::RateMidpoint => "1.17",
            Self::RateExactRamp => "1.12 (exact ramp)",
        }
    }

    /// True for the explicit forms, refused at ω·dt >= 1.
    pub const fn is_explicit(self) -> bool {
        matches!(self, Self::LoadExplicit | Self::RateExplicit)
    }

    /// True for the load (total force) forms, which carry the relaxation.
    pub const fn is_load(self) -> bool {
        matches!(self, Self::LoadExplicit | Self::LoadExponential)
    }
}

/// Parameters of one Maxwell cell as a user gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaxwellSpec {
    /// Corner angular frequency ω_i in rad/s (pole at -ω_i).
    pub omega: f64,
    /// Load fraction g_i of the high-frequency backbone.
    pub g: f64,
}

impl MaxwellSpec {
    /// A cell with corner ω (rad/s) and fraction g.
    pub const fn new(omega: f64, g: f64) -> Self {
        Self { omega, g }
    }
    /// A cell with corner frequency `f` in Hz (ω = 2π f), as Table 3.1 of
    /// seed 000 quotes them.
    pub fn hz(f: f64, g: f64) -> Self {
        Self::new(core::f64::consts::TAU * f, g)
    }
}

/// Precomputed coefficients of one cell (see the module table).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MaxwellCell<T> {
    decay: T,
    /// 1 - decay: the pole, for [`Multiplied`](crate::Multiplied) states.
    keep: T,
    rate_gain: T,
    level_gain: T,
    g: T,
    loss: T,
    tangent: f64,
}

impl<T: Real> MaxwellCell<T> {
    /// Coefficients of cell `index` of a bank in `form` at time step `dt`.
    pub fn new(
        form: MaxwellForm,
        spec: MaxwellSpec,
        dt: f64,
        index: usize,
    ) -> Result<Self, ParamError> {
        let dt = positive(Param::scalar("dt"), dt)?;
        let omega = positive(Param::item("omega", index), spec.omega)?;
        let g = positive(Param::item("g", index), spec.g)?;
        if g > 1.0 {
            return Err(ParamError::CellFractionAboveOne {
                cell: Some(index),
                g,
            });
        }
        let h = omega * dt;
        if !h.is_finite() {
            return Err(ParamError::NotFinite {
                param: Param::item("omega", index),
            });
        }
        let c = coefficients::<f64, LibmExp>(form, h, g, index)?;
        // The same check as in `coefficients`, in the working type.
        let loss = T::from_f64(c.loss);
        if !loss.is_finite() {
            return Err(ParamError::NotFinite {
                param: Param::item("omega", index),
            });
        }
        Ok(Self {
            decay: T::from_f64(c.decay),
            keep: T::from_f64(c.keep),
            rate_gain: T::from_f64(c.rate_gain),
            level_gain: T::from_f64(c.level_gain),
            g: T::from_f64(g),
            loss,
            tangent: c.tangent,
        })
    }

    /// Share of dF/dF^∞ this cell adds to the tangent.
    pub fn tangent_share(&self) -> f64 {
        self.tangent
    }
}

/// The one formula of the module table: the coefficients for
/// `h = ω dt > 0` and fraction `g`, formed in `U` with the exponentials
/// `E` (f64 and libm at construction, the working type at a re-tune).
fn coefficients<U: Real, E: Exponentials<U>>(
    form: MaxwellForm,
    h: U,
    g: U,
    index: usize,
) -> Result<MaxwellCell<U>, ParamError> {
    if form.is_explicit() && h >= U::ONE {
        return Err(ParamError::ExplicitUnstable {
            cell: index,
            omega_dt: h.to_f64(),
        });
    }
    let mid = || E::exp(-(U::HALF * h));
    let (decay, p, q) = match form {
        MaxwellForm::LoadExplicit => (h, U::ZERO, -h * g),
        MaxwellForm::LoadExponential => {
            let m = mid();
            (E::one_minus_exp_neg(h), U::HALF * h * g * m, -h * g * m)
        }
        MaxwellForm::RateExplicit => (h, g, U::ZERO),
        MaxwellForm::RateMidpoint => (E::one_minus_exp_neg(h), g * mid(), U::ZERO),
        MaxwellForm::RateExactRamp => {
            let d = E::one_minus_exp_neg(h);
            (d, g * d / h, U::ZERO)
        }
    };
    // dF_branch/dF^inf_n: p + q, plus g for the load forms.
    let tangent = p + q + if form.is_load() { g } else { U::ZERO };
    // A cell so stiff that its energy coefficient h/g overflows the working
    // type (ω·dt near its largest value) would make every step's
    // dissipated energy infinite or NaN.
    let loss = h / g;
    if !loss.is_finite() || !tangent.is_finite() {
        return Err(ParamError::NotFinite {
            param: Param::item("omega", index),
        });
    }
    Ok(MaxwellCell {
        decay,
        keep: U::ONE - decay,
        rate_gain: p,
        level_gain: q,
        g,
        loss,
        tangent: tangent.to_f64(),
    })
}

/// Sum of the cells' tangent shares, in the working type.
pub fn tangent_gain<T: Real>(cells: &[MaxwellCell<T>]) -> T {
    T::from_f64(cells.iter().map(MaxwellCell::tangent_share).sum())
}

/// Branch share of the complex stiffness over K^∞ of discrete cells in
/// `form` at the angle `theta = ω dt` per step, as (storage, loss): their
/// exact steady-state response with the coefficients as stored in `T`,
/// `Σ_i H_i(e^{iθ})` with `H_i(z) = (p (1 - z^-1) + q) / (1 - (1 - d)
/// z^-1)` (plus g_i for the load forms, whose state is the relaxation).
/// The static share `1 - Σ g_i` is not included. f64 with libm trig:
/// reports and tests, for the const-size bank and run-time sized ones.
pub fn branch_response<T: Real>(
    form: MaxwellForm,
    cells: &[MaxwellCell<T>],
    theta: f64,
) -> (f64, f64) {
    let (c, s) = (libm::cos(theta), libm::sin(theta));
    let mut sum = (0.0, 0.0);
    for cell in cells {
        let (d, p, q) = (
            cell.decay.to_f64(),
            cell.rate_gain.to_f64(),
            cell.level_gain.to_f64(),
        );
        // z^-1 = c - i s
        let (num_re, num_im) = (p * (1.0 - c) + q, p * s);
        let a = 1.0 - d;
        let (den_re, den_im) = (1.0 - a * c, a * s);
        let norm = den_re * den_re + den_im * den_im;
        let storage = (num_re * den_re + num_im * den_im) / norm;
        let level = if form.is_load() { cell.g.to_f64() } else { 0.0 };
        sum.0 += storage + level;
        sum.1 += (num_im * den_re - num_re * den_im) / norm;
    }
    sum
}

/// Advances a slice of cells by one step: the one implementation of every
/// form, used by [`MaxwellBank`] and by run-time sized banks.
/// `cells` and `states` are walked together (extra entries of the longer
/// one are ignored); `tangent_gain` is [`tangent_gain`] of the cells.
#[inline(always)]
pub fn step_cells<T: Real, A: Accumulator<T>>(
    form: MaxwellForm,
    cells: &[MaxwellCell<T>],
    states: &mut [A],
    tangent_gain: T,
    drive: &Drive<T>,
) -> EffectOutput<T> {
    advance::<T, A, true>(form.is_load(), cells, states, tangent_gain, drive)
}

/// [`step_cells`] for the force alone: the same recurrence, with the
/// dissipated energy (3 multiply-adds per cell) and the tangent left out.
#[inline(always)]
pub fn step_cells_force<T: Real, A: Accumulator<T>>(
    form: MaxwellForm,
    cells: &[MaxwellCell<T>],
    states: &mut [A],
    drive: &Drive<T>,
) -> T {
    advance::<T, A, false>(form.is_load(), cells, states, T::ZERO, drive).force
}

/// The one implementation behind [`step_cells`] and [`step_cells_force`];
/// `ENERGY` selects at compile time whether the dissipated energy and the
/// tangent are formed. The load forms run out of line (a tail call), so
/// that the rate forms, the thesis's scheme, keep a leaf kernel with no
/// register saves.
#[inline(always)]
fn advance<T: Real, A: Accumulator<T>, const ENERGY: bool>(
    load: bool,
    cells: &[MaxwellCell<T>],
    states: &mut [A],
    tangent_gain: T,
    drive: &Drive<T>,
) -> EffectOutput<T> {
    let (force, squares) = if !load {
        advance_rate::<T, A, ENERGY>(cells, states, drive)
    } else {
        advance_load::<T, A, ENERGY>(cells, states, drive)
    };
    if !ENERGY {
        return EffectOutput {
            force,
            tangent: T::ZERO,
            dissipated: T::ZERO,
        };
    }
    EffectOutput {
        force,
        tangent: tangent_gain * drive.k_inf,
        // Σ ω_i dt F_i² / (g_i K^∞), trapezoid over the step.
        dissipated: T::HALF * squares / drive.k_inf,
    }
}

/// Load forms: the state is the relaxation, the branch force is the state
/// plus g F^∞. Returns the force and Σ loss F² (zero without `ENERGY`).
#[inline(always)]
fn advance_load<T: Real, A: Accumulator<T>, const ENERGY: bool>(
    cells: &[MaxwellCell<T>],
    states: &mut [A],
    drive: &Drive<T>,
) -> (T, T) {
    let df = drive.df_inf;
    let f_new = drive.f_inf;
    let f_old = f_new - df;
    let mut force = T::ZERO;
    let mut squares = T::ZERO;
    for (c, s) in cells.iter().zip(states.iter_mut()) {
        let old = s.value();
        s.relax(c.keep, c.decay, c.rate_gain * df + c.level_gain * f_new);
        let branch_new = s.value() + c.g * f_new;
        force += branch_new;
        if ENERGY {
            let branch_old = old + c.g * f_old;
            squares += c.loss * (branch_old * branch_old + branch_new * branch_new);
        }
    }
    (force, squares)
}

/// Rate forms: the state is the branch force.
#[inline(always)]
fn advance_rate<T: Real, A: Accumulator<T>, const ENERGY: bool>(
    cells: &[MaxwellCell<T>],
    states: &mut [A],
    drive: &Drive<T>,
) -> (T, T) {
    let df = drive.df_inf;
    // The branch force and its loss c F_old² + c F_new² (zero without
    // `ENERGY`).
    let cell = |c: &MaxwellCell<T>, s: &mut A| {
        let old = s.value();
        s.relax(c.keep, c.decay, c.rate_gain * df);
        let new = s.value();
        let square = if ENERGY {
            c.loss * (old * old + new * new)
        } else {
            T::ZERO
        };
        (new, square)
    };
    // The first cell starts both sums (one addition of zero fewer each).
    let (mut force, mut squares) = (T::ZERO, T::ZERO);
    let mut pairs = cells.iter().zip(states.iter_mut());
    if let Some((c, s)) = pairs.next() {
        (force, squares) = cell(c, s);
    }
    for (c, s) in pairs {
        let (f, q) = cell(c, s);
        force += f;
        squares += q;
    }
    (force, squares)
}

/// A bank of `N` Maxwell cells in one form, coupled to the backbone by
/// force rate (eq 1.12; see the module docs for equations, limits and cost).
///
/// `A` selects the state storage: [`Plain`] (default) or
/// [`Compensated`](crate::Compensated) for slow cells in `f32`.
///
/// ```
/// use bushing::{Bushing, MaxwellBank, MaxwellForm, MaxwellSpec, ParamError, Polynomial};
///
/// // Corners 1 and 10 Hz, each taking 20 % of the backbone, at 1 kHz.
/// let cells = [MaxwellSpec::hz(1.0, 0.2), MaxwellSpec::hz(10.0, 0.2)];
/// let bank = MaxwellBank::<f32, 2>::new(MaxwellForm::RateExactRamp, &cells, 1e-3)?;
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (bank,))?;
/// let mut state = bushing.state_at(0.0);
/// // A fast ramp to 1 mm: the cells carry their share at first ...
/// let mut out = bushing.step(&mut state, 1.0);
/// assert!((out.force - 100.0).abs() < 1.0);
/// // ... and relax while the displacement is held, to g^0 = 60 %.
/// for _ in 0..5000 {
///     out = bushing.step(&mut state, 1.0);
/// }
/// assert!((out.force - 60.0).abs() < 0.1 && out.dissipated >= 0.0);
/// // An explicit form is refused where its pole leaves (0, 1).
/// let fast = [MaxwellSpec::hz(500.0, 0.2)];
/// let r = MaxwellBank::<f32, 1>::new(MaxwellForm::LoadExplicit, &fast, 1e-3);
/// assert!(matches!(r, Err(ParamError::ExplicitUnstable { cell: 0, .. })));
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct MaxwellBank<T, const N: usize, A = Plain<T>> {
    form: MaxwellForm,
    /// `form.is_load()`, kept as a flag: one test per step.
    load: bool,
    /// The cells at the reference temperature, as given.
    specs: [MaxwellSpec; N],
    /// ω_i dt at the reference temperature, in the working type.
    h_ref: [T; N],
    /// The shift factor a_T the cells are tuned to.
    shift: T,
    cells: [MaxwellCell<T>; N],
    tangent_gain: T,
    fraction: f64,
    dt: f64,
    acc: PhantomData<A>,
}

impl<T: Real, const N: usize, A: Accumulator<T>> MaxwellBank<T, N, A> {
    /// Builds the bank for time step `dt` (seconds).
    pub fn new(form: MaxwellForm, specs: &[MaxwellSpec; N], dt: f64) -> Result<Self, ParamError> {
        Self::tuned(form, specs, dt, 1.0)
    }

    /// The bank of `specs` (at the reference temperature) tuned to the
    /// shift factor `a_t`, every coefficient computed in f64.
    fn tuned(
        form: MaxwellForm,
        specs: &[MaxwellSpec; N],
        dt: f64,
        a_t: f64,
    ) -> Result<Self, ParamError> {
        let a_t = positive(Param::scalar("a_t"), a_t)?;
        let mut cells = [MaxwellCell::default(); N];
        let mut h_ref = [T::ZERO; N];
        let mut fraction = 0.0;
        for (i, ((cell, h), spec)) in cells.iter_mut().zip(&mut h_ref).zip(specs).enumerate() {
            let shifted = MaxwellSpec::new(spec.omega / a_t, spec.g);
            *cell = MaxwellCell::new(form, shifted, dt, i)?;
            *h = T::from_f64(spec.omega * dt);
            fraction += spec.g;
        }
        if fraction > 1.0 + 1e-12 {
            return Err(ParamError::FractionsAboveOne { sum: fraction });
        }
        Ok(Self {
            form,
            load: form.is_load(),
            specs: *specs,
            h_ref,
            shift: T::from_f64(a_t),
            tangent_gain: tangent_gain(&cells),
            cells,
            fraction,
            dt,
            acc: PhantomData,
        })
    }

    /// The cells' parameters at the reference temperature, as given.
    pub fn specs(&self) -> &[MaxwellSpec; N] {
        &self.specs
    }

    /// The shift factor a_T the cells are tuned to (1 as built).
    pub fn shift(&self) -> T {
        self.shift
    }

    /// The same bank at another temperature: every reference corner
    /// frequency divided by the shift factor `a_t` (seed 000 eqs 1.46-1.48,
    /// with the usual a_T > 1 on the cold, slow side; see
    /// [`crate::temperature`]). The shift is absolute (from the reference
    /// specs, whatever the bank is tuned to now), so repeated re-tunes do
    /// not drift; the coefficients are computed as at construction (f64,
    /// `expm1`): exact, but soft-float on a Cortex-M4F (see [`Self::retune`]).
    ///
    /// The state of a running bank carries over unchanged: it holds branch
    /// forces (rate forms) or relaxations (load forms), not coefficients, so
    /// swapping the bank between two steps leaves the force continuous.
    pub fn shifted(&self, a_t: f64) -> Result<Self, ParamError> {
        Self::tuned(self.form, &self.specs, self.dt, a_t)
    }

    /// Re-tunes the bank in place to the shift factor `a_t` (absolute, as
    /// [`Self::shifted`]), computing in the working type with the
    /// exponentials `E` ([`LibmExp`], or `MicromathExp` with the
    /// `micromath` feature): the on-line path of a firmware that follows a
    /// temperature sensor, with no f64.
    ///
    /// Per cell: `h = h_ref / a_t`, one or two exponentials and two
    /// divisions. Accuracy against [`Self::shifted`] in `f32`: libm within a
    /// few ulps on every coefficient; micromath within its `exp` error
    /// (2.4e-3 on e^-h, so the effective corner ln(1/(1-d))/dt moves by at
    /// most 0.34 %, at h = ln 2; the series below h = 1/16 keeps f32
    /// accuracy);
    /// see `docs/fractional.md` for the table and `docs/accuracy-cost.md`
    /// for the cost. On error (`a_t` not finite and positive, or a shifted
    /// ω_i dt that overflows, vanishes or makes an explicit form unstable)
    /// the bank is left as it was.
    pub fn retune<E: Exponentials<T>>(&mut self, a_t: T) -> Result<(), ParamError> {
        positive_in(Param::scalar("a_t"), a_t)?;
        let mut cells = self.cells;
        let mut gain = T::ZERO;
        for (i, (cell, &h_ref)) in cells.iter_mut().zip(&self.h_ref).enumerate() {
            let h = h_ref / a_t;
            if !h.is_finite() {
                return Err(ParamError::NotFinite {
                    param: Param::item("omega", i),
                });
            }
            if h <= T::ZERO {
                return Err(ParamError::NotPositive {
                    param: Param::item("omega", i),
                    value: 0.0,
                });
            }
            *cell = coefficients::<T, E>(self.form, h, cell.g, i)?;
            gain += T::from_f64(cell.tangent);
        }
        self.cells = cells;
        self.tangent_gain = gain;
        self.shift = a_t;
        Ok(())
    }

    /// The form of every cell.
    pub fn form(&self) -> MaxwellForm {
        self.form
    }

    /// Branch share of the complex stiffness over K^∞ of the discrete bank
    /// at ω (rad/s), as (storage, loss): [`branch_response`] of its cells.
    pub fn branch_response(&self, omega: f64) -> (f64, f64) {
        branch_response(self.form, &self.cells, omega * self.dt)
    }

    /// Branch forces of a state, given the backbone force at its step.
    pub fn branch_forces(&self, state: &[A; N], f_inf: T) -> [T; N] {
        let mut out = [T::ZERO; N];
        let shift = self.form.is_load();
        for ((o, s), c) in out.iter_mut().zip(state).zip(&self.cells) {
            *o = s.value() + if shift { c.g * f_inf } else { T::ZERO };
        }
        out
    }
}

impl<T: Real, const N: usize, A: Accumulator<T>> Effect<T> for MaxwellBank<T, N, A> {
    type State = [A; N];
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        Some(self.dt)
    }
    fn rest(&self, _: T) -> [A; N] {
        [A::default(); N]
    }
    /// [`MaxwellBank::retune`].
    fn retune<X: Exponentials<T>>(&mut self, a_t: T) -> Result<(), ParamError> {
        MaxwellBank::retune::<X>(self, a_t)
    }
    #[inline(always)]
    fn step(&self, state: &mut [A; N], drive: &Drive<T>) -> EffectOutput<T> {
        advance::<T, A, true>(self.load, &self.cells, state, self.tangent_gain, drive)
    }
    #[inline(always)]
    fn step_force(&self, state: &mut [A; N], drive: &Drive<T>) -> T {
        advance::<T, A, false>(self.load, &self.cells, state, T::ZERO, drive).force
    }
    #[inline(always)]
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backbone::Polynomial;
    use crate::bushing::Bushing;
    use crate::{Compensated, Multiplied};

    const SPECS: [MaxwellSpec; 3] = [
        MaxwellSpec::new(3.0, 0.1),
        MaxwellSpec::new(30.0, 0.2),
        MaxwellSpec::new(300.0, 0.15),
    ];

    #[test]
    fn cells_whose_energy_coefficient_overflows_are_refused() {
        // ω·dt = 1e306 is finite in f64, its loss h/g is not in f32; a
        // shift factor of 1e-39 does the same to a running bank. Found by
        // the step_models fuzzer.
        let huge = [MaxwellSpec::new(1e308, 0.5)];
        let r = MaxwellBank::<f32, 1>::new(MaxwellForm::RateExactRamp, &huge, 1e-2);
        assert!(matches!(r, Err(ParamError::NotFinite { .. })), "{r:?}");
        assert!(MaxwellBank::<f64, 1>::new(MaxwellForm::RateExactRamp, &huge, 1e-2).is_ok());
        let mut bank = MaxwellBank::<f32, 3>::new(MaxwellForm::RateMidpoint, &SPECS, 1e-3).unwrap();
        let before = bank.clone();
        assert!(matches!(
            bank.retune::<LibmExp>(1e-39),
            Err(ParamError::NotFinite { .. })
        ));
        assert_eq!(bank, before);
    }

    #[test]
    fn explicit_forms_refuse_omega_dt_at_or_above_one() {
        for form in [MaxwellForm::LoadExplicit, MaxwellForm::RateExplicit] {
            let e = MaxwellBank::<f64, 1>::new(form, &[MaxwellSpec::new(1000.0, 0.1)], 1e-3)
                .unwrap_err();
            assert_eq!(
                e,
                ParamError::ExplicitUnstable {
                    cell: 0,
                    omega_dt: 1.0
                }
            );
            assert!(
                MaxwellBank::<f64, 1>::new(form, &[MaxwellSpec::new(999.0, 0.1)], 1e-3).is_ok()
            );
        }
        // The exponential forms take any h.
        for form in [
            MaxwellForm::LoadExponential,
            MaxwellForm::RateMidpoint,
            MaxwellForm::RateExactRamp,
        ] {
            assert!(MaxwellBank::<f32, 1>::new(form, &[MaxwellSpec::new(1e7, 0.1)], 1e-3).is_ok());
        }
    }

    #[test]
    fn bad_parameters_name_the_cell() {
        type B = MaxwellBank<f64, 2>;
        let f = MaxwellForm::RateExactRamp;
        let ok = MaxwellSpec::new(1.0, 0.1);
        assert_eq!(
            B::new(f, &[ok, MaxwellSpec::new(-1.0, 0.1)], 1e-3),
            Err(ParamError::NotPositive {
                param: Param::item("omega", 1),
                value: -1.0
            })
        );
        assert_eq!(
            B::new(f, &[MaxwellSpec::new(1.0, f64::NAN), ok], 1e-3),
            Err(ParamError::NotFinite {
                param: Param::item("g", 0)
            })
        );
        assert_eq!(
            B::new(f, &[ok, ok], 0.0),
            Err(ParamError::NotPositive {
                param: Param::scalar("dt"),
                value: 0.0
            })
        );
        assert_eq!(
            B::new(
                f,
                &[MaxwellSpec::new(1.0, 0.6), MaxwellSpec::new(2.0, 0.6)],
                1e-3
            ),
            Err(ParamError::FractionsAboveOne { sum: 1.2 })
        );
        assert_eq!(
            B::new(f, &[ok, MaxwellSpec::new(2.0, 1.2)], 1e-3),
            Err(ParamError::CellFractionAboveOne {
                cell: Some(1),
                g: 1.2
            })
        );
    }

    #[test]
    fn every_form_relaxes_to_the_long_term_force_after_a_step() {
        for form in MaxwellForm::ALL {
            let bank = MaxwellBank::<f64, 3>::new(form, &SPECS, 1e-4).unwrap();
            let b = Bushing::new(Polynomial::<f64, 2>::linear(1000.0).unwrap(), bank).unwrap();
            let mut s = b.state_at(0.0);
            let first = b.step(&mut s, 1e-3);
            // Just after the step: close to the high-frequency force K^inf x
            // (one step of relaxation already done).
            assert!(
                first.force > 0.93 && first.force <= 1.0 + 1e-12,
                "{form:?}: {}",
                first.force
            );
            let mut out = first;
            for _ in 0..200_000 {
                out = b.step(&mut s, 1e-3);
            }
            // 20 s later the slowest cell (3 rad/s) has decayed by e^-60. Every
            // form settles on g0 F^inf exactly, except (1.15), whose trapezoid
            // leaves a static-gain error: each relaxation settles on
            // -g (h/2)/sinh(h/2) F^inf instead of -g F^inf.
            let bias: f64 = if form == MaxwellForm::LoadExponential {
                SPECS
                    .iter()
                    .map(|c| {
                        let h = c.omega * 1e-4;
                        c.g * (1.0 - 0.5 * h / libm::sinh(0.5 * h))
                    })
                    .sum()
            } else {
                0.0
            };
            let long_term = (b.g0() + bias) * 1000.0 * 1e-3;
            assert!(
                (out.force - long_term).abs() < 1e-9,
                "{form:?}: {} vs {long_term}",
                out.force
            );
        }
    }

    #[test]
    fn bank_force_is_the_same_branch_force_in_load_and_rate_forms() {
        // Exponential load (1.15) and exact ramp differ by O(h^2) per step; at
        // a small step they must agree on the branch forces.
        let dt = 1e-5;
        let a = MaxwellBank::<f64, 3>::new(MaxwellForm::LoadExponential, &SPECS, dt).unwrap();
        let b = MaxwellBank::<f64, 3>::new(MaxwellForm::RateExactRamp, &SPECS, dt).unwrap();
        let (mut sa, mut sb) = (a.rest(0.0), b.rest(0.0));
        let mut f_prev = 0.0;
        for n in 1..=20_000 {
            let t = n as f64 * dt;
            let f = 100.0 * libm::sin(20.0 * t);
            let d = Drive {
                x: f,
                dx: 0.0,
                f_inf: f,
                df_inf: f - f_prev,
                k_inf: 1.0,
            };
            let (oa, ob) = (a.step(&mut sa, &d), b.step(&mut sb, &d));
            assert!(
                (oa.force - ob.force).abs() < 1e-3,
                "t = {t}: {} vs {}",
                oa.force,
                ob.force
            );
            f_prev = f;
        }
        let fa = a.branch_forces(&sa, f_prev);
        let fb = b.branch_forces(&sb, f_prev);
        for (x, y) in fa.iter().zip(&fb) {
            assert!((x - y).abs() < 1e-3);
        }
    }

    /// Relative error of the decay rate of one f32 cell at ω dt = `h`,
    /// relaxing for `n` steps after a unit step, stepped by the force-only
    /// call.
    fn f32_rate_error<A: Accumulator<f32>>(h: f64, n: usize) -> f64 {
        let bank = MaxwellBank::<f32, 1, A>::new(
            MaxwellForm::RateExactRamp,
            &[MaxwellSpec::new(h, 0.5)],
            1.0,
        )
        .unwrap();
        let mut s = bank.rest(0.0);
        let drive = |df: f32| Drive {
            x: 0.0,
            dx: 0.0,
            f_inf: 1.0,
            df_inf: df,
            k_inf: 1.0,
        };
        let f0 = bank.step_force(&mut s, &drive(1.0)) as f64;
        let mut f = f0;
        for _ in 0..n {
            f = bank.step_force(&mut s, &drive(0.0)) as f64;
        }
        let rate = -(f / f0).ln() / n as f64;
        rate / h - 1.0
    }

    #[test]
    fn slow_f32_cell_keeps_its_decay_rate() {
        // omega*dt = 1e-6: the decay rate over 1e5 steps within 0.1 % of exact
        // with the compensated state.
        let e = f32_rate_error::<Compensated<f32>>(1e-6, 100_000);
        assert!(e.abs() < 1e-3, "compensated: {e}");
        // The multiplied pole e^-h rounds in f32: several % off at 1e-6,
        // within 0.1 % at 1e-3.
        let e = f32_rate_error::<Multiplied<f32>>(1e-6, 100_000);
        assert!(e.abs() > 1e-2, "multiplied at 1e-6: {e}");
        let e = f32_rate_error::<Multiplied<f32>>(1e-3, 2_000);
        assert!(e.abs() < 1e-3, "multiplied at 1e-3: {e}");
    }

    #[test]
    fn force_only_step_and_every_storage_follow_the_same_recurrence() {
        // Fast cells (no rounding trouble): plain, multiplied and
        // compensated states agree to rounding, and the force-only call
        // leaves the state the full step leaves.
        for form in FORMS {
            let specs = [MaxwellSpec::new(20.0, 0.2), MaxwellSpec::new(300.0, 0.3)];
            let full = MaxwellBank::<f64, 2>::new(form, &specs, 1e-3).unwrap();
            let mult = MaxwellBank::<f64, 2, Multiplied<f64>>::new(form, &specs, 1e-3).unwrap();
            let comp = MaxwellBank::<f64, 2, Compensated<f64>>::new(form, &specs, 1e-3).unwrap();
            let (mut a, mut b, mut c, mut d) = (
                full.rest(0.0),
                full.rest(0.0),
                mult.rest(0.0),
                comp.rest(0.0),
            );
            for n in 0..3000 {
                let t = n as f64 * 1e-3;
                let f_inf = libm::sin(40.0 * t) + 0.3 * libm::sin(400.0 * t);
                let f_old = libm::sin(40.0 * (t - 1e-3)) + 0.3 * libm::sin(400.0 * (t - 1e-3));
                let drive = Drive {
                    x: f_inf,
                    dx: f_inf - f_old,
                    f_inf,
                    df_inf: f_inf - f_old,
                    k_inf: 1.0,
                };
                let out = full.step(&mut a, &drive);
                let force = full.step_force(&mut b, &drive);
                assert_eq!(out.force, force);
                assert_eq!(a, b);
                let m = mult.step_force(&mut c, &drive);
                let k = comp.step_force(&mut d, &drive);
                assert!((m - force).abs() < 1e-12, "{form:?} {n}: {m} {force}");
                assert!((k - force).abs() < 1e-12, "{form:?} {n}: {k} {force}");
            }
        }
    }

    const FORMS: [MaxwellForm; 5] = [
        MaxwellForm::LoadExplicit,
        MaxwellForm::LoadExponential,
        MaxwellForm::RateExplicit,
        MaxwellForm::RateMidpoint,
        MaxwellForm::RateExactRamp,
    ];

    /// Cells from ω dt = 1e-6 (slow) to 30 (explicit forms: up to 0.5).
    fn wide_specs(form: MaxwellForm) -> [MaxwellSpec; 5] {
        let top = if form.is_explicit() { 0.5 } else { 30.0 };
        [1e-6, 1e-3, 0.05, 0.3, top].map(|h| MaxwellSpec::new(h * 1e3, 0.15))
    }

    fn coefficient_error<T: Real>(a: &MaxwellCell<T>, b: &MaxwellCell<T>) -> f64 {
        let rel = |x: T, y: T| {
            let (x, y) = (x.to_f64(), y.to_f64());
            if x == y { 0.0 } else { ((x - y) / y).abs() }
        };
        [
            rel(a.decay, b.decay),
            rel(a.rate_gain, b.rate_gain),
            rel(a.level_gain, b.level_gain),
            rel(a.loss, b.loss),
        ]
        .into_iter()
        .fold(0.0, f64::max)
    }

    #[test]
    fn shifts_are_absolute_from_the_reference() {
        let b = MaxwellBank::<f64, 3>::new(MaxwellForm::RateExactRamp, &SPECS, 1e-3).unwrap();
        assert_eq!(b.shift(), 1.0);
        let twice = b.shifted(2.0).unwrap().shifted(3.0).unwrap();
        assert_eq!(twice, b.shifted(3.0).unwrap());
        assert_eq!(twice.specs(), &SPECS);
        assert_eq!(b.shifted(1.0).unwrap(), b);
        // The shifted bank is the bank of the shifted corners.
        let moved = SPECS.map(|s| MaxwellSpec::new(s.omega / 3.0, s.g));
        let direct = MaxwellBank::<f64, 3>::new(MaxwellForm::RateExactRamp, &moved, 1e-3).unwrap();
        assert_eq!(twice.cells, direct.cells);
        assert_eq!(twice.tangent_gain, direct.tangent_gain);
    }

    #[test]
    fn working_type_retune_matches_the_f64_shift() {
        for form in FORMS {
            let specs = wide_specs(form);
            for a_t in [0.7, 1.0, 2.5, 40.0] {
                // f64 with libm: the same formula, h formed as h_ref / a_t.
                let mut b = MaxwellBank::<f64, 5>::new(form, &specs, 1e-3).unwrap();
                let exact = b.shifted(a_t).unwrap();
                b.retune::<LibmExp>(a_t).unwrap();
                for (x, y) in b.cells.iter().zip(&exact.cells) {
                    assert!(coefficient_error(x, y) < 1e-14, "{form:?} a_t={a_t}");
                }
                assert!((b.tangent_gain / exact.tangent_gain - 1.0).abs() < 1e-14);
                assert_eq!(b.shift(), a_t);
                // f32 with libm: within a few ulps of the rounded f64 path.
                let mut b = MaxwellBank::<f32, 5>::new(form, &specs, 1e-3).unwrap();
                let exact = b.shifted(a_t).unwrap();
                b.retune::<LibmExp>(a_t as f32).unwrap();
                for (x, y) in b.cells.iter().zip(&exact.cells) {
                    let e = coefficient_error(x, y);
                    assert!(e < 8.0 * f32::EPSILON as f64, "{form:?} a_t={a_t}: {e}");
                }
            }
        }
    }

    #[test]
    fn refused_retunes_leave_the_bank_as_it_was() {
        let mut b = MaxwellBank::<f32, 5>::new(
            MaxwellForm::RateExplicit,
            &wide_specs(MaxwellForm::RateExplicit),
            1e-3,
        )
        .unwrap();
        b.retune::<LibmExp>(1.5).unwrap();
        let before = b.clone();
        let a_t = Param::scalar("a_t");
        assert_eq!(
            b.retune::<LibmExp>(f32::NAN),
            Err(ParamError::NotFinite { param: a_t })
        );
        assert_eq!(
            b.retune::<LibmExp>(0.0),
            Err(ParamError::NotPositive {
                param: a_t,
                value: 0.0
            })
        );
        assert_eq!(
            b.retune::<LibmExp>(-2.0),
            Err(ParamError::NotPositive {
                param: a_t,
                value: -2.0
            })
        );
        // Warm enough that the explicit form's fastest cell reaches h = 1.
        assert_eq!(
            b.retune::<LibmExp>(0.5),
            Err(ParamError::ExplicitUnstable {
                cell: 4,
                omega_dt: 1.0
            })
        );
        // Cold enough that a slow cell's ω dt underflows to zero, and hot
        // enough that a fast one's overflows.
        for (omega, a_t, err) in [
            (
                1e-6,
                f32::MAX,
                ParamError::NotPositive {
                    param: Param::item("omega", 0),
                    value: 0.0,
                },
            ),
            (
                1e9,
                1e-38,
                ParamError::NotFinite {
                    param: Param::item("omega", 0),
                },
            ),
        ] {
            let spec = [MaxwellSpec::new(omega, 0.1)];
            let mut one =
                MaxwellBank::<f32, 1>::new(MaxwellForm::RateExactRamp, &spec, 1e-3).unwrap();
            let kept = one.clone();
            assert_eq!(one.retune::<LibmExp>(a_t), Err(err));
            assert_eq!(one, kept);
        }
        assert_eq!(b, before);
    }

    #[test]
    fn branch_response_is_the_discrete_steady_state() {
        let (dt, per) = (1e-3, 200usize);
        let omega = core::f64::consts::TAU / (dt * per as f64);
        for form in FORMS {
            let bank = MaxwellBank::<f64, 3>::new(form, &SPECS, dt).unwrap();
            let mut s = bank.rest(0.0);
            let x = |n: usize| (omega * dt * n as f64).sin();
            let (mut re, mut im) = (0.0, 0.0);
            let periods = 40; // the slowest cell (3 rad/s) decays by e^-24
            for n in 1..=periods * per {
                let (xn, xo) = (x(n), x(n - 1));
                let drive = Drive {
                    x: xn,
                    dx: xn - xo,
                    f_inf: xn,
                    df_inf: xn - xo,
                    k_inf: 1.0,
                };
                let f = bank.step(&mut s, &drive).force;
                if n > (periods - 1) * per {
                    let phase = omega * dt * n as f64;
                    re += 2.0 * f * phase.sin() / per as f64;
                    im += 2.0 * f * phase.cos() / per as f64;
                }
            }
            let (sr, lr) = bank.branch_response(omega);
            assert!(
                (re - sr).abs() < 1e-9 && (im - lr).abs() < 1e-9,
                "{form:?}: ({re}, {im}) vs ({sr}, {lr})"
            );
            // And close to eq 1.8 at h <= 0.3 (each form's own error).
            let (s8, l8) = SPECS.iter().fold((0.0, 0.0), |(a, b), c| {
                let d = omega * omega + c.omega * c.omega;
                (a + c.g * omega * omega / d, b + c.g * omega * c.omega / d)
            });
            assert!(
                (sr / s8 - 1.0).abs() < 0.05 && (lr / l8 - 1.0).abs() < 0.05,
                "{form:?}"
            );
        }
    }
}
