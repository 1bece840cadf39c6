//! The trackers of the C API, in `f32` (as in Rust, also on a core
//! without an FPU): the modal tracker of one mode on one sensor (seed 004
//! chapter 3, EKF or UKF) and the on-line complex modulus of a sine test
//! (seed 000 §1.2.1). Their specs, their building and their entry points.
// The entry points are the boundary: raw pointers from C, read and
// written through `ffi`.
#![allow(unsafe_code)]

use bushing::tracker::{
    Channel, Filter, Measured, ModalReport, ModalState, ModalTracker, ModeInit, ModeStatus,
    ModulusSpec, ModulusState, ModulusTracker, SensorSpec, SineSpec, Tuning, UtParams,
};

use crate::api::{init, status as code, step_with, trial_with};
use crate::ffi::{self, Storage};
use crate::status::{BushingError, BushingStatus, BushingStatusCode};

/// Modal tracker filter: extended Kalman filter.
pub const BUSHING_FILTER_EKF: u32 = 0;
/// Modal tracker filter: unscented Kalman filter (`ut_alpha`, `ut_beta`,
/// `ut_kappa`).
pub const BUSHING_FILTER_UKF: u32 = 1;

/// The sensor measures displacement (eq 3.26).
pub const BUSHING_MEASURED_DISPLACEMENT: u32 = 0;
/// The sensor measures velocity (eq 3.33).
pub const BUSHING_MEASURED_VELOCITY: u32 = 1;
/// The sensor measures acceleration (eq 3.32).
pub const BUSHING_MEASURED_ACCELERATION: u32 = 2;

/// 64-bit words of a `bushing_tracker_t`.
pub const BUSHING_TRACKER_WORDS: usize = 48;
/// 64-bit words of a `bushing_tracker_state_t`.
pub const BUSHING_TRACKER_STATE_WORDS: usize = 24;
/// 64-bit words of a `bushing_modulus_t`.
pub const BUSHING_MODULUS_WORDS: usize = 12;
/// 64-bit words of a `bushing_modulus_state_t`.
pub const BUSHING_MODULUS_STATE_WORDS: usize = 8;

/// A modal tracker of one mode on one sensor, as C describes it.
/// `bushing_tracker_defaults` fills every field with a usable start
/// (the core's default tuning and UT parameters); set the sensor, the
/// mode's start and the walks, then call `bushing_tracker_init`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct BushingTrackerSpec {
    /// Time between samples, s.
    pub dt_s: f64,
    /// `BUSHING_FILTER_*`.
    pub filter: u32,
    /// `BUSHING_MEASURED_*`.
    pub measured: u32,
    /// Standard deviation of the sensor's noise, in its units.
    pub noise: f64,
    /// Start natural frequency, Hz.
    pub frequency_hz: f64,
    /// Start damping ratio.
    pub damping: f64,
    /// Start complex amplitude `(re, im)` of the mode's displacement at
    /// the sensor (sensor units times s^k): a sensor reading `A sin φ`
    /// near φ = 0 starts at `(0, -A)`.
    pub amplitude: [f64; 2],
    /// Random walk of the frequency, Hz/√s.
    pub frequency_walk: f64,
    /// Random walk of the damping ratio, 1/√s.
    pub damping_walk: f64,
    /// Random walk of the amplitudes, relative, 1/√s.
    pub amplitude_walk: f64,
    /// Standard deviation of the start frequency, relative.
    pub initial_frequency_error: f64,
    /// Standard deviation of the start damping ratio, absolute.
    pub initial_damping_error: f64,
    /// Standard deviation of the start amplitudes, relative.
    pub initial_amplitude_error: f64,
    /// Innovation gate, standard deviations.
    pub gate: f64,
    /// Consecutive outliers after which the tracker re-acquires.
    pub outlier_run: u32,
    /// Amplitude-to-noise ratio below which the mode fades.
    pub fade_snr: f64,
    /// Largest |damping ratio|.
    pub max_damping: f64,
    /// Largest frequency, as a fraction of Nyquist.
    pub max_frequency: f64,
    /// UKF spread α, in (0, 1].
    pub ut_alpha: f64,
    /// UKF prior weight β >= 0.
    pub ut_beta: f64,
    /// UKF secondary scaling κ >= 0.
    pub ut_kappa: f64,
}

/// What one tracker step did, and the mode after it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BushingTrackerReport {
    /// Natural frequency f_0, Hz.
    pub frequency_hz: f32,
    /// Damping ratio ξ.
    pub damping: f32,
    /// Damped angular frequency ω, rad/s.
    pub omega: f32,
    /// Log-decay rate σ, 1/s.
    pub sigma: f32,
    /// 1 when the mode sank into the noise (ω, σ frozen).
    pub faded: u8,
    /// 1 when the sample updated the state.
    pub accepted: u8,
    /// 1 when the sample was gated out as an outlier.
    pub gated: u8,
    /// 1 when the tracker re-acquired after a run of outliers.
    pub reacquired: u8,
    /// 1 when the covariance had to be reset.
    pub repaired: u8,
    /// 1 when a non-finite sample was refused.
    pub refused: u8,
}

/// Counters of a tracker state since its reset.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BushingTrackerCounts {
    /// Samples gated out.
    pub outliers: u32,
    /// Covariance resets.
    pub repairs: u32,
    /// Re-acquisitions.
    pub reacquisitions: u32,
}

/// The on-line complex modulus of a sine test, as C describes it.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct BushingModulusSpec {
    /// Time between samples, s.
    pub dt_s: f64,
    /// Test frequency, Hz.
    pub frequency_hz: f64,
    /// Tracking bandwidth, Hz (at most half the frequency).
    pub bandwidth_hz: f64,
    /// Displacement noise standard deviation, mm.
    pub displacement_noise: f64,
    /// Expected displacement amplitude, mm.
    pub displacement_amplitude: f64,
    /// Force noise standard deviation, N.
    pub force_noise: f64,
    /// Expected force amplitude, N.
    pub force_amplitude: f64,
    /// The modulus is reported once the displacement amplitude exceeds
    /// this many standard deviations of its estimate (10 is a good start).
    pub min_snr: f64,
}

/// The modulus after a step: `valid` is 0 while the displacement is too
/// small to divide by (start-up), and the moduli are then 0.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BushingModulus {
    /// Storage modulus K', N/mm.
    pub storage: f32,
    /// Loss modulus K'', N/mm.
    pub loss: f32,
    /// 1 when the moduli are set.
    pub valid: u8,
}

/// A modal tracker in caller-owned storage (set by `init`).
#[repr(C)]
pub struct BushingTracker {
    /// Opaque.
    pub words: [u64; BUSHING_TRACKER_WORDS],
}

/// A modal tracker state in caller-owned storage (set by `reset`).
#[repr(C)]
pub struct BushingTrackerState {
    /// Opaque.
    pub words: [u64; BUSHING_TRACKER_STATE_WORDS],
}

/// A modulus tracker in caller-owned storage (set by `init`).
#[repr(C)]
pub struct BushingModulusTracker {
    /// Opaque.
    pub words: [u64; BUSHING_MODULUS_WORDS],
}

/// A modulus tracker state in caller-owned storage (set by `reset`).
#[repr(C)]
pub struct BushingModulusState {
    /// Opaque.
    pub words: [u64; BUSHING_MODULUS_STATE_WORDS],
}

// SAFETY: a struct of `u64` words only; its tag is its own (ASCII name,
// the last byte the layout's version).
unsafe impl Storage for BushingTracker {
    type Value = ModalTracker<f32, 4>;
    const TAG: u64 = u64::from_le_bytes(*b"BshTrkM\x01");
}
// SAFETY: as above.
unsafe impl Storage for BushingTrackerState {
    type Value = ModalState<f32, 4>;
    const TAG: u64 = u64::from_le_bytes(*b"BshTrkS\x01");
}
// SAFETY: as above.
unsafe impl Storage for BushingModulusTracker {
    type Value = ModulusTracker<f32>;
    const TAG: u64 = u64::from_le_bytes(*b"BshModM\x01");
}
// SAFETY: as above.
unsafe impl Storage for BushingModulusState {
    type Value = ModulusState<f32>;
    const TAG: u64 = u64::from_le_bytes(*b"BshModS\x01");
}

impl BushingTrackerSpec {
    /// The core's defaults: EKF on a displacement sensor of unit noise, a
    /// 1 Hz undamped mode of unit amplitude, the default tuning and UT.
    fn defaults() -> Self {
        let t = Tuning::default();
        let ut = UtParams::default();
        Self {
            dt_s: 1e-3,
            filter: BUSHING_FILTER_EKF,
            measured: BUSHING_MEASURED_DISPLACEMENT,
            noise: 1.0,
            frequency_hz: 1.0,
            damping: 0.0,
            amplitude: [0.0, -1.0],
            frequency_walk: t.frequency_walk,
            damping_walk: t.damping_walk,
            amplitude_walk: t.amplitude_walk,
            initial_frequency_error: t.initial_frequency_error,
            initial_damping_error: t.initial_damping_error,
            initial_amplitude_error: t.initial_amplitude_error,
            gate: t.gate,
            outlier_run: t.outlier_run,
            fade_snr: t.fade_snr,
            max_damping: t.max_damping,
            max_frequency: t.max_frequency,
            ut_alpha: ut.alpha,
            ut_beta: ut.beta,
            ut_kappa: ut.kappa,
        }
    }

    fn build(&self) -> Result<ModalTracker<f32, 4>, BushingError> {
        let filter = match self.filter {
            BUSHING_FILTER_EKF => Filter::Ekf,
            BUSHING_FILTER_UKF => Filter::Ukf(UtParams {
                alpha: self.ut_alpha,
                beta: self.ut_beta,
                kappa: self.ut_kappa,
            }),
            other => return Err(BushingError::unknown_kind("filter", other)),
        };
        let measured = match self.measured {
            BUSHING_MEASURED_DISPLACEMENT => Measured::Displacement,
            BUSHING_MEASURED_VELOCITY => Measured::Velocity,
            BUSHING_MEASURED_ACCELERATION => Measured::Acceleration,
            other => return Err(BushingError::unknown_kind("measured", other)),
        };
        let tuning = Tuning {
            frequency_walk: self.frequency_walk,
            damping_walk: self.damping_walk,
            amplitude_walk: self.amplitude_walk,
            initial_frequency_error: self.initial_frequency_error,
            initial_damping_error: self.initial_damping_error,
            initial_amplitude_error: self.initial_amplitude_error,
            gate: self.gate,
            outlier_run: self.outlier_run,
            fade_snr: self.fade_snr,
            max_damping: self.max_damping,
            max_frequency: self.max_frequency,
        };
        Ok(ModalTracker::new(
            self.dt_s,
            &[SensorSpec {
                measured,
                noise: self.noise,
            }],
            &[ModeInit {
                frequency: self.frequency_hz,
                damping: self.damping,
            }],
            &[(self.amplitude[0], self.amplitude[1])],
            &tuning,
            filter,
        )?)
    }
}

/// `Refused` for a refused sample, else `Ok`.
fn refused_or_ok(refused: bool) -> BushingStatus {
    if refused {
        BushingStatus::Refused
    } else {
        BushingStatus::Ok
    }
}

/// One sample into `s`: the report and the call's status.
fn track(
    t: &ModalTracker<f32, 4>,
    s: &mut ModalState<f32, 4>,
    sample: f32,
) -> (BushingTrackerReport, BushingStatus) {
    let r = t.step(s, &[sample]);
    (report(r, t.mode(s, 0)), refused_or_ok(r.refused))
}

/// One sample pair into `s`: the modulus and the call's status.
fn measure(
    t: &ModulusTracker<f32>,
    s: &mut ModulusState<f32>,
    displacement: f32,
    force: f32,
) -> (BushingModulus, BushingStatus) {
    let refused = t.step(s, displacement, force).is_err();
    (modulus(t, s), refused_or_ok(refused))
}

fn report(r: ModalReport, m: ModeStatus<f32>) -> BushingTrackerReport {
    BushingTrackerReport {
        frequency_hz: m.frequency,
        damping: m.damping,
        omega: m.omega,
        sigma: m.sigma,
        faded: m.faded.into(),
        accepted: r.accepted,
        gated: r.gated,
        reacquired: r.reacquired.into(),
        repaired: r.repaired.into(),
        refused: r.refused.into(),
    }
}

impl BushingModulusSpec {
    fn build(&self) -> Result<ModulusTracker<f32>, BushingError> {
        Ok(ModulusTracker::new(
            self.dt_s,
            &ModulusSpec {
                sine: SineSpec {
                    frequency: self.frequency_hz,
                    bandwidth: self.bandwidth_hz,
                },
                displacement: Channel {
                    noise: self.displacement_noise,
                    amplitude: self.displacement_amplitude,
                },
                force: Channel {
                    noise: self.force_noise,
                    amplitude: self.force_amplitude,
                },
                min_snr: self.min_snr,
            },
        )?)
    }
}

/// Fills `spec` with the core's defaults (EKF, displacement sensor of unit
/// noise, a 1 Hz mode, the default tuning and UT parameters).
///
/// # Safety
///
/// `spec` is null or points to a writable spec.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_tracker_defaults(
    spec: *mut BushingTrackerSpec,
) -> BushingStatusCode {
    // SAFETY: `spec` is null or writable (the contract).
    code(unsafe { ffi::output(spec, BushingTrackerSpec::defaults()) }.map(|()| BushingStatus::Ok))
}

/// Checks `spec` and builds the tracker into `tracker`; as
/// `bushing_f32_init`.
///
/// # Safety
///
/// As `bushing_f32_init`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_tracker_init(
    tracker: *mut BushingTracker,
    spec: *const BushingTrackerSpec,
    error: *mut BushingError,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { init(tracker, spec, error, BushingTrackerSpec::build) }
}

/// Puts `state` at the tracker's start (the spec's mode and amplitude,
/// counters at zero).
///
/// # Safety
///
/// `tracker` set by `init`, `state` writable; no overlap.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_tracker_reset(
    tracker: *const BushingTracker,
    state: *mut BushingTrackerState,
) -> BushingStatusCode {
    code((|| {
        // SAFETY: `tracker` was set by `init` and is only read.
        let t = unsafe { ffi::get(tracker) }?;
        // SAFETY: `state` is writable and does not overlap `tracker`.
        unsafe { ffi::put(state, t.start()) }?;
        Ok(BushingStatus::Ok)
    })())
}

/// One sample (sensor units): predict and update, then the mode into
/// `out`. A non-finite sample is refused (`refused` in the report, status
/// `BUSHING_STATUS_REFUSED`) and the state only predicted.
///
/// # Safety
///
/// `tracker` set by `init`, `state` by `reset`, `out` writable; no
/// overlap.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_tracker_step(
    tracker: *const BushingTracker,
    state: *mut BushingTrackerState,
    sample: f32,
    out: *mut BushingTrackerReport,
) -> BushingStatusCode {
    // SAFETY: the same contract as `step_with`'s.
    unsafe { step_with(tracker, state, out, |t, s| track(t, s, sample)) }
}

/// The report `step` would give, `state` left unchanged (a copy of the
/// state is stepped).
///
/// # Safety
///
/// As `bushing_tracker_step`, `state` only read.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_tracker_trial(
    tracker: *const BushingTracker,
    state: *const BushingTrackerState,
    sample: f32,
    out: *mut BushingTrackerReport,
) -> BushingStatusCode {
    // SAFETY: the same contract as `trial_with`'s.
    unsafe { trial_with(tracker, state, out, |t, s| track(t, s, sample)) }
}

/// The tracker's counters since its reset: outliers, covariance repairs
/// and re-acquisitions (the tracker's faults).
///
/// # Safety
///
/// `state` set by `reset`, `counts` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_tracker_counts(
    state: *const BushingTrackerState,
    counts: *mut BushingTrackerCounts,
) -> BushingStatusCode {
    code((|| {
        // SAFETY: `state` was set by `reset` and is only read.
        let s = unsafe { ffi::get(state) }?;
        let c = BushingTrackerCounts {
            outliers: s.outliers,
            repairs: s.repairs,
            reacquisitions: s.reacquisitions,
        };
        // SAFETY: `counts` is writable.
        unsafe { ffi::output(counts, c) }?;
        Ok(BushingStatus::Ok)
    })())
}

/// Checks `spec` and builds the modulus tracker; as `bushing_f32_init`.
///
/// # Safety
///
/// As `bushing_f32_init`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_modulus_init(
    tracker: *mut BushingModulusTracker,
    spec: *const BushingModulusSpec,
    error: *mut BushingError,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { init(tracker, spec, error, BushingModulusSpec::build) }
}

/// Puts `state` at the start (zero amplitudes, counters at zero).
///
/// # Safety
///
/// `tracker` set by `init`, `state` writable; no overlap.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_modulus_reset(
    tracker: *const BushingModulusTracker,
    state: *mut BushingModulusState,
) -> BushingStatusCode {
    code((|| {
        // SAFETY: `tracker` was set by `init` and is only read.
        let t = unsafe { ffi::get(tracker) }?;
        // SAFETY: `state` is writable and does not overlap `tracker`.
        unsafe { ffi::put(state, t.start()) }?;
        Ok(BushingStatus::Ok)
    })())
}

/// The modulus of `state` into `out`.
fn modulus(t: &ModulusTracker<f32>, s: &ModulusState<f32>) -> BushingModulus {
    t.modulus(s).map_or(
        BushingModulus {
            storage: 0.0,
            loss: 0.0,
            valid: 0,
        },
        |m| BushingModulus {
            storage: m.storage,
            loss: m.loss,
            valid: 1,
        },
    )
}

/// One displacement (mm) and force (N) sample taken together, then the
/// modulus into `out`. A pair with a non-finite sample, or whose update
/// would overflow, is refused (`BUSHING_STATUS_REFUSED`): the estimates
/// are carried to the sample's time.
///
/// # Safety
///
/// `tracker` set by `init`, `state` by `reset`, `out` writable; no
/// overlap.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_modulus_step(
    tracker: *const BushingModulusTracker,
    state: *mut BushingModulusState,
    displacement: f32,
    force: f32,
    out: *mut BushingModulus,
) -> BushingStatusCode {
    // SAFETY: the same contract as `step_with`'s.
    unsafe {
        step_with(tracker, state, out, |t, s| {
            measure(t, s, displacement, force)
        })
    }
}

/// The modulus `step` would give, `state` left unchanged.
///
/// # Safety
///
/// As `bushing_modulus_step`, `state` only read.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_modulus_trial(
    tracker: *const BushingModulusTracker,
    state: *const BushingModulusState,
    displacement: f32,
    force: f32,
    out: *mut BushingModulus,
) -> BushingStatusCode {
    // SAFETY: the same contract as `trial_with`'s.
    unsafe {
        trial_with(tracker, state, out, |t, s| {
            measure(t, s, displacement, force)
        })
    }
}

/// The modulus tracker's counters: refused sample pairs and covariance
/// repairs since its reset (its faults), into `refused` and `repairs`.
///
/// # Safety
///
/// `state` set by `reset`; `refused` and `repairs` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_modulus_counts(
    state: *const BushingModulusState,
    refused: *mut u32,
    repairs: *mut u32,
) -> BushingStatusCode {
    code((|| {
        // SAFETY: `state` was set by `reset` and is only read.
        let s = unsafe { ffi::get(state) }?;
        // SAFETY: `refused` is writable.
        unsafe { ffi::output(refused, s.refused()) }?;
        // SAFETY: `repairs` is writable.
        unsafe { ffi::output(repairs, s.repairs()) }?;
        Ok(BushingStatus::Ok)
    })())
}
