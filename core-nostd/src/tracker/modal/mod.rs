//! The modal Kalman tracker of seed 004 chapter 3.
//!
//! Each mode m carries a phase step and a log-decay per sample,
//! `θ_m = ω_m dt` and `λ_m = σ_m dt`, shared by all sensors (formulation B,
//! eqs 3.43-3.45), and one analytic-signal pair `(a, b)` per sensor: the
//! sensor's displacement divided by a scale fixed at construction, so that
//! every state is of order one in `f32`. The process is the exact
//! discretisation of `ż = (σ + iω) z` (eqs 3.27-3.28):
//!
//! ```text
//! a' = e^λ (cos θ a - sin θ b),   b' = e^λ (sin θ a + cos θ b),   θ' = θ,   λ' = λ
//! ```
//!
//! and a sensor sees the sum over modes of `Re[(λ + iθ)^k (a + ib)]`: k = 0
//! displacement (eq 3.26), k = 1 velocity (eq 3.33, `λ a - θ b`), k = 2
//! acceleration (eq 3.32, `(λ² - θ²) a - 2 λ θ b`), in units of the sensor
//! times dt^k over its scale. The reported natural frequency and damping
//! ratio are the closed form of eq 3.7 for this model: `ω_0 = √(ω² + σ²)`,
//! `ξ = -σ / ω_0`.
//!
//! - **Filters**: an extended Kalman filter (Jacobians of the process and of
//!   eqs 3.26/3.32/3.33) or an unscented one (scaled unscented transform,
//!   [`UtParams`]). Both apply the sensors one by one (diagonal R, eq 3.8).
//!   With the gain K zeroed on the frozen rows (frozen parameters), the
//!   Joseph form for a scalar observation, `P - K Pxzᵀ - Pxz Kᵀ + Pzz K Kᵀ`,
//!   is exactly the rank-one update `P - (v vᵀ - v_F v_Fᵀ)/Pzz` (v = Pxz,
//!   v_F its frozen entries), which is what is computed: below 8 states on
//!   one triangle, mirrored; from 8 on as whole rows of `P - w wᵀ` with
//!   `w = v/√Pzz`, the same product on both sides of the diagonal.
//! - **Structure**: F is the identity on the θ and λ rows and a scaled
//!   rotation plus two columns on each pair's rows, so the EKF prediction
//!   transforms only the pair rows and then their columns on one triangle
//!   (from 8 states on by mode blocks, with no index computed).
//!   The UKF factors P with θ and λ first: the sigma points of the amplitude
//!   columns then share the centre's θ and λ, move linearly under the
//!   process and the sensors, and add exactly `R S Rᵀ` (S the amplitude
//!   covariance given θ and λ) to the predicted covariance, `H S Hᵀ` to Pzz
//!   and `S Hᵀ` to Pxz; only the 4 modes sigma points of the θ and λ
//!   columns are propagated one by one. This is the scaled transform for
//!   that square root of P, not an approximation (tested against all
//!   2n + 1 points). From 8 states on the prediction eliminates only the θ
//!   and λ pivots (their columns and S), takes the sigma points'
//!   deviations from the propagated centre, and factors S once per step to
//!   check that P is positive definite; a sensor's innovation takes only
//!   the θ and λ columns of the factor (left-looking) and `S Hᵀ = P Hᵀ -
//!   Σ_t l_t (l_t · H)`, as whole rows.
//! - **Safety**: θ kept in (0, θ_max] below Nyquist and λ in a band given by
//!   the largest damping ratio; covariance diagonal floored; an innovation
//!   gate (outliers skipped, a run of them re-acquires); a mode whose
//!   amplitude sinks below `fade_snr` times the noise is *faded*: its ω and
//!   σ are frozen and its amplitudes kept loose until it comes back above
//!   twice that, when ω and σ get their start uncertainty again (they may
//!   have moved while the mode was gone) and are tracked again. A step
//!   that would leave a non-finite state (or meets, in the UKF, a pivot of
//!   the covariance's factorisation, or an innovation variance, that is not
//!   a positive normal number below [`Real::GUARD`]) is undone and the
//!   covariance reset to its start
//!   value. That value, the process noise and the sensor noise variances
//!   are checked below [`Real::GUARD`] in the working type at construction
//!   (a tuning beyond is a typed error), so the reset restores a finite
//!   covariance a step can use, and the state stays finite whatever the
//!   samples.
//! - **States**: `N = modes (2 sensors + 2)` values and an N×N covariance.
//! - **Cost** per sample, n = N states, M modes, C sensors: EKF about 6n²
//!   (prediction) + C (n² + 4Mn) multiply-adds and one division (from 8
//!   states, one `1/√`) per sensor; UKF per prediction the 2M θ and λ
//!   pivots eliminated (2M n² multiply-adds as whole rows), S factored
//!   (a³/6 for a = n - 2M amplitudes, a Newton `1/√d` each), `R S Rᵀ`
//!   (about 6 a n) and the sigma points' products on one triangle
//!   ((4M + 1) n²/2), and per sensor the 2M θ and λ columns of the factor
//!   (below 8 states the whole factorisation), 4M observations, `S Hᵀ`
//!   ((2M + 2) n) and the rank-one update. The rotation `e^λ (cos θ, sin θ)` is
//!   taken in `f32` from a per-mode anchor when (θ, λ) is within 2^-10 of
//!   it (a second-order series, [`ModalState`] keeps the anchor) and the
//!   sigma points' from the centre's by a fourth-order series; the sin/cos
//!   polynomial and `e^λ` run only when an anchor moves. Below 8 states
//!   (one mode) the whole step is unrolled, at 4 states on a copy of the
//!   state held in registers; from 8 on, a mode count given as the type
//!   parameter `M` ([`ModalTracker`]) makes every loop count a constant
//!   too. No f64, no libm trig and no square root per sample.
//!   Guest instructions per call of `step` through a non-inlined function
//!   on Cortex-M4F, worst of three inputs (QEMU, f32; `cargo run -q -p
//!   bushing-boards --release --target thumbv7em-none-eabihf --bin
//!   kernel-cost`, family `tracker`): one mode and one accelerometer
//!   (4 states) EKF 426, UKF 1 085; two modes and three accelerometers
//!   (16 states) with `M = 2` EKF 9 488, UKF 26 315, and with the mode
//!   count given at run time EKF 14 166, UKF 37 628. Estimated cycles in
//!   `docs/accuracy-cost.md`.

// The parts: the public inputs and outputs (`types`), construction
// (`construct`), the two filters (`ekf`, `ukf`), the rotation of the
// pairs (`rotation`), the bands, fading and checks (`safety`) and the
// fixed-size matrix helpers (`matrix`). The step, the scalar update and
// the state layout are here.
mod construct;
mod ekf;
mod matrix;
mod rotation;
mod safety;
mod types;
mod ukf;

pub use types::{
    Filter, Measured, ModalReport, ModeInit, ModeStatus, SensorSpec, Tuning, UtParams,
};

use crate::real::Real;

use crate::tracker::fast::{min_positive, rsqrt};
use construct::powk;
use matrix::{add_diag, entry, get, opaque_zero, put, set};
use rotation::{anchor_at, rotate};
use safety::{all_finite, cold};

/// Running state: estimate, covariance and counters.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalState<T, const N: usize> {
    core: Core<T, N>,
    /// Per mode, a cached rotation `[θa, λa, e^λa cos θa, e^λa sin θa]`
    /// (see `rotation_near`).
    anchor: [[T; 4]; N],
    /// Samples gated out since the start.
    pub outliers: u32,
    /// Covariance resets since the start.
    pub repairs: u32,
    /// Re-acquisitions since the start.
    pub reacquisitions: u32,
}

/// What a step works on and an undo restores: estimate, covariance,
/// faded flags, outlier run.
#[derive(Debug, Clone, PartialEq)]
struct Core<T, const N: usize> {
    x: [T; N],
    p: [[T; N]; N],
    faded: [bool; N],
    run: u32,
}

impl<T: Real, const N: usize> ModalState<T, N> {
    /// The state vector (per mode: θ, λ, then a, b per sensor).
    pub fn x(&self) -> &[T; N] {
        &self.core.x
    }
    /// The covariance.
    pub fn covariance(&self) -> &[[T; N]; N] {
        &self.core.p
    }
}

/// The tracker's parameters (see the module docs): `N` states and, with
/// `M` > 0, `M` modes fixed at compile time.
///
/// `M = 0` (the default) takes the number of modes from
/// [`ModalTracker::new`] at run time. A firmware whose mode count is known
/// should name it: from 8 states on (two modes or more), every per-sample
/// loop then has a constant trip count that the optimiser unrolls, and
/// the step is the same arithmetic in fewer instructions (the two-mode
/// trackers of `docs/accuracy-cost.md` are measured both ways; about half
/// the EKF's instructions at 8 states). `new` refuses a mode count other
/// than a non-zero `M`. Below 8 states there is one mode either way.
///
/// ```
/// use bushing::ParamError;
/// use bushing::tracker::{Filter, Measured, ModalTracker, ModeInit, SensorSpec, Tuning};
///
/// // One mode on one displacement sensor (4 states), started 4 % off.
/// let tracker = ModalTracker::<f32, 4>::new(
///     1e-3,
///     &[SensorSpec { measured: Measured::Displacement, noise: 1e-3 }],
///     &[ModeInit { frequency: 11.5, damping: 0.0 }],
///     &[(0.0, -1.0)],
///     &Tuning { initial_frequency_error: 0.05, ..Tuning::default() },
///     Filter::Ekf,
/// )?;
/// let mut state = tracker.start();
/// // A free decay at 12 Hz and 2 % damping.
/// let (f, zeta) = (12.0, 0.02);
/// let w = core::f64::consts::TAU * f;
/// for n in 0..2000 {
///     let t = n as f64 * 1e-3;
///     let x = (-zeta * w * t).exp() * (w * (1.0 - zeta * zeta).sqrt() * t).sin();
///     tracker.step(&mut state, &[x as f32]);
/// }
/// let mode = tracker.mode(&state, 0);
/// assert!((mode.frequency - 12.0).abs() < 0.05 && (mode.damping - 0.02).abs() < 0.005);
/// // A non-finite sample is refused for its sensor only.
/// assert!(tracker.step(&mut state, &[f32::NAN]).refused);
/// // N must match the modes and sensors: one mode on two sensors is 6 states.
/// let r = ModalTracker::<f32, 4>::new(
///     1e-3,
///     &[SensorSpec { measured: Measured::Displacement, noise: 1e-3 }; 2],
///     &[ModeInit { frequency: 12.0, damping: 0.0 }],
///     &[(0.0, -1.0), (0.0, -1.0)],
///     &Tuning::default(),
///     Filter::Ekf,
/// );
/// assert!(r.is_err());
///
/// // Two modes on one sensor (8 states), the mode count fixed at compile
/// // time: the same numbers as `ModalTracker::<f32, 8>`, in fewer
/// // instructions.
/// let modes = [ModeInit { frequency: 12.0, damping: 0.0 }, ModeInit { frequency: 31.0, damping: 0.0 }];
/// let sensor = [SensorSpec { measured: Measured::Displacement, noise: 1e-3 }];
/// let (amplitudes, tuning) = ([(0.0, -1.0), (0.0, -0.3)], Tuning::default());
/// let two = ModalTracker::<f32, 8, 2>::new(1e-3, &sensor, &modes, &amplitudes, &tuning, Filter::Ekf)?;
/// let free = ModalTracker::<f32, 8>::new(1e-3, &sensor, &modes, &amplitudes, &tuning, Filter::Ekf)?;
/// let (mut a, mut b) = (two.start(), free.start());
/// for n in 0..500 {
///     let t = n as f64 * 1e-3;
///     let x = (w * t).sin() + 0.3 * (core::f64::consts::TAU * 31.0 * t).sin();
///     assert_eq!(two.step(&mut a, &[x as f32]), free.step(&mut b, &[x as f32]));
/// }
/// assert_eq!(a.x(), b.x());
/// // A mode count other than M is refused.
/// let one = ModalTracker::<f32, 8, 2>::new(1e-3, &sensor, &modes[..1], &amplitudes, &tuning, Filter::Ekf);
/// assert!(matches!(one, Err(ParamError::LengthMismatch { expected: 2, got: 1, .. })));
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ModalTracker<T, const N: usize, const M: usize = 0> {
    modes: usize,
    sensors: usize,
    dt: f64,
    filter: Filter,
    measured: [Measured; N],
    /// Per sensor: dt^k / scale, from a sample to the scaled state units.
    meas_gain: [T; N],
    /// Per sensor: the displacement scale (sensor units times s^k).
    scale: [T; N],
    r: [T; N],
    q_theta: T,
    q_lambda: [T; N],
    q_amp: T,
    p0: [T; N],
    floor: [T; N],
    x0: [T; N],
    theta_max: T,
    theta_min: T,
    lambda_min: T,
    lambda_max: T,
    /// Centre and half-width of the θ band, and half-width of the λ band
    /// (centred on 0), shrunk by a few ulps: inside them no clamp is needed.
    theta_mid: T,
    theta_half: T,
    lambda_half: T,
    gate2: T,
    outlier_run: u32,
    /// Per sensor: `fade_snr² r`, below which a mode fades, and four times
    /// that, above which it is back.
    fade_below: [T; N],
    fade_above: [T; N],
    ut: Weights<T>,
    /// Elimination order of the UKF's factorisation: θ and λ of every mode,
    /// then the amplitudes.
    pivots: [usize; N],
    /// True for the amplitude states.
    amplitude: [bool; N],
}

/// Scaled-UT constants in the working type, the 2(n - 2 modes) sigma points
/// of the amplitude columns folded into the centre weights (see
/// `predict_ukf`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Weights<T> {
    /// √(n + λ).
    spread: T,
    /// W_i.
    wi: T,
    /// W_i √(n + λ).
    wi_spread: T,
    /// W_0^m + 2 W_i (n - 2 modes).
    centre_mean: T,
    /// W_0^c + 2 W_i (n - 2 modes).
    centre_cov: T,
    /// From 8 states on, the shift c that turns the sigma points'
    /// deviations D into `D - c δ` (see `construct::deviation_shift`).
    shift: T,
}

impl<T: Real, const N: usize, const M: usize> ModalTracker<T, N, M> {
    /// Number of modes.
    pub fn modes(&self) -> usize {
        self.modes
    }
    /// Number of sensors.
    pub fn sensors(&self) -> usize {
        self.sensors
    }
    /// Time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Number of modes for the per-sample code: a mode takes at least four
    /// states, so below eight there is one, known at compile time, as it is
    /// for a non-zero `M`.
    #[inline(always)]
    fn m_n(&self) -> usize {
        if N < 8 {
            1
        } else if M > 0 {
            M
        } else {
            self.modes
        }
    }

    /// Number of sensors for the per-sample code: with one mode, `(N - 2)/2`;
    /// with `M` modes, `(N/M - 2)/2`.
    #[inline(always)]
    fn c_n(&self) -> usize {
        if N < 8 {
            N.saturating_sub(2) / 2
        } else if let Some(per_mode) = N.checked_div(M) {
            per_mode.saturating_sub(2) / 2
        } else {
            self.sensors
        }
    }

    /// State index of the t-th pivot of the UKF's factorisation.
    #[inline(always)]
    fn pivot(&self, t: usize) -> usize {
        if N < 8 {
            t
        } else if M > 0 {
            // θ and λ of every mode, then each mode's amplitudes in turn.
            let block = self.block();
            match t.checked_sub(2 * M) {
                None => (t / 2) * block + t % 2,
                Some(k) => {
                    let per = block - 2;
                    let (Some(m), Some(i)) = (k.checked_div(per), k.checked_rem(per)) else {
                        return 0;
                    };
                    m * block + 2 + i
                }
            }
        } else {
            self.pivots.get(t).copied().unwrap_or(0)
        }
    }

    /// True for an amplitude state.
    #[inline(always)]
    fn is_amplitude(&self, i: usize) -> bool {
        if N < 8 {
            i >= 2
        } else {
            self.amplitude.get(i).copied().unwrap_or(false)
        }
    }

    /// The start state: the initial estimate and its diagonal covariance.
    pub fn start(&self) -> ModalState<T, N> {
        let mut anchor = [[T::ZERO; 4]; N];
        for (m, a) in anchor.iter_mut().enumerate().take(self.m_n()) {
            let (ti, li) = self.theta_lambda(m);
            *a = anchor_at(get(&self.x0, ti), get(&self.x0, li));
        }
        ModalState {
            core: Core {
                x: self.x0,
                p: self.start_covariance(),
                faded: [false; N],
                run: 0,
            },
            anchor,
            outliers: 0,
            repairs: 0,
            reacquisitions: 0,
        }
    }

    fn start_covariance(&self) -> [[T; N]; N] {
        let mut p = [[T::ZERO; N]; N];
        for (i, row) in p.iter_mut().enumerate() {
            put(row, i, get(&self.p0, i));
        }
        p
    }

    #[inline(always)]
    fn theta_lambda(&self, m: usize) -> (usize, usize) {
        let base = m * (2 * self.c_n() + 2);
        (base, base + 1)
    }

    #[inline(always)]
    fn pair(&self, m: usize, c: usize) -> (usize, usize) {
        let base = m * (2 * self.c_n() + 2) + 2 + 2 * c;
        (base, base + 1)
    }

    /// Frequency, damping and frozen flag of mode `m` (eq 3.7 closed form).
    pub fn mode(&self, state: &ModalState<T, N>, m: usize) -> ModeStatus<T> {
        let (ti, li) = self.theta_lambda(m);
        let (theta, lambda) = (get(&state.core.x, ti), get(&state.core.x, li));
        let inv_dt = T::from_f64(1.0 / self.dt);
        let w0dt = (theta * theta + lambda * lambda).sqrt();
        ModeStatus {
            frequency: w0dt * inv_dt * T::from_f64(1.0 / core::f64::consts::TAU),
            damping: if w0dt > T::ZERO {
                -lambda / w0dt
            } else {
                T::ZERO
            },
            omega: theta * inv_dt,
            sigma: lambda * inv_dt,
            faded: state.core.faded.get(m).copied().unwrap_or(false),
        }
    }

    /// Complex amplitude `(re, im)` of mode `m` in the displacement at
    /// sensor `c` (for velocity and acceleration sensors, the displacement
    /// whose derivative they measure), sensor units times s^k.
    pub fn displacement(&self, state: &ModalState<T, N>, m: usize, c: usize) -> (T, T) {
        let (ai, bi) = self.pair(m, c);
        let s = get(&self.scale, c) * T::from_f64(1.0 / powk(self.dt, self.measured_order(c)));
        (get(&state.core.x, ai) * s, get(&state.core.x, bi) * s)
    }

    fn measured_order(&self, c: usize) -> i32 {
        self.measured.get(c).copied().unwrap_or_default().order()
    }

    /// Rotates mode `m`'s analytic-signal pairs by `(ec, es)` (eq 3.28).
    #[inline(always)]
    fn rotate_mode(&self, x: &mut [T; N], m: usize, (ec, es): (T, T)) {
        for k in 0..self.c_n() {
            let (ai, bi) = self.pair(m, k);
            let (a, b) = (get(x, ai), get(x, bi));
            let (a, b) = rotate((ec, es), a, b);
            put(x, ai, a);
            put(x, bi, b);
        }
    }

    /// States per mode from 8 states on: θ, λ and a pair per sensor; at
    /// least 2 (provably, so that no chunking can panic).
    #[inline(always)]
    fn block(&self) -> usize {
        (2 * self.c_n() + 2).max(2)
    }

    /// From 8 states on: each mode's rotation (from its anchor, see
    /// [`rotation::rotation_cached`]), and every pair of `x` turned by its
    /// mode's, mode block by mode block.
    #[inline(always)]
    fn rotate_blocks(&self, x: &mut [T; N], anchor: &mut [[T; 4]; N]) -> [(T, T); N] {
        // Written and read for the modes only; zeroed by stores inline.
        let zero = opaque_zero::<T>();
        let mut rot = [(zero, zero); N];
        for ((r, a), xm) in rot
            .iter_mut()
            .zip(anchor.iter_mut())
            .zip(x.chunks_exact_mut(self.block()))
        {
            let Some(([t, l], pairs)) = xm.split_first_chunk_mut::<2>() else {
                continue;
            };
            *r = rotation::rotation_cached(a, *t, *l);
            for pair in pairs.chunks_exact_mut(2) {
                if let [a, b] = pair {
                    (*a, *b) = rotate(*r, *a, *b);
                }
            }
        }
        rot
    }

    /// `(α, β)` such that sensor `c` reads `α a + β b` of a pair whose mode
    /// has phase step `t` and log-decay `l`: the real part of `(l + i t)^k`
    /// times `a + i b`.
    #[inline(always)]
    fn coefficients(&self, c: usize, t: T, l: T) -> (T, T) {
        match self.measured.get(c).copied().unwrap_or_default() {
            Measured::Displacement => (T::ONE, T::ZERO),
            Measured::Velocity => (l, -t),
            Measured::Acceleration => (l * l - t * t, -(T::ONE + T::ONE) * l * t),
        }
    }

    /// One sample per sensor, in sensor units (`samples[c]`): predict, then
    /// update sensor by sensor. A non-finite sample is refused for that
    /// sensor only.
    pub fn step(&self, state: &mut ModalState<T, N>, samples: &[T]) -> ModalReport {
        match self.filter {
            Filter::Ekf => self.step_as::<false>(state, samples),
            Filter::Ukf(_) => self.step_as::<true>(state, samples),
        }
    }

    /// The step of one filter, with the undo: a step that fails leaves the
    /// estimate, the flags and the outlier run as they were and the
    /// covariance at its start value.
    #[inline(always)]
    fn step_as<const UKF: bool>(&self, state: &mut ModalState<T, N>, samples: &[T]) -> ModalReport {
        let ModalState {
            core,
            anchor,
            outliers,
            reacquisitions,
            ..
        } = state;
        let (mut report, ok) = if N <= 4 {
            // One mode on one sensor: the step runs on a copy that the
            // optimiser keeps in registers, and the copy is the undo. From
            // 6 states on the copy goes through memory (a copy each way,
            // a fifth of the 6-state EKF's step), so the estimate alone is
            // saved.
            let mut work = core.clone();
            let (report, ok) =
                self.run::<UKF>(&mut work, anchor, outliers, reacquisitions, samples);
            if ok {
                *core = work;
            }
            (report, ok)
        } else {
            // The covariance is reset on undo, so not saved.
            let (x, faded, run) = (core.x, core.faded, core.run);
            let (report, ok) = self.run::<UKF>(core, anchor, outliers, reacquisitions, samples);
            if !ok {
                core.x = x;
                core.faded = faded;
                core.run = run;
            }
            (report, ok)
        };
        if !ok {
            self.reset(state, &mut report);
        }
        report
    }

    /// Counts a repair and resets the covariance.
    #[cold]
    fn reset(&self, state: &mut ModalState<T, N>, report: &mut ModalReport) {
        state.repairs = state.repairs.saturating_add(1);
        state.core.p = self.start_covariance();
        report.repaired = true;
    }

    /// Predict and update; false when the step must be undone (covariance
    /// not positive definite, innovation variance not positive, or a
    /// non-finite result).
    #[inline(always)]
    fn run<const UKF: bool>(
        &self,
        state: &mut Core<T, N>,
        anchor: &mut [[T; 4]; N],
        outliers: &mut u32,
        reacquisitions: &mut u32,
        samples: &[T],
    ) -> (ModalReport, bool) {
        let mut report = ModalReport::default();
        // Unused (and optimised away) by the EKF.
        let mut scratch = ukf::Scratch::new();
        if UKF {
            if !self.predict_ukf(state, anchor, &mut scratch) {
                return (report, false);
            }
        } else {
            self.predict_ekf(state, anchor);
        }
        // Every innovation writes the whole of v before the update reads it.
        let mut v = [T::ZERO; N];
        for c in 0..self.c_n() {
            let z = samples.get(c).copied().unwrap_or(T::ZERO);
            if !z.is_finite() {
                cold();
                report.refused = true;
                continue;
            }
            let z = z * get(&self.meas_gain, c);
            let Some((zhat, s)) = self.innovation::<UKF>(state, c, &mut v, &mut scratch) else {
                return (report, false);
            };
            let y = z - zhat;
            if y * y > self.gate2 * s {
                cold();
                if state.run.saturating_add(1) < self.outlier_run {
                    state.run = state.run.saturating_add(1);
                    *outliers = outliers.saturating_add(1);
                    report.gated += 1;
                    continue;
                }
                // A run of outliers: the model lost the signal. Loosen the
                // amplitudes and take the sample.
                self.loosen_amplitudes(state, None);
                *reacquisitions = reacquisitions.saturating_add(1);
                report.reacquired = true;
                state.run = 0;
                let Some((zhat, s)) = self.innovation::<UKF>(state, c, &mut v, &mut scratch) else {
                    return (report, false);
                };
                self.update(state, &v, s, z - zhat);
            } else {
                state.run = 0;
                self.update(state, &v, s, y);
            }
            report.accepted += 1;
        }
        self.constrain(state);
        self.fade(state);
        let ok = all_finite(state);
        (report, ok)
    }

    /// Predicted sample of sensor `c`, cross-covariance into `v` and
    /// innovation variance; `None` when the covariance is not usable.
    #[inline(always)]
    fn innovation<const UKF: bool>(
        &self,
        state: &Core<T, N>,
        c: usize,
        v: &mut [T; N],
        scratch: &mut ukf::Scratch<T, N>,
    ) -> Option<(T, T)> {
        let (zhat, s) = if UKF {
            self.innovation_ukf(state, c, v, scratch)?
        } else {
            self.innovation_ekf(state, c, v)
        };
        // Positive, normal (for `update`'s 1/√s) and finite (GUARD: a
        // comparison rather than a test of the bit pattern).
        if s > min_positive::<T>() && s < T::GUARD {
            Some((zhat, s))
        } else {
            cold();
            None
        }
    }

    #[inline(always)]
    fn add_process_noise(&self, state: &mut Core<T, N>) {
        for m in 0..self.m_n() {
            let frozen = state.faded.get(m).copied().unwrap_or(false);
            let (ti, li) = self.theta_lambda(m);
            if !frozen {
                add_diag(&mut state.p, ti, self.q_theta);
                add_diag(&mut state.p, li, get(&self.q_lambda, m));
            }
            for c in 0..self.c_n() {
                let (ai, bi) = self.pair(m, c);
                add_diag(&mut state.p, ai, self.q_amp);
                add_diag(&mut state.p, bi, self.q_amp);
            }
        }
    }

    /// Scalar update with cross-covariance `v`, innovation variance `s` and
    /// innovation `y`. With K the gain `v/s` whose frozen rows are zero,
    /// the Joseph form `P - K vᵀ - v Kᵀ + s K Kᵀ` (valid for that gain) is
    /// exactly `P - (v vᵀ - v_F v_Fᵀ)/s`, v_F the frozen entries of v: a
    /// rank-one update that leaves alone the entries whose row and column
    /// are both frozen, one multiply-add per entry. Below 8 states (one
    /// mode, registers) as `P_ij - v_i k_j` on and above the diagonal,
    /// mirrored; from 8 on whole rows of `P_ij - w_i w_j` with `w = v/√s`,
    /// the same product on both sides of the diagonal, so P stays exactly
    /// symmetric with no mirror. `s` is positive and normal (checked by
    /// `innovation`).
    #[inline(always)]
    fn update(&self, state: &mut Core<T, N>, v: &[T; N], s: T, y: T) {
        let mut frozen = [false; N];
        for m in 0..self.m_n() {
            if state.faded.get(m).copied().unwrap_or(false) {
                let (ti, li) = self.theta_lambda(m);
                put(&mut frozen, ti, true);
                put(&mut frozen, li, true);
            }
        }
        let p = &mut state.p;
        if N < 8 {
            let inv = T::ONE / s;
            let (mut k, mut masked) = ([T::ZERO; N], [T::ZERO; N]);
            for (((k, m), &vi), &fi) in k.iter_mut().zip(masked.iter_mut()).zip(v).zip(&frozen) {
                *k = vi * inv;
                *m = if fi { T::ZERO } else { *k };
            }
            for (xi, mi) in state.x.iter_mut().zip(&masked) {
                *xi += *mi * y;
            }
            // Fully unrolled: every entry a register.
            for i in 0..N {
                let (vi, fi) = (get(v, i), frozen.get(i).copied().unwrap_or(false));
                for j in i..N {
                    let kj = if fi { get(&masked, j) } else { get(&k, j) };
                    let val = entry(p, i, j) - vi * kj;
                    set(p, i, j, val);
                    set(p, j, i, val);
                }
            }
            return;
        }
        let r = rsqrt(s);
        let mut w = [T::ZERO; N];
        for (w, &vi) in w.iter_mut().zip(v) {
            *w = vi * r;
        }
        // K y = w (y/√s) on the rows that are not frozen.
        let ry = r * y;
        for ((xi, &wi), &fi) in state.x.iter_mut().zip(&w).zip(&frozen) {
            if !fi {
                *xi += wi * ry;
            }
        }
        for (row, (&wi, &fi)) in p.iter_mut().zip(w.iter().zip(&frozen)) {
            if !fi {
                for (pij, &wj) in row.iter_mut().zip(&w) {
                    *pij -= wi * wj;
                }
                continue;
            }
            cold();
            for ((pij, &wj), &fj) in row.iter_mut().zip(&w).zip(&frozen) {
                if !fj {
                    *pij -= wi * wj;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
