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

use crate::backbone::Backbone;
use crate::bushing::{Bushing, BushingState, Effect};
use crate::error::{Faults, Param, ParamError, positive};
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
/// - Cost: one bushing trial per iteration, plus one to seed it; at
///   `K_0 h² < 1e-3` the iteration stops after two or three.
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
    /// Fault flags raised since the state was made: refused forces, and the
    /// restoring force's own flags.
    pub fn faults(&self) -> Faults {
        let mut all = self.faults;
        all.raise(self.restoring.faults());
        all
    }
}

/// The result of one oscillator step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OscillatorStep<T> {
    /// Modal displacement p_{n+1}.
    pub p: T,
    /// Modal velocity v_{n+1}.
    pub v: T,
    /// Modal acceleration a_{n+1}.
    pub a: T,
    /// Restoring force r(p_{n+1}).
    pub force: T,
    /// Energy dissipated by the restoring force in the step.
    pub dissipated: T,
    /// Work of the external force in the step, trapezoidal:
    /// `(f_n + f_{n+1})/2 (p_{n+1} - p_n)`.
    pub work: T,
    /// Chord iterations taken.
    pub iterations: u32,
    /// Whether the iteration met its tolerance. A refused step (non-finite
    /// force, restoring force out of range) reports `false`.
    pub converged: bool,
}

impl<T: Real, B: Backbone<T>, E: Effect<T>> Oscillator<T, B, E> {
    /// Iteration limit of [`Oscillator::new`].
    pub const DEFAULT_MAX_ITERATIONS: u32 = 32;

    /// An oscillator of time step `dt` with the restoring force `restoring`.
    /// Refuses a non-positive `dt`, and one different from the step the
    /// restoring force's effects were built for.
    pub fn new(restoring: Bushing<T, B, E>, dt: f64) -> Result<Self, ParamError> {
        let dt = positive(Param::scalar("dt"), dt)?;
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
    /// branches unloaded), so `a0 = f0 - r(p0)`. Non-finite inputs are
    /// replaced by zero and flagged.
    pub fn state_at(&self, p0: T, v0: T, f0: T) -> OscillatorState<T, E::State> {
        let mut faults = Faults::NONE;
        let mut clean = |v: T| {
            if v.is_finite() {
                v
            } else {
                faults.raise(Faults::NON_FINITE_INPUT);
                T::ZERO
            }
        };
        let (p0, v0, f0) = (clean(p0), clean(v0), clean(f0));
        let restoring = self.restoring.state_at(p0);
        OscillatorState {
            p: restoring.x(),
            v: v0,
            a: f0 - restoring.force(),
            f: f0,
            restoring,
            faults,
        }
    }

    /// Advances `state` by one step under the external force `f` (the value
    /// at the end of the step).
    pub fn step(&self, state: &mut OscillatorState<T, E::State>, f: T) -> OscillatorStep<T> {
        if !f.is_finite() {
            state.faults.raise(Faults::NON_FINITE_INPUT);
            return refused(state);
        }
        let predicted = state.p + self.h * state.v + self.beta * state.a;
        let mut a = state.a;
        // Each chord iteration steps a scratch copy of the committed state
        // (one copy per iteration, none returned).
        let mut next = state.restoring.clone();
        let mut out = self.restoring.step(&mut next, predicted + self.beta * a);
        let mut iterations = 0;
        let mut converged = false;
        while iterations < self.max_iterations {
            iterations += 1;
            let correction = (a + out.force - f) * self.inv_slope;
            a -= correction;
            next.clone_from(&state.restoring);
            out = self.restoring.step(&mut next, predicted + self.beta * a);
            let scale = a.abs() + f.abs() + out.force.abs();
            if correction.abs() <= self.tolerance * scale {
                converged = true;
                break;
            }
        }
        if out.effects.is_none() || !a.is_finite() {
            // The restoring force refused the displacement (out of range):
            // keep the state, flag it.
            state.faults.raise(Faults::OUT_OF_RANGE);
            return refused(state);
        }
        let p = predicted + self.beta * a;
        let v = state.v + self.half_h * (state.a + a);
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

#[cold]
fn refused<T: Real, S>(state: &OscillatorState<T, S>) -> OscillatorStep<T> {
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
}
