//! The named hard cases (DESIGN §8 and the hard-case lists of both theses):
//! each case drives one model where it is most fragile, measures one figure
//! and passes when that figure is within the case's bound. Every case runs
//! in f32, on the host and, unchanged, on Cortex-M under QEMU; the host run
//! writes `docs/hard-cases.md` with the measured values.
//!
//! A case returns its measured figure; [`run_hard`] compares it with the
//! bound (a NaN fails). Cases that check refusals count the inputs or
//! parameters that were not refused with the right error variant, or that
//! changed the state: their bound is 0.

use core::fmt;

use bushing::{Bushing, Effect, EffectOutput, ParamError};

use crate::check::Failure;

mod fractional;
mod friction;
mod inputs;
mod iwan;
mod maxwell;
mod outputs;
mod parameters;
mod stack;
mod tracker;
mod xf;

use fractional::*;
use friction::*;
use inputs::*;
use iwan::*;
use maxwell::*;
use outputs::*;
use parameters::*;
use stack::*;
use tracker::*;
use xf::*;

/// What a case measures: the figure, or why it could not be measured.
pub type Measure = Result<f64, Failure>;

/// One named hard case.
pub struct HardCase {
    /// Test name (also the row of `docs/hard-cases.md`).
    pub name: &'static str,
    /// Which DESIGN §8 category it belongs to.
    pub category: &'static str,
    /// What is measured, in words.
    pub measured: &'static str,
    /// The figure must be at most this.
    pub bound: f64,
    /// Runs the case and returns the figure.
    pub run: fn() -> Measure,
}

/// The outcome of one case.
#[derive(Debug, Clone, Copy)]
pub struct HardOutcome {
    /// The measured figure (NaN when the case could not measure it).
    pub value: f64,
    /// Whether it is within the bound.
    pub passed: bool,
    /// Why the case failed before measuring, if it did.
    pub error: Option<Failure>,
}

/// Runs `case` and compares its figure with the bound.
pub fn run_case(case: &HardCase) -> HardOutcome {
    match (case.run)() {
        Ok(value) => HardOutcome {
            value,
            passed: value <= case.bound,
            error: None,
        },
        Err(e) => HardOutcome {
            value: f64::NAN,
            passed: false,
            error: Some(e),
        },
    }
}

/// Runs every hard case, printing one line each and the closing
/// `N passed, N failed`; returns the number of failures.
pub fn run_hard(mut out: impl FnMut(fmt::Arguments<'_>)) -> u32 {
    let (mut passed, mut failed) = (0u32, 0u32);
    for case in HARD_CASES {
        let o = run_case(case);
        let verdict = if o.passed { "ok" } else { "FAILED" };
        match o.error {
            None => out(format_args!(
                "hard {} ... {verdict}: {:e} (bound {:e})",
                case.name, o.value, case.bound
            )),
            Some(e) => out(format_args!("hard {} ... {verdict}: {e}", case.name)),
        }
        if o.passed {
            passed += 1;
        } else {
            failed += 1;
        }
    }
    out(format_args!("{passed} passed, {failed} failed"));
    failed
}

/// Every hard case, by category.
pub const HARD_CASES: &[HardCase] = &[
    HardCase {
        name: "stiff_and_slow_cells_bounded",
        category: "stiff cells",
        measured: "largest |F| / ((g0 + 2g) max|F_inf|), every exponential form, ω·dt = 1e-7 to \
                   1e4 by decades, square wave",
        bound: 1.0 + 1e-6,
        run: stiff_and_slow_cells_bounded,
    },
    HardCase {
        name: "stiff_cell_relaxes_within_one_step",
        category: "stiff cells",
        measured: "branch force one step after a ramp, over g ΔF_inf / (ω dt), ω·dt = 1e4 \
                   (exact ramp): the closed form gives 1",
        bound: 1e-6,
        run: stiff_cell_relaxes_within_one_step,
    },
    HardCase {
        name: "slow_cell_compensated_decay_rate",
        category: "slow cells in f32",
        measured: "relative error of the decay rate of a held force, ω·dt = 1e-7, compensated \
                   state, 200 000 steps",
        bound: 1e-3,
        run: slow_cell_compensated_decay_rate,
    },
    HardCase {
        name: "slow_cell_plain_decay_rate",
        category: "slow cells in f32",
        measured: "relative error of the decay rate of a held force, ω·dt = 1e-5, plain state \
                   (d stored, F - dF), 20 000 steps",
        bound: 1e-2,
        run: slow_cell_plain_decay_rate,
    },
    HardCase {
        name: "explicit_forms_at_their_limit",
        category: "explicit schemes at their limit",
        measured: "largest |F| / ((g0 + 2g) max|F_inf|) at ω·dt = 0.999 under a square wave, \
                   both explicit forms, plus one per form not refused at ω·dt = 1",
        bound: 1.0 + 1e-6,
        run: explicit_forms_at_their_limit,
    },
    HardCase {
        name: "grunwald_alpha_near_zero",
        category: "Grünwald memory near α = 0 and 1",
        measured: "relative error of storage and loss at 5 Hz against the discrete model's \
                   response, α = 0.02, 256 taps",
        bound: 2e-3,
        run: grunwald_alpha_near_zero,
    },
    HardCase {
        name: "grunwald_alpha_near_one",
        category: "Grünwald memory near α = 0 and 1",
        measured: "relative error of storage and loss at 5 Hz against the discrete model's \
                   response, α = 0.98, 256 taps",
        bound: 2e-3,
        run: grunwald_alpha_near_one,
    },
    HardCase {
        name: "xf_exact_ramp_steps_far_above_xf",
        category: "x_f cells with steps far larger than x_f",
        measured: "|F / (g K x_f) - 1| in steady sliding, steps of 1e2, 1e3 and 1e4 x_f",
        bound: 1e-6,
        run: xf_exact_ramp_steps_far_above_xf,
    },
    HardCase {
        name: "xf_midpoint_steps_far_above_xf",
        category: "x_f cells with steps far larger than x_f",
        measured: "|F / (g K x_f) - a / (2 sinh(a/2))| in steady sliding, a = 10, 30, 100 (the \
                   midpoint form's own law, which falls to 0)",
        bound: 1e-5,
        run: xf_midpoint_steps_far_above_xf,
    },
    HardCase {
        name: "iwan_chatter_at_turning_point",
        category: "Iwan chatter",
        measured: "force difference from the clean run once the path leaves a burst of noise \
                   (100 steps, up to 0.5 x_f,min below a turning point), over the force \
                   amplitude (Madelung wipes the inner loops)",
        bound: 1e-5,
        run: iwan_chatter_at_turning_point,
    },
    HardCase {
        name: "iwan_force_within_slip_limits",
        category: "Iwan chatter",
        measured: "largest |F_iwan| / Σ slip forces, sine plus noise, 16 cells",
        bound: 1.0 + 1e-6,
        run: iwan_force_within_slip_limits,
    },
    HardCase {
        name: "iwan_sliders_tiny_oscillations_do_not_drift",
        category: "Iwan chatter",
        measured: "force drift of the slider form (positions stored) after 100 000 oscillations \
                   of 1e-4 x_f,min around a preloaded point, over the preload force",
        bound: 1e-6,
        run: iwan_sliders_tiny_oscillations_do_not_drift,
    },
    HardCase {
        name: "iwan_clamp_drift_within_rounding",
        category: "Iwan chatter",
        measured: "force drift of the clamp form (forces stored) in the same run, over its \
                   rounding bound (half an ulp of each sticking cell's slip force per step)",
        bound: 1.0,
        run: iwan_clamp_drift_within_rounding,
    },
    HardCase {
        name: "iwan_steps_exactly_at_threshold",
        category: "Iwan chatter",
        measured: "|F - slip force| / slip force after steps of exactly the slip distance, and \
                   never above it",
        bound: 1e-6,
        run: iwan_steps_exactly_at_threshold,
    },
    HardCase {
        name: "turning_point_stack_overflow",
        category: "turning-point stack overflow",
        measured: "force error of a 4-deep stack against a 32-deep one, beyond H(dropped span), N",
        bound: 1e-3,
        run: turning_point_stack_overflow,
    },
    HardCase {
        name: "first_loading_masing_factor",
        category: "first loading",
        measured: "reversal branch over twice the virgin curve at d/2, minus one (Masing)",
        bound: 1e-5,
        run: first_loading_masing_factor,
    },
    HardCase {
        name: "bouc_wen_large_exponents",
        category: "Bouc-Wen with large exponents",
        measured: "largest |F| / ultimate force, n = 5, 20 and 50, jumps of 0.01 to 100 times the \
                   yield displacement; negative dissipation counts as a failure",
        bound: 1.0 + 1e-5,
        run: bouc_wen_large_exponents,
    },
    HardCase {
        name: "dahl_huge_steps",
        category: "friction cells under huge steps",
        measured: "largest |F| / friction force, α = 0.3 to 5, jumps of 0.01 to 100 times \
                   f_f / k_d",
        bound: 1.0 + 1e-5,
        run: dahl_huge_steps,
    },
    HardCase {
        name: "berg_huge_steps",
        category: "friction cells under huge steps",
        measured: "largest |F| / f_max, jumps of 0.01 to 100 times x2",
        bound: 1.0 + 1e-5,
        run: berg_huge_steps,
    },
    HardCase {
        name: "temperature_jump_without_force_jump",
        category: "temperature jumps",
        measured: "force change at a re-tune from 20 °C to 10 °C (WLF, a_T = 1.6e4) \
                   mid-period, over the largest ordinary step change",
        bound: 1.0,
        run: temperature_jump_without_force_jump,
    },
    HardCase {
        name: "temperature_retune_refused_keeps_bank",
        category: "temperature jumps",
        measured: "shift factors 0, -1, NaN and ±∞ not refused or refused with the bank \
                   changed, plus 1e-30 and 1e30 refused or giving a non-finite step",
        bound: 0.0,
        run: temperature_retune_refused_keeps_bank,
    },
    HardCase {
        name: "non_finite_inputs_keep_state",
        category: "non-finite and huge inputs",
        measured: "NaN, +∞, -∞ inputs that changed the state, returned another force or raised \
                   no fault",
        bound: 0.0,
        run: non_finite_inputs_keep_state,
    },
    HardCase {
        name: "huge_inputs_refused_then_recover",
        category: "non-finite and huge inputs",
        measured: "inputs of ±1e30 not refused with the state kept, plus a non-finite output at \
                   ±1e12 or after recovery",
        bound: 0.0,
        run: huge_inputs_refused_then_recover,
    },
    HardCase {
        name: "maxwell_parameters_refused",
        category: "parameters at and beyond their bounds",
        measured: "Maxwell parameter sets at or beyond a bound not refused with the right variant \
                   and parameter, or at a bound refused",
        bound: 0.0,
        run: maxwell_parameters_refused,
    },
    HardCase {
        name: "hysteresis_parameters_refused",
        category: "parameters at and beyond their bounds",
        measured: "Iwan, x_f, fractional and friction parameter sets beyond a bound not refused \
                   with the right variant",
        bound: 0.0,
        run: hysteresis_parameters_refused,
    },
    HardCase {
        name: "backbone_parameters_refused",
        category: "parameters at and beyond their bounds",
        measured: "backbones (non-monotone, too few or too many points, empty range, fractions \
                   above one) not refused with the right variant",
        bound: 0.0,
        run: backbone_parameters_refused,
    },
    HardCase {
        name: "tracker_parameters_refused",
        category: "parameters at and beyond their bounds",
        measured: "tracker set-ups (frequency at or above Nyquist, zero noise, wrong amplitude \
                   count, too many states) not refused",
        bound: 0.0,
        run: tracker_parameters_refused,
    },
    HardCase {
        name: "tracker_zero_amplitude",
        category: "tracker",
        measured: "relative frequency change after 5000 samples of exact zeros, within the \
                   prior's 1 %; plus one if any state is not finite or the mode did not fade",
        bound: 1e-2,
        run: tracker_zero_amplitude,
    },
    HardCase {
        name: "tracker_frequency_jump",
        category: "tracker",
        measured: "relative frequency error 30 periods after a sustained 50 Hz tone jumps to \
                   52 Hz",
        bound: 1e-3,
        run: tracker_frequency_jump,
    },
    HardCase {
        name: "tracker_close_modes",
        category: "tracker",
        measured: "largest relative frequency error of two modes 5 % apart (20 and 21 Hz) on three \
                   accelerometers, after 2 s",
        bound: 1e-3,
        run: tracker_close_modes,
    },
    HardCase {
        name: "tracker_outliers",
        category: "tracker",
        measured: "relative frequency error after 10 periods with one sample in 50 replaced by a \
                   50 σ spike",
        bound: 5e-4,
        run: tracker_outliers,
    },
    HardCase {
        name: "tracker_signal_loss",
        category: "tracker",
        measured: "relative frequency error 20 periods after 1 s of noise only (the mode fades, \
                   then comes back 1 % higher)",
        bound: 5e-4,
        run: tracker_signal_loss,
    },
    HardCase {
        name: "tracker_mode_sinking_into_noise",
        category: "tracker",
        measured: "relative frequency error at the end of a 10 s record of a 20 Hz, 1 % decay \
                   at 40 dB, below the noise after 3.7 s and 69 dB below it at the end (frozen \
                   by the fade); plus one if any state is not finite or the mode did not fade",
        bound: 2e-3,
        run: tracker_mode_sinking_into_noise,
    },
    HardCase {
        name: "kf_table_beyond_working_type_refused",
        category: "parameters at and beyond their bounds",
        measured: "K_f tables whose k, d, slope or dissipated work leave f32's guard not refused \
                   as OutOfRange at the offending point, or a fitting table refused",
        bound: 0.0,
        run: kf_table_beyond_working_type_refused,
    },
    HardCase {
        name: "effect_forces_beyond_guard_refused",
        category: "non-finite and huge inputs",
        measured: "wrong verdicts over steps whose effect force, total force or total tangent \
                   would leave the guard (refused, state kept, FORCE_OUT_OF_RANGE) and the \
                   ordinary steps around them (accepted, within the guard)",
        bound: 0.0,
        run: effect_forces_beyond_guard_refused,
    },
    HardCase {
        name: "inner_loop_energy_at_ten_steps",
        category: "passivity",
        measured: "relative error of the energy of an asymmetric inner loop (0.2-0.4 mm after \
                   +-1 mm, 10 steps per branch) against Masing's area, worst of the STS law \
                   and a 5-cell Iwan bank",
        bound: 1e-5,
        run: inner_loop_energy_at_ten_steps,
    },
    HardCase {
        name: "six_dof_tangent_after_refused_pose",
        category: "non-finite and huge inputs",
        measured: "wrong verdicts of the 6-DOF tangent after refused poses (NaN, huge, not a \
                   rotation), both connectivities: None at the refused pose, finite at the \
                   last accepted one",
        bound: 0.0,
        run: six_dof_tangent_after_refused_pose,
    },
    HardCase {
        name: "dissipation_never_negative",
        category: "passivity",
        measured: "steps with negative dissipated energy, default-like bushing (4 Maxwell, 3 \
                   Jenkins, 1 x_f) under random closed cycles",
        bound: 0.0,
        run: dissipation_never_negative,
    },
];

// ---------------------------------------------------------------------------
// Small helpers

fn failure(what: &'static str, got: f64) -> Failure {
    Failure {
        what,
        got,
        bound: 0.0,
        bits: None,
    }
}

/// One if `cond` fails (for counting wrong verdicts).
fn miss(cond: bool) -> f64 {
    if cond { 0.0 } else { 1.0 }
}

/// NaN-propagating maximum (a NaN figure fails its bound).
fn worst(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The effect's own force of a one-effect bushing step (NaN if refused).
fn effect_force<B, E>(b: &Bushing<f32, B, (E,)>, s: &mut BushingStateOf<E>, x: f32) -> f32
where
    B: bushing::Backbone<f32>,
    E: Effect<f32, Report = EffectOutput<f32>>,
{
    b.step(s, x).effects.map_or(f32::NAN, |r| r.0.force)
}

type BushingStateOf<E> = bushing::BushingState<f32, <(E,) as Effect<f32>>::State>;

/// One if `r` is not the error `want` says it should be.
fn refused_as<T>(r: Result<T, ParamError>, want: impl Fn(&ParamError) -> bool) -> f64 {
    match r {
        Err(e) => miss(want(&e)),
        Ok(_) => 1.0,
    }
}
