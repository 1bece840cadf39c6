//! On-line modal tracking: the Kalman tracker of the joint thesis (seed 004,
//! chapter 3) that follows the frequency, damping and amplitude of decaying
//! or slowly varying modes sample by sample.
//!
//! - [`modal`]: the four-state tracker `[a, b, ω, σ]` per mode (eqs
//!   3.27-3.28), displacement, velocity or acceleration sensors (eqs 3.26,
//!   3.33, 3.32), several sensors sharing ω and σ (formulation B, eqs
//!   3.43-3.45) and several modes, as an EKF or a UKF.
//! - [`init`]: start values by least squares on the first pseudo-period.
//! - [`trig`]: sin and cos of the phase step without libm trig.

pub mod init;
pub mod modal;
pub mod trig;

pub use init::{FirstPeriodFit, FitError, SensorFit, fit_amplitudes, fit_first_period};
pub use modal::{
    Filter, Measured, ModalReport, ModalState, ModalTracker, ModeInit, ModeStatus, SensorSpec,
    Tuning, UtParams,
};
