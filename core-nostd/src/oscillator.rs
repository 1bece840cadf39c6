//! The one-degree-of-freedom modal macro-model of seed 004 §2.8 (the "Iwan
//! oscillator"), as a reusable fixed-step integrator.
//!
//! A mode of a jointed structure, with unit modal mass, obeys
//!
//! ```text
//! p'' + r(p, history) = f(t)          (seed 004 eq 2.3, 6.21, 7.6)
//! ```
//!
//! where the restoring force `r = ω_∞² p + f_h(p)` is the linear spring of
//! the contact zones that never slip in parallel with a hysteretic law
//! (Iwan, Dahl, Bouc-Wen, ...). Here `r` is any [`Bushing`]: a linear
//! backbone `Polynomial::linear(ω_0²)` with an [`crate::IwanBank`] taking the
//! fraction `1 - ω_∞²/ω_0²` gives the seed's oscillator, and any other
//! backbone and effects of this crate (Maxwell cells, x_f cells, friction
//! cells) give its viscoelastic or nonlinear variants.
//!
//! The modal tracker uses it to generate the free decays and forced
//! responses it is tested against.
//!
//! As every model of the crate, a step never poisons its state: an external
//! force that is not finite or is beyond [`Real::GUARD`], a displacement the
//! restoring force refuses, or a velocity or acceleration that would leave
//! the guard makes the step refused, the state kept and a fault flag raised;
//! a time step whose Newmark coefficients would round to zero or overflow in
//! the working type is refused at construction (see [`Oscillator`]).

use crate::backbone::Backbone;
use crate::bushing::{Bushing, BushingState, Effect};
use crate::error::{Faults, Param, ParamError, guarded, positive};
use crate::real::Real;

/// Fixed-step integrator of `p'' + r(p) = f` with unit mass.
///
/// - Equation: seed 004 eq 2.3 (`p'' + ω_∞² p + r_Iwan = f_e`), with the
///   restoring force `r` of a [`Bushing`].
/// - Scheme: Newmark's average-acceleration (trapezoidal) rule,
///   `p_{n+1} = p_n + h v_n + h²/4 (a_n + a_{n+1})`,
///   `v_{n+1} = v_n + h/2 (a_n + a_{n+1})`,
///   with `a_{n+1} = f_{n+1} - r(p_{n+1})` solved by a chord iteration on
///   `a_{n+1}`: `a ← a - (a + r(p(a)) - f) / (1 + h²/4 K_0)`, where `K_0` is
///   the tangent of `r` at rest (computed once, so the step never divides).
///   Every iterate is a pure [`Bushing::trial`]; only the converged state is
///   committed, so the hysteretic memory sees one step per period.
/// - States: `p`, `v`, `a` and the restoring force's [`BushingState`].
/// - Stability: for a linear restoring force the rule is unconditionally
///   stable and conserves the energy `v²/2 + K p²/2` exactly (no numerical
///   damping, which matters when the damping being measured is a fraction of
///   a percent); its only error is a period elongation,
///   `ω_h = (2/h) atan(ω h / 2)`, i.e. `(ω h)²/12` relative. With a passive
///   restoring force the discrete work balance
///   `Δ(v²/2) + Σ (r_n + r_{n+1})/2 Δp = Σ (f_n + f_{n+1})/2 Δp` holds to
///   rounding ([`OscillatorStep::work`]). The chord iteration contracts by
///   `|K_0 - K_t| h²/4 / (1 + K_0 h²/4)` per iteration and converges
///   whenever the algorithmic tangent stays in `-4/h² < K_t < 4/h² + 2 K_0`;
///   outside that (a strongly hardening backbone at a coarse step) the step
///   reports `converged = false` after the iteration limit and commits the
///   last iterate.
/// - Time step: [`Oscillator::new`] keeps the step coefficients `h`,
///   `h/2` and `β = h²/4` positive and within [`Real::GUARD`] in the
///   working type: `β` from the smallest power of four the type holds to
///   `GUARD`, i.e. `dt` from `2^-73` (about 1.1e-22) to `2^31` in `f32`,
///   from `2^-536` to `2^251` in `f64` (and from `2^-7` to `2^8` in `Q16`,
///   where `β` is below the resolution at any control rate). It also keeps
///   `β K_0 <= GUARD`, so that the chord slope `1 / (1 + β K_0)` does not
///   round to zero. Anything else is refused with a typed [`ParamError`]
///   naming `dt` and the bound.
/// - Refused steps: the external force must be finite and within
///   [`Real::GUARD`] ([`Faults::NON_FINITE_INPUT`], [`Faults::OUT_OF_RANGE`]
///   otherwise); the restoring force must accept the converged
///   displacement (so `p_{n+1}` and `r(p_{n+1})` are finite and within the
///   guard; [`Faults::OUT_OF_RANGE`] otherwise); and the new `v` and `a`
///   must be finite and within the guard ([`Faults::FORCE_OUT_OF_RANGE`]
///   otherwise: two accelerations near the guard added over a coarse step).
///   A refused step keeps the state bit for bit, returns the last `p`, `v`,
///   `a` and restoring force with no work, no dissipation, no iteration and
///   `converged = false`, and raises the flag in the oscillator's state.
///   Every accepted state thus holds `p`, `v`, `a`, `f` and `r` within the
///   guard, where no product the step forms overflows.
/// - Cost: one bushing trial per iteration, plus one to seed it; at
///   `K_0 h² < 1e-3` the iteration stops after two or three. The guards
///   cost three comparisons per step (on `f`, `a` and `v`), no division.
///
/// ```
/// use bushing::{Bushing, Oscillator, ParamError, Polynomial};
///
/// // A unit-mass mode on a linear 100 N/mm spring (no effect), at 1 kHz.
/// let spring = Bushing::new(Polynomial::<f64, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?, ())?;
/// let osc = Oscillator::new(spring, 1e-3)?;
/// let mut state = osc.state_at(1.0, 0.0, 0.0);
/// // Free vibration: the trapezoidal rule keeps the amplitude.
/// let mut peak: f64 = 0.0;
/// for _ in 0..2000 {
///     let s = osc.step(&mut state, 0.0);
///     assert!(s.converged);
///     peak = peak.max(s.p.abs());
/// }
/// assert!((peak - 1.0).abs() < 1e-3);
/// assert!(Oscillator::new(Bushing::new(Polynomial::<f64, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?, ())?, 0.0).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Oscillator<T, B, E> {
    restoring: Bushing<T, B, E>,
    dt: f64,
    h: T,
    half_h: T,
    beta: T,
    inv_slope: T,
    tolerance: T,
    k0: f64,
    max_iterations: u32,
}

/// State of an [`Oscillator`].
#[derive(Debug, Clone, PartialEq)]
pub struct OscillatorState<T, S> {
    p: T,
    v: T,
    a: T,
    f: T,
    restoring: BushingState<T, S>,
    faults: Faults,
}

impl<T: Real, S> OscillatorState<T, S> {
    /// Modal displacement.
    pub fn p(&self) -> T {
        self.p
    }
    /// Modal velocity.
    pub fn v(&self) -> T {
        self.v
    }
    /// Modal acceleration.
    pub fn a(&self) -> T {
        self.a
    }
    /// Kinetic energy `v²/2` (unit mass).
    pub fn kinetic(&self) -> T {
        T::HALF * self.v * self.v
    }
    /// The restoring force's state (hysteretic memory, force).
    pub fn restoring(&self) -> &BushingState<T, S> {
        &self.restoring
    }
    /// Fault flags raised since the state was made: refused starts and
    /// steps (see [`Oscillator`]), and the restoring force's own flags.
    pub fn faults(&self) -> Faults {
        let mut all = self.faults;
        all.raise(self.restoring.faults());
        all
    }
}

/// The result of one oscillator step.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OscillatorStep<T> {
    /// Modal displacement p_{n+1}, mm.
    pub p: T,
    /// Modal velocity v_{n+1}, mm/s.
    pub v: T,
    /// Modal acceleration a_{n+1}, mm/s².
    pub a: T,
    /// Restoring force r(p_{n+1}), N.
    pub force: T,
    /// Energy dissipated by the restoring force in the step, mJ.
    pub dissipated: T,
    /// Work of the external force in the step, trapezoidal:
    /// `(f_n + f_{n+1})/2 (p_{n+1} - p_n)`, mJ.
    pub work: T,
    /// Chord iterations taken.
    pub iterations: u32,
    /// Whether the iteration met its tolerance. A refused step (external
    /// force not finite or beyond the guard, restoring force out of range,
    /// new velocity or acceleration beyond the guard) reports `false`, with
    /// no iteration.
    pub converged: bool,
}

impl<T: Real, B: Backbone<T>, E: Effect<T>> Oscillator<T, B, E> {
    /// Iteration limit of [`Oscillator::new`].
    pub const DEFAULT_MAX_ITERATIONS: u32 = 32;

    /// An oscillator of time step `dt` with the restoring force `restoring`.
    /// Refuses a non-positive `dt`; a `dt` whose coefficients `h/2` or
    /// `β = dt²/4` would round to zero in the working type, or `β` exceed
    /// [`Real::GUARD`] ([`ParamError::OutOfRange`] on `dt`, from `2^-73` to
    /// `2^31` in `f32`: see [`Oscillator`]); one different from the step the
    /// restoring force's effects were built for; and one where
    /// `dt² K_0 / 4` exceeds [`Real::GUARD`] (in fixed point the chord
    /// slope `1 / (1 + dt² K_0 / 4)` would round to zero).
    pub fn new(restoring: Bushing<T, B, E>, dt: f64) -> Result<Self, ParamError> {
        let param = Param::scalar("dt");
        let dt = positive(param, dt)?;
        let (min, max) = dt_range::<T>();
        if !(min..=max).contains(&dt) {
            return Err(ParamError::OutOfRange {
                param,
                value: dt,
                min,
                min_open: false,
                max,
            });
        }
        if let Some(built) = restoring.effects().check_dt(None)?
            && (built - dt).abs() > 1e-12 * dt
        {
            return Err(ParamError::TimeStepMismatch {
                first: built,
                other: dt,
            });
        }
        let rest = restoring.state_at(T::ZERO);
        let (probe, _) = restoring.trial(&rest, T::ZERO);
        let k0 = probe.tangent.to_f64();
        let k0 = if k0.is_finite() { k0.max(0.0) } else { 0.0 };
        let beta = 0.25 * dt * dt;
        guarded::<T>(Param::scalar("dt^2 K_0 / 4"), beta * k0)?;
        Ok(Self {
            restoring,
            dt,
            h: T::from_f64(dt),
            half_h: T::from_f64(0.5 * dt),
            beta: T::from_f64(beta),
            inv_slope: T::from_f64(1.0 / (1.0 + beta * k0)),
            tolerance: T::from_f64(64.0) * T::EPSILON,
            k0,
            max_iterations: Self::DEFAULT_MAX_ITERATIONS,
        })
    }

    /// The same oscillator with another iteration limit (at least one).
    pub fn with_max_iterations(mut self, max_iterations: u32) -> Self {
        self.max_iterations = max_iterations.max(1);
        self
    }

    /// Time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Tangent of the restoring force at rest, `K_0 = ω_0²`, that sets the
    /// chord slope.
    pub fn reference_stiffness(&self) -> f64 {
        self.k0
    }

    /// The restoring force.
    pub fn restoring(&self) -> &Bushing<T, B, E> {
        &self.restoring
    }

    /// A state at displacement `p0` and velocity `v0` under the external
    /// force `f0`, with the restoring force relaxed at `p0` (all hysteretic
    /// branches unloaded), so `a0 = f0 - r(p0)`. An input that is not
    /// finite, or beyond [`Real::GUARD`], is replaced by zero and flagged
    /// ([`Faults::NON_FINITE_INPUT`], [`Faults::OUT_OF_RANGE`]); so is a
    /// force `f0` whose `a0` would leave the guard ([`Faults::OUT_OF_RANGE`]),
    /// and a `p0` the restoring force refuses (its own flag). The state
    /// holds `p`, `v`, `a`, `f` and `r` within the guard, as every step
    /// keeps it.
    pub fn state_at(&self, p0: T, v0: T, f0: T) -> OscillatorState<T, E::State> {
        let mut faults = Faults::NONE;
        let mut clean = |v: T| {
            if within(v) {
                v
            } else {
                faults.raise(if v.is_finite() {
                    Faults::OUT_OF_RANGE
                } else {
                    Faults::NON_FINITE_INPUT
                });
                T::ZERO
            }
        };
        let (p0, v0, mut f0) = (clean(p0), clean(v0), clean(f0));
        let restoring = self.restoring.state_at(p0);
        let mut a0 = f0 - restoring.force();
        if !within(a0) {
            faults.raise(Faults::OUT_OF_RANGE);
            f0 = T::ZERO;
            a0 = -restoring.force();
        }
        OscillatorState {
            p: restoring.x(),
            v: v0,
            a: a0,
            f: f0,
            restoring,
            faults,
        }
    }

    /// Advances `state` by one step under the external force `f` (the value
    /// at the end of the step). A step that cannot be taken (see
    /// [`Oscillator`]) is refused: the state is kept, a flag raised and the
    /// last values returned.
    pub fn step(&self, state: &mut OscillatorState<T, E::State>, f: T) -> OscillatorStep<T> {
        if !within(f) {
            let why = if f.is_finite() {
                Faults::OUT_OF_RANGE
            } else {
                Faults::NON_FINITE_INPUT
            };
            return refuse(state, why);
        }
        let predicted = state.p + self.h * state.v + self.beta * state.a;
        let mut a = state.a;
        let mut p = predicted + self.beta * a;
        // Each chord iteration steps a scratch copy of the committed state
        // (one copy per iteration, none returned).
        let mut next = state.restoring.clone();
        let mut out = self.restoring.step(&mut next, p);
        let mut iterations = 0;
        let mut converged = false;
        while iterations < self.max_iterations {
            iterations += 1;
            let correction = (a + out.force - f) * self.inv_slope;
            a -= correction;
            p = predicted + self.beta * a;
            next.clone_from(&state.restoring);
            out = self.restoring.step(&mut next, p);
            let scale = a.abs() + f.abs() + out.force.abs();
            if correction.abs() <= self.tolerance * scale {
                converged = true;
                break;
            }
        }
        if out.effects.is_none() {
            // The restoring force refused the displacement (out of range):
            // keep the state, flag it.
            return refuse(state, Faults::OUT_OF_RANGE);
        }
        // The restoring force accepted `p`, so `p` and its force are finite
        // and within the guard; the acceleration and the velocity are
        // checked here (each of |a_n|, |a_{n+1}| up to the guard, times h/2).
        let v = state.v + self.half_h * (state.a + a);
        if !within(a) | !within(v) {
            return refuse(state, Faults::FORCE_OUT_OF_RANGE);
        }
        let work = T::HALF * (state.f + f) * (p - state.p);
        state.p = p;
        state.v = v;
        state.a = a;
        state.f = f;
        state.restoring = next;
        OscillatorStep {
            p,
            v,
            a,
            force: out.force,
            dissipated: out.dissipated,
            work,
            iterations,
            converged,
        }
    }
}

/// The time steps [`Oscillator::new`] accepts in the working type,
/// `(min, max)`, both included: `β = dt²/4` from the smallest power of four
/// the type holds exactly (so that neither `β` nor `h/2` rounds to zero) to
/// [`Real::GUARD`]. `(2^-73, 2^31)` in `f32`, `(2^-536, 2^251)` in `f64`.
fn dt_range<T: Real>() -> (f64, f64) {
    // 4^-k and its square root 2^-k, for the largest k whose 4^-k the
    // working type holds exactly (at most 537 quarterings, in f64).
    let (mut quarter, mut root) = (1.0f64, 1.0f64);
    loop {
        let next = 0.25 * quarter;
        if !(next > 0.0 && T::from_f64(next).to_f64() == next) {
            break;
        }
        quarter = next;
        root *= 0.5;
    }
    (2.0 * root, 2.0 * libm::sqrt(T::GUARD.to_f64()))
}

/// Finite and within [`Real::GUARD`] in magnitude (a NaN fails).
#[inline(always)]
fn within<T: Real>(v: T) -> bool {
    v.abs() <= T::GUARD
}

/// Raises `why` and returns the last values, the state kept.
#[cold]
fn refuse<T: Real, S>(state: &mut OscillatorState<T, S>, why: Faults) -> OscillatorStep<T> {
    state.faults.raise(why);
    OscillatorStep {
        p: state.p,
        v: state.v,
        a: state.a,
        force: state.restoring.force(),
        dissipated: T::ZERO,
        work: T::ZERO,
        iterations: 0,
        converged: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backbone::Polynomial;
    use crate::iwan::{IwanBank, IwanCellSpec};
    use crate::maxwell::{MaxwellBank, MaxwellForm, MaxwellSpec};
    use core::f64::consts::{PI, TAU};

    type Linear = Bushing<f64, Polynomial<f64, 2>, ()>;
    type Iwan = Bushing<f64, Polynomial<f64, 2>, (IwanBank<f64, 20>,)>;

    fn linear(k: f64) -> Linear {
        Bushing::new(Polynomial::linear(k).unwrap(), ()).unwrap()
    }

    fn linear_f32(k: f64) -> Bushing<f32, Polynomial<f32, 2>, ()> {
        Bushing::new(Polynomial::linear(k).unwrap(), ()).unwrap()
    }

    /// Every value a step returns and keeps, bit for bit.
    fn kept<S>(s: &OscillatorState<f32, S>) -> [u32; 5] {
        [s.p, s.v, s.a, s.f, s.restoring.force()].map(f32::to_bits)
    }

    /// Seed 004 §4.1: 20 Jenkins cells of stiffness 0.05 slipping from 0.2
    /// to 2, in parallel with ω_∞² = 5.
    fn phis() -> impl Iterator<Item = f64> + Clone {
        (0..20).map(|i| 0.2 + 1.8 * i as f64 / 19.0)
    }

    fn reference_iwan() -> Iwan {
        let cells: [IwanCellSpec; 20] = core::array::from_fn(|i| {
            IwanCellSpec::from_slip_distance(0.05 / 6.0, 6.0, 0.2 + 1.8 * i as f64 / 19.0)
        });
        Bushing::new(
            Polynomial::linear(6.0).unwrap(),
            (IwanBank::new(&cells).unwrap(),),
        )
        .unwrap()
    }

    /// Secant damping of the reference oscillator at amplitude p_m (seed 004
    /// eq 7.10 with the Masing dissipation D = Σ 4 f_i (p_m - φ_i)).
    fn secant_damping(pm: f64) -> f64 {
        let d: f64 = phis().filter(|&f| f < pm).map(|f| 0.2 * f * (pm - f)).sum();
        let f_r = 5.0 * pm + phis().map(|f| 0.05 * pm.min(f)).sum::<f64>();
        d / (TAU * f_r * pm)
    }

    #[test]
    fn linear_rule_conserves_energy_and_has_the_newmark_period() {
        let omega = TAU;
        let h = 0.01;
        let osc = Oscillator::new(linear(omega * omega), h).unwrap();
        let mut s = osc.state_at(1.0, 0.0, 0.0);
        let energy = |s: &OscillatorState<f64, ()>| s.kinetic() + 0.5 * omega * omega * s.p * s.p;
        let e0 = energy(&s);
        let mut crossings = [0.0f64; 2];
        let mut found = 0;
        let mut prev = s.p;
        for n in 1..=5000 {
            let out = osc.step(&mut s, 0.0);
            assert!(out.converged);
            assert!((energy(&s) - e0).abs() <= 1e-12 * e0, "energy drifts");
            if prev < 0.0 && out.p >= 0.0 && found < 2 {
                // Linear interpolation of the upward zero crossing.
                crossings[found] = h * ((n - 1) as f64 + prev / (prev - out.p));
                found += 1;
            }
            prev = out.p;
        }
        assert_eq!(found, 2);
        let period = crossings[1] - crossings[0];
        let omega_h = 2.0 / h * (omega * h / 2.0).atan();
        // Interpolating a sine between samples costs (ωh)²/8 of the phase at
        // most at each crossing; 100 samples per period keep it below 1e-4.
        assert!(
            (period * omega_h / TAU - 1.0).abs() < 1e-4,
            "period {period}"
        );
        assert!(period > TAU / omega, "the rule lengthens the period");
    }

    #[test]
    fn forced_sine_follows_the_steady_state_solution() {
        // p'' + ω² p = F sin Ωt, started on the particular solution
        // p = F/(ω² - Ω²) sin Ωt, stays on it (no free vibration).
        let (omega, big_omega, force) = (TAU, 0.6 * TAU, 2.0);
        let amp = force / (omega * omega - big_omega * big_omega);
        let h = 1e-3;
        let osc = Oscillator::new(linear(omega * omega), h).unwrap();
        let mut s = osc.state_at(0.0, amp * big_omega, 0.0);
        let mut worst: f64 = 0.0;
        for n in 1..=10_000 {
            let t = n as f64 * h;
            let out = osc.step(&mut s, force * (big_omega * t).sin());
            worst = worst.max((out.p - amp * (big_omega * t).sin()).abs());
        }
        // Global error O((ωh)²) over 6 forcing periods.
        assert!(worst < 1e-3 * amp, "worst {worst} vs amplitude {amp}");
    }

    #[test]
    fn iwan_free_decay_matches_the_secant_damping() {
        // Seed 004 reports free-decay damping within 0.2 points of the
        // harmonic-balance curve; the log decrement between successive peaks
        // against the secant damping at their geometric mean.
        let osc = Oscillator::new(reference_iwan(), 0.005).unwrap();
        assert!((osc.reference_stiffness() - 6.0).abs() < 1e-12);
        let mut s = osc.state_at(2.5, 0.0, 0.0);
        let mut peaks = [0.0f64; 8];
        let mut found = 0;
        let (mut p1, mut p2) = (2.5, 2.5);
        while found < peaks.len() {
            let out = osc.step(&mut s, 0.0);
            assert!(out.converged && out.iterations <= 4);
            assert!(out.dissipated >= 0.0);
            if p2 > p1 && p2 >= out.p && p2 > 0.0 {
                peaks[found] = p2;
                found += 1;
            }
            (p1, p2) = (p2, out.p);
        }
        for w in peaks.windows(2) {
            let pm = (w[0] * w[1]).sqrt();
            let xi = (w[0] / w[1]).ln() / TAU;
            assert!(
                (xi - secant_damping(pm)).abs() < 2e-3,
                "xi {xi} vs {} at {pm}",
                secant_damping(pm)
            );
        }
        assert!(peaks[7] < peaks[0], "the oscillation decays");
    }

    #[test]
    fn discrete_work_balance_holds_to_rounding_under_forcing() {
        // Δ(v²/2) + W_restoring = W_external, exactly for the trapezoidal
        // rule; and the energy dissipated never exceeds the work the
        // restoring force absorbed (its stored energy is not negative).
        let h = 0.01;
        let osc = Oscillator::new(reference_iwan(), h).unwrap();
        let mut s = osc.state_at(0.0, 0.0, 0.0);
        let (mut w_ext, mut w_rest, mut dissipated, mut magnitude) = (0.0, 0.0, 0.0, 0.0);
        let mut r_prev = s.restoring().force();
        for n in 1..=20_000 {
            let t = n as f64 * h;
            let f = 3.0 * (2.2 * t).sin() * (-0.02 * t).exp();
            let p_prev = s.p();
            let out = osc.step(&mut s, f);
            assert!(out.converged);
            assert!(out.dissipated >= 0.0);
            w_ext += out.work;
            w_rest += 0.5 * (r_prev + out.force) * (out.p - p_prev);
            magnitude += out.work.abs();
            dissipated += out.dissipated;
            r_prev = out.force;
        }
        assert!(dissipated > 1.0, "the joint slipped");
        assert!(
            (s.kinetic() + w_rest - w_ext).abs() <= 1e-9 * magnitude,
            "balance {} vs {}",
            s.kinetic() + w_rest,
            w_ext
        );
        assert!(dissipated <= w_rest * (1.0 + 1e-3));
    }

    #[test]
    fn viscoelastic_restoring_force_damps_a_free_decay() {
        // A Maxwell cell in the restoring force: the modal energy decays
        // monotonically and the dissipated energy accounts for it.
        let h = 1e-3;
        let bank =
            MaxwellBank::<f64, 1>::new(MaxwellForm::RateExactRamp, &[MaxwellSpec::hz(1.0, 0.1)], h)
                .unwrap();
        let osc = Oscillator::new(
            Bushing::new(
                Polynomial::<f64, 2>::linear(4.0 * PI * PI).unwrap(),
                (bank,),
            )
            .unwrap(),
            h,
        )
        .unwrap();
        let mut s = osc.state_at(1.0, 0.0, 0.0);
        let mut kinetic_peak = 0.0f64;
        let mut last_peak = f64::INFINITY;
        let mut dissipated = 0.0;
        for _ in 0..10_000 {
            let v_before = s.v();
            let out = osc.step(&mut s, 0.0);
            dissipated += out.dissipated;
            kinetic_peak = kinetic_peak.max(s.kinetic());
            if v_before > 0.0 && out.v <= 0.0 {
                assert!(kinetic_peak < last_peak);
                last_peak = kinetic_peak;
                kinetic_peak = 0.0;
            }
        }
        // Released from rest with the cell relaxed, the mode holds the
        // elastic energy of the long-term branch only: g^0 K p0² / 2. A
        // passive cell cannot dissipate more; at ξ ≈ 2.5 % ten cycles leave
        // a few percent of it.
        let e0 = 0.5 * 0.9 * 4.0 * PI * PI;
        assert!(dissipated <= e0, "dissipated {dissipated} > {e0}");
        assert!(dissipated > 0.9 * e0, "dissipated {dissipated}");
        assert!(last_peak < 0.1 * e0, "last kinetic peak {last_peak}");
    }

    #[test]
    fn time_step_errors_are_typed() {
        assert_eq!(
            Oscillator::new(linear(1.0), 0.0).unwrap_err(),
            ParamError::NotPositive {
                param: Param::scalar("dt"),
                value: 0.0
            }
        );
        assert_eq!(
            Oscillator::new(linear(1.0), f64::NAN).unwrap_err(),
            ParamError::NotFinite {
                param: Param::scalar("dt")
            }
        );
        let bank = MaxwellBank::<f64, 1>::new(
            MaxwellForm::RateExactRamp,
            &[MaxwellSpec::hz(1.0, 0.1)],
            1e-3,
        )
        .unwrap();
        let b = Bushing::new(Polynomial::<f64, 2>::linear(1.0).unwrap(), (bank,)).unwrap();
        assert_eq!(
            Oscillator::new(b, 2e-3).unwrap_err(),
            ParamError::TimeStepMismatch {
                first: 1e-3,
                other: 2e-3
            }
        );
    }

    #[test]
    fn bad_inputs_are_refused_and_the_state_kept() {
        let osc = Oscillator::new(reference_iwan(), 0.01).unwrap();
        let mut s = osc.state_at(0.5, 0.1, 0.0);
        for _ in 0..10 {
            osc.step(&mut s, 1.0);
        }
        let before = s.clone();
        let out = osc.step(&mut s, f64::NAN);
        assert!(!out.converged && out.work == 0.0 && out.p == before.p());
        assert_eq!(s.p(), before.p());
        assert_eq!(s.restoring(), before.restoring());
        assert!(s.faults().contains(Faults::NON_FINITE_INPUT));
        // A force that throws the mode beyond the backbone's guard.
        let out = osc.step(&mut s, 1e300);
        assert!(!out.converged);
        assert_eq!(s.p(), before.p());
        assert!(s.faults().contains(Faults::OUT_OF_RANGE));
        // And it carries on from where it was.
        let out = osc.step(&mut s, 1.0);
        assert!(out.converged && out.p.is_finite());
        let nan_start = osc.state_at(f64::NAN, 0.0, 0.0);
        assert_eq!(nan_start.p(), 0.0);
        assert!(nan_start.faults().contains(Faults::NON_FINITE_INPUT));
    }

    #[test]
    fn a_finite_force_beyond_the_guard_is_refused_and_the_state_kept() {
        // The fuzzer's case: f32, dt = 1e-12, a force of -3e38 at the start
        // and at the step. Two accelerations near f32::MAX used to make
        // v = -inf, and every later step was refused.
        let osc = Oscillator::new(linear_f32(100.0), 1e-12).unwrap();
        let mut s = osc.state_at(0.0, 0.0, -3e38);
        // The start force is beyond the guard: replaced by zero, flagged.
        assert!(s.faults().contains(Faults::OUT_OF_RANGE));
        assert_eq!((s.p(), s.v(), s.a()), (0.0, 0.0, 0.0));
        let before = kept(&s);
        let out = osc.step(&mut s, -3e38);
        assert_eq!((out.iterations, out.converged), (0, false));
        assert_eq!(
            (out.p, out.v, out.a, out.force, out.work, out.dissipated),
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        );
        assert_eq!(kept(&s), before);
        // From a clean start the step itself raises the flag.
        let mut s = osc.state_at(0.0, 0.0, 0.0);
        assert!(s.faults().is_empty());
        let before = kept(&s);
        for (f, why) in [
            (-3e38, Faults::OUT_OF_RANGE),
            (f32::MAX, Faults::OUT_OF_RANGE),
            (-1.2e18, Faults::OUT_OF_RANGE), // just beyond 2^60
            (f32::NEG_INFINITY, Faults::NON_FINITE_INPUT),
        ] {
            let out = osc.step(&mut s, f);
            assert_eq!((out.iterations, out.converged), (0, false), "{f}");
            assert_eq!(kept(&s), before, "{f}");
            assert!(s.faults().contains(why), "{f}");
        }
        assert!(!s.faults().contains(Faults::FORCE_OUT_OF_RANGE));
        // The next ordinary step is taken: a = 1 - 100 p with p ~ 2.5e-25,
        // so v = h/2 (0 + 1) = 5e-13.
        let out = osc.step(&mut s, 1.0);
        assert!(out.converged && out.iterations >= 1);
        assert_eq!(out.a, 1.0);
        assert_eq!(s.v(), 0.5e-12);
        assert!(s.p() > 0.0 && s.p() < 1e-24);
        // And a force at the guard itself is accepted.
        let out = osc.step(&mut s, -<f32 as Real>::GUARD);
        assert!(out.iterations >= 1 && out.v.is_finite() && out.v < 0.0);
    }

    #[test]
    fn a_velocity_or_acceleration_beyond_the_guard_is_refused() {
        // f32, k = 1, dt = 1e-3, started at v = 2^60 (the guard). A force
        // of +2^60 keeps p near 1.2e15 and a near the guard, but
        // v + h/2 (a_n + a_{n+1}) would pass it by 5.8e14; a force of -2^60
        // makes a = f - r beyond the guard. Both are refused, the state
        // kept; a step with no force is then taken.
        let guard = <f32 as Real>::GUARD;
        let osc = Oscillator::new(linear_f32(1.0), 1e-3).unwrap();
        let mut s = osc.state_at(0.0, guard, 0.0);
        assert!(s.faults().is_empty());
        let before = kept(&s);
        for f in [guard, -guard] {
            let out = osc.step(&mut s, f);
            assert_eq!((out.iterations, out.converged), (0, false), "{f}");
            assert_eq!((out.v, out.p), (guard, 0.0));
            assert_eq!(kept(&s), before, "{f}");
        }
        assert!(s.faults().contains(Faults::FORCE_OUT_OF_RANGE));
        assert!(!s.faults().contains(Faults::OUT_OF_RANGE));
        let out = osc.step(&mut s, 0.0);
        assert!(out.converged);
        assert!(out.v < guard && out.v > 0.99 * guard && out.p > 1e15);
        assert!(out.a < 0.0 && out.a.abs() <= guard);
    }

    #[test]
    fn starts_beyond_the_guard_are_replaced_and_flagged() {
        let guard = <f64 as Real>::GUARD;
        let osc = Oscillator::new(linear(1.0), 1e-3).unwrap();
        // A velocity or a force beyond the guard: zero, flagged.
        let s = osc.state_at(0.5, 2.0 * guard, 0.0);
        assert_eq!((s.p(), s.v(), s.a()), (0.5, 0.0, -0.5));
        assert!(s.faults().contains(Faults::OUT_OF_RANGE));
        let s = osc.state_at(0.5, 1.0, -2.0 * guard);
        assert_eq!((s.v(), s.a()), (1.0, -0.5));
        assert!(s.faults().contains(Faults::OUT_OF_RANGE));
        let s = osc.state_at(0.5, f64::INFINITY, 0.0);
        assert_eq!(s.v(), 0.0);
        assert!(s.faults().contains(Faults::NON_FINITE_INPUT));
        // Each within the guard, but a0 = f0 - r(p0) = -1.8 guard: the
        // force is replaced by zero, so a0 = -r(p0).
        let s = osc.state_at(0.9 * guard, 0.0, -0.9 * guard);
        assert_eq!((s.p(), s.a()), (0.9 * guard, -0.9 * guard));
        assert!(s.faults().contains(Faults::OUT_OF_RANGE));
        // At the guard, accepted as given.
        let s = osc.state_at(0.0, -guard, guard);
        assert_eq!((s.v(), s.a()), (-guard, guard));
        assert!(s.faults().is_empty());
    }

    #[test]
    fn time_steps_whose_coefficients_leave_the_working_type_are_refused() {
        let refused = |value, min, max| ParamError::OutOfRange {
            param: Param::scalar("dt"),
            value,
            min,
            min_open: false,
            max,
        };
        // f32: β = dt²/4 from 2^-148 (the smallest power of four f32 holds)
        // to the guard 2^60, i.e. dt from 2^-73 to 2^31.
        let (min, max) = (2f64.powi(-73), 2f64.powi(31));
        assert_eq!(dt_range::<f32>(), (min, max));
        // dt = 1e-300 makes h, h/2 and β all 0 in f32.
        assert_eq!(
            Oscillator::new(linear_f32(100.0), 1e-300).unwrap_err(),
            refused(1e-300, min, max)
        );
        for value in [0.99 * min, 1.01 * max, 1e30] {
            assert_eq!(
                Oscillator::new(linear_f32(1.0), value).unwrap_err(),
                refused(value, min, max)
            );
        }
        // At the bounds: every coefficient positive and finite in f32.
        let osc = Oscillator::new(linear_f32(1.0), min).unwrap();
        assert!(osc.beta > 0.0 && osc.half_h > 0.0 && osc.h > 0.0);
        let osc = Oscillator::new(linear_f32(1.0), max).unwrap();
        assert_eq!(osc.beta, <f32 as Real>::GUARD);
        assert!(osc.inv_slope > 0.0);
        // f64: dt from 2^-536 to 2^251; 1e-300 would make β 0 there too.
        let (min, max) = (2f64.powi(-536), 2f64.powi(251));
        assert_eq!(dt_range::<f64>(), (min, max));
        assert_eq!(
            Oscillator::new(linear(1.0), 1e-300).unwrap_err(),
            refused(1e-300, min, max)
        );
        // The chord slope 1 / (1 + β K_0): β K_0 at most the guard.
        let k0 = 1e12f32 as f64;
        assert_eq!(
            Oscillator::new(linear_f32(1e12), 1e6).unwrap_err(),
            ParamError::OutOfRange {
                param: Param::scalar("dt^2 K_0 / 4"),
                value: 0.25 * 1e6 * 1e6 * k0,
                min: -<f32 as Real>::GUARD.to_f64(),
                min_open: false,
                max: <f32 as Real>::GUARD.to_f64()
            }
        );
        assert!(Oscillator::new(linear_f32(1e12), 1e-3).is_ok());
    }

    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_point_time_steps_keep_beta_above_the_resolution() {
        use crate::Q16;
        // Q16: β from 2^-16 (the resolution) to the guard 2^14.
        assert_eq!(dt_range::<Q16>(), (2f64.powi(-7), 2f64.powi(8)));
        let b = Bushing::new(Polynomial::<Q16, 2>::linear(1.0).unwrap(), ()).unwrap();
        assert!(matches!(
            Oscillator::new(b.clone(), 0.005),
            Err(ParamError::OutOfRange { .. })
        ));
        let osc = Oscillator::new(b, 0.01).unwrap();
        assert!(osc.beta > Q16::ZERO && osc.inv_slope > Q16::ZERO);
    }
}
