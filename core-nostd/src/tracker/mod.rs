//! On-line modal tracking: the Kalman tracker of the joint thesis (seed 004,
//! chapter 3) that follows the frequency, damping and amplitude of decaying
//! or slowly varying modes sample by sample.
//!
//! - [`modal`]: the four-state tracker `[a, b, ω, σ]` per mode (eqs
//!   3.27-3.28), displacement, velocity or acceleration sensors (eqs 3.26,
//!   3.33, 3.32), several sensors sharing ω and σ (formulation B, eqs
//!   3.43-3.45) and several modes, as an EKF or a UKF.
//! - [`init`]: start values by least squares on the first pseudo-period.
//! - [`sine`]: the two-state fixed-frequency tracker of a sine's complex
//!   amplitude (eqs 3.24-3.26) and the instantaneous complex modulus of a
//!   sine test (seed 000 eqs 1.1-1.3, Fig 1.24).
//! - [`trig`]: sin and cos of the phase step without libm trig.
//! - [`fast`]: `e^x` of a small log-decay and `1/√x` without libm calls or
//!   a division, and a clamp by comparisons, for the per-sample path.
//! - [`relevance`]: the Iwan relevance check (eqs 7.17-7.18): damping
//!   predicted from the frequency drop of a tracked curve, and the inverse.
//! - [`unscented`]: scalar unscented transform and linearisation (eqs
//!   3.34-3.40), compared with Table 1 of §3.2.4 in `docs/unscented-table.md`.

pub mod fast;
pub mod init;
pub mod modal;
pub mod relevance;
pub mod sine;
pub mod trig;
pub mod unscented;

pub use init::{FirstPeriodFit, FitError, SensorFit, fit_amplitudes, fit_first_period};
pub use modal::{
    Filter, Measured, ModalReport, ModalState, ModalTracker, ModeInit, ModeStatus, SensorSpec,
    Tuning, UtParams,
};
pub use relevance::{
    damping_from_frequency, damping_from_frequency_uniform, frequency_from_damping_uniform,
};
pub use sine::{
    Channel, Modulus, ModulusSpec, ModulusState, ModulusTracker, Refused, SineSpec, SineState,
    SineTracker,
};
pub use unscented::{ScalarUt, linearised_scalar, unscented_scalar};
