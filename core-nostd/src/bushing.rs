//! A bushing: one backbone and a set of dissipative effects, composed at
//! compile time.
//!
//! The force is split into branches (seed 000 eq 1.9):
//! `F = g^0 F^∞(x) + Σ_effects F^e`, with the long-term fraction
//! `g^0 = 1 - Σ g^i` over every cell of every effect. The backbone is
//! evaluated once per step; every effect receives the same [`Drive`].
//!
//! Effects compose as tuples `(A, B, ...)`; `()` is a bushing with no
//! dissipation and `Option<E>` an effect chosen at run time. An effect that is
//! not in the type costs no instruction and no byte.

use crate::backbone::Backbone;
use crate::error::{Faults, Param, ParamError, positive_in};
use crate::real::{Exponentials, Real, all_within};

/// What every effect sees in a step: the new displacement and the backbone
/// evaluated there, with the increments since the last accepted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive<T> {
    /// Displacement x_n, mm.
    pub x: T,
    /// Increment x_n - x_{n-1}, mm.
    pub dx: T,
    /// High-frequency backbone force F^∞(x_n), N.
    pub f_inf: T,
    /// Increment F^∞(x_n) - F^∞(x_{n-1}), N.
    pub df_inf: T,
    /// Backbone tangent K^∞(x_n) > 0, N/mm.
    pub k_inf: T,
}

/// The result of one effect over one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct EffectOutput<T> {
    /// Force carried by the effect's branches at the end of the step, N.
    pub force: T,
    /// Algorithmic tangent dF_n/dx_n of that force, the state at the start
    /// of the step held fixed, N/mm.
    pub tangent: T,
    /// Energy dissipated by the effect during the step: the work done on
    /// its branches over the step less the change of the energy they
    /// store, in the unit of force times displacement (N·mm = mJ).
    ///
    /// The contract, for every effect of the crate: finite whenever the
    /// step is accepted (a total that leaves the working type is replaced
    /// by 0 and [`Faults::ENERGY_OVERFLOW`] raised), and `>= 0` on every
    /// single step, with one exception: the Grünwald cell
    /// ([`crate::Grunwald`]) stores energy in its whole history, which its
    /// balance cannot see step by step, so a single step may report a
    /// small negative value; its sum over a closed steady cycle is the
    /// loop area. Each effect's docs say how its energy is integrated over
    /// the step (a trapezoid of the rate, or the exact work of a
    /// turning-point law).
    pub dissipated: T,
}

impl<T: Real> EffectOutput<T> {
    /// All zero.
    pub const fn zero() -> Self {
        Self {
            force: T::ZERO,
            tangent: T::ZERO,
            dissipated: T::ZERO,
        }
    }

    fn plus(self, o: Self) -> Self {
        Self {
            force: self.force + o.force,
            tangent: self.tangent + o.tangent,
            dissipated: self.dissipated + o.dissipated,
        }
    }
}

/// A dissipative effect: parameters, validated and immutable, apart from a
/// plain-data state.
pub trait Effect<T: Real> {
    /// Internal state.
    type State: Clone + core::fmt::Debug + PartialEq;
    /// Per-branch outputs of one step (one [`EffectOutput`] for a single
    /// effect, a tuple of them for a tuple of effects).
    type Report: Copy + core::fmt::Debug;

    /// Sum of the load fractions g^i this effect takes from F^∞.
    fn fraction(&self) -> f64;
    /// Time step the effect was built for, if it depends on one.
    fn dt(&self) -> Option<f64>;
    /// Folds this effect's time step (and its parts') into `dt`, failing
    /// when two parts were built for different steps.
    fn check_dt(&self, dt: Option<f64>) -> Result<Option<f64>, ParamError> {
        same_dt(dt, self.dt())
    }
    /// The relaxed state at displacement `x0`: no force in any branch.
    fn rest(&self, x0: T) -> Self::State;
    /// Advances the state by one step.
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> Self::Report;
    /// Advances the state by one step and returns the force alone: the
    /// same state as [`Effect::step`], for a loop that reads nothing else
    /// (banks override it to skip the energy and tangent work).
    #[inline(always)]
    fn step_force(&self, state: &mut Self::State, drive: &Drive<T>) -> T {
        Self::total(&self.step(state, drive)).force
    }
    /// Sum of the branch outputs of a report.
    fn total(report: &Self::Report) -> EffectOutput<T>;

    /// `|force| + |tangent|` summed over the effects of a report (a tuple
    /// adds its members'; NaN or infinite if any is): a bushing step is
    /// accepted only if this, its total force and its total tangent stay
    /// within [`Real::GUARD`], so that every effect's force and tangent do.
    #[inline(always)]
    fn magnitude(report: &Self::Report) -> T {
        let t = Self::total(report);
        t.force.abs() + t.tangent.abs()
    }

    /// Re-tunes the effect to the temperature shift factor `a_t`
    /// (absolute, as [`MaxwellBank::retune`](crate::MaxwellBank::retune)
    /// takes it), in the working type with the exponentials `X`. The
    /// Maxwell bank re-tunes its cells; an effect that does not depend on
    /// temperature keeps its coefficients (the default); a tuple or an
    /// `Option` re-tunes its members. The state carries over, since it
    /// holds branch forces and not coefficients. On error the effect may
    /// be partly re-tuned: [`Bushing::retune`] works on a copy.
    #[inline]
    fn retune<X: Exponentials<T>>(&mut self, a_t: T) -> Result<(), ParamError> {
        let _ = a_t;
        Ok(())
    }

    /// Advances the state by one step if `accept` takes the report, and
    /// otherwise leaves the state exactly as it was and returns `None`.
    /// The default keeps a copy of the state and puts it back if the step
    /// is refused (a few words for the banks of the crate, which the step
    /// loads anyway); an effect whose state is costly to copy overrides it.
    #[inline(always)]
    fn step_if(
        &self,
        state: &mut Self::State,
        drive: &Drive<T>,
        accept: impl FnOnce(&Self::Report) -> bool,
    ) -> Option<Self::Report> {
        let before = state.clone();
        let report = self.step(state, drive);
        if accept(&report) {
            Some(report)
        } else {
            *state = before;
            None
        }
    }
}

/// Finite and within [`Real::GUARD`] in magnitude (a NaN fails).
#[inline(always)]
fn within<T: Real>(v: T) -> bool {
    v.abs() <= T::GUARD
}

impl<T: Real> Effect<T> for () {
    type State = ();
    type Report = ();
    fn fraction(&self) -> f64 {
        0.0
    }
    fn dt(&self) -> Option<f64> {
        None
    }
    fn rest(&self, _: T) {}
    #[inline(always)]
    fn step(&self, _: &mut (), _: &Drive<T>) {}
    #[inline(always)]
    fn total(_: &()) -> EffectOutput<T> {
        EffectOutput::zero()
    }
}

/// An effect present or not at run time (host-side composition). `None`
/// costs one branch per step and no state.
impl<T: Real, E: Effect<T>> Effect<T> for Option<E> {
    type State = Option<E::State>;
    type Report = Option<E::Report>;
    fn fraction(&self) -> f64 {
        self.as_ref().map_or(0.0, E::fraction)
    }
    fn dt(&self) -> Option<f64> {
        self.as_ref().and_then(E::dt)
    }
    fn check_dt(&self, dt: Option<f64>) -> Result<Option<f64>, ParamError> {
        self.as_ref().map_or(Ok(dt), |e| e.check_dt(dt))
    }
    fn retune<X: Exponentials<T>>(&mut self, a_t: T) -> Result<(), ParamError> {
        self.as_mut().map_or(Ok(()), |e| e.retune::<X>(a_t))
    }
    fn rest(&self, x0: T) -> Self::State {
        self.as_ref().map(|e| e.rest(x0))
    }
    #[inline(always)]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> Self::Report {
        match (self, state) {
            (Some(e), Some(s)) => Some(e.step(s, drive)),
            _ => None,
        }
    }
    #[inline]
    fn total(report: &Self::Report) -> EffectOutput<T> {
        report.as_ref().map_or(EffectOutput::zero(), E::total)
    }
    #[inline(always)]
    fn magnitude(report: &Self::Report) -> T {
        report.as_ref().map_or(T::ZERO, E::magnitude)
    }
    #[inline(always)]
    fn step_if(
        &self,
        state: &mut Self::State,
        drive: &Drive<T>,
        accept: impl FnOnce(&Self::Report) -> bool,
    ) -> Option<Self::Report> {
        match (self, state) {
            (Some(e), Some(s)) => e.step_if(s, drive, |r| accept(&Some(*r))).map(Some),
            _ => accept(&None).then_some(None),
        }
    }
}

fn same_dt(a: Option<f64>, b: Option<f64>) -> Result<Option<f64>, ParamError> {
    match (a, b) {
        (Some(x), Some(y)) if x != y => Err(ParamError::TimeStepMismatch { first: x, other: y }),
        (Some(x), _) | (None, Some(x)) => Ok(Some(x)),
        (None, None) => Ok(None),
    }
}

/// The all-or-nothing step of a tuple: each member's `step_if` decides
/// inside the previous member's, so the innermost call sees every report
/// and asks `accept` once; each member commits only if every member after
/// it did, and each pays only its own rollback (none for the members with
/// a native `step_if`).
macro_rules! nested_step_if {
    ($s:ident, $st:ident, $d:ident, $accept:ident, $out:ident, [$($done:ident)*];) => {{
        let report = ($(*$done,)*);
        let ok = $accept(&report);
        if ok {
            $out = Some(report);
        }
        ok
    }};
    ($s:ident, $st:ident, $d:ident, $accept:ident, $out:ident, [$($done:ident)*]; $idx:tt $r:ident $($rest:tt)*) => {
        $s.$idx
            .step_if(&mut $st.$idx, $d, |$r| {
                nested_step_if!($s, $st, $d, $accept, $out, [$($done)* $r]; $($rest)*)
            })
            .is_some()
    };
}

macro_rules! tuple_effect {
    ($($name:ident $idx:tt $r:ident),+) => {
        impl<T: Real, $($name: Effect<T>),+> Effect<T> for ($($name,)+) {
            type State = ($($name::State,)+);
            type Report = ($($name::Report,)+);
            fn fraction(&self) -> f64 {
                0.0 $(+ self.$idx.fraction())+
            }
            fn dt(&self) -> Option<f64> {
                None $(.or(self.$idx.dt()))+
            }
            fn check_dt(&self, mut dt: Option<f64>) -> Result<Option<f64>, ParamError> {
                $( dt = self.$idx.check_dt(dt)?; )+
                Ok(dt)
            }
            fn retune<X: Exponentials<T>>(&mut self, a_t: T) -> Result<(), ParamError> {
                $( self.$idx.retune::<X>(a_t)?; )+
                Ok(())
            }
            fn rest(&self, x0: T) -> Self::State {
                ($(self.$idx.rest(x0),)+)
            }
            #[inline(always)]
            fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> Self::Report {
                ($(self.$idx.step(&mut state.$idx, drive),)+)
            }
            /// The members' sum from the first member's output (no
            /// addition of zero, which the compiler must keep for the sign
            /// of a zero).
            #[inline(always)]
            fn total(report: &Self::Report) -> EffectOutput<T> {
                [$($name::total(&report.$idx)),+]
                    .into_iter()
                    .reduce(EffectOutput::plus)
                    .unwrap_or(EffectOutput::zero())
            }
            #[inline(always)]
            fn magnitude(report: &Self::Report) -> T {
                [$($name::magnitude(&report.$idx)),+]
                    .into_iter()
                    .reduce(|a, b| a + b)
                    .unwrap_or(T::ZERO)
            }
            #[inline(always)]
            fn step_if(
                &self,
                state: &mut Self::State,
                drive: &Drive<T>,
                accept: impl FnOnce(&Self::Report) -> bool,
            ) -> Option<Self::Report> {
                let mut out = None;
                // `out` is set exactly when every member accepted.
                let _accepted: bool =
                    nested_step_if!(self, state, drive, accept, out, []; $($idx $r)+);
                out
            }
        }
    };
}

tuple_effect!(A 0 ra);
tuple_effect!(A 0 ra, B 1 rb);
tuple_effect!(A 0 ra, B 1 rb, C 2 rc);
tuple_effect!(A 0 ra, B 1 rb, C 2 rc, D 3 rd);
tuple_effect!(A 0 ra, B 1 rb, C 2 rc, D 3 rd, E 4 re);
tuple_effect!(A 0 ra, B 1 rb, C 2 rc, D 3 rd, E 4 re, F 5 rf);

/// The state of a bushing in `T` with effects `E`, to name in a `static`
/// or a struct field:
///
/// ```
/// use bushing::{Bushing, IwanBank, MaxwellBank, Polynomial, StateOf};
///
/// type Effects = (MaxwellBank<f32, 4>, IwanBank<f32, 3>);
/// struct Controller {
///     bushing: Bushing<f32, Polynomial<f32, 4>, Effects>,
///     state: StateOf<f32, Effects>,
/// }
/// ```
pub type StateOf<T, E> = BushingState<T, <E as Effect<T>>::State>;

/// The output of one step of a bushing in `T` with effects `E`.
pub type OutputOf<T, E> = Output<T, <E as Effect<T>>::Report>;

/// State of a [`Bushing`]: the last accepted input, backbone force and
/// output, the effects' states, and the fault flags.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BushingState<T, S> {
    x: T,
    f_inf: T,
    force: T,
    tangent: T,
    effects: S,
    faults: Faults,
    rejected: u32,
}

impl<T: Real, S> BushingState<T, S> {
    /// Last accepted displacement, mm.
    pub fn x(&self) -> T {
        self.x
    }
    /// Force after the last accepted step, N.
    pub fn force(&self) -> T {
        self.force
    }
    /// Algorithmic tangent dF/dx of the last accepted step, N/mm.
    pub fn tangent(&self) -> T {
        self.tangent
    }
    /// Effects' states.
    pub fn effects(&self) -> &S {
        &self.effects
    }
    /// Fault flags raised since the last [`BushingState::clear_faults`].
    pub fn faults(&self) -> Faults {
        self.faults
    }
    /// Number of refused steps since the last clear (saturating).
    pub fn rejected(&self) -> u32 {
        self.rejected
    }
    /// Clears the fault flags and the refused-step count.
    pub fn clear_faults(&mut self) {
        self.faults = Faults::NONE;
        self.rejected = 0;
    }
}

/// The result of one bushing step.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output<T, R> {
    /// Total force F_n, N.
    pub force: T,
    /// Algorithmic tangent dF_n/dx_n, N/mm.
    pub tangent: T,
    /// Energy dissipated in the step, all branches, mJ (N·mm).
    pub dissipated: T,
    /// Force of the long-term elastic branch g^0 F^∞(x_n), N.
    pub elastic: T,
    /// Per-effect outputs; `None` when the step was refused.
    pub effects: Option<R>,
}

/// A backbone plus a set of effects (see the module docs).
///
/// `step` never panics. A non-finite input, or one where the backbone force
/// or tangent exceeds [`Real::GUARD`], is refused; so is a step where an
/// effect's force or tangent, or the bushing's total, would not be finite
/// or would exceed [`Real::GUARD`] (a turning-point law or a fractional
/// cell driven far beyond its data). A refused step keeps the state, returns
/// the last force and tangent with zero dissipation and raises a fault flag
/// in the state ([`Faults::NON_FINITE_INPUT`], [`Faults::OUT_OF_RANGE`] or
/// [`Faults::FORCE_OUT_OF_RANGE`]). Every accepted step's force and tangent
/// are finite and within the guard.
///
/// ```
/// use bushing::{
///     Bushing, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, ParamError,
///     Polynomial,
/// };
///
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bank = MaxwellBank::<f32, 1>::new(MaxwellForm::RateExactRamp, &[MaxwellSpec::hz(5.0, 0.3)], 1e-3)?;
/// let bushing = Bushing::new(backbone, (bank,))?;
/// let mut state = bushing.state_at(0.0);
/// let before = state.clone();
/// // `trial` is `step` without touching the state.
/// let (tried, _) = bushing.trial(&state, 0.5);
/// assert_eq!(state, before);
/// let out = bushing.step(&mut state, 0.5);
/// assert_eq!(tried, out);
/// assert_eq!(out.elastic, 35.0); // g^0 F^∞ = 0.7 · 50 N
/// // A displacement beyond the guard is refused and flagged.
/// let refused = bushing.step(&mut state, f32::INFINITY);
/// assert_eq!(refused.force, out.force);
/// assert_eq!(state.faults().to_string(), "NON_FINITE_INPUT");
/// // Fractions above one in all are refused when the bushing is joined.
/// let maxwell = MaxwellBank::<f32, 1>::new(MaxwellForm::RateExactRamp, &[MaxwellSpec::hz(5.0, 0.6)], 1e-3)?;
/// let iwan = IwanBank::<f32, 1>::new(&[IwanCellSpec::new(0.6, 5.0)])?;
/// let r = Bushing::new(backbone, (maxwell, iwan));
/// assert!(matches!(r, Err(ParamError::FractionsAboveOne { .. })));
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Bushing<T, B, E> {
    backbone: B,
    effects: E,
    g0: T,
    g0_f64: f64,
}

impl<T: Real, B: Backbone<T>, E: Effect<T>> Bushing<T, B, E> {
    /// Joins a backbone and effects; refuses fractions above one, effects
    /// built for different time steps, and a backbone whose force or
    /// tangent at x = 0, the point a state falls back to after a refused
    /// start, is not finite or exceeds [`Real::GUARD`] in the working type.
    pub fn new(backbone: B, effects: E) -> Result<Self, ParamError> {
        effects.check_dt(None)?;
        let (f0, k0) = backbone.eval(T::ZERO);
        for (name, v) in [
            ("backbone force at x = 0", f0),
            ("backbone tangent at x = 0", k0),
        ] {
            if !within(v) {
                let max = T::GUARD.to_f64();
                return Err(ParamError::OutOfRange {
                    param: Param::scalar(name),
                    value: v.to_f64(),
                    min: -max,
                    min_open: false,
                    max,
                });
            }
        }
        let sum = effects.fraction();
        // One part in 1e12 of slack for fractions entered as decimals.
        if sum.is_nan() || sum > 1.0 + 1e-12 {
            return Err(ParamError::FractionsAboveOne { sum });
        }
        let g0 = (1.0 - sum).max(0.0);
        Ok(Self {
            backbone,
            effects,
            g0: T::from_f64(g0),
            g0_f64: g0,
        })
    }

    /// Long-term fraction g^0 = 1 - Σ g^i.
    pub fn g0(&self) -> f64 {
        self.g0_f64
    }

    /// The backbone.
    pub fn backbone(&self) -> &B {
        &self.backbone
    }

    /// The effects.
    pub fn effects(&self) -> &E {
        &self.effects
    }

    /// Re-tunes the effects in place to the temperature shift factor
    /// `a_t` (absolute: the factor at the new temperature against the
    /// reference), in the working type with the exponentials `X`: the
    /// call a firmware makes between two periods when its temperature
    /// reading changes (see [`crate::temperature`] for a_T). Only the
    /// Maxwell cells depend on temperature; each takes its corner
    /// ω_i / a_T. A running state carries over, so the force is continuous
    /// across the change. Refused, with the bushing left as it was, for an
    /// `a_t` that is not finite or not positive, or a cell whose
    /// coefficients would leave the working type.
    ///
    /// ```
    /// use bushing::{Bushing, LibmExp, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};
    ///
    /// let cells = [MaxwellSpec::hz(1.0, 0.2), MaxwellSpec::hz(10.0, 0.2)];
    /// let bank = MaxwellBank::<f32, 2>::new(MaxwellForm::RateExactRamp, &cells, 1e-3)?;
    /// let backbone = Polynomial::<f32, 2>::new(&[0.0, 150.0], (-5.0, 5.0))?;
    /// let mut bushing = Bushing::new(backbone, (bank,))?;
    /// let mut state = bushing.state_at(0.0);
    /// let before = bushing.step(&mut state, 0.5).force;
    /// // Warmer: the cells relax 4 times faster (a_T = 0.25).
    /// bushing.retune::<LibmExp>(0.25)?;
    /// let after = bushing.step(&mut state, 0.5).force;
    /// // No jump: the branch forces carry over, and relax faster.
    /// assert!(after < before && after > 0.9 * before);
    /// assert!(bushing.retune::<LibmExp>(-1.0).is_err());
    /// # Ok::<(), bushing::ParamError>(())
    /// ```
    pub fn retune<X: Exponentials<T>>(&mut self, a_t: T) -> Result<(), ParamError>
    where
        E: Clone,
    {
        positive_in(Param::scalar("a_t"), a_t)?;
        let mut effects = self.effects.clone();
        effects.retune::<X>(a_t)?;
        self.effects = effects;
        Ok(())
    }

    /// A relaxed state at displacement `x0` (mm): every dissipative branch at
    /// zero force, so starting away from zero creates no spurious step.
    /// A non-finite `x0` is replaced by 0 and flagged.
    pub fn state_at(&self, x0: T) -> BushingState<T, E::State> {
        let mut faults = Faults::NONE;
        let mut x = x0;
        let (mut f, mut k) = self.backbone.eval(x);
        if !within(x) || !within_guard(f, k) {
            faults.raise(if x.is_finite() {
                Faults::OUT_OF_RANGE
            } else {
                Faults::NON_FINITE_INPUT
            });
            x = T::ZERO;
            (f, k) = self.backbone.eval(x);
        }
        BushingState {
            x,
            f_inf: f,
            force: self.g0 * f,
            tangent: self.g0 * k,
            effects: self.effects.rest(x),
            faults,
            rejected: 0,
        }
    }

    /// Advances `state` to displacement `x` (mm) and returns the output.
    /// Always inlined: a control loop calls it once per period, and inlining
    /// lets the compiler drop the outputs the caller does not read (the
    /// per-branch reports). The dissipated energy is formed in every step,
    /// read or not: whether it is finite decides
    /// [`Faults::ENERGY_OVERFLOW`].
    #[inline(always)]
    pub fn step(&self, state: &mut BushingState<T, E::State>, x: T) -> Output<T, E::Report> {
        // One compare refuses NaN, infinities and finite values beyond the
        // guard; which of them it was is sorted out on the refusal path.
        if !within(x) {
            let fault = if x.is_finite() {
                Faults::OUT_OF_RANGE
            } else {
                Faults::NON_FINITE_INPUT
            };
            return refuse(state, self.g0, fault);
        }
        self.step_within(state, x)
    }

    /// [`Bushing::step`] for a displacement already known to be within
    /// [`Real::GUARD`] in magnitude (so not NaN): a caller that has checked
    /// its inputs together, as the 6-DOF kinematics check their six
    /// strains with one compare, skips the check of each.
    #[inline(always)]
    pub(crate) fn step_within(
        &self,
        state: &mut BushingState<T, E::State>,
        x: T,
    ) -> Output<T, E::Report> {
        let (f_inf, k_inf) = self.backbone.eval(x);
        if !within_guard(f_inf, k_inf) {
            return refuse(state, self.g0, Faults::OUT_OF_RANGE);
        }
        let drive = Drive {
            x,
            dx: x - state.x,
            f_inf,
            df_inf: f_inf - state.f_inf,
            k_inf,
        };
        let elastic = self.g0 * f_inf;
        let elastic_tangent = self.g0 * k_inf;
        // The effects' new state is committed only if the effects' forces
        // and tangents (their summed magnitudes, so each of them), the total
        // force and the total tangent stay finite and within the guard.
        let accept = |r: &E::Report| {
            let t = E::total(r);
            // The magnitude is a sum of magnitudes: no sign to strip.
            all_within(
                &[E::magnitude(r)],
                &[elastic + t.force, elastic_tangent + t.tangent],
                T::GUARD,
            )
        };
        let Some(report) = self.effects.step_if(&mut state.effects, &drive, accept) else {
            return refuse(state, self.g0, Faults::FORCE_OUT_OF_RANGE);
        };
        let total = E::total(&report);
        let dissipated = if total.dissipated.is_finite() {
            total.dissipated
        } else {
            overflowed(state)
        };
        let force = elastic + total.force;
        let tangent = elastic_tangent + total.tangent;
        state.x = x;
        state.f_inf = f_inf;
        state.force = force;
        state.tangent = tangent;
        Output {
            force,
            tangent,
            dissipated,
            elastic,
            effects: Some(report),
        }
    }

    /// The step `step` would take, without changing `state`: returns the
    /// output and the state it would commit (for implicit solvers that
    /// iterate on x and commit only the converged state). Always inlined,
    /// so that the copy of the state stays in registers where it can.
    #[inline(always)]
    pub fn trial(
        &self,
        state: &BushingState<T, E::State>,
        x: T,
    ) -> (Output<T, E::Report>, BushingState<T, E::State>) {
        let mut next = state.clone();
        let out = self.step(&mut next, x);
        (out, next)
    }
}

/// The backbone's force within the guard (the hysteresis laws work on
/// displacement distances, within the guard as well, the energies on
/// squared forces), and the tangent positive (the construction proves it in
/// f64; a tangent that rounds to zero in the working type would make the
/// dissipated energy 0/0) and within the guard.
#[inline(always)]
fn within_guard<T: Real>(f: T, k: T) -> bool {
    k > T::ZERO && all_within(&[k], &[f], T::GUARD)
}

/// Flags a step whose dissipated energy left the working type; it counts
/// as zero.
#[cold]
fn overflowed<T: Real, S>(state: &mut BushingState<T, S>) -> T {
    state.faults.raise(Faults::ENERGY_OVERFLOW);
    T::ZERO
}

#[cold]
fn refuse<T: Real, S, R>(state: &mut BushingState<T, S>, g0: T, why: Faults) -> Output<T, R> {
    state.faults.raise(why);
    state.rejected = state.rejected.saturating_add(1);
    Output {
        force: state.force,
        tangent: state.tangent,
        dissipated: T::ZERO,
        elastic: g0 * state.f_inf,
        effects: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backbone::Polynomial;
    use crate::maxwell::{MaxwellBank, MaxwellForm, MaxwellSpec};

    type Bank = MaxwellBank<f64, 2>;

    fn bank(g: f64, dt: f64) -> Bank {
        let specs = [MaxwellSpec::new(2.0, g), MaxwellSpec::new(200.0, g)];
        Bank::new(MaxwellForm::RateExactRamp, &specs, dt).unwrap()
    }

    fn cubic() -> Polynomial<f64, 4> {
        Polynomial::new(&[1.0, 100.0, 0.0, 2.0], (-5.0, 5.0)).unwrap()
    }

    #[test]
    fn the_backbone_guard_check_decides_as_its_three_comparisons() {
        // `within_guard` compares |f| + k first (`all_within`): it must
        // take and refuse exactly what the three comparisons do.
        let g = <f32 as Real>::GUARD;
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.6 * g,
            -0.6 * g,
            g,
            -g,
            g * 1.000_001,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for &f in &values {
            for &k in &values {
                let plain = f.abs() <= g && k > 0.0 && k <= g;
                assert_eq!(within_guard(f, k), plain, "f {f}, k {k}");
            }
        }
    }

    #[test]
    fn a_tangent_that_underflows_in_the_working_type_is_refused() {
        // Accepted in f64 (positive), zero once rounded to f32: the
        // dissipated energy would be 0/0. Found by the step_models fuzzer.
        let flat = Polynomial::<f32, 2>::new(&[0.0, 1e-300], (-1.0, 1.0)).unwrap();
        let specs = [MaxwellSpec::new(2.0, 0.2)];
        let bank = MaxwellBank::<f32, 1>::new(MaxwellForm::RateExactRamp, &specs, 1e-3).unwrap();
        let b = Bushing::new(flat, (bank,)).unwrap();
        let mut s = b.state_at(0.0);
        let out = b.step(&mut s, 0.0);
        assert!(out.effects.is_none() && out.dissipated == 0.0);
        assert!(s.faults().contains(Faults::OUT_OF_RANGE));
    }

    #[test]
    fn an_energy_that_overflows_is_flagged_and_the_step_kept() {
        // A load-exponential bank re-tuned by a_T = 1e-37: ω·dt ~ 1e36, the
        // branch does not relax in a step and its energy h/g F² overflows
        // f32. Found by the step_models fuzzer.
        let specs = [MaxwellSpec::hz(1.0, 0.2), MaxwellSpec::hz(50.0, 0.2)];
        let mut bank =
            MaxwellBank::<f32, 2>::new(MaxwellForm::LoadExponential, &specs, 1e-3).unwrap();
        bank.retune::<crate::LibmExp>(1e-37).unwrap();
        let backbone = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).unwrap();
        let b = Bushing::new(backbone, (bank,)).unwrap();
        let mut s = b.state_at(0.0);
        let out = b.step(&mut s, -10.0);
        assert!(out.effects.is_some() && out.force.is_finite() && out.tangent.is_finite());
        assert_eq!(out.dissipated, 0.0);
        assert!(s.faults().contains(Faults::ENERGY_OVERFLOW));
    }

    #[test]
    fn a_displacement_beyond_the_guard_is_refused_on_a_soft_backbone() {
        // 1e38 mm on a backbone of 1e-37 N/mm is a force of 10 N, but a
        // turning-point law would square the distance. Found by the
        // step_models fuzzer.
        let soft = Polynomial::<f32, 2>::new(&[0.0, 1e-37], (-1.0, 1.0)).unwrap();
        let law = crate::stack::Sts::<f32>::new(600.0, 1000.0).unwrap();
        let stack = crate::stack::TurningPoints::<_, 8>::new(law, crate::FirstLoading::Ignored);
        let b = Bushing::new(soft, (stack,)).unwrap();
        let mut s = b.state_at(0.0);
        let out = b.step(&mut s, -2.7e38);
        assert!(out.effects.is_none() && out.force.is_finite());
        assert!(s.faults().contains(Faults::OUT_OF_RANGE));
    }

    #[test]
    fn a_step_beyond_the_guard_is_refused_whole_in_any_composition() {
        // A stiff K_f table (1e15 N/mm) beside a Maxwell bank and an absent
        // effect: at 2000 mm the table's force, 2e18 N, leaves f32's guard.
        // Every member keeps its state, including the stack's turning
        // points, on a stack with room and on a full one.
        use crate::FirstLoading;
        use crate::stack::{KfTable, TurningPoints};
        let soft = Polynomial::<f32, 2>::linear(1.0).unwrap();
        let table = KfTable::<f32, 1>::new(&[0.0], &[1e15]).unwrap();
        let stack = TurningPoints::<_, 4>::new(table, FirstLoading::Masing);
        let specs = [MaxwellSpec::new(2.0, 0.2)];
        let bank = MaxwellBank::<f32, 1>::new(MaxwellForm::RateExactRamp, &specs, 1e-3).unwrap();
        let b = Bushing::new(soft, (bank, None::<MaxwellBank<f32, 1>>, stack)).unwrap();
        let mut s = b.state_at(0.0);
        let mut full = false;
        for (k, x) in [0.5f32, -0.45, 0.4, -0.35, 0.3, -0.25, 0.2]
            .into_iter()
            .enumerate()
        {
            b.step(&mut s, x);
            full |= s.effects().2.depth() == 4;
            let before = s.clone();
            let out = b.step(&mut s, 2000.0);
            assert!(out.effects.is_none() && out.force == before.force(), "{k}");
            assert!(s.faults().contains(Faults::FORCE_OUT_OF_RANGE));
            s.clear_faults();
            assert_eq!(
                s, before,
                "a refused step changed the state ({k} reversals)"
            );
            assert!(b.step(&mut s, 1.0).effects.is_some());
            s = before;
        }
        assert!(full, "the stack was never full");
    }

    #[test]
    fn a_backbone_beyond_the_guard_at_rest_is_refused() {
        // Finite in f32, 1e30 N at x = 0: a state that falls back to x = 0
        // after a refused start would hold it (and a 6-DOF bushing's arms
        // would turn it into infinite moments). Found by the six_dof fuzzer.
        let far = Polynomial::<f32, 2>::new(&[1e30, 100.0], (-1.0, 1.0)).unwrap();
        assert!(matches!(
            Bushing::new(far, ()),
            Err(ParamError::OutOfRange { param, .. }) if param == Param::scalar("backbone force at x = 0")
        ));
        let fine = Polynomial::<f32, 2>::new(&[1e17, 100.0], (-1.0, 1.0)).unwrap();
        assert!(Bushing::new(fine, ()).is_ok());
    }

    #[test]
    fn trial_is_pure_and_equals_step() {
        let b = Bushing::new(cubic(), (bank(0.2, 1e-3),)).unwrap();
        let mut s = b.state_at(0.0);
        for n in 0..50 {
            b.step(&mut s, 0.01 * n as f64);
        }
        let before = s.clone();
        let (out, next) = b.trial(&s, 0.7);
        assert_eq!(s, before);
        let stepped = b.step(&mut s, 0.7);
        assert_eq!(out, stepped);
        assert_eq!(next, s);
    }

    #[test]
    fn a_relaxed_start_away_from_zero_has_no_spurious_step() {
        let b = Bushing::new(cubic(), (bank(0.2, 1e-3),)).unwrap();
        let mut s = b.state_at(2.0);
        let (f_inf, k_inf) = cubic().eval(2.0);
        assert_eq!(s.force(), b.g0() * f_inf);
        let out = b.step(&mut s, 2.0);
        assert_eq!(out.force, b.g0() * f_inf);
        assert_eq!(out.dissipated, 0.0);
        assert!(out.tangent > b.g0() * k_inf);
    }

    #[test]
    fn fractions_and_time_steps_are_checked_across_effects() {
        assert_eq!(
            Bushing::new(cubic(), (bank(0.3, 1e-3), bank(0.25, 1e-3))).unwrap_err(),
            ParamError::FractionsAboveOne { sum: 1.1 }
        );
        assert_eq!(
            Bushing::new(cubic(), (bank(0.1, 1e-3), bank(0.1, 2e-3))).unwrap_err(),
            ParamError::TimeStepMismatch {
                first: 1e-3,
                other: 2e-3
            }
        );
        let b = Bushing::new(cubic(), (bank(0.1, 1e-3), None::<Bank>, bank(0.2, 1e-3))).unwrap();
        assert!((b.g0() - 0.4).abs() < 1e-15);
    }

    #[test]
    fn a_tuple_sums_its_effects_and_none_adds_nothing() {
        let single = Bushing::new(cubic(), (bank(0.2, 1e-3),)).unwrap();
        let with_none = Bushing::new(cubic(), (bank(0.2, 1e-3), None::<Bank>)).unwrap();
        let pair = Bushing::new(cubic(), (bank(0.1, 1e-3), bank(0.1, 1e-3))).unwrap();
        let (mut s1, mut s2, mut s3) = (
            single.state_at(0.0),
            with_none.state_at(0.0),
            pair.state_at(0.0),
        );
        for n in 0..300 {
            let x = (0.05 * n as f64).sin();
            let a = single.step(&mut s1, x);
            let b = with_none.step(&mut s2, x);
            let c = pair.step(&mut s3, x);
            assert_eq!(a.force, b.force);
            assert_eq!(b.effects.unwrap().1, None);
            let (e0, e1) = c.effects.unwrap();
            assert_eq!(e0, e1);
            assert!((a.force - c.force).abs() <= 1e-12 * a.force.abs().max(1.0));
            assert!((a.dissipated - c.dissipated).abs() <= 1e-12 * a.dissipated.max(1e-12));
            assert_eq!(c.force, c.elastic + (e0.force + e1.force));
        }
    }

    #[test]
    fn refused_steps_keep_everything_and_count() {
        let b = Bushing::new(cubic(), (bank(0.2, 1e-3),)).unwrap();
        let mut s = b.state_at(0.0);
        let last = b.step(&mut s, 0.5);
        let kept = s.clone();
        let out = b.step(&mut s, f64::NAN);
        assert_eq!(
            (out.force, out.tangent, out.dissipated),
            (last.force, last.tangent, 0.0)
        );
        assert_eq!(out.elastic, last.elastic);
        assert!(out.effects.is_none());
        let out = b.step(&mut s, 1e200);
        assert_eq!(out.force, last.force);
        assert!(
            s.faults().contains(Faults::NON_FINITE_INPUT)
                && s.faults().contains(Faults::OUT_OF_RANGE)
        );
        assert_eq!(s.rejected(), 2);
        s.clear_faults();
        assert_eq!(s, kept);
        // A non-finite starting point is replaced by zero and flagged.
        let s = b.state_at(f64::INFINITY);
        assert_eq!(s.x(), 0.0);
        assert!(s.faults().contains(Faults::NON_FINITE_INPUT));
    }
}
