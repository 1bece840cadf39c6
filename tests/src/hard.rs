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

use core::f64::consts::TAU;
use core::fmt;

use bushing::{
    Berg, BoucWen, Bushing, Dahl, Effect, EffectOutput, Faults, FractionalSpec, Grunwald, IwanBank,
    IwanCellSpec, IwanSliders, LibmExp, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline,
    Param, ParamError, Polynomial, ShiftFactor, XfBank, XfForm, XfSpec,
    accumulator::{Compensated, Plain},
    stack::{Relaxation, Sts},
    tracker::{Filter, Measured, ModalTracker, ModeInit, SensorSpec, Tuning},
};

use super::{Failure, Noise, demo32, param, sts_bushing, xf_saturation};

mod outputs;
mod tracker;

use outputs::*;
use tracker::*;

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

// ---------------------------------------------------------------------------
// Maxwell cells

/// Every exponential form, ω·dt from 1e-7 to 1e4, under a square wave.
fn stiff_and_slow_cells_bounded() -> Measure {
    let dt = 1e-3;
    let mut w = 0.0f64;
    for form in [
        MaxwellForm::LoadExponential,
        MaxwellForm::RateMidpoint,
        MaxwellForm::RateExactRamp,
    ] {
        for decade in -7..=4 {
            let h = libm::pow(10.0, decade as f64);
            w = worst(w, square_wave_ratio(form, h, dt)?);
        }
    }
    Ok(w)
}

/// Largest |F| / ((g0 + 2g) max|F_inf|) of a linear backbone with one cell
/// (g = 0.6) at ω·dt = `h`, under a ±1 square wave of period 14 steps.
fn square_wave_ratio(form: MaxwellForm, h: f64, dt: f64) -> Measure {
    let spec = [MaxwellSpec::new(h / dt, 0.6)];
    let bank = MaxwellBank::<f32, 1>::new(form, &spec, dt).map_err(param)?;
    let b = Bushing::new(Polynomial::<f32, 2>::linear(100.0).map_err(param)?, (bank,))
        .map_err(param)?;
    let mut s = b.state_at(0.0);
    let mut w = 0.0f64;
    for n in 0..2000 {
        let x = if (n / 7) % 2 == 0 { 1.0 } else { -1.0 };
        let out = b.step(&mut s, x);
        if !(out.force.is_finite() && out.dissipated.is_finite()) {
            return Ok(f64::NAN);
        }
        w = w.max(out.force.abs() as f64);
    }
    Ok(w / (100.0 * (0.4 + 1.2)))
}

fn stiff_cell_relaxes_within_one_step() -> Measure {
    // After a ramp of ΔF over one step the exact-ramp branch force is
    // g ΔF (1 - e^-h) / h, which is g ΔF / h to f32 precision at h = 1e4;
    // then e^-h underflows to zero and the branch is relaxed.
    let (h, dt, g, k) = (1e4f64, 1e-3f64, 0.5f64, 100.0f64);
    let bank = MaxwellBank::<f32, 1>::new(
        MaxwellForm::RateExactRamp,
        &[MaxwellSpec::new(h / dt, g)],
        dt,
    )
    .map_err(param)?;
    let b =
        Bushing::new(Polynomial::<f32, 2>::linear(k).map_err(param)?, (bank,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let first = effect_force(&b, &mut s, 1.0) as f64;
    let expected = g * k / h;
    let mut e = libm::fabs(first / expected - 1.0);
    for _ in 0..10 {
        let held = effect_force(&b, &mut s, 1.0) as f64;
        e = worst(e, libm::fabs(held) / expected);
    }
    Ok(e)
}

/// Relative error of the decay rate of a force held after a unit step,
/// cell at ω·dt = `h`, over `n` steps, with storage `A`.
fn decay_rate<A: bushing::Accumulator<f32>>(h: f64, n: usize) -> Measure {
    let dt = 1e-3;
    let bank = MaxwellBank::<f32, 1, A>::new(
        MaxwellForm::RateExactRamp,
        &[MaxwellSpec::new(h / dt, 0.5)],
        dt,
    )
    .map_err(param)?;
    let b =
        Bushing::new(Polynomial::<f32, 2>::linear(1.0).map_err(param)?, (bank,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let first = effect_force(&b, &mut s, 1.0) as f64;
    let mut last = first;
    for _ in 0..n {
        last = effect_force(&b, &mut s, 1.0) as f64;
    }
    let rate = -libm::log(last / first) / n as f64;
    Ok(libm::fabs(rate / h - 1.0))
}

fn slow_cell_compensated_decay_rate() -> Measure {
    decay_rate::<Compensated<f32>>(1e-7, 200_000)
}

fn slow_cell_plain_decay_rate() -> Measure {
    decay_rate::<Plain<f32>>(1e-5, 20_000)
}

fn explicit_forms_at_their_limit() -> Measure {
    let dt = 1e-3;
    let mut w = 0.0f64;
    for form in [MaxwellForm::LoadExplicit, MaxwellForm::RateExplicit] {
        w = worst(w, square_wave_ratio(form, 0.999, dt)?);
        let at_limit = MaxwellBank::<f32, 1>::new(form, &[MaxwellSpec::new(1.0 / dt, 0.6)], dt);
        w += miss(matches!(
            at_limit,
            Err(ParamError::ExplicitUnstable { cell: 0, .. })
        ));
    }
    Ok(w)
}

// ---------------------------------------------------------------------------
// Grünwald

/// Storage and loss of a 256-tap cell (f_c = 2 Hz, g = 0.6) at 1 kHz under
/// a 5 Hz sine, against the discrete model's own response (f64).
fn grunwald_against_response(alpha: f64) -> Measure {
    let k = 100.0f64;
    let cell =
        Grunwald::<f32, 256>::new(FractionalSpec::hz(2.0, alpha, 0.6), 1e-3).map_err(param)?;
    let (re, im) = cell.branch_response(TAU * 5.0);
    let b =
        Bushing::new(Polynomial::<f32, 2>::linear(k).map_err(param)?, (cell,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let (per, cycles) = (200usize, 8usize);
    let (mut a_sin, mut a_cos) = (0.0f64, 0.0f64);
    for n in 1..=cycles * per {
        let phase = TAU * (n % per) as f64 / per as f64;
        let f = effect_force(&b, &mut s, libm::sin(phase) as f32) as f64;
        if n > (cycles - 1) * per {
            a_sin += 2.0 * f * libm::sin(phase) / per as f64;
            a_cos += 2.0 * f * libm::cos(phase) / per as f64;
        }
    }
    // The loss share is small near α = 0: measure both against the
    // modulus, |K*| of the branch.
    let modulus = k * libm::hypot(re, im);
    Ok(worst(
        libm::fabs(a_sin - k * re) / modulus,
        libm::fabs(a_cos - k * im) / modulus,
    ))
}

fn grunwald_alpha_near_zero() -> Measure {
    grunwald_against_response(0.02)
}

fn grunwald_alpha_near_one() -> Measure {
    grunwald_against_response(0.98)
}

// ---------------------------------------------------------------------------
// x_f cells

fn xf_exact_ramp_steps_far_above_xf() -> Measure {
    let mut w = 0.0f64;
    for a in [1e2, 1e3, 1e4] {
        let r = xf_saturation::<f32>(XfForm::ExactRamp, a)?;
        w = worst(w, libm::fabs(r - 1.0));
    }
    Ok(w)
}

fn xf_midpoint_steps_far_above_xf() -> Measure {
    let mut w = 0.0f64;
    for a in [10.0, 30.0, 100.0] {
        let r = xf_saturation::<f32>(XfForm::Midpoint, a)?;
        w = worst(w, libm::fabs(r - bushing::xf::midpoint_saturation_ratio(a)));
    }
    Ok(w)
}

// ---------------------------------------------------------------------------
// Iwan banks

type Iwan16 = Bushing<f32, Polynomial<f32, 2>, (IwanBank<f32, 16>,)>;

/// 16 Jenkins cells on 150 N/mm, slip distances 0.02 to 1.5 mm (log),
/// total fraction 0.4; returns the bushing and the sum of slip forces.
fn iwan16() -> Result<(Iwan16, f64), Failure> {
    let (_, limits, cells) = jenkins16();
    let bank = IwanBank::new(&cells).map_err(param)?;
    let b = Bushing::new(Polynomial::linear(150.0).map_err(param)?, (bank,)).map_err(param)?;
    Ok((b, limits))
}

/// The cells of [`iwan16`]: (count, sum of slip forces, cells).
fn jenkins16() -> (usize, f64, [IwanCellSpec; 16]) {
    let mut cells = [IwanCellSpec::new(0.1, 1.0); 16];
    let ratio = libm::pow(75.0, 1.0 / 15.0);
    let mut x_f = 0.02;
    let mut limits = 0.0;
    for c in &mut cells {
        *c = IwanCellSpec::from_slip_distance(0.4 / 16.0, 150.0, x_f);
        limits += c.slip_force;
        x_f *= ratio;
    }
    (cells.len(), limits, cells)
}

fn iwan_chatter_at_turning_point() -> Measure {
    let (b, _) = iwan16()?;
    let (mut clean, mut noisy) = (b.state_at(0.0), b.state_at(0.0));
    let mut rng = Noise::new(3);
    let per = 400usize;
    let x = |n: usize| 2.0 * libm::sin(TAU * n as f64 / per as f64);
    let (mut w, mut amplitude) = (0.0f64, 0.0f64);
    // Up to the crest (n = per/4), 100 steps of noise below it (up to
    // 0.5 x_f,min: the crest stays the highest turning point), then on
    // along the sine for one and a half periods. Each noisy step may round
    // each sticking cell's force by half an ulp: 100 steps and 16 cells
    // stay below 1e-5 of the amplitude.
    for n in 1..=per / 4 {
        effect_force(&b, &mut clean, x(n) as f32);
        effect_force(&b, &mut noisy, x(n) as f32);
    }
    let crest = x(per / 4);
    for _ in 0..100 {
        let jitter = -0.01 * rng.uniform();
        effect_force(&b, &mut noisy, (crest + jitter) as f32);
    }
    for n in per / 4 + 1..=2 * per {
        let fc = effect_force(&b, &mut clean, x(n) as f32) as f64;
        let fnoisy = effect_force(&b, &mut noisy, x(n) as f32) as f64;
        amplitude = amplitude.max(libm::fabs(fc));
        // Once the path is more than the noise band below the crest, the
        // inner loops are wiped out.
        if x(n) < crest - 0.02 || n > per / 2 {
            w = worst(w, libm::fabs(fc - fnoisy));
        }
    }
    Ok(w / amplitude)
}

fn iwan_force_within_slip_limits() -> Measure {
    let (b, limits) = iwan16()?;
    let mut s = b.state_at(0.0);
    let mut rng = Noise::new(7);
    let mut w = 0.0f64;
    for n in 0..4000 {
        let x = 3.0 * libm::sin(TAU * n as f64 / 500.0) + 0.05 * rng.gauss();
        let f = effect_force(&b, &mut s, x as f32) as f64;
        w = worst(w, libm::fabs(f) / limits);
    }
    Ok(w)
}

fn iwan_clamp_drift_within_rounding() -> Measure {
    let (b, limits) = iwan16()?;
    let (drift, start, steps) = tiny_oscillation_drift(&b)?;
    // A sticking cell's force is rounded once per step, by at most half an
    // ulp of a value below its slip force: 2^-24 F_f,i per cell and step.
    let rounding = steps as f64 * limits * libm::pow(2.0, -24.0);
    Ok(drift * libm::fabs(start) / rounding)
}

/// Relative force drift of `b` preloaded to 1 mm then oscillating by
/// 2e-6 mm for 100 000 steps; also the preload force and the step count.
fn tiny_oscillation_drift<E: Effect<f32, Report = EffectOutput<f32>>>(
    b: &Bushing<f32, Polynomial<f32, 2>, (E,)>,
) -> Result<(f64, f64, usize), Failure> {
    let mut s = b.state_at(0.0);
    // Preload to 1 mm (some cells slip), then oscillate by 2e-6 mm.
    for n in 1..=100 {
        effect_force(b, &mut s, 0.01 * n as f32);
    }
    // The first move up lets the cells at their slip force slide by the
    // step once (Masing): measure from after that cycle.
    effect_force(b, &mut s, 1.000_002);
    let start = effect_force(b, &mut s, 1.0) as f64;
    let steps = 100_000;
    let mut end = start;
    for n in 0..steps {
        let x = if n % 2 == 0 { 1.000_002f32 } else { 1.0 };
        end = effect_force(b, &mut s, x) as f64;
    }
    if !end.is_nan() {
        end = effect_force(b, &mut s, 1.0) as f64;
    }
    Ok((libm::fabs(end - start) / libm::fabs(start), start, steps))
}

fn iwan_sliders_tiny_oscillations_do_not_drift() -> Measure {
    let (_, _, cells) = jenkins16();
    let bank = IwanSliders::<f32, 16>::new(&cells, 150.0).map_err(param)?;
    let b = Bushing::new(Polynomial::linear(150.0).map_err(param)?, (bank,)).map_err(param)?;
    Ok(tiny_oscillation_drift(&b)?.0)
}

fn iwan_steps_exactly_at_threshold() -> Measure {
    // One cell, g = 0.5 on 100 N/mm, slip distance 0.25 mm: slip force
    // 12.5 N is reached by a step of exactly 0.25 mm.
    let spec = IwanCellSpec::from_slip_distance(0.5, 100.0, 0.25);
    let bank = IwanBank::<f32, 1>::new(&[spec]).map_err(param)?;
    let b = Bushing::new(Polynomial::<f32, 2>::linear(100.0).map_err(param)?, (bank,))
        .map_err(param)?;
    let limit = spec.slip_force;
    let mut s = b.state_at(0.0);
    let mut w = 0.0f64;
    let mut x = 0.0f32;
    for k in 0..40 {
        // Up and down by exactly twice the slip distance, then hold and
        // step by the slip distance.
        x += if k % 4 < 2 { 0.25 } else { -0.25 };
        let f = effect_force(&b, &mut s, x) as f64;
        if k % 4 == 1 || k % 4 == 3 {
            w = worst(w, libm::fabs(libm::fabs(f) - limit) / limit);
        }
        w = worst(w, (libm::fabs(f) - limit).max(0.0) / limit);
    }
    Ok(w)
}

// ---------------------------------------------------------------------------
// Turning-point stacks

fn turning_point_stack_overflow() -> Measure {
    let small = sts_bushing::<4>()?;
    let big = sts_bushing::<32>()?;
    let (mut ss, mut sb) = (small.state_at(0.0), big.state_at(0.0));
    let law = Sts::<f32>::new(400.0, 300.0).map_err(param)?;
    let mut x = 0.0f32;
    let mut w = 0.0f64;
    let mut turns = [0.0f32; 21];
    for (i, t) in turns.iter_mut().enumerate().take(11) {
        let a = 3.0 - 0.25 * i as f32;
        *t = if i % 2 == 0 { a } else { -a };
    }
    for i in 11..21 {
        let back = turns.get(20 - i).copied().unwrap_or(0.0);
        if let Some(t) = turns.get_mut(i) {
            *t = back;
        }
    }
    for &p in &turns {
        for k in 1..=50 {
            let v = if k == 50 {
                p
            } else {
                x + (p - x) * k as f32 / 50.0
            };
            let fs = effect_force(&small, &mut ss, v);
            let fb = effect_force(&big, &mut sb, v);
            let bound = law.branch(ss.effects().0.dropped_span()).0;
            w = worst(w, ((fs - fb).abs() - bound) as f64);
        }
        x = p;
    }
    if ss.effects().0.overflows() == 0 {
        return Err(failure("the small stack never overflowed", 0.0));
    }
    Ok(w)
}

fn first_loading_masing_factor() -> Measure {
    let b = sts_bushing::<8>()?;
    let mut s = b.state_at(0.0);
    let mut virgin = [0.0f32; 201];
    for (k, v) in virgin.iter_mut().enumerate().skip(1) {
        *v = effect_force(&b, &mut s, 0.01 * k as f32);
    }
    let ft = virgin.last().copied().unwrap_or(f32::NAN);
    let mut w = 0.0f64;
    for (k, v) in virgin.iter().enumerate().skip(1) {
        let f = effect_force(&b, &mut s, 2.0 - 0.02 * k as f32);
        let twice = 2.0 * v;
        w = worst(w, ((ft - f - twice).abs() / twice) as f64);
    }
    Ok(w)
}

// ---------------------------------------------------------------------------
// Friction cells

/// Largest |F| / `bound` of `e` on a unit linear backbone through jumps of
/// `h` (0, h, -h, ...); NaN on a refused step, a non-finite output or a
/// negative dissipation.
fn jumps<E: Effect<f32, Report = EffectOutput<f32>>>(e: E, h: f32, bound: f32) -> Measure {
    let b = Bushing::new(Polynomial::<f32, 2>::linear(1.0).map_err(param)?, (e,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let mut w = 0.0f64;
    for k in 0..300 {
        let x = match k % 3 {
            0 => 0.0,
            1 => h,
            _ => -h,
        };
        let Some(o) = b.step(&mut s, x).effects.map(|r| r.0) else {
            return Ok(f64::NAN);
        };
        if !(o.force.is_finite() && o.dissipated >= 0.0) {
            return Ok(f64::NAN);
        }
        w = w.max((o.force.abs() / bound) as f64);
    }
    Ok(w)
}

fn bouc_wen_large_exponents() -> Measure {
    let mut w = 0.0f64;
    for n in [5.0, 20.0, 50.0] {
        let bw = BoucWen::<f32>::new(100.0, 1.0, 30.0, 10.0, n).map_err(param)?;
        let f_u = bw.ultimate_force();
        for h in [0.01f32, 1.0, 100.0] {
            w = worst(w, jumps(bw, h * f_u / 100.0, f_u)?);
        }
    }
    Ok(w)
}

fn dahl_huge_steps() -> Measure {
    let mut w = 0.0f64;
    for alpha in [0.3, 1.0, 2.0, 5.0] {
        let d = Dahl::<f32>::new(100.0, 2.0, alpha).map_err(param)?;
        for h in [0.01f32, 1.0, 100.0] {
            w = worst(w, jumps(d, h * 0.02, 2.0)?);
        }
    }
    Ok(w)
}

fn berg_huge_steps() -> Measure {
    let berg = Berg::<f32>::new(3.0, 0.1).map_err(param)?;
    let mut w = 0.0f64;
    for h in [0.001f32, 0.1, 10.0] {
        w = worst(w, jumps(berg, h, 3.0)?);
    }
    Ok(w)
}

// ---------------------------------------------------------------------------
// Temperature

fn four_cells() -> [MaxwellSpec; 4] {
    [
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(2.0, 0.15),
        MaxwellSpec::hz(8.0, 0.15),
        MaxwellSpec::hz(40.0, 0.1),
    ]
}

fn temperature_jump_without_force_jump() -> Measure {
    let (dt, per) = (1e-3f64, 200usize);
    let warm =
        MaxwellBank::<f32, 4>::new(MaxwellForm::RateExactRamp, &four_cells(), dt).map_err(param)?;
    let law = ShiftFactor::wlf(17.44, 51.6, 20.0).map_err(param)?;
    let mut cold = warm.clone();
    cold.retune::<LibmExp>(law.at_in::<f32, LibmExp>(10.0).map_err(param)?)
        .map_err(param)?;
    let k = Polynomial::<f32, 2>::linear(1.0).map_err(param)?;
    let bw = Bushing::new(k, (warm,)).map_err(param)?;
    let bc = Bushing::new(k, (cold,)).map_err(param)?;
    let mut s = bw.state_at(0.0);
    let x = |n: usize| libm::sin(TAU * (n % per) as f64 / per as f64) as f32;
    let (mut largest, mut last) = (0.0f64, 0.0f64);
    let n0 = 10 * per + per / 3;
    for n in 1..=n0 {
        let f = bw.step(&mut s, x(n)).force as f64;
        largest = largest.max(libm::fabs(f - last));
        last = f;
    }
    let f = bc.step(&mut s, x(n0 + 1)).force as f64;
    Ok(libm::fabs(f - last) / largest)
}

fn temperature_retune_refused_keeps_bank() -> Measure {
    let bank = MaxwellBank::<f32, 4>::new(MaxwellForm::RateExactRamp, &four_cells(), 1e-3)
        .map_err(param)?;
    let mut wrong = 0.0;
    for a_t in [0.0f32, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut b = bank.clone();
        let refused = b.retune::<LibmExp>(a_t).is_err();
        wrong += miss(refused && b == bank);
    }
    // Extreme but representable shifts freeze or relax every cell: accepted,
    // and the bushing then steps with finite outputs.
    for a_t in [1e-30f32, 1e30] {
        let mut b = bank.clone();
        wrong += miss(b.retune::<LibmExp>(a_t).is_ok());
        let k = Polynomial::<f32, 2>::linear(1.0).map_err(param)?;
        let bushing = Bushing::new(k, (b,)).map_err(param)?;
        let mut s = bushing.state_at(0.0);
        for n in 0..100 {
            let out = bushing.step(&mut s, libm::sinf(0.1 * n as f32));
            wrong += miss(out.force.is_finite() && out.dissipated.is_finite());
        }
    }
    Ok(wrong)
}

// ---------------------------------------------------------------------------
// Inputs

fn non_finite_inputs_keep_state() -> Measure {
    let b = demo32()?;
    let mut s = b.state_at(0.0);
    for n in 0..100 {
        b.step(&mut s, n as f32 * 0.01);
    }
    let mut wrong = 0.0;
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let before = s.clone();
        let out = b.step(&mut s, bad);
        wrong += miss(out.force == before.force() && out.dissipated == 0.0);
        wrong += miss(s.effects() == before.effects() && s.force() == before.force());
        wrong += miss(s.faults().contains(Faults::NON_FINITE_INPUT));
        s.clear_faults();
    }
    Ok(wrong)
}

fn huge_inputs_refused_then_recover() -> Measure {
    let b = demo32()?;
    let mut s = b.state_at(0.5);
    let mut wrong = 0.0;
    for huge in [1e30f32, -1e30] {
        let before = s.clone();
        let out = b.step(&mut s, huge);
        wrong += miss(s.faults().contains(Faults::OUT_OF_RANGE));
        wrong += miss(out.force == before.force() && s.effects() == before.effects());
        s.clear_faults();
    }
    for large in [1e12f32, -1e12, 0.5] {
        let out = b.step(&mut s, large);
        wrong += miss(out.effects.is_some() && out.force.is_finite() && out.dissipated.is_finite());
    }
    Ok(wrong)
}

// ---------------------------------------------------------------------------
// Parameters

/// One if `r` is not the error `want` says it should be.
fn refused_as<T>(r: Result<T, ParamError>, want: impl Fn(&ParamError) -> bool) -> f64 {
    match r {
        Err(e) => miss(want(&e)),
        Ok(_) => 1.0,
    }
}

fn maxwell_parameters_refused() -> Measure {
    let dt = 1e-3;
    let form = MaxwellForm::RateExactRamp;
    let one = |omega: f64, g: f64, dt: f64| {
        MaxwellBank::<f32, 1>::new(form, &[MaxwellSpec::new(omega, g)], dt)
    };
    let mut wrong = 0.0;
    wrong += refused_as(one(0.0, 0.2, dt), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param {
                    name: "omega",
                    index: Some(0)
                },
                ..
            }
        )
    });
    wrong += refused_as(one(-1.0, 0.2, dt), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param { name: "omega", .. },
                ..
            }
        )
    });
    wrong += refused_as(one(f64::NAN, 0.2, dt), |e| {
        matches!(
            e,
            ParamError::NotFinite {
                param: Param { name: "omega", .. }
            }
        )
    });
    wrong += refused_as(one(10.0, 0.0, dt), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param { name: "g", .. },
                ..
            }
        )
    });
    wrong += refused_as(one(10.0, 1.5, dt), |e| {
        matches!(e, ParamError::CellFractionAboveOne { cell: Some(0), .. })
    });
    wrong += refused_as(one(10.0, 0.2, 0.0), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param { name: "dt", .. },
                ..
            }
        )
    });
    wrong += refused_as(one(10.0, 0.2, f64::INFINITY), |e| {
        matches!(
            e,
            ParamError::NotFinite {
                param: Param { name: "dt", .. }
            }
        )
    });
    let two = MaxwellBank::<f32, 2>::new(
        form,
        &[MaxwellSpec::new(10.0, 0.6), MaxwellSpec::new(100.0, 0.6)],
        dt,
    );
    wrong += refused_as(two, |e| matches!(e, ParamError::FractionsAboveOne { .. }));
    // At the bounds: g = 1 and a cell at 1e-7 rad/s are accepted.
    wrong += miss(one(10.0, 1.0, dt).is_ok());
    wrong += miss(one(1e-7, 0.5, dt).is_ok());
    Ok(wrong)
}

fn hysteresis_parameters_refused() -> Measure {
    let mut wrong = 0.0;
    wrong += refused_as(
        IwanBank::<f32, 1>::new(&[IwanCellSpec::new(0.2, 0.0)]),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    wrong += refused_as(
        IwanBank::<f32, 1>::new(&[IwanCellSpec::new(0.2, f64::NAN)]),
        |e| matches!(e, ParamError::NotFinite { .. }),
    );
    wrong += refused_as(
        IwanBank::<f32, 1>::new(&[IwanCellSpec::new(-0.1, 1.0)]),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    wrong += refused_as(
        IwanBank::<f32, 2>::new(&[IwanCellSpec::new(0.7, 1.0), IwanCellSpec::new(0.7, 2.0)]),
        |e| matches!(e, ParamError::FractionsAboveOne { .. }),
    );
    wrong += refused_as(
        XfBank::<f32, 1>::new(XfForm::ExactRamp, &[XfSpec::hz(5.0, 0.1, 0.0)], 1e-3),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    // α in (0, 1]: 1 is the dashpot, accepted.
    wrong += refused_as(
        Grunwald::<f32, 16>::new(FractionalSpec::hz(2.0, 1.5, 0.5), 1e-3),
        |e| matches!(e, ParamError::OutOfRange { .. }),
    );
    wrong += refused_as(
        Grunwald::<f32, 16>::new(FractionalSpec::hz(2.0, 0.0, 0.5), 1e-3),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    wrong += miss(Grunwald::<f32, 16>::new(FractionalSpec::hz(2.0, 1.0, 0.5), 1e-3).is_ok());
    wrong += refused_as(Dahl::<f32>::new(100.0, 0.0, 1.0), |e| {
        matches!(e, ParamError::NotPositive { .. })
    });
    wrong += refused_as(BoucWen::<f32>::new(100.0, 1.0, 30.0, 10.0, 0.0), |e| {
        matches!(
            e,
            ParamError::NotPositive { .. } | ParamError::OutOfRange { .. }
        )
    });
    wrong += refused_as(Berg::<f32>::new(3.0, -0.1), |e| {
        matches!(e, ParamError::NotPositive { .. })
    });
    Ok(wrong)
}

fn backbone_parameters_refused() -> Measure {
    let mut wrong = 0.0;
    wrong += refused_as(
        MonotoneSpline::<f32, 8>::new(&[0.0, 1.0, 1.0, 2.0], &[0.0, 1.0, 2.0, 3.0]),
        |e| matches!(e, ParamError::NotIncreasing { .. }),
    );
    wrong += refused_as(
        MonotoneSpline::<f32, 8>::new(&[0.0, 1.0, 2.0, 3.0], &[0.0, 1.0, 0.5, 3.0]),
        |e| matches!(e, ParamError::NotIncreasing { .. }),
    );
    wrong += refused_as(MonotoneSpline::<f32, 8>::new(&[0.0], &[0.0]), |e| {
        matches!(e, ParamError::TooFew { .. })
    });
    wrong += refused_as(
        MonotoneSpline::<f32, 2>::new(&[0.0, 1.0, 2.0], &[0.0, 1.0, 2.0]),
        |e| {
            matches!(
                e,
                ParamError::TooMany {
                    capacity: 2,
                    got: 3,
                    ..
                }
            )
        },
    );
    wrong += refused_as(
        MonotoneSpline::<f32, 8>::new(&[0.0, 1.0, 2.0], &[0.0, 1.0]),
        |e| matches!(e, ParamError::LengthMismatch { .. }),
    );
    // A cubic whose tangent 100 - 3 x² turns negative inside the range.
    wrong += refused_as(
        Polynomial::<f32, 4>::new(&[0.0, 100.0, 0.0, -1.0], (-10.0, 10.0)),
        |e| matches!(e, ParamError::TangentNotPositive { .. }),
    );
    wrong += refused_as(Polynomial::<f32, 2>::new(&[0.0, 100.0], (1.0, 1.0)), |e| {
        matches!(e, ParamError::EmptyRange { .. })
    });
    Ok(wrong)
}

fn tracker_parameters_refused() -> Measure {
    let sensor = [SensorSpec {
        measured: Measured::Acceleration,
        noise: 0.01,
    }];
    let mode = |frequency: f64| {
        [ModeInit {
            frequency,
            damping: 0.01,
        }]
    };
    let tuning = Tuning::default();
    let dt = 1e-3;
    let mut wrong = 0.0;
    for f in [500.0, 600.0, 0.0, -20.0, f64::NAN] {
        let r =
            ModalTracker::<f32, 4>::new(dt, &sensor, &mode(f), &[(1.0, 0.0)], &tuning, Filter::Ekf);
        wrong += miss(r.is_err());
    }
    let silent = [SensorSpec {
        measured: Measured::Acceleration,
        noise: 0.0,
    }];
    wrong += miss(
        ModalTracker::<f32, 4>::new(
            dt,
            &silent,
            &mode(20.0),
            &[(1.0, 0.0)],
            &tuning,
            Filter::Ekf,
        )
        .is_err(),
    );
    wrong += miss(
        ModalTracker::<f32, 4>::new(dt, &sensor, &mode(20.0), &[], &tuning, Filter::Ekf).is_err(),
    );
    // Two sensors and one mode need 6 states, not 4.
    let two = [sensor[0], sensor[0]];
    wrong += miss(
        ModalTracker::<f32, 4>::new(
            dt,
            &two,
            &mode(20.0),
            &[(1.0, 0.0), (1.0, 0.0)],
            &tuning,
            Filter::Ekf,
        )
        .is_err(),
    );
    Ok(wrong)
}
