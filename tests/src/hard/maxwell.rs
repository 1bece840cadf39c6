//! Hard cases of Maxwell cells: stiff and slow cells, the explicit forms at
//! their limit, and temperature jumps.

use core::f64::consts::TAU;

use bushing::accumulator::{Compensated, Plain};
use bushing::{
    Bushing, LibmExp, MaxwellBank, MaxwellForm, MaxwellSpec, ParamError, Polynomial, ShiftFactor,
};

use super::{Measure, effect_force, miss, worst};
use crate::check::param;

/// Every exponential form, ω·dt from 1e-7 to 1e4, under a square wave.
pub(super) fn stiff_and_slow_cells_bounded() -> Measure {
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

pub(super) fn stiff_cell_relaxes_within_one_step() -> Measure {
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

pub(super) fn slow_cell_compensated_decay_rate() -> Measure {
    crate::maxwell::decay_rate_error::<Compensated<f32>>(1e-7, 200_000)
}

pub(super) fn slow_cell_plain_decay_rate() -> Measure {
    crate::maxwell::decay_rate_error::<Plain<f32>>(1e-5, 20_000)
}

pub(super) fn explicit_forms_at_their_limit() -> Measure {
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
// Temperature

pub(super) fn four_cells() -> [MaxwellSpec; 4] {
    [
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(2.0, 0.15),
        MaxwellSpec::hz(8.0, 0.15),
        MaxwellSpec::hz(40.0, 0.1),
    ]
}

pub(super) fn temperature_jump_without_force_jump() -> Measure {
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

pub(super) fn temperature_retune_refused_keeps_bank() -> Measure {
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
