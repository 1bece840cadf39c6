//! Cases shared by the host and the Cortex-M suites.
//!
//! Every case is a plain function returning `Result<(), Failure>`, run by
//! the `cortex_m` test binary on the host (as a normal program) and on
//! Cortex-M4F / Cortex-M3 under QEMU (through semihosting). The golden trace
//! case demands bit-identical results on both.
//!
//! The cases live in one module per model family (backbones, Maxwell banks,
//! bad inputs, Iwan banks, x_f cells, the fractional cell, turning-point
//! stacks, friction cells, the oscillator, the tracker), beside the golden
//! traces, the noise generator and the checks a case makes; what the suites
//! and the host tests use is re-exported here, and the named hard cases are
//! in [`hard`].
#![no_std]
#![forbid(unsafe_code)]

use core::fmt;

use bushing::tracker::{Filter, UtParams};
use bushing::{LibmExp, MicromathExp};

pub mod hard;

mod backbone;
mod check;
mod fractional;
mod friction;
mod golden;
mod inputs;
mod iwan;
mod maxwell;
mod oscillator;
mod stack;
mod tracker;
mod xf;

pub use bushing_kernels::Noise;
pub use check::{CaseResult, Failure, at_most, holds};
pub use golden::{
    GOLDEN_FRICTION_HASH, GOLDEN_HASH, GOLDEN_HYSTERESIS_HASH, GOLDEN_STEPS, TraceHash,
    golden_trace, golden_trace_friction, golden_trace_hysteresis,
};
pub use iwan::{ReferenceIwan, reference_iwan};

use backbone::{polynomial_f32_matches_f64, spline_f32_monotone_positive_tangent};
use fractional::grunwald_modulus_f32;
use friction::friction_cells_bounded_f32;
use golden::{golden_trace_f32, golden_trace_friction_f32, golden_trace_hysteresis_f32};
use inputs::{huge_input_refused, non_finite_input_keeps_state};
use iwan::{iwan_cycle_energy_f32, iwan_madelung_return_f32, iwan_slider_equals_clamp_f32};
use maxwell::{
    explicit_forms_refused_at_unit_omega_dt, exponential_forms_bounded_f32,
    exponential_forms_bounded_f64, slow_cell_f32_decay_rate,
    tangent_matches_central_difference_f64, temperature_retune_f32,
};
use oscillator::iwan_oscillator_free_decay_f32;
use stack::{stack_madelung_overflow_f32, stack_masing_f32};
use tracker::{
    instantaneous_modulus_maxwell_bank_f32, modal_tracker_fit_gap_reacquire_f32,
    modal_tracker_free_decay_f32, modal_tracker_modes_fixed_same_bits_f32,
};
use xf::{xf_exact_ramp_saturates_f32, xf_midpoint_under_saturation_f32};

/// A named case.
pub type Case = (&'static str, fn() -> CaseResult);

/// Every case, by name.
pub const CASES: &[Case] = &[
    ("polynomial_f32_matches_f64", polynomial_f32_matches_f64),
    (
        "spline_f32_monotone_positive_tangent",
        spline_f32_monotone_positive_tangent,
    ),
    (
        "explicit_forms_refused_at_unit_omega_dt",
        explicit_forms_refused_at_unit_omega_dt,
    ),
    (
        "exponential_forms_bounded_1e-7_to_1e4_f32",
        exponential_forms_bounded_f32,
    ),
    (
        "exponential_forms_bounded_1e-7_to_1e4_f64",
        exponential_forms_bounded_f64,
    ),
    ("slow_cell_f32_decay_rate", slow_cell_f32_decay_rate),
    (
        "tangent_matches_central_difference_f64",
        tangent_matches_central_difference_f64,
    ),
    ("non_finite_input_keeps_state", non_finite_input_keeps_state),
    ("huge_input_refused", huge_input_refused),
    ("golden_trace_f32", golden_trace_f32),
    ("iwan_cycle_energy_masing_sum_f32", iwan_cycle_energy_f32),
    ("iwan_madelung_return_f32", iwan_madelung_return_f32),
    (
        "iwan_slider_equals_clamp_linear_f32",
        iwan_slider_equals_clamp_f32,
    ),
    (
        "xf_exact_ramp_saturates_any_step_f32",
        xf_exact_ramp_saturates_f32,
    ),
    (
        "xf_midpoint_under_saturation_f32",
        xf_midpoint_under_saturation_f32,
    ),
    ("golden_trace_hysteresis_f32", golden_trace_hysteresis_f32),
    ("stack_masing_factor_two_f32", stack_masing_f32),
    (
        "stack_madelung_and_overflow_f32",
        stack_madelung_overflow_f32,
    ),
    (
        "dahl_bouc_wen_berg_bounded_huge_steps_f32",
        friction_cells_bounded_f32,
    ),
    (
        "iwan_oscillator_free_decay_f32",
        iwan_oscillator_free_decay_f32,
    ),
    ("golden_trace_friction_f32", golden_trace_friction_f32),
    ("grunwald_steady_modulus_f32", grunwald_modulus_f32),
    (
        "temperature_retune_continuous_and_shifted_f32",
        temperature_retune_f32::<LibmExp>,
    ),
    (
        "temperature_retune_micromath_f32",
        temperature_retune_f32::<MicromathExp>,
    ),
    ("modal_tracker_ekf_free_decay_f32", || {
        modal_tracker_free_decay_f32(Filter::Ekf)
    }),
    ("modal_tracker_ukf_free_decay_f32", || {
        modal_tracker_free_decay_f32(Filter::Ukf(UtParams::default()))
    }),
    (
        "instantaneous_modulus_maxwell_bank_f32",
        instantaneous_modulus_maxwell_bank_f32,
    ),
    ("modal_tracker_fit_gap_reacquire_ekf_f32", || {
        modal_tracker_fit_gap_reacquire_f32(Filter::Ekf)
    }),
    ("modal_tracker_fit_gap_reacquire_ukf_f32", || {
        modal_tracker_fit_gap_reacquire_f32(Filter::Ukf(UtParams::default()))
    }),
    ("modal_tracker_modes_fixed_same_bits_ekf_f32", || {
        modal_tracker_modes_fixed_same_bits_f32(Filter::Ekf)
    }),
    ("modal_tracker_modes_fixed_same_bits_ukf_f32", || {
        modal_tracker_modes_fixed_same_bits_f32(Filter::Ukf(UtParams::default()))
    }),
];

/// Runs every case, printing one line each and the closing
/// `N passed, N failed`; returns the number of failures.
pub fn run_all(mut out: impl FnMut(fmt::Arguments<'_>)) -> u32 {
    let (mut passed, mut failed) = (0u32, 0u32);
    for (name, case) in CASES {
        match case() {
            Ok(()) => {
                passed += 1;
                out(format_args!("test {name} ... ok"));
            }
            Err(e) => {
                failed += 1;
                out(format_args!("test {name} ... FAILED: {e}"));
            }
        }
    }
    out(format_args!("{passed} passed, {failed} failed"));
    failed
}
