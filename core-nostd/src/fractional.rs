//! The order-independent fractional-derivative cell of seed 000 §1.3.3,
//! discretised by the truncated Grünwald-Letnikov sum (eqs 1.23-1.25).
//!
//! In the bushing's force-rate frame (the frame of the Maxwell cells, eq
//! 1.12) the cell takes a fraction g of the backbone and its branch force f
//! obeys
//!
//! ```text
//! f + ω_c^-α D^α (f - g F^∞) = 0
//! ```
//!
//! which, on a linear backbone F^∞ = K^∞ x and with g^0 = 1 - g, is the
//! fractional standard solid of eq 1.18 with K^0 = g^0 K^∞: its complex
//! stiffness is eq 1.20, `K(iω) = K^∞ - g K^∞ / (1 + (iω/ω_c)^α)`, with
//! storage and loss moduli eq 1.21. Four parameters (K^∞ from the backbone,
//! g, ω_c, α) give a transition whose width is set by α, not by a number of
//! cells.
//!
//! The Grünwald sum replaces D^α u at t_n by
//! `dt^-α Σ_{j=0}^{N} A_{j+1} u_{n-j}` with the weights of eq 1.23 computed by
//! their recursion `A_1 = 1, A_{j+1} = A_j (j - 1 - α) / j` (no Γ). With
//! `c = (ω_c dt)^-α` and u = f - g F^∞ the step is
//!
//! ```text
//! f_n = c/(1 + c) (g F^∞_n - Σ_{j=1}^{N} A_{j+1} u_{n-j})          (eq 1.24)
//! ```
//!
//! so the history is one ring buffer of the last N values of u.

use crate::bushing::{Drive, Effect, EffectOutput};
use crate::error::{Param, ParamError, positive, scaled};
use crate::real::Real;

/// Parameters of a fractional cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractionalSpec {
    /// Transition angular frequency ω_c in rad/s.
    pub omega_c: f64,
    /// Order α of the derivative, 0 < α <= 1 (1 is a Maxwell cell).
    pub alpha: f64,
    /// Load fraction g of the backbone (K^0 = (1 - g) K^∞ alone).
    pub g: f64,
}

impl FractionalSpec {
    /// A cell with transition ω_c (rad/s), order α and fraction g.
    pub const fn new(omega_c: f64, alpha: f64, g: f64) -> Self {
        Self { omega_c, alpha, g }
    }

    /// The same with the transition frequency `f_c` in Hz.
    pub fn hz(f_c: f64, alpha: f64, g: f64) -> Self {
        Self::new(core::f64::consts::TAU * f_c, alpha, g)
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive(Param::scalar("omega_c"), self.omega_c)?;
        let alpha = positive(Param::scalar("alpha"), self.alpha)?;
        if alpha > 1.0 {
            return Err(ParamError::OutOfRange {
                param: Param::scalar("alpha"),
                value: alpha,
                min: 0.0,
                min_open: true,
                max: 1.0,
            });
        }
        let g = positive(Param::scalar("g"), self.g)?;
        if g > 1.0 {
            return Err(ParamError::CellFractionAboveOne { cell: None, g });
        }
        Ok(())
    }

    /// Branch share of the complex stiffness over K^∞ (continuous model,
    /// eqs 1.20-1.21): `g (iω/ω_c)^α / (1 + (iω/ω_c)^α)`, as (storage,
    /// loss). Add g^0 to the storage for the whole bushing on a linear
    /// backbone.
    pub fn branch_modulus(&self, omega: f64) -> (f64, f64) {
        let r = libm::pow(omega / self.omega_c, self.alpha);
        let phi = 0.5 * core::f64::consts::PI * self.alpha;
        let (re, im) = (r * libm::cos(phi), r * libm::sin(phi));
        let den = 1.0 + 2.0 * re + r * r;
        (self.g * (re + r * r) / den, self.g * im / den)
    }
}

/// The truncated Grünwald fractional cell with `N` history taps.
///
/// - Equation: seed 000 eqs 1.18-1.21 (continuous), 1.23-1.25 (discrete),
///   in the force-rate frame of the module docs.
/// - States: the last N values of `f - g F^∞` in a ring buffer, its write
///   position and the branch force: N + 2 words.
/// - Stability: the weights A_{j+1}, j >= 1, are all negative and sum to
///   more than -1, so the recursion is a convex combination of past values
///   scaled by c/(1+c) < 1: bounded for every dt, ω_c and N.
/// - Accuracy: the scheme is first order in dt (it is the backward
///   difference raised to the power α: the phase of (iω)^α lags by
///   α ω dt / 2), and the truncation leaves a static leak: at DC the branch
///   keeps `c S_N / (1 + c S_N)` of g F^∞, with
///   `S_N = Σ_{j=0}^{N} A_{j+1} ≈ N^-α / Γ(1 - α)`, instead of relaxing
///   to zero ([`Grunwald::dc_leak`]). The model is therefore usable in a
///   band between 1/(N dt) and a fraction of the sampling rate; see
///   `docs/grunwald-accuracy.md` for the error against eq 1.21 in the band
///   [1/(N dt), 1/(10 dt)] Hz.
/// - Dissipation: reported as the work the branch absorbs less the change
///   of `f² / (2 g K^∞)`, trapezoidal. A fractional element stores energy
///   in its whole history, so this balance is exact over a closed steady
///   cycle (where it equals π K'' x_a²) but a single step may report a
///   small negative value.
/// - Cost: N multiply-adds per step (two contiguous dot products over the
///   ring buffer), no division; the dissipated energy adds one division by
///   K^∞ (dropped when not read). Memory: N weights and N + 2 state words.
///
/// ```
/// use bushing::{Bushing, FractionalSpec, Grunwald, ParamError, Polynomial};
///
/// // Corner 5 Hz, order 0.5, 20 % of the backbone; 64 taps at 1 kHz.
/// let cell = Grunwald::<f32, 64>::new(FractionalSpec::hz(5.0, 0.5, 0.2), 1e-3)?;
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (cell,))?;
/// let mut state = bushing.state_at(0.0);
/// let out = bushing.step(&mut state, 1.0);
/// assert!(out.force > 80.0 && out.force <= 100.0);
/// // The order must be in (0, 1).
/// assert!(Grunwald::<f32, 64>::new(FractionalSpec::hz(5.0, 1.5, 0.2), 1e-3).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Grunwald<T, const N: usize> {
    /// Weights in buffer order: `rev[k] = A_{N-k+1}` (tap j = N - k).
    rev: [T; N],
    gain: T,
    g: T,
    inv_g: T,
    c: f64,
    spec: FractionalSpec,
    dt: f64,
}

/// State of a [`Grunwald`] cell.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(bound(
        serialize = "T: serde::Serialize",
        deserialize = "T: serde::Deserialize<'de> + Copy + Default"
    ))
)]
pub struct GrunwaldState<T, const N: usize> {
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_array"))]
    history: [T; N],
    head: usize,
    force: T,
}

impl<T: Real, const N: usize> GrunwaldState<T, N> {
    /// Branch force after the last step.
    pub fn force(&self) -> T {
        self.force
    }
}

impl<T: Real, const N: usize> Grunwald<T, N> {
    /// Builds the cell for time step `dt` (s). Refuses N = 0, α outside
    /// (0, 1], a non-positive ω_c, g outside (0, 1] and a non-positive dt.
    pub fn new(spec: FractionalSpec, dt: f64) -> Result<Self, ParamError> {
        spec.validate()?;
        scaled::<T>(Param::scalar("g"), spec.g)?;
        let dt = positive(Param::scalar("dt"), dt)?;
        if N == 0 {
            return Err(ParamError::TooFew {
                param: Param::scalar("taps"),
                min: 1,
                got: 0,
            });
        }
        let c = libm::pow(spec.omega_c * dt, -spec.alpha);
        if !c.is_finite() {
            return Err(ParamError::NotFinite {
                param: Param::scalar("omega_c dt"),
            });
        }
        let mut rev = [T::ZERO; N];
        for (slot, a) in rev.iter_mut().rev().zip(weights(spec.alpha)) {
            *slot = T::from_f64(a);
        }
        Ok(Self {
            rev,
            gain: T::from_f64(c / (1.0 + c)),
            g: T::from_f64(spec.g),
            inv_g: T::from_f64(1.0 / spec.g),
            c,
            spec,
            dt,
        })
    }

    /// The parameters.
    pub fn spec(&self) -> FractionalSpec {
        self.spec
    }

    /// `c = (ω_c dt)^-α`.
    pub fn c(&self) -> f64 {
        self.c
    }

    /// Share of g F^∞ the truncated branch keeps at DC,
    /// `c S_N / (1 + c S_N)` (zero for the continuous model).
    pub fn dc_leak(&self) -> f64 {
        let s: f64 = 1.0 + self.rev.iter().map(|w| w.to_f64()).sum::<f64>();
        let cs = self.c * s;
        cs / (1.0 + cs)
    }

    /// Branch share of the complex stiffness over K^∞ of the discrete model
    /// at ω (rad/s), as (storage, loss): its exact steady-state response
    /// ([`discrete_branch_response`]) with the weights as stored in `T`.
    pub fn branch_response(&self, omega: f64) -> (f64, f64) {
        let taps = self.rev.iter().rev().map(|w| w.to_f64());
        discrete_branch_response(self.spec.g, self.c, taps, omega * self.dt)
    }
}

/// The Grünwald weights A_2, A_3, ... of eq 1.23 for order `alpha`, by the
/// recursion `A_{j+1} = A_j (j - 1 - α) / j` from A_1 = 1.
pub fn weights(alpha: f64) -> impl Iterator<Item = f64> + Clone {
    (1u32..).scan(1.0f64, move |a, j| {
        *a *= (f64::from(j) - 1.0 - alpha) / f64::from(j);
        Some(*a)
    })
}

/// Steady-state branch response over K^∞ of a Grünwald cell, as (storage,
/// loss): `g c S(z) / (1 + c S(z))` at `z = e^{iθ}`, θ = ω dt, with
/// `S(z) = 1 + Σ_j A_{j+1} z^-j` over the given taps A_2, A_3, ...
/// (f64, libm trig; for reports and tests).
pub fn discrete_branch_response(
    g: f64,
    c: f64,
    taps: impl Iterator<Item = f64>,
    theta: f64,
) -> (f64, f64) {
    let (mut re, mut im) = (1.0f64, 0.0f64);
    for (j, w) in (1u32..).zip(taps) {
        let phase = f64::from(j) * theta;
        re += w * libm::cos(phase);
        im -= w * libm::sin(phase);
    }
    let (re, im) = (c * re, c * im);
    // cS / (1 + cS) = cS (1 + conj(cS)) / |1 + cS|².
    let den = (1.0 + re) * (1.0 + re) + im * im;
    (g * (re + re * re + im * im) / den, g * im / den)
}

impl<T: Real, const N: usize> Effect<T> for Grunwald<T, N> {
    type State = GrunwaldState<T, N>;
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.spec.g
    }
    fn dt(&self) -> Option<f64> {
        Some(self.dt)
    }
    fn rest(&self, _: T) -> Self::State {
        GrunwaldState {
            history: [T::ZERO; N],
            head: 0,
            force: T::ZERO,
        }
    }
    #[inline]
    fn step(&self, st: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        // history[head] holds u_{n-N}, history[head-1] u_{n-1}: the newer
        // part [..head] meets the tail of the weights, the older [head..]
        // their head.
        let head = st.head.min(N);
        let (newer, older) = st.history.split_at(head);
        let (w_older, w_newer) = self.rev.split_at(N - head);
        let mut sum = T::ZERO;
        for (w, u) in w_older.iter().zip(older) {
            sum += *w * *u;
        }
        for (w, u) in w_newer.iter().zip(newer) {
            sum += *w * *u;
        }
        let y = self.g * drive.f_inf;
        let force = self.gain * (y - sum);
        let u_new = force - y;
        let u_old = st.force - self.g * (drive.f_inf - drive.df_inf);
        if let Some(slot) = st.history.get_mut(head) {
            *slot = u_new;
        }
        st.head = if head + 1 >= N { 0 } else { head + 1 };
        let f_old = st.force;
        st.force = force;
        EffectOutput {
            force,
            tangent: self.gain * self.g * drive.k_inf,
            // Work in, less the change of f²/(2 g K^∞):
            // (f_old + f_new)(g ΔF^∞ - Δf) / (2 g K^∞) = -(f_old + f_new) Δu / (2 g K^∞).
            dissipated: -T::HALF * (f_old + force) * (u_new - u_old) * self.inv_g / drive.k_inf,
        }
    }
    #[inline(always)]
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }

    /// A step writes one slot of the ring, the head and the force: only
    /// those are kept for a refusal (the ring is N words).
    #[inline]
    fn step_if(
        &self,
        st: &mut Self::State,
        drive: &Drive<T>,
        accept: impl FnOnce(&EffectOutput<T>) -> bool,
    ) -> Option<EffectOutput<T>> {
        let (head, force) = (st.head, st.force);
        let slot = st.history.get(head.min(N)).copied();
        let report = self.step(st, drive);
        if accept(&report) {
            return Some(report);
        }
        if let (Some(p), Some(u)) = (st.history.get_mut(head.min(N)), slot) {
            *p = u;
        }
        (st.head, st.force) = (head, force);
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backbone::Polynomial;
    use crate::bushing::Bushing;
    use core::f64::consts::{PI, TAU};

    const K: f64 = 100.0;

    fn bushing<const N: usize>(
        spec: FractionalSpec,
        dt: f64,
    ) -> Bushing<f64, Polynomial<f64, 2>, (Grunwald<f64, N>,)> {
        Bushing::new(
            Polynomial::linear(K).unwrap(),
            (Grunwald::new(spec, dt).unwrap(),),
        )
        .unwrap()
    }

    #[test]
    fn weights_follow_the_recursion_and_the_gamma_ratio() {
        let cell = Grunwald::<f64, 5>::new(FractionalSpec::new(1.0, 0.3, 0.5), 1e-3).unwrap();
        // rev[k] = A_{N-k+1}: A_2 = -α, A_3 = -α(1-α)/2, ...
        assert!((cell.rev[4] + 0.3).abs() < 1e-15);
        assert!((cell.rev[3] + 0.3 * 0.7 / 2.0).abs() < 1e-15);
        assert!((cell.rev[2] + 0.3 * 0.7 * 1.7 / 6.0).abs() < 1e-15);
        assert!(cell.rev.iter().all(|&w| w < 0.0));
        // S_N of the reference table: 0.1933 for α = 0.3, N = 100.
        let c = Grunwald::<f64, 100>::new(FractionalSpec::new(1.0, 0.3, 0.5), 1e-3).unwrap();
        let s: f64 = 1.0 + c.rev.iter().sum::<f64>();
        assert!((s - 0.1933).abs() < 5e-5, "{s}");
    }

    #[test]
    fn alpha_one_is_a_backward_euler_maxwell_cell() {
        // N = 1, α = 1: f_n (1 + c) = c g F_n - c (-1)(f_{n-1} - g F_{n-1})
        // → f_n = f_{n-1}/(1 + h) + (g ΔF) / (1 + h), h = ω dt.
        let (omega, dt, g) = (20.0, 1e-3, 0.3);
        let b = bushing::<1>(FractionalSpec::new(omega, 1.0, g), dt);
        let mut s = b.state_at(0.0);
        let (mut f, mut x_old) = (0.0f64, 0.0f64);
        let h = omega * dt;
        for n in 1..200 {
            let x = (0.05 * n as f64).sin();
            let out = b.step(&mut s, x);
            f = (f + g * K * (x - x_old)) / (1.0 + h);
            x_old = x;
            let branch = out.effects.unwrap().0.force;
            assert!((branch - f).abs() < 1e-12, "step {n}: {branch} vs {f}");
        }
    }

    #[test]
    fn steady_sine_matches_the_discrete_response_and_cycle_energy_the_loss() {
        let spec = FractionalSpec::hz(2.0, 0.5, 0.6);
        let dt = 1e-3;
        let b = bushing::<512>(spec, dt);
        let cell = &b.effects().0;
        let f_hz = 5.0;
        let omega = TAU * f_hz;
        let per = 200; // samples per period
        let mut s = b.state_at(0.0);
        let (mut a_sin, mut a_cos, mut energy) = (0.0, 0.0, 0.0);
        let cycles = 12; // > N dt of memory settles
        for n in 1..=cycles * per {
            let t = n as f64 * dt;
            let out = b.step(&mut s, (omega * t).sin());
            if n > (cycles - 1) * per {
                let f = out.effects.unwrap().0.force;
                a_sin += 2.0 * f * (omega * t).sin() / per as f64;
                a_cos += 2.0 * f * (omega * t).cos() / per as f64;
                energy += out.dissipated;
            }
        }
        let (re, im) = cell.branch_response(omega);
        assert!((a_sin / K - re).abs() < 1e-3 * re, "{} vs {re}", a_sin / K);
        assert!((a_cos / K - im).abs() < 1e-3 * im, "{} vs {im}", a_cos / K);
        // Energy per cycle: π K'' x_a² (x_a = 1).
        assert!((energy / (PI * K * im) - 1.0).abs() < 2e-3, "{energy}");
    }

    #[test]
    fn discrete_response_approaches_eq_1_21_in_the_band() {
        // Mid-band (two decades above 1/(N dt), two below the sampling
        // rate): within 2 % of the continuous moduli.
        let spec = FractionalSpec::hz(1.0, 0.5, 0.6);
        let cell = Grunwald::<f64, 4096>::new(spec, 1e-3).unwrap();
        let omega = TAU * 1.0;
        let (re, im) = cell.branch_response(omega);
        let (re0, im0) = spec.branch_modulus(omega);
        let (storage, storage0) = (0.4 + re, 0.4 + re0);
        assert!(
            (storage / storage0 - 1.0).abs() < 0.02,
            "{storage} {storage0}"
        );
        assert!((im / im0 - 1.0).abs() < 0.02, "{im} {im0}");
        // The static leak: S_N ≈ N^-α / Γ(1 - α), Γ(1/2) = √π; with
        // ω_c N dt = 25.7 the branch keeps 15 % of g F^∞ at DC.
        let cs = cell.c() / (4096.0f64.sqrt() * PI.sqrt());
        let leak = cs / (1.0 + cs);
        assert!(
            (cell.dc_leak() / leak - 1.0).abs() < 1e-3,
            "{}",
            cell.dc_leak()
        );
    }

    #[test]
    fn bounded_for_any_step_and_order() {
        for alpha in [0.05, 0.5, 0.95, 1.0] {
            for dt in [1e-6, 1e-3, 10.0] {
                let b = bushing::<16>(FractionalSpec::new(10.0, alpha, 0.9), dt);
                let mut s = b.state_at(0.0);
                for n in 0..400 {
                    let x = if n % 7 < 3 { 1.0 } else { -1.0 };
                    let out = b.step(&mut s, x);
                    let f = out.effects.unwrap().0.force;
                    assert!(f.is_finite() && f.abs() <= 2.0 * 0.9 * K * (1.0 + 1e-12));
                }
            }
        }
    }

    #[test]
    fn parameter_errors() {
        let e = Grunwald::<f64, 4>::new(FractionalSpec::new(1.0, 1.5, 0.5), 1e-3).unwrap_err();
        assert!(matches!(e, ParamError::OutOfRange { param, .. } if param.name == "alpha"));
        let e = Grunwald::<f64, 4>::new(FractionalSpec::new(1.0, 0.0, 0.5), 1e-3).unwrap_err();
        assert!(matches!(e, ParamError::NotPositive { param, .. } if param.name == "alpha"));
        let e = Grunwald::<f64, 4>::new(FractionalSpec::new(-1.0, 0.5, 0.5), 1e-3).unwrap_err();
        assert!(matches!(e, ParamError::NotPositive { param, .. } if param.name == "omega_c"));
        let e = Grunwald::<f64, 4>::new(FractionalSpec::new(1.0, 0.5, 1.5), 1e-3).unwrap_err();
        assert_eq!(e, ParamError::CellFractionAboveOne { cell: None, g: 1.5 });
        let e = Grunwald::<f64, 0>::new(FractionalSpec::new(1.0, 0.5, 0.5), 1e-3).unwrap_err();
        assert!(matches!(e, ParamError::TooFew { .. }));
        let e = Grunwald::<f64, 4>::new(FractionalSpec::new(1.0, 0.5, 0.5), 0.0).unwrap_err();
        assert!(matches!(e, ParamError::NotPositive { param, .. } if param.name == "dt"));
    }
}
